//! The 3D job: a volume (TIFF stack, folder of slices, NIfTI) or a built-in
//! 3D phantom, segmented with the tetrahedral DSC into `labels.tif`,
//! `mesh.vtu`, `interface.vtp` and `report.json` through the same staged,
//! all-or-nothing output directory as the 2D job.

use super::input_summary::{with_file_values, InputSummary};
use super::{
    add_frame_and_phases, check_phantom, check_result, clamp_input, labels_of_samples, mean_dice,
    run_with_progress, ClampedInput, GroundTruth, Job, JobTimes, Provenance, RunReport, Source,
};
use crate::dim::D3;
use crate::error::{Error, Result};
use crate::io::intensity::IntensityMap;
use crate::io::resolution::is_tiff;
use crate::io::selection::Selection;
use crate::io::{save_labels_tiff, Colour, Volume};
use crate::phantom::noise::to_u8;
use crate::phantom::Phantom3Kind;
use crate::segment::measurements::Measurements;
use crate::segment::{ImageView, Init, SegmentParams, SegmentReport, Segmentation};
use crate::segmented::{Outputs, Render, Segmented};
use crate::staging::Staging;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A 3D segmentation job.
#[derive(Clone, Debug)]
pub struct Segment3dJob {
    /// The input: a volume path or a built-in 3D phantom.
    pub source: Source,
    /// The output directory (created if missing).
    pub out: PathBuf,
    /// Segmentation parameters (see [`SegmentParams::new_3d`]). For
    /// `Init::Labels` the labels are loaded from [`Segment3dJob::init_labels`].
    pub params: SegmentParams,
    /// Label volume for `Init::Labels` (its values as stored are the phases).
    pub init_labels: Option<PathBuf>,
    /// A closed triangle surface (OFF, OBJ, STL; voxel coordinates, the
    /// volume box `[0, nx]×[0, ny]×[0, nz]`): the initial complex is
    /// tetrahedralised by TetGen to conform to it, phase 1 inside and 0
    /// outside, and `params.init` is not used. Needs the `tetgen` feature.
    pub init_surface: Option<PathBuf>,
    /// The files to write.
    pub outputs: Outputs,
    /// No progress bar.
    pub quiet: bool,
    /// The channel of a multi-channel TIFF (an ImageJ hyperstack, an
    /// OME-TIFF) to segment (see [`load_volume_selected`]).
    pub channel: Option<usize>,
    /// The time point of a time-lapse TIFF to segment.
    pub time_point: Option<usize>,
    /// The voxel size (x, y, z) to use instead of the file's.
    pub spacing: Option<[f64; 3]>,
}

/// Sides of the 3D phantoms.
const PHANTOM3_SIZES: std::ops::RangeInclusive<usize> = 8..=1024;

/// Tet quality figures of the final mesh.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct QualitySummary {
    /// Smallest tet quality.
    pub min: f64,
    /// 5th percentile.
    pub p5: f64,
    /// Median.
    pub median: f64,
    /// Fraction of tets below 0.3.
    pub below_0_3: f64,
}

/// The 3D report: the shared fields, the volume size, the initial surface
/// and the final mesh's junction curves and tet quality.
#[derive(Serialize)]
struct Report<'a> {
    #[serde(flatten)]
    run: RunReport<'a>,
    dims: [usize; 3],
    input: InputSummary,
    init_surface: Option<&'a Path>,
    junction_edges: usize,
    quality: QualitySummary,
}

/// The volume's values in the file's units (as the report's means), or on
/// the loaded scale when the file's are unknown.
fn in_file_units(volume: &Volume) -> Vec<f32> {
    let map = volume.intensity().unwrap_or(IntensityMap::IDENTITY);
    volume
        .data()
        .iter()
        .map(|&v| map.original(f64::from(v)) as f32)
        .collect()
}

fn quality(c: &crate::complex::Complex3) -> QualitySummary {
    let mut q: Vec<f64> = c.cell_ids().map(|t| c.quality(t)).collect();
    if q.is_empty() {
        return QualitySummary::default();
    }
    q.sort_by(f64::total_cmp);
    QualitySummary {
        min: q[0],
        p5: q[q.len() / 20],
        median: q[q.len() / 2],
        below_0_3: q.iter().filter(|&&x| x < 0.3).count() as f64 / q.len() as f64,
    }
}

/// The 3D phantom `name`, once its name, side and noise are checked.
pub(crate) fn phantom3(name: &str, size: usize, noise: f64) -> Result<Phantom3Kind> {
    let kind = Phantom3Kind::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Phantom3Kind::ALL.iter().map(|k| k.name()).collect();
        Error::Usage(format!(
            "unknown 3D phantom {name:?} (one of {})",
            names.join(", ")
        ))
    })?;
    check_phantom("3D phantom", size, noise, PHANTOM3_SIZES)?;
    Ok(kind)
}

/// Loads a label volume: each voxel's value as the file stores it is its
/// phase (8 or 16 bits, signed, or whole-numbered floats: a NIfTI label map
/// of any type).
fn load_label_volume(path: &Path, dims: [usize; 3], phases: usize) -> Result<Vec<u8>> {
    let v = Volume::load(path)?;
    if v.dims() != dims {
        return Err(Error::Usage(format!(
            "init labels {} are {:?} voxels but the volume is {:?}",
            path.display(),
            v.dims(),
            dims
        )));
    }
    let map = v.intensity().unwrap_or(IntensityMap::unsigned(8));
    let sample_type = v.sample_type();
    let stored = v
        .data()
        .iter()
        .map(|&x| map.original_sample(f64::from(x), sample_type));
    labels_of_samples(stored, phases, path)
}

/// A 2D image file (PNG, JPEG, BMP, ...) is not a volume: `segment3d` says
/// which command takes it rather than calling its type unknown.
fn refuse_image_file(path: &Path) -> Result<()> {
    let volume_file = crate::io::volume::is_nifti(path) || crate::io::resolution::is_tiff(path);
    if path.is_file() && !volume_file && image::ImageFormat::from_path(path).is_ok() {
        return Err(Error::Usage(format!(
            "{} is a 2D image, segment it with `dsc-seg segment` (`segment3d` reads a folder of \
             slices, a multi-page TIFF or a NIfTI volume)",
            path.display()
        )));
    }
    Ok(())
}

/// A volume one voxel thick (a one-page TIFF, a NIfTI of one slice, a
/// folder of one slice) is a 2D image: `segment3d` could only call it too
/// thin to mesh, so it says which command takes it.
fn refuse_single_slice(path: &Path, volume: &Volume) -> Result<()> {
    if volume.nz() != 1 {
        return Ok(());
    }
    let (nx, ny) = (volume.nx(), volume.ny());
    let selection = volume.selection();
    if !selection.is_empty() {
        return Err(Error::Usage(format!(
            "{} at {} is one plane of {nx}×{ny} pixels: a 2D image, segment it with \
             `dsc-seg segment {}`",
            path.display(),
            selection.options(),
            selection.options()
        )));
    }
    let what = if path.is_dir() {
        format!("holds one slice of {nx}×{ny} pixels: a single slice is a 2D image")
    } else if crate::io::volume::is_nifti(path) {
        format!("is {nx}×{ny}×1 voxels, one slice: a single-slice NIfTI is a 2D image")
    } else {
        format!("is {nx}×{ny}×1 voxels, one page: a single-page TIFF is a 2D image")
    };
    Err(Error::Usage(format!(
        "{} {what}, segment it with `dsc-seg segment`",
        path.display()
    )))
}

/// Loads (or generates) a 3D input, with the phantom's ground truth.
pub fn load_volume(source: &Source) -> Result<(Volume, Option<GroundTruth>)> {
    load_volume_selected(source, Selection::default())
}

/// [`load_volume`] of one channel at one time point of a TIFF
/// ([`Volume::load_tiff_selected`]); a choice for any other input, which
/// has neither, is refused.
pub fn load_volume_selected(
    source: &Source,
    selection: Selection,
) -> Result<(Volume, Option<GroundTruth>)> {
    let tiff = matches!(source, Source::File(p) if !p.is_dir() && is_tiff(p));
    if !selection.is_empty() && !tiff {
        return Err(Error::Usage(format!(
            "{} chooses pages of a multi-channel or time-lapse TIFF (an ImageJ hyperstack or \
             an OME-TIFF); {} is not a TIFF",
            selection.options(),
            match source {
                Source::File(p) => p.display().to_string(),
                _ => "the input".into(),
            }
        )));
    }
    match source {
        Source::File(path) => {
            refuse_image_file(path)?;
            let volume = Volume::load_selected(path, selection)?;
            refuse_single_slice(path, &volume)?;
            Ok((volume, None))
        }
        Source::Phantom {
            name,
            size,
            noise,
            seed,
        } => {
            let kind = phantom3(name, *size, *noise)?;
            let ph = kind.generate(*size, *noise, *seed);
            let phases = ph.truth.iter().max().map_or(1, |&m| m as usize + 1);
            Ok((
                Volume::from_raw(ph.nx, ph.ny, ph.nz, ph.image),
                Some(GroundTruth {
                    labels: ph.truth,
                    phases,
                }),
            ))
        }
        Source::Array => Err(Error::Usage(
            "an in-memory volume has no file to load".into(),
        )),
    }
}

/// `params` with the labels of `Init::Labels` loaded from `init_labels`
/// (a label volume of size `dims`).
pub fn with_init_labels3(
    mut params: SegmentParams,
    init_labels: Option<&Path>,
    dims: [usize; 3],
) -> Result<SegmentParams> {
    if let Init::Labels { labels } = &mut params.init {
        let path = init_labels
            .ok_or_else(|| Error::Usage("--init labels needs --init-labels VOLUME".into()))?;
        *labels = load_label_volume(path, dims, params.phases)?;
    }
    Ok(params)
}

/// Runs a 3D segmentation job and writes its outputs (all: `labels.tif`,
/// multi-page 8-bit, value = phase index, phases by increasing mean;
/// `mesh.vtu`, tetrahedra with cell data `phase`; `interface.vtp`, interface
/// triangles with cell data `phase` and `phase_other`; `report.json`) into
/// the output directory.
pub fn run_segment3d(job: &Segment3dJob) -> Result<SegmentReport> {
    job.run()
}

impl Job for Segment3dJob {
    type Input = Volume;
    const THREE_D: bool = true;

    fn source(&self) -> &Source {
        &self.source
    }

    fn init_labels(&self) -> Option<&Path> {
        self.init_labels.as_deref()
    }

    fn out(&self) -> &Path {
        &self.out
    }

    fn outputs(&self) -> &Outputs {
        &self.outputs
    }

    /// The volume, with the job's voxel size if it has one.
    fn load(&self) -> Result<(Volume, Option<GroundTruth>)> {
        let selection = Selection {
            channel: self.channel,
            time_point: self.time_point,
        };
        let (volume, truth) = load_volume_selected(&self.source, selection)?;
        let volume = match self.spacing {
            Some(s) => volume.respaced(s),
            None => volume,
        };
        Ok((volume, truth))
    }

    fn params_for(&self, volume: &Volume) -> Result<SegmentParams> {
        with_init_labels3(self.params.clone(), self.init_labels(), volume.dims())
    }

    fn segment_then<T>(
        &self,
        volume: &Volume,
        params: SegmentParams,
        provenance: Provenance,
        ready: impl FnOnce() -> Result<T>,
    ) -> Result<(Segmented, T)> {
        segment_volume_then(
            volume,
            params,
            provenance,
            self.init_surface.as_deref(),
            self.quiet,
            ready,
        )
    }
}

/// Segments a volume held in memory (the parameters' `Init::Labels`, if any,
/// already loaded; `init_surface` as [`Segment3dJob::init_surface`]): the
/// labels, the final mesh and the report.
pub fn segment_volume(
    volume: &Volume,
    params: SegmentParams,
    provenance: Provenance,
    init_surface: Option<&Path>,
    quiet: bool,
) -> Result<Segmented> {
    segment_volume_then(volume, params, provenance, init_surface, quiet, || Ok(())).map(|(s, ())| s)
}

/// [`segment_volume`], calling `ready` once the input and parameters are
/// validated, before the run (to check the output directory first).
pub(crate) fn segment_volume_then<T>(
    volume: &Volume,
    params: SegmentParams,
    provenance: Provenance,
    init_surface: Option<&Path>,
    quiet: bool,
    ready: impl FnOnce() -> Result<T>,
) -> Result<(Segmented, T)> {
    let dims = volume.dims();
    let frame = volume.frame();
    let t_seg = Instant::now();
    let file_value = |v: f32| match volume.intensity() {
        Some(map) => map.original_sample(f64::from(v), volume.sample_type()),
        None => f64::from(v),
    };
    let ClampedInput {
        data: clamped,
        outlier_extremes,
        robust_range,
    } = clamp_input(volume.data(), dims, file_value, "voxels");
    let data = clamped
        .as_ref()
        .map_or(volume.data(), |(c, _)| c.as_slice());
    let mut view = ImageView::new_3d(dims, data)
        .ok_or_else(|| Error::Usage("volume buffer does not match its size".into()))?
        .with_spacing(frame.domain_scale)
        .ok_or_else(|| {
            Error::Usage(format!(
                "the voxel size {:?} must be positive and finite",
                frame.spacing
            ))
        })?;
    if let Some(range) = robust_range {
        view = view.with_robust_range(range);
    }
    let mut seg = match init_surface {
        None => Segmentation::<D3>::new(view, params.clone())
            .map_err(|e| with_file_values(e, volume.intensity(), volume.sample_type()))?,
        Some(path) => surface_segmentation(view, params.clone(), path)?,
    };
    let ready = ready()?;
    let mut report = run_with_progress(&mut seg, params.max_iterations, quiet)?;
    if let Some((_, warning)) = &clamped {
        report.warnings.insert(0, warning.clone());
    }
    // What reading the file left to say comes first: which series was read,
    // and the voxel size, which concerns every length of the result.
    let series = volume.series_warning().map(String::from);
    report.warnings.splice(
        0..0,
        series.into_iter().chain(volume.size_warnings().to_vec()),
    );
    let segment_seconds = t_seg.elapsed().as_secs_f64();

    let labels = seg.label_image();
    check_result(
        &seg,
        &view,
        &labels,
        volume.intensity().map_or(1.0, |m| m.scale()),
        &mut report,
    );
    let order = seg.phase_order();
    let complex = seg.complex();
    let truth_dice = provenance
        .truth
        .as_ref()
        .map(|t| mean_dice(&labels, &t.labels, params.phases));
    let times = JobTimes {
        load: provenance.load_seconds,
        segment: segment_seconds,
        write: 0.0,
    };
    let run = RunReport::new(
        "dsc-seg segment3d",
        (&provenance.source, provenance.init_labels.as_deref()),
        &seg,
        &report,
        times,
        truth_dice,
    );
    let input = InputSummary::new(
        (volume.sample_type(), Colour::Gray, volume.selection()),
        volume.intensity(),
        (&report, outlier_extremes),
        &run.ordered_means,
    );
    let rep = Report {
        run,
        dims,
        input,
        init_surface,
        junction_edges: complex.junction_edges().len(),
        quality: quality(complex),
    };
    let mut report_json = serde_json::to_value(&rep).map_err(|e| Error::Usage(e.to_string()))?;
    // (the samples the segmentation saw, as in 2D)
    let measurements =
        Measurements::from_labels(&labels, data, volume.intensity(), &frame, params.phases)
            .with_mesh_3d(complex, &order, &frame);
    add_frame_and_phases(&mut report_json, &frame, &measurements)?;
    let arrays = complex.to_arrays();
    let cell_phases = arrays
        .labels
        .iter()
        .map(|&l| order[(l as usize).min(order.len() - 1)])
        .collect();
    let result = Segmented {
        dims: dims.to_vec(),
        labels,
        vertices: arrays.points.iter().flatten().copied().collect(),
        cells: arrays.connectivity,
        cell_phases,
        summary: report,
        report: report_json,
        frame,
        measurements,
        render: Render::Volume {
            values: Some(in_file_units(volume)),
            complex: Box::new(complex.clone()),
            order,
            nifti_header: volume.nifti_header().map(<[u8]>::to_vec),
        },
        tiff_labels: false,
    };
    Ok((result, ready))
}

/// A segmentation starting from a TetGen mesh conforming to the surface in `path`.
#[cfg(feature = "tetgen")]
fn surface_segmentation<'a>(
    view: ImageView<'a>,
    params: SegmentParams,
    path: &Path,
) -> Result<Segmentation<'a, D3>> {
    use crate::complex::surface::complex_from_surface;
    if view.spacing != [1.0; 3] {
        return Err(Error::Usage(format!(
            "--init-surface {} is in voxel coordinates: it needs a volume without a voxel size \
             (give --spacing 1,1,1)",
            path.display()
        )));
    }
    let surface = crate::io::surface::read_surface(path)
        .map_err(|e| Error::Usage(format!("--init-surface {}: {e}", path.display())))?;
    params.validate_in(view.dims, view.spacing)?;
    let l = params.resolved_edge_length(view.dims);
    let complex = complex_from_surface(&surface, view.dims, l)
        .map_err(|e| Error::Usage(format!("--init-surface {}: {e}", path.display())))?;
    Ok(Segmentation::from_complex(view, params, complex)?)
}

/// Without the `tetgen` feature there is no TetGen to build the mesh.
#[cfg(not(feature = "tetgen"))]
fn surface_segmentation<'a>(
    _view: ImageView<'a>,
    _params: SegmentParams,
    path: &Path,
) -> Result<Segmentation<'a, D3>> {
    Err(Error::Usage(format!(
        "--init-surface {} needs TetGen: rebuild with `cargo build --release --features tetgen` \
         (needs libtet1.5-dev; TetGen is AGPL-3, so the feature is off by default)",
        path.display()
    )))
}

/// Writes 3D phantom `name` as `NAME.tif` (the 8-bit volume) and
/// `NAME_labels.tif` (ground-truth phase per voxel) into `out`; both are
/// multi-page TIFF stacks, one page per z slice. Returns the file names.
pub fn run_phantom3d(
    name: &str,
    size: usize,
    noise: f64,
    seed: u64,
    out: &Path,
) -> Result<Vec<String>> {
    let kind = phantom3(name, size, noise)?;
    let stage = Staging::new(out)?;
    let ph = kind.generate(size, noise, seed);
    let base = kind.name();
    let names = vec![format!("{base}.tif"), format!("{base}_labels.tif")];
    let image: Vec<u8> = ph.image.iter().map(|&v| to_u8(v as f64)).collect();
    let dims = [ph.nx, ph.ny, ph.nz];
    save_labels_tiff(stage.path().join(&names[0]), dims, &image, None)?;
    save_labels_tiff(stage.path().join(&names[1]), dims, &ph.truth, None)?;
    let refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    stage.publish(out, &refs)?;
    Ok(names)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phantom_files_round_trip_and_segment3d_writes_everything() {
        let dir = tempfile::tempdir().unwrap();
        let names = run_phantom3d("two_balls", 24, 0.05, 1, dir.path()).unwrap();
        let v = Volume::load(dir.path().join(&names[0])).unwrap();
        assert_eq!(v.dims(), [24, 24, 24]);
        let mut params = SegmentParams::new_3d(2);
        params.max_iterations = 10;
        let job = Segment3dJob {
            source: Source::File(dir.path().join(&names[0])),
            out: dir.path().join("out"),
            params,
            init_labels: None,
            init_surface: None,
            outputs: Outputs::ALL,
            quiet: true,
            channel: None,
            time_point: None,
            spacing: None,
        };
        let report = run_segment3d(&job).unwrap();
        assert!(report.cells > 0);
        for f in ["labels.tif", "mesh.vtu", "interface.vtp", "report.json"] {
            assert!(job.out.join(f).is_file(), "{f} missing");
        }
        let labels = Volume::load(job.out.join("labels.tif")).unwrap();
        assert_eq!(labels.dims(), [24, 24, 24]);
        let truth = Volume::load(dir.path().join(&names[1])).unwrap();
        let pred: Vec<u8> = labels.data().iter().map(|&x| to_u8(x as f64)).collect();
        let gt: Vec<u8> = truth.data().iter().map(|&x| to_u8(x as f64)).collect();
        assert!(mean_dice(&pred, &gt, 2) > 0.8);
        assert!(run_phantom3d("nope", 24, 0.1, 1, dir.path()).is_err());
    }
}
