//! Batch runs: many inputs (files, or folders of them) into one output
//! directory, `DIR/<stem>/` per input (inputs of one stem take their folders' names,
//! `s1_img`, or in one folder their whole names, `img_png`), with a summary table
//! `DIR/summary.csv`.
//!
//! - A bad input fails its own row; the others still run.
//! - An input whose outputs are complete and were made by the same command
//!   (same version, parameters, outputs and input file) is skipped, unless
//!   `force`. Completion is marked by [`MARKER`], written after the outputs.
//! - `jobs` inputs run at once, each on one thread (its own one-thread rayon
//!   pool, so the segmentation's parallel sections stay on it too).
//! - A shard `I/N` takes the inputs whose position in the list is `I` modulo
//!   `N`, for job arrays on a cluster scheduler; each shard writes its own
//!   `summary-I-of-N.csv`.

use crate::error::{Error, Result};
use crate::io::volume::{is_nifti, nifti_is_volume};
use crate::io::write_bytes_atomic;
use crate::pipeline::{Job, Segment3dJob, SegmentJob, Source};
use crate::segment::SegmentParams;
use crate::segmented::Outputs;
use crate::staging;
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// The file in `DIR/<stem>/` that says its outputs are complete, and made by what.
pub const MARKER: &str = ".dsc-seg-complete.json";

/// File extensions of the 2D images a folder is searched for, besides
/// NIfTI files (`.nii`, `.nii.gz`; see [`folder_images`]).
const IMAGE_EXTENSIONS: &[&str] = &[
    "png", "tif", "tiff", "jpg", "jpeg", "gif", "bmp", "pnm", "pgm", "ppm", "pbm",
];

/// What each input of a batch is segmented with.
#[derive(Clone, Debug)]
pub enum Task {
    /// 2D images.
    Image {
        /// The parameters (`Init::Labels` loaded per input from `init_labels`).
        params: SegmentParams,
        /// The label image for `Init::Labels`.
        init_labels: Option<PathBuf>,
        /// The channel of multi-channel TIFFs, or of colour images (else
        /// their luminance), to segment.
        channel: Option<usize>,
        /// The time point of time-lapse TIFFs to segment.
        time_point: Option<usize>,
        /// The pixel size to use instead of each file's.
        spacing: Option<[f64; 2]>,
    },
    /// 3D volumes.
    Volume {
        /// The parameters (`Init::Labels` loaded per input from `init_labels`).
        params: SegmentParams,
        /// The label volume for `Init::Labels`.
        init_labels: Option<PathBuf>,
        /// The initial surface (see [`crate::pipeline::Segment3dJob::init_surface`]).
        init_surface: Option<PathBuf>,
        /// The channel of multi-channel TIFFs to segment.
        channel: Option<usize>,
        /// The time point of time-lapse TIFFs to segment.
        time_point: Option<usize>,
        /// The voxel size to use instead of each file's.
        spacing: Option<[f64; 3]>,
    },
}

impl Task {
    fn is_3d(&self) -> bool {
        matches!(self, Task::Volume { .. })
    }
}

/// A shard of a batch: inputs `index`, `index + count`, `index + 2·count`, ...
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, `0..count`.
    pub index: usize,
    /// How many shards.
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;

    /// Parses `I/N` with `0 <= I < N`.
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let bad = || format!("{s:?}: expected I/N with 0 <= I < N (e.g. 0/4)");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

/// A batch: the inputs (already expanded) and how to run them.
#[derive(Clone, Debug)]
pub struct Batch {
    /// The inputs, in order.
    pub inputs: Vec<PathBuf>,
    /// What each is segmented with.
    pub task: Task,
    /// The output directory: `DIR/<stem>/` per input and the summary.
    pub out: PathBuf,
    /// The files written per input.
    pub outputs: Outputs,
    /// Inputs run at once.
    pub jobs: usize,
    /// This process's part of the inputs.
    pub shard: Option<Shard>,
    /// Redo inputs whose outputs are complete.
    pub force: bool,
    /// No line per finished input on stderr.
    pub quiet: bool,
}

/// How one input ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Segmented and written.
    Done,
    /// Complete from an earlier identical run.
    Skipped,
    /// Failed (the row's error says why).
    Error,
}

/// The summary table's columns, the fields of [`Row`].
pub const COLUMNS: [&str; 9] = [
    "name",
    "input",
    "phases",
    "iterations",
    "converged",
    "seconds",
    "status",
    "error",
    "warnings",
];

/// One row of the summary table.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// The input's stem, the name of its output folder.
    pub name: String,
    /// The input path.
    pub input: PathBuf,
    /// Number of phases.
    pub phases: Option<usize>,
    /// Iterations run.
    pub iterations: Option<usize>,
    /// Whether the run converged (before the iteration cap; its warnings say
    /// why one did not).
    pub converged: Option<bool>,
    /// Wall seconds of load, segmentation and writing.
    pub seconds: Option<f64>,
    /// How it ended.
    pub status: Status,
    /// The error, for a failed input.
    pub error: String,
    /// What the run warned about (a lost phase, a count at the cap), `; `
    /// between warnings; empty when all is well. A batch must not hide what
    /// a single run would print.
    #[serde(default)]
    pub warnings: String,
}

/// The rows of a finished batch, in input order, and where the summary is.
#[derive(Debug)]
pub struct BatchOutcome {
    /// One row per input of this shard.
    pub rows: Vec<Row>,
    /// The summary table written.
    pub summary: PathBuf,
}

impl BatchOutcome {
    /// How many rows have `status`.
    pub fn count(&self, status: Status) -> usize {
        self.rows.iter().filter(|r| r.status == status).count()
    }
}

/// Whether `path` names an input of a batch rather than a single run: a
/// folder of images in 2D; in 3D a folder holding volume files (NIfTI,
/// multi-page TIFF) or subfolders, rather than one volume's slices.
pub fn is_batch_folder(path: &Path, three_d: bool) -> bool {
    path.is_dir() && (!three_d || !volume_folder_entries(path).is_empty())
}

/// The inputs named by `paths`: files as they are, folders replaced by their
/// inputs in name order (see [`is_batch_folder`]; hidden entries skipped),
/// each file once (one named twice, or both alone and through its folder,
/// is one input: it would write one output folder).
pub fn expand_inputs(paths: &[PathBuf], three_d: bool) -> Result<Vec<PathBuf>> {
    let mut seen = HashSet::new();
    let inputs = listed_inputs(paths, three_d)?;
    Ok(inputs
        .into_iter()
        .filter(|p| seen.insert(canonical(p)))
        .collect())
}

/// The subfolders of the 2D batch folders among `paths` that hold images:
/// a folder's images are taken from it alone, so these are left out unless
/// named as inputs themselves (however the path is spelt), and the command
/// line says so. Each is listed once. A batch's own output folders (with
/// its completion [`MARKER`]: a folder segmented into itself) are not
/// listed: their images are results.
pub fn image_subfolders(paths: &[PathBuf], three_d: bool) -> Vec<PathBuf> {
    if three_d {
        return Vec::new();
    }
    // The folders named as inputs, then each subfolder as it is listed.
    let mut taken: HashSet<PathBuf> = paths.iter().map(|p| canonical(p)).collect();
    paths
        .iter()
        .filter(|p| is_batch_folder(p, false))
        .flat_map(|p| sorted_entries(p).unwrap_or_default())
        .filter(|e| e.is_dir() && !e.join(MARKER).is_file())
        .filter(|e| folder_images(e).is_ok_and(|i| !i.is_empty()))
        .filter(|e| taken.insert(canonical(e)))
        .collect()
}

/// `path` with links and `.`/`..` resolved, so that two spellings of one
/// file or folder compare equal; as it is when it cannot be resolved (a
/// missing file).
fn canonical(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

/// [`expand_inputs`] before the duplicates are dropped.
fn listed_inputs(paths: &[PathBuf], three_d: bool) -> Result<Vec<PathBuf>> {
    let mut inputs = Vec::new();
    for p in paths {
        // A missing file stays in the list: its row says it cannot be read.
        if !is_batch_folder(p, three_d) {
            inputs.push(p.clone());
        } else if three_d {
            inputs.extend(volume_folder_entries(p));
        } else {
            let images = folder_images(p)?;
            // An empty batch would "succeed" with an empty summary.
            if images.is_empty() {
                return Err(Error::Usage(format!(
                    "folder {} holds no image ({}, nii, nii.gz)",
                    p.display(),
                    IMAGE_EXTENSIONS.join(", ")
                )));
            }
            inputs.extend(images);
        }
    }
    Ok(inputs)
}

/// The image files of a folder ([`IMAGE_EXTENSIONS`] and NIfTI slices) in
/// name order, hidden ones left out. A NIfTI whose header says it is a
/// volume is left to `segment3d` ([`nifti_volumes_left_out`] names them);
/// one whose header cannot be read is listed, so that its row says why.
fn folder_images(dir: &Path) -> Result<Vec<PathBuf>> {
    Ok(sorted_entries(dir)?
        .into_iter()
        .filter(|e| e.is_file())
        .filter(|e| has_extension(e, IMAGE_EXTENSIONS) || is_nifti_slice(e))
        .collect())
}

/// Whether `path` is a NIfTI file not known to be a volume.
fn is_nifti_slice(path: &Path) -> bool {
    is_nifti(path) && nifti_is_volume(path) != Some(true)
}

/// The NIfTI volumes in the 2D batch folders among `paths`: `segment`
/// leaves them out of the folder's images, and the command line says so.
pub fn nifti_volumes_left_out(paths: &[PathBuf], three_d: bool) -> Vec<PathBuf> {
    if three_d {
        return Vec::new();
    }
    paths
        .iter()
        .filter(|p| is_batch_folder(p, false))
        .flat_map(|p| sorted_entries(p).unwrap_or_default())
        .filter(|e| e.is_file() && is_nifti(e) && nifti_is_volume(e) == Some(true))
        .collect()
}

/// A folder's entries in name order, hidden ones left out.
fn sorted_entries(dir: &Path) -> Result<Vec<PathBuf>> {
    let read = std::fs::read_dir(dir)
        .map_err(|e| Error::Usage(format!("cannot read folder {}: {e}", dir.display())))?;
    let mut entries: Vec<PathBuf> = read
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            !p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with('.'))
        })
        .collect();
    entries.sort();
    Ok(entries)
}

fn has_extension(path: &Path, extensions: &[&str]) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| extensions.contains(&e.to_ascii_lowercase().as_str()))
}

/// The volumes of a folder of volumes: its NIfTI files, TIFF files and
/// subfolders (each a folder of slices); nothing if it is one volume's
/// slices (no NIfTI, no subfolder, every TIFF single-page).
fn volume_folder_entries(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = sorted_entries(dir) else {
        return Vec::new();
    };
    let tiff = |p: &PathBuf| p.is_file() && has_extension(p, &["tif", "tiff"]);
    let holds_volumes = entries
        .iter()
        .any(|p| p.is_dir() || is_nifti(p) || (tiff(p) && !is_single_page_tiff(p)));
    if !holds_volumes {
        return Vec::new();
    }
    entries
        .into_iter()
        .filter(|p| p.is_dir() || is_nifti(p) || tiff(p))
        .collect()
}

/// Whether `path` is a TIFF with exactly one page (a slice, not a stack).
fn is_single_page_tiff(path: &Path) -> bool {
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    match tiff::decoder::Decoder::new(std::io::BufReader::new(file)) {
        Ok(d) => !d.more_images(),
        Err(_) => false,
    }
}

/// The name of an input's output folder: its file name without the
/// extension (both of `.nii.gz`), or the folder's name.
pub fn stem(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string());
    if path.is_dir() {
        return name;
    }
    let lower = name.to_ascii_lowercase();
    if lower.ends_with(".nii.gz") {
        return name[..name.len() - 7].to_string();
    }
    match name.rfind('.') {
        Some(i) if i > 0 => name[..i].to_string(),
        _ => name,
    }
}

/// What makes a run's outputs the same as an earlier one's: the version,
/// the command, every parameter, the outputs and the input file's size and
/// modification time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Fingerprint {
    version: String,
    three_d: bool,
    params: serde_json::Value,
    init_labels: Option<PathBuf>,
    init_surface: Option<PathBuf>,
    /// How the input is read (`--channel`, `--time-point`, `--spacing`).
    input_options: serde_json::Value,
    outputs: Vec<String>,
    input: PathBuf,
    input_bytes: u64,
    input_modified: Option<u128>,
}

/// A fingerprint's `input_options`: how an input is read, `options` with
/// each of `chosen` (`channel`, `time_point`) that is given. Those not
/// given are left out, so that outputs made before they existed are still
/// recognised.
fn input_options(
    mut options: serde_json::Value,
    chosen: [(&str, Option<usize>); 2],
) -> serde_json::Value {
    for (name, value) in chosen {
        if let Some(v) = value {
            options[name] = v.into();
        }
    }
    options
}

/// The completion marker: what made the outputs and the row it gave.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Marker {
    fingerprint: Fingerprint,
    row: Row,
}

impl Batch {
    /// Runs the batch: every input of this shard, `jobs` at once, then the
    /// summary table. Fails only for problems of the whole batch (two inputs
    /// with one stem, an unwritable output directory); each input's own
    /// failure is in its row.
    pub fn run(&self) -> Result<BatchOutcome> {
        let names = output_names(&self.inputs)?;
        let mine: Vec<(&PathBuf, String)> = self
            .inputs
            .iter()
            .zip(names)
            .enumerate()
            .filter(|(i, _)| self.shard.is_none_or(|s| i % s.count == s.index))
            .map(|(_, named)| named)
            .collect();
        std::fs::create_dir_all(&self.out).map_err(|e| Error::OutputDir {
            path: self.out.clone(),
            reason: e.to_string(),
        })?;
        let rows = self.run_all(&mine);
        let summary = self.out.join(match self.shard {
            None => "summary.csv".to_string(),
            Some(s) => format!("summary-{}-of-{}.csv", s.index, s.count),
        });
        let table = summary_csv(&rows)?;
        staging::uninterrupted(|| write_bytes_atomic(&summary, &table))?;
        Ok(BatchOutcome { rows, summary })
    }

    /// Runs `inputs` on `jobs` threads; the rows in input order.
    fn run_all(&self, inputs: &[(&PathBuf, String)]) -> Vec<Row> {
        let next = AtomicUsize::new(0);
        let finished = AtomicUsize::new(0);
        let rows: Mutex<Vec<Option<Row>>> = Mutex::new(vec![None; inputs.len()]);
        let workers = self.jobs.clamp(1, inputs.len().max(1));
        std::thread::scope(|scope| {
            for _ in 0..workers {
                scope.spawn(|| {
                    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build();
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some((input, name)) = inputs.get(i) else {
                            break;
                        };
                        let row = match &pool {
                            Ok(pool) => pool.install(|| self.run_guarded(input, name)),
                            Err(e) => error_row(input, name, format!("cannot start a thread: {e}")),
                        };
                        let done = finished.fetch_add(1, Ordering::Relaxed) + 1;
                        if !self.quiet {
                            eprintln!("[{done}/{}] {}", inputs.len(), describe(&row));
                        }
                        rows.lock().unwrap_or_else(|e| e.into_inner())[i] = Some(row);
                    }
                });
            }
        });
        rows.into_inner()
            .unwrap_or_else(|e| e.into_inner())
            .into_iter()
            .zip(inputs)
            .map(|(row, (input, name))| {
                row.unwrap_or_else(|| error_row(input, name, "not run".into()))
            })
            .collect()
    }

    /// One input's row; a panic becomes an error row rather than ending the batch.
    fn run_guarded(&self, input: &Path, name: &str) -> Row {
        let run =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| self.run_one(input, name)));
        match run {
            Ok(Ok(row)) => row,
            Ok(Err(e)) => error_row(input, name, e.to_string().replace('\n', " ")),
            Err(_) => error_row(
                input,
                name,
                "internal error (panic); please report it".into(),
            ),
        }
    }

    /// Segments one input into `DIR/<name>/`, or skips it if complete.
    fn run_one(&self, input: &Path, name: &str) -> Result<Row> {
        let start = Instant::now();
        let dir = self.out.join(name);
        let fingerprint = self.fingerprint(input)?;
        if !self.force {
            if let Some(row) = self.completed(&dir, &fingerprint) {
                return Ok(Row {
                    status: Status::Skipped,
                    ..row
                });
            }
        }
        let source = Source::File(input.to_path_buf());
        let summary = match &self.task {
            Task::Image {
                params,
                init_labels,
                channel,
                time_point,
                spacing,
            } => SegmentJob {
                source,
                out: dir.clone(),
                params: params.clone(),
                init_labels: init_labels.clone(),
                outputs: self.outputs,
                quiet: true,
                channel: *channel,
                time_point: *time_point,
                spacing: *spacing,
            }
            .run()?,
            Task::Volume {
                params,
                init_labels,
                init_surface,
                channel,
                time_point,
                spacing,
            } => Segment3dJob {
                source,
                out: dir.clone(),
                params: params.clone(),
                init_labels: init_labels.clone(),
                init_surface: init_surface.clone(),
                outputs: self.outputs,
                quiet: true,
                channel: *channel,
                time_point: *time_point,
                spacing: *spacing,
            }
            .run()?,
        };
        let row = Row {
            name: name.to_string(),
            input: input.to_path_buf(),
            // The run's own count (`--phases auto` chooses it).
            phases: Some(summary.final_means.len()),
            iterations: Some(summary.iterations),
            converged: Some(summary.converged),
            seconds: Some(start.elapsed().as_secs_f64()),
            status: Status::Done,
            error: String::new(),
            warnings: summary.warnings.join("; "),
        };
        let marker = Marker {
            fingerprint,
            row: row.clone(),
        };
        let json = serde_json::to_vec_pretty(&marker).map_err(|e| Error::Usage(e.to_string()))?;
        staging::uninterrupted(|| write_bytes_atomic(dir.join(MARKER), &json))?;
        Ok(row)
    }

    fn params(&self) -> &SegmentParams {
        match &self.task {
            Task::Image { params, .. } | Task::Volume { params, .. } => params,
        }
    }

    fn fingerprint(&self, input: &Path) -> Result<Fingerprint> {
        let meta = std::fs::metadata(input)
            .map_err(|e| Error::Usage(format!("cannot read input {}: {e}", input.display())))?;
        let modified = meta
            .modified()
            .ok()
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map(|d| d.as_nanos());
        let (init_labels, init_surface, input_options) = match &self.task {
            Task::Image {
                init_labels,
                channel,
                time_point,
                spacing,
                ..
            } => (
                init_labels.clone(),
                None,
                input_options(
                    serde_json::json!({ "channel": channel, "spacing": spacing }),
                    [("time_point", *time_point), ("channel", *channel)],
                ),
            ),
            Task::Volume {
                init_labels,
                init_surface,
                channel,
                time_point,
                spacing,
                ..
            } => (
                init_labels.clone(),
                init_surface.clone(),
                input_options(
                    serde_json::json!({ "spacing": spacing }),
                    [("channel", *channel), ("time_point", *time_point)],
                ),
            ),
        };
        Ok(Fingerprint {
            version: env!("CARGO_PKG_VERSION").to_string(),
            three_d: self.task.is_3d(),
            params: serde_json::to_value(self.params()).map_err(|e| Error::Usage(e.to_string()))?,
            init_labels,
            init_surface,
            input_options,
            outputs: self
                .outputs
                .files_for(self.task.is_3d(), input)
                .iter()
                .map(|s| s.to_string())
                .collect(),
            input: input.to_path_buf(),
            input_bytes: meta.len(),
            input_modified: modified,
        })
    }

    /// The row of an earlier run that made every output of this one the
    /// same way, if `dir` holds them all.
    fn completed(&self, dir: &Path, fingerprint: &Fingerprint) -> Option<Row> {
        let bytes = std::fs::read(dir.join(MARKER)).ok()?;
        let marker: Marker = serde_json::from_slice(&bytes).ok()?;
        let all_there = fingerprint.outputs.iter().all(|f| dir.join(f).is_file());
        (marker.fingerprint == *fingerprint && all_there).then_some(marker.row)
    }
}

/// Each input's output folder name: its [`stem`], or, where several
/// inputs share a stem (`s1/img.png`, `s2/img.png`), the stem after as many
/// of its parent folders' names as tell them apart (`s1_img`, `s2_img`).
/// Where two of them share a folder (`img.png`, `img.tif`), their whole
/// names take the stem's place (`img_png`, `img_tif`; with another folder
/// in the group, `s1_img_png`, `s2_img_png`, `s2_img_tif`). Names that
/// still clash (a name so made that is another input's stem) are refused,
/// every clash in one message.
fn output_names(inputs: &[PathBuf]) -> Result<Vec<String>> {
    let mut by_stem: HashMap<String, Vec<usize>> = HashMap::new();
    for (i, p) in inputs.iter().enumerate() {
        by_stem.entry(stem(p)).or_default().push(i);
    }
    let mut names: Vec<String> = inputs.iter().map(|p| stem(p)).collect();
    let mut clashes = Vec::new();
    for (name, group) in by_stem.iter().filter(|(_, g)| g.len() > 1) {
        let parents: Vec<Vec<String>> = group.iter().map(|&i| parent_names(&inputs[i])).collect();
        let stems = vec![name.clone(); group.len()];
        let wholes: Vec<String> = group.iter().map(|&i| whole_name(&inputs[i])).collect();
        // The stems after their folders' names, or else the whole names.
        let told_apart = [(stems, 1), (wholes, 0)]
            .into_iter()
            .find_map(|(own, from)| folder_prefixed(&parents, &own, from));
        if let Some(told_apart) = told_apart {
            for (&i, n) in group.iter().zip(told_apart) {
                names[i] = n;
            }
        }
    }
    // (a name made above may be another input's stem: `img_png.jpg`)
    let mut by_name: HashMap<&str, Vec<usize>> = HashMap::new();
    for (i, name) in names.iter().enumerate() {
        by_name.entry(name).or_default().push(i);
    }
    for (name, group) in by_name.iter().filter(|(_, g)| g.len() > 1) {
        let listed: Vec<String> = group
            .iter()
            .map(|&i| inputs[i].display().to_string())
            .collect();
        clashes.push(format!("{} would all write {name:?}", listed.join(", ")));
    }
    if !clashes.is_empty() {
        clashes.sort();
        return Err(Error::Usage(format!(
            "inputs {}; rename one of each",
            clashes.join("; ")
        )));
    }
    Ok(names)
}

/// `own` (one name per input of a group) after the fewest of the inputs'
/// folders' names (`parents`, outermost first), at least `from`, that make
/// them all differ (`s1_img`); `None` when even all of them do not.
fn folder_prefixed(parents: &[Vec<String>], own: &[String], from: usize) -> Option<Vec<String>> {
    let deepest = parents.iter().map(Vec::len).max().unwrap_or(0);
    (from..=deepest).find_map(|d| {
        let named: Vec<String> = parents
            .iter()
            .zip(own)
            .map(|(p, own)| {
                let mut parts: Vec<&str> = p.iter().rev().take(d).map(String::as_str).collect();
                parts.reverse();
                parts.push(own);
                parts.join("_")
            })
            .collect();
        let distinct: HashSet<&String> = named.iter().collect();
        (distinct.len() == named.len()).then_some(named)
    })
}

/// `path`'s file name with every dot an underscore (`img.nii.gz`:
/// `img_nii_gz`), the output folder name of an input whose stem another
/// file in the same folder shares.
fn whole_name(path: &Path) -> String {
    path.file_name()
        .map_or_else(|| stem(path), |n| n.to_string_lossy().replace('.', "_"))
}

/// The names of the folders that hold `path`, outermost first (of its
/// absolute path where it can be found, so that `img.png` and
/// `../b/img.png` are told apart).
fn parent_names(path: &Path) -> Vec<String> {
    let full = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    full.parent()
        .map(|p| {
            p.components()
                .filter_map(|c| match c {
                    std::path::Component::Normal(n) => Some(n.to_string_lossy().into_owned()),
                    _ => None,
                })
                .collect()
        })
        .unwrap_or_default()
}

fn error_row(input: &Path, name: &str, error: String) -> Row {
    Row {
        name: name.to_string(),
        input: input.to_path_buf(),
        phases: None,
        iterations: None,
        converged: None,
        seconds: None,
        status: Status::Error,
        error,
        warnings: String::new(),
    }
}

/// One line for stderr about a finished input.
fn describe(row: &Row) -> String {
    match row.status {
        Status::Error => format!("{}: error: {}", row.name, row.error),
        Status::Skipped => format!("{}: complete, skipped", row.name),
        Status::Done => {
            let line = format!(
                "{}: {} after {} iterations ({:.2} s)",
                row.name,
                if row.converged == Some(true) {
                    "converged"
                } else {
                    "stopped before converging"
                },
                row.iterations.unwrap_or(0),
                row.seconds.unwrap_or(0.0)
            );
            if row.warnings.is_empty() {
                line
            } else {
                format!("{line}; warning: {}", row.warnings)
            }
        }
    }
}

/// The summary table: a header, then one row per input.
fn summary_csv(rows: &[Row]) -> Result<Vec<u8>> {
    let mut w = csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(Vec::new());
    let err = |e: csv::Error| Error::Usage(format!("summary table: {e}"));
    w.write_record(COLUMNS).map_err(err)?;
    for row in rows {
        w.serialize(row).map_err(err)?;
    }
    w.into_inner()
        .map_err(|e| Error::Usage(format!("summary table: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inputs_named_alike_take_their_folders_names() {
        let p = |s: &str| PathBuf::from(s);
        let inputs = [p("x/s1/img.png"), p("x/s2/img.png"), p("y/b.png")];
        assert_eq!(output_names(&inputs).unwrap(), ["s1_img", "s2_img", "b"]);
        // the same folder name twice: one more level
        let deeper = [p("u/day1/img.png"), p("v/day1/img.png")];
        assert_eq!(output_names(&deeper).unwrap(), ["u_day1_img", "v_day1_img"]);
        // one folder, one stem: the whole file names
        let same = [p("z/a.png"), p("z/a.tif"), p("z/c.png"), p("z/c.nii.gz")];
        assert_eq!(
            output_names(&same).unwrap(),
            ["a_png", "a_tif", "c_png", "c_nii_gz"]
        );
        // two folders, one holding two of them: its folder and whole names
        let mixed = [p("x/s1/img.png"), p("x/s2/img.png"), p("x/s2/img.tif")];
        assert_eq!(
            output_names(&mixed).unwrap(),
            ["s1_img_png", "s2_img_png", "s2_img_tif"]
        );
        // a name so made that another input has as its stem: every clash named
        let clash = [
            p("z/a.png"),
            p("z/a.tif"),
            p("z/a_png.jpg"),
            p("y/b.png"),
            p("y/b_tif.png"),
            p("y/b.tif"),
        ];
        let err = output_names(&clash).unwrap_err().to_string();
        assert!(
            err.contains("z/a.png, z/a_png.jpg would all write \"a_png\"")
                && err.contains("y/b_tif.png, y/b.tif would all write \"b_tif\""),
            "{err}"
        );
    }
}
