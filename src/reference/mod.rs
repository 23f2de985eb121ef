//! prism's exact reference: a progressive path tracer with photon-mapped caustics in compute
//! shaders (glsl/reference/), over the same scene data as the rasterised techniques.
//!
//! What it computes is SCENES.md's "light transport measured": every path with exactly one
//! diffuse vertex. Camera paths (camera.comp) follow exact specular chains (mirror,
//! conductor Fresnel, dielectric Fresnel chosen stochastically, Snell, total internal
//! reflection, Beer-Lambert absorption, (n_i/n_t)^2 radiance scaling, per-channel ior) to
//! the environment or to a diffuse surface, which takes direct light with exact shadow rays
//! and environment light through specular chains. Caustics (light -> specular chain ->
//! diffuse) come from stochastic progressive photon mapping (photons.comp, gather.comp),
//! which converges as the photon count grows. Triangles are found through a SAH BVH built on
//! the CPU ([`bvh`]); spheres are intersected exactly.
//!
//! Graded-index media (`[volume]`, the eikonal issue): camera paths that meet the volume's
//! region (its sphere, or its box) before any surface cross it exactly
//! (glsl/reference/volume.glsl): Fresnel reflection or Snell refraction where the index
//! jumps at the region's boundary, and inside classical RK4 of the ray equation
//! dx/ds = v/n, dv/ds = grad n on the analytic profile with a step of 1/2000 of the box
//! diagonal, Beer-Lambert absorption along the curved path. Surfaces inside the region are
//! not seen. Photons cross volumes the same way (photons.comp) and the volume is a photon
//! target; shadow rays stop at it, so the light behind it arrives as caustics.
//!
//! A volume with `[[volume.region]]`s (volume sources) is traced instead through
//! the same voxel fields the view renderer gets (src/scene/volume_sources.rs): the index per
//! channel (one channel per path when dispersive), the extinction and the emission,
//! unsmoothed and trilinear, RK4 steps of 1/8 voxel, stochastic exact Fresnel at the index
//! jumps marked by the boundary indicator (glsl/reference/volume.glsl, VOLUME_FIELDS).
//! Scattering there only attenuates (in-scattering is the light simulator's), and emission
//! is counted on camera paths only.
//!
//! The reference says when it is not exact ([`ReferenceStats`]): lavapipe stops every loop of
//! an invocation once 65535 loop iterations are spent over all its loops
//! (tests/loop_limit.rs measures it), which cuts a path short without a message, so each
//! kernel ends with a canary loop that tells whether the budget ran out
//! (glsl/reference/sppm.glsl, `loop_canary`), and the paths that end at the volume's step cap
//! are counted too.
pub mod bvh;

use std::sync::Arc;

use bytemuck::Zeroable;
use glam::{Mat4, Vec3};

use crate::frame::gpu_scene::GpuScene;
use crate::frame::RenderError;
use crate::gpu::{
    vk, Access, Buffer, BufferView, ComputePipeline, GpuContext, GpuResult, MemoryLocation, Sampler, SamplerDesc,
};
use crate::graph::{Bindings, BoundSet, BufferId, FrameGraph};
use crate::scene::{Analytic, Light, Material, Scene};
use crate::*;

pub use crate::shader_structs::RefUniforms;
use crate::shader_structs::{GpuSphere, PixelState, RefLight, RefPush};
use bvh::Bvh;

/// How the reference is computed. The defaults give a converged image of the benchmark
/// scenes at 512^2 in minutes on lavapipe.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ReferenceSettings {
    /// Camera samples per pixel (each also one photon-mapping iteration).
    pub spp: u32,
    /// Photons traced in all (spread over the `spp` iterations, each in photon passes of at
    /// most [`MAX_PHOTONS_PER_PASS`]); 0 disables caustics.
    pub photons: u64,
    /// Specular interactions followed per path.
    pub max_depth: u32,
    pub seed: u32,
    /// Initial photon gathering radius in metres; default 1% of the scene's radius. With
    /// `footprint` > 0 it is only the largest initial radius.
    pub radius: Option<f32>,
    /// Initial radius of each pixel in pixel footprints on its receiver: `footprint` times
    /// the spacing of neighbouring camera rays where its path meets the diffuse surface
    /// (glsl/reference/camera.comp), at most `radius`. 0 starts every pixel at `radius`.
    /// With footprint radii the caustic's visible points sample the pixel's area (a second
    /// camera path through a uniform point of the pixel): SPPM then converges to the
    /// caustic averaged over the pixel rather than at its centre.
    pub footprint: f32,
    /// SPPM radius reduction alpha (Hachisuka et al. 2008 use 0.7; 2/3 is the usual choice).
    pub alpha: f32,
    /// Supersample each pixel's area instead of its centre.
    pub jitter: bool,
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        ReferenceSettings {
            spp: 64,
            photons: 1 << 22,
            max_depth: 16,
            seed: 1,
            radius: None,
            footprint: DEFAULT_FOOTPRINT,
            alpha: 2.0 / 3.0,
            jitter: false,
        }
    }
}

impl ReferenceSettings {
    pub fn validate(&self) -> Result<(), RenderError> {
        let bad = |m: String| Err(RenderError::Limit(m));
        if self.spp == 0 || self.spp > 1 << 20 {
            return bad(format!("spp = {} must be in 1..=1048576", self.spp));
        }
        if self.photons > 1 << 34 {
            return bad(format!("photons = {} is absurd (at most 2^34)", self.photons));
        }
        if self.max_depth > 1024 {
            return bad(format!("max_depth = {} must be at most 1024", self.max_depth));
        }
        if !(self.alpha > 0.0 && self.alpha < 1.0) {
            return bad(format!("alpha = {} must be in (0, 1)", self.alpha));
        }
        if !(self.footprint.is_finite() && self.footprint >= 0.0) {
            return bad(format!("footprint = {} must be a number of pixel footprints >= 0", self.footprint));
        }
        if let Some(r) = self.radius {
            if !(r.is_finite() && r > 0.0) {
                return bad(format!("radius = {r} must be a positive number of metres"));
            }
        }
        Ok(())
    }

    /// Photons per iteration (the photon passes of each of the `spp` iterations).
    pub fn photons_per_iteration(&self) -> u32 {
        if self.photons == 0 {
            0
        } else {
            (self.photons / self.spp as u64).clamp(1, u32::MAX as u64 / 4) as u32
        }
    }

    /// Photon passes per iteration, each tracing at most [`MAX_PHOTONS_PER_PASS`] photons and
    /// followed by its own gather (one progressive update, Hachisuka et al. 2008, Eqs. 6-8).
    pub fn passes_per_iteration(&self) -> u32 {
        self.photons_per_iteration().div_ceil(MAX_PHOTONS_PER_PASS).max(1)
    }

    /// Photons traced by each photon pass.
    pub fn photons_per_pass(&self) -> u32 {
        self.photons_per_iteration().div_ceil(self.passes_per_iteration())
    }
}

/// The default initial radius in pixel footprints ([`ReferenceSettings::footprint`]): half
/// the pixel's footprint on its receiver, the disk inscribed in its square. 1% of the scene's
/// radius is 2.5 pixels on caustic_sphere's floor at 256^2 and shrinks only as
/// N^((alpha - 1) / 2), which blurred the caustic's peak and rim. Footprint radii go with
/// visible points spread over the pixel's area (glsl/reference/camera.comp), so that a focus
/// narrower than a pixel keeps its flux (tests/reference.rs, the flux checks).
pub const DEFAULT_FOOTPRINT: f32 = 0.5;

/// The most photons one photon pass traces. lavapipe ends every loop of an invocation after
/// 65535 loop iterations in all (LP_MAX_TGSI_LOOP_ITERATIONS, counted over all its loops and
/// over the invocations it runs in lockstep; tests/loop_limit.rs); under a bright focus the gather's photon lists
/// were cut short there and the cut-off invocations' sums came out zero, so 8-pixel runs of
/// a caustic were black. A gather walks each of its at most 8 buckets once (gather.comp), and
/// each list holds at most the pass's photons, so it runs at most 8 * 8000 + 36 < 65535 loop
/// iterations, whichever buckets the invocations in lockstep walk.
pub const MAX_PHOTONS_PER_PASS: u32 = 8000;

/// The trip count of the loop canary (glsl/reference/sppm.glsl, `loop_canary`): it runs
/// fewer exactly when the driver's loop budget ran out before it.
const CANARY_TRIPS: u32 = 2;

/// What the reference's kernels counted over a run (glsl/reference/sppm.glsl): where either
/// is non-zero the image is not the exact reference.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ReferenceStats {
    /// Camera-kernel invocations (one per pixel and iteration) whose driver loop budget ran
    /// out: their paths were cut short (lavapipe's LP_MAX_TGSI_LOOP_ITERATIONS, 65535 loop
    /// iterations per vector of invocations run in lockstep, tests/loop_limit.rs). Counted
    /// per invocation of a cut vector, so it over-states cut paths by up to the vector
    /// width (8 on AVX2) and never misses one.
    pub cut_camera: u64,
    /// Photon-kernel invocations (one per photon) whose loop budget ran out.
    pub cut_photons: u64,
    /// Gather invocations (one per pixel and photon pass) whose loop budget ran out.
    pub cut_gather: u64,
    /// Camera paths (and their environment samples) that ended inside the volume at its
    /// step cap (volume.glsl, ref.volume[4].w steps per crossing).
    pub step_cap_camera: u64,
    /// Photon paths that ended inside the volume at its step cap.
    pub step_cap_photons: u64,
}

impl ReferenceStats {
    /// Invocations cut by the driver's loop limit, all kernels.
    pub fn cut(&self) -> u64 {
        self.cut_camera + self.cut_photons + self.cut_gather
    }
    /// Paths ended by the volume's step cap, camera and photon.
    pub fn step_capped(&self) -> u64 {
        self.step_cap_camera + self.step_cap_photons
    }

    /// Whether every path ran to its end: nothing cut, nothing step-capped.
    pub fn exact(&self) -> bool {
        self.cut() == 0 && self.step_capped() == 0
    }

    /// What went wrong in the reference of scene `scene`, its causes and what to do; None
    /// when it is exact.
    pub fn warning(&self, scene: &str) -> Option<String> {
        if self.exact() {
            return None;
        }
        let mut w = format!("the reference of scene {scene} is not exact:");
        if self.cut() > 0 {
            w += &format!(
                " {} shader invocations ran out of the driver's loop budget (camera {}, photons {}, gather {}), \
                 so their paths were cut short: lavapipe (llvmpipe) stops every loop after 65535 loop iterations \
                 in all per invocation (each count includes the invocations run in lockstep with a cut one). \
                 Use a coarser `volume.resolution` (fewer RK4 steps per crossing), a smaller --max-depth, \
                 or another Vulkan driver (--device).",
                self.cut(),
                self.cut_camera,
                self.cut_photons,
                self.cut_gather
            );
        }
        if self.step_capped() > 0 {
            w += &format!(
                " {} paths ended inside the volume at its step cap (camera {}, photons {}; ten crossings of \
                 the box's diagonal, at most 200000 RK4 steps): light trapped by internal reflections, or a \
                 crossing longer than the cap. Use a coarser `volume.resolution` (longer steps) or a lower \
                 index contrast or `reflectance`.",
                self.step_capped(),
                self.step_cap_camera,
                self.step_cap_photons
            );
        }
        Some(w)
    }
}

/// Workgroup counts that cover `items` invocations of the 1-D reference kernels
/// (REF_WORKGROUP each, indexed by `invocation_index` in glsl/reference/scene.glsl) within the
/// device's maxComputeWorkGroupCount `max`: rows of at most max[0] groups, as many rows as
/// needed. A 1-D dispatch of 64 pixels per group stops at 64 max[0] pixels (2^22 with
/// 65535, the least the Vulkan spec requires of a device), fewer than a 2^32-byte storage buffer
/// holds. None when even max[0] x max[1] groups are too few.
pub fn dispatch_size(items: u32, max: [u32; 3]) -> Option<[u32; 3]> {
    let groups = items.div_ceil(REF_WORKGROUP).max(1);
    let x = groups.min(max[0].max(1));
    let y = groups.div_ceil(x);
    (y <= max[1]).then_some([x, y, 1])
}

impl RefUniforms {
    /// The raytrace technique's branch cutoff (glsl/raytrace/raytrace.frag; the reference
    /// leaves it 0).
    pub fn with_cutoff(mut self, cutoff: f32) -> Self {
        self.grid[3] = cutoff;
        self
    }
}
const _: () = assert!(
    std::mem::size_of::<RefUniforms>()
        == 64 + 6 * 16 + 32 * MAX_LIGHTS as usize + 16 * REF_MAX_TARGETS as usize + 6 * 16
);

/// Kinds of volume.glsl (`ref.volume[0].w`).
const REF_VOLUME_LUNEBURG: f32 = 1.0;
const REF_VOLUME_LINEAR: f32 = 2.0;
const REF_VOLUME_CONSTANT: f32 = 3.0;
/// A volume with regions, traced through its voxel fields.
const REF_VOLUME_FIELDS: f32 = 4.0;

/// The voxel fields of a volume with regions for volume.glsl's VOLUME_FIELDS: 3 vec4 per
/// voxel, (n - 1 RGB, boundary band), (extinction RGB, 0), (emission RGB, reflectance), the
/// same fields as the view renderer's (src/scene/volume_sources.rs), unsmoothed; the band is
/// the boundary indicator widened by the one-voxel coverage ramp. A 1-texel stand-in
/// without regions (the analytic profile is traced exactly).
fn volume_voxels(volume: Option<&crate::scene::Volume>) -> (Vec<[f32; 4]>, bool) {
    let Some(volume) = volume.filter(|v| !v.regions.is_empty()) else {
        return (vec![[0.0; 4]], false);
    };
    let f = volume.fields();
    let (band, reflectance) = f.boundary_band(1);
    let mut out = Vec::with_capacity(3 * f.voxels());
    for v in 0..f.voxels() {
        out.push([f.index[0][v], f.index[1][v], f.index[2][v], band[v]]);
        let e = f.extinction[v];
        out.push([e[0], e[1], e[2], 0.0]);
        let m = f.emission[v];
        out.push([m[0], m[1], m[2], reflectance[v]]);
    }
    (out, f.dispersive)
}

/// The uniform rows of volume.glsl for `volume`: the exact analytic profile (not the voxels
/// the eikonal view renderer samples), marched with RK4 steps of 1/2000 of the box diagonal.
fn volume_uniforms(volume: &crate::scene::Volume) -> [[f32; 4]; 6] {
    use crate::scene::IndexProfile;
    let h = (volume.max - volume.min).length() / 2000.0;
    let (kind, params) = match volume.index {
        IndexProfile::Luneburg { center, radius } => (REF_VOLUME_LUNEBURG, center.extend(radius)),
        IndexProfile::Linear { n0, gradient, .. } => (REF_VOLUME_LINEAR, gradient.extend(n0)),
        IndexProfile::Constant { n, .. } => (REF_VOLUME_CONSTANT, Vec3::ZERO.extend(n)),
    };
    let (center, radius) = volume.index.region().unwrap_or(((volume.min + volume.max) * 0.5, 0.0));
    if !volume.regions.is_empty() {
        // The fields fill the box: the region is the box; steps of 1/8 voxel (the fields
        // are trilinear within a voxel), and enough of them for ten crossings of the
        // diagonal (internal reflections).
        let [nx, ny, nz] = volume.resolution;
        let h = volume.voxel_size().min_element() / 8.0;
        let steps = (10.0 * (volume.max - volume.min).length() / h).ceil().min(200_000.0);
        return [
            volume.min.extend(REF_VOLUME_FIELDS).to_array(),
            volume.max.extend(h).to_array(),
            [0.0; 4],
            [0.0; 4],
            [0.0, 0.0, 0.0, steps],
            [1.0, nx as f32, ny as f32, nz as f32],
        ];
    }
    [
        volume.min.extend(kind).to_array(),
        volume.max.extend(h).to_array(),
        center.extend(radius).to_array(),
        params.to_array(),
        volume.attenuation.extend(20_000.0).to_array(),
        [0.0; 4],
    ]
}

const FLAG_DISPERSION: u32 = 1;
const FLAG_JITTER: u32 = 2;

/// Probe modes of glsl/reference/probe.comp (tests).
#[derive(Clone, Copy, Debug)]
pub enum Probe {
    /// (o, d) -> (t_bvh, tri_bvh, t_brute, tri_brute).
    Raycast = 0,
    /// (o, d) -> final (o, outcome), (d, bounces), throughput; always transmitting.
    SpecularPath = 1,
    /// (cos_i, eta), eta_rgb, k_rgb -> F_dielectric, F_conductor rgb.
    Fresnel = 2,
    /// (N, M) -> (iterations run by a loop of N, then by a loop of M): the driver's loop
    /// limit (tests/loop_limit.rs).
    LoopLimit = 3,
}

/// Whether a dielectric has an RGB ior (the tracer then follows one channel at a time).
fn dispersive_dielectric(scene: &Scene) -> bool {
    scene.materials.iter().any(|m| matches!(m, Material::Dielectric { ior, .. } if ior.x != ior.y || ior.y != ior.z))
}

/// The exact tracer's scene besides the GPU scene's vertices and materials
/// (glsl/reference/trace.glsl): the BVH-ordered triangles, the BVH, the exact spheres, each
/// object's material and the volume's voxels. The reference binds them in set 0 of its compute
/// passes; the raytrace technique (src/technique/raytrace.rs) in set 1 of its fragment pass,
/// and keeps them across its re-creation while [`TraceGeometry::key`] is unchanged.
///
/// The shaders read the triangles, the BVH, the spheres and the objects' materials as texel
/// buffers: every lane of a traversal fetches a node or a triangle of its own, which a texel
/// fetch gathers in one instruction, where lavapipe loads a storage buffer lane by lane.
pub struct TraceGeometry {
    /// (binding, buffer, its view) of each texel buffer.
    texels: [(u32, Buffer, BufferView); 4],
    voxels: Buffer,
    triangles: u32,
    nodes: u32,
    spheres: u32,
    dispersion: bool,
}

/// The exact tracer's primitives of a scene, on the CPU: every object that is not an exact
/// sphere as triangles under one BVH, and the exact spheres. [`TraceGeometry`] uploads them
/// for the shaders; the object mask (src/metrics/mask.rs) casts its centre rays through them,
/// so that both see the same surfaces.
pub struct TracePrimitives {
    /// Per triangle: its global vertex indices (over all objects' vertices, as in the GPU
    /// scene) and its object's index, in the caller's (object) order.
    pub triangles: Vec<[u32; 4]>,
    /// Each triangle's corners, world space, in the same order.
    pub corners: Vec<[Vec3; 3]>,
    pub bvh: Bvh,
    /// The exact spheres: centre and radius, and the object's index in `info[0]`.
    pub spheres: Vec<GpuSphere>,
}

impl TracePrimitives {
    pub fn new(scene: &Scene) -> TracePrimitives {
        // Triangles of every object that is not an exact sphere, with global vertex indices.
        let mut triangles: Vec<[u32; 4]> = Vec::new();
        let mut corners: Vec<[Vec3; 3]> = Vec::new();
        let mut spheres: Vec<GpuSphere> = Vec::new();
        let mut vertex_base = 0u32;
        for (oi, o) in scene.objects.iter().enumerate() {
            match o.analytic {
                Some(Analytic::Sphere { center, radius }) => {
                    spheres.push(GpuSphere {
                        center_radius: center.extend(radius).to_array(),
                        info: [oi as u32, 0, 0, 0],
                    });
                }
                None => {
                    for t in o.mesh.indices.chunks_exact(3) {
                        triangles.push([vertex_base + t[0], vertex_base + t[1], vertex_base + t[2], oi as u32]);
                        corners.push([0, 1, 2].map(|k| o.mesh.positions[t[k] as usize]));
                    }
                }
            }
            vertex_base += o.mesh.positions.len() as u32;
        }
        let bvh = Bvh::build(&corners);
        TracePrimitives { triangles, corners, bvh, spheres }
    }

    /// The closest surface the ray `o + t d` (d unit length) meets with t in (0, t_max):
    /// (t, object index). Spheres are met exactly (the nearer positive root), triangles as
    /// the shader meets them ([`bvh::intersect_triangle`]).
    pub fn closest(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<(f32, usize)> {
        let mut best = self
            .bvh
            .intersect(&self.corners, o, d, t_max)
            .map(|h| (h.t, self.triangles[h.triangle as usize][3] as usize));
        for s in &self.spheres {
            let [cx, cy, cz, r] = s.center_radius;
            let oc = o - Vec3::new(cx, cy, cz);
            let b = oc.dot(d);
            let disc = b * b - (oc.length_squared() - r * r);
            if disc < 0.0 {
                continue;
            }
            let root = disc.sqrt();
            let t = [-b - root, -b + root].into_iter().find(|&t| t > 0.0);
            if let Some(t) = t.filter(|&t| t < best.map_or(t_max, |b| b.0)) {
                best = Some((t, s.info[0] as usize));
            }
        }
        best
    }
}

impl TraceGeometry {
    pub fn new(ctx: &Arc<GpuContext>, scene: &Scene) -> Result<TraceGeometry, RenderError> {
        let TracePrimitives { triangles: tris, bvh, spheres, .. } = TracePrimitives::new(scene);
        let ordered: Vec<[u32; 4]> = bvh.order.iter().map(|&i| tris[i as usize]).collect();
        let objects: Vec<u32> = scene.objects.iter().map(|o| o.material as u32).collect();
        let (voxels, volume_dispersive) = volume_voxels(scene.volume.as_ref());
        let dispersion = volume_dispersive || dispersive_dielectric(scene);
        // Every texel is RGBA32UI (the floats' bits, exact) but the objects' R32UI materials.
        let rgba = vk::Format::R32G32B32A32_UINT;
        let texels = |binding: u32, (buffer, view): (Buffer, BufferView)| (binding, buffer, view);
        Ok(TraceGeometry {
            texels: [
                texels(REF_BINDING_TRIANGLES, Buffer::texels(ctx, "reference_triangles", &ordered, rgba)?),
                texels(REF_BINDING_NODES, Buffer::texels(ctx, "reference_bvh", &bvh.nodes, rgba)?),
                texels(REF_BINDING_SPHERES, Buffer::texels(ctx, "reference_spheres", &spheres, rgba)?),
                texels(REF_BINDING_OBJECTS, Buffer::texels(ctx, "reference_objects", &objects, vk::Format::R32_UINT)?),
            ],
            voxels: Buffer::storage(ctx, "reference_volume_voxels", &voxels)?,
            triangles: ordered.len() as u32,
            nodes: bvh.nodes.len() as u32,
            spheres: spheres.len() as u32,
            dispersion,
        })
    }

    /// A hash of what the geometry is built from: every object's triangles or sphere and
    /// material, whether a dielectric disperses, and the volume.
    pub fn key(scene: &Scene) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        for o in &scene.objects {
            (o.material, &o.mesh.indices).hash(&mut h);
            o.mesh.positions.iter().for_each(|p| p.to_array().map(f32::to_bits).hash(&mut h));
            format!("{:?}", o.analytic).hash(&mut h);
        }
        (dispersive_dielectric(scene), format!("{:?}", scene.volume)).hash(&mut h);
        h.finish()
    }

    /// `b` with the tracer's geometry at its REF_BINDING_*: these buffers and `gpu`'s vertices.
    pub fn bind<'a>(&'a self, gpu: &'a GpuScene, b: Bindings<'a>) -> GpuResult<Bindings<'a>> {
        let mut b = b.texels(REF_BINDING_VERTICES, gpu.vertex_texels()?);
        for (binding, _, view) in &self.texels {
            b = b.texels(*binding, view);
        }
        Ok(b.storage(REF_BINDING_VOLUME, &self.voxels))
    }

    /// The tracer's uniforms for `scene` over this geometry, following at most `max_depth`
    /// specular interactions per path; no photons.
    pub fn uniforms(&self, scene: &Scene, gpu_scene: &GpuScene, max_depth: u32) -> RefUniforms {
        let scene_radius = gpu_scene.bounds_radius.max(1e-20);
        let cam = &scene.camera;
        let tan_y = (cam.vfov_deg.to_radians() * 0.5).tan();
        let mut uniforms = RefUniforms {
            inv_view: cam.view().inverse().to_cols_array_2d(),
            camera_pos: cam.position.extend(1.0).to_array(),
            // The ray epsilon scales with the scene, so that 1e-3 and 1e4 scenes behave alike.
            proj: [tan_y * cam.aspect(), tan_y, scene_radius * 2e-5, scene_radius],
            dims: [cam.width, cam.height, scene.lights.len() as u32, self.spheres],
            counts: [self.triangles, self.nodes, 0, max_depth],
            photon: [0, 0, 0, self.dispersion as u32 * FLAG_DISPERSION],
            grid: [0.0; 4],
            lights: [RefLight::zeroed(); MAX_LIGHTS as usize],
            targets: [[0.0; 4]; REF_MAX_TARGETS as usize],
            volume: scene.volume.as_ref().map(volume_uniforms).unwrap_or_default(),
        };
        for (i, l) in scene.lights.iter().enumerate() {
            uniforms.lights[i] = match l {
                Light::Point { position, intensity } => RefLight {
                    position: position.extend(LIGHT_POINT as f32).to_array(),
                    intensity: intensity.extend(0.0).to_array(),
                },
                Light::Directional { direction, irradiance } => RefLight {
                    position: direction.normalize().extend(LIGHT_DIRECTIONAL as f32).to_array(),
                    intensity: irradiance.extend(0.0).to_array(),
                },
            };
        }
        uniforms
    }
}

/// The reference renderer for one scene. Create it, `run` iterations, read the `image`.
pub struct Reference {
    settings: ReferenceSettings,
    width: u32,
    height: u32,
    iterations_done: u32,
    /// Photon passes done (each one progressive update of the caustics).
    passes_done: u32,
    photons_per_iteration: u32,
    passes_per_iteration: u32,
    /// Workgroups of the per-pixel kernels ([`dispatch_size`]).
    pixel_groups: [u32; 3],
    /// The device's maxComputeWorkGroupCount.
    max_groups: [u32; 3],
    set: BoundSet,
    camera: ComputePipeline,
    photons: ComputePipeline,
    gather: ComputePipeline,
    probe: ComputePipeline,
    graph: FrameGraph,
    accum: Buffer,
    pixels: Buffer,
    photon_buffer: Buffer,
    grid: Buffer,
    counters: Buffer,
    debug: Buffer,
    /// The canary's trip count and the counters of [`ReferenceStats`] (REF_STAT_*).
    stats: Buffer,
    ids: [BufferId; 7],
    _uniforms: Buffer,
    _trace: TraceGeometry,
    _sampler: Sampler,
    _scene: GpuScene,
    ctx: Arc<GpuContext>,
}

/// Where the photon kernel (glsl/reference/photons.comp) aims: the bounding spheres (centre,
/// radius) of the specular objects, and of the refractive volume, whose light reaches the
/// floor by photons (camera.comp's shadow rays stop at it). Shared by the reference and the
/// raytrace technique's caustics.
pub fn photon_targets(scene: &Scene) -> Result<Vec<[f32; 4]>, RenderError> {
    let mut targets = Vec::new();
    for o in &scene.objects {
        if scene.materials[o.material].is_specular() {
            let (c, r) = match o.analytic {
                Some(Analytic::Sphere { center, radius }) => (center, radius),
                None => bounding_sphere(&o.mesh.positions),
            };
            // A little margin so that the cone contains the whole tessellated object.
            targets.push([c.x, c.y, c.z, r * 1.001 + 1e-6]);
        }
    }
    if let Some(v) = &scene.volume {
        let (c, r) = match v.index.region().filter(|_| v.regions.is_empty()) {
            Some((c, r)) => (c, r),
            None => ((v.min + v.max) * 0.5, (v.max - v.min).length() * 0.5),
        };
        targets.push([c.x, c.y, c.z, r * 1.001 + 1e-6]);
    }
    if targets.len() > REF_MAX_TARGETS as usize {
        return Err(RenderError::Limit(format!(
            "the scene has {} specular objects; the reference aims photons at most {REF_MAX_TARGETS} (REF_MAX_TARGETS)",
            targets.len()
        )));
    }
    Ok(targets)
}

/// The stats buffer's contents before a kernel runs (glsl/reference/sppm.glsl): every count
/// zero and the canary's trip count.
pub fn initial_stats() -> [u32; REF_STATS as usize] {
    let mut stats = [0u32; REF_STATS as usize];
    stats[REF_STAT_CANARY_TRIPS as usize] = CANARY_TRIPS;
    stats
}

/// Bounding sphere (centre, radius) of an object's vertices.
fn bounding_sphere(positions: &[Vec3]) -> (Vec3, f32) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for &p in positions {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let c = (lo + hi) * 0.5;
    let r = positions.iter().map(|p| p.distance(c)).fold(0.0f32, f32::max);
    (c, r)
}

impl Reference {
    pub fn new(ctx: &Arc<GpuContext>, scene: &Scene, settings: &ReferenceSettings) -> Result<Reference, RenderError> {
        settings.validate()?;
        let (width, height) = (scene.camera.width, scene.camera.height);
        if width == 0 || height == 0 {
            return Err(RenderError::Limit(format!("image size {width}x{height} must not be zero")));
        }
        // The per-pixel state is one storage buffer bound whole (VK_WHOLE_SIZE), which may
        // be at most maxStorageBufferRange bytes (lavapipe: 2^27, 1448^2 pixels).
        let range = u64::from(ctx.limits().max_storage_buffer_range);
        let pixel_state = std::mem::size_of::<PixelState>() as u64;
        let state_bytes = u64::from(width) * u64::from(height) * pixel_state;
        if state_bytes > range {
            return Err(RenderError::Limit(format!(
                "image size {width}x{height} (camera.width x camera.height, or --width/--height) needs {} MiB of \
                 per-pixel state; the device's maxStorageBufferRange is {} MiB, at most {} pixels: lower the size",
                state_bytes >> 20,
                range >> 20,
                range / pixel_state
            )));
        }
        let max_groups = ctx.limits().max_compute_work_group_count;
        let pixel_groups = dispatch_size(width * height, max_groups).ok_or_else(|| {
            RenderError::Limit(format!(
                "image size {width}x{height} needs more workgroups than the device's maxComputeWorkGroupCount \
                 {max_groups:?} allows: lower the size"
            ))
        })?;
        let mut graph = FrameGraph::new();
        let gpu_scene = GpuScene::new(ctx, scene, &mut graph, 1)?;

        let trace = TraceGeometry::new(ctx, scene)?;
        let targets = photon_targets(scene)?;
        let has_photons = settings.photons > 0 && !targets.is_empty() && !scene.lights.is_empty();
        let photons_per_iteration = if has_photons { settings.photons_per_iteration() } else { 0 };
        let passes_per_iteration = if has_photons { settings.passes_per_iteration() } else { 0 };
        let photons_per_pass = if has_photons { settings.photons_per_pass() } else { 0 };
        let radius = settings.radius.unwrap_or(0.01 * gpu_scene.bounds_radius.max(1e-20));
        let table = (2 * photons_per_pass.max(1)).next_power_of_two().max(1 << 12);
        let mut uniforms = trace.uniforms(scene, &gpu_scene, settings.max_depth);
        uniforms.counts[2] = targets.len() as u32;
        uniforms.photon[0] = photons_per_pass;
        uniforms.photon[1] = photons_per_pass.max(1);
        uniforms.photon[2] = table;
        uniforms.photon[3] |= settings.jitter as u32 * FLAG_JITTER;
        // Cells twice the initial radius: a ball of radius R <= R0 then overlaps at most
        // 2 cells per axis, the 8 buckets the gather visits (0.1% margin for rounding).
        // w: the initial radius in pixel footprints (camera.comp; the raytrace technique
        // uses the slot for its cutoff instead).
        uniforms.grid = [2.002 * radius, radius, settings.alpha, settings.footprint];
        for (i, t) in targets.iter().enumerate() {
            uniforms.targets[i] = *t;
        }

        use vk::BufferUsageFlags as U;
        let ubo = Buffer::storage(ctx, "reference_uniforms", std::slice::from_ref(&uniforms))?;
        let pixels_n = (width * height) as usize;
        let accum =
            Buffer::new(ctx, "reference_accum", (pixels_n * 16) as u64, U::STORAGE_BUFFER, MemoryLocation::CpuToGpu)?;
        let mut pixels = Buffer::new(
            ctx,
            "reference_pixels",
            pixels_n as u64 * pixel_state,
            U::STORAGE_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        let initial = PixelState { vp_pos: [0.0, 0.0, 0.0, radius], ..Default::default() };
        pixels.write(0, bytemuck::cast_slice(&vec![initial; pixels_n]));
        let mut accum = accum;
        accum.write(0, &vec![0u8; pixels_n * 16]);
        let photon_buffer = Buffer::new(
            ctx,
            "reference_photons",
            photons_per_pass.max(1) as u64 * 48,
            U::STORAGE_BUFFER,
            MemoryLocation::GpuOnly,
        )?;
        let grid = Buffer::new(
            ctx,
            "reference_grid",
            table as u64 * 4,
            U::STORAGE_BUFFER | U::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        let counters =
            Buffer::new(ctx, "reference_counters", 16, U::STORAGE_BUFFER | U::TRANSFER_DST, MemoryLocation::GpuOnly)?;
        let debug = Buffer::new(
            ctx,
            "reference_debug",
            (2 * photons_per_pass.max(1) as u64).max(3 * 4096) * 16,
            U::STORAGE_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;

        let mut stats =
            Buffer::new(ctx, "reference_stats", REF_STATS as u64 * 4, U::STORAGE_BUFFER, MemoryLocation::CpuToGpu)?;
        stats.write(0, bytemuck::cast_slice(&initial_stats()));

        let sampler = Sampler::new(ctx, "reference_latlong", SamplerDesc::LATLONG)?;
        let bindings = Bindings::new(vk::ShaderStageFlags::COMPUTE)
            .storage(REF_BINDING_UNIFORMS, &ubo)
            .storage(REF_BINDING_MATERIALS, &gpu_scene.materials)
            .sampled(REF_BINDING_ENVIRONMENT, &gpu_scene.environment, &sampler)
            .storage(REF_BINDING_ACCUM, &accum)
            .storage(REF_BINDING_PIXELS, &pixels)
            .storage(REF_BINDING_PHOTONS, &photon_buffer)
            .storage(REF_BINDING_GRID, &grid)
            .storage(REF_BINDING_COUNTERS, &counters)
            .storage(REF_BINDING_DEBUG, &debug)
            .storage(REF_BINDING_STATS, &stats);
        let set = trace.bind(&gpu_scene, bindings)?.build(ctx, "reference")?;
        let push = std::mem::size_of::<RefPush>() as u32;
        let pipeline = |name: &str, shader: &str| ComputePipeline::new(ctx, name, shader, &[set.layout()], push, &[]);
        let camera = pipeline("reference_camera", "reference/camera.comp")?;
        let photons = pipeline("reference_photons", "reference/photons.comp")?;
        let gather = pipeline("reference_gather", "reference/gather.comp")?;
        let probe = pipeline("reference_probe", "reference/probe.comp")?;
        let ids = [
            graph.register_buffer(&accum),
            graph.register_buffer(&pixels),
            graph.register_buffer(&photon_buffer),
            graph.register_buffer(&grid),
            graph.register_buffer(&counters),
            graph.register_buffer(&debug),
            graph.register_buffer(&stats),
        ];
        Ok(Reference {
            settings: settings.clone(),
            width,
            height,
            iterations_done: 0,
            passes_done: 0,
            photons_per_iteration,
            passes_per_iteration,
            pixel_groups,
            max_groups,
            set,
            camera,
            photons,
            gather,
            probe,
            graph,
            accum,
            pixels,
            photon_buffer,
            grid,
            counters,
            debug,
            stats,
            ids,
            _uniforms: ubo,
            _trace: trace,
            _sampler: sampler,
            _scene: gpu_scene,
            ctx: ctx.clone(),
        })
    }

    pub fn width(&self) -> u32 {
        self.width
    }
    pub fn height(&self) -> u32 {
        self.height
    }
    pub fn iterations_done(&self) -> u32 {
        self.iterations_done
    }
    pub fn photons_per_iteration(&self) -> u32 {
        self.photons_per_iteration
    }
    /// Photons traced by each photon pass (0 without caustics).
    pub fn photons_per_pass(&self) -> u32 {
        if self.passes_per_iteration == 0 {
            0
        } else {
            self.settings.photons_per_pass()
        }
    }
    /// Photon passes done so far: each one progressive update of the caustics.
    pub fn passes_done(&self) -> u32 {
        self.passes_done
    }

    /// Run `count` more iterations (camera sample, then photon pass + gather as many times
    /// as [`ReferenceSettings::passes_per_iteration`]) in one submission.
    pub fn run(&mut self, count: u32) -> Result<(), RenderError> {
        let pixel_groups = self.pixel_groups;
        let photons_per_pass = self.photons_per_pass();
        // At most MAX_PHOTONS_PER_PASS photons: far below any device's limit.
        let photon_groups = dispatch_size(photons_per_pass, self.max_groups).unwrap_or([1, 1, 1]);
        let (passes, first_pass) = (self.passes_per_iteration, self.passes_done);
        let [accum, pixels, photons, grid, counters, debug, stats] = self.ids;
        let start = self.iterations_done;
        let Reference {
            graph,
            camera,
            photons: photon_pipe,
            gather,
            set,
            grid: grid_buf,
            counters: counter_buf,
            settings,
            ..
        } = self;
        let (camera, photon_pipe, gather, grid_buf, counter_buf) =
            (&*camera, &*photon_pipe, &*gather, &*grid_buf, &*counter_buf);
        let set = set.set();
        let seed = settings.seed;
        self.ctx.one_shot(|cmd| {
            let mut frame = graph.frame();
            for it in start..start + count {
                let push = RefPush { iteration: it, seed, mode: 0, count: 0 };
                frame
                    .pass("reference_camera")
                    .write(accum, Access::ComputeWrite)
                    .write(pixels, Access::ComputeWrite)
                    .write(stats, Access::ComputeWrite)
                    .record(move |cmd| {
                        cmd.compute(camera, &[set], &push, pixel_groups);
                    });
                for pass in 0..passes {
                    // Each photon pass draws its own photons.
                    let push = RefPush { iteration: first_pass + (it - start) * passes + pass, ..push };
                    frame
                        .pass("reference_clear_grid")
                        .write(grid, Access::TransferWrite)
                        .write(counters, Access::TransferWrite)
                        .record(|cmd| {
                            cmd.fill_buffer(grid_buf, u32::MAX);
                            cmd.fill_buffer(counter_buf, 0);
                        });
                    frame
                        .pass("reference_photons")
                        .write(photons, Access::ComputeWrite)
                        .write(grid, Access::ComputeWrite)
                        .write(counters, Access::ComputeWrite)
                        .write(debug, Access::ComputeWrite)
                        .write(stats, Access::ComputeWrite)
                        .record(move |cmd| {
                            cmd.compute(photon_pipe, &[set], &push, photon_groups);
                        });
                    frame
                        .pass("reference_gather")
                        .read(photons, Access::ComputeRead)
                        .read(grid, Access::ComputeRead)
                        .write(pixels, Access::ComputeWrite)
                        .write(stats, Access::ComputeWrite)
                        .record(move |cmd| {
                            cmd.compute(gather, &[set], &push, pixel_groups);
                        });
                }
            }
            frame.execute(cmd, None);
            graph.access_now(
                cmd,
                &[],
                &[
                    (accum, Access::HostRead),
                    (pixels, Access::HostRead),
                    (debug, Access::HostRead),
                    (stats, Access::HostRead),
                ],
            );
        })?;
        self.iterations_done += count;
        self.passes_done += count * self.passes_per_iteration;
        Ok(())
    }

    /// Run every iteration of the settings, calling `progress(done, total)` after each batch.
    /// Batches grow until one takes about half a second, so progress stays live.
    pub fn run_all(&mut self, mut progress: impl FnMut(u32, u32)) -> Result<(), RenderError> {
        let total = self.settings.spp;
        let mut batch = 1u32;
        while self.iterations_done < total {
            let n = batch.min(total - self.iterations_done);
            let t = std::time::Instant::now();
            self.run(n)?;
            progress(self.iterations_done, total);
            if t.elapsed().as_secs_f32() < 0.25 {
                batch = (batch * 2).min(64);
            }
        }
        Ok(())
    }

    /// The converged estimate so far, linear RGBA f32 (row 0 at the top): the mean of the
    /// camera paths plus the photon-mapped caustics tau / (pi R^2 iterations).
    pub fn image(&self) -> Vec<f32> {
        let accum: &[[f32; 4]] = bytemuck::cast_slice(self.accum.read());
        let pixels: &[PixelState] = bytemuck::cast_slice(self.pixels.read());
        // Each photon pass is one progressive estimate: tau sums over all of them.
        let k = self.passes_done.max(1) as f32;
        let mut out = Vec::with_capacity(accum.len() * 4);
        for (a, p) in accum.iter().zip(pixels) {
            let n = a[3].max(1.0);
            let r = p.vp_pos[3];
            let caustic = if self.passes_done > 0 && r > 0.0 { 1.0 / (std::f32::consts::PI * r * r * k) } else { 0.0 };
            for (sum, tau) in a[..3].iter().zip(&p.tau_n[..3]) {
                let v = sum / n + tau * caustic;
                out.push(if v.is_finite() { v } else { 0.0 });
            }
            out.push(1.0);
        }
        out
    }

    /// What the kernels counted so far: invocations whose driver loop budget ran out and
    /// paths that ended at the volume's step cap.
    pub fn stats(&self) -> ReferenceStats {
        let s: &[u32] = bytemuck::cast_slice(self.stats.read());
        let at = |slot: u32| s[slot as usize] as u64;
        ReferenceStats {
            cut_camera: at(REF_STAT_CUT_CAMERA),
            cut_photons: at(REF_STAT_CUT_PHOTONS),
            cut_gather: at(REF_STAT_CUT_GATHER),
            step_cap_camera: at(REF_STAT_STEP_CAP_CAMERA),
            step_cap_photons: at(REF_STAT_STEP_CAP_PHOTONS),
        }
    }

    /// The caustic part alone (for tests of convergence and energy).
    pub fn caustic_image(&self) -> Vec<f32> {
        let pixels: &[PixelState] = bytemuck::cast_slice(self.pixels.read());
        let k = self.passes_done.max(1) as f32;
        pixels
            .iter()
            .flat_map(|p| {
                let r = p.vp_pos[3];
                let s = if r > 0.0 && self.passes_done > 0 { 1.0 / (std::f32::consts::PI * r * r * k) } else { 0.0 };
                [p.tau_n[0] * s, p.tau_n[1] * s, p.tau_n[2] * s, 1.0]
            })
            .collect()
    }

    /// Number of non-finite values in every buffer the reference accumulates into (the
    /// per-pixel sums and the photon-mapping state): the stability tests want zero.
    pub fn non_finite_values(&self) -> usize {
        let f: &[f32] = bytemuck::cast_slice(self.accum.read());
        let p: &[f32] = bytemuck::cast_slice(self.pixels.read());
        let d: &[f32] = bytemuck::cast_slice(self.debug.read());
        let photons = self.photons_per_pass() as usize;
        f.iter().chain(p).chain(&d[..8 * photons]).filter(|v| !v.is_finite()).count()
    }

    /// The photon-mapping state of pixel `index`: tau (rgb) and N, visible point and radius R,
    /// its normal and validity, its weight (for tests and debugging).
    pub fn pixel_state(&self, index: usize) -> [[f32; 4]; 4] {
        let pixels: &[PixelState] = bytemuck::cast_slice(self.pixels.read());
        let p = pixels[index];
        [p.tau_n, p.vp_pos, p.vp_normal, p.vp_weight]
    }

    /// (flux rgb, outcome) of every photon of the last photon pass (PHOTON_* outcomes).
    pub fn photon_outcomes(&self) -> Vec<[f32; 4]> {
        let all: &[[f32; 4]] = bytemuck::cast_slice(self.debug.read());
        all[..self.photons_per_pass() as usize].to_vec()
    }

    /// Where each photon of the last photon pass was deposited (0 unless PHOTON_DEPOSITED).
    pub fn photon_positions(&self) -> Vec<Vec3> {
        let all: &[[f32; 4]] = bytemuck::cast_slice(self.debug.read());
        let n = self.photons_per_pass() as usize;
        all[n..2 * n].iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect()
    }

    /// Run the probe kernel on records of 3 vec4s (see glsl/reference/probe.comp); tests.
    pub fn probe(&mut self, mode: Probe, records: &[[[f32; 4]; 3]]) -> Result<Vec<[[f32; 4]; 3]>, RenderError> {
        let capacity = self.debug.size as usize / 48;
        let mut out = Vec::with_capacity(records.len());
        for chunk in records.chunks(capacity.max(1)) {
            self.debug.write(0, bytemuck::cast_slice(chunk));
            let debug = self.ids[5];
            let (graph, probe, set) = (&mut self.graph, &self.probe, self.set.set());
            let push = RefPush { iteration: 0, seed: 0, mode: mode as u32, count: chunk.len() as u32 };
            let groups = dispatch_size(chunk.len() as u32, self.max_groups).unwrap_or([1, 1, 1]);
            self.ctx.one_shot(|cmd| {
                let mut frame = graph.frame();
                frame.pass("reference_probe").write(debug, Access::ComputeWrite).record(move |cmd| {
                    cmd.compute(probe, &[set], &push, groups);
                });
                frame.execute(cmd, None);
                graph.access_now(cmd, &[], &[(debug, Access::HostRead)]);
            })?;
            let data: &[[[f32; 4]; 3]] = bytemuck::cast_slice(&self.debug.read()[..chunk.len() * 48]);
            out.extend_from_slice(data);
        }
        Ok(out)
    }
}

/// The camera's view matrix (re-exported for tests that project points).
pub fn view_matrix(scene: &Scene) -> Mat4 {
    scene.camera.view()
}

impl Drop for Reference {
    fn drop(&mut self) {
        // Pipelines and layouts are destroyed immediately: the GPU must be idle first.
        let _ = self.ctx.wait_idle();
        let _ = (&self.photon_buffer, &self.grid, &self.counters);
    }
}
