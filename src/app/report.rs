//! `prism report`: docs/ACCURACY.md, generated. For every entry of a spec file (default
//! docs/report.toml) it sweeps the entry's parameters on its benchmark scene, measures time
//! and error against the exact reference, and writes a table per entry, the error-against-
//! time plot, and the images (technique, reference, FLIP heat map) side by side.
use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use super::compare::{cached_reference, MeasureArgs};
use super::equaltime::{curve_spec, measure_interleaved, reference_noise, second_reference, Exact, ExactArgs, Setting};
use super::output::{self, Outputs};
use super::sweep::{
    cartesian, metric_of, parse_params, plot_exact, plot_svg, short_label, technique_names, Plot, PlotPoint,
};
use super::{check_validation, GpuArgs, SceneArgs};
use crate::app::compare::Measurement;
use crate::metrics::image::flip_values;
use crate::metrics::paired::{flip_difference, mse_difference, FlipMaps, Paired, SEPARATION};
use crate::scene::Scene;

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// The report's entries (scenes and parameter sweeps).
    #[arg(long, default_value = "docs/report.toml")]
    pub spec: PathBuf,
    /// The Markdown file to write; plots (and with --images the image strips) go to a folder
    /// beside it (accuracy/).
    #[arg(short, long, default_value = "docs/ACCURACY.md")]
    pub out: PathBuf,
    /// Also write each section's images (the technique, the reference and the FLIP map side
    /// by side, one PNG of 100-400 KB per section) beside the report and show them in it.
    /// Off by default: they are a run's output, not something to keep in the repository.
    #[arg(long)]
    pub images: bool,
    /// Image size for every scene.
    #[arg(long, default_value_t = 256)]
    pub size: u32,
    /// Only measure the entries whose scene is this name or whose title contains it
    /// (repeatable); the other entries keep their sections from the existing file, each with
    /// the revision and command that measured it.
    #[arg(long)]
    pub only: Vec<String>,
    #[command(flatten)]
    pub measure: MeasureArgs,
    #[command(flatten)]
    pub exact: ExactArgs,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Spec {
    /// Settings applied to every entry's scene before its `params`: docs/report.toml names the
    /// baseline techniques here, so that an entry measures what it names whatever technique
    /// a scene file selects.
    #[serde(default)]
    set: Vec<String>,
    entry: Vec<Entry>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    scene: String,
    title: String,
    #[serde(default)]
    params: Vec<String>,
}

pub fn run(args: ReportArgs) -> Result<()> {
    let text = std::fs::read_to_string(&args.spec)
        .with_context(|| format!("{}: cannot read the report spec", args.spec.display()))?;
    let spec: Spec = toml::from_str(&text).map_err(|e| anyhow::anyhow!("{}: {e}", args.spec.display()))?;
    let settings = args.measure.reference.settings();
    settings.validate()?;
    // With --only, the sections of the entries not measured now are kept from the file as it is.
    let existing = std::fs::read_to_string(&args.out).ok();
    let previous = existing.as_deref().filter(|_| !args.only.is_empty()).map(Previous::parse);
    let mut outputs = Outputs::default();
    let out = outputs.prepare(&args.out)?;
    // The plots and image strips, written as the entries are measured and moved into place
    // with the report itself.
    let mut written = Vec::new();
    let base = args.out.parent().map(|p| p.to_path_buf()).unwrap_or_default();
    let assets = base.join("accuracy");
    std::fs::create_dir_all(&assets).with_context(|| format!("cannot create {}", assets.display()))?;
    let ctx = args.gpu.context()?;

    let mut md = String::new();
    let mut summaries: Vec<SummaryRow> = Vec::new();
    let command = format!(
        "prism report --size {} --spp {} --photons {}{}",
        args.size,
        settings.spp,
        settings.photons,
        args.exact.changed_flags()
    );
    let provenance = format!("*Measured at git revision {} with `{command}`.*\n", super::bench::git_revision());

    for e in &spec.entry {
        let heading = format!("## {}: {}", e.scene, e.title);
        let selected = args.only.is_empty() || args.only.iter().any(|o| *o == e.scene || e.title.contains(o.as_str()));
        if !selected {
            match previous.as_ref().and_then(|p| p.section(&heading)) {
                Some(section) => md.push_str(&section),
                None => writeln!(md, "{heading}\n\n{NOT_MEASURED} run `prism report --only {}`.\n", e.scene)?,
            }
            continue;
        }
        // File names carry a hash of the entry: a scene may appear in several entries, and
        // entries measured at different times must not overwrite each other's images.
        let stem = format!("{}-{}", e.scene, entry_hash(e));
        let params = parse_params(&e.params)?;
        let mut loaded = Vec::new();
        // Warnings of the references (step-capped paths, or cut ones accepted with
        // --accept-cut-reference), for the section.
        let mut inexact = Vec::new();
        for setting in cartesian(&params) {
            let sa = SceneArgs {
                scene: Some(e.scene.clone().into()),
                set: spec.set.iter().chain(&setting).cloned().collect(),
                width: Some(args.size),
                height: Some(args.size),
            };
            let scene = sa.load().with_context(|| format!("report entry {}", e.scene))?;
            eprintln!("report: {} {}", e.scene, setting.join(" "));
            let r = cached_reference(&ctx, &scene, &settings, args.measure.reference_policy())?;
            inexact.extend(r.stats.warning(&scene.name).map(|w| format!("{}: {w}", setting.join(" "))));
            loaded.push((setting, scene, r.image));
        }
        let sa0 = SceneArgs {
            scene: Some(e.scene.clone().into()),
            set: spec.set.iter().chain(&loaded[0].0).cloned().collect(),
            width: Some(args.size),
            height: Some(args.size),
        };
        let (curve_spec, noise, second) = if args.exact.no_exact {
            (None, None, None)
        } else {
            let (scene, reference) = (&loaded[0].1, &loaded[0].2);
            let policy = args.measure.reference_policy();
            let noise = reference_noise(&ctx, scene, &settings, reference, policy)?;
            let second = second_reference(&ctx, scene, &settings, policy)?;
            let settings = loaded.iter().map(|(_, scene, _)| scene);
            (Some(curve_spec(&sa0, &args.measure, &args.exact, settings)?), Some(noise), Some(second))
        };
        // The entry's settings and the exact points timed interleaved (src/app/equaltime.rs).
        let timed: Vec<Setting> = loaded.iter().map(|(_, scene, reference)| Setting { scene, reference }).collect();
        let exact_reference = loaded[0].2.as_slice();
        let (measured, curve) =
            measure_interleaved(&ctx, &timed, &args.measure, curve_spec.as_ref().map(|s| (s, exact_reference)))?;
        drop(timed);
        let exact = curve.zip(noise).map(|(curve, noise)| Exact { curve, noise });
        let rows: Vec<_> = loaded
            .into_iter()
            .zip(measured)
            .map(|((setting, scene, reference), m)| (setting, scene, m, reference))
            .collect();
        check_validation(&ctx)?;
        writeln!(md, "{heading}\n")?;
        for w in &inexact {
            writeln!(md, "**Warning:** {w}\n")?;
        }
        let techniques = technique_names(&rows.iter().map(|r| &r.1).collect::<Vec<_>>());
        let (s0, ..) = (&rows[0].1, ());
        writeln!(
            md,
            "Techniques: refraction `{}`, reflection `{}`, caustics `{}`.\n",
            s0.render.refraction, s0.render.reflection, s0.render.caustics
        )?;
        let measured: Vec<_> = rows.iter().map(|(setting, _, m, _)| (setting.as_slice(), m)).collect();
        section_table(&mut md, &measured, exact.as_ref())?;
        let ranking = second.as_deref().and_then(|second| {
            let against: Vec<_> =
                rows.iter().map(|(_, scene, m, reference)| (scene, m, reference.as_slice())).collect();
            Ranking::of(&against, second)
        });
        if let Some(r) = &ranking {
            r.write(&mut md, &measured)?;
        }
        if let Some(summary) = summary_row(e, &measured, &techniques, exact.as_ref(), ranking.as_ref())? {
            summaries.push(summary);
        }
        let points: Vec<PlotPoint> = rows
            .iter()
            .zip(&techniques)
            .map(|(r, t)| {
                Ok(PlotPoint {
                    time_ms: r.2.frame.median_ms,
                    error: metric_of(&r.2, "flip_mean")?,
                    label: short_label(&r.0),
                    technique: t.clone(),
                })
            })
            .collect::<Result<_>>()?;
        if rows.len() > 1 || exact.is_some() {
            let name = format!("{stem}-sweep");
            let plot_exact = exact.as_ref().map(|x| plot_exact(x, "flip_mean")).transpose()?;
            let title = format!("{}: FLIP against GPU time", e.scene);
            let plot = Plot { title: &title, y_label: "FLIP mean", points: &points, exact: plot_exact.as_ref() };
            // The report links the SVG; a PNG copy would only add weight to the repository.
            written.push(outputs.prepare(&assets.join(format!("{name}.svg")))?.write(plot_svg(&plot)?.as_bytes())?);
            writeln!(md, "![{name}](accuracy/{name}.svg)\n")?;
        }
        // Images of the last (usually most accurate) setting: technique | reference | FLIP.
        if args.images {
            let (_, scene, m, reference) = rows.last().unwrap();
            let (w, h) = (scene.camera.width, scene.camera.height);
            let mut strip = vec![0u8; (3 * w * h * 4) as usize];
            let ref_ldr = output::tonemap_scene(reference, &scene.render);
            for (k, img) in [&m.ldr, &ref_ldr, &m.heatmap].iter().enumerate() {
                for y in 0..h as usize {
                    let src = &img[y * w as usize * 4..(y + 1) * w as usize * 4];
                    let dst = (y * 3 * w as usize + k * w as usize) * 4;
                    strip[dst..dst + src.len()].copy_from_slice(src);
                }
            }
            let name = format!("{stem}-images.png");
            written.push(output::write_png_rgb(outputs.prepare(&assets.join(&name))?, 3 * w, h, &strip)?);
            writeln!(
                md,
                "![{}](accuracy/{name})\n\n*Left to right: the technique, the reference, the FLIP error map.*\n",
                e.scene
            )?;
        }
        writeln!(md, "{provenance}")?;
    }
    let mut head = header(args.measure.frames, args.measure.warmup, &md);
    writeln!(
        head,
        "Device: {} ({} {}), git revision {}.",
        ctx.info.name,
        ctx.info.driver_name,
        ctx.info.driver_info,
        super::bench::git_revision()
    )?;
    if ctx.info.device_type == "CPU" {
        writeln!(
            head,
            "On a CPU device (lavapipe) times are CPU time: compare them within a table, not across machines."
        )?;
    }
    writeln!(head, "\nCommand: `{command}`\n")?;
    if !args.only.is_empty() {
        writeln!(
            head,
            "Sections were measured separately (`prism report --only`): each one names the revision \
             and command that measured it.\n"
        )?;
    }
    // Rows of entries not measured now are kept from the existing summary.
    if let Some(p) = &previous {
        for e in &spec.entry {
            if summaries.iter().any(|s| s.scene == e.scene && Some(s.effect.as_str()) == entry_effect(e)) {
                continue;
            }
            if let Some(line) = entry_effect(e).and_then(|effect| p.summary_line(&e.scene, effect)) {
                summaries.push(SummaryRow { scene: e.scene.clone(), effect: entry_effect(e).unwrap().into(), line });
            }
        }
    }
    // In the spec's order, whichever entries were measured now.
    summaries.sort_by_key(|s| {
        spec.entry.iter().position(|e| e.scene == s.scene && entry_effect(e) == Some(s.effect.as_str()))
    });
    head.push_str(&summary_table(&summaries));
    if let Some(block) = existing.as_deref().and_then(hand_written) {
        writeln!(head, "{block}\n")?;
    }
    written.push(out.write((head + &md).as_bytes())?);
    output::commit_all(written)?;
    eprintln!("wrote {}", args.out.display());
    Ok(())
}

/// A section's table: one numbered row per setting (the numbers of the plot), each error with
/// the interval the reference's noise leaves it, the exact tracer's FLIP at the same time and
/// the verdict; then the exact tracer's own points. The mask columns give RMSE and FLIP mean
/// over the object mask (src/metrics/mask.rs), the pixels the techniques touch; its surfaces
/// follow the table. HDR-FLIP (mean with the reference's noise, 95th percentile, mean over the
/// mask) comes last, after the columns that existed before it.
fn section_table(
    md: &mut String,
    rows: &[(&[String], &crate::app::compare::Measurement)],
    exact: Option<&Exact>,
) -> Result<()> {
    let with_noise = |metric: &str, v: f64| match exact {
        Some(x) => {
            let (lo, _) = x.noise.interval(metric, v);
            format!("{v:.4} ({lo:.4}–{v:.4})")
        }
        None => format!("{v:.4}"),
    };
    write!(
        md,
        "| # | setting | frame ms | per change ms | technique passes | RMSE | relMSE | FLIP mean | FLIP p95 | mask RMSE | mask FLIP mean |"
    )?;
    let hdr_head = " HDR-FLIP mean | HDR-FLIP p95 | mask HDR-FLIP mean |";
    if exact.is_some() {
        writeln!(md, " exact FLIP at equal time | verdict |{hdr_head}")?;
        writeln!(md, "|---:|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|")?;
    } else {
        writeln!(md, "{hdr_head}")?;
        writeln!(md, "|---:|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    }
    for (i, (setting, m)) in rows.iter().enumerate() {
        let passes: Vec<String> = m.passes.iter().map(|p| format!("{} {:.2}", p.name, p.stats.median_ms)).collect();
        write!(
            md,
            "| {} | {} | {:.2} | {:.2} | {} | {} | {:.4} | {} | {:.4} |",
            i + 1,
            if setting.is_empty() { "default".into() } else { format!("`{}`", setting.join(" ")) },
            m.frame.median_ms,
            m.per_change.ms,
            passes.join(", "),
            with_noise("rmse", m.errors.rmse),
            m.errors.rel_mse,
            with_noise("flip_mean", m.errors.flip_mean),
            m.errors.flip_p95
        )?;
        match &m.mask.errors_mask {
            Some(e) => write!(md, " {:.4} | {:.4} |", e.rmse, e.flip_mean)?,
            None => write!(md, " – | – |")?,
        }
        if let Some(x) = exact {
            let eq = x.equal_time("flip_mean", m)?;
            let at = eq.exact.map(|a| format!("{:.4}", a.error)).unwrap_or_else(|| "–".into());
            write!(md, " {at} | {} |", eq.verdict.as_str())?;
        }
        let mask_hdr = m.mask.errors_mask.map(|e| format!("{:.4}", e.hdr_flip_mean)).unwrap_or_else(|| "–".into());
        writeln!(
            md,
            " {} | {:.4} | {mask_hdr} |",
            with_noise("hdr_flip_mean", m.errors.hdr_flip_mean),
            m.errors.hdr_flip_p95
        )?;
    }
    writeln!(md)?;
    writeln!(md, "{}\n", cost_caption(rows.iter().map(|(_, m)| &m.per_change)))?;
    let mut masks: Vec<String> = rows.iter().map(|(_, m)| m.mask.describe()).collect();
    masks.dedup();
    writeln!(
        md,
        "Object mask (the pixels whose centre ray first meets a specular object, or with caustics a \
         diffuse receiver): {}.\n",
        masks.join("; ")
    )?;
    if let Some(x) = exact {
        let floor = |metric| x.noise.floor(metric);
        writeln!(
            md,
            "Reference noise (a second reference, next seed): RMSE {:.4}, FLIP mean {:.4}, HDR-FLIP \
             mean {:.4}; an error in parentheses is the range of the true error it allows (the settings \
             are ranked against each other by their paired differences, below, which the noise \
             moves far less). Exact tracer: {}:",
            floor("rmse"),
            floor("flip_mean"),
            floor("hdr_flip_mean"),
            x.curve.source.describe()
        )?;
        let pts: Vec<String> = x
            .curve
            .points
            .iter()
            .map(|p| {
                let mask = p.errors_mask.map(|e| format!(" (mask: FLIP {:.4} RMSE {:.4})", e.flip_mean, e.rmse));
                format!(
                    "{} {:.2} ms FLIP {:.4} RMSE {:.4} HDR-FLIP {:.4}{}",
                    p.label,
                    p.time_ms,
                    p.errors.flip_mean,
                    p.errors.rmse,
                    p.errors.hdr_flip_mean,
                    mask.unwrap_or_default()
                )
            })
            .collect();
        writeln!(md, "{}.\n", pts.join("; "))?;
    }
    Ok(())
}

/// Every setting of a section against the best by FLIP mean, each difference paired against
/// the one reference they share (src/metrics/paired.rs), so that the reference's noise counts
/// only where the two settings differ.
struct Ranking {
    best: usize,
    /// Per setting: its FLIP mean's and its MSE's difference from the best's; None for the
    /// best and for a setting measured against another reference.
    pairs: Vec<Option<(Paired, Paired)>>,
}

impl Ranking {
    /// `rows`: each setting's scene, measurement and reference; `second` the second reference
    /// of the first setting's (`second_reference`), which the rows that share the first
    /// setting's reference are paired with. None when the best does not share it.
    fn of(rows: &[(&Scene, &Measurement, &[f32])], second: &[f32]) -> Option<Ranking> {
        let first = rows.first()?.2;
        let best =
            (0..rows.len()).min_by(|&a, &b| rows[a].1.errors.flip_mean.total_cmp(&rows[b].1.errors.flip_mean))?;
        let shared = |i: usize| rows[i].2 == first;
        if !shared(best) {
            return None;
        }
        let (w, h) = (rows[best].0.camera.width, rows[best].0.camera.height);
        // FLIP against either reference and their mean, tone-mapped as the setting's own
        // errors were.
        let mean: Vec<f32> = first.iter().zip(second).map(|(a, b)| 0.5 * (a + b)).collect();
        let maps = |i: usize| {
            let (scene, m, _) = rows[i];
            let flip = |r: &[f32]| flip_values(&m.ldr, &output::tonemap_scene(r, &scene.render), w, h);
            FlipMaps { r1: flip(first), r2: flip(second), mean: flip(&mean) }
        };
        let best_maps = maps(best);
        let pairs = (0..rows.len())
            .map(|i| {
                (i != best && shared(i)).then(|| {
                    let flip = flip_difference(&maps(i), &best_maps, w, h);
                    let mse = mse_difference(&rows[i].1.hdr, &rows[best].1.hdr, first, second, w, h);
                    (flip, mse)
                })
            })
            .collect();
        Some(Ranking { best, pairs })
    }

    /// The section's ranking table: each setting's differences from the best with their
    /// standard errors, and whether they are ranked.
    fn write(&self, md: &mut String, rows: &[(&[String], &Measurement)]) -> Result<()> {
        let label = |i: usize| {
            let s = rows[i].0;
            if s.is_empty() {
                "default".to_string()
            } else {
                format!("`{}`", s.join(" "))
            }
        };
        writeln!(
            md,
            "Ranking against the best by FLIP mean, #{} {}: each setting's difference from it, the \
             standard error that the reference's noise leaves the difference (settings measured \
             against one reference share its noise, which cancels in their difference except where \
             they differ; estimated with the second reference: src/metrics/paired.rs) and, for \
             FLIP, the bias it may leave (from the difference against the mean of the two \
             references); ranked where the difference exceeds {} standard errors plus the bias. \
             RMSE's error is the MSE difference's over the sum of the two RMSEs; its bias is 0.\n",
            self.best + 1,
            label(self.best),
            SEPARATION
        )?;
        writeln!(
            md,
            "| # | setting | FLIP mean − best | ± standard error | bias | RMSE − best | ± standard error | ranked |\n\
             |---:|---|---:|---:|---:|---:|---:|---|"
        )?;
        for (i, pair) in self.pairs.iter().enumerate() {
            let Some((flip, mse)) = pair else { continue };
            let (a, b) = (rows[i].1.errors.rmse, rows[self.best].1.errors.rmse);
            let rmse_error = mse.standard_error / (a + b).max(1e-12);
            let ranked = match (flip.separated(), mse.separated()) {
                (true, true) => "by FLIP and RMSE",
                (true, false) => "by FLIP",
                (false, true) => "by RMSE",
                (false, false) => "within noise",
            };
            writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} | {ranked} |",
                i + 1,
                label(i),
                digits(flip.difference, 5, true),
                digits(flip.standard_error, 5, false),
                digits(flip.bias, 5, true),
                digits(a - b, 4, true),
                digits(rmse_error, 4, false)
            )?;
        }
        writeln!(md)?;
        Ok(())
    }
}

/// `v` with `decimals` decimals, or with two significant digits where those would show none
/// of it (a ranked difference of 3e-6 must not read as 0).
fn digits(v: f64, decimals: usize, signed: bool) -> String {
    let shown = v.abs() >= 0.5 * 10f64.powi(-(decimals as i32)) || v == 0.0;
    match (shown, signed) {
        (true, true) => format!("{v:+.decimals$}"),
        (true, false) => format!("{v:.decimals$}"),
        (false, true) => format!("{v:+.1e}"),
        (false, false) => format!("{v:.1e}"),
    }
}

/// What a table's time columns include: frame ms the steady frame, per change ms the costs
/// paid once per light or object change (src/app/compare.rs, `PerChange`), named with the
/// change that re-runs each.
fn cost_caption<'a>(per_change: impl Iterator<Item = &'a crate::app::compare::PerChange>) -> String {
    let mut names: Vec<String> = Vec::new();
    for c in per_change.flat_map(|p| &p.costs) {
        let name = format!("`{}` ({}, on a {})", c.name, c.clock, c.rerun_on);
        if !names.contains(&name) {
            names.push(name);
        }
    }
    let paid = if names.is_empty() { "none here".to_string() } else { names.join(", ") };
    format!(
        "*Frame ms* is the median steady frame after the warm-up: every pass that runs each frame \
         (the technique passes listed, the G-buffer, shading, tone map), none of the costs paid \
         once. *Per change ms* is paid once per light or object change, not per frame (a camera \
         move re-runs none of it): {paid}."
    )
}

/// The effect an entry compares techniques for at their defaults: an entry whose only
/// parameter is `render.refraction`, `render.reflection` or `render.caustics`.
fn entry_effect(e: &Entry) -> Option<&str> {
    match e.params.as_slice() {
        [p] => {
            let key = p.split_once('=')?.0.trim();
            ["render.refraction", "render.reflection", "render.caustics"]
                .contains(&key)
                .then(|| &key["render.".len()..])
        }
        _ => None,
    }
}

/// One row of the summary table: a scene, an effect, and its Markdown line.
struct SummaryRow {
    scene: String,
    effect: String,
    line: String,
}

/// The summary row of an entry that compares techniques at their defaults: the best of them
/// by FLIP mean (with those within the reference's noise of it), its time and error, the
/// exact tracer's error at that time, the verdict.
fn summary_row(
    e: &Entry,
    rows: &[(&[String], &crate::app::compare::Measurement)],
    techniques: &[String],
    exact: Option<&Exact>,
    ranking: Option<&Ranking>,
) -> Result<Option<SummaryRow>> {
    let Some(effect) = entry_effect(e) else { return Ok(None) };
    let Some(best) = (0..rows.len()).min_by(|&a, &b| rows[a].1.errors.flip_mean.total_cmp(&rows[b].1.errors.flip_mean))
    else {
        return Ok(None);
    };
    let name = |i: usize| {
        rows[i]
            .0
            .first()
            .and_then(|s| s.split_once('='))
            .map(|s| s.1.to_string())
            .unwrap_or_else(|| techniques[i].clone())
    };
    let m = rows[best].1;
    let interval = |v: f64| exact.map(|x| x.noise.interval("flip_mean", v)).unwrap_or((v, v));
    let (lo, hi) = interval(m.errors.flip_mean);
    // Against the same reference the paired difference decides (src/metrics/paired.rs);
    // elsewhere two errors whose intervals overlap are within noise.
    let within_noise = |i: usize| match ranking.and_then(|r| r.pairs[i].as_ref().filter(|_| r.best == best)) {
        Some((flip, _)) => !flip.separated(),
        None => interval(rows[i].1.errors.flip_mean).0 <= hi && lo <= rows[i].1.errors.flip_mean,
    };
    let ties: Vec<String> = (0..rows.len()).filter(|&i| i != best && within_noise(i)).map(name).collect();
    let mut technique = format!("`{}`", name(best));
    if !ties.is_empty() {
        technique.push_str(&format!(
            " (within noise: {})",
            ties.iter().map(|t| format!("`{t}`")).collect::<Vec<_>>().join(", ")
        ));
    }
    let (at, verdict) = match exact {
        Some(x) => {
            let eq = x.equal_time("flip_mean", m)?;
            (eq.exact.map(|a| format!("{:.4}", a.error)).unwrap_or_else(|| "–".into()), eq.verdict.as_str().to_string())
        }
        None => ("not measured".into(), "–".into()),
    };
    let line = format!(
        "| {} | {effect} | {technique} | {:.2} | {:.2} | {:.4} ({lo:.4}–{hi:.4}) | {at} | {verdict} |",
        e.scene, m.frame.median_ms, m.per_change.ms, m.errors.flip_mean
    );
    Ok(Some(SummaryRow { scene: e.scene.clone(), effect: effect.into(), line }))
}

/// The heading of the summary table; `Previous` reads its rows back for `--only`.
const SUMMARY_HEADING: &str = "## Summary: the best approximation against exact ray tracing at equal time";

fn summary_table(rows: &[SummaryRow]) -> String {
    let mut t = format!(
        "{SUMMARY_HEADING}\n\n\
         One row per scene and effect, from the sections below that compare techniques at their \
         defaults: the best by FLIP mean (others named whose paired difference from it is within \
         the reference's noise: the section's ranking table), its \
         frame time and FLIP with the range the reference's noise allows, the exact tracer's FLIP \
         at the same GPU time (interpolated on its curve, measured in the same run; each \
         section names the tracer), and the verdict: *dominated* (exact ray tracing is better \
         in the same time), *beats exact*, *within noise*, or *faster than exact* (no exact \
         image is as fast). *Frame ms* is the steady frame, every pass that runs each frame; \
         *per change ms* is paid once per light or object change (impostor maps, the eikonal \
         light simulation, the tracers' BVH, Wyman's d_N) and is in no frame, nor in the \
         equal-time verdict.\n\n\
         | scene | effect | best approximation | frame ms | per change ms | FLIP mean | exact FLIP at equal time | verdict |\n\
         |---|---|---|---:|---:|---:|---:|---|\n"
    );
    for r in rows {
        t.push_str(&r.line);
        t.push('\n');
    }
    t.push('\n');
    t
}

/// The report's title and first paragraph, which states the image size, samples per pixel
/// and photons of the commands its `sections` name in their provenance lines (with `--only`
/// they differ from section to section).
fn header(frames: u32, warmup: u32, sections: &str) -> String {
    let mut commands: Vec<(&str, usize)> = Vec::new();
    for line in sections.lines() {
        let Some(command) = line.strip_prefix("*Measured at git revision ").and_then(|l| {
            let start = l.find(" with `")? + " with `".len();
            l[start..].strip_suffix("`.*")
        }) else {
            continue;
        };
        match commands.iter_mut().find(|(c, _)| *c == command) {
            Some((_, n)) => *n += 1,
            None => commands.push((command, 1)),
        }
    }
    let settings = |command: &str| {
        let flag = |name: &str| {
            let mut words = command.split_whitespace();
            words.find(|w| *w == name).and_then(|_| words.next()).unwrap_or("?").to_string()
        };
        let size = flag("--size");
        // The flags after these three (the exact curve's, where not the defaults).
        let rest: Vec<&str> = command.split_whitespace().skip_while(|w| *w != "--photons").skip(2).collect();
        let rest = if rest.is_empty() { String::new() } else { format!(" ({})", rest.join(" ")) };
        format!("{size}x{size}, {} spp, {} photons{rest}", flag("--spp"), flag("--photons"))
    };
    let measured = match commands.as_slice() {
        [] => "none measured yet".to_string(),
        [(command, _)] => settings(command),
        _ => {
            let each: Vec<String> = commands
                .iter()
                .map(|(c, n)| format!("{} in {n} section{}", settings(c), if *n == 1 { "" } else { "s" }))
                .collect();
            format!("{} (each section's last line names its command)", each.join("; "))
        }
    };
    format!(
        "# Accuracy against the exact reference\n\n\
         Generated by `prism report` from [report.toml](report.toml); do not edit by hand. \
         Every row is measured: the scene is rendered with the technique and setting shown \
         (on top of report.toml's `set`, the baseline techniques, not the scene file's own), \
         timed over {frames} frames after {warmup} warm-up frames (GPU timestamps, median), and \
         compared with prism's exact reference of the same scene. Image size, the reference's \
         samples per pixel and its photons for caustics: {measured}. Errors are on linear \
         radiance (RMSE, relMSE) and on the tone-mapped images (FLIP, mean and 95th percentile; \
         0 = identical, 1 = maximal); HDR-FLIP is FLIP's largest value per pixel over a range of \
         exposures of the linear images (README, `prism compare`).\n\n"
    )
}

/// The markers of the report's hand-written block (the reference's convergence study), which
/// `prism report` keeps after its header: it measures the reference, not the techniques.
const HAND_WRITTEN: [&str; 2] = ["<!-- hand-written:", "<!-- end of the hand-written block -->"];

/// The hand-written block of an existing report, markers included.
fn hand_written(text: &str) -> Option<&str> {
    let start = text.find(HAND_WRITTEN[0])?;
    let end = start + text[start..].find(HAND_WRITTEN[1])? + HAND_WRITTEN[1].len();
    Some(&text[start..end])
}

/// A short stable name for an entry's files (FNV-1a of its scene, title and parameters).
fn entry_hash(e: &Entry) -> String {
    let mut h: u64 = 0xcbf29ce484222325;
    for b in e.scene.bytes().chain(e.title.bytes()).chain(e.params.iter().flat_map(|p| p.bytes())) {
        h = (h ^ b as u64).wrapping_mul(0x100000001b3);
    }
    format!("{:08x}", h as u32)
}

/// The body of a section `--only` skipped and no earlier report measured.
const NOT_MEASURED: &str = "Not measured yet:";

/// The sections of an existing report, to keep those that `--only` does not measure.
struct Previous {
    /// Heading line and the whole section (heading included, up to the next heading).
    sections: Vec<(String, String)>,
    /// "git revision X" of the file's header, for sections that do not name their own.
    revision: Option<String>,
    command: Option<String>,
}

impl Previous {
    fn parse(text: &str) -> Previous {
        let revision = text.lines().find_map(|l| {
            let rest = &l[l.find("git revision ")? + "git revision ".len()..];
            Some(rest.trim_end_matches('.').to_string())
        });
        let command = text.lines().find_map(|l| l.strip_prefix("Command: `")?.strip_suffix('`').map(str::to_string));
        let mut sections: Vec<(String, String)> = Vec::new();
        for line in text.lines() {
            if line.starts_with("## ") {
                sections.push((line.to_string(), String::new()));
            }
            if let Some((_, body)) = sections.last_mut() {
                body.push_str(line);
                body.push('\n');
            }
        }
        Previous { sections, revision, command }
    }

    /// The summary table's row for `scene` and `effect`.
    fn summary_line(&self, scene: &str, effect: &str) -> Option<String> {
        let (_, body) = self.sections.iter().find(|(h, _)| h == SUMMARY_HEADING)?;
        let prefix = format!("| {scene} | {effect} |");
        let line = body.lines().find(|l| l.starts_with(&prefix))?;
        // A row of seven cells (from a report without the per change column) gets an unknown
        // one after its frame ms, so that the kept row lines up with the header.
        if line.matches(" | ").count() == 6 {
            let cells: Vec<&str> = line.split(" | ").collect();
            return Some(format!("{} | – | {}", cells[..4].join(" | "), cells[4..].join(" | ")));
        }
        Some(line.to_string())
    }

    /// The section under `heading`, with a provenance line added if it has none; `None` for a
    /// section that was never measured (its placeholder is written afresh, without a
    /// provenance line that would claim a measurement).
    fn section(&self, heading: &str) -> Option<String> {
        let (_, body) = self.sections.iter().find(|(h, _)| h == heading)?;
        if body.contains(NOT_MEASURED) {
            return None;
        }
        if body.contains("*Measured at git revision") {
            return Some(body.clone());
        }
        let mut body = body.trim_end().to_string();
        body.push_str(&format!(
            "\n\n*Measured at git revision {} with `{}`.*\n\n",
            self.revision.as_deref().unwrap_or("unknown"),
            self.command.as_deref().unwrap_or("prism report")
        ));
        Some(body)
    }
}

#[cfg(test)]
mod tests {
    use super::Previous;
    use crate::app::compare::Measurement;
    use crate::app::equaltime::{Exact, ExactCurve, ExactPoint, ExactSource, Noise};
    use crate::metrics::image::ErrorMetrics;
    use crate::metrics::paired::Paired;
    use crate::metrics::timing::Stats;

    fn measurement(time_ms: f64, flip: f64) -> Measurement {
        Measurement {
            passes: Vec::new(),
            frame: Stats { median_ms: time_ms, ..Default::default() },
            per_change: Default::default(),
            frame_starts_ms: Vec::new(),
            errors: ErrorMetrics { flip_mean: flip, ..Default::default() },
            mask: Default::default(),
            hdr: Vec::new(),
            ldr: Vec::new(),
            heatmap: Vec::new(),
        }
    }

    fn exact(noise_flip: f64) -> Exact {
        let point = |t: f64, flip: f64| ExactPoint {
            label: format!("{t}"),
            time_ms: t,
            errors: ErrorMetrics { flip_mean: flip, ..Default::default() },
            errors_mask: None,
            frame_starts_ms: Vec::new(),
            photons: None,
        };
        Exact {
            curve: ExactCurve { source: ExactSource::Raytrace, points: vec![point(10.0, 0.2), point(100.0, 0.02)] },
            noise: Noise {
                between_references: ErrorMetrics {
                    flip_mean: noise_flip * std::f64::consts::SQRT_2,
                    ..Default::default()
                },
            },
        }
    }

    /// The summary names the best technique of an entry comparing techniques at defaults,
    /// those within noise of it, the exact tracer's FLIP at its time (log-log interpolated:
    /// 0.2 at 10 ms, 0.02 at 100 ms give 0.2 * 10^(-log10(5)) = 0.04 at 50 ms) and the verdict;
    /// the summary table keeps rows of entries not measured now from the existing file.
    #[test]
    fn summary_row_on_synthetic_data_and_kept_by_only() {
        let e = super::Entry {
            scene: "sphere_env".into(),
            title: "t".into(),
            params: vec!["render.refraction=single,wyman,hu_qin".into()],
        };
        let settings: Vec<Vec<String>> =
            ["single", "wyman", "hu_qin"].iter().map(|t| vec![format!("render.refraction={t}")]).collect();
        let ms = [measurement(20.0, 0.3), measurement(50.0, 0.101), measurement(50.0, 0.1)];
        let rows: Vec<_> = settings.iter().map(|s| s.as_slice()).zip(ms.iter()).collect();
        let techniques: Vec<String> = vec!["a".into(), "b".into(), "c".into()];
        let x = exact(0.005);
        let r = super::summary_row(&e, &rows, &techniques, Some(&x), None).unwrap().unwrap();
        assert_eq!(
            r.line,
            "| sphere_env | refraction | `hu_qin` (within noise: `wyman`) | 50.00 | 0.00 | 0.1000 (0.0950–0.1000) | 0.0400 | dominated |"
        );
        // Paired against the reference they share, wyman's 0.001 more is 10 standard errors:
        // ranked, though the intervals overlap; single's is within its (large) standard error.
        let paired = |difference: f64, standard_error: f64| {
            let p = Paired { difference, standard_error, bias: 0.0 };
            Some((p, p))
        };
        let ranking = super::Ranking { best: 2, pairs: vec![paired(0.2, 0.1), paired(0.001, 0.0001), None] };
        let r = super::summary_row(&e, &rows, &techniques, Some(&x), Some(&ranking)).unwrap().unwrap();
        assert_eq!(
            r.line,
            "| sphere_env | refraction | `hu_qin` (within noise: `single`) | 50.00 | 0.00 | 0.1000 (0.0950–0.1000) | 0.0400 | dominated |"
        );
        // An entry that sweeps a parameter has no summary row.
        let sweep = super::Entry { params: vec!["render.hu_qin.search_steps=2,4".into()], ..e };
        assert!(super::summary_row(&sweep, &rows, &techniques, Some(&x), None).unwrap().is_none());
        // `--only` keeps the rows of entries it does not measure.
        let text = format!("# A\n\n{}## sphere_env: t\n\nbody\n", super::summary_table(&[r]));
        let p = Previous::parse(&text);
        assert!(p.summary_line("sphere_env", "refraction").unwrap().ends_with("| dominated |"));
        assert_eq!(p.summary_line("sphere_env", "caustics"), None);
        // A row kept from a report without the per change column gets an unknown one.
        let old = "| a | refraction | `wyman` | 20.00 | 0.1000 (0.0950–0.1000) | 0.0400 | dominated |";
        let p = Previous::parse(&format!("{}\n\n{old}\n", super::SUMMARY_HEADING));
        assert_eq!(
            p.summary_line("a", "refraction").unwrap(),
            "| a | refraction | `wyman` | 20.00 | – | 0.1000 (0.0950–0.1000) | 0.0400 | dominated |"
        );
    }

    /// Differences too small for the table's decimals keep two significant digits.
    #[test]
    fn small_differences_keep_their_digits() {
        assert_eq!(super::digits(0.0504, 4, true), "+0.0504");
        assert_eq!(super::digits(-0.00003, 4, true), "-3.0e-5");
        assert_eq!(super::digits(0.000004, 5, false), "4.0e-6");
        assert_eq!(super::digits(0.0, 4, false), "0.0000");
    }

    /// A kept section gains the file's provenance line; a placeholder never does (it was not
    /// measured), so the next report writes it afresh.
    #[test]
    fn kept_sections_name_their_revision_and_placeholders_stay_unmeasured() {
        let text =
            "Command: `prism report --size 128`\nMeasured at git revision abc123.\n\n## a: measured\n\n| row |\n\n\
                    ## b: skipped\n\nNot measured yet: run `prism report --only b`.\n\n\
                    *Measured at git revision def456 with `prism report`.*\n";
        let p = Previous::parse(text);
        let a = p.section("## a: measured").unwrap();
        assert!(a.contains("*Measured at git revision abc123 with `prism report --size 128`.*"), "{a}");
        assert_eq!(p.section("## b: skipped"), None);
        assert_eq!(p.section("## c: absent"), None);
    }

    #[test]
    fn the_hand_written_block_is_found_whole() {
        let text = "# A\n\nheader\n\n<!-- hand-written: kept -->\n## Study\n\n| x |\n<!-- end of the hand-written block -->\n\n## b\n";
        let block = super::hand_written(text).unwrap();
        assert!(block.starts_with("<!-- hand-written:") && block.ends_with("block -->") && block.contains("| x |"));
        assert_eq!(super::hand_written("# A\n\n## b\n"), None);
    }

    /// The header of docs/ACCURACY.md states the settings its sections were measured with.
    #[test]
    fn accuracy_header_states_what_its_sections_used() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/ACCURACY.md");
        let text = std::fs::read_to_string(path).unwrap();
        let sections = &text[text.find("\n## ").unwrap()..];
        let expect = super::header(20, 5, sections);
        assert!(text.starts_with(&expect), "{path} should start with:\n{expect}");
    }
}
