//! The force stage of an iteration: every force term, the step and the
//! destinations of the deformation.

use super::model::{ForceTerm, IterationState, TermKind};
use super::normal_motion::across_interface;
use super::raster::Raster;
use super::step_gain::StepGains;
use crate::complex::{CellId, Complex, VertexId};
use crate::dim::Point;
use crate::dsc::Destinations;

/// Most sub-steps a smoothing term takes in one iteration (the default β
/// needs at most 5).
pub const MAX_SUBSTEPS: f64 = 64.0;

/// What the force stage writes, kept between iterations (no allocation per
/// iteration once the mesh stops growing).
#[derive(Debug)]
pub(crate) struct ForceStage<K: Raster> {
    /// One force buffer per force term, indexed by vertex id.
    buffers: Vec<Vec<K::Point>>,
    /// Sum of the external terms.
    external: Vec<K::Point>,
    /// Per-vertex displacement of the iteration, and a smoothing operator's output.
    displacement: Vec<K::Point>,
    applied: Vec<K::Point>,
    /// Each force term's kind in this iteration.
    term_kinds: Vec<TermKind>,
    /// Where the deformation moves the vertices.
    pub dest: Destinations<K>,
    /// Scratch space of [`across_interface`].
    star: Vec<CellId>,
    /// Per-vertex gains of the step.
    gains: StepGains<K::Point>,
    /// Scratch: the vertices a smoothing term acts on ([`ForceTerm::support_into`]).
    support: Vec<u32>,
}

/// The largest displacement of a force evaluation's destinations, in pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Reach {
    /// Of any vertex.
    pub largest: f64,
    /// Across the interface ([`across_interface`]): the motion that can move
    /// a pixel to the other side.
    pub across: f64,
}

impl<K: Raster> ForceStage<K> {
    /// Empty buffers; destinations sized for `complex`.
    pub fn new(complex: &Complex<K>) -> Self {
        ForceStage {
            buffers: Vec::new(),
            external: Vec::new(),
            displacement: Vec::new(),
            applied: Vec::new(),
            term_kinds: Vec::new(),
            dest: Destinations::new(complex),
            star: Vec::new(),
            gains: StepGains::new(),
            support: Vec::new(),
        }
    }

    /// Computes every term's forces on `complex` and fills the destinations
    /// with a step of `step`·L, each vertex's multiplied by its gain
    /// ([`StepGains`], up to [`SegmentParams::step_gain`](super::params::SegmentParams::step_gain));
    /// returns the largest displacements.
    pub fn run(
        &mut self,
        terms: &mut [Box<dyn ForceTerm<K>>],
        complex: &Complex<K>,
        state: &IterationState<'_, '_>,
        step: f64,
    ) -> Reach {
        let l = state.edge_length;
        let reference = self.add_terms(terms, complex, state);
        // Step: the largest external displacement is `step`·L once a force
        // reaches the reference magnitude (1 for eq. 6: a pixel exactly at a
        // mean); weaker fields move proportionally less, so the evolution can
        // settle. The internal terms are explicit smoothing steps of
        // coefficient k = dt·β/L; for the bending term the highest-frequency
        // mode changes by a factor 1 − 4k per step, so k ≤ 0.2 is stable (and
        // k ≤ 0.5 for the umbrella of the elasticity). A larger k is split
        // into ⌈k/0.2⌉ sub-steps (the terms are linear in the positions), so
        // β weighs the same against the region force at every step size.
        let fmax = self.external.iter().map(|f| f.length()).fold(0.0, f64::max);
        let denom = fmax.max(reference.unwrap_or(1.0));
        let scale = step * l / if denom > 0.0 { denom } else { 1.0 };
        self.displacement.clear();
        self.displacement
            .extend(self.external.iter().map(|&f| f * scale));
        let kinds = std::mem::take(&mut self.term_kinds);
        self.add_smoothing(terms, &kinds, scale, l);
        self.term_kinds = kinds;
        // (no vertex further than the largest force's `step`·L)
        let max_gain = state.params.step_gain;
        if max_gain > 1.0 {
            self.gains
                .apply(complex, &mut self.displacement, max_gain, step * l);
        }
        self.set_destinations(complex, state.params.min_move * l)
    }

    /// Every term adds into its own buffer, and the external ones are summed;
    /// returns the largest reference magnitude of the external terms.
    fn add_terms(
        &mut self,
        terms: &mut [Box<dyn ForceTerm<K>>],
        complex: &Complex<K>,
        state: &IterationState<'_, '_>,
    ) -> Option<f64> {
        let nv = complex.vertex_capacity();
        self.buffers.resize_with(terms.len(), Vec::new);
        self.external.clear();
        self.external.resize(nv, K::Point::zero());
        self.term_kinds.clear();
        let mut reference: Option<f64> = None;
        for (term, buf) in terms.iter_mut().zip(&mut self.buffers) {
            buf.clear();
            buf.resize(nv, K::Point::zero());
            term.add_forces(complex, state, buf);
            let kind = term.kind();
            if kind == TermKind::External {
                let r = term.reference_magnitude(state);
                reference = Some(reference.map_or(r, |x: f64| x.max(r)));
                for (e, f) in self.external.iter_mut().zip(buf.iter()) {
                    *e += *f;
                }
            }
            self.term_kinds.push(kind);
        }
        reference
    }

    /// Adds the smoothing terms to the displacement: term `b` with
    /// coefficient `k = scale · weight / l` (the external scale, L), as ⌈k/max_step⌉ stable
    /// sub-steps of its operator when it is linear ([`ForceTerm::apply_to`]),
    /// else capped at `max_step`. At most [`MAX_SUBSTEPS`] sub-steps: a
    /// larger coefficient is capped there, so an absurd β cannot stall a run.
    fn add_smoothing(
        &mut self,
        terms: &mut [Box<dyn ForceTerm<K>>],
        kinds: &[TermKind],
        scale: f64,
        l: f64,
    ) {
        for (b, term) in terms.iter_mut().enumerate() {
            let TermKind::Smoothing { weight, max_step } = kinds[b] else {
                continue;
            };
            let k = (scale * weight / l).min(max_step * MAX_SUBSTEPS);
            let substeps = (k / max_step).ceil().max(1.0);
            let buf = &self.buffers[b];
            if substeps == 1.0 || !term.apply_to(&self.displacement, &mut self.applied) {
                let k = k.min(max_step);
                for (d, f) in self.displacement.iter_mut().zip(buf) {
                    *d += *f * k;
                }
                continue;
            }
            let k = k / substeps;
            let support = term.support_into(&mut self.support);
            for sub in 0..substeps as usize {
                if sub > 0 {
                    term.apply_to(&self.displacement, &mut self.applied);
                }
                if support {
                    add_sub_step(&mut self.displacement, buf, &self.applied, k, &self.support);
                } else {
                    for ((d, f), a) in self.displacement.iter_mut().zip(buf).zip(&self.applied) {
                        *d += (*f + *a) * k;
                    }
                }
            }
            if support {
                // (what a sub-step adds elsewhere, `+0`: a `−0` becomes `+0`)
                for d in &mut self.displacement {
                    *d += K::Point::zero();
                }
            }
        }
    }

    /// Sets each moving vertex's destination (its displaced position, kept
    /// in the domain) where it lies at least `min_move` away; returns the
    /// largest displacements, of every vertex (the stopping rule's motion).
    fn set_destinations(&mut self, complex: &Complex<K>, min_move: f64) -> Reach {
        self.dest.clear();
        let mut reach = Reach::default();
        for (i, &d) in self.displacement.iter().enumerate() {
            let v = VertexId(i as u32);
            if d == K::Point::zero() || !complex.is_vertex_alive(v) {
                continue;
            }
            let p = complex.position(v);
            let target = complex.constrain(v, p + d);
            let d = target - p;
            let length = d.length();
            reach.largest = reach.largest.max(length);
            // (the motion across is at most the length: only a longer step
            // can raise the largest)
            if length > reach.across {
                let across = across_interface(complex, v, d, &mut self.star);
                reach.across = reach.across.max(across);
            }
            if length > 0.0 && length >= min_move {
                self.dest.set(v, target);
            }
        }
        reach
    }
}

/// One sub-step of a smoothing term, `d += (f + a)·k`, at the vertices
/// `support` only (where `f`, the term's forces, and `a`, its operator's
/// output, can be nonzero; the caller adds the `+0` of the others).
fn add_sub_step<P: Point>(d: &mut [P], f: &[P], a: &[P], k: f64, support: &[u32]) {
    for &i in support {
        let i = i as usize;
        d[i] += (f[i] + a[i]) * k;
    }
}
