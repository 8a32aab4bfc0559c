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

/// The iterator of [`Complex::interface_facets`]: a scan of the cells with
/// a neighbour of another label ([`Complex::meets_other_label`], one bit
/// per cell), so that walking the interface of a large mesh costs little
/// more than the interface itself.
pub struct InterfaceFacets<'c, K: Dim> {
    complex: &'c Complex<K>,
    /// The cell being scanned.
    cell: usize,
    /// The first local index of `cell` not yet scanned.
    next_local: usize,
}

impl<K: Dim> Iterator for InterfaceFacets<'_, K> {
    type Item = InterfaceFacet<K::Point>;

    fn next(&mut self) -> Option<Self::Item> {
        let (c, i, b) = self.next_facet()?;
        let cx = self.complex;
        Some(cx.facet_between(c, i, cx.labels[c.index()], b))
    }
}

impl<K: Dim> InterfaceFacets<'_, K> {
    /// The next interface facet: its cell, the local index of the corner
    /// opposite it and the label across it.
    #[inline]
    fn next_facet(&mut self) -> Option<(CellId, usize, Label)> {
        let cx = self.complex;
        // (only the cells with a neighbour of another label can have one)
        while let Some(c) = cx.interface_cells.next_from(self.cell) {
            if c != self.cell {
                (self.cell, self.next_local) = (c, 0);
            }
            if let Some((i, b)) = cx.next_interface_facet(c, self.next_local) {
                self.next_local = i + 1;
                return Some((CellId::new(c as u32), i, b));
            }
            (self.cell, self.next_local) = (c + 1, 0);
        }
        self.cell = cx.slots.len();
        None
    }

    /// [`next_facet`](Self::next_facet) without the label.
    fn next_id(&mut self) -> Option<(CellId, usize)> {
        self.next_facet().map(|(c, i, _)| (c, i))
    }
}

/// Layer `complex`: the interface, facet by facet.
impl<K: Dim> Complex<K> {
    /// Every interface facet once, in increasing cell id and then local index.
    pub fn interface_facets(&self) -> InterfaceFacets<'_, K> {
        InterfaceFacets {
            complex: self,
            cell: 0,
            next_local: 0,
        }
    }

    /// Every interface facet once as (cell, local index of the opposite
    /// corner), in the order of [`interface_facets`](Self::interface_facets),
    /// without its geometry.
    pub fn interface_facet_ids(&self) -> impl Iterator<Item = (CellId, usize)> + '_ {
        let mut facets = self.interface_facets();
        std::iter::from_fn(move || facets.next_id())
    }

    /// The local index, from `from` on, of the first facet of live cell `c`
    /// on the interface whose other cell has a larger id (that cell lists
    /// it), with that neighbour's label.
    #[inline]
    fn next_interface_facet(&self, c: usize, from: usize) -> Option<(usize, Label)> {
        let own = self.labels[c];
        let neighbours = self.slots[c].neighbours.as_ref();
        (from..K::NV).find_map(|i| {
            let nb = neighbours[i]?;
            let other = self.labels[nb.index()];
            (other != own && nb.index() > c).then_some((i, other))
        })
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::{D2, D3};

    /// The facets every pair of cells of different labels shares, each
    /// once from its smaller cell, in increasing cell id and local index:
    /// the definition the scan must give, facet for facet.
    fn facets_by_definition<K: Dim>(cx: &Complex<K>) -> Vec<(CellId, usize, Label, Label)> {
        let mut out = Vec::new();
        for c in cx.cell_ids() {
            for (i, nb) in cx.neighbours(c).iter().enumerate() {
                if let Some(nb) = *nb {
                    if cx.label(nb) != cx.label(c) && nb.index() > c.index() {
                        out.push((c, i, cx.label(c), cx.label(nb)));
                    }
                }
            }
        }
        out
    }

    fn assert_scan_is_the_definition<K: Dim>(cx: &Complex<K>) {
        let expected = facets_by_definition(cx);
        assert!(!expected.is_empty(), "the test's premise: an interface");
        let scanned: Vec<_> = cx
            .interface_facets()
            .map(|f| (f.cell, f.opposite, f.a, f.b))
            .collect();
        assert_eq!(scanned, expected);
        let ids: Vec<_> = cx.interface_facet_ids().collect();
        let expected_ids: Vec<_> = expected.iter().map(|&(c, i, _, _)| (c, i)).collect();
        assert_eq!(ids, expected_ids);
    }

    #[test]
    fn the_scan_lists_every_interface_facet_once_in_order() {
        let mut cx = Complex::<D2>::rectangle(40.0, 30.0, 3.0).unwrap();
        // three phases, one of them in two pieces
        cx.label_by(|p| u32::from(p.x > 20.0) + u32::from((p.x - 8.0).hypot(p.y - 8.0) < 5.0) * 2);
        assert_scan_is_the_definition(&cx);
        // dead cells among the live ones (a collapse's, before compaction)
        let cell = cx.cell_ids().nth(cx.cell_count() / 2).unwrap();
        let (u, v) = (cx.cell(cell)[0], cx.cell(cell)[1]);
        let collapsed = cx.collapse_edge(u, v, crate::ops::CollapseMode::Unsafe, 0.0, 1.0);
        assert!(collapsed.is_ok() && cx.cell_capacity() > cx.cell_count());
        assert_scan_is_the_definition(&cx);
        let mut cx = Complex::<D3>::cuboid([12.0, 10.0, 9.0], 3.0).unwrap();
        cx.label_by(|p| u32::from((p - nalgebra::Vector3::new(6.0, 5.0, 4.5)).norm() < 3.5));
        assert_scan_is_the_definition(&cx);
    }
}
