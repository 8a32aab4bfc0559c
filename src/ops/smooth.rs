//! Laplacian smoothing of vertices off the interface.
//!
//! A pass runs on one thread, vertex after vertex, each move seeing the
//! moves before it. Computing the moves ahead on rayon's threads from the
//! positions at the start of a pass was tried: most of them were computed
//! again in order, since a neighbour had moved first, and on the brain
//! phantom the pass cost more CPU time and memory than it saved wall clock
//! (benches/RESULTS.md, "Speed, 3D").

use super::ImproveMemo;
use crate::complex::{CellId, Complex, VertexId};
use crate::dim::{Dim, Point};

/// A star whose worst cell is at least this good is left alone: smoothing would
/// barely improve it, and skipping it keeps improvement cheap where the mesh is fine.
const GOOD_ENOUGH: f64 = 0.8;

/// The shortest smoothing move, as a fraction of the mean length of the
/// vertex's edges: 2 % in 3D (as the forces' smallest move, 0.02·L), none
/// in 2D. Laplacian smoothing converges slowly: a vertex that moves by a
/// hair changes the stars of its neighbours, which are then judged again and
/// move by a hair too, pass after pass. On the brain phantom smoothing was
/// a third of the run's serial part, and without such moves the run took
/// 0.89–0.94× the wall clock at the same Dice (benches/RESULTS.md, "Speed,
/// 3D"); 2D meshes are small and keep every move.
fn least_move_fraction<K: Dim>() -> f64 {
    if K::N == 3 {
        0.02
    } else {
        0.0
    }
}

/// Scratch space of smoothing, reused from vertex to vertex.
#[derive(Clone, Debug)]
pub struct SmoothScratch<K: Dim> {
    star: Vec<CellId>,
    /// Per star cell: its corners and the index of the smoothed vertex
    /// among them (read once, then used by every test of the move).
    corners: Vec<([K::Point; 4], Option<usize>)>,
    /// The star's qualities computed (not read from the memo) for its
    /// quality before a move, with their cells, to be recorded (3D).
    computed: Vec<(CellId, f64)>,
}

impl<K: Dim> Default for SmoothScratch<K> {
    fn default() -> Self {
        SmoothScratch {
            star: Vec::new(),
            corners: Vec::new(),
            computed: Vec::new(),
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
        if self.skips_smoothing(v, memo) {
            return false;
        }
        // (the recorded qualities are read only about this complex as it
        // is numbered now)
        memo.qualities.sync(self);
        memo.stars.sync(self);
        let target = self.smoothing_target(v, scratch, memo);
        self.apply_smoothing(v, target, &scratch.star, memo)
    }

    /// Moves `v` to `target` if there is one, and records the verdict;
    /// `star` holds the cells of `v`'s star.
    fn apply_smoothing(
        &mut self,
        v: VertexId,
        target: Option<K::Point>,
        star: &[CellId],
        memo: &mut ImproveMemo,
    ) -> bool {
        if let Some(p) = target {
            self.set_position_in_star(v, p, star);
        }
        memo.set_kept(self, v, target.is_none());
        target.is_some()
    }

    /// One smoothing pass over `vertices`, in their order; returns how many
    /// moved.
    pub(crate) fn smooth_pass(
        &mut self,
        vertices: &[VertexId],
        scratch: &mut SmoothScratch<K>,
        memo: &mut ImproveMemo,
    ) -> usize {
        vertices
            .iter()
            .filter(|&&v| self.smooth_vertex(v, scratch, memo))
            .count()
    }

    /// Whether smoothing leaves `v` alone without looking at its star.
    fn skips_smoothing(&self, v: VertexId, memo: &ImproveMemo) -> bool {
        !self.is_vertex_alive(v) || self.class(v).on_interface() || memo.still_kept(self, v)
    }

    /// Where smoothing moves `v`, if anywhere (see
    /// [`smooth_vertex`](Self::smooth_vertex)). Changes no cell or vertex;
    /// in 3D the qualities it computed are recorded in `memo` (the search
    /// for poor tets and later passes read them while no corner moves).
    fn smoothing_target(
        &self,
        v: VertexId,
        scratch: &mut SmoothScratch<K>,
        memo: &mut ImproveMemo,
    ) -> Option<K::Point> {
        let SmoothScratch {
            star,
            corners,
            computed,
        } = scratch;
        memo.stars.star_into(self, v, star);
        corners.clear();
        for &c in star.iter() {
            corners.push((self.cell_points(c), self.local_index(c, v)));
        }
        computed.clear();
        let known = &*memo;
        let worst_now = || {
            let qualities = star.iter().zip(corners.iter()).map(|(&c, (pts, _))| {
                known.qualities.current(self, c).unwrap_or_else(|| {
                    let q = K::quality_oriented(&pts[..K::NV]);
                    computed.push((c, q));
                    q
                })
            });
            // (the first cell of the smallest quality, with it)
            qualities.enumerate().fold(
                (1.0, 0),
                |(q, k), (j, qj)| if qj < q { (qj, j) } else { (q, k) },
            )
        };
        let target = self.smooth_star(v, corners, worst_now);
        if K::N == 3 {
            for &(c, q) in computed.iter() {
                memo.qualities.record(self, c, q);
            }
        }
        target
    }

    /// The smoothing move of `v` with its star's corners: see
    /// [`Complex::smooth_vertex`].
    ///
    /// `worst_now` gives the smallest quality of the star's cells as they
    /// are and the first cell that has it: qualities recorded while no
    /// corner has moved since are read rather than computed (the same bits:
    /// the same formula of the same corners).
    fn smooth_star(
        &self,
        v: VertexId,
        star: &[([K::Point; 4], Option<usize>)],
        worst_now: impl FnOnce() -> (f64, usize),
    ) -> Option<K::Point> {
        // A good star is left without computing the qualities. (In 3D
        // hardly any is: on the brain phantom at `--size 120` none of the
        // 2.25 million stars judged had all its tets at 0.8, and the test
        // cost a quality or two each. The star's cells are the complex's,
        // positively oriented. The moved ones are judged by the formula
        // before the orientation test below; a move must pass both, so an
        // inverted cell's formula value decides nothing.)
        if star
            .iter()
            .all(|(pts, _)| K::quality_oriented_at_least(&pts[..K::NV], GOOD_ENOUGH))
        {
            return None;
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
        let fraction = least_move_fraction::<K>();
        let mut sum = K::Point::zero();
        let mut spoke_sum = 0.0;
        let mut n = 0usize;
        for (pts, i) in star {
            for (j, w) in pts[..K::NV].iter().enumerate() {
                if Some(j) != *i {
                    sum += *w;
                    if fraction > 0.0 {
                        spoke_sum += (*w - p).length();
                    }
                    n += 1;
                }
            }
        }
        if n == 0 {
            return None;
        }
        let target = self.constrain(v, sum * (1.0 / n as f64));
        let least = fraction * spoke_sum / n as f64;
        if (target - p).length() <= least.max(1e-12) {
            return None;
        }
        // (the star's quality now, measured only for a move worth testing)
        // Every cell must keep the quality of the worst: the worst cell
        // itself, with no slack, fails most often, so it is judged first
        // (the verdict is the same in any order).
        let (before, worst) = worst_now();
        let keeps = |pts: [K::Point; 4]| K::quality_oriented_at_least(&pts[..K::NV], before);
        if !at(target).nth(worst).is_none_or(keeps)
            || !at(target)
                .enumerate()
                .all(|(k, pts)| k == worst || keeps(pts))
        {
            return None;
        }
        // The exact orientation test last: most moves fail the quality test,
        // and the formula's clamp to 0 already fails most inversions; the
        // test decides those the formula's rounding cannot.
        if !at(target).all(|pts| K::orient(&pts[..K::NV]) > 0.0) {
            return None;
        }
        Some(target)
    }
}
