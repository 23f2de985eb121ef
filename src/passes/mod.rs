//! One file per technique (../shared/DESIGN.md, rule 10). Each pass owns its pipelines and
//! render pass, declares its reads and writes to the frame graph and records its commands.
//! None of them touches raw Vulkan or records a barrier.
pub mod deferred_shading;
pub mod gbuffer;
pub mod shadow_map;
pub mod specular_single;
pub mod tonemap;

use std::sync::Arc;

use crate::gpu::{
    vk, Blend, DepthState, DescriptorSetLayout, GpuContext, GpuResult, GraphicsPipeline, GraphicsPipelineDesc,
    PipelineLayout, RenderPass, VertexLayout,
};

/// A full-screen-triangle pipeline over `fragment_shader` with set 0 (frame) and `set1`.
pub(crate) fn fullscreen_pipeline(
    ctx: &Arc<GpuContext>,
    name: &str,
    fragment_shader: &str,
    sets: &[&DescriptorSetLayout],
    pass: &RenderPass,
    specialization: &[u32],
) -> GpuResult<(PipelineLayout, GraphicsPipeline)> {
    let layout = PipelineLayout::new(ctx, name, sets, 0)?;
    let blend = vec![Blend::Off; pass.desc.colors.len()];
    let pipeline = GraphicsPipeline::new(
        ctx,
        &GraphicsPipelineDesc {
            name,
            vertex_shader: "common/fullscreen.vert",
            fragment_shader,
            vertex: VertexLayout::None,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            cull: vk::CullModeFlags::NONE,
            depth: DepthState::OFF,
            blend: &blend,
            specialization,
        },
        &layout,
        pass,
    )?;
    Ok((layout, pipeline))
}

/// Stages that can see set-1 image inputs of full-screen passes.
pub(crate) const FRAGMENT: vk::ShaderStageFlags = vk::ShaderStageFlags::FRAGMENT;
pub(crate) const SAMPLED: vk::DescriptorType = vk::DescriptorType::COMBINED_IMAGE_SAMPLER;
