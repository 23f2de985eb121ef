//! `prism sweep`: the speed-versus-accuracy trade of a technique's parameters. Every
//! combination of the given values (cartesian) is rendered, timed and compared with the
//! exact reference; one CSV row per setting, and a plot of error against time with the
//! Pareto front (the settings no other setting beats on both) marked, as SVG and PNG.
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;

use super::compare::{cached_reference, measure, print_measurement, MeasureArgs, Measurement};
use super::output::{self, Outputs};
use super::{check_validation, GpuArgs, SceneArgs};

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
    /// The error on the plot's y axis: flip_mean, flip_p95, rmse, rel_mse.
    #[arg(long, default_value = "flip_mean")]
    pub metric: String,
    #[command(flatten)]
    pub measure: MeasureArgs,
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
    Ok(match name {
        "flip_mean" => m.errors.flip_mean,
        "flip_p95" => m.errors.flip_p95,
        "rmse" => m.errors.rmse,
        "rel_mse" => m.errors.rel_mse,
        other => bail!("--metric {other}: expected flip_mean, flip_p95, rmse or rel_mse"),
    })
}

/// The size of a plot in pixels.
const PLOT_SIZE: (u32, u32) = (900, 600);

/// A scatter plot of (time, error) with labels and the Pareto front, as SVG text.
pub fn plot_svg(title: &str, y_label: &str, points: &[(f64, f64)], labels: &[String]) -> Result<String> {
    use plotters::prelude::{IntoDrawingArea, SVGBackend};
    register_font()?;
    let mut svg = String::new();
    draw_plot(SVGBackend::with_string(&mut svg, PLOT_SIZE).into_drawing_area(), title, y_label, points, labels)?;
    Ok(svg)
}

/// [`plot_svg`]'s plot as PNG bytes.
pub fn plot_png(title: &str, y_label: &str, points: &[(f64, f64)], labels: &[String]) -> Result<Vec<u8>> {
    use plotters::prelude::{BitMapBackend, IntoDrawingArea};
    register_font()?;
    let (w, h) = PLOT_SIZE;
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    draw_plot(BitMapBackend::with_buffer(&mut rgb, PLOT_SIZE).into_drawing_area(), title, y_label, points, labels)?;
    let img = image::RgbImage::from_raw(w, h, rgb).context("plot buffer has the wrong size")?;
    output::encode(image::DynamicImage::ImageRgb8(img), image::ImageFormat::Png)
}

fn draw_plot<DB: plotters::prelude::DrawingBackend>(
    root: plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    y_label: &str,
    points: &[(f64, f64)],
    labels: &[String],
) -> Result<()> {
    use plotters::prelude::*;
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow::anyhow!("plot: {e:?}");
    let front = pareto_front(points);
    root.fill(&WHITE).map_err(err)?;
    let (x_max, y_max) = points.iter().fold((0.0f64, 0.0f64), |a, p| (a.0.max(p.0), a.1.max(p.1)));
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..x_max * 1.15 + 1e-9, 0.0..y_max * 1.15 + 1e-9)
        .map_err(err)?;
    chart.configure_mesh().x_desc("GPU frame time, median (ms)").y_desc(y_label).draw().map_err(err)?;
    let mut f: Vec<(f64, f64)> = front.iter().map(|&i| points[i]).collect();
    f.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(f, RED.stroke_width(2)))
        .map_err(err)?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], RED.stroke_width(2)));
    chart
        .draw_series(points.iter().enumerate().map(|(i, &p)| {
            let on_front = front.contains(&i);
            Circle::new(p, if on_front { 5 } else { 4 }, if on_front { RED.filled() } else { BLUE.filled() })
        }))
        .map_err(err)?;
    chart
        .draw_series(points.iter().zip(labels).map(|(&p, l)| Text::new(l.clone(), p, ("sans-serif", 11))))
        .map_err(err)?;
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw().map_err(err)?;
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
}

/// The CSV: setting, each parameter's value, each pass's median ms, frame ms, errors, pareto.
pub fn csv(params: &[(String, Vec<String>)], rows: &[SweepRow], metric: &str) -> Result<String> {
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
    let quote = |s: &str| {
        if s.contains(',') || s.contains('"') {
            format!("\"{}\"", s.replace('"', "\"\""))
        } else {
            s.to_string()
        }
    };
    let mut csv = String::from("setting");
    for (k, _) in params {
        csv.push(',');
        csv.push_str(&quote(k));
    }
    for p in &passes {
        csv.push_str(&format!(",{p}_ms"));
    }
    csv.push_str(",frame_ms,rmse,psnr_db,rel_mse,flip_mean,flip_p95,pareto\n");
    for (i, r) in rows.iter().enumerate() {
        csv.push_str(&quote(&r.setting.join(" ")));
        for s in &r.setting {
            csv.push(',');
            csv.push_str(&quote(s.split_once('=').map(|x| x.1).unwrap_or("")));
        }
        for p in &passes {
            let v = r.measurement.passes.iter().find(|x| &x.name == p).map(|x| format!("{:.4}", x.stats.median_ms));
            csv.push(',');
            csv.push_str(&v.unwrap_or_default());
        }
        let e = &r.measurement.errors;
        csv.push_str(&format!(
            ",{:.4},{:.6},{:.3},{:.6},{:.5},{:.5},{}\n",
            r.measurement.frame.median_ms,
            e.rmse,
            e.psnr_db,
            e.rel_mse,
            e.flip_mean,
            e.flip_p95,
            front.contains(&i)
        ));
    }
    Ok(csv)
}

pub fn run(args: SweepArgs) -> Result<()> {
    let params = parse_params(&args.params)?;
    let settings = args.measure.reference.settings();
    settings.validate()?;
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
    let mut rows = Vec::new();
    for (o, scene) in rows_overrides.iter().zip(&scenes) {
        let (reference, _, _) = cached_reference(&ctx, scene, &settings, !args.measure.no_cache)?;
        let m = measure(&ctx, scene, &args.measure, &reference)?;
        println!("== {}", o.join(" "));
        print_measurement(&m);
        metric_of(&m, &args.metric)?;
        rows.push(SweepRow { setting: o.clone(), measurement: m });
    }
    check_validation(&ctx)?;
    let table = csv(&params, &rows, &args.metric)?;
    let points: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| Ok((r.measurement.frame.median_ms, metric_of(&r.measurement, &args.metric)?)))
        .collect::<Result<_>>()?;
    let labels: Vec<String> = rows.iter().map(|r| short_label(&r.setting)).collect();
    let title = format!("{}: {} against GPU time ({})", scenes[0].name, args.metric, ctx.info.name);
    // All outputs appear together, only once everything has succeeded.
    output::commit_all([
        csv_out.write(table.as_bytes())?,
        svg_out.write(plot_svg(&title, &args.metric, &points, &labels)?.as_bytes())?,
        png_out.write(&plot_png(&title, &args.metric, &points, &labels)?)?,
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
}
