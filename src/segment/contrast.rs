//! The phase contrast Δ that sets the energy's length weight `ν = w·Δ²/2`.
//!
//! `w` is a width in pixels: a structure narrower than `w` at contrast Δ
//! costs more boundary than it gains in fit (see
//! [`SegmentParams::length_weight`](super::SegmentParams::length_weight)).
//! The contrast it refers to is the weakest one the segmentation must
//! resolve, the smallest gap between adjacent phase means: with the mean gap
//! instead, unevenly spaced means (a photograph's dark, mid and bright
//! phases) regularise the closely spaced pair more than `w` says, and fine
//! structures at that pair's contrast are lost. Two bounds keep the smallest
//! gap honest:
//!
//! - not below twice the spread of the pixels about their phase means (the
//!   root mean square residual σ of the piecewise-constant fit, which
//!   includes the noise, correlated or not): a phase that starts as a split
//!   of noise, or as a band along edges, has a mean within a fraction of σ
//!   of its twin and would otherwise make every boundary nearly free; two
//!   phases closer than 2σ are told apart pixel by pixel for fewer than 84 %
//!   of their pixels;
//! - not above the mean gap, the contrast of evenly spaced means, so that a
//!   noisy image is regularised no more than with evenly spaced means.

/// Δ for the known phase means `means` (any order) and the pixels' spread
/// about them `spread` (a standard deviation): the smallest gap between
/// adjacent means, raised to twice the spread and capped at the mean gap. `None`
/// with fewer than two distinct means.
pub fn phase_contrast(means: &[f64], spread: f64) -> Option<f64> {
    let mut sorted = means.to_vec();
    sorted.sort_by(f64::total_cmp);
    let (lo, hi) = (*sorted.first()?, *sorted.last()?);
    if sorted.len() < 2 || hi <= lo {
        return None;
    }
    let mean_gap = (hi - lo) / (sorted.len() - 1) as f64;
    let smallest = sorted
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    Some(smallest.max(2.0 * spread).min(mean_gap))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evenly_spaced_means_give_their_gap() {
        let c = phase_contrast(&[0.7, 0.1, 0.4], 0.05).unwrap();
        assert!((c - 0.3).abs() < 1e-12, "{c}");
    }

    #[test]
    fn the_closest_pair_sets_the_contrast() {
        // gaps 0.1 and 0.6: the mean gap would be 0.35
        let c = phase_contrast(&[0.1, 0.2, 0.8], 0.02).unwrap();
        assert!((c - 0.1).abs() < 1e-12, "{c}");
    }

    #[test]
    fn a_split_of_noise_does_not_make_boundaries_free() {
        // two means 0.02 apart, pixels spread by 0.05: twice the spread counts
        let c = phase_contrast(&[0.3, 0.32, 0.7], 0.05).unwrap();
        assert!((c - 0.1).abs() < 1e-12, "{c}");
        // and never more than the mean gap
        let c = phase_contrast(&[0.3, 0.32, 0.7], 0.5).unwrap();
        assert!((c - 0.2).abs() < 1e-12, "{c}");
    }

    #[test]
    fn scaling_and_shifting_scale_the_contrast() {
        let means = [0.1, 0.25, 0.9];
        let c = phase_contrast(&means, 0.04).unwrap();
        let moved: Vec<f64> = means.iter().map(|m| 1000.0 - 64.0 * m).collect();
        let d = phase_contrast(&moved, 64.0 * 0.04).unwrap();
        assert!((d - 64.0 * c).abs() < 1e-9, "{c} {d}");
    }

    #[test]
    fn fewer_than_two_distinct_means_give_none() {
        assert_eq!(phase_contrast(&[], 0.1), None);
        assert_eq!(phase_contrast(&[0.4], 0.1), None);
        assert_eq!(phase_contrast(&[0.4, 0.4], 0.1), None);
    }
}
