//! The interface as a sequence of facets: every facet between cells of two
//! different phases, once. Forces, the energy's length term and custom force
//! terms all walk the interface this way.

use super::{CellId, Complex, Label, VertexId};
use crate::dim::{Dim, Point};

/// One interface facet: the side of `cell` opposite its local corner
/// `opposite`, between phase `a` (the cell's) and phase `b` (the neighbour's).
#[derive(Clone, Copy, Debug)]
pub struct InterfaceFacet<P> {
    /// The cell on side `a` (the one with the smaller id of the two).
    pub cell: CellId,
    /// The local index, in `cell`, of the corner opposite the facet.
    pub opposite: usize,
    /// Phase on the cell's side.
    pub a: Label,
    /// Phase on the neighbour's side.
    pub b: Label,
    /// The facet's corners (the first `N` entries), in the cell's order.
    pub corners: [VertexId; 3],
    /// Their positions.
    pub points: [P; 3],
    /// Unit normal, pointing from `a` into `b`.
    pub normal: P,
    /// Length (2D) or area (3D).
    pub measure: f64,
}

/// Layer `complex`: the interface, facet by facet.
impl<K: Dim> Complex<K> {
    /// Every interface facet once, in increasing cell id and then local index.
    pub fn interface_facets(&self) -> impl Iterator<Item = InterfaceFacet<K::Point>> + '_ {
        self.cell_ids()
            .flat_map(move |c| (0..K::NV).filter_map(move |i| self.interface_facet(c, i)))
    }

    /// The facet of `c` opposite local corner `i`, if it is on the interface
    /// and `c` is the smaller id of its two cells.
    #[inline]
    fn interface_facet(&self, c: CellId, i: usize) -> Option<InterfaceFacet<K::Point>> {
        let nb = self.neighbours(c)[i]?;
        let (a, b) = (self.label(c), self.label(nb));
        if a == b || nb.index() < c.index() {
            return None;
        }
        Some(self.facet_between(c, i, a, b))
    }

    /// The facet of `c` opposite local corner `i`, between phases `a` and `b`.
    fn facet_between(&self, c: CellId, i: usize, a: Label, b: Label) -> InterfaceFacet<K::Point> {
        let pts = self.cell_points(c);
        let verts = self.cell(c);
        let mut corners = [verts[0]; 3];
        let mut points = [K::Point::zero(); 3];
        for (n, k) in (0..K::NV).filter(|&k| k != i).enumerate() {
            corners[n] = verts[k];
            points[n] = pts[k];
        }
        InterfaceFacet {
            cell: c,
            opposite: i,
            a,
            b,
            corners,
            points,
            normal: K::facet_normal(&pts[..K::NV], i),
            measure: K::facet_measure(&pts[..K::NV], i),
        }
    }
}
