//! Output files that appear whole or not at all. The path is checked (by creating a
//! temporary file beside it) before any rendering starts, so an unwritable path fails fast;
//! data goes to the temporary file, which is renamed over the target only when complete.
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

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
    let oetf = |c: f32| {
        let c = if c.is_finite() { (exposure * c).clamp(0.0, 1.0) } else { 0.0 };
        let v = if c <= 0.0031308 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
        (v * 255.0 + 0.5) as u8
    };
    rgba.chunks_exact(4).flat_map(|p| [oetf(p[0]), oetf(p[1]), oetf(p[2]), 255]).collect()
}
