//! What eikonal view rays meet when they leave the volume or are reflected at its boundary
//! (Ihrke et al. 2007, ../shared/papers/ihrke2007-eikonal-rendering.md, §5.3 and §6).
//!
//! Section 5.3 looks up only the environment map in the exit direction. For its Fig. 7
//! comparison the paper "replaced the environment map lookup by a ray-plane intersection in
//! the fragment shader. More complex nearby geometry can be rendered accurately using the
//! approach of Hu and Qin [2007]." Both are here, chosen by `render.eikonal.nearby`:
//!
//! - `"exact"` (the default; it measured more accurate, docs/BENCHMARKS.md and the report):
//!   the flat diffuse receivers (quads and boxes: flat faces, so the face normal is the
//!   shading normal) go to eikonal_view as a triangle list ([`exact_triangles`], at most
//!   [`MAX_EIKONAL_TRIANGLES`]) that glsl/eikonal/nearby_exit.glsl intersects exactly
//!   (Moller-Trumbore, [`ray_triangle`] is the CPU twin) and shades like deferred shading. The
//!   other nearby objects (meshes, spheres, mirrors, ...) go through impostor rectangles.
//! - `"impostor"`: every nearby object through Hu & Qin 2007 §2.2's impostor rectangles with
//!   O_R = the volume's centre (src/technique/refraction/nearby_impostors.rs, glsl/include/nearby.glsl's
//!   Fig. 16 lookup with `render.eikonal.nearby_iterations` correction iterations).
//! - `"off"`: the environment only (the paper's section 5.3).
//!
//! The floor under the volume must show the volume's caustic and shadow: the light
//! simulation (src/technique/eikonal/eikonal_light.rs) has already run when the renderer is created, so
//! both the exact shading and the impostor textures (glsl/eikonal/nearby_impostor.frag)
//! replace the light's direct term by the simulated irradiance exactly as the
//! `eikonal_light` receiver pass does for the camera (glsl/eikonal/receiver.glsl).
use glam::{Vec2, Vec3};

use crate::reference::bvh::moller_trumbore;
use crate::scene::techniques::EikonalNearby;
use crate::scene::{Material, Scene};
pub use crate::shader_structs::GpuTriangle;
pub use crate::MAX_EIKONAL_TRIANGLES;

impl GpuTriangle {
    pub fn corners(&self) -> [Vec3; 3] {
        let p0 = Vec3::from_slice(&self.p0[..3]);
        [p0, p0 + Vec3::from_slice(&self.e1[..3]), p0 + Vec3::from_slice(&self.e2[..3])]
    }
}

/// Objects whose flat faces are intersected exactly: diffuse quads and boxes.
fn is_flat_diffuse(scene: &Scene, object: usize) -> bool {
    let o = &scene.objects[object];
    matches!(scene.materials[o.material], Material::Diffuse { .. }) && (o.shape == "quad" || o.shape == "box")
}

/// The triangles of the exactly intersected receivers in `"exact"` mode, object by object
/// while they fit [`MAX_EIKONAL_TRIANGLES`], and the objects whose triangles did not fit
/// (those go to the impostors).
pub fn exact_triangles(scene: &Scene, mode: EikonalNearby) -> (Vec<(usize, GpuTriangle)>, Vec<usize>) {
    let (mut tris, mut overflow) = (Vec::new(), Vec::new());
    if mode != EikonalNearby::Exact {
        return (tris, overflow);
    }
    for i in (0..scene.objects.len()).filter(|&i| is_flat_diffuse(scene, i)) {
        let m = &scene.objects[i].mesh;
        let n = m.indices.len() / 3;
        if tris.len() + n > MAX_EIKONAL_TRIANGLES as usize {
            overflow.push(i);
            continue;
        }
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|k| k as usize);
            let (p0, p1, p2) = (m.positions[a], m.positions[b], m.positions[c]);
            let uv = |k: usize| m.checker_uv.get(k).copied().unwrap_or(Vec2::ZERO);
            let (u0, u1, u2) = (uv(a), uv(b), uv(c));
            tris.push((
                i,
                GpuTriangle {
                    p0: p0.extend(0.0).to_array(),
                    e1: (p1 - p0).extend(0.0).to_array(),
                    e2: (p2 - p0).extend(0.0).to_array(),
                    uv01: [u0.x, u0.y, u1.x, u1.y],
                    uv2: [u2.x, u2.y, scene.objects[i].material as f32, 0.0],
                },
            ));
        }
    }
    (tris, overflow)
}

/// The objects that get an impostor rectangle around the volume: every non-dielectric object
/// not intersected exactly (none with `"off"`). The nearest [`crate::MAX_NEARBY_RECTS`] are
/// kept by [`crate::technique::refraction::nearby_impostors::nearby_objects`].
pub fn impostor_candidates(scene: &Scene, mode: EikonalNearby) -> Vec<usize> {
    if mode == EikonalNearby::Off {
        return Vec::new();
    }
    let (tris, overflow) = exact_triangles(scene, mode);
    (0..scene.objects.len())
        .filter(|&i| !matches!(scene.materials[scene.objects[i].material], Material::Dielectric { .. }))
        .filter(|&i| !tris.iter().any(|(o, _)| *o == i) || overflow.contains(&i))
        .collect()
}

/// O_R of the rectangles: the centre of the volume's box.
pub fn volume_origin(scene: &Scene) -> Option<Vec3> {
    scene.volume.as_ref().map(|v| 0.5 * (v.min + v.max))
}

/// Objects of [`impostor_candidates`] kept as rectangles (nearest first), and the dropped.
pub fn impostor_objects(scene: &Scene, mode: EikonalNearby) -> (Vec<usize>, Vec<usize>) {
    let Some(origin) = volume_origin(scene) else { return (Vec::new(), Vec::new()) };
    let candidates = impostor_candidates(scene, mode);
    let (kept, dropped) = crate::technique::refraction::nearby_impostors::nearby_objects(scene, origin);
    (
        kept.into_iter().filter(|i| candidates.contains(i)).collect(),
        dropped.into_iter().filter(|i| candidates.contains(i)).collect(),
    )
}

/// Whether any exactly intersected triangle reaches into the volume's box (grown by
/// `margin`): then eikonal_view tests every march step against the triangles (a floor that
/// the volume touches, or that crosses it), not only the exit ray.
pub fn triangles_meet_box(tris: &[GpuTriangle], min: Vec3, max: Vec3, margin: f32) -> bool {
    let (lo, hi) = (min - Vec3::splat(margin), max + Vec3::splat(margin));
    tris.iter().any(|t| {
        // Conservative: the triangle's bounds overlap the box's.
        let c = t.corners();
        let (tmin, tmax) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
        tmin.cmple(hi).all() && tmax.cmpge(lo).all()
    })
}

/// Storage-buffer bytes of the triangle list: a uvec4 header (x: count), then the
/// triangles (one zero triangle when there are none: a binding may not be empty).
pub fn triangle_buffer_bytes(tris: &[GpuTriangle]) -> Vec<u8> {
    let mut bytes = bytemuck::bytes_of(&[tris.len() as u32, 0, 0, 0]).to_vec();
    if tris.is_empty() {
        bytes.extend_from_slice(bytemuck::bytes_of(&GpuTriangle::default()));
    }
    for t in tris {
        bytes.extend_from_slice(bytemuck::bytes_of(t));
    }
    bytes
}

/// Moller & Trumbore 1997: the hit (t > `t_min`, barycentrics b1, b2) of `o + t d` with the
/// triangle (p0, e1, e2). Rays parallel to its plane (|det| <= 1e-12 |e1||e2||d|) miss: no
/// division by ~0. glsl/eikonal/nearby_exit.glsl's `eik_triangle_hit` is the same
/// computation (two-sided).
pub fn ray_triangle(o: Vec3, d: Vec3, p0: Vec3, e1: Vec3, e2: Vec3, t_min: f32) -> Option<(f32, f32, f32)> {
    let scale = e1.length() * e2.length() * d.length();
    let parallel = |det: f32| det.is_nan() || det.abs() <= 1e-12 * scale.max(1e-30);
    let (b1, b2, t) = moller_trumbore(o, d, p0, e1, e2, parallel)?;
    let inside = (0.0..=1.0).contains(&b1) && b2 >= 0.0 && b1 + b2 <= 1.0;
    (inside && t.is_finite() && t > t_min).then_some((t, b1, b2))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ray from above onto the unit right triangle in y = 0: t is the height, the
    /// barycentrics the hit's coordinates along the edges; parallel, grazing, backwards and
    /// NaN rays miss without NaN.
    #[test]
    fn ray_triangle_analytic() {
        let (p0, e1, e2) = (Vec3::ZERO, Vec3::X, Vec3::Z);
        let (t, b1, b2) = ray_triangle(Vec3::new(0.25, 2.0, 0.5), -Vec3::Y, p0, e1, e2, 0.0).unwrap();
        assert!((t - 2.0).abs() < 1e-6 && (b1 - 0.25).abs() < 1e-6 && (b2 - 0.5).abs() < 1e-6);
        // Oblique: from (0, 1, 0) towards (0.3, 0, 0.3), t = |(0.3, -1, 0.3)|.
        let d = Vec3::new(0.3, -1.0, 0.3);
        let (t, b1, b2) = ray_triangle(Vec3::Y, d.normalize(), p0, e1, e2, 0.0).unwrap();
        assert!((t - d.length()).abs() < 1e-5 && (b1 - 0.3).abs() < 1e-5 && (b2 - 0.3).abs() < 1e-5);
        // Two-sided: from below.
        assert!(ray_triangle(Vec3::new(0.25, -1.0, 0.25), Vec3::Y, p0, e1, e2, 0.0).is_some());
        // Outside, behind, parallel (grazing the plane), degenerate.
        assert_eq!(ray_triangle(Vec3::new(0.8, 1.0, 0.8), -Vec3::Y, p0, e1, e2, 0.0), None);
        assert_eq!(ray_triangle(Vec3::new(0.25, 1.0, 0.25), Vec3::Y, p0, e1, e2, 0.0), None);
        assert_eq!(ray_triangle(Vec3::new(-1.0, 0.0, 0.25), Vec3::X, p0, e1, e2, 0.0), None);
        assert_eq!(ray_triangle(Vec3::new(-1.0, 1e-3, 0.25), Vec3::X, p0, e1, e2, 0.0), None);
        assert_eq!(ray_triangle(Vec3::Y, Vec3::ZERO, p0, e1, e2, 0.0), None);
        assert_eq!(ray_triangle(Vec3::Y, Vec3::splat(f32::NAN), p0, e1, e2, 0.0), None);
    }

    fn scene(name: &str) -> Scene {
        crate::scene::load(&crate::scene::benchmark_scene_path(name), &[]).unwrap()
    }

    /// eikonal_sphere's floor is two exact triangles covering y = 0 and no impostor;
    /// "impostor" gives it a rectangle instead; "off" neither; scenes without objects nothing.
    #[test]
    fn receivers_per_mode() {
        let s = scene("eikonal_sphere");
        let (tris, overflow) = exact_triangles(&s, EikonalNearby::Exact);
        assert_eq!((tris.len(), overflow.len()), (2, 0));
        assert!(tris.iter().all(|(_, t)| t.corners().iter().all(|c| c.y.abs() < 1e-6)));
        assert!(impostor_objects(&s, EikonalNearby::Exact).0.is_empty());
        assert_eq!(impostor_objects(&s, EikonalNearby::Impostor).0, vec![0]);
        assert!(impostor_objects(&s, EikonalNearby::Off).0.is_empty());
        assert!(exact_triangles(&s, EikonalNearby::Off).0.is_empty());
        let v = s.volume.as_ref().unwrap();
        let t: Vec<_> = tris.iter().map(|(_, t)| *t).collect();
        // The box sits 0.15 above the floor: no per-step test; the wine glass stands on it.
        assert!(!triangles_meet_box(&t, v.min, v.max, 0.01));
        let w = scene("eikonal_wine_glass");
        let wt: Vec<_> = exact_triangles(&w, EikonalNearby::Exact).0.into_iter().map(|(_, t)| t).collect();
        let wv = w.volume.as_ref().unwrap();
        assert!(triangles_meet_box(&wt, wv.min, wv.max, 0.01));
        let l = scene("eikonal_luneburg");
        assert!(exact_triangles(&l, EikonalNearby::Exact).0.is_empty());
        assert!(impostor_objects(&l, EikonalNearby::Impostor).0.is_empty());
        assert_eq!(triangle_buffer_bytes(&[]).len(), 16 + 80);
    }
}
