//! The eikonal light simulator (Ihrke et al. 2007, sections 4.2 and 5.2,
//! ../shared/papers/ihrke2007-eikonal-rendering.md): adaptive wavefront tracing of every
//! light of the scene through the smoothed index field, producing the irradiance and direction volumes that
//! the view renderer's single scattering (section 5.3, Eqs. 6-7, glsl/eikonal/scatter.glsl)
//! and the floor under the volume (deferred shading) read.
//!
//! - Section 4.2 / 5.2: the wavefront is a list of patches of four particles each (corner
//!   positions, directions v = n dx/ds, RGB flux), initialized on the CPU as a planar
//!   wavefront (directional light) or a spherical one (point light) covering the box
//!   ([`initial_wavefront`]).
//! - Section 5.2.1 (glsl/eikonal/light_step.glsl): every step advances the corners with the
//!   equal-time ray equation, Eqs. 14-15, and absorbs with Eq. 18; the irradiance of a patch
//!   is its flux over its area (Eq. 17, intensity law Eq. 16). Where every corner is in a
//!   region of constant index (the brick map of volume.rs `uniform_reach`), a patch takes up to
//!   `light_leaps` further steps in the same dispatch as the straight line Eqs. 14-15 give
//!   there, each classified and deposited as a step of its own: the same wavefront in fewer
//!   dispatches.
//! - Section 5.2.2: each step's segment of the patch midpoint is voxelized by the
//!   track-length estimate of the intensity law (flux * length / voxel volume, splatted
//!   trilinearly, summed over all rays: glsl/eikonal/light_step.glsl says why not the
//!   paper's highest-energy dE = flux / area, which made the floor caustic's peak several
//!   times too bright), into an additive accumulator that light_resolve.glsl turns into the
//!   irradiance and (vector) direction volumes. The paper's rule is one setting away
//!   (`render.eikonal.voxelization = "highest_energy"`: an atomic max on each voxel's energy in
//!   the step kernel, then glsl/eikonal/light_commit.comp writes the winning ray). The
//!   track-length deposits go only to the voxels that the renderer reads (near a surface, or
//!   in a scattering volume: src/technique/eikonal/read_mask.rs), unless
//!   `render.eikonal.light_deposits = "everywhere"`.
//! - Section 5.2.3: each patch is classified 0/1/4 and the list is compacted and expanded by
//!   the HistoPyramid (src/technique/eikonal/histopyramid.rs) and glsl/eikonal/light_expand.comp.
//!
//! Because the accumulator only adds, the simulation is a sequence of independent runs
//! ([`LightRun`]) depositing into it: one per light (section 3.2: "a discrete number of
//! light sources", Eqs. 6-7 sum over them), per index channel of a dispersive volume
//! (section 5.3: "a separate refractive index field for each RGB channel"; each channel's
//! wavefront carries only that channel's flux), and per tile of the initial wavefront,
//! whose patches evolve independently (section 5.2: "the wavefront patches are independent
//! and thus can be stacked"), so that no list outgrows `max_patches`: the outputs of a step
//! past the list go to a spill list of the same size, and a later run continues them from
//! there (the same patches at the same time of their own evolution: nothing is simulated
//! twice). Only a run whose spill list fills too is taken back (rerun with negative
//! deposits) and split into four.
//!
//! The irradiance volume covers the volume's box extended `light_below` metres down, so that
//! a floor just under the volume lies inside it: the simplest honest way to get the caustic
//! onto the table (Fig. 1 left). The patches keep propagating through the air (n = 1) of
//! that extension, and deferred shading reads the irradiance at the floor (Lambert's cosine
//! with the stored direction) in place of the light's unoccluded direct term.
//!
//! Steps run in batches of up to [`LIGHT_BATCH`] per command buffer with indirect dispatches
//! sized by the device; only after a batch is the patch count read back to decide whether to
//! go on, and the spill list emptied. A batch is shortened to what the spill list can hold at
//! the growth the previous batch showed ([`spill_safe_batch`]).
use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;
use std::sync::Arc;
use std::time::Instant;

use glam::{DVec3, Vec3};

use crate::gpu::{
    vk, Access, Buffer, BufferView, ComputePipeline, DescriptorSet, GpuContext, GpuResult, Image, ImageDesc,
    MemoryLocation, Progress, Sampler, SamplerDesc, Spec, TimestampPool, TimestampQuery,
};
use crate::graph::{Bindings, BoundSet, BufferId, Frame, FrameGraph, ImageId};
use crate::scene::techniques::{EikonalParams, LightDeposits, LightDirectionSplat, LightIntegrator, LightVoxelization};
use crate::scene::{IndexProfile, Light, Volume};
use crate::technique::scene_specialization;
use crate::{
    EIKONAL_EULER, EIKONAL_GROUP, EIKONAL_MIDPOINT, EIKONAL_RK4, LIGHT_BINDING_ACCUM, LIGHT_BINDING_DIRECTION,
    LIGHT_BINDING_DST, LIGHT_BINDING_FIELD, LIGHT_BINDING_IRRADIANCE, LIGHT_BINDING_SRC,
};

use super::histopyramid::{initial_state, level_lengths, HistoPyramid};
use super::volume::{box_specs, prepare_volume, IndexField, RayState, VolumeTextures, LIGHT_BOX};
pub use crate::shader_structs::Patch;
use crate::shader_structs::{AirFace, RunPush};
use crate::technique::baseline::fullscreen::{fragment_set, FullscreenDesc, FullscreenPass};

/// §5.2's light simulation (run when the technique is created) and the diffuse receivers
/// inside its irradiance volume: the pass name.
pub const EIKONAL_LIGHT: &str = "eikonal_light";

/// Simulation steps recorded per command buffer between two patch-count readbacks, at most
/// (fewer where the spill list could not hold a longer batch's overflow: [`spill_safe_batch`]).
pub const LIGHT_BATCH: u32 = 16;
/// The task name of the simulation's [`Progress`] reports.
pub const LIGHT_SIMULATION: &str = "light simulation";

/// Most patches of an initial wavefront: a list of them (128 bytes each) fits one 128 MiB
/// storage-buffer binding (lavapipe's maxStorageBufferRange), like `max_patches`.
pub const MAX_INITIAL_PATCHES: u32 = 900_000;

/// Most steps of one simulation (a wavefront trapped by total internal reflection stops here).
pub const MAX_LIGHT_STEPS: u32 = 1 << 16;

/// A patch's v[0].w is its step count times this plus a substep mark (glsl/eikonal/
/// light_common.glsl `MARK_SCALE`): at most 2^16 * 128 = 2^23, exact in f32.
const STEP_MARK_SCALE: u32 = 128;

impl Patch {
    pub fn corner(&self, c: usize) -> Vec3 {
        Vec3::from_slice(&self.x[c][..3])
    }
    pub fn direction(&self, c: usize) -> Vec3 {
        Vec3::from_slice(&self.v[c][..3])
    }
    /// The flux R, G, B (W), in the corners' x.w (src/shader_structs.rs `Patch`).
    pub fn flux(&self) -> Vec3 {
        Vec3::new(self.x[0][3], self.x[1][3], self.x[2][3])
    }
    pub fn set_flux(&mut self, flux: Vec3) {
        for c in 0..3 {
            self.x[c][3] = flux[c];
        }
    }
    /// The steps taken in its run (its parent's before it was tessellated).
    pub fn steps(&self) -> u32 {
        self.v[0][3] as u32 / STEP_MARK_SCALE
    }
    /// The number of the initial particle at corner `c`, None for a particle created by
    /// tessellation (x[3].w: P * 8 + code, see `Patch`).
    pub fn particle(&self, c: usize) -> Option<u32> {
        let w = self.x[3][3] as u32;
        let (first, code) = (w / 8, w % 8);
        (code == 4 || code == c as u32).then_some(4 * first + c as u32)
    }
    /// The patch's vector area (half the cross product of its diagonals), as the shaders.
    pub fn normal(&self) -> Vec3 {
        0.5 * (self.corner(2) - self.corner(0)).cross(self.corner(3) - self.corner(1))
    }
    pub fn mid(&self) -> Vec3 {
        0.25 * (0..4).map(|c| self.corner(c)).sum::<Vec3>()
    }
}

/// One run of the simulator: a tile `start..end` of light `light`'s initial wavefront (or,
/// with `spill`, of the patches an earlier run spilled), travelling through index slab
/// `slab` and carrying the flux of `channel` only (None: all three), depositing with `sign`
/// (-1 takes an overflowing run's deposits back).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LightRun {
    pub light: usize,
    pub slab: u32,
    pub channel: Option<usize>,
    pub start: usize,
    pub end: usize,
    pub sign: f32,
    /// Index of the spilled patches this run continues (None: the initial wavefront).
    pub spill: Option<usize>,
}

/// What one run did.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct RunStats {
    pub light: usize,
    /// The channel of a dispersive volume's run (None: all three).
    pub channel: Option<usize>,
    /// The tile: initial patches `start..end` of the light's wavefront.
    pub start: usize,
    pub end: usize,
    /// -1: the take-back of an overflowing tile.
    pub sign: f32,
    /// Dispatches of the step kernel (each advances every live patch by 1 to
    /// `light_substeps` steps).
    pub steps: u32,
    /// Patch steps taken, summed over the run (as the step kernel counts them).
    pub patch_steps: u64,
    pub peak_patches: u32,
    pub dropped_patches: u32,
    /// Patches past the list's capacity, continued by a later run.
    pub spilled_patches: u32,
    /// The spilled patches this run continued (None: a tile of the initial wavefront).
    pub spill: Option<usize>,
    /// GPU time of the run's kernels (timestamps around every dispatch), ms.
    pub gpu_ms: f64,
}

/// GPU time of one light-simulation kernel, summed over every dispatch of a simulation.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct KernelTime {
    /// The frame-graph pass name: `eikonal_light_step` (Eqs. 14-15 advance, Eq. 18
    /// absorption, the §5.2.2 deposit and the §5.2.3 classification, one kernel),
    /// `histopyramid_reduce` (one dispatch per pyramid level), `histopyramid_total`,
    /// `eikonal_light_commit` (the paper's voxelization only: the winning rays' writes),
    /// `histopyramid_traverse` (the compaction/expansion descent), `eikonal_light_expand`
    /// (the output generator) and `eikonal_light_resolve` (accumulator to volumes, once).
    pub name: String,
    pub ms: f64,
    pub dispatches: u64,
}

/// What a simulation did: steps, patch count after every step, peak, clamp losses, summed
/// or concatenated over its runs (one per light, channel and tile; `runs`).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct LightStats {
    /// Initial patches of every light's wavefront (each channel's run starts them again).
    pub initial_patches: u32,
    /// Of those, the patches not simulated because their straight beams only cross air
    /// (`skip_air`): their light was added in closed form.
    pub skipped_patches: u32,
    /// Dispatches of the step kernel in all runs.
    pub steps: u32,
    /// Patches after each dispatch (the HistoPyramid's output count), run after run.
    pub patch_counts: Vec<u32>,
    /// The largest list of any run.
    pub peak_patches: u32,
    /// Patches lost because tessellation exceeded `max_patches` in a run that could not be
    /// split further (a tile of one patch); overflowing tiles are split and rerun instead.
    pub dropped_patches: u32,
    /// Runs whose spill list overflowed too, taken back and split into four.
    pub split_tiles: u32,
    /// Patches that overflowed a list and were continued from the spill list by a later run.
    pub spilled_patches: u64,
    pub runs: Vec<RunStats>,
    /// Wall-clock seconds of the whole simulation, uploads and readbacks included.
    pub seconds: f64,
    /// Patch steps taken in every run: the work the step kernel did (take-backs included).
    pub patch_steps: u64,
    /// GPU time per kernel over the whole simulation, in the order they first ran (empty
    /// where the queue has no timestamps).
    pub kernels: Vec<KernelTime>,
    /// GPU time of all kernels, ms.
    pub gpu_ms: f64,
    /// GPU time thrown away by tile splitting, ms: the runs that overflowed and were split,
    /// and their take-backs.
    pub overflow_ms: f64,
    /// Whether the deposits were added by float atomics (else a compare-and-swap loop).
    pub float_atomics: bool,
    /// Whether every deposit added one channel sum for the three of a grey light (`GRAY`).
    pub gray: bool,
}

impl LightStats {
    /// How the deposits were added, for the printed reports.
    pub fn deposits(&self) -> &'static str {
        if self.float_atomics {
            "float atomics"
        } else {
            "compare-and-swap"
        }
    }

    /// One line per kernel for `prism render` and `prism bench`: time, share and dispatches.
    pub fn kernel_lines(&self) -> Vec<String> {
        let total = self.gpu_ms.max(f64::MIN_POSITIVE);
        self.kernels
            .iter()
            .map(|k| {
                format!(
                    "  {:<24} {:>12.1} ms {:>5.1}% {:>9} dispatches",
                    k.name,
                    k.ms,
                    100.0 * k.ms / total,
                    k.dispatches
                )
            })
            .collect()
    }
}

/// Add the timestamped passes of one submission to `kernels` (by name); returns their sum.
fn add_kernel_times(kernels: &mut Vec<KernelTime>, pool: &TimestampPool, queries: &[TimestampQuery]) -> GpuResult<f64> {
    let last = queries.iter().map(|q| q.end + 1).max().unwrap_or(0);
    let Some(ticks) = pool.read_ticks(last)? else { return Ok(0.0) };
    let mut sum = 0.0;
    for q in queries {
        let ms = pool.ticks_to_ms(ticks[q.start as usize], ticks[q.end as usize]);
        sum += ms;
        match kernels.iter_mut().find(|k| k.name == q.name) {
            Some(k) => {
                k.ms += ms;
                k.dispatches += 1;
            }
            None => kernels.push(KernelTime { name: q.name.clone(), ms, dispatches: 1 }),
        }
    }
    Ok(sum)
}

/// The irradiance volume's box and resolution: the volume's box and voxels, extended
/// `below` metres down and `side` metres along -x, +x, -z, +z (whole voxels each).
pub fn light_grid(volume: &Volume, below: f32, side: f32) -> (Vec3, Vec3, [u32; 3]) {
    let voxel = volume.voxel_size();
    let whole = |m: f32, v: f32| if m > 0.0 { (m / v).ceil() as u32 } else { 0 };
    let (ex, ey, ez) = (whole(side, voxel.x), whole(below, voxel.y), whole(side, voxel.z));
    let lo = Vec3::new(ex as f32 * voxel.x, ey as f32 * voxel.y, ez as f32 * voxel.z);
    let hi = Vec3::new(ex as f32 * voxel.x, 0.0, ez as f32 * voxel.z);
    let [rx, ry, rz] = volume.resolution;
    (volume.min - lo, volume.max + hi, [rx + 2 * ex, ry + ey, rz + 2 * ez])
}

/// Whether the simulation deposits only where its volumes are read (`light_deposits`):
/// only the track-length voxelization, which sums; the paper's keeps one ray per voxel.
pub fn deposits_where_read(params: &EikonalParams) -> bool {
    params.light_deposits == LightDeposits::Read && params.voxelization == LightVoxelization::TrackLength
}

/// Whether the device can add floats atomically to an R32_SFLOAT storage image: the
/// extension's feature and the format's atomic support.
pub fn float_atomics_supported(ctx: &GpuContext) -> bool {
    ctx.info.image_float_atomic_add
        && ctx.supports_format(vk::Format::R32_SFLOAT, vk::FormatFeatureFlags::STORAGE_IMAGE_ATOMIC)
}

/// The largest refractive index of the volume (for the step budget).
fn max_index(volume: &Volume) -> f32 {
    match volume.index {
        IndexProfile::Constant { n, .. } => n.max(1.0),
        IndexProfile::Luneburg { .. } => std::f32::consts::SQRT_2,
        IndexProfile::Linear { .. } => (0..8)
            .map(|c| {
                let p = Vec3::new(
                    if c & 1 == 0 { volume.min.x } else { volume.max.x },
                    if c & 2 == 0 { volume.min.y } else { volume.max.y },
                    if c & 4 == 0 { volume.min.z } else { volume.max.z },
                );
                volume.index.n(p.as_dvec3()) as f32
            })
            .fold(1.0, f32::max),
    }
}

/// A unit tangent frame (t1, t2) with t1 x t2 = w.
fn frame(w: Vec3) -> (Vec3, Vec3) {
    let a = if w.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let t1 = w.cross(a).normalize();
    (t1, w.cross(t1))
}

/// One face of a light's initial wavefront: a k x k grid of patches. Patch (i, j) of a point
/// light's face starts at radius `r0` with the directions axis + t1 u + t2 v for u in
/// -half + 2 half [i, i + 1] / k (v alike with j): a gnomonic grid, so the straight beam of a
/// patch is exactly the cone over its cell of the plane at unit distance. A directional
/// light's patch starts at origin + t1 u + t2 v and travels along the axis.
#[derive(Clone, Copy, Debug)]
pub struct WavefrontFace {
    pub point: bool,
    /// The point light's position, or the directional wavefront's centre.
    pub origin: Vec3,
    pub axis: Vec3,
    pub t1: Vec3,
    pub t2: Vec3,
    /// tan of the half-angle (point) or the half-width in metres (directional).
    pub half: f32,
    /// Patches per side.
    pub k: u32,
    /// The radius a point light's patches start at.
    pub r0: f32,
    /// Intensity W/sr (point) or irradiance W/m^2 (directional).
    pub power: Vec3,
}

impl WavefrontFace {
    /// Grid coordinate a = 0..k of u (or v).
    fn coordinate(&self, a: u32) -> f32 {
        -self.half + 2.0 * self.half * a as f32 / self.k as f32
    }

    /// Position and unit direction of grid corner (a, b).
    fn corner(&self, a: u32, b: u32) -> (Vec3, Vec3) {
        let (u, v) = (self.coordinate(a), self.coordinate(b));
        if self.point {
            let d = (self.axis + self.t1 * u + self.t2 * v).normalize();
            (self.origin + d * self.r0, d)
        } else {
            (self.origin + self.t1 * u + self.t2 * v, self.axis)
        }
    }

    /// (u, v) of the straight ray of this face through `x`; None behind a point light's face.
    fn plane_coordinates(&self, x: Vec3) -> Option<(f32, f32)> {
        let r = x - self.origin;
        if self.point {
            let z = r.dot(self.axis);
            (z > 0.0).then(|| (r.dot(self.t1) / z, r.dot(self.t2) / z))
        } else {
            Some((r.dot(self.t1), r.dot(self.t2)))
        }
    }

    /// The cells (clamped to the grid) whose coordinate range overlaps lo..=hi.
    fn cells(&self, lo: f32, hi: f32) -> Option<std::ops::RangeInclusive<u32>> {
        if hi < -self.half || lo > self.half {
            return None;
        }
        let k = self.k as f32;
        let cell = |u: f32| (((u + self.half) * k / (2.0 * self.half)).floor()).clamp(0.0, k - 1.0) as u32;
        Some(cell(lo)..=cell(hi))
    }
}

/// The faces of `light`'s initial wavefront (section 5.2: "a planar wavefront (directional
/// light source) or a spherical wavefront (point light source) ... large enough to cover the
/// simulation volume"), `per_side` x `per_side` patches per face, just outside the bounding
/// sphere of the box `min`..`max`, in air (n = 1). A point light inside the bounding sphere
/// starts on a small sphere around it, all six cube faces.
pub fn wavefront_faces(volume: &Volume, min: Vec3, max: Vec3, light: &Light, per_side: u32) -> Vec<WavefrontFace> {
    let center = 0.5 * (min + max);
    let radius = 0.5 * (max - min).length();
    let voxel = volume.voxel_size().min_element();
    // At most MAX_INITIAL_PATCHES in all (the list must fit one storage-buffer binding):
    // fewer per side for the six faces of a point light inside the bounding sphere.
    let faces = match *light {
        Light::Point { position, .. } if (center - position).length() <= radius + voxel => 6,
        _ => 1,
    };
    let most = ((MAX_INITIAL_PATCHES / faces) as f64).sqrt() as u32;
    let k = per_side.clamp(1, most);
    match *light {
        Light::Directional { direction, irradiance } => {
            let d = direction.normalize();
            let (t1, t2) = frame(d);
            let origin = center - d * (radius + voxel);
            vec![WavefrontFace { point: false, origin, axis: d, t1, t2, half: radius, k, r0: 0.0, power: irradiance }]
        }
        Light::Point { position, intensity } => {
            let to_center = center - position;
            let dist = to_center.length();
            // (axis, tan of the half-angle, start radius) per face.
            let faces: Vec<(Vec3, f32, f32)> = if dist > radius + voxel {
                let tan = radius / (dist * dist - radius * radius).sqrt();
                vec![(to_center / dist, tan, dist - radius - voxel)]
            } else {
                [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z]
                    .iter()
                    .map(|&a| (a, 1.0, 0.5 * voxel))
                    .collect()
            };
            faces
                .into_iter()
                .map(|(w, tan, r0)| {
                    let (t1, t2) = frame(w);
                    WavefrontFace { point: true, origin: position, axis: w, t1, t2, half: tan, k, r0, power: intensity }
                })
                .collect()
        }
    }
}

/// The initial wavefront of `faces` ([`wavefront_faces`]), face after face, row (j) after
/// row, i fastest, in air or in `volume`'s index where a corner starts inside it. A
/// directional light's patches carry its irradiance E times their area; a point light's carry
/// I / r0^2 times their area at radius r0.
pub fn initial_wavefront(volume: &Volume, faces: &[WavefrontFace]) -> Vec<Patch> {
    let n_at = |x: Vec3| -> f32 {
        let inside = x.cmpge(volume.min).all() && x.cmple(volume.max).all();
        if inside {
            volume.index.n(x.as_dvec3()) as f32
        } else {
            1.0
        }
    };
    let mut patches = Vec::new();
    for face in faces {
        let e = if face.point { face.power / (face.r0 * face.r0) } else { face.power };
        for j in 0..face.k {
            for i in 0..face.k {
                let corners =
                    [face.corner(i, j), face.corner(i + 1, j), face.corner(i + 1, j + 1), face.corner(i, j + 1)];
                // x[3].w numbers the initial particles, 4 per patch (`Patch::particle`), so
                // that tests can follow them; exact in f32 below 2^21 patches.
                let id = patches.len();
                let mut p = Patch::default();
                for (c, &(x, d)) in corners.iter().enumerate() {
                    p.x[c] = x.extend(0.0).to_array();
                    p.v[c] = (d * n_at(x)).extend(0.0).to_array();
                }
                p.x[3][3] = (8 * id + 4) as f32;
                let area = p.normal().length();
                p.set_flux(e * area);
                patches.push(p);
            }
        }
    }
    patches
}

/// The skip flags of light_resolve.glsl, per cell of `faces`: bit 0 the cell's patch was
/// skipped (`skip`, [`air_patches`]), bit 1 a cell within the reach of a voxel's deposit
/// footprint (x +- one voxel, anywhere in the box `min`..`max`) differs from it, so that the
/// voxels whose rays pass this cell need the footprint's mean of the flags; elsewhere the
/// cell's own flag is that mean.
pub fn air_flags(faces: &[WavefrontFace], skip: &[bool], voxel: f32, min: Vec3, max: Vec3) -> Vec<u32> {
    let mut flags = Vec::with_capacity(skip.len());
    let mut first = 0;
    for face in faces {
        let k = face.k as usize;
        let cells = &skip[first..first + k * k];
        first += k * k;
        // How far a footprint of half-diagonal sqrt(3) voxels moves u (or v): as far for a
        // directional light; for a point light (u = x_t / z) at most (1 + tan) of it over the
        // box's nearest distance from the light.
        let step = 3f32.sqrt() * voxel;
        let reach = if face.point {
            let nearest = (face.origin.clamp(min, max) - face.origin).length().max(face.r0);
            step * (1.0 + face.half) / nearest
        } else {
            step
        };
        let r = ((reach / (2.0 * face.half / face.k as f32)).ceil() as usize).min(k);
        for j in 0..k {
            for i in 0..k {
                let own = cells[j * k + i];
                let near_edge = (j.saturating_sub(r)..(j + r + 1).min(k))
                    .any(|b| (i.saturating_sub(r)..(i + r + 1).min(k)).any(|a| cells[b * k + a] != own));
                flags.push(u32::from(own) | (u32::from(near_edge) << 1));
            }
        }
    }
    flags
}

/// Which patches of `faces` (in [`initial_wavefront`]'s order) only ever cross air: their
/// straight beams pass no box of `medium` widened by `margin`. A box is projected onto each
/// face's plane of (u, v) coordinates and every cell its corners' bounding rectangle overlaps
/// is simulated; the gnomonic grid maps the beams to these cells and the box's silhouette
/// into the rectangle, so the test is conservative. A box reaching behind a point light's
/// face (the light inside it, or beside it) keeps the whole face simulated.
pub fn air_patches(faces: &[WavefrontFace], medium: &[(Vec3, Vec3)], margin: f32) -> Vec<bool> {
    let mut skip = Vec::new();
    for face in faces {
        let k = face.k as usize;
        let mut cells = vec![true; k * k];
        for &(lo, hi) in medium {
            let (lo, hi) = (lo - Vec3::splat(margin), hi + Vec3::splat(margin));
            let corners = (0..8).map(|c| {
                Vec3::new(
                    if c & 1 == 0 { lo.x } else { hi.x },
                    if c & 2 == 0 { lo.y } else { hi.y },
                    if c & 4 == 0 { lo.z } else { hi.z },
                )
            });
            let uv: Vec<Option<(f32, f32)>> = corners.map(|x| face.plane_coordinates(x)).collect();
            if uv.iter().all(|c| c.is_none()) {
                continue; // wholly behind a point light's face: none of its rays go there
            }
            if uv.iter().any(|c| c.is_none()) {
                cells.fill(false);
                break;
            }
            let (u, v): (Vec<f32>, Vec<f32>) = uv.into_iter().flatten().unzip();
            let range = |w: &[f32]| {
                face.cells(w.iter().copied().fold(f32::MAX, f32::min), w.iter().copied().fold(f32::MIN, f32::max))
            };
            let (Some(iu), Some(iv)) = (range(&u), range(&v)) else { continue };
            for j in iv {
                for i in iu.clone() {
                    cells[j as usize * k + i as usize] = false;
                }
            }
        }
        skip.extend(cells);
    }
    skip
}

/// The GPU light simulator for the lights of a scene and one volume.
pub struct LightSim {
    pub hp: HistoPyramid,
    lists: [Buffer; 2],
    // The lists as texels, which the kernels read their patches through (light_common.glsl).
    _list_texels: [crate::gpu::BufferView; 2],
    list_ids: [BufferId; 2],
    /// Outputs of a step past the list's capacity (histopyramid_total.comp), read back after
    /// the run and continued by a run of their own.
    spill: Buffer,
    spill_id: BufferId,
    /// The spilled patches of every run so far (`LightRun::spill` indexes them).
    spilled: Vec<Vec<Patch>>,
    /// The current run's spilled patches, drained from `spill` after every batch so that
    /// the spill list only has to hold one batch's overflow.
    pending: Vec<Patch>,
    /// Initial patches per run (`tile_patches`), also of the runs that continue spills.
    tile: usize,
    /// Six f32 sums per voxel in six slabs along y: irradiance R, G, B and the vector
    /// irradiance, and a seventh: the vector's weight with the nearest direction splat, the
    /// ray's energy with the paper's voxelization (light_common.glsl `accum`): R32_SFLOAT with
    /// float atomics, else the bits in R32_UINT.
    _accum: Image,
    /// Whether the deposits are added by float atomics (else a compare-and-swap loop).
    pub float_atomics: bool,
    /// Whether the lights are grey and the medium colourless: one channel sum per deposit.
    gray: bool,
    /// Dispatches of the step kernel between two compactions (`light_substeps`).
    substeps: u32,
    accum_id: ImageId,
    /// rgb: the irradiance sum_j dE_omega,j (W/m^2) of all rays through the voxel; a: 1
    /// where lit.
    pub irradiance: Rc<Image>,
    pub irradiance_id: ImageId,
    /// xyz: the vector irradiance sum_j (E_r + E_g + E_b)_j l_j; w: sum_j (E_r + E_g + E_b)_j.
    pub direction: Rc<Image>,
    pub direction_id: ImageId,
    /// List 0 -> 1 and list 1 -> 0.
    sets: BoundSet,
    step: ComputePipeline,
    /// The paper's voxelization only: writes each voxel's highest-energy ray after a step
    /// (glsl/eikonal/light_commit.comp).
    commit: Option<ComputePipeline>,
    expand: ComputePipeline,
    resolve: ComputePipeline,
    field_id: ImageId,
    /// Nearest, or the device's trilinear filter ([`super::eikonal_view::filters_field`]).
    _field_sampler: Sampler,
    extinction_id: ImageId,
    /// The boundary band and its reflectance factor (the Fresnel loss).
    band_ids: [ImageId; 2],
    /// Which list holds the current patches.
    current: usize,
    /// Steps of the current run.
    pub steps_taken: u32,
    pub max_steps: u32,
    /// The current run's initial patches (as uploaded: a dispersive run's flux masked to
    /// its channel).
    pub initial: Vec<Patch>,
    /// Every light's initial wavefront, less the patches skipped as air-only (`skip_air`).
    pub wavefronts: Vec<Vec<Patch>>,
    /// Per light, the largest initial patch's flux per channel (skipped patches included).
    largest: Vec<Vec3>,
    /// Initial patches not simulated: only air on their way (`skip_air`).
    skipped: u32,
    /// The faces of every light's wavefront and their skip flags, which the resolve kernel
    /// reads to add the skipped patches' light, and the read mask of the step kernel's
    /// deposits.
    _buffers: [Buffer; 3],
    _read_texels: BufferView,
    /// The run in progress and the runs still to do.
    pub run: LightRun,
    pub queue: VecDeque<LightRun>,
    /// The irradiance volume's box and resolution.
    pub light_min: Vec3,
    pub light_max: Vec3,
    pub resolution: [u32; 3],
    /// The energy threshold in W of the current run (a fraction of the largest initial
    /// patch flux of its light and channel).
    pub min_flux: f32,
    threshold: f32,
    /// Timestamps around every pass of a batch (None where the queue has none).
    timestamps: Option<TimestampPool>,
    /// GPU time per kernel since the simulation began, and of the current run.
    pub kernels: Vec<KernelTime>,
    run_gpu_ms: f64,
    /// Patches of the current run after its last batch.
    run_count: u32,
    /// Wall time per step of the last batch, to fit batches into a deadline.
    seconds_per_step: Option<f64>,
    /// Dispatches the next batch may take so that the spill list holds its overflow
    /// ([`spill_safe_batch`] of the last batch).
    spill_batch: u32,
    /// The simulation so far, while it is in progress ([`LightSim::advance`]).
    progress: Option<SimProgress>,
    /// Its statistics once finished.
    finished: Option<LightStats>,
}

/// What [`LightSim::advance`] keeps between calls.
struct SimProgress {
    start: Instant,
    /// Runs finished so far.
    done_runs: u64,
    stats: LightStats,
}

/// The longest batch, at most [`LIGHT_BATCH`] dispatches and at least one, whose outputs past
/// a list of `capacity` patches are expected to fit half of the spill list (emptied after
/// every batch), given the last batch: `counts`, the list's length before and after each of
/// its dispatches, and `spilled`, the patches it spilled. A wavefront grows by a factor per
/// dispatch that changes slowly (tessellation proceeds with the spread of the rays), so the
/// next batch is predicted with the largest factor the last one showed: between two lengths
/// under the capacity, their ratio; over the dispatches that filled the list, their outputs
/// (the list and the spill) over their inputs. The half left free is for growth that speeds up
/// within the batch. Without this, a wavefront that grows by more than 1/16 of the list per
/// dispatch once the list is full (straight steps through uniform regions advance a patch
/// up to 17 steps per dispatch) overflows the spill list within one batch of 16, and its
/// tile is taken back and simulated again.
pub fn spill_safe_batch(counts: &[u32], spilled: u32, capacity: u32, spill_capacity: u32) -> u32 {
    let capacity = capacity.max(1) as f64;
    let mut growth: f64 = 1.0;
    // Over the dispatches that filled the list: what they were given and what they made of
    // it (the list's length and their share of the spill).
    let (mut full_inputs, mut full_outputs) = (0.0, spilled as f64);
    for w in counts.windows(2) {
        if (w[1] as f64) < capacity {
            if w[0] > 0 {
                growth = growth.max(w[1] as f64 / w[0] as f64);
            }
        } else {
            full_inputs += w[0] as f64;
            full_outputs += capacity;
        }
    }
    if full_inputs > 0.0 {
        growth = growth.max(full_outputs / full_inputs);
    }
    let room = 0.5 * spill_capacity as f64;
    let mut count = counts.last().copied().unwrap_or(0) as f64;
    let mut overflow = 0.0;
    for n in 1..=LIGHT_BATCH {
        let next = count * growth;
        overflow += (next - capacity).max(0.0);
        count = next.min(capacity);
        if overflow > room {
            return (n - 1).max(1);
        }
    }
    LIGHT_BATCH
}

/// The runs for `wavefronts` (one per light) through a field of `channels` index slabs, in
/// tiles of at most `tile` initial patches.
pub fn plan_runs(wavefronts: &[Vec<Patch>], channels: u32, tile: usize) -> VecDeque<LightRun> {
    let tile = tile.max(1);
    let mut runs = VecDeque::new();
    for (light, w) in wavefronts.iter().enumerate() {
        let per_channel: Vec<(u32, Option<usize>)> =
            if channels == 3 { (0..3).map(|c| (c as u32, Some(c))).collect() } else { vec![(0, None)] };
        for (slab, channel) in per_channel {
            // A channel the light does not emit deposits nothing.
            if let Some(c) = channel {
                if w.iter().all(|p| p.flux()[c] <= 0.0) {
                    continue;
                }
            }
            let mut start = 0;
            while start < w.len() {
                let end = (start + tile).min(w.len());
                runs.push_back(LightRun { light, slab, channel, start, end, sign: 1.0, spill: None });
                start = end;
            }
        }
    }
    runs
}

/// What the light simulation depends on: its settings, the medium and the lights (one
/// cache entry per distinct triple).
#[derive(Clone, Copy)]
pub struct LitVolume<'a> {
    pub params: &'a EikonalParams,
    pub volume: &'a Volume,
    pub lights: &'a [Light],
    /// Where the volumes are read: the bits of [`super::read_mask::read_mask`] over the
    /// irradiance volume's grid ([`light_grid`]); None: the simulation deposits everywhere,
    /// whatever `params.light_deposits` says.
    pub reads: Option<&'a [u32]>,
}

impl LightSim {
    /// Buffers, images and pipelines for simulating `lights` through `volume` whose smoothed
    /// (grad n, n - 1) texture is `field`; uploads the first run's initial wavefront.
    pub fn new(
        ctx: &Arc<GpuContext>,
        lit: LitVolume<'_>,
        textures: &VolumeTextures,
        sampler: &Sampler,
        graph: &mut FrameGraph,
    ) -> GpuResult<Self> {
        let LitVolume { params, volume, lights, reads } = lit;
        let (light_min, light_max, resolution) = light_grid(volume, params.light_below, params.light_side);
        // Deposits only where the renderer reads the volumes (`light_deposits`); the
        // paper's voxelization keeps its one ray per voxel everywhere.
        let mask = reads.filter(|_| deposits_where_read(params));
        let per_side = if params.light_patches > 0 {
            params.light_patches
        } else {
            volume.resolution.iter().copied().max().unwrap_or(1)
        };
        let faces: Vec<Vec<WavefrontFace>> =
            lights.iter().map(|l| wavefront_faces(volume, light_min, light_max, l, per_side)).collect();
        let mut wavefronts: Vec<Vec<Patch>> = faces.iter().map(|f| initial_wavefront(volume, f)).collect();
        // The energy threshold's reference, the largest initial patch per channel, is that
        // of the whole wavefront (skipped patches included).
        let largest: Vec<Vec3> = wavefronts.iter().map(|w| w.iter().fold(Vec3::ZERO, |m, p| m.max(p.flux()))).collect();
        // Beyond the medium's voxels the smoothed field reaches ceil(3 sigma) voxels
        // (smooth.comp), its gradient one more (central differences), and a trilinear lookup
        // one more; one voxel of slack besides.
        let margin = ((3.0 * params.sigma).ceil() + 3.0) * volume.voxel_size().max_element();
        let (mut air_faces, mut air_skip, mut skipped) = (Vec::<AirFace>::new(), Vec::<u32>::new(), 0u32);
        if params.skip_air {
            for (faces, wavefront) in faces.iter().zip(&mut wavefronts) {
                let skip = air_patches(faces, &textures.medium, margin);
                let base = air_skip.len();
                for (i, f) in faces.iter().enumerate() {
                    air_faces.push(AirFace {
                        origin: f.origin.extend(if f.point { 0.0 } else { 1.0 }).to_array(),
                        axis: f.axis.extend(f.half).to_array(),
                        t1: f.t1.extend(f.k as f32).to_array(),
                        // Cell indices stay exact in f32: at most MAX_INITIAL_PATCHES per light.
                        t2: f.t2.extend((base + i * (f.k * f.k) as usize) as f32).to_array(),
                        power: f.power.extend(f.r0).to_array(),
                    });
                }
                air_skip.extend(air_flags(faces, &skip, volume.voxel_size().max_element(), light_min, light_max));
                let mut flags = skip.iter();
                wavefront.retain(|_| !*flags.next().expect("one flag per patch"));
                skipped += skip.iter().filter(|&&s| s).count() as u32;
            }
        }
        let air_count = air_faces.len() as u32;
        // Storage buffers may not be empty.
        air_faces.resize(air_faces.len().max(1), AirFace::default());
        air_skip.resize(air_skip.len().max(1), 0);
        let air_faces = Buffer::storage(ctx, "eikonal_air_faces", &air_faces)?;
        let air_skip = Buffer::storage(ctx, "eikonal_air_skip", &air_skip)?;
        let (read_bits, read_texels) =
            Buffer::texels(ctx, "eikonal_read_mask", mask.unwrap_or(&[0]), vk::Format::R32_UINT)?;
        let voxel = volume.voxel_size().min_element();
        let dt = params.light_dt * voxel;
        // Enough time for the optical path of two box diagonals at the largest index, plus
        // the way from the initial wavefront (outside the box's bounding sphere).
        let diagonal = (light_max - light_min).length();
        let max_steps =
            ((2.0 * diagonal * max_index(volume) + 2.0 * diagonal) / dt).ceil().min(MAX_LIGHT_STEPS as f32) as u32;
        // A spill list as long as the list: one step's overflow is at most three lists (four
        // outputs per patch), but a wavefront grows by a small fraction per step, so it
        // takes the overflows of many steps; only if it fills is the run taken back.
        let hp = HistoPyramid::new(ctx, params.max_patches, params.max_patches.max(4), max_steps, graph)?;
        let capacity = hp.capacity;
        // Tiles: `tile_patches`, or an eighth of the list (room for the wavefront to grow
        // eightfold by tessellation before a tile must be split), never more than the list.
        let tile = if params.tile_patches > 0 { params.tile_patches } else { capacity / 8 }.clamp(1, capacity);
        let mut queue = plan_runs(&wavefronts, textures.channels, tile as usize);
        let run = queue.pop_front().unwrap_or(LightRun {
            light: 0,
            slab: 0,
            channel: None,
            start: 0,
            end: 0,
            sign: 1.0,
            spill: None,
        });

        // Device-local: every step reads one list and writes the other (128 bytes a patch,
        // 75 MB a step at the default capacity), which in host memory would cross a discrete
        // GPU's bus each step. The host writes a run's initial patches and reads the spill
        // (and tests the lists) through staging copies (FrameGraph::upload_buffer,
        // read_back_buffer).
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        let list_bytes = (capacity as u64) * std::mem::size_of::<Patch>() as u64;
        // The kernels read their patches through texel views of the lists (light_common.glsl).
        let list_usage = storage | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
        let lists = [
            Buffer::new(ctx, "eikonal_patches_0", list_bytes, list_usage, MemoryLocation::GpuOnly)?,
            Buffer::new(ctx, "eikonal_patches_1", list_bytes, list_usage, MemoryLocation::GpuOnly)?,
        ];
        let list_texels = [
            crate::gpu::BufferView::new(ctx, &lists[0], vk::Format::R32G32B32A32_UINT)?,
            crate::gpu::BufferView::new(ctx, &lists[1], vk::Format::R32G32B32A32_UINT)?,
        ];
        let spill_bytes = (hp.spill_capacity as u64) * std::mem::size_of::<Patch>() as u64;
        let spill = Buffer::new(ctx, "eikonal_spill", spill_bytes, storage, MemoryLocation::GpuOnly)?;
        // TRANSFER_SRC: tests read the volumes back.
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::TRANSFER_DST
            | vk::ImageUsageFlags::TRANSFER_SRC;
        let irradiance =
            Image::new(ctx, &ImageDesc::d3("eikonal_irradiance", vk::Format::R32G32B32A32_SFLOAT, resolution, usage))?;
        let direction =
            Image::new(ctx, &ImageDesc::d3("eikonal_light_dir", vk::Format::R32G32B32A32_SFLOAT, resolution, usage))?;
        // The paper's voxelization keeps one ray per voxel by an atomic max on its energy's
        // bits (light_common.glsl `accum`): a seventh slab, and integer atomics.
        let highest = params.voxelization == LightVoxelization::HighestEnergy;
        // Grey light through a colourless medium deposits one channel sum for three, a third
        // of the step kernel's atomics (docs/BENCHMARKS.md). The paper's voxelization keeps
        // each ray's own three channels.
        let gray = !highest && textures.channels == 1 && !textures.extinction_any && lights.iter().all(Light::is_grey);
        // The nearest direction splat sums its weights in a slab of their own.
        let nearest_direction = !highest && params.direction_splat == LightDirectionSplat::Nearest;
        let slabs = if highest || nearest_direction { 7 } else { 6 };
        let accum_extent = [resolution[0], slabs * resolution[1], resolution[2]];
        let accum_usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_DST;
        let float_atomics = params.float_atomics && float_atomics_supported(ctx) && !highest;
        let accum_format = if float_atomics { vk::Format::R32_SFLOAT } else { vk::Format::R32_UINT };
        let accum = Image::new(ctx, &ImageDesc::d3("eikonal_light_accum", accum_format, accum_extent, accum_usage))?;

        // The field through the device's trilinear filter where the view renderer samples it so
        // (eikonal_view::filters_field): a quarter of the step kernel's work is its 128 fetches
        // of RK4's sixteen field samples (docs/BENCHMARKS.md).
        let hardware_filter = super::eikonal_view::filters_field(ctx, params, textures.channels)?;
        let field_sampler = Sampler::new(
            ctx,
            "eikonal_light_field",
            if hardware_filter { SamplerDesc::LINEAR_BORDER } else { SamplerDesc::NEAREST_CLAMP },
        )?;
        let set = |src: usize| {
            Bindings::new(vk::ShaderStageFlags::COMPUTE)
                .storage(LIGHT_BINDING_SRC, &lists[src])
                .texels(crate::LIGHT_BINDING_SRC_TEXELS, &list_texels[src])
                .storage(LIGHT_BINDING_DST, &lists[1 - src])
                .storage(crate::LIGHT_BINDING_SPILL, &spill)
                .sampled(LIGHT_BINDING_FIELD, &textures.field, &field_sampler)
                .sampled(crate::LIGHT_BINDING_EXTINCTION, &textures.extinction, sampler)
                .storage_image(LIGHT_BINDING_ACCUM, &accum)
                .storage_image(LIGHT_BINDING_IRRADIANCE, &irradiance)
                .storage_image(LIGHT_BINDING_DIRECTION, &direction)
                .storage(crate::LIGHT_BINDING_AIR_FACES, &air_faces)
                .storage(crate::LIGHT_BINDING_AIR_SKIP, &air_skip)
                .sampled(crate::LIGHT_BINDING_BAND, &textures.emission, sampler)
                .sampled(crate::LIGHT_BINDING_REFLECTANCE, &textures.albedo, sampler)
                .texels(crate::LIGHT_BINDING_BRICKS, &textures.bricks_texels)
                .texels(crate::LIGHT_BINDING_READ_MASK, &read_texels)
        };
        let sets = Bindings::build_each(ctx, "eikonal_light", vec![set(0), set(1)])?;

        let integrator = match params.light_integrator {
            LightIntegrator::Euler => EIKONAL_EULER,
            LightIntegrator::Midpoint => EIKONAL_MIDPOINT,
            LightIntegrator::Rk4 => EIKONAL_RK4,
        };
        let volume_names = ["VOL_MIN_X", "VOL_MIN_Y", "VOL_MIN_Z", "VOL_MAX_X", "VOL_MAX_Y", "VOL_MAX_Z"];
        let spec: Vec<_> = [
            ("CAPACITY", Spec::U32(capacity)),
            ("HISTORY_LEN", Spec::U32(max_steps)),
            ("SPILL_CAPACITY", Spec::U32(hp.spill_capacity)),
            ("DT", Spec::F32(dt)),
            // Extinction (Eq. 18) from the material volumes of src/scene/volume_sources.rs.
            ("CHANNELS", Spec::U32(textures.channels)),
            // Only extinction matters to the light: a volume whose materials are a
            // Fresnel band alone is never sampled.
            ("MATERIALS", Spec::U32(textures.extinction_any as u32)),
            ("KEEP_CROSSED", Spec::U32(u32::from(params.keep_crossed))),
            ("INTEGRATOR", Spec::U32(integrator)),
            ("AIR_FACES", Spec::U32(air_count)),
            ("HIGHEST_ENERGY", Spec::U32(u32::from(highest))),
            // Only where the volume has a boundary band (real material volumes).
            ("FRESNEL", Spec::U32(u32::from(params.light_fresnel && textures.materials))),
            ("HARDWARE_FILTER", Spec::U32(u32::from(hardware_filter))),
            ("GRAY", Spec::U32(u32::from(gray))),
            ("DEPOSIT_EVERY", Spec::U32(params.light_deposit_every)),
            ("DIRECTION_NEAREST", Spec::U32(u32::from(nearest_direction))),
            // Straight steps in uniform regions (light_step.glsl), where a step is one
            // track-length deposit that carries no Fresnel state.
            (
                "LEAP_STEPS",
                Spec::U32(if highest || params.light_deposit_every != 1 || params.light_fresnel {
                    0
                } else {
                    params.light_leaps
                }),
            ),
            ("BRICK", Spec::U32(super::volume::BRICK)),
            ("READ_MASK", Spec::U32(u32::from(mask.is_some()))),
        ]
        .into_iter()
        .chain(box_specs(volume_names, volume.min, volume.max))
        .chain(box_specs(LIGHT_BOX, light_min, light_max))
        .collect();
        // Two timestamps per pass of a batch: each step is the step kernel, one reduction
        // per pyramid level above the classes, the total, the traversal and the expansion.
        let step_passes = if highest { 2 } else { 1 } * params.light_substeps;
        let passes_per_step = level_lengths(capacity).len() as u32 - 1 + 3 + step_passes;
        let timestamps = if ctx.info.timestamp_valid_bits > 0 {
            Some(TimestampPool::new(ctx, "eikonal_light_timestamps", 2 * LIGHT_BATCH * passes_per_step)?)
        } else {
            None
        };
        let layouts = [hp.set_layout(), sets.layout()];
        let push = std::mem::size_of::<RunPush>() as u32;
        let pipeline = |name: &str, shader: &str| ComputePipeline::new(ctx, name, shader, &layouts, push, &spec);
        let (step_shader, resolve_shader) = if float_atomics {
            ("eikonal/light_step_float_atomics.comp", "eikonal/light_resolve_float_atomics.comp")
        } else {
            ("eikonal/light_step.comp", "eikonal/light_resolve.comp")
        };
        let step = pipeline("eikonal_light_step", step_shader)?;
        let expand = pipeline("eikonal_light_expand", "eikonal/light_expand.comp")?;
        let commit = highest.then(|| pipeline("eikonal_light_commit", "eikonal/light_commit.comp")).transpose()?;
        let resolve = pipeline("eikonal_light_resolve", resolve_shader)?;

        let list_ids = [graph.register_buffer(&lists[0]), graph.register_buffer(&lists[1])];
        let spill_id = graph.register_buffer(&spill);
        let irradiance_id = graph.register_image(&irradiance);
        let direction_id = graph.register_image(&direction);
        let accum_id = graph.register_image(&accum);
        ctx.one_shot(|cmd| {
            graph.access_now(
                cmd,
                &[
                    (irradiance_id, Access::TransferWrite),
                    (direction_id, Access::TransferWrite),
                    (accum_id, Access::TransferWrite),
                ],
                &[],
            );
            cmd.clear_color_image(&irradiance, [0.0; 4]);
            cmd.clear_color_image(&direction, [0.0; 4]);
            // 0.0f32 has the bits 0: the accumulator's sums start at zero.
            cmd.clear_color_image(&accum, [0.0; 4]);
        })?;
        let mut sim = LightSim {
            hp,
            lists,
            _list_texels: list_texels,
            list_ids,
            spill,
            spill_id,
            spilled: Vec::new(),
            pending: Vec::new(),
            tile: tile as usize,
            _accum: accum,
            float_atomics,
            gray,
            substeps: params.light_substeps,
            accum_id,
            irradiance: Rc::new(irradiance),
            irradiance_id,
            direction: Rc::new(direction),
            direction_id,
            sets,
            step,
            commit,
            expand,
            resolve,
            field_id: textures.field_id,
            _field_sampler: field_sampler,
            extinction_id: textures.extinction_id,
            band_ids: [textures.emission_id, textures.albedo_id],
            current: 0,
            steps_taken: 0,
            max_steps,
            initial: Vec::new(),
            wavefronts,
            largest,
            skipped,
            _buffers: [air_faces, air_skip, read_bits],
            _read_texels: read_texels,
            run,
            queue,
            light_min,
            light_max,
            resolution,
            min_flux: 0.0,
            threshold: params.energy_threshold,
            timestamps,
            kernels: Vec::new(),
            run_gpu_ms: 0.0,
            run_count: 0,
            seconds_per_step: None,
            spill_batch: LIGHT_BATCH,
            progress: None,
            finished: None,
        };
        sim.begin(ctx, graph, run)?;
        Ok(sim)
    }

    /// Upload `run`'s initial patches into list 0 and reset the bookkeeping (device idle).
    pub fn begin(&mut self, ctx: &Arc<GpuContext>, graph: &mut FrameGraph, run: LightRun) -> GpuResult<()> {
        let source = match run.spill {
            Some(k) => self.spilled.get(k),
            None => self.wavefronts.get(run.light),
        };
        let mut patches: Vec<Patch> = source.map_or(&[][..], |w| &w[run.start..run.end]).to_vec();
        if let Some(c) = run.channel {
            for p in &mut patches {
                let mut flux = Vec3::ZERO;
                flux[c] = p.flux()[c];
                p.set_flux(flux);
            }
        }
        // The threshold is relative to the largest initial patch of this light and channel
        // (not of this tile, so that tiling does not change which patches are terminated).
        let largest = self.largest.get(run.light).map_or(0.0, |m| run.channel.map_or(m.max_element(), |c| m[c]));
        self.min_flux = self.threshold * largest;
        let count = patches.len() as u32;
        graph.upload_buffer(ctx, &self.lists[0], self.list_ids[0], bytemuck::cast_slice(&patches))?;
        self.hp.state.write(0, bytemuck::bytes_of(&initial_state(count)));
        self.current = 0;
        self.steps_taken = 0;
        self.pending.clear();
        self.initial = patches;
        self.run = run;
        self.run_gpu_ms = 0.0;
        self.run_count = count;
        self.spill_batch = LIGHT_BATCH;
        Ok(())
    }

    fn push(&self, substep: u32) -> RunPush {
        RunPush {
            slab: self.run.slab,
            sign: self.run.sign,
            min_flux: self.min_flux,
            max_steps: self.max_steps,
            substep,
        }
    }

    fn record_step<'a>(&'a self, frame: &mut Frame<'_, 'a>, from: usize) {
        let hp = &self.hp;
        let (set0, set1) = (hp.set(), self.sets.sets()[from]);
        let (src, dst) = (self.list_ids[from], self.list_ids[1 - from]);
        let state = &hp.state;
        let (step, expand) = (&self.step, &self.expand);
        let push = self.push(0);
        // `substeps` dispatches of the step kernel on the same list, then one compaction
        // (glsl/eikonal/light_step.glsl says why this equals a compaction per step).
        for substep in 0..self.substeps {
            let push = self.push(substep);
            frame
                .pass("eikonal_light_step")
                .read(hp.state_id, Access::IndirectArgs)
                // The count of patch steps (`advanced`).
                .write(hp.state_id, Access::ComputeWrite)
                .read(self.field_id, Access::ComputeSampled)
                .read(self.extinction_id, Access::ComputeSampled)
                .read(self.band_ids[0], Access::ComputeSampled)
                .read(self.band_ids[1], Access::ComputeSampled)
                .read(self.irradiance_id, Access::ComputeRead)
                .write(src, Access::ComputeWrite)
                // Read too: later substeps step only the patches still retained.
                .write(hp.classes_id, Access::ComputeWrite)
                .write(self.accum_id, Access::ComputeWrite)
                .record(move |cmd| {
                    cmd.compute_indirect(step, &[set0, set1], &push, state, 0);
                });
            if let Some(commit) = &self.commit {
                frame
                    .pass("eikonal_light_commit")
                    .read(hp.state_id, Access::IndirectArgs)
                    .read(src, Access::ComputeRead)
                    .read(self.irradiance_id, Access::ComputeRead)
                    .write(self.accum_id, Access::ComputeWrite)
                    .record(move |cmd| {
                        cmd.compute_indirect(commit, &[set0, set1], &push, state, 0);
                    });
            }
        }
        hp.record(frame);
        frame
            .pass("eikonal_light_expand")
            .read(hp.state_id, Access::IndirectArgs)
            .write(hp.state_id, Access::ComputeWrite)
            .read(hp.pairs_id, Access::ComputeRead)
            .read(hp.classes_id, Access::ComputeRead)
            .read(src, Access::ComputeRead)
            .read(self.field_id, Access::ComputeSampled)
            .read(self.irradiance_id, Access::ComputeRead)
            .write(dst, Access::ComputeWrite)
            .write(self.spill_id, Access::ComputeWrite)
            .record(move |cmd| {
                let offset = std::mem::offset_of!(crate::shader_structs::HpState, out_args) as u64;
                cmd.compute_indirect(expand, &[set0, set1], &push, state, offset);
            });
    }

    /// Record and run `steps` steps of the current run in one command buffer (no readback
    /// inside), then read back the bookkeeping. Returns the patch count after the last step.
    pub fn run_steps(&mut self, ctx: &Arc<GpuContext>, graph: &mut FrameGraph, steps: u32) -> GpuResult<u32> {
        let mut from = self.current;
        let queries = ctx.one_shot(|cmd| {
            let mut frame = graph.frame();
            for _ in 0..steps {
                self.record_step(&mut frame, from);
                from = 1 - from;
            }
            // More steps than the pool was sized for (a caller's long batch) go untimed.
            let pool = self.timestamps.as_ref().filter(|_| steps <= LIGHT_BATCH);
            let queries = frame.execute(cmd, pool);
            // The host reads the counts next (the lists stay on the device).
            graph.access_now(cmd, &[], &[(self.hp.state_id, Access::HostRead)]);
            queries
        })?;
        if let Some(pool) = self.timestamps.as_ref().filter(|_| steps <= LIGHT_BATCH) {
            self.run_gpu_ms += add_kernel_times(&mut self.kernels, pool, &queries)?;
        }
        self.current = from;
        self.steps_taken += steps;
        Ok(self.hp.read_state().count)
    }

    /// Turn the accumulator into the irradiance and direction volumes (after the runs; again
    /// after more runs, it always reflects everything deposited so far).
    pub fn resolve(&mut self, ctx: &Arc<GpuContext>, graph: &mut FrameGraph) -> GpuResult<()> {
        let (set0, set1) = (self.hp.set(), self.sets.set());
        let resolve = &self.resolve;
        let push = self.push(0);
        let groups = self.resolution.map(|r| r.div_ceil(EIKONAL_GROUP));
        let pool = self.timestamps.as_ref();
        let queries = ctx.one_shot(|cmd| {
            let mut frame = graph.frame();
            frame
                .pass("eikonal_light_resolve")
                .read(self.accum_id, Access::ComputeRead)
                .write(self.irradiance_id, Access::ComputeWrite)
                .write(self.direction_id, Access::ComputeWrite)
                .record(move |cmd| {
                    cmd.compute(resolve, &[set0, set1], &push, groups);
                });
            frame.execute(cmd, pool)
        })?;
        if let Some(pool) = &self.timestamps {
            add_kernel_times(&mut self.kernels, pool, &queries)?;
        }
        Ok(())
    }

    /// Step the current run in batches of [`LIGHT_BATCH`] steps until it ends (no patch
    /// left, or [`LightSim::max_steps`]: returns its statistics) or `deadline` has passed
    /// after a batch (returns None; the next call continues it), one batch at least.
    /// `progress` is called after each batch.
    fn step_run(
        &mut self,
        ctx: &Arc<GpuContext>,
        graph: &mut FrameGraph,
        deadline: Option<Instant>,
        mut progress: impl FnMut(u32, u32),
    ) -> GpuResult<Option<(RunStats, Vec<u32>)>> {
        while self.run_count > 0 && self.steps_taken < self.max_steps {
            let mut n = self.spill_batch.min(self.max_steps - self.steps_taken);
            if let (Some(d), Some(per_step)) = (deadline, self.seconds_per_step) {
                // A batch that fits the time left at the last batch's pace (a step of a large
                // wavefront can take a second on a CPU device), one step at least.
                let left = d.saturating_duration_since(Instant::now()).as_secs_f64();
                n = n.min(((left / per_step) as u32).max(1));
            }
            let start = Instant::now();
            self.run_count = self.run_steps(ctx, graph, n)?;
            self.seconds_per_step = Some(start.elapsed().as_secs_f64() / n as f64);
            let counts = self.hp.read_history(self.steps_taken as usize);
            let before = self.steps_taken as usize - n as usize;
            let first =
                if before == 0 { self.initial.len() as u32 } else { counts.get(before - 1).copied().unwrap_or(0) };
            let mut batch = vec![first];
            batch.extend_from_slice(counts.get(before..).unwrap_or(&[]));
            let spilled = self.hp.read_state().spilled;
            self.spill_batch = spill_safe_batch(&batch, spilled, self.hp.capacity, self.hp.spill_capacity);
            self.drain_spill(ctx, graph)?;
            progress(n, self.run_count);
            // At least one batch per call, so that every call advances.
            let running = self.run_count > 0 && self.steps_taken < self.max_steps;
            if running && deadline.is_some_and(|d| Instant::now() >= d) {
                return Ok(None);
            }
        }
        let state = self.hp.read_state();
        let mut counts = self.hp.read_history(self.steps_taken as usize);
        // Steps after the list emptied (the rest of the last batch) did nothing.
        if let Some(last) = counts.iter().position(|&c| c == 0) {
            counts.truncate(last + 1);
        }
        let r = self.run;
        // Counted by the step kernel: with several steps per dispatch a patch may advance
        // more than once between two of these counts.
        let patch_steps = u64::from(state.advanced);
        let stats = RunStats {
            light: r.light,
            channel: r.channel,
            start: r.start,
            end: r.end,
            sign: r.sign,
            steps: counts.len() as u32,
            patch_steps,
            peak_patches: state.peak.max(self.initial.len() as u32),
            dropped_patches: state.dropped,
            spilled_patches: self.pending.len() as u32,
            spill: r.spill,
            gpu_ms: self.run_gpu_ms,
        };
        Ok(Some((stats, counts)))
    }

    /// Move the patches the last batch spilled to `pending` and empty the spill list (device
    /// idle).
    fn drain_spill(&mut self, ctx: &Arc<GpuContext>, graph: &mut FrameGraph) -> GpuResult<()> {
        let mut state = self.hp.read_state();
        if state.spilled == 0 {
            return Ok(());
        }
        let bytes = state.spilled as u64 * std::mem::size_of::<Patch>() as u64;
        let spilled = graph.read_back_buffer(ctx, &self.spill, self.spill_id, bytes)?;
        self.pending.extend_from_slice(&bytemuck::pod_collect_to_vec::<u8, Patch>(&spilled));
        state.spilled = 0;
        state.spill_new = 0;
        self.hp.state.write(0, bytemuck::bytes_of(&state));
        Ok(())
    }

    /// Simulate every run (lights, channels, tiles) to its end, splitting the tiles that
    /// overflow the list, then resolve the volumes; a progress bar on a terminal.
    pub fn run(&mut self, ctx: &Arc<GpuContext>, graph: &mut FrameGraph) -> GpuResult<LightStats> {
        loop {
            if let Some(stats) = self.advance(ctx, graph, None)? {
                return Ok(stats);
            }
        }
    }

    /// The simulation's statistics once it has finished.
    pub fn finished(&self) -> Option<&LightStats> {
        self.finished.as_ref()
    }

    /// Continue the simulation until it finishes (returns its statistics; at once when it
    /// had) or `deadline` passes after a batch of steps (returns None). Stopped early, the
    /// volumes are resolved from what was deposited so far, so that a frame rendered now shows
    /// the light simulated up to here; the next call continues where this one stopped, and
    /// the finished volumes equal those of one uninterrupted run.
    pub fn advance(
        &mut self,
        ctx: &Arc<GpuContext>,
        graph: &mut FrameGraph,
        deadline: Option<Instant>,
    ) -> GpuResult<Option<LightStats>> {
        if let Some(stats) = &self.finished {
            return Ok(Some(stats.clone()));
        }
        let max_steps = self.max_steps as u64;
        let report = |done: u64, total: u64, detail: &str, finished: bool| {
            ctx.report_progress(&Progress { task: LIGHT_SIMULATION, done, total, detail, finished })
        };
        let lights = self.wavefronts.len();
        let skipped_patches = self.skipped;
        let initial_patches = self.wavefronts.iter().map(|w| w.len() as u32).sum::<u32>() + skipped_patches;
        let (float_atomics, gray) = (self.float_atomics, self.gray);
        let sofar = self.progress.get_or_insert_with(|| SimProgress {
            start: Instant::now(),
            done_runs: 0,
            stats: LightStats { initial_patches, skipped_patches, float_atomics, gray, ..LightStats::default() },
        });
        let (mut done_runs, started) = (sofar.done_runs, sofar.start);
        loop {
            // In steps of max_steps per run: a run that ends early counts as whole.
            let total = (done_runs + 1 + self.queue.len() as u64) * max_steps;
            let r = self.run;
            let label = format!(
                "light {}/{lights}{}, tile {}..{}{}",
                r.light + 1,
                r.channel.map_or(String::new(), |c| format!(" channel {}", ["R", "G", "B"][c])),
                r.start,
                r.end,
                if r.sign < 0.0 {
                    " (take-back)"
                } else if r.spill.is_some() {
                    " (spilled)"
                } else {
                    ""
                }
            );
            let mut taken = self.steps_taken as u64;
            let stepped = self.step_run(ctx, graph, deadline, |n, count| {
                taken += n as u64;
                let detail = format!("{label}: {count} patches");
                report(done_runs * max_steps + taken.min(max_steps), total, &detail, false);
            })?;
            let Some((run_stats, counts)) = stepped else {
                if let Some(p) = self.progress.as_mut() {
                    p.done_runs = done_runs;
                }
                self.resolve(ctx, graph)?;
                return Ok(None);
            };
            done_runs += 1;
            let stats = &mut self.progress.as_mut().expect("begun above").stats;
            stats.steps += run_stats.steps;
            stats.patch_steps += run_stats.patch_steps;
            stats.gpu_ms += run_stats.gpu_ms;
            if r.sign < 0.0 {
                stats.overflow_ms += run_stats.gpu_ms;
            }
            stats.patch_counts.extend_from_slice(&counts);
            stats.peak_patches = stats.peak_patches.max(run_stats.peak_patches);
            let overflowed = run_stats.dropped_patches > 0;
            if overflowed && r.sign > 0.0 && r.end - r.start > 1 {
                stats.overflow_ms += run_stats.gpu_ms;
                // Take the run's deposits back (the same patches, the same drops: the
                // simulation is deterministic up to the order of the float additions),
                // then simulate its four quarters. The paper's voxelization keeps a maximum,
                // which the quarters' rerun of the same rays leaves as it is: no take-back.
                stats.split_tiles += 1;
                let len = r.end - r.start;
                let quarter = len.div_ceil(4);
                let mut parts = Vec::new();
                let mut s0 = r.start;
                while s0 < r.end {
                    let e0 = (s0 + quarter).min(r.end);
                    parts.push(LightRun { start: s0, end: e0, ..r });
                    s0 = e0;
                }
                for p in parts.into_iter().rev() {
                    self.queue.push_front(p);
                }
                if self.commit.is_none() {
                    self.queue.push_front(LightRun { sign: -1.0, ..r });
                }
            } else if r.sign > 0.0 {
                stats.dropped_patches += run_stats.dropped_patches;
                if !self.pending.is_empty() {
                    // Continue the spilled patches next, in tiles like the initial wavefront.
                    let patches = std::mem::take(&mut self.pending);
                    let n = patches.len();
                    stats.spilled_patches += n as u64;
                    self.spilled.push(patches);
                    let k = self.spilled.len() - 1;
                    let starts: Vec<usize> = (0..n).step_by(self.tile.max(1)).collect();
                    for &s0 in starts.iter().rev() {
                        let e0 = (s0 + self.tile.max(1)).min(n);
                        self.queue.push_front(LightRun { start: s0, end: e0, spill: Some(k), ..r });
                    }
                }
            }
            stats.runs.push(run_stats);
            match self.queue.pop_front() {
                Some(next) => self.begin(ctx, graph, next)?,
                None => break,
            }
        }
        let total = done_runs * max_steps;
        report(total, total, "done", true);
        let before = self.kernels.iter().map(|k| k.ms).sum::<f64>();
        self.resolve(ctx, graph)?;
        let mut stats = self.progress.take().expect("begun above").stats;
        stats.gpu_ms += self.kernels.iter().map(|k| k.ms).sum::<f64>() - before;
        stats.kernels = self.kernels.clone();
        stats.seconds = started.elapsed().as_secs_f64();
        self.finished = Some(stats.clone());
        Ok(Some(stats))
    }

    /// The current patch list (after the last step's compaction/expansion), read back.
    pub fn patches(&self, ctx: &Arc<GpuContext>, graph: &mut FrameGraph) -> GpuResult<Vec<Patch>> {
        let n = self.hp.read_state().count as u64;
        let i = self.current;
        let bytes =
            graph.read_back_buffer(ctx, &self.lists[i], self.list_ids[i], n * std::mem::size_of::<Patch>() as u64)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// The last step's first `count` patches before compaction (advanced, absorbed, in
    /// the list the step read) and their classes; `count` is the list length before it.
    pub fn last_step(
        &self,
        ctx: &Arc<GpuContext>,
        graph: &mut FrameGraph,
        count: usize,
    ) -> GpuResult<(Vec<Patch>, Vec<u32>)> {
        let i = 1 - self.current;
        let bytes = (count * std::mem::size_of::<Patch>()) as u64;
        let patches = graph.read_back_buffer(ctx, &self.lists[i], self.list_ids[i], bytes)?;
        let classes = graph.read_back_buffer(ctx, &self.hp.classes, self.hp.classes_id, 4 * count as u64)?;
        Ok((bytemuck::pod_collect_to_vec(&patches), bytemuck::pod_collect_to_vec(&classes)))
    }
}

/// A light simulation with its own volume textures and frame graph, for tests and `prism
/// bench` (the renderer builds its own inside the eikonal pass).
pub struct StandaloneLight {
    pub sim: LightSim,
    pub graph: FrameGraph,
    _volume: VolumeTextures,
    _sampler: Sampler,
}

impl StandaloneLight {
    pub fn new(ctx: &Arc<GpuContext>, params: &EikonalParams, volume: &Volume, light: &Light) -> GpuResult<Self> {
        Self::with_lights(ctx, params, volume, std::slice::from_ref(light))
    }

    /// All of `lights` deposit into one pair of volumes, everywhere.
    pub fn with_lights(
        ctx: &Arc<GpuContext>,
        params: &EikonalParams,
        volume: &Volume,
        lights: &[Light],
    ) -> GpuResult<Self> {
        Self::with_reads(ctx, LitVolume { params, volume, lights, reads: None })
    }

    /// The simulation of `lit`, which deposits only where `lit.reads` says the volumes are
    /// read when its `light_deposits` is "read".
    pub fn with_reads(ctx: &Arc<GpuContext>, lit: LitVolume<'_>) -> GpuResult<Self> {
        let mut graph = FrameGraph::new();
        // No view rays here: `leaps` off spares the view's weak-gradient map.
        let textures = prepare_volume(ctx, EikonalParams { leaps: false, ..*lit.params }, lit.volume, &mut graph)?;
        let sampler = Sampler::new(ctx, "eikonal_light_field", crate::gpu::SamplerDesc::NEAREST_CLAMP)?;
        let sim = LightSim::new(ctx, lit, &textures, &sampler, &mut graph)?;
        Ok(StandaloneLight { sim, graph, _volume: textures, _sampler: sampler })
    }

    pub fn run(&mut self, ctx: &Arc<GpuContext>) -> GpuResult<LightStats> {
        self.sim.run(ctx, &mut self.graph)
    }

    pub fn run_steps(&mut self, ctx: &Arc<GpuContext>, steps: u32) -> GpuResult<u32> {
        self.sim.run_steps(ctx, &mut self.graph, steps)
    }

    /// [`LightSim::begin`]: start `run` over (its initial patches uploaded again).
    pub fn begin(&mut self, ctx: &Arc<GpuContext>, run: LightRun) -> GpuResult<()> {
        self.sim.begin(ctx, &mut self.graph, run)
    }

    /// [`LightSim::patches`].
    pub fn patches(&mut self, ctx: &Arc<GpuContext>) -> GpuResult<Vec<Patch>> {
        self.sim.patches(ctx, &mut self.graph)
    }

    /// [`LightSim::last_step`].
    pub fn last_step(&mut self, ctx: &Arc<GpuContext>, count: usize) -> GpuResult<(Vec<Patch>, Vec<u32>)> {
        self.sim.last_step(ctx, &mut self.graph, count)
    }

    /// [`LightSim::advance`]: continue the simulation until `deadline` (one batch at least).
    pub fn advance(&mut self, ctx: &Arc<GpuContext>, deadline: Option<Instant>) -> GpuResult<Option<LightStats>> {
        self.sim.advance(ctx, &mut self.graph, deadline)
    }

    /// Resolve and read the irradiance (rgba) and direction volumes back, x fastest.
    pub fn read_volumes(&mut self, ctx: &Arc<GpuContext>) -> GpuResult<(Vec<f32>, Vec<f32>)> {
        self.sim.resolve(ctx, &mut self.graph)?;
        let voxels: u64 = self.sim.resolution.iter().map(|&r| r as u64).product();
        let read = |graph: &mut FrameGraph, image: &Image, id: ImageId| -> GpuResult<Vec<f32>> {
            let buffer = Buffer::new(
                ctx,
                "eikonal_light_readback",
                16 * voxels,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?;
            ctx.one_shot(|cmd| {
                graph.access_now(cmd, &[(id, Access::TransferRead)], &[]);
                cmd.copy_image_to_buffer(image, &buffer);
            })?;
            Ok(bytemuck::cast_slice(buffer.read()).to_vec())
        };
        let e = read(&mut self.graph, &self.sim.irradiance, self.sim.irradiance_id)?;
        let d = read(&mut self.graph, &self.sim.direction, self.sim.direction_id)?;
        Ok((e, d))
    }
}

/// One equal-time step of Eqs. 14-15 by forward Euler in f64 on an analytic field (§5.2.1 as
/// the paper has it): the CPU version of light_step.glsl's `LightIntegrator::Euler`.
pub fn light_euler_step(field: &impl IndexField, s: RayState, h: f64) -> RayState {
    let (dx, dv) = light_rhs(field, s.x, s.v);
    RayState { x: s.x + h * dx, v: s.v + h * dv }
}

/// The right-hand side of Eqs. 14-15: (dx/dt, dv/dt) = (v / n^2, grad n / n).
fn light_rhs(field: &impl IndexField, x: DVec3, v: DVec3) -> (DVec3, DVec3) {
    let n = field.n(x);
    (v / (n * n), field.gradient(x) / n)
}

/// One equal-time step of Eqs. 14-15 with `integrator`, as light_step.glsl.
pub fn light_step(field: &impl IndexField, integrator: LightIntegrator, s: RayState, h: f64) -> RayState {
    match integrator {
        LightIntegrator::Euler => light_euler_step(field, s, h),
        LightIntegrator::Midpoint => light_midpoint_step(field, s, h),
        LightIntegrator::Rk4 => light_rk4_step(field, s, h),
    }
}

/// One equal-time step of Eqs. 14-15 by the explicit midpoint rule in f64 on an analytic
/// field: the CPU version of light_step.glsl's `LightIntegrator::Midpoint`.
pub fn light_midpoint_step(field: &impl IndexField, s: RayState, h: f64) -> RayState {
    let rhs = |x, v| light_rhs(field, x, v);
    let k1 = rhs(s.x, s.v);
    let k2 = rhs(s.x + 0.5 * h * k1.0, s.v + 0.5 * h * k1.1);
    RayState { x: s.x + h * k2.0, v: s.v + h * k2.1 }
}

/// One equal-time step of Eqs. 14-15 by classical RK4 in f64 on an analytic field: the CPU version of light_step.glsl's particle update.
pub fn light_rk4_step(field: &impl IndexField, s: RayState, h: f64) -> RayState {
    let rhs = |x, v| light_rhs(field, x, v);
    let k1 = rhs(s.x, s.v);
    let k2 = rhs(s.x + 0.5 * h * k1.0, s.v + 0.5 * h * k1.1);
    let k3 = rhs(s.x + 0.5 * h * k2.0, s.v + 0.5 * h * k2.1);
    let k4 = rhs(s.x + h * k3.0, s.v + h * k3.1);
    RayState {
        x: s.x + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
        v: s.v + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
    }
}

/// The optical path (integral of n ds, trapezoid rule) along a polyline: with Eqs. 14-15
/// every particle of one wavefront has covered the same S = t (Appendix, Eqs. 23-24).
pub fn optical_path(field: &impl IndexField, path: &[DVec3]) -> f64 {
    path.windows(2).map(|w| 0.5 * (field.n(w[0]) + field.n(w[1])) * w[0].distance(w[1])).sum()
}

/// The settings the light simulation depends on (its cache key, with the volume and the
/// lights): sigma shapes the field it integrates (volume.rs), the others are its own. The view
/// renderer's settings (integrator, step, nearby and its iterations and resolution) are left
/// out, so that changing them re-creates the view around the same simulation.
fn simulation_settings(p: &EikonalParams) -> impl std::fmt::Debug {
    (
        p.sigma,
        p.energy_threshold,
        p.light_dt,
        (p.light_integrator, p.light_substeps, p.light_leaps),
        (
            p.max_patches,
            p.tile_patches,
            p.keep_crossed,
            p.skip_air,
            p.voxelization,
            p.light_deposit_every,
            p.direction_splat,
            p.light_deposits,
        ),
        p.light_fresnel,
        p.hardware_filtering,
        (p.light_patches, p.light_below, p.light_side),
        p.float_atomics,
    )
}

/// The renderer's light simulation: run once when the renderer is created (the light and
/// the volume are static), and the per-frame `eikonal_light` pass that lights the diffuse
/// receivers inside the irradiance volume (glsl/eikonal/light_receiver.frag).
pub struct EikonalLight {
    /// The simulation, shared through the technique cache with the next instance when only
    /// what the simulation does not depend on changed, and continued by [`Self::advance`]
    /// while it is in progress.
    sim: Rc<RefCell<LightSim>>,
    /// Its statistics once finished.
    pub stats: Option<LightStats>,
    volumes: [Rc<Image>; 2],
    ids: [ImageId; 2],
    light_box: (Vec3, Vec3),
    receiver: FullscreenPass,
}

impl EikonalLight {
    /// The simulation's volumes and receiver pass. The simulation itself runs in
    /// [`Self::advance`], before the frames that show it: all at once, or (in the window) a
    /// little before each frame, which then shows the light simulated so far.
    pub fn new(s: &mut crate::technique::Setup<'_>, lit: LitVolume<'_>, textures: &VolumeTextures) -> GpuResult<Self> {
        let (ctx, targets, nearest) = (s.ctx, s.targets, s.nearest);
        // Dropped patches are reported by the caller from `stats.dropped_patches`.
        // The voxels read, not the surfaces: a floor moved within its plane reads the same.
        let reads = lit.reads.map(|bits| {
            use std::hash::{Hash, Hasher};
            let mut h = std::collections::hash_map::DefaultHasher::new();
            bits.hash(&mut h);
            h.finish()
        });
        let key = crate::technique::cache_key(&(simulation_settings(lit.params), lit.volume, lit.lights, reads));
        let graph = &mut *s.graph;
        let sim = s.cache.get_or_try_insert(key, || -> GpuResult<RefCell<LightSim>> {
            Ok(RefCell::new(LightSim::new(ctx, lit, textures, nearest, graph)?))
        })?;
        let shared = sim.borrow();
        let volumes = [shared.irradiance.clone(), shared.direction.clone()];
        let ids = [shared.irradiance_id, shared.direction_id];
        let light_box = (shared.light_min, shared.light_max);
        let stats = shared.finished().cloned();
        drop(shared);
        let (lo, hi) = light_box;
        let set = targets
            .gbuffer(fragment_set(), nearest, true)
            .sampled(crate::BINDING_EIKONAL_IRRADIANCE, &volumes[0], nearest)
            .read(ids[0])
            .sampled(crate::BINDING_EIKONAL_LIGHT_DIR, &volumes[1], nearest)
            .read(ids[1]);
        let receiver = FullscreenPass::new(
            ctx,
            // Overwrites deferred shading's receivers inside the irradiance volume only.
            &FullscreenDesc::over_hdr(
                EIKONAL_LIGHT,
                "eikonal/light_receiver.frag",
                targets,
                &[&box_specs(LIGHT_BOX, lo, hi)[..], &scene_specialization(s.scene)[..]].concat(),
            ),
            set,
            s.frame_layout,
        )?;
        Ok(EikonalLight { sim, stats, volumes, ids, light_box, receiver })
    }

    /// Whether the simulation has steps left.
    pub fn simulating(&self) -> bool {
        self.stats.is_none()
    }

    /// Continue the simulation until `deadline` (to its end without one; device idle).
    /// Returns whether it advanced.
    pub fn advance(
        &mut self,
        ctx: &Arc<GpuContext>,
        graph: &mut FrameGraph,
        deadline: Option<Instant>,
    ) -> GpuResult<bool> {
        if self.stats.is_some() {
            return Ok(false);
        }
        self.stats = self.sim.borrow_mut().advance(ctx, graph, deadline)?;
        Ok(true)
    }

    pub fn light_box(&self) -> (Vec3, Vec3) {
        self.light_box
    }

    pub fn images(&self) -> (&Image, &Image) {
        (&self.volumes[0], &self.volumes[1])
    }

    pub fn image_ids(&self) -> [ImageId; 2] {
        self.ids
    }

    pub fn record<'a>(
        &'a self,
        frame: &mut Frame<'_, 'a>,
        scene: &crate::frame::gpu_scene::GpuScene,
        targets: &crate::frame::targets::Targets,
        frame_set: DescriptorSet,
    ) {
        self.receiver.record(frame, frame_set, &[scene.environment_id, targets.shadow_atlas_id]);
    }
}

#[cfg(test)]
mod tests {
    use super::{spill_safe_batch, LIGHT_BATCH};

    /// A batch of `n` dispatches from a list of `count` patches growing by `growth` per
    /// dispatch: the list's lengths before and after each dispatch and what it spilled.
    fn batch(count: f64, growth: f64, n: u32, capacity: u32) -> (Vec<u32>, f64) {
        let (mut c, mut spilled, mut counts) = (count, 0.0, vec![count as u32]);
        for _ in 0..n {
            let next = c * growth;
            spilled += (next - capacity as f64).max(0.0);
            c = next.min(capacity as f64);
            counts.push(c as u32);
        }
        (counts, spilled)
    }

    /// For wavefronts that grow at a constant rate, whatever the list's fill, the next batch
    /// spills at most half the spill list (or is a single dispatch), and a wavefront that
    /// does not grow keeps whole batches.
    #[test]
    fn batches_fit_their_overflow_into_the_spill_list() {
        let capacity = 524_288;
        for growth in [0.9, 1.0, 1.01, 1.05, 1.147, 1.3, 2.0, 4.0] {
            for fill in [0.01, 0.3, 0.9, 1.0] {
                let (counts, spilled) = batch(fill * capacity as f64, growth, 4, capacity);
                let n = spill_safe_batch(&counts, spilled as u32, capacity, capacity);
                assert!((1..=LIGHT_BATCH).contains(&n), "growth {growth}, fill {fill}: {n}");
                let last = *counts.last().unwrap() as f64;
                let (_, next_spilled) = batch(last, growth, n, capacity);
                assert!(
                    n == 1 || next_spilled <= 0.5 * capacity as f64 + 1.0,
                    "growth {growth}, fill {fill}: {n} dispatches spill {next_spilled}"
                );
                if growth <= 1.0 {
                    assert_eq!(n, LIGHT_BATCH, "growth {growth}, fill {fill}");
                }
            }
        }
        // The 256^3 eikonal_sphere's first tile (straight steps on): 1.147x per dispatch as
        // the list fills. A whole batch would spill more than the spill list holds.
        let (counts, spilled) = batch(379_436.0, 1.147, 2, capacity);
        assert!(batch(*counts.last().unwrap() as f64, 1.147, LIGHT_BATCH, capacity).1 > capacity as f64);
        assert_eq!(spill_safe_batch(&counts, spilled as u32, capacity, capacity), 3);
    }
}
