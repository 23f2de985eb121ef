//! Tone map to 8-bit sRGB for PNG output and the window.
//!
//! `render.tonemap = "clamp"` (the default): srgb_oetf(clamp(exposure * L, 0, 1)), SCENES.md's
//! rule, in glsl/tonemap/tonemap.frag.
//!
//! `render.tonemap = "adaptive"`: Ihrke et al. 2007 §5.3 ("All lighting computations are
//! performed in high dynamic range and an adaptive tone-mapping based on [Krawczyk et al.
//! 2005] is applied prior to display"). Krawczyk, Myszkowski & Seidel 2005 ("Perceptual
//! effects in real-time tone mapping", SCCG) build on Reinhard et al. 2002's photographic
//! operator; what is implemented here, per frame, on the GPU:
//! - `tonemap_log_average` (glsl/tonemap/log_average.comp): per 32x32 tile, the sum of
//!   log(delta + L_w) and the largest L_w, by a tree in shared memory;
//! - `tonemap_adapt` (glsl/tonemap/adapt.comp): the log-average luminance
//!   L_avg = exp(mean(log(delta + L_w))) (Reinhard et al. 2002, Eq. 1); the adapted luminance
//!   L_a(t) = L_a(t-T) + (L_avg - L_a(t-T)) (1 - exp(-T / tau)) (Krawczyk et al. 2005, §2.2,
//!   Eq. 5) with tau_rod = 0.4 s and tau_cone = 0.1 s (Eq. 6) blended by the rods'
//!   sensitivity sigma(Y) = 0.04 / (0.04 + Y) (§2.3, Eq. 7) as tau = sigma tau_rod +
//!   (1 - sigma) tau_cone (§3.2, Eq. 12), T = the frame time in the window, converged
//!   L_a = L_avg for headless renders; the key a = 1.03 - 2 / (2 + log10(L_a + 1)) (§3.1,
//!   Eq. 11) or the scene's; L_white (the scene's or the largest scaled luminance, at least 1).
//!   Krawczyk's full text is not in ../shared: the formulas were checked against the issue
//!   and a public implementation that cites these section and equation numbers. Which Y
//!   Eq. 12 takes is our choice: the adapted luminance of the previous frame (the state of
//!   the eye whose receptors set the speed), not the new frame's average;
//! - `tonemap` (glsl/tonemap/adaptive.frag): L = exposure * a / L_a * L_w (Reinhard et al.
//!   2002, Eq. 2), L_d = L (1 + L / L_white^2) / (1 + L) (Eq. 4), colour scaled by L_d / L_w,
//!   then the sRGB OETF.
//!
//! No CPU readback is in the loop: the state lives in a 2x1 image on the device; the host
//! only reads the statistics for display after a frame's fence.
//!
//! Not implemented from Krawczyk et al. 2005: the local operator (dodging and burning on a
//! Gaussian pyramid; this is the global curve), glare, the loss of colour in scotopic and
//! mesopic vision, and the loss of visual acuity. [`crate::app::output::tonemap_adaptive`] is
//! the same operator on the CPU (compare, report, reference PNGs).

use crate::gpu::{vk, Access, Buffer, ComputePipeline, GpuResult, Image, ImageDesc, MemoryLocation};
use crate::graph::{Bindings, BoundSet, BufferId, Frame, ImageId};
use crate::scene::techniques::TonemapAdaptiveParams;
use crate::scene::Scene;
use crate::technique::{
    in_stage, params, tables, FrameInputs, Inputs, PlannedPass, Registration, RenderError, Setup, Stage, Technique,
};
use crate::{
    BINDING_HDR, BINDING_TONEMAP_STATE, TONEMAP_BINDING_HDR, TONEMAP_BINDING_PARTIALS, TONEMAP_BINDING_STATE,
    TONEMAP_BINDING_STATS, TONEMAP_BLOCK, TONEMAP_GROUP,
};

use super::fullscreen::{fragment_set, FullscreenDesc, FullscreenPass};
use crate::shader_structs::AdaptPush;

pub const TONEMAP: &str = "tonemap";
/// The adaptive tone map (`render.tonemap = "adaptive"`): the log-average luminance by a
/// reduction on the GPU, then the adaptation state.
pub const TONEMAP_LOG_AVERAGE: &str = "tonemap_log_average";
pub const TONEMAP_ADAPT: &str = "tonemap_adapt";

/// Baseline: every frame ends in the tone map, `render.tonemap = "clamp"` or `"adaptive"`
/// (parameters `[render.tonemap_adaptive]`).
pub const TECHNIQUE: Registration = Registration {
    key: TONEMAP,
    plan,
    create,
    // The adaptive tone map starts from the exposure; the clamp reads it from the uniforms.
    inputs: |scene| match scene.render.tonemap.as_str() {
        "adaptive" => Inputs::settings(format!("{} {}", scene.render.exposure, tables(scene, &["tonemap_adaptive"]))),
        _ => Inputs::default(),
    },
};

fn plan(scene: &Scene) -> Vec<(Stage, PlannedPass)> {
    let passes = if scene.render.tonemap == "adaptive" {
        vec![
            PlannedPass::new(
                TONEMAP_LOG_AVERAGE,
                "log-average luminance of the HDR image, reduced on the GPU (render.tonemap = \"adaptive\")",
            ),
            PlannedPass::new(
                TONEMAP_ADAPT,
                "adapted luminance, key and L_white (Krawczyk et al. 2005, Ihrke et al. 2007 §5.3)",
            ),
            PlannedPass::new(TONEMAP, "linear radiance -> sRGB: Reinhard's operator on the adapted luminance"),
        ]
    } else {
        vec![PlannedPass::new(TONEMAP, "linear radiance -> sRGB PNG output")]
    };
    in_stage(Stage::Tonemap, passes)
}

fn create(s: &mut Setup<'_>) -> Result<Box<dyn Technique>, RenderError> {
    let adaptive = if s.planned(TONEMAP_ADAPT) {
        let p = params("tonemap_adaptive", TonemapAdaptiveParams::from_settings(&s.scene.render))?;
        Some((p, s.scene.render.exposure))
    } else {
        None
    };
    Ok(Box::new(TonemapPass::new(s, adaptive)?))
}

impl Technique for TonemapPass {
    /// Record the tone map (and with the adaptive one its reduction) into `frame`. `slot`:
    /// the frame-in-flight slot (the statistics entry); `dt`: seconds since the last frame
    /// for temporal adaptation, `None` for the converged state (headless renders).
    fn record<'a>(&'a self, _: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        let (targets, frame_set, slot, dt) = (inputs.targets, inputs.frame_set, inputs.slot, inputs.dt);
        let Some(a) = &self.adaptive else {
            self.pass.record(frame, frame_set, &[]);
            return;
        };
        let p = &a.params;
        let push = AdaptPush {
            size: [targets.width, targets.height, a.groups[0] * a.groups[1], slot as u32],
            params: [dt.map_or(-1.0, |t| t.max(0.0)), p.delta, p.key.unwrap_or(0.0), p.white.unwrap_or(0.0)],
            params2: [p.tau_rod, p.tau_cone, p.luminance_scale, a.exposure],
        };
        let (set, pipeline, groups) = (a.set.set(), &a.log_average, a.groups);
        frame
            .pass(TONEMAP_LOG_AVERAGE)
            .read(targets.hdr_id, Access::ComputeSampled)
            .write(a.partials_id, Access::ComputeWrite)
            .record(move |cmd| {
                cmd.compute(pipeline, &[set], &push, [groups[0], groups[1], 1]);
            });
        let pipeline = &a.adapt;
        frame
            .pass(TONEMAP_ADAPT)
            .read(a.partials_id, Access::ComputeRead)
            .write(a.state_id, Access::ComputeWrite)
            .write(a.stats_id, Access::ComputeWrite)
            .record(move |cmd| {
                cmd.compute(pipeline, &[set], &push, [1, 1, 1]);
            });
        self.pass.record(frame, frame_set, &[]);
    }
}

/// What the adaptive tone map derived for one frame (read back for display and tests).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AdaptiveStats {
    /// The log-average luminance of the frame, cd/m^2.
    pub l_avg: f32,
    /// The adapted luminance (= l_avg when converged), cd/m^2.
    pub l_adapted: f32,
    /// The key a.
    pub key: f32,
    /// L_white, in units of the scaled luminance.
    pub white: f32,
}

/// The reduction kernels, their buffers and the state image of the adaptive tone map.
struct Adaptive {
    params: TonemapAdaptiveParams,
    exposure: f32,
    groups: [u32; 2],
    set: BoundSet,
    log_average: ComputePipeline,
    adapt: ComputePipeline,
    _partials: Buffer,
    partials_id: BufferId,
    state_id: ImageId,
    /// One (L_avg, L_a, a, L_white) per frame slot, host-visible.
    stats: Buffer,
    stats_id: BufferId,
    // Declared last: the descriptor set and the fragment pass refer to it.
    _state: Image,
}

pub struct TonemapPass {
    pass: FullscreenPass,
    adaptive: Option<Adaptive>,
}

impl TonemapPass {
    /// The clamp tone map, or with `adaptive = Some((params, exposure))` the adaptive one
    /// with its reduction (one statistics entry per frame in flight).
    pub fn new(s: &mut Setup<'_>, adaptive: Option<(TonemapAdaptiveParams, f32)>) -> GpuResult<Self> {
        let (ctx, frame_layout, targets, nearest, slots) = (s.ctx, s.frame_layout, s.targets, s.nearest, s.slots);
        let graph = &mut *s.graph;
        let desc = |fragment_shader| FullscreenDesc {
            name: TONEMAP,
            fragment_shader,
            target: (&targets.ldr, targets.ldr_id),
            clear: true,
            specialization: &[],
            additive: false,
        };
        let hdr = fragment_set().sampled(BINDING_HDR, &targets.hdr, nearest).read(targets.hdr_id);
        let Some((params, exposure)) = adaptive else {
            let pass = FullscreenPass::new(ctx, &desc("tonemap/tonemap.frag"), hdr, frame_layout)?;
            return Ok(TonemapPass { pass, adaptive: None });
        };
        use vk::ImageUsageFlags as U;
        let (state, state_id) = graph.image(
            ctx,
            &ImageDesc::d2("tonemap_state", vk::Format::R32G32B32A32_SFLOAT, 2, 1, U::STORAGE | U::SAMPLED),
        )?;
        let tile = TONEMAP_GROUP * TONEMAP_BLOCK;
        let groups = [targets.width.div_ceil(tile), targets.height.div_ceil(tile)];
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let partials = Buffer::new(
            ctx,
            "tonemap_partials",
            8 * groups[0] as u64 * groups[1] as u64,
            storage,
            MemoryLocation::GpuOnly,
        )?;
        let stats = Buffer::new(ctx, "tonemap_stats", 16 * slots.max(1) as u64, storage, MemoryLocation::GpuToCpu)?;
        let (partials_id, stats_id) = (graph.register_buffer(&partials), graph.register_buffer(&stats));
        // One set for both kernels; each pass declares the accesses of its own kernel.
        let set = Bindings::new(vk::ShaderStageFlags::COMPUTE)
            .sampled(TONEMAP_BINDING_HDR, &targets.hdr, nearest)
            .storage(TONEMAP_BINDING_PARTIALS, &partials)
            .storage_image(TONEMAP_BINDING_STATE, &state)
            .storage(TONEMAP_BINDING_STATS, &stats)
            .build(ctx, "tonemap_reduce")?;
        let push = std::mem::size_of::<AdaptPush>() as u32;
        let sets = [set.layout()];
        let log_average = ComputePipeline::new(ctx, TONEMAP_LOG_AVERAGE, "tonemap/log_average.comp", &sets, push, &[])?;
        let adapt = ComputePipeline::new(ctx, TONEMAP_ADAPT, "tonemap/adapt.comp", &sets, push, &[])?;
        // The host reads this frame's statistics after its fence: the pass makes them visible.
        let inputs =
            hdr.sampled(BINDING_TONEMAP_STATE, &state, nearest).read(state_id).access(stats_id, Access::HostRead);
        let pass = FullscreenPass::new(ctx, &desc("tonemap/adaptive.frag"), inputs, frame_layout)?;
        Ok(TonemapPass {
            pass,
            adaptive: Some(Adaptive {
                params,
                exposure,
                groups,
                set,
                log_average,
                adapt,
                _partials: partials,
                partials_id,
                state_id,
                stats,
                stats_id,
                _state: state,
            }),
        })
    }

    /// The statistics frame slot `slot` wrote (call after the slot's fence); `None` with the
    /// clamp tone map.
    pub fn stats(&self, slot: usize) -> Option<AdaptiveStats> {
        let a = self.adaptive.as_ref()?;
        let v: &[[f32; 4]] = bytemuck::cast_slice(a.stats.read());
        let [l_avg, l_adapted, key, white] = *v.get(slot)?;
        Some(AdaptiveStats { l_avg, l_adapted, key, white })
    }
}
