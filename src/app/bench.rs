//! `prism bench`: per-pass GPU timings over many frames, as a table, JSON and a Chrome
//! trace-event file (open it in Perfetto or chrome://tracing).
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use crate::gpu::DeviceInfo;
use crate::gpu::PassCounts;
use crate::metrics::timing::Stats;
use crate::renderer::{FrameTiming, Renderer, TechniqueMemory};

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
    /// Time this setting against the other `--versus` settings in one process, interleaved
    /// frame by frame (repeat, two or more; each ratio is against the first). KEY=VALUE as
    /// for --set, applied after every --set.
    #[arg(long, value_name = "KEY=VALUE")]
    pub versus: Vec<String>,
    /// Compare two `prism bench --json` files pass by pass, with their spread, and say which
    /// differences exceed the noise (renders nothing).
    #[arg(long, num_args = 2, value_names = ["A_JSON", "B_JSON"], conflicts_with = "versus")]
    pub diff: Option<Vec<PathBuf>>,
    /// Count each pass's pipeline statistics (vertex, geometry, fragment and compute
    /// invocations, primitives, clipping) with Vulkan queries, beside its time, in the table,
    /// the JSON and the trace.
    #[arg(long)]
    pub pipeline_stats: bool,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

#[derive(Serialize, Debug)]
pub struct PassStats {
    pub name: String,
    #[serde(flatten)]
    pub stats: Stats,
    /// Sample standard deviation (n - 1 in the denominator), ms; bench only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stddev_ms: Option<f64>,
    /// Every measured frame's time, in frame order, ms; bench only (`--diff` reads them).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub samples_ms: Vec<f64>,
    /// Median over the frames of each pipeline-statistics counter (`--pipeline-stats`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pipeline_statistics: Option<PassCounts>,
}

impl PassStats {
    /// Statistics of `samples` with the samples and their standard deviation kept.
    pub fn detailed(name: impl Into<String>, samples: Vec<f64>) -> PassStats {
        PassStats {
            name: name.into(),
            stats: Stats::of(&samples),
            stddev_ms: Some(stddev(&samples)),
            samples_ms: samples,
            pipeline_statistics: None,
        }
    }
}

/// Sample standard deviation (Bessel's n - 1); 0 for fewer than two samples.
pub fn stddev(v: &[f64]) -> f64 {
    if v.len() < 2 {
        return 0.0;
    }
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

/// What the host reports about its own state around a run. Vulkan exposes no clock or
/// power state; on lavapipe the "GPU" is these CPUs, whose load and frequency governor are
/// what moves its timings.
#[derive(Serialize, Debug, Clone, Default)]
pub struct HostState {
    /// /proc/loadavg's 1-, 5- and 15-minute load averages before and after the run.
    pub loadavg_before: Option<[f64; 3]>,
    pub loadavg_after: Option<[f64; 3]>,
    /// cpu0's cpufreq scaling governor, where the kernel exposes it.
    pub cpu_governor: Option<String>,
    pub cpus: usize,
}

impl HostState {
    pub fn before() -> HostState {
        let governor = std::fs::read_to_string("/sys/devices/system/cpu/cpu0/cpufreq/scaling_governor")
            .ok()
            .map(|s| s.trim().to_string());
        HostState {
            loadavg_before: loadavg(),
            loadavg_after: None,
            cpu_governor: governor,
            cpus: std::thread::available_parallelism().map_or(0, |n| n.get()),
        }
    }
    pub fn after(mut self) -> HostState {
        self.loadavg_after = loadavg();
        self
    }
}

fn loadavg() -> Option<[f64; 3]> {
    let s = std::fs::read_to_string("/proc/loadavg").ok()?;
    let v: Vec<f64> = s.split_whitespace().take(3).filter_map(|x| x.parse().ok()).collect();
    (v.len() == 3).then(|| [v[0], v[1], v[2]])
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
    pub frame: PassStats,
    /// Device memory each technique created, and the shared resources' ("frame").
    pub memory: Vec<TechniqueMemory>,
    pub host: HostState,
    /// The eikonal light simulation (run once when the renderer is created): steps, patch
    /// count per step, patch-steps, peak, GPU ms per kernel, wall-clock seconds. Absent
    /// without one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_simulation: Option<crate::technique::eikonal::eikonal_light::LightStats>,
    pub note: &'static str,
}

/// The git revision of the sources this binary was built from (build.rs), `-dirty` when
/// they differed from the commit.
pub fn git_revision() -> String {
    env!("PRISM_REVISION").to_string()
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
            PassStats { stats: Stats::of(&v), name, stddev_ms: None, samples_ms: Vec::new(), pipeline_statistics: None }
        })
        .collect();
    let totals: Vec<f64> = frames.iter().map(|f| f.total_ms()).collect();
    (passes, Stats::of(&totals))
}

/// [`summarize`] keeping every frame's sample and the standard deviation. A pass that runs
/// more than once in a frame contributes the sum of its runs to that frame's sample.
pub fn summarize_detailed(frames: &[FrameTiming]) -> (Vec<PassStats>, PassStats) {
    let passes = pass_names(frames)
        .into_iter()
        .map(|name| {
            let v = frames.iter().map(|f| pass_sum(f, &[name.as_str()])).collect();
            let counts: Vec<PassCounts> = frames
                .iter()
                .flat_map(|f| f.passes.iter().filter(|p| p.name == name).filter_map(|p| p.counts))
                .collect();
            let mut s = PassStats::detailed(name, v);
            s.pipeline_statistics = median_counts(&counts);
            s
        })
        .collect();
    (passes, PassStats::detailed("frame", frames.iter().map(|f| f.total_ms()).collect()))
}

/// Each counter's median (the upper one of an even count); `None` without counts. The
/// counts of a static scene are the same every frame; a median ignores a frame that differs.
fn median_counts(counts: &[PassCounts]) -> Option<PassCounts> {
    if counts.is_empty() {
        return None;
    }
    let m = |f: fn(&PassCounts) -> u64| {
        let mut v: Vec<u64> = counts.iter().map(f).collect();
        v.sort_unstable();
        v[v.len() / 2]
    };
    Some(PassCounts {
        input_vertices: m(|c| c.input_vertices),
        input_primitives: m(|c| c.input_primitives),
        vertex_invocations: m(|c| c.vertex_invocations),
        geometry_invocations: m(|c| c.geometry_invocations),
        geometry_primitives: m(|c| c.geometry_primitives),
        clipping_invocations: m(|c| c.clipping_invocations),
        clipping_primitives: m(|c| c.clipping_primitives),
        fragment_invocations: m(|c| c.fragment_invocations),
        compute_invocations: counts[0].compute_invocations.map(|_| m(|c| c.compute_invocations.unwrap_or(0))),
    })
}

/// The pipeline-statistics table (`--pipeline-stats`): each pass's median counters.
pub fn print_counts_table(passes: &[PassStats]) {
    if passes.iter().all(|p| p.pipeline_statistics.is_none()) {
        return;
    }
    let width = passes.iter().map(|p| p.name.len()).max().unwrap_or(5).max(5);
    println!(
        "{:width$}  {:>10}  {:>10}  {:>10}  {:>10}  {:>10}  {:>10}  {:>10}  {:>12}  {:>10}",
        "pass", "vertices", "primitives", "vs inv", "gs inv", "gs prims", "clip inv", "clip prims", "fs inv", "cs inv"
    );
    for p in passes {
        let Some(c) = p.pipeline_statistics else { continue };
        println!(
            "{:width$}  {:>10}  {:>10}  {:>10}  {:>10}  {:>10}  {:>10}  {:>10}  {:>12}  {:>10}",
            p.name,
            c.input_vertices,
            c.input_primitives,
            c.vertex_invocations,
            c.geometry_invocations,
            c.geometry_primitives,
            c.clipping_invocations,
            c.clipping_primitives,
            c.fragment_invocations,
            c.compute_invocations.map_or_else(|| "-".to_string(), |n| n.to_string())
        );
    }
}

/// Device memory per technique, in MiB.
pub fn print_memory_table(memory: &[TechniqueMemory]) {
    let width = memory.iter().map(|m| m.technique.len()).max().unwrap_or(9).max(9);
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    println!(
        "{:width$}  {:>11}  {:>11}  {:>11}  {:>11}",
        "technique", "buffers MiB", "images MiB", "volumes MiB", "total MiB"
    );
    for m in memory {
        let b = &m.bytes;
        println!(
            "{:width$}  {:>11.2}  {:>11.2}  {:>11.2}  {:>11.2}",
            m.technique,
            mib(b.buffer_bytes),
            mib(b.image_bytes),
            mib(b.volume_bytes),
            mib(b.total())
        );
    }
}

/// Every pass name of `frames`, in the order they first ran.
fn pass_names(frames: &[FrameTiming]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for f in frames {
        for p in &f.passes {
            if !names.contains(&p.name) {
                names.push(p.name.clone());
            }
        }
    }
    names
}

/// The time of the passes named `names` in frame `f`, summed, ms.
fn pass_sum(f: &FrameTiming, names: &[&str]) -> f64 {
    f.passes.iter().filter(|p| names.contains(&p.name.as_str())).map(|p| p.duration_ms()).sum()
}

/// Chrome trace-event JSON: one complete ("X") event per frame on thread 1 and per pass on
/// thread 2, in microseconds. Frames are laid out at their GPU start times.
pub fn chrome_trace(frames: &[FrameTiming], device: &DeviceInfo, scene: &str) -> serde_json::Value {
    chrome_trace_of(&[(format!("prism GPU ({})", device.name), frames)], scene)
}

/// [`chrome_trace`] of several runs, one process each (`--versus`: one per setting), laid
/// out on one clock from the earliest frame.
pub fn chrome_trace_of(runs: &[(String, &[FrameTiming])], scene: &str) -> serde_json::Value {
    let mut events = Vec::new();
    let t0 = runs.iter().flat_map(|(_, f)| f.first()).map(|f| f.gpu_start_ms).fold(f64::INFINITY, f64::min);
    for (i, (label, frames)) in runs.iter().enumerate() {
        let pid = i + 1;
        events.push(serde_json::json!({"name": "process_name", "ph": "M", "pid": pid, "args": {"name": label}}));
        events.push(
            serde_json::json!({"name": "thread_name", "ph": "M", "pid": pid, "tid": 1, "args": {"name": "frames"}}),
        );
        events.push(
            serde_json::json!({"name": "thread_name", "ph": "M", "pid": pid, "tid": 2, "args": {"name": "passes"}}),
        );
        for f in frames.iter() {
            let base = (f.gpu_start_ms - t0) * 1000.0;
            events.push(serde_json::json!({
                "name": format!("frame {}", f.frame), "cat": "frame", "ph": "X", "pid": pid, "tid": 1,
                "ts": base, "dur": f.total_ms() * 1000.0, "args": {"scene": scene}
            }));
            for p in &f.passes {
                let mut args = serde_json::json!({"frame": f.frame});
                if let Some(c) = &p.counts {
                    args["pipeline_statistics"] = serde_json::to_value(c).unwrap_or_default();
                }
                events.push(serde_json::json!({
                    "name": p.name, "cat": "pass", "ph": "X", "pid": pid, "tid": 2,
                    "ts": base + p.start_ms * 1000.0, "dur": p.duration_ms() * 1000.0, "args": args
                }));
            }
        }
    }
    serde_json::json!({ "traceEvents": events, "displayTimeUnit": "ms" })
}

pub fn run(args: BenchArgs) -> Result<()> {
    if let Some(files) = &args.diff {
        return super::bench_diff::run(&files[0], &files[1]);
    }
    if args.frames == 0 {
        anyhow::bail!("--frames must be at least 1");
    }
    if !args.versus.is_empty() {
        return super::bench_versus::run(args);
    }
    let host = HostState::before();
    let scene = args.scene.load()?;
    let mut outputs = Outputs::default();
    let json_out = outputs.prepare_opt(args.json.as_deref())?;
    let trace_out = outputs.prepare_opt(args.trace.as_deref())?;
    let ctx = args.gpu.context()?;
    let mut renderer = Renderer::new(&ctx, &scene).context("cannot set up the renderer")?;
    if args.pipeline_stats {
        enable_pipeline_stats(&mut renderer)?;
    }

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
    let host = host.after();
    let (passes, frame) = summarize_detailed(&frames);

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
    print_pass_table(&passes, &frame);
    if args.pipeline_stats {
        println!();
        print_counts_table(&passes);
        println!();
        print_memory_table(renderer.technique_memory());
    }
    if let Some(l) = renderer.light_stats() {
        println!(
            "eikonal light simulation (once, at setup): {:.3} s wall clock, {} step dispatches, {} initial patches ({} only crossing air, added in closed form), peak {}, {} dropped",
            l.seconds, l.steps, l.initial_patches, l.skipped_patches, l.peak_patches, l.dropped_patches
        );
        println!(
            "  {} patch-steps, GPU {:.1} ms ({:.1} ms in overflowing tiles and their take-backs); deposits by {}; per kernel:",
            l.patch_steps, l.gpu_ms, l.overflow_ms, l.deposits()
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
            memory: renderer.technique_memory().to_vec(),
            host,
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

/// Turn on the pipeline-statistics queries, or say why they cannot be.
pub fn enable_pipeline_stats(renderer: &mut Renderer) -> Result<()> {
    if !renderer.count_pipeline_stats()? {
        anyhow::bail!("--pipeline-stats: the device lacks pipelineStatisticsQuery");
    }
    Ok(())
}

/// The per-pass table: median, min, max and standard deviation of each pass and the frame.
pub fn print_pass_table(passes: &[PassStats], frame: &PassStats) {
    let width = passes.iter().map(|p| p.name.len()).max().unwrap_or(5).max(5);
    println!("{:width$}  {:>10}  {:>10}  {:>10}  {:>10}", "pass", "median ms", "min ms", "max ms", "stddev ms");
    for p in passes.iter().chain(std::iter::once(frame)) {
        println!(
            "{:width$}  {:>10.3}  {:>10.3}  {:>10.3}  {:>10.3}",
            p.name,
            p.stats.median_ms,
            p.stats.min_ms,
            p.stats.max_ms,
            p.stddev_ms.unwrap_or(0.0)
        );
    }
}
