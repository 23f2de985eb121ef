//! Output files that appear whole or not at all. The path is checked (by creating a
//! temporary file beside it) before any rendering starts, so an unwritable path fails fast;
//! data goes to the temporary file, which is renamed over the target only when complete.
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::scene::techniques::TonemapAdaptiveParams;
use crate::scene::RenderSettings;
use crate::technique::baseline::tonemap::AdaptiveStats;

pub struct OutputFile {
    target: PathBuf,
    temp: PathBuf,
    committed: bool,
}

impl OutputFile {
    pub fn prepare(target: &Path) -> Result<OutputFile> {
        let name = target.file_name().with_context(|| format!("{}: output path has no file name", target.display()))?;
        if target.is_dir() {
            anyhow::bail!(
                "{}: cannot write output: it is a directory\n  hint: give a file name, e.g. {}",
                target.display(),
                target.join("out.png").display()
            );
        }
        let dir = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if !dir.is_dir() {
            anyhow::bail!(
                "{}: cannot write output: directory {} does not exist\n  hint: create it first or choose another path",
                target.display(),
                dir.display()
            );
        }
        // Hidden, unique, and ending in the target's own extension (encoders look at it).
        let temp = dir.join(format!(".prism-tmp-{}-{}", std::process::id(), name.to_string_lossy()));
        std::fs::write(&temp, b"").with_context(|| {
            format!(
                "{}: cannot write output (directory not writable?)\n  hint: choose a writable path",
                target.display()
            )
        })?;
        Ok(OutputFile { target: target.to_path_buf(), temp, committed: false })
    }

    pub fn path(&self) -> &Path {
        &self.target
    }

    /// The temporary path to write to before [`OutputFile::commit`].
    pub fn temp_path(&self) -> &Path {
        &self.temp
    }

    /// Write `bytes` and move them into place.
    pub fn commit_bytes(self, bytes: &[u8]) -> Result<()> {
        std::fs::write(&self.temp, bytes).with_context(|| format!("{}: cannot write output", self.target.display()))?;
        self.commit()
    }

    /// Move the finished temporary file into place.
    pub fn commit(mut self) -> Result<()> {
        std::fs::rename(&self.temp, &self.target)
            .with_context(|| format!("{}: cannot move the finished output into place", self.target.display()))?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for OutputFile {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.temp);
        }
    }
}

/// Encode RGBA8 pixels as PNG into `out`.
pub fn write_png(out: OutputFile, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    let img = image::RgbaImage::from_raw(width, height, rgba.to_vec()).context("image buffer has the wrong size")?;
    img.save_with_format(out.temp_path(), image::ImageFormat::Png)
        .with_context(|| format!("{}: cannot encode PNG", out.path().display()))?;
    out.commit()
}

/// Encode linear RGBA f32 radiance as an RGB f32 OpenEXR file (unscaled, per SCENES.md).
pub fn write_exr(out: OutputFile, width: u32, height: u32, rgba: &[f32]) -> Result<()> {
    let rgb: Vec<f32> = rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
    let img = image::Rgb32FImage::from_raw(width, height, rgb).context("image buffer has the wrong size")?;
    image::DynamicImage::ImageRgb32F(img)
        .save_with_format(out.temp_path(), image::ImageFormat::OpenExr)
        .with_context(|| format!("{}: cannot encode EXR", out.path().display()))?;
    out.commit()
}

/// The PNG rule of SCENES.md on the CPU, identical to glsl/tonemap/tonemap.frag:
/// srgb_oetf(clamp(exposure * L, 0, 1)), NaN/Inf as 0. RGBA f32 in, RGBA8 out.
pub fn tonemap(rgba: &[f32], exposure: f32) -> Vec<u8> {
    let oetf = |c: f32| srgb8(if c.is_finite() { exposure * c } else { 0.0 });
    rgba.chunks_exact(4).flat_map(|p| [oetf(p[0]), oetf(p[1]), oetf(p[2]), 255]).collect()
}

/// srgb_oetf(clamp(c, 0, 1)) as an 8-bit code (glsl/include/color.glsl; UNORM rounding).
fn srgb8(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let v = if c <= 0.0031308 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (v * 255.0 + 0.5) as u8
}

/// The PNG output the scene's `render.tonemap` names, on the CPU: [`tonemap`] (clamp) or
/// [`tonemap_adaptive`] (converged, as every headless render is). Compare, report and the
/// reference's PNGs use it so that both sides of a FLIP comparison are mapped alike.
pub fn tonemap_scene(rgba: &[f32], render: &RenderSettings) -> Vec<u8> {
    if render.tonemap == "adaptive" {
        // The scene loader has checked the table: this cannot fail after loading.
        let p = TonemapAdaptiveParams::from_settings(render).unwrap_or_default();
        tonemap_adaptive(rgba, &p, render.exposure).0
    } else {
        tonemap(rgba, render.exposure)
    }
}

/// Radiance as the adaptive tone map reads it (glsl/tonemap/adaptive.glsl `tonemap_input`).
fn tonemap_input(c: f32) -> f32 {
    if c.is_finite() {
        c.clamp(0.0, 1e30)
    } else {
        0.0
    }
}

fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// The converged state of the adaptive tone map for an image (glsl/tonemap/adapt.comp with
/// T < 0): L_avg = exp(mean(log(delta + L_w))) summed in f64 (Reinhard et al. 2002, Eq. 1),
/// the key (Krawczyk et al. 2005) and L_white.
pub fn adaptive_stats(rgba: &[f32], p: &TonemapAdaptiveParams, exposure: f32) -> AdaptiveStats {
    let (mut sum, mut max, mut n) = (0f64, 0f32, 0usize);
    for px in rgba.chunks_exact(4) {
        let c = [tonemap_input(px[0]), tonemap_input(px[1]), tonemap_input(px[2])];
        let y = (p.luminance_scale * luminance(c)).min(1e35);
        sum += (p.delta as f64 + y as f64).ln();
        max = max.max(y);
        n += 1;
    }
    let l_avg = (sum / n.max(1) as f64).exp() as f32;
    let l_adapted = l_avg;
    let key = p.key.unwrap_or(1.03 - 2.0 / (2.0 + (l_adapted + 1.0).log10()));
    let scale = exposure * key * p.luminance_scale / l_adapted;
    let white = p.white.unwrap_or((scale * max / p.luminance_scale).max(1.0));
    AdaptiveStats { l_avg, l_adapted, key, white }
}

/// The adaptive tone map on the CPU, term for term as glsl/tonemap/adaptive.frag (see
/// src/technique/baseline/tonemap.rs): L = exposure a / L_a * L_w, L_d = L (1 + L / L_white^2) / (1 + L),
/// colour scaled by L_d / L_w, sRGB. RGBA f32 in, RGBA8 out, and the state it used.
pub fn tonemap_adaptive(rgba: &[f32], p: &TonemapAdaptiveParams, exposure: f32) -> (Vec<u8>, AdaptiveStats) {
    let s = adaptive_stats(rgba, p, exposure);
    (tonemap_adaptive_with(rgba, p, exposure, &s), s)
}

/// [`tonemap_adaptive`] with a given state (L_a, key, L_white), e.g. another image's:
/// compare and report map the technique's image with the reference's state.
pub fn tonemap_adaptive_with(rgba: &[f32], p: &TonemapAdaptiveParams, exposure: f32, s: &AdaptiveStats) -> Vec<u8> {
    let scale = exposure * s.key * p.luminance_scale / s.l_adapted;
    let inv_white2 = 1.0 / (s.white * s.white);
    rgba.chunks_exact(4)
        .flat_map(|px| {
            let c = [tonemap_input(px[0]), tonemap_input(px[1]), tonemap_input(px[2])];
            let y = luminance(c);
            let ratio = if y > 0.0 {
                let l = scale * y;
                (l / (1.0 + l) * (1.0 + l * inv_white2)).min(65504.0) / y
            } else {
                0.0
            };
            [srgb8(c[0] * ratio), srgb8(c[1] * ratio), srgb8(c[2] * ratio), 255]
        })
        .collect()
}
