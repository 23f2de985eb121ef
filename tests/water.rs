//! water_pool through its default technique (`render.refraction = "water"`,
//! src/technique/refraction/refraction_water.rs; `render.caustics = "caustics_map"`), checked
//! against SCENES.md's scene computed on the CPU: the ray through a pixel's centre meets
//! h(x, z) = 0.03 sin(4x) + 0.02 sin(5z + 1) (Newton), refracts with ior 1.33 (Snell) and meets
//! the floor y = -1.5, whose checker square and sunlit caustic are then known in closed form.
mod common;

use glam::DVec3;

const IOR: f64 = 1.33;
const FLOOR_Y: f64 = -1.5;
const SIZE: u32 = 128;

/// SCENES.md's water at t = 0 and its gradient.
/// water_pool's own techniques (its scene file), named so that the tests keep measuring them.
const WATER: &str = "render.refraction=water";
const CAUSTICS: &str = "render.caustics=caustics_map";

fn h(x: f64, z: f64) -> f64 {
    0.03 * (4.0 * x).sin() + 0.02 * (5.0 * z + 1.0).sin()
}
fn grad_h(x: f64, z: f64) -> (f64, f64) {
    (0.12 * (4.0 * x).cos(), 0.1 * (5.0 * z + 1.0).cos())
}
fn normal(x: f64, z: f64) -> DVec3 {
    let (hx, hz) = grad_h(x, z);
    DVec3::new(-hx, 1.0, -hz).normalize()
}

/// Where o + t d meets y = ripple * h(x, z): Newton on g(t) = o.y + t d.y - ripple h, from the
/// flat hit.
fn surface_hit(o: DVec3, d: DVec3, ripple: f64) -> DVec3 {
    let mut t = -o.y / d.y;
    for _ in 0..32 {
        let p = o + t * d;
        let (hx, hz) = grad_h(p.x, p.z);
        let g = p.y - ripple * h(p.x, p.z);
        let dg = d.y - ripple * (hx * d.x + hz * d.z);
        t -= g / dg;
    }
    o + t * d
}

/// Snell: the refracted unit direction for incident d, normal n facing d's origin, eta = n_i/n_t.
fn refract(d: DVec3, n: DVec3, eta: f64) -> Option<DVec3> {
    let c = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - c * c);
    (k >= 0.0).then(|| (eta * d + (eta * c - k.sqrt()) * n).normalize())
}

/// Exact unpolarised Fresnel reflectance, eta = n_i / n_t.
fn fresnel(cos_i: f64, eta: f64) -> f64 {
    let sin_t2 = eta * eta * (1.0 - cos_i * cos_i);
    if sin_t2 >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t2).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// A ray d from o through the surface (ripples scaled by `ripple`): the floor point it meets,
/// and the surface's Fresnel reflectance there.
fn through_water(o: DVec3, d: DVec3, ripple: f64) -> Option<(DVec3, f64)> {
    let p = surface_hit(o, d, ripple);
    let n = if ripple == 0.0 { DVec3::Y } else { normal(p.x, p.z) };
    let t = refract(d, n, 1.0 / IOR)?;
    let q = p + (FLOOR_Y - p.y) / t.y * t;
    Some((q, fresnel(-d.dot(n), 1.0 / IOR)))
}

/// The floor's checker square parity at q (true: albedo a): a horizontal quad's checker
/// coordinates are the world's (x, z) (src/scene/mod.rs), squares of 0.5 m
/// (glsl/include/common.glsl albedo_at).
fn square(q: DVec3) -> bool {
    ((q.x / 0.5).floor() + (q.z / 0.5).floor()).rem_euclid(2.0) == 0.0
}

fn pixel_ray(s: &prism::scene::Scene, i: f64, j: f64) -> (DVec3, DVec3) {
    // The camera's primary_ray at a fractional pixel: the centre of pixel (i, j) is (i, j).
    let c = &s.camera;
    let (o, forward) = (c.position.as_dvec3(), (c.target - c.position).as_dvec3().normalize());
    let right = forward.cross(c.up.as_dvec3()).normalize();
    let up = right.cross(forward);
    let tan_half = (f64::from(c.vfov_deg).to_radians() * 0.5).tan();
    let x = (2.0 * (i + 0.5) / f64::from(c.width) - 1.0) * tan_half;
    let y = (1.0 - 2.0 * (j + 0.5) / f64::from(c.height)) * tan_half;
    (o, (forward + x * right + y * up).normalize())
}

fn luminance(c: [f32; 3]) -> f64 {
    f64::from(0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2])
}

/// The ripples move the floor's checker edges where Snell's law says: at every pixel whose
/// square, predicted on the CPU through the rippled surface, is the same for offsets of 0.35
/// pixel around its centre (far enough from an edge for the mesh's tessellation, a tenth of a
/// pixel here, not to matter) and differs from the square seen through flat water, the image
/// shows the rippled square. The dark squares are set to albedo 0, so that a pixel is dark or
/// bright beyond doubt: over a dark square it holds only the reflected sky, F L at most
/// 0.1 x 2 (the chosen pixels have F <= 0.1; the sky's radiance is at most 2, on its lines);
/// over a bright one at least (1 - F) (1/1.33)^2 (0.8 / pi) E with E no less than the
/// caustic's minimum 0.73 x 2.87 W/m^2 (see the caustic test): 0.24. The threshold is their
/// midpoint.
#[test]
fn ripples_move_the_checker_edges_by_snells_law() {
    if !common::in_own_process() {
        return;
    }
    let s = common::scene("water_pool", SIZE, &[WATER, CAUSTICS, "materials.pool_floor.checker.b=[0, 0, 0]"]);
    let r = common::render(&s);
    common::assert_finite("water_pool", &r.hdr);
    assert!(r.passes.iter().any(|p| p == "refraction_water"), "passes {:?}", r.passes);
    let (mut checked, mut wrong) = (0, Vec::new());
    for j in 0..SIZE {
        for i in 0..SIZE {
            let (fi, fj) = (f64::from(i), f64::from(j));
            let (o, d) = pixel_ray(&s, fi, fj);
            let Some((q, f)) = through_water(o, d, 1.0) else { continue };
            if q.x.abs() > 2.9 || q.z.abs() > 2.9 || f > 0.1 {
                continue;
            }
            let rippled = square(q);
            let robust = [(-0.35, -0.35), (0.35, -0.35), (-0.35, 0.35), (0.35, 0.35)].iter().all(|(di, dj)| {
                let (o, d) = pixel_ray(&s, fi + di, fj + dj);
                through_water(o, d, 1.0).is_some_and(|(q, _)| square(q) == rippled)
            });
            let flat = through_water(o, d, 0.0).map(|(q, _)| square(q));
            if !robust || flat == Some(rippled) {
                continue;
            }
            checked += 1;
            let bright = luminance(r.radiance(i, j)) > 0.5 * (0.2 + 0.24);
            if bright != rippled {
                wrong.push((i, j, r.radiance(i, j), rippled));
            }
        }
    }
    eprintln!("{checked} pixels where the ripples change the square; {} disagree", wrong.len());
    assert!(checked >= 100, "only {checked} pixels to check");
    assert!(wrong.is_empty(), "pixels showing the flat water's square: {:?}", &wrong[..wrong.len().min(10)]);
}

/// The sun: SCENES.md's direction (0.2, -1, 0.1) normalized, irradiance 3 W/m^2.
const SUN_IRRADIANCE: f64 = 3.0;
fn sun() -> DVec3 {
    DVec3::new(0.2, -1.0, 0.1).normalize()
}

/// Where the sun's ray through (u, 0.3, w) (above the waves) lands on the floor, and the
/// surface's Fresnel transmittance on the way.
fn sun_landing(u: f64, w: f64) -> Option<(DVec3, f64)> {
    let l = sun();
    let p = surface_hit(DVec3::new(u, 0.3, w), l, 1.0);
    let n = normal(p.x, p.z);
    let t = refract(l, n, 1.0 / IOR)?;
    Some((p + (FLOOR_Y - p.y) / t.y * t, 1.0 - fresnel(-l.dot(n), 1.0 / IOR)))
}

/// The caustic's irradiance at floor point q in closed form: the flux the sun brings through
/// the plane y = 0.3 per unit area, E |L.y|, times the transmittance, over the Jacobian of
/// the map from that plane to the floor (central differences), at the preimage found by
/// Newton's method (the 1.5 m deep pool is far short of the ripples' focal length of about
/// 8 m, so the map is one to one). Also the preimage, to stay clear of the walls.
fn caustic_at(q: DVec3) -> Option<(f64, f64, f64)> {
    let land = |u: f64, w: f64| sun_landing(u, w).map(|(p, t)| (p.x, p.z, t));
    let jacobian = |u: f64, w: f64| -> Option<[f64; 4]> {
        let e = 1e-4;
        let (a, b) = (land(u + e, w)?, land(u - e, w)?);
        let (c, d) = (land(u, w + e)?, land(u, w - e)?);
        Some([(a.0 - b.0) / (2.0 * e), (c.0 - d.0) / (2.0 * e), (a.1 - b.1) / (2.0 * e), (c.1 - d.1) / (2.0 * e)])
    };
    let l = sun();
    // Flat water's offset as the first guess.
    let (mut u, mut w) = (q.x, q.z);
    for _ in 0..20 {
        let (x, z, _) = land(u, w)?;
        let [a, b, c, d] = jacobian(u, w)?;
        let det = a * d - b * c;
        let (rx, rz) = (x - q.x, z - q.z);
        u -= (d * rx - b * rz) / det;
        w -= (-c * rx + a * rz) / det;
    }
    let (x, z, t) = land(u, w)?;
    if (x - q.x).hypot(z - q.z) > 1e-6 {
        return None;
    }
    let [a, b, c, d] = jacobian(u, w)?;
    Some((SUN_IRRADIANCE * -l.y * t / (a * d - b * c).abs(), u, w))
}

/// The sun's caustic on the floor, seen through the water: with the floor's albedo made
/// uniform (0.8), the light caustics mapping adds to a pixel is (1 - F) (1/1.33)^2 (0.8 / pi)
/// E, E the caustic's irradiance at the floor point the pixel's refracted ray meets. E in
/// closed form (`caustic_at`) varies over the floor by about 15% on average around its flat
/// value E |L.y| T = 2.87 W/m^2 (measured below on the CPU: the ripples' second derivatives
/// 0.48 and 0.5 m^-1, times the depth and 1 - 1/1.33, are 0.18 and 0.19). The image must show
/// that pattern, not a uniform or missing caustic: its mean relative error is held to a third
/// of the pattern's own mean deviation, and its mean to the caustic flux test's 3%
/// (tests/caustics.rs: the map's flux over the water).
#[test]
fn the_suns_caustic_shows_on_the_floor_through_the_water() {
    if !common::in_own_process() {
        return;
    }
    let uniform = "materials.pool_floor.checker.b=[0.8, 0.8, 0.8]";
    let s = common::scene("water_pool", SIZE, &[WATER, CAUSTICS, uniform]);
    let with = common::render(&s);
    let without = common::render(&common::scene("water_pool", SIZE, &[WATER, uniform, "render.caustics=\"none\""]));
    let (mut n, mut err, mut modulation, mut ratio) = (0.0, 0.0, 0.0, 0.0);
    for j in (0..SIZE).step_by(2) {
        for i in (0..SIZE).step_by(2) {
            let (o, d) = pixel_ray(&s, f64::from(i), f64::from(j));
            let Some((q, f)) = through_water(o, d, 1.0) else { continue };
            if q.x.abs() > 2.5 || q.z.abs() > 2.5 {
                continue;
            }
            let Some((e, u, w)) = caustic_at(q) else { continue };
            if u.abs() > 2.9 || w.abs() > 2.9 {
                continue;
            }
            let flat = SUN_IRRADIANCE * -sun().y * (1.0 - fresnel(-sun().y, 1.0 / IOR));
            let added = luminance(with.radiance(i, j)) - luminance(without.radiance(i, j));
            let seen = added / ((1.0 - f) / (IOR * IOR) * 0.8 / std::f64::consts::PI);
            n += 1.0;
            err += (seen / e - 1.0).abs();
            modulation += (e / flat - 1.0).abs();
            ratio += seen / e;
        }
    }
    let (err, modulation, ratio) = (err / n, modulation / n, ratio / n);
    eprintln!(
        "{n} floor pixels: caustic error {err:.4} (relative, mean), its pattern {modulation:.4}, mean ratio {ratio:.4}"
    );
    assert!(n >= 500.0, "only {n} floor pixels");
    assert!(modulation > 0.1, "the closed form shows no caustic: {modulation}");
    assert!(
        err < modulation / 3.0,
        "the image's caustic is off by {err} of the closed form (its pattern: {modulation})"
    );
    assert!((ratio - 1.0).abs() < 0.03, "the caustic's mean is {ratio} of the closed form");
}
