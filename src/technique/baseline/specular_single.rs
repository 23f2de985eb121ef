//! The single-interface baseline for specular surfaces (glsl/specular/single.frag): one
//! reflection and one refraction of the view ray at the first surface, each looked up in
//! the environment, weighted by exact Fresnel. With `Mode::Refraction` it shades dielectrics
//! (`refraction_single`), with `Mode::Reflection` mirrors and conductors (`reflection_single`).
//! It is the "1-sided refraction" baseline of Wyman 2005 (Table 1) against which every
//! refraction technique's cost is compared.
use crate::gpu::{GpuResult, Spec};
use crate::graph::Frame;
use crate::scene::{Material, Scene};
use crate::technique::scene_specialization;
use crate::technique::{
    dielectric_names, list, metal_names, no_inputs, FrameInputs, Inputs, PlannedPass, Registration, Setup, Stage,
    Technique,
};
use crate::{SPECULAR_MODE_REFLECTION, SPECULAR_MODE_REFRACTION};

use super::fullscreen::{fragment_set, FullscreenDesc, FullscreenPass};

pub const REFRACTION_SINGLE: &str = "refraction_single";
pub const REFLECTION_SINGLE: &str = "reflection_single";

/// `render.refraction = "single"`: the dielectrics' baseline.
pub const REFRACTION: Registration = Registration {
    key: "refraction = \"single\"",
    plan: |scene| plan(scene, Mode::Refraction),
    create: |s| Ok(Box::new(SpecularSinglePass::new(s, Mode::Refraction)?)),
    // Material values change in place; whether one disperses changes the shader.
    inputs: |scene| Inputs { settings: format!("dispersion {}", has_dispersion(scene)), placement: false },
};

/// `render.reflection = "single"`: the mirrors' and conductors' baseline.
pub const REFLECTION: Registration = Registration {
    key: "reflection = \"single\"",
    plan: |scene| plan(scene, Mode::Reflection),
    create: |s| Ok(Box::new(SpecularSinglePass::new(s, Mode::Reflection)?)),
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
        self.pass.record_covering(frame, inputs, &[inputs.scene.environment_id]);
    }
}

/// Whether some dielectric has a different ior per channel: only then does the refraction
/// need a lookup per channel (glsl/specular/single.frag, `DISPERSION`).
pub fn has_dispersion(scene: &Scene) -> bool {
    scene.materials.iter().any(|m| matches!(m, Material::Dielectric { ior, .. } if !(ior.x == ior.y && ior.y == ior.z)))
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
    /// The pass of `mode`, shading only its objects' pixels where it can
    /// ([`super::fullscreen::Cover`]).
    pub fn new(s: &Setup<'_>, mode: Mode) -> GpuResult<Self> {
        let (name, spec) = match mode {
            Mode::Refraction => (REFRACTION_SINGLE, SPECULAR_MODE_REFRACTION),
            Mode::Reflection => (REFLECTION_SINGLE, SPECULAR_MODE_REFLECTION),
        };
        let objects = (0..s.scene.objects.len())
            .filter(|&i| {
                let m = &s.scene.materials[s.scene.objects[i].material];
                match mode {
                    Mode::Refraction => matches!(m, Material::Dielectric { .. }),
                    Mode::Reflection => matches!(m, Material::Mirror { .. } | Material::Conductor { .. }),
                }
            })
            .collect();
        let pass = FullscreenPass::covering(
            s.ctx,
            // Overwrites only the pixels of its materials.
            &FullscreenDesc::over_hdr(
                name,
                "specular/single.frag",
                s.targets,
                &[
                    &[("MODE", Spec::U32(spec)), ("DISPERSION", Spec::U32(u32::from(has_dispersion(s.scene))))],
                    &scene_specialization(s.scene)[..],
                ]
                .concat(),
            ),
            s.targets.gbuffer(fragment_set(), s.nearest, false),
            s.frame_layout,
            objects,
        )?;
        Ok(SpecularSinglePass { pass })
    }
}
