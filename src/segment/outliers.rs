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
//! far from every phase, but with the leverage of a sample at the range's
//! edge. Only isolated samples are outliers: a face-connected group of
//! more than [`MAX_GROUP`] samples beyond the bound is a structure (a
//! bright spot spread by the optics over a few pixels, a metal implant),
//! rare but real, and is left as it is. The run says how many were
//! clamped.

use super::intensity::{robust_range, MAX_SAMPLES};
use super::missed_objects::face_neighbours;
use std::collections::HashSet;

/// The largest face-connected group of samples beyond the bound that
/// counts as outliers: a hot pixel, a pair, a short cosmic-ray track.
pub const MAX_GROUP: usize = 4;

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

/// `data`, samples on the grid `dims` (x fastest), with its outliers
/// clamped, and what was clamped; `None` where no isolated sample lies more
/// than the robust range's width beyond it (the data are then used as they
/// are).
pub fn clamp_outliers(data: &[f32], dims: [usize; 3]) -> Option<(Vec<f32>, Outliers)> {
    clamp_outliers_keeping_range(data, dims).clamped
}

/// What [`clamp_outliers_keeping_range`] gives.
#[derive(Clone, Debug, PartialEq)]
pub struct Clamp {
    /// The samples with their outliers clamped, and what was clamped
    /// (`None`: the samples stand as they are).
    pub clamped: Option<(Vec<f32>, Outliers)>,
    /// The robust range selected of samples that stand as they are
    /// ([`robust_range`] over their extremes; `None` where they were
    /// clamped or are not all finite).
    pub robust_range: Option<(f64, f64)>,
}

/// [`clamp_outliers`], and the robust range it selected where it leaves
/// the data as they are: the segmentation's intensity figures take it
/// ([`ImageView::with_robust_range`](super::image::ImageView::with_robust_range))
/// instead of selecting it again.
pub fn clamp_outliers_keeping_range(data: &[f32], dims: [usize; 3]) -> Clamp {
    let kept = |robust_range| Clamp {
        clamped: None,
        robust_range,
    };
    // (`f32::min` passes over a NaN; a NaN or an infinity is the
    // segmentation's to refuse, unclamped)
    let (min, max) = data
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if !(min.is_finite() && max.is_finite()) {
        return kept(None);
    }
    let range = robust_range(data, (f64::from(min), f64::from(max)), MAX_SAMPLES);
    let (low, high) = range;
    let span = high - low;
    let clamp = ((low - span) as f32, (high + span) as f32);
    let inside = min >= clamp.0 && max <= clamp.1;
    if span.is_nan() || span <= 0.0 || inside {
        return kept(Some(range));
    }
    let beyond = |v: f32| v < clamp.0 || v > clamp.1;
    let isolated = isolated_groups(data, dims, beyond);
    if isolated.is_empty() {
        return kept(Some(range));
    }
    let mut clamped = data.to_vec();
    for &i in &isolated {
        clamped[i] = clamped[i].clamp(clamp.0, clamp.1);
    }
    let extremes = isolated
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &i| {
            (lo.min(data[i]), hi.max(data[i]))
        });
    let outliers = Outliers {
        count: isolated.len(),
        clamp,
        extremes,
    };
    Clamp {
        clamped: Some((clamped, outliers)),
        robust_range: None,
    }
}

/// The samples `beyond` selects that lie in face-connected groups of at
/// most [`MAX_GROUP`], in increasing order.
fn isolated_groups(data: &[f32], dims: [usize; 3], beyond: impl Fn(f32) -> bool) -> Vec<usize> {
    let far: HashSet<usize> = (0..data.len()).filter(|&i| beyond(data[i])).collect();
    let mut seen = HashSet::new();
    let mut isolated = Vec::new();
    for &start in &far {
        if !seen.insert(start) {
            continue;
        }
        let (mut group, mut stack) = (vec![start], vec![start]);
        while let Some(i) = stack.pop() {
            for n in face_neighbours(i, dims).into_iter().flatten() {
                if far.contains(&n) && seen.insert(n) {
                    group.push(n);
                    stack.push(n);
                }
            }
        }
        if group.len() <= MAX_GROUP {
            isolated.extend(group);
        }
    }
    isolated.sort_unstable();
    isolated
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

    /// Where the clamp leaves the data as they are, the robust range it
    /// keeps is the one the intensity figures select, to the bit.
    #[test]
    fn the_kept_range_is_the_intensity_figures_range() {
        use crate::segment::image::ImageView;
        use crate::segment::intensity::IntensityStats;
        let data = three_levels();
        let clamp = clamp_outliers_keeping_range(&data, [100, 100, 1]);
        assert!(clamp.clamped.is_none());
        let view = ImageView::new_2d(100, 100, &data).unwrap();
        let given = IntensityStats::of(&view.with_robust_range(clamp.robust_range.unwrap()));
        assert_eq!(given, IntensityStats::of(&view));
    }

    #[test]
    fn data_without_outliers_are_left_as_they_are() {
        assert_eq!(clamp_outliers(&three_levels(), [100, 100, 1]), None);
        // a constant image has no range to be outside of
        assert_eq!(clamp_outliers(&[0.5; 100], [10, 10, 1]), None);
    }

    #[test]
    fn hot_pixels_are_clamped_to_the_ranges_width_beyond_it() {
        let mut data = three_levels();
        for i in [5, 505, 5005] {
            data[i] = 1.0;
        }
        let (clamped, outliers) = clamp_outliers(&data, [100, 100, 1]).unwrap();
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
    fn a_bright_object_of_a_few_pixels_is_left_as_it_is() {
        // a 3×3 square at 255 over levels 0 and 100: 9 of 20 000 pixels
        let (w, h) = (200, 100);
        let mut data: Vec<f32> = (0..w * h)
            .map(|i| if i < w * h / 2 { 0.0 } else { 100.0 })
            .collect();
        for y in 80..83 {
            for x in 40..43 {
                data[y * w + x] = 255.0;
            }
        }
        assert_eq!(clamp_outliers(&data, [w, h, 1]), None);
        // a pair of hot pixels elsewhere is clamped, the square is not
        data[10 * w + 10] = 255.0;
        data[10 * w + 11] = 255.0;
        let (clamped, outliers) = clamp_outliers(&data, [w, h, 1]).unwrap();
        assert_eq!(outliers.count, 2);
        assert!(clamped[10 * w + 10] < 255.0 && clamped[81 * w + 41] == 255.0);
    }
}
