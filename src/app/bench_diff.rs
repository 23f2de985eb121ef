//! `prism bench --diff A.json B.json`: two bench runs compared pass by pass, with each
//! pass's spread, saying which differences exceed the noise.
//!
//! The noise of a median: for n samples of standard deviation s, the standard error of the
//! median is sqrt(pi / 2) * s / sqrt(n) (the large-sample result for normal noise; the
//! median is what the tables report because lavapipe's times have long upper tails). A
//! difference of medians counts as real when it exceeds 3 combined standard errors,
//! 3 * sqrt(se_A^2 + se_B^2): for normal noise that happens by chance in 0.3% of passes.
use std::path::Path;

use anyhow::{Context, Result};
use serde_json::Value;

/// The multiple of the combined standard error beyond which a difference is reported as
/// real (module doc).
pub const NOISE_SIGMAS: f64 = 3.0;

/// One series of a bench JSON: a pass or the frame.
#[derive(Debug, Clone)]
pub struct Series {
    pub name: String,
    pub median: f64,
    pub samples: usize,
    /// None: the file has neither standard deviations nor samples (written before they were).
    pub stddev: Option<f64>,
}

impl Series {
    fn from_json(v: &Value, name: &str) -> Option<Series> {
        let median = v["median_ms"].as_f64()?;
        let samples_ms: Option<Vec<f64>> =
            v["samples_ms"].as_array().map(|a| a.iter().filter_map(Value::as_f64).collect());
        let samples = samples_ms.as_ref().map(Vec::len).or(v["samples"].as_u64().map(|n| n as usize)).unwrap_or(0);
        let stddev = v["stddev_ms"].as_f64().or_else(|| samples_ms.as_deref().map(super::bench::stddev));
        Some(Series { name: name.to_string(), median, samples, stddev })
    }

    /// Standard error of the median (module doc).
    fn median_error(&self) -> Option<f64> {
        let s = self.stddev?;
        (self.samples > 0).then(|| (std::f64::consts::PI / 2.0).sqrt() * s / (self.samples as f64).sqrt())
    }
}

/// The comparison of one pass.
#[derive(Debug, Clone)]
pub struct Difference {
    pub name: String,
    pub a: Option<Series>,
    pub b: Option<Series>,
    /// NOISE_SIGMAS combined standard errors, ms (None without spreads).
    pub noise: Option<f64>,
}

impl Difference {
    pub fn delta(&self) -> Option<f64> {
        Some(self.b.as_ref()?.median - self.a.as_ref()?.median)
    }
    /// Some(true): the difference exceeds the noise; None: no spread or a pass missing.
    pub fn beyond_noise(&self) -> Option<bool> {
        Some(self.delta()?.abs() > self.noise?)
    }
}

/// The passes of both files (A's order, then B's new ones) and the frame, compared.
pub fn diff(a: &Value, b: &Value) -> Result<Vec<Difference>> {
    let series = |v: &Value| -> Result<Vec<Series>> {
        let passes = v["passes"].as_array().context("not a `prism bench --json` file: no \"passes\" array")?;
        let mut out: Vec<Series> =
            passes.iter().filter_map(|p| p["name"].as_str().and_then(|n| Series::from_json(p, n))).collect();
        out.push(Series::from_json(&v["frame"], "frame").context("no \"frame\" statistics")?);
        Ok(out)
    };
    let (sa, sb) = (series(a)?, series(b)?);
    let mut names: Vec<String> = sa.iter().map(|s| s.name.clone()).collect();
    for s in &sb {
        if !names.contains(&s.name) {
            names.insert(names.len() - 1, s.name.clone());
        }
    }
    Ok(names
        .into_iter()
        .map(|name| {
            let a = sa.iter().find(|s| s.name == name).cloned();
            let b = sb.iter().find(|s| s.name == name).cloned();
            let noise = match (a.as_ref().and_then(Series::median_error), b.as_ref().and_then(Series::median_error)) {
                (Some(x), Some(y)) => Some(NOISE_SIGMAS * (x * x + y * y).sqrt()),
                _ => None,
            };
            Difference { name, a, b, noise }
        })
        .collect())
}

pub fn run(a_path: &Path, b_path: &Path) -> Result<()> {
    let read = |p: &Path| -> Result<Value> {
        let bytes = std::fs::read(p).with_context(|| format!("cannot read {}", p.display()))?;
        serde_json::from_slice(&bytes).with_context(|| format!("{} is not JSON", p.display()))
    };
    let (a, b) = (read(a_path)?, read(b_path)?);
    let diffs = diff(&a, &b).with_context(|| format!("comparing {} with {}", a_path.display(), b_path.display()))?;

    let describe = |v: &Value| {
        format!(
            "{} at {}x{}, {} frames, {} ({}), revision {}",
            v["scene"].as_str().unwrap_or("?"),
            v["width"],
            v["height"],
            v["frames"],
            v["device"]["name"].as_str().unwrap_or("?"),
            v["device"]["driver_info"].as_str().unwrap_or("?"),
            v["git_revision"].as_str().unwrap_or("?")
        )
    };
    println!("A: {}: {}", a_path.display(), describe(&a));
    println!("B: {}: {}", b_path.display(), describe(&b));
    for key in ["scene", "width", "height"] {
        if a[key] != b[key] {
            println!("warning: the runs differ in {key} ({} vs {}): pass times are not comparable", a[key], b[key]);
        }
    }
    if a["device"]["name"] != b["device"]["name"] {
        println!("warning: the runs are on different devices");
    }
    let width = diffs.iter().map(|d| d.name.len()).max().unwrap_or(5).max(5);
    println!(
        "{:width$}  {:>11}  {:>11}  {:>10}  {:>7}  {:>10}  verdict",
        "pass", "A median ms", "B median ms", "B-A ms", "B/A", "noise ms"
    );
    let f = |x: Option<f64>, p: usize| x.map_or_else(|| "-".to_string(), |x| format!("{x:.p$}"));
    for d in &diffs {
        let (am, bm) = (d.a.as_ref().map(|s| s.median), d.b.as_ref().map(|s| s.median));
        let ratio = am.zip(bm).filter(|(a, _)| *a > 0.0).map(|(a, b)| b / a);
        let verdict = match (d.a.is_some(), d.b.is_some(), d.beyond_noise()) {
            (true, false, _) => "only in A",
            (false, true, _) => "only in B",
            (_, _, None) => "no spread recorded",
            (_, _, Some(false)) => "within noise",
            (_, _, Some(true)) if d.delta().unwrap_or(0.0) > 0.0 => "B slower, beyond noise",
            (_, _, Some(true)) => "B faster, beyond noise",
        };
        println!(
            "{:width$}  {:>11}  {:>11}  {:>10}  {:>7}  {:>10}  {verdict}",
            d.name,
            f(am, 3),
            f(bm, 3),
            f(d.delta(), 3),
            f(ratio, 3),
            d.noise.map_or_else(|| "-".to_string(), |n| format!("±{n:.3}")),
        );
    }
    println!(
        "noise: {NOISE_SIGMAS} combined standard errors of the medians, sqrt(pi/2) * stddev / sqrt(n) each (src/app/bench_diff.rs)"
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(name: &str, samples: &[f64]) -> Value {
        let s = crate::metrics::timing::Stats::of(samples);
        serde_json::json!({
            "passes": [{"name": name, "median_ms": s.median_ms, "samples": samples.len(),
                        "stddev_ms": super::super::bench::stddev(samples), "samples_ms": samples}],
            "frame": {"median_ms": s.median_ms, "samples": samples.len(), "samples_ms": samples},
        })
    }

    #[test]
    fn a_shift_beyond_the_spread_is_flagged_and_one_within_it_is_not() {
        // Alternating +-1 around 10 ms: stddev ~1.0, 20 samples, standard error of the
        // median ~0.28 ms, combined ~0.40, noise threshold ~1.2 ms.
        let base: Vec<f64> = (0..20).map(|i| 10.0 + if i % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let shifted = |d: f64| base.iter().map(|x| x + d).collect::<Vec<_>>();
        let d = diff(&run("p", &base), &run("p", &shifted(3.0))).unwrap();
        assert_eq!(d[0].beyond_noise(), Some(true));
        assert_eq!(d[1].name, "frame");
        assert_eq!(d[1].beyond_noise(), Some(true), "the frame's spread comes from its samples");
        let d = diff(&run("p", &base), &run("p", &shifted(0.5))).unwrap();
        assert_eq!(d[0].beyond_noise(), Some(false));
        let d = diff(&run("p", &base), &run("q", &base)).unwrap();
        assert_eq!(d.iter().map(|d| d.name.as_str()).collect::<Vec<_>>(), ["p", "q", "frame"]);
        assert_eq!(d[0].beyond_noise(), None);
    }
}
