//! The public extension points of the evolution: force terms, label rules and
//! the initialisation, all generic over the dimension.
//!
//! A [`Segmentation`](super::Segmentation) owns a [`Models`] value and, in
//! every iteration,
//!
//! 1. integrates the image over the cells ([`CellStats`], [`PhaseStats`]);
//! 2. runs every [`LabelRule`] in order (if
//!    [`SegmentParams::label_flips`] is on) and refreshes the phase means;
//! 3. asks every [`ForceTerm`] to add its per-vertex force into a slice
//!    indexed by [`VertexId::index`](crate::complex::VertexId::index), given a read-only [`ForceContext`];
//! 4. sums the terms, normalises the step (see [`TermKind`]) and deforms the
//!    complex with the DSC.
//!
//! The paper's own evolution is written against these traits: the region
//! force of eqs. (5)–(7) is [`RegionForce`], the
//! rigidity and elasticity terms of eq. (2) are
//! [`Rigidity`] and
//! [`Elasticity`], the label flips are
//! [`CellFlips`] and
//! [`ComponentFlips`], and the initialisation
//! from [`SegmentParams::init`] is [`ParamsInit`].
//! [`Models::paper`] bundles them; [`Segmentation::new`](super::Segmentation::new)
//! uses it.

use super::error::SegmentError;
use super::forces::ForceField;
use super::image::ImageView;
use super::integrate::{CellStats, PhaseStats};
use super::models::{CellFlips, ComponentFlips, Elasticity, ParamsInit, RegionForce, Rigidity};
use super::params::SegmentParams;
use super::raster::Raster;
use super::thresholds::Classes;
use crate::complex::{Complex, Label};
use crate::dim::Point;
use std::any::Any;

/// How the driver scales a force term before it moves the vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TermKind {
    /// An external force, dimensionless: the sum `F` of all external terms is
    /// scaled by `s = step · L / max(max_v |F(v)|, r)`, where `r` is the
    /// largest [`ForceTerm::reference_magnitude`] of the external terms, so
    /// that a vertex where `|F| = r` moves `step · L` (`step` is
    /// [`SegmentParams::step_fraction`], halved by the driver when the energy
    /// stalls). For eq. (6), `r = 1`: a pixel exactly at a phase mean.
    External,
    /// An internal smoothing direction in pixels (e.g. the umbrella `ΔX` or
    /// the bending `−Δ²X`) with a weight: it moves the vertices by
    /// `k · X` with `k = s · weight / L`, an explicit smoothing step. Above
    /// its stability limit `max_step`, `k` is split into equal sub-steps if
    /// the term is linear ([`ForceTerm::apply_to`]), else capped.
    Smoothing {
        /// The term's weight (β or α of eq. 2), relative to the external force.
        weight: f64,
        /// The largest stable coefficient (0.2 for bending, 0.5 for the umbrella).
        max_step: f64,
    },
}

/// What a force term may read: the state at the start of the force stage of
/// one iteration (after integration and label flips).
pub struct ForceContext<'c, 'a, K: Raster> {
    /// The complex (labels, positions, vertex classes).
    pub complex: &'c Complex<K>,
    /// The image.
    pub image: &'c ImageView<'a>,
    /// Per-phase pixel counts, sums and means.
    pub phases: &'c PhaseStats,
    /// Per-cell sums, indexed by cell id.
    pub cells: &'c [CellStats],
    /// The parameters (possibly changed mid-run by the caller).
    pub params: &'c SegmentParams,
    /// The paper's per-vertex fields of this iteration: the region force of
    /// eqs. (5)–(7), the bending and umbrella directions, the interface
    /// measure and the vertex kinds. Computed once per iteration by the driver
    /// (it also gives the energy's length term); terms may reuse it.
    pub field: &'c ForceField<K>,
    /// The average edge length L of the complex, in pixels.
    pub edge_length: f64,
    /// The image's dynamic range `(min, max)`.
    pub range: (f64, f64),
    /// The iteration being computed, from 1.
    pub iteration: usize,
}

impl<K: Raster> ForceContext<'_, '_, K> {
    /// Fills `out` (indexed by vertex id, resized to the vertex capacity) with
    /// the unit outward normal of `phase` at every vertex on its boundary: the
    /// measure-weighted average of the normals of the interface facets between
    /// `phase` and any other phase, pointing out of `phase`. Vertices not on
    /// the boundary of `phase` get zero. The domain border does not count as
    /// boundary.
    pub fn phase_normals(&self, phase: Label, out: &mut Vec<K::Point>) {
        phase_normals(self.complex, phase, out);
    }
}

impl<K: Raster> ForceContext<'_, '_, K> {
    /// A force integrated over the interface facets, the route of the paper's
    /// region force: every interface facet between phases `a` (one side) and
    /// `b` (the other) is sampled about every [`SegmentParams::sample_spacing`]
    /// pixels; the scalar `f(point, a, b)` of each sample, times the facet's
    /// unit normal `N_ab` (pointing from `a` into `b`), is spread over the
    /// facet's corners with the hat weights, and each vertex's total is divided
    /// by its hat-weighted share of the interface measure. The result, a
    /// force per unit length (area), is added into `out`. `scratch` is reused
    /// between calls, so a term that keeps it allocates nothing per iteration.
    ///
    /// For example `f = (2·I(p) − m_a − m_b)/(m_a − m_b)` is eq. (6) on
    /// two-phase interfaces, and `f = ±p` for `a` or `b` the inflated phase a
    /// balloon.
    pub fn add_facet_integrated(
        &self,
        mut f: impl FnMut(K::Point, Label, Label) -> f64,
        scratch: &mut Vec<(K::Point, f64)>,
        out: &mut [K::Point],
    ) {
        // per vertex: the integrated force and its hat-weighted share
        scratch.clear();
        scratch.resize(out.len(), (K::Point::zero(), 0.0));
        let n = K::N;
        for facet in self.complex.interface_facets() {
            let (a, b, normal, corners) = (facet.a, facet.b, facet.normal, facet.corners);
            K::facet_samples(
                &facet.points[..n],
                self.params.sample_spacing,
                &mut |p, w, ds| {
                    let v = f(p, a, b);
                    for k in 0..n {
                        let wk = w[k] * ds;
                        let acc = &mut scratch[corners[k].index()];
                        acc.0 += normal * (v * wk);
                        acc.1 += wk;
                    }
                },
            );
        }
        for (o, &(sum, share)) in out.iter_mut().zip(scratch.iter()) {
            if share > 0.0 {
                let add = sum * (1.0 / share);
                if add.is_finite() {
                    *o += add;
                }
            }
        }
    }
}

/// See [`ForceContext::phase_normals`].
pub fn phase_normals<K: Raster>(complex: &Complex<K>, phase: Label, out: &mut Vec<K::Point>) {
    out.clear();
    out.resize(complex.vertex_capacity(), K::Point::zero());
    for c in complex.cell_ids() {
        let a = complex.label(c);
        for (i, nb) in complex.neighbours(c).iter().enumerate() {
            let Some(nb) = *nb else { continue };
            let b = complex.label(nb);
            let sign = if a == phase && b != phase {
                1.0
            } else if b == phase && a != phase {
                -1.0
            } else {
                continue;
            };
            let pts = complex.cell_points(c);
            let n = K::facet_normal(&pts[..K::NV], i) * (sign * K::facet_measure(&pts[..K::NV], i));
            for (k, &v) in complex.cell(c).iter().enumerate() {
                if k != i {
                    out[v.index()] += n;
                }
            }
        }
    }
    for n in out.iter_mut() {
        let len = n.length();
        if len > 0.0 {
            *n = *n * (1.0 / len);
        }
    }
}

/// Blanket helper so that boxed models can be downcast to their concrete
/// type (see [`Models::force_mut`]). Implemented for every `'static` type.
pub trait AsAny: Any {
    /// `self` as [`Any`].
    fn as_any(&self) -> &dyn Any;
    /// `self` as mutable [`Any`].
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

impl<T: Any> AsAny for T {
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// A per-vertex force: the external or internal forces of eq. (1).
///
/// Implement [`ForceTerm::add_forces`]; the driver zeroes one buffer per term,
/// calls it, and combines the terms as [`ForceTerm::kind`] says. A term may
/// keep scratch space or state in `self` (it is `&mut`), and may be reached
/// mid-run through [`Segmentation::force_mut`](super::Segmentation::force_mut).
///
/// ```
/// use dsc_seg::segment::{ForceContext, ForceTerm, Raster};
///
/// /// Pushes every vertex on the boundary of phase 1 outwards with magnitude `p`.
/// struct Inflate(f64);
///
/// impl<K: Raster> ForceTerm<K> for Inflate {
///     fn name(&self) -> &str { "inflate" }
///     fn add_forces(&mut self, ctx: &ForceContext<'_, '_, K>, out: &mut [K::Point]) {
///         let mut normals = Vec::new();
///         ctx.phase_normals(1, &mut normals);
///         for (f, n) in out.iter_mut().zip(&normals) {
///             *f += *n * self.0;
///         }
///     }
/// }
/// ```
pub trait ForceTerm<K: Raster>: AsAny + Send {
    /// A short name for reports and debugging.
    fn name(&self) -> &str;

    /// How the driver scales this term; [`TermKind::External`] by default.
    fn kind(&self, _params: &SegmentParams) -> TermKind {
        TermKind::External
    }

    /// The force magnitude that moves a vertex a full step (see
    /// [`TermKind::External`]); 1 by default, i.e. the scale of the
    /// normalised region force of eq. (6). Ignored for smoothing terms.
    fn reference_magnitude(&self, _ctx: &ForceContext<'_, '_, K>) -> f64 {
        1.0
    }

    /// Adds this term's force at every vertex into `out`, indexed by
    /// [`VertexId::index`](crate::complex::VertexId::index) (`out.len()` is the vertex capacity; dead vertices
    /// are ignored by the driver). Vertices on the domain border are later
    /// constrained to slide along it.
    ///
    /// Called once per iteration, or twice when the label rules, checked
    /// beside this computation, turn out to change labels (the forces are
    /// then computed again on the new labels; see
    /// [`LabelRule::would_relabel`]), and so are [`kind`](Self::kind),
    /// [`reference_magnitude`](Self::reference_magnitude) and
    /// [`apply_to`](Self::apply_to): the forces should be a function of `ctx`.
    fn add_forces(&mut self, ctx: &ForceContext<'_, '_, K>, out: &mut [K::Point]);

    /// For a [`TermKind::Smoothing`] term whose direction is linear in the
    /// positions (the umbrella `ΔX`, the bending `−Δ²X`): writes the term's
    /// operator applied to the displacement field `input` into `out` and
    /// returns true. The driver then splits a coefficient above `max_step`
    /// into stable sub-steps instead of capping it, so the weight keeps its
    /// meaning at every step size. `field` is the driver's force field,
    /// lent mutably for its scratch space. The default (false) caps the
    /// coefficient.
    fn apply_to(
        &mut self,
        _field: &mut ForceField<K>,
        _input: &[K::Point],
        _out: &mut Vec<K::Point>,
    ) -> bool {
        false
    }
}

/// What a label rule may read and change.
pub struct LabelContext<'c, 'a, K: Raster> {
    /// The complex, whose cell labels the rule may change
    /// ([`Complex::set_label`], [`Complex::set_labels`]).
    pub complex: &'c mut Complex<K>,
    /// The image.
    pub image: &'c ImageView<'a>,
    /// Per-cell sums, indexed by cell id (from the start of the iteration).
    pub cells: &'c [CellStats],
    /// Phase statistics (refreshed by the driver after the rules if any flipped).
    pub phases: &'c PhaseStats,
    /// The parameters.
    pub params: &'c SegmentParams,
    /// The length weight ν of the Mumford–Shah energy (intensity² per pixel of length).
    pub length_weight: f64,
    /// The iteration being computed, from 1.
    pub iteration: usize,
}

/// What a label rule reads to predict whether it would change a label
/// ([`LabelRule::would_relabel`]): a [`LabelContext`] that cannot change any.
pub struct LabelView<'c, 'a, K: Raster> {
    /// The complex.
    pub complex: &'c Complex<K>,
    /// The image.
    pub image: &'c ImageView<'a>,
    /// Per-cell sums, indexed by cell id.
    pub cells: &'c [CellStats],
    /// Phase statistics.
    pub phases: &'c PhaseStats,
    /// The parameters.
    pub params: &'c SegmentParams,
    /// The length weight ν of the Mumford–Shah energy.
    pub length_weight: f64,
    /// The iteration being computed, from 1.
    pub iteration: usize,
}

/// A rule that changes cell labels (the paper's label flips, section III.C).
pub trait LabelRule<K: Raster>: AsAny + Send {
    /// A short name for reports and debugging.
    fn name(&self) -> &str;
    /// Changes labels; returns how many cells changed.
    fn relabel(&mut self, ctx: &mut LabelContext<'_, '_, K>) -> usize;
    /// Whether [`relabel`](Self::relabel) would change a label now, decided
    /// without changing any; `None` (the default) if the rule cannot tell.
    /// A rule that answers must have a `relabel` without any other effect
    /// when it changes no label: the driver then skips it.
    ///
    /// Most iterations flip nothing. When every rule can tell, the driver
    /// asks them on its second thread while it computes the forces, and runs
    /// the rules (and the forces again) only if one of them would change a
    /// label: the same result, the rules' time hidden behind the forces'.
    fn would_relabel(&mut self, view: &LabelView<'_, '_, K>) -> Option<bool> {
        let _ = view;
        None
    }
}

/// What an initialisation may read and change.
pub struct InitContext<'c, 'a, K: Raster> {
    /// The freshly built complex, every cell labelled 0.
    pub complex: &'c mut Complex<K>,
    /// The image.
    pub image: &'c ImageView<'a>,
    /// Per-cell sums of the initial mesh, indexed by cell id.
    pub cells: &'c [CellStats],
    /// The (validated) parameters.
    pub params: &'c SegmentParams,
    /// The image's dynamic range `(min, max)`.
    pub range: (f64, f64),
    /// The histogram split into `params.phases` classes (for
    /// [`Init::Histogram`](super::params::Init::Histogram); `None` otherwise).
    pub classes: Option<&'c Classes>,
}

/// Labels the cells before the evolution starts.
pub trait Initialiser<K: Raster>: Send {
    /// Labels the cells of `ctx.complex` with values `< params.phases` and
    /// returns a starting mean per phase where one is known before
    /// integration (`None` otherwise; the driver then uses the pixels' means).
    fn initialise(
        &mut self,
        ctx: &mut InitContext<'_, '_, K>,
    ) -> Result<Vec<Option<f64>>, SegmentError>;
}

/// Any closure `FnMut(&mut InitContext) -> Result<…>` is an initialiser.
impl<K: Raster, F> Initialiser<K> for F
where
    F: FnMut(&mut InitContext<'_, '_, K>) -> Result<Vec<Option<f64>>, SegmentError> + Send,
{
    fn initialise(
        &mut self,
        ctx: &mut InitContext<'_, '_, K>,
    ) -> Result<Vec<Option<f64>>, SegmentError> {
        self(ctx)
    }
}

/// The evolution a [`Segmentation`](super::Segmentation) runs: force terms,
/// label rules and the initialisation.
pub struct Models<K: Raster> {
    /// Force terms, summed in this order.
    pub forces: Vec<Box<dyn ForceTerm<K>>>,
    /// Label rules, applied in this order.
    pub rules: Vec<Box<dyn LabelRule<K>>>,
    /// The initialisation.
    pub init: Box<dyn Initialiser<K>>,
}

impl<K: Raster> Models<K> {
    /// The paper's evolution: [`RegionForce`], [`Rigidity`], [`Elasticity`]
    /// (weights from the parameters), [`CellFlips`] then [`ComponentFlips`],
    /// initialised by [`ParamsInit`] (i.e. [`SegmentParams::init`]).
    pub fn paper() -> Self {
        Models {
            forces: vec![
                Box::new(RegionForce),
                Box::new(Rigidity),
                Box::new(Elasticity),
            ],
            rules: vec![
                Box::new(CellFlips::default()),
                Box::new(ComponentFlips::default()),
            ],
            init: Box::new(ParamsInit),
        }
    }

    /// No force and no label rule, initialised by [`ParamsInit`]: start from
    /// here to build an evolution from scratch.
    pub fn empty() -> Self {
        Models {
            forces: Vec::new(),
            rules: Vec::new(),
            init: Box::new(ParamsInit),
        }
    }

    /// Adds a force term (builder style).
    pub fn with_force(mut self, force: impl ForceTerm<K> + 'static) -> Self {
        self.forces.push(Box::new(force));
        self
    }

    /// Adds a label rule (builder style).
    pub fn with_rule(mut self, rule: impl LabelRule<K> + 'static) -> Self {
        self.rules.push(Box::new(rule));
        self
    }

    /// Replaces the initialisation (builder style).
    pub fn with_init(mut self, init: impl Initialiser<K> + 'static) -> Self {
        self.init = Box::new(init);
        self
    }

    /// The first force term of type `T`, for changing it mid-run.
    pub fn force_mut<T: 'static>(&mut self) -> Option<&mut T> {
        self.forces
            .iter_mut()
            .find_map(|f| f.as_mut().as_any_mut().downcast_mut::<T>())
    }

    /// The first label rule of type `T`.
    pub fn rule_mut<T: 'static>(&mut self) -> Option<&mut T> {
        self.rules
            .iter_mut()
            .find_map(|r| r.as_mut().as_any_mut().downcast_mut::<T>())
    }
}

impl<K: Raster> Default for Models<K> {
    fn default() -> Self {
        Self::paper()
    }
}

/// What an observer of [`Segmentation::run_until`](super::Segmentation::run_until)
/// wants next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    /// Run another iteration (unless the iteration cap is reached).
    Continue,
    /// Stop now.
    Stop,
}
