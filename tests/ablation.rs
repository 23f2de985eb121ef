//! The oracle ablation (`render.wyman.oracle`): Wyman 2005's intermediates replaced by the
//! exact tracer's. On a rotated glass box, whose faces the rasterizer and the tracer see
//! alike (flat, the same triangles), the exact exit is known in closed form: two Snell
//! refractions at planes. With the oracle on, Wyman's exit equals it to float precision, and
//! its image equals the exact tracer's up to the one thing Wyman's model leaves out at two
//! interfaces, the Fresnel reflection at the exit.
//! Hu & Qin 2007's (`render.hu_qin.oracle`), the distance impostors' `Hit()`
//! (`render.impostor.oracle`) and caustics mapping's receiver estimate
//! (`render.caustics_map.oracle`) are checked for independence from the search they replace;
//! caustics mapping's also against CPU-traced hits on two flat mirrors.
mod common;

use common::{context, render_on};
use glam::Vec3;
use prism::renderer::Renderer;
use prism::scene::Scene;

const SIZE: u32 = 64;
const IOR: f32 = 1.5;

/// A glass box (ior 1.5, no absorption) turned so that the camera sees three faces and the
/// refracted rays leave through several: P2~ (Wyman §3.1) lands on the wrong back face near
/// the box's edges, so the exit normal of §3.2 is wrong there. Grid environment.
fn box_scene(overrides: &[&str]) -> Scene {
    let object = r#"name = "box"
        shape = "box"
        center = [0, 0, 0]
        size = [1.6, 1.2, 1.0]
        transform = { rotation = [25, 35, 0] }"#;
    common::glass_scene(SIZE, [0.0, 0.0, 4.0], IOR, object, overrides)
}

/// Nearest hit of o + t d (t > 1e-4) on the box's triangles: (t, outward unit face normal).
fn hit(s: &Scene, o: Vec3, d: Vec3) -> Option<(f32, Vec3)> {
    hit_mesh(&s.objects[0].mesh, o, d)
}

/// Nearest hit of o + t d (t > 1e-4) on `m`'s triangles: (t, unit face normal on the side
/// its normals point to).
fn hit_mesh(m: &prism::scene::Mesh, o: Vec3, d: Vec3) -> Option<(f32, Vec3)> {
    let mut best: Option<(f32, Vec3)> = None;
    for t in m.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| m.positions[t[k] as usize]);
        let (e1, e2) = (b - a, c - a);
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-12 {
            continue;
        }
        let sv = o - a;
        let u = sv.dot(p) / det;
        let q = sv.cross(e1);
        let v = d.dot(q) / det;
        let tt = e2.dot(q) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && tt > 1e-4 && best.is_none_or(|(bt, _)| tt < bt) {
            // Counter-clockwise seen from outside (Mesh::indices): the cross product points out.
            best = Some((tt, e1.cross(e2).normalize()));
        }
    }
    best
}

fn refract(i: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let c = -i.dot(n);
    let k = 1.0 - eta * eta * (1.0 - c * c);
    (k >= 0.0).then(|| eta * i + (eta * c - k.sqrt()) * n)
}

/// Exact unpolarised Fresnel reflectance (glsl/include/fresnel.glsl's formula).
fn fresnel(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (0.5 * (rs * rs + rp * rp)).clamp(0.0, 1.0)
}

/// The closed-form two-interface path of the camera ray through image point (x, y).
#[derive(Clone, Copy)]
struct Exit {
    /// Entry normal (outward) and the reflected direction at P1.
    n1: Vec3,
    reflected: Vec3,
    p1: Vec3,
    t1: Vec3,
    p2: Vec3,
    /// Outward normal at P2.
    n2: Vec3,
    /// T2; None under total internal reflection at P2.
    t2: Option<Vec3>,
    /// 1 - (n sin theta_2)^2 at P2: below 0 total internal reflection.
    k: f32,
}

fn exit(s: &Scene, x: f32, y: f32) -> Option<Exit> {
    let (o, d) = s.camera.ray_through(x, y);
    let (t, n1) = hit(s, o, d)?;
    let p1 = o + t * d;
    let t1 = refract(d, n1, 1.0 / IOR)?.normalize();
    let (t_exit, n2) = hit(s, p1, t1)?;
    let p2 = p1 + t_exit * t1;
    let c = t1.dot(n2);
    let k = 1.0 - IOR * IOR * (1.0 - c * c);
    let t2 = refract(t1, -n2, IOR).map(Vec3::normalize);
    Some(Exit { n1, reflected: d - 2.0 * d.dot(n1) * n1, p1, t1, p2, n2, t2, k })
}

/// Whether pixel (i, j)'s path is decided robustly: the rays through points 0.05 pixel
/// around its centre enter and leave through the same faces (so that the depth buffer's
/// rounding of P1 cannot move it onto another face; at the edges the pixel's centre ray and
/// the rasterizer may disagree), and the exit is not within ~3 degrees of the critical
/// angle (|k| >= 0.0025: there T2 = sqrt(k)-proportional terms amplify P1's rounding).
fn robust(s: &Scene, i: u32, j: u32) -> Option<Exit> {
    let (x, y) = (i as f32 + 0.5, j as f32 + 0.5);
    let e = exit(s, x, y)?;
    for (dx, dy) in [(-0.05, 0.0), (0.05, 0.0), (0.0, -0.05), (0.0, 0.05)] {
        let f = exit(s, x + dx, y + dy)?;
        if f.n1.dot(e.n1) < 0.9999 || f.n2.dot(e.n2) < 0.9999 {
            return None;
        }
    }
    (e.k.abs() >= 0.0025).then_some(e)
}

struct Debug {
    hdr: Vec<f32>,
    p2: Vec<f32>,
    t2: Vec<f32>,
}

fn wyman(ctx: &std::sync::Arc<prism::gpu::GpuContext>, oracle: &str) -> Debug {
    technique(ctx, "wyman", oracle)
}

/// The box rendered by `t` (wyman or hu_qin) with its debug targets and `oracle`.
fn technique(ctx: &std::sync::Arc<prism::gpu::GpuContext>, t: &str, oracle: &str) -> Debug {
    let (refraction, debug) = (format!("render.refraction={t}"), format!("render.{t}.debug=true"));
    let oracle = format!("render.{t}.oracle=\"{oracle}\"");
    let s = box_scene(&[&refraction, &debug, &oracle]);
    let mut r = Renderer::new(ctx, &s).unwrap();
    r.render_frame().unwrap();
    let hdr = r.read_hdr().unwrap();
    let p2 = r.read_target(&format!("refraction_{t}_p2")).unwrap().expect("debug P2");
    let t2 = r.read_target(&format!("refraction_{t}_t2")).unwrap().expect("debug T2");
    drop(r);
    common::assert_no_validation_errors(ctx);
    Debug { hdr, p2, t2 }
}

fn at(v: &[f32], i: u32, j: u32) -> Vec3 {
    let k = 4 * (j * SIZE + i) as usize;
    Vec3::new(v[k], v[k + 1], v[k + 2])
}

/// The unit roundoff of the G-buffer's normals (RGBA16F, src/frame/targets.rs): each
/// component of N1 is rounded to 11 significant bits, so N1's direction is off by at most
/// 2^-11 rad. It is the largest error in Wyman's inputs: the rest is f32 (2^-24).
const HALF_ROUNDOFF: f32 = 1.0 / 2048.0;

/// f32 rounding of the chain itself (two refractions, a normalisation, the depth's
/// reconstruction of P1: each a few 2^-24): 1e-5 is 100 such roundings.
const F32_CHAIN: f32 = 1e-5;

/// Per robust pixel without total internal reflection at P2: Wyman's T2 and P2 against the
/// closed form, each as a ratio to the error N1's rounding alone can cause there. A tilt delta
/// of N1 turns T1 by delta |1 - eta cos_i / cos_t| <= delta (dtheta_t / dtheta_i = eta cos_i /
/// cos_t, Snell differentiated), T2 by that times n cos_in / cos_out at P2 (the same at the
/// exit), and moves P2 on the exit face by |P2 - P1| delta / cos_in. Returns the largest
/// ratios (T2, P2), the largest errors (rad, units) and the pixel count.
fn exit_error(s: &Scene, d: &Debug) -> ((f32, f32), (f32, f32), usize) {
    let (mut ratio, mut worst, mut n) = ((0.0f32, 0.0f32), (0.0f32, 0.0f32), 0);
    for j in 0..SIZE {
        for i in 0..SIZE {
            let Some(e) = robust(s, i, j) else { continue };
            let Some(t2) = e.t2 else { continue };
            n += 1;
            let cos_in = e.t1.dot(e.n2);
            let t_bound = HALF_ROUNDOFF * IOR * cos_in / e.k.sqrt() + F32_CHAIN;
            let p_bound = HALF_ROUNDOFF * (e.p2 - e.p1).length() / cos_in + F32_CHAIN;
            let t_err = at(&d.t2, i, j).normalize().dot(t2).clamp(-1.0, 1.0).acos();
            let p_err = (at(&d.p2, i, j) - e.p2).length();
            ratio = (ratio.0.max(t_err / t_bound), ratio.1.max(p_err / p_bound));
            worst = (worst.0.max(t_err), worst.1.max(p_err));
        }
    }
    (ratio, worst, n)
}

/// With the exit normal exact (alone or with the exit point), T2 is the closed form's up to
/// what the rounding of the G-buffer's N1 causes (exit_error: the bound per pixel); with the
/// exit point exact, so is P2; without the oracle neither is. The exact normal alone already
/// makes T2 exact: a distant environment sees only T1 and N2 (§3: "only T1, the point P2, and
/// the normal N2 are necessary", and P2 only to find N2).
#[test]
fn wyman_oracle_exit_is_the_closed_form_exit() {
    if !common::in_own_process() {
        return;
    }
    let ctx = context(false);
    let s = box_scene(&[]);
    let mut report = Vec::new();
    for oracle in ["none", "exit_point", "exit_normal", "all"] {
        let d = wyman(&ctx, oracle);
        let (ratio, worst, n) = exit_error(&s, &d);
        eprintln!(
            "oracle {oracle}: {n} pixels, T2 error max {:.3e} rad ({:.3} of its rounding bound), \
             P2 error max {:.3e} ({:.3} of its bound)",
            worst.0, ratio.0, worst.1, ratio.1
        );
        assert!(n > 250, "{n} pixels");
        report.push(ratio);
    }
    let [none, point, normal, all] = [0, 1, 2, 3].map(|k| report[k]);
    assert!(normal.0 <= 1.0 && all.0 <= 1.0, "T2 with the exact normal: {} / {} of the bound", normal.0, all.0);
    assert!(point.1 <= 1.0 && all.1 <= 1.0, "P2 with the exact point: {} / {} of the bound", point.1, all.1);
    // Without the oracle, d~ misses the exit on some pixels by far more than rounding: the
    // test tells an oracle that returns the paper's values.
    assert!(none.0 > 10.0 && none.1 > 10.0 && point.0 > 10.0 && normal.1 > 10.0, "{report:?}");
}

/// With every intermediate exact, Wyman's image is the exact tracer's restricted to two
/// interfaces (`render.raytrace.max_depth = 2`: the internally reflected branch at P2 ends at
/// P3 inside the box, it never reaches the environment), except for the exit's Fresnel term:
/// per pixel the tracer gives
///   RT2 = F1 L(R) + (1 - F1) (1 - F2) L(T2)      (the (n_i/n_t)^2 scalings cancel)
///   RT1 = F1 L(R)                                (max_depth = 1: the transmitted branch ends at P2)
/// and Wyman, which weighs T2 by 1 - F1 only (§4's pseudocode has no Fresnel at P2),
///   W   = F1 L(R) + (1 - F1) L(T2),
/// so W - RT2 = F2 (W - RT1) with F2 the exit's Fresnel reflectance (1 under total internal
/// reflection, where Wyman's clamp of §3.3 refracts tangentially and the tracer reflects:
/// there the identity reads RT2 = RT1). F2 is computed here from the closed-form path.
///
/// Tolerance, per pixel: Wyman reads N1 from the RGBA16F G-buffer, the tracer from the f32
/// vertices. N1 tilted by delta = 2^-11 turns R by 2 delta, T2 by exit_error's bound, and
/// moves F1 by |F(theta_1 +- delta) - F(theta_1)|; the grid's sky is lerp(horizon, zenith, y),
/// whose radiance turns by at most 0.55 per radian, so the residual is at most
///   (1 - F2) (|dF1| 2 + F1 0.55 (2 delta) + (1 - F1) 0.55 dT2)
/// (radiance <= 2), plus 2e-5: the tracer's cutoff (1e-6, its smallest) drops at most
/// 1e-6 n^2 x 2 = 5e-6, and the sums' f32 rounding. Pixels are kept where the path is
/// robust (robust()) and the grid has no line within twice those angles of R and T2 (a line
/// is a step of ~1.5). Wrong T2s, as without the oracle, miss by degrees: lines, or the sky's
/// gradient over 0.01 rad and more.
#[test]
fn wyman_with_every_intermediate_exact_is_the_two_interface_tracer() {
    if !common::in_own_process() {
        return;
    }
    let ctx = context(false);
    let s = box_scene(&[]);
    let w = wyman(&ctx, "all");
    let rt = |depth: u32| {
        let depth = format!("render.raytrace.max_depth={depth}");
        render_on(&ctx, &box_scene(&["render.refraction=raytrace", &depth, "render.raytrace.cutoff=1e-6"])).hdr
    };
    let (rt1, rt2) = (rt(1), rt(2));
    // The grid is the same within `r` rad of d.
    let continuous = |d: Vec3, r: f32| {
        let l = prism::scene::grid_radiance(d);
        let (a, b) = d.any_orthonormal_pair();
        (1..=4).all(|k| {
            let t = r * k as f32 / 4.0;
            [a, -a, b, -b].iter().all(|&o| prism::scene::grid_radiance((d + t * o).normalize()) == l)
        })
    };
    let delta = HALF_ROUNDOFF;
    let (mut worst, mut n, mut tir) = (0.0f32, 0, 0);
    for j in 0..SIZE {
        for i in 0..SIZE {
            let Some(e) = robust(&s, i, j) else { continue };
            let (_, d) = s.camera.primary_ray(i, j);
            let theta_1 = (-d.dot(e.n1)).clamp(-1.0, 1.0).acos();
            let f1 = fresnel(theta_1.cos(), 1.0 / IOR);
            let df1 = [theta_1 - delta, theta_1 + delta]
                .map(|t| (fresnel(t.cos(), 1.0 / IOR) - f1).abs())
                .into_iter()
                .fold(0.0f32, f32::max);
            let (f2, dt2) = match e.t2 {
                // Leaving the glass: cos_i inside, eta = n.
                Some(_) => {
                    let cos_in = e.t1.dot(e.n2);
                    (fresnel(cos_in, IOR), HALF_ROUNDOFF * IOR * cos_in / e.k.sqrt() + F32_CHAIN)
                }
                None => (1.0, 0.0),
            };
            if !continuous(e.reflected, 4.0 * delta) || e.t2.is_some_and(|t| !continuous(t, 2.0 * dt2)) {
                continue;
            }
            tir += usize::from(e.t2.is_none());
            n += 1;
            let tol = (1.0 - f2) * (df1 * 2.0 + f1 * 0.55 * 2.0 * delta + (1.0 - f1) * 0.55 * dt2) + 2e-5;
            let (a, b, c) = (at(&w.hdr, i, j), at(&rt2, i, j), at(&rt1, i, j));
            let residual = ((a - b) - f2 * (a - c)).abs().max_element();
            if residual / tol > worst {
                worst = residual / tol;
                eprintln!(
                    "pixel ({i}, {j}): W {a}, RT2 {b}, RT1 {c}, F2 {f2}: residual {residual:.3e}, bound {tol:.3e}"
                );
            }
        }
    }
    eprintln!("{n} pixels ({tir} with total internal reflection at P2): largest residual {worst:.3} of its bound");
    assert!(n - tir > 200 && tir > 0, "{n} pixels, {tir} TIR");
    assert!(worst <= 1.0, "W - RT2 = F2 (W - RT1) off by {worst} of the rounding bound");
}

/// Hu & Qin's exit oracles, as Wyman's: with the exit normal exact T2 is the closed form's,
/// with the exit point exact so is P2, up to exit_error's rounding bound. Without them the
/// search of §2.1 (Figs. 7, 9) and the layer's texel (§2.1.4) are off by more on some pixels.
#[test]
fn hu_qin_oracle_exit_is_the_closed_form_exit() {
    if !common::in_own_process() {
        return;
    }
    let ctx = context(false);
    let s = box_scene(&[]);
    let mut report = Vec::new();
    for oracle in ["none", "exit_point", "exit_normal", "exit"] {
        let d = technique(&ctx, "hu_qin", oracle);
        let (ratio, worst, n) = exit_error(&s, &d);
        eprintln!(
            "hu_qin oracle {oracle}: {n} pixels, T2 error max {:.3e} rad ({:.3} of its rounding bound), \
             P2 error max {:.3e} ({:.3} of its bound)",
            worst.0, ratio.0, worst.1, ratio.1
        );
        assert!(n > 250, "{n} pixels");
        report.push(ratio);
    }
    let [none, point, normal, exit] = [0, 1, 2, 3].map(|k| report[k]);
    assert!(normal.0 <= 1.0 && exit.0 <= 1.0, "T2 with the exact normal: {} / {} of the bound", normal.0, exit.0);
    assert!(point.1 <= 1.0 && exit.1 <= 1.0, "P2 with the exact point: {} / {} of the bound", point.1, exit.1);
    assert!(none.0 > 10.0 && normal.1 > 10.0, "{report:?}");
}

/// Every oracle of both techniques renders sphere_nearby (a glass ball among diffuse objects,
/// seen through §2.2's impostors) without a validation error and finite. The nearby oracle
/// uses nothing of the lookup's search (Figs. 16, 17): its image is the same, bit for bit,
/// with the plain lookup of Fig. 13 (no correction, one seed) as with the defaults (3
/// corrections, 8 seeds), where the paper's lookup gives two different images. An oracle
/// that fell back on the paper's lookup anywhere would differ there.
#[test]
fn every_oracle_renders_a_scene_with_nearby_geometry() {
    if !common::in_own_process() {
        return;
    }
    let ctx = context(false);
    let render = |t: &str, oracle: &str, extra: &[&str]| {
        let (refraction, o) = (format!("render.refraction={t}"), format!("render.{t}.oracle=\"{oracle}\""));
        let mut overrides = vec![refraction.as_str(), o.as_str()];
        overrides.extend_from_slice(extra);
        let r = render_on(&ctx, &common::scene("sphere_nearby", 48, &overrides));
        common::assert_finite(&format!("{t} oracle {oracle} {extra:?}"), &r.hdr);
        r.hdr
    };
    for (t, names) in [("wyman", &["none", "all"][..]), ("hu_qin", &prism::scene::techniques::HuQinOracle::NAMES[..])] {
        for oracle in names {
            render(t, oracle, &[]);
        }
    }
    let plain = ["render.hu_qin.correction_iterations=0", "render.hu_qin.seed_samples=1"];
    let differing = |a: &[f32], b: &[f32]| a.iter().zip(b).filter(|(x, y)| x != y).count();
    let paper = differing(&render("hu_qin", "none", &[]), &render("hu_qin", "none", &plain));
    let oracle = differing(&render("hu_qin", "nearby", &[]), &render("hu_qin", "nearby", &plain));
    eprintln!("values that the lookup's search changes: paper's lookup {paper}, nearby oracle {oracle}");
    assert!(paper > 0, "the search changes nothing here: the test shows nothing");
    assert_eq!(oracle, 0, "the nearby oracle depends on the lookup's search");
}

/// The Hit() oracle (`render.impostor.oracle = "hit"`): on room_mirror, the mirror ball
/// reflects planar walls whose points the secant search of Szirmay-Kalos et al. 2005 (§2.2,
/// Eq. 6) approaches step by step, so its refinement steps (`render.impostor.iterations`) move
/// the reflected image: 0 steps (d_l of Eq. 4 alone) and 8 give different images. With the
/// oracle, the hit is the exact tracer's and the radiance is read towards it, so the two
/// images must be identical bit for bit: any value Hit()'s search still reached would differ.
#[test]
fn impostor_hit_oracle_is_independent_of_the_search() {
    if !common::in_own_process() {
        return;
    }
    let ctx = context(false);
    let render = |oracle: &str, iterations: u32| {
        let o = format!("render.impostor.oracle=\"{oracle}\"");
        let it = format!("render.impostor.iterations={iterations}");
        let overrides = ["render.reflection=impostor", o.as_str(), it.as_str()];
        let r = render_on(&ctx, &common::scene("room_mirror", SIZE, &overrides));
        common::assert_finite(&format!("impostor oracle {oracle}, {iterations} iterations"), &r.hdr);
        r.hdr
    };
    let differing = |a: &[f32], b: &[f32]| a.iter().zip(b).filter(|(x, y)| x != y).count();
    let paper = differing(&render("none", 0), &render("none", 8));
    let oracle = differing(&render("hit", 0), &render("hit", 8));
    eprintln!("values that Hit()'s refinement steps change: paper's Hit() {paper}, hit oracle {oracle}");
    assert!(paper > 0, "the search changes nothing here: the test shows nothing");
    assert_eq!(oracle, 0, "the hit oracle depends on Hit()'s search");
}

/// The caustic map (flux per texel, every layer) of scene `name` with caustics mapping and
/// `extra` overrides, and its total flux (W, green).
fn caustic_map(ctx: &std::sync::Arc<prism::gpu::GpuContext>, name: &str, extra: &[&str]) -> (Vec<[f32; 4]>, f64) {
    let mut o = vec!["render.caustics=caustics_map"];
    o.extend_from_slice(extra);
    let mut r = Renderer::new(ctx, &common::scene(name, 32, &o)).expect("renderer");
    r.render_frame().expect("frame");
    let (map, _) = r.read_caustic_map().expect("readback").expect("a caustic map");
    drop(r);
    common::assert_no_validation_errors(ctx);
    assert!(map.iter().flatten().all(|v| v.is_finite()), "{extra:?}: a caustic-map texel is not finite");
    let flux = map.iter().map(|v| f64::from(v[1])).sum();
    (map, flux)
}

/// The receiver oracle (`render.caustics_map.oracle = "receiver"`): on caustic_sphere, the
/// rays leaving the glass ball meet the floor at points the estimate of Shah et al. 2007
/// (§III.C, Eq. 1-2) approaches iteration by iteration, so its iteration count moves the
/// splats: 0 iterations (the receiver straight along the light ray) and 8 give different
/// caustic maps. With the oracle every ray's hit is the exact tracer's, so 0 and 8
/// iterations, and the appendix's Newton-Raphson (Eq. 4-5) in place of Eq. 1-2, must give the
/// same map bit for bit: any splat the estimate still placed would differ. And the oracle
/// places the flux rather than dropping it: every ray the ball transmits reaches the floor,
/// so the map holds the closed form of tests/caustics.rs (the light's flux through the
/// ball's solid angle times the two surfaces' Fresnel transmittance) within the same 2%
/// (the tessellated ball's grazing rays, whose exit ends in spurious total internal
/// reflection, are the grid's and the exit's, which the oracle keeps).
#[test]
fn caustics_map_receiver_oracle_is_independent_of_the_estimate() {
    if !common::in_own_process() {
        return;
    }
    let ctx = context(false);
    let differing =
        |a: &[[f32; 4]], b: &[[f32; 4]]| a.iter().flatten().zip(b.iter().flatten()).filter(|(x, y)| x != y).count();
    let render = |oracle: &str, newton: &str, iterations: u32| {
        let o = format!("render.caustics_map.oracle=\"{oracle}\"");
        let n = format!("render.caustics_map.newton=\"{newton}\"");
        let it = format!("render.caustics_map.iterations={iterations}");
        caustic_map(&ctx, "caustic_sphere", &[o.as_str(), n.as_str(), it.as_str()])
    };
    let paper = differing(&render("none", "approximate", 0).0, &render("none", "approximate", 8).0);
    let (exact, flux) = render("receiver", "approximate", 0);
    let oracle = differing(&exact, &render("receiver", "approximate", 8).0);
    let oracle_newton = differing(&exact, &render("receiver", "true", 8).0);
    let expected = common::sphere_transmitted_flux(50.0, 3.8, 1.0, 1.5);
    eprintln!(
        "caustic-map values that the receiver estimate's iterations change: paper's estimate {paper}, \
         receiver oracle {oracle} (newton = true: {oracle_newton}); oracle flux {flux:.4} W, closed form \
         {expected:.4} W"
    );
    assert!(paper > 0, "the estimate's iterations change nothing here: the test shows nothing");
    assert_eq!(oracle, 0, "the receiver oracle depends on the estimate's iterations");
    assert_eq!(oracle_newton, 0, "the receiver oracle depends on the estimate's Newton-Raphson");
    assert!((flux / expected - 1.0).abs() < 0.02, "oracle flux {flux} W, expected {expected} W");
}

/// The receiver oracle on the other caustic scenes, whose rays pass through or reflect off
/// specular objects of other kinds before they meet a receiver: caustic_bunny (a concave
/// absorbing dielectric, rays that meet the bunny again), metal_ring (a conductor, reflected
/// rays that meet the ring again), water_pool (a directional light and a single refracting
/// surface, absorption over the distance to the hit). Each map is finite and free of
/// validation errors (in `caustic_map`), and the oracle places flux rather than dropping
/// every ray.
#[test]
fn caustics_map_receiver_oracle_renders_every_caustic_scene() {
    if !common::in_own_process() {
        return;
    }
    let ctx = context(false);
    for name in ["caustic_bunny", "metal_ring", "water_pool"] {
        let (_, paper) = caustic_map(&ctx, name, &[]);
        let (_, oracle) = caustic_map(&ctx, name, &["render.caustics_map.oracle=\"receiver\""]);
        eprintln!("{name}: caustic-map flux, paper's estimate {paper:.4} W, receiver oracle {oracle:.4} W");
        assert!(oracle > 0.0, "{name}: the receiver oracle drops every ray");
    }
}

/// A square mirror standing upright (normal -x) at x = 0 over a diffuse floor (y = 0), lit
/// by a directional light travelling along (1, -1, 0) / sqrt 2: the mirror sends the light
/// down along (-1, -1, 0) / sqrt 2, onto the floor at x = -y of the mirror point. A second,
/// lying mirror at y = 0.3 crosses part of that reflected light on its way to the floor and
/// sends its own light up along (1, 1, 0) / sqrt 2 through the upright one, into the sky:
/// neither mirror is a receiver. The two do not overlap as the light sees them, nor shade
/// each other. Flat surfaces only, so the rasterized refractor layers hold the tracer's
/// planes exactly.
fn mirror_scene(overrides: &[&str]) -> Scene {
    let text = r#"
        [camera]
        position = [-3, 3, 3]
        target = [-1, 0.5, 0]
        vfov_deg = 50
        width = 32
        height = 32
        [environment]
        type = "constant"
        radiance = 0
        [[lights]]
        type = "directional"
        direction = [1, -1, 0]
        irradiance = 2
        [materials.floor]
        type = "diffuse"
        albedo = 0.8
        [materials.mirror]
        type = "mirror"
        reflectance = 0.9
        [[objects]]
        name = "floor"
        material = "floor"
        shape = "quad"
        center = [0, 0, 0]
        size = [8, 8]
        normal = [0, 1, 0]
        [[objects]]
        name = "mirror"
        material = "mirror"
        shape = "quad"
        center = [0, 1, 0.1]
        size = [1, 1]
        normal = [-1, 0, 0]
        [[objects]]
        name = "low_mirror"
        material = "mirror"
        shape = "quad"
        center = [-0.6, 0.3, 0.1]
        size = [0.6, 1]
        normal = [0, 1, 0]
    "#;
    let mut o: Vec<String> = prism::scene::BASELINE.iter().map(|s| s.to_string()).collect();
    o.push("render.caustics=caustics_map".to_string());
    o.extend(overrides.iter().map(|s| s.to_string()));
    prism::scene::load_str(text, std::path::Path::new("oracle_mirror.toml"), &o).unwrap()
}

/// The closed form of the receiver oracle's caustic map on [`mirror_scene`], traced on the
/// CPU: every grid vertex of the light's source face (src/technique/caustics/caustics_map.rs
/// `source_faces`: an orthographic box of half-side 1.02 r around the bounding sphere (c, r)
/// of the specular objects' box, its eye 2 of those half-sides before c, G^2 texels) whose
/// light ray meets a mirror reflects there and meets the floor (passing through the other
/// mirror); the splat lands where the
/// light's orthographic map (src/frame/gpu_scene.rs `lights`: half-side 1.01 R around the
/// bounding sphere (C, R) of every object and the camera, eye R before C) sees that point.
/// Every vertex carries the same flux (E times the texel's area times the reflectance,
/// Eq. 6 in physical units), so the map's flux-weighted centroid is the plain mean of those
/// points, in map texels; returns it, the number of vertices that reach the floor and the
/// source face's half-side.
fn mirror_caustic_centroid(s: &Scene, grid: u32, map_size: u32) -> (glam::DVec2, usize, f32) {
    use glam::Mat4;
    let dir = Vec3::new(1.0, -1.0, 0.0).normalize();
    let look = |centre: Vec3, half: f32, back: f32, depth: f32| {
        let eye = centre - dir * back;
        let up = if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
        Mat4::orthographic_rh(-half, half, -half, half, 0.0, depth) * Mat4::look_at_rh(eye, eye + dir, up)
    };
    let bounds = |points: &mut dyn Iterator<Item = Vec3>| {
        let (lo, hi) = points
            .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), p| (lo.min(p), hi.max(p)));
        ((lo + hi) * 0.5, (hi - lo).length() * 0.5)
    };
    let (mirrors, floor) = ([&s.objects[1].mesh, &s.objects[2].mesh], &s.objects[0].mesh);
    let (c, r) = bounds(&mut mirrors.iter().flat_map(|m| m.positions.iter().copied()));
    let source = look(c, r * 1.02, 2.0 * r * 1.02, 4.0 * r * 1.02).inverse();
    let all = s.objects.iter().flat_map(|o| o.mesh.positions.iter().copied());
    let (big_c, big_r) = bounds(&mut all.chain(std::iter::once(s.camera.position)));
    let map = look(big_c, big_r * 1.01, big_r * 1.01, 2.0 * big_r * 1.01);
    let (mut sum, mut n) = (glam::DVec2::ZERO, 0);
    for j in 0..grid {
        for i in 0..grid {
            // The texel centre's ray through the source face (NDC z 0: its near plane).
            let ndc = (glam::Vec2::new(i as f32, j as f32) + 0.5) / grid as f32 * 2.0 - 1.0;
            let o = source.project_point3(ndc.extend(0.0));
            let first = mirrors.iter().filter_map(|m| hit_mesh(m, o, dir)).min_by(|a, b| a.0.total_cmp(&b.0));
            let Some((t, normal)) = first else { continue };
            let p1 = o + t * dir;
            let reflected = dir - 2.0 * dir.dot(normal) * normal;
            let Some((t2, _)) = hit_mesh(floor, p1, reflected) else { continue };
            let clip = map.project_point3(p1 + t2 * reflected);
            sum += ((glam::Vec2::new(clip.x, clip.y) * 0.5 + 0.5) * map_size as f32).as_dvec2();
            n += 1;
        }
    }
    (sum / n.max(1) as f64, n, r * 1.02)
}

/// The receiver oracle's splats against CPU-traced hits: on [`mirror_scene`] the caustic
/// map's flux-weighted centroid (layer 0, the directional light's map) equals the mean of the
/// closed-form floor hits of the grid vertices that see a mirror, projected into the map.
/// Tolerance 0.05 map texels: float rounding of metre-sized positions is 1e-4 texel (a
/// texel is 2.02 R / 512, about 2 cm); a splat's window (offsets within 3.5 sigma of its
/// centre, sigma 1 texel) holds at most one tail texel on one side only, which moves that
/// splat's centroid by at most 3.0 exp(-4.5) / 2.5 = 0.013 texel; and a vertex whose texel
/// centre lies on the mirror's edge to float precision, which the rasterizer and the CPU
/// may count differently, moves the mean of the 3500 vertices by at most its distance from
/// the centroid (the floor patch is under 1.5 m, 65 texels, across) over 3500, 0.02 texel:
/// the bound leaves room for one or two such vertices, which only chance puts on an edge.
/// The paper's estimate without iterations puts the receiver straight along
/// the light ray from the upright mirror (at x = +y instead of -y), 2 y metres along x, which
/// the map sees foreshortened by cos 45 degrees: tens of texels off. The check fails if the
/// oracle stops at the other mirror (which the positions map of §III.B leaves out, as it
/// leaves out every specular object) or if the paper's estimate still runs.
/// The map's total flux is the closed form of those vertices: each carries E (2 h / G)^2
/// times the reflectance (h the source face's half-side); within 1e-3 (f32 sums over thousands
/// of splats, 1e-6, and a vertex counted differently at an edge, 1 / 3500 = 3e-4 each).
#[test]
fn caustics_map_receiver_oracle_splats_land_on_traced_hits() {
    if !common::in_own_process() {
        return;
    }
    let ctx = context(false);
    let centroid = |overrides: &[&str]| {
        let s = mirror_scene(overrides);
        let mut r = Renderer::new(&ctx, &s).expect("renderer");
        r.render_frame().expect("frame");
        let (map, size) = r.read_caustic_map().expect("readback").expect("a caustic map");
        drop(r);
        common::assert_no_validation_errors(&ctx);
        let (mut sum, mut flux) = (glam::DVec2::ZERO, 0.0);
        for (k, t) in map[..(size * size) as usize].iter().enumerate() {
            let at = glam::DVec2::new((k as u32 % size) as f64 + 0.5, (k as u32 / size) as f64 + 0.5);
            sum += f64::from(t[1]) * at;
            flux += f64::from(t[1]);
        }
        (sum / flux, flux, s, size)
    };
    let (oracle, flux, s, size) = centroid(&["render.caustics_map.oracle=\"receiver\""]);
    let params = prism::scene::techniques::CausticsMapParams::from_settings(&s.render).unwrap();
    let (expected, vertices, half) = mirror_caustic_centroid(&s, params.grid, size);
    // E = 2 W/m^2, reflectance 0.9 (mirror_scene).
    let texel = 2.0 * f64::from(half) / f64::from(params.grid);
    let expected_flux = vertices as f64 * 2.0 * texel * texel * 0.9;
    let (paper, _, _, _) = centroid(&["render.caustics_map.iterations=0"]);
    eprintln!(
        "mirror caustic centroid (map texels): receiver oracle {oracle:.4} ({flux:.4} W), CPU-traced {expected:.4} \
         ({vertices} vertices, {expected_flux:.4} W), paper's estimate with 0 iterations {paper:.4}"
    );
    assert!(vertices > 1000, "the mirror covers {vertices} grid vertices: the test shows little");
    assert!(
        (oracle - expected).abs().max_element() < 0.05,
        "the oracle's splats are not the traced hits: {oracle} vs {expected}"
    );
    assert!((flux / expected_flux - 1.0).abs() < 1e-3, "oracle flux {flux} W, closed form {expected_flux} W");
    assert!(
        (paper - expected).abs().max_element() > 10.0,
        "the paper's estimate is exact here: the test shows nothing"
    );
}
