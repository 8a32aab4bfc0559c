//! The paper's evolution as models: the region force, rigidity and
//! elasticity (sharing one lazily computed [`ForceField`] per force
//! evaluation), the label flips of [`Flipper`] and the initialisations of
//! [`initialise`], whose numerics they do not touch.

use crate::complex::Complex;
use crate::dim::Point;
use crate::segment::cluster_flips::ClusterFlipper;
use crate::segment::error::SegmentError;
use crate::segment::flips::Flipper;
use crate::segment::forces::{ForceField, ForceSettings};
use crate::segment::image::ImageView;
use crate::segment::init::initialise;
use crate::segment::model::{ForceTerm, Initialiser, IterationState, LabelRule, TermKind};
use crate::segment::params::{ForceModel, Init, SegmentParams};
use crate::segment::raster::Raster;
use crate::segment::smoothing::ForceImage;
use crate::segment::thresholds::split_histogram;
use std::sync::{Arc, Mutex, MutexGuard};

/// Largest stable coefficient of the explicit bending step: the
/// highest-frequency mode changes by a factor `1 − 4k` per step.
pub const MAX_BENDING_STEP: f64 = 0.2;
/// Largest stable coefficient of the explicit stretching (umbrella) step.
pub const MAX_STRETCHING_STEP: f64 = 0.5;

/// The paper's per-vertex fields (region force, bending and umbrella
/// directions) shared by the terms built together by [`PaperTerms::new`]:
/// computed by the first of them that needs it in a force evaluation, then
/// read by the others.
#[derive(Clone, Debug)]
pub struct PaperField<K: Raster> {
    shared: Arc<Mutex<CachedField<K>>>,
}

#[derive(Debug)]
struct CachedField<K: Raster> {
    field: ForceField<K>,
    settings: ForceSettings,
    /// What the region force samples.
    image: ForceImage,
    /// The force evaluation the field was computed for.
    computed_for: Option<u64>,
}

impl<K: Raster> PaperField<K> {
    /// A field computed with `settings` (`equal_means` is set from the
    /// image's range at each computation).
    pub fn new(settings: ForceSettings) -> Self {
        PaperField {
            shared: Arc::new(Mutex::new(CachedField {
                field: ForceField::new(),
                settings,
                image: ForceImage::default(),
                computed_for: None,
            })),
        }
    }

    /// The force evaluation the field was last computed for.
    pub fn computed_for(&self) -> Option<u64> {
        self.lock().computed_for
    }

    /// The field as last computed (for inspection).
    pub fn field(&self) -> impl std::ops::Deref<Target = ForceField<K>> + '_ {
        FieldGuard(self.lock())
    }

    fn lock(&self) -> MutexGuard<'_, CachedField<K>> {
        // A panic while computing leaves scratch space only: still usable.
        self.shared.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The field for the state's force evaluation, computed now unless
    /// another term already did.
    fn current(
        &self,
        complex: &Complex<K>,
        state: &IterationState<'_, '_>,
    ) -> MutexGuard<'_, CachedField<K>> {
        let mut cached = self.lock();
        if cached.computed_for != Some(state.evaluation) {
            let c = &mut *cached;
            let mut settings = c.settings;
            settings.equal_means = 1e-6 * (state.range.1 - state.range.0);
            let image = c.image.view(state.image);
            c.field.compute(complex, &image, state.phases, &settings);
            c.computed_for = Some(state.evaluation);
        }
        cached
    }
}

/// [`PaperField::field`]'s view into the locked cache.
struct FieldGuard<'g, K: Raster>(MutexGuard<'g, CachedField<K>>);

impl<K: Raster> std::ops::Deref for FieldGuard<'_, K> {
    type Target = ForceField<K>;
    fn deref(&self) -> &ForceField<K> {
        &self.0.field
    }
}

/// Adds a per-vertex field into `out`.
fn add_field<P: Point>(out: &mut [P], field: &[P]) {
    for (o, f) in out.iter_mut().zip(field) {
        *o += *f;
    }
}

/// The paper's three force terms with the settings and weights of a
/// [`SegmentParams`], sharing one field.
pub struct PaperTerms<K: Raster> {
    /// Eqs. (5)–(7).
    pub region: RegionForce<K>,
    /// Eq. (2), β.
    pub rigidity: Rigidity<K>,
    /// Eq. (2), α.
    pub elasticity: Elasticity<K>,
}

impl<K: Raster> PaperTerms<K> {
    /// The terms of `params` (force model, junction force, sample spacing,
    /// rigidity and elasticity).
    pub fn new(params: &SegmentParams) -> Self {
        let field = PaperField::new(ForceSettings {
            model: params.force,
            junction: params.junction_force,
            spacing: params.sample_spacing,
            equal_means: 0.0,
        });
        PaperTerms {
            region: RegionForce {
                model: params.force,
                field: field.clone(),
            },
            rigidity: Rigidity {
                beta: params.rigidity,
                field: field.clone(),
            },
            elasticity: Elasticity {
                alpha: params.elasticity,
                field,
            },
        }
    }
}

/// The field settings of the default [`SegmentParams`], for a term built alone.
fn default_field<K: Raster>() -> PaperField<K> {
    let p = SegmentParams::new(2);
    PaperField::new(ForceSettings {
        model: p.force,
        junction: p.junction_force,
        spacing: p.sample_spacing,
        equal_means: 0.0,
    })
}

/// The region force of eqs. (5)–(7) (the model chosen by
/// [`SegmentParams::force`]): on a two-phase interface between phases with
/// means `m_i`, `m_j`, the hat-weighted average along the facets of
/// `f(I) = (2I − m_i − m_j)/(m_i − m_j)` times the normal `N_ij` (eq. 6);
/// at triple junctions the mean-bracketing weights of eq. (7).
///
/// Reference magnitude 1 for eq. (6), `(m_0 − m_1)²` for Chan–Vese.
#[derive(Clone, Debug)]
pub struct RegionForce<K: Raster> {
    model: ForceModel,
    field: PaperField<K>,
}

impl<K: Raster> RegionForce<K> {
    /// The field this term reads (shared with the terms built with it).
    pub fn field(&self) -> &PaperField<K> {
        &self.field
    }

    /// From now on the force samples `image` smoothed by a Gaussian of
    /// standard deviation `sigma` pixels (2D; 0: `image` as it is; see
    /// [`crate::segment::smoothing`]). The driver sets it from the image's
    /// noise.
    pub fn sample_smoothed(&mut self, image: &ImageView<'_>, sigma: f64) {
        let mut cached = self.field.lock();
        cached.image = ForceImage::smoothed(image, sigma);
        cached.computed_for = None;
    }

    /// The standard deviation in pixels of the Gaussian the sampled image
    /// was smoothed with (0: none).
    pub fn smoothing(&self) -> f64 {
        self.field.lock().image.sigma()
    }
}

impl<K: Raster> ForceTerm<K> for RegionForce<K> {
    fn name(&self) -> &str {
        "region"
    }

    fn reference_magnitude(&self, state: &IterationState<'_, '_>) -> f64 {
        match self.model {
            ForceModel::Normalised => 1.0,
            ForceModel::ChanVese => {
                let (a, b) = (
                    state.phases.mean[0].unwrap_or(0.0),
                    state.phases.mean[1].unwrap_or(0.0),
                );
                ((a - b) * (a - b)).max(1e-12)
            }
        }
    }

    fn add_forces(
        &mut self,
        complex: &Complex<K>,
        state: &IterationState<'_, '_>,
        out: &mut [K::Point],
    ) {
        add_field(out, &self.field.current(complex, state).field.external);
    }
}

/// The rigidity term of eq. (2): the bending direction `−Δ²X` traced along
/// each phase boundary, weighted by β ([`SegmentParams::rigidity`] in
/// [`PaperTerms::new`]).
#[derive(Clone, Debug)]
pub struct Rigidity<K: Raster> {
    /// The weight β.
    pub beta: f64,
    field: PaperField<K>,
}

impl<K: Raster> Rigidity<K> {
    /// A rigidity of weight `beta` on its own.
    pub fn new(beta: f64) -> Self {
        Rigidity {
            beta,
            field: default_field(),
        }
    }
}

impl<K: Raster> ForceTerm<K> for Rigidity<K> {
    fn name(&self) -> &str {
        "rigidity"
    }

    fn kind(&self) -> TermKind {
        TermKind::Smoothing {
            weight: self.beta,
            max_step: MAX_BENDING_STEP,
        }
    }

    fn add_forces(
        &mut self,
        complex: &Complex<K>,
        state: &IterationState<'_, '_>,
        out: &mut [K::Point],
    ) {
        add_field(out, &self.field.current(complex, state).field.bending);
    }

    fn apply_to(&mut self, input: &[K::Point], out: &mut Vec<K::Point>) -> bool {
        self.field.lock().field.apply_bending(input, out);
        true
    }

    fn support_into(&mut self, out: &mut Vec<u32>) -> bool {
        self.field.lock().field.smoothed_vertices_into(out);
        true
    }
}

/// The elasticity term of eq. (2): the umbrella `ΔX` along each phase
/// boundary, weighted by α ([`SegmentParams::elasticity`] in
/// [`PaperTerms::new`], 0 by default).
#[derive(Clone, Debug)]
pub struct Elasticity<K: Raster> {
    /// The weight α.
    pub alpha: f64,
    field: PaperField<K>,
}

impl<K: Raster> Elasticity<K> {
    /// An elasticity of weight `alpha` on its own.
    pub fn new(alpha: f64) -> Self {
        Elasticity {
            alpha,
            field: default_field(),
        }
    }
}

impl<K: Raster> ForceTerm<K> for Elasticity<K> {
    fn name(&self) -> &str {
        "elasticity"
    }

    fn kind(&self) -> TermKind {
        TermKind::Smoothing {
            weight: self.alpha,
            max_step: MAX_STRETCHING_STEP,
        }
    }

    fn add_forces(
        &mut self,
        complex: &Complex<K>,
        state: &IterationState<'_, '_>,
        out: &mut [K::Point],
    ) {
        add_field(out, &self.field.current(complex, state).field.stretching);
    }

    fn apply_to(&mut self, input: &[K::Point], out: &mut Vec<K::Point>) -> bool {
        self.field.lock().field.apply_umbrella(input, out);
        true
    }

    fn support_into(&mut self, out: &mut Vec<u32>) -> bool {
        self.field.lock().field.smoothed_vertices_into(out);
        true
    }
}

/// The paper's cell flips (section III.C): two phases, a cell flips when its
/// mean is nearer the other phase's mean; more phases, to the phase most of
/// its pixels are nearest. With [`SegmentParams::flip_guard`] a flip must also
/// lower the Mumford–Shah energy (see [`crate::segment::flips`]).
#[derive(Clone, Debug, Default)]
pub struct CellFlips {
    flipper: Flipper,
    /// The state of the last prediction and the first cell it found would
    /// flip ([`Flipper::first_flip`]), for the sweep that follows it.
    predicted: Option<(Asked, Option<u32>)>,
}

impl<K: Raster> LabelRule<K> for CellFlips {
    fn name(&self) -> &str {
        "cell flips"
    }

    fn relabel(&mut self, complex: &mut Complex<K>, state: &IterationState<'_, '_>) -> usize {
        let (image, cells, phases) = (state.image, state.cells, state.phases);
        let (nu, guard, once) = (
            state.length_weight,
            state.params.flip_guard,
            state.params.flip_once,
        );
        match self.predicted.take() {
            Some((asked, first)) if asked == Asked::of(complex, state) => self
                .flipper
                .flip_after_first(complex, image, cells, phases, nu, guard, once, first),
            _ => self
                .flipper
                .flip(complex, image, cells, phases, nu, guard, once),
        }
    }

    fn would_relabel(
        &mut self,
        complex: &Complex<K>,
        state: &IterationState<'_, '_>,
    ) -> Option<bool> {
        let first = self.flipper.first_flip(
            complex,
            state.image,
            state.cells,
            state.phases,
            state.length_weight,
            state.params.flip_guard,
            state.params.flip_once,
        );
        self.predicted = Some((Asked::of(complex, state), first));
        Some(first.is_some())
    }
}

/// Whole-region flips (with [`SegmentParams::flip_guard`] only): every
/// connected same-phase region is relabelled to the neighbouring phase that
/// lowers the Mumford–Shah energy most, if any does. With adaptive
/// resolution, connected groups of cells that all fit another phase are
/// then relabelled together when that lowers the energy
/// ([`crate::segment::cluster_flips`]): refined cells over a thin line are
/// too small to flip one by one.
#[derive(Clone, Debug, Default)]
pub struct ComponentFlips {
    flipper: Flipper,
    clusters: ClusterFlipper,
    /// The state on which the flipper last listed the component flips
    /// ([`Flipper::would_flip_components`]), for the relabelling that
    /// follows it.
    predicted: Option<Asked>,
}

impl<K: Raster> LabelRule<K> for ComponentFlips {
    fn name(&self) -> &str {
        "component flips"
    }

    fn relabel(&mut self, complex: &mut Complex<K>, state: &IterationState<'_, '_>) -> usize {
        let listed = self.predicted.take() == Some(Asked::of(complex, state));
        if !state.params.flip_guard {
            return 0;
        }
        let nu = state.length_weight;
        let mut flips = if listed {
            self.flipper.component_flips_listed(complex)
        } else {
            self.flipper
                .component_flips(complex, state.cells, state.phases, nu)
        };
        if state.params.sizing.adaptive {
            flips += self.clusters.flip(complex, state.cells, state.phases, nu);
        }
        flips
    }

    fn would_relabel(
        &mut self,
        complex: &Complex<K>,
        state: &IterationState<'_, '_>,
    ) -> Option<bool> {
        self.predicted = None;
        if !state.params.flip_guard {
            return Some(false);
        }
        let nu = state.length_weight;
        let components = self
            .flipper
            .would_flip_components(complex, state.cells, state.phases, nu);
        self.predicted = Some(Asked::of(complex, state));
        Some(
            components
                || (state.params.sizing.adaptive
                    && self
                        .clusters
                        .would_flip(complex, state.cells, state.phases, nu)),
        )
    }
}

/// The state a label rule's prediction was made on: the complex (its
/// identity and its clocks of moves, relabellings and compactions), the
/// iteration and force evaluation, the image and cell statistics read (by
/// address), and the length weight and phase means. A `relabel` on the
/// same state follows its prediction with nothing changed between (the
/// cell statistics change only with the mesh, between iterations), so it
/// may take up the prediction's work.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Asked {
    complex: [u64; 4],
    round: [u64; 2],
    read: [usize; 3],
    length_weight: u64,
    means: u64,
}

impl Asked {
    fn of<K: Raster>(complex: &Complex<K>, state: &IterationState<'_, '_>) -> Self {
        // (the means' bits folded FNV-1a style: no allocation per iteration)
        let means = state
            .phases
            .mean
            .iter()
            .fold(0xcbf2_9ce4_8422_2325, |h, m| {
                (h ^ m.map_or(u64::MAX, f64::to_bits)).wrapping_mul(0x0100_0000_01b3)
            });
        Asked {
            complex: [
                complex.identity(),
                complex.move_clock(),
                complex.relabels(),
                complex.compactions(),
            ],
            round: [state.iteration as u64, state.evaluation],
            read: [
                state.image.data.as_ptr() as usize,
                state.cells.as_ptr() as usize,
                state.cells.len(),
            ],
            length_weight: state.length_weight.to_bits(),
            means,
        }
    }
}

/// The initialisation chosen by [`SegmentParams::init`] (histogram, range,
/// disks, balls or a label image) on the box mesh.
#[derive(Clone, Debug, Default)]
pub struct ParamsInit {
    /// The thresholds drawn by the histogram and range initialisations.
    thresholds: Vec<f64>,
}

impl<K: Raster> Initialiser<K> for ParamsInit {
    fn initialise(
        &mut self,
        complex: &mut Complex<K>,
        state: &IterationState<'_, '_>,
    ) -> Result<Vec<Option<f64>>, SegmentError> {
        let params = state.params;
        let classes = (params.init == Init::Histogram)
            .then(|| split_histogram(&state.intensity.cell_histogram(state.cells), params.phases));
        self.thresholds = match (&classes, &params.init) {
            (Some(c), _) => c.thresholds.clone(),
            (None, Init::Range) => {
                let (lo, hi) = state.range;
                let n = params.phases as f64;
                (1..params.phases)
                    .map(|k| lo + (hi - lo) * k as f64 / n)
                    .collect()
            }
            _ => Vec::new(),
        };
        initialise(
            complex,
            state.image,
            params,
            state.cells,
            state.range,
            classes.as_ref(),
        )
    }

    fn thresholds(&self) -> Vec<f64> {
        self.thresholds.clone()
    }
}

/// A given mesh whose labels are the initialisation (e.g. a complex
/// conforming to an initial surface). It must cover the image domain.
pub struct GivenMesh<K: Raster> {
    complex: Option<Complex<K>>,
}

impl<K: Raster> GivenMesh<K> {
    /// Starts from `complex` as it is labelled.
    pub fn new(complex: Complex<K>) -> Self {
        GivenMesh {
            complex: Some(complex),
        }
    }
}

impl<K: Raster> Initialiser<K> for GivenMesh<K> {
    fn start_mesh(&mut self) -> Option<Complex<K>> {
        self.complex.take()
    }

    fn initialise(
        &mut self,
        _complex: &mut Complex<K>,
        state: &IterationState<'_, '_>,
    ) -> Result<Vec<Option<f64>>, SegmentError> {
        Ok(vec![None; state.params.phases])
    }
}
