//! Dragging objects and the light in the 3D view: Ctrl + left drag moves the object under
//! the cursor, Shift + left drag moves light 0, both in the plane through the grabbed point
//! that faces the camera. Pure CPU geometry; the window turns the result into the same
//! `objects.N.center` / `lights.0.position` overrides the overlay's fields edit.
use glam::{Vec2, Vec3};

use crate::reference::bvh::intersect_triangle;
use crate::scene::{Camera, Scene};

/// The camera ray through window position `cursor` (pixels, origin top-left).
pub fn cursor_ray(cam: &Camera, cursor: Vec2, width: u32, height: u32) -> (Vec3, Vec3) {
    let tan_y = (cam.vfov_deg.to_radians() * 0.5).tan();
    let ndc = Vec2::new(cursor.x / width.max(1) as f32, cursor.y / height.max(1) as f32) * 2.0 - 1.0;
    let dir_view = Vec3::new(ndc.x * tan_y * width as f32 / height.max(1) as f32, -ndc.y * tan_y, -1.0);
    let inv_view = cam.view().inverse();
    (cam.position, inv_view.transform_vector3(dir_view).normalize())
}

/// The nearest object hit by the ray among `candidates` (object indices): (index, distance).
pub fn pick(scene: &Scene, candidates: &[usize], o: Vec3, d: Vec3) -> Option<(usize, f32)> {
    let mut best: Option<(usize, f32)> = None;
    for &i in candidates {
        let m = &scene.objects[i].mesh;
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| m.positions[t[k] as usize]);
            if let Some(dist) = intersect_triangle(o, d, a, b, c) {
                if best.is_none_or(|(_, bd)| dist < bd) {
                    best = Some((i, dist));
                }
            }
        }
    }
    best
}

/// How far the grabbed point `anchor` moves when the cursor goes from `from` to `to`: both
/// cursor rays meet the plane through `anchor` perpendicular to the view direction.
pub fn drag_delta(cam: &Camera, anchor: Vec3, from: Vec2, to: Vec2, width: u32, height: u32) -> Vec3 {
    let forward = (cam.target - cam.position).normalize_or_zero();
    let on_plane = |cursor: Vec2| {
        let (o, d) = cursor_ray(cam, cursor, width, height);
        let denom = d.dot(forward);
        // A ray parallel to the plane (cannot happen for a ray inside the view frustum).
        if denom.abs() < 1e-6 {
            return None;
        }
        Some(o + d * ((anchor - o).dot(forward) / denom))
    };
    match (on_plane(from), on_plane(to)) {
        (Some(a), Some(b)) if (b - a).is_finite() => b - a,
        _ => Vec3::ZERO,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Scene {
        crate::scene::load(
            &crate::scene::benchmark_scene_path("sphere_nearby"),
            &["camera.width=200".into(), "camera.height=100".into()],
        )
        .unwrap()
    }

    #[test]
    fn the_ray_through_the_image_centre_is_the_view_direction() {
        let s = scene();
        let (o, d) = cursor_ray(&s.camera, Vec2::new(100.0, 50.0), 200, 100);
        assert_eq!(o, s.camera.position);
        assert!(d.distance((s.camera.target - s.camera.position).normalize()) < 1e-5);
        // Agrees with the renderer's primary ray at a pixel centre.
        let (_, p) = s.camera.primary_ray(30, 70);
        let (_, q) = cursor_ray(&s.camera, Vec2::new(30.5, 70.5), 200, 100);
        assert!(p.distance(q) < 1e-5, "{p} {q}");
    }

    #[test]
    fn picking_finds_the_ball_in_front_of_the_wall() {
        let s = scene();
        let all: Vec<usize> = (0..s.objects.len()).collect();
        let (o, d) = cursor_ray(&s.camera, Vec2::new(100.0, 50.0), 200, 100);
        let (i, dist) = pick(&s, &all, o, d).expect("the view centre sees the ball");
        assert_eq!(s.objects[i].name, "ball");
        assert!((dist - (s.camera.position.length() - 1.0)).abs() < 0.05, "{dist}");
    }

    #[test]
    fn dragging_moves_the_grabbed_point_with_the_cursor() {
        let s = scene();
        let anchor = Vec3::ZERO;
        let (w, h) = (200, 100);
        let from = Vec2::new(100.0, 50.0);
        let to = Vec2::new(140.0, 50.0);
        let delta = drag_delta(&s.camera, anchor, from, to, w, h);
        // The moved point lies on the cursor's new ray, and in the plane facing the camera.
        let (o, d) = cursor_ray(&s.camera, to, w, h);
        let p = anchor + delta;
        assert!((p - o).normalize().distance(d) < 1e-4);
        let forward = (s.camera.target - s.camera.position).normalize();
        assert!(delta.dot(forward).abs() < 1e-5);
        assert!(delta.x > 0.0, "right on screen is +x for this camera: {delta}");
        assert_eq!(drag_delta(&s.camera, anchor, from, from, w, h), Vec3::ZERO);
    }
}
