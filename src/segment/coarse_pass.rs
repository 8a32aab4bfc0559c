//! The coarse first pass: a run on the image at half resolution, whose
//! final mesh starts the run at full resolution.
//!
//! From a coarse start the interfaces reach the data's layers by transport:
//! they move a fraction of `L` per iteration, so a volume whose layers are
//! folded and far from where the first coarse cells put them (the
//! brain-like phantom) takes some 70 iterations, each over the full
//! interface band at full resolution. The same transport on an image of
//! half the side costs about an eighth per voxel and a quarter per
//! interface cell (the pass runs at `2·L`, the same number of samples per
//! cell); the run at full resolution then starts from interfaces within
//! about a coarse voxel of the data's and only refines and settles them.
//!
//! The pass is the whole segmentation (initialisation, flips, re-seeding,
//! stopping rule) without the fine finish, and it ends at its first quiet
//! flip round ([`SegmentParams::quiet_round_plateau`] 0): once a round finds
//! the labels in place, the interfaces are close enough for the run at
//! full resolution, which moves them on (on the brain-like phantom the
//! pass's energy still fell slowly through 60 and more iterations). Its
//! mesh covers the coarse image's domain, which is the full image's: the
//! coarse voxels are the side divided by their number (twice the voxel
//! where a side is even; where it is odd the last one averages a single
//! layer), and [`Complex::stretch_to`] puts the mesh exactly on the full
//! domain against rounding.

use super::driver::Segmentation;
use super::image::ImageView;
use super::params::{Init, SegmentParams};
use super::raster::Raster;
use super::SegmentError;
use crate::complex::Complex;
use crate::dim::Point;
use serde::Serialize;
use std::time::Instant;

/// The shortest side, in samples, of an image the coarse pass runs on. At
/// 128 and above (the 128³ phantoms, the brain-like phantom at 150×190×160)
/// the pass gave an equal or higher Dice at 0.6–1.0× the CPU time; on the
/// brain-like phantom at 95×120×101 its half-resolution image lost the thin
/// folded layer's detail, and the run at full resolution took as many
/// iterations as without the pass (1.5× the CPU time), at 54×64×51 it lost
/// phases (benches/RESULTS.md, "Speed, 3D").
pub const MIN_SIDE: usize = 128;

/// What the coarse pass did, for the report.
#[derive(Clone, Debug, Serialize)]
pub struct CoarsePassSummary {
    /// The coarse image's size in samples.
    pub dims: [usize; 3],
    /// Its edge length (in the image's length unit, `2·L`).
    pub edge_length: f64,
    /// Iterations run on it.
    pub iterations: usize,
    /// Whether it stopped by its stopping rule (not the iteration cap).
    pub converged: bool,
    /// Cells of its final mesh, which starts the full-resolution run.
    pub cells: usize,
    /// Seconds it took (downsampling included).
    pub seconds: f64,
}

/// An image at half resolution: each sample the mean of a block of up to
/// 2 samples per axis (fewer on the last block of an odd side), axes of one
/// sample kept.
struct HalfImage {
    dims: [usize; 3],
    data: Vec<f32>,
    spacing: [f64; 3],
}

impl HalfImage {
    fn of(image: &ImageView<'_>) -> Self {
        let d = image.dims;
        let dims: [usize; 3] = std::array::from_fn(|a| d[a].div_ceil(2));
        let mut sum = vec![0.0f64; dims[0] * dims[1] * dims[2]];
        let mut count = vec![0u32; sum.len()];
        for z in 0..d[2] {
            for y in 0..d[1] {
                let row = (z * d[1] + y) * d[0];
                let out = ((z / 2) * dims[1] + y / 2) * dims[0];
                for x in 0..d[0] {
                    sum[out + x / 2] += image.data[row + x] as f64;
                    count[out + x / 2] += 1;
                }
            }
        }
        let data = sum
            .iter()
            .zip(&count)
            .map(|(&s, &n)| (s / n as f64) as f32)
            .collect();
        // Each coarse sample spans the extent of its fine samples on
        // average, so the coarse domain is the fine one (exactly when the
        // side is even).
        let spacing = std::array::from_fn(|a| image.spacing[a] * d[a] as f64 / dims[a] as f64);
        HalfImage {
            dims,
            data,
            spacing,
        }
    }

    fn view(&self) -> Option<ImageView<'_>> {
        ImageView::new_3d(self.dims, &self.data)?.with_spacing(self.spacing)
    }
}

/// Whether the coarse pass runs for these parameters on this image: asked
/// for, on an adaptive mesh started from the histogram or the range (a
/// given labelling or given shapes are already a start), and every side
/// of more than one sample at least [`MIN_SIDE`] long.
pub fn applies(params: &SegmentParams, image: &ImageView<'_>) -> bool {
    params.coarse_pass
        && params.sizing.adaptive
        && matches!(params.init, Init::Histogram | Init::Range)
        && image
            .dims
            .iter()
            .filter(|&&n| n > 1)
            .all(|&n| n >= MIN_SIDE)
}

/// Runs the coarse pass: the segmentation of the image at half resolution
/// with these parameters at `2·L` (`l` the full run's edge length), without
/// the fine finish and ending at its first quiet flip round. Returns its
/// final mesh on the full image's domain, the thresholds of its
/// initialisation (in the image's units, as the coarse samples are means of
/// the image's) and the summary.
pub fn coarse_mesh<K: Raster>(
    image: &ImageView<'_>,
    params: &SegmentParams,
    l: f64,
) -> Result<(Complex<K>, Vec<f64>, CoarsePassSummary), SegmentError> {
    let t0 = Instant::now();
    let half = HalfImage::of(image);
    let view = half.view().ok_or(SegmentError::EmptyImage)?;
    let mut coarse = params.clone();
    coarse.coarse_pass = false;
    // The length weight is a width in samples, and a coarse sample is about
    // two fine ones wide: scaled so that the pass weighs a unit of
    // interface as the full run does.
    let facet_ratio = (view.sample_step() / image.sample_step()).powi(K::N as i32 - 1);
    coarse.length_weight = params.length_weight * facet_ratio;
    coarse.edge_length = Some(2.0 * l);
    coarse.sizing.finish = None;
    coarse.quiet_round_plateau = Some(0);
    coarse.settle_rate = 0.0;
    let mut seg = Segmentation::<K>::new(view, coarse)?;
    let report = seg.run(|_| {});
    let mut complex = seg.complex().clone();
    let extent = image.extent();
    let mut new_max = K::Point::zero();
    for (a, &e) in extent.iter().enumerate().take(K::N) {
        new_max[a] = e;
    }
    complex
        .stretch_to(new_max)
        .map_err(|e| SegmentError::Init(format!("the coarse pass's mesh: {e}")))?;
    let summary = CoarsePassSummary {
        dims: half.dims,
        edge_length: 2.0 * l,
        iterations: report.iterations,
        converged: report.converged,
        cells: complex.cell_count(),
        seconds: t0.elapsed().as_secs_f64(),
    };
    Ok((complex, report.initial_thresholds, summary))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_half_image_averages_blocks_and_keeps_the_domain() {
        // 3 × 2 × 1: x = 0,1 form one block, x = 2 a block of its own.
        let data = [1.0, 3.0, 10.0, 5.0, 7.0, 20.0];
        let view = ImageView::new_3d([3, 2, 1], &data)
            .unwrap()
            .with_spacing([0.5, 2.0, 1.0])
            .unwrap();
        let half = HalfImage::of(&view);
        assert_eq!(half.dims, [2, 1, 1]);
        assert_eq!(half.data, vec![4.0, 15.0]);
        let coarse = half.view().unwrap();
        assert_eq!(coarse.extent(), view.extent());
        assert_eq!(half.spacing, [0.75, 4.0, 1.0]);
    }

    #[test]
    fn the_pass_applies_to_large_histogram_started_adaptive_runs_only() {
        let data = vec![0.0f32; MIN_SIDE * MIN_SIDE];
        let flat = ImageView::new_3d([MIN_SIDE, MIN_SIDE, 1], &data).unwrap();
        let mut params = SegmentParams::new_3d(2);
        assert!(applies(&params, &flat), "the 3D default");
        params.coarse_pass = false;
        assert!(!applies(&params, &flat));
        params.coarse_pass = true;
        let small = ImageView::new_3d([MIN_SIDE - 1, MIN_SIDE, 1], &data[MIN_SIDE..]).unwrap();
        assert!(!applies(&params, &small));
        let mut uniform = params.clone();
        uniform.sizing.adaptive = false;
        assert!(!applies(&uniform, &flat));
        let mut balls = params;
        balls.init = Init::Balls(Vec::new());
        assert!(!applies(&balls, &flat));
    }
}
