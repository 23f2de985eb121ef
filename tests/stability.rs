//! Numerical stability at the extremes: every technique that exists and the reference
//! render at 64^2 and must produce no NaN or Inf pixel (and the reference no NaN in any of
//! its buffers): ior near 1, below 1 and very large, grazing cameras, a camera inside a
//! refractor, tiny and huge scene scales, degenerate triangles and zero-length normals, and
//! a light inside a refractor. Where the answer is known (ior 1, scale invariance), the test
//! checks it too.
mod common;

use std::path::Path;

use prism::metrics::image::{non_finite_count, rmse_rgba};
use prism::reference::{Reference, ReferenceSettings};
use prism::renderer::Renderer;
use prism::scene::{self, Scene, REFRACTION_TECHNIQUES};

const SIZE: u32 = 64;

/// What the last [`render_all`] built, kept alive until the next call has built its own
/// (common::render_after): the next call's renderers and reference reuse the pipelines that
/// did not change instead of compiling them again (lavapipe takes about 3 s for the exact
/// tracer's and the reference's each, at every scene).
#[derive(Default)]
struct Warm {
    renderers: Vec<Option<Renderer>>,
    reference: Option<Reference>,
}

impl Warm {
    /// Drop what is kept, with the validation layer's verdict on the teardown.
    fn finish(self, ctx: &std::sync::Arc<prism::gpu::GpuContext>) {
        drop(self);
        common::assert_no_validation_errors(ctx);
    }
}

/// Render `s` with every refraction technique and with the reference; assert finiteness.
/// Returns (technique images, reference image).
fn render_all(
    ctx: &std::sync::Arc<prism::gpu::GpuContext>,
    s: &Scene,
    what: &str,
    warm: &mut Warm,
) -> (Vec<Vec<f32>>, Vec<f32>) {
    warm.renderers.resize_with(REFRACTION_TECHNIQUES.len(), || None);
    let mut images = Vec::new();
    for (t, last) in REFRACTION_TECHNIQUES.iter().zip(&mut warm.renderers) {
        let mut s = s.clone();
        s.render.refraction = t.to_string();
        let r = common::render_after(ctx, &s, last);
        assert_eq!(non_finite_count(&r.hdr), 0, "{what}: technique {t} produced NaN/Inf");
        images.push(r.hdr);
    }
    let st = ReferenceSettings { spp: 4, photons: 1 << 14, ..ReferenceSettings::default() };
    let mut r = Reference::new(ctx, s, &st).unwrap_or_else(|e| panic!("{what}: {e}"));
    r.run_all(|_, _| {}).unwrap();
    assert_eq!(r.non_finite_values(), 0, "{what}: NaN/Inf in the reference's buffers");
    let img = r.image();
    assert_eq!(non_finite_count(&img), 0, "{what}: reference image");
    warm.reference = Some(r);
    common::assert_no_validation_errors(ctx);
    (images, img)
}

#[test]
fn ior_extremes() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let mut warm = Warm::default();
    for ior in ["0.5", "0.75", "0.999", "1.0", "1.0001", "1.5", "2.42", "4.0"] {
        let s = common::scene("sphere_env", SIZE, &[&format!("materials.glass.ior={ior}")]);
        render_all(&ctx, &s, &format!("ior {ior}"), &mut warm);
    }
    // ior 1 is defined: the ball is invisible, for every technique and for the reference.
    let with = common::scene("sphere_env", SIZE, &["materials.glass.ior=1.0"]);
    let without = common::scene("sphere_env", SIZE, &["objects.0.radius=0.0001"]);
    let (a, ra) = render_all(&ctx, &with, "ior 1", &mut warm);
    let (b, rb) = render_all(&ctx, &without, "no ball", &mut warm);
    for (k, t) in REFRACTION_TECHNIQUES.iter().enumerate() {
        let e = rmse_rgba(&a[k], &b[k]);
        assert!(e < 0.02, "{t}: ior 1 ball changes the image: RMSE {e}");
    }
    let e = rmse_rgba(&ra, &rb);
    assert!(e < 1e-3, "reference: ior 1 ball changes the image: RMSE {e}");
    warm.finish(&ctx);
}

#[test]
fn grazing_cameras() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let mut warm = Warm::default();
    // Rays that just graze the ball's silhouette, and a camera 1e-4 m above the floor
    // looking along it.
    let s = common::scene("sphere_env", SIZE, &["camera.position=[0, 1.0, 4]", "camera.target=[0, 1.0, 0]"]);
    render_all(&ctx, &s, "grazing the refractor", &mut warm);
    let s =
        common::scene("sphere_nearby", SIZE, &["camera.position=[0, -0.9999, 4]", "camera.target=[0, -0.9999, -3]"]);
    render_all(&ctx, &s, "grazing the floor", &mut warm);
    warm.finish(&ctx);
}

#[test]
fn camera_inside_a_refractor_and_light_inside_a_refractor() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let mut warm = Warm::default();
    let s = common::scene("sphere_env", SIZE, &["camera.position=[0, 0, 0.2]"]);
    render_all(&ctx, &s, "camera inside the ball", &mut warm);
    let s = common::scene("caustic_sphere", SIZE, &["lights.0.position=[0, 1.2, 0]"]);
    render_all(&ctx, &s, "light inside the ball", &mut warm);
    warm.finish(&ctx);
}

/// A scene template scaled by `k`: lengths times k, point-light intensity times k^2, so
/// that irradiance I / r^2 and hence the image are unchanged.
fn scaled(k: f64) -> Scene {
    let text = format!(
        r#"
[camera]
position = [0, {cy}, {cz}]
target = [0, 0, 0]
vfov_deg = 40
width = {SIZE}
height = {SIZE}
[environment]
type = "constant"
radiance = 0.05
[[lights]]
type = "point"
position = [{lx}, {ly}, {lz}]
intensity = {i}
[materials.glass]
type = "dielectric"
ior = 1.5
[materials.floor]
type = "diffuse"
checker = {{ a = 0.8, b = 0.2, size = {cs} }}
[materials.box]
type = "diffuse"
albedo = 0.6
[[objects]]
material = "floor"
shape = "quad"
center = [0, {fy}, 0]
size = [{fs}, {fs}]
normal = [0, 1, 0]
[[objects]]
material = "glass"
shape = "sphere"
center = [0, 0, 0]
radius = {r}
[[objects]]
material = "box"
shape = "box"
center = [{bx}, {by}, 0]
size = [{bs}, {bs}, {bs}]
"#,
        cy = 0.5 * k,
        cz = 5.0 * k,
        lx = 2.0 * k,
        ly = 5.0 * k,
        lz = 3.0 * k,
        i = 40.0 * k * k,
        cs = 0.5 * k,
        fy = -k,
        fs = 10.0 * k,
        r = 1.0 * k,
        bx = 1.6 * k,
        by = -0.6 * k,
        bs = 0.8 * k,
    );
    scene::load_str(&text, Path::new("scaled.toml"), &[]).unwrap()
}

#[test]
fn tiny_and_huge_scene_scales_give_the_same_image() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let mut warm = Warm::default();
    let (base, base_ref) = render_all(&ctx, &scaled(1.0), "scale 1", &mut warm);
    for k in [1e-3, 1e4] {
        let (imgs, reference) = render_all(&ctx, &scaled(k), &format!("scale {k}"), &mut warm);
        for (t, (a, b)) in REFRACTION_TECHNIQUES.iter().zip(imgs.iter().zip(&base)) {
            let e = rmse_rgba(a, b);
            assert!(e < 0.01, "{t} at scale {k}: RMSE {e} against scale 1");
        }
        // The reference is stochastic but seeded identically: only rounding differs, which can
        // flip individual Fresnel choices; compare loosely.
        let e = rmse_rgba(&reference, &base_ref);
        assert!(e < 0.05, "reference at scale {k}: RMSE {e} against scale 1");
    }
    warm.finish(&ctx);
}

const DEGENERATE_OBJ: &str = "\
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
v 2 2 0
v 3 3 0
vn 0 0 0
vn 0 0 1
f 1//1 2//1 3//1
f 2//2 4//2 3//2
f 4//1 5//1 6//1
f 1//1 1//1 1//1
";

#[test]
fn degenerate_triangles_and_zero_length_normals() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let mut warm = Warm::default();
    let dir = std::env::temp_dir().join(format!("prism-degenerate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("bad.obj"), DEGENERATE_OBJ).unwrap();
    for material in ["glass", "white"] {
        let text = format!(
            r#"
[camera]
position = [0.5, 0.5, 3]
target = [0.5, 0.5, 0]
width = {SIZE}
height = {SIZE}
[environment]
type = "constant"
radiance = 1
[[lights]]
type = "point"
position = [0, 2, 3]
intensity = 5
[materials.glass]
type = "dielectric"
ior = 1.5
[materials.white]
type = "diffuse"
albedo = 0.7
[[objects]]
material = "{material}"
shape = "mesh"
file = "bad.obj"
"#
        );
        let s = scene::load_str(&text, &dir.join("scene.toml"), &[]).unwrap();
        render_all(&ctx, &s, &format!("degenerate mesh, {material}"), &mut warm);
    }
    warm.finish(&ctx);
    let _ = std::fs::remove_dir_all(&dir);
}
