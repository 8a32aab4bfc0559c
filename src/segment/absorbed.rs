//! A class of the image that the result gave to its neighbours.
//!
//! Where a class is thinner than the length weight's width or than the
//! cells (the cortex of a brain MRI at 2 mm is one to one and a half voxels
//! thick), the energy's minimum hands its voxels to the phases around it, and
//! its label ends as a sliver: not empty, its mean not a neighbour's, not a
//! band the blur of an edge explains, and the stopping rule sees nothing
//! wrong. The image does: far more voxels look like the phase than carry its
//! label. Lightly smoothed (a Gaussian of one pixel or voxel, which takes
//! most of the noise's scatter out and keeps layers a voxel thick), the
//! voxels whose value lies in the middle half of the phase's nearest-mean
//! range (within a quarter of the gap to each neighbouring mean) are counted;
//! a phase holding fewer than a quarter of that count was absorbed.
//!
//! The quarter separates the two kinds of result measured so far
//! (`benches/RESULTS.md`, "Absorbed phases"): correct results of phantoms,
//! small volumes and real photographs hold at least 0.40 of their count (the
//! six-disk phantom at σ 0.25, whose darkest disks sit 0.1 above a large
//! background), the absorbed ones at most 0.16.

/// Smallest share of the voxels that look like a phase it must hold.
pub const ABSORBED_SHARE: f64 = 0.25;

/// A phase holding fewer than [`ABSORBED_SHARE`] of the voxels that look
/// like it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Absorbed {
    /// Its rank among the present phases by increasing mean.
    pub rank: usize,
    /// The pixels or voxels it holds.
    pub count: u64,
    /// The pixels or voxels whose smoothed value lies in the middle half of
    /// its nearest-mean range.
    pub looks_like: u64,
}

/// The absorbed phases of a result whose phases, by increasing mean, have
/// means `means` and hold `count` pixels or voxels (the present phases
/// only), over the image `smoothed` as the checks read it
/// ([`CheckImage`](super::check_image::CheckImage)): the segmentation's cell
/// statistics give the counts, so no labelling of the image is needed.
pub fn absorbed_by_count(smoothed: &[f32], count: &[u64], means: &[f64]) -> Vec<Absorbed> {
    if means.len() < 2 || count.len() != means.len() {
        return Vec::new();
    }
    let mut looks_like = vec![0u64; means.len()];
    for &value in smoothed {
        if let Some(r) = middle_half_rank(means, value as f64) {
            looks_like[r] += 1;
        }
    }
    (0..means.len())
        .filter(|&r| (count[r] as f64) < ABSORBED_SHARE * looks_like[r] as f64)
        .map(|r| Absorbed {
            rank: r,
            count: count[r],
            looks_like: looks_like[r],
        })
        .collect()
}

/// How many entries of `ranks` (a labelling's phase per pixel, as ranks)
/// hold each rank below `n`: the counts [`absorbed_by_count`] takes.
pub fn pixels_by_rank(ranks: &[u8], n: usize) -> Vec<u64> {
    let mut count = vec![0u64; n];
    for &r in ranks {
        if let Some(c) = count.get_mut(r as usize) {
            *c += 1;
        }
    }
    count
}

/// The rank whose middle half of the nearest-mean range holds `value`
/// (`means` increasing; the lowest and highest ranges are open outwards).
fn middle_half_rank(means: &[f64], value: f64) -> Option<usize> {
    let upper = means.partition_point(|&m| m <= value);
    let near = |r: usize| {
        let m = means[r];
        if value < m {
            r == 0 || value > m - 0.25 * (m - means[r - 1])
        } else {
            r + 1 == means.len() || value < m + 0.25 * (means[r + 1] - m)
        }
    };
    [
        upper.checked_sub(1),
        Some(upper).filter(|&r| r < means.len()),
    ]
    .into_iter()
    .flatten()
    .find(|&r| near(r))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::segment::check_image::CheckImage;
    use crate::segment::image::ImageView;

    /// [`absorbed_by_count`] of a labelling: `ranks` gives each pixel's
    /// phase as its rank by increasing mean.
    fn absorbed_phases(image: &ImageView<'_>, ranks: &[u8], means: &[f64]) -> Vec<Absorbed> {
        let smoothed = CheckImage::default();
        absorbed_by_count(
            smoothed.of(image),
            &pixels_by_rank(ranks, means.len()),
            means,
        )
    }

    #[test]
    fn values_count_for_the_phase_whose_middle_half_holds_them() {
        let means = [0.0, 0.4, 0.6];
        assert_eq!(middle_half_rank(&means, -5.0), Some(0));
        assert_eq!(middle_half_rank(&means, 0.09), Some(0));
        assert_eq!(middle_half_rank(&means, 0.2), None);
        assert_eq!(middle_half_rank(&means, 0.31), Some(1));
        assert_eq!(middle_half_rank(&means, 0.44), Some(1));
        assert_eq!(middle_half_rank(&means, 0.5), None);
        assert_eq!(middle_half_rank(&means, 0.56), Some(2));
        assert_eq!(middle_half_rank(&means, 9.0), Some(2));
    }

    /// Three stripes of 0, 0.5 and 1: labelled right, no phase is absorbed;
    /// with the middle stripe given to the dark phase but for one column,
    /// the middle phase is.
    #[test]
    fn a_phase_whose_voxels_went_to_its_neighbour_is_absorbed() {
        let (w, h) = (30, 20);
        let data: Vec<f32> = (0..w * h).map(|i| [0.0, 0.5, 1.0][(i % w) / 10]).collect();
        let view = ImageView::new_2d(w, h, &data).unwrap();
        let right: Vec<u8> = (0..w * h).map(|i| ((i % w) / 10) as u8).collect();
        assert!(absorbed_phases(&view, &right, &[0.0, 0.5, 1.0]).is_empty());
        let merged: Vec<u8> = (0..w * h)
            .map(|i| match i % w {
                x if x < 19 => 0,
                19 => 1,
                _ => 2,
            })
            .collect();
        let absorbed = absorbed_phases(&view, &merged, &[0.05, 0.5, 1.0]);
        assert_eq!(absorbed.len(), 1, "{absorbed:?}");
        assert_eq!((absorbed[0].rank, absorbed[0].count), (1, h as u64));
        assert!(absorbed[0].looks_like >= 8 * h as u64, "{absorbed:?}");
    }

    /// A layer two voxels thick between two others, in a volume: kept, it is
    /// not absorbed; given to the bright side, it is.
    #[test]
    fn a_thin_layer_of_a_volume_given_to_its_neighbour_is_absorbed() {
        let dims = [6, 5, 12];
        let layer = |i: usize| match i / (dims[0] * dims[1]) {
            z if z < 5 => 0u8,
            5 | 6 => 1,
            _ => 2,
        };
        let data: Vec<f32> = (0..dims.iter().product::<usize>())
            .map(|i| [0.0, 0.4, 0.8][layer(i) as usize])
            .collect();
        let view = ImageView::new_3d(dims, &data).unwrap();
        let kept: Vec<u8> = (0..data.len()).map(layer).collect();
        assert!(absorbed_phases(&view, &kept, &[0.0, 0.4, 0.8]).is_empty());
        let lost: Vec<u8> = kept.iter().map(|&l| if l == 1 { 2 } else { l }).collect();
        let absorbed = absorbed_phases(&view, &lost, &[0.0, 0.4, 0.7]);
        assert_eq!(absorbed.len(), 1, "{absorbed:?}");
        assert_eq!((absorbed[0].rank, absorbed[0].count), (1, 0));
    }
}
