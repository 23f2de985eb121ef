//! Environment lighting: the lat-long mapping, the procedural `grid` environment and
//! loading of environment images.

use std::f32::consts::{PI, TAU};
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use crate::{
    GRID_GROUND, GRID_LINE_HALF_WIDTH_DEG, GRID_LINE_RADIANCE, GRID_SKY_HORIZON, GRID_SKY_ZENITH, GRID_SPACING_DEG,
};

/// Radiance arriving from every direction not blocked by the scene.
#[derive(Debug, Clone, PartialEq)]
pub enum Environment {
    Constant(Vec3),
    /// The procedural grid of [`grid_radiance`], evaluated exactly per lookup on the GPU
    /// (glsl/include/common.glsl), as the reference and any other renderer see it.
    Grid,
    /// A lat-long image (see [`dir_to_latlong`]).
    Image {
        path: PathBuf,
        width: u32,
        height: u32,
        /// Linear RGBA, row 0 = top (+Y), `width * height` texels.
        texels: Vec<[f32; 4]>,
    },
}

/// Direction -> lat-long (u, v): u = 0.5 + atan2(x, -z) / 2pi, v = acos(y) / pi,
/// (0, 0) the top-left corner. -Z maps to the image centre, +Y to the top row.
pub fn dir_to_latlong(d: Vec3) -> Vec2 {
    let d = d.normalize_or(Vec3::NEG_Z);
    Vec2::new(0.5 + d.x.atan2(-d.z) / TAU, d.y.clamp(-1.0, 1.0).acos() / PI)
}

/// Lat-long (u, v) -> unit direction; the inverse of [`dir_to_latlong`].
pub fn latlong_dir(u: f32, v: f32) -> Vec3 {
    let phi = (u - 0.5) * TAU;
    let theta = v * PI;
    let s = theta.sin();
    Vec3::new(s * phi.sin(), theta.cos(), -s * phi.cos())
}

/// The procedural grid environment (SCENES.md): a sky blending from (0.8, 0.85, 0.9)
/// at the horizon to (0.25, 0.45, 0.9) at the zenith, a ground of (0.3, 0.25, 0.2)
/// below, and lines of radiance 2 within 0.5 degree of every multiple of 15 degrees
/// of longitude atan2(x, -z) and latitude 90 - acos(y). The lines make refraction
/// error visible. The one definition: glsl/include/common.glsl's `grid_radiance` evaluates
/// the same angles with the same constants (src/shader_shared.rs).
pub fn grid_radiance(d: Vec3) -> Vec3 {
    let d = d.normalize_or(Vec3::NEG_Z);
    let lon = d.x.atan2(-d.z).to_degrees();
    let lat = 90.0 - d.y.clamp(-1.0, 1.0).acos().to_degrees();
    let near_line = |a: f32| {
        let m = a.rem_euclid(GRID_SPACING_DEG);
        m <= GRID_LINE_HALF_WIDTH_DEG || m >= GRID_SPACING_DEG - GRID_LINE_HALF_WIDTH_DEG
    };
    if near_line(lon) || near_line(lat) {
        return Vec3::splat(GRID_LINE_RADIANCE);
    }
    if d.y >= 0.0 {
        Vec3::from_array(GRID_SKY_HORIZON).lerp(Vec3::from_array(GRID_SKY_ZENITH), d.y)
    } else {
        Vec3::from_array(GRID_GROUND)
    }
}

/// The grid sampled at texel centres, row 0 on top.
pub fn grid_texels(width: u32, height: u32) -> Vec<[f32; 4]> {
    let mut t = Vec::with_capacity(width as usize * height as usize);
    for j in 0..height {
        for i in 0..width {
            let d = latlong_dir((i as f32 + 0.5) / width as f32, (j as f32 + 0.5) / height as f32);
            let c = grid_radiance(d);
            t.push([c.x, c.y, c.z, 1.0]);
        }
    }
    t
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads an .exr, .hdr or .png as linear RGBA (PNG is decoded from sRGB).
pub(crate) fn read_image(path: &Path) -> Result<(u32, u32, Vec<[f32; 4]>), String> {
    super::read::regular_file(path).map_err(|e| e.to_string())?;
    let img =
        image::ImageReader::open(path).map_err(|e| e.to_string())?.with_guessed_format().map_err(|e| e.to_string())?;
    let is_png = img.format() == Some(image::ImageFormat::Png);
    let img = img.decode().map_err(|e| e.to_string())?;
    let rgba = img.into_rgba32f();
    let (w, h) = rgba.dimensions();
    let texels = rgba
        .pixels()
        .map(|p| {
            let [r, g, b, a] = p.0;
            if is_png {
                [srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b), a]
            } else {
                [r, g, b, a]
            }
        })
        .collect();
    Ok((w, h, texels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latlong_round_trip() {
        for &(u, v) in &[(0.5, 0.5), (0.1, 0.3), (0.9, 0.8), (0.25, 0.01), (0.75, 0.99)] {
            let d = latlong_dir(u, v);
            assert!((d.length() - 1.0).abs() < 1e-5);
            let uv = dir_to_latlong(d);
            assert!((uv - Vec2::new(u, v)).length() < 1e-5, "{u},{v} -> {uv}");
        }
        for d in [Vec3::new(0.3, 0.4, -0.5), Vec3::new(-1.0, -0.2, 0.7), Vec3::X] {
            let d = d.normalize();
            let uv = dir_to_latlong(d);
            assert!((latlong_dir(uv.x, uv.y) - d).length() < 1e-5);
        }
        assert!((dir_to_latlong(Vec3::NEG_Z) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!(dir_to_latlong(Vec3::Y).y.abs() < 1e-6);
        assert!((dir_to_latlong(Vec3::X) - Vec2::new(0.75, 0.5)).length() < 1e-6);
    }

    #[test]
    fn grid_spot_values() {
        let dir = |lon: f32, lat: f32| {
            let (lon, lat) = (lon.to_radians(), lat.to_radians());
            Vec3::new(lat.cos() * lon.sin(), lat.sin(), -lat.cos() * lon.cos())
        };
        // Lines at lon 0, 15, -30 and lat 0, 45 (within 0.5 degree).
        for (lon, lat) in [(0.2, 7.0), (15.4, 7.0), (-30.3, 7.0), (7.0, 0.3), (7.0, 44.6), (7.0, -60.0)] {
            assert_eq!(grid_radiance(dir(lon, lat)), Vec3::splat(2.0), "{lon},{lat}");
        }
        // Sky between lines: mix(horizon, zenith, y).
        // lat 37: y = sin 37 deg = 0.601815, so (0.8 - 0.55 y, 0.85 - 0.4 y, 0.9).
        let d = dir(7.0, 37.0);
        assert!((grid_radiance(d) - Vec3::new(0.469002, 0.609274, 0.9)).length() < 1e-5);
        // Ground.
        assert_eq!(grid_radiance(dir(7.0, -20.0)), Vec3::new(0.3, 0.25, 0.2));
        // Just outside a line.
        assert_ne!(grid_radiance(dir(15.6, 7.0)), Vec3::splat(2.0));
    }

    #[test]
    fn grid_texels_follow_latlong() {
        let t = grid_texels(64, 32);
        assert_eq!(t.len(), 64 * 32);
        // Row 0 is the sky near the zenith; the last row is ground.
        let top = t[3];
        assert!(top[2] > 0.85 && top[0] < 0.4 || top[0] == 2.0);
        let bottom = t[31 * 64 + 3];
        assert!(bottom == [0.3, 0.25, 0.2, 1.0] || bottom[0] == 2.0);
    }
}
