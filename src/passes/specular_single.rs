//! The single-interface baseline for specular surfaces (glsl/specular/single.frag): one
//! reflection and one refraction of the view ray at the first surface, each looked up in
//! the environment, weighted by exact Fresnel. With `Mode::Refraction` it shades dielectrics
//! (`refraction_single`), with `Mode::Reflection` mirrors and conductors (`reflection_single`).
//! It is the "1-sided refraction" baseline of Wyman 2005 (Table 1) against which every
//! refraction technique's cost is compared.
use std::sync::Arc;

use crate::gpu::{DescriptorSet, DescriptorSetLayout, GpuContext, GpuResult, Sampler};
use crate::graph::Frame;
use crate::renderer::gpu_scene::GpuScene;
use crate::renderer::plan::{REFLECTION_SINGLE, REFRACTION_SINGLE};
use crate::renderer::targets::Targets;
use crate::{BINDING_GBUF_DEPTH, BINDING_GBUF_NORMAL, SPECULAR_MODE_REFLECTION, SPECULAR_MODE_REFRACTION};

use super::fullscreen::{FullscreenDesc, FullscreenPass};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Refraction,
    Reflection,
}

pub struct SpecularSinglePass {
    pass: FullscreenPass,
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
        let pass = FullscreenPass::new(
            ctx,
            &FullscreenDesc {
                name,
                fragment_shader: "specular/single.frag",
                inputs: &[(BINDING_GBUF_NORMAL, &targets.gbuf_normal), (BINDING_GBUF_DEPTH, &targets.depth)],
                target: (&targets.hdr, targets.hdr_id),
                // Keeps the deferred result and overwrites only the pixels of its materials.
                clear: false,
                specialization: &[spec],
            },
            frame_layout,
            nearest,
        )?;
        Ok(SpecularSinglePass { pass })
    }

    pub fn record<'a>(
        &'a self,
        frame: &mut Frame<'_, 'a>,
        scene: &GpuScene,
        targets: &Targets,
        frame_set: DescriptorSet,
    ) {
        self.pass.record(frame, frame_set, &[targets.gbuf_normal_id, targets.depth_id, scene.environment_id]);
    }
}
