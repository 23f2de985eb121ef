//! Equal-time comparison with exact ray tracing: is an approximation worth it against the
//! exact tracer given the same GPU time?
//!
//! The exact tracer's own time/error curve is measured in the same run as the techniques:
//!
//! - the `raytrace` technique (docs/raytrace.md) for refraction and reflection. It traces one
//!   centre ray per pixel with deterministic splitting, so more samples per pixel would give
//!   the same image: its cost knob is `max_depth`, the specular interactions per branch, and
//!   its curve runs over `--exact-depths`;
//! - the reference itself (src/reference) at increasing samples per pixel where `raytrace`
//!   cannot: when the setting renders caustics, which `raytrace` does not compute. Its time is
//!   the wall-clock time of its iterations alone (setup excluded; each submission waits on
//!   its fence), which on lavapipe is the same CPU time the GPU timestamps measure.
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

use super::compare::{cached_reference, measure, MeasureArgs, Measurement, ReferencePolicy};
use super::output;
use super::SceneArgs;

#[derive(Args, Debug, Clone)]
pub struct ExactArgs {
    /// `max_depth` values of the `raytrace` technique for the exact tracer's time/error curve.
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,16")]
    pub exact_depths: Vec<u32>,
    /// Samples per pixel of the reference's curve, used instead of `raytrace` when the setting
    /// renders caustics (which `raytrace` does not compute).
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8")]
    pub exact_spp: Vec<u32>,
    /// Frames timed per point of the exact curve (after one warm-up frame). A raytraced
    /// frame costs seconds on lavapipe, where the spread between frames is a few percent.
    #[arg(long, default_value_t = 3)]
    pub exact_frames: u32,
    /// Measure no exact curve and no reference noise (no equal-time verdicts).
    #[arg(long)]
    pub no_exact: bool,
}

/// Which exact tracer a curve measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ExactSource {
    /// The `raytrace` technique at increasing `max_depth`.
    Raytrace,
    /// The reference at increasing samples per pixel (the setting renders caustics).
    Reference,
}

impl ExactSource {
    pub fn describe(self) -> &'static str {
        match self {
            ExactSource::Raytrace => "raytrace (exact, deterministic splitting) at increasing max_depth",
            ExactSource::Reference => "the reference at increasing samples per pixel (raytrace has no caustics)",
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
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct ExactCurve {
    pub source: ExactSource,
    pub points: Vec<ExactPoint>,
}

/// The reference's own noise: the metrics of a second reference (another seed, same samples)
/// against the first. For MSE-like errors the expectation is additive: a technique image T,
/// independent of the reference R = mu + noise of variance s^2 per channel, has
/// E[MSE(T, R)] = MSE(T, mu) + s^2, and two references differ by MSE(R1, R2) = 2 s^2. So the
/// reference's noise RMSE is s = RMSE(R1, R2) / sqrt(2), and since sqrt(m + s^2) <= sqrt(m) + s,
/// a measured RMSE e stands for a true one in [e - s, e]. relMSE behaves like MSE (floor
/// relMSE(R1, R2) / 2). FLIP is not additive; the same rule as RMSE is applied to it as an
/// estimate of how far the reference's noise moves it.
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
    let second = ReferenceSettings { seed: settings.seed.wrapping_add(1), ..settings.clone() };
    let other = cached_reference(ctx, scene, &second, policy)?.image;
    let (a, b) = (output::tonemap_scene(&other, &scene.render), output::tonemap_scene(reference, &scene.render));
    let (m, _) = ErrorMetrics::between(&other, reference, &a, &b, scene.camera.width, scene.camera.height);
    Ok(Noise { between_references: m })
}

/// Whether a setting's techniques can be replaced by `raytrace` (it has no caustics).
pub fn source_for(scene: &Scene) -> ExactSource {
    if scene.render.caustics == "none" {
        ExactSource::Raytrace
    } else {
        ExactSource::Reference
    }
}

/// Measure the exact tracer's curve on the scene that `scene_args` loads (the same scene as
/// the techniques, with `raytrace` selected for refraction and reflection), against
/// `reference`.
pub fn measure_curve(
    ctx: &Arc<GpuContext>,
    scene_args: &SceneArgs,
    measure_args: &MeasureArgs,
    exact: &ExactArgs,
    reference: &[f32],
) -> Result<ExactCurve> {
    let base = scene_args.load()?;
    let source = source_for(&base);
    let mut points = Vec::new();
    match source {
        ExactSource::Raytrace => {
            if exact.exact_depths.is_empty() {
                bail!("--exact-depths: no values");
            }
            for &d in &exact.exact_depths {
                let mut sa = scene_args.clone();
                sa.set.extend([
                    "render.refraction=raytrace".to_string(),
                    "render.reflection=raytrace".to_string(),
                    format!("render.raytrace.max_depth={d}"),
                ]);
                let scene = sa.load().with_context(|| format!("exact curve, raytrace max_depth={d}"))?;
                let args = MeasureArgs { frames: exact.exact_frames.max(1), warmup: 1, ..measure_args.clone() };
                eprintln!("exact: raytrace max_depth={d}");
                let m = measure(ctx, &scene, &args, reference)?;
                points.push(ExactPoint {
                    label: format!("max_depth={d}"),
                    time_ms: m.frame.median_ms,
                    errors: m.errors,
                    errors_mask: m.mask.errors_mask,
                });
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
            let mut r = Reference::new(ctx, &base, &s).context("exact curve: cannot set up the reference")?;
            let ref_ldr = output::tonemap_scene(reference, &base.render);
            let mask = crate::metrics::mask::ObjectMask::of_scene(&base);
            let mut elapsed = 0.0f64;
            for &n in &spp {
                let t = std::time::Instant::now();
                r.run(n - r.iterations_done())?;
                elapsed += t.elapsed().as_secs_f64() * 1e3;
                let img = r.image();
                let ldr = output::tonemap_scene(&img, &base.render);
                let (w, h) = (base.camera.width, base.camera.height);
                let (errors, errors_mask, _) =
                    ErrorMetrics::between_with_mask(&img, reference, &ldr, &ref_ldr, w, h, Some(&mask.pixels));
                eprintln!("exact: reference {n} spp");
                points.push(ExactPoint { label: format!("{n} spp"), time_ms: elapsed, errors, errors_mask });
            }
        }
    }
    Ok(ExactCurve { source, points })
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
        other => bail!("--metric {other}: expected flip_mean, flip_p95, rmse or rel_mse"),
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
