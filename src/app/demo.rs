//! `prism demo`: the renderer in a window. The same [`Renderer`] as the headless path
//! records the scene's passes; the window appends two passes of its own through the frame
//! graph (`present_blit`: the tone-mapped image onto the swapchain image; `overlay`: the
//! egui heads-up display on top) and presents. Parameters change by reloading the scene with
//! `--set`-style overrides and rebuilding the renderer; errors while running (a bad scene
//! edit, a lost surface) are shown or recovered from, never a panic.
mod ab;
mod camera;
mod drag;
mod shaders;
mod ui;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime};

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use glam::{Vec2, Vec3};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::raw_window_handle::HasDisplayHandle;
use winit::window::{Window, WindowId};

use crate::gpu::{vk, Acquired, GpuContext, GpuError, Overlay, Presented, SubmitSync, Swapchain};
use crate::graph::ImageId;
use crate::renderer::{OverlayDraw, RenderError, Renderer, WindowTarget, FRAMES_IN_FLIGHT};
use crate::scene::techniques::RaytraceParams;
use crate::scene::{self, Scene};

use super::output::{self, OutputFile, Outputs};
use super::{check_validation, resolve_scene_path, GpuArgs, SceneArgs};
use camera::{CameraController, Drag};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OnOff {
    On,
    Off,
}

#[derive(Args, Debug)]
pub struct DemoArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub gpu: GpuArgs,
    /// Wait for vertical blank (FIFO) or present as soon as possible (MAILBOX or IMMEDIATE
    /// when the driver offers them).
    #[arg(long, value_enum, default_value = "on")]
    pub vsync: OnOff,
    /// Render N frames in the window, then exit (for tests and docs).
    #[arg(long, value_name = "N")]
    pub frames: Option<u64>,
    /// On exit (see --frames), write the last frame without the overlay to this PNG.
    #[arg(long, value_name = "PNG")]
    pub screenshot: Option<PathBuf>,
    /// On exit, also write the last frame's linear radiance to this OpenEXR file.
    #[arg(long, value_name = "EXR")]
    pub screenshot_exr: Option<PathBuf>,
    /// Start with the overlay hidden (F1 shows it).
    #[arg(long)]
    pub no_overlay: bool,
    /// Script a resize: after FRAME presented frames, ask the window system to resize the
    /// window to WxH pixels (repeatable), as a user dragging its border would.
    #[arg(long, num_args = 2, value_names = ["FRAME", "WxH"])]
    pub resize_at: Vec<String>,
    /// Show the frame's image NAME (as `prism render --targets` names it, layer 0) in place of
    /// the final image, clamped to [0, 1]; the overlay's "show" list offers every image.
    #[arg(long, value_name = "NAME")]
    pub show_target: Option<String>,
    /// Start with the overlay's invocation counts on (pipeline-statistics queries around every
    /// pass, as `prism bench --pipeline-stats`); with --frames, the last frame's counts are
    /// printed to stderr at the end.
    #[arg(long)]
    pub pipeline_stats: bool,
    /// Start with the A/B view on: the techniques' image wiped against the exact image of the
    /// same view, which the reference renderer accumulates live (one sample per frame while
    /// nothing changes); the overlay shows the live FLIP mean and relMSE and both costs. With
    /// --screenshot, the PNG is the A/B picture.
    #[arg(long)]
    pub ab: bool,
    /// Photons traced per exact sample in the A/B view (0: no caustics; default
    /// `prism reference`'s rate, 2^22 photons over 64 samples).
    #[arg(long, value_name = "N", default_value_t = ab::DEFAULT_PHOTONS,
          value_parser = clap::value_parser!(u32).range(..=ab::MAX_PHOTONS as i64))]
    pub ab_photons: u32,
    /// Where the A/B view's wipe starts: the technique left of this fraction of the window's
    /// width, the exact image right of it (the overlay's "split" slider).
    #[arg(long, value_name = "F", default_value_t = 0.5, value_parser = unit_fraction)]
    pub ab_split: f32,
    /// Milliseconds the light simulation of a volume runs at least before each frame, and at
    /// least as long as the frame's GPU time (so that slow frames do not starve it); each
    /// frame shows the light simulated so far and the window answers input meanwhile. 0: all
    /// of it before the next frame, the window frozen until it ends (its progress in the
    /// title).
    #[arg(long, value_name = "MS", default_value_t = 100)]
    pub work_per_frame: u64,
    /// Every N presented frames, print resident memory and GPU allocator usage to stderr
    /// (scripts/soak).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub stats: Option<u64>,
    /// The GLSL tree to watch and recompile when a shader changes (default: the source
    /// tree's glsl/ when it exists). Only the pipelines built from a changed shader are
    /// re-created; a compile error is shown with its file:line and the old shaders stay.
    #[arg(long, value_name = "DIR")]
    pub shaders: Option<PathBuf>,
    /// Do not watch any GLSL tree: use the SPIR-V embedded at build time only.
    #[arg(long)]
    pub no_shader_reload: bool,
    /// Test hook: exit (writing --screenshot) two frames after the Nth successful shader
    /// reload.
    #[arg(long, hide = true, value_name = "N")]
    pub exit_after_shader_reloads: Option<u32>,
    /// Script a change: after FRAME presented frames, apply `--set KEY=VALUE` to the running
    /// renderer (repeatable). The log names what each change re-created and how long it took.
    #[arg(long, value_name = "FRAME:KEY=VALUE")]
    pub at: Vec<String>,
    /// Test hook: after FRAME presented frames, behave as if the window surface had been
    /// lost (VK_ERROR_SURFACE_LOST_KHR, which X11 cannot be asked to produce): destroy the
    /// surface and swapchain and create new ones, as the error path does.
    #[arg(long, hide = true, value_name = "FRAME")]
    pub lose_surface_at: Option<u64>,
}

/// A number in [0, 1].
fn unit_fraction(v: &str) -> Result<f32, String> {
    match v.parse::<f32>() {
        Ok(f) if (0.0..=1.0).contains(&f) => Ok(f),
        _ => Err(format!("{v:?} is not a fraction of the width in [0, 1]")),
    }
}

/// `--resize-at FRAME WxH`, each time it is given (clap hands the pairs over in one list).
fn parse_resize(v: &[String]) -> Result<Vec<(u64, u32, u32)>> {
    v.chunks_exact(2)
        .map(|pair| {
            let (frame, size) = (&pair[0], &pair[1]);
            let frame: u64 = frame.parse().with_context(|| format!("--resize-at: bad frame number {frame:?}"))?;
            let (w, h) = size.split_once('x').with_context(|| format!("--resize-at: size {size:?} is not WxH"))?;
            let (w, h): (u32, u32) = (w.parse()?, h.parse()?);
            if w == 0 || h == 0 {
                bail!("--resize-at: the size must be at least 1x1");
            }
            Ok((frame, w, h))
        })
        .collect()
}

/// The GLSL tree the window watches: `--shaders`, else the source tree's when it exists.
fn shader_dir(args: &DemoArgs) -> Option<PathBuf> {
    if args.no_shader_reload {
        return None;
    }
    let dir = args.shaders.clone().unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl"));
    dir.is_dir().then_some(dir)
}

/// `--at FRAME:KEY=VALUE`.
fn parse_at(v: &[String]) -> Result<Vec<(u64, String)>> {
    v.iter()
        .map(|a| {
            let (frame, set) = a.split_once(':').with_context(|| format!("--at {a:?}: write FRAME:KEY=VALUE"))?;
            let frame: u64 = frame.parse().with_context(|| format!("--at {a:?}: bad frame number {frame:?}"))?;
            if !set.contains('=') {
                bail!("--at {a:?}: the change must be KEY=VALUE, e.g. 10:render.hu_qin.search_steps=4");
            }
            Ok((frame, set.to_string()))
        })
        .collect()
}

pub fn run(mut args: DemoArgs) -> Result<()> {
    let resize_at = parse_resize(&args.resize_at)?;
    let at = parse_at(&args.at)?;
    if let Some(dir) = args.shaders.as_deref().filter(|d| !d.is_dir()) {
        bail!("--shaders {}: not a directory (give the GLSL tree to watch, e.g. glsl)", dir.display());
    }
    // Refuse a bad change now, not after FRAME frames: every change applied at once must load.
    if !at.is_empty() {
        let mut all = args.scene.clone();
        all.set.extend(at.iter().map(|(_, s)| s.clone()));
        all.load()?;
    }
    let path = resolve_scene_path(args.scene.scene.as_deref());
    let mut scene = args.scene.load()?;
    // Volume scenes open with the adaptive tone map (Ihrke et al. 2007 §5.3 displays its
    // HDR results so) unless the scene file or a --set names one; headless output keeps the
    // scene's setting. As the first override, every later --set or overlay choice wins.
    if scene.volume.is_some() && !scene.render.tonemap_named {
        args.scene.set.insert(0, "render.tonemap=adaptive".into());
        scene = args.scene.load()?;
    }
    let mut outputs = Outputs::default();
    let screenshot = outputs.prepare_opt(args.screenshot.as_deref())?;
    let screenshot_exr = outputs.prepare_opt(args.screenshot_exr.as_deref())?;
    if (screenshot.is_some() || screenshot_exr.is_some()) && args.frames.is_none() {
        bail!("--screenshot needs --frames N (interactively, F12 writes screenshots)");
    }
    if args.frames == Some(0) {
        bail!("--frames must be at least 1");
    }
    let event_loop = EventLoop::new()
        .map_err(|e| anyhow::anyhow!("no display: run under xvfb-run or set DISPLAY (the window system said: {e})"))?;
    let mut app = App {
        args,
        path,
        resize_at,
        at,
        screenshot,
        screenshot_exr,
        initial: Some(scene),
        running: None,
        result: Ok(()),
    };
    event_loop.run_app(&mut app).context("the window event loop failed")?;
    app.result
}

struct App {
    args: DemoArgs,
    path: PathBuf,
    resize_at: Vec<(u64, u32, u32)>,
    /// Scripted changes (`--at`), by frame.
    at: Vec<(u64, String)>,
    screenshot: Option<OutputFile>,
    screenshot_exr: Option<OutputFile>,
    /// The scene loaded before the window opened, taken by `resumed`.
    initial: Option<Scene>,
    running: Option<Running>,
    result: Result<()>,
}

/// What a Ctrl or Shift drag holds: the override it edits, the point grabbed (moves with
/// the cursor in the plane facing the camera) and the value it writes (moves with it).
struct Grab {
    key: String,
    anchor: Vec3,
    value: Vec3,
    /// The object dragged (Ctrl): moved in place by `Renderer::move_object`, so its distance
    /// impostors regenerate only past `render.impostor.regenerate_distance` (Szirmay-Kalos et
    /// al. 2005, §6) instead of with every rebuilt renderer.
    object: Option<String>,
}

/// Everything that exists while the window is open. Field order is drop order: GPU objects
/// before the context, the surface (in the swapchain) before the window.
struct Running {
    /// The A/B view's exact renderer (GPU objects, dropped before the context).
    ab: ab::AbView,
    renderer: Renderer,
    overlay: Overlay,
    swapchain: Swapchain,
    ctx: Arc<GpuContext>,
    egui: egui_winit::State,
    window: Arc<Window>,

    scene: Scene,
    /// The swapchain images as registered in the current renderer's frame graph.
    swap_ids: Vec<ImageId>,
    swapchain_stale: bool,
    needs_rebuild: bool,
    /// What asked for the next rebuild, for its log line (None: the animation, or no log).
    change: Option<String>,
    /// The changes `--at` applied so far, as `--set`s after the command line's.
    scripted: Vec<String>,
    /// The GLSL tree being watched, if any.
    shader_watch: Option<shaders::ShaderWatch>,
    /// Successful shader reloads so far, and the frame at which to exit after them
    /// (`--exit-after-shader-reloads`).
    shader_reloads: u32,
    exit_at: Option<u64>,
    /// Scene updates applied to the renderer (changes, resizes, reloads).
    updates: u32,
    /// An object was moved in the renderer (Ctrl + drag): reload the CPU scene (picking, the
    /// overlay's fields) from the overrides once the drag ends, without a new renderer.
    scene_stale: bool,
    /// The scene file changed on disk: report the outcome of the rebuild.
    reloading: bool,
    camera: CameraController,
    ui: ui::UiState,
    stats: ui::Stats,
    /// The intermediate target shown in place of the final image, and its name.
    target_texture: Option<(String, egui::TextureHandle)>,
    /// `--show-target`: a name no image has is an error, not a status line.
    args_target: Option<String>,
    cursor: Option<Vec2>,
    /// Keyboard modifiers: Ctrl + drag moves an object, Shift + drag the light.
    modifiers: winit::keyboard::ModifiersState,
    /// An object or the light being dragged in the view.
    grab: Option<Grab>,
    start: Instant,
    /// The water's time while the overlay animates it (on the GPU), kept when it stops.
    water_time: Option<f32>,
    last_frame: Instant,
    scene_mtime: Option<SystemTime>,
    last_poll: Instant,
    frames: u64,
    screenshots: u32,
    /// Frames shown while the light simulation was still running.
    frames_in_progress: u64,
    /// Long work in progress (its task, detail and fraction done), for the overlay.
    progress: Arc<std::sync::Mutex<Option<ui::WorkProgress>>>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        let Some(scene) = self.initial.take() else { return };
        match Running::new(event_loop, &self.args, &self.path, scene) {
            Ok(r) => self.running = Some(r),
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(r) = self.running.as_mut() else { return };
        match event {
            WindowEvent::CloseRequested => self.finish(event_loop),
            WindowEvent::RedrawRequested => {
                let outcome = r.frame(&self.args);
                match outcome {
                    Ok(true) => {}
                    Ok(false) => return self.finish(event_loop),
                    Err(e) => return self.fail(event_loop, e),
                }
                if self.args.lose_surface_at == Some(r.frames) {
                    if let Err(e) = r.recreate_surface() {
                        return self.fail(event_loop, e);
                    }
                }
                for (_, set) in self.at.iter().filter(|(f, _)| *f == r.frames) {
                    r.scripted.push(set.clone());
                    r.change = Some(set.clone());
                    r.needs_rebuild = true;
                }
                for &(_, w, h) in self.resize_at.iter().filter(|(f, ..)| *f == r.frames) {
                    eprintln!("demo: requesting a resize to {w}x{h}");
                    let _ = r.window.request_inner_size(PhysicalSize::new(w, h));
                }
                if self.args.stats.is_some_and(|n| r.frames % n == 0) {
                    super::print_stats(r.frames, &r.ctx);
                }
                if self.args.frames.is_some_and(|n| r.frames >= n) || r.exit_at.is_some_and(|f| r.frames >= f) {
                    eprintln!("demo: {} frames, {} renderer updates", r.frames, r.updates);
                    if r.ui.counts {
                        r.print_counts();
                    }
                    self.finish(event_loop)
                }
            }
            event => {
                if r.input(event) {
                    self.finish(event_loop)
                }
            }
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(r) = self.running.as_mut() else { return };
        let size = r.window.inner_size();
        if size.width == 0 || size.height == 0 {
            // Minimized: pause rendering, look again in a while.
            event_loop.set_control_flow(ControlFlow::WaitUntil(Instant::now() + Duration::from_millis(100)));
        } else {
            event_loop.set_control_flow(ControlFlow::Poll);
            r.window.request_redraw();
        }
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        self.shutdown();
    }
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        if self.result.is_ok() {
            self.result = Err(e);
        }
        self.shutdown();
        event_loop.exit();
    }

    /// Normal end: write the requested screenshots, check validation, close.
    fn finish(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(r) = self.running.as_mut() {
            // What the overlay shows of the running mean, for scripted runs (--frames).
            if let Some(n) = r.renderer.accumulated_frames() {
                let limit = RaytraceParams::from_settings(&r.scene.render).map_or(1, |p| p.accumulate);
                eprintln!("demo: raytrace: {n} of {limit} frames accumulated");
            }
            let png = self.screenshot.take();
            let exr = self.screenshot_exr.take();
            if png.is_some() || exr.is_some() {
                if let Err(e) = r.write_screenshot(png, exr) {
                    return self.fail(event_loop, e);
                }
            }
        }
        self.shutdown();
        event_loop.exit();
    }

    /// Free every GPU object (renderer, overlay, swapchain: each waits for the device), then
    /// check what the validation layer reported.
    fn shutdown(&mut self) {
        if let Some(r) = self.running.take() {
            let Running { ab, renderer, overlay, swapchain, ctx, window, .. } = r;
            drop(ab);
            drop(renderer);
            drop(overlay);
            drop(swapchain);
            let checked = check_validation(&ctx);
            drop(ctx);
            drop(window);
            if let Err(e) = checked {
                if self.result.is_ok() {
                    self.result = Err(e);
                }
            }
        }
    }
}

fn mtime(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

impl Running {
    fn new(event_loop: &ActiveEventLoop, args: &DemoArgs, path: &Path, scene: Scene) -> Result<Running> {
        let (w, h) = (scene.camera.width, scene.camera.height);
        let attributes = Window::default_attributes()
            .with_title(format!("prism: {}", scene.name))
            .with_inner_size(PhysicalSize::new(w, h));
        let window = Arc::new(event_loop.create_window(attributes).context("cannot open a window")?);
        let display = window.display_handle().context("the window has no display handle")?.as_raw();
        let ctx = GpuContext::for_display(&args.gpu.desc(), display)?;
        let progress = Arc::new(std::sync::Mutex::new(None));
        ctx.set_progress(window_progress(window.clone(), format!("prism: {}", scene.name), progress.clone()));
        let size = window.inner_size();
        let swapchain =
            Swapchain::new(&ctx, &*window, (size.width, size.height), args.vsync == OnOff::On, FRAMES_IN_FLIGHT)
                .context("cannot create the swapchain")?;
        let overlay = Overlay::new(&ctx, &swapchain, FRAMES_IN_FLIGHT).context("cannot create the overlay")?;
        let renderer = Renderer::new(&ctx, &scene).context("cannot set up the renderer")?;
        let egui_ctx = egui::Context::default();
        let max_texture = ctx.limits().max_image_dimension2_d as usize;
        let egui = egui_winit::State::new(
            egui_ctx,
            egui::ViewportId::ROOT,
            &*window,
            Some(window.scale_factor() as f32),
            None,
            Some(max_texture),
        );
        eprintln!(
            "demo: {} on {}, window {}x{}, swapchain {}x{} ({:?})",
            scene.name,
            ctx.info.name,
            size.width,
            size.height,
            swapchain.extent().width,
            swapchain.extent().height,
            swapchain.present_mode()
        );
        let now = Instant::now();
        let mut r = Running {
            ab: ab::AbView::default(),
            renderer,
            overlay,
            swapchain,
            ctx,
            egui,
            window,
            camera: CameraController::new(scene.camera),
            scene,
            swap_ids: Vec::new(),
            swapchain_stale: false,
            needs_rebuild: false,
            change: None,
            scripted: Vec::new(),
            shader_watch: shader_dir(args).map(shaders::ShaderWatch::new),
            shader_reloads: 0,
            exit_at: None,
            updates: 0,
            scene_stale: false,
            reloading: false,
            ui: ui::UiState {
                counts: args.pipeline_stats,
                shown_target: args.show_target.clone(),
                ab: ab::AbOptions { on: args.ab, photons: args.ab_photons, split: args.ab_split, ..Default::default() },
                ..ui::UiState::new(!args.no_overlay)
            },
            stats: ui::Stats::default(),
            target_texture: None,
            args_target: args.show_target.clone(),
            cursor: None,
            modifiers: Default::default(),
            grab: None,
            start: now,
            water_time: None,
            last_frame: now,
            scene_mtime: mtime(path),
            last_poll: now,
            frames: 0,
            screenshots: 0,
            frames_in_progress: 0,
            progress,
        };
        r.register_swapchain();
        if let Some(w) = &r.shader_watch {
            eprintln!("demo: watching {} for shader changes", w.dir().display());
        }
        Ok(r)
    }

    /// Register the swapchain images with the current renderer's frame graph.
    fn register_swapchain(&mut self) {
        let graph = self.renderer.graph_mut();
        self.swap_ids = self
            .swapchain
            .images()
            .iter()
            .enumerate()
            .map(|(i, img)| {
                graph.register_external_image(img.raw, vk::ImageAspectFlags::COLOR, 1, &format!("swapchain_{i}"))
            })
            .collect();
    }

    fn has_heightfield(&self) -> bool {
        self.scene.objects.iter().any(|o| o.shape == "heightfield")
    }

    /// Every override: the command line's, the window size, the overlay's, the animation time.
    fn overrides(&self, args: &DemoArgs, size: (u32, u32)) -> Vec<String> {
        let mut o = args.scene.set.clone();
        o.extend(self.scripted.iter().cloned());
        o.push(format!("camera.width={}", size.0));
        o.push(format!("camera.height={}", size.1));
        o.extend(self.ui.overrides.iter().map(|(k, v)| format!("{k}={v}")));
        if let Some(t) = self.water_time {
            for (i, obj) in self.scene.objects.iter().enumerate() {
                if obj.shape == "heightfield" {
                    o.push(format!("objects.{i}.time={t}"));
                }
            }
        }
        o
    }

    /// Reload the scene with the current overrides and rebuild the renderer at `size`.
    /// A failure keeps the previous scene and renderer and shows the error in the overlay.
    fn rebuild(&mut self, args: &DemoArgs, path: &Path, size: (u32, u32)) -> Result<()> {
        let overrides = self.overrides(args, size);
        let scene = match scene::load(path, &overrides) {
            Ok(s) => s,
            Err(e) => {
                if self.ui.error.as_deref() != Some(&e.to_string()) {
                    eprintln!("demo: scene error (the last good scene stays on screen): {e}");
                }
                self.ui.error = Some(e.to_string());
                return Ok(());
            }
        };
        match self.renderer.update(&scene) {
            Ok(update) => {
                self.updates += 1;
                if update.rebuilt {
                    self.register_swapchain();
                }
                if let Some(change) = self.change.take() {
                    eprintln!("demo: frame {}: {change}: {} {}", self.frames, update.describe(), update.cost());
                    self.ui.status = Some(format!("{change}: {}", update.describe()));
                }
                let camera_moved = scene.camera.position != self.scene.camera.position
                    || scene.camera.target != self.scene.camera.target
                    || scene.camera.up != self.scene.camera.up
                    || scene.camera.vfov_deg != self.scene.camera.vfov_deg;
                if camera_moved {
                    // The file's camera changed (hot reload): start from it.
                    self.camera = CameraController::new(scene.camera);
                }
                self.scene = scene;
                if std::mem::take(&mut self.reloading) {
                    eprintln!("demo: reloaded {}", path.display());
                    self.ui.status = Some(format!("reloaded {}", path.display()));
                }
                self.ui.error = None;
                self.stats.clear_gpu();
            }
            Err(RenderError::Gpu(e @ (GpuError::Vk { .. } | GpuError::Alloc { .. }))) => {
                return Err(e).context("cannot rebuild the renderer");
            }
            Err(e) => self.ui.error = Some(format!("{e}")),
        }
        Ok(())
    }

    /// Recompile the shaders that changed on disk and re-create the techniques built from
    /// them. A compile error goes to the overlay and the log; the running shaders stay.
    fn poll_shaders(&mut self, args: &DemoArgs) -> Result<()> {
        let Some(watch) = self.shader_watch.as_mut() else { return Ok(()) };
        let changed = watch.poll();
        if changed.is_empty() {
            return Ok(());
        }
        let dir = watch.dir().to_path_buf();
        let (mut compiled, mut errors) = (Vec::new(), Vec::new());
        for rel in &changed {
            match crate::gpu::compile_shader(&dir, rel) {
                Ok((code, _)) => {
                    self.ctx.set_shader(rel, code);
                    compiled.push(rel.clone());
                }
                Err(e) => errors.push(e),
            }
        }
        if !errors.is_empty() {
            let e = errors.join("\n");
            eprintln!("demo: shader error (the last good shaders stay in use):\n{e}");
            self.ui.error = Some(e);
        }
        if compiled.is_empty() {
            return Ok(());
        }
        match self.renderer.reload_shaders(&self.scene, &compiled) {
            Ok(update) => {
                if update.rebuilt {
                    self.register_swapchain();
                }
                let names = compiled.iter().map(|r| format!("glsl/{r}")).collect::<Vec<_>>().join(", ");
                eprintln!("demo: frame {}: {names} recompiled: {} {}", self.frames, update.describe(), update.cost());
                self.ui.status = Some(format!("{names} recompiled"));
                if errors.is_empty() {
                    self.ui.error = None;
                }
                self.shader_reloads += 1;
                if args.exit_after_shader_reloads.is_some_and(|n| self.shader_reloads >= n) {
                    self.exit_at = Some(self.frames + 2);
                }
            }
            Err(RenderError::Gpu(e @ (GpuError::Vk { .. } | GpuError::Alloc { .. }))) => {
                return Err(e).context("cannot re-create the pipelines of the reloaded shaders");
            }
            Err(e) => self.ui.error = Some(format!("{e}")),
        }
        Ok(())
    }

    /// Handle one input event. Returns true when the user asked to quit.
    fn input(&mut self, event: WindowEvent) -> bool {
        let response = self.egui.on_window_event(&self.window, &event);
        let egui_ctx = self.egui.egui_ctx().clone();
        match event {
            WindowEvent::Resized(_) => self.swapchain_stale = true,
            WindowEvent::Focused(false) => self.camera.release_all(),
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else { return false };
                let pressed = event.state == ElementState::Pressed;
                if response.consumed && pressed {
                    return false;
                }
                self.camera.set_key(code, pressed);
                if pressed && !event.repeat {
                    match code {
                        KeyCode::Escape => return true,
                        KeyCode::Tab => self.camera.toggle_mode(),
                        KeyCode::KeyR => self.camera.reset(),
                        KeyCode::F1 | KeyCode::KeyH => self.ui.visible = !self.ui.visible,
                        KeyCode::F5 => self.needs_rebuild = true,
                        KeyCode::F12 | KeyCode::KeyP => self.screenshot_now(),
                        KeyCode::Space => self.ui.animate = !self.ui.animate,
                        _ => {}
                    }
                }
                if pressed {
                    self.move_light(code);
                }
            }
            WindowEvent::ModifiersChanged(m) => self.modifiers = m.state(),
            WindowEvent::MouseInput { state, button, .. } => {
                let pressed = state == ElementState::Pressed;
                if pressed && (response.consumed || egui_ctx.wants_pointer_input()) {
                    return false;
                }
                if button == MouseButton::Left && !pressed && self.grab.take().is_some() {
                    return false;
                }
                if button == MouseButton::Left
                    && pressed
                    && (self.modifiers.control_key() || self.modifiers.shift_key())
                {
                    self.grab = self.start_grab();
                    return false;
                }
                let drag = match button {
                    MouseButton::Left => Some(Drag::Rotate),
                    MouseButton::Right | MouseButton::Middle => Some(Drag::Pan),
                    _ => None,
                };
                if drag.is_some() {
                    self.camera.set_drag(if pressed { drag } else { None });
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let p = Vec2::new(position.x as f32, position.y as f32);
                if let (Some(last), Some(grab)) = (self.cursor, self.grab.as_mut()) {
                    let (w, h) = (self.renderer.width(), self.renderer.height());
                    let delta = drag::drag_delta(&self.camera.camera(w, h), grab.anchor, last, p, w, h);
                    grab.anchor += delta;
                    grab.value += delta;
                    self.ui.overrides.insert(grab.key.clone(), ui::format_vec(grab.value));
                    let moved = match &grab.object {
                        Some(name) => self.renderer.move_object(name, grab.value),
                        None => Ok(false),
                    };
                    match moved {
                        Ok(true) => self.scene_stale = true,
                        // The light, or a failed move: rebuild from the overrides.
                        Ok(false) | Err(_) => self.needs_rebuild = true,
                    }
                } else if let Some(last) = self.cursor {
                    if self.camera.dragging() {
                        self.camera.mouse_moved(p - last);
                    }
                }
                self.cursor = Some(p);
            }
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::MouseWheel { delta, .. } => {
                if response.consumed || egui_ctx.wants_pointer_input() {
                    return false;
                }
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.camera.wheel(lines);
            }
            _ => {}
        }
        false
    }

    /// Ctrl + click grabs the object under the cursor (one whose scene entry has a `center`),
    /// Shift + click grabs point light 0.
    fn start_grab(&mut self) -> Option<Grab> {
        let cursor = self.cursor?;
        let (w, h) = (self.renderer.width(), self.renderer.height());
        let cam = self.camera.camera(w, h);
        if self.modifiers.shift_key() {
            let scene::Light::Point { position, .. } = self.scene.lights.first()? else { return None };
            return Some(Grab { key: "lights.0.position".into(), anchor: *position, value: *position, object: None });
        }
        let centers = ui::object_centers(&self.scene);
        let candidates: Vec<usize> = centers.iter().map(|c| c.0).collect();
        let (o, d) = drag::cursor_ray(&cam, cursor, w, h);
        let (index, t) = drag::pick(&self.scene, &candidates, o, d)?;
        let (_, name, center) = centers.iter().find(|c| c.0 == index)?.clone();
        Some(Grab { key: format!("objects.{index}.center"), anchor: o + d * t, value: center, object: Some(name) })
    }

    /// Arrow keys move light 0 in the horizontal plane, Page Up/Down along up (a point
    /// light); a directional light's direction turns the same way.
    fn move_light(&mut self, code: KeyCode) {
        let (right, up, back) = self.camera.frame();
        let dir = match code {
            KeyCode::ArrowLeft => -right,
            KeyCode::ArrowRight => right,
            KeyCode::ArrowUp => -back,
            KeyCode::ArrowDown => back,
            KeyCode::PageUp => up,
            KeyCode::PageDown => -up,
            _ => return,
        };
        let step = match self.scene.lights.first() {
            Some(scene::Light::Point { .. }) => self.camera.scale() * 0.05,
            _ => 0.05,
        };
        if let Some((k, v)) = ui::light_override(&self.scene, dir * step) {
            self.ui.overrides.insert(k, v);
            self.needs_rebuild = true;
        }
    }

    /// F12: the current frame without the overlay, as PNG and EXR in the working directory.
    fn screenshot_now(&mut self) {
        self.screenshots += 1;
        let stem = format!("prism-{}-{}", self.scene.name, self.screenshots);
        let result = (|| -> Result<()> {
            let mut outputs = Outputs::default();
            let png = outputs.prepare(Path::new(&format!("{stem}.png")))?;
            let exr = outputs.prepare(Path::new(&format!("{stem}.exr")))?;
            self.write_screenshot(Some(png), Some(exr))
        })();
        match result {
            Ok(()) => self.ui.status = Some(format!("wrote {stem}.png and {stem}.exr")),
            Err(e) => self.ui.error = Some(format!("screenshot: {e:#}")),
        }
    }

    fn write_screenshot(&mut self, png: Option<OutputFile>, exr: Option<OutputFile>) -> Result<()> {
        let (w, h) = (self.renderer.width(), self.renderer.height());
        // The A/B view's picture when it is on: the window's image without the overlay.
        let ldr = match &self.ab.picture {
            Some((pw, ph, pixels)) if (*pw, *ph) == (w, h) => pixels.clone(),
            _ => self.renderer.read_ldr()?,
        };
        let png = png.map(|png| output::write_png(png, w, h, &ldr)).transpose()?;
        let exr = exr.map(|exr| output::write_exr(exr, w, h, &self.renderer.read_hdr()?)).transpose()?;
        let written: Vec<_> = png.into_iter().chain(exr).collect();
        let paths: Vec<_> = written.iter().map(|f| f.path().display().to_string()).collect();
        output::commit_all(written)?;
        for path in paths {
            eprintln!("demo: wrote {path} ({w}x{h})");
        }
        Ok(())
    }

    /// Poll the scene file's modification time (twice a second) for hot reload.
    fn poll_scene_file(&mut self, path: &Path) {
        if self.last_poll.elapsed() < Duration::from_millis(500) {
            return;
        }
        self.last_poll = Instant::now();
        let now = mtime(path);
        if now != self.scene_mtime {
            self.scene_mtime = now;
            self.needs_rebuild = true;
            self.reloading = true;
        }
    }

    /// Recreate the swapchain (and the overlay's framebuffers) for the window's size.
    /// Returns false while the window has no area.
    fn refresh_swapchain(&mut self) -> Result<bool> {
        let size = self.window.inner_size();
        let ready = match self.swapchain.recreate((size.width, size.height)) {
            Ok(ready) => ready,
            Err(GpuError::SurfaceLost) => {
                self.recreate_surface()?;
                return Ok(self.swapchain.is_ready());
            }
            Err(e) => return Err(e).context("cannot recreate the swapchain"),
        };
        self.overlay.set_targets(&self.swapchain)?;
        self.register_swapchain();
        self.swapchain_stale = false;
        if ready {
            let e = self.swapchain.extent();
            eprintln!("demo: swapchain {}x{}", e.width, e.height);
        }
        Ok(ready)
    }

    /// The surface was lost: make a new surface and swapchain for the same window.
    fn recreate_surface(&mut self) -> Result<()> {
        eprintln!("demo: the window surface was lost; creating a new one");
        let size = self.window.inner_size();
        self.swapchain
            .recreate_surface(&*self.window, (size.width, size.height))
            .context("cannot recreate the window surface")?;
        self.overlay.set_targets(&self.swapchain)?;
        self.register_swapchain();
        Ok(())
    }

    /// Render and present one frame. Returns false when the window should close.
    /// Read the target the overlay shows back after the last frame (layer 0, or slice 0 of a
    /// volume) into the overlay's texture: values clamped to [0, 1], or mapped from their
    /// finite min..max with "min..max"; one channel grey, two red-green. Returns the names of
    /// the images that can be shown.
    fn update_shown_target(&mut self, egui_ctx: &egui::Context) -> Result<Vec<String>> {
        let images = self.renderer.frame_images();
        let names = images.iter().filter(|i| i.unreadable.is_none()).map(|i| i.name.clone()).collect();
        let Some(name) = self.ui.shown_target.clone() else {
            self.target_texture = None;
            return Ok(names);
        };
        if self.frames == 0 {
            // Nothing rendered yet: no image holds anything to show.
            return Ok(names);
        }
        let found = images.iter().find(|i| i.name == name && i.unreadable.is_none());
        let values = match found {
            Some(image) => self.renderer.read_frame_image(image)?.map(|v| (image, v)),
            None => None,
        };
        let Some((image, values)) = values else {
            if self.target_texture.is_none() && self.args_target.as_ref() == Some(&name) {
                anyhow::bail!(
                    "--show-target {name}: scene {} has no such image (written in the first frame); its images: {}",
                    self.scene.name,
                    names.join(", ")
                );
            }
            let why = format!("no image {name} to show in this frame (the overlay's \"show\" list has them)");
            eprintln!("demo: {why}");
            self.ui.status = Some(why);
            self.ui.shown_target = None;
            self.target_texture = None;
            return Ok(names);
        };
        let (w, h, c) = (image.width as usize, image.height as usize, image.channels.max(1) as usize);
        let shown = |t: &[f32]| match c {
            1 => [t[0]; 3],
            2 => [t[0], t[1], 0.0],
            _ => [t[0], t[1], t[2]],
        };
        let texels: Vec<[f32; 3]> = values.chunks_exact(c).take(w * h).map(shown).collect();
        let (lo, hi) = match self.ui.normalize_target {
            true => texels
                .iter()
                .flatten()
                .filter(|v| v.is_finite())
                .fold((f32::MAX, f32::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v))),
            false => (0.0, 1.0),
        };
        let scale = if hi > lo { 1.0 / (hi - lo) } else { 0.0 };
        // NaN maps to black (`as u8` saturates and takes NaN to 0).
        let byte = |v: f32| (((v - lo) * scale).clamp(0.0, 1.0) * 255.0).round() as u8;
        let pixels = texels.iter().map(|t| egui::Color32::from_rgb(byte(t[0]), byte(t[1]), byte(t[2]))).collect();
        let picture = egui::ColorImage::new([w, h], pixels);
        match &mut self.target_texture {
            Some((shown_name, texture)) if *shown_name == name => texture.set(picture, egui::TextureOptions::NEAREST),
            _ => {
                eprintln!("demo: showing {name} ({w}x{h}, {}) in place of the final image", image.format);
                let texture = egui_ctx.load_texture("shown_target", picture, egui::TextureOptions::NEAREST);
                self.target_texture = Some((name, texture));
            }
        }
        Ok(names)
    }

    /// The overlay's counts of the last frame, one line per pass, to stderr.
    fn print_counts(&self) {
        for (name, _, _, counts) in self.stats.passes() {
            if let Some(c) = counts {
                let compute = c.compute_invocations.map_or_else(|| "-".to_string(), |n| n.to_string());
                eprintln!(
                    "demo: counts {name}: {} vertices, {} fragments, {compute} compute",
                    c.vertex_invocations, c.fragment_invocations
                );
            }
        }
    }

    fn frame(&mut self, args: &DemoArgs) -> Result<bool> {
        let now = Instant::now();
        let dt = now.duration_since(self.last_frame).as_secs_f32();
        self.last_frame = now;
        let size = self.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(true);
        }
        if (self.swapchain_stale || !self.swapchain.is_ready()) && !self.refresh_swapchain()? {
            return Ok(true);
        }
        let extent = self.swapchain.extent();
        let path = resolve_scene_path(args.scene.scene.as_deref());
        self.poll_scene_file(&path);
        self.poll_shaders(args)?;
        let resized = (self.renderer.width(), self.renderer.height()) != (extent.width, extent.height);
        if self.ui.animate && self.has_heightfield() {
            // Only the water's vertices move, on the GPU; when the animation stops, what is
            // fitted to where things are catches up at the time it stopped at.
            let t = self.start.elapsed().as_secs_f32();
            self.water_time = Some(t);
            self.renderer.animate(t);
        } else if self.renderer.animated() {
            self.scene_stale = true;
            self.change.get_or_insert_with(|| "water animation stopped".to_string());
        }
        if resized && self.change.is_none() {
            self.change = Some(format!("resize to {}x{}", extent.width, extent.height));
        }
        if self.needs_rebuild || resized {
            self.needs_rebuild = false;
            self.scene_stale = false;
            self.rebuild(args, &path, (extent.width, extent.height))?;
        } else if self.scene_stale && self.grab.is_none() {
            // After a Ctrl + drag: while dragging, only the object's vertices followed the
            // cursor; now everything built from positions catches up (impostor rectangles,
            // light frusta, photon rectangles, distance impostors, shadow faces).
            self.scene_stale = false;
            self.change.get_or_insert_with(|| "object moved".to_string());
            self.rebuild(args, &path, (extent.width, extent.height))?;
        }
        self.camera.update(dt);
        let camera = self.camera.camera(self.renderer.width(), self.renderer.height());
        self.renderer.set_camera(&camera);
        // The overlay's counts: the queries start with the next frame (and again after a
        // rebuilt renderer, which starts without them).
        if self.ui.counts && !self.renderer.count_pipeline_stats()? {
            self.ui.counts = false;
            self.ui.status = Some("this device cannot count pipeline statistics".into());
        }

        // The overlay's UI for this frame.
        let input = self.egui.take_egui_input(&self.window);
        let egui_ctx = self.egui.egui_ctx().clone();
        let present_mode = format!("{:?}", self.swapchain.present_mode());
        let device = self.ctx.info.name.clone();
        let has_heightfield = self.has_heightfield();
        let targets = self.update_shown_target(&egui_ctx)?;
        if self.frames > 0 {
            // Everything the exact image depends on besides the scene file: the camera, the
            // size, the overrides (overlay, scripted, water time) and renderer rebuilds.
            let state =
                format!("{camera:?} {:?} {}", self.overrides(args, (extent.width, extent.height)), self.updates);
            let last = args.frames == Some(self.frames + 1);
            let (ctx, ab) = (self.ctx.clone(), &mut self.ab);
            ab.update(&ctx, &self.scene, camera, state, &mut self.renderer, &self.ui.ab, last, &egui_ctx)?;
        }
        let mut requests = ui::Requests::default();
        let full = egui_ctx.run(input, |c| {
            let view = ui::View {
                scene: &self.scene,
                plan: self.renderer.plan(),
                device: &device,
                render_size: (self.renderer.width(), self.renderer.height()),
                present_mode: &present_mode,
                stats: &self.stats,
                camera_mode: self.camera.mode,
                has_heightfield,
                tonemap: self.renderer.tonemap_stats(),
                memory: self.renderer.technique_memory(),
                targets: &targets,
                target_texture: self.ab.texture.as_ref().or(self.target_texture.as_ref().map(|(_, t)| t)),
                progress: self.progress.lock().unwrap_or_else(|e| e.into_inner()).clone(),
                ab: self.ab.status(),
                accumulated: self.renderer.accumulated_frames(),
            };
            requests = ui::draw(c, &mut self.ui, &view);
        });
        self.egui.handle_platform_output(&self.window, full.platform_output);
        let primitives = egui_ctx.tessellate(full.shapes, full.pixels_per_point);
        self.apply(requests);

        // Acquire with the slot's semaphore once the slot's previous frame has finished.
        let slot = self.renderer.wait_for_next_slot()?;
        let acquired = match self.swapchain.acquire(slot) {
            Ok(a) => a,
            Err(GpuError::SurfaceLost) => {
                self.recreate_surface()?;
                self.swapchain_stale = true;
                return Ok(true);
            }
            Err(e) => return Err(e.into()),
        };
        let Acquired::Image { index, wait, render_done, suboptimal } = acquired else {
            self.swapchain_stale = true;
            return Ok(true);
        };
        self.overlay.update_textures(&full.textures_delta)?;
        let swap_id = self.swap_ids[index as usize];
        let swap_raw = self.swapchain.images()[index as usize].raw;
        // The blit is the image's first use: wait for the acquire there, and let the graph
        // chain its transition from UNDEFINED onto that wait.
        let first_use = vk::PipelineStageFlags::TRANSFER;
        self.renderer.graph_mut().reacquire_image(swap_id, first_use);
        let sync = SubmitSync { wait: vec![(wait, first_use)], signal: vec![render_done] };
        // The adaptive tone map adapts over the frame time (Krawczyk et al. 2005).
        self.renderer.set_tonemap_time_step(Some(dt));
        let show_overlay = self.ui.visible && !primitives.is_empty();
        let overlay = show_overlay.then(|| OverlayDraw {
            overlay: &mut self.overlay,
            pixels_per_point: full.pixels_per_point,
            primitives: &primitives,
        });
        let target = WindowTarget { id: swap_id, raw: swap_raw, extent, index };
        let preparing = self.renderer.preparing();
        // The light simulation of a volume runs a little before each frame, which shows the
        // light simulated so far, so the window answers input meanwhile: at least
        // --work-per-frame, and as long as a frame takes, so that it gets half the time.
        let budget = (args.work_per_frame > 0).then(|| {
            let frame = Duration::from_secs_f64(self.stats.technique_total_ms().max(0.0) / 1000.0);
            Duration::from_millis(args.work_per_frame).max(frame)
        });
        self.renderer.set_work_budget(budget);
        self.renderer.render_to_window(&sync, &target, overlay)?;
        if self.renderer.preparing() {
            self.frames_in_progress += 1;
        } else if preparing {
            let seconds = self.renderer.light_stats().map_or(0.0, |l| l.seconds);
            eprintln!(
                "demo: frame {}: the light simulation finished in {seconds:.2} s; {} frames showed it in progress",
                self.frames, self.frames_in_progress
            );
            self.frames_in_progress = 0;
        }
        match self.swapchain.present(index) {
            Ok(Presented::Ok) => self.swapchain_stale |= suboptimal,
            Ok(Presented::Stale) => self.swapchain_stale = true,
            Err(GpuError::SurfaceLost) => {
                self.recreate_surface()?;
                self.swapchain_stale = true;
            }
            Err(e) => return Err(e.into()),
        }
        self.overlay.free_textures()?;
        for t in self.renderer.take_timings() {
            self.stats.push_gpu(t);
        }
        self.stats.push_cpu(dt as f64 * 1000.0);
        self.frames += 1;
        Ok(true)
    }

    fn apply(&mut self, r: ui::Requests) {
        if r.toggle_mode {
            self.camera.toggle_mode();
        }
        if r.reset_camera {
            self.camera.reset();
        }
        if r.rebuild || r.reload {
            self.needs_rebuild = true;
        }
        if r.screenshot {
            self.screenshot_now();
        }
    }
}

/// Long work inside the renderer (the eikonal light simulation, spread over frames or, with
/// `--work-per-frame 0`, blocking the frame loop): its progress goes to the window's title,
/// which the window system draws even while the loop is blocked, to the overlay (`shown`)
/// and to the log every tenth of the way.
fn window_progress(
    window: Arc<Window>,
    title: String,
    shown: Arc<std::sync::Mutex<Option<ui::WorkProgress>>>,
) -> crate::gpu::ProgressSink {
    let logged = std::sync::Mutex::new(None::<u64>);
    Box::new(move |p| {
        let percent = (100 * p.done).checked_div(p.total).unwrap_or(100u64).min(100);
        *shown.lock().unwrap_or_else(|e| e.into_inner()) = (!p.finished).then(|| ui::WorkProgress {
            task: p.task.to_string(),
            detail: p.detail.to_string(),
            fraction: percent as f32 / 100.0,
        });
        if p.finished {
            window.set_title(&title);
            eprintln!("demo: {} done", p.task);
            *logged.lock().unwrap_or_else(|e| e.into_inner()) = None;
            return;
        }
        window.set_title(&format!("{title} ({} {percent}%)", p.task));
        let mut logged = logged.lock().unwrap_or_else(|e| e.into_inner());
        if logged.is_none_or(|l| percent >= l + 10) {
            eprintln!("demo: {} {percent}%: {}", p.task, p.detail);
            *logged = Some(percent);
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resize_hook_parses_frame_and_size() {
        assert_eq!(parse_resize(&[]).unwrap(), []);
        assert_eq!(parse_resize(&["3".into(), "200x100".into()]).unwrap(), [(3, 200, 100)]);
        let two: Vec<String> = ["3", "200x100", "9", "64x48"].map(String::from).to_vec();
        assert_eq!(parse_resize(&two).unwrap(), [(3, 200, 100), (9, 64, 48)]);
        assert!(parse_resize(&["x".into(), "200x100".into()]).is_err());
        assert!(parse_resize(&["3".into(), "200".into()]).is_err());
        assert!(parse_resize(&["3".into(), "0x5".into()]).is_err());
    }
}
