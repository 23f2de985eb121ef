//! Exact ray tracing of the specular objects, interactive: the reference's light transport
//! at one centre ray per pixel, so that each approximation can be weighed against exact ray
//! tracing at equal time (glsl/raytrace/raytrace.frag).
//!
//! What it computes is the reference's model (src/reference/mod.rs), SCENES.md's "light
//! transport measured", without the caustics. Every pixel the G-buffer gives to a dielectric
//! (`render.refraction = "raytrace"`, pass `refraction_raytrace`) or to a mirror or conductor
//! (`render.reflection = "raytrace"`, `reflection_raytrace`) traces the ray through its centre
//! from the camera, through the reference's BVH and exact spheres
//! (glsl/reference/trace.glsl, the same code and buffers), along the exact specular chain:
//! mirror reflectance, conductor Fresnel, and at a dielectric *both* branches, the reflected
//! one weighted by exact Fresnel F and the refracted one by 1 - F, with Snell, total internal
//! reflection, Beer-Lambert absorption, the (n_i/n_t)^2 radiance scaling and, for an RGB ior,
//! one branch tree per channel. Where the reference chooses a branch with probability F and
//! converges to their sum, this sums them once (deterministic splitting). A branch ends
//! - at the environment, with its radiance;
//! - at a diffuse surface, which gathers what the reference's camera path gathers there
//!   (glsl/reference/paths.glsl): direct light with exact shadow rays, and the environment
//!   through one cosine-weighted specular chain, sampled the same way in every frame;
//! - after `max_depth` specular interactions (the reference's `max_depth`, and its default);
//! - when its largest throughput channel falls below `cutoff` (the (n_i/n_t)^2 scaling
//!   included, so a branch dropped inside a dielectric of index n would have carried at most
//!   `cutoff * n^2` out of it).
//!
//! Not computed: the caustics (light reaching a diffuse surface through specular chains),
//! which the reference gathers from photons; they stay out of this technique. Graded-index
//! volumes are crossed as the reference crosses them (glsl/reference/volume.glsl).
//!
//! It composites like the other techniques of its stage: a full-screen pass over the HDR
//! image that keeps every pixel not of its objects. The tracer's buffers are built once per
//! geometry and kept in the technique cache, so a moved camera or light re-creates only the
//! uniforms and the pass.
use std::rc::Rc;

use crate::gpu::{Buffer, Spec};
use crate::graph::Frame;
use crate::reference::TraceGeometry;
use crate::scene::techniques::RaytraceParams;
use crate::scene::Scene;
use crate::technique::baseline::fullscreen::{fragment_set, FullscreenDesc, FullscreenPass};
use crate::technique::baseline::specular_single::Mode;
use crate::technique::{
    dielectric_names, list, metal_names, params, tables_and_placement, FrameInputs, Inputs, PlannedPass, Registration,
    RenderError, Setup, Stage, Technique,
};
use crate::*;

pub const REFRACTION_RAYTRACE: &str = "refraction_raytrace";
pub const REFLECTION_RAYTRACE: &str = "reflection_raytrace";

/// `render.refraction = "raytrace"`: the dielectrics, traced exactly.
pub const REFRACTION: Registration = Registration {
    key: "refraction = \"raytrace\"",
    plan: |scene| plan(scene, Mode::Refraction),
    create: |s| create(s, Mode::Refraction),
    inputs,
};

/// `render.reflection = "raytrace"`: the mirrors and conductors, traced exactly.
pub const REFLECTION: Registration = Registration {
    key: "reflection = \"raytrace\"",
    plan: |scene| plan(scene, Mode::Reflection),
    create: |s| create(s, Mode::Reflection),
    inputs,
};

/// Its parameters, and where things are: the tracer's triangles, spheres and lights.
fn inputs(scene: &Scene) -> Inputs {
    tables_and_placement(scene, &["raytrace"])
}

// Set 1 holds the tracer's buffers at their REF_BINDING_* and the G-buffer's albedo (object
// index) and depth at theirs: those must not meet.
const _: () = {
    let tracer = [
        REF_BINDING_UNIFORMS,
        REF_BINDING_VERTICES,
        REF_BINDING_TRIANGLES,
        REF_BINDING_NODES,
        REF_BINDING_SPHERES,
        REF_BINDING_OBJECTS,
        REF_BINDING_VOLUME,
    ];
    let mut i = 0;
    while i < tracer.len() {
        assert!(tracer[i] != BINDING_GBUF_ALBEDO && tracer[i] != BINDING_GBUF_DEPTH);
        i += 1;
    }
};

fn plan(scene: &Scene, mode: Mode) -> Vec<(Stage, PlannedPass)> {
    let (objects, selected, stage, name, what) = match mode {
        Mode::Refraction => {
            (dielectric_names(scene), &scene.render.refraction, Stage::Refraction, REFRACTION_RAYTRACE, "dielectric")
        }
        Mode::Reflection => {
            (metal_names(scene), &scene.render.reflection, Stage::Reflection, REFLECTION_RAYTRACE, "mirror/conductor")
        }
    };
    if objects.is_empty() || selected != "raytrace" {
        return Vec::new();
    }
    let effect = if mode == Mode::Refraction { "refraction" } else { "reflection" };
    vec![(
        stage,
        PlannedPass::new(name, format!("{what} {} traced exactly (render.{effect} = \"raytrace\")", list(&objects))),
    )]
}

struct Raytrace {
    pass: FullscreenPass,
    // Bound in the pass's set 1.
    _uniforms: Buffer,
    geometry: Rc<crate::technique::Timed<TraceGeometry>>,
}

fn create(s: &mut Setup<'_>, mode: Mode) -> Result<Box<dyn Technique>, RenderError> {
    let p = params("raytrace", RaytraceParams::from_settings(&s.scene.render))?;
    let (ctx, scene) = (s.ctx, s.scene);
    let timed = s.cache.get_or_try_insert_timed(TraceGeometry::key(scene), || TraceGeometry::new(ctx, scene))?;
    let geometry = &timed.value;
    let (name, spec) = match mode {
        Mode::Refraction => (REFRACTION_RAYTRACE, SPECULAR_MODE_REFRACTION),
        Mode::Reflection => (REFLECTION_RAYTRACE, SPECULAR_MODE_REFLECTION),
    };
    let uniforms = geometry.uniforms(scene, s.gpu, p.max_depth).with_cutoff(p.cutoff);
    let uniforms = Buffer::storage(ctx, &format!("{name}_uniforms"), std::slice::from_ref(&uniforms))?;
    // Host-written once at creation (the graph tracks images only): visible at submission.
    let targets = s.targets;
    let mut set = fragment_set()
        .sampled(BINDING_GBUF_ALBEDO, &targets.gbuf_albedo, s.nearest)
        .read(targets.gbuf_albedo_id)
        .sampled(BINDING_GBUF_DEPTH, &targets.depth, s.nearest)
        .read(targets.depth_id)
        .storage(REF_BINDING_UNIFORMS, &uniforms)
        .storage(REF_BINDING_VERTICES, &s.gpu.vertices);
    for (binding, buffer) in geometry.buffers() {
        set = set.storage(binding, buffer);
    }
    let pass = FullscreenPass::new(
        ctx,
        // Overwrites only the pixels of its objects.
        &FullscreenDesc::over_hdr(name, "raytrace/raytrace.frag", targets, &[("MODE", Spec::U32(spec))]),
        set,
        s.frame_layout,
    )?;
    Ok(Box::new(Raytrace { pass, _uniforms: uniforms, geometry: timed }))
}

impl Technique for Raytrace {
    fn record<'a>(&'a self, _: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        self.pass.record(frame, inputs.frame_set, &[inputs.scene.environment_id]);
    }

    fn once_costs(&self) -> Vec<crate::technique::OnceCost> {
        vec![crate::technique::trace_geometry_cost(&self.geometry)]
    }
}
