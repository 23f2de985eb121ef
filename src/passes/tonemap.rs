//! Tone map to 8-bit sRGB for PNG output: srgb_oetf(clamp(exposure * L, 0, 1)) (SCENES.md).
use std::sync::Arc;

use crate::gpu::{DescriptorSet, DescriptorSetLayout, GpuContext, GpuResult, Sampler};
use crate::graph::Frame;
use crate::renderer::plan::TONEMAP;
use crate::renderer::targets::Targets;
use crate::BINDING_HDR;

use super::fullscreen::{FullscreenDesc, FullscreenPass};

pub struct TonemapPass {
    pass: FullscreenPass,
}

impl TonemapPass {
    pub fn new(
        ctx: &Arc<GpuContext>,
        frame_layout: &DescriptorSetLayout,
        targets: &Targets,
        nearest: &Sampler,
    ) -> GpuResult<Self> {
        let pass = FullscreenPass::new(
            ctx,
            &FullscreenDesc {
                name: TONEMAP,
                fragment_shader: "tonemap/tonemap.frag",
                inputs: &[(BINDING_HDR, &targets.hdr)],
                target: (&targets.ldr, targets.ldr_id),
                clear: true,
                specialization: &[],
            },
            frame_layout,
            nearest,
        )?;
        Ok(TonemapPass { pass })
    }

    pub fn record<'a>(&'a self, frame: &mut Frame<'_, 'a>, targets: &Targets, frame_set: DescriptorSet) {
        self.pass.record(frame, frame_set, &[targets.hdr_id]);
    }
}
