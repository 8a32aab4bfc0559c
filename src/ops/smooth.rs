//! Laplacian smoothing of vertices off the interface.

use crate::complex::{CellId, Complex, VertexId};
use crate::dim::{Dim, Point};

/// A star whose worst cell is at least this good is left alone: smoothing would
/// barely improve it, and skipping it keeps improvement cheap where the mesh is fine.
const GOOD_ENOUGH: f64 = 0.8;

/// The vertices smoothing left where they were, and when.
///
/// Whether a vertex moves depends only on its star: the cells (their ids and
/// corners) and the positions of their corners. A vertex left in place at
/// move clock `t` ([`Complex::move_clock`]) whose star still holds only
/// cells that existed then, none of whose corners has moved since, would be
/// left in place again, so it is not evaluated again. Deform smooths the
/// same band four times or more per call and most of it never moves: this
/// saves the quality tests there. Valid until the complex is compacted (the
/// ids change), so one memo serves one `deform` call.
#[derive(Clone, Debug, Default)]
pub struct SmoothMemo {
    /// Per vertex id: (move clock, cell capacity) when smoothing left it in
    /// place; `None` if it moved or was never looked at.
    kept: Vec<Option<(u64, u32)>>,
}

impl SmoothMemo {
    /// An empty memo.
    pub fn new() -> Self {
        Self::default()
    }

    fn get(&self, v: VertexId) -> Option<(u64, u32)> {
        self.kept.get(v.index()).copied().flatten()
    }

    fn set(&mut self, v: VertexId, entry: Option<(u64, u32)>) {
        if v.index() >= self.kept.len() {
            self.kept.resize(v.index() + 1, None);
        }
        self.kept[v.index()] = entry;
    }
}

impl<K: Dim> Complex<K> {
    /// Moves a non-interface vertex towards the mean of its neighbours (sliding
    /// along the domain boundary if it lies on it), unless its star is already
    /// good. Accepted only if no cell inverts and the worst quality of its star
    /// does not drop. Returns whether it moved. `memo` skips the vertices
    /// whose answer cannot have changed since it was last asked.
    pub fn smooth_vertex(
        &mut self,
        v: VertexId,
        star: &mut Vec<CellId>,
        memo: &mut SmoothMemo,
    ) -> bool {
        if !self.is_vertex_alive(v) || self.class(v).on_interface() {
            return false;
        }
        self.star_into(v, star);
        if let Some((clock, cells_below)) = memo.get(v) {
            if self.star_unchanged_since(star, clock, cells_below) {
                return false;
            }
        }
        let moved = self.smooth_star(v, star);
        let entry = (!moved).then(|| (self.move_clock(), self.cell_capacity() as u32));
        memo.set(v, entry);
        moved
    }

    /// Whether every cell of `star` has an id below `cells_below` and none
    /// of their corners moved after `clock`.
    fn star_unchanged_since(&self, star: &[CellId], clock: u64, cells_below: u32) -> bool {
        star.iter()
            .all(|&c| c.0 < cells_below && self.cell(c).iter().all(|&w| self.moved_at(w) <= clock))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::D2;
    use crate::dsc::{Connectivity, Destinations, DscParams};
    use nalgebra::Vector2;

    /// Smoothing with a memo kept across rounds of moves, flips and
    /// smoothing moves every vertex exactly as smoothing without one.
    #[test]
    fn memo_gives_the_answers_of_a_fresh_evaluation() {
        let l = 4.0;
        let mut mesh = Complex::<D2>::rectangle(60.0, 52.0, l).unwrap();
        mesh.label_by(|p| u32::from((p - Vector2::new(30.0, 26.0)).norm() < 14.0));
        let params = DscParams::new::<D2>(l);
        // An irregular start: a few deform steps (which compact).
        for step in 0..3 {
            let mut dest = Destinations::new(&mesh);
            for v in mesh.vertex_ids().collect::<Vec<_>>() {
                let p = mesh.position(v);
                let d = Vector2::new((p.y * 0.3 + step as f64).sin(), (p.x * 0.2).cos());
                dest.set(v, mesh.constrain(v, p + d * l * 0.4));
            }
            mesh.deform(&dest, &params);
        }
        let (mut fresh, mut memoised) = (mesh.clone(), mesh);
        let mut memo = SmoothMemo::new();
        let mut star = Vec::new();
        for round in 0..12 {
            for c in [&mut fresh, &mut memoised] {
                let ids: Vec<VertexId> = c.vertex_ids().collect();
                // Odd rounds only flip (the stars change, no vertex moves).
                for (k, &v) in ids.iter().enumerate() {
                    if round % 2 == 0 && (k + round) % 3 == 0 {
                        let p = c.position(v);
                        let d = Vector2::new((k as f64).sin(), (round as f64 + k as f64).cos());
                        c.move_towards(v, p + d * (0.6 * l), 1e-4 * l, &mut star);
                    }
                }
                if round % 2 == 1 {
                    D2::improve_connectivity(c, &params);
                }
            }
            let ids: Vec<VertexId> = fresh.vertex_ids().collect();
            let a = fresh.smooth_vertices(&ids, &mut SmoothMemo::new());
            let b = memoised.smooth_vertices(&ids, &mut memo);
            assert_eq!(a, b, "round {round}");
            for &v in &ids {
                assert_eq!(fresh.position(v), memoised.position(v), "round {round}");
            }
        }
    }
}
