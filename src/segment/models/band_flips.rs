//! The blurred-band flips of [`crate::segment::band_flips`] as a label rule
//! (on with [`SegmentParams::band_flips`](crate::segment::SegmentParams::band_flips):
//! 3D runs with three or more phases).

use crate::complex::Complex;
use crate::segment::band_flips::{BandFlipper, BandInputs};
use crate::segment::model::{IterationState, LabelRule};
use crate::segment::raster::Raster;

/// Layers of an intermediate phase as thin as a blurred edge's band between
/// two other phases go back to those phases.
#[derive(Clone, Debug, Default)]
pub struct BandFlips {
    flipper: BandFlipper,
}

impl BandFlips {
    /// The edge blur estimated at the last flip round (mesh units), if any.
    pub fn blur(&self) -> Option<f64> {
        self.flipper.blur()
    }
}

fn inputs<'r, 'a>(state: &'r IterationState<'r, 'a>) -> BandInputs<'r, 'a> {
    BandInputs {
        image: state.image,
        cells: state.cells,
        phases: state.phases,
        edge_length: state.edge_length,
    }
}

impl<K: Raster> LabelRule<K> for BandFlips {
    fn name(&self) -> &str {
        "blurred-band flips"
    }

    fn relabel(&mut self, complex: &mut Complex<K>, state: &IterationState<'_, '_>) -> usize {
        self.flipper.flip(complex, &inputs(state))
    }

    fn would_relabel(
        &mut self,
        complex: &Complex<K>,
        state: &IterationState<'_, '_>,
    ) -> Option<bool> {
        Some(self.flipper.would_flip(complex, &inputs(state)))
    }
}
