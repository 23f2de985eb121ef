//! Image error metrics and timing statistics.
pub mod image;
pub mod timing;
