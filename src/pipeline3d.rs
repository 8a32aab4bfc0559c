//! 3D jobs as the command line runs them: load a volume (TIFF stack, folder
//! of slices, NIfTI) or generate a built-in 3D phantom, segment it with the
//! tetrahedral DSC, and write `labels.tif`, `mesh.vtu`, `interface.vtp` and
//! `report.json` through the same staged, all-or-nothing output directory as
//! the 2D pipeline.

use crate::dim::D3;
use crate::error::{Error, Result};
use crate::io::{save_labels_tiff, write_bytes_atomic, Volume};
use crate::phantom::noise::to_u8;
use crate::phantom::Phantom3Kind;
use crate::pipeline::{
    check_phantom, mean_dice, publish, run_with_progress, staging, JobTimes, RunReport, Source,
};
use crate::segment::{ImageView, Init, SegmentParams, SegmentReport, Segmentation};
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
    /// Label volume for `Init::Labels` (8-bit values are the phases).
    pub init_labels: Option<PathBuf>,
    /// A closed triangle surface (OFF, OBJ, STL; voxel coordinates, the
    /// volume box `[0, nx]×[0, ny]×[0, nz]`): the initial complex is
    /// tetrahedralised by TetGen to conform to it, phase 1 inside and 0
    /// outside, and `params.init` is not used. Needs the `tetgen` feature.
    pub init_surface: Option<PathBuf>,
    /// No progress bar.
    pub quiet: bool,
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
    init_surface: Option<&'a Path>,
    junction_edges: usize,
    quality: QualitySummary,
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

fn phantom_kind(name: &str) -> Result<Phantom3Kind> {
    Phantom3Kind::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Phantom3Kind::ALL.iter().map(|k| k.name()).collect();
        Error::Usage(format!(
            "unknown 3D phantom {name:?} (one of {})",
            names.join(", ")
        ))
    })
}

/// Loads a label volume: values in `[0, 1]` from 8-bit data are scaled back to `0..=255`.
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
    let labels: Vec<u8> = v.data().iter().map(|&x| to_u8(x as f64)).collect();
    if let Some(&m) = labels.iter().max() {
        if m as usize >= phases {
            return Err(Error::Usage(format!(
                "init labels {} use label {m}, but labels must be below the number of phases ({phases})",
                path.display()
            )));
        }
    }
    Ok(labels)
}

/// Runs a 3D segmentation job and writes `labels.tif` (multi-page 8-bit,
/// value = phase index, phases by increasing mean), `mesh.vtu` (tetrahedra,
/// cell data `phase`), `interface.vtp` (interface triangles, cell data
/// `phase` and `phase_other`) and `report.json` into the output directory.
pub fn run_segment3d(job: &Segment3dJob) -> Result<SegmentReport> {
    let t_load = Instant::now();
    let mut params = job.params.clone();
    let (volume, truth) = match &job.source {
        Source::File(path) => (Volume::load(path)?, None),
        Source::Phantom {
            name,
            size,
            noise,
            seed,
        } => {
            let kind = phantom_kind(name)?;
            check_phantom("3D phantom", *size, *noise, PHANTOM3_SIZES)?;
            let ph = kind.generate(*size, *noise, *seed);
            (
                Volume::from_raw(ph.nx, ph.ny, ph.nz, ph.image.clone()),
                Some(ph.truth),
            )
        }
    };
    let dims = volume.dims();
    if let Init::Labels { labels } = &mut params.init {
        let path = job
            .init_labels
            .as_ref()
            .ok_or_else(|| Error::Usage("--init labels needs --init-labels VOLUME".into()))?;
        *labels = load_label_volume(path, dims, params.phases)?;
    }
    let load_seconds = t_load.elapsed().as_secs_f64();

    let view = ImageView::new_3d(dims, volume.data())
        .ok_or_else(|| Error::Usage("volume buffer does not match its size".into()))?;
    let t_seg = Instant::now();
    let mut seg = match &job.init_surface {
        None => Segmentation::<D3>::new(view, params.clone())?,
        Some(path) => surface_segmentation(view, params.clone(), path)?,
    };
    let stage = staging(&job.out)?;
    let report = run_with_progress(&mut seg, params.max_iterations, job.quiet);
    let segment_seconds = t_seg.elapsed().as_secs_f64();

    let t_write = Instant::now();
    let labels = seg.label_image();
    let order = seg.phase_order();
    let complex = seg.complex();
    let dir = stage.path();
    save_labels_tiff(dir.join("labels.tif"), dims, &labels)?;
    complex.write_mesh_vtu(dir.join("mesh.vtu"), &order)?;
    complex.write_interface_vtp(dir.join("interface.vtp"), &order)?;
    let truth_dice = truth.map(|t| mean_dice(&labels, &t, params.phases));
    let times = JobTimes {
        load: load_seconds,
        segment: segment_seconds,
        write: t_write.elapsed().as_secs_f64(),
    };
    let rep = Report {
        run: RunReport::new(
            "dsc-seg segment3d",
            (&job.source, job.init_labels.as_deref()),
            &seg,
            &report,
            times,
            truth_dice,
        ),
        dims,
        init_surface: job.init_surface.as_deref(),
        junction_edges: complex.junction_edges().len(),
        quality: quality(complex),
    };
    let json = serde_json::to_vec_pretty(&rep).map_err(|e| Error::Usage(e.to_string()))?;
    write_bytes_atomic(dir.join("report.json"), &json)?;
    publish(
        stage,
        &job.out,
        &["labels.tif", "mesh.vtu", "interface.vtp", "report.json"],
    )?;
    Ok(report)
}

/// A segmentation starting from a TetGen mesh conforming to the surface in `path`.
#[cfg(feature = "tetgen")]
fn surface_segmentation<'a>(
    view: ImageView<'a>,
    params: SegmentParams,
    path: &Path,
) -> Result<Segmentation<'a, D3>> {
    use crate::segment::tetgen_init::complex_from_surface;
    let surface = crate::io::surface::read_surface(path)
        .map_err(|e| Error::Usage(format!("--init-surface {}: {e}", path.display())))?;
    params.validate_dims(view.dims)?;
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
    let kind = phantom_kind(name)?;
    check_phantom("3D phantom", size, noise, PHANTOM3_SIZES)?;
    let stage = staging(out)?;
    let ph = kind.generate(size, noise, seed);
    let base = kind.name();
    let names = vec![format!("{base}.tif"), format!("{base}_labels.tif")];
    let image: Vec<u8> = ph.image.iter().map(|&v| to_u8(v as f64)).collect();
    let dims = [ph.nx, ph.ny, ph.nz];
    save_labels_tiff(stage.path().join(&names[0]), dims, &image)?;
    save_labels_tiff(stage.path().join(&names[1]), dims, &ph.truth)?;
    let refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    publish(stage, out, &refs)?;
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
            quiet: true,
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
