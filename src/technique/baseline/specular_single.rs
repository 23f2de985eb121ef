//! The single-interface baseline for specular surfaces (glsl/specular/single.frag): one
//! reflection and one refraction of the view ray at the first surface, each looked up in
//! the environment, weighted by exact Fresnel. With `Mode::Refraction` it shades dielectrics
//! (`refraction_single`), with `Mode::Reflection` mirrors and conductors (`reflection_single`).
//! It is the "1-sided refraction" baseline of Wyman 2005 (Table 1) against which every
//! refraction technique's cost is compared.
use std::sync::Arc;

use crate::frame::targets::Targets;
use crate::gpu::{DescriptorSetLayout, GpuContext, GpuResult, Sampler, Spec};
use crate::graph::Frame;
use crate::scene::Scene;
use crate::technique::{
    dielectric_names, list, metal_names, no_inputs, FrameInputs, PlannedPass, Registration, Stage, Technique,
};
use crate::{SPECULAR_MODE_REFLECTION, SPECULAR_MODE_REFRACTION};

use super::fullscreen::{fragment_set, FullscreenDesc, FullscreenPass};

pub const REFRACTION_SINGLE: &str = "refraction_single";
pub const REFLECTION_SINGLE: &str = "reflection_single";

/// `render.refraction = "single"`: the dielectrics' baseline.
pub const REFRACTION: Registration = Registration {
    key: "refraction = \"single\"",
    plan: |scene| plan(scene, Mode::Refraction),
    create: |s| Ok(Box::new(SpecularSinglePass::new(s.ctx, Mode::Refraction, s.frame_layout, s.targets, s.nearest)?)),
    inputs: no_inputs,
};

/// `render.reflection = "single"`: the mirrors' and conductors' baseline.
pub const REFLECTION: Registration = Registration {
    key: "reflection = \"single\"",
    plan: |scene| plan(scene, Mode::Reflection),
    create: |s| Ok(Box::new(SpecularSinglePass::new(s.ctx, Mode::Reflection, s.frame_layout, s.targets, s.nearest)?)),
    inputs: no_inputs,
};

fn plan(scene: &Scene, mode: Mode) -> Vec<(Stage, PlannedPass)> {
    let (objects, selected, stage, name, what) = match mode {
        Mode::Refraction => (
            dielectric_names(scene),
            &scene.render.refraction,
            Stage::Refraction,
            REFRACTION_SINGLE,
            "dielectric {} (render.refraction = \"single\")",
        ),
        Mode::Reflection => (
            metal_names(scene),
            &scene.render.reflection,
            Stage::Reflection,
            REFLECTION_SINGLE,
            "mirror/conductor {} (render.reflection = \"single\")",
        ),
    };
    if objects.is_empty() || selected != "single" {
        return Vec::new();
    }
    vec![(stage, PlannedPass::new(name, what.replace("{}", &list(&objects))))]
}

impl Technique for SpecularSinglePass {
    fn record<'a>(&'a self, _: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        let (scene, frame_set) = (inputs.scene, inputs.frame_set);
        self.pass.record(frame, frame_set, &[scene.environment_id]);
    }
}

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
            // Overwrites only the pixels of its materials.
            &FullscreenDesc::over_hdr(name, "specular/single.frag", targets, &[("MODE", Spec::U32(spec))]),
            targets.gbuffer(fragment_set(), nearest, false),
            frame_layout,
        )?;
        Ok(SpecularSinglePass { pass })
    }
}
