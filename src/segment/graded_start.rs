//! The graded start of a 2D adaptive run: the coarse start mesh refined to
//! `L` wherever its cells mix the classes of the initial thresholds, before
//! the cells are labelled.
//!
//! A start mesh at `h_max` (coarse to fine) labelled by its cells' means
//! loses what is smaller than a cell: a square's corners, a 5-px bar, fall
//! to the class of the cells around them and must be found again by
//! refinement, which under noise it only partly does. A start at `L`
//! everywhere keeps them, but the first deform then coarsens the whole
//! mesh (a third or more of the run's work). Graded, the start is fine
//! where the thresholds' structures are and coarse elsewhere, so the first
//! labelling follows the structures and the first deform has little to
//! change.

use super::adaptive::{AdaptiveSizing, START_SPLIT};
use super::image::ImageView;
use super::integrate::{CellCache, CellStats};
use super::intensity::IntensityStats;
use super::raster::Raster;
use super::thresholds::split_histogram;
use crate::complex::Complex;
use crate::dsc::{Destinations, DscParams, DscWorkspace};
use spin_join::SpinHelper;

/// Passes of the graded start at most: each refines the cells that mix
/// classes by a factor of about 1.5–2 in edge length, from `h_max` (the
/// smallest side/16 by default) to `L/2` (about the side/128), so five to
/// six passes reach `L/2`; a pass that refines nothing ends it.
pub const GRADING_PASSES: usize = 6;

/// What the graded start works with.
pub struct StartGrading<'s, 'a, K: Raster> {
    /// The image.
    pub image: &'s ImageView<'a>,
    /// Its intensity figures (the cell-mean histogram's range).
    pub intensity: &'s IntensityStats,
    /// The number of phases (classes of the thresholds).
    pub phases: usize,
    /// The DSC's thresholds (the resize).
    pub dsc: &'s DscParams,
    /// The thread the integration may split onto.
    pub helper: &'s SpinHelper,
    /// The cache of the cells' statistics.
    pub cache: &'s mut CellCache<K>,
    /// The cells' statistics, by cell id.
    pub cells: &'s mut Vec<CellStats>,
    /// The deform's workspace (its sizing field is the start's).
    pub workspace: &'s mut DscWorkspace<K>,
}

impl<K: Raster> StartGrading<'_, '_, K> {
    /// Refines `complex` (the start mesh at `h_max`) until no coarse cell
    /// mixes the classes of the thresholds of its cells' means, at most
    /// [`GRADING_PASSES`] times; the refinements become requests of
    /// `sizing` for the run. Returns the passes that refined.
    pub fn run(&mut self, complex: &mut Complex<K>, sizing: &mut AdaptiveSizing) -> usize {
        for pass in 0..GRADING_PASSES {
            self.integrate(complex);
            let histogram = self.intensity.cell_histogram(self.cells);
            let classes = split_histogram(&histogram, self.phases);
            let means: Vec<f64> = classes.means.iter().flatten().copied().collect();
            let start = START_SPLIT * sizing.sizes().interface;
            let coarse = self.dsc.max_measure * K::regular_measure(start);
            let asked = sizing.grade_start(complex, self.cells, &means, coarse);
            if asked == 0 {
                return pass;
            }
            self.workspace.copy_sizing(sizing.start_field());
            let still = Destinations::new(complex);
            complex.deform_with(&still, self.dsc, self.workspace);
        }
        GRADING_PASSES
    }

    fn integrate(&mut self, complex: &Complex<K>) {
        self.cache
            .integrate_on(self.helper, complex, self.image, self.cells);
    }
}
