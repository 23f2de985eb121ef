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
        let before: Vec<_> = self.listing();
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_prism"));
        cmd.arg("render").arg(scene).arg("-o").arg(self.dir.join("out.png")).arg("--exr").arg(self.dir.join("out.exr"));
        cmd.args(args).current_dir(&self.dir);
        for (k, v) in env {
            cmd.env(k, v);
        }
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
