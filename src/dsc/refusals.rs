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
//! without the record.

use crate::complex::{CellId, Complex, VertexId};
use crate::dim::Dim;

/// Per cell: when the collapse of its shortest edge was last refused.
#[derive(Clone, Debug, Default)]
pub(crate) struct RefusedCollapses {
    /// Per cell id: the move clock right after the refusal.
    refused: Vec<Option<u64>>,
    /// The complex the record is about (its identity and compactions, which
    /// number its cells) and the collapses' quality and straightness bounds.
    about: Option<(u64, u64)>,
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
        let about = Some((complex.identity(), complex.compactions()));
        let bounds = [min_quality, straight_cos];
        if self.about != about || self.bounds != bounds {
            self.refused.clear();
            self.about = about;
            self.bounds = bounds;
        }
    }

    /// Records that the collapse of `uv`, the shortest edge of `c`, was refused now.
    pub(crate) fn record<K: Dim>(&mut self, complex: &Complex<K>, c: CellId) {
        if c.index() >= self.refused.len() {
            self.refused.resize(c.index() + 1, None);
        }
        self.refused[c.index()] = Some(complex.move_clock());
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
            .get(c.index())
            .copied()
            .flatten()
            .is_some_and(|t| complex.star_changed_at(u) <= t && complex.star_changed_at(v) <= t)
    }

    /// Carries the record through the compaction `complex` just made (its
    /// cell map), so that it holds across deforms.
    pub(crate) fn follow_compaction<K: Dim>(&mut self, complex: &Complex<K>) {
        if self.about.is_none_or(|(identity, compactions)| {
            identity != complex.identity() || compactions + 1 != complex.compactions()
        }) {
            self.refused.clear();
            self.about = None;
            return;
        }
        // New ids are dense and in the old ids' order, never above them:
        // forward copies are safe, and the first `live` entries are written.
        let map = &complex.last_cell_map()[..self.refused.len().min(complex.last_cell_map().len())];
        for (old, new) in map.iter().enumerate() {
            if let Some(new) = new {
                self.refused[new.index()] = self.refused[old];
            }
        }
        let live = map.iter().flatten().count();
        self.refused.truncate(live);
        self.about = Some((complex.identity(), complex.compactions()));
    }
}
