//! Deferred shading of diffuse surfaces (direct light with shadow maps, environment
//! irradiance) and the environment background: glsl/shading/deferred.frag.
use std::sync::Arc;

use crate::gpu::{
    vk, Access, Attachment, Clear, DescriptorSet, DescriptorSetLayout, DescriptorWrite, Framebuffer, GpuContext,
    GpuResult, GraphicsPipeline, PipelineLayout, RenderPass, RenderPassDesc, Sampler,
};
use crate::graph::Frame;
use crate::renderer::gpu_scene::GpuScene;
use crate::renderer::plan::DEFERRED_SHADING;
use crate::renderer::targets::Targets;
use crate::{BINDING_GBUF_ALBEDO, BINDING_GBUF_DEPTH, BINDING_GBUF_NORMAL};

use super::{fullscreen_pipeline, FRAGMENT, SAMPLED};

pub struct DeferredShadingPass {
    render_pass: RenderPass,
    _set_layout: DescriptorSetLayout,
    set: DescriptorSet,
    _layout: PipelineLayout,
    pipeline: GraphicsPipeline,
    framebuffer: Framebuffer,
    /// Whether the shadow atlas is written this frame (a shadow_map pass exists).
    shadowed: bool,
}

impl DeferredShadingPass {
    pub fn new(
        ctx: &Arc<GpuContext>,
        frame_layout: &DescriptorSetLayout,
        targets: &Targets,
        nearest: &Sampler,
        shadowed: bool,
    ) -> GpuResult<Self> {
        let render_pass = RenderPass::new(
            ctx,
            DEFERRED_SHADING,
            &RenderPassDesc {
                colors: vec![Attachment { format: targets.hdr.format(), clear: true }],
                depth: None,
                depth_read_only: false,
            },
        )?;
        let set_layout = DescriptorSetLayout::new(
            ctx,
            DEFERRED_SHADING,
            &[
                (BINDING_GBUF_NORMAL, SAMPLED, FRAGMENT),
                (BINDING_GBUF_ALBEDO, SAMPLED, FRAGMENT),
                (BINDING_GBUF_DEPTH, SAMPLED, FRAGMENT),
            ],
            1,
        )?;
        let set = set_layout.allocate(
            DEFERRED_SHADING,
            &[
                DescriptorWrite::Sampled(
                    BINDING_GBUF_NORMAL,
                    targets.gbuf_normal.view(),
                    nearest,
                    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                ),
                DescriptorWrite::Sampled(
                    BINDING_GBUF_ALBEDO,
                    targets.gbuf_albedo.view(),
                    nearest,
                    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                ),
                DescriptorWrite::Sampled(
                    BINDING_GBUF_DEPTH,
                    targets.depth.view(),
                    nearest,
                    vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL,
                ),
            ],
        )?;
        let (layout, pipeline) = fullscreen_pipeline(
            ctx,
            DEFERRED_SHADING,
            "shading/deferred.frag",
            &[frame_layout, &set_layout],
            &render_pass,
            &[],
        )?;
        let framebuffer =
            Framebuffer::new(ctx, DEFERRED_SHADING, &render_pass, &[targets.hdr.view()], targets.extent())?;
        Ok(DeferredShadingPass {
            render_pass,
            _set_layout: set_layout,
            set,
            _layout: layout,
            pipeline,
            framebuffer,
            shadowed,
        })
    }

    pub fn record<'a>(
        &'a self,
        frame: &mut Frame<'_, 'a>,
        scene: &GpuScene,
        targets: &Targets,
        frame_set: DescriptorSet,
    ) {
        let mut pass = frame
            .pass(DEFERRED_SHADING)
            .read(targets.gbuf_normal_id, Access::FragmentSampled)
            .read(targets.gbuf_albedo_id, Access::FragmentSampled)
            .read(targets.depth_id, Access::FragmentSampled)
            .read(scene.environment_id, Access::FragmentSampled)
            .write(targets.hdr_id, Access::ColorAttachment);
        if self.shadowed {
            pass = pass.read(targets.shadow_atlas_id, Access::FragmentSampled);
        }
        pass.record(move |cmd| {
            cmd.begin_render_pass(&self.render_pass, &self.framebuffer, &[Clear::Color([0.0; 4])]);
            cmd.bind_graphics(&self.pipeline, &[frame_set, self.set]);
            cmd.draw(3, 1);
            cmd.end_render_pass();
        });
    }
}
