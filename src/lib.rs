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
/// Rust side of `shared_rgb!` (src/shader_shared.rs): a `pub const [f32; 3]` per colour.
macro_rules! shared_rgb {
    ($($name:ident = [$r:expr, $g:expr, $b:expr];)*) => {
        $(pub const $name: [f32; 3] = [$r, $g, $b];)*
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

/// Rust side of `shared_structs!` (src/shader_structs.rs): a `#[repr(C)]` Pod struct per
/// declaration, whose offsets and size are checked at compile time against the GLSL layout
/// rules of its kind (`push` and `buffer`: std430; `uniform`: std140 and std430).
macro_rules! shared_structs {
    ($(
        $(#[$meta:meta])*
        $kind:ident struct $name:ident {
            $($(#[$field_meta:meta])* $field:ident : $ty:tt),* $(,)?
        }
    )*) => {
        $(
            $(#[$meta])*
            #[repr(C)]
            #[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
            pub struct $name {
                $($(#[$field_meta])* pub $field: glsl_rust_type!($ty),)*
            }
            impl $name {
                /// The layout GLSL gives this struct under `rule`.
                pub const fn glsl_layout(rule: $crate::shader_layout::Rule) -> $crate::shader_layout::Layout {
                    $crate::shader_layout::Layout::structure(&[$(glsl_layout!($ty, rule)),*], rule)
                }
            }
            const _: () = {
                let rules = glsl_rules!($kind, $name);
                let mut r = 0;
                while r < rules.len() {
                    $crate::shader_layout::Layout::check(
                        stringify!($name),
                        &[$(concat!(stringify!($name), ".", stringify!($field))),*],
                        &[$(glsl_layout!($ty, rules[r])),*],
                        &[$(std::mem::offset_of!($name, $field)),*],
                        std::mem::size_of::<$name>(),
                        rules[r],
                    );
                    r += 1;
                }
            };
        )*
    };
}
/// The Rust type of a `shared_structs!` member's GLSL type: a scalar, an array of scalars
/// for a vector, columns of a matrix, a shared struct, or an array `[T; N]` of any of them.
macro_rules! glsl_rust_type {
    (float) => {
        f32
    };
    (int) => {
        i32
    };
    (uint) => {
        u32
    };
    (vec2) => {
        [f32; 2]
    };
    (vec3) => {
        [f32; 3]
    };
    (vec4) => {
        [f32; 4]
    };
    (ivec4) => {
        [i32; 4]
    };
    (uvec2) => {
        [u32; 2]
    };
    (uvec4) => {
        [u32; 4]
    };
    (mat4) => {
        [[f32; 4]; 4]
    };
    ([$ty:tt; $n:expr]) => {
        [glsl_rust_type!($ty); ($n) as usize]
    };
    ($name:ident) => {
        $name
    };
}
/// The GLSL layout of a `shared_structs!` member's type under `rule`.
macro_rules! glsl_layout {
    (float, $rule:expr) => {
        $crate::shader_layout::Layout::SCALAR
    };
    (int, $rule:expr) => {
        $crate::shader_layout::Layout::SCALAR
    };
    (uint, $rule:expr) => {
        $crate::shader_layout::Layout::SCALAR
    };
    (vec2, $rule:expr) => {
        $crate::shader_layout::Layout::vector(2)
    };
    (vec3, $rule:expr) => {
        $crate::shader_layout::Layout::vector(3)
    };
    (vec4, $rule:expr) => {
        $crate::shader_layout::Layout::vector(4)
    };
    (ivec4, $rule:expr) => {
        $crate::shader_layout::Layout::vector(4)
    };
    (uvec2, $rule:expr) => {
        $crate::shader_layout::Layout::vector(2)
    };
    (uvec4, $rule:expr) => {
        $crate::shader_layout::Layout::vector(4)
    };
    (mat4, $rule:expr) => {
        $crate::shader_layout::Layout::matrix(4)
    };
    ([$ty:tt; $n:expr], $rule:expr) => {
        glsl_layout!($ty, $rule).array(($n) as usize, $rule)
    };
    ($name:ident, $rule:expr) => {
        $name::glsl_layout($rule)
    };
}
/// The layout rules a struct of each kind is read under; push constants must also fit the
/// 128 bytes every Vulkan device offers.
macro_rules! glsl_rules {
    (push, $name:ident) => {{
        assert!(std::mem::size_of::<$name>() <= 128, stringify!($name));
        [$crate::shader_layout::Rule::Std430]
    }};
    (buffer, $name:ident) => {
        [$crate::shader_layout::Rule::Std430]
    };
    (uniform, $name:ident) => {
        [$crate::shader_layout::Rule::Std140, $crate::shader_layout::Rule::Std430]
    };
}
pub mod shader_layout;
/// The structs GLSL reads, declared once in src/shader_structs.rs (their GLSL mirrors are in
/// the generated header `prism_shared.glsl`).
pub mod shader_structs {
    use crate::{HP_MAX_LEVELS, MAX_LIGHTS, MAX_NEARBY_SETS, REF_MAX_TARGETS};
    include!("shader_structs.rs");
}

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
