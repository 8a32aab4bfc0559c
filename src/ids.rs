//! Typed handles of vertices and cells, the lowest layer: the dimension
//! trait ([`crate::dim`]) and the complex ([`crate::complex`]) both use them.
//!
//! Ids are indices (a cell's stored plus one, see [`CellId`]). They stay valid across every local mesh operation:
//! removed vertices and cells are tombstoned, never reused, so a work queue can
//! hold ids and simply skip dead ones. Only
//! [`Complex::compact`](crate::complex::Complex::compact) renumbers, and it
//! returns the old-to-new maps.
//!
//! Only the crate makes ids (the complex hands them out: `cell_ids()`,
//! `vertex_ids()`, neighbours, stars); outside it they cannot be forged from a
//! number. They serialise as their index (validation findings, reports) but
//! are not deserialised.

use serde::{Serialize, Serializer};
use std::num::NonZeroU32;

/// A vertex of the complex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub struct VertexId(pub(crate) u32);

/// A top-dimensional cell (triangle or tetrahedron) of the complex.
///
/// It holds its index plus one, so that `Option<CellId>` (a neighbour across
/// a facet, a vertex's incident cell) takes four bytes instead of eight: the
/// neighbour arrays that every star search reads are half the size. Ids keep
/// the order of their indices.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct CellId(NonZeroU32);

/// A phase label carried by every cell.
pub type Label = u32;

impl VertexId {
    /// The index into per-vertex arrays.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

impl CellId {
    /// The cell of index `index` (below `u32::MAX`).
    #[inline]
    pub(crate) const fn new(index: u32) -> Self {
        match NonZeroU32::new(index.wrapping_add(1)) {
            Some(id) => CellId(id),
            None => panic!("cell index u32::MAX is out of range"),
        }
    }

    /// The index into per-cell arrays.
    #[inline]
    pub fn index(self) -> usize {
        self.raw() as usize
    }

    /// The index as stored in 32 bits.
    #[inline]
    pub(crate) fn raw(self) -> u32 {
        self.0.get() - 1
    }
}

impl std::fmt::Debug for CellId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_tuple("CellId").field(&self.raw()).finish()
    }
}

/// Serialised as its index.
impl Serialize for CellId {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_u32(self.raw())
    }
}
