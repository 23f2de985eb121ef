//! The raytrace technique (src/technique/raytrace.rs) is the reference's light transport
//! without caustics: its one centre ray per pixel, split deterministically at every
//! dielectric, equals the converged reference (photons off) within the reference's own noise,
//! and conserves energy exactly where the answer is known in closed form.
mod common;

use std::sync::Arc;

use glam::Vec3;
use prism::gpu::GpuContext;
use prism::reference::{Reference, ReferenceSettings};
use prism::scene::techniques::RaytraceParams;
use prism::scene::Scene;

const SIZE: u32 = 64;

/// The reference at `spp` samples per pixel, centre rays (SCENES.md), no photons.
fn reference(ctx: &Arc<GpuContext>, s: &Scene, spp: u32, seed: u32) -> Vec<f32> {
    let st = ReferenceSettings { spp, photons: 0, seed, ..ReferenceSettings::default() };
    let mut r = Reference::new(ctx, s, &st).expect("reference");
    r.run_all(|_, _| {}).unwrap();
    r.image()
}

/// The pixels a technique wrote: where its image differs from `render.<effect> = "single"`.
/// Both composite exactly the G-buffer's pixels of their objects over the same deferred image,
/// and no pixel of a glass or mirror ball comes out bit-identical from both.
fn written(a: &[f32], b: &[f32]) -> Vec<usize> {
    (0..a.len() / 4).filter(|&p| a[4 * p..4 * p + 3] != b[4 * p..4 * p + 3]).collect()
}

/// (RMSE, mean signed difference) of a against b over the RGB of `pixels`.
fn stats(a: &[f32], b: &[f32], pixels: &[usize]) -> (f64, f64) {
    let (mut sq, mut sum) = (0.0f64, 0.0f64);
    for &p in pixels {
        for c in 0..3 {
            let d = (a[4 * p + c] - b[4 * p + c]) as f64;
            sq += d * d;
            sum += d;
        }
    }
    let n = (3 * pixels.len()).max(1) as f64;
    ((sq / n).sqrt(), sum / n)
}

/// Render `name` with `effect` traced and with the single-interface baseline; compare the
/// traced pixels with two independent reference runs of `spp` samples.
///
/// Threshold: the reference's noise. Two runs A and B with different seeds differ by
/// RMSE(A, B) = sqrt(2) sigma, sigma the RMSE of one run against its converged value; a
/// technique that computes the converged value differs from A by sigma = RMSE(A, B) / sqrt(2)
/// up to sampling, so RMSE(raytrace, A) <= RMSE(A, B) leaves a sqrt(2) margin and no room for
/// a bias as large as the noise. The mean signed difference must lie within 4 standard errors
/// (sigma / sqrt(samples)) of zero, less on the dark side what the cutoff may drop (at most
/// cutoff n^2 of each pixel's radiance, the test below): no other systematic darkening or
/// brightening. Where the reference has no noise at all (a mirror seen against diffuse walls
/// lit by a point light and a black environment: no random choice on its paths), the floor
/// of 1e-4 covers the rounding between the two camera-ray computations (the frame's camera
/// and the reference's). A control, `broken`, must fail by far.
fn matches_reference(ctx: &Arc<GpuContext>, name: &str, effect: &str, ior: f64, spp: u32, broken: &str) {
    let s = common::scene(name, SIZE, &[&format!("render.{effect}=raytrace")]);
    let traced = common::render_on(ctx, &s).hdr;
    let single = common::render_on(ctx, &common::scene(name, SIZE, &[&format!("render.{effect}=single")])).hdr;
    let pixels = written(&traced, &single);
    assert!(pixels.len() > 300, "{name}: only {} pixels traced", pixels.len());
    let a = reference(ctx, &s, spp, 1);
    let b = reference(ctx, &s, spp, 2);
    let (noise, _) = stats(&a, &b, &pixels);
    let (error, bias) = stats(&traced, &a, &pixels);
    let threshold = noise.max(1e-4);
    let sigma = threshold / 2f64.sqrt();
    let bias_limit = 4.0 * sigma / ((3 * pixels.len()) as f64).sqrt();
    let (mean, _) = stats(&a, &vec![0.0; a.len()], &pixels);
    let cutoff_loss = RaytraceParams::default().cutoff as f64 * ior * ior * mean;
    eprintln!(
        "{name} ({effect}, {} pixels, {spp} spp): RMSE raytrace-ref {error:.5}, ref-ref {noise:.5}; \
         mean difference {bias:.6} (limits -{bias_limit:.6} - {cutoff_loss:.6}, {bias_limit:.6})",
        pixels.len()
    );
    assert!(error <= threshold, "{name}: RMSE {error} against the reference exceeds its noise {threshold}");
    assert!(bias <= bias_limit && bias >= -bias_limit - cutoff_loss, "{name}: mean difference {bias}");

    let control = common::scene(name, SIZE, &[&format!("render.{effect}=raytrace"), broken]);
    let (control, _) = stats(&common::render_on(ctx, &control).hdr, &a, &pixels);
    eprintln!("{name}: control {broken}: RMSE {control:.5}");
    assert!(control > 4.0 * threshold, "{name}: the comparison cannot tell {broken} ({control}) from the defaults");
    common::assert_no_validation_errors(ctx);
}

#[test]
fn equals_the_converged_reference_on_sphere_env() {
    if !common::in_own_process() {
        return;
    }
    // max_depth 1: no light leaves the glass.
    matches_reference(&common::context(false), "sphere_env", "refraction", 1.5, 256, "render.raytrace.max_depth=1");
}

#[test]
fn equals_the_converged_reference_on_bunny_env() {
    if !common::in_own_process() {
        return;
    }
    matches_reference(&common::context(false), "bunny_env", "refraction", 1.2, 256, "render.raytrace.max_depth=1");
}

#[test]
fn equals_the_reference_on_room_mirror() {
    if !common::in_own_process() {
        return;
    }
    // A cutoff above the mirror's reflectance 0.95 drops every reflection.
    matches_reference(&common::context(false), "room_mirror", "reflection", 1.0, 16, "render.raytrace.cutoff=0.96");
}

/// The centre ray of pixel (i, j) of sphere_env's camera ((0, 0, 4) looking down -z, vfov 40,
/// square): its distance from the ball's centre, in units of the radius 1.
fn impact(i: u32, j: u32, size: u32) -> f32 {
    let t = (20f32).to_radians().tan();
    let ndc = |k: u32| (k as f32 + 0.5) / size as f32 * 2.0 - 1.0;
    let d = Vec3::new(ndc(i) * t, -ndc(j) * t, -1.0).normalize();
    Vec3::new(0.0, 0.0, 4.0).cross(d).length()
}

/// Energy conservation of the split, in closed form: a non-absorbing glass ball (ior 1.5) in
/// a constant environment L. Every path that leaves the ball entered it once more than it
/// left, so its (n_i/n_t)^2 factors cancel, and the Fresnel weights of all branches sum to 1:
/// the radiance through the ball is L, less the branches dropped. In a sphere each split
/// leaves one branch outside (it escapes) and one inside, so one branch is dropped per pixel,
/// carrying throughput below the cutoff inside the glass, i.e. at most cutoff * n^2 of L once
/// out. max_depth 64 makes truncation negligible where the centre ray meets the ball at most
/// 0.95 of its radius from the centre (Fresnel at most 0.2 inside: 0.2^63).
#[test]
fn the_split_conserves_energy_through_a_glass_ball() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let l = 0.7f32;
    let n2 = 1.5f32 * 1.5;
    let env = ["environment.type=constant", "environment.radiance=0.7", "render.refraction=raytrace"];
    for (cutoff, some_loss) in [(1e-3f32, false), (0.05, true)] {
        let mut set: Vec<String> = env.iter().map(|s| s.to_string()).collect();
        set.push("render.raytrace.max_depth=64".into());
        set.push(format!("render.raytrace.cutoff={cutoff}"));
        let set: Vec<&str> = set.iter().map(String::as_str).collect();
        let r = common::render_on(&ctx, &common::scene("sphere_env", SIZE, &set));
        let (mut inside, mut worst, mut most) = (0, 0.0f32, f32::MIN);
        for j in 0..SIZE {
            for i in 0..SIZE {
                let v = r.radiance(i, j);
                for c in v {
                    // Never more than L, on or off the ball.
                    assert!(c <= l * (1.0 + 1e-5), "pixel ({i}, {j}): {c} > L = {l}");
                    most = most.max(c);
                }
                if impact(i, j, SIZE) < 0.95 {
                    inside += 1;
                    let loss = 1.0 - v.into_iter().fold(f32::MAX, f32::min) / l;
                    worst = worst.max(loss);
                }
            }
        }
        eprintln!("cutoff {cutoff}: {inside} pixels, largest loss {worst:.6} (bound {:.6})", cutoff * n2);
        assert!(inside > 1000, "{inside} pixels on the ball");
        assert!(worst <= cutoff * n2 + 1e-5, "cutoff {cutoff}: lost {worst} of L, beyond cutoff n^2");
        if some_loss {
            // At normal incidence the branch after one internal reflection carries
            // T R / n^2 = 0.017 < 0.05 inside and is dropped: 3.7% of L.
            assert!(worst > 0.03, "cutoff {cutoff}: no branch was dropped ({worst})");
        }
        assert!(most >= l * (1.0 - 1e-5), "the background is L");
    }
    common::assert_no_validation_errors(&ctx);
}

/// With absorption, the ray through the centre of the ball meets it at normal incidence each
/// time: F0 = ((n - 1) / (n + 1))^2, each chord 2r attenuates by a = exp(-2 r sigma), and
/// the split sums the series of the exits through the back and, after reflections, the
/// front: L (F0 + (1 - F0)^2 a / (1 - F0 a)). 65^2 puts a pixel centre on the axis. Tolerance:
/// every ray inside starts 2e-5 scene radii off the surface (the reference's offset), which
/// shortens the chords by 1e-4 of their length and raises the result by about 3e-5 of L.
#[test]
fn absorption_along_the_axis_is_the_closed_form_series() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let (l, n, sigma) = (0.7f64, 1.5f64, 0.4f64);
    let s = common::scene(
        "sphere_env",
        65,
        &[
            "environment.type=constant",
            "environment.radiance=0.7",
            "render.refraction=raytrace",
            "materials.glass.absorption=0.4",
            "render.raytrace.cutoff=1e-6",
        ],
    );
    let v = common::render_on(&ctx, &s).radiance(32, 32);
    let f0 = ((n - 1.0) / (n + 1.0)).powi(2);
    let a = (-2.0 * sigma).exp();
    let expected = l * (f0 + (1.0 - f0).powi(2) * a / (1.0 - f0 * a));
    eprintln!("axis: {v:?}, closed form {expected:.6}");
    for c in v {
        assert!((c as f64 - expected).abs() < 1e-4 * l, "axis radiance {c}, closed form {expected}");
    }
    common::assert_no_validation_errors(&ctx);
}

#[test]
fn defaults_are_the_reference_s_and_bad_values_are_refused() {
    if !common::in_own_process() {
        return;
    }
    assert_eq!(RaytraceParams::default().max_depth, ReferenceSettings::default().max_depth);
    for bad in ["render.raytrace.max_depth=0", "render.raytrace.max_depth=65", "render.raytrace.cutoff=2"] {
        let e = prism::scene::load(&prism::scene::benchmark_scene_path("sphere_env"), &[bad.to_string()]);
        assert!(e.is_err(), "{bad} was accepted");
    }
}

#[test]
fn its_passes_are_planned_with_their_reasons() {
    if !common::in_own_process() {
        return;
    }
    for (scene, name, what) in [
        ("sphere_env", "refraction_raytrace", "dielectric ball"),
        ("room_mirror", "reflection_raytrace", "mirror/conductor ball"),
    ] {
        let s = common::scene(scene, 16, &["render.refraction=raytrace", "render.reflection=raytrace"]);
        let recipe = prism::technique::recipe(&s);
        let p = recipe.passes.iter().find(|p| p.name == name).unwrap_or_else(|| panic!("{scene}: no {name}"));
        assert!(p.reason.starts_with(what) && p.reason.contains("raytrace"), "{name}: {}", p.reason);
    }
    // Nothing to trace, nothing planned.
    let s = common::scene("sphere_env", 16, &["render.reflection=raytrace"]);
    assert!(!prism::technique::has(&prism::technique::recipe(&s).passes, "reflection_raytrace"));
}
