//! The shape shared by full-screen passes: one triangle, a fragment shader reading set 0
//! (frame) and a set 1 of its own, writing one colour target. Deferred shading, the
//! specular baseline and the tone map are each this plus their own reads.
use std::sync::Arc;

use crate::frame::targets::Targets;
use crate::gpu::{
    vk, Access, Clear, DescriptorSet, DescriptorSetLayout, GpuContext, GpuResult, GraphicsPipeline,
    GraphicsPipelineDesc, Image, RenderTarget, Specs,
};
use crate::graph::{Bindings, BoundSet, Frame, ImageId};

pub struct FullscreenPass {
    name: &'static str,
    target: RenderTarget,
    set: BoundSet,
    pipeline: GraphicsPipeline,
    clear: bool,
    target_id: ImageId,
}

pub struct FullscreenDesc<'a> {
    /// Pass name (snake_case; timing, label and golden-image name).
    pub name: &'static str,
    /// Fragment shader under glsl/ (the vertex shader is common/fullscreen.vert).
    pub fragment_shader: &'a str,
    pub target: (&'a Image, ImageId),
    /// Clear the target first (true) or keep what earlier passes wrote (false).
    pub clear: bool,
    /// Specialisation constants of the fragment shader, by name.
    pub specialization: Specs<'a>,
}

impl<'a> FullscreenDesc<'a> {
    /// A pass composited into the HDR image: it keeps what earlier passes wrote there and
    /// overwrites the pixels its shader writes (a specular object, a volume, a receiver).
    pub fn over_hdr(
        name: &'static str,
        fragment_shader: &'a str,
        targets: &'a Targets,
        specialization: Specs<'a>,
    ) -> Self {
        FullscreenDesc { name, fragment_shader, target: (&targets.hdr, targets.hdr_id), clear: false, specialization }
    }
}

/// Set 1 of a full-screen pass: fragment-stage resources.
pub fn fragment_set<'a>() -> Bindings<'a> {
    Bindings::new(vk::ShaderStageFlags::FRAGMENT)
}

impl FullscreenPass {
    /// The pass of `desc` with `set` as its set 1 (its tracked resources are the pass's reads).
    pub fn new(
        ctx: &Arc<GpuContext>,
        desc: &FullscreenDesc<'_>,
        set: Bindings<'_>,
        frame_layout: &DescriptorSetLayout,
    ) -> GpuResult<Self> {
        let (target, target_id) = desc.target;
        let render_target = RenderTarget::new(ctx, desc.name, &[target], None, desc.clear)?;
        let set = set.build(ctx, desc.name)?;
        let pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                specialization: desc.specialization,
                ..GraphicsPipelineDesc::fullscreen(desc.name, desc.fragment_shader)
            },
            &[frame_layout, set.layout()],
            0,
            &render_target.pass,
        )?;
        Ok(FullscreenPass { name: desc.name, target: render_target, set, pipeline, clear: desc.clear, target_id })
    }

    /// Add the pass to `frame`: its set's reads, and `reads` of the frame set (set 0) in
    /// its fragment shader.
    pub fn record<'a>(&'a self, frame: &mut Frame<'_, 'a>, frame_set: DescriptorSet, reads: &[ImageId]) {
        let mut pass = frame.pass(self.name).uses(&self.set);
        for &id in reads {
            pass = pass.read(id, Access::FragmentSampled);
        }
        pass.write(self.target_id, Access::ColorAttachment).record(move |cmd| {
            let clear = if self.clear { Clear::Color([0.0; 4]) } else { Clear::None };
            cmd.in_target(&self.target, 0, &[clear], |cmd| {
                cmd.bind_graphics(&self.pipeline, &[frame_set, self.set.set()]);
                cmd.draw(3, 1);
            });
        });
    }
}
