//! Tone map to 8-bit sRGB for PNG output: srgb_oetf(clamp(exposure * L, 0, 1)) (SCENES.md).
use std::sync::Arc;

use crate::gpu::{
    vk, Access, Attachment, Clear, DescriptorSet, DescriptorSetLayout, DescriptorWrite, Framebuffer, GpuContext,
    GpuResult, GraphicsPipeline, PipelineLayout, RenderPass, RenderPassDesc, Sampler,
};
use crate::graph::Frame;
use crate::renderer::plan::TONEMAP;
use crate::renderer::targets::Targets;
use crate::BINDING_HDR;

use super::{fullscreen_pipeline, FRAGMENT, SAMPLED};

pub struct TonemapPass {
    render_pass: RenderPass,
    _set_layout: DescriptorSetLayout,
    set: DescriptorSet,
    _layout: PipelineLayout,
    pipeline: GraphicsPipeline,
    framebuffer: Framebuffer,
}

impl TonemapPass {
    pub fn new(
        ctx: &Arc<GpuContext>,
        frame_layout: &DescriptorSetLayout,
        targets: &Targets,
        nearest: &Sampler,
    ) -> GpuResult<Self> {
        let render_pass = RenderPass::new(
            ctx,
            TONEMAP,
            &RenderPassDesc {
                colors: vec![Attachment { format: targets.ldr.format(), clear: true }],
                depth: None,
                depth_read_only: false,
            },
        )?;
        let set_layout = DescriptorSetLayout::new(ctx, TONEMAP, &[(BINDING_HDR, SAMPLED, FRAGMENT)], 1)?;
        let set = set_layout.allocate(
            TONEMAP,
            &[DescriptorWrite::Sampled(
                BINDING_HDR,
                targets.hdr.view(),
                nearest,
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            )],
        )?;
        let (layout, pipeline) =
            fullscreen_pipeline(ctx, TONEMAP, "tonemap/tonemap.frag", &[frame_layout, &set_layout], &render_pass, &[])?;
        let framebuffer = Framebuffer::new(ctx, TONEMAP, &render_pass, &[targets.ldr.view()], targets.extent())?;
        Ok(TonemapPass { render_pass, _set_layout: set_layout, set, _layout: layout, pipeline, framebuffer })
    }

    pub fn record<'a>(&'a self, frame: &mut Frame<'_, 'a>, targets: &Targets, frame_set: DescriptorSet) {
        frame
            .pass(TONEMAP)
            .read(targets.hdr_id, Access::FragmentSampled)
            .write(targets.ldr_id, Access::ColorAttachment)
            .record(move |cmd| {
                cmd.begin_render_pass(&self.render_pass, &self.framebuffer, &[Clear::Color([0.0; 4])]);
                cmd.bind_graphics(&self.pipeline, &[frame_set, self.set]);
                cmd.draw(3, 1);
                cmd.end_render_pass();
            });
    }
}
