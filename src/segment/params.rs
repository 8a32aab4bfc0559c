//! The segmentation's parameters, with documented defaults.

use super::adaptive::{Finish, SizingParams};
use super::error::SegmentError;
use serde::{Deserialize, Serialize};

/// Largest number of phases.
pub const MAX_PHASES: usize = 64;

/// The energy-plateau rule of adaptive runs: converged once the energy has
/// not reached a new low for this many iterations.
pub const PLATEAU_ITERATIONS: usize = 10;

/// The 2D default of [`SegmentParams::converge_plateau`]: with the step
/// gains ([`STEP_GAIN_2D`]) the interfaces are in place within a few
/// iterations of the energy's last new low; on the ten two- and four-phase
/// benchmark images the runs take 11–21 iterations instead of 21–43 at the
/// same Dice (within 0.0004) (`docs/parameters.md`, "Step gain").
pub const PLATEAU_ITERATIONS_2D: usize = 5;

/// The 3D default of [`SegmentParams::converge_plateau`]. With the settle
/// round (a plateau before the second flip round brings that round
/// forward, see [`SegmentParams::flip_interval`]) and a round that
/// relabels 1 % of the cells or more restarting the count, 7 iterations
/// end the 128³ benchmark runs after 16 % fewer iterations than 10 did, at
/// a Dice within 0.0009; 5 cut twice as many but lowered the Dice of every
/// 128³ volume, one by 0.0012 (`docs/parameters.md`, "3D: fewer
/// iterations").
pub const PLATEAU_ITERATIONS_3D: usize = 7;

/// The 2D default of [`SegmentParams::step_gain`].
pub const STEP_GAIN_2D: f64 = 3.0;

/// Largest accepted [`SegmentParams::step_gain`] (a displacement is never
/// longer than the step anyway).
pub const MAX_STEP_GAIN: f64 = 100.0;

/// The 2D default of [`SegmentParams::converge_pixels`]: a run has converged
/// once no vertex moves the interface across itself by more than a
/// twentieth of a pixel per iteration.
pub const CONVERGE_PIXELS: f64 = 0.05;

/// The 2D default of [`SegmentParams::min_move`] on the uniform mesh: after
/// the first iterations of a run on a noisy image a third to two thirds of
/// the interface vertices are asked to move less than 0.01·L (0.04 px at
/// L = 4), the noise's jitter about a settled interface, and moving them
/// made the mesh improvement and the cell statistics redo the whole
/// interface band every iteration. On the 40 images of the 2D benchmark set
/// (five phantoms, 256² and 512², σ 0.1 and 0.2, noise seeds 1–2) every
/// Dice stays within 0.0003 of moving every vertex, and the sixteen
/// two-phase images take 0.87× the instructions; 0.02 lowered the Dice of
/// all eight two_phase images, 0.03 and 0.05 the mean Dice of the set
/// (`docs/parameters.md`, "Smallest move").
/// Adaptive runs ([`SegmentParams::use_adaptive_mesh`]) keep 0.
pub const MIN_MOVE_2D: f64 = 0.01;

/// The 3D default of [`SegmentParams::min_move`]: vertices asked to move
/// less than this fraction of L stay, as the stopping rule counts no motion
/// below it ([`SegmentParams::converge_displacement`]'s default). On the 64³
/// and 128³ benchmark volumes it cuts a run's CPU time by about a third at the
/// same mean Dice; on the brain phantom, whose interfaces still travel when
/// the step is halved, it costs Dice (0.9664 against 0.9685) and iterations
/// (91 against 73) (`benches/RESULTS.md`, "Speed, 3D").
pub const MIN_MOVE_3D: f64 = 0.02;

/// The 3D default of [`SegmentParams::quiet_round_fraction`]: a flip round
/// relabelling fewer than 1 % of the cells is quiet.
pub const QUIET_ROUND_FRACTION_3D: f64 = 0.01;

/// The 3D default of [`SegmentParams::settle_rate`]: the settle round
/// comes once the energy falls at under 5 % of its fastest fall per
/// iteration. On the 64³ phantoms the labels then change no more until the
/// round (four-phase σ 0.2: mean Dice 0.9266 at iteration 8 and 0.9262 at
/// 20, where the plateau rule called the round), and the runs take 8–25
/// iterations instead of 16–33 at a Dice within −0.0021 to +0.0015
/// (benches/RESULTS.md, "Speed, 3D", "A settle round once the energy's
/// fall slows").
pub const SETTLE_RATE_3D: f64 = 0.05;

/// The 2D default of [`SegmentParams::new_low_fraction`].
pub const NEW_LOW_FRACTION_2D: f64 = 3e-4;

/// The 3D default of [`SegmentParams::new_low_fraction`]. Past its first
/// tens of iterations a 3D run under noise creeps: on the brain phantom the
/// energy fell by 0.01–0.03 % per iteration from the 30th to the 55th, each
/// few iterations a new low by 3·10⁻⁴, while the Dice rose from 0.9675 to
/// 0.9688 (`docs/parameters.md`, "3D: fewer iterations").
pub const NEW_LOW_FRACTION_3D: f64 = 1e-3;

/// Whether a parameter is 0, which serde leaves out of the written parameters.
fn is_zero(value: &f64) -> bool {
    *value == 0.0
}

fn default_new_low_fraction() -> f64 {
    NEW_LOW_FRACTION_2D
}

/// The 3D default of [`SegmentParams::step_fraction`] with three or more
/// phases. On the 64³ and 128³ benchmark volumes of three and four phases
/// (noise seeds 1 and 2) the Dice rose on 11 of 12 (by up to 0.0068; the
/// twelfth fell by 0.0007) at 0.96–1.32× the CPU time; on two phases 0.3
/// moved the Dice by ±0.0004 and some runs took more iterations, so they
/// keep 0.2 (`benches/RESULTS.md`, "Speed, 3D"). The explicit step
/// `0.3·L·0.7` stays below the stability limit 2 across a blurred edge up
/// to L = 9.5 voxels.
pub const STEP_FRACTION_3D_MULTIPHASE: f64 = 0.3;

/// The 2D sizing field freezes once the energy has not reached a new low
/// for this many iterations (half the plateau: the last iterations polish
/// the interfaces on a fixed mesh size).
pub const SETTLE_ITERATIONS: usize = 5;

/// Which region force drives interface points between two phases.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ForceModel {
    /// Eq. (6): `f(I) = (2I − m_i − m_j)/(m_i − m_j)` along `N_ij`; `±1` where
    /// `I` equals one of the two means, whatever the contrast.
    Normalised,
    /// Eq. (5), the Chan–Vese force `(m_i − m_j)(2I − m_i − m_j)` along `N_ij`
    /// (eq. 6 times `(m_i − m_j)²`; the paper prints it with the opposite
    /// normal). Two phases only.
    ChanVese,
}

/// How the external force of a triple junction (a junction where every
/// surrounding region is a distinct phase) is evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JunctionForce {
    /// Eq. (7) applied literally to every sample along the junction's
    /// adjacent edges: each sample is bracketed by the two junction phases
    /// whose means lie directly below and above it, which push along their
    /// region normals `N_k` (pointing away from region `k`), weighted linearly
    /// in `I`. A sample on an edge between phases 0 and 2 with `I` near `m_1`
    /// thus pushes phase 1 even though phase 1 does not touch that edge:
    /// along blurred edges between non-adjacent means the middle phase grows
    /// a small wedge at the junction (measured on the four-phase phantoms).
    Paper,
    /// Eq. (7) evaluated at each sample point with the phases around *that
    /// point* (the default): a sample on the edge between `a` and `b` is
    /// bracketed by `a` and `b` only, with `N_a = N_ab`, `N_b = −N_ab`, and
    /// the linear weights of eq. (7) then give exactly eq. (6) on that edge;
    /// the junction gets the hat-weighted sum of its edges' forces, like an
    /// interface vertex (the gradient of the data term with respect to the
    /// junction's position). No wedges (measurements: `docs/parameters.md`).
    EdgeLocal,
}

/// How cells are labelled before the evolution starts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Init {
    /// Cells labelled by their mean against the thresholds that split the
    /// histogram of the cell means (each cell weighted by its pixels, over
    /// the image's 0.1–99.9 % range) into `N` classes of least within-class
    /// variance (multi-level Otsu, exact up to 8 phases; k-means++ beyond;
    /// see [`thresholds`](super::thresholds)). The default: a few outliers
    /// neither stretch the bins nor get a class, the classes follow the
    /// histogram's modes wherever they lie, and cell means are far less
    /// noisy than pixels (on the four-phase phantoms at σ = 0.2 the pixel
    /// histogram has no valleys left; the cell means' does).
    Histogram,
    /// Cells labelled by their mean: two phases bisect the dynamic range,
    /// `N` phases split it into `N` equal intervals.
    Range,
    /// Everything phase 0 except the cells whose centroid lies in a disk,
    /// which get the disk's phase (later disks win).
    Disks(Vec<InitDisk>),
    /// Everything phase 0 except the cells whose centroid lies in a ball
    /// (3D), which get the ball's phase (later balls win).
    Balls(Vec<InitBall>),
    /// A label per pixel (row-major, the image's size, values `< phases`);
    /// each cell gets the label of the majority of its pixels.
    Labels {
        /// The label image (not serialised; the CLI records its path).
        #[serde(skip)]
        labels: Vec<u8>,
    },
}

/// A disk of the [`Init::Disks`] initialisation, in pixel units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct InitDisk {
    /// Centre x (column direction).
    pub x: f64,
    /// Centre y (row direction).
    pub y: f64,
    /// Radius.
    pub r: f64,
    /// Phase given to the cells inside.
    pub phase: u32,
}

/// A ball of the [`Init::Balls`] initialisation, in voxel units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct InitBall {
    /// Centre (x, y, z).
    pub centre: [f64; 3],
    /// Radius.
    pub r: f64,
    /// Phase given to the cells inside.
    pub phase: u32,
}

/// Everything that determines a segmentation run (see the field docs for the
/// defaults and why they were chosen).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SegmentParams {
    /// Number of phases `N` (2..=64).
    pub phases: usize,
    /// When set, the pipelines choose the number of phases from the data,
    /// trying 2 up to this many ([`choose_phases`](super::auto::choose_phases)),
    /// and run with the chosen one (written into `phases`).
    #[serde(default)]
    pub auto_phases: Option<usize>,
    /// Average edge length `L` of the DSC in pixels. `None` picks
    /// [`default_edge_length`] from the image size, in 2D shortened by
    /// [`contrast_edge_length`] on an image with little noise.
    pub edge_length: Option<f64>,
    /// Iteration cap.
    pub max_iterations: usize,
    /// Initialisation.
    pub init: Init,
    /// Whether cells may change label (the paper's label flips).
    pub label_flips: bool,
    /// Label flips are tried on iteration 1 and then every `flip_interval`
    /// = k iterations after the last round (1: every iteration, the 2D
    /// default). With k > 1 a *settle round* comes earlier: when the
    /// energy plateau of [`converge_plateau`](Self::converge_plateau) is
    /// reached before any round after the first, the next iteration is a
    /// flip round instead of the end of the run, so that the labels are
    /// judged again once the interfaces have settled (the three-phase
    /// volumes' blurred bands go back to their sides there) without waiting
    /// for iteration k + 1. Between flip iterations only the interfaces
    /// move, and an iteration without a flip attempt counts as flip-free for
    /// the stopping rule. The 3D reference code relabelled every 20
    /// iterations; see [`SegmentParams::new_3d`] for the 3D default.
    #[serde(default = "one")]
    pub flip_interval: usize,
    /// Whether a phase that empties or duplicates another's mean is re-seeded
    /// by splitting the phase of largest variance (see
    /// [`reseed`](super::reseed)); on by default. Either way a phase still
    /// lost at the end is reported in [`SegmentReport::warnings`](super::SegmentReport::warnings).
    #[serde(default = "yes")]
    pub reseed: bool,
    /// Whether flips must also lower the Mumford–Shah energy (see [`crate::segment::flips`]).
    pub flip_guard: bool,
    /// Whether a pixel may be relabelled by a cell flip only once per run
    /// (see [`Flipper::flip`](crate::segment::flips::Flipper::flip)); off in
    /// 2D, on in 3D (see [`SegmentParams::new_3d`]).
    #[serde(default)]
    pub flip_once: bool,
    /// Region force for two-phase interfaces.
    pub force: ForceModel,
    /// External force of triple junctions (see [`JunctionForce`]).
    pub junction_force: JunctionForce,
    /// Weight β of the rigidity term of eq. (2), dimensionless, relative to
    /// the normalised region force (the bending term `−Δ²X`, in pixels, is
    /// divided by L). Default 5: a zig-zag of amplitude `a` feels `20·a/L`,
    /// a circle of radius R ≫ L only `≈ 5·L³/(4R⁴)`. In 2D the driver
    /// raises it in proportion to the force noise `2σ̂/Δ` where that exceeds 1
    /// ([`contrast_rigidity`]). The driver splits the bending step
    /// into stable sub-steps, so β means the same at every step size.
    /// Evidence for the default: `docs/parameters.md`.
    pub rigidity: f64,
    /// Weight α of the elasticity term of eq. (2); 0 by default, as the paper
    /// argues (the DSC keeps the curve's sampling itself).
    pub elasticity: f64,
    /// Largest displacement per iteration as a fraction of L (when the
    /// largest force reaches 1, i.e. a pixel exactly at a mean). Default 0.2,
    /// below the explicit step's stability limit across a blurred edge for
    /// every default L; in 3D with three or more phases 0.3
    /// ([`STEP_FRACTION_3D_MULTIPHASE`]). The driver halves the step (down to 1/16) whenever
    /// the energy has not reached a new low for 10 iterations, so that noisy
    /// runs settle. Evidence: `docs/parameters.md`.
    pub step_fraction: f64,
    /// Largest per-vertex gain of the step (`segment/step_gain.rs`):
    /// a vertex whose displacement points the same way as in the previous
    /// iteration has its step multiplied by a gain that grows by 1.5 per
    /// such iteration up to this value, and falls back to 1 when it turns;
    /// no vertex moves further than `step_fraction`·L. 1: off, one step for
    /// every vertex. Default 3 in 2D (corners and the ends of thin bars,
    /// where the region force and the bending term nearly cancel, crept by
    /// 0.05–0.1 px per iteration for the last 15–20 iterations of a run);
    /// 1 in 3D ([`new_3d`](Self::new_3d)). Evidence: `docs/parameters.md`.
    #[serde(default = "unit_gain")]
    pub step_gain: f64,
    /// A vertex whose displacement of the iteration is below this fraction
    /// of L stays where it is: below the motion the stopping rule counts
    /// (`converge_displacement`), such moves are the noise's jitter about a
    /// settled interface, and moving them makes the mesh improvement and the
    /// integration work on the whole interface band every iteration. 2D:
    /// [`MIN_MOVE_2D`] (0.01) on the uniform mesh, 0 (every vertex moves) on
    /// the adaptive one. 3D: 0.02 (see [`new_3d`](Self::new_3d)).
    #[serde(default)]
    pub min_move: f64,
    /// Converged when the largest displacement stays below this fraction of L
    /// (in 2D its component across the interface: sliding along it, as the
    /// bending term evens out the vertices' spacing, moves no pixel) ...
    pub converge_displacement: f64,
    /// ... and, if set, below this many pixels (2D default 0.05; `None` in
    /// 3D). Dice counts pixels, not fractions of L: at 0.02·L alone a 512²
    /// image (L = 8) stopped while its corners still filled in by 0.13 px
    /// per iteration, with a third of its wrong pixels at the corners.
    #[serde(default)]
    pub converge_pixels: Option<f64>,
    /// ... and nothing flips, for this many iterations in a row.
    pub converge_iterations: usize,
    /// Also converged when the energy has not reached a new low (lower than
    /// the lowest so far by [`new_low_fraction`](Self::new_low_fraction) of
    /// itself, the test that halves the step)
    /// for this many iterations in a row: the labelling and the interfaces
    /// no longer change the energy meaningfully, and under noise the largest
    /// displacement of the rule above only falls once the step has been
    /// halved four times. Only while the label flips are on (without them
    /// the interfaces travel from their start, lowering the energy by little
    /// per iteration), and where flips run every iteration only on one that
    /// flipped nothing. 2D: 5 (with the step gains the interfaces reach
    /// their place within a few iterations of the energy's last new low, and
    /// the displacement rule waited for the last creeping corner); adaptive
    /// runs at least 10 ([`use_adaptive_mesh`](Self::use_adaptive_mesh)). 3D:
    /// [`PLATEAU_ITERATIONS_3D`], a plateau before the second flip round
    /// bringing that round forward rather than ending the run (see
    /// [`flip_interval`](Self::flip_interval) and [`new_3d`](Self::new_3d)).
    #[serde(default)]
    pub converge_plateau: Option<usize>,
    /// A flip round (see [`flip_interval`](Self::flip_interval)) that
    /// relabels fewer than this fraction of the cells is *quiet*: the
    /// energy it lowers does not restart the plateau of
    /// [`converge_plateau`](Self::converge_plateau), and one that comes when
    /// the plateau has lasted half its length ends the run on the state
    /// after the round. Such a round relabels noise-sized cells along
    /// settled interfaces, and each one used to buy ten more iterations at
    /// an unchanged Dice. A round that relabels more restarts the plateau
    /// count: the relabelled state gets a whole plateau to relax. 0 (2D,
    /// where flips run every iteration): every round counts.
    /// 3D: [`QUIET_ROUND_FRACTION_3D`].
    #[serde(default)]
    pub quiet_round_fraction: f64,
    /// How far below the lowest energy so far, as a fraction of the energy,
    /// an iteration's energy must come to be a new low: the plateau of
    /// [`converge_plateau`](Self::converge_plateau) and the step's halving
    /// count the iterations since the last one. 2D [`NEW_LOW_FRACTION_2D`],
    /// 3D [`NEW_LOW_FRACTION_3D`].
    #[serde(default = "default_new_low_fraction")]
    pub new_low_fraction: f64,
    /// The iterations without a new low of the energy after which a quiet
    /// flip round ([`quiet_round_fraction`](Self::quiet_round_fraction))
    /// ends the run (as does one after the energy's fall has slowed,
    /// [`settle_rate`](Self::settle_rate)); `None`: half of
    /// [`converge_plateau`](Self::converge_plateau), rounded up. The
    /// coarse pass ([`coarse_pass`](Self::coarse_pass)) uses 0: its
    /// labels need only be close, and the run at full resolution moves the
    /// interfaces on.
    #[serde(default)]
    pub quiet_round_plateau: Option<usize>,
    /// In runs with flip rounds (a [`flip_interval`](Self::flip_interval)
    /// above 1 and a [`converge_plateau`](Self::converge_plateau)), the rate
    /// of the energy's fall below which the interfaces count as settled:
    /// once the energy's mean fall per iteration over the last 3 is less
    /// than this fraction of its fastest fall in one iteration (since the
    /// start, the last re-seed or the last relabelling round), the settle
    /// round is due and a quiet flip round ends the run, as on the energy
    /// plateau. A rate relative to the run's own fall does not depend on the
    /// noise, whose variance sets the energy's size and so the plateau's
    /// threshold. 0: only the plateau. 2D 0, 3D [`SETTLE_RATE_3D`]; the
    /// coarse pass 0 (its end at its first quiet round would come before
    /// its interfaces have travelled). Not written when 0, so that the
    /// parameters of runs without it read as before.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub settle_rate: f64,
    /// Whether layers of an intermediate phase as thin as the band a blurred
    /// edge leaves between two other phases are given back to those phases
    /// at each flip round ([`band_flips`](super::band_flips)). Off in 2D
    /// (cells are larger than the band there, and a cluster along a blurred
    /// edge is already left alone); on in 3D with three or more phases
    /// ([`new_3d`](Self::new_3d)).
    #[serde(default)]
    pub band_flips: bool,
    /// Weight `w` of the length (3D: area) term of the Mumford–Shah energy,
    /// a width in pixels (3D: voxels): `ν = w·Δ²/2`, with Δ the smallest gap
    /// between adjacent initial phase means, not below twice the pixels'
    /// spread about their phase means (a phase split out of noise close to another
    /// does not make every boundary nearly free) nor above the mean gap ([`phase_contrast`](super::contrast::phase_contrast)).
    /// A stripe `d` pixels wide whose
    /// intensity differs by Δ from its surroundings lowers the data term by
    /// `d·Δ²` per pixel of its length and costs `2ν = w·Δ²` in boundary, so
    /// structures narrower than `w` pixels (disks of smaller radius) at that
    /// contrast are not worth their boundary, and wider ones are; at a
    /// contrast `k·Δ` the limit is `w/k²`. ν is in intensity² per pixel of
    /// length like the data term per pixel, so `a·I + b` gives the labels of
    /// `I`. ν is reported, and used by the flip guard. Default 1.6 for two
    /// phases (lower leaves the crossings of Fig. 2 unresolved), 5.5 for
    /// more (with more phases the pixel-dominant flip rule grows bands of
    /// intermediate phases along blurred edges, and noise-split phases
    /// persist at lower weights); in 3D 0.6 and 1.2
    /// ([`new_3d`](Self::new_3d)). Evidence: `docs/parameters.md`.
    pub length_weight: f64,
    /// Spacing of the samples along interface facets, in pixels/voxels
    /// (sample steps, whatever the voxel size's unit).
    pub sample_spacing: f64,
    /// Adaptive resolution (off: the paper's uniform mesh at `L`).
    #[serde(default)]
    pub sizing: SizingParams,
    /// Whether an adaptive run started from the histogram or the range on
    /// an image of at least [`MIN_SIDE`](super::coarse_pass::MIN_SIDE)
    /// samples a side starts from the final mesh of a run on the image at
    /// half resolution ([`coarse_pass`](super::coarse_pass)).
    #[serde(default)]
    pub coarse_pass: bool,
}

impl SegmentParams {
    /// The defaults for `phases` phases.
    pub fn new(phases: usize) -> Self {
        SegmentParams {
            phases,
            auto_phases: None,
            edge_length: None,
            max_iterations: 500,
            init: Init::Histogram,
            label_flips: true,
            flip_interval: 1,
            reseed: true,
            flip_guard: true,
            flip_once: false,
            band_flips: false,
            force: ForceModel::Normalised,
            junction_force: JunctionForce::EdgeLocal,
            rigidity: 5.0,
            elasticity: 0.0,
            step_fraction: 0.2,
            step_gain: STEP_GAIN_2D,
            min_move: MIN_MOVE_2D,
            converge_displacement: 0.02,
            converge_pixels: Some(CONVERGE_PIXELS),
            converge_iterations: 5,
            converge_plateau: Some(PLATEAU_ITERATIONS_2D),
            quiet_round_fraction: 0.0,
            new_low_fraction: NEW_LOW_FRACTION_2D,
            quiet_round_plateau: None,
            settle_rate: 0.0,
            length_weight: if phases == 2 { 1.6 } else { 5.5 },
            sample_spacing: 1.0,
            sizing: SizingParams {
                settle: Some(SETTLE_ITERATIONS),
                ..SizingParams::default()
            },
            coarse_pass: false,
        }
    }

    /// Turns on adaptive resolution with the stopping rules it needs: the
    /// energy-plateau rule ([`converge_plateau`](Self::converge_plateau), at
    /// least 10), and every vertex moving where the smallest move was the 2D
    /// uniform mesh's default ([`MIN_MOVE_2D`]). Parameters that are adaptive already (the 3D defaults,
    /// whose plateau is [`PLATEAU_ITERATIONS_3D`]) are left as they are. In
    /// 2D the sizing field also settles
    /// ([`SizingParams::settle`]): without both, refinement at blurred
    /// four-phase edges kept the mesh splitting and collapsing cells and the
    /// runs reached the iteration cap (`benches/RESULTS.md`, "Adaptive
    /// resolution").
    pub fn use_adaptive_mesh(&mut self) {
        if self.sizing.adaptive {
            // Adaptive already (the 3D defaults): its stopping rules are set.
            return;
        }
        self.sizing.adaptive = true;
        // (the uniform mesh's smallest move was not measured on the
        // adaptive one, whose runs and figures are those of every vertex
        // moving)
        if self.min_move == MIN_MOVE_2D {
            self.min_move = 0.0;
        }
        self.converge_plateau = Some(
            self.converge_plateau
                .map_or(PLATEAU_ITERATIONS, |n| n.max(PLATEAU_ITERATIONS)),
        );
    }

    /// The defaults for a volume (3D) with `phases` phases: as [`new`](Self::new)
    /// but `length_weight` 0.6 for two phases and 1.2 for more (the length
    /// term is an area, and thin structures have more area per voxel than 2D
    /// shapes have length per pixel), `flip_interval` 20 as the 3D reference code (with flips every
    /// iteration a few cells flip every iteration and the stopping rule never
    /// fires) and `flip_once` on (under strong noise each flip round
    /// relabelled interface voxels that the rigidity then smoothed back),
    /// `min_move` 0.02 (vertices asked to move less than 0.02·L stay),
    /// `step_fraction` 0.3 with three or more phases
    /// ([`STEP_FRACTION_3D_MULTIPHASE`]), the energy plateau rule `converge_plateau`
    /// [`PLATEAU_ITERATIONS_3D`] (the σ = 0.2 phantoms
    /// reach their Dice within 10–30 iterations, then spent 50–250 more
    /// fitting noise), and adaptive resolution from a coarse start (`L` at
    /// the interfaces, cells up to the smallest side / 10 elsewhere: 2.5–12×
    /// fewer tetrahedra at an equal or higher Dice on the benchmark volumes)
    /// ending with a fine finish ([`Finish::for_phases`]: data differing by
    /// a re-quantisation give the same labels), and on volumes of at least
    /// [`MIN_SIDE`](super::coarse_pass::MIN_SIDE) voxels a side the coarse
    /// pass ([`coarse_pass`](Self::coarse_pass)).
    /// Evidence: `docs/parameters.md`.
    pub fn new_3d(phases: usize) -> Self {
        SegmentParams {
            length_weight: if phases == 2 { 0.6 } else { 1.2 },
            flip_interval: 20,
            flip_once: true,
            band_flips: phases >= 3,
            min_move: MIN_MOVE_3D,
            step_fraction: if phases == 2 {
                0.2
            } else {
                STEP_FRACTION_3D_MULTIPHASE
            },
            step_gain: 1.0,
            converge_pixels: None,
            converge_plateau: Some(PLATEAU_ITERATIONS_3D),
            quiet_round_fraction: QUIET_ROUND_FRACTION_3D,
            new_low_fraction: NEW_LOW_FRACTION_3D,
            settle_rate: SETTLE_RATE_3D,
            sizing: SizingParams {
                adaptive: true,
                coarse_start: true,
                finish: Some(Finish::for_phases(phases)),
                ..SizingParams::default()
            },
            coarse_pass: true,
            ..Self::new(phases)
        }
    }

    /// Checks every value against the image size; the first violation is returned.
    pub fn validate(&self, width: usize, height: usize) -> Result<(), SegmentError> {
        self.validate_dims([width, height, 1])
    }

    /// [`validate`](Self::validate) for an image or volume of `dims` samples
    /// (`dims[2] == 1` for a 2D image) of unit size.
    pub fn validate_dims(&self, dims: [usize; 3]) -> Result<(), SegmentError> {
        self.validate_in(dims, [1.0; 3])
    }

    /// [`validate`](Self::validate) for an image or volume of `dims` samples
    /// of size `spacing` (`dims[2] == 1` for a 2D image): the edge length is
    /// in the spacing's unit, at least one sample step ([`sample_step`]) and
    /// at most the smallest extent.
    pub fn validate_in(&self, dims: [usize; 3], spacing: [f64; 3]) -> Result<(), SegmentError> {
        let [width, height, depth] = dims;
        if self.phases < 2 || self.phases > MAX_PHASES {
            return Err(SegmentError::Phases(self.phases));
        }
        if let Some(max) = self.auto_phases {
            if !(2..=MAX_PHASES).contains(&max) {
                return Err(SegmentError::Phases(max));
            }
            if !matches!(self.init, Init::Histogram | Init::Range) {
                return Err(SegmentError::InitOption(
                    "choosing the number of phases needs the histogram or range start".into(),
                ));
            }
        }
        if let Some(l) = self.edge_length {
            let unit = if spacing == [1.0; 3] { " px" } else { "" };
            let max = smallest_extent(dims, spacing);
            let step = sample_step(dims, spacing);
            if !(l.is_finite() && l > 0.0) {
                return Err(SegmentError::EdgeLength(
                    l,
                    "must be a positive number".into(),
                ));
            }
            if l > max {
                return Err(SegmentError::EdgeLength(
                    l,
                    format!(
                        "must not exceed the image's smaller side ({}{unit})",
                        max as f32
                    ),
                ));
            }
            if l < step {
                return Err(SegmentError::EdgeLength(
                    l,
                    if unit.is_empty() {
                        format!("must be at least 1 pixel step ({})", step as f32)
                    } else {
                        "must be at least 1 pixel".into()
                    },
                ));
            }
        }
        let check = |name: &'static str, v: f64, ok: bool, range: &'static str| {
            if ok && v.is_finite() {
                Ok(())
            } else {
                Err(SegmentError::Param(name, v, range))
            }
        };
        self.sizing.validate()?;
        let non_negative = "must be a finite number ≥ 0";
        check(
            "rigidity",
            self.rigidity,
            self.rigidity >= 0.0,
            non_negative,
        )?;
        check(
            "elasticity",
            self.elasticity,
            self.elasticity >= 0.0,
            non_negative,
        )?;
        check(
            "step_fraction",
            self.step_fraction,
            self.step_fraction > 0.0 && self.step_fraction <= 0.5,
            "must lie in (0, 0.5]",
        )?;
        check(
            "step_gain",
            self.step_gain,
            (1.0..=MAX_STEP_GAIN).contains(&self.step_gain),
            "must lie in [1, 100]",
        )?;
        check(
            "min_move",
            self.min_move,
            self.min_move >= 0.0,
            non_negative,
        )?;
        check(
            "converge_displacement",
            self.converge_displacement,
            self.converge_displacement >= 0.0,
            non_negative,
        )?;
        check(
            "quiet_round_fraction",
            self.quiet_round_fraction,
            (0.0..=1.0).contains(&self.quiet_round_fraction),
            "must lie in [0, 1]",
        )?;
        check(
            "settle_rate",
            self.settle_rate,
            (0.0..1.0).contains(&self.settle_rate),
            "must lie in [0, 1)",
        )?;
        check(
            "new_low_fraction",
            self.new_low_fraction,
            (0.0..0.1).contains(&self.new_low_fraction),
            "must lie in [0, 0.1)",
        )?;
        if let Some(pixels) = self.converge_pixels {
            check("converge_pixels", pixels, pixels >= 0.0, non_negative)?;
        }
        check(
            "length_weight",
            self.length_weight,
            self.length_weight >= 0.0,
            non_negative,
        )?;
        check(
            "sample_spacing",
            self.sample_spacing,
            self.sample_spacing > 0.0 && self.sample_spacing <= 16.0,
            "must lie in (0, 16]",
        )?;
        if self.flip_interval == 0 {
            return Err(SegmentError::Param(
                "flip_interval",
                0.0,
                "must be at least 1",
            ));
        }
        if self.max_iterations == 0 {
            return Err(SegmentError::Param(
                "max_iterations",
                0.0,
                "must be at least 1",
            ));
        }
        if self.force == ForceModel::ChanVese && self.phases != 2 {
            return Err(SegmentError::ChanVeseNeedsTwoPhases(self.phases));
        }
        match &self.init {
            Init::Histogram | Init::Range => {}
            Init::Disks(disks) => {
                if disks.is_empty() {
                    return Err(SegmentError::InitOption(
                        "at least one disk is needed".into(),
                    ));
                }
                for d in disks {
                    if !(d.x.is_finite() && d.y.is_finite() && d.r.is_finite() && d.r > 0.0) {
                        return Err(SegmentError::InitOption(format!(
                            "disk {},{},{} needs finite numbers and a positive radius",
                            d.x, d.y, d.r
                        )));
                    }
                    if d.phase as usize >= self.phases {
                        return Err(SegmentError::InitOption(format!(
                            "disk phase {} is not below the number of phases {}",
                            d.phase, self.phases
                        )));
                    }
                }
            }
            Init::Balls(balls) => {
                if balls.is_empty() {
                    return Err(SegmentError::InitOption(
                        "at least one ball is needed".into(),
                    ));
                }
                for b in balls {
                    if !(b.centre.iter().all(|x| x.is_finite()) && b.r.is_finite() && b.r > 0.0) {
                        return Err(SegmentError::InitOption(format!(
                            "ball {:?},{} needs finite numbers and a positive radius",
                            b.centre, b.r
                        )));
                    }
                    if b.phase as usize >= self.phases {
                        return Err(SegmentError::InitOption(format!(
                            "ball phase {} is not below the number of phases {}",
                            b.phase, self.phases
                        )));
                    }
                }
            }
            Init::Labels { labels } => {
                if labels.len() != width * height * depth {
                    return Err(SegmentError::Init(format!(
                        "the label image has {} samples but the image has {}",
                        labels.len(),
                        if depth > 1 {
                            format!("{width}×{height}×{depth}")
                        } else {
                            format!("{width}×{height}")
                        }
                    )));
                }
                if let Some(&m) = labels.iter().max() {
                    if m as usize >= self.phases {
                        return Err(SegmentError::Init(format!(
                            "the label image uses label {m} but there are only {} phases",
                            self.phases
                        )));
                    }
                }
            }
        }
        Ok(())
    }

    /// Checks that every disk or ball of the initialisation overlaps the
    /// domain `[0, extent]` (the image's size in the complex's units): one
    /// outside would label nothing and leave a silent all-background start.
    pub fn check_shapes_inside(&self, extent: [f64; 3]) -> Result<(), SegmentError> {
        let overlaps = |centre: &[f64], r: f64| {
            let d2: f64 = centre
                .iter()
                .zip(extent)
                .map(|(&c, e)| (c - c.clamp(0.0, e)).powi(2))
                .sum();
            d2 < r * r
        };
        match &self.init {
            Init::Disks(disks) => {
                if let Some(d) = disks.iter().find(|d| !overlaps(&[d.x, d.y], d.r)) {
                    return Err(SegmentError::InitOption(format!(
                        "disk {},{},{} lies outside the {}×{} image",
                        d.x, d.y, d.r, extent[0], extent[1]
                    )));
                }
            }
            Init::Balls(balls) => {
                if let Some(b) = balls.iter().find(|b| !overlaps(&b.centre, b.r)) {
                    return Err(SegmentError::InitOption(format!(
                        "ball {},{},{},{} lies outside the volume [0, {}]×[0, {}]×[0, {}]",
                        b.centre[0], b.centre[1], b.centre[2], b.r, extent[0], extent[1], extent[2]
                    )));
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// The edge length to use for an image or volume of `dims` samples of
    /// size `spacing`, in the same length unit: the given one, or the
    /// default of [`resolved_edge_length`](Self::resolved_edge_length)
    /// counted in voxel-sized steps (the cube root of the voxel volume), so
    /// that cells hold as many voxels as in an isotropic volume of the same
    /// physical shape.
    pub fn resolved_edge_length_in(&self, dims: [usize; 3], spacing: [f64; 3]) -> f64 {
        if self.edge_length.is_some() || spacing == [1.0; 3] {
            return self.resolved_edge_length(dims);
        }
        let step = sample_step(dims, spacing);
        let side = (smallest_extent(dims, spacing) / step).max(1.0) as usize;
        default_edge_length_of(dims, side, self.phases) * step
    }

    /// Whether the result answers for every pixel or voxel, so that a class
    /// the labels leave out anywhere is the run's loss: with label flips,
    /// which relabel the whole image, or from a start that labels all of it
    /// by intensity (histogram, range). A start the user drew (disks,
    /// balls, a labelling) evolved without flips (the paper's single-region
    /// evolutions) claims only what it reaches, and the pixels elsewhere
    /// that look like its phase were never asked for.
    pub fn claims_whole_image(&self) -> bool {
        self.label_flips || matches!(self.init, Init::Histogram | Init::Range)
    }

    /// These parameters for `phases` phases: the phase count replaced, and a
    /// length weight left at its default for the old count moved to the
    /// default for the new one (the defaults differ between two phases and more).
    pub fn with_phases(&self, phases: usize) -> Self {
        let default_weight = |n: usize| {
            if self.flip_interval == 20 {
                Self::new_3d(n).length_weight
            } else {
                Self::new(n).length_weight
            }
        };
        let mut p = self.clone();
        if self.length_weight == default_weight(self.phases) {
            p.length_weight = default_weight(phases);
        }
        p.phases = phases;
        p
    }

    /// The edge length to use for an image or volume of `dims` samples.
    pub fn resolved_edge_length(&self, dims: [usize; 3]) -> f64 {
        // The smallest extent counts (a 2D image has depth 1, which does not):
        // a thin stack of slices must not get cells thicker than itself.
        let side = dims.iter().copied().filter(|&d| d > 1).min().unwrap_or(1);
        self.edge_length
            .unwrap_or_else(|| default_edge_length_of(dims, side, self.phases))
    }
}

fn unit_gain() -> f64 {
    1.0
}

fn one() -> usize {
    1
}

fn yes() -> bool {
    true
}

/// The size of one sample step of a grid of `dims` samples of size
/// `spacing`: the geometric mean of the sizes along the axes with more
/// than one sample (1 for unit samples). Lengths given in samples (the
/// default edge lengths, the smallest adaptive cell) are this many units.
pub fn sample_step(dims: [usize; 3], spacing: [f64; 3]) -> f64 {
    // Called by the region force for every pair of phases each iteration:
    // no allocation.
    let (product, axes) = (0..3)
        .filter(|&a| dims[a] > 1)
        .fold((1.0f64, 0usize), |(p, n), a| (p * spacing[a], n + 1));
    product.powf(1.0 / axes.max(1) as f64)
}

/// The smallest extent (`dims · spacing`) over the axes with more than one
/// sample, in the spacing's unit.
pub fn smallest_extent(dims: [usize; 3], spacing: [f64; 3]) -> f64 {
    (0..3)
        .filter(|&a| dims[a] > 1)
        .map(|a| dims[a] as f64 * spacing[a])
        .fold(f64::INFINITY, f64::min)
        .min(f64::MAX)
}

/// The default average edge length for `phases` phases: `min(W, H) / 64 ·
/// √(N − 1)`, clamped to `[3, 10]` pixels and to a quarter of the smaller side.
///
/// Accuracy is limited by how well straight edges of length ≥ L/2 follow
/// curved boundaries and thin structures (a 5-pixel bar needs L ≤ 4), speed by
/// the number of cells (∝ 1/L²). About 64 edges across the image gives a 256²
/// two-phase image L = 4 (≈ 9k cells) and a 512² one L = 8. With N phases
/// the gaps between the means shrink like 1/(N − 1), so the normalised
/// force of eq. (6) is (N − 1) times noisier per pixel; averaging it along
/// longer edges compensates part of that: √(N − 1) longer edges (L ≈ 6.9 for
/// four phases at 256², 10 at 512²) measured best on the four-phase phantoms
/// (256², σ = 0.2: Dice 0.966 at L = 4, 0.980 at L = 6). Never below 3 px,
/// where cells hold too few pixels for their means to be reliable under noise.
pub fn default_edge_length(width: usize, height: usize, phases: usize) -> f64 {
    let m = width.min(height) as f64;
    let n = phases.max(2) as f64;
    (m / 64.0 * (n - 1.0).sqrt())
        .clamp(3.0, 10.0)
        .min(m / 4.0)
        .max(1.0)
}

/// Smallest default edge length of a volume, in voxels: the floor of
/// [`default_edge_length`], which its cap at a quarter of the thinnest side
/// would undercut on a stack of a few slices. A tetrahedral mesh at L = 1
/// holds about 12 cells per voxel: a disk in a 200×200×3 stack took 1.47
/// million tets, 1 GB and 7.6 s at L = 1, and 43 257 tets, 54 MB and 0.3 s
/// at L = 3, with the same labels (a 300×300×6 stack with two disks: 1.84
/// million tets and 1.26 GB at L = 1.5, 189 194 tets and 186 MB at 3, mean
/// Dice 1.0000 and 0.9999). Never above the thinnest side, so that cells
/// are no thicker than the stack.
pub const MIN_VOLUME_EDGE_LENGTH: f64 = 3.0;

/// The default edge length of an image or volume of `dims` samples whose
/// smallest side is `side`: [`default_edge_length`], and for a volume not
/// below [`MIN_VOLUME_EDGE_LENGTH`] (nor above `side`).
fn default_edge_length_of(dims: [usize; 3], side: usize, phases: usize) -> f64 {
    let l = default_edge_length(side, side, phases);
    let volume = dims.iter().all(|&d| d > 1);
    if volume {
        l.max(MIN_VOLUME_EDGE_LENGTH.min(side as f64))
    } else {
        l
    }
}

/// Noise-to-contrast ratio `σ̂/Δ` (noise over the smallest gap between the
/// phase means) that [`default_edge_length`] is made for: the noisiest
/// images it must average over; on the least noisy benchmark phantom the
/// ratio is 0.26.
pub const NOISE_TO_CONTRAST_OF_SIZE_DEFAULT: f64 = 0.2;

/// Smallest edge length [`contrast_edge_length`] gives, in pixels: the size
/// default of a 256² two-phase image (the cost grows as 1/L²).
pub const SMALLEST_CONTRAST_EDGE_LENGTH: f64 = 4.0;

/// The 2D default edge length for an image whose noise `noise` (σ̂) is
/// `noise/gap` of the smallest gap between its phase means: the size default
/// `size_default` ([`default_edge_length`]) where the noise is at least
/// [`NOISE_TO_CONTRAST_OF_SIZE_DEFAULT`] of the gap, and proportionally
/// shorter edges where it is less, down to [`SMALLEST_CONTRAST_EDGE_LENGTH`].
///
/// The size default makes cells large enough that their mean intensities
/// separate the phases under the noise of the benchmark phantoms. A cell of
/// edge L averages ≈ 0.43·L² pixels, so its mean's error is ≈ σ̂/(0.66·L):
/// relative to the gap it is the same at `L·Δ/σ̂` constant. A photograph whose
/// noise is a few percent of the phase gap needs no large cells, and on one
/// its fine structure is lost at the size default (e.g. the piecewise-constant
/// fit of a 512² photograph at 4 phases is 1.5× that of a pixel-based method
/// at L = 10 px, 1.07× at L = 4).
pub fn contrast_edge_length(size_default: f64, noise: f64, gap: f64) -> f64 {
    if !(gap > 0.0 && noise.is_finite()) {
        return size_default;
    }
    let ratio = noise / gap;
    let scaled = size_default * (ratio / NOISE_TO_CONTRAST_OF_SIZE_DEFAULT).min(1.0);
    scaled.max(SMALLEST_CONTRAST_EDGE_LENGTH.min(size_default))
}

/// The 2D rigidity for an image whose noise `noise` (σ̂) is `noise/gap` of
/// the smallest gap between its phase means: β where the noise of the
/// normalised region force of eq. (6) per pixel, `2σ̂/Δ`, is at most 1 (as
/// strong as the push of a pixel at a phase mean; σ̂ = 0.2 on the two-phase
/// benchmark phantom), and β times that noise where it is more.
///
/// The bending term holds down the wiggles that noise drives, so past the
/// point where the noise outweighs a phase mean's push it grows with it
/// (the piecewise-constant MAP weight grows with σ² in the same way). It
/// is not lowered on cleaner images: bending is also what resolves a
/// two-phase crossing (no region force acts there) and keeps thin
/// structures on a coarse mesh, and a weight falling with the noise left
/// the checkerboard crossing of the paper's Fig. 2 unresolved.
pub fn contrast_rigidity(rigidity: f64, noise: f64, gap: f64) -> f64 {
    if !(gap > 0.0 && noise.is_finite()) {
        return rigidity;
    }
    let force_noise = 2.0 * noise / gap;
    rigidity * force_noise.max(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contrast_edge_length_shrinks_only_for_images_with_little_noise() {
        // as noisy as the benchmark phantoms: the size default
        assert_eq!(contrast_edge_length(8.0, 0.1, 0.4), 8.0);
        assert_eq!(contrast_edge_length(8.0, 0.2, 0.2), 8.0);
        // a tenth of the gap: half the size default
        assert!((contrast_edge_length(10.0, 0.02, 0.2) - 5.0).abs() < 1e-9);
        // nearly noise-free: the floor, never above the size default
        assert_eq!(contrast_edge_length(10.0, 0.0, 0.2), 4.0);
        assert_eq!(contrast_edge_length(3.0, 0.0, 0.2), 3.0);
        // no gap known: the size default
        assert_eq!(contrast_edge_length(8.0, 0.01, 0.0), 8.0);
    }

    #[test]
    fn contrast_rigidity_grows_with_the_force_noise() {
        // the force's noise per pixel reaches a phase mean's push: β
        assert_eq!(contrast_rigidity(5.0, 0.2, 0.4), 5.0);
        // noisier: in proportion
        assert!((contrast_rigidity(5.0, 0.3, 0.4) - 7.5).abs() < 1e-12);
        // cleaner: still β
        assert_eq!(contrast_rigidity(5.0, 0.05, 0.4), 5.0);
        assert_eq!(contrast_rigidity(5.0, 0.0, 0.4), 5.0);
        // no gap known: β
        assert_eq!(contrast_rigidity(5.0, 0.01, 0.0), 5.0);
    }

    #[test]
    fn default_edge_length_follows_the_smallest_extent() {
        let p = SegmentParams::new_3d(2);
        assert_eq!(p.resolved_edge_length([512, 512, 1]), 8.0);
        assert_eq!(p.resolved_edge_length([512, 512, 512]), 8.0);
        // a thin stack: 20 slices, not the 512-pixel slices, set L
        assert_eq!(p.resolved_edge_length([512, 512, 20]), 3.0);
        // a stack of a few slices: not below 3 voxels, nor above its depth
        assert_eq!(p.resolved_edge_length([200, 200, 3]), 3.0);
        assert_eq!(p.resolved_edge_length([200, 200, 5]), 3.0);
        assert_eq!(p.resolved_edge_length([200, 200, 2]), 2.0);
        assert_eq!(p.resolved_edge_length([200, 200, 1]), 3.125);
        let given = SegmentParams {
            edge_length: Some(5.5),
            ..p
        };
        assert_eq!(given.resolved_edge_length([512, 512, 20]), 5.5);
        assert_eq!(
            given.resolved_edge_length_in([512, 512, 20], [0.5, 0.5, 2.0]),
            5.5
        );
    }

    #[test]
    fn default_edge_length_counts_voxel_sized_steps() {
        let p = SegmentParams::new_3d(2);
        // Unit voxels: as before.
        assert_eq!(p.resolved_edge_length_in([512, 512, 512], [1.0; 3]), 8.0);
        // 0.5 × 0.5 × 2 mm voxels, 512 × 512 × 128: a 256 mm cube, counted
        // in steps of ∛0.5 mm (322 of them), as an isotropic 322³ volume.
        let step = 0.5f64.cbrt();
        let l = p.resolved_edge_length_in([512, 512, 128], [0.5, 0.5, 2.0]);
        assert!((l - 322.0 / 64.0 * step).abs() < 1e-9, "{l}");
    }
}
