//! The `dsc-seg` command line: argument parsing only; the library does the work.

use clap::{Parser, Subcommand, ValueEnum};
use dsc_seg::pipeline::{run_phantom, run_segment, SegmentJob, Source};
use dsc_seg::pipeline3d::{run_phantom3d, run_segment3d, Segment3dJob};
use dsc_seg::segment::{Init, InitBall, InitDisk, JunctionForce, SegmentParams};
use dsc_seg::Error;
use std::path::PathBuf;
use std::process::ExitCode;

/// Multiphase image segmentation with the deformable simplicial complex (DSC).
#[derive(Parser, Debug)]
#[command(name = "dsc-seg", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Segment an image (or, without IMAGE, a built-in phantom) into N phases.
    ///
    /// Writes labels.png (phase index 0..N-1 ordered by increasing mean),
    /// overlay.png and overlay.svg, mesh.vtu (cell data `phase`) and
    /// report.json into --out.
    Segment(SegmentArgs),
    /// Write a phantom image with its ground truth (NAME.png, NAME_gt.png, NAME_labels.png).
    Phantom(PhantomArgs),
    /// Segment a volume (or, without VOLUME, a built-in 3D phantom) into N phases
    /// with the tetrahedral DSC.
    ///
    /// Writes labels.tif (multi-page 8-bit, phase index 0..N-1 ordered by
    /// increasing mean), mesh.vtu (tetrahedra, cell data `phase`),
    /// interface.vtp (interface triangles, cell data `phase` and `phase_other`)
    /// and report.json into --out.
    Segment3d(Segment3dArgs),
    /// Write a 3D phantom volume with its ground truth (NAME.tif, NAME_labels.tif).
    Phantom3d(Phantom3dArgs),
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum Init3Kind {
    /// Cells labelled by mean: N equal intervals of the dynamic range (bisection for N = 2).
    Range,
    /// Balls given with --ball, everything else phase 0.
    Balls,
    /// A label volume given with --init-labels.
    Labels,
}

#[derive(Parser, Debug)]
#[command(allow_negative_numbers = true)]
struct Segment3dArgs {
    /// Input volume: a multi-page TIFF stack (8/16 bit), a folder of 2D slices, or
    /// NIfTI (.nii, .nii.gz). Without it, a built-in 3D phantom is segmented.
    volume: Option<PathBuf>,
    /// Output directory (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Number of phases N, 2..=64.
    #[arg(long, allow_hyphen_values = true, default_value_t = 2)]
    phases: i64,
    /// Average edge length L of the mesh in voxels [default: smallest side/64·sqrt(N-1) clamped to 3..10].
    #[arg(long, allow_hyphen_values = true)]
    edge_length: Option<f64>,
    /// Initialisation.
    #[arg(long, value_enum, default_value_t = Init3Kind::Range)]
    init: Init3Kind,
    /// A ball for --init balls: X,Y,Z,R in voxels, optionally ,PHASE (default 1). Repeatable.
    #[arg(
        long = "ball",
        value_name = "X,Y,Z,R[,PHASE]",
        allow_hyphen_values = true
    )]
    balls: Vec<String>,
    /// Label volume for --init labels (same size as the volume, 8-bit values 0..N-1).
    #[arg(long)]
    init_labels: Option<PathBuf>,
    /// Initial surface (closed triangle mesh: OFF, OBJ or STL, in voxel
    /// coordinates strictly inside [0,nx]×[0,ny]×[0,nz]): the initial mesh is
    /// tetrahedralised by TetGen to conform to it, phase 1 inside, 0 outside;
    /// replaces --init. Needs a build with `--features tetgen` (AGPL-3 TetGen).
    #[arg(long, value_name = "FILE")]
    init_surface: Option<PathBuf>,
    #[command(flatten)]
    evolution: EvolutionArgs,
    /// Built-in 3D phantom to segment when no VOLUME is given.
    #[arg(long, default_value = "two_balls")]
    phantom: String,
    /// Phantom side in voxels (without VOLUME).
    #[arg(long, default_value_t = 64)]
    phantom_size: usize,
    /// Phantom noise standard deviation (without VOLUME).
    #[arg(long, default_value_t = 0.1)]
    phantom_noise: f64,
    /// Phantom noise seed (without VOLUME).
    #[arg(long, default_value_t = 1)]
    phantom_seed: u64,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

#[derive(Parser, Debug)]
#[command(allow_negative_numbers = true)]
struct Phantom3dArgs {
    /// two_balls, torus or hollow_sphere.
    name: String,
    /// Side in voxels.
    #[arg(long, default_value_t = 64)]
    size: usize,
    /// Standard deviation of the additive Gaussian noise (intensities in [0,1]).
    #[arg(long, default_value_t = 0.1, allow_hyphen_values = true)]
    noise: f64,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
}

/// The evolution's options, shared by `segment` and `segment3d`.
#[derive(clap::Args, Debug)]
struct EvolutionArgs {
    /// Iteration cap.
    #[arg(long, default_value_t = 500)]
    max_iterations: usize,
    /// Keep every cell's label: only the interfaces move.
    #[arg(long)]
    no_label_flips: bool,
    /// Try label flips every K iterations [default: 1 in 2D, 20 in 3D].
    #[arg(long, value_name = "K")]
    flip_interval: Option<usize>,
    /// Rigidity weight β of eq. (2).
    #[arg(long, allow_hyphen_values = true)]
    rigidity: Option<f64>,
    /// Elasticity weight α of eq. (2) (off by default, as in the paper).
    #[arg(long, allow_hyphen_values = true)]
    elasticity: Option<f64>,
    /// Largest displacement per iteration as a fraction of L.
    #[arg(long, allow_hyphen_values = true)]
    step_fraction: Option<f64>,
    /// Triple-junction force of eq. (7): `edge-local` (the default: each
    /// sample bracketed by its own edge's phases) or `paper` (literal: the
    /// junction's phases bracket every sample; grows wedges on blurred edges).
    #[arg(long, value_enum)]
    junction_force: Option<JunctionArg>,
    /// Weight of the length (3D: area) term of the Mumford–Shah energy, as a
    /// multiple of the smallest gap between phase means.
    #[arg(long, allow_hyphen_values = true)]
    length_weight: Option<f64>,
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
        set(&mut p.length_weight, self.length_weight);
        p.flip_interval = self.flip_interval.unwrap_or(p.flip_interval);
        if let Some(j) = self.junction_force {
            p.junction_force = match j {
                JunctionArg::Paper => JunctionForce::Paper,
                JunctionArg::EdgeLocal => JunctionForce::EdgeLocal,
            };
        }
    }
}

/// The number of phases, `default` when not given.
fn phase_count(given: Option<i64>, default: usize) -> Result<usize, Error> {
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
fn parse_shape(s: &str, option: &str, fixed: usize, form: &str) -> Result<(Vec<f64>, u32), Error> {
    let bad = || Error::Usage(format!("{option} {s:?}: expected {form}"));
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    let phase = match v.get(fixed) {
        _ if v.len() < fixed || v.len() > fixed + 1 => return Err(bad()),
        None => 1,
        Some(&p) if p >= 0.0 && p.fract() == 0.0 => p as u32,
        Some(_) => return Err(bad()),
    };
    Ok((v[..fixed].to_vec(), phase))
}

/// `--junction-force` values.
#[derive(Clone, Copy, Debug, ValueEnum)]
enum JunctionArg {
    Paper,
    EdgeLocal,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum InitKind {
    /// Cells labelled by mean: N equal intervals of the dynamic range (bisection for N = 2).
    Range,
    /// Disks given with --disk, everything else phase 0.
    Disks,
    /// A label PNG given with --init-labels.
    Labels,
}

#[derive(Parser, Debug)]
#[command(allow_negative_numbers = true)]
struct SegmentArgs {
    /// Input image (PNG, TIFF, JPEG, ...; 8/16 bit, gray or colour). Without it, a built-in phantom is segmented.
    image: Option<PathBuf>,
    /// Output directory (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Number of phases N, 2..=64 [default: 2, or the phantom's].
    #[arg(long, allow_hyphen_values = true)]
    phases: Option<i64>,
    /// Average edge length L of the mesh in pixels [default: min(W,H)/64·sqrt(N-1) clamped to 3..10].
    #[arg(long, allow_hyphen_values = true)]
    edge_length: Option<f64>,
    /// Initialisation.
    #[arg(long, value_enum, default_value_t = InitKind::Range)]
    init: InitKind,
    /// A disk for --init disks: X,Y,R in pixels, optionally ,PHASE (default 1). Repeatable.
    #[arg(
        long = "disk",
        value_name = "X,Y,R[,PHASE]",
        allow_hyphen_values = true
    )]
    disks: Vec<String>,
    /// Label PNG for --init labels (same size as the image, values 0..N-1).
    #[arg(long)]
    init_labels: Option<PathBuf>,
    #[command(flatten)]
    evolution: EvolutionArgs,
    /// Built-in phantom to segment when no IMAGE is given.
    #[arg(long, default_value = "four_phase")]
    phantom: String,
    /// Phantom size in pixels (without IMAGE).
    #[arg(long, default_value_t = 256)]
    phantom_size: usize,
    /// Phantom noise standard deviation (without IMAGE).
    #[arg(long, default_value_t = 0.1)]
    phantom_noise: f64,
    /// Phantom noise seed (without IMAGE).
    #[arg(long, default_value_t = 1)]
    phantom_seed: u64,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

#[derive(Parser, Debug)]
#[command(allow_negative_numbers = true)]
struct PhantomArgs {
    /// two_phase, four_phase, fig2, fig3, fig4, fig5 or fig6.
    name: String,
    /// Side in pixels.
    #[arg(long, default_value_t = 256)]
    size: usize,
    /// Standard deviation of the additive Gaussian noise (intensities in [0,1]).
    #[arg(long, default_value_t = 0.1, allow_hyphen_values = true)]
    noise: f64,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
}

/// Every `--disk`/`--ball` value parsed; `init` needs at least one.
fn parse_all<T>(
    specs: &[String],
    init: &str,
    option: &str,
    parse: impl Fn(&str) -> Result<T, Error>,
) -> Result<Vec<T>, Error> {
    if specs.is_empty() {
        return Err(Error::Usage(format!("{init} needs at least one {option}")));
    }
    specs.iter().map(|s| parse(s)).collect()
}

/// `--init labels`: the labels are loaded by the pipeline from `--init-labels`.
fn labels_init(given: bool, what: &str) -> Result<Init, Error> {
    if !given {
        return Err(Error::Usage(format!(
            "--init labels needs --init-labels {what}"
        )));
    }
    Ok(Init::Labels { labels: Vec::new() })
}

fn parse_disk(s: &str) -> Result<InitDisk, Error> {
    let (v, phase) = parse_shape(s, "--disk", 3, "X,Y,R[,PHASE]")?;
    Ok(InitDisk {
        x: v[0],
        y: v[1],
        r: v[2],
        phase,
    })
}

fn segment(a: SegmentArgs) -> Result<(), Error> {
    let (source, default_phases) = match &a.image {
        Some(p) => (Source::File(p.clone()), 2),
        None => {
            let kind = dsc_seg::phantom::Phantom2Kind::from_name(&a.phantom)
                .ok_or_else(|| Error::Usage(format!("unknown phantom {:?}", a.phantom)))?;
            (
                Source::Phantom {
                    name: kind.name().to_string(),
                    size: a.phantom_size,
                    noise: a.phantom_noise,
                    seed: a.phantom_seed,
                },
                kind.phases(),
            )
        }
    };
    let mut params = SegmentParams::new(phase_count(a.phases, default_phases)?);
    params.edge_length = a.edge_length;
    a.evolution.apply(&mut params);
    params.init = match a.init {
        InitKind::Range => Init::Range,
        InitKind::Disks => Init::Disks(parse_all(
            &a.disks,
            "--init disks",
            "--disk X,Y,R",
            parse_disk,
        )?),
        InitKind::Labels => labels_init(a.init_labels.is_some(), "PNG")?,
    };
    let job = SegmentJob {
        source,
        out: a.out,
        params,
        init_labels: a.init_labels,
        quiet: a.quiet,
    };
    let report = run_segment(&job)?;
    if !a.quiet {
        print_summary(&report, "cells", &job.out);
    }
    Ok(())
}

fn parse_ball(s: &str) -> Result<InitBall, Error> {
    let (v, phase) = parse_shape(s, "--ball", 4, "X,Y,Z,R[,PHASE]")?;
    Ok(InitBall {
        centre: [v[0], v[1], v[2]],
        r: v[3],
        phase,
    })
}

fn segment3d(a: Segment3dArgs) -> Result<(), Error> {
    let source = match &a.volume {
        Some(p) => Source::File(p.clone()),
        None => Source::Phantom {
            name: a.phantom.clone(),
            size: a.phantom_size,
            noise: a.phantom_noise,
            seed: a.phantom_seed,
        },
    };
    let mut params = SegmentParams::new_3d(phase_count(Some(a.phases), 2)?);
    params.edge_length = a.edge_length;
    a.evolution.apply(&mut params);
    params.init = match a.init {
        Init3Kind::Range => Init::Range,
        Init3Kind::Balls => Init::Balls(parse_all(
            &a.balls,
            "--init balls",
            "--ball X,Y,Z,R",
            parse_ball,
        )?),
        Init3Kind::Labels => labels_init(a.init_labels.is_some(), "VOLUME")?,
    };
    let job = Segment3dJob {
        source,
        out: a.out,
        params,
        init_labels: a.init_labels,
        init_surface: a.init_surface,
        quiet: a.quiet,
    };
    let report = run_segment3d(&job)?;
    if !a.quiet {
        print_summary(&report, "tets", &job.out);
    }
    Ok(())
}

/// One line on stderr: how the run ended and where the outputs are.
fn print_summary(report: &dsc_seg::segment::SegmentReport, cells: &str, out: &std::path::Path) {
    let ending = if report.converged {
        "converged"
    } else {
        "stopped at the iteration cap"
    };
    eprintln!(
        "{ending} after {} iterations ({:.2} s), {} {cells}; outputs in {}",
        report.iterations,
        report.times.total,
        report.cells,
        out.display()
    );
}

/// A command-line parse error as one line, like every other error: clap's
/// first paragraph (its usage and tips follow a blank line) with the lines joined.
fn one_line(e: &clap::Error) -> String {
    let text = e.to_string();
    let first: Vec<&str> = text
        .lines()
        .take_while(|l| !l.trim().is_empty())
        .map(str::trim)
        .collect();
    let msg = first.join(" ");
    format!(
        "{} (see --help)",
        msg.strip_prefix("error: ").unwrap_or(&msg)
    )
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        // --help, --version and a bare `dsc-seg` get clap's full text.
        Err(e)
            if !e.use_stderr()
                || e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand =>
        {
            e.exit()
        }
        Err(e) => {
            eprintln!("error: {}", one_line(&e));
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        Command::Segment(a) => segment(a),
        Command::Phantom(a) => run_phantom(&a.name, a.size, a.noise, a.seed, &a.out).map(|names| {
            for n in names {
                println!("{}", a.out.join(n).display());
            }
        }),
        Command::Segment3d(a) => segment3d(a),
        Command::Phantom3d(a) => {
            run_phantom3d(&a.name, a.size, a.noise, a.seed, &a.out).map(|names| {
                for n in names {
                    println!("{}", a.out.join(n).display());
                }
            })
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let msg = e.to_string().replace('\n', " ");
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}
