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
//!    indexed by [`VertexId::index`](crate::complex::VertexId::index);
//! 4. sums the terms, normalises the step (see [`TermKind`]) and deforms the
//!    complex with the DSC.
//!
//! Every hook sees the complex (mutable where it may change labels) and one
//! [`IterationState`]: the image, its statistics and the parameters, borrowed
//! for the call. A term owns its own parameters and scratch space.
//!
//! The paper's own evolution is written against these traits, in
//! [`models::paper`](super::models::paper): the region force of eqs. (5)–(7)
//! is [`RegionForce`](super::models::RegionForce), the rigidity and elasticity terms of eq. (2) are
//! [`Rigidity`](super::models::Rigidity) and [`Elasticity`](super::models::Elasticity) (the three share one lazily computed field
//! per iteration), the label flips are [`CellFlips`] and [`ComponentFlips`],
//! and the initialisation from [`SegmentParams::init`] is [`ParamsInit`].
//! [`Models::paper`] bundles them; [`Segmentation::new`](super::Segmentation::new)
//! uses it. [`Models::empty`] has none of them, and computes none of their
//! fields.

use super::error::SegmentError;
use super::image::ImageView;
use super::integrate::{CellStats, PhaseStats};
use super::intensity::IntensityStats;
use super::models::paper::{PaperField, PaperTerms};
use super::models::{BandFlips, CellFlips, ComponentFlips, ParamsInit};
use super::params::SegmentParams;
use super::raster::Raster;
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

/// What every hook of the evolution reads besides the complex: the state
/// of the segmentation at the call (after integration; for the force terms,
/// after the label flips too), borrowed for the call.
#[derive(Clone, Copy)]
pub struct IterationState<'s, 'a> {
    /// The image.
    pub image: &'s ImageView<'a>,
    /// The image's intensity figures (range, robust range, noise, histogram).
    pub intensity: &'s IntensityStats,
    /// Per-phase pixel counts, sums and means (no means yet for an
    /// initialiser).
    pub phases: &'s PhaseStats,
    /// Per-cell sums, indexed by cell id.
    pub cells: &'s [CellStats],
    /// The parameters (possibly changed mid-run by the caller).
    pub params: &'s SegmentParams,
    /// The image's dynamic range `(min, max)`.
    pub range: (f64, f64),
    /// The average edge length L of the complex, in pixels.
    pub edge_length: f64,
    /// The length weight ν of the Mumford–Shah energy (intensity² per pixel
    /// of length; 0 before the first iteration).
    pub length_weight: f64,
    /// The iteration being computed, from 1 (0: the initialisation).
    pub iteration: usize,
    /// A number that differs between any two force evaluations of a run (a
    /// term caching work per state keys it on this).
    pub evaluation: u64,
}

impl IterationState<'_, '_> {
    /// A force integrated over the interface facets of `complex`, the route
    /// of the paper's region force: every interface facet between phases `a`
    /// (one side) and `b` (the other) is sampled about every
    /// [`SegmentParams::sample_spacing`] pixels/voxels; the scalar `f(point, a, b)`
    /// of each sample, times the facet's unit normal `N_ab` (pointing from
    /// `a` into `b`), is spread over the facet's corners with the hat
    /// weights, and each vertex's total is divided by its hat-weighted share
    /// of the interface measure. The result, a force per unit length (area),
    /// is added into `out`. `scratch` is reused between calls, so a term that
    /// keeps it allocates nothing per iteration.
    ///
    /// For example `f = (2·I(p) − m_a − m_b)/(m_a − m_b)` is eq. (6) on
    /// two-phase interfaces, and `f = ±p` for `a` or `b` the inflated phase a
    /// balloon.
    pub fn add_facet_integrated<K: Raster>(
        &self,
        complex: &Complex<K>,
        mut f: impl FnMut(K::Point, Label, Label) -> f64,
        scratch: &mut Vec<(K::Point, f64)>,
        out: &mut [K::Point],
    ) {
        // per vertex: the integrated force and its hat-weighted share
        scratch.clear();
        scratch.resize(out.len(), (K::Point::zero(), 0.0));
        let n = K::N;
        let spacing = self.params.sample_spacing * self.image.sample_step();
        for facet in complex.interface_facets() {
            let (a, b, normal, corners) = (facet.a, facet.b, facet.normal, facet.corners);
            K::facet_samples(&facet.points[..n], spacing, &mut |p, w, ds| {
                let v = f(p, a, b);
                for k in 0..n {
                    let wk = w[k] * ds;
                    let acc = &mut scratch[corners[k].index()];
                    acc.0 += normal * (v * wk);
                    acc.1 += wk;
                }
            });
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

/// Fills `out` (indexed by vertex id, resized to the vertex capacity) with
/// the unit outward normal of `phase` at every vertex on its boundary: the
/// measure-weighted average of the normals of the interface facets between
/// `phase` and any other phase, pointing out of `phase`. Vertices not on the
/// boundary of `phase` get zero. The domain border does not count as
/// boundary.
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
/// calls it, and combines the terms as [`ForceTerm::kind`] says. A term owns
/// its parameters and may keep scratch space or state in `self` (it is
/// `&mut`); it may be reached mid-run through
/// [`Segmentation::force_mut`](super::Segmentation::force_mut).
///
/// A user's force, pulling every interface vertex towards a point:
///
/// ```
/// use dsc_seg::complex::Complex;
/// use dsc_seg::dim::D2;
/// use dsc_seg::segment::{ForceTerm, ImageView, IterationState, Models2, SegmentParams};
/// use dsc_seg::segment::Segmentation2;
/// use nalgebra::Vector2;
///
/// /// Pulls interface vertices towards `centre` with unit strength.
/// struct Pull {
///     centre: Vector2<f64>,
/// }
///
/// impl ForceTerm<D2> for Pull {
///     fn name(&self) -> &str {
///         "pull"
///     }
///     fn add_forces(&mut self, complex: &Complex<D2>, _: &IterationState, out: &mut [Vector2<f64>]) {
///         for v in complex.vertex_ids().filter(|&v| complex.class(v).on_interface()) {
///             out[v.index()] += (self.centre - complex.position(v)).normalize();
///         }
///     }
/// }
///
/// let pixels: Vec<f32> = (0..32 * 32).map(|i| if i % 32 < 16 { 0.2 } else { 0.8 }).collect();
/// let image = ImageView::new_2d(32, 32, &pixels).unwrap();
/// let models = Models2::empty().with_force(Pull { centre: Vector2::new(16.0, 16.0) });
/// let mut seg = Segmentation2::with_models(image, SegmentParams::new(2), models)?;
/// assert!(seg.step().max_displacement > 0.0);
/// # Ok::<(), dsc_seg::segment::SegmentError>(())
/// ```
pub trait ForceTerm<K: Raster>: AsAny + Send {
    /// A short name for reports and debugging.
    fn name(&self) -> &str;

    /// How the driver scales this term; [`TermKind::External`] by default.
    fn kind(&self) -> TermKind {
        TermKind::External
    }

    /// The force magnitude that moves a vertex a full step (see
    /// [`TermKind::External`]); 1 by default, i.e. the scale of the
    /// normalised region force of eq. (6). Ignored for smoothing terms.
    fn reference_magnitude(&self, _state: &IterationState<'_, '_>) -> f64 {
        1.0
    }

    /// Adds this term's force at every vertex into `out`, indexed by
    /// [`VertexId::index`](crate::complex::VertexId::index) (`out.len()` is
    /// the vertex capacity; dead vertices are ignored by the driver).
    /// Vertices on the domain border are later constrained to slide along it.
    ///
    /// Called once per iteration, or twice when the label rules, checked
    /// beside this computation, turn out to change labels (the forces are
    /// then computed again on the new labels; see
    /// [`LabelRule::would_relabel`]), and so are [`kind`](Self::kind),
    /// [`reference_magnitude`](Self::reference_magnitude) and
    /// [`apply_to`](Self::apply_to): the forces should be a function of the
    /// complex and the state.
    fn add_forces(
        &mut self,
        complex: &Complex<K>,
        state: &IterationState<'_, '_>,
        out: &mut [K::Point],
    );

    /// For a [`TermKind::Smoothing`] term whose direction is linear in the
    /// positions (the umbrella `ΔX`, the bending `−Δ²X`): writes the term's
    /// operator, as of the last [`add_forces`](Self::add_forces), applied to
    /// the displacement field `input` into `out` and returns true. The driver
    /// then splits a coefficient above `max_step` into stable sub-steps
    /// instead of capping it, so the weight keeps its meaning at every step
    /// size. The default (false) caps the coefficient.
    fn apply_to(&mut self, _input: &[K::Point], _out: &mut Vec<K::Point>) -> bool {
        false
    }

    /// The vertices where this term's forces (as of the last
    /// [`add_forces`](Self::add_forces)) and the output of
    /// [`apply_to`](Self::apply_to) can be nonzero, listed into `out`
    /// (cleared first); elsewhere both are exactly `+0`. Returns false
    /// (the default) where the term does not say: any vertex. The driver
    /// then adds a smoothing term's sub-steps at those vertices only.
    fn support_into(&mut self, _out: &mut Vec<u32>) -> bool {
        false
    }
}

/// A rule that changes cell labels (the paper's label flips, section III.C).
pub trait LabelRule<K: Raster>: AsAny + Send {
    /// A short name for reports and debugging.
    fn name(&self) -> &str;
    /// Changes labels of `complex` ([`Complex::set_label`],
    /// [`Complex::set_labels`]); returns how many cells changed. The state's
    /// cell sums are from the start of the iteration; its phase statistics
    /// are refreshed by the driver after the rules if any changed.
    fn relabel(&mut self, complex: &mut Complex<K>, state: &IterationState<'_, '_>) -> usize;
    /// Whether [`relabel`](Self::relabel) would change a label now, decided
    /// without changing any; `None` (the default) if the rule cannot tell.
    /// A rule that answers must have a `relabel` without any other effect
    /// when it changes no label: the driver then skips it.
    ///
    /// Most iterations flip nothing. When every rule can tell, the driver
    /// asks them in order until one says yes, on its second thread while it
    /// computes the forces (the rules' time hidden behind the forces'), or
    /// before the forces on one thread; it runs the rules (and then the
    /// forces) only if one of them would change a label: the same result.
    fn would_relabel(
        &mut self,
        complex: &Complex<K>,
        state: &IterationState<'_, '_>,
    ) -> Option<bool> {
        let _ = (complex, state);
        None
    }
}

/// Builds or labels the first mesh before the evolution starts: the only
/// way a segmentation is initialised.
pub trait Initialiser<K: Raster>: Send {
    /// A mesh to start from instead of the box mesh at L (e.g. one conforming
    /// to a surface), whose labels are the initialisation; asked once, before
    /// the image is integrated. `None` (the default): the box mesh.
    fn start_mesh(&mut self) -> Option<Complex<K>> {
        None
    }

    /// Labels the cells of `complex` (freshly built, every cell labelled 0,
    /// unless [`start_mesh`](Self::start_mesh) gave it) with values
    /// `< state.params.phases` and returns a starting mean per phase where
    /// one is known before integration (`None` otherwise; the driver then
    /// uses the pixels' means). The state's cell sums are of this mesh; it
    /// has no phase means yet.
    fn initialise(
        &mut self,
        complex: &mut Complex<K>,
        state: &IterationState<'_, '_>,
    ) -> Result<Vec<Option<f64>>, SegmentError>;

    /// The intensity thresholds the initialisation drew, in the input's
    /// units, for the report; none by default.
    fn thresholds(&self) -> Vec<f64> {
        Vec::new()
    }
}

/// Any closure `FnMut(&mut Complex, &IterationState) -> Result<…>` is an
/// initialiser of the box mesh.
impl<K: Raster, F> Initialiser<K> for F
where
    F: FnMut(&mut Complex<K>, &IterationState<'_, '_>) -> Result<Vec<Option<f64>>, SegmentError>
        + Send,
{
    fn initialise(
        &mut self,
        complex: &mut Complex<K>,
        state: &IterationState<'_, '_>,
    ) -> Result<Vec<Option<f64>>, SegmentError> {
        self(complex, state)
    }
}

/// The label rules of [`Models::paper`].
fn paper_rules<K: Raster>(params: &SegmentParams) -> Vec<Box<dyn LabelRule<K>>> {
    let mut rules: Vec<Box<dyn LabelRule<K>>> = vec![
        Box::new(CellFlips::default()),
        Box::new(ComponentFlips::default()),
    ];
    if params.band_flips {
        rules.push(Box::new(BandFlips::default()));
    }
    rules
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
    /// The field the paper's terms share, for the records' junction counts.
    paper_field: Option<PaperField<K>>,
}

impl<K: Raster> Models<K> {
    /// The paper's evolution with the weights and settings of `params`:
    /// [`RegionForce`](super::models::RegionForce), [`Rigidity`](super::models::Rigidity), [`Elasticity`](super::models::Elasticity) (sharing one field per
    /// iteration), [`CellFlips`] then [`ComponentFlips`] (then [`BandFlips`]
    /// with [`SegmentParams::band_flips`]), initialised by
    /// [`ParamsInit`] (i.e. [`SegmentParams::init`]). The terms keep their
    /// parameters: change them mid-run through
    /// [`force_mut`](Self::force_mut), not through the `SegmentParams`.
    pub fn paper(params: &SegmentParams) -> Self {
        let PaperTerms {
            region,
            rigidity,
            elasticity,
        } = PaperTerms::new(params);
        let field = region.field().clone();
        Models {
            forces: vec![Box::new(region), Box::new(rigidity), Box::new(elasticity)],
            rules: paper_rules(params),
            init: Box::new(ParamsInit::default()),
            paper_field: Some(field),
        }
    }

    /// No force and no label rule, initialised by [`ParamsInit`]: start from
    /// here to build an evolution from scratch. Nothing of the paper's
    /// forces is computed.
    pub fn empty() -> Self {
        Models {
            forces: Vec::new(),
            rules: Vec::new(),
            init: Box::new(ParamsInit::default()),
            paper_field: None,
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

    /// The first force term of type `T`.
    pub fn force<T: 'static>(&self) -> Option<&T> {
        self.forces
            .iter()
            .find_map(|f| f.as_ref().as_any().downcast_ref::<T>())
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

    /// The field shared by [`Models::paper`]'s terms, if they computed it
    /// for force evaluation `evaluation` (see [`IterationState::evaluation`]).
    pub fn paper_field(&self, evaluation: u64) -> Option<&PaperField<K>> {
        self.paper_field
            .as_ref()
            .filter(|f| f.computed_for() == Some(evaluation))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::D2;
    use crate::segment::forces::tests::computations;
    use crate::segment::Segmentation;

    /// Runs 3 iterations of `models` on a two-phase image; returns how many
    /// times the paper's field was computed.
    fn paper_field_computations(models: Models<D2>) -> usize {
        // One thread: the helper runs inline, so every computation is counted here.
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        pool.install(|| {
            let pixels: Vec<f32> = (0..32 * 32)
                .map(|i| if i % 32 < 12 { 0.2 } else { 0.8 })
                .collect();
            let image = ImageView::new_2d(32, 32, &pixels).unwrap();
            let before = computations();
            let mut seg = Segmentation::with_models(image, SegmentParams::new(2), models).unwrap();
            for _ in 0..3 {
                seg.step();
            }
            computations() - before
        })
    }

    #[test]
    fn empty_models_compute_no_paper_field() {
        let params = SegmentParams::new(2);
        // the paper's three terms share one computation per force evaluation
        let paper = paper_field_computations(Models::paper(&params));
        assert!((3..=6).contains(&paper), "{paper} computations");
        assert_eq!(paper_field_computations(Models::empty()), 0);
        // a rule alone computes no force field either
        let rules = Models::empty().with_rule(CellFlips::default());
        assert_eq!(paper_field_computations(rules), 0);
    }
}
