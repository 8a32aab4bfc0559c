//! Vertex classification: interior, interface, junction, and domain boundary.

use super::{CellId, Complex, Label, VertexId};
use crate::dim::Dim;
use serde::{Deserialize, Serialize};
use smallvec::SmallVec;

/// How a vertex sits relative to the phase interface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum VertexKind {
    /// Every cell around the vertex has the same phase.
    Interior,
    /// The star splits into exactly two same-phase pieces: a point of one curve (2D) or sheet (3D).
    Interface,
    /// Three or more same-phase pieces meet: a triple junction, or a crossing where a
    /// phase occurs twice (2D checkerboard corner, 3D junction curve).
    Junction,
}

/// The class of a vertex: its interface kind and which domain-box faces it lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct VertexClass {
    /// Relation to the interface.
    pub kind: VertexKind,
    /// Bit `2·axis` set: on the box face `x_axis = min`; bit `2·axis + 1`: on `x_axis = max`.
    pub boundary: u8,
}

impl VertexClass {
    /// Whether the vertex lies on the domain boundary.
    pub fn on_boundary(self) -> bool {
        self.boundary != 0
    }
    /// Whether the vertex lies on the interface (including junctions).
    pub fn on_interface(self) -> bool {
        self.kind != VertexKind::Interior
    }
    /// Whether the vertex may not move at all: a corner of the domain box in every axis.
    pub fn pinned_axes(self) -> u8 {
        let mut axes = 0;
        for axis in 0..3 {
            if self.boundary & (0b11 << (2 * axis)) != 0 {
                axes |= 1 << axis;
            }
        }
        axes
    }
}

/// Layer `complex`: vertex classes (interior, interface, junction; box faces).
impl<K: Dim> Complex<K> {
    /// Which box faces `p` lies on (exact comparison: boundary vertices are kept exactly on the box).
    pub(crate) fn boundary_mask(&self, p: &K::Point) -> u8 {
        let mut mask = 0;
        for axis in 0..K::N {
            if p[axis] == self.domain_min[axis] {
                mask |= 1 << (2 * axis);
            }
            if p[axis] == self.domain_max[axis] {
                mask |= 1 << (2 * axis + 1);
            }
        }
        mask
    }

    /// Recomputes the class of `v` from the labels around it.
    pub(crate) fn compute_class(&self, v: VertexId) -> VertexClass {
        self.compute_class_with(v, &mut Vec::new())
    }

    /// [`compute_class`](Self::compute_class); `star` is scratch.
    pub(super) fn compute_class_with(&self, v: VertexId, star: &mut Vec<CellId>) -> VertexClass {
        let pieces = self.phase_pieces_with(v, star);
        let kind = match pieces {
            0 | 1 => VertexKind::Interior,
            2 => VertexKind::Interface,
            _ => VertexKind::Junction,
        };
        VertexClass {
            kind,
            boundary: self.boundary_mask(&self.positions[v.index()]),
        }
    }

    /// Number of connected same-label pieces of the star of `v` (connected through facets containing `v`).
    pub fn count_phase_pieces(&self, v: VertexId) -> usize {
        self.phase_pieces_with(v, &mut Vec::new())
    }

    /// [`count_phase_pieces`](Self::count_phase_pieces); `star` is scratch.
    fn phase_pieces_with(&self, v: VertexId, star: &mut Vec<CellId>) -> usize {
        if K::STAR_IS_FAN {
            if let Some(pieces) = self.fan_phase_pieces(v) {
                return pieces;
            }
        }
        self.phase_pieces_by_search(v, star)
    }

    /// The 2D star is a fan, so its same-label pieces are the runs between
    /// label changes along it: counted in one walk around `v`, without the
    /// search and its buffers (every flip and move reclassifies vertices).
    /// `None` if the walk does not close or end within a sane number of
    /// steps (only a broken complex), for the general search to answer.
    pub(super) fn fan_phase_pieces(&self, v: VertexId) -> Option<usize> {
        let Some(start) = self.vertex_cell[v.index()] else {
            return Some(0);
        };
        let mut changes = 0;
        for first in self.fan_sides(start, v, None) {
            let (mut prev, mut cur) = (start, first);
            let mut steps = 0;
            while let Some(c) = cur {
                changes += usize::from(self.labels[c.index()] != self.labels[prev.index()]);
                if c == start {
                    return Some(changes.max(1));
                }
                steps += 1;
                if steps > 1024 {
                    return None;
                }
                let [a, b] = self.fan_sides(c, v, Some(prev));
                (prev, cur) = (c, a.or(b));
            }
        }
        // Both walks ended at the border: an open fan.
        Some(changes + 1)
    }

    /// The neighbours of `c` across its two edges through `v`, leaving out `except`.
    #[inline]
    fn fan_sides(&self, c: CellId, v: VertexId, except: Option<CellId>) -> [Option<CellId>; 2] {
        let verts = self.slots[c.index()].corners.as_ref();
        let mut out = [None; 2];
        let mut k = 0;
        for (i, &nb) in self.slots[c.index()].neighbours.as_ref().iter().enumerate() {
            if verts[i] != v && k < 2 {
                out[k] = nb.filter(|&n| Some(n) != except);
                k += 1;
            }
        }
        out
    }

    /// [`count_phase_pieces`](Self::count_phase_pieces) by a search over the
    /// star (`star` is scratch; the rest is on the stack for stars of up to
    /// 64 cells).
    pub(super) fn phase_pieces_by_search(&self, v: VertexId, star: &mut Vec<CellId>) -> usize {
        self.star_into(v, star);
        // A star of one label is one piece: the search collected its cells
        // across facets through `v`, so they hang together that way.
        if let Some((first, rest)) = star.split_first() {
            let label = self.labels[first.index()];
            if rest.iter().all(|c| self.labels[c.index()] == label) {
                return 1;
            }
        }
        let mut piece: SmallVec<[usize; 64]> = SmallVec::from_elem(usize::MAX, star.len());
        let mut pieces = 0;
        let mut stack: SmallVec<[usize; 64]> = SmallVec::new();
        for start in 0..star.len() {
            if piece[start] != usize::MAX {
                continue;
            }
            piece[start] = pieces;
            stack.push(start);
            while let Some(i) = stack.pop() {
                let c = star[i];
                let label = self.labels[c.index()];
                for (local, nb) in self.neighbours(c).iter().enumerate() {
                    let Some(nb) = nb else { continue };
                    if self.slots[c.index()].corners.as_ref()[local] == v
                        || self.labels[nb.index()] != label
                    {
                        continue;
                    }
                    if let Some(j) = star.iter().position(|s| s == nb) {
                        if piece[j] == usize::MAX {
                            piece[j] = pieces;
                            stack.push(j);
                        }
                    }
                }
            }
            pieces += 1;
        }
        pieces
    }

    /// Distinct labels around `v`, in increasing order.
    pub fn labels_around(&self, v: VertexId, out: &mut Vec<Label>) {
        let mut star = Vec::new();
        self.star_into(v, &mut star);
        out.clear();
        out.extend(star.iter().map(|c| self.labels[c.index()]));
        out.sort_unstable();
        out.dedup();
    }

    /// Recomputes the class of every live vertex of the given cells.
    /// Each vertex once, however many of the cells hold it (a class depends
    /// only on the labels and positions, not on the order of the updates).
    /// The corners of every flip and collapse (a 3D collapse's star: about
    /// 30 tets) are listed on the stack.
    pub(crate) fn reclassify_cells(&mut self, cells: &[CellId]) {
        if cells.len() >= self.cell_count() {
            // (an initialisation labels every cell: its corners are most
            // vertices, taken in id order by a mark each rather than sorted)
            let mut corner = vec![false; self.vertex_capacity()];
            for &c in cells.iter().filter(|&&c| self.is_alive(c)) {
                for v in self.slots[c.index()].corners.as_ref() {
                    corner[v.index()] = true;
                }
            }
            let mut corners: Vec<VertexId> = (0..corner.len() as u32)
                .map(VertexId)
                .filter(|v| corner[v.index()])
                .collect();
            self.reclassify_vertices(&mut corners);
            return;
        }
        let mut corners: SmallVec<[VertexId; 128]> = cells
            .iter()
            .filter(|&&c| self.is_alive(c))
            .flat_map(|&c| self.slots[c.index()].corners.as_ref().iter().copied())
            .collect();
        self.reclassify_vertices(&mut corners);
    }

    /// Recomputes the class of each listed vertex once (sorts the list).
    pub(crate) fn reclassify_vertices(&mut self, vertices: &mut [VertexId]) {
        vertices.sort_unstable();
        // (the 2D pieces are counted by a walk around the fan, without a star)
        let mut star = if K::STAR_IS_FAN {
            Vec::new()
        } else {
            self.take_list()
        };
        let mut last = None;
        for &v in vertices.iter() {
            if last != Some(v) {
                self.classes[v.index()] = self.compute_class_with(v, &mut star);
                last = Some(v);
            }
        }
        if !K::STAR_IS_FAN {
            self.give_back(star);
        }
    }
}
