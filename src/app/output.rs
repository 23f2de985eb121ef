//! Output files that appear whole or not at all. A command claims all its outputs in one
//! [`Outputs`] before any rendering starts, so that a path that cannot be an output fails
//! fast: a missing directory, a directory, a device node or FIFO (renaming over it would
//! replace the node), or the same file named twice (one output would silently replace the
//! other). An empty temporary file created beside each target proves its directory
//! writable. Encoders write into memory; the bytes go to the temporary file, which is synced
//! to disk and checked at every step (a full disk is an error, not an empty file), and only
//! then renamed over the target. A command with several outputs writes every one before it
//! renames any ([`commit_all`]), so a failure leaves none of them. A symlink to a regular
//! file is followed: the file it names is replaced and the link kept. Ctrl-C (or SIGTERM,
//! SIGHUP) while outputs are pending removes their temporary files
//! ([`remove_pending_on_interrupt`]).
use std::fs::{File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard};

use anyhow::{bail, Context, Result};

use crate::renderer::FrameImage;
use crate::scene::techniques::TonemapAdaptiveParams;
use crate::scene::RenderSettings;
use crate::technique::baseline::tonemap::AdaptiveStats;

/// The temporary files that exist and are not yet renamed into place. Every creation,
/// rename and removal of one happens with this lock held, so the interrupt handler, which
/// keeps it until the process exits, sees each temporary file either listed or gone.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn pending() -> MutexGuard<'static, Vec<PathBuf>> {
    PENDING.lock().unwrap_or_else(|p| p.into_inner())
}

/// Exit status after an interrupt: 128 + SIGINT, the shell's convention for Ctrl-C.
pub const INTERRUPTED_EXIT: i32 = 130;

/// Installs the handler that, on SIGINT, SIGTERM or SIGHUP, removes every pending temporary
/// output file and exits with [`INTERRUPTED_EXIT`]. Without it the default action kills the
/// process and leaves the hidden `.prism-tmp-*` files behind. The handler runs on a thread
/// of the `ctrlc` crate, so it may lock and touch the file system.
pub fn remove_pending_on_interrupt() -> Result<()> {
    ctrlc::set_handler(|| {
        // Held until exit: no temporary file is created or renamed after this point.
        let mut temps = pending();
        for temp in temps.drain(..) {
            let _ = std::fs::remove_file(temp);
        }
        // _exit, not exit: exit runs the C++ static destructors of the loaded driver (LLVM)
        // while the main thread may still be initializing or using it, which aborts.
        // SAFETY: _exit ends the process at once; nothing of this process runs after it.
        unsafe { libc::_exit(INTERRUPTED_EXIT) }
    })
    .context("cannot install the interrupt handler")
}

/// The outputs one command has claimed, to refuse a file named twice.
#[derive(Default)]
pub struct Outputs {
    /// (the file that will be replaced, the path as the user gave it)
    claimed: Vec<(PathBuf, PathBuf)>,
}

impl Outputs {
    /// Check `target` as an output of this command and reserve it (see the module doc).
    pub fn prepare(&mut self, target: &Path) -> Result<OutputFile> {
        let out = OutputFile::prepare(target)?;
        if let Some((_, first)) = self.claimed.iter().find(|(file, _)| *file == out.target) {
            bail!(
                "{}: named twice as an output of this command (also as {}): one would replace the other\n  \
                 hint: give each output its own file name",
                target.display(),
                first.display()
            );
        }
        self.claimed.push((out.target.clone(), target.to_path_buf()));
        Ok(out)
    }

    /// [`Outputs::prepare`] for an optional output.
    pub fn prepare_opt(&mut self, target: Option<&Path>) -> Result<Option<OutputFile>> {
        target.map(|t| self.prepare(t)).transpose()
    }
}

/// An output claimed but not yet written. Dropping it removes its temporary file.
pub struct OutputFile {
    /// The path as given, for messages.
    given: PathBuf,
    /// The file that will be replaced: symlinks resolved, its directory canonical.
    target: PathBuf,
    temp: PathBuf,
    committed: bool,
}

/// An output whose bytes are on disk in its temporary file, waiting for [`commit_all`].
pub struct Written(OutputFile);

impl OutputFile {
    /// Check `target` and create its temporary file, outside any [`Outputs`]: for a file
    /// that is not a command's output (a cache).
    pub fn prepare(target: &Path) -> Result<OutputFile> {
        let shown = target.display();
        let name = target.file_name().with_context(|| format!("{shown}: output path has no file name"))?;
        let resolved = match std::fs::symlink_metadata(target) {
            Ok(m) if m.file_type().is_symlink() => std::fs::canonicalize(target).with_context(|| {
                format!("{shown}: cannot write output: it is a symlink to nothing\n  hint: remove the link or choose another path")
            })?,
            _ => target.to_path_buf(),
        };
        match std::fs::metadata(&resolved) {
            Ok(m) if m.is_dir() => bail!(
                "{shown}: cannot write output: it is a directory\n  hint: give a file name, e.g. {}",
                target.join("out.png").display()
            ),
            Ok(m) if !m.is_file() => bail!(
                "{shown}: cannot write output: it exists and is {}, not a regular file\n  \
                 hint: prism replaces its output files whole; give the path of a regular file or a new one",
                file_kind(&m.file_type())
            ),
            Ok(_) => {}
            Err(e) if e.kind() == io::ErrorKind::NotFound => {}
            Err(e) => return Err(e).with_context(|| format!("{shown}: cannot write output")),
        }
        let dir = match resolved.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if !dir.is_dir() {
            bail!(
                "{shown}: cannot write output: directory {} does not exist\n  hint: create it first or choose another path",
                dir.display()
            );
        }
        let dir = std::fs::canonicalize(&dir).with_context(|| format!("{shown}: cannot write output"))?;
        let name = resolved.file_name().unwrap_or(name);
        // Hidden, unique within the process too, and ending in the target's own name.
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let temp = dir.join(format!(".prism-tmp-{}-{n}-{}", std::process::id(), name.to_string_lossy()));
        let mut temps = pending();
        OpenOptions::new().write(true).create_new(true).open(&temp).with_context(|| {
            format!("{shown}: cannot write output (directory not writable?)\n  hint: choose a writable path")
        })?;
        temps.push(temp.clone());
        drop(temps);
        Ok(OutputFile { given: target.to_path_buf(), target: dir.join(name), temp, committed: false })
    }

    /// The path as given.
    pub fn path(&self) -> &Path {
        &self.given
    }

    /// Put `bytes` on disk in the temporary file; [`commit_all`] moves it into place.
    pub fn write(self, bytes: &[u8]) -> Result<Written> {
        self.write_with(|file| write_durably(file, bytes))
    }

    /// Write and move into place: for a command's only output.
    pub fn commit_bytes(self, bytes: &[u8]) -> Result<()> {
        self.write(bytes)?.commit()
    }

    /// The temporary file opened for `write`; on an error it is removed (by drop).
    fn write_with(self, write: impl FnOnce(&mut File) -> io::Result<()>) -> Result<Written> {
        let written = OpenOptions::new().write(true).truncate(true).open(&self.temp).and_then(|mut f| write(&mut f));
        written.with_context(|| format!("{}: cannot write output (disk full?)", self.given.display()))?;
        Ok(Written(self))
    }
}

impl Written {
    pub fn path(&self) -> &Path {
        self.0.path()
    }

    pub fn commit(self) -> Result<()> {
        commit_all([self])
    }
}

/// Every byte, then `sync_all`, so that a full disk or an I/O error is seen here and not
/// lost in a buffer or at close.
fn write_durably(file: &mut File, bytes: &[u8]) -> io::Result<()> {
    file.write_all(bytes)?;
    file.flush()?;
    file.sync_all()
}

/// Move written outputs into place together: only called once every one of them is on
/// disk, so that a failed write leaves no output at all. The directories are synced so
/// that the renames are durable too.
pub fn commit_all(files: impl IntoIterator<Item = Written>) -> Result<()> {
    let mut files: Vec<Written> = files.into_iter().collect();
    let mut dirs: Vec<PathBuf> = Vec::new();
    for Written(f) in &mut files {
        let mut temps = pending();
        std::fs::rename(&f.temp, &f.target)
            .with_context(|| format!("{}: cannot move the finished output into place", f.given.display()))?;
        temps.retain(|t| *t != f.temp);
        f.committed = true;
        if let Some(dir) = f.target.parent().filter(|d| !dirs.iter().any(|x| x == d)) {
            dirs.push(dir.to_path_buf());
        }
    }
    for dir in dirs {
        File::open(&dir)
            .and_then(|d| d.sync_all())
            .with_context(|| format!("{}: cannot sync the directory of the outputs", dir.display()))?;
    }
    Ok(())
}

fn file_kind(t: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a file"
    }
}

impl Drop for OutputFile {
    fn drop(&mut self) {
        if !self.committed {
            let mut temps = pending();
            let _ = std::fs::remove_file(&self.temp);
            temps.retain(|t| *t != self.temp);
        }
    }
}

/// Encode RGBA8 pixels as PNG. The encoder writes into memory, where finishing (the final
/// chunk, written when it is dropped) cannot fail.
fn encode_png(width: u32, height: u32, rgba: &[u8]) -> Result<Vec<u8>> {
    let img = image::RgbaImage::from_raw(width, height, rgba.to_vec()).context("image buffer has the wrong size")?;
    encode(image::DynamicImage::ImageRgba8(img), image::ImageFormat::Png)
}

/// Encode an image into memory (see [`encode_png`]).
pub fn encode(img: image::DynamicImage, format: image::ImageFormat) -> Result<Vec<u8>> {
    let mut bytes = io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, format).with_context(|| format!("cannot encode {format:?}"))?;
    Ok(bytes.into_inner())
}

/// Encode RGBA8 pixels as PNG into `out`.
pub fn write_png(out: OutputFile, width: u32, height: u32, rgba: &[u8]) -> Result<Written> {
    out.write(&encode_png(width, height, rgba)?)
}

/// Encode opaque RGBA8 pixels as an RGB PNG into `out`: three quarters of RGBA's size for
/// the report's image strips (`prism report --images`), the alpha being 255 everywhere.
pub fn write_png_rgb(out: OutputFile, width: u32, height: u32, rgba: &[u8]) -> Result<Written> {
    let rgb: Vec<u8> = rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
    let img = image::RgbImage::from_raw(width, height, rgb).context("image buffer has the wrong size")?;
    out.write(&encode(image::DynamicImage::ImageRgb8(img), image::ImageFormat::Png)?)
}

/// Encode linear RGBA f32 radiance as an RGB f32 OpenEXR file (unscaled, per SCENES.md).
pub fn write_exr(out: OutputFile, width: u32, height: u32, rgba: &[f32]) -> Result<Written> {
    let rgb: Vec<f32> = rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
    let img = image::Rgb32FImage::from_raw(width, height, rgb).context("image buffer has the wrong size")?;
    out.write(&encode(image::DynamicImage::ImageRgb32F(img), image::ImageFormat::OpenExr)?)
}

/// The EXR part names of an image of `layers` array layers (or 3D slices): its name alone
/// for one, `NAME.LAYER` for several.
pub fn target_part_names(name: &str, layers: u32) -> Vec<String> {
    if layers == 1 {
        vec![name.to_string()]
    } else {
        (0..layers).map(|l| format!("{name}.{l}")).collect()
    }
}

/// The channel names of an image of `channels` f32 channels: R, G, B, A; Y for one colour
/// channel, Z for a depth image (OpenEXR's conventions for luminance and depth).
fn target_channel_names(channels: u32, format: &str) -> &'static [&'static str] {
    let depth = format.starts_with('D') || format.starts_with("X8_D");
    match channels {
        1 if depth => &["Z"],
        1 => &["Y"],
        2 => &["R", "G"],
        3 => &["R", "G", "B"],
        _ => &["R", "G", "B", "A"],
    }
}

/// Every readable image of a frame ([`crate::renderer::Renderer::frame_images`] with what
/// `read_frame_image` returned) as one multi-part OpenEXR file: one part per image and
/// array layer (slice of a 3D image), each of its own size, f32 channels
/// ([`target_channel_names`]). Images that could not be read are left out (the table of
/// [`targets_table`] says why).
pub fn write_targets_exr(out: OutputFile, images: &[(FrameImage, Option<Vec<f32>>)]) -> Result<Written> {
    use exr::prelude::*;
    let mut parts = Vec::new();
    for (image, data) in images {
        let Some(data) = data else { continue };
        let (w, h, c) = (image.width as usize, image.height as usize, image.channels as usize);
        let names = target_part_names(&image.name, image.layers * image.depth);
        let texels = w * h;
        if data.len() != texels * c * names.len() {
            bail!("{}: read back {} values, expected {}", image.name, data.len(), texels * c * names.len());
        }
        for (part, name) in names.iter().enumerate() {
            let texels_of_part = &data[part * texels * c..(part + 1) * texels * c];
            let channels = target_channel_names(image.channels, &image.format)
                .iter()
                .enumerate()
                .map(|(k, channel)| {
                    let samples = texels_of_part.iter().skip(k).step_by(c).copied().collect();
                    AnyChannel::new(*channel, FlatSamples::F32(samples))
                })
                .collect::<Vec<_>>();
            let attributes = LayerAttributes::named(name.as_str());
            parts.push(Layer::new((w, h), attributes, Encoding::FAST_LOSSLESS, AnyChannels::sort(channels.into())));
        }
    }
    if parts.is_empty() {
        bail!("{}: no image of the frame could be read back", out.path().display());
    }
    // The display window covers the largest part; each part keeps its own data window.
    let (w, h) = parts.iter().fold((1, 1), |(w, h), p| (p.size.width().max(w), p.size.height().max(h)));
    let image = Image::from_layers(ImageAttributes::new(IntegerBounds::from_dimensions((w, h))), parts);
    let mut bytes = io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut bytes)
        .with_context(|| format!("{}: cannot encode the EXR", out.path().display()))?;
    out.write(&bytes.into_inner())
}

/// What [`write_targets_exr`] wrote, one image a line: name, size, layers, format, and
/// why an image was left out.
pub fn targets_table(images: &[(FrameImage, Option<Vec<f32>>)]) -> String {
    let width = images.iter().map(|(i, _)| i.name.len()).max().unwrap_or(4).max(4);
    let mut out = format!("{:width$}  {:>11}  {:>6}  format", "name", "size", "layers");
    for (i, data) in images {
        let size = if i.depth > 1 {
            format!("{}x{}x{}", i.width, i.height, i.depth)
        } else {
            format!("{}x{}", i.width, i.height)
        };
        let note = match (data, i.unreadable) {
            (Some(_), _) => String::new(),
            (None, Some(why)) => format!("  (skipped: {why})"),
            (None, None) => "  (skipped: no longer exists)".to_string(),
        };
        out += &format!("\n{:width$}  {size:>11}  {:>6}  {}{note}", i.name, i.layers, i.format);
    }
    out
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh directory for one test.
    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("prism-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn listing(dir: &Path) -> Vec<String> {
        let mut v: Vec<_> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn a_full_device_is_an_error() {
        let mut full = OpenOptions::new().write(true).open("/dev/full").unwrap();
        let e = write_durably(&mut full, &[0u8; 100_000]).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::StorageFull, "{e}");
    }

    #[test]
    fn a_failed_write_leaves_neither_target_nor_temp() {
        let dir = scratch("failed");
        let mut outputs = Outputs::default();
        let png = outputs.prepare(&dir.join("a.png")).unwrap();
        let exr = outputs.prepare(&dir.join("a.exr")).unwrap();
        assert_eq!(listing(&dir).len(), 2, "the temporary files exist while the outputs are pending");
        let png = png.write(b"png").unwrap();
        let e = exr.write_with(|_| Err(io::Error::from(io::ErrorKind::StorageFull))).err().unwrap();
        assert!(format!("{e:#}").contains("a.exr: cannot write output"), "{e:#}");
        drop(png);
        assert!(listing(&dir).is_empty(), "{:?}", listing(&dir));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn outputs_commit_together() {
        let dir = scratch("together");
        let mut outputs = Outputs::default();
        let a = outputs.prepare(&dir.join("a.csv")).unwrap().write(b"a").unwrap();
        let b = outputs.prepare(&dir.join("b.svg")).unwrap().write(b"b").unwrap();
        assert_eq!(listing(&dir).iter().filter(|n| !n.starts_with(".prism-tmp-")).count(), 0);
        commit_all([a, b]).unwrap();
        assert_eq!(listing(&dir), ["a.csv", "b.svg"]);
        assert_eq!(std::fs::read(dir.join("b.svg")).unwrap(), b"b");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn non_regular_files_and_names_given_twice_are_refused() {
        let dir = scratch("refused");
        for dev in ["/dev/null", "/dev/full"] {
            let e = OutputFile::prepare(Path::new(dev)).err().unwrap().to_string();
            assert!(e.starts_with(dev) && e.contains("a character device, not a regular file"), "{e}");
        }
        let fifo = dir.join("fifo");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
        let e = OutputFile::prepare(&fifo).err().unwrap().to_string();
        assert!(e.contains("a FIFO (named pipe), not a regular file"), "{e}");
        std::fs::create_dir(dir.join("sub")).unwrap();
        assert!(OutputFile::prepare(&dir.join("sub")).err().unwrap().to_string().contains("is a directory"));
        // The same file under two names: spelt differently, and through a symlink.
        std::fs::write(dir.join("x.png"), b"old").unwrap();
        std::os::unix::fs::symlink(dir.join("x.png"), dir.join("link.png")).unwrap();
        for other in [dir.join("sub/../x.png"), dir.join("link.png")] {
            let mut outputs = Outputs::default();
            let _first = outputs.prepare(&dir.join("x.png")).unwrap();
            let e = outputs.prepare(&other).err().unwrap().to_string();
            assert!(e.contains("named twice as an output") && e.contains("x.png"), "{e}");
        }
        // A symlink to a regular file is followed: the file is replaced, the link kept.
        OutputFile::prepare(&dir.join("link.png")).unwrap().commit_bytes(b"new").unwrap();
        assert!(std::fs::symlink_metadata(dir.join("link.png")).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(dir.join("x.png")).unwrap(), b"new");
        assert_eq!(listing(&dir), ["fifo", "link.png", "sub", "x.png"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
