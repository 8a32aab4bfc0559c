//! Edge split: insert the midpoint of an edge and halve every cell around it.
//!
//! ```text
//!      a                 a
//!     / \               /|\
//!    u---v     ==>     u-m-v    (each cell on uv becomes two; labels kept)
//!     \ /               \|/
//!      b                 b
//! ```

use crate::complex::{CellId, Complex, Label, Rejection, VertexId};
use crate::dim::Dim;
use smallvec::SmallVec;

/// Layer `ops`: edge splits.
impl<K: Dim> Complex<K> {
    /// Splits edge `uv` at its midpoint, returning the new vertex. Per-phase
    /// measures are unchanged (each cell is cut exactly in two).
    pub fn split_edge(&mut self, u: VertexId, v: VertexId) -> Result<VertexId, Rejection> {
        if u == v || !self.is_vertex_alive(u) || !self.is_vertex_alive(v) {
            return Err(Rejection::Stale);
        }
        let mut star = self.take_list();
        let mut old = self.take_list();
        self.cells_of_edge(u, v, &mut star, &mut old);
        let result = self.split_cells_of_edge(u, v, &old);
        self.give_back(star);
        self.give_back(old);
        result
    }

    /// Splits the cells `old` of the edge `uv` (see [`split_edge`](Self::split_edge)).
    fn split_cells_of_edge(
        &mut self,
        u: VertexId,
        v: VertexId,
        old: &[CellId],
    ) -> Result<VertexId, Rejection> {
        if old.is_empty() {
            return Err(Rejection::Stale);
        }
        let mid = (self.position(u) + self.position(v)) * 0.5;
        let m = self.add_vertex(mid);
        // (4 cells in 2D; about 14 in 3D)
        let mut new: SmallVec<[(K::Cell, Label); 16]> = SmallVec::new();
        for &c in old {
            for replaced in [u, v] {
                let mut cell = K::cell(self.cell(c));
                for w in cell.as_mut() {
                    if *w == replaced {
                        *w = m;
                    }
                }
                new.push((cell, self.label(c)));
            }
        }
        self.replace_cells(old, &new)?;
        Ok(m)
    }

    /// The longest edge of a cell.
    pub fn longest_edge(&self, c: CellId) -> (VertexId, VertexId) {
        self.extreme_edge(c, true)
    }

    /// The shortest edge of a cell.
    pub fn shortest_edge(&self, c: CellId) -> (VertexId, VertexId) {
        self.extreme_edge(c, false)
    }

    fn extreme_edge(&self, c: CellId, longest: bool) -> (VertexId, VertexId) {
        let cell = self.cell(c);
        let mut best = (cell[0], cell[1]);
        let mut best_len = if longest { -1.0 } else { f64::INFINITY };
        for i in 0..K::NV {
            for j in i + 1..K::NV {
                let d = self.position(cell[i]) - self.position(cell[j]);
                let len = crate::dim::Point::length(&d);
                if (longest && len > best_len) || (!longest && len < best_len) {
                    best_len = len;
                    best = (cell[i], cell[j]);
                }
            }
        }
        best
    }

    /// Edges of a cell sorted by increasing length.
    pub fn edges_by_length(&self, c: CellId) -> Vec<(VertexId, VertexId)> {
        self.sorted_edges(c).to_vec()
    }

    /// [`edges_by_length`](Self::edges_by_length), on the stack.
    pub(crate) fn sorted_edges(&self, c: CellId) -> SmallVec<[(VertexId, VertexId); 6]> {
        let cell = self.cell(c);
        let mut edges: SmallVec<[(f64, VertexId, VertexId); 6]> = SmallVec::new();
        for i in 0..K::NV {
            for j in i + 1..K::NV {
                let d = self.position(cell[i]) - self.position(cell[j]);
                edges.push((crate::dim::Point::length(&d), cell[i], cell[j]));
            }
        }
        edges.sort_by(|a, b| a.0.total_cmp(&b.0));
        edges.into_iter().map(|(_, a, b)| (a, b)).collect()
    }
}
