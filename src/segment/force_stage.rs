//! The force stage of an iteration: the paper's fields, every force term,
//! the step and the destinations of the deformation.

use super::driver::MAX_SUBSTEPS;
use super::forces::{ForceField, ForceSettings};
use super::image::ImageView;
use super::integrate::{CellStats, PhaseStats};
use super::model::{ForceContext, ForceTerm, TermKind};
use super::params::SegmentParams;
use super::raster::Raster;
use crate::complex::{Complex, VertexId};
use crate::dim::Point;
use crate::dsc::Destinations;

/// What the force stage reads.
pub(crate) struct ForceInputs<'r, 'a, K: Raster> {
    pub complex: &'r Complex<K>,
    pub image: &'r ImageView<'a>,
    pub phases: &'r PhaseStats,
    pub cells: &'r [CellStats],
    pub params: &'r SegmentParams,
    /// The image's dynamic range `(min, max)`.
    pub range: (f64, f64),
    /// L, in pixels.
    pub edge_length: f64,
    /// The current step fraction.
    pub step: f64,
    pub iteration: usize,
}

/// What the force stage writes, kept between iterations (no allocation per
/// iteration once the mesh stops growing).
#[derive(Debug)]
pub(crate) struct ForceStage<K: Raster> {
    /// The paper's per-vertex fields.
    pub field: ForceField<K>,
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
}

impl<K: Raster> ForceStage<K> {
    /// Empty buffers; destinations sized for `complex`.
    pub fn new(complex: &Complex<K>) -> Self {
        ForceStage {
            field: ForceField::new(),
            buffers: Vec::new(),
            external: Vec::new(),
            displacement: Vec::new(),
            applied: Vec::new(),
            term_kinds: Vec::new(),
            dest: Destinations::new(complex),
        }
    }

    /// Computes the fields and every term's forces and fills the
    /// destinations; returns the interface measure and the largest
    /// displacement (pixels).
    pub fn run(
        &mut self,
        terms: &mut [Box<dyn ForceTerm<K>>],
        input: &ForceInputs<'_, '_, K>,
    ) -> (f64, f64) {
        let l = input.edge_length;
        let settings = ForceSettings {
            model: input.params.force,
            junction: input.params.junction_force,
            spacing: input.params.sample_spacing,
            equal_means: 1e-6 * (input.range.1 - input.range.0),
        };
        self.field
            .compute(input.complex, input.image, input.phases, &settings);
        let length = self.field.interface_measure;
        // Every term adds into its own buffer; external terms are summed.
        let nv = input.complex.vertex_capacity();
        let ctx = ForceContext {
            complex: input.complex,
            image: input.image,
            phases: input.phases,
            cells: input.cells,
            params: input.params,
            field: &self.field,
            edge_length: l,
            range: input.range,
            iteration: input.iteration,
        };
        self.buffers.resize_with(terms.len(), Vec::new);
        self.external.clear();
        self.external.resize(nv, K::Point::zero());
        let mut reference: Option<f64> = None;
        let mut kinds = std::mem::take(&mut self.term_kinds);
        kinds.clear();
        for (term, buf) in terms.iter_mut().zip(&mut self.buffers) {
            buf.clear();
            buf.resize(nv, K::Point::zero());
            term.add_forces(&ctx, buf);
            let kind = term.kind(ctx.params);
            if kind == TermKind::External {
                let r = term.reference_magnitude(&ctx);
                reference = Some(reference.map_or(r, |x: f64| x.max(r)));
                for (e, f) in self.external.iter_mut().zip(buf.iter()) {
                    *e += *f;
                }
            }
            kinds.push(kind);
        }
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
        let scale = input.step * l / if denom > 0.0 { denom } else { 1.0 };
        self.displacement.clear();
        self.displacement
            .extend(self.external.iter().map(|&f| f * scale));
        self.add_smoothing(terms, &kinds, scale, l);
        self.term_kinds = kinds;
        (length, self.set_destinations(input.complex))
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
            if substeps == 1.0
                || !term.apply_to(&mut self.field, &self.displacement, &mut self.applied)
            {
                let k = k.min(max_step);
                for (d, f) in self.displacement.iter_mut().zip(buf) {
                    *d += *f * k;
                }
                continue;
            }
            let k = k / substeps;
            for sub in 0..substeps as usize {
                if sub > 0 {
                    term.apply_to(&mut self.field, &self.displacement, &mut self.applied);
                }
                for ((d, f), a) in self.displacement.iter_mut().zip(buf).zip(&self.applied) {
                    *d += (*f + *a) * k;
                }
            }
        }
    }

    /// Sets each moving vertex's destination (its displaced position, kept
    /// in the domain); returns the largest displacement.
    fn set_destinations(&mut self, complex: &Complex<K>) -> f64 {
        self.dest.clear();
        let mut max_disp: f64 = 0.0;
        for (i, &d) in self.displacement.iter().enumerate() {
            let v = VertexId(i as u32);
            if d == K::Point::zero() || !complex.is_vertex_alive(v) {
                continue;
            }
            let p = complex.position(v);
            let target = complex.constrain(v, p + d);
            let d = (target - p).length();
            if d > 0.0 {
                max_disp = max_disp.max(d);
                self.dest.set(v, target);
            }
        }
        max_disp
    }
}
