//! Typed handles into a [`Complex`](super::Complex).
//!
//! Ids are plain indices. They stay valid across every local mesh operation:
//! removed vertices and cells are tombstoned, never reused, so a work queue can
//! hold ids and simply skip dead ones. Only [`Complex::compact`](super::Complex::compact)
//! renumbers, and it returns the old-to-new maps.

use serde::{Deserialize, Serialize};

/// A vertex of the complex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct VertexId(pub u32);

/// A top-dimensional cell (triangle or tetrahedron) of the complex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct CellId(pub u32);

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
