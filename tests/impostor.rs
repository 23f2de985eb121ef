//! Distance impostors (Szirmay-Kalos et al. 2005, src/technique/impostor/distance_impostor.rs): Hit()
//! against the analytic room of room_mirror (the paper's exact case: planar walls), the
//! error against prism's exact reference compared with classic environment mapping, the
//! conductor Fresnel approximation against the exact formula, regeneration when the sphere
//! moves, and stability at the degenerate cases. Hit() and the Fresnel terms run in
//! glsl/impostor/probe.comp, which includes the very GLSL the shading passes use.
mod common;

use glam::Vec3;
use prism::metrics::image::{non_finite_count, rmse_rgba};
use prism::reference::{Reference, ReferenceSettings};
use prism::renderer::{ImpostorEffect, Renderer};

/// room_mirror's ball (SCENES.md) and room: x in [-3, 3], y in [0, 4], z in [-3, 3].
const BALL: Vec3 = Vec3::new(1.2, 1.0, -0.5);
const BALL_RADIUS: f32 = 0.7;
const ROOM_LO: Vec3 = Vec3::new(-3.0, 0.0, -3.0);
const ROOM_HI: Vec3 = Vec3::new(3.0, 4.0, 3.0);

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.next(), self.next(), self.next()) * 2.0 - 1.0;
            if (0.01..1.0).contains(&v.length_squared()) {
                return v.normalize();
            }
        }
    }
}

/// Where the ray o + t d (o inside the room) leaves the room: the analytic wall hit.
fn room_hit(o: Vec3, d: Vec3) -> Vec3 {
    let mut t = f32::INFINITY;
    for a in 0..3 {
        if d[a] > 0.0 {
            t = t.min((ROOM_HI[a] - o[a]) / d[a]);
        } else if d[a] < 0.0 {
            t = t.min((ROOM_LO[a] - o[a]) / d[a]);
        }
    }
    o + d * t
}

/// Rays from `n` random points of the ball's surface in random directions of the outer
/// hemisphere: what the reflection pass traces.
fn ball_rays(n: usize) -> Vec<(Vec3, Vec3)> {
    let mut rng = Rng(7);
    (0..n)
        .map(|_| {
            let normal = rng.unit();
            let mut d = rng.unit();
            if d.dot(normal) < 0.0 {
                d = -d;
            }
            (BALL + normal * BALL_RADIUS, d)
        })
        .collect()
}

fn records(rays: &[(Vec3, Vec3)]) -> Vec<[[f32; 4]; 3]> {
    rays.iter().map(|(o, d)| [o.extend(0.0).to_array(), d.extend(0.0).to_array(), [0.0; 4]]).collect()
}

fn room_mirror_renderer(ctx: &std::sync::Arc<prism::gpu::GpuContext>, overrides: &[&str]) -> Renderer {
    let mut o = vec!["render.reflection=impostor"];
    o.extend_from_slice(overrides);
    let mut r = Renderer::new(ctx, &common::scene("room_mirror", 32, &o)).unwrap();
    r.render_frame().unwrap();
    r
}

/// The hit points of Hit() approach the analytic wall intersections as the iterations grow
/// (§2.2), for rays from many points of the sphere, and converge to the error floor of the
/// bilinearly filtered 256^2 distance map.
#[test]
fn hit_points_converge_to_the_walls() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let mut r = room_mirror_renderer(&ctx, &[]);
    let rays = ball_rays(4000);
    let mut means = Vec::new();
    for iterations in [0, 1, 2, 4, 8, 16] {
        let out = r.probe_impostor(ImpostorEffect::Reflection, false, iterations, &records(&rays)).unwrap().unwrap();
        let errors: Vec<f32> = rays
            .iter()
            .zip(&out)
            .map(|((o, d), rec)| {
                assert_eq!(rec[0][3], 0.0, "no ray leaves a closed room");
                Vec3::from_slice(&rec[0][..3]).distance(room_hit(*o, *d))
            })
            .collect();
        let mean = errors.iter().sum::<f32>() / errors.len() as f32;
        let mut sorted = errors.clone();
        sorted.sort_by(f32::total_cmp);
        let p99 = sorted[sorted.len() * 99 / 100];
        eprintln!(
            "iterations {iterations:2}: mean error {mean:.5} m, p99 {p99:.5} m, max {:.4} m",
            sorted.last().unwrap()
        );
        means.push((iterations, mean, p99));
    }
    // Shrinking with the iterations (small slack for the floor's float noise).
    for w in means.windows(2) {
        assert!(w[1].1 <= w[0].1 * 1.02 + 1e-5, "{means:?}");
    }
    let (first, last) = (means[0], means[means.len() - 1]);
    assert!(last.1 < first.1 / 4.0, "{means:?}");
    // Converged: mean below 2 mm and p99 below 1 cm in a 6 m room (a 256^2 face texel spans
    // about 1.5 cm at the walls from the reference point).
    assert!(last.1 < 2e-3 && last.2 < 1e-2, "{means:?}");
    drop(r);
    common::assert_no_validation_errors(&ctx);
}

/// Classic environment mapping reflects the room as if it were infinitely far; the distance
/// impostor localizes it. Against the exact reference the impostor's error is far smaller,
/// on room_mirror (reflection) and room_glass (double refraction, with the box's occlusion).
/// Measured at 64^2 over the specular pixels (64 spp reference without photons): room_mirror
/// RMSE 2.38 (single) vs 0.027 (impostor), room_glass 0.164 vs 0.047.
#[test]
fn impostor_error_is_far_below_classic_environment_mapping() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    for (scene, effect) in [("room_mirror", "reflection"), ("room_glass", "refraction")] {
        let s = common::scene(scene, 64, &[]);
        let mut r = Reference::new(&ctx, &s, &ReferenceSettings { spp: 64, photons: 0, ..Default::default() }).unwrap();
        r.run_all(|_, _| {}).unwrap();
        let reference = r.image();
        drop(r);
        let render = |t: &str| {
            let s = common::scene(scene, 64, &[&format!("render.{effect}={t}")]);
            let hdr = common::render_on(&ctx, &s).hdr;
            assert_eq!(non_finite_count(&hdr), 0);
            hdr
        };
        let (single, impostor) = (render("single"), render("impostor"));
        // RMSE over the specular object's pixels: where the two techniques differ at all (the
        // rest is the same deferred shading).
        let mask: Vec<bool> = single.chunks(4).zip(impostor.chunks(4)).map(|(a, b)| a != b).collect();
        let masked = |img: &[f32]| -> f64 {
            let pick = |v: &[f32]| -> Vec<f32> {
                v.chunks(4).zip(&mask).filter(|(_, &m)| m).flat_map(|(p, _)| p.to_vec()).collect()
            };
            rmse_rgba(&pick(img), &pick(&reference))
        };
        let (single, impostor) = (masked(&single), masked(&impostor));
        eprintln!("{scene}: RMSE single {single:.4}, impostor {impostor:.4}");
        assert!(impostor < 0.6 * single, "{scene}: single {single}, impostor {impostor}");
    }
}

/// The conductor Fresnel approximation of §3 against the exact formula, through the shaders'
/// own functions. Gold: Johnson & Christy 1972 (Phys. Rev. B 6, 4370), Table II, at the
/// tabulated wavelengths nearest R, G, B: 659.5 nm (n 0.14, k 3.697), 548.6 nm (0.43, 2.455),
/// 450.9 nm (1.38, 1.914). Silver: the same table at the same wavelengths: n (0.05, 0.06,
/// 0.04), k (4.483, 3.586, 2.657). Aluminium: Rakic 1995 (Appl. Opt. 34, 4755), linearly
/// interpolated to the same wavelengths between its tabulated photon energies: n (1.623,
/// 1.009, 0.636), k (7.800, 6.611, 5.465). (Both tables as transcribed by the
/// refractiveindex.info database, main/Ag/Johnson.yml and main/Al/Rakic.yml.) The RGB n, k
/// that renderers commonly copy are spectra averaged over RGB bands, not point values; the
/// earlier gold entry of that kind, n = (0.143, 0.375, 1.442), k = (3.983, 2.386, 1.603), is
/// 0.4 off Johnson & Christy's k at 650 nm. The paper gives no error bound; its approximation
/// is Schlick's with F(0) from n and k, exact at normal and grazing incidence. The bounds
/// below are the measured maximum absolute errors over cos in [0, 1] (gold 0.0176, silver
/// 0.0066, aluminium 0.1333: the dip of aluminium's reflectance near grazing that Lazanyi &
/// Szirmay-Kalos 2005 add a term for) plus about 10%.
#[test]
fn conductor_fresnel_approximation_is_close_to_exact() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let mut r = room_mirror_renderer(&ctx, &[]);
    let metals = [
        ("gold", [0.14, 0.43, 1.38], [3.697, 2.455, 1.914], 0.02),
        ("silver", [0.05, 0.06, 0.04], [4.483, 3.586, 2.657], 0.008),
        ("aluminium", [1.623, 1.009, 0.636], [7.800, 6.611, 5.465], 0.147),
    ];
    for (name, eta, k, bound) in metals {
        let recs: Vec<_> = (0..=200)
            .map(|i| [[i as f32 / 200.0, 0.0, 0.0, 0.0], [eta[0], eta[1], eta[2], 0.0], [k[0], k[1], k[2], 0.0]])
            .collect();
        let out = r.probe_impostor(ImpostorEffect::Reflection, true, 0, &recs).unwrap().unwrap();
        let mut worst = 0f32;
        for (i, rec) in out.iter().enumerate() {
            for (&approx, &exact) in rec[0][..3].iter().zip(&rec[1][..3]) {
                assert!(approx.is_finite() && exact.is_finite());
                worst = worst.max((approx - exact).abs());
                // Exact at normal incidence (cos = 1) and at grazing incidence (F = 1).
                if i == 200 || i == 0 {
                    assert!((approx - exact).abs() < 1e-4, "{name} cos {}: {approx} vs {exact}", i as f32 / 200.0);
                }
            }
        }
        eprintln!("{name}: max |F_approx - F_exact| = {worst:.4}");
        assert!(worst < bound, "{name}: {worst}");
    }
    drop(r);
    common::assert_no_validation_errors(&ctx);
}

/// §6: the map is rendered again only when the object moved farther than the threshold from
/// the reference point. Moving the ball where an override puts it gives the same image as a
/// renderer made for the overridden scene.
#[test]
fn moving_the_sphere_regenerates_the_impostor() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let mut r = room_mirror_renderer(&ctx, &[]);
    let map = |r: &Renderer| {
        let m = r.impostor_map(ImpostorEffect::Reflection).unwrap();
        (m.generations(), m.reference())
    };
    assert_eq!(map(&r), (1, BALL));
    r.render_frame().unwrap();
    assert_eq!(map(&r).0, 1, "nothing moved: no new map");

    let center = |overrides: &[&str]| match common::scene("room_mirror", 32, overrides).objects[6].analytic {
        Some(prism::scene::Analytic::Sphere { center, .. }) => center,
        None => panic!("the ball is an exact sphere"),
    };
    // 0.05 m < regenerate_distance 0.25 x radius 0.7: the map stays.
    let near = center(&["objects.6.center=[1.25, 1.0, -0.5]"]);
    assert!(r.move_object("ball", near).unwrap());
    r.render_frame().unwrap();
    assert_eq!(map(&r), (1, BALL));

    let far_overrides = ["objects.6.center=[-1.0, 1.2, 0.5]"];
    let far = center(&far_overrides);
    assert!(r.move_object("ball", far).unwrap());
    r.render_frame().unwrap();
    assert_eq!(map(&r), (2, far));
    let moved = r.read_hdr().unwrap();
    drop(r);
    let mut o = vec!["render.reflection=impostor"];
    o.extend_from_slice(&far_overrides);
    let fresh = common::render_on(&ctx, &common::scene("room_mirror", 32, &o)).hdr;
    let e = rmse_rgba(&moved, &fresh);
    assert!(e < 1e-4, "moved ball vs a scene with the ball there: RMSE {e}");
    common::assert_no_validation_errors(&ctx);
}

/// No NaN or Inf anywhere: rays parallel to walls, rays starting at the reference point and on
/// a wall, the reference point on a wall (distance 0 in the map), iterations 0..32.
#[test]
fn stable_at_degenerate_rays_and_reference_points() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let mut r = room_mirror_renderer(&ctx, &["render.impostor.resolution=64"]);
    let mut rays = Vec::new();
    let axes = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    for &a in &axes {
        // Parallel to four walls each, from the ball, from the reference point itself, and
        // along a wall from a point on it.
        rays.push((BALL + Vec3::Y * BALL_RADIUS, a));
        rays.push((BALL, a));
        rays.push((Vec3::new(3.0, 1.0, 0.0), a));
        rays.push((Vec3::new(0.0, 0.0, 0.0), a));
        rays.push((Vec3::new(-3.0, 4.0, -3.0), a));
    }
    for d in [Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, -1.0), Vec3::new(-1.0, 1.0, 0.0)] {
        rays.push((BALL, d.normalize()));
        rays.push((Vec3::new(0.0, 0.0, 0.0), d.normalize()));
    }
    let recs = records(&rays);
    for iterations in 0..=32 {
        let out = r.probe_impostor(ImpostorEffect::Reflection, false, iterations, &recs).unwrap().unwrap();
        for (ray, rec) in rays.iter().zip(&out) {
            assert!(rec.iter().flatten().all(|v| v.is_finite()), "{iterations} iterations, ray {ray:?}: {rec:?}");
        }
    }
    drop(r);
    // The reference point on the right wall (the ball half outside the room), and the
    // default placement, rendered with every iteration count.
    for ball in ["objects.6.center=[3.0, 1.0, -0.5]", "objects.6.center=[1.2, 1.0, -0.5]"] {
        for iterations in [0, 1, 2, 3, 5, 8, 13, 21, 32] {
            let it = format!("render.impostor.iterations={iterations}");
            let s = common::scene(
                "room_mirror",
                64,
                &["render.reflection=impostor", "render.impostor.resolution=64", ball, &it],
            );
            let hdr = common::render_on(&ctx, &s).hdr;
            assert_eq!(non_finite_count(&hdr), 0, "{ball}, {iterations} iterations");
        }
    }
    common::assert_no_validation_errors(&ctx);
}

/// room_mirror with a second mirror ball: two specular objects for `render.impostor.maps`.
fn two_balls(size: u32, overrides: &[&str]) -> prism::scene::Scene {
    let base = std::fs::read_to_string(prism::scene::benchmark_scene_path("room_mirror")).unwrap();
    // Inserted before [render]: a smaller second ball in the opposite corner, and a diffuse
    // box next to each ball (non-planar surroundings near the balls: where the reference
    // point's placement matters, §2).
    let ball2 = "[[objects]]\nname = \"ball2\"\nmaterial = \"ball\"\nshape = \"sphere\"\n\
                 center = [-1.4, 0.6, -1.6]\nradius = 0.4\n\n\
                 [[objects]]\nname = \"crate1\"\nmaterial = \"red\"\nshape = \"box\"\n\
                 center = [2.3, 0.6, -2.2]\nsize = [1.2, 1.2, 1.2]\n\n\
                 [[objects]]\nname = \"crate2\"\nmaterial = \"green\"\nshape = \"box\"\n\
                 center = [-2.4, 0.5, -2.4]\nsize = [1.0, 1.0, 1.0]\n\n[render]";
    let text = base.replacen("[render]", ball2, 1);
    // One file per call: tests run in parallel threads, and one must not read the file while
    // another rewrites it.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("impostor_two_balls_{call}.toml"));
    std::fs::write(&path, text).unwrap();
    let mut o = vec![format!("camera.width={size}"), format!("camera.height={size}")];
    o.extend(prism::scene::BASELINE.iter().chain(overrides).map(|s| s.to_string()));
    prism::scene::load(&path, &o).unwrap()
}

/// §6, "a single environment map for all of them, or ... a separate map for each": with two
/// mirror balls, one map per object (centred on each ball) against one shared map around their
/// mean centre, over the balls' pixels against the exact reference (64^2, 64 spp without
/// photons). Measured RMSE, shared / per_object: Hit() iterations 0 (d_l of Eq. 4 only): 0.0442
/// / 0.0276; 1: 0.0305 / 0.0287; 4: 0.0263 / 0.0286; the small ball alone (ball2, far from the
/// mean centre) at 4 iterations: 0.0179 / 0.0141. The initial guesses are good only near the
/// reference point (§2.1), so per-object maps win where Hit() is cheap, and for the object far
/// from the shared centre at any iteration count. With converged iterations the large ball is
/// closer with the shared map on this scene: its per-object map holds the other mirror ball
/// black (as deferred shading leaves it) where the shared map leaves it out and shows the room
/// behind it, which is closer to what that ball reflects.
#[test]
fn per_object_maps_are_closer_to_the_reference_than_a_shared_map() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let s = two_balls(64, &[]);
    let mut r = Reference::new(&ctx, &s, &ReferenceSettings { spp: 64, photons: 0, ..Default::default() }).unwrap();
    r.run_all(|_, _| {}).unwrap();
    let reference = r.image();
    drop(r);
    let render = |o: &[&str]| {
        let hdr = common::render_on(&ctx, &two_balls(64, o)).hdr;
        assert_eq!(non_finite_count(&hdr), 0, "{o:?}");
        hdr
    };
    let single = render(&[]);
    // The balls' pixels (where the techniques differ at all); ball2 is in the left half.
    let balls: Vec<bool> = {
        let shared = render(&["render.reflection=impostor"]);
        single.chunks(4).zip(shared.chunks(4)).map(|(a, b)| a != b).collect()
    };
    let ball2: Vec<bool> = balls.iter().enumerate().map(|(i, &m)| m && i % 64 < 32).collect();
    assert!(balls.iter().filter(|&&m| m).count() > 300 && ball2.iter().filter(|&&m| m).count() > 40);
    let error = |img: &[f32], mask: &[bool]| -> f64 {
        let pick = |v: &[f32]| -> Vec<f32> {
            v.chunks(4).zip(mask).filter(|(_, &m)| m).flat_map(|(p, _)| p.to_vec()).collect()
        };
        rmse_rgba(&pick(img), &pick(&reference))
    };
    for iterations in [0, 1, 4] {
        let it = format!("render.impostor.iterations={iterations}");
        let shared = render(&["render.reflection=impostor", "render.impostor.maps=shared", &it]);
        let per_object = render(&["render.reflection=impostor", "render.impostor.maps=per_object", &it]);
        let (s_all, p_all) = (error(&shared, &balls), error(&per_object, &balls));
        let (s_2, p_2) = (error(&shared, &ball2), error(&per_object, &ball2));
        eprintln!(
            "iterations {iterations}: RMSE shared {s_all:.4}, per_object {p_all:.4}; ball2 shared {s_2:.4}, per_object {p_2:.4}"
        );
        match iterations {
            0 => assert!(p_all < 0.75 * s_all, "{iterations}: shared {s_all}, per_object {p_all}"),
            1 => assert!(p_all < s_all, "{iterations}: shared {s_all}, per_object {p_all}"),
            _ => assert!(p_2 < 0.9 * s_2, "{iterations}: ball2 shared {s_2}, per_object {p_2}"),
        }
    }
    common::assert_no_validation_errors(&ctx);
}

/// Per object, each map is regenerated only when its own object leaves its reference point;
/// the shared map follows the mean centre.
#[test]
fn moving_one_object_regenerates_only_its_map() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    let generations = |r: &Renderer| -> Vec<(u32, Vec3)> {
        r.impostor_maps(ImpostorEffect::Reflection).iter().map(|m| (m.generations(), m.reference())).collect()
    };
    let ball2 = Vec3::new(-1.4, 0.6, -1.6);
    let mut r = Renderer::new(&ctx, &two_balls(32, &["render.reflection=impostor", "render.impostor.maps=per_object"]))
        .unwrap();
    r.render_frame().unwrap();
    assert_eq!(generations(&r), vec![(1, BALL), (1, ball2)]);
    // 0.05 m < 0.25 x 0.4: nothing is rendered again.
    assert!(r.move_object("ball2", ball2 + Vec3::X * 0.05).unwrap());
    r.render_frame().unwrap();
    assert_eq!(generations(&r), vec![(1, BALL), (1, ball2)]);
    // 0.5 m: only ball2's map, re-centred on it.
    let moved = ball2 + Vec3::new(0.5, 0.0, 0.0);
    assert!(r.move_object("ball2", moved).unwrap());
    r.render_frame().unwrap();
    r.render_frame().unwrap();
    assert_eq!(generations(&r), vec![(1, BALL), (2, moved)]);
    let hdr = r.read_hdr().unwrap();
    assert_eq!(non_finite_count(&hdr), 0);
    drop(r);

    // Shared: one map at the mean centre; the same move (0.25 m of the mean > 0.25 x 0.7).
    let mut r =
        Renderer::new(&ctx, &two_balls(32, &["render.reflection=impostor", "render.impostor.maps=shared"])).unwrap();
    r.render_frame().unwrap();
    assert_eq!(generations(&r), vec![(1, (BALL + ball2) * 0.5)]);
    assert!(r.move_object("ball2", moved).unwrap());
    r.render_frame().unwrap();
    assert_eq!(generations(&r), vec![(2, (BALL + moved) * 0.5)]);
    drop(r);
    common::assert_no_validation_errors(&ctx);
}

/// With one specular object a per-object map is the shared map (same reference point, same
/// draws): the images must agree exactly, for reflection (room_mirror) and for refraction
/// (room_glass, whose per-object path also has its own refractor map and picks its pixels by
/// the G-buffer's object index).
#[test]
fn per_object_equals_shared_with_one_object() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    for (scene, effect) in [("room_mirror", "reflection"), ("room_glass", "refraction")] {
        let render = |maps: &str| {
            let o = [format!("render.{effect}=impostor"), format!("render.impostor.maps={maps}")];
            let o: Vec<&str> = o.iter().map(String::as_str).collect();
            common::render_on(&ctx, &common::scene(scene, 32, &o)).hdr
        };
        let (shared, per_object) = (render("shared"), render("per_object"));
        assert_eq!(non_finite_count(&per_object), 0);
        assert_eq!(shared, per_object, "{scene}");
    }
    common::assert_no_validation_errors(&ctx);
}
