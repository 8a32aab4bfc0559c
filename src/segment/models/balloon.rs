//! The balloon (pressure) force of Cohen (1991): the boundary of one phase is
//! pushed along its outward normal with a constant pressure, so that a small
//! seed inflates (negative pressure: deflates) and reaches edges the image
//! force alone would not see. Optionally the pressure fades at edges,
//! `p · 1/(1 + P/k)` with the edge potential `P` of an [`EdgeMap`], and
//! combined with [`EdgeAttraction`](super::EdgeAttraction) the edge holds the
//! balloon.

use super::edge::EdgeMap;
use crate::complex::Complex;
use crate::complex::Label;
use crate::segment::model::{phase_normals, ForceTerm, IterationState};
use crate::segment::raster::Raster;
use std::sync::Arc;

/// Pressure on the boundary of one phase (see the [module docs](self)).
#[derive(Clone, Debug)]
pub struct Balloon<P = ()> {
    /// The inflated phase.
    pub phase: Label,
    /// The pressure: force per vertex along the outward unit normal (positive
    /// inflates), in units of the reference magnitude 1.
    pub pressure: f64,
    /// Optional edge stop: the map and the potential `k` at which the pressure halves.
    pub edge_stop: Option<(Arc<EdgeMap>, f64)>,
    normals: Vec<P>,
}

impl<P> Balloon<P> {
    /// A balloon inflating `phase` with `pressure`, without edge stop.
    pub fn new(phase: Label, pressure: f64) -> Self {
        Balloon {
            phase,
            pressure,
            edge_stop: None,
            normals: Vec::new(),
        }
    }

    /// Fades the pressure to `1/(1 + P/k)` of itself where the edge potential is `P`.
    pub fn with_edge_stop(mut self, map: Arc<EdgeMap>, k: f64) -> Self {
        self.edge_stop = Some((map, k));
        self
    }
}

impl<K: Raster> ForceTerm<K> for Balloon<K::Point> {
    fn name(&self) -> &str {
        "balloon"
    }

    fn add_forces(
        &mut self,
        complex: &Complex<K>,
        _state: &IterationState<'_, '_>,
        out: &mut [K::Point],
    ) {
        phase_normals(complex, self.phase, &mut self.normals);
        for v in complex.vertex_ids() {
            let n = self.normals[v.index()];
            let mut p = self.pressure;
            if let Some((map, k)) = &self.edge_stop {
                p /= 1.0 + map.potential::<K>(complex.position(v)) / k;
            }
            out[v.index()] += n * p;
        }
    }
}
