//! Tests of the scene module as a whole: the benchmark scenes, overrides and errors.

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::*;

fn bench(name: &str) -> Scene {
    match load(&benchmark_scene_path(name), &[]) {
        Ok(s) => s,
        Err(e) => panic!("{name}: {e}"),
    }
}

fn sets(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

fn close(a: Vec3, b: Vec3, eps: f32) -> bool {
    (a - b).length() <= eps
}

/// A minimal valid scene; line numbers are used by the error tests.
const BASE: &str = r#"[camera]
position = [0, 0, 4]
target = [0, 0, 0]

[environment]
type = "constant"
radiance = 0

[materials.glass]
type = "dielectric"
ior = 1.5

[[objects]]
material = "glass"
shape = "sphere"
radius = 1
"#;

fn base_err(text: &str, overrides: &[&str]) -> SceneError {
    match load_str(text, Path::new("test.toml"), &sets(overrides)) {
        Ok(_) => panic!("expected an error for:\n{text}\n{overrides:?}"),
        Err(e) => e,
    }
}

/// The error of BASE with `from` replaced by `to`.
fn replaced_err(from: &str, to: &str) -> SceneError {
    base_err(&BASE.replace(from, to), &[])
}

fn at(e: &SceneError) -> (Option<usize>, Option<usize>) {
    let loc = e.location().unwrap_or_else(|| panic!("no location: {e}"));
    (loc.line, loc.column)
}

/// A fresh directory under the system temp dir for files a test writes.
fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("prism-scene-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create temp dir");
    d
}

#[test]
fn every_benchmark_scene_loads_with_expected_counts() {
    // (name, objects, lights, materials)
    let expect = [
        ("sphere_env", 1, 0, 1),
        ("bunny_env", 1, 0, 1),
        ("bubble_env", 1, 0, 1),
        ("sphere_nearby", 4, 1, 4),
        ("caustic_sphere", 2, 1, 2),
        ("caustic_bunny", 2, 1, 2),
        ("metal_ring", 2, 1, 2),
        ("water_pool", 6, 1, 3),
        ("room_mirror", 7, 1, 5),
        ("room_glass", 8, 1, 6),
    ];
    assert_eq!(expect.len(), BENCHMARK_SCENES.len());
    for (name, objects, lights, materials) in expect {
        let s = bench(name);
        assert_eq!(s.name, name);
        assert_eq!(s.objects.len(), objects, "{name} objects");
        assert_eq!(s.lights.len(), lights, "{name} lights");
        assert_eq!(s.materials.len(), materials, "{name} materials");
        assert_eq!((s.camera.width, s.camera.height), (512, 512), "{name}");
        // Each scene selects its techniques (docs/scene-format.md, "The bundled scenes'
        // techniques"); every other [render] key, technique parameters included, is at its
        // default, except water_pool's caustic grid (its splats leave a lattice at 128).
        let mut d = RenderSettings::default();
        if name == "water_pool" {
            d.params.insert("caustics_map".into(), toml::toml! { grid = 256 });
        }
        let mut r = s.render.clone();
        (r.refraction, r.reflection, r.caustics) = (d.refraction.clone(), d.reflection.clone(), d.caustics.clone());
        assert_eq!(r, d, "{name}");
        for o in &s.objects {
            let m = &o.mesh;
            assert!(m.triangle_count() > 0, "{name}/{}", o.name);
            assert_eq!(m.normals.len(), m.positions.len());
            assert_eq!(m.checker_uv.len(), m.positions.len());
            assert!(m.indices.iter().all(|&i| (i as usize) < m.positions.len()));
            assert!(m.positions.iter().all(|p| p.is_finite()));
            assert!(m.normals.iter().all(|n| n.is_finite() && (n.length() - 1.0).abs() < 1e-4), "{name}/{}", o.name);
        }
    }
}

#[test]
fn sphere_env_numbers() {
    let s = bench("sphere_env");
    let c = s.camera;
    assert_eq!(c.position, Vec3::new(0.0, 0.0, 4.0));
    assert_eq!(c.target, Vec3::ZERO);
    assert_eq!(c.up, Vec3::Y);
    assert_eq!(c.vfov_deg, 40.0);
    let ball = &s.objects[0];
    assert_eq!(ball.shape, "sphere");
    assert_eq!(ball.analytic, Some(Analytic::Sphere { center: Vec3::ZERO, radius: 1.0 }));
    assert_eq!(*s.material_of(ball), Material::Dielectric { ior: Vec3::splat(1.5), absorption: Vec3::ZERO });
    assert!(s.material_of(ball).is_specular());
    assert_eq!(s.material_of(ball).kind_name(), "dielectric");
    // 128 x 64 default tessellation.
    assert_eq!(ball.mesh.triangle_count(), 128 * 64 * 2 - 2 * 128);
    // The grid is evaluated from its formula, not baked into an image.
    assert_eq!(s.environment, Environment::Grid);
    // bubble_env differs only in the ior.
    let b = bench("bubble_env");
    assert_eq!(b.materials[0], Material::Dielectric { ior: Vec3::splat(0.75), absorption: Vec3::ZERO });
}

#[test]
fn bunny_scenes_are_fitted() {
    let b = bench("bunny_env");
    let (lo, hi) = b.objects[0].mesh.bounds();
    assert!(((hi - lo).max_element() - 2.0).abs() < 1e-5);
    assert!(close((lo + hi) * 0.5, Vec3::ZERO, 1e-5));
    assert_eq!(b.objects[0].mesh.triangle_count(), 3674);

    let s = bench("caustic_bunny");
    let bunny = s.object("bunny").expect("bunny");
    assert_eq!(
        *s.material_of(bunny),
        Material::Dielectric { ior: Vec3::splat(1.3), absorption: Vec3::new(0.1, 0.8, 2.0) }
    );
    let (lo, hi) = bunny.mesh.bounds();
    assert!(((hi - lo).max_element() - 2.0).abs() < 1e-5);
    assert!(lo.y.abs() < 1e-5, "resting on the floor: {lo}");
    assert!(((lo.x + hi.x) * 0.5).abs() < 1e-5 && ((lo.z + hi.z) * 0.5).abs() < 1e-5);
    assert_eq!(s.lights[0], Light::Point { position: Vec3::new(1.0, 5.0, 1.0), intensity: Vec3::splat(50.0) });

    let n = bench("sphere_nearby");
    let bunny = n.object("bunny").expect("bunny");
    let (lo, hi) = bunny.mesh.bounds();
    assert!(((hi - lo).max_element() - 1.2).abs() < 1e-5);
    assert!((lo.y + 1.0).abs() < 1e-5);
    assert!(((lo.x + hi.x) * 0.5 - 1.6).abs() < 1e-5);
    assert!(((lo.z + hi.z) * 0.5 + 1.5).abs() < 1e-5);
    // The OBJ's own orientation: +Y up means the bunny is taller than deep.
    assert!(hi.y - lo.y > hi.z - lo.z);
    assert_eq!(*n.material_of(bunny), Material::Diffuse { albedo: Albedo::Constant(Vec3::new(0.7, 0.5, 0.3)) });
}

#[test]
fn sphere_nearby_walls_and_checker_coordinates() {
    let s = bench("sphere_nearby");
    assert_eq!(s.environment, Environment::Constant(Vec3::splat(0.05)));
    let floor = s.object("floor").expect("floor");
    let (lo, hi) = floor.mesh.bounds();
    assert!(close(lo, Vec3::new(-5.0, -1.0, -5.0), 1e-6) && close(hi, Vec3::new(5.0, -1.0, 5.0), 1e-6));
    // Horizontal quad: (s, t) = world (x, z).
    for (p, st) in floor.mesh.positions.iter().zip(&floor.mesh.checker_uv) {
        assert_eq!(*st, Vec2::new(p.x, p.z));
    }
    let wall = s.object("back_wall").expect("wall");
    let (lo, hi) = wall.mesh.bounds();
    assert!(close(lo, Vec3::new(-5.0, -1.0, -3.0), 1e-6) && close(hi, Vec3::new(5.0, 5.0, -3.0), 1e-6));
    assert!(wall.mesh.normals.iter().all(|n| *n == Vec3::Z));
    // Vertical quad: distances from its centre (0, 2, -3) along u = +X and v = +Y.
    for (p, st) in wall.mesh.positions.iter().zip(&wall.mesh.checker_uv) {
        assert!((*st - Vec2::new(p.x, p.y - 2.0)).length() < 1e-6);
    }
    let Material::Diffuse { albedo } = *s.material_of(floor) else { panic!("floor is diffuse") };
    let (a, b) = (Vec3::splat(0.8), Vec3::splat(0.2));
    assert_eq!(albedo, Albedo::Checker { a, b, size: 0.5 });
    assert_eq!(albedo.eval(Vec2::new(0.25, 0.25)), a);
    assert_eq!(albedo.eval(Vec2::new(0.75, 0.25)), b);
    assert_eq!(albedo.eval(Vec2::new(-0.25, 0.25)), b);
    assert_eq!(albedo.eval(Vec2::new(-0.25, -0.25)), a);
    // Sphere checker coordinates are world (x, z) too.
    let ball = s.object("ball").expect("ball");
    let (p, st) = (ball.mesh.positions[77], ball.mesh.checker_uv[77]);
    assert_eq!(st, Vec2::new(p.x, p.z));
}

#[test]
fn metal_ring_profile_and_light() {
    let s = bench("metal_ring");
    let ring = s.object("ring").expect("ring");
    assert_eq!(*s.material_of(ring), Material::Mirror { reflectance: Vec3::splat(0.95) });
    let (lo, hi) = ring.mesh.bounds();
    assert!(lo.y.abs() < 1e-6 && (hi.y - 0.5).abs() < 1e-6);
    assert!((hi.x - 1.0).abs() < 1e-5);
    for (p, n) in ring.mesh.positions.iter().zip(&ring.mesh.normals) {
        let r = Vec2::new(p.x, p.z).length();
        let radial = Vec3::new(p.x, 0.0, p.z) / r;
        if n.y > 0.999 {
            assert!((p.y - 0.5).abs() < 1e-6, "only the top rim faces up");
        } else if (r - 1.0).abs() < 1e-5 {
            assert!(n.dot(radial) > 0.999, "outer wall faces out");
        } else {
            assert!((r - 0.97).abs() < 1e-5 && n.dot(radial) < -0.999, "inner wall faces in");
        }
        assert!(n.y > -0.5, "no bottom cap");
    }
    let d = Vec3::new(-0.866, -0.5, 0.0).normalize();
    match s.lights[0] {
        Light::Directional { direction, irradiance } => {
            assert!(close(direction, d, 1e-6));
            assert_eq!(irradiance, Vec3::splat(3.0));
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn water_pool_heights_follow_the_formula() {
    let s = bench("water_pool");
    let h = |x: f32, z: f32| 0.03 * (4.0 * x).sin() + 0.02 * (5.0 * z + 1.0).sin();
    let waves = [
        Wave { amplitude: 0.03, kx: 4.0, kz: 0.0, omega: 3.0, phase: 0.0 },
        Wave { amplitude: 0.02, kx: 0.0, kz: 5.0, omega: -2.0, phase: 1.0 },
    ];
    for (x, z) in [(0.0, 0.0), (0.3, -1.2), (-2.5, 2.9), (1.0, 1.0)] {
        assert!((wave_height(&waves, x, z, 0.0) - h(x, z)).abs() < 1e-6);
    }
    // At t = 1 the phases move: 0.03 sin(4x + 3) + 0.02 sin(5z - 2 + 1).
    let x = 0.4f32;
    let z = -0.2f32;
    let ht = 0.03 * (4.0 * x + 3.0).sin() + 0.02 * (5.0 * z - 1.0).sin();
    assert!((wave_height(&waves, x, z, 1.0) - ht).abs() < 1e-6);
    let water = s.object("water").expect("water");
    assert_eq!(water.mesh.positions.len(), 129 * 129);
    for p in &water.mesh.positions {
        assert!((p.y - h(p.x, p.z)).abs() < 1e-6, "{p}");
    }
    assert!(water.mesh.normals.iter().all(|n| n.y > 0.8), "water normals face up");
    let (lo, hi) = water.mesh.bounds();
    assert!((lo.x + 3.0).abs() < 1e-6 && (hi.z - 3.0).abs() < 1e-6);
    match s.lights[0] {
        Light::Directional { direction, .. } => {
            assert!(close(direction, Vec3::new(0.2, -1.0, 0.1).normalize(), 1e-6))
        }
        other => panic!("{other:?}"),
    }
    // Walls face into the pool and span y = -1.5 .. 0.
    for name in ["wall_left", "wall_right", "wall_back", "wall_front"] {
        let w = s.object(name).expect(name);
        let (lo, hi) = w.mesh.bounds();
        assert!((lo.y + 1.5).abs() < 1e-6 && hi.y.abs() < 1e-6, "{name}");
        let c = (lo + hi) * 0.5;
        assert!(w.mesh.normals[0].dot(-c) > 0.0, "{name} faces inward");
    }
}

#[test]
fn rooms_face_inward() {
    let m = bench("room_mirror");
    let g = bench("room_glass");
    assert_eq!(*m.material_of(m.object("ball").expect("ball")), Material::Mirror { reflectance: Vec3::splat(0.95) });
    assert_eq!(
        *g.material_of(g.object("ball").expect("ball")),
        Material::Dielectric { ior: Vec3::splat(1.5), absorption: Vec3::ZERO }
    );
    let room_centre = Vec3::new(0.0, 2.0, 0.0);
    for name in ["floor", "ceiling", "left_wall", "right_wall", "back_wall", "front_wall"] {
        let w = m.object(name).expect(name);
        let (lo, hi) = w.mesh.bounds();
        assert!(w.mesh.normals[0].dot(room_centre - (lo + hi) * 0.5) > 0.0, "{name}");
        assert!(lo.cmpge(Vec3::new(-3.0, 0.0, -3.0) - 1e-6).all());
        assert!(hi.cmple(Vec3::new(3.0, 4.0, 3.0) + 1e-6).all());
    }
    let left = m.material_of(m.object("left_wall").expect("left"));
    assert_eq!(*left, Material::Diffuse { albedo: Albedo::Constant(Vec3::new(0.8, 0.1, 0.1)) });
    let b = g.object("box").expect("box");
    let (lo, hi) = b.mesh.bounds();
    assert!(close(lo, Vec3::new(-1.6, 0.0, -1.4), 1e-6) && close(hi, Vec3::new(-0.8, 0.8, -0.6), 1e-6));
    assert_eq!(
        g.camera,
        Camera {
            position: Vec3::new(0.0, 2.0, 2.9),
            target: Vec3::new(0.0, 1.0, -1.0),
            up: Vec3::Y,
            vfov_deg: 60.0,
            width: 512,
            height: 512
        }
    );
}

#[test]
fn camera_rays() {
    let mut c = bench("sphere_env").camera;
    c.width = 5;
    c.height = 3;
    let (o, d) = c.primary_ray(2, 1);
    assert_eq!(o, c.position);
    assert!(close(d, Vec3::NEG_Z, 1e-6), "centre pixel looks at the target");
    let (_, top) = c.primary_ray(2, 0);
    assert!(top.y > 0.0, "row 0 is the top");
    let (_, right) = c.primary_ray(4, 1);
    assert!(right.x > 0.0, "column W-1 is on the right");
    // The top edge of the image is vfov/2 above the axis.
    c.height = 1000;
    c.width = 1000;
    let (_, edge) = c.primary_ray(500, 0);
    let angle = edge.angle_between(Vec3::NEG_Z).to_degrees();
    assert!((angle - 20.0).abs() < 0.05, "{angle}");
    let v = c.view();
    assert!(close(v.transform_point3(Vec3::ZERO), Vec3::new(0.0, 0.0, -4.0), 1e-6));
}

#[test]
fn overrides_set_existing_keys() {
    let p = benchmark_scene_path("sphere_env");
    let s = load(
        &p,
        &sets(&["camera.width=256", "objects.0.radius=0.5", "materials.glass.ior=1.2", "objects.0.center.1=0.25"]),
    )
    .expect("overrides apply");
    assert_eq!(s.camera.width, 256);
    assert_eq!(s.camera.height, 512);
    assert_eq!(s.objects[0].analytic, Some(Analytic::Sphere { center: Vec3::new(0.0, 0.25, 0.0), radius: 0.5 }));
    assert_eq!(s.materials[0], Material::Dielectric { ior: Vec3::splat(1.2), absorption: Vec3::ZERO });
    assert!(s.canonical.contains("width = 256"), "{}", s.canonical);
    let plain = load(&p, &[]).expect("plain");
    assert_ne!(plain.canonical, s.canonical);
    // RGB values and unquoted strings.
    let s = load(&p, &sets(&["materials.glass.ior=[1.5, 1.52, 1.54]", "render.refraction=single"])).expect("rgb ior");
    assert_eq!(s.materials[0], Material::Dielectric { ior: Vec3::new(1.5, 1.52, 1.54), absorption: Vec3::ZERO });
    assert_eq!(s.render.refraction, "single");
}

#[test]
fn overrides_create_render_parameters_only() {
    let s = load_str(BASE, Path::new("t.toml"), &sets(&["render.hu_qin.max_iterations=4", "render.exposure=2"]))
        .expect("render tables are created");
    assert_eq!(s.render.exposure, 2.0);
    let wyman = s.render.params.get("hu_qin").expect("params");
    assert_eq!(wyman.get("max_iterations").and_then(|v| v.as_integer()), Some(4));
    // The effective scene holds them, so a cached result keyed by it differs.
    assert!(s.canonical.contains("max_iterations = 4"), "{}", s.canonical);

    // A key left at its default may be set; a misspelt one is caught by the schema and
    // the error names the override.
    let s = load_str(BASE, Path::new("t.toml"), &sets(&["camera.vfov_deg=30"])).expect("default key set");
    assert_eq!(s.camera.vfov_deg, 30.0);
    let e = base_err(BASE, &["camera.fov=3"]);
    assert!(e.to_string().contains("--set camera.fov=3") && e.to_string().contains("fov"), "{e}");

    for (set, needle) in [
        ("objects.3.radius=1", "index 3 is out of range"),
        ("materials.metal.ior=1", "`materials.metal` does not exist"),
        ("lights.0.intensity=1", "`lights` does not exist"),
        ("objects.x.radius=1", "not an index"),
        ("camera.target.0.x=1", "not a table"),
        ("camera", "no `=`"),
    ] {
        let e = base_err(BASE, &[set]);
        let SceneError::Override { set: s, message, .. } = &e else {
            panic!("{set}: expected an override error, got {e}");
        };
        assert_eq!(s, set);
        assert!(message.contains(needle), "{set}: {message}");
        assert!(e.to_string().starts_with(&format!("--set {set}: ")), "{e}");
    }
}

#[test]
fn technique_names_are_validated() {
    let e = base_err(BASE, &["render.refraction=wyman2"]);
    assert_eq!(e.kind(), Some(ErrorKind::Value));
    let text = e.to_string();
    assert!(text.contains("--set render.refraction=wyman2"), "{text}");
    assert!(text.contains("unknown refraction technique `wyman2`"), "{text}");
    assert!(text.contains("`single`"), "{text}");
    let e = base_err(&format!("{BASE}\n[render]\ncaustics = \"photon\"\n"), &[]);
    assert_eq!(at(&e).0, Some(19));
    assert!(e.to_string().contains("accepted values: `none`"), "{e}");
    let e = base_err(&format!("{BASE}\n[render]\nshadow_map = 5\n"), &[]);
    assert_eq!(e.kind(), Some(ErrorKind::Schema));
    assert!(e.to_string().contains("unknown key `shadow_map`"), "{e}");
    // Technique parameters are checked by the technique, naming the key and the override.
    let e = base_err(BASE, &["render.hu_qin.search_steps=0"]);
    assert_eq!(e.kind(), Some(ErrorKind::Value));
    let text = e.to_string();
    assert!(text.contains("--set render.hu_qin.search_steps=0") && text.contains("`search_steps`"), "{text}");
    let e = base_err(BASE, &["render.wyman.back_surfaces=\"second\""]);
    assert!(e.to_string().contains("unknown parameter `back_surfaces`"), "{e}");
}

#[test]
fn errors_caused_by_overrides_name_them() {
    let e = base_err(BASE, &["camera.position=[0, 0, nan]"]);
    assert!(e.to_string().contains("test.toml:2:"), "{e}");
    assert!(e.to_string().contains("--set camera.position=[0, 0, nan]: "), "{e}");
    let e = base_err(BASE, &["objects.0.radius=-2"]);
    assert_eq!(at(&e).0, Some(16));
    assert!(e.to_string().contains("--set objects.0.radius=-2"), "{e}");
    // A type error found by serde is attributed through its span.
    let e = base_err(BASE, &["objects.0.radius=big"]);
    assert_eq!(e.kind(), Some(ErrorKind::Schema));
    assert!(e.to_string().contains("--set objects.0.radius=big"), "{e}");
}

#[test]
fn error_missing_scene_file() {
    let e = load(Path::new("/nonexistent/dir/scene.toml"), &[]).unwrap_err();
    assert!(matches!(e, SceneError::Io { .. }));
    let text = e.to_string();
    assert!(text.contains("/nonexistent/dir/scene.toml"), "{text}");
    assert!(text.contains("hint:"), "{text}");
}

#[test]
fn error_malformed_toml() {
    let e = replaced_err("shape = \"sphere\"", "shape = sphere");
    assert_eq!(e.kind(), Some(ErrorKind::Syntax));
    assert_eq!(at(&e).0, Some(15));
    let e = replaced_err("target = [0, 0, 0]", "target = [0, 0, 0] oops");
    assert_eq!(at(&e), (Some(3), Some(20)));
    assert!(e.to_string().starts_with("test.toml:3:20: malformed TOML"), "{e}");
}

#[test]
fn error_unknown_key() {
    let e = replaced_err("radius = 1", "radius = 1\nradiuss = 2");
    assert_eq!(e.kind(), Some(ErrorKind::Schema));
    assert_eq!(at(&e), (Some(17), Some(1)));
    assert!(e.to_string().contains("unknown field `radiuss`"), "{e}");
    // A key of another shape.
    let e = replaced_err("radius = 1", "radius = 1\nsize = [1, 1]");
    assert_eq!(at(&e), (Some(17), Some(1)));
    assert!(e.to_string().contains("not used by shape `sphere`"), "{e}");
    // Inside an inline table, with the column of the key.
    let e = replaced_err("radius = 1", "radius = 1\ntransform = { scale = 2, spin = 3 }");
    assert_eq!(at(&e), (Some(17), Some(26)));
    // A missing required key points at its table.
    let e = replaced_err("radius = 1", "");
    assert_eq!(at(&e).0, Some(13));
    assert!(e.to_string().contains("needs `radius`"), "{e}");
}

#[test]
fn error_unknown_material() {
    let e = replaced_err("material = \"glass\"", "material = \"glas\"");
    assert_eq!(e.kind(), Some(ErrorKind::Reference));
    assert_eq!(at(&e), (Some(14), Some(12)));
    let text = e.to_string();
    assert!(text.contains("unknown material `glas`"), "{text}");
    assert!(text.contains("known materials: `glass`"), "{text}");
}

#[test]
fn error_bad_values() {
    for (from, to, line, needle) in [
        ("radius = 1", "radius = -1", 16, "greater than 0"),
        ("radius = 1", "radius = nan", 16, "finite"),
        ("ior = 1.5", "ior = 0", 11, "greater than 0"),
        ("ior = 1.5", "ior = [1.5, -1, 1.5]", 11, "greater than 0"),
        ("target = [0, 0, 0]", "target = [0, 0, 4]", 3, "looks nowhere"),
        ("radiance = 0", "radiance = -1", 7, "at least 0"),
    ] {
        let e = base_err(&BASE.replace(from, to), &[]);
        assert_eq!(e.kind(), Some(ErrorKind::Value), "{e}");
        assert_eq!(at(&e).0, Some(line), "{e}");
        assert!(e.to_string().contains(needle), "{e}");
        assert!(e.to_string().contains("hint: "), "{e}");
    }
    let e = base_err(&BASE.replace("target = [0, 0, 0]", "target = [0, 0, 0]\nwidth = 0"), &[]);
    assert_eq!(e.kind(), Some(ErrorKind::Value));
    assert_eq!(at(&e), (Some(4), Some(9)));
    assert!(e.to_string().starts_with("test.toml:4:9: `width` must be from 1"), "{e}");
    let e = base_err(BASE, &["camera.target=[0, 0, 4]"]);
    assert_eq!(e.kind(), Some(ErrorKind::Value));
    assert!(e.to_string().contains("--set camera.target=[0, 0, 4]"), "{e}");
    let dir_light = format!("{BASE}\n[[lights]]\ntype = \"directional\"\ndirection = [0, 0, 0]\nirradiance = 1\n");
    let e = base_err(&dir_light, &[]);
    assert_eq!(at(&e).0, Some(20));
    assert!(e.to_string().contains("zero length"), "{e}");
}

#[test]
fn mesh_file_errors() {
    let dir = temp_dir("meshes");
    let scene = |obj: &str| {
        format!(
            "[camera]\nposition = [0, 0, 4]\ntarget = [0, 0, 0]\n[environment]\ntype = \"constant\"\nradiance = 0\n\
             [materials.m]\ntype = \"diffuse\"\nalbedo = 0.5\n[[objects]]\nmaterial = \"m\"\nshape = \"mesh\"\nfile = \"{obj}\"\n"
        )
    };
    let origin = dir.join("scene.toml");
    std::fs::write(dir.join("nan.obj"), "v 0 0 0\nv 1 0 0\nv 0 NaN 0\nf 1 2 3\n").unwrap();
    std::fs::write(dir.join("oob.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 3\nf 1 2 9\n").unwrap();
    std::fs::write(dir.join("ok.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 2 2 4\n").unwrap();

    let e = load_str(&scene("nan.obj"), &origin, &[]).unwrap_err();
    assert_eq!(e.kind(), Some(ErrorKind::Mesh));
    let loc = e.location().unwrap();
    assert_eq!((loc.file.clone(), loc.line), (dir.join("nan.obj"), Some(3)));
    assert!(e.to_string().contains("non-finite"), "{e}");
    assert!(e.to_string().contains("scene.toml:13"), "names the referencing line: {e}");

    let e = load_str(&scene("oob.obj"), &origin, &[]).unwrap_err();
    assert_eq!(e.kind(), Some(ErrorKind::Mesh));
    assert_eq!(e.location().unwrap().line, Some(6));
    assert!(e.to_string().contains("out of range"), "{e}");

    let e = load_str(&scene("missing.obj"), &origin, &[]).unwrap_err();
    assert_eq!(e.kind(), Some(ErrorKind::MissingFile));
    assert_eq!(e.location().unwrap().file, origin);
    assert_eq!(at(&e), (Some(13), Some(8)));
    assert!(e.to_string().contains("missing.obj"), "{e}");

    // Degenerate triangles are kept and have finite normals.
    let s = load_str(&scene("ok.obj"), &origin, &[]).expect("ok.obj");
    let m = &s.objects[0].mesh;
    assert_eq!(m.triangle_count(), 2);
    assert!(m.normals.iter().all(|n| n.is_finite() && (n.length() - 1.0).abs() < 1e-5));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn image_environments_load_linear() {
    let dir = temp_dir("images");
    let png = dir.join("env.png");
    let img = image::RgbaImage::from_pixel(4, 2, image::Rgba([188, 255, 0, 255]));
    img.save(&png).expect("write png");
    let text = BASE.replace("type = \"constant\"\nradiance = 0", "type = \"image\"\nfile = \"env.png\"");
    let s = load_str(&text, &dir.join("s.toml"), &[]).expect("image env");
    match &s.environment {
        Environment::Image { width, height, texels, .. } => {
            assert_eq!((*width, *height), (4, 2));
            // sRGB 188/255 is linear 0.5 (to 3 digits).
            assert!((texels[0][0] - 0.5029).abs() < 1e-3, "{:?}", texels[0]);
            assert_eq!(texels[0][1], 1.0);
        }
        other => panic!("{other:?}"),
    }
    let e = load_str(&text.replace("env.png", "nope.exr"), &dir.join("s.toml"), &[]).unwrap_err();
    assert_eq!(e.kind(), Some(ErrorKind::MissingFile));
    assert_eq!(at(&e).0, Some(7));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn canonical_ignores_layout_and_comments() {
    let a = load_str(BASE, Path::new("a.toml"), &[]).expect("a");
    let commented = BASE.replace("radius = 1", "radius   =   1   # one metre");
    let b = load_str(&commented, Path::new("b.toml"), &[]).expect("b");
    assert_eq!(a.canonical, b.canonical);
    let c = load_str(BASE, Path::new("a.toml"), &sets(&["objects.0.radius=2"])).expect("c");
    assert_ne!(a.canonical, c.canonical);
    // The default name is the file stem.
    assert_eq!(a.name, "a");
    assert_eq!(a.objects[0].name, "sphere0");
}

#[test]
fn default_paths() {
    assert!(default_scene_path().exists());
    assert!(assets_dir().join("meshes").join("bunny.obj").exists());
    assert!(load(&default_scene_path(), &[]).is_ok());
}

/// BASELINE selects the defaults of `[render]`: a scene without a `[render]` table.
#[test]
fn the_baseline_is_the_render_defaults() {
    let without = load_str(BASE, Path::new("t.toml"), &[]).unwrap();
    let baseline: Vec<String> = BASELINE.iter().map(|s| s.to_string()).collect();
    let with = load(&benchmark_scene_path("caustic_sphere"), &baseline).unwrap();
    for s in [&without, &with] {
        let r = &s.render;
        assert_eq!((r.refraction.as_str(), r.reflection.as_str(), r.caustics.as_str()), ("single", "single", "none"));
    }
}

#[test]
fn tone_map_setting_and_adaptive_parameters() {
    use crate::scene::techniques::TonemapAdaptiveParams;
    let s = load_str(BASE, Path::new("t.toml"), &[]).unwrap();
    assert_eq!((s.render.tonemap.as_str(), s.render.tonemap_named), ("clamp", false));
    let s = load_str(BASE, Path::new("t.toml"), &sets(&["render.tonemap=clamp"])).unwrap();
    assert_eq!((s.render.tonemap.as_str(), s.render.tonemap_named), ("clamp", true));
    let s = load_str(
        BASE,
        Path::new("t.toml"),
        &sets(&[
            "render.tonemap=adaptive",
            "render.tonemap_adaptive.key=0.18",
            "render.tonemap_adaptive.white=\"auto\"",
        ]),
    )
    .unwrap();
    assert_eq!((s.render.tonemap.as_str(), s.render.tonemap_named), ("adaptive", true));
    let p = TonemapAdaptiveParams::from_settings(&s.render).unwrap();
    assert_eq!(p, TonemapAdaptiveParams { key: Some(0.18), white: None, ..Default::default() });
    // The defaults: Krawczyk et al. 2005's time constants, automatic key and white.
    let d = TonemapAdaptiveParams::default();
    assert_eq!((d.tau_rod, d.tau_cone, d.key, d.white), (0.4, 0.1, None, None));
    for bad in ["render.tonemap=aces", "render.tonemap_adaptive.delta=-1", "render.tonemap_adaptive.white=\"max\""] {
        let e = load_str(BASE, Path::new("t.toml"), &sets(&[bad])).expect_err(bad).to_string();
        assert!(e.contains("--set"), "{bad}: {e}");
    }
}

#[test]
fn every_bundled_scene_has_a_one_line_description() {
    let names = bundled_scenes().unwrap();
    for name in BENCHMARK_SCENES {
        assert!(names.iter().any(|n| n == name), "{name} is not in assets/scenes/");
    }
    for name in &names {
        let d = bench(name).description.unwrap_or_default();
        assert!(!d.is_empty() && !d.contains('\n'), "{name}: {d:?}");
    }
}

#[test]
fn description_is_one_line() {
    let s = load_str(&format!("description = \"a ball\"\n{BASE}"), Path::new("test.toml"), &[]).unwrap();
    assert_eq!(s.description.as_deref(), Some("a ball"));
    let e = load_str(&format!("description = \"\"\"a\nball\"\"\"\n{BASE}"), Path::new("test.toml"), &[]).unwrap_err();
    assert!(e.to_string().contains("description"), "{e}");
    let e = load_str(&format!("descripton = \"a ball\"\n{BASE}"), Path::new("test.toml"), &[]).unwrap_err();
    assert!(e.to_string().contains("descripton"), "{e}");
}

#[test]
fn counts_beyond_their_limits_are_refused() {
    let sphere = "[[objects]]\nmaterial = \"glass\"\nshape = \"sphere\"\nradius = 1\nsegments = 8\n";
    let many = format!("{BASE}{}", sphere.repeat(super::MAX_OBJECTS));
    let e = base_err(&many, &[]);
    assert!(e.to_string().contains("`objects` has 1025 entries; the limit is 1024"), "{e}");

    // Spheres of 1024 segments have 1024^2 triangles each: the 65th passes 2^26.
    let spheres = "[[objects]]\nmaterial = \"glass\"\nshape = \"sphere\"\nradius = 1\n".repeat(1000);
    let e = base_err(&format!("{BASE}{spheres}"), &["render.sphere_segments=1024"]);
    assert!(e.to_string().contains("sphere_segments") && e.to_string().contains("limit is 67108864"), "{e}");

    let points: Vec<String> = (0..=super::MAX_PROFILE_POINTS).map(|k| format!("[1, {k}]")).collect();
    let lathe = format!("[[objects]]\nmaterial = \"glass\"\nshape = \"lathe\"\nprofile = [{}]\n", points.join(", "));
    let e = base_err(&format!("{BASE}{lathe}"), &[]);
    assert!(e.to_string().contains("`objects.1.profile` has 4097 entries; the limit is 4096"), "{e}");

    let volume = "[volume]\nbounds = { min = [-1, -1, -1], max = [1, 1, 1] }\nresolution = [4, 4, 4]\n";
    let region = "[[volume.region]]\nshape = \"sphere\"\nradius = 0.5\n";
    let e = base_err(&format!("{BASE}{volume}{}", region.repeat(super::volume_sources::MAX_REGIONS + 1)), &[]);
    assert!(e.to_string().contains("`volume.region` has 257 entries; the limit is 256"), "{e}");
    let lathe = format!("[[volume.region]]\nshape = \"lathe\"\nprofile = [{}]\n", points.join(", "));
    let e = base_err(&format!("{BASE}{volume}{lathe}"), &[]);
    assert!(e.to_string().contains("`volume.region.0.profile` has 4097 entries"), "{e}");

    // The shading passes' uniform buffer holds MAX_MATERIALS (BASE defines one, glass).
    let max = crate::MAX_MATERIALS as usize;
    let materials =
        |n: usize| (0..n).map(|k| format!("[materials.m{k}]\ntype = \"diffuse\"\nalbedo = 0.5\n")).collect::<String>();
    let e = base_err(&format!("{BASE}{}", materials(max)), &[]);
    assert!(e.to_string().contains("defines 257 materials; the limit is 256"), "{e}");
    load_str(&format!("{BASE}{}", materials(max - 1)), Path::new("test.toml"), &[]).expect("256 materials are allowed");
}

#[test]
fn heightfields_count_towards_the_triangle_limit_and_waves_are_limited() {
    let field = |res: &str, waves: usize| {
        let wave = "{ amplitude = 0.01, kx = 1 }, ".repeat(waves);
        format!(
            "{BASE}[[objects]]\nmaterial = \"glass\"\nshape = \"heightfield\"\nsize = [1, 1]\n\
             resolution = {res}\nwaves = [{wave}]\n"
        )
    };
    // 8192 x 8192 cells are 2^27 triangles, twice the limit, though each axis is in range.
    let e = base_err(&field("[8192, 8192]", 1), &[]);
    assert!(e.to_string().contains("up to objects.1") && e.to_string().contains("limit is 67108864"), "{e}");
    assert_eq!(at(&e), (Some(21), Some(14)), "the error points at `resolution`: {e}");
    let e = base_err(&field("[8, 8]", MAX_WAVES + 1), &[]);
    assert!(e.to_string().contains("`objects.1.waves` has 65 entries; the limit is 64"), "{e}");
    let s = load_str(&field("[8, 8]", MAX_WAVES), Path::new("test.toml"), &[]).expect("64 waves are allowed");
    assert_eq!(s.objects[1].heightfield.as_ref().map(|h| h.waves.len()), Some(MAX_WAVES));
}
