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
include!("shader_shared.rs");
