//! Eikonal rendering (Ihrke et al. 2007; src/technique/eikonal/eikonal_view.rs): the integrators of the ray
//! equation on the CPU (straight rays, the Luneburg focus, fourth-order convergence of RK4),
//! the GPU view renderer on the volume scenes and their edge cases, and the scene checks.
mod common;

use glam::DVec3;
use prism::scene::techniques::Integrator;
use prism::scene::{self, IndexProfile};
use prism::technique::eikonal::volume::{
    euler_step, midpoint_step, rk4_step, sphere_crossing, trace, verlet_tau_step, RayState,
};

const LENS: IndexProfile = IndexProfile::Luneburg { center: glam::Vec3::ZERO, radius: 1.0 };

/// A unit vector orthogonal to `d`.
fn orthogonal(d: DVec3) -> DVec3 {
    let a = if d.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    d.cross(a).normalize()
}

#[test]
fn rays_in_a_homogeneous_volume_are_straight() {
    if !common::in_own_process() {
        return;
    }
    let field = IndexProfile::Constant { n: 1.33, sphere: None };
    let d = DVec3::new(0.3, -0.5, 0.8).normalize();
    for integrator in [Integrator::Euler, Integrator::Midpoint, Integrator::Rk4, Integrator::Verlet] {
        let start = RayState::new(&field, DVec3::new(0.1, 0.2, -0.3), d);
        let path = trace(&field, integrator, start, 0.01, 200, |_| true);
        let end = path.last().unwrap();
        // Arc length 2: the ray moves 2 along d (Appendix: constant spatial step), v unchanged.
        assert!((end.x - (start.x + 2.0 * d)).length() < 1e-12, "{integrator:?}: {:?}", end.x);
        assert!((end.v - start.v).length() < 1e-12);
    }
}

/// Parallel rays entering a Luneburg lens meet its far surface at the point diametrically
/// opposite the entry direction (c + R d), within a voxel of the 64^3 grid of
/// eikonal_luneburg, for impact parameters up to 0.95 R and several directions.
#[test]
fn luneburg_lens_focuses_parallel_rays_on_the_far_surface() {
    if !common::in_own_process() {
        return;
    }
    let voxel = 2.1 / 64.0;
    let h = 0.25 * voxel;
    let mut worst: f64 = 0.0;
    for d in [DVec3::Z, -DVec3::X, DVec3::new(1.0, 2.0, -0.5).normalize()] {
        let (u, w) = (orthogonal(d), d.cross(orthogonal(d)));
        let focus = d; // c + R d with c = 0, R = 1
        for (b, angle) in [(0.05, 0.0), (0.3, 1.0), (0.5, 2.0), (0.7, 3.0), (0.85, 4.0), (0.95, 5.0)] {
            let offset = b * (u * f64::cos(angle) + w * f64::sin(angle));
            // The straight ray outside meets the sphere at offset - sqrt(1 - b^2) d.
            let entry = offset - (1.0 - b * b).sqrt() * d;
            let start = RayState::new(&LENS, entry, d);
            assert!((start.v.length() - 1.0).abs() < 1e-9, "n = 1 on the rim");
            // Step once inside, then march until the ray leaves the lens.
            let path = trace(&LENS, Integrator::Rk4, start, h, 10_000, |x| x.length() < 1.0);
            let (a, z) = (path[path.len() - 2].x, path[path.len() - 1].x);
            assert!(z.length() >= 1.0, "the ray never left the lens");
            let exit = sphere_crossing(a, z, DVec3::ZERO, 1.0);
            let miss = exit.distance(focus);
            worst = worst.max(miss);
            assert!(miss < voxel, "b = {b}, d = {d}: exit {exit} is {miss} from the focus {focus} (voxel {voxel})");
        }
    }
    eprintln!("Luneburg: worst distance to the analytic focus {worst:.2e} (voxel {voxel:.2e})");
    // A homogeneous ball of the same size does not focus there: the test can fail.
    let ball = IndexProfile::Constant { n: 1.5, sphere: Some((glam::Vec3::ZERO, 1.0)) };
    let entry = DVec3::new(0.5, 0.0, -(0.75f64).sqrt());
    let path = trace(&ball, Integrator::Rk4, RayState::new(&ball, entry, DVec3::Z), h, 10_000, |x| x.length() < 1.0);
    let exit = path.last().unwrap().x;
    assert!(exit.distance(DVec3::Z) > voxel, "a ray without bending should miss the focus");
}

/// Error of integrating arc length `s` with `n` steps, against a tiny-step RK4 solution.
fn error(
    step: fn(&IndexProfile, RayState, f64) -> RayState,
    start: RayState,
    s: f64,
    n: usize,
    exact: RayState,
) -> f64 {
    let mut state = start;
    for _ in 0..n {
        state = step(&LENS, state, s / n as f64);
    }
    (state.x - exact.x).length() + (state.v - exact.v).length()
}

/// Halving the step divides a scheme of order p's error by 2^p: 16, 4 and 2. The bounds are
/// that leading-order ratio up to the next term of the error expansion, about 15% at 8 to 64
/// steps (measured: RK4 16.00-16.01, the midpoint rule 3.96-3.99).
#[test]
fn rk4_converges_at_fourth_order_the_midpoint_rule_at_second_and_euler_at_first() {
    if !common::in_own_process() {
        return;
    }
    // A ray inside the lens (n smooth there) over arc length 0.6.
    let start = RayState::new(&LENS, DVec3::new(0.2, -0.1, 0.1), DVec3::new(0.3, 0.8, 0.5).normalize());
    let s = 0.6;
    let mut exact = start;
    let fine = 1 << 14;
    for _ in 0..fine {
        exact = rk4_step(&LENS, exact, s / fine as f64);
    }
    assert!(exact.x.length() < 0.95, "the test ray must stay inside the lens");
    let rk = |n| error(rk4_step, start, s, n, exact);
    let eu = |n| error(euler_step, start, s, n, exact);
    let mid = |n| error(midpoint_step, start, s, n, exact);
    for n in [8, 16, 32] {
        let ratio = rk(n) / rk(2 * n);
        eprintln!("RK4 {n} -> {} steps: error {:.3e} -> {:.3e}, ratio {ratio:.2}", 2 * n, rk(n), rk(2 * n));
        assert!((13.0..19.0).contains(&ratio), "RK4 error ratio {ratio} when halving the step ({n} steps)");
        let ratio = eu(n) / eu(2 * n);
        assert!((1.7..2.3).contains(&ratio), "Euler error ratio {ratio} ({n} steps)");
        let ratio = mid(n) / mid(2 * n);
        eprintln!("midpoint {n} -> {} steps: ratio {ratio:.2}", 2 * n);
        assert!((3.4..4.6).contains(&ratio), "midpoint error ratio {ratio} ({n} steps)");
    }
}

/// Velocity Verlet integrates Eqs. 9-10 in tau (d tau = ds / n) as x'' = n grad n: halving its
/// parameter step divides the error by 4 (second order), within the bounds of the test above.
/// The solution it converges to is the first-order system dx/d tau = v, dv/d tau = n grad n
/// integrated here with tiny classical RK4 steps, independently of it.
#[test]
fn velocity_verlet_converges_at_second_order() {
    if !common::in_own_process() {
        return;
    }
    let start = RayState::new(&LENS, DVec3::new(0.2, -0.1, 0.1), DVec3::new(0.3, 0.8, 0.5).normalize());
    // Parameter length 0.45: about 0.6 of arc length at n between 1.2 and 1.4.
    let t_total = 0.45;
    let rhs = |s: RayState| (s.v, LENS.n(s.x) * LENS.gradient(s.x));
    let mut exact = start;
    let fine = 1 << 14;
    let dt = t_total / fine as f64;
    for _ in 0..fine {
        let at = |k: (DVec3, DVec3), f: f64| RayState { x: exact.x + f * k.0, v: exact.v + f * k.1 };
        let k1 = rhs(exact);
        let k2 = rhs(at(k1, 0.5 * dt));
        let k3 = rhs(at(k2, 0.5 * dt));
        let k4 = rhs(at(k3, dt));
        exact = RayState {
            x: exact.x + dt / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
            v: exact.v + dt / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
        };
    }
    assert!(exact.x.length() < 0.95, "the test ray must stay inside the lens");
    let error = |n: usize| {
        let mut state = start;
        for _ in 0..n {
            state = verlet_tau_step(&LENS, state, t_total / n as f64);
        }
        (state.x - exact.x).length() + (state.v - exact.v).length()
    };
    for n in [8, 16, 32] {
        let ratio = error(n) / error(2 * n);
        eprintln!("Verlet {n} -> {} steps: ratio {ratio:.2}", 2 * n);
        assert!((3.4..4.6).contains(&ratio), "Verlet error ratio {ratio} ({n} steps)");
    }
}

/// The scenes as these view-renderer tests know them: "eikonal_sphere" is the constant
/// n = 1.5 ball of radius 1 at the origin in the grid environment (sphere_env's ball; the
/// layout of eikonal_sphere before it got caustic_sphere's floor and light), built
/// from eikonal_luneburg's camera and box at 128^3.
fn view_scene(name: &str, size: u32, overrides: &[&str]) -> scene::Scene {
    if name != "eikonal_sphere" {
        return common::scene(name, size, overrides);
    }
    let mut o = vec![
        "volume.index={ type = \"constant\", n = 1.5, center = [0, 0, 0], radius = 1 }",
        "volume.resolution=[128, 128, 128]",
        "volume.name=\"ball\"",
    ];
    o.extend_from_slice(overrides);
    let mut s = common::scene("eikonal_luneburg", size, &o);
    s.name = "eikonal_sphere".into();
    s
}

fn no_nan(name: &str, hdr: &[f32]) {
    let bad = hdr.iter().filter(|v| !v.is_finite()).count();
    assert_eq!(bad, 0, "{name}: {bad} non-finite values");
}

/// Pixels whose RGB differ by more than `tol` in any channel.
fn differing(a: &[f32], b: &[f32], tol: f32) -> usize {
    a.chunks(4).zip(b.chunks(4)).filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > tol)).count()
}

#[test]
fn a_volume_of_index_one_leaves_the_view_unchanged() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let one = common::scene("eikonal_luneburg", 64, &["volume.index.type=\"constant\"", "volume.index.n=1.0"]);
    assert!(common::render_on(&ctx, &one).passes.contains(&"eikonal_view".to_string()));
    let mut without = one.clone();
    without.volume = None;
    let with = common::render_on(&ctx, &one);
    let without = common::render_on(&ctx, &without);
    let n = differing(&with.hdr, &without.hdr, 1e-4);
    assert_eq!(n, 0, "{n} pixels changed by a volume of n = 1");
    // n = 1.5 in the same sphere bends the rays: the comparison can fail.
    let glass = common::scene("eikonal_luneburg", 64, &["volume.index.type=\"constant\"", "volume.index.n=1.5"]);
    let bent = common::render_on(&ctx, &glass);
    assert!(differing(&bent.hdr, &without.hdr, 1e-4) > 200, "n = 1.5 should change the view");
}

#[test]
fn the_view_renderer_renders_the_volume_scenes() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(true);
    for name in ["eikonal_luneburg", "eikonal_sphere"] {
        for integrator in ["euler", "midpoint", "rk4"] {
            let s = view_scene(name, 64, &[&format!("render.eikonal.integrator=\"{integrator}\"")]);
            let r = common::render_on(&ctx, &s);
            no_nan(name, &r.hdr);
            assert!(r.passes.contains(&"eikonal_view".to_string()), "{:?}", r.passes);
            // The lens inverts the view: the centre column's top shows the ground (dark),
            // the sky (bright blue) is at the bottom, unlike the environment around it.
            let blue = |rows: std::ops::Range<u32>| {
                let px: Vec<f32> =
                    rows.flat_map(|j| (26..38).map(move |i| (i, j))).map(|(i, j)| r.radiance(i, j)[2]).collect();
                px.iter().sum::<f32>() / px.len() as f32
            };
            let (top, bottom) = (blue(20..28), blue(36..44));
            assert!(bottom > 1.3 * top, "{name} {integrator}: not inverted: top {top}, bottom {bottom}");
        }
    }
}

#[test]
fn sharp_single_voxel_and_non_cubic_volumes_give_no_nan() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let cases: &[&[&str]] = &[
        &["render.eikonal.sigma=0"],
        &["render.eikonal.sigma=0", "render.eikonal.integrator=\"euler\"", "render.eikonal.step=4"],
        &["volume.resolution=[1, 1, 1]"],
        &["volume.resolution=[17, 40, 5]", "render.eikonal.sigma=2.5"],
        &["volume.resolution=[3, 64, 1]", "render.eikonal.sigma=0"],
        &["volume.index.type=\"linear\"", "volume.index.n0=1.3", "volume.index.gradient=[0, 0.2, 0]"],
        &["volume.attenuation=[0.5, 1, 2]"],
    ];
    for overrides in cases {
        for name in ["eikonal_luneburg", "eikonal_sphere"] {
            let mut o = overrides.to_vec();
            if o.iter().any(|s| s.contains("linear")) {
                // The linear profile takes neither centre nor radius.
                o.insert(0, "volume.index={ type = \"linear\", n0 = 1.3, gradient = [0, 0.2, 0] }");
                o.retain(|s| !s.starts_with("volume.index."));
            }
            let s = view_scene(name, 32, &o);
            let r = common::render_on(&ctx, &s);
            no_nan(&format!("{name} {o:?}"), &r.hdr);
        }
    }
}

#[test]
fn absorption_darkens_the_volume() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let clear = common::render_on(&ctx, &common::scene("eikonal_luneburg", 32, &[]));
    let dark = common::render_on(&ctx, &common::scene("eikonal_luneburg", 32, &["volume.attenuation=[0, 0, 2]"]));
    // The central ray crosses 2 m of the lens: blue falls by e^-4, red and green do not.
    let (c, d) = (clear.radiance(16, 16), dark.radiance(16, 16));
    assert!((d[0] - c[0]).abs() < 1e-5 && (d[1] - c[1]).abs() < 1e-5, "{c:?} {d:?}");
    let ratio = d[2] / c[2];
    assert!((ratio - (-4.0f32).exp()).abs() < 0.01, "blue transmittance {ratio}, expected e^-4");
}

/// `render.eikonal.min_transmittance` stops a view ray once its transmittance is below the
/// threshold in every channel. In a uniform environment of radiance 1, with absorption and
/// no emission or reflection, a pixel's radiance is its ray's transmittance where it leaves
/// the volume: a ray that stops gives 0 where the full march gives less than the threshold,
/// and a ray that never falls below it is marched exactly as before.
#[test]
fn early_termination_drops_less_than_the_transmittance_threshold() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let threshold = 1e-3f32;
    // The central ray crosses 2 m of the lens: T = e^-8 = 3.4e-4 at its exit, below the
    // threshold after ln(1000) / 4 = 1.73 m.
    let at = |t: f32| {
        common::scene(
            "eikonal_luneburg",
            48,
            &[
                "environment.type=\"constant\"",
                "environment.radiance=1",
                "volume.attenuation=[4, 4, 4]",
                &format!("render.eikonal.min_transmittance={t}"),
            ],
        )
    };
    let r = common::render_each(&ctx, &[at(0.0), at(threshold)]);
    let (full, cut) = (&r[0].hdr, &r[1].hdr);
    no_nan("early termination", cut);
    let (mut stopped, mut worst, mut worst_kept) = (0, 0.0f32, 0.0f32);
    for (p, q) in full.chunks(4).zip(cut.chunks(4)) {
        for c in 0..3 {
            let change = (p[c] - q[c]).abs();
            worst = worst.max(change);
            if p[c] > 1.01 * threshold {
                worst_kept = worst_kept.max(change);
            }
        }
        if q[0] == 0.0 && p[0] > 0.0 {
            stopped += 1;
        }
    }
    eprintln!("{stopped} rays stopped; largest change {worst:.3e}, {worst_kept:.3e} where T stays above the threshold");
    assert!(stopped > 20, "only {stopped} rays stopped early");
    assert!(worst < threshold, "stopping changed a pixel by {worst}, more than the threshold {threshold}");
    // The same march up to the stop: rounding only.
    assert!(worst_kept < 1e-6, "a ray that never fell below the threshold changed by {worst_kept}");
}

fn load_error(volume: &str, render: &str) -> String {
    let text = format!(
        "[camera]\nposition = [0, 0, 4]\ntarget = [0, 0, 0]\n[environment]\ntype = \"grid\"\n{volume}\n[render]\n{render}\n"
    );
    match scene::load_str(&text, std::path::Path::new("bad.toml"), &[]) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

const GOOD: &str = "[volume]\nbounds = { min = [-1, -1, -1], max = [1, 1, 1] }\nresolution = [8, 8, 8]\n";

#[test]
fn invalid_volumes_and_parameters_give_clear_errors() {
    if !common::in_own_process() {
        return;
    }
    let lens = "index = { type = \"luneburg\", center = [0, 0, 0], radius = 1 }";
    let cases = [
        (format!("{GOOD}{lens}").replace("[8, 8, 8]", "[0, 8, 8]"), "", "resolution"),
        (format!("{GOOD}{lens}").replace("[8, 8, 8]", "[8, 300, 8]"), "", "256"),
        (format!("{GOOD}{lens}").replace("max = [1, 1, 1]", "max = [1, -1, 1]"), "", "bounds.min"),
        (format!("{GOOD}index = {{ type = \"luneburg\", center = [0, 0, 0], radius = -1 }}"), "", "radius"),
        (format!("{GOOD}index = {{ type = \"luneburg\", center = [0, 0, 0] }}"), "", "radius"),
        (format!("{GOOD}index = {{ type = \"cubic\" }}"), "", "unknown index type `cubic`"),
        (format!("{GOOD}index = {{ type = \"constant\", n = 0 }}"), "", "refractive index"),
        (format!("{GOOD}index = {{ type = \"constant\", n = 1.5, radius = 1 }}"), "", "center"),
        (format!("{GOOD}index = {{ type = \"constant\", n = 1.5, n0 = 1 }}"), "", "n0"),
        (format!("{GOOD}index = {{ type = \"linear\", n0 = 1, gradient = [0, 2, 0] }}"), "", "refractive index"),
        (format!("{GOOD}{lens}\nattenuation = [-1, 0, 0]"), "", "attenuation"),
        // An integrator prism does not offer ("midpoint" is one of its choices).
        (format!("{GOOD}{lens}"), "[render.eikonal]\nintegrator = \"rk2\"", "integrator"),
        (format!("{GOOD}{lens}"), "[render.eikonal]\nstep = 0", "step"),
        (format!("{GOOD}{lens}"), "[render.eikonal]\nsigma = -1", "sigma"),
        (format!("{GOOD}{lens}"), "[render.eikonal]\nsteps = 1", "unknown parameter `steps`"),
        // The light simulator's keys.
        (format!("{GOOD}{lens}"), "[render.eikonal]\nenergy_threshold = 1", "energy_threshold"),
        (format!("{GOOD}{lens}"), "[render.eikonal]\nlight_dt = 0", "light_dt"),
        (format!("{GOOD}{lens}"), "[render.eikonal]\nmax_patches = 10000000", "max_patches"),
        (format!("{GOOD}{lens}"), "[render.eikonal]\nlight_patches = -1", "light_patches"),
        (format!("{GOOD}{lens}"), "[render.eikonal]\nlight_below = -1", "light_below"),
        (format!("{GOOD}{lens}"), "[render.eikonal]\nlight = \"yes\"", "light"),
        (format!("{GOOD}{lens}\nsigma_s = [0, -1, 0]"), "", "sigma_s"),
        (format!("{GOOD}{lens}\nhg_g = 1"), "", "hg_g"),
    ];
    for (volume, render, expected) in cases {
        let e = load_error(&volume, render);
        assert!(e.contains(expected), "expected `{expected}` in:\n{e}");
        assert!(e.contains("bad.toml"), "the error should name the file:\n{e}");
    }
}

/// The reference (src/reference, glsl/reference/volume.glsl) integrates the analytic
/// profile with small RK4 steps and refracts at index jumps with exact Fresnel.
fn reference(ctx: &std::sync::Arc<prism::gpu::GpuContext>, s: &scene::Scene, spp: u32) -> Vec<f32> {
    use prism::reference::{Reference, ReferenceSettings};
    let settings = ReferenceSettings { spp, photons: 0, ..ReferenceSettings::default() };
    let mut r = Reference::new(ctx, s, &settings).expect("reference");
    r.run_all(|_, _| {}).unwrap();
    assert_eq!(r.non_finite_values(), 0);
    r.image()
}

#[test]
fn the_reference_sees_the_volumes() {
    if !common::in_own_process() {
        return;
    }
    use prism::metrics::image::rmse_rgba;
    let ctx = common::context(false);
    let size = 32;
    // The constant-index ball is sphere_env's glass ball: the same reference image.
    let ball = reference(&ctx, &view_scene("eikonal_sphere", size, &[]), 64);
    let glass = reference(&ctx, &common::scene("sphere_env", size, &[]), 64);
    let mut empty = view_scene("eikonal_sphere", size, &[]);
    empty.volume = None;
    let background = reference(&ctx, &empty, 4);
    let (same, none) = (rmse_rgba(&ball, &glass), rmse_rgba(&background, &glass));
    eprintln!("reference: eikonal_sphere vs sphere_env RMSE {same:.4}, no volume vs sphere_env {none:.4}");
    assert!(same < 0.25 * none, "eikonal_sphere's reference should match sphere_env's: {same} vs {none}");
    // The view renderer's ball (Fresnel at the boundary band; the numbers
    // below were measured before it) approaches it as the volume is
    // sampled finer (at 64^2, 32 spp: RMSE 0.33 at 128^3, 0.24 at 256^3 with step 0.25;
    // sphere_env's single-interface baseline: 0.41).
    let sphere_view =
        |o: &[&str]| rmse_rgba(&common::render_on(&ctx, &view_scene("eikonal_sphere", size, o)).hdr, &ball);
    let (coarse, fine) = (
        sphere_view(&["volume.resolution=[64, 64, 64]"]),
        sphere_view(&["volume.resolution=[256, 256, 256]", "render.eikonal.step=0.25"]),
    );
    eprintln!("eikonal_view vs reference (eikonal_sphere): 64^3 {coarse:.4}, 256^3 {fine:.4}, no volume {none:.4}");
    assert!(fine < none, "eikonal_sphere at 256^3 ({fine}) should beat no volume ({none})");
    assert!(fine < 0.9 * coarse, "eikonal_sphere: no convergence to the reference: 64^3 {coarse}, 256^3 {fine}");

    // The view renderer against the RK4 reference on the Luneburg lens: it converges as the
    // volume is sampled finer (measured at 32^2: RMSE 0.32 at 64^3 with sigma 0.75, 0.17 at
    // 128^3, 0.019 at 256^3 with sigma 0.5 and step 0.25; no volume at all: 0.43).
    let lens = common::scene("eikonal_luneburg", size, &[]);
    let truth = reference(&ctx, &lens, 16);
    let view = |o: &[&str]| {
        let mut o = o.to_vec();
        o.push("render.eikonal.integrator=\"rk4\"");
        rmse_rgba(&common::render_on(&ctx, &common::scene("eikonal_luneburg", size, &o)).hdr, &truth)
    };
    let coarse = view(&[]);
    let fine = view(&["volume.resolution=[256, 256, 256]", "render.eikonal.sigma=0.5", "render.eikonal.step=0.25"]);
    let mut no_lens = lens.clone();
    no_lens.volume = None;
    let none = rmse_rgba(&common::render_on(&ctx, &no_lens).hdr, &truth);
    eprintln!("eikonal_view vs RK4 reference (Luneburg): 64^3 {coarse:.4}, 256^3 {fine:.4}, no volume {none:.4}");
    assert!(coarse < none, "64^3: {coarse}, no volume: {none}");
    assert!(fine < 0.2 * coarse, "no convergence to the reference: 64^3 {coarse}, 256^3 {fine}");
}

/// `render.eikonal.leaps` with `weak_gradient` = 0 merges whole steps into one where the
/// smoothed index is constant (air, the inside of the constant-index ball), which is what the
/// full march does there (every stage of a step sees grad n = 0, Eqs. 9-10: a straight line):
/// the two images may differ only by f32 rounding (m steps added at once instead of one by
/// one). The bound: the environment's steepest radiance
/// slope, a grid line of 2.0 across one texel of the 2048-wide bake, is
/// 2 * 2048 / (2 pi) = 652 per radian; a leap replaces up to 256 steps (the ball's diameter
/// at 0.5 voxel of 128^3), each rounding the direction by at most 2^-24, so a pixel may move
/// by 652 * 256 * 2^-24 = 0.01. A leap past a non-zero gradient or off the full march's
/// step lattice moves pixels by far more (by as much as the march's own step error: 46
/// pixels by more than 0.05 at this size when the step is halved).
/// Both scenes are tested: the ball has a uniform inside; the Luneburg lens's index varies
/// everywhere inside, so only its air leaps.
#[test]
fn leaps_through_uniform_regions_equal_the_full_march() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let bound = 2.0 * 2048.0 / (2.0 * std::f32::consts::PI) * 256.0 * 2f32.powi(-24);
    for name in ["eikonal_sphere", "eikonal_luneburg"] {
        let at = |o: &str| view_scene(name, 64, &[o, "render.eikonal.weak_gradient=0"]);
        let r = common::render_each(&ctx, &[at("render.eikonal.leaps=false"), at("render.eikonal.leaps=true")]);
        let (full, leaps) = (&r[0].hdr, &r[1].hdr);
        no_nan(name, leaps);
        let worst = leaps.iter().zip(full).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
        assert!(worst <= bound, "{name}: the leaps moved a pixel by {worst}, more than f32 rounding's {bound}");
    }
}

/// The default `render.eikonal.weak_gradient` also merges steps where the smoothed index
/// changes by at most that much per voxel (the tails of the ball's smoothed boundary), where
/// the ray turns by at most that much per voxel travelled (Eq. 10). That must cost the image
/// far less than the march's own discretisation does: the mean change is bounded by a tenth
/// of the change that halving the step makes (measured: 5.0e-6 against 3.5e-3 on the ball,
/// 2.8e-8 against 1.7e-6 on the lens).
/// On the Luneburg lens the index changes steeply up to its rim, so nearly nothing merges.
#[test]
fn merged_weak_steps_change_the_image_less_than_the_step_error() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let mean =
        |a: &[f32], b: &[f32]| a.iter().zip(b).map(|(x, y)| f64::from((x - y).abs())).sum::<f64>() / a.len() as f64;
    for name in ["eikonal_sphere", "eikonal_luneburg"] {
        let at = |o: &[&str]| view_scene(name, 64, o);
        let exact = "render.eikonal.weak_gradient=0";
        let r = common::render_each(&ctx, &[at(&[exact]), at(&[]), at(&[exact, "render.eikonal.step=0.25"])]);
        no_nan(name, &r[1].hdr);
        let (merged, halved) = (mean(&r[1].hdr, &r[0].hdr), mean(&r[2].hdr, &r[0].hdr));
        eprintln!("{name}: merged weak steps change the image by {merged:.3e}, halving the step by {halved:.3e}");
        assert!(
            merged <= 0.1 * halved,
            "{name}: merged weak steps changed the image by {merged}, halving the step {halved}"
        );
        if name == "eikonal_sphere" {
            assert!(merged > 0.0, "the ball's smoothed boundary has weak tails, but no step merged there");
        }
    }
}

/// `render.eikonal.hardware_filtering` samples the field with the device's trilinear filter
/// instead of eight fetches interpolated in f32. The device may interpolate with coarser
/// weights (8 fractional bits on many GPUs), so the images differ; the trade is worth
/// offering only while that difference stays below the march's own discretisation error,
/// measured here as the change when the step is halved. Both the ball (a steep smoothed
/// shell) and the Luneburg lens (a gradient everywhere inside) are checked.
#[test]
fn hardware_filtering_stays_within_the_march_error() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let rms = |a: &[f32], b: &[f32]| {
        (a.iter().zip(b).map(|(x, y)| ((x - y) as f64).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
    };
    for name in ["eikonal_sphere", "eikonal_luneburg"] {
        let at = |o: &[&str]| view_scene(name, 64, o);
        let r = common::render_each(
            &ctx,
            &[
                at(&["render.eikonal.hardware_filtering=false"]),
                at(&["render.eikonal.hardware_filtering=true"]),
                at(&["render.eikonal.hardware_filtering=false", "render.eikonal.step=0.25"]),
            ],
        );
        no_nan(name, &r[1].hdr);
        let (filtering, step) = (rms(&r[1].hdr, &r[0].hdr), rms(&r[2].hdr, &r[0].hdr));
        let worst = r[1].hdr.iter().zip(&r[0].hdr).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
        eprintln!("{name}: hardware filtering moves the image by RMS {filtering:.3e} (largest {worst:.3e}); halving the step by {step:.3e}");
        // The filtered lookup ran (on lavapipe its weights are f32, so only rounding differs).
        assert!(worst > 0.0, "{name}: hardware filtering left every pixel as it was");
        assert!(filtering < step, "{name}: the filtering's change {filtering} exceeds the step's {step}");
    }
}

/// `hardware_filtering = "auto"` uses the device's filter where a probe finds it exact. The
/// probe (glsl/eikonal/filter_probe.comp) tells filters apart: a nearest sampler, the coarsest
/// weights there are, is off by up to half the texels' difference (bound 0.25; its 256
/// samples come within 1/256 of the worst 0.5), llvmpipe's linear filter, which weighs in
/// f32, by rounding only (bound 1e-5, the probe's own). Where the probe finds the filter exact,
/// "auto" renders the `true` image bit for bit, elsewhere the `false` one.
#[test]
fn auto_filters_in_hardware_where_a_probe_finds_the_filter_exact() {
    use prism::gpu::SamplerDesc;
    use prism::technique::eikonal::eikonal_view::{filter_error, filters_in_full_precision};
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let nearest = filter_error(&ctx, SamplerDesc::NEAREST_CLAMP).unwrap();
    let linear = filter_error(&ctx, SamplerDesc::LINEAR_CLAMP).unwrap();
    eprintln!("{}: the filter probe's largest error: nearest {nearest:.3e}, linear {linear:.3e}", ctx.info.driver_name);
    assert!(nearest > 0.25, "the probe does not see a nearest sampler's steps: {nearest}");
    if ctx.info.driver_name == "llvmpipe" {
        assert!(linear < 1e-5, "llvmpipe's f32 filter off by {linear}");
    }
    let exact = filters_in_full_precision(&ctx).unwrap();
    assert_eq!(exact, linear < 1e-5);
    let at = |value: &str| view_scene("eikonal_sphere", 32, &[&format!("render.eikonal.hardware_filtering={value}")]);
    let r = common::render_each(&ctx, &[at("\"auto\""), at("true"), at("false")]);
    let expected = if exact { &r[1].hdr } else { &r[2].hdr };
    assert!(r[0].hdr == *expected, "\"auto\" is neither the filtered nor the f32 image it should be (exact: {exact})");
    assert!(r[1].hdr != r[2].hdr, "the filtered and the f32 images are the same: the comparison proves nothing");
    common::assert_no_validation_errors(&ctx);
}

/// A furnace: a glass ball (a constant index of 1.5 with its Fresnel band) in an environment
/// of radiance 1 everywhere, no light. Each Fresnel event at the band reflects F of the
/// transmittance T it meets towards the environment and carries T (1 - F) on, so the
/// reflected light and the light leaving the box sum to T = 1 on every ray, whatever the
/// march's discretisation: every pixel is 1 up to f32 rounding (bound 1e-4). Without the
/// reflected rays' light the ball would be darker by F per crossing (0.04 at normal
/// incidence, more towards the rim).
#[test]
fn a_glass_volume_in_a_uniform_environment_disappears() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let text = r#"
name = "furnace_ball"
[camera]
position = [0, 0, 4]
target = [0, 0, 0]
up = [0, 1, 0]
vfov_deg = 40
width = 48
height = 48
[environment]
type = "constant"
radiance = 1
[volume]
name = "ball"
bounds = { min = [-1.05, -1.05, -1.05], max = [1.05, 1.05, 1.05] }
resolution = [48, 48, 48]
index = { type = "constant", n = 1.5, center = [0, 0, 0], radius = 1 }
"#;
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("eikonal_furnace_ball.toml");
    std::fs::write(&path, text).unwrap();
    let s = prism::scene::load(&path, &[]).unwrap();
    let r = common::render_on(&ctx, &s);
    no_nan("furnace", &r.hdr);
    let (lo, hi) = r
        .hdr
        .chunks(4)
        .flat_map(|p| p[..3].iter().copied())
        .fold((f32::MAX, f32::MIN), |(a, b), v| (a.min(v), b.max(v)));
    eprintln!("furnace ball: pixel radiance from {lo} to {hi}");
    assert!((lo - 1.0).abs() <= 1e-4 && (hi - 1.0).abs() <= 1e-4, "the ball is visible: radiance {lo} to {hi}, not 1");
    common::assert_clean_teardown(ctx);
}

/// Velocity Verlet on the GPU (glsl/eikonal/view.frag) is a second-order scheme. At the same
/// step each scheme's image departs from RK4's (fourth order) by its own truncation error, where
/// the field is smooth (the Luneburg lens' graded index): two second-order schemes by error
/// constants a small factor apart, a first-order one by orders of magnitude more (Euler: about
/// 9000 times the midpoint rule's here; a Verlet step without its second half kick, first order,
/// about 1000 times; the Verlet step about 2 times). The bound, 10 times the midpoint rule's,
/// tells the orders apart, and Euler's departure shows that it does.
#[test]
fn verlet_view_rays_are_second_order_like_the_midpoint_rule() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let mae = |a: &[f32], b: &[f32]| a.iter().zip(b).map(|(x, y)| (x - y).abs() as f64).sum::<f64>() / a.len() as f64;
    let at =
        |integrator: &str| common::scene("eikonal_luneburg", 48, &[&format!("render.eikonal.integrator={integrator}")]);
    let r = common::render_each(&ctx, &[at("rk4"), at("verlet"), at("midpoint"), at("euler")]);
    no_nan("eikonal_luneburg verlet", &r[1].hdr);
    let (verlet, midpoint, euler) = (mae(&r[1].hdr, &r[0].hdr), mae(&r[2].hdr, &r[0].hdr), mae(&r[3].hdr, &r[0].hdr));
    eprintln!("mean absolute difference from RK4: verlet {verlet:.3e}, midpoint {midpoint:.3e}, euler {euler:.3e}");
    assert!(midpoint > 0.0 && verlet > 0.0, "the integrators ran the same code");
    assert!(verlet < 10.0 * midpoint, "Verlet departs from RK4 by {verlet}, the midpoint rule by {midpoint}");
    assert!(euler > 10.0 * midpoint, "Euler ({euler}) is not told apart from the midpoint rule ({midpoint})");
    common::assert_no_validation_errors(&ctx);
}
