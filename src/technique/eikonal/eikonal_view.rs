//! Eikonal rendering (Ihrke et al. 2007, ../shared/papers/ihrke2007-eikonal-rendering.md):
//! the view renderer of sections 4.1 and 5.3 for scenes with a `[volume]`.
//!
//! - Section 5.1: the analytic index profile is sampled at the voxel centres on the CPU
//!   ([`Volume::sample`], as n - 1), uploaded, smoothed and differentiated on the GPU
//!   ([`super::volume`]), once per volume and sigma.
//! - Sections 4.1, 5.3: `eikonal_view` (glsl/eikonal/view.frag) marches every camera ray that
//!   enters the volume's box with the ray equation, Eqs. 9-10, by Euler (Eqs. 11-12), the
//!   midpoint rule, RK4 or velocity Verlet, absorbs along the curved path (Eq. 5) and looks up
//!   the environment in the exit direction, over the deferred result.
//! - prism's departure, `render.eikonal.leaps` and `weak_gradient`: whole steps merge into one
//!   where a per-voxel map (volume.rs `weak_reach`) finds the smoothed index constant (the
//!   full march's straight line exactly) or changing by at most the threshold per voxel;
//!   `leaps = false` marches at `step` everywhere, as the paper does (docs/BENCHMARKS.md).
//! - Volume sources (src/scene/volume_sources.rs): the fields of `[[volume.region]]`s
//!   are evaluated on the CPU; a per-channel index is uploaded as three slabs stacked along z
//!   and smoothed/differentiated slab by slab (dispersion: one march per channel), and the
//!   materials go to three RGBA16F volumes ([`VolumeTextures`]) for RGB extinction, emission
//!   and Fresnel reflection at the boundary indicator's band.
use std::sync::Arc;

use crate::gpu::{
    vk, Access, Buffer, ComputePipeline, GpuContext, GpuResult, Image, ImageDesc, Sampler, SamplerDesc, Spec,
};
use crate::graph::{Bindings, Frame, FrameGraph};
use crate::scene::techniques::{EikonalParams, HardwareFilter, Integrator};
use crate::scene::{Scene, Volume};
use crate::technique::scene_specialization;
use crate::technique::{
    describe_lights, list, params, registration, FrameInputs, PlannedPass, Registration, RenderError, Setup, Stage,
    Technique,
};
use crate::{
    BINDING_EIKONAL_ALBEDO, BINDING_EIKONAL_EMISSION, BINDING_EIKONAL_EXTINCTION, BINDING_EIKONAL_FIELD,
    BINDING_FILTER_PROBE_ERRORS, BINDING_FILTER_PROBE_TEXELS, BINDING_GBUF_DEPTH, EIKONAL_EULER, EIKONAL_MIDPOINT,
    EIKONAL_RK4, EIKONAL_VERLET,
};

use super::eikonal_light::EIKONAL_LIGHT;
use super::eikonal_nearby;
use super::read_mask::{read_mask, ReadSites};
use super::volume::{box_specs, prepare_volume, VolumeTextures, LIGHT_BOX};
use crate::technique::baseline::fullscreen::{fragment_set, FullscreenDesc, FullscreenPass};
use crate::technique::refraction::nearby_impostors::{ImpostorShading, NearbyDesc, NearbyImpostors, NearbyRects};

pub const EIKONAL_VIEW: &str = "eikonal_view";
/// Hu & Qin 2007 §2.2 impostor textures of the objects near the volume, for eikonal_view's
/// exit and reflected rays (src/technique/eikonal/eikonal_nearby.rs).
pub const EIKONAL_NEARBY: &str = "eikonal_nearby";

/// Every scene with a `[volume]`; parameters `[render.eikonal]`.
pub const TECHNIQUE: Registration = registration!("[volume]", plan, EikonalPass, ["eikonal"]);

/// Whether the view renderer and the light simulator sample the field through the device's
/// trilinear filter (`render.eikonal.hardware_filtering`): one slab only (a dispersive
/// volume's three would blend into each other), and a format the device filters linearly;
/// else the f32 interpolation of eight fetches.
pub fn filters_field(ctx: &Arc<GpuContext>, params: &EikonalParams, channels: u32) -> GpuResult<bool> {
    Ok(channels == 1
        && ctx.supports_format(vk::Format::R32G32B32A32_SFLOAT, vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR)
        && match params.hardware_filtering {
            HardwareFilter::True => true,
            HardwareFilter::False => false,
            HardwareFilter::Auto => filters_in_full_precision(ctx)?,
        })
}

/// Whether the device's linear filter interpolates RGBA32F texels in full precision, so that
/// one filtered lookup of the field equals the f32 interpolation of its eight voxels: every
/// sample of [`filter_error`] within 1e-5 (f32 weights round to about 1e-7; 8-bit weights are
/// off by up to 2e-3).
pub fn filters_in_full_precision(ctx: &Arc<GpuContext>) -> GpuResult<bool> {
    Ok(filter_error(ctx, SamplerDesc::LINEAR_CLAMP)? < 1e-5)
}

/// The largest error of `sampler` over 256 samples between a texel holding 0 and one holding
/// 1, each against its fraction of the way between their centres
/// (glsl/eikonal/filter_probe.comp). Its own images and graph; waits for the device.
pub fn filter_error(ctx: &Arc<GpuContext>, sampler: SamplerDesc) -> GpuResult<f32> {
    const SAMPLES: usize = 256;
    let mut graph = FrameGraph::new();
    let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
    let image =
        Image::new(ctx, &ImageDesc::d3("filter_probe_texels", vk::Format::R32G32B32A32_SFLOAT, [2, 1, 1], usage))?;
    let texels = [0.0f32, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
    let staging = Buffer::with_data(ctx, "filter_probe_upload", &texels, vk::BufferUsageFlags::TRANSFER_SRC)?;
    let errors = Buffer::storage(ctx, "filter_probe_errors", &[0.0f32; SAMPLES])?;
    let sampler = Sampler::new(ctx, "filter_probe", sampler)?;
    let (image_id, errors_id) = (graph.register_image(&image), graph.register_buffer(&errors));
    let set = Bindings::new(vk::ShaderStageFlags::COMPUTE)
        .sampled(BINDING_FILTER_PROBE_TEXELS, &image, &sampler)
        .read(image_id)
        .storage(BINDING_FILTER_PROBE_ERRORS, &errors)
        .build(ctx, "filter_probe")?;
    let pipeline = ComputePipeline::new(ctx, "filter_probe", "eikonal/filter_probe.comp", &[set.layout()], 0, &[])?;
    ctx.one_shot(|cmd| {
        graph.access_now(cmd, &[(image_id, Access::TransferWrite)], &[]);
        cmd.copy_buffer_to_image(&staging, &image);
        let mut frame = graph.frame();
        frame.pass("filter_probe").uses(&set).write(errors_id, Access::ComputeWrite).record(|cmd| {
            cmd.bind_compute(&pipeline, &[set.set()]);
            cmd.dispatch((SAMPLES as u32).div_ceil(64), 1, 1);
        });
        frame.execute(cmd, None);
        graph.access_now(cmd, &[], &[(errors_id, Access::HostRead)]);
    })?;
    ctx.wait_idle()?;
    let measured: &[f32] = bytemuck::cast_slice(errors.read());
    Ok(measured.iter().fold(0.0, |m, &e| if e.is_nan() { f32::INFINITY } else { m.max(e) }))
}

fn plan(scene: &Scene) -> Vec<(Stage, PlannedPass)> {
    let Some(v) = scene.volume.as_ref().filter(|_| scene.render.volume == "eikonal") else {
        return Vec::new();
    };
    let p = EikonalParams::from_settings(&scene.render).unwrap_or_default();
    let mut passes = Vec::new();
    if !scene.lights.is_empty() && p.light {
        let reason = format!(
            "volume {} lit by {}: wavefront light simulation, Ihrke et al. 2007 §4.2, §5.2 (receivers in its irradiance volume)",
            v.name,
            describe_lights(scene, ", ")
        );
        passes.push((Stage::Lighting, PlannedPass::new(EIKONAL_LIGHT, reason)));
    }
    // After eikonal_light (the simulation ran at creation; the textures carry its caustic
    // and shadow), before the view pass that reads them.
    let (kept, dropped) = eikonal_nearby::impostor_objects(scene, p.nearby);
    if !kept.is_empty() {
        let names = |v: &[usize]| v.iter().map(|&i| scene.objects[i].name.clone()).collect::<Vec<_>>();
        let mut reason = format!(
            "impostor rectangles + textures of {} around the volume for its exit and reflected rays (Hu & Qin 2007 §2.2)",
            list(&names(&kept))
        );
        if !dropped.is_empty() {
            reason += &format!("; {} left to the environment map", list(&names(&dropped)));
        }
        passes.push((Stage::Volume, PlannedPass::new(EIKONAL_NEARBY, reason)));
    }
    let [nx, ny, nz] = v.resolution;
    let reason = format!("volume {} ({nx}x{ny}x{nz}): curved view rays, Ihrke et al. 2007 §4.1, §5.3", v.name);
    passes.push((Stage::Volume, PlannedPass::new(EIKONAL_VIEW, reason)));
    passes
}

impl Technique for EikonalPass {
    /// Lighting: the simulated light on the receivers (eikonal_light, after deferred
    /// shading; nothing without a simulation). Volume: `eikonal_nearby` (when the scene has
    /// impostor rectangles), then `eikonal_view`.
    /// The light simulation, run at creation outside the frame graph: its kernels' GPU time.
    fn once_costs(&self) -> Vec<crate::technique::OnceCost> {
        // Sampled, smoothed and differentiated once per volume and sigma (its cache key).
        let volume = crate::technique::OnceCost {
            name: "eikonal_volume".into(),
            ms: self.volume.ms,
            clock: "cpu",
            rerun_on: "volume change",
        };
        let light = self.light_stats().map(|s| crate::technique::OnceCost {
            name: "eikonal_light_simulation".into(),
            ms: s.gpu_ms,
            clock: "gpu",
            // Its cache key: the volume, the lights and the simulation's settings; a moved
            // object or camera re-creates the technique around the cached result.
            rerun_on: "light or volume change",
        });
        std::iter::once(volume).chain(light).collect()
    }

    fn record<'a>(&'a self, stage: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        if stage == Stage::Lighting {
            if let Some(l) = &self.light {
                l.record(frame, inputs.scene, inputs.targets, inputs.frame_set);
            }
            return;
        }
        if !self.nearby.is_empty() {
            self.nearby.record(frame, inputs);
        }
        let mut reads = vec![inputs.scene.environment_id];
        if let Some(l) = &self.light {
            reads.extend(l.image_ids());
        }
        // The exit rays' shading reads the shadow maps (and the impostor textures, in set 1).
        reads.extend(inputs.shadow_atlas);
        self.view.record(frame, inputs.frame_set, &reads);
    }

    fn kept(&mut self) -> Option<&mut crate::technique::Regeneration> {
        Some(&mut self.nearby.regeneration)
    }

    fn preparing(&self) -> bool {
        self.light.as_ref().is_some_and(|l| l.simulating())
    }

    fn prepare(
        &mut self,
        ctx: &std::sync::Arc<crate::gpu::GpuContext>,
        graph: &mut crate::graph::FrameGraph,
        deadline: Option<std::time::Instant>,
    ) -> Result<(), RenderError> {
        let Some(light) = self.light.as_mut() else { return Ok(()) };
        if light.advance(ctx, graph, deadline)? {
            // The impostor textures show the simulated light: render them again with it.
            self.nearby.regeneration.changed();
        }
        Ok(())
    }
}

/// Fig. 16's stopping tolerance (a fraction of d_i) and Fig. 17's seeds for the impostor
/// lookup of exit rays: render.hu_qin's defaults (src/scene/techniques.rs).
const NEARBY_TOLERANCE: f32 = 1e-3;
const NEARBY_SEEDS: u32 = 8;

/// Most steps a view ray may take (a ray that circles inside a lens stops here).
pub const MAX_VIEW_STEPS: u32 = 8192;

/// The `eikonal_view` pass and the volume it renders.
pub struct EikonalPass {
    // Bound by the view pass.
    volume: std::rc::Rc<crate::technique::Timed<VolumeTextures>>,
    view: FullscreenPass,
    // The nearby geometry of exit rays
    // (src/technique/eikonal/eikonal_nearby.rs): impostors (a 1x1 stand-in without rectangles)
    // and the exact triangles.
    nearby: NearbyImpostors,
    _triangles: (crate::gpu::Buffer, crate::gpu::BufferView),
    // The field's sampler (trilinear with a zero border for `hardware_filtering`).
    _field_sampler: Sampler,
    // The light simulation and its receiver pass.
    light: Option<super::eikonal_light::EikonalLight>,
}

impl EikonalPass {
    /// Sample, upload, smooth and differentiate `volume`, and create the view pass.
    /// The scene's volume, lit by its lights when the plan has the light simulation.
    pub fn new(s: &mut Setup<'_>) -> Result<Self, RenderError> {
        let p = params("eikonal", EikonalParams::from_settings(&s.scene.render))?;
        let scene = s.scene;
        let volume = scene.volume.as_ref().expect("planned only with a volume");
        let lights: &[crate::scene::Light] = if s.planned(EIKONAL_LIGHT) { &scene.lights } else { &[] };
        Ok(Self::build(s, p, volume, lights)?)
    }

    fn build(
        s: &mut Setup<'_>,
        params: EikonalParams,
        volume: &Volume,
        lights: &[crate::scene::Light],
    ) -> GpuResult<Self> {
        // The sampled, smoothed and differentiated volume depends on the volume, sigma and the
        // merged steps' map only: a resize or a change of another setting re-creates the pass
        // around it.
        let (ctx, graph) = (s.ctx, &mut *s.graph);
        let key = crate::technique::cache_key(&(params.sigma, params.leaps, params.weak_gradient, volume));
        let timed = s.cache.get_or_try_insert_timed(key, || prepare_volume(ctx, params, volume, graph))?;
        let textures = &timed.value;
        // Section 5.2's light simulation before the view pass is built.
        // Every light of the scene: their runs add into one pair of volumes.
        let light = match lights {
            [_, ..] if params.light => {
                let (light_min, light_max, resolution) =
                    super::eikonal_light::light_grid(volume, params.light_below, params.light_side);
                let sites = ReadSites::of_scene(s.scene, volume, textures.scatters, light_min, light_max);
                let reads = read_mask(&sites, light_min, light_max, resolution);
                let reads = super::eikonal_light::deposits_where_read(&params).then_some(&reads[..]);
                let lit = super::eikonal_light::LitVolume { params: &params, volume, lights, reads };
                Some(super::eikonal_light::EikonalLight::new(s, lit, textures)?)
            }
            _ => None,
        };
        let (ctx, scene, gpu, frame_layout, targets, nearest) =
            (s.ctx, s.scene, s.gpu, s.frame_layout, s.targets, s.nearest);
        let graph = &mut *s.graph;
        let voxel = volume.voxel_size();
        let h = params.step * voxel.min_element();
        // Enough steps for four crossings of the box diagonal (curved and internally
        // reflected rays are longer than straight ones).
        let steps = (4.0 * (volume.max - volume.min).length() / h).ceil().min(MAX_VIEW_STEPS as f32) as u32;
        let integrator = match params.integrator {
            Integrator::Euler => EIKONAL_EULER,
            Integrator::Midpoint => EIKONAL_MIDPOINT,
            Integrator::Rk4 => EIKONAL_RK4,
            Integrator::Verlet => EIKONAL_VERLET,
        };
        let (light_min, light_max) = light.as_ref().map_or((glam::Vec3::ZERO, glam::Vec3::ONE), |l| l.light_box());
        // Without a simulation the field stands in for the light volumes (never read).
        let (irradiance, direction) = light.as_ref().map_or((&textures.field, &textures.field), |l| l.images());
        // What exit and reflected rays meet (src/technique/eikonal/eikonal_nearby.rs).
        let tris: Vec<_> =
            eikonal_nearby::exact_triangles(scene, params.nearby).0.into_iter().map(|(_, t)| t).collect();
        let (triangles, triangle_texels) = crate::gpu::Buffer::texels(
            ctx,
            "eikonal_triangles",
            &eikonal_nearby::triangle_buffer_bytes(&tris),
            vk::Format::R32G32B32A32_UINT,
        )?;
        // The march crosses the box's faces by up to one step (its margin).
        let in_box = eikonal_nearby::triangles_meet_box(&tris, volume.min, volume.max, h);
        let (kept, _) = eikonal_nearby::impostor_objects(scene, params.nearby);
        let desc = NearbyDesc {
            resolution: params.nearby_resolution,
            recursion_depth: 0,
            correction_iterations: params.nearby_iterations,
            correction_tolerance: NEARBY_TOLERANCE,
            seed_samples: NEARBY_SEEDS,
            // view.frag keeps Fig. 13's rectangle choice.
            lookup: crate::scene::techniques::NearbyLookup::Paper,
            // Around a volume (NearbyRects::around) no object refracts: the exit settings
            // are never used.
            exit: crate::scene::techniques::RecursiveExit::BoundingSphere,
            search_steps: 8,
            max_iterations: 32,
        };
        let nearby = if kept.is_empty() {
            NearbyImpostors::stand_in(ctx, EIKONAL_NEARBY, gpu, graph, frame_layout)?
        } else {
            let origin = eikonal_nearby::volume_origin(scene).unwrap_or(glam::Vec3::ZERO);
            // With a light simulation the textures carry the simulated caustic and shadow
            // (glsl/eikonal/nearby_impostor.frag): its volumes in a set of their own.
            let spec = box_specs(LIGHT_BOX, light_min, light_max);
            let shading = match &light {
                Some(l) => {
                    let ((irr, dir), [irr_id, dir_id]) = (l.images(), l.image_ids());
                    let set = fragment_set()
                        .sampled(crate::BINDING_EIKONAL_IRRADIANCE, irr, nearest)
                        .read(irr_id)
                        .sampled(crate::BINDING_EIKONAL_LIGHT_DIR, dir, nearest)
                        .read(dir_id)
                        .build(ctx, EIKONAL_NEARBY)?;
                    Some(ImpostorShading {
                        fragment_shader: "eikonal/nearby_impostor.frag",
                        set,
                        specialization: &spec,
                    })
                }
                None => None,
            };
            let rects = NearbyRects::around(origin, &kept, scene);
            let scene_specs = scene_specialization(scene);
            NearbyImpostors::build(ctx, EIKONAL_NEARBY, &desc, rects, graph, frame_layout, shading, &scene_specs)?
        };
        let hardware_filter = filters_field(ctx, &params, textures.channels)?;
        let field_sampler = Sampler::new(
            ctx,
            "eikonal_field",
            if hardware_filter { SamplerDesc::LINEAR_BORDER } else { SamplerDesc::NEAREST_CLAMP },
        )?;
        let box_names = ["BOX_MIN_X", "BOX_MIN_Y", "BOX_MIN_Z", "BOX_MAX_X", "BOX_MAX_Y", "BOX_MAX_Z"];
        let spec: Vec<_> = [
            ("INTEGRATOR", Spec::U32(integrator)),
            ("STEP", Spec::F32(h)),
            ("MAX_STEPS", Spec::U32(steps.max(1))),
            // Index slabs (3: dispersion) and whether materials are bound.
            ("CHANNELS", Spec::U32(textures.channels)),
            ("MATERIALS", Spec::U32(textures.materials as u32)),
            // Which material volumes hold anything (the others are never sampled).
            ("EXTINCTION", Spec::U32(textures.extinction_any as u32)),
            ("EMISSION", Spec::U32(textures.emission_any as u32)),
            // Merged steps where the field is constant or weak (volume.rs, `weak_reach`).
            ("LEAPS", Spec::U32(params.leaps as u32)),
            ("MIN_TRANSMITTANCE", Spec::F32(params.min_transmittance)),
            ("HARDWARE_FILTER", Spec::U32(u32::from(hardware_filter))),
            // Single scattering (glsl/eikonal/scatter.glsl) with the
            // irradiance and direction volumes of the light simulation.
            ("SCATTER", Spec::U32(u32::from(light.is_some()))),
            // What exit rays meet: nearby_exit.glsl.
            ("TRIANGLES_IN_BOX", Spec::U32(u32::from(in_box))),
            ("NEARBY_ITERATIONS", Spec::U32(params.nearby_iterations)),
            ("NEARBY_TOLERANCE", Spec::F32(NEARBY_TOLERANCE)),
            ("NEARBY_SEEDS", Spec::U32(NEARBY_SEEDS)),
            ("IMPOSTORS", Spec::U32(u32::from(!kept.is_empty()))),
        ]
        .into_iter()
        .chain(box_specs(box_names, volume.min, volume.max))
        .chain(box_specs(LIGHT_BOX, light_min, light_max))
        .chain(scene_specialization(scene))
        .collect();
        let set = fragment_set()
            .sampled(BINDING_GBUF_DEPTH, &targets.depth, nearest)
            .read(targets.depth_id)
            .sampled(BINDING_EIKONAL_FIELD, &textures.field, &field_sampler)
            .read(textures.field_id)
            .sampled(BINDING_EIKONAL_EXTINCTION, &textures.extinction, nearest)
            .read(textures.extinction_id)
            .sampled(BINDING_EIKONAL_ALBEDO, &textures.albedo, nearest)
            .read(textures.albedo_id)
            .sampled(BINDING_EIKONAL_EMISSION, &textures.emission, nearest)
            .read(textures.emission_id)
            // Read when the simulation wrote them (`record`); the field stands in otherwise.
            .sampled(crate::BINDING_EIKONAL_IRRADIANCE, irradiance, nearest)
            .sampled(crate::BINDING_EIKONAL_LIGHT_DIR, direction, nearest)
            .sampled(crate::BINDING_NEARBY_TEXTURE, &nearby.texture, nearest)
            .read(nearby.texture_id)
            .uniform(crate::BINDING_NEARBY_RECTS, &nearby.rect_buffer)
            .texels(crate::BINDING_EIKONAL_TRIANGLES, &triangle_texels)
            .texels(crate::BINDING_EIKONAL_MARCH, &textures.march_texels);
        let view = FullscreenPass::new(
            ctx,
            // Overwrites the pixels whose ray enters the box.
            &FullscreenDesc::over_hdr(EIKONAL_VIEW, "eikonal/view.frag", targets, &spec),
            set,
            frame_layout,
        )?;
        Ok(EikonalPass {
            volume: timed,
            view,
            nearby,
            _triangles: (triangles, triangle_texels),
            _field_sampler: field_sampler,
            light,
        })
    }

    /// The light simulation's statistics (None without a simulation).
    pub fn light_stats(&self) -> Option<&super::eikonal_light::LightStats> {
        self.light.as_ref().and_then(|l| l.stats.as_ref())
    }
}
