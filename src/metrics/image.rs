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
    /// HDR-FLIP (Andersson et al. 2021; [`hdr_flip_map`]) of the linear images, at the same
    /// pixels per degree: LDR FLIP at each of the reference's exposures, the per-pixel maximum,
    /// its mean and 95th percentile. Unlike `flip_*`, it sees errors above the display's range.
    /// Absent (0) in measurements written before it existed.
    #[serde(default)]
    pub hdr_flip_mean: f64,
    #[serde(default)]
    pub hdr_flip_p95: f64,
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

/// The per-pixel FLIP values between two RGBA8 sRGB images, row-major.
pub fn flip_values(test: &[u8], reference: &[u8], width: u32, height: u32) -> Vec<f32> {
    flip_map(test, reference, width, height).to_vec()
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

/// FLIP's ACES fit, (c0 x^2 + c1 x + c2) / (c3 x^2 + c4 x + c5) per channel, its default tone
/// mapper for HDR-FLIP (FLIP's tensor.h, `ToneMappingCoefficients[1]`: Narkowicz's fit of the
/// ACES curve with its 0.6 pre-exposure folded into the coefficients).
const ACES: [f32; 6] = [0.6 * 0.6 * 2.51, 0.6 * 0.03, 0.0, 0.6 * 0.6 * 2.43, 0.6 * 0.59, 0.14];

/// The ACES fit of one linear channel (FLIP's tensor.h, `toneMap("aces")`).
fn aces(x: f32) -> f32 {
    let c = ACES;
    (x * x * c[0] + x * c[1] + c[2]) / (x * x * c[3] + x * c[4] + c[5])
}

/// sRGB encoding of a linear channel in [0, 1] (FLIP's color.h, `LinearRGB2sRGB`).
fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Luminance of linear Rec. 709 RGB (FLIP's color.h, `linearRGB2Luminance`).
fn luminance(p: &[f32]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

/// The tone-mapped value FLIP places the reference's extremes at when choosing exposures
/// (FLIP's image.h, `computeExposures`: `t = 0.85`).
const EXPOSURE_TARGET: f32 = 0.85;

/// The exposures HDR-FLIP evaluates: `count` stops evenly spaced from `start` to `stop`, in
/// log2 units (an image is multiplied by 2^exposure before tone mapping).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exposures {
    pub start: f32,
    pub stop: f32,
    pub count: usize,
}

impl Exposures {
    /// FLIP's defaults for the ACES tone mapper, from the reference alone (Andersson et al.
    /// 2021; FLIP's image.h, `computeExposures`, and the exposure count of FLIP's command-line
    /// tool, FLIP.cpp, which nv-flip-sys does not ship): with
    /// x_max the input that ACES maps to 0.85 (the larger root of
    /// (c0 - 0.85 c3) x^2 + (c1 - 0.85 c4) x + (c2 - 0.85 c5) = 0),
    /// start = log2(x_max / Y_max), which brings the brightest pixel to 0.85, and
    /// stop = log2(x_max / Y_median), which brings the median to 0.85; Y is the luminance of
    /// linear RGB and the median the mean of the two middle values of the sorted luminances
    /// (the lower of them at index n/2 - 1). count = max(2, ceil(stop - start)), about one
    /// exposure per stop.
    ///
    /// Where FLIP's rule has no value prism picks one: non-finite pixels are left out of the
    /// statistics (prism reports them separately); a median of 0 (more than half the image
    /// black) would make the stop infinite, so the smallest non-zero luminance, which
    /// `computeExposures` finds but does not use, takes its place; a black reference gives
    /// start = stop = 0.
    pub fn of_reference(reference: &[f32]) -> Exposures {
        let c = ACES;
        let t = EXPOSURE_TARGET;
        let (a, b, cc) = (c[0] - t * c[3], c[1] - t * c[4], c[2] - t * c[5]);
        // FLIP's sharedflip.h, `solveSecondDegree`: the larger root.
        let x_max = if a == 0.0 {
            -cc / b
        } else {
            let d1 = -0.5 * (b / a);
            d1 + (d1 * d1 - cc / a).sqrt()
        };
        let mut lum: Vec<f32> = reference.chunks_exact(4).map(luminance).filter(|y| y.is_finite()).collect();
        lum.sort_by(f32::total_cmp);
        let y_max = lum.last().copied().unwrap_or(0.0);
        if y_max <= 0.0 {
            return Exposures { start: 0.0, stop: 0.0, count: 2 };
        }
        let y_median = match lum.len() {
            1 => lum[0],
            n => 0.5 * (lum[n / 2 - 1] + lum[n / 2]),
        };
        let y_median = if y_median > 0.0 { y_median } else { lum.iter().copied().find(|&y| y > 0.0).unwrap_or(y_max) };
        let (start, stop) = ((x_max / y_max).log2(), (x_max / y_median).log2());
        Exposures { start, stop, count: (stop - start).ceil().max(2.0) as usize }
    }

    /// The `i`-th exposure (FLIP.cpp: start + i (stop - start) / (count - 1)).
    pub fn at(&self, i: usize) -> f32 {
        let step = (self.stop - self.start) / (self.count - 1) as f32;
        self.start + i as f32 * step
    }
}

/// An RGBA f32 linear image at `exposure` as FLIP's LDR path takes it, RGB8: multiplied by
/// 2^exposure, ACES, clamped to [0, 1], sRGB-encoded (FLIP.cpp's exposure loop: `expose`,
/// `toneMap`, `clamp`, `LinearRGB2sRGB`), then rounded to 8 bits, the one step FLIP does not
/// take (see [`hdr_flip_map`]).
fn exposed_rgb8(image: &[f32], exposure: f32) -> Vec<u8> {
    let m = 2.0f32.powf(exposure);
    let encode = |v: f32| (linear_to_srgb(aces(v * m).clamp(0.0, 1.0)) * 255.0 + 0.5) as u8;
    image.chunks_exact(4).flat_map(|p| [encode(p[0]), encode(p[1]), encode(p[2])]).collect()
}

/// The LDR-FLIP map of two RGB8 sRGB images, as a flat vector (row-major).
fn flip_map_rgb8(test: &[u8], reference: &[u8], width: u32, height: u32) -> Vec<f32> {
    let r = nv_flip::FlipImageRgb8::with_data(width, height, reference);
    let t = nv_flip::FlipImageRgb8::with_data(width, height, test);
    nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec()
}

/// The HDR-FLIP map (Andersson et al. 2021, "Visualizing Errors in Rendered High Dynamic
/// Range Images", Eurographics short paper) of two RGBA f32 linear-radiance images, and the
/// exposures it took.
/// Both images are exposed at each of the reference's [`Exposures::of_reference`], tone
/// mapped with ACES, clamped and sRGB-encoded, LDR-FLIP is computed per exposure (through
/// `nv_flip`, at prism's 67 pixels per degree), and each pixel keeps its largest error over
/// the exposures (FLIP.cpp's exposure loop and image.h's `setMaxExposure`). An error in
/// radiance above 1, which a display mapping clamps away, shows at the exposure that brings it
/// into range.
///
/// One departure: `nv_flip` takes RGB8 images, so each exposure's encoded image is rounded to
/// 8 bits, where FLIP keeps floats. Rounding moves each channel by at most half a quantum
/// (1/510 of the sRGB range): two images whose encoded channels round alike at every
/// exposure get 0 (a difference under half a quantum vanishes), and two that are equal
/// before rounding stay equal. Two values on either side of a rounding boundary become one
/// quantum apart: in a flat region that adds at most the FLIP of a uniform grey against the
/// next 8-bit level, 0.036 at most over all 255 steps (levels 24 and 25, where the lightness
/// L* changes most per level; closed form in `one_quantum_flip_is_bounded`).
pub fn hdr_flip_map(test: &[f32], reference: &[f32], width: u32, height: u32) -> (Vec<f32>, Exposures) {
    assert_eq!(test.len(), reference.len(), "images differ in size");
    let exposures = Exposures::of_reference(reference);
    let mut map = vec![0.0f32; (width * height) as usize];
    for i in 0..exposures.count {
        let e = exposures.at(i);
        let ldr = flip_map_rgb8(&exposed_rgb8(test, e), &exposed_rgb8(reference, e), width, height);
        for (m, v) in map.iter_mut().zip(ldr) {
            *m = m.max(v);
        }
    }
    (map, exposures)
}

/// Mean and 95th percentile of a flat FLIP map, by FLIP's own pool.
fn flip_stats_of(values: &[f32]) -> (f64, f64) {
    flip_stats(&nv_flip::FlipImageFloat::with_data(values.len() as u32, 1, values))
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
    /// percentile of the map's values there. HDR-FLIP likewise: its map, from the whole
    /// images at the whole reference's exposures, pooled over the mask.
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
        let (hdr_map, _) = hdr_flip_map(test_hdr, ref_hdr, width, height);
        let (hdr_flip_mean, hdr_flip_p95) = flip_stats_of(&hdr_map);
        let whole = ErrorMetrics { rmse, psnr_db, rel_mse, flip_mean, flip_p95, hdr_flip_mean, hdr_flip_p95 };
        let masked = mask.and_then(|mask| {
            assert_eq!(mask.len(), (width * height) as usize, "the mask differs in size from the images");
            let inside =
                |values: &[f32]| -> Vec<f32> { values.iter().zip(mask).filter(|(_, &m)| m).map(|(&v, _)| v).collect() };
            let ldr_inside = inside(&map.to_vec());
            if ldr_inside.is_empty() {
                return None;
            }
            let (rmse, psnr_db, rel_mse) = linear_metrics_over(test_hdr, ref_hdr, Some(mask));
            let (flip_mean, flip_p95) = flip_stats_of(&ldr_inside);
            let (hdr_flip_mean, hdr_flip_p95) = flip_stats_of(&inside(&hdr_map));
            Some(ErrorMetrics { rmse, psnr_db, rel_mse, flip_mean, flip_p95, hdr_flip_mean, hdr_flip_p95 })
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
        // HDR-FLIP over the mask likewise pools the whole image's HDR-FLIP map.
        let (hdr, _) = hdr_flip_map(&test, &reference, w, h);
        let hdr_mean = hdr.iter().zip(&mask).filter(|(_, &m)| m).map(|(&v, _)| v as f64).sum::<f64>() / n;
        assert!(
            hdr_mean > 0.0 && (masked.hdr_flip_mean - hdr_mean).abs() < 1e-6,
            "{} {hdr_mean}",
            masked.hdr_flip_mean
        );
        // The whole mask gives the whole-image metrics; an empty one gives none.
        let with = |m: &[bool]| ErrorMetrics::between_with_mask(&test, &reference, &tl, &rl, w, h, Some(m)).1;
        let full = with(&vec![true; (w * h) as usize]).unwrap();
        assert_eq!((full.rmse, full.psnr_db, full.rel_mse), (all.rmse, all.psnr_db, all.rel_mse));
        assert!((full.flip_mean - all.flip_mean).abs() < 1e-6 && (full.flip_p95 - all.flip_p95).abs() < 1e-6);
        assert!(
            (full.hdr_flip_mean - all.hdr_flip_mean).abs() < 1e-6
                && (full.hdr_flip_p95 - all.hdr_flip_p95).abs() < 1e-6
        );
        assert!(with(&vec![false; (w * h) as usize]).is_none());
    }
}

#[cfg(test)]
mod hdr_flip_tests {
    use super::*;

    /// A `w` x `h` RGBA image of grey `v(x, y)`.
    fn grey(w: u32, h: u32, v: impl Fn(u32, u32) -> f32) -> Vec<f32> {
        (0..w * h)
            .flat_map(|i| {
                let g = v(i % w, i / w);
                [g, g, g, 1.0]
            })
            .collect()
    }

    /// FLIP between uniform sRGB greys `k1` and `k2` in closed form (Andersson et al. 2020,
    /// FLIP's colour pipeline; image.h's `computeColorDifference` in nv-flip-sys): on uniform images the spatial filters change nothing and the feature error is 0,
    /// so FLIP is the colour error alone. A grey's CIELAB a* and b* are 0, so the Hunt-adjusted
    /// HyAB distance is |L1 - L2|, L = 116 Y^(1/3) - 16 (Y > (6/29)^3, Y the linear grey, the
    /// D65 white's Y being 1), raised to q_c = 0.7 and redistributed with p_c = 0.4,
    /// p_t = 0.95 against c_max = HyAB(Hunt(green), Hunt(blue))^0.7 = 203.3017^0.7 = 41.2761
    /// (FLIP's color.h, `computeMaxDistance`).
    fn flip_of_greys(k1: u8, k2: u8) -> f64 {
        let lightness = |k: u8| {
            let s = k as f64 / 255.0;
            let y = if s <= 0.04045 { s / 12.92 } else { ((s + 0.055) / 1.055).powf(2.4) };
            let d = 6.0f64 / 29.0;
            let f = if y > d * d * d { y.cbrt() } else { y / (3.0 * d * d) + 4.0 / 29.0 };
            116.0 * f - 16.0
        };
        let e = (lightness(k1) - lightness(k2)).abs().powf(0.7);
        let (cmax, pc, pt) = (41.2761f64, 0.4, 0.95);
        if e < pc * cmax {
            e * pt / (pc * cmax)
        } else {
            pt + (e - pc * cmax) / (cmax - pc * cmax) * (1.0 - pt)
        }
    }

    fn uniform_rgba8(w: u32, h: u32, k: u8) -> Vec<u8> {
        (0..w * h).flat_map(|_| [k, k, k, 255]).collect()
    }

    #[test]
    fn hdr_flip_of_identical_images_is_zero() {
        let (w, h) = (24u32, 16u32);
        // Radiance from 0 to 50: above and below the display range.
        let img = grey(w, h, |x, y| 0.01 * ((x * 7 + y * 13) % 50) as f32 * (1.0 + (x + y) as f32));
        let (map, exposures) = hdr_flip_map(&img, &img, w, h);
        assert!(exposures.count >= 2);
        assert!(map.iter().all(|&v| v.abs() < 1e-6), "{:?}", map.iter().copied().fold(0.0f32, f32::max));
        let ldr: Vec<u8> = img.iter().map(|&v| (v.clamp(0.0, 1.0) * 255.0) as u8).collect();
        let (m, _) = ErrorMetrics::between(&img, &img, &ldr, &ldr, w, h);
        assert!(m.hdr_flip_mean < 1e-6 && m.hdr_flip_p95 < 1e-6, "{m:?}");
    }

    #[test]
    fn hdr_flip_sees_errors_above_one_that_clamping_hides() {
        let (w, h) = (16u32, 16u32);
        let (reference, test) = (grey(w, h, |_, _| 2.0), grey(w, h, |_, _| 8.0));
        // Clamped to [0, 1] both are white: LDR FLIP 0.
        let ldr: Vec<u8> = reference.iter().map(|&v| (v.clamp(0.0, 1.0) * 255.0) as u8).collect();
        let (m, _) = ErrorMetrics::between(&test, &reference, &ldr, &ldr, w, h);
        assert!(m.flip_mean < 1e-6, "{m:?}");
        // A uniform reference has Y_max = Y_median = 2, so start = stop = log2(x_max / 2): the
        // one exposure (taken twice) maps the reference to ACES(x_max) = 0.85, sRGB
        // 1.055 * 0.85^(1/2.4) - 0.055 = 0.93100, 8 bits round(237.39) = 237; the test's
        // 8.0 becomes 4 x_max = 8.47549, ACES (0.9036 * 71.834 + 0.018 * 8.4755) /
        // (0.8748 * 71.834 + 0.354 * 8.4755 + 0.14) = 0.98640, sRGB 0.99385, 8 bits
        // round(253.43) = 253.
        let (map, exposures) = hdr_flip_map(&test, &reference, w, h);
        assert_eq!(exposures.count, 2);
        assert_eq!(exposed_rgb8(&reference, exposures.at(0))[..3], [237, 237, 237]);
        assert_eq!(exposed_rgb8(&test, exposures.at(0))[..3], [253, 253, 253]);
        // So HDR-FLIP is the FLIP of uniform greys 237 and 253, 0.19125 in closed form; the
        // tolerance covers FLIP's f32 arithmetic.
        let expected = flip_of_greys(237, 253);
        assert!((expected - 0.19125).abs() < 1e-4, "{expected}");
        for &v in &map {
            assert!((v as f64 - expected).abs() < 1e-3, "{v} {expected}");
        }
        assert!((m.hdr_flip_mean - expected).abs() < 1e-3, "{m:?}");
    }

    #[test]
    fn exposures_follow_flips_defaults() {
        // Luminances 16 (pure green 16 / 0.7152: the weights matter), 0.4, 0.1, 0.2 (greys,
        // weights summing to 1). Sorted: 0.1, 0.2, 0.4, 16; n = 4, so the median is the mean of
        // indices n/2 - 1 = 1 and n/2 = 2: (0.2 + 0.4) / 2 = 0.3; Y_max = 16.
        // ACES at t = 0.85: a = 0.9036 - 0.85 * 0.8748 = 0.16002, b = 0.018 - 0.85 * 0.354 =
        // -0.2829, c = -0.85 * 0.14 = -0.119; d1 = -b / 2a = 0.883952,
        // x_max = d1 + sqrt(d1^2 - c / a) = 0.883952 + sqrt(0.781371 + 0.743657) = 2.118872.
        // start = log2(2.118872 / 16) = -2.916703, stop = log2(2.118872 / 0.3) = 2.820262,
        // count = max(2, ceil(5.736966)) = 6, step 5.736966 / 5 = 1.147393.
        let reference = [0.0, 16.0 / 0.7152, 0.0, 1.0, 0.4, 0.4, 0.4, 1.0, 0.1, 0.1, 0.1, 1.0, 0.2, 0.2, 0.2, 1.0];
        let e = Exposures::of_reference(&reference);
        assert!((e.start - -2.916703).abs() < 1e-4, "{e:?}");
        assert!((e.stop - 2.820262).abs() < 1e-4, "{e:?}");
        assert_eq!(e.count, 6);
        assert!((e.at(1) - (-2.916703 + 1.147393)).abs() < 1e-4 && (e.at(5) - e.stop).abs() < 1e-5);
        // ACES maps x_max to the target exactly (the root's definition).
        let x_max = 2.0f32.powf(e.start) * 16.0;
        assert!((aces(x_max) - 0.85).abs() < 1e-5 && (x_max - 2.118872).abs() < 1e-4);
    }

    #[test]
    fn exposures_where_flips_rule_has_no_value() {
        // More than half black: FLIP's median is 0 and its stop infinite; the smallest non-zero
        // luminance, 0.3, stands in (the NaN pixel is left out, so n = 5 and the middle values
        // at indices 1 and 2 are both 0): stop = log2(2.118872 / 0.3) = 2.820262, start =
        // log2(2.118872 / 4) = -0.916703, count = max(2, ceil(3.736966)) = 4.
        let g = |v: f32| [v, v, v, 1.0];
        let reference: Vec<f32> = [0.0, 0.0, 0.0, 0.3, 4.0, f32::NAN].into_iter().flat_map(g).collect();
        let e = Exposures::of_reference(&reference);
        assert!((e.start - -0.916703).abs() < 1e-4 && (e.stop - 2.820262).abs() < 1e-4, "{e:?}");
        assert_eq!(e.count, 4, "{e:?}");
        // A black reference: one exposure, 2^0, taken twice.
        let black: Vec<f32> = [0.0; 4].into_iter().flat_map(g).collect();
        assert_eq!(Exposures::of_reference(&black), Exposures { start: 0.0, stop: 0.0, count: 2 });
    }

    #[test]
    fn hdr_flip_is_the_per_pixel_maximum_over_exposures() {
        // 3/4 of the reference at 0.01 and 1/4 at 8: Y_max = 8, Y_median = 0.01, so
        // start = log2(2.118872 / 8) = -1.9167 and stop = log2(211.8872) = 7.7271: 10
        // exposures. A bright error (8 -> 12) shows at the low exposures and saturates at the
        // high ones (8 * 2^7.73 = 1695 -> ACES 1.03, clamped to 1 like 12's); a dark one
        // (0.01 -> 0.011) shows at the high exposures and vanishes at the start: there
        // 0.01 * 2^-1.9167 = 0.002649 -> ACES 3.83e-4 -> sRGB 0.00495 -> 8 bits round(1.26) = 1,
        // and 0.011 -> 0.002913 -> ACES 4.26e-4 -> 0.00551 -> round(1.40) = 1 too. A mean over
        // exposures would fall below the largest at both.
        let (w, h) = (32u32, 16u32);
        let reference = grey(w, h, |x, _| if x < 8 { 8.0 } else { 0.01 });
        let patch = |x: u32, y: u32| (4..12).contains(&y) && ((2..6).contains(&x) || (18..26).contains(&x));
        let test = grey(w, h, |x, y| {
            let r = if x < 8 { 8.0 } else { 0.01 };
            if patch(x, y) {
                r * if x < 8 { 1.5 } else { 1.1 }
            } else {
                r
            }
        });
        let (map, e) = hdr_flip_map(&test, &reference, w, h);
        assert_eq!(e.count, 10, "{e:?}");
        let per_exposure: Vec<Vec<f32>> = (0..e.count)
            .map(|i| flip_map_rgb8(&exposed_rgb8(&test, e.at(i)), &exposed_rgb8(&reference, e.at(i)), w, h))
            .collect();
        for (p, &v) in map.iter().enumerate() {
            let max = per_exposure.iter().map(|m| m[p]).fold(0.0f32, f32::max);
            assert_eq!(v, max, "pixel {p}");
        }
        // Each error is missed at one end of the range (FLIP 0 there) and found inside it (above
        // 0.1), so a mean over the exposures falls at least max / count below the maximum.
        let at = |x: u32, y: u32| (y * w + x) as usize;
        let (bright, dark) = (at(3, 8), at(21, 8));
        for (p, missed_at) in [(bright, e.count - 1), (dark, 0)] {
            let values: Vec<f32> = per_exposure.iter().map(|m| m[p]).collect();
            assert!(values[missed_at] < 1e-6 && map[p] > 0.1, "pixel {p}: {values:?}");
            let mean = values.iter().sum::<f32>() / e.count as f32;
            assert!(map[p] - mean >= map[p] / e.count as f32 - 1e-6, "pixel {p}: {} {mean}", map[p]);
        }
    }

    #[test]
    fn one_quantum_flip_is_bounded() {
        // nv_flip on uniform greys k and k + 1 agrees with the closed form, whose largest value
        // over k bounds what 8-bit rounding adds in a flat region (hdr_flip_map's doc).
        let (w, h) = (8u32, 8u32);
        let mut largest = (0.0f64, 0u8);
        for k in 0..255u8 {
            let (a, b) = (uniform_rgba8(w, h, k), uniform_rgba8(w, h, k + 1));
            let (mean, _, _) = flip_rgba8(&b, &a, w, h);
            let expected = flip_of_greys(k, k + 1);
            assert!((mean - expected).abs() < 1e-3, "level {k}: {mean} {expected}");
            if expected > largest.0 {
                largest = (expected, k);
            }
        }
        assert_eq!(largest.1, 24, "{largest:?}");
        assert!(largest.0 < 0.036, "{largest:?}");
    }
}
