//! `prism bench`: per-pass GPU timings over many frames, as a table, JSON and a Chrome
//! trace-event file (open it in Perfetto or chrome://tracing).
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use crate::gpu::DeviceInfo;
use crate::metrics::timing::Stats;
use crate::renderer::{FrameTiming, Renderer};

use super::output::{self, Outputs};
use super::{check_validation, GpuArgs, SceneArgs};

/// The most frames `--frames` or `--warmup` may ask for (bench, compare, sweep, report):
/// every frame's pass timings (some 1 KiB with their names) stay in memory until the end, and
/// a million frames is already hours on lavapipe.
pub const MAX_FRAMES: i64 = 1_000_000;

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Frames to measure (at most 1000000).
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(..=MAX_FRAMES))]
    pub frames: u32,
    /// Frames rendered first and not measured (pipeline caches, clocks; at most 1000000).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(..=MAX_FRAMES))]
    pub warmup: u32,
    /// Write the results as JSON (device, driver, resolution, git revision, settings, stats).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Write a Chrome trace-event JSON of every measured frame (Perfetto opens it).
    #[arg(long, value_name = "FILE")]
    pub trace: Option<PathBuf>,
    /// Every N frames, print resident memory and GPU allocator usage to stderr (scripts/soak).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub stats: Option<u64>,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

#[derive(Serialize, Debug)]
pub struct PassStats {
    pub name: String,
    #[serde(flatten)]
    pub stats: Stats,
}

#[derive(Serialize, Debug)]
pub struct BenchReport {
    pub scene: String,
    pub scene_file: String,
    pub device: DeviceInfo,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub warmup: u32,
    pub git_revision: String,
    pub settings: Vec<String>,
    /// The effective scene (after overrides), as TOML.
    pub scene_toml: String,
    pub passes: Vec<PassStats>,
    pub frame: Stats,
    /// The eikonal light simulation (run once when the renderer is created): steps, patch
    /// count per step, patch-steps, peak, GPU ms per kernel, wall-clock seconds. Absent
    /// without one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_simulation: Option<crate::technique::eikonal::eikonal_light::LightStats>,
    pub note: &'static str,
}

/// `git describe`-like revision of the source tree, with `-dirty` for local changes.
pub fn git_revision() -> String {
    let dir = env!("CARGO_MANIFEST_DIR");
    let run = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .current_dir(dir)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    match run(&["rev-parse", "--short=12", "HEAD"]) {
        Some(rev) => {
            let dirty = run(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
            if dirty {
                format!("{rev}-dirty")
            } else {
                rev
            }
        }
        None => "unknown".into(),
    }
}

/// Per-pass statistics over `frames`, in the order the passes ran.
pub fn summarize(frames: &[FrameTiming]) -> (Vec<PassStats>, Stats) {
    let mut names: Vec<String> = Vec::new();
    for f in frames {
        for p in &f.passes {
            if !names.contains(&p.name) {
                names.push(p.name.clone());
            }
        }
    }
    let passes = names
        .into_iter()
        .map(|name| {
            let v: Vec<f64> = frames
                .iter()
                .flat_map(|f| f.passes.iter().filter(|p| p.name == name).map(|p| p.duration_ms()))
                .collect();
            PassStats { stats: Stats::of(&v), name }
        })
        .collect();
    let totals: Vec<f64> = frames.iter().map(|f| f.total_ms()).collect();
    (passes, Stats::of(&totals))
}

/// Chrome trace-event JSON: one complete ("X") event per frame on thread 1 and per pass on
/// thread 2, in microseconds. Frames are laid out at their GPU start times.
pub fn chrome_trace(frames: &[FrameTiming], device: &DeviceInfo, scene: &str) -> serde_json::Value {
    let mut events = vec![
        serde_json::json!({"name": "process_name", "ph": "M", "pid": 1, "args": {"name": format!("prism GPU ({})", device.name)}}),
        serde_json::json!({"name": "thread_name", "ph": "M", "pid": 1, "tid": 1, "args": {"name": "frames"}}),
        serde_json::json!({"name": "thread_name", "ph": "M", "pid": 1, "tid": 2, "args": {"name": "passes"}}),
    ];
    let t0 = frames.first().map(|f| f.gpu_start_ms).unwrap_or(0.0);
    for f in frames {
        let base = (f.gpu_start_ms - t0) * 1000.0;
        events.push(serde_json::json!({
            "name": format!("frame {}", f.frame), "cat": "frame", "ph": "X", "pid": 1, "tid": 1,
            "ts": base, "dur": f.total_ms() * 1000.0, "args": {"scene": scene}
        }));
        for p in &f.passes {
            events.push(serde_json::json!({
                "name": p.name, "cat": "pass", "ph": "X", "pid": 1, "tid": 2,
                "ts": base + p.start_ms * 1000.0, "dur": p.duration_ms() * 1000.0, "args": {"frame": f.frame}
            }));
        }
    }
    serde_json::json!({ "traceEvents": events, "displayTimeUnit": "ms" })
}

pub fn run(args: BenchArgs) -> Result<()> {
    if args.frames == 0 {
        anyhow::bail!("--frames must be at least 1");
    }
    let scene = args.scene.load()?;
    let mut outputs = Outputs::default();
    let json_out = outputs.prepare_opt(args.json.as_deref())?;
    let trace_out = outputs.prepare_opt(args.trace.as_deref())?;
    let ctx = args.gpu.context()?;
    let mut renderer = Renderer::new(&ctx, &scene).context("cannot set up the renderer")?;

    let total = u64::from(args.warmup) + u64::from(args.frames);
    let bar = ProgressBar::new(total).with_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} frames, eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(format!("bench {}", scene.name));
    for frame in 1..=total {
        renderer.render_frame()?;
        bar.inc(1);
        if args.stats.is_some_and(|n| frame % n == 0) {
            bar.suspend(|| super::print_stats(frame, &ctx));
        }
    }
    renderer.finish()?;
    bar.finish_and_clear();
    check_validation(&ctx)?;
    let frames: Vec<FrameTiming> =
        renderer.take_timings().into_iter().filter(|f| f.frame >= u64::from(args.warmup)).collect();
    let (passes, frame) = summarize(&frames);

    println!(
        "prism bench: {} at {}x{}, {} frames after {} warm-up, on {} ({} {})",
        scene.name,
        renderer.width(),
        renderer.height(),
        frames.len(),
        args.warmup,
        ctx.info.name,
        ctx.info.driver_name,
        ctx.info.driver_info
    );
    let width = passes.iter().map(|p| p.name.len()).max().unwrap_or(5).max(5);
    println!("{:width$}  {:>10}  {:>10}  {:>10}", "pass", "median ms", "min ms", "max ms");
    for p in &passes {
        println!("{:width$}  {:>10.3}  {:>10.3}  {:>10.3}", p.name, p.stats.median_ms, p.stats.min_ms, p.stats.max_ms);
    }
    println!("{:width$}  {:>10.3}  {:>10.3}  {:>10.3}", "frame", frame.median_ms, frame.min_ms, frame.max_ms);
    if let Some(l) = renderer.light_stats() {
        println!(
            "eikonal light simulation (once, at setup): {:.3} s wall clock, {} steps, {} initial patches, peak {}, {} dropped",
            l.seconds, l.steps, l.initial_patches, l.peak_patches, l.dropped_patches
        );
        println!(
            "  {} patch-steps, GPU {:.1} ms ({:.1} ms in overflowing tiles and their take-backs); per kernel:",
            l.patch_steps, l.gpu_ms, l.overflow_ms
        );
        for line in l.kernel_lines() {
            println!("{line}");
        }
    }
    if ctx.info.device_type == "CPU" {
        println!(
            "note: a CPU device (lavapipe): times are CPU time; compare ratios within one run, not absolute times."
        );
    }

    // Both files are on disk before either is moved into place.
    let mut written = Vec::new();
    if let Some(out) = json_out {
        let report = BenchReport {
            scene: scene.name.clone(),
            scene_file: scene.source.display().to_string(),
            device: ctx.info.clone(),
            width: renderer.width(),
            height: renderer.height(),
            frames: frames.len() as u32,
            warmup: args.warmup,
            git_revision: git_revision(),
            settings: args.scene.set.clone(),
            scene_toml: scene.canonical.clone(),
            passes,
            frame,
            light_simulation: renderer.light_stats().cloned(),
            note: "GPU timestamps; on a CPU device (lavapipe) these are CPU times: compare ratios, not absolute values",
        };
        written.push(out.write(serde_json::to_string_pretty(&report)?.as_bytes())?);
    }
    if let Some(out) = trace_out {
        let trace = chrome_trace(&frames, &ctx.info, &scene.name);
        written.push(out.write(serde_json::to_string(&trace)?.as_bytes())?);
    }
    output::commit_all(written)
}
