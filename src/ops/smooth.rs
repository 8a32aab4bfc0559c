//! Laplacian smoothing of vertices off the interface.

use super::ImproveMemo;
use crate::complex::{CellId, Complex, VertexId};
use crate::dim::{Dim, Point};

/// A star whose worst cell is at least this good is left alone: smoothing would
/// barely improve it, and skipping it keeps improvement cheap where the mesh is fine.
const GOOD_ENOUGH: f64 = 0.8;

impl<K: Dim> Complex<K> {
    /// Moves a non-interface vertex towards the mean of its neighbours (sliding
    /// along the domain boundary if it lies on it), unless its star is already
    /// good. Accepted only if no cell inverts and the worst quality of its star
    /// does not drop. Returns whether it moved. `memo` skips the vertices
    /// whose answer cannot have changed since it was last asked (see
    /// [`ImproveMemo`]).
    pub fn smooth_vertex(
        &mut self,
        v: VertexId,
        star: &mut Vec<CellId>,
        memo: &mut ImproveMemo,
    ) -> bool {
        if !self.is_vertex_alive(v) || self.class(v).on_interface() || memo.still_kept(self, v) {
            return false;
        }
        self.star_into(v, star);
        let moved = self.smooth_star(v, star);
        memo.set_kept(self, v, !moved);
        moved
    }

    /// The smoothing move of `v` with its star: see [`Complex::smooth_vertex`].
    fn smooth_star(&mut self, v: VertexId, star: &[CellId]) -> bool {
        // Most stars are good: decide that without computing the qualities.
        if star
            .iter()
            .all(|&c| K::quality_at_least(&self.cell_points(c)[..K::NV], GOOD_ENOUGH))
        {
            return false;
        }
        let p = self.position(v);
        let before = self.min_quality_at(star, v, p);
        let mut sum = K::Point::zero();
        let mut n = 0usize;
        for &c in star.iter() {
            for &w in self.cell(c) {
                if w != v {
                    sum += self.position(w);
                    n += 1;
                }
            }
        }
        if n == 0 {
            return false;
        }
        let target = self.constrain(v, sum * (1.0 / n as f64));
        if (target - p).length() <= 1e-12 {
            return false;
        }
        if !self.star_positive_at(star, v, target)
            || !self.qualities_at_least(star, v, target, before)
        {
            return false;
        }
        self.set_position(v, target);
        true
    }
}
