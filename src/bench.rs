//! Internals the criterion benchmarks time on their own (`benches/`): not
//! part of the library's interface, and hidden from its documentation.

use crate::complex::Complex;
use crate::segment::{CellStats, ImageView, Raster};
use spin_join::SpinHelper;

/// The segmentation's cache of per-cell statistics (only cells whose
/// corners moved are integrated again), as the driver keeps it.
#[derive(Clone, Debug, Default)]
pub struct CellCache<K: Raster>(crate::segment::integrate::CellCache<K>);

impl<K: Raster> CellCache<K> {
    /// An empty cache.
    pub fn new() -> Self {
        CellCache(crate::segment::integrate::CellCache::new())
    }

    /// Fills `out` as `segment::integrate::integrate_cells` does, integrating
    /// only the cells that changed since the last call; returns how many.
    pub fn integrate(
        &mut self,
        complex: &Complex<K>,
        image: &ImageView<'_>,
        out: &mut Vec<CellStats>,
    ) -> usize {
        self.0.integrate(complex, image, out)
    }

    /// [`integrate`](Self::integrate), sharing the work with `helper`'s thread.
    pub fn integrate_on(
        &mut self,
        helper: &SpinHelper,
        complex: &Complex<K>,
        image: &ImageView<'_>,
        out: &mut Vec<CellStats>,
    ) -> usize {
        self.0.integrate_on(helper, complex, image, out)
    }
}
