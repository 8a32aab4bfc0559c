//! Moving one vertex as far as possible towards a destination without inverting a cell.

use crate::complex::{CellId, Complex, VertexId};
use crate::dim::{Dim, Point};

/// What a single move achieved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MoveOutcome {
    /// The vertex reached its (constrained) destination.
    Arrived,
    /// The vertex moved part of the way; it is this far from its destination.
    Partial(f64),
    /// The vertex could not move at all without inverting a cell.
    Blocked,
}

/// Layer `ops`: the DSC's vertex move (as far as possible without inversion).
impl<K: Dim> Complex<K> {
    /// Restricts a destination to what `v` may reach: coordinates pinned by the
    /// domain faces the vertex lies on are kept, the rest is clamped into the box.
    /// Interface vertices on the border therefore slide along it.
    pub fn constrain(&self, v: VertexId, dest: K::Point) -> K::Point {
        let p = self.position(v);
        let pinned = self.class(v).pinned_axes();
        let (lo, hi) = self.domain();
        let mut out = dest;
        for axis in 0..K::N {
            out[axis] = if pinned & (1 << axis) != 0 {
                p[axis]
            } else {
                dest[axis].clamp(lo[axis], hi[axis])
            };
        }
        out
    }

    /// Moves `v` towards `dest` as the DSC does: every cell of the star has a
    /// signed measure linear in the move parameter, so the first cell to collapse
    /// is found in closed form; the vertex goes at most half-way to that point,
    /// and the new position is confirmed with exact predicates (halving on failure).
    /// `star` is scratch space.
    pub fn move_towards(
        &mut self,
        v: VertexId,
        dest: K::Point,
        tolerance: f64,
        star: &mut Vec<CellId>,
    ) -> MoveOutcome {
        let p = self.position(v);
        let target = self.constrain(v, dest);
        let r = target - p;
        let dist = r.length();
        if dist <= tolerance {
            return MoveOutcome::Arrived;
        }
        self.star_into(v, star);
        let mut t_hit = f64::INFINITY;
        for &c in star.iter() {
            let (before, after) = self.measure_moved(c, v, target);
            if after < before {
                t_hit = t_hit.min(before / (before - after));
            }
        }
        let mut step = if t_hit.is_finite() {
            (0.5 * (dist * t_hit - tolerance)).min(dist)
        } else {
            dist
        };
        for _ in 0..8 {
            if step <= 0.0 {
                break;
            }
            let q = if step >= dist {
                target
            } else {
                p + r * (step / dist)
            };
            if self.star_positive_at(star, v, q) {
                self.set_position_in_star(v, q, star);
                return if step >= dist {
                    MoveOutcome::Arrived
                } else {
                    MoveOutcome::Partial(dist - step)
                };
            }
            step *= 0.5;
        }
        MoveOutcome::Blocked
    }

    /// Signed measure of `c` before and after moving `v` to `q`.
    fn measure_moved(&self, c: CellId, v: VertexId, q: K::Point) -> (f64, f64) {
        let mut pts = self.cell_points(c);
        let before = K::signed_measure(&pts[..K::NV]);
        let i = self
            .local_index(c, v)
            .expect("star cell contains the vertex");
        pts[i] = q;
        (before, K::signed_measure(&pts[..K::NV]))
    }

    /// Whether every cell in `cells` stays positively oriented with `v` at `q` (exact).
    pub(crate) fn star_positive_at(&self, cells: &[CellId], v: VertexId, q: K::Point) -> bool {
        cells.iter().all(|&c| {
            let mut pts = self.cell_points(c);
            if let Some(i) = self.local_index(c, v) {
                pts[i] = q;
            }
            K::orient(&pts[..K::NV]) > 0.0
        })
    }
}
