//! The gpu layer: the only module that makes raw `ash` calls (../shared/DESIGN.md, rule 1).
//!
//! Everything above it (frame graph, passes, app) works with the small wrappers here:
//! [`GpuContext`] owns the instance, device, queue, allocator and the deferred-deletion
//! queue; [`Buffer`] and [`Image`] free themselves after the last frame that used them;
//! [`Cmd`] records commands; [`Access`] names how a pass touches a resource so that the
//! frame graph can derive barriers.

/// `Drop` for wrappers that own one device object in `raw` and hold the context in `ctx`:
/// `destroy_on_drop!(Wrapper => destroy_fn, ...)` destroys `raw` with `destroy_fn`.
macro_rules! destroy_on_drop {
    ($($wrapper:ty => $destroy:ident),+ $(,)?) => {$(
        impl Drop for $wrapper {
            fn drop(&mut self) {
                // SAFETY: every owner of these wrappers (the renderer, the caches, the
                // swapchain) drops them only after the device is idle, so no pending command
                // buffer references the object.
                unsafe { self.ctx.raw().$destroy(self.raw, None) };
            }
        }
    )+};
}

mod bindings;
mod buffer;
mod command;
mod context;
mod debug;
mod descriptor;
mod error;
mod glsl;
pub use glsl::SpecConstant;
mod image;
mod overlay;
mod pipeline;
mod render_pass;
mod swapchain;
mod sync;
mod timing;

pub use ash::vk;
pub use bindings::{Bindings, BoundSet};
pub use buffer::{Buffer, BufferView};
pub use command::{Clear, Cmd, CommandPool, SubmitSync};
pub use context::{
    ContextDesc, DeviceInfo, GpuContext, MemoryKinds, MemoryUsage, PipelineCounts, Progress, ProgressSink,
};
pub use debug::ValidationLog;
use descriptor::DescriptorWrite;
pub use descriptor::{DescriptorSet, DescriptorSetLayout};
pub use error::{GpuError, GpuResult};
pub use image::{read_aspect, texel_layout, texels_to_f32, Image, ImageDesc, ImageViewKind, Sampler, SamplerDesc};
pub use overlay::Overlay;
pub use pipeline::{
    Blend, ComputePipeline, DepthState, GraphicsPipeline, GraphicsPipelineDesc, Spec, Specs, VertexLayout,
};
pub use render_pass::{Framebuffer, RenderPass, RenderTarget};
pub use swapchain::{Acquired, Presented, Semaphore, Swapchain, SwapchainImage};
pub use sync::{Access, BufferBarrier, ImageBarrier};
pub use timing::{OcclusionQueryPool, PassCounts, PipelineStatsPool, TimestampPool, TimestampQuery};

pub use gpu_allocator::MemoryLocation;

/// SPIR-V of every shader under `glsl/`, compiled by build.rs.
mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

/// A shader's SPIR-V words and the specialisation constants it declares.
#[derive(Clone, Debug)]
pub struct ShaderCode {
    pub words: Vec<u32>,
    pub specs: Vec<SpecConstant>,
}

/// The embedded shader at `path` (relative to `glsl/`, e.g. `"gbuffer/gbuffer.vert"`).
pub fn shader_code(path: &str) -> GpuResult<ShaderCode> {
    let (_, bytes, specs) =
        shaders::SHADERS.iter().find(|(p, ..)| *p == path).ok_or_else(|| GpuError::MissingShader(path.to_string()))?;
    let words = ash::util::read_spv(&mut std::io::Cursor::new(bytes))
        .map_err(|e| GpuError::InvalidShader(path.to_string(), e.to_string()))?;
    let specs = specs.iter().map(|&(name, id, ty)| SpecConstant { name: name.into(), id, ty: ty.into() }).collect();
    Ok(ShaderCode { words, specs })
}

/// The SPIR-V words of the embedded shader at `path`.
pub fn shader_spirv(path: &str) -> GpuResult<Vec<u32>> {
    shader_code(path).map(|c| c.words)
}

/// The shader-interface header build.rs generated (`prism_shared.glsl`), for run-time
/// compiles.
const SHARED_HEADER: &str = include_str!(concat!(env!("OUT_DIR"), "/prism_shared.glsl"));

/// Compile the shader `rel` of the tree `glsl` at run time, exactly as build.rs compiles the
/// embedded ones (the window's hot reload: [`GpuContext::set_shader`]). Returns the shader
/// and the files it included; an error names the file and line.
pub fn compile_shader(glsl: &std::path::Path, rel: &str) -> Result<(ShaderCode, Vec<std::path::PathBuf>), String> {
    let compiler = shaderc::Compiler::new().map_err(|e| format!("shaderc: {e}"))?;
    let mut includes = Vec::new();
    let compiled = glsl::compile_glsl(&compiler, glsl, rel, SHARED_HEADER, &mut includes)?;
    let words =
        ash::util::read_spv(&mut std::io::Cursor::new(compiled.spirv)).map_err(|e| format!("glsl/{rel}: {e}"))?;
    Ok((ShaderCode { words, specs: compiled.specs }, includes))
}

/// Names of every embedded shader (for tests and `--help` diagnostics).
pub fn shader_names() -> impl Iterator<Item = &'static str> {
    shaders::SHADERS.iter().map(|(p, ..)| *p)
}
