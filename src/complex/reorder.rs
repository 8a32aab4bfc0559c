//! Spatial renumbering: the compaction's occasional second step.
//!
//! Splits, collapses and flips append their new cells and vertices at the
//! end of the arrays, and compaction keeps the survivors' relative order,
//! so after many iterations a vertex's star is scattered over the arrays.
//! A 3D mesh outgrows the caches (hundreds of thousands of tetrahedra, tens
//! of megabytes), and then every star search, edge turn and neighbour read
//! misses. Once enough cells lie outside the spatial order, the compaction
//! renumbers the vertices along a Z-order (Morton) curve through their
//! positions and the cells by their lowest-numbered corner, so that cells
//! close in space are close in memory again. The order depends on the
//! mesh alone (ties broken by the old ids), never on the thread count.

use super::{CellId, Complex, Slot, VertexId};
use crate::dim::Dim;

/// Renumber once more than `1 / REORDER_SHARE` of the live cells were
/// appended since the last spatial renumbering: rare enough that the sort
/// costs little beside the iterations between, often enough that most
/// stars stay compact.
const REORDER_SHARE: usize = 4;

/// Bits per axis of the quantised positions: three axes fill 63 bits.
const KEY_BITS: u32 = 21;

impl<K: Dim> Complex<K> {
    /// Whether the compaction just made should renumber spatially: in the
    /// dimensions that do, once the cells appended out of order (`live`
    /// cells, of which the first `ordered` are in order) exceed the share.
    pub(super) fn reorder_due(&self, ordered: usize, live: usize) -> bool {
        K::REORDERS_SPATIALLY
            && !self.book.renumbering_held
            && (live - ordered) * REORDER_SHARE > live
    }

    /// How many live cells lie before the end of the last spatial order
    /// (the compaction's first `kept_cells` are all live): the cells in that
    /// order after the compaction. 0 where nothing is renumbered, which
    /// need not count.
    pub(super) fn ordered_survivors(&self, kept_cells: usize) -> usize {
        if !K::REORDERS_SPATIALLY {
            return 0;
        }
        let end = self.book.ordered_cells.min(self.alive.len());
        let kept = kept_cells.min(end);
        kept + self.alive[kept..end].iter().filter(|&&a| a).count()
    }

    /// Holds the spatial renumbering off (`held`) or lets it happen again.
    /// A sweep that relabels cells one after the other in id order (the
    /// guarded label flips) decides differently when the ids follow space,
    /// where one relabelled cell makes its neighbour's flip pay next; the
    /// refined 3D start, whose passes each end with such a sweep over the
    /// cells just refined, holds the renumbering off until its passes end
    /// (`benches/RESULTS.md`, "Speed, 3D").
    pub fn hold_spatial_renumbering(&mut self, held: bool) {
        self.book.renumbering_held = held;
    }

    /// Renumbers the (compacted) vertices in Z-order of their positions and
    /// the cells by their lowest new corner, and composes the renumbering
    /// into the last compaction's maps.
    pub(super) fn reorder_spatially(&mut self) {
        let vertex_order = self.vertices_in_z_order();
        let mut new_vertex = vec![0u32; vertex_order.len()];
        for (new, &old) in vertex_order.iter().enumerate() {
            new_vertex[old as usize] = new as u32;
        }
        let cell_order = self.cells_by_lowest_corner(&new_vertex);
        let mut new_cell = vec![0u32; cell_order.len()];
        for (new, &old) in cell_order.iter().enumerate() {
            new_cell[old as usize] = new as u32;
        }
        self.permute_vertices(&vertex_order, &new_cell);
        self.permute_cells(&cell_order, &new_vertex, &new_cell);
        for v in self.book.last_vertex_map.iter_mut().flatten() {
            *v = VertexId(new_vertex[v.index()]);
        }
        for c in self.book.last_cell_map.iter_mut().flatten() {
            *c = CellId::new(new_cell[c.index()]);
        }
    }

    /// The vertex ids sorted by the Morton code of their positions,
    /// quantised on a grid over the domain (ties by id).
    fn vertices_in_z_order(&self) -> Vec<u32> {
        let (lo, hi) = self.domain();
        let cells_per_axis = f64::from((1u32 << KEY_BITS) - 1);
        let mut keyed: Vec<(u64, u32)> = self
            .positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let mut key = 0u64;
                for axis in 0..K::N {
                    let t = (p[axis] - lo[axis]) / (hi[axis] - lo[axis]);
                    let q = (t.clamp(0.0, 1.0) * cells_per_axis) as u64;
                    key |= spread(q, K::N) << axis;
                }
                (key, i as u32)
            })
            .collect();
        keyed.sort_unstable();
        keyed.into_iter().map(|(_, i)| i).collect()
    }

    /// The cell ids ordered by their lowest corner under `new_vertex`
    /// (ties by id): a counting sort, so the cells around a vertex follow
    /// one another as the vertices do.
    fn cells_by_lowest_corner(&self, new_vertex: &[u32]) -> Vec<u32> {
        let lowest = |slot: &Slot<K>| {
            slot.corners
                .as_ref()
                .iter()
                .map(|v| new_vertex[v.index()])
                .min()
                .expect("a cell has corners") as usize
        };
        let mut start = vec![0u32; new_vertex.len() + 1];
        for slot in &self.slots {
            start[lowest(slot) + 1] += 1;
        }
        for i in 1..start.len() {
            start[i] += start[i - 1];
        }
        let mut order = vec![0u32; self.slots.len()];
        for (i, slot) in self.slots.iter().enumerate() {
            let place = &mut start[lowest(slot)];
            order[*place as usize] = i as u32;
            *place += 1;
        }
        order
    }

    /// Moves every vertex record to its new id (`order`: old id by new id).
    fn permute_vertices(&mut self, order: &[u32], new_cell: &[u32]) {
        self.positions = gather_from(&self.positions, order);
        self.classes = gather_from(&self.classes, order);
        self.book.moved_at = gather_from(&self.book.moved_at, order);
        self.book.star_changed_at = gather_from(&self.book.star_changed_at, order);
        self.book.cells_changed_at = gather_from(&self.book.cells_changed_at, order);
        self.vertex_cell = gather_mapped(&self.vertex_cell, order, |c| {
            c.map(|c| CellId::new(new_cell[c.index()]))
        });
    }

    /// Moves every cell record to its new id (`order`: old id by new id),
    /// renaming its corners and neighbours.
    fn permute_cells(&mut self, order: &[u32], new_vertex: &[u32], new_cell: &[u32]) {
        self.slots = gather_mapped(&self.slots, order, |mut slot| {
            for v in slot.corners.as_mut() {
                *v = VertexId(new_vertex[v.index()]);
            }
            for c in slot.neighbours.as_mut() {
                *c = c.map(|c| CellId::new(new_cell[c.index()]));
            }
            slot
        });
        self.labels = gather_from(&self.labels, order);
        self.interface_cells = self.interface_cells.gathered(order);
    }
}

/// `values` in `order` (an index list), with the capacity of `values`: the
/// arrays keep the room they had grown to, instead of growing again (and
/// doubling) at the next cells appended.
fn gather_from<T: Copy>(values: &Vec<T>, order: &[u32]) -> Vec<T> {
    gather_mapped(values, order, |x| x)
}

/// [`gather_from`] with each entry passed through `f`.
fn gather_mapped<T: Copy>(values: &Vec<T>, order: &[u32], f: impl Fn(T) -> T) -> Vec<T> {
    let mut out = Vec::with_capacity(values.capacity());
    out.extend(order.iter().map(|&i| f(values[i as usize])));
    out
}

/// The low bits of `q` spread `n` apart (bit `b` to bit `b·n`), so that the
/// spread coordinates of `n` axes interleave into a Morton code.
fn spread(q: u64, n: usize) -> u64 {
    (0..KEY_BITS).fold(0, |key, b| key | ((q >> b) & 1) << (b as usize * n))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::D3;
    use crate::dsc::{Destinations, DscParams};
    use nalgebra::Vector3;

    /// A ball labelled in a box mesh, pushed outwards by a few deforms, so
    /// that splits, collapses and flips appended cells out of order.
    fn deformed_ball() -> Complex<D3> {
        let l = 3.0;
        let mut c = Complex::<D3>::cuboid([24.0, 21.0, 18.0], l).unwrap();
        let centre = Vector3::new(12.0, 10.5, 9.0);
        c.label_by(|p| u32::from((p - centre).norm() < 5.0));
        let params = DscParams::new::<D3>(l);
        for _ in 0..4 {
            let mut dest = Destinations::new(&c);
            for v in c.vertex_ids().collect::<Vec<_>>() {
                let p = c.position(v);
                let d = p - centre;
                if d.norm() < 8.0 {
                    dest.set(v, c.constrain(v, p + d * 0.2));
                }
            }
            c.deform(&dest, &params);
        }
        c
    }

    /// The renumbering moves every vertex and cell record whole (positions,
    /// classes, clocks, corners in their order, neighbours, labels) to the
    /// ids its maps give, leaves a valid mesh, and puts the vertices in
    /// Z-order and the cells in the order of their lowest corners.
    #[test]
    fn renumbering_moves_every_record_and_orders_the_mesh() {
        let mut c = deformed_ball();
        let before = c.clone();
        // Everything counts as appended: the next compaction renumbers.
        c.book.ordered_cells = 0;
        c.compact_in_place();
        assert!(c.last_compaction_reordered());
        assert!(c.validate().is_empty());
        assert_eq!(c.cell_count(), before.cell_count());
        let vmap = c.last_vertex_map().to_vec();
        let cmap = c.last_cell_map().to_vec();
        let moved = |v: VertexId| vmap[v.index()].expect("a live vertex keeps an id");
        for v in before.vertex_ids() {
            let w = moved(v);
            assert_eq!(c.position(w), before.position(v));
            assert_eq!(c.class(w), before.class(v));
            assert_eq!(c.moved_at(w), before.moved_at(v));
            assert_eq!(c.star_changed_at(w), before.star_changed_at(v));
            assert_eq!(c.cells_changed_at(w), before.cells_changed_at(v));
        }
        let mut renumbered = 0;
        for x in before.cell_ids() {
            let y = cmap[x.index()].expect("a live cell keeps an id");
            renumbered += usize::from(x != y);
            let corners: Vec<_> = before.cell(x).iter().map(|&v| moved(v)).collect();
            assert_eq!(c.cell(y), &corners[..]);
            assert_eq!(c.label(y), before.label(x));
            let across: Vec<_> = before
                .neighbours(x)
                .iter()
                .map(|n| n.map(|n| cmap[n.index()].unwrap()))
                .collect();
            assert_eq!(c.neighbours(y), &across[..]);
        }
        assert!(renumbered > 0, "the deforms appended cells out of order");
        let lowest = |x: CellId| c.cell(x).iter().min().copied().unwrap();
        let cells: Vec<_> = c.cell_ids().collect();
        assert!(cells.windows(2).all(|w| lowest(w[0]) <= lowest(w[1])));
    }

    /// The vertices follow the Z-order curve: quantised positions'
    /// Morton codes never decrease along the ids.
    #[test]
    fn vertices_follow_the_z_order_curve() {
        let mut c = deformed_ball();
        c.book.ordered_cells = 0;
        c.compact_in_place();
        let order = c.vertices_in_z_order();
        assert!(order.iter().enumerate().all(|(i, &v)| v as usize == i));
    }

    /// Interleaving: bit `b` of axis `a` lands on bit `3b + a`.
    #[test]
    fn spread_interleaves_the_axes() {
        assert_eq!(spread(0b1, 3), 0b1);
        assert_eq!(spread(0b11, 3), 0b1001);
        assert_eq!(spread(0b101, 2), 0b10001);
        let top = 1u64 << (KEY_BITS - 1);
        assert_eq!(spread(top, 3) << 2, 1u64 << 62);
    }

    /// A compaction renumbers once a quarter of the cells were appended,
    /// never in 2D.
    #[test]
    fn renumbering_is_due_for_many_appended_cells_in_3d_only() {
        let c3 = Complex::<D3>::cuboid([6.0, 6.0, 6.0], 3.0).unwrap();
        assert!(!c3.reorder_due(100, 125));
        assert!(c3.reorder_due(100, 134));
        let c2 = Complex::<crate::dim::D2>::rectangle(6.0, 6.0, 3.0).unwrap();
        assert!(!c2.reorder_due(0, 100));
    }
}
