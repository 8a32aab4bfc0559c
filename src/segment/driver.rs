//! The iteration driver: integrate, flip, compute forces, deform, check convergence.

use super::absorbed::{absorbed_by_count, pixels_by_rank};
use super::adaptive::{AdaptiveSizing, Sizes};
use super::band_phase::{band_phases, range_counts, VoxelSize};
use super::check_image::CheckImage;
use super::coarse_pass::{self, CoarsePassSummary};
use super::contrast::phase_contrast;
use super::error::SegmentError;
use super::force_stage::{ForceStage, Reach};
use super::graded_start::StartGrading;
use super::image::ImageView;
use super::integrate::{CellCache, CellStats, PhaseStats};
use super::intensity::IntensityStats;
use super::missed_objects::MissedObjects;
use super::model::{Flow, IterationState, LabelRule, Models};
use super::models::{GivenMesh, PaperField, RegionForce, Rigidity};
use super::noise_correlation::correlated_noise_warning;
use super::params::{
    contrast_edge_length, contrast_rigidity, sample_step, smallest_extent, SegmentParams,
};
use super::partial_volume::phase_plateaus;
use super::raster::Raster;
use super::reseed::{
    any_lost, lost_phases, merge_phase, plateau_twins, speckled_pairs, split_most_structured_phase,
    vestiges, LostPhase,
};
use super::reseed_trial::{ReseedTrial, RunProgress};
use super::shading::PhaseTrend;
use super::smoothing::force_smoothing;
use super::thresholds::smallest_class_gap;
use crate::complex::{Complex, Label};
use crate::dsc::{Destinations, DscParams, DscWorkspace};
use serde::Serialize;
use spin_join::SpinHelper;
use std::time::Instant;

/// Iterations without a new lowest energy after which the step is halved.
pub const STALL_ITERATIONS: usize = 10;

/// Iterations over which [`energy_fall_slowed`] measures the energy's
/// recent fall ([`SegmentParams::settle_rate`]).
const SETTLE_SPAN: usize = 3;

/// The start's refinement ends after a pass that grows the mesh by less
/// than 1/`START_GROWTH` of its cells.
const START_GROWTH: usize = 10;

/// On an adaptive 2D mesh, an iteration relabelling at most this fraction of
/// the cells is calm for the energy-plateau rule (the driver's `calm`):
/// along thin structures under noise, cells at the
/// smallest size flip back and forth every iteration, so no iteration is
/// without flips and the plateau never ends the run (the `thin` phantom's
/// runs reached the iteration cap with 2–6 flips of 2 500–6 300 cells per
/// iteration and the energy within 0.05 % over 400 iterations).
const ADAPTIVE_CALM_FLIPS: f64 = 0.005;

/// A run whose last [`SWAP_ITERATIONS`] iterations each relabelled more than
/// [`SWAP_SHARE`] of the cells, without a new low of the energy, is swapping
/// labels and stops: two phases that
/// divide one region of the image by noise (a phase more than the image
/// holds) can trade their cells every iteration, each component judging its
/// flip against the other's labels as they are, up to the iteration cap (a
/// 256² image of two halves asked for four phases: 1 600 of 3 200 cells at
/// every one of 500 iterations), and so can the few cells over an image of
/// a few pixels (a 2×2 checkerboard). A run from a poor start relabels as
/// many cells in its first iterations, but its energy falls meanwhile.
pub const SWAP_ITERATIONS: usize = 6;

/// See [`SWAP_ITERATIONS`].
pub const SWAP_SHARE: f64 = 0.2;

/// What one iteration saw and did.
#[derive(Clone, Debug, Serialize)]
pub struct IterationRecord {
    /// Iteration number, from 1.
    pub iteration: usize,
    /// Mumford–Shah energy (data + ν·length) of the state the iteration started from.
    pub energy: f64,
    /// Data term `Σ (I − m_label)²`.
    pub data_energy: f64,
    /// Interface length (area in 3D).
    pub length: f64,
    /// Cells that changed label.
    pub flips: usize,
    /// Largest requested displacement, in units of L.
    pub max_displacement: f64,
    /// Largest requested displacement across the interface, in units of
    /// L: in 2D a two-phase interface vertex's motion along the interface
    /// (the bending term evening out the vertices' spacing) is left out, as
    /// it moves no pixel to the other side; the stopping rule reads this.
    pub max_displacement_across: f64,
    /// Phase means the forces used.
    pub means: Vec<Option<f64>>,
    /// Triple junctions with an external force, and crossings without (of
    /// the paper's region force; `(0, 0)` without it).
    pub junctions: (usize, usize),
    /// Cells of the mesh after the iteration.
    #[serde(default)]
    pub cells: usize,
    /// Smallest, median and largest edge length after the iteration
    /// (adaptive runs only; the uniform mesh keeps its edges near `L`).
    #[serde(default)]
    pub edge_lengths: Option<[f64; 3]>,
}

/// Why the run stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// Nothing flipped and nothing moved (beyond the threshold) for long enough.
    Converged,
    /// The iteration cap was reached.
    MaxIterations,
    /// The observer of [`Segmentation::run_until`] asked to stop.
    Stopped,
    /// The labels swapped between states for [`SWAP_ITERATIONS`] iterations
    /// ([`Segmentation::labels_swapping`]).
    SwappingLabels,
}

/// The warning of a run that reached the iteration cap before its stopping
/// rule: its interfaces may still have been moving, so the result may not
/// be the segmentation the method converges to.
pub fn cap_warning(max_iterations: usize) -> String {
    format!(
        "the run stopped at the iteration cap ({max_iterations} iterations) before converging: \
         the interfaces may still be moving; --max-iterations raises the cap"
    )
}

/// A segmentation split into disjoint borrows: the state the models read
/// and the parts they, or the force stage, change.
struct Parts<'s, 'a, K: Raster> {
    state: IterationState<'s, 'a>,
    complex: &'s mut Complex<K>,
    force: &'s mut ForceStage<K>,
    models: &'s mut Models<K>,
    helper: &'s SpinHelper,
    /// The current step fraction.
    step: f64,
}

/// The driver's second thread ([`SpinHelper`]): one if rayon may use more
/// than one (`RAYON_NUM_THREADS=1` keeps a whole run on one thread, e.g.
/// for instruction counts).
#[derive(Debug)]
struct Helper {
    thread: SpinHelper,
    inline: SpinHelper,
}

impl Helper {
    fn new() -> Self {
        let thread = if rayon::current_num_threads() > 1 {
            SpinHelper::new()
        } else {
            SpinHelper::none()
        };
        Helper {
            thread,
            inline: SpinHelper::none(),
        }
    }

    /// The helper, or none on one of rayon's worker threads: there the
    /// helper's jobs (which may post rayon work) could wait for workers that
    /// all wait for the helper (segmentations run by `par_iter`).
    fn here(&self) -> &SpinHelper {
        if rayon::current_thread_index().is_some() {
            &self.inline
        } else {
            &self.thread
        }
    }
}

/// What the setup reads from the image before it builds the mesh: checked
/// to hold enough distinct values, with the figures the edge length is
/// chosen from.
struct ImageFigures {
    /// Smallest and largest sample.
    range: (f64, f64),
    intensity: IntensityStats,
    /// The contrast between the classes ([`class_gap`](Self::class_gap)).
    gap: Option<f64>,
    /// The edge length L ([`edge_length`](Self::edge_length)).
    l: f64,
}

impl ImageFigures {
    /// The figures of `image`, or why it cannot be segmented into
    /// `params.phases` phases (not finite, constant, too few distinct values).
    fn of<K: Raster>(image: &ImageView<'_>, params: &SegmentParams) -> Result<Self, SegmentError> {
        let range = image.range().ok_or(SegmentError::NonFinite)?;
        if range.1 - range.0 <= 0.0 {
            return Err(SegmentError::ConstantImage(range.0));
        }
        let distinct = image.distinct_values(params.phases);
        if distinct < params.phases {
            return Err(SegmentError::TooFewIntensities {
                distinct,
                phases: params.phases,
            });
        }
        let intensity = IntensityStats::of(image);
        let gap = Self::class_gap::<K>(params, image, &intensity);
        let l = Self::edge_length(params, image, &intensity, gap);
        Ok(ImageFigures {
            range,
            intensity,
            gap,
            l,
        })
    }

    /// In 2D, the smallest gap between the class means of the least-variance
    /// split of the pixels' histogram, the contrast that the noise is weighed
    /// against for the edge length and the rigidity; `None` in 3D, which
    /// keeps both as given.
    fn class_gap<K: Raster>(
        params: &SegmentParams,
        image: &ImageView<'_>,
        intensity: &IntensityStats,
    ) -> Option<f64> {
        if K::N != 2 {
            return None;
        }
        smallest_class_gap(&intensity.histogram(image), params.phases)
    }

    /// The edge length L: the parameter's if given; else the size default,
    /// in 2D shortened for an image whose noise is small against the
    /// contrast `gap` between its phases ([`contrast_edge_length`], the
    /// contrast from [`class_gap`](Self::class_gap)). 3D keeps the size
    /// default.
    fn edge_length(
        params: &SegmentParams,
        image: &ImageView<'_>,
        intensity: &IntensityStats,
        gap: Option<f64>,
    ) -> f64 {
        let l = params.resolved_edge_length_in(image.dims, image.spacing);
        match gap {
            Some(gap) if params.edge_length.is_none() => {
                contrast_edge_length(l, intensity.noise, gap)
            }
            _ => l,
        }
    }
}

/// Seconds spent in each stage of the evolution.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct StageTimes {
    /// Building and initialising the mesh (with the refined start's
    /// refinement and flips, if any).
    pub setup: f64,
    /// Integrating the image over the cells.
    pub integrate: f64,
    /// Label flips (a check of the rules that ran beside the forces, or
    /// before them on one thread, see [`LabelRule::would_relabel`],
    /// is in `forces`).
    pub flips: f64,
    /// Force computation.
    pub forces: f64,
    /// DSC deformation (move, improve, resize).
    pub deform: f64,
    /// Everything (the segmentation time, excluding file I/O).
    pub total: f64,
}

/// The outcome of a run.
#[derive(Clone, Debug, Serialize)]
pub struct SegmentReport {
    /// Edge length L used.
    pub edge_length: f64,
    /// Iterations run.
    pub iterations: usize,
    /// Whether the run stopped by convergence.
    pub converged: bool,
    /// Why it stopped.
    pub stop_reason: StopReason,
    /// Final means per mesh label, `None` for a phase without pixels.
    pub final_means: Vec<Option<f64>>,
    /// Final energy.
    pub final_energy: f64,
    /// Length weight ν used in the energy and flip guard (intensity² per
    /// pixel of length, in the input's units).
    pub length_weight_abs: f64,
    /// The rigidity β the bending term used: in 2D the parameter weighed
    /// against the image's noise ([`contrast_rigidity`]); `None` without a
    /// rigidity term. A fine finish may multiply it for its own iterations
    /// ([`Finish::rigidity_factor`](super::adaptive::Finish::rigidity_factor)).
    pub rigidity: Option<f64>,
    /// The standard deviation, in pixels, of the Gaussian the image the
    /// region force samples was smoothed with (2D, on the uniform and the
    /// adaptive mesh, from the image's noise: [`force_smoothing`]; 0 for
    /// none); `None` without the region force.
    pub force_smoothing: Option<f64>,
    /// The input's intensity figures (range, robust range, noise estimate).
    pub intensity: IntensityStats,
    /// The thresholds of the initialisation, in the input's units: the
    /// histogram split of [`Init::Histogram`](super::params::Init::Histogram), the interval bounds of
    /// [`Init::Range`](super::params::Init::Range); empty for the other initialisations.
    pub initial_thresholds: Vec<f64>,
    /// Lost phases re-seeded during the run and kept (see [`crate::segment::reseed`]).
    pub reseeds: usize,
    /// Re-seeds of phases judged bands that did not lower the energy by the
    /// next flip round and were undone ([`crate::segment::reseed_trial`]).
    pub reseeds_undone: usize,
    /// What the user must know about the result: phases lost at the end
    /// (empty, or duplicating another's mean), the iteration cap, correlated
    /// noise. Empty when all is well.
    pub warnings: Vec<String>,
    /// Those of `warnings` that say a phase was lost, for a caller that
    /// says it otherwise: `--phases auto` at its floor of two phases
    /// ([`PhaseChoice::floor_warning`](super::auto::PhaseChoice::floor_warning))
    /// replaces them. Not in the report, where `warnings` has them.
    #[serde(skip)]
    pub lost_phase_warnings: Vec<String>,
    /// Per-iteration records.
    pub history: Vec<IterationRecord>,
    /// Stage timings.
    pub times: StageTimes,
    /// Vertices of the final mesh.
    pub vertices: usize,
    /// Cells of the final mesh.
    pub cells: usize,
    /// The sizes of adaptive resolution (`None`: the uniform mesh at `L`).
    pub sizes: Option<Sizes>,
    /// The coarse pass that gave the start mesh (`None`: none ran; see
    /// [`SegmentParams::coarse_pass`]). `iterations` and `history` are the
    /// full-resolution run's.
    pub coarse_pass: Option<CoarsePassSummary>,
    /// Objects of one phase the result left inside another, found in the
    /// data against the output labels (filled by the pipeline, which
    /// rasterises them; see [`missed_objects`](super::missed_objects));
    /// `None` when not looked for.
    pub missed_objects: Option<Vec<MissedObjects>>,
    /// The smooth trend of intensity fitted inside each phase (uneven
    /// illumination, a bias field; filled by the pipeline, see
    /// [`shading`](super::shading)); `None` when not looked for.
    pub shading: Option<Vec<PhaseTrend>>,
}

/// A segmentation in progress: the complex, the image, the models of the
/// evolution and all scratch space.
///
/// One segmentation loop for any evolution: [`step`](Self::step) runs one
/// iteration and returns its [`IterationRecord`]; [`run`](Self::run) iterates
/// until the built-in stopping rule or the cap; [`run_until`](Self::run_until)
/// hands every record and the segmentation itself to an observer that may
/// record frames ([`label_image`](Self::label_image), [`complex`](Self::complex)),
/// change parameters ([`params_mut`](Self::params_mut)) or models
/// ([`force_mut`](Self::force_mut), [`models_mut`](Self::models_mut)) and
/// decide when to stop.
pub struct Segmentation<'a, K: Raster> {
    image: ImageView<'a>,
    params: SegmentParams,
    dsc: DscParams,
    complex: Complex<K>,
    cells: Vec<CellStats>,
    /// Keeps the statistics of cells that did not move between iterations.
    cell_cache: CellCache<K>,
    /// The second thread of the short parallel sections of an iteration.
    helper: Helper,
    /// The input as the checks after the run read it.
    check_image: CheckImage,
    phases: PhaseStats,
    models: Models<K>,
    /// The force stage's fields, buffers and destinations.
    force: ForceStage<K>,
    /// The deform's memo and buffers, kept so that an iteration's deform
    /// does not allocate.
    deform_workspace: DscWorkspace<K>,
    /// The sizing field of adaptive resolution (`None`: uniform at `L`).
    adaptive: Option<AdaptiveSizing>,
    /// Force evaluations so far (the last one's number is the state's
    /// [`IterationState::evaluation`] of the forces that moved the mesh).
    evaluations: u64,
    /// Whether the label rules can predict their changes
    /// ([`LabelRule::would_relabel`]) so that
    /// they are checked beside (or before) the forces.
    predict_flips: bool,
    nu: f64,
    range: (f64, f64),
    intensity: IntensityStats,
    initial_thresholds: Vec<f64>,
    /// The voxels within each phase's initial threshold range (empty when
    /// the initialisation drew no thresholds): what a phase that ends as a
    /// band along other phases' edges is measured against.
    initial_range_counts: Vec<u64>,
    reseeds: usize,
    /// The state before a re-seed of a band, until the next flip round
    /// judges it ([`super::reseed_trial`]).
    reseed_trial: Option<ReseedTrial<K>>,
    /// Band re-seeds undone, and the labels they were of: not re-seeded
    /// again (a band that then empties is the same lost class, reported at
    /// the end).
    reseeds_undone: usize,
    refused_reseeds: Vec<Label>,
    times: StageTimes,
    history: Vec<IterationRecord>,
    quiet_iterations: usize,
    /// Current step fraction (the parameter, halved when the energy stalls).
    step: f64,
    best_energy: f64,
    stalled: usize,
    /// Iterations since the energy last reached a new low (not reset when
    /// the step is halved): the plateau of [`SegmentParams::converge_plateau`].
    since_new_low: usize,
    /// The first record of `history` from which [`energy_fall_slowed`]
    /// measures the energy's fall: the energy of a re-seeded or relabelled
    /// state starts a fall of its own (a re-seed weighs the length term
    /// anew, and the rise across it is no fall).
    fall_origin: usize,
    /// Whether a quiet flip round came on an energy plateau
    /// ([`SegmentParams::quiet_round_fraction`]): the run has converged.
    quiet_round_on_plateau: bool,
    /// The iteration of the last regular flip round (0 before the first;
    /// the finish's round is not one).
    last_flip_round: usize,
    /// Iterations of the fine finish still to run (`None`: not begun; see
    /// [`Finish`](super::adaptive::Finish)).
    finish_left: Option<usize>,
    /// Whether a re-seed called the finish off once it had begun: the run
    /// then stops on the stopping rule, without a finish.
    finish_called_off: bool,
    /// The run's rigidity β while the finish raises it
    /// ([`Finish::rigidity_factor`](super::adaptive::Finish::rigidity_factor)).
    rigidity_before_finish: Option<f64>,
    /// What the coarse pass that gave the start mesh did, if one ran.
    coarse_pass: Option<CoarsePassSummary>,
}

impl<'a, K: Raster> Segmentation<'a, K> {
    /// The paper's segmentation ([`Models::paper`]): validates the input,
    /// builds the mesh at edge length L and initialises the labels.
    /// With [`SegmentParams::coarse_pass`] on an image it
    /// [applies](coarse_pass::applies) to, the mesh and labels come from a
    /// run on the image at half resolution ([`coarse_pass`]).
    pub fn new(image: ImageView<'a>, params: SegmentParams) -> Result<Self, SegmentError> {
        // Before the coarse pass, whose error would name the halved size.
        Self::check_size(&image)?;
        if coarse_pass::applies(&params, &image) {
            return Self::after_coarse_pass(image, params);
        }
        let models = Models::paper(&params);
        Self::with_models(image, params, models)
    }

    /// The paper's segmentation started from the final mesh of the coarse
    /// pass, its labels and its initial thresholds (for the report and the
    /// band-phase test).
    fn after_coarse_pass(
        image: ImageView<'a>,
        params: SegmentParams,
    ) -> Result<Self, SegmentError> {
        params.validate_in(image.dims, image.spacing)?;
        let l = params.resolved_edge_length_in(image.dims, image.spacing);
        let (complex, thresholds, summary) = coarse_pass::coarse_mesh::<K>(&image, &params, l)?;
        let mut s = Self::from_complex(image, params, complex)?;
        if thresholds.len() + 1 == s.params.phases {
            s.initial_range_counts = range_counts(s.image.data, &thresholds);
        }
        s.initial_thresholds = thresholds;
        s.times.setup += summary.seconds;
        s.coarse_pass = Some(summary);
        Ok(s)
    }

    /// A segmentation running the given models (see [`Models`]): validates the
    /// input, builds the mesh at edge length L and initialises the labels
    /// with `models.init`.
    pub fn with_models(
        image: ImageView<'a>,
        params: SegmentParams,
        models: Models<K>,
    ) -> Result<Self, SegmentError> {
        Self::build(image, params, models)
    }

    /// Starts the paper's models from a given complex (e.g. one conforming to
    /// an initial surface) whose labels are the initialisation: `params.init`
    /// is not used, and `params.edge_length` (or its default) sets the DSC's
    /// L. The complex must cover the image domain `[0, dims]`.
    pub fn from_complex(
        image: ImageView<'a>,
        params: SegmentParams,
        complex: Complex<K>,
    ) -> Result<Self, SegmentError> {
        let models = Models::paper(&params).with_init(GivenMesh::new(complex));
        Self::with_models(image, params, models)
    }

    /// An error unless the image has at least two samples along each of
    /// the K axes (the smallest grid a mesh covers).
    fn check_size(image: &ImageView<'_>) -> Result<(), SegmentError> {
        if image.is_empty() {
            return Err(SegmentError::EmptyImage);
        }
        let dims = &image.dims[..K::N];
        if dims.iter().any(|&d| d < 2) {
            let size: Vec<String> = dims.iter().map(|d| d.to_string()).collect();
            return Err(SegmentError::ImageTooSmall(
                format!("{} {}", size.join("×"), K::SAMPLES),
                K::SMALLEST_GRID,
            ));
        }
        Ok(())
    }

    fn build(
        image: ImageView<'a>,
        params: SegmentParams,
        mut models: Models<K>,
    ) -> Result<Self, SegmentError> {
        let t0 = Instant::now();
        Self::check_size(&image)?;
        params.validate_in(image.dims, image.spacing)?;
        params.check_shapes_inside(image.extent())?;
        let helper = Helper::new();
        let check_image = CheckImage::default();
        // The image's figures on this thread; the checks' smoothed image on
        // the helper, which needs none of them.
        let checks_now = K::N == 2 && params.claims_whole_image();
        let (figures, ()) = helper.here().join(
            || ImageFigures::of::<K>(&image, &params),
            || {
                if checks_now {
                    check_image.of(&image);
                }
            },
        );
        let ImageFigures {
            range,
            intensity,
            gap,
            l,
        } = figures?;
        if let (Some(gap), Some(rigidity)) = (gap, models.force_mut::<Rigidity<K>>()) {
            rigidity.beta = contrast_rigidity(rigidity.beta, intensity.noise, gap);
        }
        let dsc = DscParams::new::<K>(l);
        let sizes = (params.sizing.adaptive).then(|| {
            let (extent, step) = (
                smallest_extent(image.dims, image.spacing),
                sample_step(image.dims, image.spacing),
            );
            params.sizing.sizes(K::N, extent, step, l)
        });
        let given = models.init.start_mesh();
        let coarse_start = given.is_none() && sizes.is_some_and(|s| s.start > s.interface);
        let refinements = if coarse_start {
            params.sizing.start_refinements
        } else {
            0
        };
        // The mesh on this thread; the region force's smoothed image on the
        // helper.
        let force_smoothing = gap.map(|gap| force_smoothing(intensity.noise, gap));
        let region = models.force_mut::<RegionForce<K>>();
        let (complex, ()) = helper.here().join(
            || match given {
                Some(c) => Ok(c),
                None => K::box_complex(&image, sizes.map_or(l, |s| s.start)),
            },
            || {
                if let (Some(sigma), Some(region)) = (force_smoothing, region) {
                    region.sample_smoothed(&image, sigma);
                }
            },
        );
        let mut complex = complex?;
        let mut adaptive = sizes.map(|sizes| {
            let (lo, hi) = complex.domain();
            AdaptiveSizing::new::<K>(&params.sizing, sizes, lo, hi)
        });
        let mut cells = Vec::new();
        // Through the cache: the initialisation relabels cells but rarely
        // moves them, so the first step finds them integrated already.
        let mut cell_cache = CellCache::new();
        let mut deform_workspace = DscWorkspace::new();
        if let Some(sizing) = adaptive.as_mut().filter(|_| coarse_start && K::N == 2) {
            StartGrading {
                image: &image,
                intensity: &intensity,
                phases: params.phases,
                dsc: &dsc,
                helper: helper.here(),
                cache: &mut cell_cache,
                cells: &mut cells,
                workspace: &mut deform_workspace,
            }
            .run(&mut complex, sizing);
        }
        cell_cache.integrate_on(helper.here(), &complex, &image, &mut cells);
        let mut hints = models.init.initialise(
            &mut complex,
            &IterationState {
                image: &image,
                intensity: &intensity,
                phases: &PhaseStats::new(params.phases),
                cells: &cells,
                params: &params,
                range,
                edge_length: l,
                length_weight: 0.0,
                iteration: 0,
                evaluation: 0,
            },
        )?;
        let initial_thresholds = models.init.thresholds();
        let initial_range_counts = if initial_thresholds.len() + 1 == params.phases {
            range_counts(image.data, &initial_thresholds)
        } else {
            Vec::new()
        };
        if let Some(c) = complex
            .cell_ids()
            .find(|&c| complex.label(c) as usize >= params.phases)
        {
            return Err(SegmentError::Init(format!(
                "the initialisation gave label {} but there are only {} phases",
                complex.label(c),
                params.phases
            )));
        }
        hints.resize(params.phases, None);
        let mut phases = PhaseStats::new(params.phases);
        phases.mean = hints;
        phases.update(&complex, &cells);
        if phases.present() < 1 {
            return Err(SegmentError::Init("no phase covers any pixel".into()));
        }
        let force = ForceStage::new(&complex);
        let mut s = Segmentation {
            image,
            params,
            dsc,
            complex,
            cells,
            cell_cache,
            helper,
            check_image,
            phases,
            models,
            force,
            deform_workspace,
            adaptive,
            evaluations: 0,
            predict_flips: true,
            nu: 0.0,
            range,
            intensity,
            initial_thresholds,
            initial_range_counts,
            reseeds: 0,
            reseed_trial: None,
            reseeds_undone: 0,
            refused_reseeds: Vec::new(),
            times: StageTimes::default(),
            history: Vec::new(),
            quiet_iterations: 0,
            step: 0.0,
            best_energy: f64::INFINITY,
            stalled: 0,
            since_new_low: 0,
            fall_origin: 0,
            quiet_round_on_plateau: false,
            last_flip_round: 0,
            finish_left: None,
            finish_called_off: false,
            rigidity_before_finish: None,
            coarse_pass: None,
        };
        s.step = s.params.step_fraction;
        s.nu = s.length_weight();
        // The refined start is setup: its integration and flips stay out
        // of the iterations' stage times.
        let stages = s.times;
        s.refine_start(refinements);
        s.times = stages;
        s.times.setup = t0.elapsed().as_secs_f64();
        Ok(s)
    }

    /// Coarse to fine before the first iteration, `passes` times at most:
    /// the mesh is resized to the sizing field (`L` at the labels'
    /// interfaces, finer where cells are not explained) and the label rules
    /// run on the refined cells, so that the first iteration starts with the
    /// interfaces within about `L` of where the data puts them rather than
    /// where the coarse cells did. The rules, not the initialisation's
    /// thresholds, label the refined cells: under noise the small cells'
    /// means scatter across the thresholds, and the rules' energy guard
    /// keeps such specks out. They may relabel these voxels again later
    /// (this pass does not count against `flip_once`). Ends early after a
    /// pass that grows the mesh by less than a tenth.
    fn refine_start(&mut self, passes: usize) {
        // (the passes' flip sweeps judge the refined cells in creation
        // order: `Complex::hold_spatial_renumbering`)
        self.complex.hold_spatial_renumbering(true);
        self.refine_start_passes(passes);
        self.complex.hold_spatial_renumbering(false);
    }

    /// The passes of [`refine_start`](Self::refine_start).
    fn refine_start_passes(&mut self, passes: usize) {
        for _ in 0..passes {
            let before = self.complex.cell_count();
            self.update_sizing();
            let none = Destinations::new(&self.complex);
            self.complex
                .deform_with(&none, &self.dsc, &mut self.deform_workspace);
            self.integrate();
            let once = std::mem::replace(&mut self.params.flip_once, false);
            self.relabel(0);
            self.params.flip_once = once;
            if self.complex.cell_count() < before + before / START_GROWTH {
                break;
            }
        }
    }

    /// ν = `length_weight` × Δ² / 2, Δ the contrast between phases
    /// ([`phase_contrast`]: the smallest gap between adjacent known means,
    /// not below twice the pixels' spread about their phase means nor above the
    /// mean gap; the robust range
    /// over N if fewer than two means are known). A stripe d pixels wide at
    /// contrast Δ lowers the data term by d·Δ² per pixel of its length and
    /// costs 2ν in boundary, so it pays for itself when d > `length_weight`
    /// (a disk when its radius does): the weight is a width in pixels, and ν
    /// is in intensity² per pixel like the data term, so `a·I + b` gives the
    /// same labels as `I`. The data term counts samples while lengths and
    /// areas are measured in the image's unit (a volume's millimetres), so ν
    /// is divided by the facet measure of one sample step h
    /// ([`ImageView::sample_step`]), h^(N−1): the width stays counted in
    /// samples, and a volume of 4 mm voxels gives the labels it gives at 1 mm.
    fn length_weight(&self) -> f64 {
        let known: Vec<f64> = self.phases.mean.iter().flatten().copied().collect();
        let pixels: u64 = self.phases.count.iter().sum();
        let spread = (self.data_energy() / pixels.max(1) as f64).sqrt();
        let contrast = phase_contrast(&known, spread)
            .unwrap_or_else(|| self.intensity.scale() / self.params.phases as f64);
        let step_facet = self.image.sample_step().powi(K::N as i32 - 1);
        self.params.length_weight * contrast * contrast / 2.0 / step_facet
    }

    /// The complex in its current state.
    pub fn complex(&self) -> &Complex<K> {
        &self.complex
    }

    /// The parameters.
    pub fn params(&self) -> &SegmentParams {
        &self.params
    }

    /// The input smoothed as the checks after a run read it
    /// ([`CheckImage`]), made now if no check has asked yet.
    pub fn check_image(&self) -> &[f32] {
        self.check_image.of(&self.image)
    }

    /// The parameters, to change mid-run. Changes take effect at the next
    /// [`step`](Self::step); the mesh and its edge length L stay as built,
    /// and the length weight ν (from the initial means) is kept.
    pub fn params_mut(&mut self) -> &mut SegmentParams {
        &mut self.params
    }

    /// The models of the evolution.
    pub fn models(&self) -> &Models<K> {
        &self.models
    }

    /// The models, to add, remove or change terms and rules mid-run.
    pub fn models_mut(&mut self) -> &mut Models<K> {
        // (new rules may predict their flips again)
        self.predict_flips = true;
        &mut self.models
    }

    /// The first force term of type `T` (e.g. to move a user's attraction
    /// point mid-run); `None` if there is none.
    pub fn force_mut<T: 'static>(&mut self) -> Option<&mut T> {
        self.models.force_mut::<T>()
    }

    /// The per-cell image statistics of the last integration, indexed by cell id.
    pub fn cell_stats(&self) -> &[CellStats] {
        &self.cells
    }

    /// The length weight ν of the energy (intensity² per pixel of length).
    pub fn length_weight_abs(&self) -> f64 {
        self.nu
    }

    /// The field of the paper's force terms ([`Models::paper`]) as the last
    /// force evaluation computed it (region force, bending and umbrella
    /// directions); `None` if no term computed it then.
    pub fn paper_field(&self) -> Option<&PaperField<K>> {
        self.models.paper_field(self.evaluations)
    }

    /// The current step fraction (the parameter, halved when the energy stalls).
    pub fn step_fraction(&self) -> f64 {
        self.step
    }

    /// The DSC thresholds in use.
    pub fn dsc_params(&self) -> &DscParams {
        &self.dsc
    }

    /// Current phase statistics.
    pub fn phases(&self) -> &PhaseStats {
        &self.phases
    }

    /// The mean of each phase that covers a pixel or voxel, `None` for an
    /// empty one (whose [`PhaseStats::mean`] is the mean it had before it
    /// emptied, kept so flips can revive it, but the mean of nothing).
    fn present_means(&self) -> Vec<Option<f64>> {
        let phases = &self.phases;
        phases
            .mean
            .iter()
            .zip(&phases.count)
            .map(|(&m, &n)| m.filter(|_| n > 0))
            .collect()
    }

    /// The records so far.
    pub fn history(&self) -> &[IterationRecord] {
        &self.history
    }

    fn data_energy(&self) -> f64 {
        assert!(
            self.cells.len() >= self.complex.cell_capacity(),
            "a statistic per cell id"
        );
        self.complex
            .label_slots()
            .zip(&self.cells)
            .filter_map(|(label, st)| {
                let m = self.phases.mean_of(label?).unwrap_or(0.0);
                Some(st.sse(m))
            })
            .sum()
    }

    fn integrate(&mut self) {
        let t = Instant::now();
        self.cell_cache.integrate_on(
            self.helper.here(),
            &self.complex,
            &self.image,
            &mut self.cells,
        );
        self.phases.update(&self.complex, &self.cells);
        self.times.integrate += t.elapsed().as_secs_f64();
    }

    /// One iteration; returns its record.
    pub fn step(&mut self) -> IterationRecord {
        let iteration = self.history.len() + 1;
        self.integrate();

        let flips_due = self.params.label_flips
            && (self.flip_round_due(iteration) && self.finish_left.is_none()
                || self.finish_flip_round_due());
        if flips_due {
            self.judge_reseed_trial();
        }
        if flips_due && self.finish_left.is_none() {
            self.last_flip_round = iteration;
        }
        // Most iterations flip nothing: after one that flipped nothing, the
        // rules only check whether they would flip (beside the forces, on
        // two threads).
        let mut forces = None;
        if flips_due && self.predict_flips && self.history.last().is_some_and(|r| r.flips == 0) {
            let t = Instant::now();
            forces = self.forces_unless_relabelling(iteration);
            self.times.forces += t.elapsed().as_secs_f64();
        }
        let cells_before_flips = self.complex.cell_count();
        let mut flips = 0;
        if flips_due && forces.is_none() {
            flips = self.relabel(iteration);
        }
        let reseeded = flips_due && self.recover_lost_phases() > 0;
        if reseeded {
            forces = None;
            self.cancel_finish();
        }
        let quiet_round = flips_due
            && iteration > 1
            && !reseeded
            && (flips as f64) < self.params.quiet_round_fraction * cells_before_flips as f64;
        // The record is of one state: the labels after the flips, whose
        // length term the forces measure below.
        let data_energy = self.data_energy();

        let (length, reach) = forces.unwrap_or_else(|| {
            let t = Instant::now();
            let computed = self.forces_and_destinations(iteration);
            self.times.forces += t.elapsed().as_secs_f64();
            computed
        });
        let l = self.dsc.edge_length;

        let t = Instant::now();
        self.update_sizing();
        if !self.force.dest.is_empty() || self.adaptive.is_some() {
            self.complex
                .deform_with(&self.force.dest, &self.dsc, &mut self.deform_workspace);
        }
        self.times.deform += t.elapsed().as_secs_f64();

        let rec = IterationRecord {
            iteration,
            energy: data_energy + self.nu * length,
            data_energy,
            length,
            flips,
            max_displacement: reach.largest / l,
            max_displacement_across: reach.across / l,
            means: self.phases.mean.clone(),
            junctions: self
                .models
                .paper_field(self.evaluations)
                .map_or((0, 0), |f| f.field().junctions),
            cells: self.complex.cell_count(),
            edge_lengths: self
                .adaptive
                .as_ref()
                .map(|_| self.complex.edge_length_summary()),
        };
        if quiet_round {
            self.judge_quiet_round(rec.energy);
        }
        // Under noise a fixed step never lets every vertex settle: once the
        // energy has not reached a new low for `STALL_ITERATIONS`, halve the
        // step (down to 1/16 of the parameter).
        let new_low = self.best_energy - self.params.new_low_fraction * rec.energy.abs();
        if !quiet_round && rec.energy < new_low {
            self.best_energy = rec.energy;
            self.stalled = 0;
            self.since_new_low = 0;
        } else {
            self.since_new_low += 1;
            self.stalled += 1;
            if self.stalled >= STALL_ITERATIONS {
                self.step = (self.step * 0.5).max(self.params.step_fraction / 16.0);
                self.stalled = 0;
            }
        }
        if self.relabelling_round(flips_due && iteration > 1 && !reseeded, flips, quiet_round) {
            // The relabelled state gets a whole plateau to relax.
            self.since_new_low = 0;
            self.fall_origin = self.history.len();
        }
        if flips == 0 && self.settled(rec.max_displacement_across) {
            self.quiet_iterations += 1;
        } else {
            self.quiet_iterations = 0;
        }
        self.advance_finish();
        self.history.push(rec.clone());
        rec
    }

    /// Whether iteration `iteration` is a regular flip round: the first,
    /// `flip_interval` iterations after the last one, or a settle round
    /// ([`settle_round_due`](Self::settle_round_due)).
    fn flip_round_due(&self, iteration: usize) -> bool {
        iteration == 1
            || iteration - self.last_flip_round >= self.params.flip_interval.max(1)
            || self.settle_round_due()
    }

    /// Whether the energy plateau is reached, or the energy's fall has
    /// slowed ([`SegmentParams::settle_rate`]), in a run with flip rounds
    /// ([`flip_interval`](SegmentParams::flip_interval) > 1) whose only round
    /// so far was the first iteration's: the labels have not been judged
    /// since the interfaces settled, so the next iteration is a flip round
    /// rather than the end of the run. A run from a coarse start settles
    /// in 10–20 iterations; the three-phase volumes' blurred bands go back
    /// to their sides only at the round after that (stopped before it, the
    /// 64³ three-phase volumes lost 0.009–0.014 of Dice), while a two-phase
    /// volume's round finds the labels in place and, quiet, ends the run.
    fn settle_round_due(&self) -> bool {
        self.params.label_flips
            && self.params.flip_interval > 1
            && self.last_flip_round == 1
            && self
                .params
                .converge_plateau
                .is_some_and(|n| self.since_new_low >= n || self.energy_fall_slowed())
    }

    /// Whether the energy's fall since [`fall_origin`](Self::fall_origin)
    /// has slowed below [`SegmentParams::settle_rate`] ([`energy_fall_slowed`]).
    fn energy_fall_slowed(&self) -> bool {
        let since = &self.history[self.fall_origin.min(self.history.len())..];
        energy_fall_slowed(since, self.params.settle_rate)
    }

    /// Whether a flip round (`round`: one after the first iteration that
    /// re-seeded nothing) relabelled enough cells to restart the plateau
    /// count: in runs with flip rounds, one that was not quiet
    /// ([`quiet_round_fraction`](SegmentParams::quiet_round_fraction)).
    /// Band flips often raise the energy, so without the restart the count
    /// from before the round ended the run a few iterations after it, before
    /// the interfaces had moved into the relabelled cells.
    fn relabelling_round(&self, round: bool, flips: usize, quiet: bool) -> bool {
        round && self.params.flip_interval > 1 && flips > 0 && !quiet
    }

    /// A quiet flip round (fewer flips than
    /// [`quiet_round_fraction`](SegmentParams::quiet_round_fraction) of the
    /// cells) whose state has `energy`: the energy its flips took off does
    /// not count as a new low, so the plateau goes on (the flips are noise
    /// along settled interfaces, and counting them bought ten more
    /// iterations per round), and the lower energy becomes the one to beat.
    /// A quiet round that finds the energy on a plateau for
    /// [`quiet_round_plateau`](SegmentParams::quiet_round_plateau)
    /// iterations (by default half of
    /// [`converge_plateau`](SegmentParams::converge_plateau)), or its fall
    /// slowed ([`SegmentParams::settle_rate`]), ends the run on the state
    /// after it.
    fn judge_quiet_round(&mut self, energy: f64) {
        let needed = self
            .params
            .quiet_round_plateau
            .or_else(|| self.params.converge_plateau.map(|n| n.div_ceil(2)));
        let on_plateau =
            needed.is_some_and(|n| self.since_new_low >= n) || self.energy_fall_slowed();
        if self.params.converge_plateau.is_some() && on_plateau {
            self.quiet_round_on_plateau = true;
        }
        self.best_energy = self.best_energy.min(energy);
    }

    /// Counts down the fine finish, or begins it once the stopping rule is
    /// met: the next deform refines the interfaces to a fraction of `L`;
    /// from the finish's second iteration to its end the bending term
    /// weighs the finish's multiple of β.
    /// A run whose finish a re-seed called off stops without one: its
    /// phases are not settled (a phase lost as a band may be lost again),
    /// and on a CT-like volume whose thin fat class ends as a band the
    /// finish's flip round and finer cells emptied a phase outright. A
    /// re-seed before the finish does not stop it (a start that holds two
    /// phases in one class re-seeds at the first flip round).
    fn advance_finish(&mut self) {
        let Some(finish) = self.params.sizing.finish else {
            return;
        };
        if let Some(left) = &mut self.finish_left {
            *left = left.saturating_sub(1);
            let left = *left;
            if left + 1 == finish.iterations {
                self.raise_rigidity(finish.rigidity_factor);
            }
            if left == 0 {
                self.restore_rigidity();
            }
        } else if self.stopping_rule_met() && !self.finish_called_off && self.reseed_trial.is_none()
        {
            if let Some(adaptive) = &mut self.adaptive {
                adaptive.refine_interfaces(finish.interface_fraction * self.dsc.edge_length);
                self.finish_left = Some(finish.iterations);
            }
        }
    }

    /// Multiplies the bending term's β by `factor` for the finish, keeping
    /// the run's β to restore after it (the report gives the run's).
    fn raise_rigidity(&mut self, factor: f64) {
        if let Some(rigidity) = self.models.force_mut::<Rigidity<K>>() {
            self.rigidity_before_finish = Some(rigidity.beta);
            rigidity.beta *= factor;
        }
    }

    /// Gives the bending term back the run's β once the finish is over or
    /// called off.
    fn restore_rigidity(&mut self) {
        if let Some(beta) = self.rigidity_before_finish.take() {
            if let Some(rigidity) = self.models.force_mut::<Rigidity<K>>() {
                rigidity.beta = beta;
            }
        }
    }

    /// Whether this iteration is the finish's first and the finish begins
    /// with a flip round ([`Finish::flip_round`](super::adaptive::Finish::flip_round)).
    fn finish_flip_round_due(&self) -> bool {
        self.params
            .sizing
            .finish
            .is_some_and(|f| f.flip_round && self.finish_left == Some(f.iterations))
    }

    /// Calls off a finish that has begun: a phase re-seeded in its flip
    /// round starts the evolution over, and the run goes on at `L` until
    /// the stopping rule is met again.
    fn cancel_finish(&mut self) {
        if self.finish_left.take().is_some() {
            self.finish_called_off = true;
            if let Some(adaptive) = &mut self.adaptive {
                adaptive.refine_interfaces(self.dsc.edge_length);
            }
            self.restore_rigidity();
        }
    }

    /// Whether the run ends with a fine finish (adaptive runs with
    /// [`SizingParams::finish`](super::adaptive::SizingParams::finish)).
    fn has_finish(&self) -> bool {
        self.params.sizing.finish.is_some() && self.adaptive.is_some()
    }

    /// Whether a step whose largest displacement across the interface was
    /// `max_displacement` (a fraction of L) moved little enough to count
    /// towards convergence:
    /// below [`converge_displacement`](SegmentParams::converge_displacement)
    /// and, if set, [`converge_pixels`](SegmentParams::converge_pixels).
    fn settled(&self, max_displacement: f64) -> bool {
        let pixels = max_displacement * self.dsc.edge_length;
        max_displacement < self.params.converge_displacement
            && self.params.converge_pixels.is_none_or(|p| pixels < p)
    }

    /// What the next [`step`](Self::step) does before it deforms, without
    /// its flips: the image statistics of the current complex (cached, so
    /// only moved cells are integrated) and the force stage, which runs
    /// every force term (a new force evaluation: the paper's terms compute
    /// their field again, see [`paper_field`](Self::paper_field)) and sets the
    /// destinations. Nothing moves. Returns the largest requested
    /// displacement in units of L. For benchmarks (a second call measures
    /// the forces, the statistics then being unchanged) and inspection; a
    /// force term with state of its own sees one more call.
    pub fn compute_forces(&mut self) -> f64 {
        self.integrate();
        let (_, reach) = self.forces_and_destinations(self.history.len() + 1);
        reach.largest / self.dsc.edge_length
    }

    /// Phase means closer than this are duplicates: 0.3 times the noise's
    /// standard deviation plus a thousandth of the robust range (so
    /// noise-free images need a real difference too). Splitting pure noise
    /// at the least-variance threshold of cell means of 10–20 pixels gives
    /// means about 0.2σ apart (a 256² disk image asked for three phases
    /// ended at 0.21σ), while distinct phases 0.4σ apart (four phases 0.1
    /// apart at σ = 0.25) must stay distinct.
    pub fn duplicate_tolerance(&self) -> f64 {
        0.3 * self.intensity.noise + 1e-3 * self.intensity.scale()
    }

    /// Phases lost now: empty, duplicating another's mean, or shrunk to a
    /// band along the edge between two others.
    pub fn lost_phases(&self) -> Vec<LostPhase> {
        let mut lost = lost_phases(&self.phases, self.duplicate_tolerance());
        lost.extend(self.band_phases());
        lost
    }

    /// The phases that ended as a band along the edge between two others
    /// ([`super::band_phase`]), in runs that model such bands
    /// (`band_flips`; `--keep-thin-layers` says thin layers are real); a
    /// phase already listed lost is not listed again.
    fn band_phases(&self) -> Vec<LostPhase> {
        if !self.params.band_flips {
            return Vec::new();
        }
        let spacing = &self.image.spacing[..K::N];
        let voxel = VoxelSize {
            measure: spacing.iter().product(),
            smallest_side: spacing.iter().copied().fold(f64::INFINITY, f64::min),
        };
        let listed = lost_phases(&self.phases, self.duplicate_tolerance());
        band_phases(
            &self.complex,
            &self.phases,
            &self.initial_range_counts,
            voxel,
        )
        .into_iter()
        .filter(|b| !listed.iter().any(|l| l.label() == b.phase))
        .map(|b| LostPhase::Band {
            phase: b.phase,
            twin: b.nearer,
        })
        .collect()
    }

    /// The phases present in fewer pixels or voxels than one regular cell at
    /// the edge length holds, and not listed lost already: a result with such
    /// a vestige of a phase has one phase fewer than its label values say
    /// (seen on a block of a real brain MRI, where one of four phases ended as one voxel), so
    /// the run warns rather than pass it for one with every phase.
    pub(crate) fn vestige_phases(&self, listed: &[LostPhase]) -> Vec<LostPhase> {
        let voxel: f64 = self.image.spacing[..K::N].iter().product();
        let cell = K::regular_measure(self.dsc.edge_length) / voxel;
        vestiges(&self.phases.count, cell, listed)
    }

    /// The present phases not in `listed` that hold under a quarter of the
    /// pixels or voxels that look like them ([`super::absorbed`]; a pass
    /// over the image at the end of a run). Only where the result answers
    /// for the whole image ([`SegmentParams::claims_whole_image`]).
    fn absorbed_phases(&self, listed: &[LostPhase]) -> Vec<LostPhase> {
        if !self.params.claims_whole_image() {
            return Vec::new();
        }
        let mut by_rank: Vec<(usize, f64)> = (0..self.phases.count.len())
            .filter(|&l| self.phases.count[l] > 0)
            .filter_map(|l| self.phases.mean[l].map(|m| (l, m)))
            .collect();
        by_rank.sort_by(|a, b| a.1.total_cmp(&b.1));
        let mut rank = vec![u8::MAX; self.phases.count.len()];
        for (r, &(l, _)) in by_rank.iter().enumerate() {
            rank[l] = r as u8;
        }
        let means: Vec<f64> = by_rank.iter().map(|&(_, m)| m).collect();
        // (the cells' pixel counts, summed by label after the last
        // integration: those of the label image, which is not made here)
        let count: Vec<u64> = by_rank.iter().map(|&(l, _)| self.phases.count[l]).collect();
        debug_assert_eq!(
            count,
            pixels_by_rank(&self.label_image_with(&rank), count.len()),
            "the cells' pixel counts are the label image's"
        );
        absorbed_by_count(self.check_image.of(&self.image), &count, &means)
            .into_iter()
            .map(|a| LostPhase::Absorbed {
                phase: by_rank[a.rank].0 as Label,
                count: a.count,
                looks_like: a.looks_like,
            })
            .filter(|a| !listed.iter().any(|l| l.label() == a.label()))
            .collect()
    }

    /// The present phases not in `listed` whose plateau another phase shares
    /// within the duplicate tolerance ([`plateau_twins`]; a pass over the
    /// label image at the end of a run), or that are specks of one region
    /// with another, neither with a measured plateau ([`speckled_pairs`]),
    /// the smaller of each pair: the mean
    /// test during the run misses a region that noise divides, whose halves'
    /// means differ by about a third of the noise. Only asked when two
    /// present phases' means are closer than the noise: the halves of a
    /// region split by noise differ by about `2·√(2/π)·σ/√n` for cells of
    /// `n` pixels, under σ for any cell the mesh holds, and most runs skip
    /// the pass (a tenth of a second on a 128³ volume).
    fn shared_plateau_phases(&self, listed: &[LostPhase]) -> Vec<LostPhase> {
        if !any_lost(&self.phases, self.intensity.noise) {
            return Vec::new();
        }
        let order = self.phase_order();
        let mut label_of_rank = vec![0 as Label; order.len()];
        for (label, &rank) in order.iter().enumerate() {
            label_of_rank[rank as usize] = label as Label;
        }
        let labels = self.label_image_with(&order);
        let plateaus = phase_plateaus(&labels, self.image.data, self.image.dims, order.len());
        let means: Vec<Option<f64>> = plateaus.iter().map(|p| p.map(|p| p.mean)).collect();
        let samples: Vec<usize> = plateaus
            .iter()
            .map(|p| p.map_or(0, |p| p.samples))
            .collect();
        let rank_means: Vec<Option<f64>> = label_of_rank
            .iter()
            .map(|&l| self.phases.mean[l as usize].filter(|_| self.phases.count[l as usize] > 0))
            .collect();
        let tolerance = self.duplicate_tolerance();
        let count = |l: Label| self.phases.count[l as usize];
        let smaller_first = |(a, b): (Label, Label)| {
            if count(a) <= count(b) {
                (a, b)
            } else {
                (b, a)
            }
        };
        let shared = plateau_twins(&means, tolerance)
            .into_iter()
            .map(|(a, b)| (label_of_rank[a], label_of_rank[b]))
            .filter(|&(a, b)| count(a) > 0 && count(b) > 0)
            .map(|pair| {
                let (phase, twin) = smaller_first(pair);
                LostPhase::SharedPlateau { phase, twin }
            });
        let speckled = speckled_pairs(&rank_means, &samples, self.intensity.noise, tolerance)
            .into_iter()
            .map(|(a, b)| {
                let (phase, twin) = smaller_first((label_of_rank[a], label_of_rank[b]));
                LostPhase::Speckled { phase, twin }
            });
        let mut found: Vec<LostPhase> = Vec::new();
        for lost in shared.chain(speckled) {
            let taken = |l: &LostPhase| l.label() == lost.label();
            if !listed.iter().any(taken) && !found.iter().any(taken) {
                found.push(lost);
            }
        }
        found
    }

    /// Merges each duplicate phase, and each band along the edge between two
    /// others, into its twin and re-seeds every lost
    /// label by splitting the phase with the most structure beyond noise (at most `2·N`
    /// times a run, so data with fewer phases than asked cannot cycle);
    /// returns how many labels were re-seeded. After a re-seed the length
    /// weight is measured again from the new means and the stopping rule
    /// starts over.
    fn recover_lost_phases(&mut self) -> usize {
        if !self.params.reseed {
            return 0;
        }
        if !any_lost(&self.phases, self.duplicate_tolerance()) && self.band_phases().is_empty() {
            return 0;
        }
        let t = Instant::now();
        let lost: Vec<LostPhase> = self
            .lost_phases()
            .into_iter()
            .filter(|l| !self.refused_reseeds.contains(&l.label()))
            .collect();
        let bands: Vec<Label> = lost
            .iter()
            .filter(|l| matches!(l, LostPhase::Band { .. }))
            .map(LostPhase::label)
            .collect();
        let trial = (!bands.is_empty()).then(|| self.reseed_trial_from_here(bands));
        let mut done = 0;
        for lost in lost {
            if self.reseeds >= 2 * self.params.phases {
                break;
            }
            if let LostPhase::Duplicate { phase, twin } | LostPhase::Band { phase, twin } = lost {
                merge_phase(&mut self.complex, phase, twin);
                self.phases.update(&self.complex, &self.cells);
            }
            let range = (
                self.intensity.low,
                self.intensity.low + self.intensity.scale(),
            );
            if split_most_structured_phase(
                &mut self.complex,
                &self.cells,
                &self.phases,
                lost.label(),
                range,
                self.intensity.noise,
            ) {
                self.reseeds += 1;
                done += 1;
                // The label's initial threshold range is another class's now.
                if let Some(count) = self.initial_range_counts.get_mut(lost.label() as usize) {
                    *count = 0;
                }
            }
            self.phases.update(&self.complex, &self.cells);
        }
        if done > 0 {
            self.reseed_trial = trial.map(|t| ReseedTrial { reseeds: done, ..t });
            self.nu = self.length_weight();
            self.quiet_iterations = 0;
            self.best_energy = f64::INFINITY;
            self.stalled = 0;
            self.since_new_low = 0;
            self.fall_origin = self.history.len();
            self.quiet_round_on_plateau = false;
            self.step = self.params.step_fraction;
        }
        self.times.flips += t.elapsed().as_secs_f64();
        done
    }

    /// The state now, before a round of re-seeds that includes the bands
    /// `bands`, with its energy: what [`judge_reseed_trial`](Self::judge_reseed_trial)
    /// restores if the re-seeds do not lower the energy.
    fn reseed_trial_from_here(&self, bands: Vec<Label>) -> ReseedTrial<K> {
        ReseedTrial {
            complex: self.complex.clone(),
            adaptive: self.adaptive.clone(),
            energy: self.data_energy() + self.nu * self.interface_measure(),
            length_weight: self.nu,
            bands,
            reseeds: 0,
            initial_range_counts: self.initial_range_counts.clone(),
            progress: self.progress(),
        }
    }

    /// At the flip round after a re-seed of a band (or at the end of the
    /// run), with the statistics integrated: keeps the re-seeded state if
    /// its energy is lower than the state's before the re-seed, otherwise
    /// restores that state, counts the re-seeds undone and does not re-seed
    /// those bands again ([`super::reseed_trial`]).
    fn judge_reseed_trial(&mut self) {
        let Some(trial) = self.reseed_trial.take() else {
            return;
        };
        if trial.improved(self.data_energy(), self.interface_measure()) {
            return;
        }
        self.reseeds -= trial.reseeds;
        self.reseeds_undone += trial.reseeds;
        self.refused_reseeds.extend(&trial.bands);
        self.complex = trial.complex;
        self.adaptive = trial.adaptive;
        if self.finish_left.is_none() {
            // A trial begun in the finish's flip round: the finish is off.
            if let Some(adaptive) = &mut self.adaptive {
                adaptive.refine_interfaces(self.dsc.edge_length);
            }
        }
        self.nu = trial.length_weight;
        self.initial_range_counts = trial.initial_range_counts;
        self.restore_progress(trial.progress);
        // The caches are of the re-seeded mesh: start them afresh.
        self.cell_cache = CellCache::new();
        self.force = ForceStage::new(&self.complex);
        self.deform_workspace = DscWorkspace::new();
        self.integrate();
    }

    /// The step size and the stopping rule's counters.
    fn progress(&self) -> RunProgress {
        RunProgress {
            step: self.step,
            best_energy: self.best_energy,
            stalled: self.stalled,
            since_new_low: self.since_new_low,
            fall_origin: self.fall_origin,
            quiet_iterations: self.quiet_iterations,
            quiet_round_on_plateau: self.quiet_round_on_plateau,
        }
    }

    fn restore_progress(&mut self, p: RunProgress) {
        self.step = p.step;
        self.best_energy = p.best_energy;
        self.stalled = p.stalled;
        self.since_new_low = p.since_new_low;
        self.fall_origin = p.fall_origin;
        self.quiet_iterations = p.quiet_iterations;
        self.quiet_round_on_plateau = p.quiet_round_on_plateau;
    }

    /// The segmentation split into the state every model reads (for force
    /// evaluation `self.evaluations`) and the parts the models change.
    fn parts(&mut self, iteration: usize) -> Parts<'_, 'a, K> {
        Parts {
            state: IterationState {
                image: &self.image,
                intensity: &self.intensity,
                phases: &self.phases,
                cells: &self.cells,
                params: &self.params,
                range: self.range,
                edge_length: self.dsc.edge_length,
                length_weight: self.nu,
                iteration,
                evaluation: self.evaluations,
            },
            complex: &mut self.complex,
            force: &mut self.force,
            models: &mut self.models,
            helper: self.helper.here(),
            step: self.step,
        }
    }

    /// Runs the label rules; returns how many cells changed label.
    fn relabel(&mut self, iteration: usize) -> usize {
        let t = Instant::now();
        let Parts {
            state,
            complex,
            models,
            ..
        } = self.parts(iteration);
        let mut flips = 0;
        for rule in &mut models.rules {
            flips += rule.relabel(complex, &state);
        }
        if flips > 0 {
            self.phases.update(&self.complex, &self.cells);
        }
        self.times.flips += t.elapsed().as_secs_f64();
        flips
    }

    /// The forces of iteration `iteration`
    /// ([`forces_and_destinations`](Self::forces_and_destinations)) if no
    /// label rule would change a label, `None` if one would: the flips then
    /// come first and the forces are computed after them. With the helper
    /// thread the rules are asked there while the forces are computed (their
    /// time hidden behind the forces'); without it, or while it rests, they
    /// are asked first, so that an iteration that flips computes its forces
    /// once.
    fn forces_unless_relabelling(&mut self, iteration: usize) -> Option<(f64, Reach)> {
        let helper = self.helper.here();
        if !helper.is_threaded() || helper.is_resting() {
            let Parts {
                state,
                complex,
                models,
                ..
            } = self.parts(iteration);
            let answer = would_relabel(&mut models.rules, complex, &state);
            return (!self.predicts_flips(answer)).then(|| self.forces_and_destinations(iteration));
        }
        self.evaluations += 1;
        let Parts {
            state,
            complex,
            force,
            models,
            helper,
            step,
        } = self.parts(iteration);
        let complex = &*complex;
        let (terms, rules) = (&mut models.forces, &mut models.rules);
        let (reach, answer) = helper.join(
            || force.run(terms, complex, &state, step),
            || would_relabel(rules, complex, &state),
        );
        let computed = (self.interface_length(), reach);
        (!self.predicts_flips(answer)).then_some(computed)
    }

    /// Whether the rules' `answer` ([`would_relabel`]) is that a label
    /// would change; a rule that cannot tell counts as yes, and turns the
    /// predictions off for the run.
    fn predicts_flips(&mut self, answer: Option<bool>) -> bool {
        if answer.is_none() {
            self.predict_flips = false;
        }
        answer.unwrap_or(true)
    }

    /// Computes the forces of iteration `iteration` and fills the
    /// destinations; returns the interface measure and the largest
    /// displacements (pixels).
    fn forces_and_destinations(&mut self, iteration: usize) -> (f64, Reach) {
        self.evaluations += 1;
        let Parts {
            state,
            complex,
            force,
            models,
            step,
            ..
        } = self.parts(iteration);
        let reach = force.run(&mut models.forces, complex, &state, step);
        (self.interface_length(), reach)
    }

    /// The interface measure of the current mesh for the energy's length
    /// term: [`interface_measure`](Self::interface_measure), or taken from
    /// the paper's field when the last force evaluation computed it (the
    /// same sum in the same order).
    fn interface_length(&self) -> f64 {
        match self.models.paper_field(self.evaluations) {
            Some(f) => f.field().interface_measure,
            None => self.interface_measure(),
        }
    }

    /// The warning of a run stopped because its labels swap.
    fn swap_warning(&self) -> String {
        let last = self.history.last().map_or((0, 0), |r| (r.flips, r.cells));
        format!(
            "the run stopped after {} iterations because its labels swapped between states \
             instead of settling ({} of {} cells relabelled in each of the last \
             {SWAP_ITERATIONS}): where the image holds fewer phases than the {} asked for, two \
             phases divide one region between them by noise (--phases auto chooses the count); \
             on an image of a few pixels, its regions are smaller than the mesh's cells",
            self.history.len(),
            last.0,
            last.1,
            self.params.phases
        )
    }

    /// Whether each of the last [`SWAP_ITERATIONS`] iterations relabelled
    /// more than [`SWAP_SHARE`] of the cells while the energy reached no
    /// new low: the labels swap between states rather than settle, and
    /// [`run`](Self::run) stops. (A run from a poor start relabels as much
    /// in its first iterations, but its energy falls.)
    pub fn labels_swapping(&self) -> bool {
        self.history.len() >= SWAP_ITERATIONS
            && self.since_new_low >= SWAP_ITERATIONS
            && self.history[self.history.len() - SWAP_ITERATIONS..]
                .iter()
                .all(|r| r.flips as f64 > SWAP_SHARE * r.cells as f64)
    }

    /// Whether the stopping rule is met and the fine finish, if any, has
    /// run.
    pub fn converged(&self) -> bool {
        if self.reseed_trial.is_some() {
            false
        } else if self.finishes() {
            self.finish_left == Some(0)
        } else {
            self.stopping_rule_met()
        }
    }

    /// Whether the run ends with its fine finish: adaptive runs with one,
    /// unless a re-seed called it off (such a run stops on the stopping
    /// rule, see [`advance_finish`](Self::advance_finish)).
    fn finishes(&self) -> bool {
        self.has_finish() && !self.finish_called_off
    }

    /// Whether the stopping rule (displacement or energy plateau, or a quiet
    /// flip round on a plateau) is met. The plateau counts only while the
    /// label flips are on: without them the interfaces travel the whole way
    /// from their start (the paper's single-region evolutions, a model
    /// pushing them), and a front crossing a region lowers the energy by
    /// less per iteration than the plateau's new-low fraction of it.
    fn stopping_rule_met(&self) -> bool {
        let on_plateau = self.params.label_flips
            && (self
                .params
                .converge_plateau
                .is_some_and(|n| self.since_new_low >= n)
                || self.quiet_round_on_plateau);
        self.quiet_iterations >= self.params.converge_iterations
            || (on_plateau && !self.settle_round_due() && self.calm() && self.sizing_settled())
    }

    /// Whether the last iteration flipped nothing, where flips run every
    /// iteration (2D; always true between 3D's flip rounds), or on an
    /// adaptive 2D mesh at most [`ADAPTIVE_CALM_FLIPS`] of the cells: the
    /// energy plateau ends a run only then. Flips that go on while the
    /// energy stalls are interfaces still being rebuilt (under strong
    /// noise, two close phases at a junction); stopping among them lost up
    /// to 0.0036 of Dice on the hard phantoms (`docs/parameters.md`, "Step
    /// gain").
    fn calm(&self) -> bool {
        let few = |flips: usize, cells: usize| {
            K::N == 2
                && self.adaptive.is_some()
                && flips as f64 <= ADAPTIVE_CALM_FLIPS * cells as f64
        };
        self.params.flip_interval > 1
            || self
                .history
                .last()
                .is_none_or(|r| r.flips == 0 || few(r.flips, r.cells))
    }

    /// Whether the sizing field has settled, as far as the plateau rule is
    /// concerned: always for the uniform mesh and for adaptive runs without
    /// [`settle`](super::adaptive::SizingParams::settle) (3D); otherwise once
    /// it settled, so that a run still finding thin detail (each find
    /// lowers the energy by little) goes on.
    fn sizing_settled(&self) -> bool {
        self.params.sizing.settle.is_none()
            || self
                .adaptive
                .as_ref()
                .is_none_or(AdaptiveSizing::is_settled)
    }

    /// Iterates until the built-in stopping rule ([`converged`](Self::converged))
    /// or the cap; `progress` sees every record.
    pub fn run(&mut self, mut progress: impl FnMut(&IterationRecord)) -> SegmentReport {
        self.run_loop(true, |s, rec| {
            progress(rec);
            if s.converged() || s.labels_swapping() {
                Flow::Stop
            } else {
                Flow::Continue
            }
        })
    }

    /// Iterates until `observe` returns [`Flow::Stop`] or
    /// [`SegmentParams::max_iterations`] is reached. The built-in stopping
    /// rule is *not* applied: call [`converged`](Self::converged) in the
    /// observer to keep it, or replace it with your own. The observer sees
    /// the segmentation after each step, so it may record a snapshot, change
    /// parameters or models, and read statistics.
    pub fn run_until(
        &mut self,
        observe: impl FnMut(&mut Self, &IterationRecord) -> Flow,
    ) -> SegmentReport {
        self.run_loop(false, observe)
    }

    /// The segmentation loop. With `builtin_rule` (the loop of
    /// [`run`](Self::run)) the built-in rule is tested before the first step
    /// too, and a stop that is not convergence is the swap rule's; a stop by
    /// [`run_until`](Self::run_until)'s observer is its own, whatever the
    /// labels did.
    fn run_loop(
        &mut self,
        builtin_rule: bool,
        mut observe: impl FnMut(&mut Self, &IterationRecord) -> Flow,
    ) -> SegmentReport {
        let t0 = Instant::now();
        let mut stopped = false;
        while self.history.len() < self.params.max_iterations
            && !(builtin_rule && self.converged())
            && !crate::cancel::requested()
        {
            let rec = self.step();
            if observe(self, &rec) == Flow::Stop {
                stopped = true;
                break;
            }
        }
        self.integrate();
        self.judge_reseed_trial();
        let final_energy = self.data_energy() + self.nu * self.interface_measure();
        self.times.total = self.times.setup + t0.elapsed().as_secs_f64();
        let converged = self.converged();
        let stop_reason = if converged {
            StopReason::Converged
        } else if stopped && builtin_rule && self.labels_swapping() {
            StopReason::SwappingLabels
        } else if stopped {
            StopReason::Stopped
        } else {
            StopReason::MaxIterations
        };
        let order = self.phase_order();
        let mut lost = self.lost_phases();
        lost.extend(self.vestige_phases(&lost));
        lost.extend(self.absorbed_phases(&lost));
        lost.extend(self.shared_plateau_phases(&lost));
        let lost_phase_warnings: Vec<String> = lost
            .iter()
            .map(|l| {
                let undone = if self.refused_reseeds.contains(&l.label()) {
                    "; it was a band along the edge between two other phases earlier, \
                     and re-seeding it raised the energy"
                } else {
                    ""
                };
                format!(
                    "{}{undone}: the result has fewer than the {} distinct phases asked for (the image may hold fewer)",
                    l.describe(&order),
                    self.params.phases
                )
            })
            .collect();
        let mut warnings = lost_phase_warnings.clone();
        match stop_reason {
            StopReason::MaxIterations => warnings.push(cap_warning(self.params.max_iterations)),
            StopReason::SwappingLabels => warnings.push(self.swap_warning()),
            _ => {}
        }
        let final_means = self.present_means();
        warnings.extend(correlated_noise_warning(&self.intensity, &final_means));
        SegmentReport {
            edge_length: self.dsc.edge_length,
            iterations: self.history.len(),
            converged,
            stop_reason,
            final_means,
            final_energy,
            length_weight_abs: self.nu,
            rigidity: self.models.force::<Rigidity<K>>().map(|r| r.beta),
            force_smoothing: self
                .models
                .force::<RegionForce<K>>()
                .map(RegionForce::smoothing),
            intensity: self.intensity.clone(),
            initial_thresholds: self.initial_thresholds.clone(),
            reseeds: self.reseeds,
            reseeds_undone: self.reseeds_undone,
            warnings,
            lost_phase_warnings,
            history: self.history.clone(),
            times: self.times,
            vertices: self.complex.vertex_count(),
            cells: self.complex.cell_count(),
            sizes: self.adaptive.as_ref().map(AdaptiveSizing::sizes),
            coarse_pass: self.coarse_pass.clone(),
            missed_objects: None,
            shading: None,
        }
    }

    /// Adaptive runs: the sizing field for the next deform, from the
    /// current interfaces and statistics.
    fn update_sizing(&mut self) {
        if let Some(adaptive) = &mut self.adaptive {
            // Settled: the energy stalls and no new detail was found.
            if adaptive.new_requests == 0
                && self
                    .params
                    .sizing
                    .settle
                    .is_some_and(|n| self.since_new_low >= n)
            {
                adaptive.settle();
            }
            let field = adaptive.update(&self.complex, &self.cells, &self.phases);
            self.deform_workspace.copy_sizing(field);
        }
    }

    /// Total interface measure of the current mesh, summed facet by facet
    /// along [`Complex::interface_facets`].
    pub fn interface_measure(&self) -> f64 {
        self.complex
            .interface_facets()
            .fold(0.0, |total, f| total + f.measure)
    }

    /// Mesh label → output phase index, phases ordered by increasing mean,
    /// empty phases last in label order (the mean an empty phase keeps for
    /// the flips is the mean of nothing). The numbering is that of the
    /// current state: while a phase is empty mid-run, the phases above it
    /// shift down until it is re-seeded.
    pub fn phase_order(&self) -> Vec<u8> {
        let n = self.params.phases;
        let means = self.present_means();
        let mut idx: Vec<usize> = (0..n).collect();
        idx.sort_by(|&a, &b| {
            let ma = means[a].unwrap_or(f64::INFINITY);
            let mb = means[b].unwrap_or(f64::INFINITY);
            ma.total_cmp(&mb).then(a.cmp(&b))
        });
        let mut map = vec![0u8; n];
        for (rank, &l) in idx.iter().enumerate() {
            map[l] = rank as u8;
        }
        map
    }

    /// The final labelling rasterised per pixel (pixel-centre rule), values
    /// `0..N` ordered by increasing phase mean.
    pub fn label_image(&self) -> Vec<u8> {
        self.label_image_with(&self.phase_order())
    }

    /// The labelling rasterised per pixel, each mesh label `l` written as
    /// `map[l]` (labels past the map's end as its last entry).
    fn label_image_with(&self, map: &[u8]) -> Vec<u8> {
        let mut out = vec![0u8; self.image.len()];
        for c in self.complex.cell_ids() {
            let l = map[(self.complex.label(c) as usize).min(map.len() - 1)];
            let pts = self.complex.cell_points(c);
            K::cell_pixels(&self.image, &pts[..K::NV], &mut |p| out[p] = l);
        }
        out
    }
}

/// Whether the energy of `history` has slowed its fall: over the last
/// [`SETTLE_SPAN`] iterations it fell by less, per iteration, than `rate`
/// times its fastest fall in one iteration. The interfaces have reached the
/// data's edges, and what is left is the slow relaxation of noise-sized
/// bumps ([`SegmentParams::settle_rate`]). Never with a `rate` of 0, nor on
/// an energy that never fell.
fn energy_fall_slowed(history: &[IterationRecord], rate: f64) -> bool {
    if rate <= 0.0 || history.len() <= SETTLE_SPAN {
        return false;
    }
    let fastest = history
        .windows(2)
        .map(|w| w[0].energy - w[1].energy)
        .fold(0.0, f64::max);
    let last = history.len() - 1;
    let mean_recent =
        (history[last - SETTLE_SPAN].energy - history[last].energy) / SETTLE_SPAN as f64;
    fastest > 0.0 && mean_recent < rate * fastest
}

/// Whether one of `rules` would change a label
/// ([`LabelRule::would_relabel`]),
/// asking them in order until one says yes; `None` if a rule asked cannot
/// tell.
fn would_relabel<K: Raster>(
    rules: &mut [Box<dyn LabelRule<K>>],
    complex: &Complex<K>,
    state: &IterationState<'_, '_>,
) -> Option<bool> {
    for rule in rules {
        if rule.would_relabel(complex, state)? {
            return Some(true);
        }
    }
    Some(false)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn history(energies: &[f64]) -> Vec<IterationRecord> {
        energies
            .iter()
            .enumerate()
            .map(|(i, &energy)| IterationRecord {
                iteration: i + 1,
                energy,
                data_energy: energy,
                length: 0.0,
                flips: 0,
                max_displacement: 0.0,
                max_displacement_across: 0.0,
                means: Vec::new(),
                junctions: (0, 0),
                cells: 0,
                edge_lengths: None,
            })
            .collect()
    }

    #[test]
    fn the_energy_fall_slows_against_its_fastest_step() {
        // A fall of 100, then 2 per iteration: 2 < 0.05 · 100.
        let slowed = history(&[1000.0, 900.0, 898.0, 896.0, 894.0]);
        assert!(energy_fall_slowed(&slowed, 0.05));
        assert!(!energy_fall_slowed(&slowed, 0.0), "0 turns the rule off");
        assert!(!energy_fall_slowed(&slowed, 0.01));
        // Too short to measure a fall over 3 iterations.
        assert!(!energy_fall_slowed(&slowed[..3], 0.05));
        // Still falling by 10 per iteration.
        let falling = history(&[1000.0, 900.0, 890.0, 880.0, 870.0]);
        assert!(!energy_fall_slowed(&falling, 0.05));
        // An energy that never fell has no rate to slow from.
        let flat = history(&[1000.0, 1000.0, 1001.0, 1001.0, 1001.0]);
        assert!(!energy_fall_slowed(&flat, 0.05));
    }
}
