//! `prism render --targets`: every image of the frame graph in one multi-part OpenEXR file,
//! read back here with the `exr` crate and checked against the renderer's own list, the
//! `--exr` output, and the scene's geometry.
mod common;

use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

use exr::prelude::*;
use glam::Vec3;
use prism::renderer::Renderer;

const SIZE: u32 = 64;

/// caustic_sphere with its own techniques (hu_qin with nearby impostors and back-face
/// layers, caustics_map, shadow map), the atlases made small so that the file stays a few MB.
const OVERRIDES: [&str; 2] = ["render.shadow_map_size=64", "render.caustics_map.map_size=64"];

/// Every part of a multi-part EXR: name -> (width, height, channels by name).
type Parts = std::collections::BTreeMap<String, (usize, usize, Vec<(String, Vec<f32>)>)>;

fn read_parts(path: &Path) -> Parts {
    let image = read_all_flat_layers_from_file(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    image
        .layer_data
        .into_iter()
        .map(|layer| {
            let name = layer.attributes.layer_name.map(|t| t.to_string()).unwrap_or_default();
            let channels = layer
                .channel_data
                .list
                .into_iter()
                .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
                .collect();
            (name, (layer.size.width(), layer.size.height(), channels))
        })
        .collect()
}

fn channel<'a>(parts: &'a Parts, part: &str, name: &str) -> &'a [f32] {
    let (_, _, channels) = parts.get(part).unwrap_or_else(|| panic!("no part {part} in {:?}", parts.keys()));
    &channels.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("{part} has no channel {name}")).1
}

/// The unit ray from the camera through (x, y) in pixels (y down): glam's right-handed
/// look-at, the vertical field of view of 40 degrees, row 0 at the top (SCENES.md).
fn camera_ray(x: f32, y: f32) -> (Vec3, Vec3) {
    let (eye, target) = (Vec3::new(0.0, 3.0, 5.0), Vec3::new(0.0, 0.5, 0.0));
    let forward = (target - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let t = (40f32.to_radians() / 2.0).tan();
    let (u, v) = (2.0 * x / SIZE as f32 - 1.0, 1.0 - 2.0 * y / SIZE as f32);
    (eye, (forward + u * t * right + v * t * up).normalize())
}

/// The ball's outward unit normal where the ray through (x, y) first meets it.
fn ball_normal(x: f32, y: f32) -> Vec3 {
    let (eye, d) = camera_ray(x, y);
    let center = Vec3::new(0.0, 1.2, 0.0);
    let oc = eye - center;
    let b = oc.dot(d);
    let t = -b - (b * b - (oc.length_squared() - 1.0)).sqrt();
    (eye + t * d - center).normalize()
}

/// The object the camera ray through (x, y) in pixels (y down) meets first in
/// caustic_sphere (assets/scenes/caustic_sphere.toml): 0 the floor quad, 1 the ball, `None`
/// nothing. The scene's geometry in closed form, independent of the renderer.
fn hits_geometry(x: f32, y: f32) -> Option<u32> {
    let (eye, d) = camera_ray(x, y);
    // Floor: y = 0, |x|, |z| <= 4.
    let floor = d.y < 0.0 && {
        let p = eye + d * (-eye.y / d.y);
        p.x.abs() <= 4.0 && p.z.abs() <= 4.0
    };
    // Ball: centre (0, 1.2, 0), radius 1.
    let oc = eye - Vec3::new(0.0, 1.2, 0.0);
    let b = oc.dot(d);
    // The ball is above the floor and the camera above both: where a ray meets both, the
    // ball is in front.
    let ball = b * b - (oc.length_squared() - 1.0) >= 0.0 && b < 0.0;
    if ball {
        Some(1)
    } else if floor {
        Some(0)
    } else {
        None
    }
}

#[test]
fn every_image_of_the_frame_is_one_part_of_the_targets_exr() {
    if !common::in_own_process() {
        return;
    }
    let scratch = common::ScratchDir::new("prism-targets");
    let dir = scratch.path();
    let size = SIZE.to_string();
    let sets: Vec<&str> = OVERRIDES.iter().flat_map(|s| ["--set", s]).collect();
    let out = Command::new(env!("CARGO_BIN_EXE_prism"))
        .args(["render", "caustic_sphere", "--width", &size, "--height", &size, "--validation"])
        .args(["-o", "out.png", "--exr", "out.exr", "--targets", "targets.exr"])
        .args(&sets)
        .current_dir(dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");

    // The renderer's list of the same scene's images, after the same one frame.
    let names = {
        let ctx = common::context(false);
        let scene = common::shipped("caustic_sphere", SIZE, &OVERRIDES);
        let mut r = Renderer::new(&ctx, &scene).unwrap();
        r.render_frame().unwrap();
        let images = r.frame_images();
        // The generic read-back of the HDR target is the renderer's own read_hdr.
        let hdr = images.iter().find(|i| i.name == "hdr").expect("the graph lists the HDR target");
        assert_eq!(r.read_frame_image(hdr).unwrap().unwrap(), r.read_hdr().unwrap());
        let names: BTreeSet<String> = images
            .iter()
            .filter(|i| i.unreadable.is_none())
            .flat_map(|i| {
                let layers = i.layers * i.depth;
                (0..layers).map(move |l| if layers == 1 { i.name.clone() } else { format!("{}.{l}", i.name) })
            })
            .collect();
        drop(r);
        common::assert_no_validation_errors(&ctx);
        names
    };
    // What the issue names: G-buffer, back-face layers, impostor textures, caustic maps.
    for part in [
        "gbuf_normal",
        "depth",
        "hdr",
        "refraction_hu_qin_layers_1_depth",
        "refraction_hu_qin_nearby_texture",
        "caustic_atlas.0",
        "shadow_atlas.5",
    ] {
        assert!(names.contains(part), "{part} missing from the renderer's list {names:?}");
    }

    let parts = read_parts(&dir.join("targets.exr"));
    let written: BTreeSet<String> = parts.keys().cloned().collect();
    assert_eq!(written, names, "the EXR's parts are not the graph's images");
    for (name, (w, h, channels)) in &parts {
        let n = channels.len();
        assert!(channels.iter().all(|(_, v)| v.len() == w * h), "{name}: {n} channels of {w}x{h}");
    }

    // The HDR part is the `--exr` output texel for texel (bitwise: both are f32 copies).
    let exr = read_parts(&dir.join("out.exr"));
    let (_, (w, h, _)) = exr.iter().next().unwrap();
    assert_eq!((*w, *h), (SIZE as usize, SIZE as usize));
    let radiance = |parts: &Parts, part: &str| -> Vec<u32> {
        let [r, g, b] = ["R", "G", "B"].map(|c| channel(parts, part, c));
        (0..r.len()).flat_map(|i| [r[i], g[i], b[i]]).map(f32::to_bits).collect()
    };
    let main = exr.keys().next().unwrap().clone();
    assert_eq!(radiance(&parts, "hdr"), radiance(&exr, &main));
    assert!(channel(&parts, "hdr", "R").iter().any(|&v| v > 0.0), "the HDR target is black");

    // Depth is reversed Z with an infinite far plane (src/renderer/mod.rs
    // camera_projection): 0 where the ray meets nothing, > 0 on the floor and the ball.
    // The G-buffer (glsl/gbuffer/gbuffer.frag) holds the unit world normal in gbuf_normal's
    // RGB and the object index in gbuf_albedo's A, both RGBA16F: the floor's normal (0, 1, 0)
    // and the indices 0 and 1 are exact in half floats, a unit normal's length is 1 to
    // within three half-float roundings of its components (3 * 2^-11 < 2e-3).
    // Pixels an outline crosses (centre and corners disagree) are left out.
    let depth = channel(&parts, "depth", "Z");
    let normal = ["R", "G", "B"].map(|c| channel(&parts, "gbuf_normal", c));
    let object = channel(&parts, "gbuf_albedo", "A");
    let mut counts = [0; 3];
    for j in 0..SIZE {
        for i in 0..SIZE {
            let (x, y) = (i as f32, j as f32);
            let corners = [(0.5, 0.5), (0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
            let samples = corners.map(|(a, b)| hits_geometry(x + a, y + b));
            if samples.iter().any(|&s| s != samples[0]) {
                continue;
            }
            let k = (j * SIZE + i) as usize;
            let (z, n) = (depth[k], Vec3::new(normal[0][k], normal[1][k], normal[2][k]));
            match samples[0] {
                None => {
                    assert_eq!(z, 0.0, "depth at ({i}, {j}), where the ray meets nothing");
                    counts[2] += 1;
                }
                Some(o) => {
                    assert!(z > 0.0, "depth {z} at ({i}, {j}) on object {o}");
                    assert_eq!(object[k], o as f32, "object index at ({i}, {j})");
                    if o == 0 {
                        assert_eq!(n, Vec3::Y, "the floor's normal at ({i}, {j})");
                    } else {
                        assert!((n.length() - 1.0).abs() < 2e-3, "the ball's normal {n} at ({i}, {j})");
                        // The sphere's normal where the pixel's centre ray meets it: the
                        // interpolated normal of a facet is within one ring step of it
                        // (cos(pi / 64) = 0.9988), less the half-float rounding (2e-3).
                        let exact = ball_normal(x + 0.5, y + 0.5);
                        assert!(n.dot(exact) > 0.996, "the ball's normal {n} at ({i}, {j}), the sphere's {exact}");
                    }
                    counts[o as usize] += 1;
                }
            }
        }
    }
    // Every kind of pixel is there in numbers (the horizon is in the upper part of the view).
    assert!(counts.iter().all(|&c| c > 64), "floor, ball, background pixels: {counts:?}");

    // The shadow map's cube faces are parts shadow_atlas.0 to .5 in Vulkan's face order (+X,
    // -X, +Y, -Y, +Z, -Z) and hold the distance to the light (glsl/shadow/shadow.frag). The
    // light at (0, 5, 0) sees nothing upwards (+Y: the cleared FAR_DISTANCE everywhere); the
    // four centre texels of -Y look down within atan(sqrt(2) / 64) of the axis onto the
    // ball's top: the distance in closed form, to within the tessellation's sagitta
    // r (1 - cos(pi / 64)) = 1.2e-3 at render.sphere_segments = 128 (64 rings), taken as 2e-3.
    use prism::technique::baseline::shadow_map::FAR_DISTANCE;
    assert!(channel(&parts, "shadow_atlas.2", "Y").iter().all(|&d| d == FAR_DISTANCE), "+Y face");
    let down = channel(&parts, "shadow_atlas.3", "Y");
    let d = Vec3::new(1.0 / 64.0, -1.0, 1.0 / 64.0).normalize();
    let oc = Vec3::new(0.0, 5.0 - 1.2, 0.0);
    let b = oc.dot(d);
    let expected = -b - (b * b - (oc.length_squared() - 1.0)).sqrt();
    for (i, j) in [(31, 31), (32, 31), (31, 32), (32, 32)] {
        let got = down[j * 64 + i];
        assert!((got - expected).abs() < 2e-3, "-Y face at ({i}, {j}): {got}, the ball's top at {expected}");
    }
}
