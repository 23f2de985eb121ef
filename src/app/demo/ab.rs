//! The window's A/B view: the frame the selected techniques render, wiped against the exact
//! image of the same view computed live by the reference renderer (src/reference: path
//! tracing with progressive photon mapping, `prism reference`'s renderer, same seed and
//! settings). The exact image accumulates one sample (camera path and photon passes) per
//! window frame while nothing changes, and starts again when the camera, the window size or
//! any parameter changes, so the comparison follows every edit. The overlay shows the live
//! error, `prism compare`'s metrics on the same images (relMSE of linear radiance, FLIP of
//! the tone-mapped images, HDR-FLIP), and both costs: the technique's GPU time per frame and the
//! exact renderer's time per sample.
//!
//! Falcor's error view compares against a reference image loaded from disk; here the
//! reference follows the camera and every parameter, at the price of the reference's
//! noise, which falls as the samples accumulate (the sample count is shown with the error).
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};

use crate::app::compare::technique_ldr;
use crate::app::output;
use crate::gpu::GpuContext;
use crate::metrics::image::ErrorMetrics;
use crate::reference::{Reference, ReferenceSettings};
use crate::renderer::Renderer;
use crate::scene::{Camera, Scene};

/// What the A/B view draws in place of the final image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbMode {
    /// The technique left of the split, the exact image right of it.
    Wipe,
    /// The exact image alone.
    Exact,
    /// FLIP's per-pixel error map (magma) of the technique against the exact image.
    Error,
}

impl AbMode {
    pub const ALL: [AbMode; 3] = [AbMode::Wipe, AbMode::Exact, AbMode::Error];

    pub fn name(self) -> &'static str {
        match self {
            AbMode::Wipe => "wipe",
            AbMode::Exact => "exact",
            AbMode::Error => "FLIP map",
        }
    }
}

/// Photons per exact sample by default: `prism reference`'s default rate (2^22 photons over
/// 64 samples), so that after 64 samples the view's exact image is `prism reference`'s.
pub const DEFAULT_PHOTONS: u32 = ((1u64 << 22) / 64) as u32;

/// The most photons per exact sample the overlay offers: with [`MAX_SAMPLES`] samples the
/// reference's photon total stays within its 2^34 bound.
pub const MAX_PHOTONS: u32 = 1 << 18;

/// Samples the exact image accumulates at most (the reference is created for this many).
const MAX_SAMPLES: u32 = 1 << 16;

/// The overlay's A/B settings.
#[derive(Clone, Debug)]
pub struct AbOptions {
    pub on: bool,
    pub mode: AbMode,
    /// Where the wipe splits the window, as a fraction of its width.
    pub split: f32,
    /// Photons traced per exact sample (0: no caustics).
    pub photons: u32,
}

impl Default for AbOptions {
    fn default() -> Self {
        AbOptions { on: false, mode: AbMode::Wipe, split: 0.5, photons: DEFAULT_PHOTONS }
    }
}

/// The live error and costs, for the overlay.
#[derive(Clone, Debug)]
pub struct AbStatus {
    pub samples: u32,
    pub photons: u32,
    /// Wall time per exact sample (the sample's submission and wait), ms.
    pub ms_per_sample: f64,
    /// The errors and the sample count they were measured at.
    pub errors: Option<(u32, ErrorMetrics)>,
}

struct Exact {
    reference: Reference,
    photons: u32,
    seconds: f64,
    /// The technique's image against this exact image: errors, sample count, FLIP map.
    errors: Option<(u32, ErrorMetrics)>,
    heat: Vec<u8>,
    errors_at: Instant,
}

/// The A/B view's state across frames.
#[derive(Default)]
pub struct AbView {
    exact: Option<Exact>,
    /// The state (camera, size, parameters) the exact image was made for.
    key: Option<String>,
    /// Last frame's state: an exact image is made only once a state held for a frame, so
    /// that no reference is built per frame while the camera moves.
    last_key: Option<String>,
    pub texture: Option<egui::TextureHandle>,
    /// The last picture drawn (width, height, RGBA8): `--screenshot` writes it.
    pub picture: Option<(u32, u32, Vec<u8>)>,
    /// How often the exact image started again after a change.
    pub restarts: u32,
}

impl AbView {
    pub fn status(&self) -> Option<AbStatus> {
        let e = self.exact.as_ref()?;
        let samples = e.reference.iterations_done();
        Some(AbStatus {
            samples,
            photons: e.photons,
            ms_per_sample: e.seconds * 1000.0 / samples.max(1) as f64,
            errors: e.errors,
        })
    }

    /// Turn the view off and free the exact renderer.
    pub fn clear(&mut self) {
        *self = AbView { restarts: self.restarts, ..AbView::default() };
    }

    /// One window frame, before the renderer records it. `scene` is the scene the renderer
    /// draws and `camera` the camera it was last given; `state` names everything the image
    /// depends on (camera included). The previous frame's image is read back here: an exact
    /// image is only made once `state` held for a frame, so that image had the same state.
    /// Adds one sample to the exact image, measures the errors when the sample count reached
    /// a power of two, a second passed or `measure_now`, and draws the view's picture.
    #[allow(clippy::too_many_arguments)]
    pub fn update(
        &mut self,
        ctx: &Arc<GpuContext>,
        scene: &Scene,
        camera: Camera,
        state: String,
        renderer: &mut Renderer,
        options: &AbOptions,
        measure_now: bool,
        egui_ctx: &egui::Context,
    ) -> Result<()> {
        if !options.on {
            self.clear();
            return Ok(());
        }
        let key = format!("{state} photons={}", options.photons);
        if self.key.as_ref() != Some(&key) && self.exact.take().is_some() {
            self.restarts += 1;
            eprintln!("demo: A/B: the view changed, the exact image starts again");
        }
        let held = self.last_key.as_ref() == Some(&key);
        self.last_key = Some(key.clone());
        if self.exact.is_none() {
            if !held {
                // Changing: the window shows the techniques' live image meanwhile.
                self.texture = None;
                self.picture = None;
                return Ok(());
            }
            let settings = ReferenceSettings {
                spp: MAX_SAMPLES,
                photons: options.photons as u64 * MAX_SAMPLES as u64,
                ..ReferenceSettings::default()
            };
            let view = Scene { camera, ..scene.clone() };
            let reference = Reference::new(ctx, &view, &settings).context("cannot start the exact image")?;
            self.exact = Some(Exact {
                reference,
                photons: options.photons,
                seconds: 0.0,
                errors: None,
                heat: Vec::new(),
                errors_at: Instant::now(),
            });
            self.key = Some(key);
        }
        let Some(exact) = self.exact.as_mut() else { return Ok(()) };
        if exact.reference.iterations_done() < MAX_SAMPLES {
            let t = Instant::now();
            exact.reference.run(1)?;
            exact.seconds += t.elapsed().as_secs_f64();
        }
        let samples = exact.reference.iterations_done();
        let (w, h) = (camera.width, camera.height);
        let image = exact.reference.image();
        let exact_ldr = output::tonemap_scene(&image, &scene.render);
        let hdr = renderer.read_hdr()?;
        let ldr = technique_ldr(renderer, scene, &hdr, &image)?;
        let due = samples.is_power_of_two() || exact.errors_at.elapsed().as_secs_f64() >= 1.0 || measure_now;
        if due && exact.errors.is_none_or(|(n, _)| n != samples) {
            let (errors, heat) = ErrorMetrics::between(&hdr, &image, &ldr, &exact_ldr, w, h);
            eprintln!(
                "demo: A/B: {samples} exact samples ({} photons each, {:.1} ms per sample): FLIP mean {:.6}, HDR-FLIP mean {:.6}, relMSE {:.6}, RMSE {:.6}",
                exact.photons,
                exact.seconds * 1000.0 / samples.max(1) as f64,
                errors.flip_mean,
                errors.hdr_flip_mean,
                errors.rel_mse,
                errors.rmse
            );
            exact.errors = Some((samples, errors));
            exact.heat = heat;
            exact.errors_at = Instant::now();
        }
        let pixels = match options.mode {
            AbMode::Wipe => wipe(&ldr, &exact_ldr, w as usize, options.split),
            AbMode::Exact => exact_ldr,
            AbMode::Error if !exact.heat.is_empty() => exact.heat.clone(),
            AbMode::Error => ldr,
        };
        let picture = egui::ColorImage::from_rgba_unmultiplied([w as usize, h as usize], &pixels);
        self.picture = Some((w, h, pixels));
        match &mut self.texture {
            Some(texture) => texture.set(picture, egui::TextureOptions::NEAREST),
            None => self.texture = Some(egui_ctx.load_texture("ab_view", picture, egui::TextureOptions::NEAREST)),
        }
        Ok(())
    }
}

/// The technique's RGBA8 image left of `split` (a fraction of the width), the exact image
/// right of it, and a one-pixel white line between them.
fn wipe(technique: &[u8], exact: &[u8], width: usize, split: f32) -> Vec<u8> {
    let column = ((split.clamp(0.0, 1.0) * width as f32) as usize).min(width);
    let mut out = exact.to_vec();
    for (i, (o, t)) in out.chunks_exact_mut(4).zip(technique.chunks_exact(4)).enumerate() {
        let x = i % width;
        if x < column {
            o.copy_from_slice(t);
        } else if x == column {
            o.copy_from_slice(&[255, 255, 255, 255]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wipe_takes_the_technique_left_of_the_split() {
        let t = [10u8; 4 * 4];
        let e = [20u8; 4 * 4];
        let out = wipe(&t, &e, 4, 0.5);
        let firsts: Vec<u8> = out.chunks_exact(4).map(|p| p[0]).collect();
        assert_eq!(firsts, [10, 10, 255, 20]);
        assert_eq!(wipe(&t, &e, 4, 0.0).chunks_exact(4).map(|p| p[0]).collect::<Vec<_>>(), [255, 20, 20, 20]);
        assert_eq!(wipe(&t, &e, 4, 1.0).chunks_exact(4).map(|p| p[0]).collect::<Vec<_>>(), [10; 4]);
    }
}
