//! Helpers shared by the integration tests: a validated Vulkan context, small renders of
//! benchmark scenes, and golden-image comparison.
#![allow(dead_code)] // each test binary uses a different subset

use std::path::PathBuf;
use std::sync::{Arc, Condvar, Mutex};
use std::thread::ThreadId;

use prism::gpu::{ContextDesc, GpuContext};
use prism::metrics::image::{diff_heatmap_rgba8, fraction_differing_rgba8, psnr_rgba8};
use prism::renderer::Renderer;
use prism::scene::{self, Scene};

/// Test renders are small (CI has 2 cores and lavapipe): 96^2 unless a test says otherwise.
pub const SIZE: u32 = 96;

/// Whether the tests run under CI: `CI` set to anything non-empty (GitHub sets "true",
/// other services "1" or their name).
pub fn under_ci() -> bool {
    std::env::var_os("CI").is_some_and(|v| !v.is_empty())
}

/// A context with the validation layer on (and synchronization validation if `sync`).
/// Under CI a missing validation layer is a failure: without it "zero validation errors"
/// would be vacuous.
///
/// Every GPU test gets its context here, and the returned [`TestContext`] checks the
/// validation log when it is dropped, teardown included, so no test can forget to.
pub fn context(sync: bool) -> TestContext {
    assert!(
        std::env::var_os(OWN_PROCESS).is_some(),
        "a GPU test must begin with `if !common::in_own_process() {{ return; }}` (see in_own_process)"
    );
    let turn = GpuTurn::take();
    let ctx = GpuContext::new(&ContextDesc { validation: true, sync_validation: sync, device: None })
        .expect("cannot create a Vulkan context (is mesa-vulkan-drivers installed?)");
    if under_ci() {
        assert!(ctx.info.validation, "CI is set but VK_LAYER_KHRONOS_validation is not installed");
    }
    TestContext(Some(ctx), Some(turn))
}

/// Set in the child process that runs one GPU test.
const OWN_PROCESS: &str = "PRISM_TEST_OWN_PROCESS";

/// Runs the calling test again in a process of its own (this test binary, `--exact` this
/// test), and returns `false` in the parent once that child passed, `true` in the child,
/// where the test's body runs. Every GPU test begins with
/// `if !common::in_own_process() { return; }`, and [`context`] refuses to run anywhere else.
///
/// Why: the Khronos validation layer (1.3.239, Debian bookworm) does not survive many
/// instances and devices in one process: test binaries died inside
/// libVkLayer_khronos_validation.so (a general protection fault, and a segfault in an
/// unordered_map lookup with every GPU test of the binary serialised by [`GpuTurn`]), while
/// the CLI tests, one `prism` process each, never did (docs/RELIABILITY.md). A process per
/// test gives each test a fresh layer (and fresh loader and driver state), and lets the
/// binary's tests run in parallel.
///
/// A child killed by a signal (a crash, not a failed assertion, which exits with status
/// 101) is run once more, and the crash is reported on stderr: a C++ exception thrown
/// through a Vulkan call can also end a process that holds a single context, from a C++
/// library under the Vulkan calls (the layer, or LLVM in lavapipe), not from a test's
/// assertions (docs/RELIABILITY.md). A test that crashes twice fails.
#[must_use]
pub fn in_own_process() -> bool {
    use std::os::unix::process::ExitStatusExt;
    if std::env::var_os(OWN_PROCESS).is_some() {
        return true;
    }
    // libtest runs each test on a thread named after it (its full path), whatever the
    // number of test threads.
    let name = std::thread::current().name().expect("libtest names each test's thread").to_string();
    let exe = std::env::current_exe().expect("the test binary's path");
    let run = || {
        std::process::Command::new(&exe)
            .args([name.as_str(), "--exact", "--test-threads=1", "--nocapture"])
            .env(OWN_PROCESS, "1")
            .output()
            .expect("cannot start the test's own process")
    };
    let mut out = run();
    if let Some(signal) = out.status.signal() {
        // Straight to the process's stderr, which libtest does not capture: the crash shows in
        // the log even when the second run passes.
        let notice = format!(
            "{name}: its process was killed by signal {signal} (a crash, not a failed assertion); \
             running it once more. Its output:\n{}{}\n",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        let _ = std::io::Write::write_all(&mut std::io::stderr(), notice.as_bytes());
        out = run();
    }
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    // The child's output, for `--nocapture` and for a failure's report.
    print!("{stdout}");
    eprint!("{stderr}");
    assert!(
        out.status.success() && stdout.contains("test result: ok. 1 passed"),
        "{name} in its own process: {} (its output is above)",
        out.status
    );
    false
}

/// One GPU test at a time in a test binary. The Khronos validation layer (1.3.239, Debian
/// bookworm) is not safe with several instances and devices used from parallel threads of
/// one process: a test binary once died with a general protection fault inside
/// libVkLayer_khronos_validation.so (tests/photon_buffer.rs, the kernel log's trap line) and
/// once with a C++ exception thrown through a Vulkan call (tests/impostor.rs), each after
/// hundreds of clean runs (docs/RELIABILITY.md). Each context holds the binary's turn from
/// its creation to the end of its teardown check; a thread may hold several contexts.
/// Separate processes (the CLI tests' `prism` runs) do not share the layer's state.
struct GpuTurn;

/// The thread holding the turn and how many contexts it holds.
static TURN: (Mutex<Option<(ThreadId, usize)>>, Condvar) = (Mutex::new(None), Condvar::new());

impl GpuTurn {
    fn take() -> GpuTurn {
        let me = std::thread::current().id();
        let mut held = TURN.0.lock().unwrap_or_else(|e| e.into_inner());
        loop {
            match *held {
                None => {
                    *held = Some((me, 1));
                    return GpuTurn;
                }
                Some((t, n)) if t == me => {
                    *held = Some((t, n + 1));
                    return GpuTurn;
                }
                Some(_) => held = TURN.1.wait(held).unwrap_or_else(|e| e.into_inner()),
            }
        }
    }
}

impl Drop for GpuTurn {
    fn drop(&mut self) {
        let mut held = TURN.0.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((t, n)) = *held {
            *held = (n > 1).then_some((t, n - 1));
        }
        TURN.1.notify_all();
    }
}

thread_local! {
    /// The turns of [`TestContext::unchecked`] contexts, given back when the test's thread ends.
    static KEPT: std::cell::RefCell<Vec<GpuTurn>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// A test's Vulkan context. Used as an `Arc<GpuContext>` (it derefs to one); dropping it
/// fails the test on any validation error, then destroys the device and instance and fails
/// on any error the layer reports while they are destroyed: objects still alive at
/// `vkDestroyDevice` (leaks) are reported only then. Everything made from the context
/// (renderers, buffers) must be dropped before it, which Rust's reverse declaration order
/// does for locals declared after it.
pub struct TestContext(Option<Arc<GpuContext>>, Option<GpuTurn>);

impl TestContext {
    /// The context without the teardown check, for a test that expects errors (it keeps the
    /// GPU turn until the test's thread ends).
    pub fn unchecked(mut self) -> Arc<GpuContext> {
        if let Some(turn) = self.1.take() {
            KEPT.with(|k| k.borrow_mut().push(turn));
        }
        self.0.take().unwrap()
    }
}

impl std::ops::Deref for TestContext {
    type Target = Arc<GpuContext>;
    fn deref(&self) -> &Arc<GpuContext> {
        self.0.as_ref().unwrap()
    }
}

impl Drop for TestContext {
    fn drop(&mut self) {
        let Some(ctx) = self.0.take() else { return };
        // A test already failing would abort on a second panic, and its own message says more.
        if std::thread::panicking() {
            return;
        }
        assert_no_validation_errors(&ctx);
        let log = ctx.validation_log();
        assert_eq!(
            Arc::strong_count(&ctx),
            1,
            "the context is still shared at the test's end (drop what holds it first), so its teardown is unchecked"
        );
        drop(ctx);
        assert_eq!(log.errors(), 0, "validation errors at teardown:\n{}", log.messages().join("\n"));
    }
}

pub fn assert_no_validation_errors(ctx: &GpuContext) {
    let n = ctx.validation_errors();
    assert_eq!(n, 0, "validation errors:\n{}", ctx.validation_messages().join("\n"));
}

/// Check `ctx` now, teardown included, rather than where it goes out of scope (see
/// [`TestContext`]'s drop).
pub fn assert_clean_teardown(ctx: TestContext) {
    drop(ctx);
}

/// One glass object of index `ior` alone in the `grid` environment, seen at `size`^2 from
/// `camera` looking at the origin (40 degrees vertical field of view): `object` holds the
/// rest of its `[[objects]]` table (name, shape and its keys; the material is "glass"). The
/// baseline techniques (scene::BASELINE), then `overrides`.
pub fn glass_scene(size: u32, camera: [f32; 3], ior: f32, object: &str, overrides: &[&str]) -> Scene {
    let [x, y, z] = camera;
    let text = format!(
        r#"
        [camera]
        position = [{x}, {y}, {z}]
        target = [0, 0, 0]
        vfov_deg = 40
        width = {size}
        height = {size}
        [environment]
        type = "grid"
        [materials.glass]
        type = "dielectric"
        ior = {ior}
        [[objects]]
        material = "glass"
        {object}
    "#
    );
    let mut o: Vec<String> = scene::BASELINE.iter().map(|s| s.to_string()).collect();
    o.extend(overrides.iter().map(|s| s.to_string()));
    scene::load_str(&text, std::path::Path::new("glass.toml"), &o).unwrap()
}

/// A bundled scene at `size`^2 with the baseline techniques (`prism::scene::BASELINE`:
/// refraction, reflection and caustics "single", "single", "none"), then `overrides`. The
/// scene files select better techniques; starting from the baseline, a test measures what
/// it names, and keeps measuring it when a scene's selection changes. `shipped` loads a
/// scene with its own selection.
pub fn scene(name: &str, size: u32, overrides: &[&str]) -> Scene {
    let mut o: Vec<&str> = scene::BASELINE.to_vec();
    o.extend_from_slice(overrides);
    shipped(name, size, &o)
}

/// A bundled scene at `size`^2 as its file ships it (its own techniques), with extra overrides.
pub fn shipped(name: &str, size: u32, overrides: &[&str]) -> Scene {
    let mut o: Vec<String> = vec![format!("camera.width={size}"), format!("camera.height={size}")];
    o.extend(overrides.iter().map(|s| s.to_string()));
    scene::load(&scene::benchmark_scene_path(name), &o).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// `prism::scene::BASELINE` as command-line arguments (`--set KEY=VALUE` each), for tests
/// that run the `prism` binary on a bundled scene.
pub fn baseline_args() -> Vec<&'static str> {
    scene::BASELINE.iter().flat_map(|s| ["--set", s]).collect()
}

pub struct Rendered {
    pub width: u32,
    pub height: u32,
    pub hdr: Vec<f32>,
    pub ldr: Vec<u8>,
    pub passes: Vec<String>,
}

impl Rendered {
    /// Linear RGB at pixel (i, j), j = 0 the top row.
    pub fn radiance(&self, i: u32, j: u32) -> [f32; 3] {
        let k = 4 * (j * self.width + i) as usize;
        [self.hdr[k], self.hdr[k + 1], self.hdr[k + 2]]
    }
}

/// Render one frame of `scene` on `ctx`, read back HDR and LDR, and check validation, the
/// renderer's teardown included.
pub fn render_on(ctx: &Arc<GpuContext>, scene: &Scene) -> Rendered {
    let mut renderer = None;
    let out = render_after(ctx, scene, &mut renderer);
    drop(renderer);
    assert_no_validation_errors(ctx);
    out
}

/// Render `scene` with a fresh renderer built while `last` (the previous call's) is still
/// alive, then keep the new one in `last`: the context caches pipelines weakly under their
/// description, so a renderer built beside one with the same pipelines reuses them instead of
/// compiling them again (lavapipe takes seconds for the larger shaders). The caller drops
/// `last` at the end and asserts the teardown's validation.
pub fn render_after(ctx: &Arc<GpuContext>, scene: &Scene, last: &mut Option<Renderer>) -> Rendered {
    let mut r = Renderer::new(ctx, scene).expect("renderer");
    r.render_frame().expect("frame");
    let hdr = r.read_hdr().expect("hdr readback");
    let ldr = r.read_ldr().expect("ldr readback");
    let passes = r.plan().iter().map(|p| p.name.to_string()).collect();
    let out = Rendered { width: r.width(), height: r.height(), hdr, ldr, passes };
    *last = Some(r);
    assert_no_validation_errors(ctx);
    out
}

/// Render each of `scenes` in turn with one renderer, taking each next scene as a live change
/// (`Renderer::update`): what a change does not touch is kept, above all the eikonal light
/// simulation when only the view renderer's settings or the image size differ. tests/live.rs
/// shows that a live change renders what a fresh renderer does.
pub fn render_each(ctx: &Arc<GpuContext>, scenes: &[Scene]) -> Vec<Rendered> {
    let mut r = Renderer::new(ctx, &scenes[0]).expect("renderer");
    let mut out = Vec::new();
    for (k, scene) in scenes.iter().enumerate() {
        if k > 0 {
            r.update(scene).expect("live update");
        }
        r.render_frame().expect("frame");
        let hdr = r.read_hdr().expect("hdr readback");
        let ldr = r.read_ldr().expect("ldr readback");
        let passes = r.plan().iter().map(|p| p.name.to_string()).collect();
        out.push(Rendered { width: r.width(), height: r.height(), hdr, ldr, passes });
    }
    drop(r);
    assert_no_validation_errors(ctx);
    out
}

pub fn render(scene: &Scene) -> Rendered {
    let ctx = context(false);
    render_on(&ctx, scene)
}

/// Golden-image limits (see `assert_golden` for where they come from).
pub const MAX_DIFFERING: f64 = 0.002;
pub const MIN_PSNR: f64 = 40.0;

pub fn golden_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden")
}

/// Compare `image` with tests/golden/NAME.png.
///
/// Metric and threshold: lavapipe renders bit-identically run to run on one machine, but
/// another CPU (AVX2 vs AVX-512 llvmpipe), LLVM or Mesa version may round differently, which
/// moves a few silhouette and shadow-edge pixels and shifts smooth regions by a level or
/// two. So the comparison allows at most 0.2% of pixels (33 at 128^2, about the length of
/// one silhouette) to differ by more than 8/255 in any channel, and needs PSNR >= 40 dB.
/// Small real changes exceed both: tests/golden.rs checks that ior 1.5 -> 1.45, and moving
/// sphere_nearby's light by 0.3 m (0.5% of pixels, 36 dB), fail.
///
/// `PRISM_UPDATE_GOLDEN=1` rewrites the reference. A missing reference is written and the
/// test passes, except under CI (`under_ci`), where it fails. On failure NAME-actual.png and
/// NAME-diff.png are written beside the reference.
/// (fraction of pixels differing by more than 8/255, PSNR in dB) of `r` against the golden.
pub fn golden_difference(name: &str, r: &Rendered) -> (f64, f64) {
    let golden = image::open(golden_dir().join(format!("{name}.png"))).expect("golden image").to_rgba8();
    assert_eq!((golden.width(), golden.height()), (r.width, r.height), "{name}: golden size differs");
    let golden = golden.into_raw();
    (fraction_differing_rgba8(&r.ldr, &golden, 8), psnr_rgba8(&r.ldr, &golden))
}

pub fn assert_golden(name: &str, r: &Rendered) {
    let dir = golden_dir();
    let path = dir.join(format!("{name}.png"));
    let actual_path = dir.join(format!("{name}-actual.png"));
    let diff_path = dir.join(format!("{name}-diff.png"));
    // Written beside the target and renamed over it: rename is atomic, so a test binary
    // reading the golden while another rewrites it (tests/golden.rs) sees the old image or
    // the new one, never a partial PNG.
    let save = |p: &PathBuf, data: &[u8]| {
        let tmp = p.with_extension(format!("tmp-{}.png", std::process::id()));
        image::RgbaImage::from_raw(r.width, r.height, data.to_vec()).unwrap().save(&tmp).unwrap();
        std::fs::rename(&tmp, p).unwrap();
    };
    let update = std::env::var("PRISM_UPDATE_GOLDEN").is_ok_and(|v| v == "1");
    if update || !path.exists() {
        assert!(
            update || !under_ci(),
            "golden image {} is missing (CI is set): run the tests locally with PRISM_UPDATE_GOLDEN=1 and commit it",
            path.display()
        );
        save(&path, &r.ldr);
        eprintln!("wrote golden image {}", path.display());
        return;
    }
    let golden = image::open(&path).expect("golden image").to_rgba8();
    assert_eq!((golden.width(), golden.height()), (r.width, r.height), "{name}: golden size differs");
    let golden = golden.into_raw();
    let differing = fraction_differing_rgba8(&r.ldr, &golden, 8);
    let psnr = psnr_rgba8(&r.ldr, &golden);
    if differing > MAX_DIFFERING || psnr < MIN_PSNR {
        save(&actual_path, &r.ldr);
        save(&diff_path, &diff_heatmap_rgba8(&r.ldr, &golden, 32));
        panic!(
            "{name}: {:.2}% of pixels differ by more than 8/255 (limit {:.1}%), PSNR {psnr:.1} dB (limit {MIN_PSNR}); \
             see {} and {}",
            differing * 100.0,
            MAX_DIFFERING * 100.0,
            actual_path.display(),
            diff_path.display()
        );
    }
    let _ = std::fs::remove_file(&actual_path);
    let _ = std::fs::remove_file(&diff_path);
}

/// (column, row) of the brightest pixel (the caustic's focus) of the green channel of an
/// RGBA f32 image, after a 3x3 box filter.
pub fn brightest(img: &[f32], w: usize, h: usize) -> (usize, usize) {
    let mut best = (0, 0, f32::MIN);
    for j in 1..h - 1 {
        for i in 1..w - 1 {
            let mut s = 0.0;
            for dj in 0..3 {
                for di in 0..3 {
                    s += img[4 * ((j + dj - 1) * w + i + di - 1) + 1];
                }
            }
            if s > best.2 {
                best = (i, j, s);
            }
        }
    }
    (best.0, best.1)
}

/// Flux leaving a glass ball of radius r at distance d from a point light of intensity I
/// through both surfaces (exact Fresnel at entry and, by the sphere's symmetry, the same
/// angle at exit): I * integral over the cone of (1 - F(theta_i))^2 dOmega.
pub fn sphere_transmitted_flux(intensity: f64, d: f64, r: f64, ior: f64) -> f64 {
    let alpha = (r / d).asin();
    let steps = 20000;
    let mut sum = 0.0;
    for k in 0..steps {
        let theta = (k as f64 + 0.5) / steps as f64 * alpha;
        let sin_i = (d * theta.sin() / r).min(1.0);
        let cos_i = (1.0 - sin_i * sin_i).sqrt();
        let sin_t = sin_i / ior;
        let cos_t = (1.0 - sin_t * sin_t).sqrt();
        let rs = (cos_i - ior * cos_t) / (cos_i + ior * cos_t);
        let rp = (ior * cos_i - cos_t) / (ior * cos_i + cos_t);
        let f = 0.5 * (rs * rs + rp * rp);
        sum += (1.0 - f) * (1.0 - f) * 2.0 * std::f64::consts::PI * theta.sin() * (alpha / steps as f64);
    }
    intensity * sum
}

/// Fails the test if any value of an image is NaN or infinite.
pub fn assert_finite(name: &str, hdr: &[f32]) {
    let bad = hdr.iter().filter(|v| !v.is_finite()).count();
    assert_eq!(bad, 0, "{name}: {bad} non-finite values");
}

/// Sum of the RGB radiance of an image.
pub fn total(hdr: &[f32]) -> f64 {
    hdr.chunks(4).map(|p| (p[0] + p[1] + p[2]) as f64).sum()
}

/// `--set`-style overrides as the `&[&str]` that `scene` takes.
pub fn refs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

/// Whether a disk of `reach` pixels around image point (x, y) (pixel (floor x, floor y))
/// reaches a pixel whose `selected` differs from its own: a photon gathered by such a disk can
/// count on either side of the selection's border (the flux checks' border share).
pub fn disk_crosses_border(selected: impl Fn(i64, i64) -> bool, x: f32, y: f32, reach: f32) -> bool {
    let (i, j) = (x.floor() as i64, y.floor() as i64);
    let k = reach.ceil() as i64;
    let me = selected(i, j);
    (-k..=k).any(|a| {
        (-k..=k).any(|b| {
            let dx = ((i + a) as f32 - x).max(x - (i + a + 1) as f32).max(0.0);
            let dy = ((j + b) as f32 - y).max(y - (j + b + 1) as f32).max(0.0);
            selected(i + a, j + b) != me && dx * dx + dy * dy < reach * reach
        })
    })
}

/// Render `frames` frames of `scene` counting pipeline statistics and return the renderer and
/// the last frame's counts for the pass `pass` (which must exist): what a pass drew, for tests
/// that check a technique's work, not only its image.
pub fn render_counting(
    ctx: &Arc<GpuContext>,
    scene: &Scene,
    frames: u32,
    pass: &str,
) -> (Renderer, prism::gpu::PassCounts) {
    let mut r = Renderer::new(ctx, scene).expect("renderer");
    assert!(r.count_pipeline_stats().expect("statistics"), "the device counts no pipeline statistics");
    for _ in 0..frames {
        r.render_frame().expect("frame");
    }
    r.finish().expect("finish");
    let timing = r.take_timings().pop().expect("a timed frame");
    let p = timing.passes.iter().find(|p| p.name == pass).unwrap_or_else(|| panic!("no pass {pass}"));
    let counts = p.counts.unwrap_or_else(|| panic!("{pass}: no counts"));
    (r, counts)
}

/// A scratch directory for the files a test writes, unique to this process and call, and
/// removed with everything in it when dropped: a suite run leaves nothing behind in the
/// system's temporary directory.
pub struct ScratchDir(PathBuf);

impl ScratchDir {
    pub fn new(prefix: &str) -> Self {
        static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let d = std::env::temp_dir().join(format!("{prefix}-{}-{call}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("scratch directory");
        ScratchDir(d)
    }

    pub fn path(&self) -> &std::path::Path {
        &self.0
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
