//! The object mask: the pixels a scene's techniques touch, so that an error can be given over
//! them beside the whole image. A technique wrong only on an object that covers a fraction f
//! of the image shows a whole-image MSE f times its MSE over the object: the pixels around
//! it, drawn the same way by every technique and by the reference, dilute it (f = 0.40 for
//! sphere_env's ball, 0.22 for caustic_sphere's, and smaller still for a distant object).
//!
//! Which pixels count: pixel (i, j) is in the mask when the ray through its centre
//! ([`Camera::primary_ray`], SCENES.md's pixel convention, the reference's camera ray) first
//! meets, before any other surface,
//!
//! - a specular object (dielectric, mirror or conductor): the refraction and reflection
//!   techniques shade exactly these (every one of them, even `single`, replaces the surface's
//!   shading with its approximation of the specular chain);
//! - with a caustics technique selected (`render.caustics` other than `none`), also a diffuse
//!   object: every caustics technique lights the diffuse objects as its receivers
//!   (caustics_map's receiver draws, photon_buffer's and impostor_lightmap's receivers are the
//!   diffuse objects), so its error can lie on any of them (the "diffuse mask");
//! - the region of a `[volume]` (its sphere, or its box), met before any surface: the eikonal
//!   renderer draws every pixel whose ray crosses it.
//!
//! Surfaces seen through a specular object are in the mask through that object's pixels; a
//! diffuse surface seen directly is not (without caustics the techniques all shade it by the
//! same direct light and shadow map, whose error is the baseline's, not the technique's).
//! The rays meet the reference's exact geometry ([`TracePrimitives`]: exact spheres, the
//! meshes' triangles), so a tessellated sphere's silhouette differs from the mask by at most
//! its outermost pixels.
use glam::Vec3;

use crate::reference::TracePrimitives;
use crate::scene::Scene;

/// The pixels a scene's techniques touch (see the module header) and what they show.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectMask {
    pub width: u32,
    pub height: u32,
    /// Row-major, row 0 at the top: whether the pixel is in the mask.
    pub pixels: Vec<bool>,
    /// The surfaces seen in the mask, each with its role and its pixel count, in scene order
    /// (e.g. "ball (dielectric): 6473 px").
    pub surfaces: Vec<String>,
}

/// What a ray first meets.
#[derive(Clone, Copy, Debug, PartialEq)]
enum First {
    Object(usize),
    Volume,
}

impl ObjectMask {
    /// The mask of `scene` from its camera, one centre ray per pixel.
    pub fn of_scene(scene: &Scene) -> ObjectMask {
        let prims = TracePrimitives::new(scene);
        let caustics = scene.render.caustics != "none";
        let counted = |first: First| match first {
            First::Object(o) => {
                let m = scene.material_of(&scene.objects[o]);
                m.is_specular() || (caustics && m.is_diffuse())
            }
            First::Volume => true,
        };
        let (w, h) = (scene.camera.width, scene.camera.height);
        let mut pixels = Vec::with_capacity((w * h) as usize);
        let mut objects = vec![0usize; scene.objects.len()];
        let mut volume = 0usize;
        for j in 0..h {
            for i in 0..w {
                let (o, d) = scene.camera.primary_ray(i, j);
                let surface = prims.closest(o, d, f32::INFINITY);
                let region = scene.volume.as_ref().and_then(|v| volume_entry(v, o, d));
                let first = match (surface, region) {
                    (Some((ts, _)), Some(tv)) if tv < ts => Some(First::Volume),
                    (None, Some(_)) => Some(First::Volume),
                    (Some((_, obj)), _) => Some(First::Object(obj)),
                    (None, None) => None,
                };
                let inside = first.is_some_and(counted);
                if inside {
                    match first {
                        Some(First::Object(obj)) => objects[obj] += 1,
                        _ => volume += 1,
                    }
                }
                pixels.push(inside);
            }
        }
        let mut surfaces: Vec<String> = scene
            .objects
            .iter()
            .zip(&objects)
            .filter(|(_, &n)| n > 0)
            .map(|(o, n)| {
                let m = scene.material_of(o);
                let role = if m.is_diffuse() { "diffuse caustic receiver" } else { m.kind_name() };
                format!("{} ({role}): {n} px", o.name)
            })
            .collect();
        if volume > 0 {
            let name = scene.volume.as_ref().map(|v| v.name.as_str()).unwrap_or("volume");
            surfaces.push(format!("{name} (volume): {volume} px"));
        }
        ObjectMask { width: w, height: h, pixels, surfaces }
    }

    /// Pixels in the mask.
    pub fn count(&self) -> usize {
        self.pixels.iter().filter(|&&p| p).count()
    }

    /// The mask as an RGBA8 image: white inside, black outside (for `--images`).
    pub fn to_rgba8(&self) -> Vec<u8> {
        self.pixels.iter().flat_map(|&p| if p { [255; 4] } else { [0, 0, 0, 255] }).collect()
    }
}

/// Where the ray `o + t d` (d unit length) enters the volume's region, t >= 0 (0 when it
/// starts inside): its sphere for an analytic profile with a spherical region, else its box,
/// as the reference bounds it (src/reference/mod.rs, `volume_uniforms`).
fn volume_entry(v: &crate::scene::Volume, o: Vec3, d: Vec3) -> Option<f32> {
    match v.index.region().filter(|_| v.regions.is_empty()) {
        Some((c, r)) if r > 0.0 => {
            let oc = o - c;
            let b = oc.dot(d);
            let disc = b * b - (oc.length_squared() - r * r);
            if disc < 0.0 {
                return None;
            }
            let (near, far) = (-b - disc.sqrt(), -b + disc.sqrt());
            (far > 0.0).then_some(near.max(0.0))
        }
        _ => {
            let inv = d.recip();
            let (t0, t1) = ((v.min - o) * inv, (v.max - o) * inv);
            let near = t0.min(t1).max_element().max(0.0);
            let far = t0.max(t1).min_element();
            (near <= far).then_some(near)
        }
    }
}
