//! Single-interface refraction of nearby geometry: a water surface over the receivers it
//! covers, the scene of Shah, Konttinen & Pattanaik 2007 (../shared/papers/
//! shah2007-caustics-mapping.md, Fig. 1: "dynamic water caustic"; §III.E, single-surface
//! refraction, where the light "is refracted only once" and travels in the water to the
//! receiver). glsl/refraction/water.frag.
//!
//! `render.refraction = "water"`, pass `refraction_water`. At every pixel the G-buffer gives to
//! a dielectric, the ray through the pixel's centre meets the surface at the G-buffer's point
//! and refracts at its interpolated normal (both follow the window's animation of the water's
//! vertices), and splits there by exact Fresnel F:
//!
//! - the reflected branch, weight F, and the refracted one, weight (1 - F) (n_i/n_t)^2 (Snell;
//!   SCENES.md's radiance scaling, which a single interface does not cancel), each go on in a
//!   straight line to the first surface they meet, found by the exact tracer's BVH
//!   (glsl/reference/trace.glsl). Its bounds are those of the loaded time: an animated water
//!   surface may be missed by them, which the branches leaving the surface never need;
//! - a diffuse receiver there is shaded as deferred shading shades a visible one (direct light
//!   with the shadow maps, the environment's irradiance) plus the caustic the selected caustic
//!   technique put on it, so under the water the sun arrives as the caustic of
//!   `render.caustics = "caustics_map"` (or `"photon_buffer"`) and nowhere else: the shadow
//!   map holds the water;
//! - no surface: the environment in that direction. A second specular surface is not
//!   followed either (one interface: a closed refractor wants `wyman`, `hu_qin`, `impostor`
//!   or `raytrace`), and the environment is looked up in its place;
//! - Beer-Lambert absorption along the branch in the water.
//!
//! Why the exact receivers rather than Hu & Qin's impostor rectangles (§2.2): the tracer's
//! buffers already exist for `raytrace` and the reference, are built once per geometry and
//! kept in the technique cache, and give the exact hit for any receiver shape; the impostors'
//! iterative depth correction (Fig. 16) would add its own displacement to the ripples'.
use std::rc::Rc;

use crate::frame::gpu_scene::{environment_sh_below, GRID_SH_WIDTH};
use crate::gpu::Buffer;
use crate::graph::Frame;
use crate::reference::TraceGeometry;
use crate::scene::{Environment, Material, Scene};
use crate::technique::baseline::deferred_shading::CausticReads;
use crate::technique::baseline::fullscreen::{fragment_set, FullscreenDesc, FullscreenPass};
use crate::technique::scene_specialization;
use crate::technique::{
    dielectric_names, list, FrameInputs, Inputs, PlannedPass, Registration, RenderError, Setup, Stage, Technique,
};
use crate::*;

pub const REFRACTION_WATER: &str = "refraction_water";

/// `render.refraction = "water"`.
pub const TECHNIQUE: Registration = Registration {
    key: "refraction = \"water\"",
    plan,
    create,
    // The caustic textures it reads, the index its sky under the water is refracted with, and
    // where things are (the tracer's triangles).
    inputs: |scene| Inputs {
        settings: format!("{} ior {}", CausticReads::settings(scene), water_ior(scene)),
        placement: true,
    },
};

fn plan(scene: &Scene) -> Vec<(Stage, PlannedPass)> {
    let objects = dielectric_names(scene);
    if objects.is_empty() || scene.render.refraction != "water" {
        return Vec::new();
    }
    let reason = format!(
        "dielectric {} refracting and reflecting the nearby receivers once (render.refraction = \"water\")",
        list(&objects)
    );
    vec![(Stage::Refraction, PlannedPass::new(REFRACTION_WATER, reason))]
}

struct Water {
    pass: FullscreenPass,
    caustics: CausticReads,
    shadowed: bool,
    // Bound in the pass's set 1.
    _uniforms: Buffer,
    _sky: Buffer,
    geometry: Rc<crate::technique::Timed<TraceGeometry>>,
}

fn create(s: &mut Setup<'_>) -> Result<Box<dyn Technique>, RenderError> {
    let (ctx, scene) = (s.ctx, s.scene);
    let caustics = CausticReads::new(s)?;
    let shadowed = s.planned(crate::technique::baseline::shadow_map::SHADOW_MAP);
    let timed = s.cache.get_or_try_insert_timed(TraceGeometry::key(scene), || TraceGeometry::new(ctx, scene))?;
    let geometry = &timed.value;
    // max_depth is the tracer's; this pass follows one interaction and reads only the rest.
    let uniforms = geometry.uniforms(scene, s.gpu, 1);
    let uniforms = Buffer::storage(ctx, "refraction_water_uniforms", std::slice::from_ref(&uniforms))?;
    // Host-written once at creation (the graph tracks images only): visible at submission.
    let sky = Buffer::storage(ctx, "refraction_water_sky", &sky_below(scene))?;
    let targets = s.targets;
    let set = fragment_set()
        .sampled(BINDING_WATER_GBUF_NORMAL, &targets.gbuf_normal, s.nearest)
        .read(targets.gbuf_normal_id)
        .sampled(BINDING_GBUF_DEPTH, &targets.depth, s.nearest)
        .read(targets.depth_id)
        .storage(REF_BINDING_UNIFORMS, &uniforms)
        .storage(BINDING_WATER_SKY, &sky);
    let set = geometry.bind(s.gpu, set)?;
    let pass = FullscreenPass::new(
        ctx,
        // Overwrites only the pixels of the dielectrics.
        &FullscreenDesc::over_hdr(
            REFRACTION_WATER,
            "refraction/water.frag",
            targets,
            &[&caustics.specialization()[..], &scene_specialization(s.scene)[..]].concat(),
        ),
        set,
        s.frame_layout,
    )?;
    Ok(Box::new(Water { pass, caustics, shadowed, _uniforms: uniforms, _sky: sky, geometry: timed }))
}

/// The index of the water: the first dielectric's (green channel).
fn water_ior(scene: &Scene) -> f32 {
    let ior = scene.materials.iter().find_map(|m| match m {
        Material::Dielectric { ior, .. } => Some(ior.y),
        _ => None,
    });
    ior.unwrap_or(1.0)
}

/// The environment seen from under the water at rest (gpu_scene::environment_sh_below): the
/// receivers under the surface are lit by the sky through it only.
fn sky_below(scene: &Scene) -> Vec<[f32; 4]> {
    let ior = water_ior(scene);
    let (w, h, texels) = match &scene.environment {
        // Enough texels for the window's edge to be resolved.
        Environment::Constant(c) => (64, 32, vec![[c.x, c.y, c.z, 1.0]; 64 * 32]),
        Environment::Image { width, height, texels, .. } => (*width, *height, texels.clone()),
        Environment::Grid => {
            let (w, h) = (GRID_SH_WIDTH, GRID_SH_WIDTH / 2);
            (w, h, crate::scene::grid_texels(w, h))
        }
    };
    environment_sh_below(w, h, &texels, ior).to_vec()
}

impl Technique for Water {
    fn record<'a>(&'a self, _: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        let mut reads = vec![inputs.scene.environment_id];
        if self.shadowed {
            reads.push(inputs.targets.shadow_atlas_id);
        }
        reads.extend(self.caustics.reads(inputs.targets));
        self.pass.record(frame, inputs.frame_set, &reads);
    }

    fn once_costs(&self) -> Vec<crate::technique::OnceCost> {
        vec![crate::technique::trace_geometry_cost(&self.geometry)]
    }
}
