//! `dsc_seg._native`: the compiled half of the `dsc_seg` Python package.
//!
//! The Python half (`dsc_seg/__init__.py`) turns `segment(image, **options)`'s
//! keywords into the command line's option arguments; this half parses them
//! with the command line's own option structs, converts the NumPy array,
//! runs the library's in-memory pipeline with the GIL released, and hands
//! back the result's arrays, report and writer.

mod convert;
mod errors;

use clap::Parser;
use dsc_seg::cancel;
use dsc_seg::options::{Segment3dOptions, SegmentOptions};
use dsc_seg::pipeline::{
    load_image, load_volume, segment_image, segment_volume, with_init_labels, with_init_labels3,
    Provenance, Source,
};
use dsc_seg::segmented::{Outputs, Segmented};
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::Arc;
use std::time::Duration;

use crate::errors::{parse_error, to_py};

/// How often a running segmentation looks for Ctrl-C.
const SIGNAL_CHECK: Duration = Duration::from_millis(50);

/// `segment`'s options in 2D, exactly as `dsc-seg segment` takes them.
#[derive(Parser, Debug)]
#[command(name = "segment", allow_negative_numbers = true)]
struct Options2 {
    #[command(flatten)]
    options: SegmentOptions,
    /// The length unit of `spacing` (an array has none of its own).
    #[arg(long)]
    unit: Option<String>,
}

/// `segment`'s options in 3D, exactly as `dsc-seg segment3d` takes them.
#[derive(Parser, Debug)]
#[command(name = "segment", allow_negative_numbers = true)]
struct Options3 {
    #[command(flatten)]
    options: Segment3dOptions,
    /// The length unit of `spacing` (an array has none of its own).
    #[arg(long)]
    unit: Option<String>,
}

/// Refuses `channel` and `time_point`, which choose the pages of an image
/// file: an array has none (its caller indexes it instead).
fn refuse_pages(channel: Option<usize>, time_point: Option<usize>) -> PyResult<()> {
    if channel.is_some() || time_point.is_some() {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "channel and time_point choose a channel or time point of an image file; index \
             the array instead",
        ));
    }
    Ok(())
}

/// Segments a 2D or 3D array; `args` are command-line option arguments.
#[pyfunction]
fn segment(py: Python<'_>, image: &Bound<'_, PyAny>, args: Vec<String>) -> PyResult<Segmentation> {
    let argv = std::iter::once("segment".to_string()).chain(args);
    let ndim: usize = image.getattr("ndim")?.extract()?;
    let inner = match ndim {
        2 => {
            let o = Options2::try_parse_from(argv).map_err(|e| parse_error(&e))?;
            refuse_pages(o.options.channel, o.options.time_point)?;
            let spacing = o.options.spacing().map_err(to_py)?;
            let unit = checked_unit(o.unit)?;
            let image = convert::image(image)?.with_spacing(spacing).with_unit(unit);
            let params = o.options.params(2).map_err(to_py)?;
            let params = with_init_labels(params, o.options.init_labels.as_deref(), image.dims())
                .map_err(to_py)?;
            interruptible(py, || {
                segment_image(&image, params, Provenance::array(), true)
            })
        }
        3 => {
            let o = Options3::try_parse_from(argv).map_err(|e| parse_error(&e))?;
            refuse_pages(o.options.channel, o.options.time_point)?;
            let volume = match o.options.spacing().map_err(to_py)? {
                Some(spacing) => convert::volume(image)?.respaced(spacing),
                None => convert::volume(image)?,
            };
            let volume = match checked_unit(o.unit)? {
                Some(unit) => volume.with_unit(&unit),
                None => volume,
            };
            let params = o.options.params(2).map_err(to_py)?;
            let params = with_init_labels3(params, o.options.init_labels.as_deref(), volume.dims())
                .map_err(to_py)?;
            let surface = o.options.init_surface;
            interruptible(py, || {
                segment_volume(
                    &volume,
                    params,
                    Provenance::array(),
                    surface.as_deref(),
                    true,
                )
            })
        }
        n => {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "image has {n} dimensions; expected a 2D image (rows, columns) or a 3D volume \
                 (slices, rows, columns)"
            )))
        }
    };
    Ok(Segmentation {
        inner: inner?.map_err(to_py)?,
    })
}

/// The `unit` keyword: a short ASCII name such as `um` or `mm`, which
/// every output can store (a TIFF's ImageJ description is ASCII).
fn checked_unit(unit: Option<String>) -> PyResult<Option<String>> {
    match unit {
        Some(u) if u.is_empty() || !u.chars().all(|c| c.is_ascii_graphic()) => {
            Err(pyo3::exceptions::PyValueError::new_err(format!(
                "unit {u:?}: expected a length unit such as \"um\" or \"mm\" \
                 (ASCII, no spaces; \"um\" for µm)"
            )))
        }
        u => Ok(u),
    }
}

/// Runs `job` on a thread of its own with the GIL released, looking for a
/// Python signal every [`SIGNAL_CHECK`]: on Ctrl-C (or a notebook's
/// "interrupt"), the job stops at its next iteration ([`cancel`]) and the
/// signal's exception (`KeyboardInterrupt`) is raised, the interpreter alive.
fn interruptible<T: Send>(py: Python<'_>, job: impl FnOnce() -> T + Send) -> PyResult<T> {
    let token = Arc::new(AtomicBool::new(false));
    let (sender, mut receiver) = mpsc::channel();
    std::thread::scope(|scope| {
        let worker_token = token.clone();
        scope.spawn(move || {
            // (the receiver is gone only after an error, when no one waits)
            let _ = sender.send(cancel::with_token(worker_token, job));
        });
        loop {
            let (back, waited) = py.detach(move || {
                let waited = receiver.recv_timeout(SIGNAL_CHECK);
                (receiver, waited)
            });
            receiver = back;
            match waited {
                Ok(result) => return Ok(result),
                Err(RecvTimeoutError::Timeout) => {
                    if let Err(signal) = py.check_signals() {
                        token.store(true, Ordering::Relaxed);
                        return Err(signal);
                    }
                }
                // The worker panicked: the scope re-raises its panic.
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(PyRuntimeError::new_err("segmentation thread failed"))
                }
            }
        }
    })
}

/// A phantom and its true labels as 8-bit arrays, like `dsc-seg phantom`'s
/// (or `phantom3d`'s) files.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn phantom<'py>(
    py: Python<'py>,
    name: &str,
    size: usize,
    noise: f64,
    seed: u64,
    ndim: Option<usize>,
) -> PyResult<(Bound<'py, PyArrayDyn<u8>>, Bound<'py, PyArrayDyn<u8>>)> {
    let source = Source::Phantom {
        name: name.to_string(),
        size,
        noise,
        seed,
    };
    // A name both commands know (`four_phase`) is the image unless ndim=3.
    let three_d = match ndim {
        Some(3) => true,
        Some(2) => false,
        Some(n) => {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "ndim={n}: a phantom is 2D or 3D"
            )))
        }
        None => {
            dsc_seg::phantom::Phantom2Kind::from_name(name).is_none()
                && dsc_seg::phantom::Phantom3Kind::from_name(name).is_some()
        }
    };
    let (samples, truth, shape) = if three_d {
        let (v, truth) = load_volume(&source).map_err(to_py)?;
        let [nx, ny, nz] = v.dims();
        (v.into_data(), truth, vec![nz, ny, nx])
    } else {
        let (img, truth) = load_image(&source).map_err(to_py)?;
        let (w, h) = img.dims();
        (img.into_data(), truth, vec![h, w])
    };
    let image: Vec<u8> = samples
        .iter()
        .map(|&v| dsc_seg::phantom::noise::to_u8(v as f64))
        .collect();
    let truth = truth.map(|t| t.labels).unwrap_or_default();
    Ok((array(py, image, &shape)?, array(py, truth, &shape)?))
}

/// A NumPy array of `shape` holding `data`.
fn array<'py, T: numpy::Element>(
    py: Python<'py>,
    data: Vec<T>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<T>>> {
    PyArray1::from_vec(py, data).reshape(shape)
}

/// The result of `dsc_seg.segment`: labels, final mesh and report.
#[pyclass(frozen, module = "dsc_seg")]
struct Segmentation {
    inner: Segmented,
}

#[pymethods]
impl Segmentation {
    /// Phase index per pixel/voxel (uint8, the input's shape), 0..N-1 by increasing mean.
    #[getter]
    fn labels<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
        let mut shape = self.inner.dims.clone();
        shape.reverse();
        array(py, self.inner.labels.clone(), &shape)
    }

    /// Vertex positions of the final mesh (float64, vertices × 2 or 3), x first, in the
    /// input's physical units (`spacing`, 1 per pixel/voxel without it) from the outer corner
    /// of pixel/voxel 0, in 2D as in 3D.
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let d = self.inner.dims.len();
        let n = self.inner.vertices.len() / d;
        array(py, self.inner.physical_vertices(), &[n, d])
    }

    /// The mesh's triangles (2D) or tetrahedra (3D) as vertex indices (uint32, cells × 3 or 4).
    #[getter]
    fn cells<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<u32>>> {
        let k = self.inner.dims.len() + 1;
        let n = self.inner.cells.len() / k;
        array(py, self.inner.cells.clone(), &[n, k])
    }

    /// Each cell's phase index (uint8), as in `labels`.
    #[getter]
    fn cell_phases<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
        let n = self.inner.cell_phases.len();
        array(py, self.inner.cell_phases.clone(), &[n])
    }

    /// The run's warnings (a lost phase, the iteration cap, the choice of
    /// `--phases auto`, correlated noise), as the command line prints them.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.summary.warnings.clone()
    }

    /// The report (what `report.json` holds) as JSON text.
    #[getter]
    fn report_json(&self) -> String {
        self.inner.report.to_string()
    }

    /// Writes the command line's output files into `dir`, all or nothing.
    #[pyo3(signature = (dir, outputs = "all"))]
    fn write(&self, py: Python<'_>, dir: PathBuf, outputs: &str) -> PyResult<()> {
        let outputs = Outputs::parse(outputs, self.inner.is_3d()).map_err(to_py)?;
        py.detach(|| self.inner.write(&dir, &outputs))
            .map_err(to_py)
    }
}

/// The compiled part of `dsc_seg`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(segment, m)?)?;
    m.add_function(wrap_pyfunction!(phantom, m)?)?;
    m.add_class::<Segmentation>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
