//! prism: a hand-written Vulkan renderer for interactive refraction, reflection and
//! caustics. See README.md for the architecture.
#![warn(unsafe_op_in_unsafe_fn)]

pub mod scene;
