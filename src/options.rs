//! The segmentation options as the command line spells them, shared by the
//! `dsc-seg` binary and the Python package.
//!
//! Both parse the same clap structs: the binary from its argument list, the
//! Python package from `segment(image, **options)`'s keywords turned into
//! `--name value` arguments. So every option, its default, its validation and
//! its error message are the same in both, and a new option added here is a
//! new keyword in Python without further code.

use crate::error::{Error, Result};
use crate::segment::{Init, InitBall, InitDisk, JunctionForce, SegmentParams};
use clap::{Args, ValueEnum};
use std::path::PathBuf;

/// The evolution's options, shared by `segment` and `segment3d`.
#[derive(Args, Clone, Debug)]
pub struct EvolutionArgs {
    /// Iteration cap.
    #[arg(long, default_value_t = 500)]
    pub max_iterations: usize,
    /// Keep every cell's label: only the interfaces move.
    #[arg(long)]
    pub no_label_flips: bool,
    /// Try label flips every K iterations; with K > 1 the second round comes
    /// earlier, at the first energy plateau (--converge-plateau) [default: 1
    /// in 2D, 20 in 3D].
    #[arg(long, value_name = "K")]
    pub flip_interval: Option<usize>,
    /// Rigidity weight β of eq. (2). In 2D it is raised in proportion to the
    /// image's force noise 2σ̂/Δ where that exceeds 1 (report.json gives the
    /// weight used).
    #[arg(long, allow_hyphen_values = true)]
    pub rigidity: Option<f64>,
    /// Elasticity weight α of eq. (2) (off by default, as in the paper).
    #[arg(long, allow_hyphen_values = true)]
    pub elasticity: Option<f64>,
    /// Largest displacement per iteration as a fraction of L [default: 0.2;
    /// 0.3 in 3D with three or more phases].
    #[arg(long, allow_hyphen_values = true)]
    pub step_fraction: Option<f64>,
    /// Largest per-vertex gain of the step: a vertex that keeps moving the
    /// same way has its step multiplied by up to G (never beyond
    /// --step-fraction·L); 1 gives every vertex the one step [default: 3 in
    /// 2D, 1 in 3D].
    #[arg(long, value_name = "G", allow_hyphen_values = true)]
    pub step_gain: Option<f64>,
    /// Vertices asked to move less than this fraction of L in an iteration
    /// stay where they are (the noise's jitter about a settled interface)
    /// [default: 0.01 in 2D, 0 with --adaptive in 2D, 0.02 in 3D].
    #[arg(long, allow_hyphen_values = true)]
    pub min_move: Option<f64>,
    /// Also converged once the energy has not reached a new low (by 3·10⁻⁴
    /// of itself in 2D, 10⁻³ in 3D) for N iterations; 0: only the
    /// displacement rule [default: 5 in 2D, 7 in 3D, 10 with --adaptive in 2D].
    #[arg(long, value_name = "N")]
    pub converge_plateau: Option<usize>,
    /// A flip round that relabels fewer than this fraction of the cells is
    /// quiet: it does not restart the energy plateau of the stopping rule,
    /// and one that comes on a plateau half as long ends the run (0: every
    /// round counts) [default: 0 in 2D, 0.01 in 3D].
    #[arg(long, value_name = "F")]
    pub quiet_round_fraction: Option<f64>,
    /// Runs with flip rounds (3D; in 2D only with --flip-interval above 1):
    /// the interfaces count as settled once the energy's mean fall per
    /// iteration over the last 3 is less than this fraction of its fastest
    /// fall in one iteration; the settle round follows, and a quiet round
    /// ends the run (0: only the energy plateau) [default: 0 in 2D, 0.05 in
    /// 3D].
    #[arg(long, value_name = "F")]
    pub settle_rate: Option<f64>,
    /// Triple-junction force of eq. (7): `edge-local` (the default: each
    /// sample bracketed by its own edge's phases) or `paper` (literal: the
    /// junction's phases bracket every sample; grows wedges on blurred edges).
    #[arg(long, value_enum)]
    pub junction_force: Option<JunctionArg>,
    /// Weight w of the length (3D: area) term of the Mumford–Shah energy, a
    /// width in pixels (3D: voxels): a structure narrower than w pixels (a
    /// disk of smaller radius) whose intensity differs from its surroundings
    /// by Δ, the smallest gap between adjacent initial phase means (not below
    /// twice the pixels' spread about their means, not above the mean gap),
    /// costs more in boundary than it gains in fit and is removed; one k times
    /// that contrast is kept down to w/k² pixels. In practice the limit is
    /// wider: an edge's blur lowers a narrow structure's gain, and a structure
    /// much smaller than the cells (--edge-length) has none to hold it; the
    /// run warns of the objects it left out. One pixel of boundary costs
    /// w·Δ²/2 of data energy, so scaling or shifting the intensities changes
    /// nothing. Larger w: smoother, fewer small regions [default: 1.6 for 2
    /// phases, 5.5 for more; 3D 0.6 and 1.2].
    #[arg(long, allow_hyphen_values = true)]
    pub length_weight: Option<f64>,
    /// Adaptive resolution: a graded mesh, L at the interfaces, finer where
    /// the data is not explained (down to --min-edge-length), coarser away
    /// from interfaces (up to --max-edge-length). In 2D it starts at L and
    /// coarsens (--coarse-start: from a coarse mesh); in 3D, where it is the
    /// default, it starts from a coarse mesh.
    #[arg(long)]
    pub adaptive: bool,
    /// Smallest target edge length of the adaptive mesh, in the unit of the
    /// edge length [default: 1.5 pixels/voxels]; implies --adaptive.
    #[arg(long, allow_hyphen_values = true)]
    pub min_edge_length: Option<f64>,
    /// Largest target edge length of the adaptive mesh [default: smallest
    /// side/16 (3D: /10), at least L]; implies --adaptive.
    #[arg(long, allow_hyphen_values = true)]
    pub max_edge_length: Option<f64>,
    /// Adaptive runs: start from a mesh at the largest edge length and
    /// refine (coarse to fine) instead of starting at L and coarsening; in
    /// 2D the start is first refined where its cells mix the classes of the
    /// initial thresholds.
    #[arg(long)]
    pub coarse_start: bool,
}

impl EvolutionArgs {
    /// Overrides the defaults in `p` with every option given.
    fn apply(&self, p: &mut SegmentParams) {
        p.max_iterations = self.max_iterations;
        p.label_flips = !self.no_label_flips;
        let set = |field: &mut f64, v: Option<f64>| *field = v.unwrap_or(*field);
        set(&mut p.rigidity, self.rigidity);
        set(&mut p.elasticity, self.elasticity);
        set(&mut p.step_fraction, self.step_fraction);
        set(&mut p.step_gain, self.step_gain);
        set(&mut p.quiet_round_fraction, self.quiet_round_fraction);
        set(&mut p.settle_rate, self.settle_rate);
        set(&mut p.length_weight, self.length_weight);
        p.flip_interval = self.flip_interval.unwrap_or(p.flip_interval);
        if self.adaptive || self.min_edge_length.is_some() || self.max_edge_length.is_some() {
            p.use_adaptive_mesh();
        }
        // (after the adaptive mesh, which sets its own default)
        set(&mut p.min_move, self.min_move);
        if let Some(n) = self.converge_plateau {
            p.converge_plateau = (n > 0).then_some(n);
        }
        p.sizing.min_edge_length = self.min_edge_length.or(p.sizing.min_edge_length);
        p.sizing.max_edge_length = self.max_edge_length.or(p.sizing.max_edge_length);
        p.sizing.coarse_start |= self.coarse_start;
        if let Some(j) = self.junction_force {
            p.junction_force = match j {
                JunctionArg::Paper => JunctionForce::Paper,
                JunctionArg::EdgeLocal => JunctionForce::EdgeLocal,
            };
        }
    }
}

/// `--junction-force` values.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum JunctionArg {
    /// The junction's phases bracket every sample (the paper, literally).
    Paper,
    /// Each sample bracketed by its own edge's phases.
    EdgeLocal,
}

/// `--init` values of `segment`.
#[derive(Clone, Copy, Debug, PartialEq, ValueEnum)]
pub enum InitKind {
    /// Cells labelled by mean against the least-variance (multi-Otsu) thresholds of the histogram of the cell means.
    Histogram,
    /// Cells labelled by mean: N equal intervals of the dynamic range (bisection for N = 2).
    Range,
    /// Disks given with --disk, everything else phase 0.
    Disks,
    /// A label image given with --init-labels.
    Labels,
}

/// `--init` values of `segment3d`.
#[derive(Clone, Copy, Debug, PartialEq, ValueEnum)]
pub enum Init3Kind {
    /// Cells labelled by mean against the least-variance (multi-Otsu) thresholds of the histogram of the cell means.
    Histogram,
    /// Cells labelled by mean: N equal intervals of the dynamic range (bisection for N = 2).
    Range,
    /// Balls given with --ball, everything else phase 0.
    Balls,
    /// A label volume given with --init-labels.
    Labels,
}

/// The options of a 2D segmentation (everything but the input and outputs).
#[derive(Args, Clone, Debug)]
pub struct SegmentOptions {
    /// Number of phases N, 2..=64, or `auto`: chosen from the data (the
    /// largest count up to --max-phases whose phases are all regions of their
    /// own mean: none empty, none duplicating another's mean within the noise,
    /// none a band along edges, none without a plateau of its own beyond the
    /// blur of its edges) [default: 2, or the phantom's].
    #[arg(long, allow_hyphen_values = true, value_parser = parse_phases)]
    pub phases: Option<PhaseCount>,
    /// Largest number of phases tried by --phases auto.
    #[arg(long, default_value_t = crate::segment::auto::DEFAULT_MAX_PHASES)]
    pub max_phases: usize,
    /// Average edge length L of the mesh in pixels [default: min(W,H)/64·sqrt(N-1) clamped to 3..10,
    /// shortened down to 4 on an image whose noise is below a fifth of the gap between its phase means].
    #[arg(long, allow_hyphen_values = true)]
    pub edge_length: Option<f64>,
    /// Initialisation [default: disks when --disk is given, labels with
    /// --init-labels, else histogram].
    #[arg(long, value_enum)]
    pub init: Option<InitKind>,
    /// A disk for --init disks: X,Y,R in pixels, optionally ,PHASE (default 1). Repeatable.
    #[arg(
        long = "disk",
        value_name = "X,Y,R[,PHASE]",
        allow_hyphen_values = true
    )]
    pub disks: Vec<String>,
    /// Label image for --init labels (grayscale, same size as the image,
    /// values 0..N-1 as stored: 8 or 16 bit, or whole-numbered floats);
    /// implies --init labels.
    #[arg(long)]
    pub init_labels: Option<PathBuf>,
    /// Segment channel K (0-based) of a multi-channel TIFF (an ImageJ
    /// hyperstack or an OME-TIFF of several channels: only its pixels are
    /// decoded; of a multi-page TIFF, grayscale pages only), or of a colour image instead of its luminance (0 =
    /// red, 1 = green, 2 = blue, 3 = alpha; for a gray image with alpha 0 =
    /// gray, 1 = alpha).
    #[arg(long, value_name = "K")]
    pub channel: Option<usize>,
    /// Segment time point T (0-based) of a time-lapse TIFF (an ImageJ
    /// hyperstack or time series, an OME-TIFF of several time points): only
    /// its pixels are decoded (grayscale pages only).
    #[arg(long, value_name = "T")]
    pub time_point: Option<usize>,
    /// Pixel size X,Y to use instead of the file's (TIFF resolution tags,
    /// PNG pHYs; 1 otherwise), in the file's length unit.
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub spacing: Option<String>,
    /// The evolution's options.
    #[command(flatten)]
    pub evolution: EvolutionArgs,
}

impl SegmentOptions {
    /// `--spacing X,Y`: two positive numbers.
    pub fn spacing(&self) -> Result<Option<[f64; 2]>> {
        parse_spacing(self.spacing.as_deref(), "X,Y")
    }

    /// The segmentation parameters these options give, `default_phases`
    /// when `--phases` is absent. `--init labels` yields empty labels, which
    /// the pipeline loads from `--init-labels` once it knows the image size.
    pub fn params(&self, default_phases: usize) -> Result<SegmentParams> {
        let (given, auto) = match self.phases {
            Some(PhaseCount::Auto) => (None, Some(self.max_phases)),
            Some(PhaseCount::Count(n)) => (Some(n), None),
            None => (None, None),
        };
        let mut params = SegmentParams::new(phase_count(given, default_phases)?);
        params.auto_phases = auto;
        params.edge_length = self.edge_length;
        self.evolution.apply(&mut params);
        let init = implied_start(
            self.init,
            (!self.disks.is_empty()).then_some((InitKind::Disks, "--disk", "disks")),
            self.init_labels.is_some(),
            InitKind::Labels,
        )?
        .unwrap_or(InitKind::Histogram);
        params.init = match init {
            InitKind::Histogram => Init::Histogram,
            InitKind::Range => Init::Range,
            InitKind::Disks => Init::Disks(parse_all(
                &self.disks,
                "--init disks",
                "--disk X,Y,R",
                parse_disk,
            )?),
            InitKind::Labels => labels_init(self.init_labels.is_some(), "PNG")?,
        };
        Ok(params)
    }
}

/// The options of a 3D segmentation (everything but the input and outputs).
#[derive(Args, Clone, Debug)]
pub struct Segment3dOptions {
    /// Number of phases N, 2..=64 [default: the phantom's number without
    /// VOLUME, else 2]. (`auto` is for 2D images only.)
    #[arg(long, allow_hyphen_values = true, value_parser = parse_phases_3d)]
    pub phases: Option<i64>,
    /// Average edge length L of the mesh in the volume's length unit (voxels without a voxel
    /// size) [default: smallest side/64·sqrt(N-1) clamped to 3..10 voxel-sized steps].
    #[arg(long, allow_hyphen_values = true)]
    pub edge_length: Option<f64>,
    /// Initialisation [default: balls when --ball is given, labels with
    /// --init-labels, else histogram].
    #[arg(long, value_enum)]
    pub init: Option<Init3Kind>,
    /// A ball for --init balls: X,Y,Z,R in the volume's length unit from the corner of voxel 0
    /// (voxels without a voxel size), optionally ,PHASE (default 1). Repeatable.
    #[arg(
        long = "ball",
        value_name = "X,Y,Z,R[,PHASE]",
        allow_hyphen_values = true
    )]
    pub balls: Vec<String>,
    /// Label volume for --init labels (same size as the volume, values
    /// 0..N-1 as stored, of any integer type or whole-numbered floats);
    /// implies --init labels.
    #[arg(long)]
    pub init_labels: Option<PathBuf>,
    /// Initial surface (closed triangle mesh: OFF, OBJ or STL, in voxel
    /// coordinates strictly inside [0,nx]×[0,ny]×[0,nz], so for a volume
    /// without a voxel size, or with --spacing 1,1,1): the initial mesh is
    /// tetrahedralised by TetGen to conform to it, phase 1 inside, 0 outside;
    /// replaces --init. Needs a build with `--features tetgen` (AGPL-3 TetGen).
    #[allow(rustdoc::broken_intra_doc_links)] // the brackets are intervals, shown as is by --help
    #[arg(long, value_name = "FILE")]
    pub init_surface: Option<PathBuf>,
    /// Segment channel C (0-based) of a multi-channel TIFF (an ImageJ
    /// hyperstack or an OME-TIFF of several channels): only that channel's
    /// slices are read, at the file's voxel size.
    #[arg(long, value_name = "C")]
    pub channel: Option<usize>,
    /// Segment time point T (0-based) of a time-lapse TIFF (an ImageJ
    /// hyperstack, an OME-TIFF of several time points): only that time
    /// point's slices are read.
    #[arg(long, value_name = "T")]
    pub time_point: Option<usize>,
    /// Voxel size X,Y,Z to use instead of the file's (a NIfTI's axes keep
    /// their directions and voxel 0 its place).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub spacing: Option<String>,
    /// The paper's uniform mesh at L everywhere, started at L, instead of
    /// the 3D default (adaptive resolution from a coarse start).
    #[arg(long, conflicts_with_all = ["adaptive", "min_edge_length", "max_edge_length", "coarse_start", "refine_start"])]
    pub uniform: bool,
    /// Refine the coarse start mesh up to N times before the first
    /// iteration, each time resizing it to the sizing field (L at the
    /// labels' interfaces) and running the label flips on the refined
    /// cells: the interfaces start near where the data puts them. Fewer
    /// iterations at a higher Dice on the brain-like phantom, a lower Dice
    /// on the three- and four-phase phantoms. With the coarse pass (volumes
    /// of 128 voxels a side and more) it refines the pass's start mesh
    /// [default: 0]
    #[arg(long, value_name = "N")]
    pub refine_start: Option<usize>,
    /// Stop when the stopping rule is met, without the fine finish (the
    /// interfaces refined to L/2, not below the edge of a tetrahedron of one
    /// voxel, for 2 more iterations; with three or more
    /// phases the first of them is a last flip round), which
    /// makes data differing by a re-quantisation give the same labels
    #[arg(long)]
    pub no_fine_finish: bool,
    /// The fine finish's rigidity after its first iteration, as a multiple
    /// of the run's β: a stiffer refined surface rests closer to where two
    /// runs on slightly different data put it (with a 5-iteration finish, 4
    /// raised the 64³ three- and four-phase phantoms' Dice and agreement but
    /// lowered the brain-like phantom's) [default: 1]
    #[arg(long, value_name = "F")]
    pub finish_rigidity: Option<f64>,
    /// Start from the mesh of the volume itself rather than from the final
    /// mesh of a run on the volume at half resolution (at 2·L, without the
    /// fine finish), which volumes of at least 128 voxels a side get by
    /// default: their interfaces then start near the data's instead of
    /// travelling there at full resolution
    #[arg(long)]
    pub no_coarse_pass: bool,
    /// Keep layers of an intermediate phase as thin as the band a blurred
    /// edge leaves between two other phases: by default (three or more
    /// phases) they go back to the phases on their sides, since under the
    /// edges' blur (estimated from the data) they cannot be told from that
    /// band; keep them for real layers that thin
    #[arg(long)]
    pub keep_thin_layers: bool,
    /// The evolution's options.
    #[command(flatten)]
    pub evolution: EvolutionArgs,
}

impl Segment3dOptions {
    /// `--spacing X,Y,Z`: three positive numbers.
    pub fn spacing(&self) -> Result<Option<[f64; 3]>> {
        parse_spacing(self.spacing.as_deref(), "X,Y,Z")
    }

    /// The segmentation parameters these options give, `default_phases`
    /// when `--phases` is absent (see [`SegmentOptions::params`] for
    /// `--init labels`).
    pub fn params(&self, default_phases: usize) -> Result<SegmentParams> {
        let mut params = SegmentParams::new_3d(phase_count(self.phases, default_phases)?);
        params.edge_length = self.edge_length;
        if self.uniform {
            params.sizing.adaptive = false;
            params.sizing.coarse_start = false;
        }
        if let Some(n) = self.refine_start {
            params.sizing.start_refinements = n;
        }
        if self.no_fine_finish {
            params.sizing.finish = None;
        }
        if let (Some(factor), Some(finish)) = (self.finish_rigidity, &mut params.sizing.finish) {
            finish.rigidity_factor = factor;
        }
        if self.no_coarse_pass {
            params.coarse_pass = false;
        }
        if self.keep_thin_layers {
            params.band_flips = false;
        }
        self.evolution.apply(&mut params);
        let init = implied_start(
            self.init,
            (!self.balls.is_empty()).then_some((Init3Kind::Balls, "--ball", "balls")),
            self.init_labels.is_some(),
            Init3Kind::Labels,
        )?
        .unwrap_or(Init3Kind::Histogram);
        params.init = match init {
            Init3Kind::Histogram => Init::Histogram,
            Init3Kind::Range => Init::Range,
            Init3Kind::Balls => Init::Balls(parse_all(
                &self.balls,
                "--init balls",
                "--ball X,Y,Z,R",
                parse_ball,
            )?),
            Init3Kind::Labels => labels_init(self.init_labels.is_some(), "VOLUME")?,
        };
        Ok(params)
    }
}

/// A `--spacing` value: `N` positive finite numbers separated by commas
/// (`form` names them in the error).
fn parse_spacing<const N: usize>(given: Option<&str>, form: &str) -> Result<Option<[f64; N]>> {
    let Some(s) = given else {
        return Ok(None);
    };
    let bad = || {
        Error::Usage(format!(
            "--spacing {s:?}: expected {N} positive numbers {form}"
        ))
    };
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| bad())?;
    if !v.iter().all(|d| d.is_finite() && *d > 0.0) {
        return Err(bad());
    }
    v.try_into().map(Some).map_err(|_| bad())
}

/// A `--phases` value: a count, or `auto`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhaseCount {
    /// This many phases.
    Count(i64),
    /// Chosen from the data.
    Auto,
}

fn parse_phases(s: &str) -> std::result::Result<PhaseCount, String> {
    if s.trim().eq_ignore_ascii_case("auto") {
        return Ok(PhaseCount::Auto);
    }
    s.trim()
        .parse::<i64>()
        .map(PhaseCount::Count)
        .map_err(|_| format!("{s:?} is neither a number of phases nor auto"))
}

/// A `segment3d --phases` value: a count (the choice from the data,
/// `auto`, is for 2D images only).
fn parse_phases_3d(s: &str) -> std::result::Result<i64, String> {
    match parse_phases(s)? {
        PhaseCount::Count(n) => Ok(n),
        PhaseCount::Auto => Err(
            "auto chooses the number of phases of 2D images only (`dsc-seg segment`); \
             give segment3d a number"
                .into(),
        ),
    }
}

/// The number of phases, `default` when not given.
fn phase_count(given: Option<i64>, default: usize) -> Result<usize> {
    match given {
        None => Ok(default),
        Some(n) if (2..=64).contains(&n) => Ok(n as usize),
        Some(n) => Err(Error::Usage(format!(
            "--phases {n}: the number of phases must be between 2 and 64"
        ))),
    }
}

/// The comma-separated numbers of a `--disk`/`--ball` value: `fixed` of
/// them, then optionally a phase (a whole number ≥ 0; 1 when absent).
fn parse_shape(s: &str, option: &str, fixed: usize, form: &str) -> Result<(Vec<f64>, u32)> {
    let bad = || Error::Usage(format!("{option} {s:?}: expected {form}"));
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| bad())?;
    let phase = match v.get(fixed) {
        _ if v.len() < fixed || v.len() > fixed + 1 => return Err(bad()),
        None => 1,
        Some(&p) if p >= 0.0 && p.fract() == 0.0 => p as u32,
        Some(_) => return Err(bad()),
    };
    Ok((v[..fixed].to_vec(), phase))
}

/// Every `--disk`/`--ball` value parsed; `init` needs at least one.
fn parse_all<T>(
    specs: &[String],
    init: &str,
    option: &str,
    parse: impl Fn(&str) -> Result<T>,
) -> Result<Vec<T>> {
    if specs.is_empty() {
        return Err(Error::Usage(format!("{init} needs at least one {option}")));
    }
    specs.iter().map(|s| parse(s)).collect()
}

/// `--init labels`: the labels are loaded by the pipeline from `--init-labels`.
/// The start `--init` and the start's own options ask for (`None`: the
/// default). A shape option (`shapes`: its start, flag and `--init` name)
/// or `--init-labels` (`labels`, whose start is `labels_kind`) implies its
/// start; one given with another start is an error rather than ignored.
fn implied_start<T: Copy + PartialEq>(
    init: Option<T>,
    shapes: Option<(T, &str, &str)>,
    labels: bool,
    labels_kind: T,
) -> Result<Option<T>> {
    let usage = |flag: &str, name: &str| {
        Error::Usage(format!(
            "{flag} is only used by --init {name} (or without --init)"
        ))
    };
    if let Some((kind, flag, name)) = shapes {
        if labels {
            return Err(Error::Usage(format!(
                "{flag} and --init-labels are two different starts: give one"
            )));
        }
        return match init {
            Some(k) if k != kind => Err(usage(flag, name)),
            _ => Ok(Some(kind)),
        };
    }
    if labels {
        return match init {
            Some(k) if k != labels_kind => Err(usage("--init-labels", "labels")),
            _ => Ok(Some(labels_kind)),
        };
    }
    Ok(init)
}

fn labels_init(given: bool, what: &str) -> Result<Init> {
    if !given {
        return Err(Error::Usage(format!(
            "--init labels needs --init-labels {what}"
        )));
    }
    Ok(Init::Labels { labels: Vec::new() })
}

fn parse_disk(s: &str) -> Result<InitDisk> {
    let (v, phase) = parse_shape(s, "--disk", 3, "X,Y,R[,PHASE]")?;
    Ok(InitDisk {
        x: v[0],
        y: v[1],
        r: v[2],
        phase,
    })
}

fn parse_ball(s: &str) -> Result<InitBall> {
    let (v, phase) = parse_shape(s, "--ball", 4, "X,Y,Z,R[,PHASE]")?;
    Ok(InitBall {
        centre: [v[0], v[1], v[2]],
        r: v[3],
        phase,
    })
}

/// A command-line parse error as one line, like every other error: clap's
/// first paragraph (its usage and tips follow a blank line) with the lines joined.
pub fn one_line(e: &clap::Error) -> String {
    let text = e.to_string();
    let first: Vec<&str> = text
        .lines()
        .take_while(|l| !l.trim().is_empty())
        .map(str::trim)
        .collect();
    let msg = first.join(" ");
    msg.strip_prefix("error: ").unwrap_or(&msg).to_string()
}
