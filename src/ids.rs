//! Typed handles of vertices and cells, the lowest layer: the dimension
//! trait ([`crate::dim`]) and the complex ([`crate::complex`]) both use them.
//!
//! Ids are plain indices. They stay valid across every local mesh operation:
//! removed vertices and cells are tombstoned, never reused, so a work queue can
//! hold ids and simply skip dead ones. Only
//! [`Complex::compact`](crate::complex::Complex::compact) renumbers, and it
//! returns the old-to-new maps.
//!
//! Only the crate makes ids (the complex hands them out: `cell_ids()`,
//! `vertex_ids()`, neighbours, stars); outside it they cannot be forged from a
//! number. They serialise as their index (validation findings, reports) but
//! are not deserialised.

use serde::Serialize;

/// A vertex of the complex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub struct VertexId(pub(crate) u32);

/// A top-dimensional cell (triangle or tetrahedron) of the complex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub struct CellId(pub(crate) u32);

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
    /// The index into per-cell arrays.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}
