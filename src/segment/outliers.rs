//! Samples far outside the image's range (hot pixels, cosmic rays, dead
//! pixels, a stray marker), clamped before the segmentation so that a
//! handful of them cannot pull a phase's mean.
//!
//! The data term is a sum of squares, so a phase's mean is its samples'
//! mean, and one sample `d` away from the rest moves it by `d/n` for a phase
//! of `n` samples. On a 16-bit micrograph whose phases all lie within a
//! thousandth of the full scale, five hot pixels at 65535 moved the
//! brightest of three phases by more than half the gap to the next one:
//! its pixels went to that phase and it ended as the hot pixels alone. A
//! sample more than the robust range's width beyond the robust range (its
//! [`ROBUST_TAIL`](super::intensity::ROBUST_TAIL) quantiles, so fewer than
//! a thousandth of the samples) counts as if it lay at that distance: still
//! far from every phase, so a small object that bright keeps a label of
//! its own, but with the leverage of a sample at the range's edge. The run
//! says how many were clamped.

use super::intensity::robust_range;

/// Samples the robust range is estimated from (evenly strided): its 0.1 %
/// quantiles are then the 5th samples from each end, which the few hot
/// pixels this is for do not reach (a strided sample holds one in 16 of a
/// 256² image's), at a small part of the run's setup.
const RANGE_SAMPLES: usize = 1 << 12;

/// The samples clamped, and where.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outliers {
    /// How many samples were clamped.
    pub count: usize,
    /// The values they were clamped to (below, above).
    pub clamp: (f32, f32),
    /// The most extreme samples (lowest, highest).
    pub extremes: (f32, f32),
}

/// `data` with its outliers clamped, and what was clamped; `None` where no
/// sample lies more than the robust range's width beyond it (the data are
/// then used as they are).
pub fn clamp_outliers(data: &[f32]) -> Option<(Vec<f32>, Outliers)> {
    // (`f32::min` passes over a NaN; a NaN or an infinity is the
    // segmentation's to refuse, unclamped)
    let (min, max) = data
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if !(min.is_finite() && max.is_finite()) {
        return None;
    }
    let (low, high) = robust_range(data, (f64::from(min), f64::from(max)), RANGE_SAMPLES);
    let span = high - low;
    let clamp = ((low - span) as f32, (high + span) as f32);
    let inside = min >= clamp.0 && max <= clamp.1;
    if span.is_nan() || span <= 0.0 || inside {
        return None;
    }
    let count = data.iter().filter(|&&v| v < clamp.0 || v > clamp.1).count();
    let clamped = data.iter().map(|&v| v.clamp(clamp.0, clamp.1)).collect();
    let outliers = Outliers {
        count,
        clamp,
        extremes: (min, max),
    };
    Some((clamped, outliers))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 100² image of three levels under a deterministic ripple.
    fn three_levels() -> Vec<f32> {
        (0..10_000)
            .map(|i| {
                let level = [0.015, 0.0165, 0.018][(i % 100) / 34];
                level + 0.0002 * ((i * 7919 % 11) as f32 / 5.0 - 1.0)
            })
            .collect()
    }

    #[test]
    fn data_without_outliers_are_left_as_they_are() {
        assert_eq!(clamp_outliers(&three_levels()), None);
        // a constant image has no range to be outside of
        assert_eq!(clamp_outliers(&[0.5; 100]), None);
    }

    #[test]
    fn hot_pixels_are_clamped_to_the_ranges_width_beyond_it() {
        let mut data = three_levels();
        for i in [5, 505, 5005] {
            data[i] = 1.0;
        }
        let (clamped, outliers) = clamp_outliers(&data).unwrap();
        assert_eq!(outliers.count, 3);
        assert_eq!(outliers.extremes.1, 1.0);
        // clamped well above the brightest level, far below the hot value
        assert!(
            outliers.clamp.1 > 0.019 && outliers.clamp.1 < 0.03,
            "{outliers:?}"
        );
        assert_eq!(clamped[5], outliers.clamp.1);
        let changed = clamped.iter().zip(&data).filter(|(a, b)| a != b).count();
        assert_eq!(changed, 3, "only the outliers change");
    }

    #[test]
    fn a_bright_object_stays_brighter_than_every_phase() {
        // 8 pixels of a 10 000 at 255 over levels 0 and 100
        let mut data: Vec<f32> = (0..10_000)
            .map(|i| if i < 5000 { 0.0 } else { 100.0 })
            .collect();
        for v in &mut data[9000..9008] {
            *v = 255.0;
        }
        let (clamped, outliers) = clamp_outliers(&data).unwrap();
        assert_eq!(outliers.count, 8);
        assert!(clamped[9000] >= 200.0, "{outliers:?}");
    }
}
