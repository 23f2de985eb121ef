//! Bad input: each case gives a clear error naming the file (and line where there is one),
//! a non-zero exit, no panic, and no output file, not even a partial one.
use std::path::{Path, PathBuf};
use std::process::Command;

struct Case {
    dir: PathBuf,
}

impl Case {
    fn new(name: &str) -> Case {
        let dir = std::env::temp_dir().join(format!("prism-bad-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Case { dir }
    }

    fn file(&self, name: &str, text: &str) -> PathBuf {
        let p = self.dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    /// Run `prism render SCENE -o DIR/out.png --exr DIR/out.exr ARGS` with `env`, expect
    /// failure, and return stderr. Checks: exit code 1, no panic, no output or temp file.
    fn render_fails(&self, scene: &Path, args: &[&str], env: &[(&str, &str)]) -> String {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_prism"));
        cmd.arg("render").arg(scene).arg("-o").arg(self.dir.join("out.png")).arg("--exr").arg(self.dir.join("out.exr"));
        cmd.args(args).current_dir(&self.dir);
        for (k, v) in env {
            cmd.env(k, v);
        }
        self.fails(&mut cmd)
    }

    /// Run `cmd`, expect failure, and return stderr (the checks of `render_fails`).
    fn fails(&self, cmd: &mut Command) -> String {
        let before: Vec<_> = self.listing();
        let out = cmd.output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        assert_eq!(out.status.code(), Some(1), "expected exit 1:\n{stderr}");
        assert!(!stderr.contains("panicked"), "panic:\n{stderr}");
        // The Vulkan loader may print its own lines first; prism's own line starts with "error: ".
        assert!(stderr.lines().any(|l| l.starts_with("error: ")), "{stderr}");
        assert_eq!(self.listing(), before, "output files were left behind:\n{stderr}");
        stderr
    }

    fn listing(&self) -> Vec<String> {
        let mut v: Vec<_> = std::fs::read_dir(&self.dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }
}

impl Drop for Case {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

const GOOD: &str = r#"[camera]
position = [0, 0, 4]
target = [0, 0, 0]
width = 32
height = 32

[environment]
type = "constant"
radiance = 0.5

[materials.glass]
type = "dielectric"
ior = 1.5

[materials.white]
type = "diffuse"
albedo = 0.8

[[objects]]
material = "glass"
shape = "sphere"
center = [0, 0, 0]
radius = 1
"#;

#[test]
fn good_scene_renders() {
    // The control: the same harness with a valid scene writes both files.
    let c = Case::new("good");
    let scene = c.file("scene.toml", GOOD);
    let out = Command::new(env!("CARGO_BIN_EXE_prism"))
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(c.dir.join("out.png"))
        .arg("--exr")
        .arg(c.dir.join("out.exr"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(c.listing(), ["out.exr", "out.png", "scene.toml"]);
    // The EXR holds unscaled linear radiance: the constant environment exactly.
    let exr = image::open(c.dir.join("out.exr")).unwrap().to_rgb32f();
    assert_eq!(exr.get_pixel(0, 0).0, [0.5, 0.5, 0.5]);
}

#[test]
fn missing_scene_file() {
    let c = Case::new("missing");
    let e = c.render_fails(&c.dir.join("nope.toml"), &[], &[]);
    assert!(e.contains("nope.toml") && e.contains("cannot read scene file"), "{e}");
}

#[test]
fn malformed_toml_names_line_and_column() {
    let c = Case::new("malformed");
    let scene = c.file("scene.toml", &GOOD.replace("radius = 1", "radius = = 1"));
    let e = c.render_fails(&scene, &[], &[]);
    assert!(e.contains("scene.toml:23:10"), "{e}");
}

#[test]
fn unknown_key_is_named() {
    let c = Case::new("unknown");
    let scene = c.file("scene.toml", &GOOD.replace("radius = 1", "radius = 1\nradiuss = 2"));
    let e = c.render_fails(&scene, &[], &[]);
    assert!(e.contains("scene.toml:24:1") && e.contains("radiuss"), "{e}");
}

#[test]
fn negative_radius() {
    let c = Case::new("radius");
    let scene = c.file("scene.toml", &GOOD.replace("radius = 1", "radius = -1"));
    let e = c.render_fails(&scene, &[], &[]);
    assert!(e.contains("scene.toml:23:10") && e.contains("radius"), "{e}");
}

#[test]
fn ior_not_positive() {
    let c = Case::new("ior");
    for ior in ["0", "-1.5"] {
        let scene = c.file("scene.toml", &GOOD.replace("ior = 1.5", &format!("ior = {ior}")));
        let e = c.render_fails(&scene, &[], &[]);
        assert!(e.contains("scene.toml:13") && e.contains("ior"), "{e}");
    }
}

fn mesh_scene(c: &Case, obj: &str) -> PathBuf {
    c.file("mesh.obj", obj);
    c.file(
        "scene.toml",
        &GOOD.replace("shape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1", "shape = \"mesh\"\nfile = \"mesh.obj\""),
    )
}

#[test]
fn obj_with_out_of_range_indices() {
    let c = Case::new("obj-index");
    let scene = mesh_scene(&c, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
    let e = c.render_fails(&scene, &[], &[]);
    assert!(e.contains("mesh.obj"), "{e}");
}

#[test]
fn obj_with_nan_positions() {
    let c = Case::new("obj-nan");
    let scene = mesh_scene(&c, "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
    let e = c.render_fails(&scene, &[], &[]);
    assert!(e.contains("mesh.obj:2"), "{e}");
}

#[test]
fn zero_size_image() {
    let c = Case::new("zero");
    let scene = c.file("scene.toml", GOOD);
    let e = c.render_fails(&scene, &["--width", "0"], &[]);
    assert!(e.contains("width"), "{e}");
}

#[test]
fn unwritable_output_path() {
    let c = Case::new("unwritable");
    let scene = c.file("scene.toml", GOOD);
    let out = Command::new(env!("CARGO_BIN_EXE_prism"))
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(c.dir.join("no/such/dir/out.png"))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1));
    assert!(e.contains("does not exist") && !e.contains("panicked"), "{e}");
    // A directory as the output path.
    std::fs::create_dir(c.dir.join("adir")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_prism"))
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(c.dir.join("adir"))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1));
    assert!(e.contains("is a directory"), "{e}");
    assert_eq!(c.listing(), ["adir", "scene.toml"]);
}

#[test]
fn no_vulkan_driver() {
    let c = Case::new("nodriver");
    let scene = c.file("scene.toml", GOOD);
    let e = c.render_fails(
        &scene,
        &[],
        &[("VK_DRIVER_FILES", "/nonexistent/icd.json"), ("VK_ICD_FILENAMES", "/nonexistent/icd.json")],
    );
    assert!(e.contains("no Vulkan driver") && e.contains("mesa-vulkan-drivers"), "{e}");
}

#[test]
fn unknown_benchmark_scene_and_bad_override() {
    let c = Case::new("names");
    let e = c.render_fails(Path::new("no_such_scene"), &[], &[]);
    assert!(e.contains("no_such_scene"), "{e}");
    let scene = c.file("scene.toml", GOOD);
    let e = c.render_fails(&scene, &["--set", "render.refraction=magic"], &[]);
    assert!(e.contains("magic") && e.contains("single"), "{e}");
    let e = c.render_fails(&scene, &["--set", "render.shadow_map_size=0"], &[]);
    assert!(e.contains("shadow_map_size"), "{e}");
}

#[test]
fn misspelt_technique_tables_and_keys_name_the_closest() {
    // A misspelt table is an error, not a silently ignored table: in the file (with its line)
    // and through --set (naming the override), each with the name it most likely meant.
    let c = Case::new("misspelt");
    let scene = c.file("scene.toml", &format!("{GOOD}\n[render.huqin]\nsearch_steps = 4\n"));
    let e = c.render_fails(&scene, &[], &[]);
    assert!(e.contains("scene.toml:26") && e.contains("[render.huqin]") && e.contains("[render.hu_qin]"), "{e}");
    let scene = c.file("ok.toml", GOOD);
    for (set, wrong, meant) in [
        ("render.hu_quin.search_steps=4", "hu_quin", "[render.hu_qin]"),
        ("render.hu_qin.search_step=4", "search_step", "`search_steps`"),
        ("render.exposur=2", "exposur", "`exposure`"),
    ] {
        let e = c.render_fails(&scene, &["--set", set], &[]);
        assert!(e.contains(wrong) && e.contains(&format!("did you mean {meant}")) && e.contains(set), "{set}: {e}");
    }
    // A name unlike every table gets the list, without a guess.
    let e = c.render_fails(&scene, &["--set", "render.zzzzzzzz.x=1"], &[]);
    assert!(e.contains("[render.zzzzzzzz]") && !e.contains("did you mean") && e.contains("[render.wyman]"), "{e}");
}

#[test]
fn absurd_photon_buffer_and_caustics_map_parameters() {
    // Hu & Qin 2007 §3 (render.photon_buffer) and Shah et al.'s Eq. 6 weight
    // (render.caustics_map.flux): the key, the allowed values, no output file.
    let c = Case::new("photon_buffer");
    let scene = c.file(
        "scene.toml",
        &format!("{GOOD}\n[render]\ncaustics = \"photon_buffer\"\n[render.photon_buffer]\nfilter_k = 99\n"),
    );
    let e = c.render_fails(&scene, &[], &[]);
    assert!(e.contains("filter_k") && e.contains("scene.toml:") && e.contains("0 to 16"), "{e}");
    let scene = c.file("ok.toml", GOOD);
    for (set, key) in [
        ("render.photon_buffer.size=0", "size"),
        ("render.photon_buffer.normalization=\"none\"", "normalization"),
        ("render.photon_buffer.filter_s=-1", "filter_s"),
        ("render.caustics_map.flux=\"area\"", "flux"),
    ] {
        let e = c.render_fails(&scene, &["--set", set], &[]);
        assert!(e.contains(key), "{set}: {e}");
    }
}

#[test]
fn absurd_eikonal_nearby_parameters() {
    // render.eikonal.nearby and its impostor settings name the key, the
    // allowed values, the file and line; no output file is written.
    let c = Case::new("eikonal_nearby");
    let scene = c.file("scene.toml", &format!("{GOOD}\n[render.eikonal]\nnearby = \"mirror\"\n"));
    let e = c.render_fails(&scene, &[], &[]);
    assert!(e.contains("nearby") && e.contains("scene.toml:") && e.contains("\"exact\""), "{e}");
    let scene = c.file("ok.toml", GOOD);
    for (set, key) in [
        ("render.eikonal.nearby=true", "nearby"),
        ("render.eikonal.nearby_iterations=-1", "nearby_iterations"),
        ("render.eikonal.nearby_iterations=1000", "nearby_iterations"),
        ("render.eikonal.nearby_resolution=1", "nearby_resolution"),
        ("render.eikonal.nearby_resolution=100000", "nearby_resolution"),
    ] {
        let e = c.render_fails(&scene, &["--set", set], &[]);
        assert!(e.contains(key), "{set}: {e}");
    }
}

#[test]
fn absurd_eikonal_light_parameters() {
    // Ihrke et al. 2007 §5.2 (render.eikonal): a tile larger than the patch list, a
    // non-boolean keep_crossed; the error names the key and the file, and no file is written.
    let c = Case::new("eikonal_light");
    let scene = c.file("scene.toml", &format!("{GOOD}\n[render.eikonal]\nmax_patches = 1000\ntile_patches = 5000\n"));
    let e = c.render_fails(&scene, &[], &[]);
    assert!(e.contains("tile_patches") && e.contains("max_patches") && e.contains("scene.toml"), "{e}");
    let scene = c.file("ok.toml", GOOD);
    for (set, key) in [
        ("render.eikonal.keep_crossed=3", "keep_crossed"),
        ("render.eikonal.tile_patches=-1", "tile_patches"),
        ("render.eikonal.tile_patches=2000000", "tile_patches"),
    ] {
        let e = c.render_fails(&scene, &["--set", set], &[]);
        assert!(e.contains(key), "{set}: {e}");
    }
}

#[test]
fn absurd_tone_map_settings() {
    // render.tonemap names one of the accepted tone maps; [render.tonemap_adaptive] checks
    // its numbers (file:line for the file, the key and the range for --set).
    let c = Case::new("tonemap");
    let scene = c.file(
        "scene.toml",
        &format!("{GOOD}\n[render]\ntonemap = \"adaptive\"\n[render.tonemap_adaptive]\ndelta = 0\n"),
    );
    let e = c.render_fails(&scene, &[], &[]);
    assert!(e.contains("delta") && e.contains("scene.toml:"), "{e}");
    let scene = c.file("ok.toml", GOOD);
    let e = c.render_fails(&scene, &["--set", "render.tonemap=filmic"], &[]);
    assert!(e.contains("filmic") && e.contains("clamp") && e.contains("adaptive"), "{e}");
    for (set, key) in [
        ("render.tonemap_adaptive.key=-1", "key"),
        ("render.tonemap_adaptive.key=\"high\"", "auto"),
        ("render.tonemap_adaptive.white=0", "white"),
        ("render.tonemap_adaptive.tau_rod=-0.4", "tau_rod"),
        ("render.tonemap_adaptive.luminance_scale=nan", "luminance_scale"),
        ("render.tonemap_adaptive.gamma=2.2", "gamma"),
    ] {
        let e = c.render_fails(&scene, &["--set", "render.tonemap=adaptive", "--set", set], &[]);
        assert!(e.contains(key), "{set}: {e}");
    }
}

/// Run prism with `args` in `dir`: its exit code and stderr, after checking that it did not
/// panic.
fn prism(dir: &Path, args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_prism")).args(args).current_dir(dir).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!stderr.contains("panicked"), "panic:\n{stderr}");
    (out.status.code(), stderr)
}

fn is_fifo(p: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    std::fs::symlink_metadata(p).unwrap().file_type().is_fifo()
}

#[test]
fn outputs_that_are_not_regular_files_or_named_twice_are_refused() {
    let c = Case::new("outputs");
    c.file("scene.toml", GOOD);
    // A FIFO would be replaced by the PNG (renamed over it), as would a device node.
    assert!(Command::new("mkfifo").arg(c.dir.join("pipe.png")).status().unwrap().success());
    let (code, e) = prism(&c.dir, &["render", "scene.toml", "-o", "pipe.png"]);
    assert_eq!(code, Some(1), "{e}");
    assert!(e.contains("pipe.png: cannot write output: it exists and is a FIFO (named pipe)"), "{e}");
    assert!(is_fifo(&c.dir.join("pipe.png")));
    // A character device of our own (/dev/null as in /dev), where this user may create one.
    let made_device = Command::new("mknod").arg(c.dir.join("null")).args(["c", "1", "3"]).status();
    if made_device.is_ok_and(|s| s.success()) {
        let (code, e) = prism(&c.dir, &["render", "scene.toml", "-o", "null", "--exr", "out.exr"]);
        assert_eq!(code, Some(1), "{e}");
        assert!(e.contains("null: cannot write output: it exists and is a character device"), "{e}");
        std::fs::remove_file(c.dir.join("null")).unwrap();
    }
    // The same file twice: as given, and spelt differently.
    for exr in ["x.png", "./x.png"] {
        let (code, e) = prism(&c.dir, &["render", "scene.toml", "-o", "x.png", "--exr", exr]);
        assert_eq!(code, Some(1), "{e}");
        assert!(e.contains(&format!("{exr}: named twice as an output of this command (also as x.png)")), "{e}");
    }
    // A PNG output named as another format (a PNG in x.exr would pass for linear radiance).
    let (code, e) = prism(&c.dir, &["render", "scene.toml", "-o", "x.exr"]);
    assert_eq!(code, Some(1), "{e}");
    assert!(e.contains("x.exr: `-o` writes a tone-mapped PNG, not a .exr file") && e.contains("--exr"), "{e}");
    // compare's heat map and image pair colliding.
    let args =
        ["compare", "scene.toml", "--heatmap", "p-technique.png", "--images", "p", "--spp", "1", "--frames", "1"];
    let (code, e) = prism(&c.dir, &args);
    assert_eq!(code, Some(1), "{e}");
    assert!(e.contains("p-technique.png: named twice as an output"), "{e}");
    assert_eq!(c.listing(), ["pipe.png", "scene.toml"]);
}

/// A full filesystem: an 8 KiB tmpfs whose two pages a 6 KiB file fills, mounted in a mount
/// namespace of this test's own (`unshare -rm`: as root, or as a user mapped to root where
/// user namespaces are allowed). The PNG and the EXR cannot be written: exit 1 and no file,
/// not even the PNG that went to a directory with room (the outputs commit together).
#[test]
fn a_full_filesystem_fails_and_leaves_no_file() {
    let c = Case::new("full");
    c.file("scene.toml", GOOD);
    std::fs::create_dir(c.dir.join("full")).unwrap();
    let script = r#"mount -t tmpfs -o size=8k tmpfs full || exit 0
        echo mounted
        head -c 6144 /dev/zero > full/fill
        "$0" render scene.toml -o full/out.png; echo "exit $?"
        "$0" render scene.toml -o full/out.png --exr out.exr; echo "exit $?"
        "$0" render scene.toml -o out.png --exr full/out.exr; echo "exit $?"
        ls -A . full"#;
    let out = Command::new("unshare")
        .args(["-rm", "sh", "-c", script, env!("CARGO_BIN_EXE_prism")])
        .current_dir(&c.dir)
        .output()
        .unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    if !stdout.contains("mounted") {
        // The unit tests of src/app/output.rs cover the error path with /dev/full and a
        // failing writer.
        eprintln!("skipping: cannot mount a tmpfs here (unshare -rm):\n{stderr}");
        return;
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
    let exits: Vec<&str> = stdout.lines().filter(|l| l.starts_with("exit ")).collect();
    assert_eq!(exits, ["exit 1"; 3], "{stdout}\n{stderr}");
    assert!(stderr.contains("full/out.png: cannot write output (disk full?)"), "{stderr}");
    assert!(stderr.contains("full/out.exr: cannot write output (disk full?)"), "{stderr}");
    // `ls -A . full`: only the scene, the mount point and the filler remain.
    let listed: Vec<&str> = stdout.lines().skip_while(|l| !l.starts_with(".:")).collect();
    assert_eq!(listed, [".:", "full", "scene.toml", "", "full:", "fill"], "{stdout}");
}

#[test]
fn absurd_frame_counts_are_refused() {
    let c = Case::new("frames");
    c.file("scene.toml", GOOD);
    for command in ["bench", "compare"] {
        let args = [command, "scene.toml", "--warmup", "4294967295", "--frames", "2", "--spp", "1"];
        let args = if command == "bench" { &args[..6] } else { &args[..] };
        let (code, e) = prism(&c.dir, args);
        assert_eq!(code, Some(2), "{command}: {e}");
        assert!(e.contains("--warmup") && e.contains("4294967295 is not in 0..=1000000"), "{command}: {e}");
        let (code, e) = prism(&c.dir, &[command, "scene.toml", "--frames", "1000001"]);
        assert_eq!(code, Some(2), "{command}: {e}");
        assert!(e.contains("--frames") && e.contains("1000000"), "{command}: {e}");
    }
    assert_eq!(c.listing(), ["scene.toml"]);
}

#[test]
fn input_files_that_are_not_regular_or_too_large_are_refused() {
    let c = Case::new("inputs");
    // The scene file itself: a device that never ends, and a directory.
    for scene in [Path::new("/dev/zero"), c.dir.as_path()] {
        let e = c.render_fails(scene, &[], &[]);
        assert!(e.contains(&scene.display().to_string()) && e.contains("not a regular file"), "{e}");
    }
    // A mesh and an environment image the scene names.
    let mesh = c.file(
        "mesh.toml",
        &GOOD.replace("shape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1", "shape = \"mesh\"\nfile = \"/dev/zero\""),
    );
    let env = c.file(
        "env.toml",
        &GOOD.replace("type = \"constant\"\nradiance = 0.5", "type = \"image\"\nfile = \"/dev/zero\""),
    );
    for scene in [mesh, env] {
        let e = c.render_fails(&scene, &[], &[]);
        assert!(e.contains("/dev/zero") && e.contains("not a regular file"), "{e}");
    }
    // A scene file over the 16 MiB cap (a valid scene padded with a comment).
    let big = c.file("big.toml", &format!("{GOOD}#{}\n", "x".repeat(16 << 20)));
    let e = c.render_fails(&big, &[], &[]);
    assert!(e.contains("big.toml") && e.contains("16 MiB"), "{e}");
}

#[test]
fn a_very_deep_override_key_is_refused() {
    let c = Case::new("deep");
    let scene = c.file("scene.toml", GOOD);
    let deep = format!("render.{}=1", vec!["a"; 50_000].join("."));
    let e = c.render_fails(&scene, &["--set", &deep], &[]);
    assert!(e.contains("more than 64 segments"), "{}", &e[e.len().saturating_sub(400)..]);
}

#[test]
fn huge_and_tiny_finite_values_are_refused_with_the_range() {
    let c = Case::new("huge");
    let nearby = Path::new("sphere_nearby");
    for (set, key, range) in [
        ("objects.0.size=[1e38,1e38]", "size", "1e-6 to 1e6"),
        ("objects.3.radius=1e30", "radius", "1e-6 to 1e6"),
        ("objects.3.radius=1e-30", "radius", "1e-6 to 1e6"),
        ("objects.3.center=[0,0,1e30]", "center", "1e-6 to 1e6"),
        ("camera.position=[0,1e-30,5]", "position", "1e-6 to 1e6"),
        ("camera.vfov_deg=1e-30", "vfov_deg", "0.01 to 179"),
        ("camera.vfov_deg=179.5", "vfov_deg", "0.01 to 179"),
    ] {
        let e = c.render_fails(nearby, &["--set", set], &[]);
        assert!(e.contains(set) && e.contains(key) && e.contains(range), "{set}: {e}");
    }
    // A transform's scale (a mesh's as any other object's).
    let scene = c.file("scene.toml", &GOOD.replace("radius = 1", "radius = 1\ntransform = { scale = 1e30 }"));
    let e = c.render_fails(&scene, &[], &[]);
    assert!(e.contains("scene.toml:24") && e.contains("scale") && e.contains("1e-6 to 1e6"), "{e}");
}

#[test]
fn interrupt_leaves_no_temporary_file() {
    // Ctrl-C while rendering: the outputs' hidden temporary files, created before the
    // render starts, are removed and the exit status is 130 (128 + SIGINT).
    let c = Case::new("interrupt");
    let scene = c.file("scene.toml", &GOOD.replace("width = 32\nheight = 32", "width = 256\nheight = 256"));
    let mut child = Command::new(env!("CARGO_BIN_EXE_prism"))
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(c.dir.join("out.png"))
        .arg("--exr")
        .arg(c.dir.join("out.exr"))
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let temp = |c: &Case| c.listing().iter().any(|n| n.starts_with(".prism-tmp-"));
    let start = std::time::Instant::now();
    while !temp(&c) {
        assert!(child.try_wait().unwrap().is_none(), "prism exited before its temporary files were seen");
        assert!(start.elapsed() < std::time::Duration::from_secs(60), "no temporary file appeared");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let kill = Command::new("kill").arg("-INT").arg(child.id().to_string()).status().unwrap();
    assert!(kill.success());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(out.status.code(), Some(130), "signal {:?}: {stderr}", out.status.signal());
    assert_eq!(c.listing(), ["scene.toml"], "{stderr}");
}

#[test]
fn environment_image_wider_than_the_device_allows() {
    // lavapipe's maxImageDimension2D is 16384 (Mesa 22.3): one texel more is refused before
    // the image is created, naming the key and the limit.
    let c = Case::new("env-limit");
    image::RgbaImage::new(16385, 1).save(c.dir.join("wide.png")).unwrap();
    let scene = c.file(
        "scene.toml",
        &GOOD.replace("type = \"constant\"\nradiance = 0.5", "type = \"image\"\nfile = \"wide.png\""),
    );
    let e = c.render_fails(&scene, &["--validation"], &[]);
    assert!(e.contains("environment.file") && e.contains("maxImageDimension2D is 16384"), "{e}");
}

#[test]
fn reference_pixel_state_beyond_the_storage_buffer_range() {
    // 64 bytes of per-pixel state at 2048^2 are 256 MiB; lavapipe's maxStorageBufferRange
    // is 128 MiB (2^27), and the buffer is bound whole. One sample and no photons: without
    // the check the render, its validation errors and its failure take seconds, not the
    // default settings' many minutes.
    let c = Case::new("reference-limit");
    let scene = c.file("scene.toml", GOOD);
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_prism"));
    cmd.arg("reference").arg(&scene).args(["--width", "2048", "--height", "2048", "--spp", "1", "--photons", "0"]);
    cmd.args(["--validation", "-o"]);
    cmd.arg(c.dir.join("ref.exr")).current_dir(&c.dir);
    let e = c.fails(&mut cmd);
    assert!(e.contains("--width/--height") && e.contains("maxStorageBufferRange is 128 MiB"), "{e}");
}

#[test]
fn caustic_grid_beyond_the_storage_buffer_range() {
    // caustics mapping keeps one 32-byte splat record per grid vertex (one source face on
    // caustic_sphere, one channel): 2100^2 of them are 134.6 MB, more than lavapipe's
    // maxStorageBufferRange of 128 MiB (2^27 = 134.2 MB); 2048^2 (128 MiB exactly) would fit.
    let c = Case::new("caustic-grid-limit");
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/caustic_sphere.toml");
    let sets = ["--set", "render.caustics=caustics_map", "--set", "render.caustics_map.grid=2100"];
    let e =
        c.render_fails(&scene, &[&["--width", "16", "--height", "16", "--validation"][..], &sets[..]].concat(), &[]);
    assert!(e.contains("render.caustics_map.grid = 2100") && e.contains("maxStorageBufferRange is 128 MiB"), "{e}");
}
