//! Dimensions: the one generic axis of the crate.
//!
//! Everything that differs between triangles and tetrahedra (point type, the
//! fixed-size vertex and neighbour arrays of a cell, exact orientation, measure,
//! quality) sits behind the sealed [`Dim`] trait, implemented by the zero-sized
//! [`D2`] and [`D3`]. The complex, the mesh operations and the deform loop are
//! written once against it.

mod d2;
mod d3;
mod point;

pub use d2::D2;
pub use d3::D3;
pub use point::Point;

use crate::ids::{CellId, VertexId};
use std::fmt::Debug;

mod sealed {
    pub trait Sealed {}
    impl Sealed for super::D2 {}
    impl Sealed for super::D3 {}
}

/// The default quality thresholds of a dimension's mesh (see
/// [`DscParams`](crate::dsc::DscParams), which starts from them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QualityDefaults {
    /// A cell below this quality is degenerate and removed.
    pub degenerate: f64,
    /// A collapse is safe only if the cells it creates reach this quality.
    pub minimum: f64,
    /// Interface facets meeting within this angle (degrees) of a straight
    /// line or plane count as flat.
    pub straight_angle_deg: f64,
}

/// A spatial dimension (2 or 3) with the cell shape that fills it.
pub trait Dim: sealed::Sealed + Copy + Clone + Debug + Default + Send + Sync + 'static {
    /// Spatial dimension.
    const N: usize;
    /// Vertices per cell (`N + 1`).
    const NV: usize = Self::N + 1;
    /// Whether the cells around a vertex form a fan (2D), walked around the
    /// vertex; otherwise (3D) they are found by a search across facets.
    const STAR_IS_FAN: bool;
    /// Whether interfaces can meet along an edge (3D junction curves); in
    /// 2D they meet at vertices only.
    const EDGE_JUNCTIONS: bool;
    /// What the grid's samples are called ("pixels", "voxels").
    const SAMPLES: &'static str;
    /// The smallest grid a mesh can cover ("2×2", "2×2×2").
    const SMALLEST_GRID: &'static str;
    /// Whether a degenerate cell that no collapse removes is split at its
    /// longest edge (3D, where slivers whose every collapse would invert a
    /// neighbour are common); in 2D such a triangle is left as it is.
    const SPLITS_UNCOLLAPSIBLE: bool;
    /// Whether compaction renumbers the mesh in spatial order once enough
    /// cells were appended out of it (3D, whose mesh arrays outgrow the
    /// caches; a 2D mesh fits in them and keeps its order).
    const REORDERS_SPATIALLY: bool;
    /// A point or vector of the space.
    type Point: Point;
    /// The `N + 1` vertices of a cell, positively oriented.
    type Cell: Copy + Debug + PartialEq + Send + Sync + AsRef<[VertexId]> + AsMut<[VertexId]>;
    /// Neighbour across the facet opposite each local vertex; `None` on the domain boundary.
    type Neighbours: Copy
        + Debug
        + PartialEq
        + Send
        + Sync
        + AsRef<[Option<CellId>]>
        + AsMut<[Option<CellId>]>;

    /// The default quality thresholds of the mesh in this dimension.
    fn quality_defaults() -> QualityDefaults;
    /// Builds a cell from exactly `NV` vertex ids.
    fn cell(vertices: &[VertexId]) -> Self::Cell;
    /// A neighbour array with every entry `None`.
    fn no_neighbours() -> Self::Neighbours;
    /// Exact orientation test of a cell's `NV` corners: positive when the cell is
    /// positively oriented, zero when degenerate. The sign is exact (adaptive
    /// precision); the magnitude is a multiple of the measure.
    fn orient(p: &[Self::Point]) -> f64;
    /// Signed area (2D) or volume (3D) in floating point.
    fn signed_measure(p: &[Self::Point]) -> f64;
    /// Shape quality in `[0, 1]`, 1 for the regular simplex, 0 when degenerate.
    fn quality(p: &[Self::Point]) -> f64;
    /// [`quality`](Self::quality) of a simplex known to be positively
    /// oriented by the exact test (every cell of a complex, a candidate
    /// that passed [`orient`](Self::orient)): the same value, without
    /// repeating that test. On a simplex that is not positively oriented
    /// the answer is meaningless.
    #[inline]
    fn quality_oriented(p: &[Self::Point]) -> f64 {
        Self::quality(p)
    }
    /// Whether `quality(p) >= q_min`, exactly; dimensions may answer most
    /// cases without the square root and division of `quality`.
    #[inline]
    fn quality_at_least(p: &[Self::Point], q_min: f64) -> bool {
        Self::quality(p) >= q_min
    }
    /// [`quality_at_least`](Self::quality_at_least) of a simplex known to be
    /// positively oriented (see [`quality_oriented`](Self::quality_oriented)).
    #[inline]
    fn quality_oriented_at_least(p: &[Self::Point], q_min: f64) -> bool {
        Self::quality_at_least(p, q_min)
    }
    /// Measure of the regular cell with edge length `l`: the DSC's average
    /// cell area `A = √3/4·l²` (2D) or volume `V = √2/12·l³` (3D).
    fn regular_measure(l: f64) -> f64;
    /// Unit normal of the facet opposite corner `opposite`, pointing away from that corner.
    fn facet_normal(p: &[Self::Point], opposite: usize) -> Self::Point;
    /// Measure (length or area) of the facet opposite corner `opposite`.
    fn facet_measure(p: &[Self::Point], opposite: usize) -> f64;
}
