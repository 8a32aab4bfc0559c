//! Phantoms that defeat a start from the dynamic range or a fixed number of
//! phases: close phase means, salt-and-pepper specks, and `N` phases of
//! evenly spaced levels (for choosing the number of phases).

use super::shapes2d::{four_phase, four_phase_labels, label_map, sq, two_phase};
use super::{Phantom2, RenderOptions};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Levels of [`three_close`]: 0.15 apart.
pub const THREE_CLOSE_LEVELS: [f64; 3] = [0.35, 0.5, 0.65];

/// Levels of [`four_close`]: 0.1 apart.
pub const FOUR_CLOSE_LEVELS: [f64; 4] = [0.35, 0.45, 0.55, 0.65];

/// Fraction of the pixels [`with_specks`] sets to 0 or 1.
pub const SPECK_FRACTION: f64 = 0.005;

/// The four-phase geometry with phase 3 merged into phase 1 and levels
/// 0.35 / 0.5 / 0.65: three phases whose means are close.
pub fn three_close(size: usize, noise_sigma: f64, seed: u64) -> Phantom2 {
    let truth: Vec<u8> = four_phase_labels(size)
        .into_iter()
        .map(|l| if l == 3 { 1 } else { l })
        .collect();
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom2::from_labels(size, size, truth, &THREE_CLOSE_LEVELS, &opts)
}

/// The four-phase geometry with levels 0.35 / 0.45 / 0.55 / 0.65.
pub fn four_close(size: usize, noise_sigma: f64, seed: u64) -> Phantom2 {
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom2::from_labels(
        size,
        size,
        four_phase_labels(size),
        &FOUR_CLOSE_LEVELS,
        &opts,
    )
}

/// `ph` with [`SPECK_FRACTION`] of its pixels, drawn at random (seeded),
/// set to 0 or 1 (half each): outliers that are not a phase.
pub fn with_specks(mut ph: Phantom2, seed: u64) -> Phantom2 {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_5bec);
    let n = ph.image.len();
    let specks = (n as f64 * SPECK_FRACTION).round() as usize;
    for k in 0..specks {
        let p = rng.random_range(0..n);
        ph.image[p] = (k % 2) as f32;
    }
    ph
}

/// [`two_phase`] with salt-and-pepper specks.
pub fn two_phase_specks(size: usize, noise_sigma: f64, seed: u64) -> Phantom2 {
    with_specks(two_phase(size, noise_sigma, seed), seed)
}

/// [`four_phase`] with salt-and-pepper specks.
pub fn four_phase_specks(size: usize, noise_sigma: f64, seed: u64) -> Phantom2 {
    with_specks(four_phase(size, noise_sigma, seed), seed)
}

/// Ground truth of [`disks`]: a 4×4 grid of disks and squares of radius
/// 0.05–0.09 (some overlapping their neighbours) on phase 0; shape `t`
/// (row-major) has phase `1 + t mod (N − 1)`, so every phase has several.
pub fn disks_labels(size: usize, phases: usize) -> Vec<u8> {
    let others = phases.max(2) - 1;
    label_map(size, |x, y| {
        let mut lab = 0;
        for t in 0..16 {
            let (i, j) = ((t % 4) as f64, (t / 4) as f64);
            let (cx, cy) = (0.14 + 0.24 * i, 0.14 + 0.24 * j);
            let r = 0.05 + 0.01 * ((t * 7) % 5) as f64;
            let inside = if t % 2 == 0 {
                sq(x - cx) + sq(y - cy) < sq(r)
            } else {
                (x - cx).abs() < r && (y - cy).abs() < r
            };
            if inside {
                lab = 1 + (t % others) as u8;
            }
        }
        lab
    })
}

/// `phases` phases (2..=8) with evenly spaced levels from 0.15 to 0.85 on
/// the geometry of [`disks_labels`].
pub fn disks(size: usize, phases: usize, noise_sigma: f64, seed: u64) -> Phantom2 {
    let levels: Vec<f64> = (0..phases)
        .map(|k| 0.15 + 0.7 * k as f64 / (phases - 1) as f64)
        .collect();
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom2::from_labels(size, size, disks_labels(size, phases), &levels, &opts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phantoms_have_their_phases_and_specks() {
        for n in 2..=6 {
            let ph = disks(64, n, 0.0, 1);
            assert_eq!(ph.phases, n);
            assert!(ph.phase_counts().iter().all(|&c| c > 0), "{n}");
        }
        let ph = three_close(64, 0.0, 1);
        assert!(ph.phase_counts().iter().all(|&c| c > 0));
        let clean = two_phase(64, 0.0, 1);
        let specked = two_phase_specks(64, 0.0, 1);
        let changed = clean
            .image
            .iter()
            .zip(&specked.image)
            .filter(|(a, b)| a != b)
            .count();
        assert!(changed > 0 && changed <= (64.0 * 64.0 * SPECK_FRACTION) as usize + 1);
    }
}
