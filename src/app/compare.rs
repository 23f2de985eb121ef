//! `prism compare`: one scene, its selected techniques and the exact reference, side by
//! side: per-pass GPU time and the error against the reference. The reference is cached on
//! disk, keyed by everything it depends on, so comparing many settings costs one reference.
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result};
use clap::Args;

use crate::gpu::GpuContext;
use crate::metrics::image::ErrorMetrics;
use crate::metrics::mask::ObjectMask;
use crate::metrics::timing::Stats;
use crate::reference::{ReferenceSettings, ReferenceStats};
use crate::renderer::{FrameTiming, Renderer};
use crate::scene::techniques::TonemapAdaptiveParams;
use crate::scene::{Environment, Scene};

use super::bench::{summarize, PassStats, MAX_FRAMES};
use super::output::{self, OutputFile, Outputs};
use super::reference::{render_reference, ReferenceArgs};
use super::{check_validation, GpuArgs, SceneArgs};

#[derive(Args, Debug, Clone)]
pub struct MeasureArgs {
    /// Frames timed per setting (at most 1000000).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(..=MAX_FRAMES))]
    pub frames: u32,
    /// Frames rendered before timing (at most 1000000).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(..=MAX_FRAMES))]
    pub warmup: u32,
    #[command(flatten)]
    pub reference: ReferenceArgs,
    /// Recompute the reference even if a cached one exists.
    #[arg(long)]
    pub no_cache: bool,
    /// Measure against a reference whose paths the driver's loop limit cut short instead of
    /// failing; the counts are still reported.
    #[arg(long)]
    pub accept_cut_reference: bool,
}

impl MeasureArgs {
    pub fn reference_policy(&self) -> ReferencePolicy {
        ReferencePolicy { use_cache: !self.no_cache, accept_cut: self.accept_cut_reference }
    }
}

/// How the measuring commands get their reference: from the cache or not, and whether a
/// reference with paths cut by the driver's loop limit ([`ReferenceStats::cut`]) may rank
/// techniques.
#[derive(Clone, Copy, Debug)]
pub struct ReferencePolicy {
    pub use_cache: bool,
    pub accept_cut: bool,
}

/// The technique's last image tone-mapped as the errors see it: the renderer's own LDR image,
/// except with the adaptive tone map, where both images are mapped with the reference's state
/// (the eye adapted to the true scene), so that FLIP sees the technique's error under one
/// display mapping rather than the exposure shift of a second adaptation to the wrong image.
pub fn technique_ldr(renderer: &mut Renderer, scene: &Scene, hdr: &[f32], reference: &[f32]) -> Result<Vec<u8>> {
    if scene.render.tonemap == "adaptive" {
        let p = TonemapAdaptiveParams::from_settings(&scene.render).unwrap_or_default();
        let state = output::adaptive_stats(reference, &p, scene.render.exposure);
        Ok(output::tonemap_adaptive_with(hdr, &p, scene.render.exposure, &state))
    } else {
        Ok(renderer.read_ldr()?)
    }
}

/// A reference image and where it came from.
pub struct CachedReference {
    /// RGBA f32.
    pub image: Vec<f32>,
    /// Its file in the cache.
    pub path: PathBuf,
    /// Whether it was read from the cache.
    pub cached: bool,
    /// What its kernels counted (zero for an exact reference).
    pub stats: ReferenceStats,
}

#[derive(Args, Debug)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub measure: MeasureArgs,
    /// FLIP error heat map (PNG); default: SCENE-error.png in the current directory.
    #[arg(long)]
    pub heatmap: Option<PathBuf>,
    /// Also write the technique's image and the reference's, tone-mapped, as PNG files with
    /// this prefix (PREFIX-technique.png, PREFIX-reference.png).
    #[arg(long)]
    pub images: Option<String>,
    /// Write the results as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    #[command(flatten)]
    pub exact: super::equaltime::ExactArgs,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

/// Where cached references live: `PRISM_CACHE_DIR`, else `$XDG_CACHE_HOME/prism`, else
/// `~/.cache/prism`, else the system's temporary directory.
pub fn cache_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("PRISM_CACHE_DIR") {
        return PathBuf::from(d);
    }
    if let Some(d) = std::env::var_os("XDG_CACHE_HOME") {
        return PathBuf::from(d).join("prism");
    }
    if let Some(h) = std::env::var_os("HOME") {
        return PathBuf::from(h).join(".cache/prism");
    }
    std::env::temp_dir().join("prism-cache")
}

/// 64-bit FNV-1a: stable across Rust versions and platforms (unlike `DefaultHasher`).
struct Fnv(u64);
impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf29ce484222325)
    }
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 = (self.0 ^ x as u64).wrapping_mul(0x100000001b3);
        }
    }
}

/// The key of a reference: everything the reference image depends on. The effective scene
/// without its `[render]` table (technique choices do not change the truth), the geometry
/// and environment actually loaded (a changed OBJ or image changes the key even if the file
/// name does not), the settings, and the reference shaders' SPIR-V (a fixed bug invalidates
/// old references).
pub fn reference_key(scene: &Scene, settings: &ReferenceSettings) -> String {
    let mut h = Fnv::new();
    let mut table: toml::Table = toml::from_str(&scene.canonical).unwrap_or_default();
    table.remove("render");
    table.remove("name");
    // An analytic index profile is traced exactly (glsl/reference/volume.glsl): the voxel
    // resolution only matters to the reference when regions are rasterized into fields.
    if scene.volume.as_ref().is_some_and(|v| v.regions.is_empty()) {
        if let Some(toml::Value::Table(v)) = table.get_mut("volume") {
            v.remove("resolution");
        }
    }
    h.bytes(toml::to_string(&table).unwrap_or_default().as_bytes());
    // Exact spheres are intersected analytically (their keys are in the scene text): their
    // tessellation does not change the reference.
    for o in scene.objects.iter().filter(|o| o.analytic.is_none()) {
        h.bytes(bytemuck::cast_slice(&o.mesh.positions));
        h.bytes(bytemuck::cast_slice(&o.mesh.normals));
        h.bytes(bytemuck::cast_slice(&o.mesh.indices));
    }
    if let Environment::Image { texels, .. } = &scene.environment {
        h.bytes(bytemuck::cast_slice(texels));
    }
    h.bytes(serde_json::to_string(settings).unwrap_or_default().as_bytes());
    for shader in crate::gpu::shader_names().filter(|n| n.starts_with("reference/")) {
        h.bytes(&crate::gpu::shader_spirv(shader).map(|w| bytemuck::cast_slice(&w).to_vec()).unwrap_or_default());
    }
    format!("{:016x}", h.0)
}

/// The reference of `scene`, from the cache when present. A reference with paths cut by the
/// driver's loop limit is an error unless the policy accepts it: the cut depends on the
/// driver, not on the scene, and can be as large as a whole region of the image. Paths ended
/// at the volume's step cap are the reference's own rule for light trapped by internal
/// reflection (volume.glsl), which the shipped field volumes meet on a few paths in 10^5
/// (eikonal_wine_glass: 42 at 64x64, 4 spp, 65536 photons): those only warn. Every warning is
/// printed.
pub fn cached_reference(
    ctx: &Arc<GpuContext>,
    scene: &Scene,
    settings: &ReferenceSettings,
    policy: ReferencePolicy,
) -> Result<CachedReference> {
    let r = load_or_render_reference(ctx, scene, settings, policy.use_cache)?;
    if let Some(w) = r.stats.warning(&scene.name) {
        if r.stats.cut() > 0 && !policy.accept_cut {
            anyhow::bail!("{w} It would rank techniques against a wrong image: pass --accept-cut-reference to measure against it anyway.");
        }
        eprintln!("warning: {w}");
    }
    Ok(r)
}

fn load_or_render_reference(
    ctx: &Arc<GpuContext>,
    scene: &Scene,
    settings: &ReferenceSettings,
    use_cache: bool,
) -> Result<CachedReference> {
    let dir = cache_dir();
    let path = dir.join(format!(
        "{}-{}x{}-{}.exr",
        scene.name,
        scene.camera.width,
        scene.camera.height,
        reference_key(scene, settings)
    ));
    // Beside the image, what its kernels counted; an image without it is rendered anew.
    let stats_path = path.with_extension("stats.json");
    if use_cache && path.exists() {
        let stats = std::fs::read(&stats_path).ok().and_then(|b| serde_json::from_slice::<ReferenceStats>(&b).ok());
        if let (Ok(img), Some(stats)) = (image::open(&path), stats) {
            let rgb = img.to_rgb32f();
            if (rgb.width(), rgb.height()) == (scene.camera.width, scene.camera.height) {
                let image = rgb.pixels().flat_map(|p| [p[0], p[1], p[2], 1.0]).collect();
                return Ok(CachedReference { image, path, cached: true, stats });
            }
        }
    }
    let (image, stats) = render_reference(ctx, scene, settings)?;
    // A cache that cannot be written is not an error: the result is still correct. The
    // counts go first, so that an image in the cache always has its own.
    if std::fs::create_dir_all(&dir).is_ok() {
        let counts = OutputFile::prepare(&stats_path)
            .and_then(|out| out.commit_bytes(serde_json::to_string(&stats).unwrap_or_default().as_bytes()));
        if counts.is_ok() {
            if let Ok(out) = OutputFile::prepare(&path) {
                let _ =
                    output::write_exr(out, scene.camera.width, scene.camera.height, &image).and_then(|f| f.commit());
            }
        }
    }
    Ok(CachedReference { image, path, cached: false, stats })
}

/// One technique setting, timed and compared.
#[derive(Debug, serde::Serialize)]
pub struct Measurement {
    /// The passes of the steady frames (after the warm-up) that did work there: a cached
    /// pass that ran only in the first frame is in [`PerChange`] instead.
    pub passes: Vec<PassStats>,
    /// The steady frame: every pass recorded each frame, none of the costs paid once per
    /// change ([`PerChange`]).
    pub frame: Stats,
    #[serde(flatten)]
    pub per_change: PerChange,
    /// When each timed frame started on the device's clock, ms: how the frames of settings
    /// timed together were interleaved (src/app/equaltime.rs).
    pub frame_starts_ms: Vec<f64>,
    pub errors: ErrorMetrics,
    #[serde(flatten)]
    pub mask: MaskErrors,
    #[serde(skip)]
    pub hdr: Vec<f32>,
    #[serde(skip)]
    pub ldr: Vec<u8>,
    #[serde(skip)]
    pub heatmap: Vec<u8>,
}

/// "per change ms": what a setting pays once per light or object change rather than every
/// frame, measured in the same run as its frames.
///
/// - The passes that did work in the first frame and none in every later one (the distance
///   impostors' environment, uv and refractor maps, src/technique/impostor/): their GPU time in
///   frame 0. Their techniques are built from where things are (`Inputs::placement`), so a
///   scene update that moves a light or an object re-creates them and the maps render again;
///   an object dragged in place (`Renderer::move_object`) re-renders an environment map only
///   beyond `render.impostor.regenerate_distance` (Szirmay-Kalos et al. 2005, §6), a
///   refractor map never.
/// - What techniques compute at creation outside the frame graph and keep in the technique
///   cache or the process ([`crate::technique::Technique::once_costs`]), each re-run only when
///   its cache key changes: the eikonal light simulation's GPU time (keyed by the volume, the
///   lights and its settings: a light or volume change, not an object or camera move); the
///   eikonal volume's sampling, smoothing and differentiation (host wall-clock, uploads and
///   GPU work waited for; keyed by the volume and sigma); the tracers' geometry, BVH and
///   buffers, of `raytrace` and `water` (host wall-clock; keyed by the objects' triangles,
///   spheres and materials: an object change); Wyman 2005 §3.1's d_N on the host, for
///   `wyman` and `caustics_map` (cached per mesh: a mesh change, not a rigid move).
///
/// A camera move (`Renderer::set_camera`, the window's) re-runs none of them: it costs only
/// frames. What is not counted: pipeline creation and the uploads every technique makes at
/// creation (the scene's buffers, cleared stand-in textures).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct PerChange {
    /// The sum of `per_change_costs`, ms.
    #[serde(rename = "per_change_ms")]
    pub ms: f64,
    #[serde(rename = "per_change_costs")]
    pub costs: Vec<crate::technique::OnceCost>,
}

impl PerChange {
    /// The costs of a renderer's run: `timings` of every frame from frame 0 (the passes that
    /// did work in frame 0 and in no later frame; none without a later frame to tell them
    /// by) and its techniques' `once` costs.
    pub fn of(timings: &[FrameTiming], once: Vec<crate::technique::OnceCost>) -> PerChange {
        let mut costs = Vec::new();
        let later: Vec<&FrameTiming> = timings.iter().filter(|f| f.frame > 0).collect();
        if let (Some(first), false) = (timings.iter().find(|f| f.frame == 0), later.is_empty()) {
            for p in first.passes.iter().filter(|p| !p.idle) {
                let idle_after = later.iter().flat_map(|f| &f.passes).filter(|q| q.name == p.name).all(|q| q.idle);
                if idle_after {
                    costs.push(crate::technique::OnceCost {
                        name: p.name.clone(),
                        ms: p.duration_ms(),
                        clock: "gpu",
                        rerun_on: "light or object change",
                    });
                }
            }
        }
        costs.extend(once);
        // A fold from +0: `sum` of no f64 is -0, which prints as "-0.000".
        PerChange { ms: costs.iter().fold(0.0, |a, c| a + c.ms), costs }
    }

    /// "name 1.234 ms (gpu; light or object change), ..." for the printed line.
    pub fn describe(&self) -> String {
        if self.costs.is_empty() {
            return "none".into();
        }
        let each: Vec<String> =
            self.costs.iter().map(|c| format!("{} {:.3} ms ({}; {})", c.name, c.ms, c.clock, c.rerun_on)).collect();
        each.join(", ")
    }
}

/// The errors over the object mask (src/metrics/mask.rs): the pixels the techniques touch.
#[derive(Debug, Default, serde::Serialize)]
pub struct MaskErrors {
    /// The metrics over the mask's pixels alone; `None` (JSON null) when no masked surface is
    /// in view.
    pub errors_mask: Option<ErrorMetrics>,
    /// Pixels in the mask.
    pub mask_pixels: usize,
    /// The surfaces seen in the mask with their role and pixel count.
    pub mask_surfaces: Vec<String>,
}

impl MaskErrors {
    /// "N pixels: surfaces" for the printed line and the report.
    pub fn describe(&self) -> String {
        if self.mask_surfaces.is_empty() {
            format!("{} pixels", self.mask_pixels)
        } else {
            format!("{} pixels: {}", self.mask_pixels, self.mask_surfaces.join(", "))
        }
    }
}

/// A setting's renderer, created before its frames, so that its frames can be interleaved
/// with other settings' ([`super::bench_versus::Interleave`]) and none of them overlaps a
/// creation (pipeline compilation, the eikonal light simulation).
pub struct Timing<'a> {
    renderer: Renderer,
    scene: &'a Scene,
    warmup: u32,
    reference: &'a [f32],
    frames: u64,
}

impl<'a> Timing<'a> {
    pub fn new(
        ctx: &Arc<GpuContext>,
        scene: &'a Scene,
        warmup: u32,
        frames: u32,
        reference: &'a [f32],
    ) -> Result<Timing<'a>> {
        // The error is scored on the frame whose time is measured: a running mean over the
        // frames (`render.raytrace.accumulate`, for the window) would be scored against one
        // frame's cost. A scene or `--set` that names the key keeps its value.
        let mut single = scene.clone();
        let raytrace = single.render.params.entry("raytrace".to_string()).or_default();
        raytrace.entry("accumulate").or_insert(toml::Value::Integer(1));
        let renderer = Renderer::new(ctx, &single).context("cannot set up the renderer")?;
        let frames = u64::from(warmup) + u64::from(frames.max(1));
        Ok(Timing { renderer, scene, warmup, reference, frames })
    }

    /// Its frames, warm-up included.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Render one frame and wait for it: an interleaved frame must not share the CPU
    /// (lavapipe runs on it) with the next participant's recording.
    pub fn step(&mut self) -> Result<()> {
        self.renderer.render_frame()?;
        self.renderer.finish()?;
        Ok(())
    }

    /// The timings of the frames after the warm-up, the costs paid once per change, and the
    /// last image's errors against the reference.
    pub fn finish(self) -> Result<Measurement> {
        let Timing { mut renderer, scene, warmup, reference, .. } = self;
        renderer.finish()?;
        let timings = renderer.take_timings();
        let per_change = PerChange::of(&timings, renderer.once_costs());
        let frames: Vec<FrameTiming> = timings.into_iter().filter(|f| f.frame >= u64::from(warmup)).collect();
        let (mut passes, frame) = summarize(&frames);
        // A pass idle in every steady frame costs nothing there (its timestamps bracket no work).
        passes.retain(|p| frames.iter().flat_map(|f| &f.passes).any(|q| q.name == p.name && !q.idle));
        let hdr = renderer.read_hdr()?;
        let ref_ldr = output::tonemap_scene(reference, &scene.render);
        let ldr = technique_ldr(&mut renderer, scene, &hdr, reference)?;
        let (w, h) = (scene.camera.width, scene.camera.height);
        let object_mask = ObjectMask::of_scene(scene);
        let (errors, errors_mask, heatmap) =
            ErrorMetrics::between_with_mask(&hdr, reference, &ldr, &ref_ldr, w, h, Some(&object_mask.pixels));
        let mask = MaskErrors { errors_mask, mask_pixels: object_mask.count(), mask_surfaces: object_mask.surfaces };
        let frame_starts_ms = frames.iter().map(|f| f.gpu_start_ms).collect();
        Ok(Measurement { passes, frame, per_change, frame_starts_ms, errors, mask, hdr, ldr, heatmap })
    }
}

#[derive(serde::Serialize)]
struct CompareReport<'a> {
    scene: &'a str,
    scene_file: String,
    width: u32,
    height: u32,
    device: &'a crate::gpu::DeviceInfo,
    git_revision: String,
    settings: &'a [String],
    techniques: serde_json::Value,
    reference: &'a ReferenceSettings,
    /// Paths the reference's kernels cut or ended early (all zero for an exact reference).
    reference_stats: ReferenceStats,
    reference_cache: String,
    frames: u32,
    #[serde(flatten)]
    measurement: &'a Measurement,
    exact: Option<&'a super::equaltime::ExactCurve>,
    reference_noise: Option<&'a super::equaltime::Noise>,
}

/// The exact tracer's curve and, per metric, the setting's error with the reference's noise,
/// the exact tracer's at the same time and the verdict.
pub fn print_equal_time(x: &super::equaltime::Exact, m: &Measurement) -> Result<()> {
    println!("exact tracer: {}", x.curve.source.describe());
    for p in &x.curve.points {
        println!(
            "  {:>12}  {:>10.3} ms  RMSE {:.5}  FLIP mean {:.4}  HDR-FLIP mean {:.4}",
            p.label, p.time_ms, p.errors.rmse, p.errors.flip_mean, p.errors.hdr_flip_mean
        );
    }
    for metric in ["rmse", "flip_mean", "hdr_flip_mean"] {
        let value = super::equaltime::metric_value(&m.errors, metric)?;
        let (lo, _) = x.noise.interval(metric, value);
        let eq = x.equal_time(metric, m)?;
        let at = eq.exact.map(|a| format!("{:.4}{}", a.error, if a.beyond { " (its slowest point)" } else { "" }));
        println!(
            "equal time, {metric}: this {value:.4} (reference noise: [{lo:.4}, {value:.4}]), exact {}: {}",
            at.unwrap_or_else(|| "none as fast".into()),
            eq.verdict.as_str()
        );
    }
    Ok(())
}

pub fn print_measurement(m: &Measurement) {
    let width = m.passes.iter().map(|p| p.name.len()).max().unwrap_or(5).max(5);
    println!("{:width$}  {:>10}", "pass", "median ms");
    for p in &m.passes {
        println!("{:width$}  {:>10.3}", p.name, p.stats.median_ms);
    }
    println!(
        "{:width$}  {:>10.3}  (every pass of a steady frame; none of the per-change costs)",
        "frame", m.frame.median_ms
    );
    println!("per change ms {:.3}, paid once per light or object change: {}", m.per_change.ms, m.per_change.describe());
    let line = |e: &ErrorMetrics| {
        format!(
            "RMSE {:.5}  PSNR {:.2} dB  relMSE {:.5}  FLIP mean {:.4}  FLIP p95 {:.4}  HDR-FLIP mean {:.4}  \
             HDR-FLIP p95 {:.4}",
            e.rmse, e.psnr_db, e.rel_mse, e.flip_mean, e.flip_p95, e.hdr_flip_mean, e.hdr_flip_p95
        )
    };
    println!("error vs reference: {}", line(&m.errors));
    match &m.mask.errors_mask {
        Some(e) => println!("  over the object mask ({}): {}", m.mask.describe(), line(e)),
        None => println!("  over the object mask: no masked surface in view"),
    }
}

pub fn run(args: CompareArgs) -> Result<()> {
    let scene = args.scene.load()?;
    let settings = args.measure.reference.settings();
    settings.validate()?;
    let heat_path = args.heatmap.clone().unwrap_or_else(|| PathBuf::from(format!("{}-error.png", scene.name)));
    let mut outputs = Outputs::default();
    let heat_out = outputs.prepare(&heat_path)?;
    let json_out = outputs.prepare_opt(args.json.as_deref())?;
    let image_outs = match &args.images {
        Some(prefix) => Some((
            outputs.prepare(Path::new(&format!("{prefix}-technique.png")))?,
            outputs.prepare(Path::new(&format!("{prefix}-reference.png")))?,
        )),
        None => None,
    };
    let ctx = args.gpu.context()?;
    let policy = args.measure.reference_policy();
    let CachedReference { image: reference, path: cache, cached, stats } =
        cached_reference(&ctx, &scene, &settings, policy)?;
    // The setting and the exact points timed interleaved, each frame waited for, as `sweep`
    // and `report` time theirs (src/app/equaltime.rs).
    use super::equaltime::{curve_spec, measure_interleaved, reference_noise, Exact, Setting};
    let (spec, noise) = if args.exact.no_exact {
        (None, None)
    } else {
        let spec = curve_spec(&args.scene, &args.measure, &args.exact, [&scene])?;
        (Some(spec), Some(reference_noise(&ctx, &scene, &settings, &reference, policy)?))
    };
    let setting = Setting { scene: &scene, reference: &reference };
    let (mut m, curve) =
        measure_interleaved(&ctx, &[setting], &args.measure, spec.as_ref().map(|s| (s, &reference[..])))?;
    let m = m.remove(0);
    let exact = curve.zip(noise).map(|(curve, noise)| Exact { curve, noise });
    check_validation(&ctx)?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    println!(
        "prism compare: {} at {w}x{h} on {}; refraction = {}, reflection = {}, caustics = {}",
        scene.name, ctx.info.name, scene.render.refraction, scene.render.reflection, scene.render.caustics
    );
    println!(
        "reference: {} spp, {} photons{} ({})",
        settings.spp,
        settings.photons,
        if cached { ", from the cache" } else { "" },
        cache.display()
    );
    print_measurement(&m);
    if let Some(x) = &exact {
        print_equal_time(x, &m)?;
    }
    if ctx.info.device_type == "CPU" {
        println!("note: a CPU device (lavapipe): times are CPU time; compare ratios within one run.");
    }
    // Every output is on disk before any is moved into place.
    let mut written = vec![output::write_png(heat_out, w, h, &m.heatmap)?];
    if let Some((t, r)) = image_outs {
        written.push(output::write_png(t, w, h, &m.ldr)?);
        written.push(output::write_png(r, w, h, &output::tonemap_scene(&reference, &scene.render))?);
    }
    if let Some(out) = json_out {
        let techniques = serde_json::json!({
            "refraction": scene.render.refraction,
            "reflection": scene.render.reflection,
            "caustics": scene.render.caustics,
        });
        let report = CompareReport {
            scene: &scene.name,
            scene_file: scene.source.display().to_string(),
            width: w,
            height: h,
            device: &ctx.info,
            git_revision: super::bench::git_revision(),
            settings: &args.scene.set,
            techniques,
            reference: &settings,
            reference_stats: stats,
            reference_cache: cache.display().to_string(),
            frames: args.measure.frames,
            measurement: &m,
            exact: exact.as_ref().map(|x| &x.curve),
            reference_noise: exact.as_ref().map(|x| &x.noise),
        };
        written.push(out.write(serde_json::to_string_pretty(&report)?.as_bytes())?);
    }
    output::commit_all(written)?;
    eprintln!("wrote FLIP heat map {}", heat_path.display());
    Ok(())
}
