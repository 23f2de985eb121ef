//! Image error metrics and timing statistics.
pub mod image;
pub mod mask;
pub mod paired;
pub mod timing;
