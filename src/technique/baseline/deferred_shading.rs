//! Deferred shading of diffuse surfaces (direct light with shadow maps, environment
//! irradiance) and the environment background: glsl/shading/deferred.frag.
use std::sync::Arc;

use crate::frame::targets::Targets;
use crate::gpu::{DescriptorSetLayout, GpuContext, GpuResult, Sampler, Spec, Specs};
use crate::graph::{Frame, ImageId};
use crate::scene::techniques::CausticsMapParams;
use crate::scene::Scene;
use crate::technique::{
    diffuse_names, list, params, scene_specialization, tables, FrameInputs, Inputs, PlannedPass, Registration,
    RenderError, Setup, Stage, Technique,
};

use super::fullscreen::{fragment_set, FullscreenDesc, FullscreenPass};

pub const DEFERRED_SHADING: &str = "deferred_shading";

/// Baseline: every frame shades its diffuse surfaces and draws the environment behind them.
pub const TECHNIQUE: Registration = Registration {
    key: DEFERRED_SHADING,
    plan,
    create,
    // Which caustic technique runs decides what it reads, with caustics mapping's filter and
    // the photon buffer's rectangles and normalisation.
    // The photon rectangles (their count) follow the receivers.
    inputs: |scene| Inputs {
        settings: CausticReads::settings(scene),
        placement: scene.render.caustics == "photon_buffer",
    },
};

fn plan(scene: &crate::scene::Scene) -> Vec<(Stage, PlannedPass)> {
    let diffuse = diffuse_names(scene);
    let reason = if diffuse.is_empty() {
        "environment background (no diffuse object)".to_string()
    } else if scene.lights.is_empty() {
        format!("environment background; diffuse {} lit by the environment only", list(&diffuse))
    } else {
        format!("environment background; diffuse {} lit by {} light(s)", list(&diffuse), scene.lights.len())
    };
    vec![(Stage::Shading, PlannedPass::new(DEFERRED_SHADING, reason))]
}

/// Reads whatever the shadow and caustic techniques planned before it.
fn create(s: &mut Setup<'_>) -> Result<Box<dyn Technique>, RenderError> {
    let caustics = CausticReads::new(s)?;
    let shadowed = s.planned(super::shadow_map::SHADOW_MAP);
    // Whether any object is diffuse is part of the shared fingerprint (the materials' kinds):
    // a change re-creates the renderer, and this pass with it.
    let diffuse = !diffuse_names(s.scene).is_empty();
    let mut scene = vec![("DIFFUSE", Spec::U32(u32::from(diffuse)))];
    scene.extend(scene_specialization(s.scene));
    Ok(Box::new(DeferredShadingPass::new(s.ctx, s.frame_layout, s.targets, s.nearest, shadowed, caustics, &scene)?))
}

/// The caustic textures a pass shading diffuse receivers reads (glsl/include/caustic_lookup.glsl),
/// from whichever caustic technique planned its passes: caustics mapping's atlas with its
/// low-pass filter radius, or the photon buffer's textures with their rectangle count and
/// normalisation.
#[derive(Clone, Copy, Debug)]
pub struct CausticReads {
    filter: Option<u32>,
    photon: Option<(u32, u32, ImageId)>,
}

impl CausticReads {
    pub fn new(s: &Setup<'_>) -> Result<Self, RenderError> {
        let filter = if s.planned(crate::technique::caustics::caustics_map::CAUSTICS_MAP) {
            Some(params("caustics_map", CausticsMapParams::from_settings(&s.scene.render))?.filter)
        } else {
            None
        };
        let c = s.photon_caustics;
        let photon =
            s.planned(crate::technique::caustics::photon_buffer::PHOTON_BUFFER).then_some((c.count, c.mode, c.id));
        Ok(CausticReads { filter, photon })
    }

    /// What the choice depends on: the caustic technique, caustics mapping's filter and the
    /// photon buffer's settings (its rectangles follow the receivers' placement).
    pub fn settings(scene: &Scene) -> String {
        let filter = CausticsMapParams::from_settings(&scene.render).map(|p| p.filter).ok();
        format!("{} {filter:?} {}", scene.render.caustics, tables(scene, &["photon_buffer"]))
    }

    /// The specialisation constants of caustic_lookup.glsl.
    pub fn specialization(&self) -> [(&'static str, Spec); 4] {
        [
            ("CAUSTICS", Spec::U32(u32::from(self.filter.is_some()))),
            ("CAUSTIC_FILTER", Spec::U32(self.filter.unwrap_or(0))),
            ("PHOTON_RECTS", Spec::U32(self.photon.map_or(0, |p| p.0))),
            ("PHOTON_MODE", Spec::U32(self.photon.map_or(0, |p| p.1))),
        ]
    }

    /// The images the lookups read this frame.
    pub fn reads(&self, targets: &Targets) -> Vec<ImageId> {
        let atlas = self.filter.map(|_| [targets.caustic.flux_id, targets.caustic.receivers_id]);
        atlas.into_iter().flatten().chain(self.photon.map(|p| p.2)).collect()
    }
}

impl Technique for DeferredShadingPass {
    fn record<'a>(&'a self, _: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        let (scene, targets, frame_set) = (inputs.scene, inputs.targets, inputs.frame_set);
        let mut reads = vec![scene.environment_id];
        if self.shadowed {
            reads.push(targets.shadow_atlas_id);
        }
        reads.extend(self.caustics.reads(targets));
        self.pass.record(frame, frame_set, &reads);
    }
}

pub struct DeferredShadingPass {
    pass: FullscreenPass,
    /// Whether a shadow_map pass writes the atlas this frame (then it is a declared read).
    shadowed: bool,
    /// The caustic textures written this frame, read by the lookups.
    caustics: CausticReads,
}

impl DeferredShadingPass {
    pub fn new(
        ctx: &Arc<GpuContext>,
        frame_layout: &DescriptorSetLayout,
        targets: &Targets,
        nearest: &Sampler,
        shadowed: bool,
        caustics: CausticReads,
        scene: Specs<'_>,
    ) -> GpuResult<Self> {
        let mut specialization = caustics.specialization().to_vec();
        specialization.extend_from_slice(scene);
        let pass = FullscreenPass::new(
            ctx,
            &FullscreenDesc {
                name: DEFERRED_SHADING,
                fragment_shader: "shading/deferred.frag",
                target: (&targets.hdr, targets.hdr_id),
                clear: true,
                specialization: &specialization,
                additive: false,
            },
            targets.gbuffer(fragment_set(), nearest, true),
            frame_layout,
        )?;
        Ok(DeferredShadingPass { pass, shadowed, caustics })
    }
}
