//! Whether the noise is spatially correlated, and the warning that says so.
//!
//! The segmentation's energy takes every sample's noise as independent of
//! its neighbours': a cell's mean then has the noise of one sample over the
//! square root of its samples, and the length weight keeps noise from
//! forming regions. Reconstructed CT and MRI, upsampled or compressed images
//! and textured photographs break that: their noise (or texture) comes in
//! blobs a few samples wide, which average out far less over a cell and
//! which the run labels as phases (a 64³ four-phase volume with Gaussian
//! noise of σ 0.15 smoothed over 1.5 voxels: mean Dice 0.41 against 0.96
//! with white noise of the same σ, five times the tetrahedra and about
//! twenty times the time).
//! Nothing in the result shows it, so the run says so.
//!
//! The figure compares the differences of samples one and [`FAR_LAG`]
//! apart along x: for stationary Gaussian noise of variance σ² and
//! correlation ρ(k) at lag k, `|I(x+k) − I(x)|` is distributed as
//! `σ·√(2·(1 − ρ(k)))` times one law, so any statistic of it that scales
//! (here the mean of its smallest three quarters, which leaves the edges
//! out) does too. Taking the far pair as independent gives
//! `1 − (near/far)²`, a lower bound of the neighbours' correlation.

use super::image::ImageView;
use super::intensity::{strided_abs_differences, IntensityStats, SamplePairs};

/// Samples apart of the far differences: Gaussian noise smoothed over 1.5
/// samples still has correlation 0.37 there (its neighbours 0.89, and the
/// figure reads 0.84), while the edges, blurred over 1.5 samples, are few
/// among the smallest differences.
pub const FAR_LAG: usize = 3;

/// The smallest differences kept for the means: the largest quarter, where
/// the edges are, is left out. A mean rather than a median because on
/// quantised data with noise of a few steps the medians are whole steps
/// (1 against 2 gives 0.75 for white noise).
const KEPT_FRACTION: f64 = 0.75;

/// Largest number of pairs each mean reads (an evenly strided subset of
/// larger inputs): the figure, a ratio of two means over some sixteen
/// thousand differences each, moves by at most 0.02 against the means of
/// all the pairs on the images of its measurements.
const FIGURE_SAMPLES: usize = 1 << 14;

/// Fewest pairs a mean of the figure reads: with fewer (an 8×8 image holds
/// 40 pairs three samples apart) the edges are no longer few among the
/// smallest differences, and an 8×8 image of white noise read 0.98; over
/// 512 pairs each mean is within a few percent of the noise's.
const MIN_FIGURE_PAIRS: usize = 512;

/// A correlation figure above this may get a warning: white noise on the
/// phantoms (2D and 3D, σ 0.01–0.25, blurred edges) reads 0–0.27; the
/// brain phantom's smooth inhomogeneity under noise of σ 0.01–0.02 reads
/// up to 0.52, where the noise is far too small against the phase gaps for
/// [`correlated_noise_warning`] to speak.
pub const CORRELATED_NOISE_WARNING: f64 = 0.5;

/// The noise correlation figure of `image` (in `[0, 1]`), whose noise
/// estimate `noise` read the `pairs` it reads too: `None` for noise-free
/// data (`noise` 0: the differences are the structure's, which is
/// correlated by nature) and when fewer than [`MIN_FIGURE_PAIRS`] pairs
/// of samples `FAR_LAG` apart lie along x.
pub(super) fn noise_correlation(
    image: &ImageView<'_>,
    noise: f64,
    pairs: SamplePairs,
) -> Option<f64> {
    if noise <= 0.0 {
        return None;
    }
    let near = trimmed_mean_abs_difference(image, 1, pairs)?;
    let far = trimmed_mean_abs_difference(image, FAR_LAG, pairs)?;
    Some((1.0 - (near / far).powi(2)).clamp(0.0, 1.0))
}

/// The mean of the smallest [`KEPT_FRACTION`] of `|I(x+lag) − I(x)|`
/// along x over at most [`FIGURE_SAMPLES`] evenly strided pairs (of those
/// `pairs` admits); `None` if fewer than [`MIN_FIGURE_PAIRS`] fit or the
/// mean is 0.
fn trimmed_mean_abs_difference(
    image: &ImageView<'_>,
    lag: usize,
    pairs: SamplePairs,
) -> Option<f64> {
    // The bits of a non-negative float order as the float does, and
    // selecting among integers is faster than through a comparison.
    let mut differences: Vec<u32> = strided_abs_differences(image, lag, FIGURE_SAMPLES, pairs)
        .map(f32::to_bits)
        .collect();
    if differences.len() < MIN_FIGURE_PAIRS {
        return None;
    }
    let kept = ((differences.len() as f64 * KEPT_FRACTION) as usize).max(1);
    let smallest = if kept < differences.len() {
        differences.select_nth_unstable(kept).0
    } else {
        &mut differences[..]
    };
    let sum: f64 = smallest.iter().map(|&d| f32::from_bits(d) as f64).sum();
    let mean = sum / smallest.len() as f64;
    (mean > 0.0).then_some(mean)
}

/// The noise's standard deviation over a patch, against the smallest gap
/// between adjacent phase means, above which correlated noise gets a
/// warning. With Gaussian noise smoothed over 1.5 voxels (the 64³
/// phantoms, noise seed 1) the four-phase volume keeps a mean Dice of 0.966
/// at 0.17 of the gap, 0.943 at 0.26 and 0.53 at 0.60; the two balls 0.988
/// at 0.08, 0.981 at 0.12 and 0.960 at 0.23.
pub const CORRELATED_NOISE_OF_GAP: f64 = 0.15;

/// The warning for a run on an image whose noise correlation figure ρ is
/// above [`CORRELATED_NOISE_WARNING`] and whose noise over a patch is more
/// than [`CORRELATED_NOISE_OF_GAP`] of the smallest gap between adjacent
/// phase `means` (an empty phase has none). The noise estimate σ̂ reads
/// neighbours' differences, which correlation shrinks by `√(1 − ρ)`, so
/// `σ̂/√(1 − ρ)` is the noise a region of a few samples sees. Texture on a photograph reads as
/// correlated too, but at a small fraction of its phases' gaps it cannot
/// move a label.
pub fn correlated_noise_warning(
    intensity: &IntensityStats,
    means: &[Option<f64>],
) -> Option<String> {
    let rho = intensity.noise_correlation?;
    let patch_noise = intensity.noise / (1.0 - rho).max(f64::EPSILON).sqrt();
    let mut sorted: Vec<f64> = means.iter().flatten().copied().collect();
    sorted.sort_by(f64::total_cmp);
    let gap = sorted
        .windows(2)
        .map(|w| w[1] - w[0])
        .min_by(f64::total_cmp)?;
    let of_gap = patch_noise / gap.max(f64::MIN_POSITIVE);
    (rho > CORRELATED_NOISE_WARNING && of_gap > CORRELATED_NOISE_OF_GAP).then(|| {
        format!(
            "the image's noise is spatially correlated or it is textured (neighbouring samples' \
             noise correlation at least {rho:.2}, its spread over a few samples {of_gap:.2} of \
             the smallest gap between phase means): the segmentation takes each sample's noise \
             as independent, so blobs of noise or texture may have been labelled as phases; a \
             larger --length-weight, or denoising the input first, may help"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phantom::noise::add_smoothed_noise_2d;

    const SIDE: usize = 256;

    /// Noise of σ 0.1 on a square of level 0.6 on 0.3, the noise smoothed by
    /// `passes` box blurs of 3 samples along x and y first (none: white).
    fn square_with_noise(passes: usize) -> Vec<f32> {
        let mut square: Vec<f32> = (0..SIDE * SIDE)
            .map(|i| {
                let (x, y) = (i % SIDE, i / SIDE);
                let inside = (64..192).contains(&x) && (64..192).contains(&y);
                if inside {
                    0.6
                } else {
                    0.3
                }
            })
            .collect();
        add_smoothed_noise_2d(&mut square, SIDE, 0.1, passes, 3);
        square
    }

    fn correlation_of(data: &[f32]) -> Option<f64> {
        let view = ImageView::new_2d(SIDE, SIDE, data).unwrap();
        IntensityStats::of(&view).noise_correlation
    }

    #[test]
    fn white_noise_reads_uncorrelated() {
        let rho = correlation_of(&square_with_noise(0)).unwrap();
        assert!(rho < 0.2, "{rho}");
    }

    #[test]
    fn smoothed_noise_reads_correlated() {
        let rho = correlation_of(&square_with_noise(2)).unwrap();
        assert!(rho > CORRELATED_NOISE_WARNING, "{rho}");
    }

    /// An 8×8 image of white noise: 40 pairs three samples apart, too few
    /// for a figure (this one read 0.36, another such image 0.98).
    #[test]
    fn tiny_images_have_no_figure() {
        let mut tiny = vec![0.5f32; 64];
        add_smoothed_noise_2d(&mut tiny, 8, 0.1, 0, 3);
        let view = ImageView::new_2d(8, 8, &tiny).unwrap();
        assert_eq!(IntensityStats::of(&view).noise_correlation, None);
    }

    #[test]
    fn noise_free_images_have_no_figure() {
        let flat_square: Vec<f32> = (0..SIDE * SIDE)
            .map(|i| if i % SIDE < 100 { 0.2 } else { 0.7 })
            .collect();
        assert_eq!(correlation_of(&flat_square), None);
    }

    fn stats(noise: f64, noise_correlation: Option<f64>) -> IntensityStats {
        IntensityStats {
            min: 0.0,
            max: 1.0,
            low: 0.0,
            high: 1.0,
            noise,
            noise_excludes_extremes: false,
            noise_correlation,
        }
    }

    /// The warning needs both a high correlation and noise over a patch
    /// that is a fair part of the smallest gap between the means.
    #[test]
    fn only_strong_correlated_noise_warns() {
        let means = [Some(0.2), None, Some(0.5), Some(0.9)];
        // σ̂/√(1 − 0.84) = 2.5·σ̂ against the gap 0.3
        assert!(correlated_noise_warning(&stats(0.03, Some(0.84)), &means).is_some());
        assert!(correlated_noise_warning(&stats(0.01, Some(0.84)), &means).is_none());
        // white noise as strong as the gap
        assert!(correlated_noise_warning(&stats(0.3, Some(0.1)), &means).is_none());
        assert!(correlated_noise_warning(&stats(0.0, None), &means).is_none());
        // fewer than two means: no gap to compare with
        assert!(correlated_noise_warning(&stats(0.03, Some(0.84)), &[Some(0.2)]).is_none());
    }

    #[test]
    fn the_figure_does_not_depend_on_the_intensity_scale() {
        let data = square_with_noise(1);
        let mapped: Vec<f32> = data.iter().map(|&v| 20_000.0 - 300.0 * v).collect();
        let (a, b) = (
            correlation_of(&data).unwrap(),
            correlation_of(&mapped).unwrap(),
        );
        assert!((a - b).abs() < 0.02, "{a} {b}");
    }
}
