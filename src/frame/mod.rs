//! What every technique of a frame shares: the scene's GPU data ([`gpu_scene`]), the
//! frame's render targets ([`targets`]) and the error creating any of them returns.
pub mod gpu_scene;
pub mod heightfield;
pub mod targets;

use crate::gpu::GpuError;

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error("{0}")]
    Limit(String),
    /// A technique parameter (`[render.<technique>]`) that is unknown or out of range.
    #[error("render.{technique}.{}: {error}", error.key)]
    Param { technique: &'static str, error: crate::scene::techniques::ParamError },
}
