//! Additive Gaussian noise (seeded ChaCha RNG), clipping and 8-bit
//! quantisation of the phantoms.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Adds `N(0, sigma²)` noise to every sample (in storage order) from a
/// `ChaCha8Rng` seeded with `seed`, then clips to `[0, 1]`.
/// Deterministic for a given seed; `sigma <= 0` only clips.
pub fn add_gaussian_noise(image: &mut [f32], sigma: f64, seed: u64) {
    let mut wide: Vec<f64> = image.iter().map(|&v| v as f64).collect();
    add_gaussian_noise_f64(&mut wide, sigma, seed);
    image
        .iter_mut()
        .zip(&wide)
        .for_each(|(v, &w)| *v = w as f32);
}

/// [`add_gaussian_noise`] on `f64` samples; the same seed draws the same
/// noise sequence.
pub fn add_gaussian_noise_f64(image: &mut [f64], sigma: f64, seed: u64) {
    if sigma > 0.0 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        for v in image.iter_mut() {
            let n: f64 = StandardNormal.sample(&mut rng);
            *v += sigma * n;
        }
    }
    for v in image.iter_mut() {
        *v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    }
}

/// Adds noise smoothed over a few samples, as a reconstructed CT or MRI
/// slice has, to the `width`-wide 2D `image`: `N(0, 1)` noise (seeded with
/// `seed`) blurred `passes` times by a box of 3 samples along x and then y
/// (edges clamped), scaled to standard deviation `sigma`; then clips to
/// `[0, 1]`.
pub fn add_smoothed_noise_2d(
    image: &mut [f32],
    width: usize,
    sigma: f64,
    passes: usize,
    seed: u64,
) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut noise: Vec<f64> = (0..image.len())
        .map(|_| StandardNormal.sample(&mut rng))
        .collect();
    for _ in 0..passes {
        noise = box_blur_3(&box_blur_3(&noise, width, 1), width, width);
    }
    let spread = (noise.iter().map(|v| v * v).sum::<f64>() / noise.len().max(1) as f64).sqrt();
    for (v, n) in image.iter_mut().zip(&noise) {
        *v += (sigma * n / spread.max(f64::MIN_POSITIVE)) as f32;
    }
    clip_unit(image);
}

/// The mean of each sample and its neighbours `step` samples before and
/// after in storage order (`step` 1: along x; `width`: along y), the
/// neighbours clamped to the image's rows and columns.
fn box_blur_3(data: &[f64], width: usize, step: usize) -> Vec<f64> {
    (0..data.len())
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let before = if (step == 1 && x > 0) || (step > 1 && y > 0) {
                i - step
            } else {
                i
            };
            let last_row = data.len() / width - 1;
            let after = if (step == 1 && x + 1 < width) || (step > 1 && y < last_row) {
                i + step
            } else {
                i
            };
            (data[before] + data[i] + data[after]) / 3.0
        })
        .collect()
}

/// Clips every sample to `[0, 1]` (NaN becomes 0).
pub fn clip_unit(image: &mut [f32]) {
    for v in image.iter_mut() {
        *v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    }
}

/// Converts a `[0, 1]` sample to 8 bit like NumPy's `rint`:
/// `rint(clip(v, 0, 1) · 255)` with ties to even.
pub fn to_u8(v: f64) -> u8 {
    let c = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    (c * 255.0).round_ties_even() as u8
}

/// Quantises every sample to the 8-bit grid `k / 255` in place (see [`to_u8`]).
pub fn quantize_8bit(image: &mut [f32]) {
    for v in image.iter_mut() {
        *v = to_u8(*v as f64) as f32 / 255.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The smoothed noise has the asked spread, and neighbours that share
    /// most of it.
    #[test]
    fn smoothed_noise_is_correlated_at_its_spread() {
        let side = 128;
        let mut image = vec![0.5f32; side * side];
        add_smoothed_noise_2d(&mut image, side, 0.1, 2, 9);
        let n: Vec<f64> = image.iter().map(|&v| v as f64 - 0.5).collect();
        let var = n.iter().map(|v| v * v).sum::<f64>() / n.len() as f64;
        assert!((var.sqrt() - 0.1).abs() < 0.005, "{}", var.sqrt());
        let neighbours = (0..n.len() - 1)
            .filter(|i| (i + 1) % side != 0)
            .map(|i| n[i] * n[i + 1])
            .sum::<f64>()
            / (n.len() - side) as f64;
        assert!(neighbours / var > 0.7, "{}", neighbours / var);
    }

    #[test]
    fn noise_is_deterministic_and_clipped() {
        let mut a = vec![0.5f32; 1000];
        let mut b = a.clone();
        let mut c = a.clone();
        add_gaussian_noise(&mut a, 0.3, 7);
        add_gaussian_noise(&mut b, 0.3, 7);
        add_gaussian_noise(&mut c, 0.3, 8);
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert!(a.iter().all(|v| (0.0..=1.0).contains(v)));
        let mean: f32 = a.iter().sum::<f32>() / a.len() as f32;
        assert!((mean - 0.5).abs() < 0.03);
    }

    #[test]
    fn quantisation_rounds_half_to_even() {
        assert_eq!(to_u8(0.0), 0);
        assert_eq!(to_u8(1.0), 255);
        assert_eq!(to_u8(2.0), 255);
        assert_eq!(to_u8(-1.0), 0);
        // 0.3 * 255 == 76.5 in f64, ties to even like numpy.rint
        assert_eq!(to_u8(0.3), 76);
        assert_eq!(to_u8(0.7), 178);
        let mut v = vec![0.2f32, 0.8];
        quantize_8bit(&mut v);
        assert_eq!(v, vec![51.0 / 255.0, 204.0 / 255.0]);
    }
}
