//! Laplacian smoothing of vertices off the interface.

use super::ImproveMemo;
use crate::complex::{CellId, Complex, VertexId};
use crate::dim::{Dim, Point};

/// A star whose worst cell is at least this good is left alone: smoothing would
/// barely improve it, and skipping it keeps improvement cheap where the mesh is fine.
const GOOD_ENOUGH: f64 = 0.8;

/// Scratch space of smoothing, reused from vertex to vertex.
#[derive(Clone, Debug)]
pub struct SmoothScratch<K: Dim> {
    star: Vec<CellId>,
    /// Per star cell: its corners and the index of the smoothed vertex
    /// among them (read once, then used by every test of the move).
    corners: Vec<([K::Point; 4], Option<usize>)>,
}

impl<K: Dim> Default for SmoothScratch<K> {
    fn default() -> Self {
        SmoothScratch {
            star: Vec::new(),
            corners: Vec::new(),
        }
    }
}

/// Layer `ops`: vertex smoothing.
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
        scratch: &mut SmoothScratch<K>,
        memo: &mut ImproveMemo,
    ) -> bool {
        if !self.is_vertex_alive(v) || self.class(v).on_interface() || memo.still_kept(self, v) {
            return false;
        }
        self.star_into(v, &mut scratch.star);
        scratch.corners.clear();
        for &c in &scratch.star {
            scratch
                .corners
                .push((self.cell_points(c), self.local_index(c, v)));
        }
        let moved = self.smooth_star(v, &scratch.corners);
        memo.set_kept(self, v, !moved);
        moved
    }

    /// The smoothing move of `v` with its star's corners: see
    /// [`Complex::smooth_vertex`].
    fn smooth_star(&mut self, v: VertexId, star: &[([K::Point; 4], Option<usize>)]) -> bool {
        // Most stars are good: decide that without computing the qualities.
        if star
            .iter()
            .all(|(pts, _)| K::quality_at_least(&pts[..K::NV], GOOD_ENOUGH))
        {
            return false;
        }
        let p = self.position(v);
        let at = |q: K::Point| {
            star.iter().map(move |&(mut pts, i)| {
                if let Some(i) = i {
                    pts[i] = q;
                }
                pts
            })
        };
        let before = at(p)
            .map(|pts| K::quality(&pts[..K::NV]))
            .fold(1.0, f64::min);
        let mut sum = K::Point::zero();
        let mut n = 0usize;
        for (pts, i) in star {
            for (j, w) in pts[..K::NV].iter().enumerate() {
                if Some(j) != *i {
                    sum += *w;
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
        if !at(target).all(|pts| K::orient(&pts[..K::NV]) > 0.0)
            || !at(target).all(|pts| K::quality_at_least(&pts[..K::NV], before))
        {
            return false;
        }
        self.set_position(v, target);
        true
    }
}
