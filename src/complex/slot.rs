//! A cell's record in the complex: its corners and its neighbours side by
//! side.
//!
//! The star search, the hottest query of 3D mesh work, reads both for every
//! cell it meets, and the cells of one star lie hundreds to thousands of ids
//! apart: kept in two arrays, each cell it meets cost two cache lines; side
//! by side, one (a tet's record is 32 bytes, aligned to 32, so it never
//! straddles a line).

use crate::dim::Dim;

/// The corners of one cell and the neighbour across the facet opposite
/// each of them.
#[repr(C, align(32))]
pub(super) struct Slot<K: Dim> {
    /// The `N + 1` corners, positively oriented.
    pub corners: K::Cell,
    /// The neighbour opposite each corner; `None` on the domain boundary.
    pub neighbours: K::Neighbours,
}

impl<K: Dim> Slot<K> {
    /// The record of a cell.
    #[inline]
    pub fn new(corners: K::Cell, neighbours: K::Neighbours) -> Self {
        Slot {
            corners,
            neighbours,
        }
    }
}

// (by hand: a derive would ask `K` itself to be `Clone`, `Copy` and `Debug`)
impl<K: Dim> Clone for Slot<K> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<K: Dim> Copy for Slot<K> {}

impl<K: Dim> std::fmt::Debug for Slot<K> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Slot")
            .field("corners", &self.corners)
            .field("neighbours", &self.neighbours)
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::{D2, D3};

    #[test]
    fn a_record_fits_in_one_cache_line_half() {
        assert_eq!(std::mem::size_of::<Slot<D3>>(), 32);
        assert_eq!(std::mem::align_of::<Slot<D3>>(), 32);
        assert_eq!(std::mem::size_of::<Slot<D2>>(), 32);
    }
}
