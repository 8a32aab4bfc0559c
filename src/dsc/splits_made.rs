//! The vertices one removal of degenerate cells made by splitting edges,
//! which the same removal does not collapse away.
//!
//! In 3D a degenerate tet that no collapse removes is split at its longest
//! edge (a new vertex `m` at the midpoint). The halves of a flat tet are flat
//! too, so the removal finds one of them degenerate at once, and the collapse
//! it finds there may merge `m` with a vertex of the old tet at that vertex's
//! place: the old cells are back, under new ids, and the removal splits them
//! again. Flat tets squeezed between an interface and a box face of a 1 mm
//! brain MRI block sent one removal round such a circle 300 000 times, until
//! its work budget ran out. A removal therefore collapses no edge at a vertex
//! it made by a split, and splits no cell with such a vertex for a corner: a
//! half that stays degenerate is left to the flips of the improvement that
//! follows (as is a degenerate cell whose longest edge is shorter than the
//! target size). Each collapse then removes a vertex the mesh had before the
//! removal, and each split a cell all of whose corners it had: only
//! collapses make such cells, so the removal's work is bounded by the region
//! it was given and the cells its collapses reshape, not by a budget.

use crate::complex::VertexId;

/// The vertices one removal made by splitting edges.
#[derive(Debug, Default)]
pub(crate) struct SplitsMade {
    /// In the order made, so increasing (vertex ids only grow between
    /// compactions, and a removal runs within one).
    made: Vec<VertexId>,
}

impl SplitsMade {
    /// Forgets the vertices of the last removal.
    pub(crate) fn clear(&mut self) {
        self.made.clear();
    }

    /// Records that the removal made `m` by a split.
    pub(crate) fn record(&mut self, m: VertexId) {
        debug_assert!(self.made.last().is_none_or(|&last| last < m));
        self.made.push(m);
    }

    /// Whether an end of the edge `ab` is a vertex the removal made.
    pub(crate) fn holds_an_end_of(&self, a: VertexId, b: VertexId) -> bool {
        self.holds_a_corner_of(&[a, b])
    }

    /// Whether one of `corners` is a vertex the removal made.
    pub(crate) fn holds_a_corner_of(&self, corners: &[VertexId]) -> bool {
        !self.made.is_empty() && corners.iter().any(|w| self.made.binary_search(w).is_ok())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_edge_at_a_vertex_made_by_a_split_is_held() {
        let [u, v, m, n] = [0, 1, 7, 9].map(VertexId);
        let mut splits = SplitsMade::default();
        assert!(!splits.holds_an_end_of(m, u));
        splits.record(m);
        splits.record(n);
        assert!(splits.holds_an_end_of(m, u));
        assert!(splits.holds_an_end_of(v, n));
        assert!(splits.holds_an_end_of(m, n));
        assert!(!splits.holds_an_end_of(u, v));
        assert!(splits.holds_a_corner_of(&[u, v, n]));
        assert!(!splits.holds_a_corner_of(&[u, v]));
        splits.clear();
        assert!(!splits.holds_an_end_of(m, u));
    }
}
