//! The raytrace technique (src/technique/raytrace.rs) is the reference's light transport: its
//! one centre ray per pixel, split deterministically at every dielectric, equals the converged
//! reference (photons off) within the reference's own noise, and conserves energy exactly where
//! the answer is known in closed form; the caustic it gathers from each frame's photons,
//! averaged over frames, is the reference's.
mod common;

use std::sync::Arc;

use glam::Vec3;
use prism::gpu::GpuContext;
use prism::reference::{Reference, ReferenceSettings};
use prism::scene::techniques::RaytraceParams;
use prism::scene::Scene;

const SIZE: u32 = 64;

/// Every frame shown as traced, not the running mean of the frames.
const SINGLE: &str = "render.raytrace.accumulate=1";

/// The reference at `spp` samples per pixel, centre rays (SCENES.md), no photons. Built
/// beside `last`, the previous call's, whose pipelines it reuses (common::render_after), and
/// kept there.
fn reference(ctx: &Arc<GpuContext>, s: &Scene, spp: u32, seed: u32, last: &mut Option<Reference>) -> Vec<f32> {
    let st = ReferenceSettings { spp, photons: 0, seed, ..ReferenceSettings::default() };
    let mut r = Reference::new(ctx, s, &st).expect("reference");
    r.run_all(|_, _| {}).unwrap();
    let image = r.image();
    *last = Some(r);
    image
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
    // The reference without photons: the technique without them too (room_mirror has a light,
    // a mirror and diffuse walls; caustic_through_the_glass_matches_the_reference checks the
    // caustics).
    let off = "render.raytrace.photons_per_frame=0";
    let s = common::scene(name, SIZE, &[&format!("render.{effect}=raytrace"), off]);
    // Kept for the control below, which reuses its pipelines.
    let mut tracer = None;
    let traced = common::render_after(ctx, &s, &mut tracer).hdr;
    let single = common::render_on(ctx, &common::scene(name, SIZE, &[&format!("render.{effect}=single")])).hdr;
    let pixels = written(&traced, &single);
    assert!(pixels.len() > 300, "{name}: only {} pixels traced", pixels.len());
    let mut last = None;
    let a = reference(ctx, &s, spp, 1, &mut last);
    let b = reference(ctx, &s, spp, 2, &mut last);
    drop(last);
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

    let control = common::scene(name, SIZE, &[&format!("render.{effect}=raytrace"), off, broken]);
    let (control, _) = stats(&common::render_after(ctx, &control, &mut tracer).hdr, &a, &pixels);
    drop(tracer);
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
fn equals_the_converged_reference_on_bubble_env() {
    if !common::in_own_process() {
        return;
    }
    // An air bubble in water (ior 0.75, total internal reflection towards its rim); max_depth 1:
    // no light leaves the bubble.
    matches_reference(&common::context(false), "bubble_env", "refraction", 0.75, 256, "render.raytrace.max_depth=1");
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

/// `render.volume = "raytrace"` renders a `[volume]` scene's whole frame (eikonal_sphere: the
/// graded-index ball over its floor) as the reference does, in place of eikonal rendering.
///
/// Threshold: at the volume's boundary the tracer makes the reference's own stochastic Fresnel
/// choice (glsl/reference/volume.glsl, one choice per pixel, fixed over frames), and on this
/// scene (no specular surface, a black environment) its paths are the reference's camera
/// paths; so its image is distributed as a 1-spp reference's. Against reference A (16 spp),
/// its squared differences and those of a 1-spp reference C of another seed are then samples
/// of the same mean: with m and s the mean and standard deviation of C's n squared
/// differences, raytrace's mean square difference lies within m + 4 s sqrt(2 / n) (a 4-sigma
/// bound on the difference of two means of n). The mean signed difference lies within 4
/// standard errors of zero. A control, the ball at another index, must fail the bound.
#[test]
fn renders_a_volume_scene_as_the_reference_does() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let size = 32;
    let off = "render.raytrace.photons_per_frame=0";
    let s = common::scene("eikonal_sphere", size, &["render.volume=raytrace", off]);
    let recipe = prism::technique::recipe(&s);
    let p = recipe.passes.iter().find(|p| p.name == "volume_raytrace").expect("volume_raytrace planned");
    assert!(p.reason.contains("volume ball") && p.reason.contains("render.volume"), "{}", p.reason);
    assert!(!prism::technique::has(&recipe.passes, "eikonal_view"), "eikonal rendering planned beside raytrace");
    let traced = common::render_on(&ctx, &s).hdr;
    common::assert_finite("volume_raytrace", &traced);
    let all: Vec<usize> = (0..traced.len() / 4).collect();
    let mut last = None;
    let a = reference(&ctx, &s, 16, 1, &mut last);
    let c = reference(&ctx, &s, 1, 3, &mut last);
    drop(last);
    let sq: Vec<f64> =
        all.iter().flat_map(|&p| (0..3).map(move |k| 4 * p + k)).map(|i| ((c[i] - a[i]) as f64).powi(2)).collect();
    let n = sq.len() as f64;
    let m = sq.iter().sum::<f64>() / n;
    let sd = (sq.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let bound = m + 4.0 * sd * (2.0 / n).sqrt();
    let (error, bias) = stats(&traced, &a, &all);
    let mse = error * error;
    let bias_limit = 4.0 * m.sqrt() / n.sqrt();
    eprintln!(
        "eikonal_sphere, whole frame traced: mean square difference against 16 spp {mse:.6} (1-spp reference: \
         {m:.6}, bound {bound:.6}); mean difference {bias:.6} (limit {bias_limit:.6})"
    );
    assert!(
        mse <= bound,
        "mean square difference {mse} against the reference exceeds a 1-spp reference's bound {bound}"
    );
    assert!(bias.abs() <= bias_limit, "mean difference {bias}");
    let control = common::scene("eikonal_sphere", size, &["render.volume=raytrace", off, "volume.index.n=1.2"]);
    let (control, _) = stats(&common::render_on(&ctx, &control).hdr, &a, &all);
    eprintln!("control volume.index.n=1.2: mean square difference {:.6}", control * control);
    // It must fail the same bound (measured: 1.9 times it at 32^2).
    assert!(control * control > bound, "the comparison cannot tell another index ({control}) from the scene's");
    common::assert_no_validation_errors(&ctx);
}

/// The mean and, per value, the variance of that mean over `frames` frames of one renderer:
/// each frame traces new photons (the photon kernel's iteration is the frame's), and
/// everything else in a frame is a function of the scene, so the frames are independent
/// samples of the caustic. The scene shows single frames (`render.raytrace.accumulate = 1`,
/// [`SINGLE`]), not their running mean.
fn frame_statistics(ctx: &Arc<GpuContext>, s: &Scene, frames: u32) -> (Vec<f64>, Vec<f64>) {
    assert_eq!(RaytraceParams::from_settings(&s.render).unwrap().accumulate, 1, "{}: frames accumulated", s.name);
    let mut r = prism::renderer::Renderer::new(ctx, s).expect("renderer");
    let (mut sum, mut sum2) = (Vec::new(), Vec::new());
    for _ in 0..frames {
        r.render_frame().expect("frame");
        let hdr = r.read_hdr().expect("hdr");
        common::assert_finite(&s.name, &hdr);
        sum.resize(hdr.len(), 0.0f64);
        sum2.resize(hdr.len(), 0.0f64);
        for (k, &v) in hdr.iter().enumerate() {
            sum[k] += v as f64;
            sum2[k] += v as f64 * v as f64;
        }
    }
    drop(r);
    common::assert_no_validation_errors(ctx);
    let n = frames as f64;
    let mean: Vec<f64> = sum.iter().map(|s| s / n).collect();
    // The unbiased sample variance of one frame, over n: the variance of the mean.
    let var = sum2.iter().zip(&mean).map(|(s2, m)| ((s2 / n - m * m) * n / (n - 1.0)).max(0.0) / n).collect();
    (mean, var)
}

/// The reference's caustic alone (its photon-mapped part) with the raytrace technique's
/// gathering disk: every visible point starts at the largest radius (`footprint` 0, 1% of the
/// scene's radius) and keeps it (alpha close to 1), at the centre ray of its pixel.
/// Built beside `last`, whose pipelines it reuses, and kept there (as `reference`).
fn reference_caustic(
    ctx: &Arc<GpuContext>,
    s: &Scene,
    spp: u32,
    photons: u64,
    seed: u32,
    last: &mut Option<Reference>,
) -> (Vec<f32>, f32) {
    let st = ReferenceSettings { spp, photons, seed, footprint: 0.0, alpha: 0.999, ..ReferenceSettings::default() };
    let mut r = Reference::new(ctx, s, &st).expect("reference");
    r.run_all(|_, _| {}).unwrap();
    assert!(r.stats().exact(), "{:?}", r.stats());
    // How far the radii shrank: the smallest final radius over the initial one.
    let initial = 0.01 * scene_radius(s);
    let shrink = (0..(s.camera.width * s.camera.height) as usize)
        .map(|k| r.pixel_state(k))
        .filter(|p| p[2][3] > 0.5)
        .map(|p| p[1][3] / initial)
        .fold(1.0f32, f32::min);
    let image = r.caustic_image();
    *last = Some(r);
    (image, shrink)
}

/// The GPU scene's bounding radius (src/frame/gpu_scene.rs): every vertex and the camera.
fn scene_radius(s: &Scene) -> f32 {
    let (mut lo, mut hi) = (s.camera.position, s.camera.position);
    for p in s.objects.iter().flat_map(|o| &o.mesh.positions) {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    (hi - lo).length() * 0.5
}

/// caustic_sphere's caustic seen through the glass ball from above (the camera over the ball,
/// looking down through it at the focused ring on the floor): the technique's, averaged over
/// frames, against the reference's converged one, at the same gathering disk. With
/// `gather_radius` 16 footprints every disk is at its cap, 1% of the scene's radius (a
/// footprint through the ball is at least 1.8 m, the way to the ball's top, times the pixel's
/// 0.018 rad: 16 of them, 0.52 m, exceed the cap, 0.06 m), and
/// the reference is given the same fixed radius at its pixels' centre rays (reference_caustic),
/// so both estimate the same disk average of the irradiance: the reference choosing one
/// Fresnel branch at random, the technique summing them. No blur bias between them but the
/// reference's radius reduction, which alpha = 0.999 keeps below the printed `shrink` (the
/// disk's area falls by shrink^2 at most; the flux it collects with it).
///
/// Threshold, from the noise of both: the technique's per-pixel variance of its mean over the
/// frames, and the reference's from two seeds ((A - B)^2 / 2 per pixel estimates one run's).
/// The mean over the pixels of the squared difference then has the expected value
/// mean(var_rt) + mean(var_ref); with hundreds of pixels its own relative spread is a few
/// per cent, so 1.5 times that plus the bias of the shrink (at most (1 - shrink^2) of the
/// caustic, squared) fails for any systematic error above about 0.7 of the noise. The mean
/// signed difference must lie within 4 standard errors of zero plus that bias. The control:
/// the technique with no photons has all of the caustic as its error.
#[test]
fn caustic_through_the_glass_matches_the_reference() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let set = [
        "render.refraction=raytrace",
        "render.caustics=none",
        "render.raytrace.gather_radius=16",
        SINGLE,
        "camera.position=[0, 4, 0.3]",
        "camera.target=[0, 0, 0]",
        "camera.up=[0, 0, -1]",
        "camera.vfov_deg=60",
    ];
    let s = common::scene("caustic_sphere", SIZE, &set);
    let frames = 16;
    let (lit, var_rt) = frame_statistics(&ctx, &s, frames);
    let dark = common::render_on(
        &ctx,
        &common::scene("caustic_sphere", SIZE, &[&set[..], &["render.raytrace.photons_per_frame=0"]].concat()),
    )
    .hdr;
    let single = common::render_on(
        &ctx,
        &common::scene("caustic_sphere", SIZE, &["render.refraction=single", "render.caustics=none"]),
    )
    .hdr;
    let pixels = written(&dark, &single);
    assert!(pixels.len() > 300, "only {} pixels traced", pixels.len());
    let photons = 1u64 << 21;
    let mut last = None;
    let (a, shrink) = reference_caustic(&ctx, &s, 32, photons, 1, &mut last);
    let (b, _) = reference_caustic(&ctx, &s, 32, photons, 2, &mut last);
    drop(last);
    let (mut sq, mut sum, mut noise, mut control, mut caustic, mut lit_pixels) =
        (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64, 0);
    for &p in &pixels {
        for c in 0..3 {
            let k = 4 * p + c;
            let rt = lit[k] - dark[k] as f64;
            let reference = 0.5 * (a[k] as f64 + b[k] as f64);
            let d = rt - reference;
            sq += d * d;
            sum += d;
            // Var of the mean of A and B: (A - B)^2 / 2 / 2.
            let ab = a[k] as f64 - b[k] as f64;
            noise += var_rt[k] + ab * ab / 4.0;
            control += reference * reference;
            caustic += reference;
        }
        if a[4 * p] > 0.0 {
            lit_pixels += 1;
        }
    }
    let n = (3 * pixels.len()) as f64;
    let (msd, mean, noise, control, caustic) = (sq / n, sum / n, noise / n, control / n, caustic / n);
    let bias = (1.0 - (shrink as f64).powi(2)) * caustic;
    let limit = 1.5 * noise + bias * bias;
    let mean_limit = 4.0 * (noise / n).sqrt() + bias;
    eprintln!(
        "caustic through the glass ({} pixels, {lit_pixels} with caustic; {frames} frames, reference 2 x 32 spp, {photons} photons): \
         mean square difference {msd:.3e}, noise {noise:.3e}, limit {limit:.3e}; mean difference {mean:.3e} (limit {mean_limit:.3e}), \
         mean caustic {caustic:.4}, shrink {shrink:.5}; control (no photons) {control:.3e}",
        pixels.len()
    );
    assert!(lit_pixels > 50, "only {lit_pixels} pixels see the caustic through the glass");
    assert!(msd <= limit, "mean square difference {msd} beyond the noise {noise} (limit {limit})");
    assert!(mean.abs() <= mean_limit, "mean difference {mean}, limit {mean_limit}");
    assert!(control > 4.0 * limit, "the comparison cannot tell a missing caustic ({control}) from noise ({limit})");
    common::assert_no_validation_errors(&ctx);
}

/// Without photons (`photons_per_frame` = 0) the technique plans no photon pass and its image
/// is the one without caustics: the same in every frame (nothing random changes between
/// frames but the photons), and with photons the caustic only adds light, on some pixels. That
/// it is exactly the tracer without caustics is equals_the_reference_on_room_mirror's check:
/// there, without photons, the technique and the photon-less reference agree to the bit.
#[test]
fn no_photons_is_the_image_without_caustics() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let base = ["render.refraction=raytrace", "render.caustics=none"];
    let off = common::scene("caustic_sphere", SIZE, &[&base[..], &["render.raytrace.photons_per_frame=0"]].concat());
    let recipe = prism::technique::recipe(&off);
    assert!(!prism::technique::has(&recipe.passes, "refraction_raytrace_photons"));
    let on = common::scene("caustic_sphere", SIZE, &base);
    let recipe = prism::technique::recipe(&on);
    assert!(prism::technique::has(&recipe.passes, "refraction_raytrace_photon_reset"));
    assert!(prism::technique::has(&recipe.passes, "refraction_raytrace_photons"));
    let frames = common::render_each(&ctx, &[off.clone(), off.clone()]);
    assert_eq!(frames[0].hdr, frames[1].hdr, "without photons the image changes from frame to frame");
    let lit = common::render_on(&ctx, &on).hdr;
    let dark = &frames[0].hdr;
    let (mut brighter, mut darker) = (0, 0);
    for p in 0..dark.len() / 4 {
        for c in 0..3 {
            let (d, l) = (dark[4 * p + c], lit[4 * p + c]);
            if l > d {
                brighter += 1;
            }
            if l < d {
                darker += 1;
            }
        }
    }
    eprintln!("photons on against off: {brighter} values brighter, {darker} darker");
    // The caustic only adds light.
    assert_eq!(darker, 0, "the photons darkened {darker} values");
    assert!(brighter > 100, "the photons brightened only {brighter} values");
    common::assert_no_validation_errors(&ctx);
}

/// `render.caustics = "raytrace"` conserves the photons' flux: over the floor pixels seen
/// directly, the caustic it adds, integrated over their footprints, equals the reflected flux
/// (albedo / pi times the flux, W/sr) of the photons landing in those footprints. The photons
/// are the technique's own: frame k traces the photons of the reference's photon pass k with
/// the technique's seed and as many photons a pass (PHOTON_SEED), read back from the
/// reference. caustic_sphere's light is moved aside so that the caustic falls beside the ball,
/// in view.
///
/// Tolerance, as tests/reference.rs's flux checks: a photon at x counts in the sum over
/// pixels with weight w(x) = sum over the disks holding x of A_px / (pi r^2), whose mean over
/// a pixel is 1 (the disk's share of the footprint times its weight) and whose variance is at
/// most 4 / pi - 1 (the disk inscribed in a square footprint, a disk grows with the pixel's
/// obliquity faster than its footprint: A_px / (pi r^2) = 4 cos^3(theta) / pi, theta the angle
/// off the camera's axis). So 3 standard deviations of the sum are 3 sqrt((4/pi - 1) sum f^2)
/// / sum f of it, over the frames; plus the share of the photons' flux within a disk's reach of
/// the selection's border (0.5 footprints over sqrt(cos), on either side: there a disk counts
/// photons the selection leaves out or misses ones it counts). The control: the technique
/// with its gather disabled (no caustic) misses all of it.
#[test]
fn direct_caustic_conserves_the_photons_flux() {
    if !common::in_own_process() {
        return;
    }
    use prism::PHOTON_DEPOSITED;
    let ctx = common::context(false);
    let (frames, per_frame) = (8u32, 8000u32);
    let photons = format!("render.raytrace.photons_per_frame={per_frame}");
    let base =
        ["render.refraction=single", "render.caustics=raytrace", "lights.0.position=[4, 5, 0]", &photons, SINGLE];
    let s = common::scene("caustic_sphere", SIZE, &base);
    assert!(prism::technique::has(&prism::technique::recipe(&s).passes, "caustics_raytrace"));
    let (lit, _) = frame_statistics(&ctx, &s, frames);
    let dark = common::render_on(
        &ctx,
        &common::scene("caustic_sphere", SIZE, &[&base[..], &["render.caustics=none"]].concat()),
    )
    .hdr;

    let st = ReferenceSettings {
        spp: frames,
        photons: (per_frame * frames) as u64,
        seed: prism::technique::raytrace::PHOTON_SEED,
        ..ReferenceSettings::default()
    };
    let mut r = Reference::new(&ctx, &s, &st).expect("reference");
    assert_eq!(r.photons_per_pass(), per_frame);
    let mut deposited = Vec::new();
    for _ in 0..frames {
        r.run(1).unwrap();
        for (o, p) in r.photon_outcomes().iter().zip(r.photon_positions()) {
            if o[3] as u32 == PHOTON_DEPOSITED {
                deposited.push((p, o[0] as f64));
            }
        }
    }
    drop(r);

    // The floor pixels seen directly: the centre and the four corner rays reach the floor
    // (y = 0, |x|, |z| < 4) past the ball (centre (0, 1.2, 0), radius 1).
    let cam = s.camera.position;
    let (ball, radius, albedo) = (Vec3::new(0.0, 1.2, 0.0), 1.0f32, 0.8f64);
    let on_floor = |x: f32, y: f32| {
        let (_, d) = s.camera.ray_through(x, y);
        let t = -cam.y / d.y;
        let p = cam + t * d;
        let oc = cam - ball;
        let b = oc.dot(d);
        let hits_ball = b * b - (oc.length_squared() - radius * radius) > 0.0 && -b > 0.0;
        (t > 0.0 && p.x.abs() < 4.0 && p.z.abs() < 4.0 && !hits_ball).then_some(p)
    };
    let n = SIZE as usize;
    let footprint: Vec<Option<f64>> = (0..n * n)
        .map(|k| {
            let (i, j) = ((k % n) as f32, (k / n) as f32);
            on_floor(i + 0.5, j + 0.5)?;
            let q = [on_floor(i, j)?, on_floor(i + 1.0, j)?, on_floor(i + 1.0, j + 1.0)?, on_floor(i, j + 1.0)?];
            Some(
                0.5 * (0..4).map(|m| (q[m].x * q[(m + 1) % 4].z - q[(m + 1) % 4].x * q[m].z) as f64).sum::<f64>().abs(),
            )
        })
        .collect();
    let selected = |i: i64, j: i64| {
        (0..n as i64).contains(&i) && (0..n as i64).contains(&j) && footprint[j as usize * n + i as usize].is_some()
    };

    // Which pixel each photon lands in, and whether a disk can carry it across the border.
    let (mut sum, mut sum2, mut border, mut count) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    for &(p, f) in &deposited {
        if p.y.abs() > 1e-4 {
            continue;
        }
        let e = f * albedo / std::f64::consts::PI;
        let q = p - cam;
        let forward = (s.camera.target - cam).normalize();
        let right = forward.cross(s.camera.up).normalize();
        let up = right.cross(forward);
        let tan_y = (s.camera.vfov_deg.to_radians() * 0.5).tan();
        let z = q.dot(forward);
        let x = (q.dot(right) / z / (tan_y * s.camera.aspect()) + 1.0) * 0.5 * SIZE as f32;
        let y = (1.0 - q.dot(up) / z / tan_y) * 0.5 * SIZE as f32;
        let (i, j) = (x.floor() as i64, y.floor() as i64);
        let cos = (cam - p).normalize().y.abs().max(0.05);
        let reach = RaytraceParams::default().gather_radius / cos.sqrt();
        let me = selected(i, j);
        if common::disk_crosses_border(selected, x, y, reach) {
            border += e;
        }
        if me {
            sum += e;
            sum2 += e * e;
            count += 1;
        }
    }
    let integral: f64 =
        footprint.iter().enumerate().filter_map(|(k, a)| Some((lit[4 * k] - dark[4 * k] as f64) * a.as_ref()?)).sum();
    let flux = sum / frames as f64;
    let sigma = ((4.0 / std::f64::consts::PI - 1.0) * sum2).sqrt() / sum;
    let tolerance = 3.0 * sigma + border / sum;
    eprintln!(
        "direct caustic: photons' reflected flux {flux:.5} W/sr ({count} photons over {frames} frames), integrated \
         radiance {integral:.5} (ratio {:.4}), sigma {sigma:.4}, border {:.4}, tolerance {tolerance:.4}, {} pixels",
        integral / flux,
        border / sum,
        footprint.iter().flatten().count()
    );
    assert!(count >= 1000, "only {count} photons land on the floor seen directly");
    assert!((integral - flux).abs() / flux < tolerance, "integrated caustic {integral}, photons' flux {flux}");
    common::assert_no_validation_errors(&ctx);
}

/// The frame's `raytrace` techniques share one photon map: with `caustics = "raytrace"` too,
/// only the caustics technique traces photons (one photon pass planned), and the refraction
/// technique gathers exactly the photons it traced alone (frame k's photons are the same
/// whoever traces them: the kernel's seed and iteration), so every pixel it writes is the
/// same, bit for bit, caustic included; the other pixels only gain the caustic seen directly.
/// The camera looks down through the ball at its focused ring, so that the refracted pixels
/// hold a caustic.
#[test]
fn one_photon_map_serves_every_raytrace_technique() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let view = ["camera.position=[0, 4, 0.3]", "camera.target=[0, 0, 0]", "camera.up=[0, 0, -1]", "camera.vfov_deg=60"];
    let with = |set: &[&str]| common::scene("caustic_sphere", SIZE, &[&view[..], set].concat());
    let alone = with(&["render.refraction=raytrace", "render.caustics=none"]);
    let shared = with(&["render.refraction=raytrace", "render.caustics=raytrace"]);
    let plan = prism::technique::recipe(&shared).passes;
    let photon_passes: Vec<_> = plan.iter().filter(|p| p.name.ends_with("_photons")).map(|p| p.name).collect();
    assert_eq!(photon_passes, ["caustics_raytrace_photons"]);
    let [alone, shared, single] = [alone, shared, with(&["render.refraction=single", "render.caustics=none"])]
        .map(|s| common::render_on(&ctx, &s).hdr);
    let refracted = written(&alone, &single);
    let (no_photons, _) = stats(
        &alone,
        &common::render_on(
            &ctx,
            &with(&["render.refraction=raytrace", "render.caustics=none", "render.raytrace.photons_per_frame=0"]),
        )
        .hdr,
        &refracted,
    );
    let same = refracted.iter().filter(|&&p| alone[4 * p..4 * p + 3] == shared[4 * p..4 * p + 3]).count();
    let (mut brighter, mut darker) = (0, 0);
    for p in 0..alone.len() / 4 {
        for c in 0..3 {
            brighter += usize::from(shared[4 * p + c] > alone[4 * p + c]);
            darker += usize::from(shared[4 * p + c] < alone[4 * p + c]);
        }
    }
    eprintln!(
        "shared photons: {same} of {} refracted pixels identical (their caustic: RMSE {no_photons:.4} against none); \
         {brighter} values brighter, {darker} darker",
        refracted.len()
    );
    assert!(refracted.len() > 300 && no_photons > 0.1, "the refracted pixels show no caustic");
    assert_eq!(same, refracted.len(), "the refraction technique gathered other photons");
    assert!(darker == 0 && brighter > 100, "{brighter} values brighter, {darker} darker");
    common::assert_no_validation_errors(&ctx);
}

/// caustic_sphere's caustic seen directly, traced from `photons` photons a frame, showing up
/// to `accumulate` frames' running mean.
fn accumulating(size: u32, accumulate: u32, extra: &[&str]) -> Scene {
    let acc = format!("render.raytrace.accumulate={accumulate}");
    let base = ["render.refraction=raytrace", "render.caustics=raytrace", "render.raytrace.photons_per_frame=4000"];
    common::scene("caustic_sphere", size, &[&base[..], extra, &[acc.as_str()]].concat())
}

/// The values where `a` and `b` differ.
fn differing(a: &[f32], b: &[f32]) -> usize {
    a.iter().zip(b).filter(|(x, y)| x != y).count()
}

/// `render.raytrace.accumulate = N` shows the running mean of the frames since the last
/// change: frame k (from 0) shows the mean of frames 0..=k, up to N frames, then holds the mean
/// of the first N. The single frames come from a second renderer with `accumulate = 1`: the
/// two trace the same photons frame by frame (the photon kernel's iteration is the frame's
/// since the renderer began), so its frame k is what the first blended in.
///
/// Threshold, a rounding bound: one step m + (x - m) / (n + 1) in f32 rounds a difference and
/// a sum (correctly rounded, 2^-24 of the result each) and a quotient (Vulkan allows 2.5 ulp,
/// 5 2^-24 of the result); with P the largest |value| of that channel over the frames, the
/// difference is at most 2P and enters divided by n + 1, the quotient and the sum at most P:
/// at most 7 2^-24 P a step, and the earlier steps' errors shrink by n / (n + 1). After n
/// frames the mean is within 7 n 2^-24 P of the exact mean; the test allows 8 n 2^-24 P. A
/// value equal in every frame (all but the caustic) stays exactly itself.
#[test]
fn accumulation_is_the_mean_of_the_single_frames() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let (limit, frames) = (6u32, 8u32);
    let (single_scene, mean_scene) = (accumulating(SIZE, 1, &[]), accumulating(SIZE, limit, &[]));
    let planned = |s: &Scene| prism::technique::has(&prism::technique::recipe(s).passes, "raytrace_accumulate");
    assert!(planned(&mean_scene) && !planned(&single_scene));
    let mut single = prism::renderer::Renderer::new(&ctx, &single_scene).expect("renderer");
    let mut mean = prism::renderer::Renderer::new(&ctx, &mean_scene).expect("renderer");
    let (mut sum, mut peak, mut first) = (Vec::new(), Vec::new(), Vec::new());
    let mut held: Option<Vec<f32>> = None;
    for k in 0..frames {
        single.render_frame().expect("frame");
        mean.render_frame().expect("frame");
        let (x, m) = (single.read_hdr().expect("hdr"), mean.read_hdr().expect("hdr"));
        let n = (k + 1).min(limit);
        assert_eq!((single.accumulated_frames(), mean.accumulated_frames()), (None, Some(n)), "frame {k}");
        if k == 0 {
            assert_eq!(m, x, "the first frame's mean is not the frame");
            (sum, peak, first) = (vec![0f64; x.len()], vec![0f32; x.len()], x.clone());
        }
        if k >= limit {
            let d = differing(&m, held.as_ref().unwrap());
            eprintln!("frame {k}: {d} values differ from the mean of {limit} frames held");
            assert_eq!(d, 0, "frame {k}: the mean of {limit} frames is not held");
            continue;
        }
        for (i, &v) in x.iter().enumerate() {
            sum[i] += v as f64;
            peak[i] = peak[i].max(v.abs());
        }
        let (mut worst, mut over) = (0f64, 0usize);
        for i in 0..m.len() {
            let error = (m[i] as f64 - sum[i] / n as f64).abs();
            let bound = 8.0 * n as f64 * 2f64.powi(-24) * peak[i] as f64;
            if error > bound {
                over += 1;
            }
            if error > 0.0 {
                worst = worst.max(error / bound);
            }
        }
        let varied = differing(&x, &first);
        eprintln!(
            "frame {k}: mean of {n} frames; {varied} values of this frame differ from frame 0's, {} from the \
             mean shown; the mean's largest error {worst:.3} of its rounding bound, {over} values over it",
            differing(&x, &m)
        );
        assert_eq!(over, 0, "frame {k}: the image shown is not the mean of the {n} single frames");
        if k > 0 {
            assert!(varied > 50, "frame {k}: the photons' caustic does not vary ({varied} values)");
        }
        held = Some(m);
    }
    drop((single, mean));
    common::assert_no_validation_errors(&ctx);
}

/// Any change starts the mean again: the frame after it shows the frame itself, bit for bit
/// the frame of a renderer that does not accumulate (`accumulate = 1`, driven through the same
/// changes, so that both trace the same photons), and the count is 1; the frame after that is
/// a mean of two again. Setting the same camera again is no change. The changes: the camera
/// (`Renderer::set_camera`, as the window moves it every frame), a live update that keeps the
/// techniques (the exposure), one that re-creates them (a light moved), a dragged object
/// (`Renderer::move_object`) and a resize.
#[test]
fn any_change_restarts_the_mean() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let mut single = prism::renderer::Renderer::new(&ctx, &accumulating(SIZE, 1, &[])).expect("renderer");
    let mut mean = prism::renderer::Renderer::new(&ctx, &accumulating(SIZE, 16, &[])).expect("renderer");
    let frame = |single: &mut prism::renderer::Renderer, mean: &mut prism::renderer::Renderer| {
        single.render_frame().expect("frame");
        mean.render_frame().expect("frame");
        let (x, m) = (single.read_hdr().expect("hdr"), mean.read_hdr().expect("hdr"));
        (differing(&x, &m), mean.accumulated_frames())
    };
    for _ in 0..3 {
        frame(&mut single, &mut mean);
    }
    let camera = accumulating(SIZE, 16, &[]).camera;
    single.set_camera(&camera);
    mean.set_camera(&camera);
    let (d, n) = frame(&mut single, &mut mean);
    eprintln!("the same camera set again: {n:?} frames, {d} values differ from the single frame");
    assert!(n == Some(4) && d > 50, "setting the same camera restarted the mean ({n:?} frames, {d} values)");

    // Each change as given to a renderer accumulating `a` frames.
    type Change = Box<dyn Fn(&mut prism::renderer::Renderer, u32)>;
    let moved = prism::scene::Camera { position: camera.position + Vec3::new(0.4, 0.2, 0.0), ..camera };
    let changes: [(&str, Change); 5] = [
        ("camera moved", Box::new(move |r, _| r.set_camera(&moved))),
        (
            "exposure (techniques kept)",
            Box::new(|r, a| {
                let u = r.update(&accumulating(SIZE, a, &["render.exposure=1.5"])).expect("update");
                assert!(!u.rebuilt && u.recreated.is_empty(), "{u:?}");
            }),
        ),
        (
            "light moved (techniques re-created)",
            Box::new(|r, a| {
                let u = r.update(&accumulating(SIZE, a, &["lights.0.position=[0.5, 6, 0]"])).expect("update");
                assert!(!u.recreated.is_empty(), "{u:?}");
            }),
        ),
        ("object dragged", Box::new(|r, _| assert!(r.move_object("ball", Vec3::new(0.3, 1.2, 0.0)).expect("move")))),
        (
            "resize",
            Box::new(|r, a| {
                r.update(&accumulating(48, a, &["lights.0.position=[0.5, 6, 0]"])).expect("update");
            }),
        ),
    ];
    for (what, change) in changes {
        // The running mean is of several frames before the change.
        frame(&mut single, &mut mean);
        let (_, before) = frame(&mut single, &mut mean);
        change(&mut single, 1);
        change(&mut mean, 16);
        let (d, n) = frame(&mut single, &mut mean);
        let (d2, n2) = frame(&mut single, &mut mean);
        eprintln!(
            "{what}: {before:?} frames before; after it {n:?} frames, {d} values differ from the single frame; \
             then {n2:?} frames, {d2} values differ"
        );
        assert!(before.unwrap() >= 2, "{what}: no mean before the change");
        assert_eq!((n, d), (Some(1), 0), "{what}: the frame after the change is not the frame itself");
        assert!(n2 == Some(2) && d2 > 50, "{what}: the mean does not go on after the change");
    }
    drop((single, mean));
    common::assert_no_validation_errors(&ctx);
}

/// `accumulate = 1` is the technique without accumulation: no `raytrace_accumulate` pass, no
/// count, and every frame is shown as traced, its own photons' caustic, so that consecutive
/// frames differ where the caustic is (a mean would hold them ever closer). With accumulation
/// on, the pass is planned after the frame's last raytrace pass, where the mean of everything
/// they wrote is taken, and only where photons make the frames differ.
#[test]
fn accumulate_one_shows_every_frame_as_traced() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let s = accumulating(SIZE, 1, &[]);
    let names: Vec<_> = prism::technique::recipe(&s).passes.iter().map(|p| p.name).collect();
    assert!(!names.contains(&"raytrace_accumulate"), "{names:?}");
    let with = prism::technique::recipe(&accumulating(SIZE, 2, &[])).passes;
    let with: Vec<_> = with.iter().map(|p| p.name).collect();
    let at = with.iter().position(|&p| p == "raytrace_accumulate").expect("no raytrace_accumulate planned");
    assert_eq!(with[at - 1], "refraction_raytrace", "{with:?}");
    // Without photons every frame is the same image: nothing to average.
    let dark = accumulating(SIZE, 2, &["render.raytrace.photons_per_frame=0"]);
    assert!(!prism::technique::has(&prism::technique::recipe(&dark).passes, "raytrace_accumulate"));
    let mut r = prism::renderer::Renderer::new(&ctx, &s).expect("renderer");
    let mut last: Option<Vec<f32>> = None;
    for k in 0..4 {
        r.render_frame().expect("frame");
        let x = r.read_hdr().expect("hdr");
        assert_eq!(r.accumulated_frames(), None);
        if let Some(l) = &last {
            let d = differing(&x, l);
            eprintln!("accumulate = 1, frame {k}: {d} values differ from frame {}", k - 1);
            assert!(d > 50, "frame {k} is not a frame of its own ({d} values differ)");
        }
        last = Some(x);
    }
    drop(r);
    common::assert_no_validation_errors(&ctx);
}
