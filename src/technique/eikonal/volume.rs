//! The volume of eikonal rendering (Ihrke et al. 2007, ../shared/papers/ihrke2007-eikonal-rendering.md)
//! as both of its passes read it: the view renderer of sections 4.1 and 5.3
//! (eikonal_view.rs) and the light simulation of section 5.2 (eikonal_light.rs).
//!
//! - Section 5.1 on the GPU ([`prepare_volume`]): the sampled index (n - 1) uploaded, smoothed
//!   by a separable Gaussian (`render.eikonal.sigma` voxels; glsl/eikonal/smooth.comp) and
//!   differentiated by central differences into a (grad n, n - 1) texture
//!   (glsl/eikonal/gradient.comp), and the material volumes ([`VolumeTextures`]).
//! - The ray equation, Eqs. 9-10, on the CPU in f64 ([`euler_step`] for Eqs. 11-12,
//!   [`rk4_step`], [`trace`]): the tests check the Luneburg focus and RK4's order with them,
//!   and they document what the shaders do.
use std::sync::Arc;

use glam::DVec3;

use crate::gpu::{vk, Access, ComputePipeline, GpuContext, GpuResult, Image, ImageDesc, Spec, Specs};
use crate::graph::{Bindings, FrameGraph, ImageId};
use crate::scene::techniques::{EikonalParams, Integrator};
use crate::scene::{IndexProfile, Volume};
use crate::{EIKONAL_BINDING_DST, EIKONAL_BINDING_SRC, EIKONAL_GROUP};

/// A refractive-index field with its gradient, for the CPU integrators.
pub trait IndexField {
    fn n(&self, x: DVec3) -> f64;
    fn gradient(&self, x: DVec3) -> DVec3;
}

impl IndexField for IndexProfile {
    fn n(&self, x: DVec3) -> f64 {
        IndexProfile::n(self, x)
    }
    fn gradient(&self, x: DVec3) -> DVec3 {
        IndexProfile::gradient(self, x)
    }
}

/// A point of a ray: position and optical direction v (|v| = n, Eq. 9: dx/ds = v / n).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayState {
    pub x: DVec3,
    pub v: DVec3,
}

impl RayState {
    /// A ray at `x` heading along the unit direction `d`: v = n(x) d.
    pub fn new(field: &impl IndexField, x: DVec3, d: DVec3) -> Self {
        RayState { x, v: d.normalize() * field.n(x) }
    }
}

/// (dx/ds, dv/ds) = (v / n, grad n): Eqs. 9-10.
fn rhs(field: &impl IndexField, s: RayState) -> (DVec3, DVec3) {
    (s.v / field.n(s.x), field.gradient(s.x))
}

/// One forward-Euler step of arc length `h`: Eqs. 11-12.
pub fn euler_step(field: &impl IndexField, s: RayState, h: f64) -> RayState {
    let (dx, dv) = rhs(field, s);
    RayState { x: s.x + h * dx, v: s.v + h * dv }
}

/// One classical fourth-order Runge-Kutta step of arc length `h` of Eqs. 9-10.
pub fn rk4_step(field: &impl IndexField, s: RayState, h: f64) -> RayState {
    let at = |k: (DVec3, DVec3), f: f64| RayState { x: s.x + f * k.0, v: s.v + f * k.1 };
    let k1 = rhs(field, s);
    let k2 = rhs(field, at(k1, 0.5 * h));
    let k3 = rhs(field, at(k2, 0.5 * h));
    let k4 = rhs(field, at(k3, h));
    RayState {
        x: s.x + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
        v: s.v + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
    }
}

/// One explicit midpoint step of arc length `h` of Eqs. 9-10 (second order).
pub fn midpoint_step(field: &impl IndexField, s: RayState, h: f64) -> RayState {
    let k1 = rhs(field, s);
    let k2 = rhs(field, RayState { x: s.x + 0.5 * h * k1.0, v: s.v + 0.5 * h * k1.1 });
    RayState { x: s.x + h * k2.0, v: s.v + h * k2.1 }
}

/// The acceleration of Eqs. 9-10 in the parameter tau with d tau = ds / n: then dx/d tau = v
/// and dv/d tau = n grad n = grad(n^2 / 2), a second-order equation x'' = a(x) whose right-hand
/// side does not depend on x' (the Nyström method below integrates that form).
fn acceleration(field: &impl IndexField, x: DVec3) -> DVec3 {
    field.n(x) * field.gradient(x)
}

/// One velocity-Verlet (Störmer-Verlet) step of x'' = a(x) over the parameter step `t`,
/// second order: a half kick with a(x), a drift, a half kick with a at the new point.
pub fn verlet_tau_step(field: &impl IndexField, s: RayState, t: f64) -> RayState {
    let v_half = s.v + 0.5 * t * acceleration(field, s.x);
    let x = s.x + t * v_half;
    RayState { x, v: v_half + 0.5 * t * acceleration(field, x) }
}

/// [`verlet_tau_step`] with the parameter step of arc length `h` where the step starts.
pub fn verlet_step(field: &impl IndexField, s: RayState, h: f64) -> RayState {
    verlet_tau_step(field, s, h / field.n(s.x))
}

/// One step with `integrator`.
pub fn step(field: &impl IndexField, integrator: Integrator, s: RayState, h: f64) -> RayState {
    match integrator {
        Integrator::Euler => euler_step(field, s, h),
        Integrator::Midpoint => midpoint_step(field, s, h),
        Integrator::Rk4 => rk4_step(field, s, h),
        Integrator::Verlet => verlet_step(field, s, h),
    }
}

/// March from `start` with steps of `h` while `inside(x)` holds (at most `max_steps`);
/// returns every state, the first being `start` and the last the first one outside (or the
/// last one taken).
pub fn trace(
    field: &impl IndexField,
    integrator: Integrator,
    start: RayState,
    h: f64,
    max_steps: usize,
    inside: impl Fn(DVec3) -> bool,
) -> Vec<RayState> {
    let mut path = vec![start];
    let mut s = start;
    for _ in 0..max_steps {
        s = step(field, integrator, s, h);
        path.push(s);
        if !inside(s.x) {
            break;
        }
    }
    path
}

/// Where the segment from `a` (inside) to `b` (outside) crosses the sphere (`center`,
/// `radius`): the linear interpolation of the distance to the surface.
pub fn sphere_crossing(a: DVec3, b: DVec3, center: DVec3, radius: f64) -> DVec3 {
    let (da, db) = (a.distance(center) - radius, b.distance(center) - radius);
    let t = if db != da { (da / (da - db)).clamp(0.0, 1.0) } else { 0.0 };
    a.lerp(b, t)
}

/// The volume's GPU textures: the sampled index (n - 1, one slab of `nz` slices per channel,
/// stacked along z: 1 slab, or 3 with dispersion), a scratch texture of the separable blur,
/// (grad n, n - 1) per slab after smoothing and differentiation, and the three material
/// volumes of src/scene/volume_sources.rs.
///
/// Bytes per voxel: 24 per index slab (R32F raw + R32F scratch + RGBA32F field), so 24 or
/// 72, plus 28 for the materials (3 x RGBA16F: extinction + g, albedo + reflectance,
/// emission + boundary band; and the band's factor, an f32 buffer), or a 1x1x1 stand-in of
/// each when the volume has no material (no extinction, emission or index jump anywhere).
pub struct VolumeTextures {
    _raw: Image,
    _scratch: Image,
    pub(crate) field: Image,
    pub(crate) field_id: ImageId,
    /// (sigma_a + sigma_s RGB per metre, Henyey-Greenstein g).
    pub extinction: Image,
    pub extinction_id: ImageId,
    /// (sigma_s / extinction RGB, surface reflectance factor).
    pub albedo: Image,
    pub albedo_id: ImageId,
    /// (emission RGB per metre, boundary band 0/1).
    pub emission: Image,
    pub emission_id: ImageId,
    /// Index slabs in `field` (3: a per-channel index, dispersion).
    pub channels: u32,
    /// Whether the material volumes are real (not stand-ins).
    pub materials: bool,
    /// Whether any voxel has extinction, and whether any has emission (the view renderer
    /// samples neither volume where it is all zero).
    pub extinction_any: bool,
    pub emission_any: bool,
    /// Whether any voxel scatters (sigma_s = albedo x extinction > 0 in a channel): only
    /// then do view rays read the light volumes inside the volume (Eq. 6).
    pub scatters: bool,
    /// The uniform-region map of the light patches' leaps ([`uniform_reach`]), and its R32UI
    /// view.
    pub bricks: crate::gpu::Buffer,
    pub bricks_texels: crate::gpu::BufferView,
    /// The view rays' march map ([`march_map`]: the band's reflectance factor and the
    /// weak-gradient reach per voxel), device-local, read through its R32UI view: the march
    /// reads it once per step, and a texel fetch from a buffer of 32-bit texels costs lavapipe
    /// one gather where a storage buffer load, or a texel of 8 bits, is a loop over the lanes
    /// (docs/BENCHMARKS.md).
    pub march: crate::gpu::Buffer,
    pub march_texels: crate::gpu::BufferView,
    /// Where the light can be anything but straight ([`medium_bricks`]).
    pub medium: Vec<(glam::Vec3, glam::Vec3)>,
}

/// The names of the irradiance volume's box in glsl/eikonal (`LIGHT_{MIN,MAX}_{X,Y,Z}`).
pub(super) const LIGHT_BOX: [&str; 6] =
    ["LIGHT_MIN_X", "LIGHT_MIN_Y", "LIGHT_MIN_Z", "LIGHT_MAX_X", "LIGHT_MAX_Y", "LIGHT_MAX_Z"];

/// Specialisation constants `names` (min x, y, z, max x, y, z) of the box `min`..`max`.
pub(super) fn box_specs(names: [&'static str; 6], min: glam::Vec3, max: glam::Vec3) -> [(&'static str, Spec); 6] {
    let v = [min.x, min.y, min.z, max.x, max.y, max.z];
    std::array::from_fn(|i| (names[i], Spec::F32(v[i])))
}

/// IEEE half precision of `x` (round to nearest even; overflow to infinity, which the scene
/// checks rule out: coefficients are at most 10^4).
pub fn f16_bits(x: f32) -> u16 {
    let b = x.to_bits();
    let sign = ((b >> 16) & 0x8000) as u16;
    let exp = ((b >> 23) & 0xff) as i32;
    let man = b & 0x7f_ffff;
    if exp == 0xff {
        return sign | 0x7c00 | if man != 0 { 0x200 } else { 0 };
    }
    let e = exp - 127 + 15;
    if e >= 31 {
        return sign | 0x7c00;
    }
    if e <= 0 {
        if e < -10 {
            return sign;
        }
        // Subnormal: shift the mantissa with its implicit bit, rounding to nearest even.
        let m = man | 0x80_0000;
        let shift = (14 - e) as u32;
        let half = 1u32 << (shift - 1);
        let rest = m & ((1u32 << shift) - 1);
        let mut h = m >> shift;
        if rest > half || (rest == half && h & 1 == 1) {
            h += 1;
        }
        return sign | h as u16;
    }
    let mut h = ((e as u32) << 10) | (man >> 13);
    let rest = man & 0x1fff;
    if rest > 0x1000 || (rest == 0x1000 && h & 1 == 1) {
        h += 1; // may carry into the exponent, which is still correct rounding
    }
    sign | h as u16
}

/// Section 5.1 on the GPU: upload n - 1 (per channel slab), blur along x, y, z,
/// differentiate; upload the material volumes.
pub(crate) fn prepare_volume(
    ctx: &Arc<GpuContext>,
    params: EikonalParams,
    volume: &Volume,
    graph: &mut FrameGraph,
) -> GpuResult<VolumeTextures> {
    let fields = volume.fields();
    let channels: u32 = if fields.dispersive { 3 } else { 1 };
    let [nx, ny, nz] = volume.resolution;
    let extent = [nx, ny, nz * channels];
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_DST;
    let raw = Image::new(ctx, &ImageDesc::d3("eikonal_index", vk::Format::R32_SFLOAT, extent, usage))?;
    let scratch = Image::new(ctx, &ImageDesc::d3("eikonal_smoothed", vk::Format::R32_SFLOAT, extent, usage))?;
    let field = Image::new(
        ctx,
        &ImageDesc::d3(
            "eikonal_field",
            vk::Format::R32G32B32A32_SFLOAT,
            extent,
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED,
        ),
    )?;
    let (raw_id, scratch_id, field_id) =
        (graph.register_image(&raw), graph.register_image(&scratch), graph.register_image(&field));

    // The material volumes: real when anything in them is non-zero.
    // The boundary indicator widened to the band in which the smoothed index still changes
    // (3 sigma of the Gaussian plus the one-voxel coverage ramp), see view.frag.
    let (band, band_reflectance) = fields.boundary_band((3.0 * params.sigma).ceil() as u32 + 1);
    let rgb_any = |v: &[[f32; 4]]| v.iter().any(|e| e[0] > 0.0 || e[1] > 0.0 || e[2] > 0.0);
    let (extinction_any, emission_any) = (rgb_any(&fields.extinction), rgb_any(&fields.emission));
    let materials = band.iter().any(|&b| b > 0.0) || extinction_any || emission_any;
    let scatters = fields.extinction.iter().zip(&fields.albedo).any(|(e, a)| (0..3).any(|c| e[c] * a[c] > 0.0));
    // Where a light patch may leap: nothing but a constant index within reach of the smoothing
    // (ceil(3 sigma), as smooth.comp), the central differences and the trilinear lookup.
    let material_at: Vec<bool> = (0..fields.voxels())
        .map(|i| {
            let (e, m) = (fields.extinction[i], fields.emission[i]);
            band[i] > 0.0 || e[..3].iter().chain(&m[..3]).any(|&c| c > 0.0)
        })
        .collect();
    let index_slabs: Vec<&[f32]> = fields.index[..channels as usize].iter().map(|v| v.as_slice()).collect();
    let reach = uniform_reach(&index_slabs, &material_at, fields.resolution, (3.0 * params.sigma).ceil() as usize + 2);
    let (bricks, bricks_texels) = crate::gpu::Buffer::texels(ctx, "eikonal_bricks", &reach, vk::Format::R32_UINT)?;
    let absorbs: Vec<bool> = fields.extinction.iter().map(|e| e[..3].iter().any(|&c| c > 0.0)).collect();
    let weak_reach = if params.leaps {
        let integrated: Vec<bool> =
            absorbs.iter().zip(&fields.emission).map(|(&a, e)| a || e[..3].iter().any(|&c| c > 0.0)).collect();
        weak_reach(
            &index_slabs,
            &integrated,
            fields.resolution,
            volume.voxel_size(),
            params.sigma,
            params.weak_gradient,
        )
    } else {
        vec![0]
    };
    let medium = medium_bricks(&index_slabs, &absorbs, fields.resolution, volume.min, volume.voxel_size());
    let material_extent = if materials { volume.resolution } else { [1, 1, 1] };
    let material_usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
    let half = |name: &str| {
        Image::new(ctx, &ImageDesc::d3(name, vk::Format::R16G16B16A16_SFLOAT, material_extent, material_usage))
    };
    let (extinction, albedo, emission) =
        (half("eikonal_extinction")?, half("eikonal_albedo")?, half("eikonal_emission")?);
    let (extinction_id, albedo_id, emission_id) =
        (graph.register_image(&extinction), graph.register_image(&albedo), graph.register_image(&emission));
    let pack = |texels: &mut dyn Iterator<Item = [f32; 4]>| -> Vec<u16> {
        if materials {
            texels.flat_map(|t| t.map(f16_bits)).collect()
        } else {
            vec![0; 4]
        }
    };
    let ext_data = pack(&mut fields.extinction.iter().copied());
    let alb_data = pack(&mut fields.albedo.iter().zip(&band_reflectance).map(|(a, &r)| [a[0], a[1], a[2], r]));
    // The view's march map (`VolumeTextures::march`), one stand-in texel when the view reads
    // neither the band nor the reach.
    let band_factor: Vec<f32> = if materials {
        band.iter().zip(&band_reflectance).map(|(&b, &r)| if b > 0.5 { r } else { -1.0 }).collect()
    } else {
        vec![-1.0]
    };
    let march = march_map(&band_factor, &weak_reach);
    // Device-local (on a discrete GPU every step of every view ray reads it), filled by a
    // copy below.
    let march_bytes = std::mem::size_of_val(march.as_slice()) as u64;
    let march_usage = vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
    let march_buffer =
        crate::gpu::Buffer::new(ctx, "eikonal_march", march_bytes, march_usage, crate::gpu::MemoryLocation::GpuOnly)?;
    let march_texels = crate::gpu::BufferView::new(ctx, &march_buffer, vk::Format::R32_UINT)?;
    let march_id = graph.register_buffer(&march_buffer);
    let emi_data = pack(&mut fields.emission.iter().zip(&band).map(|(e, &b)| [e[0], e[1], e[2], b]));

    // The blur ping-pongs raw -> scratch -> raw -> scratch; the gradient reads scratch.
    let passes = [(&raw, &scratch), (&scratch, &raw), (&raw, &scratch), (&scratch, &field)];
    let sets = passes.iter().map(|&(src, dst)| {
        Bindings::new(vk::ShaderStageFlags::COMPUTE)
            .storage_image(EIKONAL_BINDING_SRC, src)
            .storage_image(EIKONAL_BINDING_DST, dst)
    });
    let sets = Bindings::build_each(ctx, "eikonal_volume", sets.collect())?;
    let pipeline =
        |name: &str, shader: &str, spec: Specs<'_>| ComputePipeline::new(ctx, name, shader, &[sets.layout()], 0, spec);
    let smooth: Vec<ComputePipeline> = (0..3u32)
        .map(|axis| {
            pipeline(
                &format!("eikonal_smooth_{axis}"),
                "eikonal/smooth.comp",
                &[("AXIS", Spec::U32(axis)), ("SIGMA", Spec::F32(params.sigma)), ("SLAB", Spec::I32(nz as i32))],
            )
        })
        .collect::<GpuResult<_>>()?;
    let voxel = volume.voxel_size();
    let gradient = pipeline(
        "eikonal_gradient",
        "eikonal/gradient.comp",
        &[
            ("VOXEL_X", Spec::F32(voxel.x)),
            ("VOXEL_Y", Spec::F32(voxel.y)),
            ("VOXEL_Z", Spec::F32(voxel.z)),
            ("SLAB", Spec::I32(nz as i32)),
        ],
    )?;

    let mut samples: Vec<f32> = Vec::with_capacity(fields.voxels() * channels as usize);
    for c in 0..channels as usize {
        samples.extend_from_slice(&fields.index[c]);
    }
    let upload =
        |name: &str, bytes: &[u8]| crate::gpu::Buffer::with_data(ctx, name, bytes, vk::BufferUsageFlags::TRANSFER_SRC);
    let staging = upload("eikonal_index_upload", bytemuck::cast_slice(&samples))?;
    let staging_materials = [
        upload("eikonal_extinction_upload", bytemuck::cast_slice(&ext_data))?,
        upload("eikonal_albedo_upload", bytemuck::cast_slice(&alb_data))?,
        upload("eikonal_emission_upload", bytemuck::cast_slice(&emi_data))?,
    ];
    let march_staging = upload("eikonal_march_upload", bytemuck::cast_slice(&march))?;
    let groups = extent.map(|n| n.div_ceil(EIKONAL_GROUP));
    let ids = [(raw_id, scratch_id), (scratch_id, raw_id), (raw_id, scratch_id), (scratch_id, field_id)];
    let names = ["eikonal_smooth_x", "eikonal_smooth_y", "eikonal_smooth_z", "eikonal_gradient"];
    ctx.one_shot(|cmd| {
        graph.access_now(
            cmd,
            &[
                (raw_id, Access::TransferWrite),
                (extinction_id, Access::TransferWrite),
                (albedo_id, Access::TransferWrite),
                (emission_id, Access::TransferWrite),
            ],
            &[(march_id, Access::TransferWrite)],
        );
        cmd.copy_buffer_to_image(&staging, &raw);
        for (buffer, image) in staging_materials.iter().zip([&extinction, &albedo, &emission]) {
            cmd.copy_buffer_to_image(buffer, image);
        }
        cmd.copy_buffer(&march_staging, &march_buffer, march_bytes);
        // Only eikonal_view's fragments read it, in every later frame.
        graph.access_now(cmd, &[], &[(march_id, Access::FragmentStorageRead)]);
        let mut frame = graph.frame();
        for (i, &(src, dst)) in ids.iter().enumerate() {
            let pipeline = if i < 3 { &smooth[i] } else { &gradient };
            let set = sets.sets()[i];
            frame.pass(names[i]).read(src, Access::ComputeRead).write(dst, Access::ComputeWrite).record(move |cmd| {
                cmd.bind_compute(pipeline, &[set]);
                cmd.dispatch(groups[0], groups[1], groups[2]);
            });
        }
        frame.execute(cmd, None);
    })?;
    Ok(VolumeTextures {
        _raw: raw,
        _scratch: scratch,
        field,
        field_id,
        extinction,
        extinction_id,
        albedo,
        albedo_id,
        emission,
        emission_id,
        channels,
        materials,
        extinction_any,
        scatters,
        emission_any,
        bricks,
        bricks_texels,
        march: march_buffer,
        march_texels,
        medium,
    })
}

/// The boxes (world space) of the bricks of [`BRICK`]^3 voxels holding a voxel whose index
/// differs from air's in any slab of `index` (n - 1 per voxel, before smoothing) or which
/// `absorbs`: beyond these, widened by the smoothing's and the lookups' reach, the light
/// simulator's field is exactly n = 1 with no gradient and no extinction, so light travels
/// straight (its `skip_air`).
pub fn medium_bricks(
    index: &[&[f32]],
    absorbs: &[bool],
    resolution: [u32; 3],
    min: glam::Vec3,
    voxel: glam::Vec3,
) -> Vec<(glam::Vec3, glam::Vec3)> {
    let (dims, brick) = (resolution.map(|r| r as usize), BRICK as usize);
    let nb = dims.map(|d| d.div_ceil(brick));
    let mut hit = vec![false; nb[0] * nb[1] * nb[2]];
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let i = x + dims[0] * (y + dims[1] * z);
                if absorbs[i] || index.iter().any(|slab| slab[i] != 0.0) {
                    hit[x / brick + nb[0] * (y / brick + nb[1] * (z / brick))] = true;
                }
            }
        }
    }
    let mut boxes = Vec::new();
    for (b, _) in hit.iter().enumerate().filter(|(_, &h)| h) {
        let at = glam::UVec3::new((b % nb[0]) as u32, ((b / nb[0]) % nb[1]) as u32, (b / (nb[0] * nb[1])) as u32);
        let lo = at * BRICK;
        let hi = (lo + BRICK).min(glam::UVec3::from(resolution));
        boxes.push((min + lo.as_vec3() * voxel, min + hi.as_vec3() * voxel));
    }
    boxes
}

/// Voxels per edge of a brick of the uniform-region map ([`uniform_reach`]).
pub const BRICK: u32 = 4;

/// The uniform-region map of the light simulator's leaps (glsl/eikonal/light_step.glsl,
/// `render.eikonal.light_leaps`), one u32 per brick of [`BRICK`]^3 voxels, x fastest: the Chebyshev
/// distance, in bricks and at most 255, to the nearest brick that is not uniform (0: this
/// brick is not). A brick is uniform when every index slab in `index` (n - 1 per voxel) is
/// one constant over the brick's voxels widened by `radius` voxels, the air beyond the box
/// (n - 1 = 0) included, and no voxel within one of the brick has a material
/// (`material`). There the smoothed field has no gradient, so the ray equation's solution
/// (Eqs. 9-10 with grad n = 0: dv/ds = 0) is a straight line, and the march has nothing to
/// absorb, emit or reflect: the cube of 2k - 1 bricks around a brick of distance k is
/// crossed in one straight leap. `radius` must cover everything the march's field sample
/// reads: the smoothing's ceil(3 sigma), one voxel of central differences and one of the
/// trilinear lookup.
pub fn uniform_reach(index: &[&[f32]], material: &[bool], resolution: [u32; 3], radius: usize) -> Vec<u32> {
    let dims = resolution.map(|n| n as usize);
    let m = material.iter().map(|&b| if b { (1.0, 1.0) } else { (0.0, 0.0) }).collect();
    let (range, nb) = brick_range(m, dims, 1);
    let mut uniform: Vec<bool> = range.iter().map(|&(_, hi)| hi == 0.0).collect();
    for slab in index {
        let (range, _) = brick_range(slab.iter().map(|&v| (v, v)).collect(), dims, radius);
        for (u, (lo, hi)) in uniform.iter_mut().zip(range) {
            *u &= lo == hi;
        }
    }
    chebyshev_distance(&uniform, nb)
}

/// (min, max) of `values` (x fastest, `dims` voxels) over each brick widened by `radius`
/// voxels, 0 standing for everything beyond the box: three separable passes, one per axis.
fn brick_range(values: Vec<(f32, f32)>, dims: [usize; 3], radius: usize) -> (Vec<(f32, f32)>, [usize; 3]) {
    (0..3).fold((values, dims), |(src, dims), axis| {
        let n = dims[axis];
        let mut out_dims = dims;
        out_dims[axis] = n.div_ceil(BRICK as usize);
        let stride = |d: [usize; 3]| [1, d[0], d[0] * d[1]];
        let (si, so) = (stride(dims), stride(out_dims));
        let mut out = vec![(0.0, 0.0); out_dims.iter().product()];
        for z in 0..out_dims[2] {
            for y in 0..out_dims[1] {
                for x in 0..out_dims[0] {
                    let p = [x, y, z];
                    let lo = (p[axis] * BRICK as usize) as isize - radius as isize;
                    let hi = ((p[axis] + 1) * BRICK as usize + radius) as isize;
                    // A range reaching past the box also reads the air's 0.
                    let mut r = if lo < 0 || hi > n as isize { (0.0f32, 0.0f32) } else { (f32::MAX, f32::MIN) };
                    let base: usize = (0..3).filter(|&a| a != axis).map(|a| p[a] * si[a]).sum();
                    for i in lo.max(0)..hi.min(n as isize) {
                        let v = src[base + i as usize * si[axis]];
                        r = (r.0.min(v.0), r.1.max(v.1));
                    }
                    out[x * so[0] + y * so[1] + z * so[2]] = r;
                }
            }
        }
        (out, out_dims)
    })
}

/// The view rays' march map (glsl/eikonal/view.frag, `march_voxel`): per voxel, the bits of
/// the boundary band's reflectance factor (`band`, -1 outside the band) with its eight lowest
/// mantissa bits replaced by the weak-gradient reach (`reach`, [`weak_reach`]), so that the
/// march's one 32-bit fetch per step gives both. The factor keeps 15 of its 23 mantissa bits
/// (a relative change under 2^-15, where the factor only scales a Fresnel term; 1, -1 and 0
/// exactly). Either slice may be one stand-in texel where the view reads none of it (it then
/// stands for -1 or 0 everywhere).
pub fn march_map(band: &[f32], reach: &[u8]) -> Vec<u32> {
    let voxels = band.len().max(reach.len());
    (0..voxels)
        .map(|i| {
            let factor = if band.len() == voxels { band[i] } else { -1.0 };
            let k = if reach.len() == voxels { reach[i] } else { 0 };
            (factor.to_bits() & !0xff) | u32::from(k)
        })
        .collect()
}

/// The weak-gradient map of the view rays' merged steps (glsl/eikonal/view.frag,
/// `weak_length`; `render.eikonal.weak_gradient`): per voxel, x fastest, the Chebyshev
/// distance in voxels, at most 255, to the nearest voxel that is not weak (0: this one is
/// not). A voxel is weak when the smoothed index of every slab in `index` (n - 1 per voxel,
/// before smoothing) changes there by at most `threshold` per voxel, |grad n| times the
/// smallest edge of `voxel` (not at all for a threshold of 0), and it has no material
/// (`material`: extinction or emission, which the march integrates per step). In the cube of
/// 2k - 1 voxels around a voxel of distance k, less half a voxel on each side, a trilinear
/// field lookup reads weak voxels only, so |grad n| is at most `threshold` per voxel edge and
/// a ray turns by at most `threshold` per voxel travelled (Eq. 10, dv/ds = grad n, n >= 1);
/// with a threshold of 0 it goes straight. The smoothing and the gradient are those of
/// glsl/eikonal/smooth.comp and gradient.comp: where the index is constant within the
/// smoothing's reach, both give the same value at every voxel and a gradient of exactly 0.
pub fn weak_reach(
    index: &[&[f32]],
    material: &[bool],
    resolution: [u32; 3],
    voxel: glam::Vec3,
    sigma: f32,
    threshold: f32,
) -> Vec<u8> {
    let dims = resolution.map(|n| n as usize);
    let strides = [1, dims[0], dims[0] * dims[1]];
    let edges = voxel.to_array();
    let smallest = voxel.min_element();
    let mut strong = material.to_vec();
    for slab in index {
        let s = smoothed(slab, dims, sigma);
        let mut i = 0;
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    // Central differences, the air beyond the box at n - 1 = 0.
                    let mut g2 = 0.0;
                    for (a, c) in [x, y, z].into_iter().enumerate() {
                        let hi = if c + 1 < dims[a] { s[i + strides[a]] } else { 0.0 };
                        let lo = if c > 0 { s[i - strides[a]] } else { 0.0 };
                        let g = (hi - lo) / (2.0 * edges[a]);
                        g2 += g * g;
                    }
                    strong[i] |= g2.sqrt() * smallest > threshold;
                    i += 1;
                }
            }
        }
    }
    let weak: Vec<bool> = strong.iter().map(|&s| !s).collect();
    chebyshev_distance(&weak, dims).into_iter().map(|d| d as u8).collect()
}

/// One slab of n - 1 smoothed as glsl/eikonal/smooth.comp smooths it: a separable Gaussian of
/// `sigma` voxels over ceil(3 sigma) voxels on each side, the air beyond the box adding its
/// weight with n - 1 = 0.
fn smoothed(slab: &[f32], dims: [usize; 3], sigma: f32) -> Vec<f32> {
    let radius = (3.0 * sigma).ceil() as usize;
    let weights: Vec<f32> = (0..=2 * radius)
        .map(|j| {
            let k = j as f32 - radius as f32;
            if sigma > 0.0 {
                (-(k * k) / (2.0 * sigma * sigma)).exp()
            } else {
                1.0
            }
        })
        .collect();
    let total: f32 = weights.iter().sum();
    let (mut src, mut dst) = (slab.to_vec(), vec![0.0; slab.len()]);
    let strides = [1, dims[0], dims[0] * dims[1]];
    for axis in 0..3 {
        let (stride, n) = (strides[axis], dims[axis]);
        // Each line along `axis` in a buffer padded with the air's 0 on both sides: a tap
        // beyond the box adds exactly 0, as the shader's skipped ones add nothing.
        let mut line = vec![0.0f32; n + 2 * radius];
        // The other two axes.
        let (a, b) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        for j in 0..dims[b] {
            for k in 0..dims[a] {
                let start = k * strides[a] + j * strides[b];
                for c in 0..n {
                    line[radius + c] = src[start + c * stride];
                }
                for c in 0..n {
                    let taps = &line[c..c + 2 * radius + 1];
                    let sum: f32 = weights.iter().zip(taps).map(|(w, v)| w * v).sum();
                    dst[start + c * stride] = sum / total;
                }
            }
        }
        std::mem::swap(&mut src, &mut dst);
    }
    src
}

/// Chebyshev distance (in bricks, at most 255) from each brick to the nearest one that is
/// not `uniform`: two raster passes over the 26-neighbourhood with unit weights, which is
/// exact for the Chebyshev metric.
fn chebyshev_distance(uniform: &[bool], nb: [usize; 3]) -> Vec<u32> {
    let mut d: Vec<u32> = uniform.iter().map(|&u| if u { 255 } else { 0 }).collect();
    // The 13 neighbours before a cell in raster order (the other 13 after it, mirrored).
    let neighbours: Vec<[isize; 3]> = (-1..=1)
        .flat_map(|z| (-1..=1).flat_map(move |y| (-1..=1).map(move |x| [x, y, z])))
        .filter(|&[x, y, z]| (z, y, x) < (0, 0, 0))
        .collect();
    let strides = [1, nb[0] as isize, (nb[0] * nb[1]) as isize];
    let offset = |o: [isize; 3]| o[0] * strides[0] + o[1] * strides[1] + o[2] * strides[2];
    for forward in [true, false] {
        let sign = if forward { 1 } else { -1 };
        let steps: Vec<([isize; 3], isize)> =
            neighbours.iter().map(|o| o.map(|c| c * sign)).map(|o| (o, offset(o))).collect();
        for z in 0..nb[2] {
            for y in 0..nb[1] {
                for x in 0..nb[0] {
                    let p = if forward { [x, y, z] } else { [nb[0] - 1 - x, nb[1] - 1 - y, nb[2] - 1 - z] };
                    let k = offset(p.map(|c| c as isize));
                    // Inside, every neighbour exists; on the border each is checked.
                    let interior = (0..3).all(|a| p[a] > 0 && p[a] + 1 < nb[a]);
                    let mut best = d[k as usize];
                    for &(o, delta) in &steps {
                        let inside = interior || (0..3).all(|a| (0..nb[a] as isize).contains(&(p[a] as isize + o[a])));
                        if inside {
                            best = best.min(d[(k + delta) as usize] + 1);
                        }
                    }
                    d[k as usize] = best;
                }
            }
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The brick map against brute force on a ball of constant index in a 30^3 volume (not a
    /// multiple of the brick: the last bricks reach past the box), with a material voxel: a
    /// brick is uniform exactly when no non-constant index voxel lies within `radius` of it
    /// (the air beyond the box counted as 0) and no material voxel within 1, and each
    /// brick's distance is the Chebyshev distance to the nearest brick that is not uniform.
    #[test]
    fn uniform_reach_matches_brute_force() {
        let n = 30usize;
        let radius = 5usize;
        let at = |x: usize, y: usize, z: usize| x + n * (y + n * z);
        let mut index = vec![0.0f32; n * n * n];
        let mut material = vec![false; n * n * n];
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let d = [x, y, z].map(|c| c as f32 + 0.5 - 12.0);
                    if d.iter().map(|c| c * c).sum::<f32>() < 64.0 {
                        index[at(x, y, z)] = 0.5;
                    }
                }
            }
        }
        material[at(27, 3, 20)] = true;
        let reach = uniform_reach(&[&index], &material, [n as u32; 3], radius);
        let b = BRICK as usize;
        let nb = n.div_ceil(b);
        assert_eq!(reach.len(), nb * nb * nb);
        let value = |q: [isize; 3]| {
            if q.iter().all(|&c| c >= 0 && (c as usize) < n) {
                index[at(q[0] as usize, q[1] as usize, q[2] as usize)]
            } else {
                0.0
            }
        };
        let mat = |q: [isize; 3]| {
            q.iter().all(|&c| c >= 0 && (c as usize) < n) && material[at(q[0] as usize, q[1] as usize, q[2] as usize)]
        };
        let uniform = |bx: usize, by: usize, bz: usize| {
            let first = value([(bx * b) as isize, (by * b) as isize, (bz * b) as isize]);
            let r = radius as isize;
            let range = |c: usize| (c * b) as isize - r..((c + 1) * b) as isize + r;
            range(bz).all(|z| range(by).all(|y| range(bx).all(|x| value([x, y, z]) == first))) && {
                let range1 = |c: usize| (c * b) as isize - 1..((c + 1) * b) as isize + 1;
                !range1(bz).any(|z| range1(by).any(|y| range1(bx).any(|x| mat([x, y, z]))))
            }
        };
        let flags: Vec<bool> = (0..nb * nb * nb).map(|k| uniform(k % nb, k / nb % nb, k / (nb * nb))).collect();
        assert!(flags.iter().any(|&u| u) && flags.iter().any(|&u| !u), "the case must have both kinds");
        for (k, &got) in reach.iter().enumerate() {
            let p = [k % nb, k / nb % nb, k / (nb * nb)].map(|c| c as isize);
            let expected = (0..flags.len())
                .filter(|&j| !flags[j])
                .map(|j| {
                    let q = [j % nb, j / nb % nb, j / (nb * nb)].map(|c| c as isize);
                    (0..3).map(|a| (p[a] - q[a]).unsigned_abs() as u32).max().unwrap()
                })
                .min()
                .unwrap_or(255);
            assert_eq!(got, expected.min(255), "brick {p:?}");
        }
    }

    /// The march map unpacked as glsl/eikonal/view.frag unpacks it (`band_factor_of`,
    /// `weak_reach_of`): every reach exactly, every factor within its 15 mantissa bits (a
    /// relative 2^-15), and the sign of -1 (outside the band) and of 0 (inside) kept whatever
    /// the reach. A stand-in slice of one texel stands for -1 or 0 everywhere.
    #[test]
    fn march_map_keeps_the_reach_and_the_band_factor() {
        let band = [-1.0f32, 0.0, 1.0, 0.04, 0.6, 1.0 / 3.0, -1.0];
        let reach = [0u8, 255, 1, 17, 2, 128, 255];
        let map = march_map(&band, &reach);
        for (i, &bits) in map.iter().enumerate() {
            assert_eq!(bits & 0xff, u32::from(reach[i]), "reach of voxel {i}");
            let factor = f32::from_bits(bits & !0xff);
            assert_eq!(factor >= 0.0, band[i] >= 0.0, "band flag of voxel {i}");
            assert!((factor - band[i]).abs() <= band[i].abs() * 2f32.powi(-15), "factor {factor} of {}", band[i]);
        }
        assert_eq!(march_map(&band, &[0]).iter().map(|b| b & 0xff).max(), Some(0));
        let outside = march_map(&[-1.0], &reach);
        assert!(outside.iter().all(|&b| f32::from_bits(b & !0xff) == -1.0));
    }

    /// The weak-gradient map against brute force on a ball of constant index (radius 6
    /// voxels, with its one-voxel ramp) in a 24^3 volume with a material voxel: the smoothing
    /// as one 3D convolution in f64, central differences, and each voxel's Chebyshev distance
    /// to the nearest voxel whose index changes by more than the threshold per voxel or that
    /// has a material. No voxel's change lies within 1e-5 of the threshold (checked), so f32
    /// rounding cannot move one across it. With a threshold of 0 every voxel whose index is
    /// constant within the smoothing's reach and one more voxel is weak.
    #[test]
    fn weak_reach_matches_brute_force() {
        let (n, sigma, h) = (24usize, 0.75f32, 0.1f32);
        let at = |x: usize, y: usize, z: usize| x + n * (y + n * z);
        let mut index = vec![0.0f32; n * n * n];
        for (i, v) in index.iter_mut().enumerate() {
            let r = [i % n, i / n % n, i / (n * n)].map(|c| c as f32 + 0.5 - 11.0);
            let d = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt() - 6.0;
            *v = 0.5 * (0.5 - d).clamp(0.0, 1.0);
        }
        let mut material = vec![false; n * n * n];
        material[at(20, 3, 18)] = true;
        let radius = (3.0 * sigma).ceil() as isize;
        let w = |k: isize| (-((k * k) as f64) / (2.0 * f64::from(sigma).powi(2))).exp();
        let total: f64 = (-radius..=radius).map(w).sum::<f64>().powi(3);
        let value = |q: [isize; 3]| {
            if q.iter().all(|&c| c >= 0 && (c as usize) < n) {
                f64::from(index[at(q[0] as usize, q[1] as usize, q[2] as usize)])
            } else {
                0.0
            }
        };
        let smooth = |q: [isize; 3]| {
            let mut sum = 0.0;
            for dz in -radius..=radius {
                for dy in -radius..=radius {
                    for dx in -radius..=radius {
                        sum += w(dx) * w(dy) * w(dz) * value([q[0] + dx, q[1] + dy, q[2] + dz]);
                    }
                }
            }
            sum / total
        };
        let voxel = |i: usize| [i % n, i / n % n, i / (n * n)].map(|c| c as isize);
        let change: Vec<f64> = (0..n * n * n)
            .map(|i| {
                let q = voxel(i);
                let g: f64 = (0..3)
                    .map(|a| {
                        let (mut lo, mut hi) = (q, q);
                        lo[a] -= 1;
                        hi[a] += 1;
                        ((smooth(hi) - smooth(lo)) / 2.0).powi(2)
                    })
                    .sum();
                g.sqrt()
            })
            .collect();
        let threshold = 1e-3;
        assert!(change.iter().all(|c| (c - threshold).abs() > 1e-5), "a voxel's change lies at the threshold");
        let strong: Vec<bool> = (0..n * n * n).map(|i| material[i] || change[i] > threshold).collect();
        let got = weak_reach(&[&index], &material, [n as u32; 3], glam::Vec3::splat(h), sigma, threshold as f32);
        assert!(got.contains(&0) && got.iter().any(|&k| k > 1), "the case must have both kinds");
        for (i, &k) in got.iter().enumerate() {
            let q = voxel(i);
            let expected = (0..n * n * n)
                .filter(|&j| strong[j])
                .map(|j| (0..3).map(|a| (voxel(j)[a] - q[a]).unsigned_abs()).max().unwrap())
                .min()
                .unwrap_or(255);
            assert_eq!(u32::from(k), expected.min(255) as u32, "voxel {q:?}");
        }
        // Threshold 0: the index constant within the smoothing's reach plus one voxel (the
        // central differences) and no material makes a voxel weak.
        let exact = weak_reach(&[&index], &material, [n as u32; 3], glam::Vec3::splat(h), sigma, 0.0);
        let reach = radius + 1;
        for (i, &k) in exact.iter().enumerate() {
            let q = voxel(i);
            let first = value(q);
            let constant = (-reach..=reach).all(|dz| {
                (-reach..=reach).all(|dy| (-reach..=reach).all(|dx| value([q[0] + dx, q[1] + dy, q[2] + dz]) == first))
            });
            if constant && !material[i] {
                assert!(k > 0, "voxel {q:?} has a constant index around it but is not weak");
            }
            if change[i] > 1e-6 {
                assert_eq!(k, 0, "voxel {q:?} changes by {} but is weak", change[i]);
            }
        }
    }
}
