//! Error between two images of the same size.

/// Mean squared error over the RGB channels of two RGBA images (alpha is ignored).
fn mse_rgb<T: Copy + Into<f64>>(a: &[T], b: &[T]) -> f64 {
    assert_eq!(a.len(), b.len(), "images differ in size");
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (pa, pb) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        for (&x, &y) in pa[..3].iter().zip(&pb[..3]) {
            let d = x.into() - y.into();
            sum += d * d;
            n += 1;
        }
    }
    sum / n.max(1) as f64
}

/// Root-mean-square error over the RGB channels of two RGBA f32 images.
pub fn rmse_rgba(a: &[f32], b: &[f32]) -> f64 {
    mse_rgb(a, b).sqrt()
}

/// Peak signal-to-noise ratio in dB for 8-bit RGBA images (peak 255), over RGB.
/// Infinite for identical images.
pub fn psnr_rgba8(a: &[u8], b: &[u8]) -> f64 {
    let mse = mse_rgb(a, b);
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (255.0 * 255.0 / mse).log10()
    }
}

/// Fraction of pixels whose largest 8-bit channel difference exceeds `tolerance`.
pub fn fraction_differing_rgba8(a: &[u8], b: &[u8], tolerance: u8) -> f64 {
    assert_eq!(a.len(), b.len(), "images differ in size");
    let pixels = a.len() / 4;
    let bad = a
        .chunks_exact(4)
        .zip(b.chunks_exact(4))
        .filter(|(pa, pb)| (0..3).any(|c| pa[c].abs_diff(pb[c]) > tolerance))
        .count();
    bad as f64 / pixels.max(1) as f64
}

/// A heat map of the per-pixel difference (largest channel), scaled so that `full_scale`
/// maps to white: black = equal, red -> yellow -> white = growing error. RGBA8.
pub fn diff_heatmap_rgba8(a: &[u8], b: &[u8], full_scale: u8) -> Vec<u8> {
    assert_eq!(a.len(), b.len(), "images differ in size");
    let mut out = Vec::with_capacity(a.len());
    for (pa, pb) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        let d = (0..3).map(|c| pa[c].abs_diff(pb[c])).max().unwrap_or(0) as f32;
        let t = (d / full_scale.max(1) as f32).clamp(0.0, 1.0) * 3.0;
        let r = t.clamp(0.0, 1.0);
        let g = (t - 1.0).clamp(0.0, 1.0);
        let bl = (t - 2.0).clamp(0.0, 1.0);
        out.extend_from_slice(&[(r * 255.0) as u8, (g * 255.0) as u8, (bl * 255.0) as u8, 255]);
    }
    out
}

/// Count of non-finite values (NaN or Inf) in an f32 image.
pub fn non_finite_count(a: &[f32]) -> usize {
    a.iter().filter(|v| !v.is_finite()).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_on_known_differences() {
        let a = [0u8, 0, 0, 255, 10, 10, 10, 255];
        let b = [0u8, 0, 0, 255, 10, 10, 20, 255];
        assert_eq!(fraction_differing_rgba8(&a, &b, 5), 0.5);
        // MSE = 100 / 6.
        let psnr = psnr_rgba8(&a, &b);
        assert!((psnr - 10.0 * (255.0f64 * 255.0 * 6.0 / 100.0).log10()).abs() < 1e-9);
        assert!(psnr_rgba8(&a, &a).is_infinite());
        let fa = [1.0f32, 2.0, 3.0, 1.0];
        let fb = [1.0f32, 2.0, 6.0, 0.0];
        assert!((rmse_rgba(&fa, &fb) - 3.0f64.sqrt()).abs() < 1e-9);
        assert_eq!(non_finite_count(&[1.0, f32::NAN, f32::INFINITY]), 2);
    }
}

/// Errors of an image against a reference, as `prism compare` and `prism sweep` report them.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ErrorMetrics {
    /// Root-mean-square error of linear radiance over RGB.
    pub rmse: f64,
    /// PSNR of linear radiance in dB, with the reference's largest channel value as the peak.
    pub psnr_db: f64,
    /// Relative MSE of linear radiance: mean of (x - y)^2 / (y^2 + 0.01) over RGB, which weighs
    /// errors in dark regions like those in bright ones (the 0.01 keeps black pixels finite).
    pub rel_mse: f64,
    /// FLIP (Andersson et al. 2020) of the tone-mapped images at 67 pixels per degree
    /// (a 0.7 m viewing distance from a 24" 4K display): mean and 95th percentile.
    pub flip_mean: f64,
    pub flip_p95: f64,
}

/// Linear-radiance metrics of `test` against `reference` (RGBA f32, same size).
pub fn linear_metrics(test: &[f32], reference: &[f32]) -> (f64, f64, f64) {
    linear_metrics_over(test, reference, None)
}

/// [`linear_metrics`] over the pixels where `mask` is true (all pixels without one); the PSNR's
/// peak is the reference's largest channel value over those pixels.
fn linear_metrics_over(test: &[f32], reference: &[f32], mask: Option<&[bool]>) -> (f64, f64, f64) {
    assert_eq!(test.len(), reference.len(), "images differ in size");
    let (mut se, mut rel, mut n, mut peak) = (0.0f64, 0.0f64, 0usize, 0.0f64);
    for (i, (t, r)) in test.chunks_exact(4).zip(reference.chunks_exact(4)).enumerate() {
        if mask.is_some_and(|m| !m[i]) {
            continue;
        }
        for c in 0..3 {
            let (x, y) = (t[c] as f64, r[c] as f64);
            let d = x - y;
            se += d * d;
            rel += d * d / (y * y + 0.01);
            peak = peak.max(y);
            n += 1;
        }
    }
    let mse = se / n.max(1) as f64;
    let psnr = if mse == 0.0 { f64::INFINITY } else { 10.0 * (peak.max(1e-12).powi(2) / mse).log10() };
    (mse.sqrt(), psnr, rel / n.max(1) as f64)
}

/// The per-pixel FLIP map between two RGBA8 sRGB images.
fn flip_map(test: &[u8], reference: &[u8], width: u32, height: u32) -> nv_flip::FlipImageFloat {
    let rgb = |img: &[u8]| img.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect::<Vec<u8>>();
    let r = nv_flip::FlipImageRgb8::with_data(width, height, &rgb(reference));
    let t = nv_flip::FlipImageRgb8::with_data(width, height, &rgb(test));
    nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE)
}

/// Mean and 95th percentile of a FLIP map, by FLIP's own pool (its histogram percentile).
fn flip_stats(map: &nv_flip::FlipImageFloat) -> (f64, f64) {
    let mut pool = nv_flip::FlipPool::from_image(map);
    (pool.mean() as f64, pool.get_percentile(0.95, true) as f64)
}

/// FLIP between two RGBA8 sRGB images: (mean, 95th percentile, the error map as RGBA8 in the
/// magma colour map).
pub fn flip_rgba8(test: &[u8], reference: &[u8], width: u32, height: u32) -> (f64, f64, Vec<u8>) {
    let map = flip_map(test, reference, width, height);
    let (mean, p95) = flip_stats(&map);
    (mean, p95, heat_rgba8(&map))
}

/// A FLIP map as RGBA8 in the magma colour map.
fn heat_rgba8(map: &nv_flip::FlipImageFloat) -> Vec<u8> {
    let colored = map.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    colored.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect()
}

impl ErrorMetrics {
    /// All metrics of `test` against `reference`; the tone-mapped images are given too, so
    /// that FLIP sees exactly what the PNGs show. Returns the metrics and the FLIP heat map.
    pub fn between(
        test_hdr: &[f32],
        ref_hdr: &[f32],
        test_ldr: &[u8],
        ref_ldr: &[u8],
        width: u32,
        height: u32,
    ) -> (ErrorMetrics, Vec<u8>) {
        let (whole, _, heat) = Self::between_with_mask(test_hdr, ref_hdr, test_ldr, ref_ldr, width, height, None);
        (whole, heat)
    }

    /// [`ErrorMetrics::between`], and with a `mask` (row-major, one per pixel;
    /// src/metrics/mask.rs) the same metrics over the pixels where it is true only, `None`
    /// when it holds no pixel. RMSE, PSNR and relMSE over the mask are [`linear_metrics`]'s
    /// sums over those pixels alone (PSNR's peak: the reference's largest value there), so
    /// where the images differ only inside the mask, RMSE_mask^2 N_mask = RMSE^2 N. FLIP is
    /// computed once on the whole image (its filters see each pixel's neighbourhood, inside the
    /// mask or not) and its per-pixel map is pooled over the mask: the mean and 95th
    /// percentile of the map's values there.
    pub fn between_with_mask(
        test_hdr: &[f32],
        ref_hdr: &[f32],
        test_ldr: &[u8],
        ref_ldr: &[u8],
        width: u32,
        height: u32,
        mask: Option<&[bool]>,
    ) -> (ErrorMetrics, Option<ErrorMetrics>, Vec<u8>) {
        let (rmse, psnr_db, rel_mse) = linear_metrics(test_hdr, ref_hdr);
        let map = flip_map(test_ldr, ref_ldr, width, height);
        let (flip_mean, flip_p95) = flip_stats(&map);
        let whole = ErrorMetrics { rmse, psnr_db, rel_mse, flip_mean, flip_p95 };
        let masked = mask.and_then(|mask| {
            assert_eq!(mask.len(), (width * height) as usize, "the mask differs in size from the images");
            let values = map.to_vec();
            let inside: Vec<f32> = values.iter().zip(mask).filter(|(_, &m)| m).map(|(&v, _)| v).collect();
            if inside.is_empty() {
                return None;
            }
            let (rmse, psnr_db, rel_mse) = linear_metrics_over(test_hdr, ref_hdr, Some(mask));
            let (flip_mean, flip_p95) =
                flip_stats(&nv_flip::FlipImageFloat::with_data(inside.len() as u32, 1, &inside));
            Some(ErrorMetrics { rmse, psnr_db, rel_mse, flip_mean, flip_p95 })
        });
        (whole, masked, heat_rgba8(&map))
    }
}

#[cfg(test)]
mod error_tests {
    use super::*;

    #[test]
    fn linear_metrics_of_a_known_error() {
        let reference = [1.0f32, 0.0, 0.5, 1.0, 0.2, 0.2, 0.2, 1.0];
        let test = [1.1f32, 0.0, 0.5, 1.0, 0.2, 0.2, 0.2, 1.0];
        let (rmse, psnr, rel) = linear_metrics(&test, &reference);
        assert!((rmse - (0.01f64 / 6.0).sqrt()).abs() < 1e-7);
        assert!((psnr - 10.0 * (1.0 / (0.01 / 6.0f64)).log10()).abs() < 1e-4);
        assert!((rel - 0.01 / 1.01 / 6.0).abs() < 1e-7);
    }

    #[test]
    fn flip_is_zero_for_equal_images_and_grows_with_difference() {
        let a: Vec<u8> = (0..32 * 32).flat_map(|i| [(i % 256) as u8, 100, 50, 255]).collect();
        let mut b = a.clone();
        assert!(flip_rgba8(&a, &b, 32, 32).0 < 1e-6);
        for p in b.chunks_exact_mut(4).take(256) {
            p[1] = 250;
        }
        let (mean, p95, heat) = flip_rgba8(&b, &a, 32, 32);
        assert!(mean > 0.01 && p95 > mean, "{mean} {p95}");
        assert_eq!(heat.len(), 32 * 32 * 4);
    }

    #[test]
    fn masked_metrics_are_the_metrics_of_the_masked_pixels() {
        let (w, h) = (16u32, 16u32);
        let reference: Vec<f32> = (0..w * h).flat_map(|i| [0.2 + 0.001 * i as f32, 0.5, 0.3, 1.0]).collect();
        let mut test = reference.clone();
        let mask: Vec<bool> = (0..w * h).map(|i| (i % w) >= 4 && (i / w) < 6).collect();
        for (i, p) in test.chunks_exact_mut(4).enumerate() {
            if mask[i] {
                p[0] += 0.05 * (i % 7) as f32;
            }
        }
        let ldr = |img: &[f32]| img.iter().map(|&v| (v.clamp(0.0, 1.0) * 255.0) as u8).collect::<Vec<u8>>();
        let (tl, rl) = (ldr(&test), ldr(&reference));
        let (all, masked, _) = ErrorMetrics::between_with_mask(&test, &reference, &tl, &rl, w, h, Some(&mask));
        let masked = masked.unwrap();
        assert_eq!(ErrorMetrics::between(&test, &reference, &tl, &rl, w, h).0, all);
        // Every differing pixel is inside: the squared errors' sum is the same.
        let n = mask.iter().filter(|&&m| m).count() as f64;
        let (sum_all, sum_mask) = (all.rmse.powi(2) * (w * h) as f64, masked.rmse.powi(2) * n);
        assert!((sum_all - sum_mask).abs() <= 1e-9 * sum_all, "{sum_all} {sum_mask}");
        assert!((all.rel_mse * (w * h) as f64 - masked.rel_mse * n).abs() < 1e-9);
        // FLIP over the mask is the mean of the whole image's map over the mask.
        let map = flip_map(&tl, &rl, w, h).to_vec();
        let mean = map.iter().zip(&mask).filter(|(_, &m)| m).map(|(&v, _)| v as f64).sum::<f64>() / n;
        assert!((masked.flip_mean - mean).abs() < 1e-6, "{} {mean}", masked.flip_mean);
        // The whole mask gives the whole-image metrics; an empty one gives none.
        let with = |m: &[bool]| ErrorMetrics::between_with_mask(&test, &reference, &tl, &rl, w, h, Some(m)).1;
        let full = with(&vec![true; (w * h) as usize]).unwrap();
        assert_eq!((full.rmse, full.psnr_db, full.rel_mse), (all.rmse, all.psnr_db, all.rel_mse));
        assert!((full.flip_mean - all.flip_mean).abs() < 1e-6 && (full.flip_p95 - all.flip_p95).abs() < 1e-6);
        assert!(with(&vec![false; (w * h) as usize]).is_none());
    }
}
