//! prism: a hand-written Vulkan renderer for interactive refraction, reflection and
//! caustics, measuring each technique's GPU time against its error. See README.md for the
//! architecture: scene file -> scene -> pass plan -> passes -> frame graph -> images/timings.
#![warn(unsafe_op_in_unsafe_fn)]
// Scene errors are cold (at most one per failed load) and carry what the user needs: the
// file, line and column, the override that caused them and a hint. Boxing them to shrink
// `Result` would only add noise to every fallible scene function.
#![allow(clippy::result_large_err)]

pub mod app;
pub mod frame;
pub mod gpu;
pub mod graph;
pub mod metrics;
pub mod reference;
pub mod renderer;
pub mod scene;
pub mod technique;

/// Rust side of `shared_constants!` (src/shader_shared.rs): plain `pub const`s.
macro_rules! shared_constants {
    ($($name:ident : $ty:ty = $value:expr;)*) => {
        $(pub const $name: $ty = $value;)*
    };
}
/// Rust side of `shared_floats!` (src/shader_shared.rs): plain `pub const`s.
macro_rules! shared_floats {
    ($($name:ident : $ty:ty = $value:expr;)*) => {
        $(pub const $name: $ty = $value;)*
    };
}
/// Rust side of `shared_bindings!` (src/shader_shared.rs): a `pub const` per binding and one
/// list per group, checked for two bindings of one number.
macro_rules! shared_bindings {
    ($($group:ident { $($name:ident = $value:expr;)* })*) => {
        $(
            $(pub const $name: u32 = $value;)*
            pub const $group: &[(&str, u32)] = {
                let group = &[$((stringify!($name), $name)),*];
                distinct_bindings(&[group]);
                group
            };
            const _: &[(&str, u32)] = $group;
        )*
    };
}
/// Rust side of `descriptor_sets!` (src/shader_shared.rs): the groups of each set, checked
/// together.
macro_rules! descriptor_sets {
    ($($set:ident = [$($group:ident),*];)*) => {
        $(
            pub const $set: &[&[(&str, u32)]] = {
                let set = &[$($group),*];
                distinct_bindings(set);
                set
            };
            const _: &[&[(&str, u32)]] = $set;
        )*
    };
}
include!("shader_shared.rs");

/// Panics (at compile time, where `shared_bindings!` and `descriptor_sets!` call it: "evaluation
/// of `SET` failed ... panicked: NAME") with the name of a binding whose number an earlier
/// binding of the same set already has.
const fn distinct_bindings(groups: &[&[(&str, u32)]]) {
    let mut g = 0;
    while g < groups.len() {
        let mut i = 0;
        while i < groups[g].len() {
            let (mut h, mut j) = (g, i + 1);
            while h < groups.len() {
                if j >= groups[h].len() {
                    (h, j) = (h + 1, 0);
                    continue;
                }
                if groups[h][j].1 == groups[g][i].1 {
                    panic!("{}", groups[h][j].0);
                }
                j += 1;
            }
            i += 1;
        }
        g += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::distinct_bindings;

    /// The check the binding groups and sets run at compile time finds a number used twice
    /// across the groups of one set, and names the later binding.
    #[test]
    fn two_bindings_of_one_number_in_a_set_are_refused() {
        distinct_bindings(&[&[("A", 0), ("B", 1)], &[("C", 2)]]);
        for set in [&[&[("A", 0), ("B", 0)][..]][..], &[&[("A", 0), ("X", 1)], &[("B", 0)]]] {
            let e = std::panic::catch_unwind(|| distinct_bindings(set)).unwrap_err();
            assert_eq!(e.downcast_ref::<String>().map(String::as_str), Some("B"));
        }
    }
}
