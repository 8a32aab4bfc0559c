//! The interface cells: one bit per cell id, set for every live cell with a
//! neighbour of another label, kept current by every change of labels or
//! neighbours. The interface scans
//! ([`Complex::interface_facets`]) visit these cells only, and a label
//! sweep tells a cell inside a phase by one bit instead of its neighbours'
//! labels: most cells of a mesh lie inside a phase.
//!
//! Who keeps the bits: the construction and [`Complex::label_by`] mark
//! every cell, [`Complex::set_label`] and [`Complex::set_labels`] the
//! relabelled cells and their neighbours, a cavity replacement the new
//! cells and the cells around the cavity (the only cells whose neighbours
//! change), and the compaction and the spatial renumbering move the bits
//! with the cells. [`Complex::validate`] checks every bit.

use super::{CellId, Complex};
use crate::dim::Dim;

/// A set of cell ids, one bit each.
#[derive(Clone, Debug, Default)]
pub(super) struct CellBits {
    words: Vec<u64>,
}

impl CellBits {
    /// Room for the ids below `cells`; ids from `cells` on are dropped.
    pub(super) fn resize(&mut self, cells: usize) {
        self.words.resize(cells.div_ceil(64), 0);
        if cells % 64 != 0 {
            if let Some(last) = self.words.last_mut() {
                *last &= (1u64 << (cells % 64)) - 1;
            }
        }
    }

    /// Whether id `i` is in the set.
    #[inline]
    pub(super) fn contains(&self, i: usize) -> bool {
        self.words
            .get(i / 64)
            .is_some_and(|w| w >> (i % 64) & 1 == 1)
    }

    /// Puts id `i` in the set (`on`) or takes it out.
    #[inline]
    pub(super) fn set(&mut self, i: usize, on: bool) {
        let bit = 1u64 << (i % 64);
        let word = &mut self.words[i / 64];
        if on {
            *word |= bit;
        } else {
            *word &= !bit;
        }
    }

    /// The smallest id in the set from `i` on.
    #[inline]
    pub(super) fn next_from(&self, i: usize) -> Option<usize> {
        let mut word = i / 64;
        let mut bits = self.words.get(word)? & (u64::MAX << (i % 64));
        while bits == 0 {
            word += 1;
            bits = *self.words.get(word)?;
        }
        Some(word * 64 + bits.trailing_zeros() as usize)
    }

    /// The set renumbered: id `order[k]` becomes `k`.
    pub(super) fn gathered(&self, order: &[u32]) -> CellBits {
        let mut out = CellBits::default();
        out.resize(order.len());
        for (k, &old) in order.iter().enumerate() {
            if self.contains(old as usize) {
                out.set(k, true);
            }
        }
        out
    }
}

/// Layer `complex`: the interface cells.
impl<K: Dim> Complex<K> {
    /// Whether live cell `c` has a neighbour of another label (one bit,
    /// kept current; `false` for a dead cell).
    #[inline]
    pub fn meets_other_label(&self, c: CellId) -> bool {
        self.interface_cells.contains(c.index())
    }

    /// Whether cell `c` is live and has a neighbour of another label, from
    /// the neighbours' labels themselves: what its bit must hold.
    pub(super) fn meets_other_label_now(&self, c: CellId) -> bool {
        let own = self.labels[c.index()];
        self.alive[c.index()]
            && self.slots[c.index()]
                .neighbours
                .as_ref()
                .iter()
                .flatten()
                .any(|nb| self.labels[nb.index()] != own)
    }

    /// Sets the bit of `c` from its neighbours.
    pub(super) fn remark_interface_cell(&mut self, c: CellId) {
        let on = self.meets_other_label_now(c);
        self.interface_cells.set(c.index(), on);
    }

    /// Sets the bits of `c` and its neighbours (after `c`'s label changed).
    pub(super) fn remark_interface_cells_around(&mut self, c: CellId) {
        self.remark_interface_cell(c);
        for k in 0..K::NV {
            if let Some(nb) = self.slots[c.index()].neighbours.as_ref()[k] {
                self.remark_interface_cell(nb);
            }
        }
    }

    /// Sets the bits after a cavity replacement: the `old` cells died, the
    /// cells of ids `new` were appended, and the cells `around` the cavity
    /// have new neighbours.
    pub(super) fn remark_interface_cells_of_cavity(
        &mut self,
        old: &[CellId],
        new: std::ops::Range<u32>,
        around: &[CellId],
    ) {
        self.interface_cells.resize(self.slots.len());
        for &c in old {
            self.interface_cells.set(c.index(), false);
        }
        for c in new.map(CellId::new).chain(around.iter().copied()) {
            self.remark_interface_cell(c);
        }
    }

    /// Sets every bit.
    pub(super) fn remark_all_interface_cells(&mut self) {
        self.interface_cells = CellBits::default();
        self.interface_cells.resize(self.slots.len());
        for i in 0..self.slots.len() {
            self.remark_interface_cell(CellId::new(i as u32));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::{D2, D3};
    use crate::dsc::{Connectivity, Destinations, DscParams};
    use crate::ops::CollapseMode;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    /// Every bit against its definition.
    fn assert_marks_current<K: Dim>(cx: &Complex<K>, step: usize) {
        for i in 0..cx.cell_capacity() {
            let c = CellId::new(i as u32);
            assert_eq!(
                cx.meets_other_label(c),
                cx.meets_other_label_now(c),
                "cell {i} after step {step}"
            );
        }
        assert!(!cx.interface_cells.contains(cx.cell_capacity()));
    }

    #[test]
    fn bits_follow_every_set_and_take() {
        let mut bits = CellBits::default();
        bits.resize(130);
        for i in [0, 63, 64, 129] {
            bits.set(i, true);
        }
        assert_eq!(bits.next_from(0), Some(0));
        assert_eq!(bits.next_from(1), Some(63));
        assert_eq!(bits.next_from(65), Some(129));
        bits.set(63, false);
        assert_eq!(bits.next_from(1), Some(64));
        bits.resize(100);
        assert_eq!(bits.next_from(65), None);
        let order = [64u32, 0, 5];
        let gathered = bits.gathered(&order);
        assert!(gathered.contains(0) && gathered.contains(1) && !gathered.contains(2));
    }

    /// A random step of the sequences below: a relabelling of one cell or
    /// of a cell's neighbours, an edge split or collapse, or a compaction.
    fn random_step<K: Dim>(cx: &mut Complex<K>, rng: &mut StdRng) {
        let c = CellId::new(rng.random_range(0..cx.cell_capacity() as u32));
        if !cx.is_alive(c) {
            return;
        }
        let (u, v) = (cx.cell(c)[0], cx.cell(c)[1]);
        match rng.random_range(0..5) {
            0 => cx.set_label(c, rng.random_range(0..3)),
            1 => {
                let changes: Vec<_> = cx
                    .neighbours(c)
                    .iter()
                    .flatten()
                    .map(|&nb| (nb, rng.random_range(0..3)))
                    .collect();
                cx.set_labels(&changes);
            }
            2 => {
                let _ = cx.split_edge(u, v);
            }
            3 => {
                let _ = cx.collapse_edge(u, v, CollapseMode::Unsafe, 0.0, 1.0);
            }
            _ => cx.compact_in_place(),
        }
    }

    /// Random moves of a tenth of the vertices by up to `reach`, deformed.
    fn random_deform<K: Connectivity>(cx: &mut Complex<K>, rng: &mut StdRng, reach: f64) {
        let mut dest = Destinations::new(cx);
        let vertices: Vec<_> = cx.vertex_ids().collect();
        for v in vertices {
            if rng.random_range(0..10) == 0 {
                let mut p = cx.position(v);
                for axis in 0..K::N {
                    p[axis] += rng.random_range(-reach..reach);
                }
                dest.set(v, p);
            }
        }
        cx.deform(&dest, &DscParams::new::<K>(2.0));
    }

    /// A random sequence of relabellings, edge flips (2D), splits,
    /// collapses, compactions and deformations keeps every bit equal to a
    /// recomputation from the labels and neighbours.
    #[test]
    fn the_marks_follow_relabels_and_mesh_changes_2d() {
        let mut rng = StdRng::seed_from_u64(7);
        let mut cx = Complex::<D2>::rectangle(30.0, 24.0, 2.0).unwrap();
        cx.label_by(|p| u32::from((p.x - 15.0).hypot(p.y - 12.0) < 7.0));
        assert_marks_current(&cx, 0);
        for step in 1..600 {
            if step % 50 == 0 {
                random_deform(&mut cx, &mut rng, 1.5);
            } else if step % 7 == 0 {
                let c = CellId::new(rng.random_range(0..cx.cell_capacity() as u32));
                let _ = cx.flip_if_better(c, rng.random_range(0..3));
            } else {
                random_step(&mut cx, &mut rng);
            }
            assert_marks_current(&cx, step);
        }
        assert!(cx.validate().is_empty());
    }

    /// The same in 3D, where a compaction may also renumber spatially.
    #[test]
    fn the_marks_follow_relabels_and_mesh_changes_3d() {
        let mut rng = StdRng::seed_from_u64(11);
        let mut cx = Complex::<D3>::cuboid([10.0, 9.0, 8.0], 2.0).unwrap();
        cx.label_by(|p| u32::from((p - nalgebra::Vector3::new(5.0, 4.5, 4.0)).norm() < 3.0));
        assert_marks_current(&cx, 0);
        let mut reordered = 0;
        for step in 1..300 {
            if step % 40 == 0 {
                random_deform(&mut cx, &mut rng, 1.0);
            } else {
                random_step(&mut cx, &mut rng);
            }
            reordered += usize::from(cx.last_compaction_reordered());
            assert_marks_current(&cx, step);
        }
        assert!(cx.validate().is_empty());
        assert!(reordered > 0, "the test's premise: a spatial renumbering");
    }
}
