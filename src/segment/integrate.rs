//! Integration of the image over the cells: per-cell sums, per-phase means.

use super::image::ImageView;
use super::raster::Raster;
use crate::complex::{CellId, Complex, Label};
use rayon::prelude::*;
use serde::Serialize;

/// Sum, sum of squares and number of the pixels whose centre lies in a cell.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CellStats {
    /// Sum of the intensities.
    pub sum: f64,
    /// Sum of the squared intensities.
    pub sum_sq: f64,
    /// Number of pixels.
    pub count: u32,
}

impl CellStats {
    /// Mean intensity, `None` for a cell that covers no pixel centre.
    pub fn mean(&self) -> Option<f64> {
        (self.count > 0).then(|| self.sum / self.count as f64)
    }
    /// Sum of squared deviations from `m`: `Σ (I − m)²`.
    pub fn sse(&self, m: f64) -> f64 {
        (self.sum_sq - 2.0 * m * self.sum + self.count as f64 * m * m).max(0.0)
    }
}

/// Fills `out` (indexed by cell id; dead cells get zeros) with the statistics
/// of every live cell, in parallel. `out` is reused: it only grows.
pub fn integrate_cells<K: Raster>(
    complex: &Complex<K>,
    image: &ImageView<'_>,
    out: &mut Vec<CellStats>,
) {
    out.clear();
    out.resize(complex.cell_capacity(), CellStats::default());
    out.par_iter_mut().enumerate().for_each(|(i, s)| {
        let c = CellId(i as u32);
        if !complex.is_alive(c) {
            return;
        }
        let pts = complex.cell_points(c);
        *s = cell_stats::<K>(image, &pts[..K::NV]);
    });
}

/// The statistics of the pixels whose centre lies in the cell with the given
/// corners: row spans summed as contiguous slices, in increasing pixel order
/// (so the sums are bit-identical to a pixel-by-pixel loop).
#[inline]
pub fn cell_stats<K: Raster>(image: &ImageView<'_>, corners: &[K::Point]) -> CellStats {
    let (mut sum, mut sum_sq, mut count) = (0.0f64, 0.0f64, 0usize);
    K::cell_spans(image, corners, &mut |a, b| {
        for &v in &image.data[a..b] {
            let v = v as f64;
            sum += v;
            sum_sq += v * v;
        }
        count += b - a;
    });
    CellStats {
        sum,
        sum_sq,
        count: count as u32,
    }
}

/// Per-phase totals and means.
#[derive(Clone, Debug, Default, Serialize)]
pub struct PhaseStats {
    /// Pixel count of each phase.
    pub count: Vec<u64>,
    /// Intensity sum of each phase.
    pub sum: Vec<f64>,
    /// Current mean of each phase. A phase without pixels keeps its previous
    /// mean (or `None` if it never had one), so it can be revived by flips.
    pub mean: Vec<Option<f64>>,
}

impl PhaseStats {
    /// Empty statistics for `phases` phases.
    pub fn new(phases: usize) -> Self {
        PhaseStats {
            count: vec![0; phases],
            sum: vec![0.0; phases],
            mean: vec![None; phases],
        }
    }

    /// Recomputes counts, sums and means from per-cell statistics and the
    /// current labels. Phases left without pixels keep their previous mean.
    pub fn update<K: Raster>(&mut self, complex: &Complex<K>, cells: &[CellStats]) {
        self.count.iter_mut().for_each(|c| *c = 0);
        self.sum.iter_mut().for_each(|s| *s = 0.0);
        for c in complex.cell_ids() {
            let l = complex.label(c) as usize;
            if l < self.count.len() {
                self.count[l] += cells[c.index()].count as u64;
                self.sum[l] += cells[c.index()].sum;
            }
        }
        for k in 0..self.count.len() {
            if self.count[k] > 0 {
                self.mean[k] = Some(self.sum[k] / self.count[k] as f64);
            }
        }
    }

    /// Mean of phase `l` (`None` if it never had pixels).
    pub fn mean_of(&self, l: Label) -> Option<f64> {
        self.mean.get(l as usize).copied().flatten()
    }

    /// Number of phases that currently cover at least one pixel.
    pub fn present(&self) -> usize {
        self.count.iter().filter(|&&c| c > 0).count()
    }
}
