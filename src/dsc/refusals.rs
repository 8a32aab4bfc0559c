//! The collapses that coarsening tried and the mesh refused, remembered
//! across deforms so that they are not tried again while nothing they
//! depend on has changed.
//!
//! Away from the interfaces a graded mesh hardly changes from one iteration
//! to the next, yet every resize coarsens the whole interior again: it tries
//! the shortest edge of every interior cell below the coarsening length, and
//! the mesh refuses most of those collapses (a new cell would be too flat, or
//! the link condition fails) the same way every time. Whether the safe
//! collapse of an edge `uv` between two interior vertices is refused depends
//! on the stars of `u` and `v` alone (their cells, corner positions and
//! open box facets, and the two vertices' classes, which coarsening checks
//! anyway) and on the quality and straightness bounds. The complex stamps
//! every change of a star with its move clock ([`Complex::star_changed_at`]),
//! so a refusal at clock `t` stands while neither star has changed since:
//! trying again would be refused again. Exact: coarsening does what it did
//! without the record. The flips of 3D mesh improvement are remembered the
//! same way ([`ImproveMemo`](crate::ops::ImproveMemo)'s refused flips).

use crate::complex::{CellId, Complex, VertexId};
use crate::dim::Dim;
use crate::ops::CellStamps;

/// Per cell: when the collapse of its shortest edge was last refused.
#[derive(Clone, Debug, Default)]
pub(crate) struct RefusedCollapses {
    /// Per cell id: the move clock right after the refusal.
    refused: CellStamps,
    /// The collapses' quality and straightness bounds.
    bounds: [f64; 2],
}

impl RefusedCollapses {
    /// Forgets what does not hold for `complex` and collapses judged by the
    /// quality bound `min_quality` and straightness `straight_cos`:
    /// everything if it is another complex, was renumbered by a compaction
    /// the record did not follow ([`follow_compaction`](Self::follow_compaction)),
    /// or the bounds changed.
    pub(crate) fn sync<K: Dim>(
        &mut self,
        complex: &Complex<K>,
        min_quality: f64,
        straight_cos: f64,
    ) {
        let bounds = [min_quality, straight_cos];
        if !self.refused.sync(complex) && self.bounds != bounds {
            self.refused.forget();
        }
        self.bounds = bounds;
    }

    /// Records that the collapse of `uv`, the shortest edge of `c`, was refused now.
    pub(crate) fn record<K: Dim>(&mut self, complex: &Complex<K>, c: CellId) {
        self.refused.record(complex, c);
    }

    /// Whether the collapse of `uv`, the shortest edge of `c`, was refused
    /// and neither star has changed since (the cell's corners then have not
    /// moved either, so `uv` is still its shortest edge).
    #[inline]
    pub(crate) fn still_refused<K: Dim>(
        &self,
        complex: &Complex<K>,
        c: CellId,
        (u, v): (VertexId, VertexId),
    ) -> bool {
        self.refused
            .get(c)
            .is_some_and(|t| complex.star_changed_at(u) <= t && complex.star_changed_at(v) <= t)
    }

    /// Carries the record through the compaction `complex` just made (its
    /// cell map), so that it holds across deforms.
    pub(crate) fn follow_compaction<K: Dim>(&mut self, complex: &Complex<K>) {
        self.refused.follow_compaction(complex);
    }
}
