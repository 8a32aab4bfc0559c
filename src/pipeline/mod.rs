//! Whole jobs as the command line runs them: load, validate, segment, write
//! every output into a directory without ever leaving it half-written.
//!
//! Every job goes through the same skeleton, [`Job::run`]: load (or generate)
//! the input, validate it with the parameters (loading `Init::Labels` from
//! their file), check the output directory, segment, and write. The two input
//! kinds fill in the stages: [`SegmentJob`] (a 2D image, [`d2`]) and
//! [`Segment3dJob`] (a 3D volume, [`d3`]).
//!
//! Outputs are first written into a hidden staging directory inside the
//! output directory and only renamed into place once all of them exist, so a
//! failure leaves the directory as it was (see [`crate::staging`]). The runs
//! themselves are [`segment_image`] and [`segment_volume`], which the Python
//! package calls directly.

pub mod d2;
pub mod d3;
mod input_summary;

pub use d2::{
    load_image, load_image_channel, load_image_selected, run_phantom, run_segment,
    save_overlay_png, segment_image, with_init_labels, SegmentJob,
};
pub use d3::{
    load_volume, load_volume_selected, run_phantom3d, run_segment3d, segment_volume,
    with_init_labels3, QualitySummary, Segment3dJob,
};

use crate::error::{Error, Result};
use crate::io::Frame;
use crate::segment::measurements::Measurements;
use crate::segment::missed_objects::{missed_objects, Noise};
use crate::segment::outliers::{clamp_outliers_keeping_range, Outliers};
use crate::segment::params::MAX_PHASES;
use crate::segment::shading::{phase_trends, FitNoise};
use crate::segment::ImageView;
use crate::segment::{Raster, SegmentParams, SegmentReport, Segmentation};
use crate::segmented::{Outputs, Segmented};
use crate::staging::Staging;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Where the image comes from.
#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    /// An image file.
    File(PathBuf),
    /// A built-in phantom.
    Phantom {
        /// Phantom name.
        name: String,
        /// Side in pixels.
        size: usize,
        /// Noise standard deviation.
        noise: f64,
        /// RNG seed.
        seed: u64,
    },
    /// An array handed over in memory (the Python package).
    Array,
}

/// The stages of a job, whatever its input kind; [`Job::run`] chains them.
pub trait Job {
    /// The loaded input: a 2D image or a 3D volume.
    type Input;
    /// Whether the input is a 3D volume (its outputs' names differ).
    const THREE_D: bool;

    /// Where the input comes from.
    fn source(&self) -> &Source;
    /// The label file of `Init::Labels`, if any.
    fn init_labels(&self) -> Option<&Path>;
    /// The output directory.
    fn out(&self) -> &Path;
    /// The files to write.
    fn outputs(&self) -> &Outputs;

    /// Loads (or generates) the input, with a phantom's ground truth.
    fn load(&self) -> Result<(Self::Input, Option<GroundTruth>)>;

    /// The parameters for `input`, `Init::Labels` loaded and checked against it.
    fn params_for(&self, input: &Self::Input) -> Result<SegmentParams>;

    /// Segments `input`, calling `ready` once the input and parameters are
    /// validated, before the run.
    fn segment_then<T>(
        &self,
        input: &Self::Input,
        params: SegmentParams,
        provenance: Provenance,
        ready: impl FnOnce() -> Result<T>,
    ) -> Result<(Segmented, T)>;

    /// Load → validate → segment → write: runs the job and writes its outputs
    /// into the output directory (checked after the parameters, before any
    /// work), all or none of them.
    fn run(&self) -> Result<SegmentReport> {
        refuse_replacing_inputs(self)?;
        let t_load = Instant::now();
        let (input, truth) = self.load()?;
        let params = self.params_for(&input)?;
        let provenance = Provenance {
            source: self.source().clone(),
            init_labels: self.init_labels().map(Path::to_path_buf),
            truth,
            load_seconds: t_load.elapsed().as_secs_f64(),
        };
        let (result, stage) = self
            .segment_then(&input, params, provenance, || Staging::new(self.out()))
            .map_err(|e| match self.source() {
                Source::File(path) => e.naming_input(path),
                _ => e,
            })?;
        result.write_staged(stage, self.out(), self.outputs())?;
        Ok(result.summary)
    }
}

/// Refuses a run of `job` that would publish one of its outputs over its
/// own input file or its label file (`labels.png` segmented with `--out`
/// set to its own folder): the user's data would be replaced by the
/// result. An output is the same file as an input when both paths resolve
/// to one (links, `.`/`..` and, where the file system ignores case, the
/// stored spelling all resolved).
fn refuse_replacing_inputs<J: Job + ?Sized>(job: &J) -> Result<()> {
    let Source::File(input) = job.source() else {
        return Ok(());
    };
    let written = job.outputs().files_for(J::THREE_D, input);
    let inputs = [
        (Some(input.as_path()), "input"),
        (job.init_labels(), "label file"),
    ];
    for (file, what) in inputs {
        let Some(full) = file.and_then(|f| f.canonicalize().ok()) else {
            continue;
        };
        let replaced = written
            .iter()
            .any(|name| job.out().join(name).canonicalize().is_ok_and(|o| o == full));
        if replaced {
            return Err(Error::OutputDir {
                path: job.out().to_path_buf(),
                reason: format!(
                    "the run would replace its {what} {} with an output of the same name; \
                     choose another --out",
                    file.unwrap_or(input).display()
                ),
            });
        }
    }
    Ok(())
}

/// A phantom's true labels (phases by increasing mean).
#[derive(Clone, Debug)]
pub struct GroundTruth {
    /// Phase per pixel or voxel.
    pub labels: Vec<u8>,
    /// Number of phases.
    pub phases: usize,
}

/// What a report says about a run's input beyond the image itself.
#[derive(Clone, Debug)]
pub struct Provenance {
    /// Where the image came from.
    pub source: Source,
    /// The label file `Init::Labels` was loaded from.
    pub init_labels: Option<PathBuf>,
    /// The ground truth, for the report's Dice score.
    pub truth: Option<GroundTruth>,
    /// Seconds spent loading the input.
    pub load_seconds: f64,
}

impl Provenance {
    /// An in-memory input without ground truth.
    pub fn array() -> Self {
        Provenance {
            source: Source::Array,
            init_labels: None,
            truth: None,
            load_seconds: 0.0,
        }
    }
}

/// Seconds per stage of a job.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct JobTimes {
    /// Loading (or generating) the input.
    pub load: f64,
    /// The segmentation proper (mesh set-up and evolution).
    pub segment: f64,
    /// Rendering and writing the outputs.
    pub write: f64,
}

/// What every `report.json` holds, 2D or 3D: enough to reproduce the run
/// (tool, input, every parameter) and to follow it (energy and flips per
/// iteration, timings per stage). The pipelines add their own fields.
#[derive(Serialize)]
pub(crate) struct RunReport<'a> {
    tool: &'static str,
    version: &'static str,
    source: &'a Source,
    init_labels: Option<&'a Path>,
    params: &'a SegmentParams,
    dsc: &'a crate::dsc::DscParams,
    /// Rank (by increasing mean) of each mesh label: the value written for it.
    phase_order: Vec<u8>,
    /// The final means by rank, i.e. of output values 0, 1, ...
    ordered_means: Vec<Option<f64>>,
    /// Every warning of the run (lost phases, the iteration cap, the
    /// choice of `--phases auto`), as printed on stderr; empty when all is well.
    warnings: &'a [String],
    iterations: usize,
    converged: bool,
    /// The final means of output values 0, 1, ... (ascending, as the
    /// labels and `phases`; `segmentation.final_means` is per mesh label).
    final_means: Vec<Option<f64>>,
    final_energy: f64,
    energy: Vec<f64>,
    flips: Vec<usize>,
    vertices: usize,
    cells: usize,
    times: JobTimes,
    truth_dice: Option<f64>,
    segmentation: &'a SegmentReport,
}

impl<'a> RunReport<'a> {
    /// The shared part of the report of a finished run of `seg`.
    pub(crate) fn new<K: Raster>(
        tool: &'static str,
        (source, init_labels): (&'a Source, Option<&'a Path>),
        seg: &'a Segmentation<'_, K>,
        report: &'a SegmentReport,
        times: JobTimes,
        truth_dice: Option<f64>,
    ) -> Self {
        let order = seg.phase_order();
        let ordered_means = ordered_means(&order, report);
        RunReport {
            tool,
            version: env!("CARGO_PKG_VERSION"),
            source,
            init_labels,
            params: seg.params(),
            dsc: seg.dsc_params(),
            phase_order: order,
            ordered_means: ordered_means.clone(),
            warnings: &report.warnings,
            iterations: report.iterations,
            converged: report.converged,
            final_means: ordered_means,
            final_energy: report.final_energy,
            energy: report.history.iter().map(|r| r.energy).collect(),
            flips: report.history.iter().map(|r| r.flips).collect(),
            vertices: report.vertices,
            cells: report.cells,
            times,
            truth_dice,
            segmentation: report,
        }
    }
}

/// Runs a segmentation to its end with a progress bar on stderr (hidden when
/// `quiet`), shared by the 2D and 3D pipelines; [`Error::Interrupted`] when
/// the caller cancelled it ([`crate::cancel`]).
pub(crate) fn run_with_progress<K: Raster>(
    seg: &mut Segmentation<'_, K>,
    max_iterations: usize,
    quiet: bool,
) -> Result<SegmentReport> {
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(max_iterations as u64);
        b.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b
    };
    let report = seg.run(|r| {
        bar.set_position(r.iteration as u64);
        bar.set_message(format!(
            "E={:.4} flips={} move={:.3}L",
            r.energy, r.flips, r.max_displacement
        ));
    });
    bar.finish_and_clear();
    if crate::cancel::requested() {
        return Err(Error::Interrupted);
    }
    Ok(report)
}

/// The run's final means by output value: mesh label `l`'s at `order[l]`
/// ([`Segmentation::phase_order`]).
fn ordered_means(order: &[u8], report: &SegmentReport) -> Vec<Option<f64>> {
    let mut means = vec![None; order.len()];
    for (label, &rank) in order.iter().enumerate() {
        means[rank as usize] = report.final_means.get(label).copied().flatten();
    }
    means
}

/// The checks of a result against its image, after the run: objects the
/// result left inside another phase ([`warn_missed_objects`]) and smooth
/// trends inside the phases ([`warn_shading`]), each added to `report` with
/// its warnings. `labels` are the output labels of `seg` over `image`;
/// `scale` turns a difference of loaded values into the file's units. Only
/// where the result answers for the whole image
/// ([`SegmentParams::claims_whole_image`]).
pub(crate) fn check_result<K: Raster>(
    seg: &Segmentation<'_, K>,
    image: &ImageView<'_>,
    labels: &[u8],
    scale: f64,
    report: &mut SegmentReport,
) {
    if !seg.params().claims_whole_image() {
        return;
    }
    let means = ordered_means(&seg.phase_order(), report);
    warn_missed_objects(seg, image, labels, &means, report);
    warn_shading(image, labels, &means, scale, report);
}

/// Adds to `report` a warning for each kind of object the result left
/// inside another phase ([`missed_objects`]): structures smaller than the
/// regularisation keeps, which no lost-phase check sees while their phase
/// lives on elsewhere. `means` are the final means by output value.
fn warn_missed_objects<K: Raster>(
    seg: &Segmentation<'_, K>,
    image: &ImageView<'_>,
    labels: &[u8],
    means: &[Option<f64>],
    report: &mut SegmentReport,
) {
    let noise = Noise {
        sigma: report.intensity.noise,
        correlation: report.intensity.noise_correlation,
    };
    let found = missed_objects(image, seg.check_image(), labels, means, noise);
    let three_d = image.dims[2] > 1;
    let adaptive = seg.params().sizing.adaptive;
    report
        .warnings
        .extend(found.iter().map(|m| m.warning(three_d, adaptive)));
    report.missed_objects = Some(found);
}

/// Adds to `report` the trend of intensity fitted inside each phase
/// ([`phase_trends`]: uneven illumination, a bias field, vignetting) and a
/// warning for each phase whose trend spans a large share of the gap to
/// the nearest other phase's mean.
fn warn_shading(
    image: &ImageView<'_>,
    labels: &[u8],
    means: &[Option<f64>],
    scale: f64,
    report: &mut SegmentReport,
) {
    let noise = FitNoise {
        correlation: report.intensity.noise_correlation,
    };
    let trends = phase_trends(image, labels, means, noise, scale);
    let three_d = image.dims[2] > 1;
    report.warnings.extend(
        trends
            .iter()
            .filter(|t| t.warned)
            .map(|t| t.warning(three_d)),
    );
    report.shading = Some(trends);
}

/// The input's samples with their outliers clamped ([`clamp_input`]).
pub(crate) struct ClampedInput {
    /// The clamped samples and the warning that says so (`None`: the
    /// samples stand as they are).
    pub data: Option<(Vec<f32>, String)>,
    /// The lowest and highest of the samples clamped, as loaded (`None`:
    /// none was): with the clamped data's own extremes, the input's.
    pub outlier_extremes: Option<(f32, f32)>,
    /// The robust range the clamp selected of samples that stand, for
    /// [`ImageView::with_robust_range`](crate::segment::ImageView::with_robust_range).
    pub robust_range: Option<(f64, f64)>,
}

/// The input's samples `data` (on the grid `dims`) with their outliers clamped
/// ([`clamp_outliers`](crate::segment::outliers::clamp_outliers)) and the
/// warning that says so, its values in the file's units (`file_value`);
/// no data where no sample lies far outside the rest. `samples` names them
/// ("pixels" or "voxels").
pub(crate) fn clamp_input(
    data: &[f32],
    dims: [usize; 3],
    file_value: impl Fn(f32) -> f64,
    samples: &str,
) -> ClampedInput {
    let clamp = clamp_outliers_keeping_range(data, dims);
    ClampedInput {
        outlier_extremes: clamp.clamped.as_ref().map(|(_, o)| o.extremes),
        data: clamp
            .clamped
            .map(|(clamped, outliers)| (clamped, outlier_warning(&outliers, file_value, samples))),
        robust_range: clamp.robust_range,
    }
}

/// The warning of [`clamp_input`].
fn outlier_warning(o: &Outliers, file_value: impl Fn(f32) -> f64, samples: &str) -> String {
    let (below, above) = (o.extremes.0 < o.clamp.0, o.extremes.1 > o.clamp.1);
    let v = |x: f32| file_value(x);
    let (where_, kind, taken) = match (below, above) {
        (true, true) => (
            format!(
                "outside the rest of the image ({} to {})",
                v(o.extremes.0),
                v(o.extremes.1)
            ),
            "dead or hot pixels, or other outliers",
            format!("{} or {}", v(o.clamp.0), v(o.clamp.1)),
        ),
        (true, false) => (
            format!(
                "far below the rest of the image (down to {})",
                v(o.extremes.0)
            ),
            "dead pixels or other outliers",
            format!("{}", v(o.clamp.0)),
        ),
        _ => (
            format!(
                "far above the rest of the image (up to {})",
                v(o.extremes.1)
            ),
            "hot pixels, cosmic rays or other outliers",
            format!("{}", v(o.clamp.1)),
        ),
    };
    let (samples, lie, them, they) = if o.count == 1 {
        (samples.trim_end_matches('s'), "lies", "it", "it")
    } else {
        (samples, "lie", "them", "they")
    };
    format!(
        "{} {samples} {lie} {where_}: {kind}; the segmentation and the measurements count \
         {them} as {taken}, so that {they} cannot pull a phase's mean or size",
        o.count
    )
}

/// Checks the name, side and noise of a phantom `source` (2D, or 3D with
/// `three_d`) before any work; other sources pass. The command line refuses
/// a bad one as an option value.
pub fn check_phantom_source(source: &Source, three_d: bool) -> Result<()> {
    let Source::Phantom {
        name, size, noise, ..
    } = source
    else {
        return Ok(());
    };
    if three_d {
        d3::phantom3(name, *size, *noise).map(|_| ())
    } else {
        d2::phantom2(name, *size, *noise).map(|_| ())
    }
}

/// Checks a phantom's side and noise before generating it: a huge side would
/// exhaust memory, a NaN noise would poison every sample.
pub(crate) fn check_phantom(
    what: &str,
    size: usize,
    noise: f64,
    sizes: RangeInclusive<usize>,
) -> Result<()> {
    if !sizes.contains(&size) {
        return Err(Error::Usage(format!(
            "{what} size {size} must lie in {}..={}",
            sizes.start(),
            sizes.end()
        )));
    }
    if !(noise.is_finite() && noise >= 0.0) {
        return Err(Error::Usage(format!(
            "noise {noise} must be a non-negative number"
        )));
    }
    Ok(())
}

/// The phases of an initial labelling read from `path`, from its samples as
/// the file stores them (`stored`: an 8-bit, 16-bit, signed or float image
/// alike, so that a 16-bit label image's 1 is phase 1, not 1/65535 of the
/// 8-bit range): each must be a whole number below `phases`.
pub(crate) fn labels_of_samples(
    stored: impl Iterator<Item = f64>,
    phases: usize,
    path: &Path,
) -> Result<Vec<u8>> {
    let mut labels = Vec::with_capacity(stored.size_hint().0);
    let mut largest: f64 = 0.0;
    for v in stored {
        let label = v.round();
        if !(label >= 0.0 && (v - label).abs() <= 1e-3) {
            return Err(Error::Usage(format!(
                "init labels {} hold the value {v}, which is not a phase number \
                 (labels are whole numbers from 0 to the number of phases − 1)",
                path.display()
            )));
        }
        largest = largest.max(label);
        labels.push(label.min(255.0) as u8);
    }
    if largest >= phases as f64 {
        let hint = if largest == 255.0 {
            "labels are phase numbers from 0, not a mask's 0/255".to_string()
        } else if largest < MAX_PHASES as f64 {
            format!("give --phases {} to use them all", largest + 1.0)
        } else {
            format!("at most {MAX_PHASES} phases")
        };
        return Err(Error::Usage(format!(
            "init labels {} use label {largest}, but labels must be below the number of \
             phases ({phases}): {hint}",
            path.display()
        )));
    }
    Ok(labels)
}

/// Mean Dice over the truth's phases (labels already in the same order).
pub fn mean_dice(pred: &[u8], truth: &[u8], phases: usize) -> f64 {
    let mut total = 0.0;
    for k in 0..phases as u8 {
        let tp = pred
            .iter()
            .zip(truth)
            .filter(|(a, b)| **a == k && **b == k)
            .count();
        let np = pred.iter().filter(|&&a| a == k).count();
        let nt = truth.iter().filter(|&&a| a == k).count();
        total += if np + nt == 0 {
            1.0
        } else {
            2.0 * tp as f64 / (np + nt) as f64
        };
    }
    total / phases as f64
}

/// Adds the input's frame and the measurements to a report.
pub(crate) fn add_frame_and_phases(
    report: &mut serde_json::Value,
    frame: &Frame,
    measurements: &Measurements,
) -> Result<()> {
    let value =
        |v: serde_json::Result<serde_json::Value>| v.map_err(|e| Error::Usage(e.to_string()));
    report["frame"] = value(serde_json::to_value(frame))?;
    report["phases"] = value(serde_json::to_value(measurements))?;
    Ok(())
}
