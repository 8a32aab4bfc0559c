//! A brain-like 3D phantom: four classes in folded, cortex-like layers
//! (background, CSF, grey matter, white matter, as in a skull-stripped T1
//! MRI), a smooth multiplicative intensity inhomogeneity (bias field) and
//! noise. The volume is `160 × 190 × 150` voxels at `size = 190` (the
//! shape of a 1 mm brain MRI), scaled with `size`.
//!
//! Geometry, in coordinates normalised by the ellipsoid's semi-axes (the
//! brain's outline is the unit sphere `ρ = 1`): white matter inside a folded
//! surface `ρ < w(direction)`, grey matter a ribbon of constant normalised
//! thickness over it, CSF between the ribbon and `ρ = 1` (deep in the
//! sulci, thin over the gyri) and in two ventricles, background outside.
//! Where a gyrus reaches the outline, grey matter meets the background and
//! the CSF along junction curves.

use super::{Phantom3, RenderOptions};

/// Intensity levels of background, CSF, grey and white matter (T1 contrast).
pub const BRAIN_LEVELS: [f64; 4] = [0.05, 0.3, 0.55, 0.8];

/// The extent at `size = 190`.
pub const BRAIN_DIMS: [usize; 3] = [160, 190, 150];

/// Largest relative change of the bias field from its mean (±).
pub const BRAIN_BIAS: f64 = 0.12;

/// The volume's extent for a longest side of `size` voxels.
pub fn brain_dims(size: usize) -> [usize; 3] {
    BRAIN_DIMS.map(|d| ((d * size) as f64 / 190.0).round().max(1.0) as usize)
}

/// The folded white-matter surface's normalised radius in the direction
/// of the unit vector `d` (between 0.48 and 0.84): sums of plane waves over
/// the direction, so the folds run every way and have no poles.
fn white_radius(d: [f64; 3]) -> f64 {
    let folds = 0.5 * (12.0 * d[0] + 5.0 * d[2]).sin() * (11.0 * d[1] + 4.0 * d[0]).sin()
        + 0.5 * (13.0 * d[2] - 6.0 * d[1] + 1.0).sin();
    0.66 + 0.18 * folds
}

/// Class of the point `p` in normalised coordinates (centre 0, outline at
/// `|p| = 1`).
fn brain_class(p: [f64; 3]) -> u8 {
    let rho = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
    if rho >= 1.0 {
        return 0;
    }
    // Two ventricles: ellipsoids left and right of the midline.
    let ventricle = |cx: f64| {
        let q = [
            (p[0] - cx) / 0.08,
            (p[1] + 0.05) / 0.3,
            (p[2] - 0.05) / 0.12,
        ];
        q[0] * q[0] + q[1] * q[1] + q[2] * q[2] < 1.0
    };
    if ventricle(-0.13) || ventricle(0.13) {
        return 1;
    }
    if rho < 1e-9 {
        return 3;
    }
    let w = white_radius(p.map(|a| a / rho));
    if rho < w {
        3
    } else if rho < w + 0.17 {
        2
    } else {
        1
    }
}

/// The smooth multiplicative bias field at normalised position `p` (each
/// coordinate in about `[-1, 1]`): a tilted linear ramp with a gentle
/// quadratic bowl, within `1 ± BRAIN_BIAS`.
fn bias(p: [f64; 3]) -> f64 {
    let ramp = 0.5 * p[0] + 0.35 * p[1] - 0.25 * p[2];
    let bowl = 0.3 * (p[0] * p[0] + p[2] * p[2]) - 0.15;
    1.0 + BRAIN_BIAS * (ramp + bowl).clamp(-1.0, 1.0)
}

/// Ground truth and noise-free biased intensities of the brain phantom of
/// longest side `size`.
fn brain_base(size: usize) -> ([usize; 3], Vec<u8>, Vec<f64>) {
    let dims = brain_dims(size);
    let [nx, ny, nz] = dims;
    let semi_axes = [0.46, 0.46, 0.44];
    let mut truth = Vec::with_capacity(nx * ny * nz);
    let mut base = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let centred =
                    [(i, nx), (j, ny), (k, nz)].map(|(a, n)| (a as f64 + 0.5) / n as f64 - 0.5);
                let p = [0, 1, 2].map(|a| centred[a] / semi_axes[a]);
                let class = brain_class(p);
                truth.push(class);
                base.push(BRAIN_LEVELS[class as usize] * bias(p));
            }
        }
    }
    (dims, truth, base)
}

/// Ground truth of [`brain`] (0 background, 1 CSF, 2 grey, 3 white matter).
pub fn brain_labels(size: usize) -> Vec<u8> {
    brain_base(size).1
}

/// The brain-like phantom of longest side `size` (`160 × 190 × 150` at
/// 190): biased class levels, blur, noise of standard deviation
/// `noise_sigma`, 8-bit quantisation.
pub fn brain(size: usize, noise_sigma: f64, seed: u64) -> Phantom3 {
    let (dims, truth, base) = brain_base(size);
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom3::from_base(dims, base, truth, BRAIN_LEVELS.len(), &opts)
}
