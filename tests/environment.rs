//! The procedural `grid` environment is the formula of SCENES.md: every technique and the
//! reference see `grid_radiance` of each pixel's centre ray (src/scene/environment.rs), with
//! no texture between them.
mod common;

use glam::Vec3;
use prism::reference::{Reference, ReferenceSettings};
use prism::scene::{grid_radiance, Scene};

/// Fraction of sphere_env's background pixels (those whose centre ray misses the unit ball)
/// that differ from the formula by more than 0.5 in a channel, and the relative difference
/// of their mean radiance from the formula's.
fn background_error(s: &Scene, hdr: &[f32]) -> (f64, f64, usize) {
    let (w, h) = (s.camera.width, s.camera.height);
    let (mut off, mut count, mut sum, mut formula) = (0usize, 0usize, 0f64, 0f64);
    for j in 0..h {
        for i in 0..w {
            let (o, d) = s.camera.primary_ray(i, j);
            // The ray's distance from the ball's centre: the rasterised ball lies inside the
            // exact one, so a ray that misses the exact ball sees the environment.
            let b = o.dot(d);
            if o.length_squared() - b * b <= 1.0 {
                continue;
            }
            let k = 4 * (j * w + i) as usize;
            let got = Vec3::new(hdr[k], hdr[k + 1], hdr[k + 2]);
            let want = grid_radiance(d);
            count += 1;
            if (got - want).abs().max_element() > 0.5 {
                off += 1;
            }
            sum += got.element_sum() as f64;
            formula += want.element_sum() as f64;
        }
    }
    (off as f64 / count as f64, sum / formula - 1.0, count)
}

/// At 256^2 with a 40-degree field of view a pixel spans 0.16 degree, and the 1-degree lines
/// are six pixels wide. Evaluating the formula leaves only float rounding of atan2/acos (about
/// 1e-5 degree, 1e-4 of a pixel) to move a line's edge, which can flip a pixel whose centre
/// lies that close to an edge: a handful of pixels at most. The bounds, 0.1% of the pixels
/// and 0.1% of the mean, are 20 times below the 2% of pixels and the 2.2% brighter mean that
/// a 2048 x 1024 bake looked up bilinearly gives (its lines a pixel wider, the +15-degree
/// latitude line a pixel higher): the half-pixel rule, that a centre sample sees the formula.
const MAX_OFF: f64 = 1e-3;
const MAX_MEAN: f64 = 1e-3;

#[test]
fn grid_background_is_the_formula_in_every_technique_and_the_reference() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let size = 256;
    // Deferred shading draws the background for every technique (glsl/shading/deferred.frag),
    // through the lookup every technique's refracted and reflected rays use.
    let s = common::scene("sphere_env", size, &[]);
    let out = common::render_on(&ctx, &s);
    let (off, mean, count) = background_error(&s, &out.hdr);
    eprintln!("techniques: {count} background pixels, {:.3}% off by > 0.5, mean {:+.4}%", off * 100.0, mean * 100.0);
    assert!(off <= MAX_OFF, "{:.3}% of the background differs from the grid's formula", off * 100.0);
    assert!(mean.abs() <= MAX_MEAN, "the background's mean is {:+.3}% off the formula's", mean * 100.0);
    // The reference's centre rays (no jitter): one sample a pixel, no photons.
    let st = ReferenceSettings { spp: 1, photons: 0, ..ReferenceSettings::default() };
    let mut r = Reference::new(&ctx, &s, &st).expect("reference");
    r.run_all(|_, _| {}).expect("reference run");
    let img = r.image();
    drop(r);
    common::assert_no_validation_errors(&ctx);
    let (off, mean, count) = background_error(&s, &img);
    eprintln!("reference: {count} background pixels, {:.3}% off by > 0.5, mean {:+.4}%", off * 100.0, mean * 100.0);
    assert!(off <= MAX_OFF, "reference: {:.3}% of the background differs from the grid's formula", off * 100.0);
    assert!(mean.abs() <= MAX_MEAN, "reference: the background's mean is {:+.3}% off the formula's", mean * 100.0);
}

/// Deferred shading compiles in the scene's environment kind, light count and light kinds
/// (src/technique/mod.rs `scene_specialization`). A floor under a point light and a
/// directional light in a constant environment, then with a third light, a second point
/// light: every floor pixel must be the closed form of all of its lights, each by its own
/// kind, L = albedo / pi (pi c + sum I cos / r^2 + sum E cos) (a constant environment c gives
/// E = pi c on any surface). Nothing casts a shadow. The albedo, 0.625, is exact in the
/// G-buffer's half floats (0.6 would be stored 6.5e-4 low). Float rounding of the G-buffer's depth
/// (D32, reversed Z: about 1e-6 of the distance in the reconstructed position) and of the SH
/// projection of a constant (its nine coefficients exact to 1e-6) keep the shading within
/// 1e-4 of the formula; a light shaded as the other kind, or left out, is off by 10% or more.
#[test]
fn deferred_shading_lights_each_light_by_its_kind_under_the_scene_s_specialisation() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let size = 64u32;
    let c = 0.05f32;
    let (albedo, point, intensity) = (0.625f32, Vec3::new(0.5, 3.0, -0.5), 20.0f32);
    let (dir, irradiance) = (Vec3::new(0.3, -1.0, 0.2).normalize(), 1.5f32);
    let (point2, intensity2) = (Vec3::new(-1.0, 2.0, 1.0), 8.0f32);
    let text = |third: bool| {
        let extra = if third {
            format!(
                "[[lights]]\ntype = \"point\"\nposition = [{}, {}, {}]\nintensity = {intensity2}\n",
                point2.x, point2.y, point2.z
            )
        } else {
            String::new()
        };
        format!(
            r#"
            [camera]
            position = [0, 4, 4]
            target = [0, 0, 0]
            vfov_deg = 30
            width = {size}
            height = {size}
            [environment]
            type = "constant"
            radiance = {c}
            [[lights]]
            type = "point"
            position = [{}, {}, {}]
            intensity = {intensity}
            [[lights]]
            type = "directional"
            direction = [{}, {}, {}]
            irradiance = {irradiance}
            {extra}
            [materials.floor]
            type = "diffuse"
            albedo = {albedo}
            [[objects]]
            name = "floor"
            material = "floor"
            shape = "quad"
            center = [0, 0, 0]
            size = [20, 20]
            normal = [0, 1, 0]
        "#,
            point.x, point.y, point.z, dir.x, dir.y, dir.z
        )
    };
    for third in [false, true] {
        let s = prism::scene::load_str(&text(third), std::path::Path::new("lights.toml"), &[]).unwrap();
        let out = common::render_on(&ctx, &s);
        let mut worst = 0f32;
        for j in 0..size {
            for i in 0..size {
                let (o, d) = s.camera.primary_ray(i, j);
                let p = o + d * (-o.y / d.y);
                let mut e = std::f32::consts::PI * c + irradiance * (-dir.y);
                let lights: &[(Vec3, f32)] =
                    if third { &[(point, intensity), (point2, intensity2)] } else { &[(point, intensity)] };
                for &(at, i) in lights {
                    let to = at - p;
                    e += i * to.y / to.length() / to.length_squared();
                }
                let want = albedo / std::f32::consts::PI * e;
                let got = out.radiance(i, j);
                worst = worst.max(got.iter().map(|g| (g - want).abs() / want).fold(0.0, f32::max));
            }
        }
        eprintln!("{} lights: largest relative difference from the closed form {worst:.2e}", 2 + third as u32);
        assert!(worst <= 1e-4, "{} lights: a floor pixel is {worst:.2e} off the closed form", 2 + third as u32);
    }
    common::assert_clean_teardown(ctx);
}
