//! The single-interface baseline for specular surfaces (glsl/specular/single.frag): one
//! reflection and one refraction of the view ray at the first surface, each looked up in
//! the environment, weighted by exact Fresnel. With `Mode::Refraction` it shades dielectrics
//! (`refraction_single`), with `Mode::Reflection` mirrors and conductors (`reflection_single`).
//! It is the "1-sided refraction" baseline of Wyman 2005 (Table 1) against which every
//! refraction technique's cost is compared.
use std::sync::Arc;

use crate::gpu::{
    vk, Access, Attachment, Clear, DescriptorSet, DescriptorSetLayout, DescriptorWrite, Framebuffer, GpuContext,
    GpuResult, GraphicsPipeline, PipelineLayout, RenderPass, RenderPassDesc, Sampler,
};
use crate::graph::Frame;
use crate::renderer::gpu_scene::GpuScene;
use crate::renderer::plan::{REFLECTION_SINGLE, REFRACTION_SINGLE};
use crate::renderer::targets::Targets;
use crate::{BINDING_GBUF_DEPTH, BINDING_GBUF_NORMAL, SPECULAR_MODE_REFLECTION, SPECULAR_MODE_REFRACTION};

use super::{fullscreen_pipeline, FRAGMENT, SAMPLED};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Refraction,
    Reflection,
}

pub struct SpecularSinglePass {
    name: &'static str,
    render_pass: RenderPass,
    _set_layout: DescriptorSetLayout,
    set: DescriptorSet,
    _layout: PipelineLayout,
    pipeline: GraphicsPipeline,
    framebuffer: Framebuffer,
}

impl SpecularSinglePass {
    pub fn new(
        ctx: &Arc<GpuContext>,
        mode: Mode,
        frame_layout: &DescriptorSetLayout,
        targets: &Targets,
        nearest: &Sampler,
    ) -> GpuResult<Self> {
        let (name, spec) = match mode {
            Mode::Refraction => (REFRACTION_SINGLE, SPECULAR_MODE_REFRACTION),
            Mode::Reflection => (REFLECTION_SINGLE, SPECULAR_MODE_REFLECTION),
        };
        // Loads the deferred result and overwrites only the pixels of its materials.
        let render_pass = RenderPass::new(
            ctx,
            name,
            &RenderPassDesc {
                colors: vec![Attachment { format: targets.hdr.format(), clear: false }],
                depth: None,
                depth_read_only: false,
            },
        )?;
        let set_layout = DescriptorSetLayout::new(
            ctx,
            name,
            &[(BINDING_GBUF_NORMAL, SAMPLED, FRAGMENT), (BINDING_GBUF_DEPTH, SAMPLED, FRAGMENT)],
            1,
        )?;
        let set = set_layout.allocate(
            name,
            &[
                DescriptorWrite::Sampled(
                    BINDING_GBUF_NORMAL,
                    targets.gbuf_normal.view(),
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
            name,
            "specular/single.frag",
            &[frame_layout, &set_layout],
            &render_pass,
            &[spec],
        )?;
        let framebuffer = Framebuffer::new(ctx, name, &render_pass, &[targets.hdr.view()], targets.extent())?;
        Ok(SpecularSinglePass {
            name,
            render_pass,
            _set_layout: set_layout,
            set,
            _layout: layout,
            pipeline,
            framebuffer,
        })
    }

    pub fn record<'a>(
        &'a self,
        frame: &mut Frame<'_, 'a>,
        scene: &GpuScene,
        targets: &Targets,
        frame_set: DescriptorSet,
    ) {
        frame
            .pass(self.name)
            .read(targets.gbuf_normal_id, Access::FragmentSampled)
            .read(targets.depth_id, Access::FragmentSampled)
            .read(scene.environment_id, Access::FragmentSampled)
            .write(targets.hdr_id, Access::ColorAttachment)
            .record(move |cmd| {
                cmd.begin_render_pass(&self.render_pass, &self.framebuffer, &[Clear::None]);
                cmd.bind_graphics(&self.pipeline, &[frame_set, self.set]);
                cmd.draw(3, 1);
                cmd.end_render_pass();
            });
    }
}
