//! Exact ray tracing of the specular objects, interactive: the reference's light transport
//! at one centre ray per pixel, so that each approximation can be weighed against exact ray
//! tracing at equal time (glsl/raytrace/raytrace.frag), and its caustics on the diffuse
//! surfaces seen directly (`render.caustics = "raytrace"`, glsl/raytrace/caustics.frag).
//!
//! What it computes is the reference's model (src/reference/mod.rs), SCENES.md's "light
//! transport measured". Every pixel the G-buffer gives to a dielectric
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
//! Caustics (light reaching a diffuse surface through specular chains) come from the
//! reference's photons, traced anew every frame: where the scene has a light, a specular
//! object and a diffuse receiver and `photons_per_frame` > 0, the pass is preceded by a
//! reset of the photon grid's heads and counter and by the reference's photon kernel
//! (glsl/reference/photons.comp, its buffers and its hashed grid, a new iteration each
//! frame), and every diffuse vertex a branch reaches (with `caustics = "raytrace"` also the
//! diffuse surface each diffuse pixel's centre ray meets) adds the photons' radiance estimate
//! within `gather_radius` pixel footprints (Jensen's photon-map estimate over the grid walk of
//! the reference's SPPM gather, glsl/reference/photon_grid.glsl). With a fixed radius the
//! estimate is biased by the blur over that disk and noisy as one frame's photons are; the
//! frames' mean converges to the caustic averaged over the disk. Graded-index volumes are
//! crossed as the reference crosses them (glsl/reference/volume.glsl).
//!
//! It composites like the other techniques of its stage: a full-screen pass over the HDR
//! image that keeps every pixel not of its objects (the caustic pass adds to the diffuse
//! pixels after deferred shading instead). The tracer's buffers are built once per geometry
//! and kept in the technique cache, so a moved camera or light re-creates only the uniforms,
//! the photon buffers and the passes. The `refraction`, `reflection` and `caustics`
//! techniques set to `"raytrace"` share a frame's photons through the technique cache: the
//! first of them in the frame traces them, every one gathers them.
//!
//! Progressive accumulation (`render.raytrace.accumulate` = N > 1, pass
//! `raytrace_accumulate`): while nothing changes, the image shown is the running mean of the
//! frames since the last change, frame n (from 0) blended in with weight 1/(n + 1), up to N
//! frames, after which the mean of the first N is held (glsl/raytrace/accumulate.comp). What
//! differs between frames is the photon batch alone, so the mean's caustic is the estimate of
//! N batches of photons, its noise 1/sqrt(N) of a frame's, and its bias the same blur over
//! the gathering disk; the rest of a frame is a function of the scene (the diffuse vertices'
//! environment chain is sampled the same way in every frame, and every ray goes through its
//! pixel's centre: a sub-pixel jitter would move the traced ray off the pixel the G-buffer
//! gave to the object, and antialias only the pixels inside its coverage), its own mean bit
//! for bit. Without photons nothing differs and nothing is accumulated. The mean is one
//! compute pass over the HDR image after the frame's last `raytrace` pass (the technique
//! that records it is the last one in the recipe), so that the refraction, reflection and
//! caustics of one frame are averaged together and every later pass (the tone map) reads the
//! mean as it would the frame; it lives in the technique, not in the renderer, because the
//! technique is what varies from frame to frame and knows whether it does. The frames it
//! costs are the frames `prism bench` times, plus that pass. Every change starts it again:
//! the camera ([`Technique::camera_moved`], from `Renderer::set_camera`), a live update
//! ([`Technique::restart`]; a resize or a changed parameter re-creates the technique), a
//! dragged object ([`Technique::objects_moved`]), rewritten materials or animated water
//! ([`Technique::contents_changed`]; with `render.update = "every_frame"` every frame is a
//! change, and nothing accumulates). The first frame after a change is that frame, bit for
//! bit the frame with `accumulate = 1`; with `accumulate = 1` there is no pass and every
//! frame is shown as traced.
use std::rc::Rc;
use std::sync::Arc;

use crate::frame::gpu_scene::GpuScene;
use crate::frame::targets::HDR_FORMAT;
use crate::gpu::GpuContext;
use crate::gpu::{vk, Access, Buffer, ComputePipeline, Image, ImageDesc, MemoryLocation, Sampler, SamplerDesc, Spec};
use crate::graph::{Bindings, BoundSet, BufferId, Frame, FrameGraph};
use crate::reference::{dispatch_size, initial_stats, photon_targets, TraceGeometry};
use crate::scene::techniques::RaytraceParams;
use crate::scene::Scene;
use crate::shader_structs::AccumulatePush;
use crate::shader_structs::RefPush;
use crate::shader_structs::RefUniforms;
use crate::technique::baseline::fullscreen::{fragment_set, FullscreenDesc, FullscreenPass};
use crate::technique::scene_specialization;
use crate::technique::{
    cache_key, dielectric_names, diffuse_names, list, metal_names, params, specular_names, tables_and_placement,
    FrameInputs, Inputs, PlannedPass, Registration, RenderError, Setup, Stage, Technique,
};
use crate::*;

pub const REFRACTION_RAYTRACE: &str = "refraction_raytrace";
pub const REFLECTION_RAYTRACE: &str = "reflection_raytrace";
pub const CAUSTICS_RAYTRACE: &str = "caustics_raytrace";
pub const VOLUME_RAYTRACE: &str = "volume_raytrace";
/// Each effect's photon passes: the grid's reset, then the photon kernel.
pub const REFRACTION_PHOTON_RESET: &str = "refraction_raytrace_photon_reset";
pub const REFRACTION_PHOTONS: &str = "refraction_raytrace_photons";
pub const REFLECTION_PHOTON_RESET: &str = "reflection_raytrace_photon_reset";
pub const REFLECTION_PHOTONS: &str = "reflection_raytrace_photons";
pub const CAUSTICS_PHOTON_RESET: &str = "caustics_raytrace_photon_reset";
pub const CAUSTICS_PHOTONS: &str = "caustics_raytrace_photons";
pub const VOLUME_PHOTON_RESET: &str = "volume_raytrace_photon_reset";
pub const VOLUME_PHOTONS: &str = "volume_raytrace_photons";
/// The running mean of the frames since the last change (`render.raytrace.accumulate`).
pub const RAYTRACE_ACCUMULATE: &str = "raytrace_accumulate";

/// The grid's empty bucket (photon_grid.glsl's END_OF_LIST).
const END_OF_PHOTON_LIST: u32 = u32::MAX;

/// The photon kernel's seed: not the reference's (1 by default), so that a test comparing
/// the two compares independent photons. Frame k (from 0) traces the photons of the
/// reference's photon pass k with this seed and as many photons per pass (photons.comp), which
/// a test reads back from the reference.
pub const PHOTON_SEED: u32 = 0x5eed_ca05;

/// What a `raytrace` technique puts into the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Effect {
    /// The dielectrics' pixels, traced.
    Refraction,
    /// The mirrors' and conductors' pixels, traced.
    Reflection,
    /// The caustic on the diffuse pixels seen directly, added to deferred shading's.
    Caustics,
    /// Every pixel of the frame, traced from the camera through the `[volume]` (as the
    /// reference crosses it) and everything else: the whole frame exact.
    Volume,
}

impl Effect {
    /// (stage, fragment pass, photon grid reset, photon kernel).
    fn passes(self) -> (Stage, &'static str, &'static str, &'static str) {
        match self {
            Effect::Refraction => (Stage::Refraction, REFRACTION_RAYTRACE, REFRACTION_PHOTON_RESET, REFRACTION_PHOTONS),
            Effect::Reflection => (Stage::Reflection, REFLECTION_RAYTRACE, REFLECTION_PHOTON_RESET, REFLECTION_PHOTONS),
            // After deferred shading, whose diffuse radiance it adds to.
            Effect::Caustics => (Stage::Lighting, CAUSTICS_RAYTRACE, CAUSTICS_PHOTON_RESET, CAUSTICS_PHOTONS),
            // The eikonal view pass's stage, which it replaces.
            Effect::Volume => (Stage::Volume, VOLUME_RAYTRACE, VOLUME_PHOTON_RESET, VOLUME_PHOTONS),
        }
    }
}

/// `render.refraction = "raytrace"`: the dielectrics, traced exactly.
pub const REFRACTION: Registration = Registration {
    key: "refraction = \"raytrace\"",
    plan: |scene| plan(scene, Effect::Refraction),
    create: |s| create(s, Effect::Refraction),
    inputs,
};

/// `render.reflection = "raytrace"`: the mirrors and conductors, traced exactly.
pub const REFLECTION: Registration = Registration {
    key: "reflection = \"raytrace\"",
    plan: |scene| plan(scene, Effect::Reflection),
    create: |s| create(s, Effect::Reflection),
    inputs,
};

/// `render.volume = "raytrace"`: a `[volume]` scene's whole frame traced exactly, in place of
/// eikonal rendering.
pub const VOLUME: Registration = Registration {
    key: "volume = \"raytrace\"",
    plan: |scene| plan(scene, Effect::Volume),
    create: |s| create(s, Effect::Volume),
    inputs,
};

/// `render.caustics = "raytrace"`: the photons' caustic on the diffuse surfaces seen directly,
/// so that `refraction = reflection = caustics = "raytrace"` traces the whole frame's light
/// transport exactly.
pub const CAUSTICS: Registration = Registration {
    key: "caustics = \"raytrace\"",
    plan: |scene| plan(scene, Effect::Caustics),
    create: |s| create(s, Effect::Caustics),
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
        REF_BINDING_PHOTONS,
        REF_BINDING_GRID,
    ];
    let mut i = 0;
    while i < tracer.len() {
        assert!(tracer[i] != BINDING_GBUF_ALBEDO && tracer[i] != BINDING_GBUF_DEPTH);
        i += 1;
    }
};

/// Whether the technique traces photons for `scene`: a light, a diffuse receiver and a
/// photon budget (its objects are the specular casters), as the caustics techniques decide.
fn has_caustics(scene: &Scene) -> bool {
    let photons = RaytraceParams::from_settings(&scene.render).map_or(0, |p| p.photons_per_frame);
    photons > 0 && !scene.lights.is_empty() && !diffuse_names(scene).is_empty()
}

/// What the photons are aimed at: the specular objects and the `[volume]`
/// (src/reference/mod.rs `photon_targets`).
fn casters(scene: &Scene) -> Vec<String> {
    let mut names = specular_names(scene);
    names.extend(scene.volume.iter().map(|v| v.name.clone()));
    names
}

/// Whether `effect` is selected in `scene` and has something to trace: the `[render]` key that
/// selects it and the reason for its pass.
fn selection(scene: &Scene, effect: Effect) -> Option<(&'static str, String)> {
    let (objects, selected, key, reason) = match effect {
        Effect::Refraction => {
            let objects = dielectric_names(scene);
            let reason = format!("dielectric {} traced exactly", list(&objects));
            (objects, &scene.render.refraction, "refraction", reason)
        }
        Effect::Reflection => {
            let objects = metal_names(scene);
            let reason = format!("mirror/conductor {} traced exactly", list(&objects));
            (objects, &scene.render.reflection, "reflection", reason)
        }
        Effect::Caustics => {
            // No light, no receiver or no photons: no caustic to add.
            if !has_caustics(scene) {
                return None;
            }
            let objects = casters(scene);
            let reason =
                format!("photons' caustic of {} on {} seen directly", list(&objects), list(&diffuse_names(scene)));
            (objects, &scene.render.caustics, "caustics", reason)
        }
        Effect::Volume => {
            let Some(v) = &scene.volume else { return None };
            let reason = format!("volume {} and the whole frame traced exactly from the camera", v.name);
            (vec![v.name.clone()], &scene.render.volume, "volume", reason)
        }
    };
    (!objects.is_empty() && selected == "raytrace").then_some((key, reason))
}

/// The `raytrace` technique that traces the frame's photons, which every `raytrace` technique
/// of the frame gathers: the first in the recipe (caustics after shading, then refraction,
/// then reflection, then the whole frame of a volume), where the scene has caustics.
fn photon_owner(scene: &Scene) -> Option<Effect> {
    if !has_caustics(scene) {
        return None;
    }
    [Effect::Caustics, Effect::Refraction, Effect::Reflection, Effect::Volume]
        .into_iter()
        .find(|&e| selection(scene, e).is_some())
}

/// `render.raytrace.accumulate`: the frames the running mean averages at most (1: none).
fn accumulation(scene: &Scene) -> u32 {
    RaytraceParams::from_settings(&scene.render).map_or(1, |p| p.accumulate)
}

/// The `raytrace` technique that keeps the running mean: the last in the recipe, so that the
/// mean is taken of the image every `raytrace` pass of the frame has written, where
/// `render.raytrace.accumulate` > 1 and the frames differ: where photons are traced
/// ([`has_caustics`]). Without photons every frame is the same image, its own mean.
fn accumulator(scene: &Scene) -> Option<Effect> {
    if accumulation(scene) <= 1 || !has_caustics(scene) {
        return None;
    }
    [Effect::Caustics, Effect::Refraction, Effect::Reflection, Effect::Volume]
        .into_iter()
        .rev()
        .find(|&e| selection(scene, e).is_some())
}

fn plan(scene: &Scene, effect: Effect) -> Vec<(Stage, PlannedPass)> {
    let (stage, name, reset, photons) = effect.passes();
    let Some((key, reason)) = selection(scene, effect) else { return Vec::new() };
    let mut passes = Vec::new();
    if photon_owner(scene) == Some(effect) {
        let why = format!(
            "caustics of {} on {} (render.raytrace.photons_per_frame)",
            list(&casters(scene)),
            list(&diffuse_names(scene))
        );
        passes.push((stage, PlannedPass::new(reset, format!("photon grid reset: {why}"))));
        passes.push((stage, PlannedPass::new(photons, format!("photons from the lights: {why}"))));
    }
    passes.push((stage, PlannedPass::new(name, format!("{reason} (render.{key} = \"raytrace\")"))));
    if accumulator(scene) == Some(effect) {
        let why = format!(
            "mean of up to {} frames of the photons' caustic while nothing changes (render.raytrace.accumulate)",
            accumulation(scene)
        );
        passes.push((stage, PlannedPass::new(RAYTRACE_ACCUMULATE, why)));
    }
    passes
}

/// The reference's photon kernel (glsl/reference/photons.comp) with its buffers, in set 0 as
/// the reference binds them.
struct PhotonKernel {
    pipeline: ComputePipeline,
    set: BoundSet,
    groups: [u32; 3],
    counters: Buffer,
    counters_id: BufferId,
    /// The kernel's records of every photon (flux and outcome, where it was deposited) and
    /// the loop canary's counts: written, never read here.
    _debug: Buffer,
    _stats: Buffer,
    _sampler: Sampler,
    /// What the kernel reads of the tracer's uniforms (the lights, the targets, the photon
    /// counts, max_depth).
    _uniforms: Buffer,
}

/// A frame's photons, shared by the frame's `raytrace` techniques through the technique
/// cache: the photon map (the photons and the grid's heads) that they gather from, and the
/// kernel that the owner ([`photon_owner`]) runs. Without caustics the map is a stand-in of
/// one element, bound but never read (ref.photon.x = 0), and there is no kernel.
struct Photons {
    photons: Buffer,
    photons_id: BufferId,
    grid: Buffer,
    grid_id: BufferId,
    kernel: Option<PhotonKernel>,
    _geometry: Rc<crate::technique::Timed<TraceGeometry>>,
}

/// The running mean of the frames since the last change (glsl/raytrace/accumulate.comp), in
/// an image of its own, written back over the frame's HDR image.
///
/// It lives in the technique rather than in the renderer because what varies between frames,
/// and so what there is to average, is the technique's own (its photon batches): the
/// renderer's other images are functions of the scene, and a technique that does not vary
/// has no mean to show. It is one pass over the HDR image after the last `raytrace` pass,
/// rather than a mean per pass, so that the refraction, reflection and caustics passes of
/// one frame are averaged once, together, and the passes after it (a tone map, another
/// stage's technique) read the mean as they would read the frame.
struct Accumulation {
    pipeline: ComputePipeline,
    set: BoundSet,
    groups: [u32; 3],
    /// `render.raytrace.accumulate`.
    limit: u32,
    size: (u32, u32),
    /// The mean, bound in the set.
    _mean: Image,
}

struct Raytrace {
    pass: FullscreenPass,
    /// The running mean, where this technique keeps it ([`accumulator`]).
    accumulation: Option<Accumulation>,
    /// The frames begun since the last change (camera, scene, objects, contents), and of
    /// them those before the frame being recorded: its weight in the mean is 1/(frames + 1).
    since_change: u32,
    frames: u32,
    photons: Rc<Photons>,
    /// The names of the photon passes, where this technique records them.
    owner: Option<(&'static str, &'static str)>,
    /// The photon kernel's iteration: the frames begun before this one, so that every frame
    /// traces new photons.
    iteration: u32,
    begun: u32,
    // Bound in the pass's set 1.
    _uniforms: Buffer,
    geometry: Rc<crate::technique::Timed<TraceGeometry>>,
}

fn create(s: &mut Setup<'_>, effect: Effect) -> Result<Box<dyn Technique>, RenderError> {
    let p = params("raytrace", RaytraceParams::from_settings(&s.scene.render))?;
    let (ctx, scene) = (s.ctx, s.scene);
    let timed = s.cache.get_or_try_insert_timed(TraceGeometry::key(scene), || TraceGeometry::new(ctx, scene))?;
    let geometry = &timed.value;
    let (_, name, reset, trace) = effect.passes();
    let refraction = [("MODE", Spec::U32(SPECULAR_MODE_REFRACTION))];
    let reflection = [("MODE", Spec::U32(SPECULAR_MODE_REFLECTION))];
    let frame = [("MODE", Spec::U32(RAYTRACE_MODE_FRAME))];
    let (shader, mode): (_, &[_]) = match effect {
        Effect::Refraction => ("raytrace/raytrace.frag", &refraction),
        Effect::Reflection => ("raytrace/raytrace.frag", &reflection),
        Effect::Caustics => ("raytrace/caustics.frag", &[]),
        Effect::Volume => ("raytrace/raytrace.frag", &frame),
    };
    let spec = &[mode, &scene_specialization(scene)[..]].concat();
    let mut uniforms = geometry.uniforms(scene, s.gpu, p.max_depth).with_cutoff(p.cutoff);
    let count = if has_caustics(scene) { p.photons_per_frame } else { 0 };
    // The reference's photon map for `count` photons (src/reference/mod.rs, Reference::new):
    // a table of twice as many buckets, at least 4096; the largest radius 1% of the scene's
    // radius (the reference's initial radius) and cells twice that, so that a gathering disk
    // overlaps at most 2x2x2 cells (photon_grid.glsl).
    let table = (2 * count.max(1)).next_power_of_two().max(1 << 12);
    let cap = 0.01 * s.gpu.bounds_radius.max(1e-20);
    let targets = photon_targets(scene)?;
    uniforms.counts[2] = targets.len() as u32;
    uniforms.targets[..targets.len()].copy_from_slice(&targets);
    uniforms.photon[0] = count;
    uniforms.photon[1] = count.max(1);
    uniforms.photon[2] = table;
    uniforms.grid[0] = 2.002 * cap;
    uniforms.grid[1] = cap;
    uniforms.grid[2] = p.gather_radius;

    // Shared while what the photons depend on is: the geometry, the lights, the photon count,
    // max_depth and the grid's cells (the scene's radius, which the camera's position is part
    // of). The GPU scene's buffers bound with them live as long as the renderer, as the cache.
    let key = cache_key(&(TraceGeometry::key(scene), &scene.lights, count, p.max_depth, cap.to_bits()));
    let (cache, graph, gpu) = (&mut *s.cache, &mut *s.graph, s.gpu);
    let photons = cache.get_or_try_insert(key, || make_photons(ctx, graph, gpu, &timed, &uniforms, count))?;
    let owner = (photon_owner(scene) == Some(effect)).then_some((reset, trace));
    let uniforms = Buffer::storage(ctx, &format!("{name}_uniforms"), std::slice::from_ref(&uniforms))?;

    // The uniforms are host-written once at creation: visible at submission.
    let targets = s.targets;
    let set = fragment_set()
        .sampled(BINDING_GBUF_ALBEDO, &targets.gbuf_albedo, s.nearest)
        .read(targets.gbuf_albedo_id)
        .sampled(BINDING_GBUF_DEPTH, &targets.depth, s.nearest)
        .read(targets.depth_id)
        .storage(REF_BINDING_UNIFORMS, &uniforms)
        .storage(REF_BINDING_PHOTONS, &photons.photons)
        .read(photons.photons_id)
        .storage(REF_BINDING_GRID, &photons.grid)
        .read(photons.grid_id);
    let set = geometry.bind(s.gpu, set)?;
    let pass = FullscreenPass::new(
        ctx,
        // Overwrites only the pixels of its objects; the caustic is added to the diffuse ones'.
        &FullscreenDesc {
            additive: effect == Effect::Caustics,
            ..FullscreenDesc::over_hdr(name, shader, targets, spec)
        },
        set,
        s.frame_layout,
    )?;
    let accumulation = match accumulator(scene) == Some(effect) {
        true => Some(make_accumulation(ctx, s.graph, targets, p.accumulate)?),
        false => None,
    };
    Ok(Box::new(Raytrace {
        pass,
        accumulation,
        since_change: 0,
        frames: 0,
        photons,
        owner,
        iteration: 0,
        begun: 0,
        _uniforms: uniforms,
        geometry: timed,
    }))
}

/// The running mean over the frame's HDR image, of up to `limit` frames.
fn make_accumulation(
    ctx: &Arc<GpuContext>,
    graph: &mut FrameGraph,
    targets: &crate::frame::targets::Targets,
    limit: u32,
) -> Result<Accumulation, RenderError> {
    let (width, height) = (targets.width, targets.height);
    // The HDR image's format: the mean of its values in the same precision, so that a pixel
    // equal in every frame is copied back unchanged.
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
    let mean = Image::new(ctx, &ImageDesc::d2("raytrace_mean", HDR_FORMAT, width, height, usage))?;
    let mean_id = graph.register_image(&mean);
    let set = Bindings::new(vk::ShaderStageFlags::COMPUTE)
        .storage_image(ACCUMULATE_BINDING_HDR, &targets.hdr)
        .access(targets.hdr_id, Access::ComputeWrite)
        .storage_image(ACCUMULATE_BINDING_MEAN, &mean)
        .access(mean_id, Access::ComputeWrite)
        .build(ctx, RAYTRACE_ACCUMULATE)?;
    let push = std::mem::size_of::<AccumulatePush>() as u32;
    let pipeline =
        ComputePipeline::new(ctx, RAYTRACE_ACCUMULATE, "raytrace/accumulate.comp", &[set.layout()], push, &[])?;
    let groups = [width.div_ceil(WORKGROUP_2D), height.div_ceil(WORKGROUP_2D), 1];
    Ok(Accumulation { pipeline, set, groups, limit, size: (width, height), _mean: mean })
}

/// The photon map for `count` photons a frame and, with photons, the reference's photon
/// kernel over it, reading `uniforms`.
fn make_photons(
    ctx: &Arc<GpuContext>,
    graph: &mut FrameGraph,
    gpu: &GpuScene,
    geometry: &Rc<crate::technique::Timed<TraceGeometry>>,
    uniforms: &RefUniforms,
    count: u32,
) -> Result<Photons, RenderError> {
    use vk::BufferUsageFlags as U;
    let table = uniforms.photon[2];
    let photons =
        Buffer::new(ctx, "raytrace_photon_list", count.max(1) as u64 * 48, U::STORAGE_BUFFER, MemoryLocation::GpuOnly)?;
    let grid = Buffer::new(
        ctx,
        "raytrace_photon_grid",
        if count > 0 { table as u64 * 4 } else { 4 },
        U::STORAGE_BUFFER | U::TRANSFER_DST,
        MemoryLocation::GpuOnly,
    )?;
    let (photons_id, grid_id) = (graph.register_buffer(&photons), graph.register_buffer(&grid));
    let kernel = if count == 0 {
        None
    } else {
        let uniforms = Buffer::storage(ctx, "raytrace_photon_uniforms", std::slice::from_ref(uniforms))?;
        let counters = Buffer::new(
            ctx,
            "raytrace_photon_counter",
            16,
            U::STORAGE_BUFFER | U::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        // (flux, outcome) and the deposit's position of every photon (photons.comp).
        let debug = Buffer::new(
            ctx,
            "raytrace_photon_debug",
            2 * count as u64 * 16,
            U::STORAGE_BUFFER,
            MemoryLocation::GpuOnly,
        )?;
        let stats = Buffer::storage(ctx, "raytrace_photon_stats", &initial_stats())?;
        let sampler = Sampler::new(ctx, "raytrace_photon_latlong", SamplerDesc::LATLONG)?;
        let counters_id = graph.register_buffer(&counters);
        let (debug_id, stats_id) = (graph.register_buffer(&debug), graph.register_buffer(&stats));
        let bindings = Bindings::new(vk::ShaderStageFlags::COMPUTE)
            .storage(REF_BINDING_UNIFORMS, &uniforms)
            .storage(REF_BINDING_MATERIALS, &gpu.materials)
            .sampled(REF_BINDING_ENVIRONMENT, &gpu.environment, &sampler)
            .read(gpu.environment_id)
            .storage(REF_BINDING_PHOTONS, &photons)
            .access(photons_id, Access::ComputeWrite)
            .storage(REF_BINDING_GRID, &grid)
            .access(grid_id, Access::ComputeWrite)
            .storage(REF_BINDING_COUNTERS, &counters)
            .access(counters_id, Access::ComputeWrite)
            .storage(REF_BINDING_DEBUG, &debug)
            .access(debug_id, Access::ComputeWrite)
            .storage(REF_BINDING_STATS, &stats)
            .access(stats_id, Access::ComputeWrite);
        let set = geometry.value.bind(gpu, bindings)?.build(ctx, "raytrace_photons")?;
        let push = std::mem::size_of::<RefPush>() as u32;
        let pipeline =
            ComputePipeline::new(ctx, "raytrace_photons", "reference/photons.comp", &[set.layout()], push, &[])?;
        let groups = dispatch_size(count, ctx.limits().max_compute_work_group_count).ok_or_else(|| {
            RenderError::Limit(format!("{count} photons a frame need more workgroups than the device allows"))
        })?;
        Some(PhotonKernel {
            pipeline,
            set,
            groups,
            counters,
            counters_id,
            _debug: debug,
            _stats: stats,
            _sampler: sampler,
            _uniforms: uniforms,
        })
    };
    Ok(Photons { photons, photons_id, grid, grid_id, kernel, _geometry: geometry.clone() })
}

impl Technique for Raytrace {
    fn record<'a>(&'a self, _: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        if let (Some((reset, trace)), Some(k)) = (self.owner, &self.photons.kernel) {
            let (grid, counters) = (&self.photons.grid, &k.counters);
            frame
                .pass(reset)
                .write(self.photons.grid_id, Access::TransferWrite)
                .write(k.counters_id, Access::TransferWrite)
                .record(move |cmd| {
                    cmd.fill_buffer(grid, END_OF_PHOTON_LIST);
                    cmd.fill_buffer(counters, 0);
                });
            let push = RefPush { iteration: self.iteration, seed: PHOTON_SEED, mode: 0, count: 0 };
            let (pipeline, set, groups) = (&k.pipeline, k.set.set(), k.groups);
            // The set declares the kernel's accesses: the photons, grid, counter, debug records
            // and canary counts written, the environment read.
            frame.pass(trace).uses(&k.set).record(move |cmd| cmd.compute(pipeline, &[set], &push, groups));
        }
        self.pass.record(frame, inputs.frame_set, &[inputs.scene.environment_id]);
        if let Some(a) = &self.accumulation {
            let push = AccumulatePush { frames: self.frames, limit: a.limit, width: a.size.0, height: a.size.1 };
            let (pipeline, set, groups) = (&a.pipeline, a.set.set(), a.groups);
            // The set declares the HDR image and the mean, both read and written.
            frame
                .pass(RAYTRACE_ACCUMULATE)
                .uses(&a.set)
                .record(move |cmd| cmd.compute(pipeline, &[set], &push, groups));
        }
    }

    fn begin_frame(&mut self) {
        self.iteration = self.begun;
        self.begun = self.begun.wrapping_add(1);
        self.frames = self.since_change;
        self.since_change = self.since_change.saturating_add(1);
    }

    fn restart(&mut self) {
        self.begun = 0;
        self.since_change = 0;
    }

    // Every change restarts the mean: what the frames before it show is not this view.
    fn camera_moved(&mut self) {
        self.since_change = 0;
    }

    fn objects_moved(&mut self, _bounds: &[(glam::Vec3, f32)]) {
        self.since_change = 0;
    }

    fn contents_changed(&mut self) {
        self.since_change = 0;
    }

    fn accumulated(&self) -> Option<u32> {
        self.accumulation.as_ref().map(|a| self.since_change.min(a.limit))
    }

    fn once_costs(&self) -> Vec<crate::technique::OnceCost> {
        vec![crate::technique::trace_geometry_cost(&self.geometry)]
    }
}
