//! Ranking two settings against one noisy reference: the difference of their errors, and how
//! far the reference's noise can move that difference.
//!
//! An error against a reference R = mu + n carries the reference's noise, and the interval of
//! src/app/equaltime.rs (`Noise`) bounds each error alone: for a sampled reference that bound
//! is wide (on caustic_sphere at 64 spp it spans every caustic technique's error). Two
//! settings measured against the *same* reference share most of it. For MSE exactly:
//!
//!     MSE(A, R) - MSE(B, R) = MSE(A, mu) - MSE(B, mu) - (2 / M) sum_p (A_p - B_p) n_p,
//!
//! so the noise's own MSE cancels and what is left weighs the noise by where the two settings
//! differ: a caustic that one technique draws and another misses is ranked by the noise inside
//! the caustic only, not by the whole image's noise. The sum's variance is estimated from the
//! second reference of [`crate::app`]'s noise measurement: R1 - R2 = n1 - n2 has twice the
//! noise's variance, and summing the products over blocks of [`BLOCK`]^2 pixels, larger than
//! the distance over which the noise of neighbouring pixels is correlated, makes the block
//! sums independent, so
//!
//!     Var = (4 / M^2) sum_blocks (sum_p (A_p - B_p)(R1_p - R2_p))^2 / 2.
//!
//! FLIP is not a sum of squares, so nothing cancels in closed form; its difference is taken
//! against R1 and again against R2, and the spread between the two, pooled the same way over
//! blocks, estimates the noise of the difference. Nor need the noise's effect on FLIP be the
//! same for both settings, so the difference may also be biased: for noise of small variance
//! s^2 a bias grows like s^2, so against the mean of the two references (s^2 / 2) it is half
//! of that against either, and twice the gap between the difference against either and the
//! difference against the mean estimates it ([`FlipMaps`]). Two settings are ranked when
//! their difference exceeds [`SEPARATION`] standard errors plus that bias.

/// Block side in pixels over which the noise's products are summed before squaring. The
/// reference's photons are gathered within a pixel's footprint, but FLIP filters each pixel's
/// error over its neighbours: at 67 pixels per degree (`ErrorMetrics`), its edge and point
/// detectors' Gaussians (sigma 0.082 degrees, 5.5 pixels) reach 3 sigma = 17 pixels, so blocks
/// of 32 hold nearly all of a pixel's influence. A 256^2 image has 64 of them: the variance
/// estimate itself is then good to about sqrt(2 / 64) = 18%.
pub const BLOCK: u32 = 32;

/// Standard errors by which a difference must exceed the noise to be ranked: 3, the rule of
/// the reference's flux checks (tests/reference.rs), a chance of 0.3% for a Gaussian.
pub const SEPARATION: f64 = 3.0;

/// The difference of two settings' errors against one reference (A's minus B's), its
/// standard error due to the reference's noise and the bias that noise may leave in it (0 for
/// MSE, where it cancels exactly).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Paired {
    pub difference: f64,
    pub standard_error: f64,
    pub bias: f64,
}

impl Paired {
    /// Whether the difference exceeds the reference's noise ([`SEPARATION`] standard errors
    /// and the bias).
    pub fn separated(&self) -> bool {
        self.difference.abs() > SEPARATION * self.standard_error + self.bias.abs()
    }
}

/// One setting's per-pixel FLIP maps (row-major) against the first reference R1, the second
/// R2 and their mean.
pub struct FlipMaps {
    pub r1: Vec<f32>,
    pub r2: Vec<f32>,
    pub mean: Vec<f32>,
}

/// The block index of each pixel, row-major, and the number of blocks.
fn blocks(width: u32, height: u32) -> (Vec<usize>, usize) {
    let (bw, bh) = (width.div_ceil(BLOCK) as usize, height.div_ceil(BLOCK) as usize);
    let index = (0..height as usize)
        .flat_map(|y| (0..width as usize).map(move |x| (y / BLOCK as usize) * bw + x / BLOCK as usize))
        .collect();
    (index, bw * bh)
}

/// Sum of the squared block sums of `per_pixel`.
fn squared_block_sums(per_pixel: impl Iterator<Item = f64>, width: u32, height: u32) -> f64 {
    let (index, count) = blocks(width, height);
    let mut sums = vec![0.0f64; count];
    for (b, v) in index.iter().zip(per_pixel) {
        sums[*b] += v;
    }
    sums.iter().map(|s| s * s).sum()
}

/// MSE(A, R1) - MSE(B, R1) over RGB of linear RGBA images, with its standard error from the
/// second reference R2 (see the module's text).
pub fn mse_difference(a: &[f32], b: &[f32], r1: &[f32], r2: &[f32], width: u32, height: u32) -> Paired {
    let n = (width * height) as usize;
    assert!([a.len(), b.len(), r1.len(), r2.len()].iter().all(|&l| l == 4 * n), "images differ in size");
    let m = 3.0 * n as f64;
    let pixels =
        || (0..n).map(|i| (&a[4 * i..4 * i + 3], &b[4 * i..4 * i + 3], &r1[4 * i..4 * i + 3], &r2[4 * i..4 * i + 3]));
    let difference = pixels()
        .map(|(a, b, r, _)| {
            (0..3).map(|c| (a[c] as f64 - r[c] as f64).powi(2) - (b[c] as f64 - r[c] as f64).powi(2)).sum::<f64>()
        })
        .sum::<f64>()
        / m;
    let products = pixels()
        .map(|(a, b, r1, r2)| (0..3).map(|c| (a[c] as f64 - b[c] as f64) * (r1[c] as f64 - r2[c] as f64)).sum::<f64>());
    let variance = 4.0 / (m * m) * squared_block_sums(products, width, height) / 2.0;
    Paired { difference, standard_error: variance.sqrt(), bias: 0.0 }
}

/// mean(FLIP(A, R1)) - mean(FLIP(B, R1)), with its standard error from the same difference
/// against R2 and its bias from the difference against their mean (see the module's text).
pub fn flip_difference(a: &FlipMaps, b: &FlipMaps, width: u32, height: u32) -> Paired {
    let n = (width * height) as usize;
    let maps = [&a.r1, &b.r1, &a.r2, &b.r2, &a.mean, &b.mean];
    assert!(maps.iter().all(|m| m.len() == n), "maps differ in size");
    let mean_difference = |x: &[f32], y: &[f32]| (0..n).map(|i| x[i] as f64 - y[i] as f64).sum::<f64>() / n as f64;
    let difference = mean_difference(&a.r1, &b.r1);
    let spread = (0..n).map(|i| (a.r1[i] as f64 - b.r1[i] as f64) - (a.r2[i] as f64 - b.r2[i] as f64));
    let variance = squared_block_sums(spread, width, height) / (2.0 * (n as f64).powi(2));
    let either = 0.5 * (difference + mean_difference(&a.r2, &b.r2));
    let bias = 2.0 * (either - mean_difference(&a.mean, &b.mean));
    Paired { difference, standard_error: variance.sqrt(), bias }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic Gaussian sequence (xorshift64 and Box-Muller), for noise.
    struct Gauss(u64);

    impl Gauss {
        fn uniform(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }

        fn next(&mut self) -> f64 {
            let (u, v) = (self.uniform(), self.uniform());
            (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
        }
    }

    const W: u32 = 128;
    const H: u32 = 128;

    /// A truth with a bright blob, technique A exact inside the blob and technique B a
    /// quarter too dark there, both slightly off elsewhere.
    fn scene() -> (Vec<f32>, Vec<f32>, Vec<f32>) {
        let mut truth = Vec::new();
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for y in 0..H {
            for x in 0..W {
                let r2 = ((x as f32 - 40.0).powi(2) + (y as f32 - 60.0).powi(2)) / 100.0;
                let v = 0.2 + 5.0 * (-r2).exp();
                let off = 0.02 * ((x + 3 * y) % 5) as f32;
                for c in 0..4 {
                    let t = if c == 3 { 1.0 } else { v };
                    truth.push(t);
                    a.push(if c == 3 { 1.0 } else { v + off });
                    b.push(if c == 3 { 1.0 } else { 0.2 + off + 0.75 * (v - 0.2) });
                }
            }
        }
        (truth, a, b)
    }

    /// A reference: the truth plus noise of standard deviation `sigma`, correlated over 2x2
    /// pixels (one draw per 2x2 cell, as photons gathered over a footprint of two pixels).
    fn reference(truth: &[f32], sigma: f64, g: &mut Gauss) -> Vec<f32> {
        let cells: Vec<f64> = (0..(W / 2) * (H / 2) * 3).map(|_| sigma * g.next()).collect();
        let mut r = truth.to_vec();
        for y in 0..H {
            for x in 0..W {
                for c in 0..3 {
                    let cell = (((y / 2) * (W / 2) + x / 2) * 3 + c) as usize;
                    r[((y * W + x) * 4 + c) as usize] += cells[cell] as f32;
                }
            }
        }
        r
    }

    fn mse(a: &[f32], b: &[f32]) -> f64 {
        let (s, n) = a.chunks_exact(4).zip(b.chunks_exact(4)).fold((0.0, 0usize), |(s, n), (p, q)| {
            (s + (0..3).map(|c| (p[c] as f64 - q[c] as f64).powi(2)).sum::<f64>(), n + 3)
        });
        s / n as f64
    }

    /// The standard error matches the spread of the difference over many references, and the
    /// true difference lies within it: the rule ranks what a noise-free reference ranks,
    /// where the per-error intervals (one noise RMSE wide) cannot.
    #[test]
    fn the_mse_difference_s_standard_error_is_the_spread_over_references() {
        let (truth, a, b) = scene();
        let true_difference = mse(&a, &truth) - mse(&b, &truth);
        let mut g = Gauss(0x9e37_79b9_7f4a_7c15);
        let sigma = 0.5;
        let runs: Vec<Paired> = (0..100)
            .map(|_| {
                let (r1, r2) = (reference(&truth, sigma, &mut g), reference(&truth, sigma, &mut g));
                mse_difference(&a, &b, &r1, &r2, W, H)
            })
            .collect();
        let mean = runs.iter().map(|p| p.difference).sum::<f64>() / runs.len() as f64;
        let spread = (runs.iter().map(|p| (p.difference - mean).powi(2)).sum::<f64>() / (runs.len() - 1) as f64).sqrt();
        let estimated = runs.iter().map(|p| p.standard_error).sum::<f64>() / runs.len() as f64;
        // The mean of 100 differences is within 3 of their standard errors of the truth (the
        // noise's own MSE, 0.25 here, has cancelled: it is 1000x the difference).
        assert!(
            (mean - true_difference).abs() < 3.0 * spread / (runs.len() as f64).sqrt(),
            "{mean} {true_difference} {spread}"
        );
        // The estimates (16 blocks each: 18% apiece, 2% for their mean over 100 runs) match
        // the spread over 100 pairs (itself good to 7%) within 25%, over 3 of those errors; a
        // factor sqrt(2) wrong (R1 - R2 taken for the noise itself) would be 41% or 29% off.
        assert!((estimated / spread - 1.0).abs() < 0.25, "estimated {estimated}, measured spread {spread}");
        // Ranked every time: the difference is far beyond its standard error...
        assert!(runs.iter().all(|p| p.separated() && p.difference < 0.0), "{runs:?}");
        // ...while the per-error intervals [e - s, e] of each overlap: s = 0.5 is the noise
        // RMSE, far more than the two errors' distance.
        let e = |t: &[f32], r: &[f32]| mse(t, r).sqrt();
        let r = reference(&truth, sigma, &mut g);
        assert!((e(&a, &r) - e(&b, &r)).abs() < sigma);
    }

    /// Two settings that differ by nothing but an offset the noise hides are not ranked.
    #[test]
    fn equal_errors_are_not_ranked() {
        let (truth, a, _) = scene();
        // B: A with the offset mirrored, so the two have the same error against the truth.
        let b: Vec<f32> =
            a.iter().zip(&truth).enumerate().map(|(i, (x, t))| if i % 4 == 3 { 1.0 } else { 2.0 * t - x }).collect();
        assert!((mse(&a, &truth) - mse(&b, &truth)).abs() < 1e-9);
        let mut g = Gauss(7);
        let ranked = (0..40)
            .filter(|_| {
                let (r1, r2) = (reference(&truth, 0.5, &mut g), reference(&truth, 0.5, &mut g));
                mse_difference(&a, &b, &r1, &r2, W, H).separated()
            })
            .count();
        // 3 standard errors: 0.3% each for a Gaussian; with the estimate's own spread a few
        // percent, so at most 2 of 40.
        assert!(ranked <= 2, "{ranked} of 40 ranked");
    }

    #[test]
    fn flip_difference_pools_the_spread_between_references_and_takes_out_the_bias() {
        let (w, h) = (64u32, 64u32);
        let n = (w * h) as usize;
        let flat = |v: f32| vec![v; n];
        let maps = |r1: f32, r2: f32, mean: f32| FlipMaps { r1: flat(r1), r2: flat(r2), mean: flat(mean) };
        // The same maps against every reference: no spread, no bias, the difference exact.
        let a = maps(0.2, 0.2, 0.2);
        let p = flip_difference(&a, &maps(0.1, 0.1, 0.1), w, h);
        assert!((p.difference - 0.1).abs() < 1e-7 && p.standard_error == 0.0 && p.bias.abs() < 1e-7, "{p:?}");
        assert!(p.separated());
        // Against R2 every pixel's difference is 0.1 smaller: the block sums are 1024 * 0.1
        // in each of 4 blocks, variance 4 * 102.4^2 / (2 * 4096^2), standard error 0.0354.
        let p = flip_difference(&a, &maps(0.1, 0.2, 0.15), w, h);
        assert!((p.standard_error - (4.0f64 * 102.4 * 102.4 / (2.0 * 4096.0 * 4096.0)).sqrt()).abs() < 1e-6, "{p:?}");
        assert!(!p.separated());
        // A difference of 0.1 against either reference and 0.075 against their mean: a bias
        // of 2 x 0.025 = 0.05 (the noise-free difference extrapolates to 0.05), so a standard
        // error that alone would rank it (0.1 > 3 x 0.02) does not.
        let p = flip_difference(&a, &maps(0.1, 0.1, 0.125), w, h);
        assert!((p.bias - 0.05).abs() < 1e-6 && p.standard_error == 0.0, "{p:?}");
        let p = Paired { standard_error: 0.02, ..p };
        assert!(!p.separated());
    }
}
