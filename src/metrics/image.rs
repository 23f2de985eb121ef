//! Error between two images of the same size.

/// Root-mean-square error over the RGB channels of two RGBA f32 images.
pub fn rmse_rgba(a: &[f32], b: &[f32]) -> f64 {
    assert_eq!(a.len(), b.len(), "images differ in size");
    let mut sum = 0.0f64;
    let mut n = 0usize;
    for (pa, pb) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        for c in 0..3 {
            let d = pa[c] as f64 - pb[c] as f64;
            sum += d * d;
            n += 1;
        }
    }
    (sum / n.max(1) as f64).sqrt()
}

/// Peak signal-to-noise ratio in dB for 8-bit RGBA images (peak 255), over RGB.
/// Infinite for identical images.
pub fn psnr_rgba8(a: &[u8], b: &[u8]) -> f64 {
    assert_eq!(a.len(), b.len(), "images differ in size");
    let mut sum = 0.0f64;
    let mut n = 0usize;
    for (pa, pb) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        for c in 0..3 {
            let d = pa[c] as f64 - pb[c] as f64;
            sum += d * d;
            n += 1;
        }
    }
    let mse = sum / n.max(1) as f64;
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
