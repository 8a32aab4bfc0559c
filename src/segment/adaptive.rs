//! Adaptive resolution: the sizing field the segmentation gives the DSC each
//! iteration, fine where the data has detail, coarse where it is flat.
//!
//! The field starts at the coarsest size `h_max` everywhere and is lowered
//!
//! - to the interface size `L` (the average edge length of the uniform
//!   mesh) at every cell touching an interface, so interfaces keep the
//!   resolution of the paper's mesh;
//! - towards `h_min` wherever the data is not explained: a cell away from
//!   every interface whose pixels deviate from its phase's mean clearly more
//!   than the noise does (its excess residual above the estimated noise is
//!   both statistically significant and worth at least one smallest cell of
//!   mislabelled pixels). Such a cell asks for a third of its size at its
//!   centroid. Requests away from the interfaces are remembered for the
//!   whole run (they mark structure, which does not go away), so a thin line
//!   or a small blob ends up in cells small enough for the label flips to
//!   give it its own phase; requests of cells touching an interface hold for
//!   one iteration (the interface may be passing through) and, in 2D, must
//!   exceed a whole pixel layer across the cell (a blurred edge leaves less), so an
//!   interface that cannot fit the data at size `L` (a thin line once
//!   labelled, a sharp corner) is refined for as long as it does not fit;
//! - in 2D, to `h_min` at every pinch, where one phase's cells touch at a
//!   vertex only (a thin line narrowed to a point), for the iteration;
//!
//! then limited in gradation. Everything else coarsens towards `h_max`
//! (interior collapses in `resize`), so cells far from every interface in
//! homogeneous regions are few. The run starts from the uniform mesh at `L`
//! and coarsens, or (`coarse_start`) from a mesh at `h_max` and refines
//! around the interfaces and the unexplained detail (coarse to fine); in
//! 2D that start is graded before it is labelled
//! ([`AdaptiveSizing::grade_start`]).
//!
//! In 2D the field settles ([`SizingParams::settle`]): once the energy has
//! not reached a new low for a few iterations and no new detail was found
//! away from the interfaces, cells at interfaces stop asking for
//! refinement. Along blurred edges between phases whose means are not
//! adjacent, such cells kept asking, were refined, fitted, were coarsened
//! and asked again: a field that changes every iteration keeps the mesh
//! splitting and collapsing cells and the labels flipping, so the stopping
//! rule never fired. Settled, the interfaces keep `L` and the requests away
//! from them stand (and may still grow where new detail is found), and the
//! energy-plateau rule may stop the run.

use super::integrate::{CellStats, PhaseStats};
use super::SegmentError;
use crate::complex::{CellId, Complex, VertexKind};
use crate::dim::{Dim, Point};
use crate::dsc::SizingField;
use serde::{Deserialize, Serialize};

/// The adaptive-resolution options of a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SizingParams {
    /// Whether the mesh is adaptive (`false`: the paper's uniform mesh at `L`).
    pub adaptive: bool,
    /// Smallest target edge length `h_min`, in the image's length unit
    /// like `L` (`None`: 1.5 sample steps).
    pub min_edge_length: Option<f64>,
    /// Largest target edge length `h_max`, in the image's length unit
    /// (`None`: the smallest image extent / 16 in 2D, / 10 in 3D, at least
    /// `L`).
    pub max_edge_length: Option<f64>,
    /// Gradation `g`: `h(a) ≤ h(b) + g·|a − b|`, so neighbouring cells of
    /// size about `h` differ by at most a factor of about `1 + g`.
    pub gradation: f64,
    /// A cell's excess residual must exceed this many standard deviations
    /// of the noise's residual to ask for refinement.
    pub residual_sigmas: f64,
    /// Whether the run starts from a mesh at `h_max` (coarse to fine) rather
    /// than at `L`: the initialisation then labels coarse cells, and detail
    /// smaller than them must be found again by refinement. In 2D the
    /// start is first refined where its cells mix the classes of the
    /// initial thresholds ([`AdaptiveSizing::grade_start`]), so the first
    /// labels keep that detail.
    #[serde(default)]
    pub coarse_start: bool,
    /// Cells at interfaces stop asking for refinement once the energy has
    /// not reached a new low for this many iterations and no new detail was
    /// found away from the interfaces (`None`: they ask to the end).
    /// Refinement keeps asking where the blur of an edge leaves a residual,
    /// and a field that keeps changing keeps the mesh splitting and
    /// collapsing the same cells: once the energy no longer falls, the
    /// interfaces' refinement has done its work.
    #[serde(default)]
    pub settle: Option<usize>,
    /// Coarse starts: how many times the start mesh is refined before the
    /// first iteration (labelled, the field updated, the mesh resized to it
    /// and labelled again), so that the first iteration starts with the
    /// interfaces within about `L` of where the initialisation's thresholds
    /// put them. Without, the start's coarse cells are refined around their
    /// interfaces over the first iterations, each keeping its parent's
    /// label, and the interfaces then travel the rest of the way at a
    /// fraction of `L` per iteration. 0, the default, keeps that: on the
    /// three- and four-phase 64³ phantoms the refined start lowered the
    /// Dice (0.902–0.926 against 0.920–0.952), on the brain-like phantom it
    /// raised it in fewer iterations (benches/RESULTS.md, "Speed, 3D").
    #[serde(default)]
    pub start_refinements: usize,
    /// Once the stopping rule is met, the interfaces are refined to a
    /// fraction of `L` and the run goes on for a few iterations without
    /// label flips (`None`: it stops there; the 3D defaults are
    /// [`Finish::TWO_PHASE`] and [`Finish::MULTIPHASE`]). See [`Finish`].
    #[serde(default)]
    pub finish: Option<Finish>,
}

/// The fine finish of an adaptive run: once the stopping rule is met, the
/// cells with a facet on an interface ask for `interface_fraction·L` (at
/// least `h_min`, and at least [`single_sample_edge`]: the finish refines
/// no cell below the one sample it needs to hold) and the run goes on for
/// `iterations` more iterations, then stops. The first of them may be a
/// last flip round (`flip_round`); the others flip no label. The resize
/// splits an edge longer than twice the size asked for, so below
/// `L` = 2·2.04 voxels (the 3D default `L` = 3 among them) the floor leaves
/// few interface edges to split, and the finish is mostly its iterations
/// without flips on the surface at `L`; the figures below were measured
/// with the refinement to `L/2`, before the floor.
///
/// Why: a surface of flat facets about `L` long cuts a curved interface a
/// fraction of a voxel inside or outside of it depending on where its
/// vertices lie, and where they lie depends on the path the run took (a
/// coarse cell flipped or not at the first flip round). Two runs on data
/// that differ by a re-quantisation ended on equally good surfaces (Dice
/// 0.9905–0.9960 between them on the 48³ two-phase phantoms); refined at
/// the end, both surfaces follow the same data closer (0.9924–0.9968).
/// With three or more phases the same holds, and the runs also part
/// where the last flip round left a thin layer of an intermediate phase
/// along a blurred edge: see [`Finish::MULTIPHASE`]. The runs do not part
/// because they stop mid-motion: over the last iterations of a 5-iteration
/// finish their labels changed by 0.06–0.2 % per iteration, and going on until nothing
/// moves changed the
/// agreement between two encodings by under 0.001; each run rests on a
/// surface of its own, and a stiffer one at the end rests closer to the
/// other's ([`Finish::rigidity_factor`], not the default: it cost the
/// brain phantom's folded layers Dice).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Finish {
    /// The interface size of the finish, as a fraction of `L`.
    pub interface_fraction: f64,
    /// Iterations of the finish: the first moves the interfaces and
    /// refines the mesh around them, the others move the refined surface.
    pub iterations: usize,
    /// Whether the finish's first iteration is a flip round (every label
    /// rule, the blurred-band flips among them), whatever the flip
    /// interval: the layers of an intermediate phase that formed along
    /// blurred edges since the last regular round are given back before
    /// the surface is refined.
    #[serde(default)]
    pub flip_round: bool,
    /// The rigidity β of the finish's iterations after its first, as a
    /// multiple of the run's (1: the run's β; the run's is restored after
    /// the finish, and is the one reported). Each vertex of a surface
    /// refined to `L/2` averages the region force over a quarter of the
    /// area it did at `L`, so it follows more of the noise; a stiffer surface rests
    /// where the data put it over a wider patch, and two runs that took
    /// different paths rest closer together. The first iteration keeps the
    /// run's β: after a flip round its relabelled cells leave jagged
    /// interfaces, which a stiff bending term moved by nearly `L` at once
    /// (1.45× the CPU time of a 64³ three-phase run). 4, measured with the
    /// 5-iteration multiphase finish (four stiff iterations), raised the
    /// Dice against the truth and between encodings on all eight 64³
    /// three- and four-phase phantoms but lowered the brain phantom's from
    /// 0.9705 to 0.9668 (benches/RESULTS.md, "Encoding stability, 3D"), so
    /// both defaults keep 1.
    #[serde(default = "unit_factor")]
    pub rigidity_factor: f64,
}

/// The default of [`Finish::rigidity_factor`]: the run's rigidity.
fn unit_factor() -> f64 {
    1.0
}

impl Finish {
    /// The 3D two-phase default: interfaces at `L/2` (not below
    /// [`single_sample_edge`]) for 2 iterations (the first moves the surface
    /// at `L` and refines it, the second moves the refined surface). Against 3 iterations, 2 save 8–10 % of a 64³ or
    /// 128³ run's instructions and move the Dice against the truth by −0.0003
    /// to +0.0004 on the 64³ and 128³ two-phase phantoms (−0.0006 on the
    /// 48³ two balls); the 64-level re-encodings of the 48³ ones stay at
    /// Dice 0.992–0.996 from the 8-bit runs (benches/RESULTS.md, "Speed,
    /// 3D", "A shorter fine finish").
    /// Not for more phases: on the three- and four-phase phantoms, finer
    /// cells along the blurred edges between phases whose means are not
    /// adjacent let the interfaces between the intermediate phases fit
    /// thin layers of them, and the Dice fell by 0.005–0.008 (a 6-iteration
    /// finish, measured before the blurred-band flips); see
    /// [`Finish::MULTIPHASE`].
    pub const TWO_PHASE: Finish = Finish {
        interface_fraction: 0.5,
        iterations: 2,
        flip_round: false,
        rigidity_factor: 1.0,
    };

    /// The 3D default for three or more phases: a last flip round, which
    /// also refines the interfaces to `L/2`, then one move of the refined
    /// surface (2 iterations, as with two phases). The flip round gives
    /// back the thin layers of intermediate phases that formed along
    /// blurred edges since the regular round, before the finer cells fit
    /// them.
    ///
    /// Why 2 and not more: the refined surface's first move brings what the
    /// finish gives the Dice against the truth, and later moves mostly
    /// follow the noise. Read off each run's own per-iteration Dice on 30
    /// three- and four-phase phantoms (48³–128³, σ 0.1 and 0.2), stopping
    /// after 2 finish iterations instead of 5 gave −0.0012 to +0.0015
    /// (higher on 20, lower on 8; the brain phantom −0.0010) for 9–27 % of
    /// the iterations' time. The 64³ runs on 64-level re-encodings agree
    /// with the 8-bit runs at Dice 0.9888–0.9917 (three phases, above no
    /// finish's 0.9851–0.9882) and 0.9805–0.9888 (four phases; at σ 0.2
    /// 0.9805–0.9806, below no finish's 0.9821–0.9829), 0.0007–0.0020
    /// below the 5-iteration finish (benches/RESULTS.md, "Speed, 3D", "A
    /// 2-iteration finish with three or more phases").
    pub const MULTIPHASE: Finish = Finish {
        interface_fraction: 0.5,
        iterations: 2,
        flip_round: true,
        rigidity_factor: 1.0,
    };

    /// The 3D default finish of a run with `phases` phases.
    pub fn for_phases(phases: usize) -> Finish {
        if phases == 2 {
            Finish::TWO_PHASE
        } else {
            Finish::MULTIPHASE
        }
    }
}

impl Default for SizingParams {
    fn default() -> Self {
        SizingParams {
            adaptive: false,
            min_edge_length: None,
            max_edge_length: None,
            gradation: 1.0,
            residual_sigmas: 5.0,
            coarse_start: false,
            settle: None,
            start_refinements: 0,
            finish: None,
        }
    }
}

/// An unexplained cell asks for this fraction of its longest edge: below
/// `1/√5`, so that resizing (which splits cells above 5 times the regular
/// measure of `h`) splits it.
const REFINE_FACTOR: f64 = 0.3;

/// A cell's mean must deviate from its phase's by this many standard errors
/// (`σ̂/√n`) to ask for refinement on that ground alone.
const MEAN_SHIFT_SIGMAS: f64 = 4.0;

/// The smallest target edge length when none is given.
pub const DEFAULT_MIN_EDGE_LENGTH: f64 = 1.5;

/// The default `h_max` is the smallest extent divided by this: 16 in 2D,
/// 10 in 3D, where a cell of the same relative size holds far fewer voxels
/// (a 64³ volume's interior cells then hold about 40 voxels, a 512² image's
/// about 500 pixels).
fn default_coarsening(dimension: usize) -> f64 {
    if dimension >= 3 {
        10.0
    } else {
        16.0
    }
}

/// The resolved sizes of a run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Sizes {
    /// Smallest target edge length.
    pub h_min: f64,
    /// Target edge length at interfaces (`L`).
    pub interface: f64,
    /// Largest target edge length.
    pub h_max: f64,
    /// Edge length of the initial mesh (`L`, or `h_max` for a coarse start).
    pub start: f64,
    /// The image's sample step in the same unit (1 for unit pixels/voxels):
    /// converts lengths to sample counts where the data term counts samples.
    pub sample_step: f64,
}

impl SizingParams {
    /// The sizes for an image of `dimension` axes whose smallest extent is
    /// `extent` and whose sample step is `step` (both in the spacing's
    /// unit: see [`sample_step`](crate::segment::params::sample_step)),
    /// and interface edge length `l`: `h_min ≤ L ≤ h_max`. The defaults
    /// scale with the grid, so a volume gets the same mesh whatever the
    /// unit its voxel size is given in.
    pub fn sizes(&self, dimension: usize, extent: f64, step: f64, l: f64) -> Sizes {
        let h_max = self
            .max_edge_length
            .unwrap_or(extent / default_coarsening(dimension))
            .max(l);
        let h_min = self
            .min_edge_length
            .unwrap_or(DEFAULT_MIN_EDGE_LENGTH * step)
            .min(l);
        let h_max = h_max.min(extent);
        Sizes {
            h_min,
            interface: l,
            h_max,
            start: if self.coarse_start { h_max } else { l },
            sample_step: step,
        }
    }

    /// Checks the values.
    pub fn validate(&self) -> Result<(), SegmentError> {
        let check = |name: &'static str, v: f64, ok: bool, range: &'static str| {
            if ok && v.is_finite() {
                Ok(())
            } else {
                Err(SegmentError::Param(name, v, range))
            }
        };
        let positive = "must be a positive number";
        if let Some(v) = self.min_edge_length {
            check("min_edge_length", v, v > 0.0, positive)?;
        }
        if let Some(v) = self.max_edge_length {
            check("max_edge_length", v, v > 0.0, positive)?;
        }
        if let (Some(a), Some(b)) = (self.min_edge_length, self.max_edge_length) {
            check(
                "min_edge_length",
                a,
                a <= b,
                "must not exceed max_edge_length",
            )?;
        }
        check("gradation", self.gradation, self.gradation > 0.0, positive)?;
        check(
            "residual_sigmas",
            self.residual_sigmas,
            self.residual_sigmas > 0.0,
            positive,
        )?;
        if let Some(finish) = &self.finish {
            let factor = finish.rigidity_factor;
            check("finish_rigidity", factor, factor > 0.0, positive)?;
        }
        Ok(())
    }
}

/// What the adaptive sizing keeps across iterations.
#[derive(Clone, Debug)]
pub struct AdaptiveSizing {
    sizes: Sizes,
    gradation: f64,
    residual_sigmas: f64,
    /// The refinement requests so far (lowered only), on the field's grid.
    requests: SizingField,
    /// The field of the last update.
    field: SizingField,
    /// The field of the last update before its gradation was limited: when
    /// an update lowers the same samples, the limited field is the last one.
    unlimited: SizingField,
    /// Buffers kept so that an update copies no grid into a new allocation:
    /// the field being built, and the padded grid of the gradation sweeps.
    building: SizingField,
    sweeps: Vec<f64>,
    /// Cells that asked for refinement in the last update.
    pub last_requests: usize,
    /// Cells away from the interfaces that asked for a finer size than any
    /// request before at their place, in the last update: detail still
    /// being found.
    pub new_requests: usize,
    /// The estimated noise variance of the last update.
    pub noise_variance: f64,
    /// Whether the field has settled (see [`SizingParams::settle`]).
    settled: bool,
    /// The size cells at interfaces ask for: `L`, finer in the
    /// [`Finish`].
    interface: f64,
    /// The finest size the [`Finish`] asks for: `h_min`, and not below
    /// [`single_sample_edge`].
    finest_interface: f64,
}

impl AdaptiveSizing {
    /// The sizing of a run on the domain `[lo, hi]` of a `K` complex.
    pub fn new<K: Dim>(params: &SizingParams, sizes: Sizes, lo: K::Point, hi: K::Point) -> Self {
        let (lo, hi) = (coords::<K>(lo), coords::<K>(hi));
        let spacing = grid_spacing(&sizes);
        let requests = SizingField::constant(&lo, &hi, K::N, spacing, sizes.h_max);
        AdaptiveSizing {
            sizes,
            gradation: params.gradation,
            residual_sigmas: params.residual_sigmas,
            field: requests.clone(),
            unlimited: SizingField::uniform(),
            building: requests.clone(),
            sweeps: Vec::new(),
            requests,
            last_requests: 0,
            new_requests: 0,
            noise_variance: 0.0,
            settled: false,
            interface: sizes.interface,
            finest_interface: sizes.h_min.max(single_sample_edge::<K>(sizes.sample_step)),
        }
    }

    /// The resolved sizes.
    pub fn sizes(&self) -> Sizes {
        self.sizes
    }

    /// Whether the field has settled: cells at interfaces no longer ask
    /// for refinement.
    pub fn is_settled(&self) -> bool {
        self.settled
    }

    /// Settles the field (see [`SizingParams::settle`]).
    pub fn settle(&mut self) {
        self.settled = true;
    }

    /// From the next update on, cells with a facet on an interface ask for
    /// `size` (at least `h_min` and [`single_sample_edge`]) instead of `L`
    /// (see [`Finish`]).
    pub fn refine_interfaces(&mut self, size: f64) {
        self.interface = size.max(self.finest_interface).min(self.sizes.interface);
    }

    /// The size cell `c`, which touches an interface, asks for: `L`; in the
    /// [`Finish`], the finer size if one of its facets lies on the
    /// interface. The finish refines the surface's facets; a cell touching
    /// the interface only at a vertex or an edge holds none of them, and
    /// refining it too (a band of cells around the surface) cost a third
    /// more tetrahedra for the same surface.
    fn interface_size<K: Dim>(&self, complex: &Complex<K>, c: CellId) -> f64 {
        let holds_surface = || (0..K::NV).any(|i| complex.is_interface_facet(c, i));
        if self.interface < self.sizes.interface && holds_surface() {
            self.interface
        } else {
            self.sizes.interface
        }
    }

    /// The field for the next deform of `complex`, whose cells have the
    /// statistics `cells` (indexed by cell id) and the phases `phases`.
    pub fn update<K: Dim>(
        &mut self,
        complex: &Complex<K>,
        cells: &[CellStats],
        phases: &PhaseStats,
    ) -> &SizingField {
        self.last_requests = 0;
        self.new_requests = 0;
        self.noise_variance = noise_variance(complex, cells);
        let gap = smallest_gap(phases);
        // In samples, as the residuals count them.
        let step = self.sizes.sample_step;
        let smallest_cell = K::regular_measure(self.sizes.h_min / step).max(1.0);
        let mut field = std::mem::take(&mut self.building);
        field.fill(self.sizes.h_max);
        for c in complex.cell_ids() {
            let pts = complex.cell_points(c);
            let pts = &pts[..K::NV];
            let centroid = centroid(pts);
            let on_interface = complex
                .cell(c)
                .iter()
                .any(|&v| complex.class(v).on_interface());
            if on_interface {
                let size = self.interface_size(complex, c);
                field.lower(&centroid, size);
                if K::N == 2 {
                    lower_at_interface_edges(complex, c, &mut field, size);
                }
            }
            let Some(stats) = cells.get(c.index()) else {
                continue;
            };
            if self.settled && on_interface {
                continue;
            }
            let longest = longest_edge(pts);
            // At a 2D interface, a blurred edge leaves a residual of a
            // fraction of a pixel's width along the cell: ask for more than
            // a whole pixel layer across it (refining for less kept runs at
            // σ 0.1 from converging). In 3D a layer across a coarse tet's
            // face is many voxels, and with that bound the coarse-to-fine
            // start lost accuracy, so 3D asks for a smallest cell.
            let floor = if on_interface && K::N == 2 {
                longest / step
            } else {
                smallest_cell
            };
            if self.unexplained(complex, c, stats, phases, gap, floor) {
                let target = (REFINE_FACTOR * longest).max(self.sizes.h_min);
                if on_interface {
                    // Where the interface is, for now: it may be moving.
                    field.lower(&centroid, target);
                } else {
                    if target < self.requests.at(&centroid, self.sizes.h_max) {
                        self.new_requests += 1;
                    }
                    self.requests.lower(&centroid, target);
                }
                self.last_requests += 1;
            }
        }
        if K::N == 2 {
            self.last_requests += refine_pinches(complex, &mut field, self.sizes.h_min);
        }
        field.lower_to(&self.requests);
        if field != self.unlimited {
            // The new unlimited field is kept; the old one's buffer takes
            // its copy, limited, and the old limited field's buffer is the
            // next update's to build in.
            std::mem::swap(&mut self.unlimited, &mut field);
            field.clone_from(&self.unlimited);
            field.limit_gradation_with(self.gradation, &mut self.sweeps);
            std::mem::swap(&mut self.field, &mut field);
        }
        self.building = field;
        &self.field
    }

    /// Whether the pixels of `c` deviate from its phase's mean clearly more
    /// than noise of the estimated variance would, by more than `floor`
    /// pixels labelled across the smallest gap between means.
    fn unexplained<K: Dim>(
        &self,
        complex: &Complex<K>,
        c: CellId,
        stats: &CellStats,
        phases: &PhaseStats,
        gap: f64,
        floor: f64,
    ) -> bool {
        let Some(mean) = phases
            .mean
            .get(complex.label(c) as usize)
            .copied()
            .flatten()
        else {
            return false;
        };
        self.unexplained_by::<K>(stats, mean, gap, floor)
    }

    /// Whether pixels of the statistics `stats` deviate from `mean` clearly
    /// more than noise of the estimated variance would, by more than
    /// `floor` pixels labelled across `gap` (see [`unexplained`](Self::unexplained)).
    fn unexplained_by<K: Dim>(&self, stats: &CellStats, mean: f64, gap: f64, floor: f64) -> bool {
        let n = stats.count as f64;
        if stats.count < 4 {
            return false;
        }
        let var = self.noise_variance;
        let excess = stats.sse(mean) - n * var;
        if excess <= gap * gap * floor {
            return false;
        }
        // The sum of n squared Gaussian residuals has standard deviation
        // σ²·√(2n); a mislabelled smallest cell costs gap²·its pixels.
        if excess > self.residual_sigmas * var * (2.0 * n).sqrt() {
            return true;
        }
        // Part of a thin line shifts the cell's mean long before it raises
        // the spread of its pixels above that of n residuals: the mean of n
        // pixels of the phase deviates from its mean by σ/√n. (2D: in 3D,
        // where far more cells are tested, the test refined noise and cost
        // Dice on the two-balls volumes.)
        let shift = stats.sum / n - mean;
        K::N == 2 && shift * shift * n > MEAN_SHIFT_SIGMAS * MEAN_SHIFT_SIGMAS * var
    }
}

/// The graded start of a 2D coarse start (`segment/graded_start.rs`).
impl AdaptiveSizing {
    /// One pass of the graded start: every cell larger than
    /// `coarse_measure` (one the resize splits at `h = L/2`) whose pixels
    /// the class mean nearest its own mean does not explain
    /// (`class_means`: the classes of the initial thresholds; the test of
    /// the run's refinement, against the estimated noise) asks for a third
    /// of its longest edge, not below `L/2`, over all of its area. Returns
    /// the number of cells that asked; [`start_field`](Self::start_field)
    /// is the field to resize the start mesh to.
    ///
    /// Why: a start mesh at `h_max` labelled by its cells' means averages
    /// away what is smaller than a cell (a square's corners, a 5-px bar).
    /// Refined first where a cell mixes classes, step by step so that only
    /// the children that still mix are refined again, the start is
    /// labelled at about `L` wherever the thresholds' structures are, and
    /// is coarse elsewhere. The requests are the start's only: once the
    /// cells are labelled, the interfaces hold `L` in the run's field.
    pub fn grade_start<K: Dim>(
        &mut self,
        complex: &Complex<K>,
        cells: &[CellStats],
        class_means: &[f64],
        coarse_measure: f64,
    ) -> usize {
        self.noise_variance = noise_variance(complex, cells);
        let gap = smallest_gap_of(class_means.to_vec());
        if !gap.is_finite() || gap <= 0.0 {
            return 0;
        }
        let step = self.sizes.sample_step;
        let smallest_cell = K::regular_measure(self.sizes.h_min / step).max(1.0);
        let finest = START_SPLIT * self.sizes.interface;
        let mut requests = 0;
        for c in complex.cell_ids() {
            let pts = complex.cell_points(c);
            let pts = &pts[..K::NV];
            let Some(stats) = cells.get(c.index()) else {
                continue;
            };
            let Some(mean) = stats.mean() else {
                continue;
            };
            if complex.measure(c) <= coarse_measure {
                continue;
            }
            let nearest = class_means
                .iter()
                .copied()
                .min_by(|a, b| (a - mean).abs().total_cmp(&(b - mean).abs()))
                .unwrap_or(mean);
            if self.unexplained_by::<K>(stats, nearest, gap, smallest_cell) {
                let spacing = grid_spacing(&self.sizes);
                let target = (REFINE_FACTOR * longest_edge(pts)).max(finest);
                // (the building buffer is free until the first update)
                lower_over_triangle(&mut self.building, pts, spacing, target);
                requests += 1;
            }
        }
        requests
    }

    /// The start's requests so far, limited in gradation: the field the
    /// start mesh is resized to after a pass of
    /// [`grade_start`](Self::grade_start).
    pub fn start_field(&mut self) -> &SizingField {
        self.field.clone_from(&self.building);
        self.field
            .limit_gradation_with(self.gradation, &mut self.sweeps);
        &self.field
    }
}

/// The graded start refines the cells that mix classes down to this
/// fraction of `L`: the resize splits a cell above `max_measure` (5) times
/// the regular measure of `h`, so at `h = L` cells of up to `√5·L` would
/// stay, and their labels cut the corners of the structures by half such a
/// cell (two_phase 256² σ 0.1: Dice 0.9910 after the run, against 0.9940
/// from a start at `L`); at `L/2` they end at about `L`, as on the uniform
/// mesh.
pub const START_SPLIT: f64 = 0.5;

/// Lowers `field` to `h` at the midpoint of every edge of `c` whose two
/// ends lie on an interface. The resize judges an edge by `h` at its
/// midpoint, and with the request at the cell's centroid alone the grid
/// samples along the interface were a gradation step coarser: the 2D
/// interface edges grew a tenth longer than the uniform mesh's (mean 7.5
/// against 6.8 px at `L` = 8), and the adaptive Dice fell below the uniform
/// mesh's on the 512² two-phase images. In 3D, whose fine finish refines
/// the interfaces anyway and whose time is the constraint, the same
/// requests added 3–5 % tets at a Dice within ±0.0004 on three 64³ phantoms,
/// so only 2D makes them (`benches/RESULTS.md`, "Adaptive resolution").
fn lower_at_interface_edges<K: Dim>(
    complex: &Complex<K>,
    c: CellId,
    field: &mut SizingField,
    h: f64,
) {
    let corners = complex.cell(c);
    for i in 0..K::NV {
        for j in i + 1..K::NV {
            let (a, b) = (corners[i], corners[j]);
            if complex.class(a).on_interface() && complex.class(b).on_interface() {
                field.lower(&((complex.position(a) + complex.position(b)) * 0.5), h);
            }
        }
    }
}

/// The edge length of the regular cell whose measure is one sample's, for
/// samples `step` apart: 2.04 steps in 3D, 1.52 in 2D. The fine finish
/// refines no surface cell below it. At the 3D default `L` = 3 voxels its
/// `L/2` made tetrahedra of 0.4 voxel volume each along the surface; with
/// this floor the 64³ and 128³ phantoms of `benches/compare` end with 22–44 %
/// fewer tetrahedra in 0.83–0.92× the instructions, at a Dice within
/// −0.0008 and +0.0011 of the finer finish's (the 48³ two-phase volumes of
/// the encoding test lose up to 0.0012; benches/RESULTS.md, "Speed, 3D",
/// "A finish no finer than a voxel").
pub fn single_sample_edge<K: Dim>(step: f64) -> f64 {
    step * K::regular_measure(1.0).recip().powf(1.0 / K::N as f64)
}

/// The spacing of the sizing field's grid: fine enough to place the
/// interface size; each sample is a min.
fn grid_spacing(sizes: &Sizes) -> f64 {
    sizes.h_min.max(0.5 * sizes.interface)
}

/// Lowers `field` to `h` at every grid sample the triangle `pts` (its
/// first three corners) covers: the resize reads the field at cell
/// centroids, so a request at a coarse cell's centroid alone would refine
/// only the children that hold that sample.
fn lower_over_triangle<P: Point>(field: &mut SizingField, pts: &[P], spacing: f64, h: f64) {
    let (a, b, c) = (pts[0], pts[1], pts[2]);
    let divisions = (longest_edge(&pts[..3]) / (0.5 * spacing)).ceil().max(1.0) as usize;
    let step = 1.0 / divisions as f64;
    for i in 0..=divisions {
        for j in 0..=divisions - i {
            let (u, v) = (i as f64 * step, j as f64 * step);
            field.lower(&(a * (1.0 - u - v) + b * u + c * v), h);
        }
    }
}

/// Lowers `field` to `h_min` at every pinch of a 2D complex: a vertex
/// where a phase occurs in more than one piece of the star (two cells of
/// one phase touching only at the vertex, as where a thin line narrows to a
/// point between two cells of the other phase that each hold a part of it).
/// Such a crossing gets no force and the cells around it are too large for
/// their pixels to decide the topology; smallest cells there let the label
/// flips join the two pieces or separate them, as the data says. Returns
/// the number of pinches.
fn refine_pinches<K: Dim>(complex: &Complex<K>, field: &mut SizingField, h_min: f64) -> usize {
    let mut labels = Vec::new();
    let mut pinches = 0;
    for v in complex.vertex_ids() {
        if complex.class(v).kind != VertexKind::Junction {
            continue;
        }
        complex.labels_around(v, &mut labels);
        if complex.count_phase_pieces(v) > labels.len() {
            field.lower(&complex.position(v), h_min);
            pinches += 1;
        }
    }
    pinches
}

/// The noise variance, estimated as the median over cells of their pixels'
/// variance about the cell's own mean (robust: most cells are homogeneous).
fn noise_variance<K: Dim>(complex: &Complex<K>, cells: &[CellStats]) -> f64 {
    let mut v: Vec<f64> = complex
        .cell_ids()
        .filter_map(|c| cells.get(c.index()))
        .filter(|s| s.count >= 4)
        .map(|s| {
            let n = s.count as f64;
            let m = s.sum / n;
            ((s.sum_sq - n * m * m) / (n - 1.0)).max(0.0)
        })
        .collect();
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// The smallest gap between two known phase means (0 with fewer than two).
fn smallest_gap(phases: &PhaseStats) -> f64 {
    smallest_gap_of(phases.mean.iter().flatten().copied().collect())
}

/// The smallest gap between two of the means `m` (0 with fewer than two).
fn smallest_gap_of(mut m: Vec<f64>) -> f64 {
    m.sort_by(f64::total_cmp);
    m.windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min)
        .min(if m.len() < 2 { 0.0 } else { f64::INFINITY })
}

fn coords<K: Dim>(p: K::Point) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (a, o) in out.iter_mut().enumerate().take(K::N) {
        *o = p[a];
    }
    out
}

fn centroid<P: Point>(pts: &[P]) -> P {
    let mut c = P::zero();
    for &p in pts {
        c += p;
    }
    c * (1.0 / pts.len() as f64)
}

fn longest_edge<P: Point>(pts: &[P]) -> f64 {
    let mut longest: f64 = 0.0;
    for i in 0..pts.len() {
        for j in i + 1..pts.len() {
            longest = longest.max((pts[i] - pts[j]).length());
        }
    }
    longest
}
