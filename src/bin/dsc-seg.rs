//! The `dsc-seg` command line: argument parsing only; the library does the work.

use clap::{Parser, Subcommand};
use dsc_seg::batch::{
    expand_inputs, image_subfolders, is_batch_folder, nifti_volumes_left_out, Batch, Shard, Status,
    Task,
};
use dsc_seg::options::{one_line, Segment3dOptions, SegmentOptions};
use dsc_seg::pipeline::{
    check_phantom_source, run_phantom, run_phantom3d, run_segment, run_segment3d, Segment3dJob,
    SegmentJob, Source,
};
use dsc_seg::segmented::Outputs;
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
    /// Segment images (or, without IMAGE, a built-in phantom) into N phases.
    ///
    /// One image: writes into --out labels.png (phase index 0..N-1 ordered
    /// by increasing mean; a TIFF input also gets labels.tif), overlay.png
    /// and overlay.svg, mesh.vtu (cell data `phase`), interface.vtp,
    /// image.vti, scene.vtm and scene.pvd, phases.csv and interfaces.csv,
    /// and report.json (--outputs chooses). Several images or a folder: the
    /// same into --out/<stem>/ per image, and --out/summary.csv.
    Segment(SegmentArgs),
    /// Write a phantom image with its ground truth (NAME.png, NAME_gt.png,
    /// NAME_labels.png; fig6 also NAME_init.png, the user labelling of Fig. 6).
    Phantom(PhantomArgs),
    /// Segment volumes (or, without VOLUME, a built-in 3D phantom) into N
    /// phases with the tetrahedral DSC.
    ///
    /// One volume: writes into --out labels.tif (multi-page 8-bit, phase
    /// index 0..N-1 ordered by increasing mean; labels.nii.gz instead for a
    /// NIfTI input), mesh.vtu (tetrahedra, cell data `phase`),
    /// interface.vtp (interface triangles, cell data `phase` and
    /// `phase_other`), image.vti, scene.vtm and scene.pvd, phases.csv and
    /// interfaces.csv, and report.json (--outputs chooses). Several volumes
    /// or a folder of volumes: the same into --out/<stem>/ per volume, and
    /// --out/summary.csv.
    Segment3d(Segment3dArgs),
    /// Write a 3D phantom volume with its ground truth (NAME.tif, NAME_labels.tif).
    Phantom3d(Phantom3dArgs),
}

/// The options of runs over several inputs.
#[derive(clap::Args, Debug)]
struct BatchArgs {
    /// The outputs to write, comma-separated: labels, overlay (2D), mesh,
    /// interface, image (image.vti), phases (phases.csv, interfaces.csv),
    /// report, or all. scene.vtm and scene.pvd come with any VTK file.
    #[arg(long, default_value = "all")]
    outputs: String,
    /// Inputs segmented at once, each on one thread, at least 1 (checked
    /// for a single input too) [default: the number of cores].
    #[arg(long, value_name = "N", value_parser = parse_jobs)]
    jobs: Option<std::num::NonZeroUsize>,
    /// Only inputs I, I+N, I+2N, ... of the list (0 <= I < N), for job
    /// arrays on a cluster; the summary is then summary-I-of-N.csv.
    #[arg(long, value_name = "I/N")]
    shard: Option<Shard>,
    /// Redo inputs whose outputs are already complete.
    #[arg(long)]
    force: bool,
}

#[derive(Parser, Debug)]
#[command(allow_negative_numbers = true)]
struct Segment3dArgs {
    /// Input volumes: multi-page grayscale TIFF stacks (8/16 bit, or signed,
    /// 32-bit or float samples), folders of 2D slices,
    /// NIfTI (.nii, .nii.gz), or folders of these. Without any, a built-in 3D
    /// phantom is segmented.
    volumes: Vec<PathBuf>,
    /// Output directory (created if missing).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    options: Segment3dOptions,
    #[command(flatten)]
    batch: BatchArgs,
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
    /// two_balls, torus, hollow_sphere (two phases), three_phase, four_phase
    /// (junction curves) or brain (four classes, 160×190×150 at --size 190).
    name: String,
    /// Side in voxels (the brain's longest side).
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

#[derive(Parser, Debug)]
#[command(allow_negative_numbers = true)]
struct SegmentArgs {
    /// Input images (PNG, TIFF, JPEG, ...; 8/16 bit, gray or colour; TIFFs
    /// of float or signed samples; a NIfTI one slice thick) or folders of
    /// them. Without any, a built-in phantom is segmented.
    images: Vec<PathBuf>,
    /// Output directory (created if missing).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    options: SegmentOptions,
    #[command(flatten)]
    batch: BatchArgs,
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
    /// two_phase, four_phase (the benchmark images), fig2 ... fig6 (the
    /// paper's figures), three_close, four_close (close means),
    /// two_phase_specks, four_phase_specks (salt-and-pepper specks),
    /// disks2 ... disks6 (disks of 2 to 6 phases) or thin (lines, arcs,
    /// small blobs, a slit, a star).
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

/// Whether `inputs` make a batch: more than one, or a folder of inputs.
fn is_batch(inputs: &[PathBuf], three_d: bool) -> bool {
    inputs.len() > 1 || inputs.iter().any(|p| is_batch_folder(p, three_d))
}

/// How a command failed: an option that does not parse or fit (exit 2, as
/// clap's own usage errors) or the run itself (exit 1).
enum Failure {
    Options(Error),
    Run(Error),
}

impl From<Error> for Failure {
    /// A parameter out of its range is an option's failure, whichever stage
    /// checks it; anything else, the run's.
    fn from(e: Error) -> Self {
        match &e {
            Error::Segment(s) if s.is_parameter() => Failure::Options(e),
            _ => Failure::Run(e),
        }
    }
}

/// A `phantom`/`phantom3d` failure: its name, side or noise (the only usage
/// errors it has) are options; writing the files is the run.
fn phantom_failure(e: Error) -> Failure {
    match e {
        Error::Usage(_) => Failure::Options(e),
        _ => Failure::Run(e),
    }
}

/// An option's value, or the usage failure it is.
fn option<T>(value: Result<T, Error>) -> Result<T, Failure> {
    value.map_err(Failure::Options)
}

fn segment(a: SegmentArgs) -> Result<(), Failure> {
    let outputs = option(Outputs::parse(&a.batch.outputs, false))?;
    if is_batch(&a.images, false) {
        let task = Task::Image {
            params: option(a.options.params(2))?,
            init_labels: a.options.init_labels.clone(),
            channel: a.options.channel,
            time_point: a.options.time_point,
            spacing: option(a.options.spacing())?,
        };
        return run_batch(&a.images, task, a.out, outputs, &a.batch, a.quiet);
    }
    let (source, default_phases) = match a.images.first() {
        Some(p) => (Source::File(p.clone()), 2),
        None => {
            let kind = dsc_seg::phantom::Phantom2Kind::from_name(&a.phantom)
                .ok_or_else(|| Error::Usage(format!("unknown phantom {:?}", a.phantom)))
                .map_err(Failure::Options)?;
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
    option(check_phantom_source(&source, false))?;
    let spacing = option(a.options.spacing())?;
    let job = SegmentJob {
        source,
        out: a.out,
        params: option(a.options.params(default_phases))?,
        init_labels: a.options.init_labels,
        outputs,
        quiet: a.quiet,
        channel: a.options.channel,
        time_point: a.options.time_point,
        spacing,
    };
    let report = run_segment(&job)?;
    print_warnings(&report);
    print_earlier_outputs(&outputs.earlier_outputs(false, &job.out), &job.out);
    if !a.quiet {
        print_summary(&report, "cells", &job.out);
    }
    Ok(())
}

fn segment3d(a: Segment3dArgs) -> Result<(), Failure> {
    let outputs = option(Outputs::parse(&a.batch.outputs, true))?;
    if is_batch(&a.volumes, true) {
        let task = Task::Volume {
            params: option(a.options.params(2))?,
            init_labels: a.options.init_labels.clone(),
            init_surface: a.options.init_surface.clone(),
            channel: a.options.channel,
            time_point: a.options.time_point,
            spacing: option(a.options.spacing())?,
        };
        return run_batch(&a.volumes, task, a.out, outputs, &a.batch, a.quiet);
    }
    let (source, default_phases) = match a.volumes.first() {
        Some(p) => (Source::File(p.clone()), 2),
        None => (
            Source::Phantom {
                name: a.phantom.clone(),
                size: a.phantom_size,
                noise: a.phantom_noise,
                seed: a.phantom_seed,
            },
            // An unknown name is reported when the phantom is made.
            dsc_seg::phantom::Phantom3Kind::from_name(&a.phantom)
                .map_or(2, dsc_seg::phantom::Phantom3Kind::phases),
        ),
    };
    option(check_phantom_source(&source, true))?;
    let spacing = option(a.options.spacing())?;
    let job = Segment3dJob {
        source,
        out: a.out,
        params: option(a.options.params(default_phases))?,
        init_labels: a.options.init_labels,
        init_surface: a.options.init_surface,
        outputs,
        quiet: a.quiet,
        channel: a.options.channel,
        time_point: a.options.time_point,
        spacing,
    };
    let report = run_segment3d(&job)?;
    print_warnings(&report);
    print_earlier_outputs(&outputs.earlier_outputs(true, &job.out), &job.out);
    if !a.quiet {
        print_summary(&report, "tets", &job.out);
    }
    Ok(())
}

/// Runs a batch; an error if any input failed (each is in the summary).
fn run_batch(
    paths: &[PathBuf],
    task: Task,
    out: PathBuf,
    outputs: Outputs,
    args: &BatchArgs,
    quiet: bool,
) -> Result<(), Failure> {
    let jobs = match args.jobs {
        Some(n) => n.get(),
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    print_skipped_subfolders(&image_subfolders(paths, task_is_3d(&task)));
    print_skipped_volumes(&nifti_volumes_left_out(paths, task_is_3d(&task)));
    let batch = Batch {
        inputs: expand_inputs(paths, task_is_3d(&task))?,
        task,
        out,
        outputs,
        jobs,
        shard: args.shard,
        force: args.force,
        quiet,
    };
    BATCH_RUNNING.store(true, std::sync::atomic::Ordering::Relaxed);
    let outcome = batch.run()?;
    let failed = outcome.count(Status::Error);
    if !quiet {
        eprintln!(
            "{} done, {} skipped (complete), {failed} failed; summary in {}",
            outcome.count(Status::Done),
            outcome.count(Status::Skipped),
            outcome.summary.display()
        );
    }
    if failed > 0 {
        return Err(Failure::Run(Error::Usage(format!(
            "{failed} of {} inputs failed (see {})",
            outcome.rows.len(),
            outcome.summary.display()
        ))));
    }
    Ok(())
}

fn task_is_3d(task: &Task) -> bool {
    matches!(task, Task::Volume { .. })
}

/// Every warning of the run on stderr, quiet or not: a result with a lost
/// phase must not pass for a good one.
fn print_warnings(report: &dsc_seg::segment::SegmentReport) {
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
}

/// Names the subfolders of image folders that a 2D batch leaves out, quiet
/// or not: images that are not segmented must not go unnoticed.
fn print_skipped_subfolders(folders: &[PathBuf]) {
    if !folders.is_empty() {
        let names: Vec<String> = folders.iter().map(|f| f.display().to_string()).collect();
        eprintln!(
            "note: the images in {} are not segmented: a folder's images are taken from it \
             alone; name a subfolder as an input to include it",
            names.join(", ")
        );
    }
}

/// Names the NIfTI volumes of the folders given to `segment`, which it
/// leaves to `segment3d`.
fn print_skipped_volumes(volumes: &[PathBuf]) {
    if !volumes.is_empty() {
        let names: Vec<String> = volumes.iter().map(|f| f.display().to_string()).collect();
        eprintln!(
            "note: {} are NIfTI volumes, not segmented by `segment`: segment them with \
             `dsc-seg segment3d`",
            names.join(", ")
        );
    }
}

/// Names the files of an earlier run that this one left beside its own
/// outputs (see [`Outputs::earlier_outputs`]), quiet or not.
fn print_earlier_outputs(names: &[&str], out: &std::path::Path) {
    if !names.is_empty() {
        eprintln!(
            "note: {} in {} are from an earlier run, not this one",
            names.join(", "),
            out.display()
        );
    }
}

/// One line on stderr: how the run ended and where the outputs are.
fn print_summary(report: &dsc_seg::segment::SegmentReport, cells: &str, out: &std::path::Path) {
    use dsc_seg::segment::StopReason;
    let ending = match report.stop_reason {
        StopReason::Converged if !report.warnings.is_empty() => "converged with warnings (above)",
        StopReason::Converged => "converged",
        StopReason::MaxIterations => "stopped at the iteration cap",
        StopReason::SwappingLabels => "stopped with its labels swapping (above)",
        StopReason::Stopped => "stopped",
    };
    eprintln!(
        "{ending} after {} iterations ({:.2} s), {} {cells}; outputs in {}",
        report.iterations,
        report.times.total,
        report.cells,
        out.display()
    );
}

/// Set while a batch runs: its interruption keeps the inputs it finished.
static BATCH_RUNNING: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// On Ctrl-C (SIGINT) or SIGTERM: remove every staging directory (waiting
/// for an output being moved into place), then exit with 128 + the signal's
/// number (130, 143), as a shell or a batch scheduler expects.
fn exit_cleanly_on_interrupt() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            let _hold = dsc_seg::staging::remove_all_and_hold();
            if BATCH_RUNNING.load(std::sync::atomic::Ordering::Relaxed) {
                eprintln!(
                    "error: interrupted; unfinished outputs removed, finished inputs kept \
                     (the same command goes on from there)"
                );
            } else {
                eprintln!("error: interrupted; unfinished outputs removed");
            }
            std::process::exit(128 + signal);
        }
    });
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
            eprintln!("error: {} (see --help)", one_line(&e));
            return ExitCode::from(2);
        }
    };
    exit_cleanly_on_interrupt();
    let result = match cli.command {
        Command::Segment(a) => segment(a),
        Command::Phantom(a) => run_phantom(&a.name, a.size, a.noise, a.seed, &a.out)
            .map(|names| {
                for n in names {
                    println!("{}", a.out.join(n).display());
                }
            })
            .map_err(phantom_failure),
        Command::Segment3d(a) => segment3d(a),
        Command::Phantom3d(a) => run_phantom3d(&a.name, a.size, a.noise, a.seed, &a.out)
            .map(|names| {
                for n in names {
                    println!("{}", a.out.join(n).display());
                }
            })
            .map_err(phantom_failure),
    };
    let (e, code) = match result {
        Ok(()) => return ExitCode::SUCCESS,
        Err(Failure::Options(e)) => (e, 2),
        Err(Failure::Run(e)) => (e, 1),
    };
    eprintln!("error: {}", e.to_string().replace('\n', " "));
    ExitCode::from(code)
}

/// A `--jobs` value: a whole number, at least 1 (clap's own message for 0
/// is the library's "number would be zero for non-zero type").
fn parse_jobs(s: &str) -> std::result::Result<std::num::NonZeroUsize, String> {
    let expected = || format!("{s:?}: expected a whole number, at least 1");
    let n: usize = s.trim().parse().map_err(|_| expected())?;
    std::num::NonZeroUsize::new(n).ok_or_else(expected)
}
