//! Equal-time comparison with exact ray tracing: is an approximation worth it against the
//! exact tracer given the same GPU time?
//!
//! The exact tracer's own time/error curve is measured in the same run as the techniques:
//!
//! - the `raytrace` technique (docs/raytrace.md) for refraction and reflection. It traces one
//!   centre ray per pixel with deterministic splitting, so more samples per pixel would give
//!   the same image: its cost knob is `max_depth`, the specular interactions per branch, and
//!   its curve runs over `--exact-depths`;
//! - the `raytrace` technique with its caustics (refraction, reflection and caustics traced)
//!   where the setting renders caustics: its cost knob is the photon budget, its curve runs
//!   over `--exact-photons` ([`photon_frames`]: one frame, or the mean of frames above 4
//!   photons per pixel);
//! - the reference itself (src/reference) at increasing samples per pixel where the setting
//!   renders a graded-index volume, which `raytrace` draws with a stochastic choice at its
//!   boundary ([`source_for`]), or with `--exact-source reference`. Its time is the
//!   wall-clock time of its iterations alone (setup excluded; each submission waits on its
//!   fence), which on lavapipe is the same CPU time the GPU timestamps measure.
//!
//! The exact points are timed interleaved with the settings, in one run
//! ([`measure_interleaved`], the round-robin of `prism bench --versus`,
//! [`super::bench_versus::Interleave`]): every setting's renderer, every `raytrace` point's
//! and the reference's tracer are created first and kept alive together; then each round
//! renders one frame of every participant due in it, waiting for each, the first participant
//! rotating. The settings render every round (`--warmup` + `--frames`); a `raytrace` point's
//! warm-up and `--exact-frames` frames, or the reference's iterations, are spread evenly over
//! the same rounds, the last in the last round. A change of load on a shared machine then
//! weighs on both sides of a verdict alike. Only the timing schedule is shared: each image is
//! its participant's last frame, as when it is rendered alone, so the errors are unchanged.
//! The price is memory: all of a sweep's renderers exist at once.
//!
//! Every error carries the reference's own noise (a second reference with another seed):
//! see [`Noise`]. A setting is *dominated* when even its lowest error allowed by that noise
//! is above the exact tracer's error at the same time, *beats exact* in the mirror case, and
//! *within noise* otherwise: such differences are flagged, never ranked.
use std::sync::Arc;

use anyhow::{bail, Context, Result};
use clap::Args;

use crate::gpu::GpuContext;
use crate::metrics::image::ErrorMetrics;
use crate::reference::{Reference, ReferenceSettings};
use crate::scene::Scene;

use super::bench_versus::Interleave;
use super::compare::{cached_reference, MeasureArgs, Measurement, ReferencePolicy, Timing};
use super::output;
use super::SceneArgs;

#[derive(Args, Debug, Clone)]
pub struct ExactArgs {
    /// `max_depth` values of the `raytrace` technique for the exact tracer's time/error curve
    /// of settings that render no caustics and no volume.
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,16")]
    pub exact_depths: Vec<u32>,
    /// Photon budgets of the `raytrace` points (refraction, reflection and caustics traced)
    /// that make the exact curve of settings rendering caustics without a volume: one frame
    /// of that many photons, or, above 4 photons per pixel, the mean of as many frames of at
    /// most 4 per pixel as the budget needs, timed as their sum (src/app/equaltime.rs,
    /// `photon_frames`).
    #[arg(long, value_delimiter = ',', default_value = "4096,16384,65536,262144")]
    pub exact_photons: Vec<u64>,
    /// Samples per pixel of the reference's curve: the exact curve of settings that render a
    /// graded-index volume (which `raytrace` draws with a stochastic choice at its boundary),
    /// or of every setting with `--exact-source reference`.
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8")]
    pub exact_spp: Vec<u32>,
    /// Which exact tracer draws the curve: `auto` (`raytrace` over `--exact-depths` without
    /// caustics, over `--exact-photons` with them, the reference with a volume) or
    /// `reference` (the reference over `--exact-spp` for every setting).
    #[arg(long, value_enum, default_value_t = ExactChoice::Auto)]
    pub exact_source: ExactChoice,
    /// Frames timed per point of the exact curve (after one warm-up frame). A raytraced
    /// frame costs seconds on lavapipe, where the spread between frames is a few percent.
    #[arg(long, default_value_t = 3)]
    pub exact_frames: u32,
    /// Measure no exact curve and no reference noise (no equal-time verdicts).
    #[arg(long)]
    pub no_exact: bool,
}

impl ExactArgs {
    /// The flags whose values differ from their defaults, as they would be typed, each with
    /// a leading space: what a report section's provenance line must add to its command for
    /// the section to be measured again as it was (" --exact-spp 1").
    pub fn changed_flags(&self) -> String {
        #[derive(clap::Parser)]
        struct Defaults {
            #[command(flatten)]
            exact: ExactArgs,
        }
        let d = <Defaults as clap::Parser>::parse_from(["prism"]).exact;
        fn list<T: ToString>(v: &[T]) -> String {
            v.iter().map(ToString::to_string).collect::<Vec<_>>().join(",")
        }
        let mut flags = String::new();
        if self.no_exact {
            flags += " --no-exact";
        }
        if self.exact_source != d.exact_source {
            flags += " --exact-source reference";
        }
        if self.exact_depths != d.exact_depths {
            flags += &format!(" --exact-depths {}", list(&self.exact_depths));
        }
        if self.exact_photons != d.exact_photons {
            flags += &format!(" --exact-photons {}", list(&self.exact_photons));
        }
        if self.exact_spp != d.exact_spp {
            flags += &format!(" --exact-spp {}", list(&self.exact_spp));
        }
        if self.exact_frames != d.exact_frames {
            flags += &format!(" --exact-frames {}", self.exact_frames);
        }
        flags
    }
}

/// `--exact-source`: the exact tracer chosen from the settings, or the reference forced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ExactChoice {
    /// [`source_for_all`].
    Auto,
    /// The reference over `--exact-spp`.
    Reference,
}

/// Which exact tracer a curve measures, in the order [`source_for_all`] escalates: a later
/// one renders everything an earlier one does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ExactSource {
    /// The `raytrace` technique at increasing `max_depth`, photons off.
    Raytrace,
    /// The `raytrace` technique with its caustics (refraction, reflection and caustics
    /// traced, default `max_depth`) at increasing photons per frame.
    RaytracePhotons,
    /// The reference at increasing samples per pixel (the setting renders a graded-index
    /// volume, or `--exact-source reference`).
    Reference,
}

impl ExactSource {
    /// Its name in the CSV's rows and on the plot.
    pub fn name(self) -> &'static str {
        match self {
            ExactSource::Raytrace => "raytrace",
            ExactSource::RaytracePhotons => "raytrace_photons",
            ExactSource::Reference => "reference",
        }
    }

    pub fn describe(self) -> &'static str {
        match self {
            ExactSource::Raytrace => "raytrace (exact, deterministic splitting) at increasing max_depth",
            ExactSource::RaytracePhotons => {
                "raytrace with its caustics (refraction, reflection and caustics traced, photons \
                 gathered within half a pixel's footprint) at increasing photon budgets, one frame each up \
                 to 4 photons per pixel, the mean of frames beyond"
            }
            ExactSource::Reference => "the reference at increasing samples per pixel",
        }
    }
}

/// One measured point of the exact tracer.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ExactPoint {
    pub label: String,
    pub time_ms: f64,
    pub errors: ErrorMetrics,
    /// The errors over the object mask (src/metrics/mask.rs), the same pixels as the
    /// settings'; `None` when no masked surface is in view.
    pub errors_mask: Option<ErrorMetrics>,
    /// When each timed frame of a `raytrace` point started on the device's clock, ms, as
    /// [`Measurement::frame_starts_ms`] (none for the reference, timed on the host).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub frame_starts_ms: Vec<f64>,
    /// A `raytrace` point with photons: its photons per frame and gather radius (pixel
    /// footprints).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub photons: Option<PhotonBudget>,
}

/// The photon budget of one point of a [`ExactSource::RaytracePhotons`] curve: `frames`
/// frames of `photons_per_frame` photons, averaged (`render.raytrace.accumulate`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct PhotonBudget {
    pub photons: u64,
    pub photons_per_frame: u32,
    pub frames: u32,
}

impl PhotonBudget {
    pub fn label(&self) -> String {
        if self.frames == 1 {
            format!("{} photons", self.photons)
        } else {
            format!("{} photons ({} frames of {})", self.photons, self.frames, self.photons_per_frame)
        }
    }
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct ExactCurve {
    pub source: ExactSource,
    pub points: Vec<ExactPoint>,
}

impl ExactCurve {
    /// The tracer and its points' budgets, for the report text and the commands' output:
    /// "raytrace with its caustics ... per frame: 4096 photons/frame r=1.00, ...".
    pub fn describe(&self) -> String {
        let labels: Vec<&str> = self.points.iter().map(|p| p.label.as_str()).collect();
        format!("{}: {}", self.source.describe(), labels.join(", "))
    }
}

/// The reference's own noise: the metrics of a second reference (another seed, same samples)
/// against the first. For MSE-like errors the expectation is additive: a technique image T,
/// independent of the reference R = mu + noise of variance s^2 per channel, has
/// E[MSE(T, R)] = MSE(T, mu) + s^2, and two references differ by MSE(R1, R2) = 2 s^2. So the
/// reference's noise RMSE is s = RMSE(R1, R2) / sqrt(2), and since sqrt(m + s^2) <= sqrt(m) + s,
/// a measured RMSE e stands for a true one in [e - s, e]. relMSE behaves like MSE (floor
/// relMSE(R1, R2) / 2). FLIP and HDR-FLIP are not additive; the same rule as RMSE is applied
/// to them as an estimate of how far the reference's noise moves them.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Noise {
    pub between_references: ErrorMetrics,
}

impl Noise {
    /// The part of a measured `metric` that the reference's noise may account for.
    pub fn floor(&self, metric: &str) -> f64 {
        let b = &self.between_references;
        match metric {
            "rmse" => b.rmse / std::f64::consts::SQRT_2,
            "rel_mse" => b.rel_mse / 2.0,
            "flip_mean" => b.flip_mean / std::f64::consts::SQRT_2,
            "flip_p95" => b.flip_p95 / std::f64::consts::SQRT_2,
            "hdr_flip_mean" => b.hdr_flip_mean / std::f64::consts::SQRT_2,
            "hdr_flip_p95" => b.hdr_flip_p95 / std::f64::consts::SQRT_2,
            _ => 0.0,
        }
    }

    /// The interval of the true error for a measured `value` of `metric`: [value - floor, value].
    pub fn interval(&self, metric: &str, value: f64) -> (f64, f64) {
        ((value - self.floor(metric)).max(0.0), value)
    }
}

/// The reference's noise for `scene`: a second reference with the next seed (cached like the
/// first), compared with `reference`.
pub fn reference_noise(
    ctx: &Arc<GpuContext>,
    scene: &Scene,
    settings: &ReferenceSettings,
    reference: &[f32],
    policy: ReferencePolicy,
) -> Result<Noise> {
    let other = second_reference(ctx, scene, settings, policy)?;
    let (a, b) = (output::tonemap_scene(&other, &scene.render), output::tonemap_scene(reference, &scene.render));
    let (m, _) = ErrorMetrics::between(&other, reference, &a, &b, scene.camera.width, scene.camera.height);
    Ok(Noise { between_references: m })
}

/// The second reference of [`reference_noise`] (the next seed; cached like the first, so a
/// second call loads it): src/metrics/paired.rs ranks settings with it.
pub fn second_reference(
    ctx: &Arc<GpuContext>,
    scene: &Scene,
    settings: &ReferenceSettings,
    policy: ReferencePolicy,
) -> Result<Vec<f32>> {
    let second = ReferenceSettings { seed: settings.seed.wrapping_add(1), ..settings.clone() };
    Ok(cached_reference(ctx, scene, &second, policy)?.image)
}

/// The exact tracer of one setting: `raytrace` with its photons off where it renders no
/// caustics and no graded-index volume; `raytrace` with its caustics where it renders
/// caustics but no volume (photons gathered within a disk of half a pixel's footprint, the
/// caustic's pixel average as the budget grows: [`photon_frames`]); the reference where it renders a `[volume]`. `raytrace` traces
/// the pixels the G-buffer gives to specular objects, and a `[volume]` is drawn over pixels
/// that are not (with its caustic on the floor); `render.volume = "raytrace"` traces them, but
/// makes the reference's stochastic Fresnel choice at the volume's boundary, so its curve over
/// its budget is not its error curve: the reference's over samples is.
pub fn source_for(scene: &Scene) -> ExactSource {
    if scene.volume.is_some() {
        ExactSource::Reference
    } else if scene.render.caustics != "none" {
        ExactSource::RaytracePhotons
    } else {
        ExactSource::Raytrace
    }
}

/// The exact points, loaded and checked before any GPU work: the `raytrace` scenes, one per
/// `--exact-depths` or `--exact-photons` value, or the reference's settings and its stops.
pub struct CurveSpec {
    source: ExactSource,
    /// (label, scene, photon budget) of each `raytrace` point.
    raytrace: Vec<(String, Scene, Option<PhotonBudget>)>,
    /// The scene the reference traces, its settings (every stop's photons) and its stops in
    /// samples per pixel, ascending.
    reference: Option<(Scene, ReferenceSettings, Vec<u32>)>,
    frames: u32,
}

/// The source of one exact curve for every setting of `settings` (a sweep's, a report
/// entry's): the first in [`ExactSource`]'s order that renders what each of them does, since
/// the curve is drawn against each setting (a sweep from `caustics = none` to `caustics_map`
/// must be weighed against an exact image with the caustic).
pub fn source_for_all<'a>(settings: impl IntoIterator<Item = &'a Scene>) -> ExactSource {
    settings.into_iter().map(source_for).max().unwrap_or(ExactSource::Raytrace)
}

/// Photons per pixel a frame of the exact curve traces at most. Under caustic_sphere's
/// focus a pixel's gather walks the photons within its disk, and above this lavapipe's loop
/// limit (docs/raytrace.md) cuts the walk: one frame of 16 photons per pixel gave RMSE 0.187
/// at 128^2 against 0.120 for 4, and 64 per pixel 0.720 (the focus dark), at 256^2 in 12.7 s
/// a frame instead of 1.1 s for 4 per pixel.
pub const MAX_PHOTONS_PER_PIXEL: u64 = 4;

/// How an exact point spends `photons` on a `width` x `height` image: one frame while that
/// is at most [`MAX_PHOTONS_PER_PIXEL`] photons per pixel, else the mean of the fewest
/// frames of at most that many (`render.raytrace.accumulate`), each of `photons / frames`
/// rounded up, timed as the sum of the frames.
///
/// One frame rather than the mean of frames wherever it fits: the same photons give the same
/// caustic noise (1/sqrt of their number) either way, and every frame pays the camera's rays
/// again. On caustic_sphere (`prism sweep`, lavapipe, 64-spp 8M-photon reference), 128^2:
/// 65 536 photons in one frame 224 to 372 ms (two runs), RMSE 0.120 to 0.130, FLIP 0.033;
/// 4 frames of 16 384, 4 x 123 to 183 ms, RMSE 0.125, FLIP 0.033; 16 frames of 4096,
/// 16 x 143 ms, RMSE 0.114, FLIP 0.032. 256^2: 262 144 in one frame 1111 ms, RMSE 0.137,
/// FLIP 0.032; 4 frames of 65 536, 4 x 425 ms, RMSE 0.135, FLIP 0.032.
///
/// The gathering disk stays `raytrace`'s default, half a pixel's footprint, at every budget,
/// so that the points converge as the budget grows to the caustic's average over each
/// pixel's inscribed disk (a consistent estimate of the pixel's average the reference
/// converges to). A wider disk for fewer photons, as the reference's SPPM shrinks its radius
/// (r ~ N^(-1/6)), was measured at 128^2 and not kept: radii of 0.5, 1 and 2 footprints gave
/// RMSE 0.191, 0.207, 0.267 at 4096 photons and 0.120, 0.193, 0.258 at 65 536 (the focus
/// blurred), FLIP 0.0463, 0.0464, 0.0482 and 0.0332, 0.0308, 0.0323.
pub fn photon_frames(photons: u64, width: u32, height: u32) -> PhotonBudget {
    // At most the photons a frame holds (`photons_per_frame`'s range) on a large image.
    let cap = (MAX_PHOTONS_PER_PIXEL * u64::from(width) * u64::from(height)).clamp(1, 1 << 20);
    let frames = photons.div_ceil(cap).max(1);
    let per_frame = photons.div_ceil(frames);
    PhotonBudget {
        photons: per_frame * frames,
        photons_per_frame: u32::try_from(per_frame).unwrap_or(u32::MAX),
        frames: u32::try_from(frames).unwrap_or(u32::MAX),
    }
}

/// The exact curve of the scene that `scene_args` loads (the same scene as the techniques,
/// with `raytrace` selected for refraction and reflection, and caustics where they are
/// rendered, or the reference), drawn for the `settings` it is compared with
/// ([`source_for_all`], or `--exact-source`).
pub fn curve_spec<'a>(
    scene_args: &SceneArgs,
    measure_args: &MeasureArgs,
    exact: &ExactArgs,
    settings: impl IntoIterator<Item = &'a Scene>,
) -> Result<CurveSpec> {
    let base = scene_args.load()?;
    let source = match exact.exact_source {
        ExactChoice::Reference => ExactSource::Reference,
        ExactChoice::Auto => source_for(&base).max(source_for_all(settings)),
    };
    let mut spec = CurveSpec { source, raytrace: Vec::new(), reference: None, frames: exact.exact_frames.max(1) };
    let raytrace = |set: &[String], what: &str| {
        let mut sa = scene_args.clone();
        sa.set.extend(["render.refraction=raytrace".to_string(), "render.reflection=raytrace".to_string()]);
        sa.set.extend_from_slice(set);
        sa.load().with_context(|| format!("exact curve, raytrace {what}"))
    };
    match source {
        ExactSource::Raytrace => {
            if exact.exact_depths.is_empty() {
                bail!("--exact-depths: no values");
            }
            for &d in &exact.exact_depths {
                // The settings render no caustics: neither does their exact counterpart.
                let set = [format!("render.raytrace.max_depth={d}"), "render.raytrace.photons_per_frame=0".to_string()];
                let scene = raytrace(&set, &format!("max_depth={d}"))?;
                spec.raytrace.push((format!("max_depth={d}"), scene, None));
            }
        }
        ExactSource::RaytracePhotons => {
            let mut budgets: Vec<u64> = exact.exact_photons.iter().copied().filter(|&p| p > 0).collect();
            budgets.sort_unstable();
            budgets.dedup();
            if budgets.is_empty() {
                bail!("--exact-photons: no positive values");
            }
            for p in budgets {
                let b = photon_frames(p, base.camera.width, base.camera.height);
                // The caustics on the diffuse surfaces seen directly too, so that the whole
                // frame is traced; the image scored is the mean of the budget's frames
                // (`Timing` keeps a named `accumulate`, src/app/compare.rs).
                let set = [
                    "render.caustics=raytrace".to_string(),
                    format!("render.raytrace.photons_per_frame={}", b.photons_per_frame),
                    format!("render.raytrace.accumulate={}", b.frames),
                ];
                let scene = raytrace(&set, &format!("{p} photons"))?;
                spec.raytrace.push((b.label(), scene, Some(b)));
            }
        }
        ExactSource::Reference => {
            let mut spp: Vec<u32> = exact.exact_spp.iter().copied().filter(|&s| s > 0).collect();
            spp.sort_unstable();
            spp.dedup();
            let Some(&max) = spp.last() else { bail!("--exact-spp: no positive values") };
            let settings = measure_args.reference.settings();
            // The reference's photons per iteration, so that each point is the reference
            // stopped early; a seed of its own keeps it independent of both references.
            let per_iteration = settings.photons / u64::from(settings.spp.max(1));
            let s = ReferenceSettings {
                spp: max,
                photons: per_iteration * u64::from(max),
                seed: settings.seed.wrapping_add(2),
                ..settings
            };
            spec.reference = Some((base, s, spp));
        }
    }
    Ok(spec)
}

/// A setting of an interleaved run: its scene, timed over `warmup` + `frames` frames, and the
/// reference it is compared with.
pub struct Setting<'a> {
    pub scene: &'a Scene,
    pub reference: &'a [f32],
}

/// The reference stopped at increasing samples per pixel: one iteration per step, timed
/// alone (its setup excluded; each iteration waits on its fence), the errors taken at each
/// stop.
struct ReferenceCurve<'a> {
    tracer: Reference,
    scene: &'a Scene,
    stops: &'a [u32],
    reference: &'a [f32],
    /// The reference tone-mapped and the object mask, for the errors at each stop.
    ref_ldr: Vec<u8>,
    mask: crate::metrics::mask::ObjectMask,
    elapsed_ms: f64,
    points: Vec<ExactPoint>,
}

impl ReferenceCurve<'_> {
    fn step(&mut self) -> Result<()> {
        let t = std::time::Instant::now();
        self.tracer.run(1)?;
        self.elapsed_ms += t.elapsed().as_secs_f64() * 1e3;
        let n = self.tracer.iterations_done();
        if self.stops.contains(&n) {
            let (base, reference) = (self.scene, self.reference);
            let img = self.tracer.image();
            let ldr = output::tonemap_scene(&img, &base.render);
            let (w, h, mask) = (base.camera.width, base.camera.height, Some(&self.mask.pixels[..]));
            let (errors, errors_mask, _) =
                ErrorMetrics::between_with_mask(&img, reference, &ldr, &self.ref_ldr, w, h, mask);
            eprintln!("exact: reference {n} spp");
            let (label, time_ms) = (format!("{n} spp"), self.elapsed_ms);
            self.points.push(ExactPoint {
                label,
                time_ms,
                errors,
                errors_mask,
                frame_starts_ms: Vec::new(),
                photons: None,
            });
        }
        Ok(())
    }
}

/// One participant of an interleaved run. Boxed: a renderer and a tracer are a few kilobytes each, moved once into the list.
enum Part<'a> {
    Setting(Box<Timing<'a>>),
    Reference(Box<ReferenceCurve<'a>>),
}

/// Time `settings` (each over `measure_args`' warm-up and frames) and, with `exact`, the exact
/// tracer's points (against the reference given with them, the first setting's) in one run,
/// their frames interleaved ([`Interleave`]): every renderer and the reference's tracer are
/// created first, all alive at once, then each round renders one frame of each participant
/// due in it (a `raytrace` point's warm-up frame and `--exact-frames` frames, or one of the
/// reference's iterations, spread evenly over the settings' rounds), each frame waited for.
/// A change of the machine's load then weighs on the settings and the exact points alike.
/// The images and errors are those of each participant's last frame, as when timed alone.
pub fn measure_interleaved(
    ctx: &Arc<GpuContext>,
    settings: &[Setting<'_>],
    measure_args: &MeasureArgs,
    exact: Option<(&CurveSpec, &[f32])>,
) -> Result<(Vec<Measurement>, Option<ExactCurve>)> {
    let mut parts = Vec::new();
    for s in settings {
        parts.push(Part::Setting(Box::new(Timing::new(
            ctx,
            s.scene,
            measure_args.warmup,
            measure_args.frames,
            s.reference,
        )?)));
    }
    if let Some((spec, reference)) = exact {
        for (_, scene, photons) in &spec.raytrace {
            // A point that averages N frames renders at least N (the warm-up among them), so
            // that its image is their mean.
            let accumulated = photons.map_or(1, |b| b.frames);
            let frames = spec.frames.max(accumulated.saturating_sub(1));
            parts.push(Part::Setting(Box::new(Timing::new(ctx, scene, 1, frames, reference)?)));
        }
        if let Some((scene, s, stops)) = &spec.reference {
            let tracer = Reference::new(ctx, scene, s).context("exact curve: cannot set up the reference")?;
            let (ref_ldr, mask) =
                (output::tonemap_scene(reference, &scene.render), crate::metrics::mask::ObjectMask::of_scene(scene));
            let curve =
                ReferenceCurve { tracer, scene, stops, reference, ref_ldr, mask, elapsed_ms: 0.0, points: Vec::new() };
            parts.push(Part::Reference(Box::new(curve)));
        }
    }
    let frames = parts
        .iter()
        .map(|p| match p {
            Part::Setting(t) => t.frames(),
            Part::Reference(r) => u64::from(r.stops.last().copied().unwrap_or(0)),
        })
        .collect();
    let schedule = Interleave::new(frames);
    eprintln!(
        "timing {} setting(s) and {} exact-curve participant(s) interleaved over {} rounds",
        settings.len(),
        parts.len() - settings.len(),
        schedule.order().count()
    );
    for order in schedule.order() {
        for i in order {
            match &mut parts[i] {
                Part::Setting(t) => t.step()?,
                Part::Reference(r) => r.step()?,
            }
        }
    }
    let mut measured = Vec::new();
    let mut points = Vec::new();
    for (i, p) in parts.into_iter().enumerate() {
        match p {
            Part::Setting(t) if i < settings.len() => measured.push(t.finish()?),
            Part::Setting(t) => {
                let m = t.finish()?;
                let (label, photons) = exact
                    .map(|(spec, _)| {
                        let (label, _, photons) = &spec.raytrace[i - settings.len()];
                        (label.clone(), *photons)
                    })
                    .unwrap_or_default();
                // An averaged point's time is the sum of its frames.
                let frames = photons.map_or(1, |b| b.frames);
                points.push(ExactPoint {
                    label,
                    time_ms: m.frame.median_ms * f64::from(frames),
                    errors: m.errors,
                    errors_mask: m.mask.errors_mask,
                    frame_starts_ms: m.frame_starts_ms,
                    photons,
                });
            }
            Part::Reference(r) => points.extend(r.points),
        }
    }
    let curve = exact.map(|(spec, _)| ExactCurve { source: spec.source, points });
    Ok((measured, curve))
}

/// The exact tracer's error at a time, interpolated on its curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtTime {
    /// The measured error (against the reference) the exact tracer reaches in that time.
    pub error: f64,
    /// Beyond the curve's slowest point: its error, which more time can only lower.
    pub beyond: bool,
}

impl ExactCurve {
    /// The points that no other point beats in both time and `metric` (what the exact tracer
    /// can reach within a budget: it may always choose a cheaper setting), sorted by time.
    pub fn front(&self, metric: &str) -> Vec<(f64, f64)> {
        let pts: Vec<(f64, f64)> =
            self.points.iter().map(|p| (p.time_ms, metric_value(&p.errors, metric).unwrap_or(f64::NAN))).collect();
        let mut f: Vec<(f64, f64)> = super::sweep::pareto_front(&pts).into_iter().map(|i| pts[i]).collect();
        f.sort_by(|a, b| a.0.total_cmp(&b.0));
        f.dedup_by(|a, b| a.0 == b.0);
        f
    }

    /// The exact tracer's `metric` at `time_ms`; `None` when even its cheapest point is slower.
    /// Between two points of the front the interpolation is linear in log time and log error:
    /// a Monte Carlo error falls as a power of the time spent (RMSE as time^-1/2), and a
    /// power law is a straight line there, so it is interpolated exactly.
    pub fn error_at(&self, metric: &str, time_ms: f64) -> Option<AtTime> {
        let f = self.front(metric);
        let &(t0, _) = f.first()?;
        if time_ms < t0 {
            return None;
        }
        let &(tn, en) = f.last()?;
        if time_ms >= tn {
            return Some(AtTime { error: en, beyond: time_ms > tn });
        }
        let k = f.windows(2).position(|w| time_ms < w[1].0).unwrap_or(0);
        let ((ta, ea), (tb, eb)) = (f[k], f[k + 1]);
        let error = if ea > 0.0 && eb > 0.0 && ta > 0.0 {
            let s = (time_ms.ln() - ta.ln()) / (tb.ln() - ta.ln());
            (ea.ln() + s * (eb.ln() - ea.ln())).exp()
        } else {
            ea + (time_ms - ta) / (tb - ta) * (eb - ea)
        };
        Some(AtTime { error, beyond: false })
    }
}

pub fn metric_value(e: &ErrorMetrics, name: &str) -> Result<f64> {
    Ok(match name {
        "flip_mean" => e.flip_mean,
        "flip_p95" => e.flip_p95,
        "rmse" => e.rmse,
        "rel_mse" => e.rel_mse,
        "hdr_flip_mean" => e.hdr_flip_mean,
        "hdr_flip_p95" => e.hdr_flip_p95,
        other => bail!("--metric {other}: expected flip_mean, flip_p95, rmse, rel_mse, hdr_flip_mean or hdr_flip_p95"),
    })
}

/// A setting against the exact tracer at the same time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Faster than the exact tracer's cheapest point: nothing exact fits in its time.
    Faster,
    /// Even the lowest error the reference's noise allows is above the exact tracer's.
    Dominated,
    /// Its error is below the lowest the exact tracer's could be.
    BeatsExact,
    /// The two differ by less than the reference's noise: not ranked.
    WithinNoise,
}

impl Verdict {
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Faster => "faster than exact",
            Verdict::Dominated => "dominated",
            Verdict::BeatsExact => "beats exact",
            Verdict::WithinNoise => "within noise",
        }
    }
}

/// The equal-time comparison of one setting: the exact tracer's error at its time and the
/// verdict.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EqualTime {
    pub exact: Option<AtTime>,
    pub verdict: Verdict,
}

/// Compare a setting (its time and measured `metric` value) with the exact curve, both
/// errors taken with the reference's noise.
pub fn equal_time(curve: &ExactCurve, noise: &Noise, metric: &str, time_ms: f64, value: f64) -> EqualTime {
    let Some(at) = curve.error_at(metric, time_ms) else {
        return EqualTime { exact: None, verdict: Verdict::Faster };
    };
    let (lo, hi) = noise.interval(metric, value);
    let (xlo, xhi) = noise.interval(metric, at.error);
    let verdict = if lo > xhi {
        Verdict::Dominated
    } else if hi < xlo {
        Verdict::BeatsExact
    } else {
        Verdict::WithinNoise
    };
    EqualTime { exact: Some(at), verdict }
}

/// Everything a command needs to state equal-time verdicts.
pub struct Exact {
    pub curve: ExactCurve,
    pub noise: Noise,
}

impl Exact {
    pub fn equal_time(&self, metric: &str, m: &Measurement) -> Result<EqualTime> {
        Ok(equal_time(&self.curve, &self.noise, metric, m.frame.median_ms, metric_value(&m.errors, metric)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changed_exact_flags_are_the_ones_typed() {
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            exact: ExactArgs,
        }
        let parse = |args: &[&str]| <Cli as clap::Parser>::parse_from(args).exact.changed_flags();
        assert_eq!(parse(&["prism"]), "");
        assert_eq!(parse(&["prism", "--exact-spp", "1,2,4,8"]), "");
        assert_eq!(parse(&["prism", "--exact-spp", "1"]), " --exact-spp 1");
        assert_eq!(
            parse(&["prism", "--exact-depths", "1,16", "--exact-source", "reference"]),
            " --exact-source reference --exact-depths 1,16"
        );
    }

    fn curve(points: &[(f64, f64)]) -> ExactCurve {
        ExactCurve {
            source: ExactSource::Reference,
            points: points
                .iter()
                .map(|&(t, e)| ExactPoint {
                    label: format!("{t}"),
                    time_ms: t,
                    errors: ErrorMetrics { rmse: e, ..Default::default() },
                    errors_mask: None,
                    frame_starts_ms: Vec::new(),
                    photons: None,
                })
                .collect(),
        }
    }

    /// On a power law (Monte Carlo RMSE = c t^-1/2) the interpolation is exact between the
    /// points, clamps beyond the slowest, and has nothing before the cheapest.
    #[test]
    fn interpolation_is_exact_on_a_power_law() {
        let e = |t: f64| 0.8 * t.powf(-0.5);
        let c = curve(&[(10.0, e(10.0)), (20.0, e(20.0)), (80.0, e(80.0)), (160.0, e(160.0))]);
        for t in [10.0, 13.0, 20.0, 47.5, 100.0, 160.0] {
            let at = c.error_at("rmse", t).unwrap();
            assert!((at.error - e(t)).abs() < 1e-12 * e(t).max(1.0), "t={t}: {} vs {}", at.error, e(t));
            assert!(!at.beyond);
        }
        assert_eq!(c.error_at("rmse", 500.0), Some(AtTime { error: e(160.0), beyond: true }));
        assert_eq!(c.error_at("rmse", 9.0), None);
    }

    /// A slower exact point with a larger error is not on the curve: the tracer could spend
    /// less time for less error.
    #[test]
    fn interpolation_follows_the_front() {
        let c = curve(&[(10.0, 0.4), (20.0, 0.1), (40.0, 0.2), (80.0, 0.05)]);
        let at = c.error_at("rmse", 40.0).unwrap().error;
        let expect = (0.1f64.ln() + 0.5 * (0.05f64.ln() - 0.1f64.ln())).exp();
        assert!((at - expect).abs() < 1e-12, "{at} vs {expect}");
    }

    fn load(name: &str, set: &[&str]) -> Scene {
        let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
        crate::scene::load(&crate::scene::benchmark_scene_path(name), &set).unwrap()
    }

    /// The bundled scenes' exact tracer: `raytrace` with its photons off where the setting
    /// renders no caustics and no graded-index volume, with them where it renders caustics,
    /// the reference where it renders a volume.
    #[test]
    fn the_exact_tracer_follows_what_the_setting_renders() {
        assert_eq!(source_for(&load("sphere_env", &[])), ExactSource::Raytrace);
        assert_eq!(source_for(&load("room_mirror", &["render.caustics=none"])), ExactSource::Raytrace);
        for caustics in ["caustics_map", "photon_buffer", "impostor_lightmap", "raytrace"] {
            let scene = load("caustic_sphere", &[&format!("render.caustics={caustics}")]);
            assert_eq!(source_for(&scene), ExactSource::RaytracePhotons, "{caustics}");
        }
        for volume in ["eikonal_sphere", "eikonal_amber_bunny"] {
            assert_eq!(source_for(&load(volume, &["render.caustics=none"])), ExactSource::Reference, "{volume}");
            // A volume's caustic on the floor does not make `raytrace` its exact tracer.
            assert_eq!(source_for(&load(volume, &[])), ExactSource::Reference, "{volume}");
        }
        // A sweep over caustic techniques whose first setting renders none: one curve for
        // all, with the caustic; and a volume among them makes it the reference's.
        let sweep = [
            load("caustic_sphere", &["render.caustics=none"]),
            load("caustic_sphere", &["render.caustics=photon_buffer"]),
        ];
        assert_eq!(source_for_all(&sweep), ExactSource::RaytracePhotons);
        assert_eq!(source_for_all(&sweep[..1]), ExactSource::Raytrace);
        let mixed = [sweep[1].clone(), load("eikonal_sphere", &["render.caustics=none"])];
        assert_eq!(source_for_all(&mixed), ExactSource::Reference);
    }

    fn spec(name: &str, set: &[&str], exact_args: &[&str]) -> CurveSpec {
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            scene: SceneArgs,
            #[command(flatten)]
            measure: MeasureArgs,
            #[command(flatten)]
            exact: ExactArgs,
        }
        use clap::Parser;
        let mut argv = vec!["prism".to_string(), name.to_string()];
        for s in set {
            argv.extend(["--set".to_string(), s.to_string()]);
        }
        argv.extend(exact_args.iter().map(|s| s.to_string()));
        let cli = Cli::try_parse_from(argv).unwrap();
        let scene = cli.scene.load().unwrap();
        curve_spec(&cli.scene, &cli.measure, &cli.exact, [&scene]).unwrap()
    }

    /// A caustic setting's curve is `raytrace` with refraction, reflection and caustics
    /// traced, one point per photon budget: a single frame up to 4 photons per pixel, the mean
    /// of frames beyond; `--exact-source reference` brings back the reference's curve.
    #[test]
    fn a_caustic_settings_curve_is_raytrace_with_photons_unless_the_reference_is_asked_for() {
        let size = ["--width", "64", "--height", "64"];
        let photons = [&size[..], &["--exact-photons", "65536,1024,16384,1024"]].concat();
        let s = spec("caustic_sphere", &["render.caustics=caustics_map"], &photons);
        assert_eq!(s.source, ExactSource::RaytracePhotons);
        assert!(s.reference.is_none());
        let labels: Vec<&str> = s.raytrace.iter().map(|(l, _, _)| l.as_str()).collect();
        assert_eq!(labels, ["1024 photons", "16384 photons", "65536 photons (4 frames of 16384)"]);
        for (label, scene, budget) in &s.raytrace {
            let r = &scene.render;
            assert_eq!((&r.refraction[..], &r.reflection[..], &r.caustics[..]), ("raytrace", "raytrace", "raytrace"));
            let p = crate::scene::techniques::RaytraceParams::from_settings(r).unwrap();
            let b = budget.unwrap();
            assert_eq!((p.photons_per_frame, p.accumulate), (b.photons_per_frame, b.frames), "{label}");
            assert_eq!(u64::from(p.photons_per_frame) * u64::from(p.accumulate), b.photons, "{label}");
            // The default depth and gathering disk: the points differ by their photons only.
            let default = crate::scene::techniques::RaytraceParams::from_settings(
                &load("caustic_sphere", &["render.refraction=raytrace"]).render,
            )
            .unwrap();
            assert_eq!((p.max_depth, p.gather_radius), (default.max_depth, default.gather_radius), "{label}");
        }
        // At 256^2 the cap is 262144 photons a frame.
        assert_eq!(
            photon_frames(262_144, 256, 256),
            PhotonBudget { photons: 262_144, photons_per_frame: 262_144, frames: 1 }
        );
        assert_eq!(
            photon_frames(1 << 20, 256, 256),
            PhotonBudget { photons: 1 << 20, photons_per_frame: 262_144, frames: 4 }
        );
        assert_eq!(
            photon_frames(100_000, 128, 128),
            PhotonBudget { photons: 100_000, photons_per_frame: 50_000, frames: 2 }
        );
        // On a large image a frame holds at most `photons_per_frame`'s largest value.
        let large = photon_frames(3 << 20, 1024, 1024);
        assert_eq!((large.photons_per_frame, large.frames), (1 << 20, 3));

        let reference = [&size[..], &["--exact-source", "reference", "--exact-spp", "2,1"]].concat();
        let s = spec("caustic_sphere", &["render.caustics=caustics_map"], &reference);
        assert_eq!(s.source, ExactSource::Reference);
        assert!(s.raytrace.is_empty());
        assert_eq!(s.reference.as_ref().map(|r| r.2.clone()), Some(vec![1, 2]));
        // Without caustics the curve stays over depth, photons off.
        let s = spec("caustic_sphere", &["render.caustics=none"], &size);
        assert_eq!(s.source, ExactSource::Raytrace);
        assert!(s.raytrace.iter().all(|(l, sc, b)| l.starts_with("max_depth=")
            && b.is_none()
            && sc.render.caustics == "none"
            && crate::scene::techniques::RaytraceParams::from_settings(&sc.render).unwrap().photons_per_frame == 0));
        // A volume keeps the reference.
        let s = spec("eikonal_sphere", &[], &size);
        assert_eq!(s.source, ExactSource::Reference);
    }

    #[test]
    fn dominance_verdicts_on_synthetic_data() {
        let c = curve(&[(10.0, 0.2), (40.0, 0.1)]);
        // Reference noise: RMSE between two references 0.02 * sqrt(2), so floor 0.02.
        let noise =
            Noise { between_references: ErrorMetrics { rmse: 0.02 * std::f64::consts::SQRT_2, ..Default::default() } };
        assert!((noise.floor("rmse") - 0.02).abs() < 1e-12);
        let v = |t, e| equal_time(&c, &noise, "rmse", t, e).verdict;
        assert_eq!(v(5.0, 0.9), Verdict::Faster);
        // At 40 ms the exact tracer reaches 0.1: 0.2 is dominated, 0.05 beats it, 0.11 and
        // 0.09 are within the noise (intervals [e - 0.02, e] overlap).
        assert_eq!(v(40.0, 0.2), Verdict::Dominated);
        assert_eq!(v(40.0, 0.05), Verdict::BeatsExact);
        assert_eq!(v(40.0, 0.11), Verdict::WithinNoise);
        assert_eq!(v(40.0, 0.09), Verdict::WithinNoise);
        // Between the points, against the interpolated error (0.1414 at 20 ms).
        assert_eq!(v(20.0, 0.17), Verdict::Dominated);
        assert_eq!(v(20.0, 0.15), Verdict::WithinNoise);
        // Without noise every difference ranks.
        let exact = equal_time(&c, &Noise::default(), "rmse", 40.0, 0.1001);
        assert_eq!(exact.verdict, Verdict::Dominated);
    }
}
