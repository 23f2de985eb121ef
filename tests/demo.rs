//! `prism demo` in a real window under Xvfb, on lavapipe with the validation layer.
//!
//! Uses $DISPLAY when set; otherwise starts its own Xvfb on a free display number and kills
//! it at the end. Without Xvfb the tests skip with a message, except under CI (`CI` set
//! to anything non-empty), where a missing Xvfb is a failure (`./x` installs the `xvfb` package).
mod common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Xvfb display numbers are picked one test at a time.
static PICK: Mutex<()> = Mutex::new(());

/// A display to run on; an Xvfb of our own is stopped on drop.
struct Display {
    name: String,
    xvfb: Option<Child>,
}

impl Drop for Display {
    fn drop(&mut self) {
        if let Some(child) = self.xvfb.as_mut() {
            // SIGTERM, so that Xvfb removes its lock file and socket: a SIGKILLed one leaves
            // both behind, and after a few hundred test runs they filled every display number
            // the picker tries. SIGKILL only if it does not end within 5 s.
            let _ = Command::new("kill").args(["-TERM", &child.id().to_string()]).status();
            let deadline = Instant::now() + Duration::from_secs(5);
            while Instant::now() < deadline && child.try_wait().ok().flatten().is_none() {
                std::thread::sleep(Duration::from_millis(20));
            }
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// Whether display `n` is taken: its lock file names a live process (a lock whose process is
/// gone, and its socket, are left over by a killed X server and are removed).
fn display_taken(n: u32) -> bool {
    let (lock, socket) = (PathBuf::from(format!("/tmp/.X{n}-lock")), PathBuf::from(format!("/tmp/.X11-unix/X{n}")));
    let owner = std::fs::read_to_string(&lock).ok().and_then(|t| t.trim().parse::<u32>().ok());
    match owner {
        Some(pid) if Path::new(&format!("/proc/{pid}")).exists() => true,
        Some(_) => {
            let _ = std::fs::remove_file(&lock);
            let _ = std::fs::remove_file(&socket);
            false
        }
        // No lock (or one being written): taken only while a socket exists.
        None => socket.exists() || lock.exists(),
    }
}

fn in_path(program: &str) -> bool {
    std::env::var_os("PATH").map(|p| std::env::split_paths(&p).any(|d| d.join(program).is_file())).unwrap_or(false)
}

/// The display to use, or None (skip) when there is none and Xvfb is not installed.
fn display() -> Option<Display> {
    if let Some(d) = std::env::var("DISPLAY").ok().filter(|d| !d.is_empty()) {
        return Some(Display { name: d, xvfb: None });
    }
    if !in_path("Xvfb") {
        assert!(
            !common::under_ci(),
            "Xvfb is not installed (apt-get install xvfb; ./x installs it) and DISPLAY is unset"
        );
        eprintln!("skipping: no DISPLAY and no Xvfb (apt-get install xvfb)");
        return None;
    }
    let _guard = PICK.lock().unwrap_or_else(|e| e.into_inner());
    let base = 100 + (std::process::id() % 300);
    for n in base..base + 50 {
        let socket = PathBuf::from(format!("/tmp/.X11-unix/X{n}"));
        if display_taken(n) {
            continue;
        }
        let mut child = Command::new("Xvfb")
            .args([format!(":{n}").as_str(), "-screen", "0", "1024x768x24", "-nolisten", "tcp"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("cannot start Xvfb");
        let deadline = Instant::now() + Duration::from_secs(15);
        while Instant::now() < deadline {
            if socket.exists() {
                return Some(Display { name: format!(":{n}"), xvfb: Some(child) });
            }
            if child.try_wait().ok().flatten().is_some() {
                break; // taken by someone else: try the next number
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = child.kill();
        let _ = child.wait();
    }
    panic!("could not start Xvfb on any display number from :{base}");
}

fn demo(display: &Display, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_prism"))
        .arg("demo")
        .args(common::baseline_args())
        .args(args)
        .env("DISPLAY", &display.name)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("cannot run prism")
}

/// A `prism demo` running in the background, its stderr read line by line.
struct Running {
    child: Child,
    lines: std::sync::mpsc::Receiver<String>,
    log: String,
}

impl Running {
    fn spawn(display: &Display, args: &[&str]) -> Running {
        use std::io::{BufRead, BufReader};
        let mut child = Command::new(env!("CARGO_BIN_EXE_prism"))
            .arg("demo")
            .args(common::baseline_args())
            .args(args)
            .env("DISPLAY", &display.name)
            .env_remove("WAYLAND_DISPLAY")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let (tx, lines) = std::sync::mpsc::channel();
        let stderr = child.stderr.take().unwrap();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                let _ = tx.send(line);
            }
        });
        Running { child, lines, log: String::new() }
    }

    /// Read the log until a line contains `needle` (true), or `secs` seconds pass (false).
    fn wait_for(&mut self, needle: &str, secs: u64) -> bool {
        let deadline = Instant::now() + Duration::from_secs(secs);
        while let Some(left) = deadline.checked_duration_since(Instant::now()) {
            match self.lines.recv_timeout(left) {
                Ok(line) => {
                    self.log.push_str(&line);
                    self.log.push('\n');
                    if line.contains(needle) {
                        return true;
                    }
                }
                Err(_) => return false,
            }
        }
        false
    }

    /// Read what is left of the log once the process has exited.
    fn drain(&mut self) {
        while let Ok(line) = self.lines.recv_timeout(Duration::from_millis(500)) {
            self.log.push_str(&line);
            self.log.push('\n');
        }
    }
}

fn out_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn demo_runs_frames_with_a_resize_and_no_validation_error() {
    let Some(display) = display() else { return };
    let dir = out_dir("demo_resize");
    let shot = dir.join("shot.png");
    let out = demo(
        &display,
        &[
            "sphere_nearby",
            "--frames",
            "6",
            "--width",
            "160",
            "--height",
            "120",
            "--validation",
            "--resize-at",
            "2",
            "200x150",
            "--screenshot",
            shot.to_str().unwrap(),
        ],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "prism demo failed:\n{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!stderr.contains("VUID") && !stderr.contains("SYNC-HAZARD"), "validation messages:\n{stderr}");
    assert!(stderr.contains("swapchain 200x150"), "the swapchain was not recreated at the new size:\n{stderr}");
    // The renderer was rebuilt at the window's new size: the screenshot has it.
    let img = image::open(&shot).expect("screenshot").to_rgba8();
    assert_eq!(img.dimensions(), (200, 150));
}

/// Losing the window surface is survived: the surface and swapchain are created anew (the
/// error path for VK_ERROR_SURFACE_LOST_KHR, driven by a test hook since X11 cannot be asked
/// to lose a surface), rendering goes on, and the validation layer reports nothing.
#[test]
fn demo_survives_a_lost_surface() {
    let Some(display) = display() else { return };
    let out = demo(
        &display,
        &["sphere_env", "--frames", "5", "--width", "96", "--height", "96", "--validation", "--lose-surface-at", "2"],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "prism demo failed:\n{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains("surface was lost"), "the hook did not run:\n{stderr}");
    assert!(!stderr.contains("VUID") && !stderr.contains("SYNC-HAZARD"), "validation messages:\n{stderr}");
}

#[test]
fn demo_screenshot_is_the_frame_without_the_overlay() {
    let Some(display) = display() else { return };
    let dir = out_dir("demo_screenshot");
    let shot = dir.join("shot.png");
    let exr = dir.join("shot.exr");
    let reference = dir.join("reference.png");
    let size = ["--width", "160", "--height", "120"];
    let mut args = vec!["sphere_nearby", "--frames", "3", "--screenshot", shot.to_str().unwrap()];
    args.extend(["--screenshot-exr", exr.to_str().unwrap()]);
    args.extend(size);
    let out = demo(&display, &args);
    assert!(out.status.success(), "prism demo failed:\n{}", String::from_utf8_lossy(&out.stderr));
    let out = Command::new(env!("CARGO_BIN_EXE_prism"))
        .arg("render")
        .args(common::baseline_args())
        .args(["sphere_nearby", "-o", reference.to_str().unwrap()])
        .args(size)
        .output()
        .unwrap();
    assert!(out.status.success(), "prism render failed:\n{}", String::from_utf8_lossy(&out.stderr));

    let a = image::open(&shot).unwrap().to_rgba8();
    let b = image::open(&reference).unwrap().to_rgba8();
    assert_eq!(a.dimensions(), (160, 120));
    assert_eq!(b.dimensions(), (160, 120));
    let exr = image::open(&exr).unwrap();
    assert_eq!((exr.width(), exr.height()), (160, 120));
    // Same renderer, same camera (up to the controller's float round trip): the frames
    // agree except for rare edge pixels. The overlay (a panel of text over the top-left
    // corner) would change thousands of pixels by far more than 8/255.
    let differing =
        a.pixels().zip(b.pixels()).filter(|(p, q)| p.0.iter().zip(q.0.iter()).any(|(x, y)| x.abs_diff(*y) > 8)).count();
    let total = (160 * 120) as f64;
    assert!(
        (differing as f64) < total * 0.002,
        "{differing} of {total} pixels differ from `prism render`: the screenshot is not the plain frame"
    );
}

#[test]
fn demo_hot_reload_shows_a_scene_error_and_recovers() {
    let Some(display) = display() else { return };
    let dir = out_dir("demo_reload");
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    let good = std::fs::read_to_string(scenes.join("sphere_env.toml")).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, &good).unwrap();
    // Runs until killed: the test reads its progress from stderr.
    let mut demo =
        Running::spawn(&display, &[scene.to_str().unwrap(), "--frames", "1000000", "--width", "64", "--height", "48"]);
    let started = demo.wait_for("swapchain", 60);
    // A syntax error on disk: reported, and the window keeps running.
    std::thread::sleep(Duration::from_millis(600));
    std::fs::write(&scene, format!("{good}\nbroken = = 1\n")).unwrap();
    let errored = started && demo.wait_for("scene error", 60);
    // Fixed again, with a different exposure: reloaded.
    std::thread::sleep(Duration::from_millis(600));
    std::fs::write(&scene, good.replace("[render]", "[render]\nexposure = 2.0")).unwrap();
    let reloaded = errored && demo.wait_for("demo: reloaded", 60);
    let still_running = demo.child.try_wait().unwrap().is_none();
    let _ = demo.child.kill();
    let _ = demo.child.wait();
    let log = demo.log;
    assert!(started, "the demo did not start:\n{log}");
    assert!(errored, "the broken scene was not reported:\n{log}");
    assert!(reloaded, "the fixed scene was not reloaded:\n{log}");
    assert!(still_running, "the demo exited:\n{log}");
    assert!(!log.contains("panicked"), "{log}");
}

#[test]
fn demo_opens_volume_scenes_with_the_adaptive_tone_map() {
    // A scene with a [volume] that names no tone map opens with render.tonemap = "adaptive"
    // in the window (Ihrke et al. 2007 §5.3); headless `render` keeps the scene's clamp.
    // The scene is static, so the temporal adaptation stays at the converged state of the
    // first frame and the screenshot matches a headless adaptive render.
    let Some(display) = display() else { return };
    let dir = out_dir("demo_tonemap");
    let shot = dir.join("shot.png");
    let size = ["--width", "96", "--height", "72"];
    let mut args = vec!["eikonal_luneburg", "--frames", "3", "--screenshot", shot.to_str().unwrap()];
    args.extend(size);
    let out = demo(&display, &args);
    assert!(out.status.success(), "prism demo failed:\n{}", String::from_utf8_lossy(&out.stderr));
    let shot = image::open(&shot).unwrap().to_rgba8();
    let differing = |tonemap: &str| {
        let reference = dir.join(format!("{tonemap}.png"));
        let out = Command::new(env!("CARGO_BIN_EXE_prism"))
            .arg("render")
            .args(common::baseline_args())
            .args(["eikonal_luneburg", "-o", reference.to_str().unwrap(), "--set"])
            .arg(format!("render.tonemap={tonemap}"))
            .args(size)
            .output()
            .unwrap();
        assert!(out.status.success(), "prism render failed:\n{}", String::from_utf8_lossy(&out.stderr));
        let b = image::open(&reference).unwrap().to_rgba8();
        shot.pixels()
            .zip(b.pixels())
            .filter(|(p, q)| p.0.iter().zip(q.0.iter()).any(|(x, y)| x.abs_diff(*y) > 8))
            .count()
    };
    // Same threshold as the screenshot test above (rare edge pixels); the clamp rule
    // differs everywhere on this scene (measured: every pixel, by far more than 8/255).
    let total = 96.0 * 72.0;
    let adaptive = differing("adaptive");
    assert!((adaptive as f64) < total * 0.002, "{adaptive} pixels differ from the adaptive render");
    let clamp = differing("clamp");
    assert!((clamp as f64) > total * 0.5, "only {clamp} pixels differ from the clamp render");
}

#[test]
fn demo_applies_changes_to_the_running_renderer() {
    // Scripted changes in a running window: each re-creates only what depends on it, and the
    // log says what and how long it took.
    let Some(display) = display() else { return };
    let out = demo(
        &display,
        &[
            "sphere_nearby",
            "--set",
            "render.refraction=hu_qin",
            "--set",
            "camera.width=96",
            "--set",
            "camera.height=96",
            "--frames",
            "8",
            "--validation",
            "--at",
            "2:render.hu_qin.search_steps=4",
            "--at",
            "3:materials.glass.ior=1.33",
            "--at",
            "4:render.caustics=caustics_map",
            "--at",
            "5:render.caustics_map.grid=64",
            "--resize-at",
            "6",
            "120x100",
        ],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "prism demo failed:\n{stderr}");
    assert!(!stderr.contains("VUID") && !stderr.contains("SYNC-HAZARD"), "validation messages:\n{stderr}");
    let line = |change: &str| {
        stderr.lines().find(|l| l.contains(change)).unwrap_or_else(|| panic!("no log line for {change}:\n{stderr}"))
    };
    assert!(line("render.hu_qin.search_steps=4").contains("re-created refraction = \"hu_qin\" ("), "{stderr}");
    assert!(line("materials.glass.ior=1.33").contains("rewrote the materials buffer ("), "{stderr}");
    assert!(
        line("render.caustics=caustics_map").contains("re-created caustics = \"caustics_map\", deferred_shading ("),
        "{stderr}"
    );
    assert!(line("render.caustics_map.grid=64").contains("re-created caustics = \"caustics_map\" ("), "{stderr}");
    // A resize makes the image-sized targets and the techniques drawn at the image's size;
    // the shadow and caustic maps keep theirs.
    let resize = line(": resize to 120x100:");
    assert!(resize.contains("made the targets at the new size; re-created gbuffer,"), "{stderr}");
    assert!(!resize.contains("shadow_map") && !resize.contains("caustics_map"), "{stderr}");
    assert!(!stderr.contains("whole renderer"), "{stderr}");
}

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let (src, dst) = (e.path(), to.join(e.file_name()));
        if src.is_dir() {
            copy_tree(&src, &dst);
        } else {
            std::fs::copy(&src, &dst).unwrap();
        }
    }
}

#[test]
fn demo_recompiles_an_edited_shader_and_shows_its_errors() {
    let Some(display) = display() else { return };
    let dir = out_dir("demo_shaders");
    let glsl = dir.join("glsl");
    let _ = std::fs::remove_dir_all(&glsl);
    copy_tree(&Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl"), &glsl);
    let tonemap = glsl.join("tonemap/tonemap.frag");
    let original = std::fs::read_to_string(&tonemap).unwrap();
    let (shot, reference) = (dir.join("shot.png"), dir.join("reference.png"));
    let _ = std::fs::remove_file(&shot);
    let size = ["--width", "64", "--height", "48"];
    let mut args = vec!["sphere_env", "--frames", "1000000", "--validation", "--no-overlay"];
    args.extend(["--shaders", glsl.to_str().unwrap(), "--exit-after-shader-reloads", "1"]);
    args.extend(["--screenshot", shot.to_str().unwrap()]);
    args.extend(size);
    let mut demo = Running::spawn(&display, &args);
    let started = demo.wait_for("for shader changes", 120);
    // A syntax error on line 9: reported with its file and line, and the window goes on.
    std::thread::sleep(Duration::from_millis(600));
    let broken = original.replacen("void main() {", "void main() {\n    this is not glsl;", 1);
    std::fs::write(&tonemap, broken).unwrap();
    let errored = started && demo.wait_for("glsl/tonemap/tonemap.frag:9:", 120);
    let running_after_error = demo.child.try_wait().unwrap().is_none();
    // A valid edit: a quarter of the exposure. Only the tone map is re-created.
    std::thread::sleep(Duration::from_millis(600));
    std::fs::write(&tonemap, original.replace("frame.camera_position.w * L", "0.25 * frame.camera_position.w * L"))
        .unwrap();
    let reloaded = errored && demo.wait_for("glsl/tonemap/tonemap.frag recompiled: re-created tonemap (", 120);
    let deadline = Instant::now() + Duration::from_secs(120);
    let status = loop {
        match demo.child.try_wait().unwrap() {
            Some(s) => break Some(s),
            None if Instant::now() > deadline => break None,
            None => std::thread::sleep(Duration::from_millis(100)),
        }
    };
    if status.is_none() {
        let _ = demo.child.kill();
    }
    let _ = demo.child.wait();
    // The rest of the log (validation messages come at exit).
    demo.drain();
    let log = demo.log;
    assert!(started, "the demo did not start:\n{log}");
    assert!(errored, "the broken shader was not reported with its file and line:\n{log}");
    assert!(running_after_error, "the demo stopped on a shader error:\n{log}");
    assert!(reloaded, "the fixed shader was not recompiled, or more than the tone map was re-created:\n{log}");
    assert!(status.is_some_and(|s| s.success()), "the demo did not exit cleanly:\n{log}");
    assert!(!log.contains("VUID") && !log.contains("panicked"), "{log}");

    // 0.25 x exposure x L is exposure 0.25 x L exactly (a power of two): the same image as a
    // render with render.exposure = 0.25, up to the screenshot test's rare edge pixels.
    let out = Command::new(env!("CARGO_BIN_EXE_prism"))
        .arg("render")
        .args(common::baseline_args())
        .args(["sphere_env", "--set", "render.exposure=0.25", "-o", reference.to_str().unwrap()])
        .args(size)
        .output()
        .unwrap();
    assert!(out.status.success(), "prism render failed:\n{}", String::from_utf8_lossy(&out.stderr));
    let (a, b) = (image::open(&shot).unwrap().to_rgba8(), image::open(&reference).unwrap().to_rgba8());
    let differing =
        a.pixels().zip(b.pixels()).filter(|(p, q)| p.0.iter().zip(q.0.iter()).any(|(x, y)| x.abs_diff(*y) > 8)).count();
    assert!((differing as f64) < (64.0 * 48.0) * 0.002, "{differing} pixels differ from the exposure-0.25 render");
}

#[test]
fn demo_animates_the_water_without_updating_the_renderer() {
    // The water moves by a compute pass on the GPU: no frame re-creates anything.
    let Some(display) = display() else { return };
    let out = demo(&display, &["water_pool", "--frames", "6", "--width", "96", "--height", "96", "--validation"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "prism demo failed:\n{stderr}");
    assert!(!stderr.contains("VUID") && !stderr.contains("SYNC-HAZARD"), "validation messages:\n{stderr}");
    assert!(!stderr.contains("re-created"), "{stderr}");
    assert!(stderr.contains("demo: 6 frames, 0 renderer updates"), "{stderr}");
}

#[test]
fn demo_re_runs_the_light_simulation_with_its_progress_after_a_light_moves() {
    // Moving the light re-creates only the volume technique, whose light simulation runs
    // again; its progress is logged (and shown in the window's title) while it runs.
    let Some(display) = display() else { return };
    let out = demo(
        &display,
        &[
            "eikonal_sphere",
            "--set",
            "volume.resolution=[24, 24, 24]",
            "--set",
            "render.eikonal.light_patches=16",
            "--width",
            "64",
            "--height",
            "64",
            "--frames",
            "4",
            "--at",
            "2:lights.0.position=[0.3, 5, 0]",
            // All of each simulation before the next frame, as this test counts on.
            "--work-per-frame",
            "0",
        ],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "prism demo failed:\n{stderr}");
    let change = stderr.lines().position(|l| l.contains("lights.0.position")).expect("no log line for the move");
    let line = stderr.lines().nth(change).unwrap();
    assert!(line.contains("re-created shadow_map, [volume];"), "{stderr}");
    // Once when the window opened, once after the move, each with its progress (the second
    // runs before the frame after the change is recorded, so after its log line).
    assert_eq!(stderr.matches("demo: light simulation done").count(), 2, "{stderr}");
    let is_progress = |l: &&str| l.starts_with("demo: light simulation ") && l.contains('%');
    assert!(stderr.lines().take(change).filter(is_progress).count() >= 1, "{stderr}");
    assert!(stderr.lines().skip(change).filter(is_progress).count() >= 1, "{stderr}");
    assert!(!stderr.contains("whole renderer"), "{stderr}");
}

/// The light simulation runs a little before each frame (`--work-per-frame`), so frames are
/// shown while it runs, and the frame after it finished is `prism render`'s, which runs it
/// all before its one frame.
#[test]
fn demo_shows_frames_while_the_light_simulation_runs() {
    let Some(display) = display() else { return };
    let dir = out_dir("demo_progressive_light");
    let (shot, reference) = (dir.join("shot.png"), dir.join("reference.png"));
    // The clamping tone map: the window would open a volume scene with the adaptive one.
    let scene = [
        "eikonal_sphere",
        "--set",
        "volume.resolution=[24, 24, 24]",
        "--set",
        "render.eikonal.light_patches=16",
        "--set",
        "render.tonemap=\"clamp\"",
    ];
    let size = ["--width", "64", "--height", "64"];
    let mut args = scene.to_vec();
    args.extend(size);
    args.extend(["--frames", "20", "--validation", "--work-per-frame", "1", "--screenshot", shot.to_str().unwrap()]);
    let out = demo(&display, &args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "prism demo failed:\n{stderr}");
    assert!(!stderr.contains("VUID") && !stderr.contains("SYNC-HAZARD"), "validation messages:\n{stderr}");
    let line =
        stderr.lines().find(|l| l.contains("the light simulation finished")).unwrap_or_else(|| panic!("{stderr}"));
    // The simulation takes 41 step dispatches here, in batches: a budget of 1 ms lets one
    // batch run before each frame, so frames showed it before it finished. Run all at once
    // (--work-per-frame 0), no frame would.
    let shown: u64 = line.split("; ").nth(1).unwrap().split_whitespace().next().unwrap().parse().unwrap();
    assert!(shown >= 1, "{stderr}");
    let out = Command::new(env!("CARGO_BIN_EXE_prism"))
        .arg("render")
        .args(common::baseline_args())
        .args(scene)
        .args(size)
        .args(["-o", reference.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "prism render failed:\n{}", String::from_utf8_lossy(&out.stderr));
    // As demo_screenshot_is_the_frame_without_the_overlay: same renderer and camera up to the
    // controller's float round trip, and here the simulation's deposits summed in another
    // order (float atomics); a volume resolved before the simulation ended would darken or
    // light thousands of pixels.
    let (a, b) = (image::open(&shot).unwrap().to_rgba8(), image::open(&reference).unwrap().to_rgba8());
    let differing =
        a.pixels().zip(b.pixels()).filter(|(p, q)| p.0.iter().zip(q.0.iter()).any(|(x, y)| x.abs_diff(*y) > 8)).count();
    assert!((differing as f64) < 64.0 * 64.0 * 0.002, "{differing} pixels differ from `prism render`\n{stderr}");
}

/// The README's demo commands (`cargo run --release -- demo ARGS`, alone or behind
/// `xvfb-run`), run as `prism demo ARGS` on this test's display with the validation layer,
/// for 3 frames each: as written they run until the window is closed.
#[test]
fn readme_demo_commands_run() {
    let Some(display) = display() else { return };
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let mut ran = 0;
    for line in readme.lines() {
        let Some((_, command)) = line.split_once("cargo run --release -- demo ") else { continue };
        let args: Vec<&str> = command.split('#').next().unwrap().split_whitespace().collect();
        // A command that runs until the window is closed gets a frame count; one that scripts
        // changes keeps its own.
        let frames: &[&str] = if args.contains(&"--frames") { &[] } else { &["--frames", "3"] };
        let out = Command::new(env!("CARGO_BIN_EXE_prism"))
            .arg("demo")
            .args(&args)
            .args(frames)
            .arg("--validation")
            .env("DISPLAY", &display.name)
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap();
        assert!(out.status.success(), "prism demo {command}:\n{}", String::from_utf8_lossy(&out.stderr));
        ran += 1;
    }
    assert!(ran >= 2, "the README's demo commands were not found");
}

/// The overlay's invocation counts (`--pipeline-stats`): pipeline-statistics queries around
/// every pass of the window's frame, with no validation message, and the last frame's counts
/// printed at the end. Deferred shading is a full-screen pass, so it shades at least every
/// pixel of the 160x120 frame (lavapipe counts 16 per 4x4 block a triangle touches, never
/// fewer than the pixels); the G-buffer draws the scene's vertices.
#[test]
fn demo_overlay_counts_every_pass() {
    let Some(display) = display() else { return };
    let out = demo(
        &display,
        &["sphere_nearby", "--frames", "4", "--width", "160", "--height", "120", "--validation", "--pipeline-stats"],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "prism demo failed:\n{stderr}");
    assert!(!stderr.contains("VUID") && !stderr.contains("SYNC-HAZARD"), "validation messages:\n{stderr}");
    let count = |pass: &str, what: &str| -> u64 {
        let line = stderr
            .lines()
            .find(|l| l.starts_with(&format!("demo: counts {pass}:")))
            .unwrap_or_else(|| panic!("no counts for {pass}:\n{stderr}"));
        let (n, _) = line
            .split(':')
            .nth(2)
            .unwrap()
            .split(',')
            .find(|p| p.trim().ends_with(what))
            .unwrap()
            .trim()
            .split_once(' ')
            .unwrap();
        n.parse().unwrap()
    };
    assert!(count("deferred_shading", "fragments") >= 160 * 120, "{stderr}");
    assert!(count("gbuffer", "vertices") > 0, "{stderr}");
}

/// `--show-target NAME` (the overlay's "show" list): the frame's image is read back after
/// each frame and drawn in place of the final image, with no validation message; a name the
/// frame has no image for is an error (non-zero exit) that lists the images.
#[test]
fn demo_shows_an_intermediate_target() {
    let Some(display) = display() else { return };
    let args = |target: &'static str| {
        ["sphere_nearby", "--frames", "3", "--width", "160", "--height", "120", "--validation", "--show-target", target]
    };
    let out = demo(&display, &args("gbuf_normal"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "prism demo failed:\n{stderr}");
    assert!(!stderr.contains("VUID") && !stderr.contains("SYNC-HAZARD"), "validation messages:\n{stderr}");
    assert!(stderr.contains("demo: showing gbuf_normal (160x120, R16G16B16A16_SFLOAT)"), "{stderr}");
    let out = demo(&display, &args("no_such_image"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "an unknown target was accepted:\n{stderr}");
    assert!(stderr.contains("--show-target no_such_image") && stderr.contains("gbuf_normal"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// `--ab`: the exact image accumulates one sample per frame while nothing changes, a change
/// starts it again, and its live errors are `prism compare`'s against a reference of as many
/// samples and photons per sample (the same renderer, settings and seed: the same image, so
/// the errors agree to the log's six digits). The screenshot is the A/B picture: the
/// technique's image left of the split, the exact image right of it.
#[test]
fn demo_ab_view_measures_what_compare_measures() {
    let Some(display) = display() else { return };
    let dir = out_dir("demo_ab");
    let shot = dir.join("ab.png");
    let size = ["--width", "64", "--height", "64"];
    let mut args = vec!["sphere_env", "--frames", "9", "--validation", "--ab", "--screenshot", shot.to_str().unwrap()];
    args.extend(size);
    args.extend(["--at", "4:render.exposure=2"]);
    let out = demo(&display, &args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "prism demo failed:\n{stderr}");
    assert!(!stderr.contains("VUID") && !stderr.contains("SYNC-HAZARD"), "validation messages:\n{stderr}");
    assert_eq!(stderr.matches("the exact image starts again").count(), 1, "{stderr}");
    // Frames 0..=8. The change is queued once 4 frames were presented and applied in frame 4,
    // where the exact image stops; it is made again in frame 5 (its state held for a frame)
    // and gains a sample in each of frames 5 to 8. Without the restart it would hold a
    // sample from each frame since frame 2 (7).
    let last = stderr.lines().rfind(|l| l.starts_with("demo: A/B: ") && l.contains("exact samples"));
    let last = last.unwrap_or_else(|| panic!("no A/B errors logged:\n{stderr}"));
    let field = |name: &str| -> f64 {
        let at = last.find(name).unwrap_or_else(|| panic!("no {name} in {last}")) + name.len();
        last[at..].trim_start().split(|c: char| c == ',' || c.is_whitespace()).next().unwrap().parse().unwrap()
    };
    let samples: u32 = last["demo: A/B: ".len()..].split_whitespace().next().unwrap().parse().unwrap();
    assert_eq!(samples, 4, "{stderr}");

    let json = dir.join("compare.json");
    let prefix = dir.join("compare");
    let photons = (samples as u64 * 65536).to_string();
    let spp = samples.to_string();
    let mut compare = Command::new(env!("CARGO_BIN_EXE_prism"));
    compare.arg("compare").args(common::baseline_args()).args(["sphere_env", "--set", "render.exposure=2"]);
    compare.args(size).args(["--spp", &spp, "--photons", &photons, "--no-cache", "--frames", "1", "--warmup", "1"]);
    compare.args(["--json", json.to_str().unwrap(), "--images", prefix.to_str().unwrap()]);
    compare.arg("--heatmap").arg(dir.join("heat.png")).current_dir(&dir);
    let c = compare.output().unwrap();
    assert!(c.status.success(), "prism compare failed:\n{}", String::from_utf8_lossy(&c.stderr));
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    for (name, key) in
        [("FLIP mean", "flip_mean"), ("HDR-FLIP mean", "hdr_flip_mean"), ("relMSE", "rel_mse"), ("RMSE", "rmse")]
    {
        let expected = report["errors"][key].as_f64().unwrap();
        let live = field(name);
        assert!((live - expected).abs() <= 0.5e-6, "{name}: A/B view {live} vs prism compare {expected}\n{stderr}");
    }

    let ab = image::open(&shot).unwrap().to_rgba8();
    let technique = image::open(dir.join("compare-technique.png")).unwrap().to_rgba8();
    let exact = image::open(dir.join("compare-reference.png")).unwrap().to_rgba8();
    for (x, y, p) in ab.enumerate_pixels() {
        let expected = match x {
            0..32 => technique.get_pixel(x, y),
            32 => &image::Rgba([255, 255, 255, 255]),
            _ => exact.get_pixel(x, y),
        };
        assert_eq!(p, expected, "A/B screenshot pixel ({x}, {y})");
    }
}

/// The window shows the raytrace technique's running mean while nothing changes
/// (`render.raytrace.accumulate`, default 64) and starts it again on a change: with the
/// camera left alone, 8 frames with a scripted change applied after frame 5 end with a mean of
/// the 3 frames since (the count the overlay shows, logged on exit). A window camera that
/// restarted it every frame would leave 1, a change that did not restart it 8.
#[test]
fn demo_accumulates_the_raytraced_frames_until_a_change() {
    let Some(display) = display() else { return };
    let set = ["render.refraction=raytrace", "render.caustics=raytrace", "render.raytrace.photons_per_frame=2000"];
    let mut args = vec!["caustic_sphere", "--width", "48", "--height", "48", "--frames", "8", "--validation"];
    args.extend(set.iter().flat_map(|s| ["--set", s]));
    let still = demo(&display, &args);
    args.extend(["--at", "5:render.exposure=1.5"]);
    let changed = demo(&display, &args);
    for (out, count) in [(still, 8), (changed, 3)] {
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "prism demo failed:\n{stderr}");
        let line = stderr.lines().find(|l| l.starts_with("demo: raytrace: ")).unwrap_or_else(|| panic!("{stderr}"));
        eprintln!("{line}");
        assert_eq!(line, format!("demo: raytrace: {count} of 64 frames accumulated"), "{stderr}");
    }
}
