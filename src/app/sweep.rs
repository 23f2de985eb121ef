//! `prism sweep`: the speed-versus-accuracy trade of a technique's parameters. Every
//! combination of the given values (cartesian) is rendered, timed and compared with the
//! exact reference; one CSV row per setting, and a plot of error against time with the
//! Pareto front (the settings no other setting beats on both) marked, as SVG and PNG.
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;

use super::compare::{cached_reference, print_measurement, MeasureArgs, Measurement};
use super::equaltime::{curve_spec, measure_interleaved, metric_value, reference_noise, Exact, ExactArgs, Setting};
use super::output::{self, Outputs};
use super::{check_validation, GpuArgs, SceneArgs};
use crate::metrics::image::ErrorMetrics;
use crate::scene::Scene;

#[derive(Args, Debug)]
pub struct SweepArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// A parameter and its values, KEY=V1,V2,... (repeatable; all combinations are measured).
    /// Commas inside brackets belong to the value: --param 'lights.0.position=[0,5,0],[1,5,1]'.
    #[arg(long = "param", value_name = "KEY=V1,V2,...", required = true)]
    pub params: Vec<String>,
    /// Output prefix: writes PREFIX.csv, PREFIX.svg and PREFIX.png.
    #[arg(short, long, default_value = "sweep")]
    pub out: String,
    /// The error on the plot's y axis: flip_mean, flip_p95, rmse, rel_mse, hdr_flip_mean,
    /// hdr_flip_p95.
    #[arg(long, default_value = "flip_mean")]
    pub metric: String,
    #[command(flatten)]
    pub measure: MeasureArgs,
    #[command(flatten)]
    pub exact: ExactArgs,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

/// Split "a,b,[1,2],c" at top-level commas.
pub fn split_values(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    let (mut depth, mut cur) = (0i32, String::new());
    for ch in s.chars() {
        match ch {
            '[' | '{' => depth += 1,
            ']' | '}' => depth -= 1,
            ',' if depth == 0 => {
                out.push(std::mem::take(&mut cur).trim().to_string());
                continue;
            }
            _ => {}
        }
        cur.push(ch);
    }
    out.push(cur.trim().to_string());
    out
}

/// Parse `--param` values into (key, values).
pub fn parse_params(params: &[String]) -> Result<Vec<(String, Vec<String>)>> {
    params
        .iter()
        .map(|p| {
            let Some((k, v)) = p.split_once('=') else {
                bail!("--param {p}: expected KEY=V1,V2,... (e.g. --param render.shadow_map_size=256,512,1024)");
            };
            let values = split_values(v);
            if k.trim().is_empty() || values.iter().any(|v| v.is_empty()) {
                bail!("--param {p}: empty key or value");
            }
            Ok((k.trim().to_string(), values))
        })
        .collect()
}

/// Every combination of the parameters' values, as lists of "key=value" overrides.
pub fn cartesian(params: &[(String, Vec<String>)]) -> Vec<Vec<String>> {
    let mut rows: Vec<Vec<String>> = vec![Vec::new()];
    for (k, values) in params {
        rows = rows
            .into_iter()
            .flat_map(|row| {
                values.iter().map(move |v| {
                    let mut r = row.clone();
                    r.push(format!("{k}={v}"));
                    r
                })
            })
            .collect();
    }
    rows
}

/// Indices of the points no other point beats in both coordinates (lower is better).
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    (0..points.len())
        .filter(|&i| {
            let (ti, ei) = points[i];
            !points.iter().enumerate().any(|(j, &(tj, ej))| j != i && tj <= ti && ej <= ei && (tj < ti || ej < ei))
        })
        .collect()
}

pub fn metric_of(m: &Measurement, name: &str) -> Result<f64> {
    metric_value(&m.errors, name)
}

/// The size of a plot in pixels.
const PLOT_SIZE: (u32, u32) = (900, 600);

/// One technique setting on a plot.
pub struct PlotPoint {
    pub time_ms: f64,
    pub error: f64,
    /// Its short label, printed only if it is on the Pareto front; every point is numbered
    /// (1-based, its row in the table beside the plot).
    pub label: String,
    /// The technique it renders with: points are coloured by it.
    pub technique: String,
}

/// The exact tracer's curve on a plot: (time, measured error, lowest error the reference's
/// noise allows) per point, drawn as a line with that band.
pub struct PlotExact {
    pub name: String,
    pub points: Vec<(f64, f64, f64)>,
}

/// The settings, the Pareto front and the exact curve: everything a plot shows.
pub struct Plot<'a> {
    pub title: &'a str,
    pub y_label: &'a str,
    pub points: &'a [PlotPoint],
    pub exact: Option<&'a PlotExact>,
}

/// An axis spanning more than a decade of positive values is drawn in log10.
fn wants_log(values: impl Iterator<Item = f64>) -> bool {
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |a, v| (a.0.min(v), a.1.max(v)));
    lo > 0.0 && hi / lo > 10.0
}

/// Point colours, one per technique: Tableau's ten categorical colours (grey, used by the
/// exact curve, left out), distinct on white and to most colour-blind readers.
const TECHNIQUE_COLOURS: [plotters::style::RGBColor; 9] = {
    use plotters::style::RGBColor as C;
    [
        C(31, 119, 180),
        C(255, 127, 14),
        C(44, 160, 44),
        C(214, 39, 40),
        C(148, 103, 189),
        C(140, 86, 75),
        C(227, 119, 194),
        C(188, 189, 34),
        C(23, 190, 207),
    ]
};

/// A tick label with three significant digits (25.1, 0.0631, 1200).
fn significant(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}

/// A scatter plot of (time, error) as SVG text.
pub fn plot_svg(plot: &Plot) -> Result<String> {
    use plotters::prelude::{IntoDrawingArea, SVGBackend};
    register_font()?;
    let mut svg = String::new();
    draw_plot(SVGBackend::with_string(&mut svg, PLOT_SIZE).into_drawing_area(), plot)?;
    Ok(svg)
}

/// [`plot_svg`]'s plot as PNG bytes.
pub fn plot_png(plot: &Plot) -> Result<Vec<u8>> {
    use plotters::prelude::{BitMapBackend, IntoDrawingArea};
    register_font()?;
    let (w, h) = PLOT_SIZE;
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    draw_plot(BitMapBackend::with_buffer(&mut rgb, PLOT_SIZE).into_drawing_area(), plot)?;
    let img = image::RgbImage::from_raw(w, h, rgb).context("plot buffer has the wrong size")?;
    output::encode(image::DynamicImage::ImageRgb8(img), image::ImageFormat::Png)
}

fn draw_plot<DB: plotters::prelude::DrawingBackend>(
    root: plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    plot: &Plot,
) -> Result<()> {
    use plotters::prelude::*;
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow::anyhow!("plot: {e:?}");
    let pts: Vec<(f64, f64)> = plot.points.iter().map(|p| (p.time_ms, p.error)).collect();
    let front = pareto_front(&pts);
    let exact: &[(f64, f64, f64)] = plot.exact.map(|e| e.points.as_slice()).unwrap_or(&[]);
    let xs = || pts.iter().map(|p| p.0).chain(exact.iter().map(|p| p.0));
    let ys = || pts.iter().map(|p| p.1).chain(exact.iter().map(|p| p.1));
    // Log axes are drawn by plotting log10 of the values on a linear axis and labelling the
    // ticks with the values themselves.
    let (log_x, log_y) = (wants_log(xs()), wants_log(ys()));
    let (min_y_pos, _) =
        ys().fold((f64::INFINITY, 0.0), |a: (f64, f64), v| (if v > 0.0 { a.0.min(v) } else { a.0 }, a.1));
    let fx = move |v: f64| if log_x { v.log10() } else { v };
    // A band reaching 0 is cut at a tenth of the smallest error on a log axis.
    let fy = move |v: f64| if log_y { v.max(min_y_pos * 0.1).log10() } else { v };
    let range = |it: &mut dyn Iterator<Item = f64>, log: bool| {
        let (lo, hi) = it.fold((f64::INFINITY, f64::NEG_INFINITY), |a, v| (a.0.min(v), a.1.max(v)));
        if !lo.is_finite() {
            return 0.0..1.0;
        }
        // Room on the right for the labels beside the points.
        if log {
            let span = (hi - lo).max(0.1);
            lo - span * 0.08..hi + span * 0.25
        } else {
            0.0..hi * 1.25 + 1e-9
        }
    };
    let x_range = range(&mut xs().map(fx), log_x);
    let y_range = range(&mut ys().chain(exact.iter().map(|p| p.2)).map(fy), log_y);
    root.fill(&WHITE).map_err(err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(plot.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x_range, y_range)
        .map_err(err)?;
    let tick = |log: bool| move |v: &f64| significant(if log { 10f64.powf(*v) } else { *v });
    let scale = |log: bool| if log { " (log scale)" } else { "" };
    chart
        .configure_mesh()
        .x_desc(format!("GPU frame time, median (ms){}", scale(log_x)))
        .y_desc(format!("{}{}", plot.y_label, scale(log_y)))
        .x_label_formatter(&tick(log_x))
        .y_label_formatter(&tick(log_y))
        .draw()
        .map_err(err)?;
    if let Some(e) = plot.exact {
        // The line and its band follow the exact points no other beats in time and error:
        // what the exact tracer reaches within a budget, and what the verdicts interpolate.
        let grey = RGBColor(120, 120, 120);
        let xy: Vec<(f64, f64)> = e.points.iter().map(|p| (p.0, p.1)).collect();
        let mut line: Vec<(f64, f64, f64)> = pareto_front(&xy).into_iter().map(|i| e.points[i]).collect();
        line.sort_by(|a, b| a.0.total_cmp(&b.0));
        let band: Vec<(f64, f64)> =
            line.iter().map(|p| (fx(p.0), fy(p.1))).chain(line.iter().rev().map(|p| (fx(p.0), fy(p.2)))).collect();
        chart.draw_series(std::iter::once(Polygon::new(band, grey.mix(0.25).filled()))).map_err(err)?;
        chart
            .draw_series(LineSeries::new(line.iter().map(|p| (fx(p.0), fy(p.1))), grey.stroke_width(2)))
            .map_err(err)?
            .label(format!("exact: {} (band: reference noise)", e.name))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], grey.stroke_width(2)));
        chart
            .draw_series(e.points.iter().map(|p| Cross::new((fx(p.0), fy(p.1)), 4, grey.stroke_width(2))))
            .map_err(err)?;
    }
    let mut f: Vec<(f64, f64)> = front.iter().map(|&i| (fx(pts[i].0), fy(pts[i].1))).collect();
    f.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(f, BLACK.mix(0.6).stroke_width(1)))
        .map_err(err)?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.mix(0.6).stroke_width(1)));
    let mut techniques: Vec<&str> = Vec::new();
    for p in plot.points {
        if !techniques.contains(&p.technique.as_str()) {
            techniques.push(&p.technique);
        }
    }
    for (k, t) in techniques.iter().enumerate() {
        let colour = TECHNIQUE_COLOURS[k % TECHNIQUE_COLOURS.len()];
        chart
            .draw_series(plot.points.iter().enumerate().filter(|(_, p)| p.technique == *t).map(|(i, p)| {
                let r = if front.contains(&i) { 6 } else { 4 };
                Circle::new((fx(p.time_ms), fy(p.error)), r, colour.filled())
            }))
            .map_err(err)?
            .label(t.to_string())
            .legend(move |(x, y)| Circle::new((x + 9, y), 4, colour.filled()));
    }
    // Only the front is labelled in full; the other points carry their row number.
    let mut front_order = front.clone();
    front_order.sort_by(|&a, &b| pts[a].0.total_cmp(&pts[b].0));
    chart
        .draw_series(plot.points.iter().enumerate().map(|(i, p)| {
            // Neighbours on the front alternate above and below their points, so that two
            // close labels do not overprint.
            let rank = front_order.iter().position(|&j| j == i);
            let text = if rank.is_some() { format!("{} {}", i + 1, p.label) } else { format!("{}", i + 1) };
            let dy = if rank.is_some_and(|r| r % 2 == 1) { 6 } else { -14 };
            EmptyElement::at((fx(p.time_ms), fy(p.error))) + Text::new(text, (6, dy), ("sans-serif", 12))
        }))
        .map_err(err)?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// Plot text needs a TrueType font: DejaVu Sans from Debian's fonts-dejavu-core.
fn register_font() -> Result<()> {
    static ONCE: std::sync::OnceLock<Result<(), String>> = std::sync::OnceLock::new();
    ONCE.get_or_init(|| {
        let candidates = [
            "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
            "/usr/share/fonts/TTF/DejaVuSans.ttf",
            "/usr/share/fonts/dejavu/DejaVuSans.ttf",
        ];
        let path = std::env::var("PRISM_PLOT_FONT")
            .ok()
            .or_else(|| candidates.iter().find(|p| Path::new(p).exists()).map(|s| s.to_string()));
        let Some(path) = path else {
            return Err("no font for plots: install fonts-dejavu-core or set PRISM_PLOT_FONT to a .ttf".into());
        };
        let bytes = std::fs::read(&path).map_err(|e| format!("{path}: {e}"))?;
        // The font lives for the whole process.
        let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
        plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, bytes)
            .map_err(|_| format!("{path}: not a usable TrueType font"))
    })
    .clone()
    .map_err(|e| anyhow::anyhow!(e))
}

/// "materials.glass.ior=1.5 render.hu_qin.search_steps=8" -> "ior=1.5 search_steps=8".
pub fn short_label(setting: &[String]) -> String {
    setting
        .iter()
        .map(|s| match s.split_once('=') {
            Some((k, v)) => format!("{}={v}", k.rsplit('.').next().unwrap_or(k)),
            None => s.clone(),
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// One measured row of a sweep.
pub struct SweepRow {
    pub setting: Vec<String>,
    pub measurement: Measurement,
    /// The technique it renders with (see [`technique_names`]).
    pub technique: String,
}

/// Reads one effect's technique from a scene.
type EffectTechnique = fn(&Scene) -> &str;

/// Each scene's technique, named by the effects whose technique differs between the scenes
/// ("refraction=wyman"); the refraction technique when none differs.
pub fn technique_names(scenes: &[&Scene]) -> Vec<String> {
    let effects: [(&str, EffectTechnique); 3] = [
        ("refraction", |s| s.render.refraction.as_str()),
        ("reflection", |s| s.render.reflection.as_str()),
        ("caustics", |s| s.render.caustics.as_str()),
    ];
    let varying: Vec<_> = effects.iter().filter(|(_, get)| scenes.iter().any(|s| get(s) != get(scenes[0]))).collect();
    scenes
        .iter()
        .map(|s| {
            if varying.is_empty() {
                format!("refraction={}", s.render.refraction)
            } else {
                varying.iter().map(|(name, get)| format!("{name}={}", get(s))).collect::<Vec<_>>().join(" ")
            }
        })
        .collect()
}

/// The exact curve as a plot draws it, in `metric` with the reference's noise band.
pub fn plot_exact(exact: &Exact, metric: &str) -> Result<PlotExact> {
    // A photon curve names its budgets: its points' labels are not drawn.
    let budgets: Vec<u64> = exact.curve.points.iter().filter_map(|p| p.photons.map(|b| b.photons)).collect();
    let name = match (budgets.first(), budgets.last()) {
        (Some(a), Some(b)) => format!("{}, {a} to {b} photons", exact.curve.source.name()),
        _ => exact.curve.source.name().to_string(),
    };
    let points = exact
        .curve
        .points
        .iter()
        .map(|p| {
            let v = metric_value(&p.errors, metric)?;
            Ok((p.time_ms, v, exact.noise.interval(metric, v).0))
        })
        .collect::<Result<_>>()?;
    Ok(PlotExact { name, points })
}

fn quote(s: &str) -> String {
    if s.contains(',') || s.contains('"') {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The CSV: one row per setting (kind `technique`, numbered as on the plot) and, with an
/// exact curve, one per exact point (kind `exact`): each parameter's value, each pass's median
/// ms over the steady frames, frame ms (the steady frame: every pass that runs each frame),
/// per change ms (paid once per light or object change, not in frame ms:
/// [`super::compare::PerChange`]; empty on an exact row, whose time is a frame's), errors, the mask's pixel count, the errors over it and its surfaces
/// (`mask_*`; an exact row gives only the errors, over the settings' mask; empty where no
/// masked surface is in view), whether on the Pareto front, the
/// technique, the lowest value of
/// `metric` the reference's noise allows, the exact tracer's `metric` at the same time and the
/// equal-time verdict.
pub fn csv(params: &[(String, Vec<String>)], rows: &[SweepRow], metric: &str, exact: Option<&Exact>) -> Result<String> {
    let mut passes: Vec<String> = Vec::new();
    for r in rows {
        for p in &r.measurement.passes {
            if !passes.contains(&p.name) {
                passes.push(p.name.clone());
            }
        }
    }
    let points: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| Ok((r.measurement.frame.median_ms, metric_of(&r.measurement, metric)?)))
        .collect::<Result<_>>()?;
    let front = pareto_front(&points);
    let mut csv = String::from("n,kind,setting");
    for (k, _) in params {
        csv.push(',');
        csv.push_str(&quote(k));
    }
    for p in &passes {
        csv.push_str(&format!(",{p}_ms"));
    }
    csv.push_str(&format!(
        ",frame_ms,per_change_ms,rmse,psnr_db,rel_mse,flip_mean,flip_p95,mask_pixels,mask_rmse,mask_psnr_db,mask_rel_mse,\
         mask_flip_mean,mask_flip_p95,mask_surfaces,pareto,technique,{metric}_low,exact_{metric},verdict,\
         hdr_flip_mean,hdr_flip_p95,mask_hdr_flip_mean,mask_hdr_flip_p95\n"
    ));
    let errors = |e: &ErrorMetrics| {
        format!(",{:.6},{:.3},{:.6},{:.5},{:.5}", e.rmse, e.psnr_db, e.rel_mse, e.flip_mean, e.flip_p95)
    };
    // HDR-FLIP, whole and over the mask: appended after the columns that existed before it, so
    // that readers of those keep their positions.
    let hdr = |e: &ErrorMetrics, mask: Option<&ErrorMetrics>| {
        let m = mask.map(|m| format!("{:.5},{:.5}", m.hdr_flip_mean, m.hdr_flip_p95)).unwrap_or_else(|| ",".into());
        format!(",{:.5},{:.5},{m}\n", e.hdr_flip_mean, e.hdr_flip_p95)
    };
    for (i, r) in rows.iter().enumerate() {
        csv.push_str(&format!("{},technique,{}", i + 1, quote(&r.setting.join(" "))));
        for s in &r.setting {
            csv.push(',');
            csv.push_str(&quote(s.split_once('=').map(|x| x.1).unwrap_or("")));
        }
        for p in &passes {
            let v = r.measurement.passes.iter().find(|x| &x.name == p).map(|x| format!("{:.4}", x.stats.median_ms));
            csv.push(',');
            csv.push_str(&v.unwrap_or_default());
        }
        csv.push_str(&format!(",{:.4},{:.4}", r.measurement.frame.median_ms, r.measurement.per_change.ms));
        csv.push_str(&errors(&r.measurement.errors));
        csv.push_str(&format!(",{}", r.measurement.mask.mask_pixels));
        csv.push_str(&r.measurement.mask.errors_mask.as_ref().map(errors).unwrap_or_else(|| ",".repeat(5)));
        csv.push(',');
        csv.push_str(&quote(&r.measurement.mask.mask_surfaces.join("; ")));
        csv.push_str(&format!(",{},{}", front.contains(&i), quote(&r.technique)));
        match exact {
            Some(x) => {
                let value = metric_of(&r.measurement, metric)?;
                let eq = x.equal_time(metric, &r.measurement)?;
                let at = eq.exact.map(|a| format!("{:.6}", a.error)).unwrap_or_default();
                csv.push_str(&format!(",{:.6},{at},{}", x.noise.interval(metric, value).0, eq.verdict.as_str()));
            }
            None => csv.push_str(",,,"),
        }
        csv.push_str(&hdr(&r.measurement.errors, r.measurement.mask.errors_mask.as_ref()));
    }
    if let Some(x) = exact {
        let name = x.curve.source.name();
        for p in &x.curve.points {
            csv.push_str(&format!(",exact,{}", quote(&format!("{name} {}", p.label))));
            csv.push_str(&",".repeat(params.len() + passes.len()));
            csv.push_str(&format!(",{:.4},", p.time_ms));
            csv.push_str(&errors(&p.errors));
            // The mask's pixels and surfaces are the settings' rows'.
            csv.push(',');
            csv.push_str(&p.errors_mask.as_ref().map(errors).unwrap_or_else(|| ",".repeat(5)));
            csv.push(',');
            let value = metric_value(&p.errors, metric)?;
            csv.push_str(&format!(",,{name},{:.6},,", x.noise.interval(metric, value).0));
            csv.push_str(&hdr(&p.errors, p.errors_mask.as_ref()));
        }
    }
    Ok(csv)
}

pub fn run(args: SweepArgs) -> Result<()> {
    let params = parse_params(&args.params)?;
    let settings = args.measure.reference.settings();
    settings.validate()?;
    metric_value(&Default::default(), &args.metric)?;
    // Check the metric name and every combination's scene before any GPU work.
    let rows_overrides = cartesian(&params);
    let mut scenes = Vec::new();
    for o in &rows_overrides {
        let mut sa = args.scene.clone();
        sa.set.extend(o.iter().cloned());
        scenes.push(sa.load().with_context(|| format!("setting {}", o.join(" ")))?);
    }
    let (csv_path, svg_path, png_path) = (
        PathBuf::from(format!("{}.csv", args.out)),
        PathBuf::from(format!("{}.svg", args.out)),
        PathBuf::from(format!("{}.png", args.out)),
    );
    let mut outputs = Outputs::default();
    let csv_out = outputs.prepare(&csv_path)?;
    let svg_out = outputs.prepare(&svg_path)?;
    let png_out = outputs.prepare(&png_path)?;
    let ctx = args.gpu.context()?;
    let techniques = technique_names(&scenes.iter().collect::<Vec<_>>());
    // The exact tracer on the first setting's scene: the settings a sweep compares usually
    // share it (a swept scene parameter changes the truth, and the curve is that of the first).
    let spec = if args.exact.no_exact {
        None
    } else {
        let mut sa = args.scene.clone();
        sa.set.extend(rows_overrides[0].iter().cloned());
        Some(curve_spec(&sa, &args.measure, &args.exact, &scenes)?)
    };
    let references: Vec<Vec<f32>> = scenes
        .iter()
        .map(|scene| Ok(cached_reference(&ctx, scene, &settings, args.measure.reference_policy())?.image))
        .collect::<Result<_>>()?;
    let noise = match &spec {
        Some(_) => Some(reference_noise(&ctx, &scenes[0], &settings, &references[0], args.measure.reference_policy())?),
        None => None,
    };
    // Every setting and the exact points timed interleaved (src/app/equaltime.rs).
    let timed: Vec<Setting> =
        scenes.iter().zip(&references).map(|(scene, reference)| Setting { scene, reference }).collect();
    let (measured, curve) =
        measure_interleaved(&ctx, &timed, &args.measure, spec.as_ref().map(|s| (s, references[0].as_slice())))?;
    let exact = curve.zip(noise).map(|(curve, noise)| Exact { curve, noise });
    let mut rows = Vec::new();
    for ((o, m), technique) in rows_overrides.iter().zip(measured).zip(techniques) {
        println!("== {}", o.join(" "));
        print_measurement(&m);
        rows.push(SweepRow { setting: o.clone(), measurement: m, technique });
    }
    check_validation(&ctx)?;
    if let Some(x) = &exact {
        println!("exact tracer: {}", x.curve.describe());
        for (i, r) in rows.iter().enumerate() {
            let eq = x.equal_time(&args.metric, &r.measurement)?;
            let at = eq.exact.map(|a| format!("{:.4}", a.error)).unwrap_or_else(|| "-".into());
            println!(
                "#{} {}: exact {} at equal time {at}: {}",
                i + 1,
                r.setting.join(" "),
                args.metric,
                eq.verdict.as_str()
            );
        }
    }
    let table = csv(&params, &rows, &args.metric, exact.as_ref())?;
    let points: Vec<PlotPoint> = rows
        .iter()
        .map(|r| {
            Ok(PlotPoint {
                time_ms: r.measurement.frame.median_ms,
                error: metric_of(&r.measurement, &args.metric)?,
                label: short_label(&r.setting),
                technique: r.technique.clone(),
            })
        })
        .collect::<Result<_>>()?;
    let plot_exact = exact.as_ref().map(|x| plot_exact(x, &args.metric)).transpose()?;
    let title = format!("{}: {} against GPU time ({})", scenes[0].name, args.metric, ctx.info.name);
    let plot = Plot { title: &title, y_label: &args.metric, points: &points, exact: plot_exact.as_ref() };
    // All outputs appear together, only once everything has succeeded.
    output::commit_all([
        csv_out.write(table.as_bytes())?,
        svg_out.write(plot_svg(&plot)?.as_bytes())?,
        png_out.write(&plot_png(&plot)?)?,
    ])?;
    eprintln!("wrote {}, {}, {}", csv_path.display(), svg_path.display(), png_path.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_split_at_top_level_commas_and_combine_cartesian() {
        assert_eq!(split_values("1,2, 3"), ["1", "2", "3"]);
        assert_eq!(split_values("[0,5,0],[1,5,1]"), ["[0,5,0]", "[1,5,1]"]);
        let p = parse_params(&["a=1,2".into(), "b=x,y,z".into()]).unwrap();
        let rows = cartesian(&p);
        assert_eq!(rows.len(), 6);
        assert_eq!(rows[0], ["a=1", "b=x"]);
        assert_eq!(rows[5], ["a=2", "b=z"]);
        assert!(parse_params(&["novalues".into()]).is_err());
    }

    #[test]
    fn pareto_front_keeps_the_undominated() {
        let pts = [(1.0, 5.0), (2.0, 3.0), (3.0, 4.0), (4.0, 1.0), (2.0, 3.0)];
        // (3,4) is beaten by (2,3); the two equal points do not dominate each other.
        assert_eq!(pareto_front(&pts), [0, 1, 3, 4]);
    }

    fn row(setting: &str, time_ms: f64, flip: f64, technique: &str) -> SweepRow {
        SweepRow {
            setting: vec![setting.to_string()],
            measurement: Measurement {
                passes: Vec::new(),
                frame: crate::metrics::timing::Stats { median_ms: time_ms, ..Default::default() },
                per_change: Default::default(),
                frame_starts_ms: Vec::new(),
                errors: crate::metrics::image::ErrorMetrics { flip_mean: flip, ..Default::default() },
                mask: Default::default(),
                hdr: Vec::new(),
                ldr: Vec::new(),
                heatmap: Vec::new(),
            },
            technique: technique.to_string(),
        }
    }

    /// The CSV numbers the settings, adds the exact curve's rows and each setting's verdict;
    /// the plot labels only the Pareto front in full, numbers the rest, colours by technique,
    /// draws the exact curve with its band, and turns to log axes over more than a decade.
    #[test]
    fn csv_and_plot_structure_with_an_exact_curve() {
        use crate::app::equaltime::{ExactCurve, ExactPoint, ExactSource, Noise};
        use crate::metrics::image::ErrorMetrics;
        let params = parse_params(&["render.refraction=single,wyman,hu_qin".into()]).unwrap();
        let mut rows = [
            row("render.refraction=single", 10.0, 0.30, "refraction=single"),
            row("render.refraction=wyman", 40.0, 0.35, "refraction=wyman"),
            row("render.refraction=hu_qin", 400.0, 0.02, "refraction=hu_qin"),
        ];
        rows[0].measurement.mask = crate::app::compare::MaskErrors {
            errors_mask: Some(ErrorMetrics {
                rmse: 0.5,
                flip_mean: 0.6,
                hdr_flip_mean: 0.8,
                hdr_flip_p95: 0.9,
                ..Default::default()
            }),
            mask_pixels: 120,
            mask_surfaces: vec!["ball (dielectric): 100 px".into(), "floor (diffuse caustic receiver): 20 px".into()],
        };
        rows[2].measurement.per_change = crate::app::compare::PerChange { ms: 12.5, costs: Vec::new() };
        rows[0].measurement.errors.hdr_flip_mean = 0.7;
        let point = |label: &str, t: f64, flip: f64| ExactPoint {
            label: label.into(),
            time_ms: t,
            errors: ErrorMetrics { flip_mean: flip, ..Default::default() },
            errors_mask: (t > 100.0).then_some(ErrorMetrics { rmse: 0.25, ..Default::default() }),
            frame_starts_ms: Vec::new(),
            photons: None,
        };
        let exact = Exact {
            curve: ExactCurve {
                source: ExactSource::Raytrace,
                points: vec![point("max_depth=1", 20.0, 0.25), point("max_depth=16", 200.0, 0.05)],
            },
            noise: Noise::default(),
        };
        let text = csv(&params, &rows, "flip_mean", Some(&exact)).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 1 + 3 + 2, "{text}");
        assert_eq!(
            lines[0],
            "n,kind,setting,render.refraction,frame_ms,per_change_ms,rmse,psnr_db,rel_mse,flip_mean,flip_p95,mask_pixels,\
             mask_rmse,mask_psnr_db,mask_rel_mse,mask_flip_mean,mask_flip_p95,mask_surfaces,pareto,technique,\
             flip_mean_low,exact_flip_mean,verdict,hdr_flip_mean,hdr_flip_p95,mask_hdr_flip_mean,mask_hdr_flip_p95"
        );
        let columns = lines[0].split(',').count();
        assert!(lines.iter().all(|l| l.split(',').count() == columns), "{text}");
        assert!(
            lines[1].starts_with("1,technique,render.refraction=single,single,")
                && lines[1].ends_with(",,faster than exact,0.70000,0.00000,0.80000,0.90000"),
            "{}",
            lines[1]
        );
        assert!(
            lines[1].contains(
                ",120,0.500000,0.000,0.000000,0.60000,0.00000,\
                 ball (dielectric): 100 px; floor (diffuse caustic receiver): 20 px,true,"
            ),
            "{}",
            lines[1]
        );
        assert!(lines[2].contains(",0,,,,,,,false,"), "no mask errors: {}", lines[2]);
        // Frame ms, then per change ms beside it.
        assert!(lines[1].contains(",10.0000,0.0000,") && lines[3].contains(",400.0000,12.5000,"), "{text}");
        // HDR-FLIP after the verdict (no mask errors: no mask HDR-FLIP). wyman at 40 ms: exact
        // reaches 0.25 * 0.2^(log 2 / log 10) = 0.1540 < 0.35.
        assert!(
            lines[2].ends_with(",false,refraction=wyman,0.350000,0.154003,dominated,0.00000,0.00000,,"),
            "{}",
            lines[2]
        );
        assert!(
            lines[3].ends_with(",true,refraction=hu_qin,0.020000,0.050000,beats exact,0.00000,0.00000,,"),
            "{}",
            lines[3]
        );
        assert!(lines[4].starts_with(",exact,raytrace max_depth=1,,20.0000,,"), "{}", lines[4]);
        assert!(lines[4].contains(",0.25000,0.00000,,,,,,,,,raytrace,"), "no mask errors: {}", lines[4]);
        assert!(
            lines[5].contains(",0.05000,0.00000,,0.250000,0.000,0.000000,0.00000,0.00000,,,raytrace,"),
            "{}",
            lines[5]
        );
        assert!(lines[4].ends_with(",,raytrace,0.250000,,,0.00000,0.00000,,"), "{}", lines[4]);
        assert!(lines[5].ends_with(",,raytrace,0.050000,,,0.00000,0.00000,0.00000,0.00000"), "{}", lines[5]);
        let points: Vec<PlotPoint> = rows
            .iter()
            .map(|r| PlotPoint {
                time_ms: r.measurement.frame.median_ms,
                error: r.measurement.errors.flip_mean,
                label: short_label(&r.setting),
                technique: r.technique.clone(),
            })
            .collect();
        let pe = plot_exact(&exact, "flip_mean").unwrap();
        let svg = plot_svg(&Plot { title: "t", y_label: "FLIP mean", points: &points, exact: Some(&pe) }).unwrap();
        let texts: Vec<&str> =
            svg.split("</text>").filter_map(|t| t.rsplit_once('>').map(|(_, text)| text.trim())).collect();
        // Full labels on the front (1 and 3), a bare number for the dominated setting 2.
        assert!(texts.contains(&"1 refraction=single") && texts.contains(&"3 refraction=hu_qin"), "{texts:?}");
        assert!(texts.contains(&"2") && !texts.contains(&"2 refraction=wyman"), "{texts:?}");
        assert!(texts.iter().any(|t| t.starts_with("exact: raytrace")) && texts.contains(&"Pareto front"));
        assert!(svg.contains("<polygon"), "the exact curve's band");
        // Times 10 to 400 ms and errors 0.02 to 0.35 span more than a decade: log axes.
        assert!(texts.contains(&"GPU frame time, median (ms) (log scale)") && texts.contains(&"FLIP mean (log scale)"));
        // Three techniques, three fill colours for the points.
        let fills: std::collections::HashSet<&str> =
            svg.split("<circle").skip(1).filter_map(|c| c.split("fill=\"").nth(1)?.split('"').next()).collect();
        assert!(fills.len() >= 3, "{fills:?}");
    }
}
