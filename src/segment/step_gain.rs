//! Per-vertex step gains: a vertex that keeps moving the same way goes
//! faster.
//!
//! The force stage scales every vertex by one step, set so that the largest
//! force moves its vertex `step·L`. Near equilibrium the force on most
//! interface vertices is a small remainder (the region force against the
//! bending term at a corner or the tip of a thin bar), so they approach
//! their resting place by a fixed fraction of the remainder per iteration:
//! on the two-phase phantoms the last 15–20 iterations of a run were one or
//! two such corners creeping by 0.05–0.1 px per iteration. Here each vertex
//! keeps a gain (as in resilient back-propagation, Riedmiller & Braun 1993):
//! while its displacement points the same way as in the previous iteration
//! the gain grows by [`GROWTH`] up to a ceiling; when it turns back the
//! vertex has overshot and the gain falls back to 1. A vertex in the noise's
//! jitter about a settled interface turns back often and keeps gain 1, the
//! global step; no vertex moves further than the global step allows the
//! vertex of the largest force (`step·L`).

use crate::complex::Complex;
use crate::dim::{Dim, Point};

/// Factor by which a vertex's gain grows after an iteration whose
/// displacement points the same way as the previous one's.
pub const GROWTH: f64 = 1.5;

/// Each vertex's gain and the displacement it was last asked for, indexed by
/// vertex id and carried through the complex's renumberings.
///
/// Only the vertices that moved hold a gain other than 1 or a displacement
/// (a tenth of a 2D mesh's vertices, along the interface), so the record
/// keeps them in lists and touches the per-vertex arrays only there: an
/// evaluation and a renumbering cost one pass over the displacements and
/// the moving vertices, not passes over every vertex's entries.
#[derive(Debug)]
pub(crate) struct StepGains<P> {
    /// The gains and displacements of the last deformed state, per vertex
    /// id: 1 and zero but at the vertices in `held`.
    gain: Vec<f64>,
    previous: Vec<P>,
    /// The vertices whose entries above may differ from 1 and zero.
    held: Vec<u32>,
    /// The last force evaluation's moving vertices (id, gain, displacement
    /// asked for), which become the entries above once the complex has
    /// deformed by them; every other vertex had gain 1 and no displacement.
    next: Vec<(u32, f64, P)>,
    /// The complex's identity and compaction count when `next` was
    /// written (`None`: nothing written yet).
    written: Option<(u64, u64)>,
}

impl<P: Point> StepGains<P> {
    /// No history: every gain 1.
    pub fn new() -> Self {
        StepGains {
            gain: Vec::new(),
            previous: Vec::new(),
            held: Vec::new(),
            next: Vec::new(),
            written: None,
        }
    }

    /// Multiplies each vertex's displacement by its gain, at most
    /// `max_gain`, and shortens it to `cap` (pixels) where the gain made it
    /// longer than that.
    pub fn apply<K: Dim<Point = P>>(
        &mut self,
        complex: &Complex<K>,
        displacement: &mut [P],
        max_gain: f64,
        cap: f64,
    ) {
        self.follow(complex);
        let n = displacement.len();
        if self.gain.len() < n {
            self.gain.resize(n, 1.0);
            self.previous.resize(n, P::zero());
        }
        self.next.clear();
        for (i, d) in displacement.iter_mut().enumerate() {
            // (at rest: gain 1, nothing to remember)
            if *d == P::zero() {
                continue;
            }
            let asked = *d;
            let mut next = 1.0;
            // (turned back: gain 1, the displacement as it is)
            if d.dot(&self.previous[i]) > 0.0 {
                next = (self.gain[i] * GROWTH).min(max_gain);
                let length = d.length();
                let boosted = length * next;
                if boosted > length {
                    *d = *d * (boosted.min(cap.max(length)) / length);
                }
            }
            self.next.push((i as u32, next, asked));
        }
        self.written = Some((complex.identity(), complex.compactions()));
    }

    /// Brings the last evaluation's gains in when the complex was deformed
    /// by them (it has been compacted once since), renumbered as the
    /// compaction renumbered the vertices; forgets them when it was not (a
    /// second evaluation of the same state: the earlier one is replaced) and
    /// forgets everything for another complex or after more renumberings.
    fn follow<K: Dim<Point = P>>(&mut self, complex: &Complex<K>) {
        let Some((identity, compactions)) = self.written.take() else {
            return;
        };
        if identity != complex.identity() || complex.compactions() > compactions + 1 {
            self.forget_held();
            return;
        }
        if complex.compactions() == compactions {
            return;
        }
        self.forget_held();
        let map = complex.last_vertex_map();
        let n = complex.vertex_capacity();
        if self.gain.len() < n {
            self.gain.resize(n, 1.0);
            self.previous.resize(n, P::zero());
        }
        for &(old, gain, asked) in &self.next {
            if let Some(new) = map.get(old as usize).copied().flatten() {
                self.gain[new.index()] = gain;
                self.previous[new.index()] = asked;
                self.held.push(new.index() as u32);
            }
        }
    }

    /// Sets every held entry back to gain 1 and no displacement.
    fn forget_held(&mut self) {
        for &i in &self.held {
            self.gain[i as usize] = 1.0;
            self.previous[i as usize] = P::zero();
        }
        self.held.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::D2;
    use crate::dsc::{Destinations, DscParams};
    use crate::ops::CollapseMode;
    use nalgebra::Vector2;

    fn mesh() -> Complex<D2> {
        Complex::<D2>::rectangle(16.0, 16.0, 4.0).expect("mesh")
    }

    /// One evaluation of `d` at every vertex, as the force stage applies it.
    fn evaluate(
        gains: &mut StepGains<Vector2<f64>>,
        c: &Complex<D2>,
        d: Vector2<f64>,
    ) -> Vec<Vector2<f64>> {
        let mut displacement = vec![d; c.vertex_capacity()];
        gains.apply(c, &mut displacement, 3.0, 1.0);
        displacement
    }

    /// Deforms `c` by nothing: a compaction, as after every iteration.
    fn deform(c: &mut Complex<D2>) {
        let none = Destinations::new(c);
        c.deform(&none, &DscParams::new::<D2>(4.0));
    }

    #[test]
    fn gain_grows_while_the_direction_holds_and_resets_when_it_turns() {
        let mut c = mesh();
        let mut gains = StepGains::new();
        let d = Vector2::new(0.1, 0.0);
        let mut lengths = Vec::new();
        for _ in 0..5 {
            lengths.push(evaluate(&mut gains, &c, d)[0].x);
            deform(&mut c);
        }
        // 1, 1.5, 2.25, then the ceiling 3
        let expected = [0.1, 0.15, 0.225, 0.3, 0.3];
        for (got, want) in lengths.iter().zip(expected) {
            assert!((got - want).abs() < 1e-12, "{lengths:?}");
        }
        let back = evaluate(&mut gains, &c, -d)[0];
        assert_eq!(back, -d, "a vertex that turns back gets gain 1");
    }

    #[test]
    fn a_boosted_step_stops_at_the_cap_and_a_long_one_is_kept() {
        let mut c = mesh();
        let mut gains = StepGains::new();
        let d = Vector2::new(0.0, 0.6);
        for _ in 0..3 {
            evaluate(&mut gains, &c, d);
            deform(&mut c);
        }
        let capped = evaluate(&mut gains, &c, d)[0];
        assert!((capped.y - 1.0).abs() < 1e-12, "{capped:?}");
        let mut long = StepGains::new();
        let beyond = evaluate(&mut long, &c, Vector2::new(0.0, 1.5))[0];
        assert_eq!(beyond.y, 1.5, "the gain never shortens a step");
    }

    #[test]
    fn a_second_evaluation_of_one_state_replaces_the_first() {
        let mut c = mesh();
        let mut gains = StepGains::new();
        let d = Vector2::new(0.1, 0.0);
        evaluate(&mut gains, &c, d);
        deform(&mut c);
        // the same state evaluated twice: the gain grows once
        assert!((evaluate(&mut gains, &c, d)[0].x - 0.15).abs() < 1e-12);
        assert!((evaluate(&mut gains, &c, d)[0].x - 0.15).abs() < 1e-12);
        // another complex: no history
        let other = mesh();
        assert_eq!(evaluate(&mut gains, &other, d)[0], d);
    }

    #[test]
    fn gains_follow_the_renumbering_of_a_compaction() {
        let mut c = mesh();
        let mut gains = StepGains::new();
        let d = Vector2::new(0.1, 0.0);
        // even vertices turn back at the next evaluation (gain 1), odd ones
        // hold their direction (gain 1.5)
        let mut first: Vec<_> = (0..c.vertex_capacity())
            .map(|i| if i % 2 == 0 { -d } else { d })
            .collect();
        gains.apply(&c, &mut first, 3.0, 1.0);
        let expected: Vec<(Vector2<f64>, f64)> = c
            .vertex_ids()
            .map(|v| (c.position(v), if v.index() % 2 == 0 { 0.1 } else { 0.15 }))
            .collect();
        // remove an interior vertex of low id, so that the compaction
        // renumbers every vertex after it
        let (u, w) = c
            .vertex_ids()
            .filter(|&v| !c.class(v).on_boundary())
            .find_map(|v| {
                let nb = c.vertex_ids().find(|&w| {
                    w != v
                        && !c.class(w).on_boundary()
                        && (c.position(w) - c.position(v)).norm() < 4.5
                })?;
                Some((v, nb))
            })
            .expect("two interior neighbours");
        let kept = c
            .collapse_edge(u, w, CollapseMode::Safe, 0.0, -1.0)
            .expect("collapse");
        let gone = if kept == u { w } else { u };
        assert!(gone.index() + 1 < c.vertex_capacity());
        let moved = [c.position(kept)];
        c.compact_in_place();
        let out = evaluate(&mut gains, &c, d);
        let mut checked = 0;
        for v in c.vertex_ids() {
            let p = c.position(v);
            if moved.contains(&p) {
                continue;
            }
            let want = expected
                .iter()
                .find(|(q, _)| *q == p)
                .expect("same place")
                .1;
            assert!((out[v.index()].x - want).abs() < 1e-12, "vertex at {p:?}");
            checked += 1;
        }
        assert!(checked + 2 >= expected.len());
    }
}
