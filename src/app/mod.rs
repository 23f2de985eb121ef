//! The command line: `prism render`, `prism bench`, `prism passes`, `prism scenes`, ... The CLI parses,
//! loads, and hands work to the renderer; it never records commands itself.
pub mod ablation;
pub mod bench;
mod bench_diff;
mod bench_versus;
pub mod compare;
pub mod demo;
pub mod equaltime;
pub mod output;
pub mod reference;
pub mod report;
pub mod scenes;
pub mod sweep;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use crate::gpu::{ContextDesc, GpuContext};
use crate::renderer::Renderer;
use crate::scene::{self, Scene};

use output::Outputs;

#[derive(Parser, Debug)]
#[command(
    name = "prism",
    version = concat!(env!("CARGO_PKG_VERSION"), " (", env!("PRISM_REVISION"), ")"),
    about = "A Vulkan renderer for refraction, reflection and caustics that measures each technique's GPU time against its error.",
    long_about = long_about()
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// `--help`'s description, with the bundled scenes as assets/scenes/ holds them.
fn long_about() -> String {
    let scenes = scene::bundled_scenes().map(|n| n.join(", ")).unwrap_or_else(|e| format!("cannot list them: {e}"));
    format!(
        "prism renders the scenes of five classic papers on interactive refraction, reflection and caustics \
         side by side, times every pass with GPU timestamps and compares each technique against an exact \
         reference (`prism compare`, `prism report`). It runs headless on any Vulkan 1.2 device, including \
         Mesa's lavapipe on the CPU.\n\n\
         SCENE is a path to a .toml scene file or the name of a scene in assets/scenes/ ({scenes}; \
         `prism scenes` describes them). Without SCENE, the default scene ({}) is used. \
         Every scene key is documented in docs/scene-format.md.\n\n\
         Environment: PRISM_DEVICE picks a device like --device; PRISM_VALIDATION=1 (or sync) enables the \
         Vulkan validation layer (and synchronization validation); VK_DRIVER_FILES selects a driver, e.g. \
         /usr/share/vulkan/icd.d/lvp_icd.x86_64.json for lavapipe.",
        scene::DEFAULT_SCENE
    )
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene to a PNG (tone-mapped) and optionally a linear EXR.
    Render(RenderArgs),
    /// Render N frames and print per-pass GPU times (median, min, max) and the frame total.
    Bench(bench::BenchArgs),
    /// Print the passes a scene needs and which object, light or setting requires each.
    Passes(PassesArgs),
    /// List the bundled scenes (assets/scenes/) with their descriptions and techniques.
    Scenes,
    /// Show a scene in a window: orbit/fly camera, live pass timings and parameters (X11;
    /// headless under xvfb-run). Keys and mouse: see README.md, "Interactive demo".
    Demo(demo::DemoArgs),
    /// Render the exact reference (path tracing + photon-mapped caustics) to EXR/PNG.
    Reference(reference::ReferenceCmd),
    /// Time the scene's techniques and measure their error against the exact reference.
    Compare(compare::CompareArgs),
    /// Measure every combination of parameter values: CSV, and error against time plots.
    Sweep(sweep::SweepArgs),
    /// Where a technique's error comes from: its approximations replaced one at a time by the
    /// exact tracer's values (render.wyman.oracle, render.hu_qin.oracle, render.impostor.oracle,
    /// render.caustics_map.oracle), a table of each one's share of the error.
    Ablation(ablation::AblationArgs),
    /// Regenerate docs/ACCURACY.md: every technique and setting's time and error, with plots.
    Report(report::ReportArgs),
}

/// Options shared by every command that loads a scene.
#[derive(Args, Debug, Clone)]
pub struct SceneArgs {
    /// Scene file (.toml) or benchmark scene name; default: the caustic_sphere scene.
    pub scene: Option<PathBuf>,
    /// Override any scene key, e.g. --set render.refraction=single --set materials.glass.ior=1.33
    /// (repeatable; dotted path, array elements by index: objects.0.radius=0.5).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Image width in pixels (same as --set camera.width=W).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels (same as --set camera.height=H).
    #[arg(long)]
    pub height: Option<u32>,
}

/// Options for choosing and checking the Vulkan device.
#[derive(Args, Debug, Clone)]
pub struct GpuArgs {
    /// Vulkan device by index or by a substring of its name (default: prefer a discrete GPU).
    #[arg(long)]
    pub device: Option<String>,
    /// Enable the Vulkan validation layer; the command fails if it reports any error.
    #[arg(long)]
    pub validation: bool,
    /// Also enable synchronization validation (slow; implies --validation).
    #[arg(long)]
    pub sync_validation: bool,
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output PNG (tone-mapped sRGB: render.tonemap = "clamp" (default) or "adaptive"), named
    /// *.png or without an extension (`--exr` writes linear radiance). Output paths must be new or regular files (a symlink to one is followed), each named
    /// once; every output of a command is written in full before any is moved into place.
    #[arg(short, long, default_value = "prism.png")]
    pub output: PathBuf,
    /// Also write linear radiance to this OpenEXR file.
    #[arg(long)]
    pub exr: Option<PathBuf>,
    /// Also write every image of the frame (G-buffer, back-face layers, impostor textures,
    /// caustic maps, volumes, ...) to this multi-part OpenEXR file: one part per image and
    /// array layer (`NAME` or `NAME.LAYER`), f32 channels R, G, B, A (Y for one channel, Z
    /// for depth).
    #[arg(long, value_name = "PATH")]
    pub targets: Option<PathBuf>,
    /// Print details: the eikonal light simulation's patch count after every step.
    #[arg(short, long)]
    pub verbose: bool,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

#[derive(Args, Debug)]
pub struct PassesArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// SCENE as given: an existing path, or a benchmark scene's name.
pub fn resolve_scene_path(scene: Option<&Path>) -> PathBuf {
    match scene {
        None => scene::default_scene_path(),
        Some(p) if p.exists() => p.to_path_buf(),
        Some(p) => {
            let s = p.to_string_lossy();
            if !s.contains('/') && p.extension().is_none() {
                scene::benchmark_scene_path(&s)
            } else {
                p.to_path_buf()
            }
        }
    }
}

impl SceneArgs {
    pub fn load(&self) -> Result<Scene> {
        let path = resolve_scene_path(self.scene.as_deref());
        let mut overrides = self.set.clone();
        if let Some(w) = self.width {
            overrides.push(format!("camera.width={w}"));
        }
        if let Some(h) = self.height {
            overrides.push(format!("camera.height={h}"));
        }
        Ok(scene::load(&path, &overrides)?)
    }
}

impl GpuArgs {
    /// The headless context, with long work's progress on a terminal bar (see
    /// [`terminal_progress`]).
    pub fn context(&self) -> Result<Arc<GpuContext>> {
        let ctx = GpuContext::new(&self.desc())?;
        ctx.set_progress(terminal_progress());
        Ok(ctx)
    }

    /// The context description these flags (and PRISM_VALIDATION / PRISM_DEVICE) ask for.
    pub fn desc(&self) -> ContextDesc {
        let mut desc = ContextDesc::from_env();
        desc.validation |= self.validation || self.sync_validation;
        desc.sync_validation |= self.sync_validation;
        desc.device = self.device.clone();
        desc
    }
}

/// `--stats N` (bench, demo): after every N frames one line on stderr with the process's
/// resident memory and gpu-allocator's totals, which scripts/soak reads to check that
/// neither grows over thousands of frames.
pub fn print_stats(frame: u64, ctx: &GpuContext) {
    let rss = resident_kib().map_or_else(|| "?".to_string(), |k| k.to_string());
    let m = ctx.memory_usage();
    eprintln!(
        "stats: frame {frame} rss_kib {rss} gpu_allocated_bytes {} gpu_block_bytes {} gpu_allocations {} validation_errors {}",
        m.allocated_bytes,
        m.block_bytes,
        m.allocations,
        ctx.validation_errors()
    );
}

/// VmRSS of /proc/self/status, in KiB (None where there is no /proc).
fn resident_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Fail if validation was on and reported errors: they are bugs, never noise.
pub fn check_validation(ctx: &GpuContext) -> Result<()> {
    let errors = ctx.validation_errors();
    if errors > 0 {
        anyhow::bail!("the Vulkan validation layer reported {errors} error(s) (printed above)");
    }
    Ok(())
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render(args) => render(args),
        Command::Bench(args) => bench::run(args),
        Command::Passes(args) => passes(args),
        Command::Scenes => scenes::run(),
        Command::Demo(args) => demo::run(args),
        Command::Reference(args) => reference::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Sweep(args) => sweep::run(args),
        Command::Ablation(args) => ablation::run(args),
        Command::Report(args) => report::run(args),
    }
}

fn render(args: RenderArgs) -> Result<()> {
    let scene = args.scene.load()?;
    // Check the output paths before any work so that a bad path fails fast and leaves nothing.
    if let Some(ext) = args.output.extension().filter(|e| !e.eq_ignore_ascii_case("png")) {
        anyhow::bail!(
            "{}: `-o` writes a tone-mapped PNG, not a .{} file\n  \
             hint: name it *.png; for linear radiance add `--exr FILE.exr`",
            args.output.display(),
            ext.to_string_lossy()
        );
    }
    let mut outputs = Outputs::default();
    let png = outputs.prepare(&args.output)?;
    let exr = outputs.prepare_opt(args.exr.as_deref())?;
    let targets = outputs.prepare_opt(args.targets.as_deref())?;
    let ctx = args.gpu.context()?;
    let mut renderer = Renderer::new(&ctx, &scene).context("cannot set up the renderer")?;
    renderer.render_frame()?;
    let (w, h) = (renderer.width(), renderer.height());
    let hdr = renderer.read_hdr()?;
    let ldr = renderer.read_ldr()?;
    let timing = renderer.take_timings();
    let images = match targets {
        Some(_) => {
            let list = renderer.frame_images();
            let data = list.iter().map(|i| renderer.read_frame_image(i)).collect::<Result<Vec<_>, _>>()?;
            list.into_iter().zip(data).collect()
        }
        None => Vec::new(),
    };
    check_validation(&ctx)?;
    // Every file is on disk before any is moved into place.
    let png = output::write_png(png, w, h, &ldr)?;
    let exr = exr.map(|exr| output::write_exr(exr, w, h, &hdr)).transpose()?;
    let targets = targets.map(|t| output::write_targets_exr(t, &images)).transpose()?;
    let exr_path = exr.as_ref().map(|e| e.path().to_path_buf());
    let targets_path = targets.as_ref().map(|e| e.path().to_path_buf());
    output::commit_all(std::iter::once(png).chain(exr).chain(targets))?;
    if let Some(path) = exr_path {
        eprintln!("wrote {}", path.display());
    }
    if let Some(path) = targets_path {
        eprintln!("wrote {}: every image of the frame", path.display());
        eprintln!("{}", output::targets_table(&images));
    }
    if let Some(l) = renderer.light_stats() {
        eprintln!(
            "eikonal light simulation: {} runs (lights x channels x tiles; {} tiles split), {} step dispatches, {} initial patches ({} only crossing air, added in closed form), peak {}, {} dropped at max_patches, {:.2} s",
            l.runs.len(), l.split_tiles, l.steps, l.initial_patches, l.skipped_patches, l.peak_patches, l.dropped_patches, l.seconds
        );
        eprintln!(
            "eikonal light simulation: {} patch-steps, GPU {:.1} ms, of which {:.1} ms in overflowing tiles and their take-backs; deposits by {}; per kernel:",
            l.patch_steps, l.gpu_ms, l.overflow_ms, l.deposits()
        );
        for line in l.kernel_lines() {
            eprintln!("{line}");
        }
        if l.dropped_patches > 0 {
            eprintln!(
                "warning: eikonal light simulation: {} patches dropped at the max_patches clamp by tiles of one patch \
                 (raise render.eikonal.max_patches)",
                l.dropped_patches
            );
        }
        if args.verbose {
            let mut at = 0usize;
            for r in &l.runs {
                let end = (at + r.steps as usize).min(l.patch_counts.len());
                eprintln!(
                    "run light {} channel {:?} tile {}..{} sign {}: patches after each dispatch: {:?}",
                    r.light,
                    r.channel,
                    r.start,
                    r.end,
                    r.sign,
                    &l.patch_counts[at..end]
                );
                at = end;
            }
        }
    }
    if let Some(t) = renderer.tonemap_stats() {
        eprintln!(
            "adaptive tone map: L_avg {:.4e}, adapted {:.4e} (converged), key {:.4}, L_white {:.4}",
            t.l_avg, t.l_adapted, t.key, t.white
        );
    }
    let total = timing.first().map(|t| t.total_ms()).unwrap_or(0.0);
    eprintln!(
        "wrote {} ({w}x{h}, scene {}, {} on {}, GPU frame {total:.2} ms)",
        args.output.display(),
        scene.name,
        renderer.plan().iter().map(|p| p.name).collect::<Vec<_>>().join(" -> "),
        ctx.info.name
    );
    Ok(())
}

fn passes(args: PassesArgs) -> Result<()> {
    let scene = args.scene.load()?;
    let plan = crate::renderer::plan::plan(&scene);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&plan)?);
    } else {
        println!("passes for {} ({}):", scene.name, scene.source.display());
        let width = plan.iter().map(|p| p.name.len()).max().unwrap_or(0);
        for (i, p) in plan.iter().enumerate() {
            println!("  {:>2}. {:width$}  {}", i + 1, p.name, p.reason);
        }
    }
    Ok(())
}

/// A progress bar on stderr for the library's long tasks (hidden when stderr is not a
/// terminal), cleared when the task finishes.
pub fn terminal_progress() -> crate::gpu::ProgressSink {
    let bar: std::sync::Mutex<Option<indicatif::ProgressBar>> = std::sync::Mutex::default();
    Box::new(move |p| {
        let mut bar = bar.lock().unwrap_or_else(|e| e.into_inner());
        if p.finished {
            if let Some(b) = bar.take() {
                b.finish_and_clear();
            }
            return;
        }
        let b = bar.get_or_insert_with(|| {
            indicatif::ProgressBar::new(p.total).with_style(
                indicatif::ProgressStyle::with_template(&format!("{} {{bar:40}} {{pos}}/{{len}}, {{msg}}", p.task))
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            )
        });
        b.set_length(p.total);
        b.set_position(p.done);
        b.set_message(p.detail.to_string());
    })
}
