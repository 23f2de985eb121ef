//! The exact reference is right: its own GLSL (through the probe kernel) and its images
//! against closed-form answers, the BVH against brute force, convergence and determinism.
mod common;

use glam::Vec3;
use prism::reference::{Probe, Reference, ReferenceSettings};
use prism::scene::{self, Scene};
use prism::{PHOTON_DEPOSITED, PHOTON_DIRECT, PHOTON_ESCAPED, PHOTON_LOST, PHOTON_MISSED};

fn settings(spp: u32, photons: u64) -> ReferenceSettings {
    ReferenceSettings { spp, photons, ..ReferenceSettings::default() }
}

fn reference(ctx: &std::sync::Arc<prism::gpu::GpuContext>, s: &Scene, st: &ReferenceSettings) -> Reference {
    Reference::new(ctx, s, st).expect("reference")
}

fn rec(o: Vec3, d: Vec3) -> [[f32; 4]; 3] {
    [o.extend(0.0).to_array(), d.extend(0.0).to_array(), [0.0; 4]]
}

/// SplitMix64 for reproducible test inputs.
fn rng(state: &mut u64) -> f32 {
    *state = state.wrapping_add(0x9E3779B97F4A7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
    ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
}

/// Every invocation index below `items` is dispatched, within the limit, and no whole
/// row or group beyond it.
#[test]
fn dispatch_covers_every_item_within_the_group_count_limit() {
    if !common::in_own_process() {
        return;
    }
    let spec_minimum = [65_535, 65_535, 65_535];
    for (items, max) in [
        (1u64, spec_minimum),
        (64, spec_minimum),
        (65, spec_minimum),
        (2048 * 2048, spec_minimum),           // 65 536 groups: one more than a row
        ((1u64 << 32) / 64 - 1, spec_minimum), // a 2^32-byte buffer of 64-byte pixel states
        (1000 * 1000, [1000, 65_535, 65_535]),
        (64 * 7 * 5 + 1, [7, 6, 1]),
    ]
    .map(|(n, m)| (n as u32, m))
    {
        let [x, y, z] = prism::reference::dispatch_size(items, max).expect("fits");
        assert!(x <= max[0] && y <= max[1] && z == 1, "{items}: {x} x {y} over {max:?}");
        let covered = u64::from(x) * u64::from(y) * u64::from(prism::REF_WORKGROUP);
        assert!(covered >= u64::from(items), "{items}: only {covered} invocations");
        // Not a whole row too many, and each row full but the last one's tail.
        assert!(u64::from(x) * u64::from(y - 1) * 64 < u64::from(items), "{items}: {x} x {y}");
    }
    // 64 * 7 * 6 items fill 7 x 6 groups exactly; one more does not fit.
    assert_eq!(prism::reference::dispatch_size(64 * 7 * 6, [7, 6, 1]), Some([7, 6, 1]));
    assert_eq!(prism::reference::dispatch_size(64 * 7 * 6 + 1, [7, 6, 1]), None);
}

#[test]
fn gpu_bvh_traversal_agrees_exactly_with_brute_force_on_the_bunny() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let s = common::scene("bunny_env", 16, &[]);
    let mut r = reference(&ctx, &s, &settings(1, 0));
    let mut state = 3u64;
    let rays: Vec<_> = (0..3000)
        .map(|_| {
            let o = Vec3::new(rng(&mut state) - 0.5, rng(&mut state) - 0.5, rng(&mut state) - 0.5).normalize() * 3.0;
            let t = Vec3::new(rng(&mut state) - 0.5, rng(&mut state) - 0.5, rng(&mut state) - 0.5) * 1.6;
            rec(o, (t - o).normalize())
        })
        .collect();
    let out = r.probe(Probe::Raycast, &rays).unwrap();
    let mut hits = 0;
    for (i, o) in out.iter().enumerate() {
        let [t_bvh, tri_bvh, t_bf, tri_bf] = o[0];
        assert_eq!(t_bvh, t_bf, "ray {i}: t differs");
        if t_bvh >= 0.0 {
            assert_eq!(tri_bvh.to_bits(), tri_bf.to_bits(), "ray {i}: triangle differs");
            hits += 1;
        }
    }
    assert!(hits > 800, "only {hits} hits");
    drop(r);
    common::assert_clean_teardown(ctx);
}

/// Analytic path through a sphere of radius R at the origin: entry by Snell, exit by Snell.
fn sphere_exit(o: Vec3, d: Vec3, r: f32, n: f32) -> Option<(Vec3, Vec3)> {
    let b = o.dot(d);
    let c = o.dot(o) - r * r;
    let disc = b * b - c;
    if disc < 0.0 {
        return None;
    }
    let p1 = o + (-b - disc.sqrt()) * d;
    let n1 = p1 / r;
    let t1 = refract(d, n1, 1.0 / n)?;
    // Inside: the chord from p1 along t1 ends at p2 = p1 - 2 (p1 . t1) t1.
    let p2 = p1 - 2.0 * p1.dot(t1) * t1;
    let n2 = -p2 / r;
    let t2 = refract(t1, n2, n)?;
    Some((p2, t2))
}

/// GLSL's refract: eta = n_i / n_t, n facing the incoming ray.
fn refract(i: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let c = n.dot(i);
    let k = 1.0 - eta * eta * (1.0 - c * c);
    (k >= 0.0).then(|| (eta * i - (eta * c + k.sqrt()) * n).normalize())
}

#[test]
fn ray_through_a_glass_sphere_matches_snell_twice() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let s = common::scene("sphere_env", 16, &[]);
    let mut r = reference(&ctx, &s, &settings(1, 0));
    let cam = Vec3::new(0.0, 0.0, 4.0);
    let mut records = Vec::new();
    let mut expected = Vec::new();
    for k in 0..200 {
        // Rays from the camera at offsets up to 0.95 of the silhouette.
        let a = k as f32 / 200.0 * std::f32::consts::TAU;
        let rho = 0.95 * (k as f32 / 200.0).sqrt();
        let target = Vec3::new(rho * a.cos(), rho * a.sin(), 0.0);
        let d = (target - cam).normalize();
        records.push(rec(cam, d));
        expected.push(sphere_exit(cam, d, 1.0, 1.5));
    }
    let out = r.probe(Probe::SpecularPath, &records).unwrap();
    for (k, (o, e)) in out.iter().zip(&expected).enumerate() {
        let (p2, t2) = e.expect("analytic path");
        assert_eq!(o[0][3] as u32, PHOTON_ESCAPED, "ray {k} should escape");
        assert_eq!(o[1][3] as u32, 2, "ray {k}: two refractions");
        // The probe's final origin is the exit point pushed off the surface by the epsilon.
        let p = Vec3::new(o[0][0], o[0][1], o[0][2]);
        let d = Vec3::new(o[1][0], o[1][1], o[1][2]);
        // Tolerances: the origin offset (2e-5 scene radii) and f32 arithmetic near grazing
        // incidence; a pixel of sphere_env at 512^2 spans 1.4e-3 rad, far more.
        assert!(p.distance(p2) < 1e-3, "ray {k}: exit point {p} vs {p2}");
        assert!(d.distance(t2) < 5e-4, "ray {k}: exit direction {d} vs {t2}");
    }
    drop(r);
    common::assert_clean_teardown(ctx);
}

#[test]
fn total_internal_reflection_sets_in_at_the_critical_angle() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let s = common::scene("sphere_env", 16, &[]);
    let mut r = reference(&ctx, &s, &settings(1, 0));
    // From the centre of the glass ball a ray meets the surface at normal incidence; start
    // on the chord at distance h from the centre so that the angle of incidence is asin(h).
    let critical = (1.0f32 / 1.5).asin();
    let mut records = Vec::new();
    for delta in [-0.01f32, 0.01] {
        let h = (critical + delta).sin();
        records.push(rec(Vec3::new(0.0, h, 0.0), Vec3::X));
    }
    let out = r.probe(Probe::SpecularPath, &records).unwrap();
    // Below the critical angle: one refraction and out. Above: reflected inside, again and again.
    assert_eq!(out[0][1][3] as u32, 1, "below critical: {:?}", out[0]);
    assert!(out[1][1][3] as u32 > 1, "above critical: {:?}", out[1]);
    // The transmitted ray obeys Snell: sin(theta_t) = 1.5 sin(theta_i).
    let n = Vec3::new((1.0 - (critical - 0.01).sin().powi(2)).sqrt(), (critical - 0.01).sin(), 0.0);
    let d = Vec3::new(out[0][1][0], out[0][1][1], out[0][1][2]);
    let sin_t = d.cross(n).length();
    assert!((sin_t - 1.5 * (critical - 0.01).sin()).abs() < 1e-4, "{sin_t}");
    drop(r);
    common::assert_clean_teardown(ctx);
}

#[test]
fn fresnel_matches_closed_forms() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let s = common::scene("sphere_env", 16, &[]);
    let mut r = reference(&ctx, &s, &settings(1, 0));
    let n = 1.5f32;
    let brewster = n.atan();
    // Gold at 550 nm (Johnson & Christy 1972, via refractiveindex.info): n = 0.43, k = 2.45.
    let (gn, gk) = (0.43f32, 2.45f32);
    let records = [
        [[1.0, 1.0 / n, 0.0, 0.0], [gn; 4], [gk; 4]],
        [[brewster.cos(), 1.0 / n, 0.0, 0.0], [gn; 4], [gk; 4]],
        [[0.3, n, 0.0, 0.0], [gn; 4], [gk; 4]], // from inside, beyond the critical angle
    ];
    let out = r.probe(Probe::Fresnel, &records).unwrap();
    let normal = ((n - 1.0) / (n + 1.0)).powi(2);
    assert!((out[0][0][0] - normal).abs() < 1e-6, "normal incidence: {}", out[0][0][0]);
    // At Brewster's angle r_p = 0, so F = r_s^2 / 2 with r_s = (cos_i - n cos_t)/(cos_i + n cos_t).
    let cos_t = (1.0 - (brewster.sin() / n).powi(2)).sqrt();
    let rs = (brewster.cos() - n * cos_t) / (brewster.cos() + n * cos_t);
    assert!((out[1][0][0] - 0.5 * rs * rs).abs() < 1e-6, "Brewster: {} vs {}", out[1][0][0], 0.5 * rs * rs);
    assert_eq!(out[2][0][0], 1.0, "total internal reflection");
    // Conductor at normal incidence: ((n-1)^2 + k^2) / ((n+1)^2 + k^2).
    let f0 = ((gn - 1.0).powi(2) + gk * gk) / ((gn + 1.0).powi(2) + gk * gk);
    assert!((out[0][1][0] - f0).abs() < 1e-5, "gold at normal incidence {} vs {f0}", out[0][1][0]);
    drop(r);
    common::assert_clean_teardown(ctx);
}

const SLAB: &str = r#"
[camera]
position = [0, 0, 4]
target = [0, 0, 0]
width = 16
height = 16
[environment]
type = "constant"
radiance = 1
[materials.tinted]
type = "dielectric"
ior = 1.5
absorption = [0.5, 1.0, 2.0]
[[objects]]
material = "tinted"
shape = "box"
center = [0, 0, 0]
size = [2, 2, 0.3]
"#;

#[test]
fn beer_lambert_through_a_slab() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let s = scene::load_str(SLAB, std::path::Path::new("slab.toml"), &[]).unwrap();
    let mut r = reference(&ctx, &s, &settings(1, 0));
    let out = r.probe(Probe::SpecularPath, &[rec(Vec3::new(0.1, 0.2, 4.0), -Vec3::Z)]).unwrap();
    let beta = out[0][2];
    for (c, sigma) in [0.5f32, 1.0, 2.0].iter().enumerate() {
        // exp(-sigma d) with d the slab's thickness: the path length implied by the
        // attenuation must be 0.3 m within 1e-4 m (ray origins are pushed off surfaces by
        // 2e-5 scene radii, which shortens the path inside by about that much).
        let d = -beta[c].ln() / sigma;
        assert!(
            (d - 0.3).abs() < 1e-4,
            "channel {c}: attenuation {} implies {d} m, expected exp(-{sigma} * 0.3)",
            beta[c]
        );
    }
    drop(r);
    common::assert_clean_teardown(ctx);
}

/// caustic_sphere: the ball lens focuses the point light at the paraxial image distance
/// from its centre, 1/s_i = 2(n-1)/(nR) - 1/s_o (s_o = 3.8, n = 1.5, R = 1: s_i = 2.478).
#[test]
fn ball_lens_focus_matches_the_paraxial_formula() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    // Without the floor, so that the rays leave the lens and can be intersected with the axis.
    let s = common::scene("caustic_sphere", 16, &["objects.0.size=[0.001, 0.001]", "objects.0.center=[50, -50, 50]"]);
    let mut r = reference(&ctx, &s, &settings(1, 0));
    let light = Vec3::new(0.0, 5.0, 0.0);
    let centre = Vec3::new(0.0, 1.2, 0.0);
    let mut records = Vec::new();
    for k in 1..=4 {
        let h = 0.002 * k as f32; // heights at the lens, 0.2% to 0.8% of R: paraxial
        records.push(rec(light, (centre + Vec3::new(h, 0.0, 0.0) - light).normalize()));
    }
    let out = r.probe(Probe::SpecularPath, &records).unwrap();
    let (n, radius, s_o) = (1.5f32, 1.0f32, 3.8f32);
    let s_i = 1.0 / (2.0 * (n - 1.0) / (n * radius) - 1.0 / s_o);
    for o in &out {
        let p = Vec3::new(o[0][0], o[0][1], o[0][2]);
        let d = Vec3::new(o[1][0], o[1][1], o[1][2]);
        // Where the exit ray crosses the axis x = 0.
        let t = -p.x / d.x;
        let y = p.y + t * d.y;
        let distance = centre.y - y;
        assert!((distance - s_i).abs() / s_i < 0.01, "focus at {distance}, paraxial {s_i}");
    }
    drop(r);
    common::assert_clean_teardown(ctx);
}

/// A non-absorbing glass ball: every photon aimed at it ends on the floor or escapes, and the
/// flux on the floor plus the flux elsewhere equals the light's flux through the ball's solid
/// angle, I * 2 pi (1 - cos theta), sin theta = R / distance.
#[test]
fn photon_energy_is_conserved_through_a_clear_sphere() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let s = common::scene("caustic_sphere", 32, &[]);
    let mut r = reference(&ctx, &s, &settings(1, 1 << 16));
    r.run(1).unwrap();
    let photons = r.photon_outcomes();
    let (mut floor, mut elsewhere, mut lost, mut past) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for p in &photons {
        match p[3] as u32 {
            PHOTON_DEPOSITED => floor += p[0] as f64,
            PHOTON_ESCAPED => elsewhere += p[0] as f64,
            PHOTON_LOST => lost += p[0] as f64,
            // The target sphere is 0.1% larger than the ball (a margin for tessellated
            // objects): a thin ring of photons passes it and lights the floor directly.
            PHOTON_MISSED | PHOTON_DIRECT => past += p[0] as f64,
            _ => unreachable!(),
        }
    }
    let cone = |r: f64| {
        let sin_t = r / 3.8;
        50.0 * 2.0 * std::f64::consts::PI * (1.0 - (1.0 - sin_t * sin_t).sqrt())
    };
    let emitted = floor + elsewhere + lost + past;
    assert!((emitted - cone(1.001)).abs() / cone(1.001) < 1e-4, "emitted {emitted} vs {}", cone(1.001));
    // Flux through the ball itself: the light's flux through its solid angle, within the
    // Monte Carlo error of the ring's share.
    let through = floor + elsewhere + lost;
    assert!((through - cone(1.0)).abs() / cone(1.0) < 2e-3, "through the ball {through} vs {}", cone(1.0));
    assert!(lost / through < 1e-3, "too much flux lost at the depth limit: {lost}");
    let total = through;
    // Most of the light goes through the ball to the floor (Fresnel reflects about 8%).
    assert!(floor / total > 0.8 && floor / total < 0.97, "floor fraction {}", floor / total);
    drop(r);
    common::assert_clean_teardown(ctx);
}

/// Monte Carlo error falls as 1/sqrt(samples): against a 16x longer render, 4 spp has about
/// sqrt((1/4 + 1/256) / (1/16 + 1/256)) = 1.96 times the RMSE of 16 spp.
#[test]
fn reference_converges_as_one_over_sqrt_samples() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let s = common::scene("sphere_nearby", 32, &[]);
    let render = |spp: u32, seed: u32| {
        let st = ReferenceSettings { spp, photons: 0, seed, ..ReferenceSettings::default() };
        let mut r = reference(&ctx, &s, &st);
        r.run_all(|_, _| {}).unwrap();
        r.image()
    };
    let truth = render(256, 1);
    let e4 = prism::metrics::image::rmse_rgba(&render(4, 2), &truth);
    let e16 = prism::metrics::image::rmse_rgba(&render(16, 3), &truth);
    let ratio = e4 / e16;
    assert!(ratio > 1.6 && ratio < 2.4, "RMSE 4 spp {e4}, 16 spp {e16}: ratio {ratio}");
    common::assert_clean_teardown(ctx);
}

/// More photons converge: the caustic's error against a long render falls with the photon
/// count (progressive photon mapping is consistent).
#[test]
fn caustics_converge_with_more_photons() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let s = common::scene("caustic_sphere", 32, &[]);
    let caustic = |spp: u32, photons: u64, seed: u32| {
        // The fixed initial radius: this checks the photon count's convergence alone; with
        // the default footprint radii the caustic's visible points also sample each pixel's
        // area, whose noise at 4 spp on a 32^2 image this ordering does not allow for.
        let st = ReferenceSettings { spp, photons, seed, footprint: 0.0, ..ReferenceSettings::default() };
        let mut r = reference(&ctx, &s, &st);
        r.run_all(|_, _| {}).unwrap();
        r.caustic_image()
    };
    let truth = caustic(64, 1 << 22, 1);
    let errors: Vec<f64> = [(4, 1u64 << 14), (16, 1 << 16), (64, 1 << 18)]
        .iter()
        .map(|&(spp, n)| prism::metrics::image::rmse_rgba(&caustic(spp, n, 7), &truth))
        .collect();
    assert!(errors[0] > errors[1] && errors[1] > errors[2], "errors {errors:?}");
    // The caustic is there: bright pixels under the ball.
    assert!(truth.chunks(4).any(|p| p[0] > 1.0), "no caustic found");
    common::assert_clean_teardown(ctx);
}

#[test]
fn same_seed_same_image() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let s = common::scene("sphere_nearby", 24, &[]);
    let run = || {
        let mut r = reference(&ctx, &s, &settings(4, 1 << 14));
        r.run_all(|_, _| {}).unwrap();
        r.image()
    };
    let (a, b) = (run(), run());
    // Camera paths are bit-identical; caustics may differ in the last bits, since photons in
    // one grid cell are summed in the order the GPU inserted them.
    let max_rel = a.iter().zip(&b).map(|(x, y)| (x - y).abs() / x.abs().max(1e-3)).fold(0.0f32, f32::max);
    assert!(max_rel < 1e-4, "{max_rel}");
    common::assert_clean_teardown(ctx);
}

/// The caustic at a floor point does not depend on the image's resolution. (A gather that
/// visited too few grid cells once lost photons depending on where each pixel's visible
/// point fell on the grid: 0.7 instead of 6.5 inside caustic_sphere's disk at 64^2.) The
/// interior of the disk is about 6.5 W/(m^2 sr), which a 1D trace of the ball lens confirms.
#[test]
fn caustic_radiance_is_independent_of_resolution() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let floor_point = |size: u32| {
        let s = common::scene("caustic_sphere", size, &[]);
        let mut r = reference(&ctx, &s, &settings(16, 1 << 21));
        r.run_all(|_, _| {}).unwrap();
        let c = r.caustic_image();
        // Mean over pixels whose centre ray reaches the floor directly within 0.05-0.15 m of
        // the disk's centre (off the bright axial spot).
        let (mut sum, mut n) = (0.0f64, 0);
        for j in 0..size {
            for i in 0..size {
                let (o, d) = s.camera.primary_ray(i, j);
                let oc = o - Vec3::new(0.0, 1.2, 0.0);
                let b = oc.dot(d);
                let hits_ball = b * b - (oc.dot(oc) - 1.0) >= 0.0 && b < 0.0;
                if hits_ball || d.y >= 0.0 {
                    continue;
                }
                let p = o + (-o.y / d.y) * d;
                let r = (p.x * p.x + p.z * p.z).sqrt();
                if (0.05..0.15).contains(&r) {
                    sum += c[4 * (j * size + i) as usize] as f64;
                    n += 1;
                }
            }
        }
        assert!(n > 0, "no floor pixel in the disk at {size}^2");
        sum / n as f64
    };
    let (a, b) = (floor_point(64), floor_point(128));
    assert!((a - b).abs() / b < 0.15, "caustic at 64^2 {a} vs 128^2 {b}");
    assert!(b > 5.0 && b < 8.5, "caustic interior {b}, expected about 6.5");
    common::assert_clean_teardown(ctx);
}

/// A horizontal diffuse quad that receives a caustic: its height and its albedo (checker
/// coordinates are world (x, z) on horizontal quads).
struct Receiver {
    y: f32,
    albedo: prism::scene::Albedo,
}

fn receiver(s: &Scene, name: &str) -> Receiver {
    let o = s.objects.iter().find(|o| o.name == name).unwrap_or_else(|| panic!("{}: no object {name}", s.name));
    let albedo = match &s.materials[o.material] {
        prism::scene::Material::Diffuse { albedo } => *albedo,
        m => panic!("{name} is {}, not diffuse", m.kind_name()),
    };
    assert!(o.mesh.normals.iter().all(|n| n.y.abs() > 0.999), "{name} is not horizontal");
    Receiver { y: o.mesh.positions[0].y, albedo }
}

/// A reference of a caustic scene with the default settings, and what the flux check reads
/// of it: the caustic radiance per pixel (red), every pixel's photon-mapping state, the
/// photons deposited by the last photon pass of every iteration (position, red flux), and per
/// pixel its footprint on the receiver (the points of its four corner rays) where its centre
/// ray and all four corner rays reach the receiver directly (exact tracing
/// through the reference's own probe, so every occluder counts).
struct CausticRender {
    scene: Scene,
    caustic: Vec<f32>,
    states: Vec<[[f32; 4]; 4]>,
    photons: Vec<(Vec3, f32)>,
    passes_sampled: u32,
    footprint: Vec<Option<[Vec3; 4]>>,
}

fn caustic_render(name: &str, size: u32, overrides: &[&str], st: &ReferenceSettings, rec_: &Receiver) -> CausticRender {
    let ctx = common::context(false);
    let scene = common::scene(name, size, overrides);
    let mut r = reference(&ctx, &scene, st);
    let mut photons = Vec::new();
    for _ in 0..st.spp {
        r.run(1).unwrap();
        for (o, p) in r.photon_outcomes().iter().zip(r.photon_positions()) {
            if o[3] as u32 == PHOTON_DEPOSITED {
                photons.push((p, o[0]));
            }
        }
    }
    let caustic = r.caustic_image().chunks(4).map(|p| p[0]).collect();
    let states: Vec<_> = (0..(size * size) as usize).map(|k| r.pixel_state(k)).collect();
    let cam = scene.camera.position;
    let corner = |i: u32, j: u32| rec(cam, camera_ray(&scene, i as f32, j as f32));
    let mut records: Vec<_> =
        (0..=size).flat_map(|j| (0..=size).map(move |i| (i, j))).map(|(i, j)| corner(i, j)).collect();
    for j in 0..size {
        for i in 0..size {
            records.push(rec(cam, camera_ray(&scene, i as f32 + 0.5, j as f32 + 0.5)));
        }
    }
    let out = r.probe(Probe::SpecularPath, &records).unwrap();
    // Where a ray from the camera first meets a surface, if that is the receiver. The probe
    // follows surfaces only: a ray that crosses a `[volume]`'s medium is bent there (camera
    // paths cross it in RK4 steps), so it does not see that point. The medium: the profile's
    // sphere grown by four voxels (the Gaussian pre-smoothing spreads it by about three),
    // else the whole box.
    let clear = |p: Vec3| {
        scene.volume.as_ref().is_none_or(|v| match v.index.region() {
            Some((c, r)) if v.regions.is_empty() => {
                segment_distance(cam, p, c) > r + 4.0 * v.voxel_size().max_element()
            }
            _ => !segment_meets_box(cam, p, v.min, v.max),
        })
    };
    let direct = |o: &[[f32; 4]; 3]| {
        let p = Vec3::new(o[0][0], o[0][1], o[0][2]);
        (o[0][3] as u32 == PHOTON_DEPOSITED && o[1][3] as u32 == 0 && (p.y - rec_.y).abs() < 1e-3 && clear(p))
            .then_some(p)
    };
    let n = (size + 1) as usize;
    let footprint = (0..size as usize)
        .flat_map(|j| (0..size as usize).map(move |i| (i, j)))
        .map(|(i, j)| {
            direct(&out[n * n + j * size as usize + i])?;
            let c = |a: usize, b: usize| direct(&out[(j + b) * n + i + a]);
            Some([c(0, 0)?, c(1, 0)?, c(1, 1)?, c(0, 1)?])
        })
        .collect();
    drop(r);
    common::assert_clean_teardown(ctx);
    CausticRender { scene, caustic, states, photons, passes_sampled: st.spp, footprint }
}

/// The distance from c to the segment a -> b.
fn segment_distance(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let d = b - a;
    let t = ((c - a).dot(d) / d.dot(d)).clamp(0.0, 1.0);
    (a + t * d).distance(c)
}

/// Whether the segment a -> b passes through the box [lo, hi] (slab test).
fn segment_meets_box(a: Vec3, b: Vec3, lo: Vec3, hi: Vec3) -> bool {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for k in 0..3 {
        if d[k].abs() < 1e-12 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return false;
            }
            continue;
        }
        let (u, v) = ((lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]);
        t0 = t0.max(u.min(v));
        t1 = t1.min(u.max(v));
    }
    t0 <= t1
}

/// The ray from the camera through image point (x, y) in pixels, (0, 0) the top-left corner.
fn camera_ray(s: &Scene, x: f32, y: f32) -> Vec3 {
    let c = &s.camera;
    let forward = (c.target - c.position).normalize();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    let tan_half = (c.vfov_deg.to_radians() * 0.5).tan();
    let u = (2.0 * x / c.width as f32 - 1.0) * tan_half * c.aspect();
    let v = (1.0 - 2.0 * y / c.height as f32) * tan_half;
    (forward + u * right + v * up).normalize()
}

/// The image point (column, row in pixels, (0, 0) the top-left corner) that p projects to.
fn image_point(s: &Scene, p: Vec3) -> (f32, f32) {
    let c = &s.camera;
    let forward = (c.target - c.position).normalize();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    let tan_y = (c.vfov_deg.to_radians() * 0.5).tan();
    let q = p - c.position;
    let z = q.dot(forward);
    let x = (q.dot(right) / z / (tan_y * c.aspect()) + 1.0) * 0.5 * c.width as f32;
    let y = (1.0 - q.dot(up) / z / tan_y) * 0.5 * c.height as f32;
    (x, y)
}

/// Whether the segment from `o` to `p` passes through the sphere (centre, radius).
fn segment_hits_sphere(o: Vec3, p: Vec3, centre: Vec3, radius: f32) -> bool {
    let d = p - o;
    let t = ((centre - o).dot(d) / d.dot(d)).clamp(0.0, 1.0);
    (o + t * d).distance(centre) < radius
}

/// The flux balance of the photon gather over the pixels that see the receiver directly
/// (`CausticRender::footprint`): the photons' reflected flux and the integrated caustic
/// radiance, both in W/sr (a photon of flux Phi on albedo rho leaves Phi rho / pi, the
/// radiance the pixels show integrated over their footprint); the photons counted; the
/// relative standard deviation of the photons' sum; the share of the photons' flux that a
/// gathering disk can move across the selection's border; and the selected pixels whose
/// caustic is 0 although at least 50 photons of the sampled passes landed in them.
struct FluxBalance {
    photons: f64,
    integral: f64,
    n: usize,
    sigma: f64,
    border: f64,
    holes: Vec<(u32, u32, usize)>,
}

fn flux_balance(c: &CausticRender, rec_: &Receiver, footprints: f32) -> FluxBalance {
    let s = &c.scene;
    let (w, h) = (s.camera.width as i64, s.camera.height as i64);
    let selected =
        |i: i64, j: i64| (0..w).contains(&i) && (0..h).contains(&j) && c.footprint[(j * w + i) as usize].is_some();
    let inv_pi = std::f64::consts::FRAC_1_PI;
    let (mut sum, mut sum2, mut border, mut n) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    let mut count = vec![0usize; (w * h) as usize];
    for &(p, f) in &c.photons {
        if (p.y - rec_.y).abs() > 1e-4 {
            continue;
        }
        let e = f as f64 * rec_.albedo.eval(glam::Vec2::new(p.x, p.z)).x as f64 * inv_pi;
        let (x, y) = image_point(s, p);
        let (i, j) = (x.floor() as i64, y.floor() as i64);
        // A gathering disk starts at `footprints` times the pixel's footprint over
        // sqrt(cos) (camera.comp) and only shrinks; seen from the camera it reaches at most
        // footprints / sqrt(cos) pixels from the visible point, which lies in its pixel.
        let cos = (s.camera.position - p).normalize().y.abs().max(0.05);
        let reach = footprints / cos.sqrt();
        let me = selected(i, j);
        if common::disk_crosses_border(selected, x, y, reach) {
            border += e;
        }
        if me {
            sum += e;
            sum2 += e * e;
            n += 1;
            count[(j * w + i) as usize] += 1;
        }
    }
    let k = c.passes_sampled as f64;
    let mut integral = 0.0f64;
    let mut holes = Vec::new();
    for (idx, q) in c.footprint.iter().enumerate() {
        let Some(q) = q else { continue };
        let area = 0.5 * (0..4).map(|m| q[m].x * q[(m + 1) % 4].z - q[(m + 1) % 4].x * q[m].z).sum::<f32>().abs();
        integral += (c.caustic[idx] * area) as f64;
        if c.states[idx][0][0] == 0.0 && count[idx] >= 50 {
            holes.push(((idx as i64 % w) as u32, (idx as i64 / w) as u32, count[idx]));
        }
    }
    let share = |x: f64| x / sum.max(1e-30);
    FluxBalance { photons: sum / k, integral, n, sigma: sum2.sqrt() / sum.max(1e-30), border: share(border), holes }
}

/// The gather conserves the photons' flux: over the pixels that see the receiver directly,
/// the caustic radiance integrated over their footprints equals the reflected flux of the
/// photons landing in those footprints, and no pixel that many photons reach is black. (Under
/// room_glass's focus lavapipe once cut the gather's long photon lists short and 8-pixel runs
/// came out black: about half of the caustic's flux around the focus was lost.) Each pixel's
/// caustic estimates the average over its area (camera.comp: visible points spread over the
/// pixel), so the sum over pixels is the integral over their footprints with no midpoint
/// error. Tolerance: 3 standard deviations of the sampled photons' sum (the relative standard
/// deviation of a sum of independent photons, sqrt(sum f^2) / sum f), plus the share of the
/// photons' flux within a gathering disk's reach of the selection's border (on either side:
/// a disk there can count photons the selection leaves out or miss ones it counts). The pixel side's own noise comes
/// from all photon passes, 1 / passes_per_iteration of which are sampled here: it is smaller.
/// A 50-photon pixel is black by chance with probability below 0.8^50 = 1.4e-5 (its disk
/// covers at least a fifth of its footprint until its first photon).
fn check_caustic(name: &str, size: u32, overrides: &[&str], spp: u32, photons: u64, receiver_name: &str) {
    let st = settings(spp, photons);
    let s = common::scene(name, size, overrides);
    let rec_ = receiver(&s, receiver_name);
    let c = caustic_render(name, size, overrides, &st, &rec_);
    let b = flux_balance(&c, &rec_, st.footprint);
    let tolerance = 3.0 * b.sigma + b.border;
    eprintln!(
        "{name}: photons' flux {:.5}, integrated radiance {:.5} (ratio {:.4}), {} photons, sigma {:.4}, border {:.4}, \
         tolerance {tolerance:.4}, {} pixels, {} holes ({st:?})",
        b.photons,
        b.integral,
        b.integral / b.photons,
        b.n,
        b.sigma,
        b.border,
        c.footprint.iter().flatten().count(),
        b.holes.len()
    );
    assert!(b.n >= 1000, "{name}: only {} photons land on the pixels that see {receiver_name}", b.n);
    assert!(b.holes.is_empty(), "{name}: black pixels inside the caustic at {:?}", &b.holes[..b.holes.len().min(20)]);
    assert!(
        (b.integral - b.photons).abs() / b.photons < tolerance,
        "{name}: the pixels hold {} W/sr of caustic, the photons {} W/sr (tolerance {tolerance})",
        b.integral,
        b.photons
    );
}

// The flux check on every bundled scene whose reference has caustics on a surface, seen
// directly by the scene's camera or one moved for the purpose. 128^2, 8 spp, 2^20 photons
// (17 passes of about 7700 each per iteration).
#[test]
fn room_glass_caustic_conserves_the_photons_flux() {
    if !common::in_own_process() {
        return;
    }
    check_caustic("room_glass", 128, &[], 8, 1 << 20, "floor");
}

#[test]
fn caustic_sphere_caustic_conserves_the_photons_flux() {
    if !common::in_own_process() {
        return;
    }
    // The scene's camera sees the caustic's centre just past the ball's lower edge, which
    // runs through the caustic; from this lower camera the ray to any point of the caustic
    // disk (radius 0.26) passes under the ball (its lowest point is 0.2 above the floor).
    let low = ["camera.position=[0, 1.2, 4]", "camera.target=[0, 0, 0]"];
    check_caustic("caustic_sphere", 128, &low, 8, 1 << 20, "floor");
}

#[test]
fn caustic_bunny_caustic_conserves_the_photons_flux() {
    if !common::in_own_process() {
        return;
    }
    check_caustic("caustic_bunny", 128, &[], 8, 1 << 20, "floor");
}

#[test]
fn metal_ring_caustic_conserves_the_photons_flux() {
    if !common::in_own_process() {
        return;
    }
    check_caustic("metal_ring", 128, &[], 8, 1 << 20, "floor");
}

#[test]
fn room_mirror_caustic_conserves_the_photons_flux() {
    if !common::in_own_process() {
        return;
    }
    check_caustic("room_mirror", 128, &[], 8, 1 << 20, "floor");
}

#[test]
fn sphere_nearby_caustic_conserves_the_photons_flux() {
    if !common::in_own_process() {
        return;
    }
    check_caustic("sphere_nearby", 128, &[], 8, 1 << 20, "floor");
}

#[test]
fn water_pool_caustic_conserves_the_photons_flux() {
    if !common::in_own_process() {
        return;
    }
    // The sun's caustic lies on the pool's floor, under the wavy surface that focuses it; the
    // scene's camera sees it only through that surface. A camera under the water sees the
    // floor directly (its rays meet no interface on the way down, and a diffuse floor's
    // radiance does not depend on the medium it leaves into), so the same balance holds.
    let under = ["camera.position=[0, -0.6, 2.2]", "camera.target=[0, -1.5, 0]"];
    check_caustic("water_pool", 128, &under, 8, 1 << 20, "pool_floor");
}

#[test]
fn eikonal_sphere_caustic_conserves_the_photons_flux() {
    if !common::in_own_process() {
        return;
    }
    // The graded-index ball's caustic on the floor, its photons crossing the volume in RK4
    // steps (glsl/reference/volume.glsl). The ball and floor of caustic_sphere, and its check's
    // lower camera: only pixels whose rays pass clear of the medium count (caustic_render).
    // 2^19 photons, each marching the ball in small RK4 steps (2^20 made this the suite's
    // second longest test, 65 s): the check samples one photon pass per iteration, which
    // holds about as many photons either way (49 225 against 52 192 land on the counted
    // pixels, sigma 0.0045 against 0.0044), and the tolerance is mostly the border's share.
    let low = ["camera.position=[0, 1.2, 4]", "camera.target=[0, 0, 0]"];
    check_caustic("eikonal_sphere", 128, &low, 8, 1 << 19, "floor");
}

#[test]
fn eikonal_wine_glass_caustic_conserves_the_photons_flux() {
    if !common::in_own_process() {
        return;
    }
    // The table behind and to the left of the wine glass, away from the light (at [1.5, 3,
    // 2]), where the light the glass refracts lands outside the volume's box (|x|, |z| <=
    // 0.5), seen from above so that the counted rays pass clear of the box. Its photons cross
    // the lathe regions in RK4 steps of an eighth of a voxel (glsl/reference/volume.glsl): at
    // half the scene's 88 x 128 x 88, which halves their steps (the scene's own took 138 s,
    // the suite's longest test), 64^2 and 2^18 photons.
    let behind = [
        "camera.position=[-1.4, 2.2, -1.9]",
        "camera.target=[-0.75, 0, -0.95]",
        "camera.vfov_deg=20",
        "volume.resolution=[44, 64, 44]",
    ];
    check_caustic("eikonal_wine_glass", 64, &behind, 8, 1 << 18, "table");
}

#[test]
fn two_glass_balls_caustic_conserves_the_photons_flux() {
    if !common::in_own_process() {
        return;
    }
    check_caustic("two_glass_balls", 128, &[], 8, 1 << 20, "floor");
}

/// The photons' kernel blurs caustic_sphere's caustic by no more than a pixel. The bright rim
/// of the caustic disk on the floor is the fold where the landing position of the rays the
/// ball refracts twice is largest on their own side of the axis, r_edge (traced here by
/// Snell's law); only the marginal rays that crossed the axis land beyond it, thinly spread.
/// With the default settings a pixel gathers the photons within its radius, at most half its
/// footprint on the floor, around visible points spread over its area, so a pixel whose
/// centre lies 1.5 to 2.5 footprints beyond r_edge reaches at most 1.5 footprints out and
/// gets none of the rim (which reaches 20 to 30 at pixel scale), only the thin light beyond
/// the fold, which is 0.2% of the disk's interior radiance (6.5, see
/// caustic_radiance_is_independent_of_resolution) in the ring 4 to 8 footprints out, where no
/// kernel reaches the rim: the ring may hold ten times that, 2%. Initial radii of 1% of the
/// scene's radius (2.5 footprints at 256^2, `footprint: 0`) spread the rim into it.
#[test]
fn caustic_sphere_edge_is_sharp_at_pixel_scale() {
    if !common::in_own_process() {
        return;
    }
    const SIZE: u32 = 256;
    let (light, centre) = (Vec3::new(0.0, 5.0, 0.0), Vec3::new(0.0, 1.2, 0.0));
    let theta_max = (1.0f32 / (light - centre).length()).asin();
    let r_edge = (1..20_000)
        .filter_map(|k| {
            let theta = theta_max * k as f32 / 20_000.0;
            let (p, t) = sphere_exit(light - centre, Vec3::new(theta.sin(), -theta.cos(), 0.0), 1.0, 1.5)?;
            (t.y < 0.0).then(|| p.x + (-centre.y - p.y) / t.y * t.x)
        })
        .fold(0.0f32, f32::max);
    let ctx = common::context(false);
    let scene = common::scene("caustic_sphere", SIZE, &[]);
    let st = settings(4, 1 << 20);
    let mut r = reference(&ctx, &scene, &st);
    r.run_all(|_, _| {}).unwrap();
    let c = r.caustic_image();
    let pixel_angle = 2.0 * (scene.camera.vfov_deg.to_radians() * 0.5).tan() / SIZE as f32;
    let (mut near, mut far) = ((0.0f64, 0), (0.0f64, 0));
    for j in 0..SIZE {
        for i in 0..SIZE {
            let (o, d) = scene.camera.primary_ray(i, j);
            if d.y >= 0.0 || segment_hits_sphere(o, o + (-o.y / d.y) * d, centre, 1.0) {
                continue;
            }
            let t = -o.y / d.y;
            let p = o + t * d;
            let footprint = pixel_angle * t / (-d.y).sqrt();
            let beyond = ((p.x * p.x + p.z * p.z).sqrt() - r_edge) / footprint;
            let v = c[4 * (j * SIZE + i) as usize] as f64;
            if (1.5..2.5).contains(&beyond) {
                near = (near.0 + v, near.1 + 1);
            } else if (4.0..8.0).contains(&beyond) {
                far = (far.0 + v, far.1 + 1);
            }
        }
    }
    let (near, far) = (near.0 / near.1.max(1) as f64, far.0 / far.1.max(1) as f64);
    eprintln!(
        "caustic_sphere: r_edge {r_edge}, caustic 1.5-2.5 footprints out {near}, 4-8 out {far} (footprint {})",
        st.footprint
    );
    const INTERIOR: f64 = 6.5;
    assert!(near <= 0.02 * INTERIOR, "the caustic's rim spreads past its edge: {near} (further out {far})");
    drop(r);
    common::assert_clean_teardown(ctx);
}
