//! Initial labelling of the cells: by histogram thresholds, by range, by
//! disks, or from a label image.

use super::error::SegmentError;
use super::image::ImageView;
use super::integrate::CellStats;
use super::params::{Init, SegmentParams};
use super::raster::Raster;
use super::thresholds::Classes;
use crate::complex::{CellId, Complex, Label};
use crate::dim::Point;

/// Labels the cells of `complex` per `params.init` and returns a starting mean
/// per phase where one is known before integration (the class means of
/// [`Init::Histogram`], the interval midpoints of [`Init::Range`]; `None`
/// otherwise). `classes` is the histogram split [`Init::Histogram`] uses.
pub fn initialise<K: Raster>(
    complex: &mut Complex<K>,
    image: &ImageView<'_>,
    params: &SegmentParams,
    cells: &[CellStats],
    range: (f64, f64),
    classes: Option<&Classes>,
) -> Result<Vec<Option<f64>>, SegmentError> {
    let n = params.phases;
    let ids: Vec<CellId> = complex.cell_ids().collect();
    let mut changes: Vec<(CellId, Label)> = Vec::with_capacity(ids.len());
    let centroid = |cx: &Complex<K>, c: CellId| {
        let pts = cx.cell_points(c);
        let mut g = K::Point::zero();
        for p in &pts[..K::NV] {
            g += *p;
        }
        g * (1.0 / K::NV as f64)
    };
    let cell_mean = |cx: &Complex<K>, c: CellId| {
        cells[c.index()]
            .mean()
            .unwrap_or_else(|| K::sample(image, centroid(cx, c)))
    };
    match &params.init {
        Init::Histogram => {
            let classes = classes.ok_or_else(|| {
                SegmentError::Init("the histogram initialisation needs the histogram".into())
            })?;
            for &c in &ids {
                let k = classes.class_of(cell_mean(complex, c)).min(n - 1);
                changes.push((c, k as Label));
            }
            complex.set_labels(&changes);
            let mut means = classes.means.clone();
            means.resize(n, None);
            Ok(means)
        }
        Init::Range => {
            let (lo, hi) = range;
            let width = (hi - lo) / n as f64;
            for &c in &ids {
                let m = cell_mean(complex, c);
                let k = (((m - lo) / width).floor().max(0.0) as usize).min(n - 1);
                changes.push((c, k as Label));
            }
            complex.set_labels(&changes);
            Ok((0..n)
                .map(|k| Some(lo + (k as f64 + 0.5) * width))
                .collect())
        }
        Init::Disks(disks) => {
            for &c in &ids {
                let g = centroid(complex, c);
                let mut l = 0;
                for d in disks {
                    let (dx, dy) = (g[0] - d.x, g[1] - d.y);
                    if dx * dx + dy * dy < d.r * d.r {
                        l = d.phase;
                    }
                }
                changes.push((c, l));
            }
            complex.set_labels(&changes);
            Ok(vec![None; n])
        }
        Init::Balls(balls) => {
            for &c in &ids {
                let g = centroid(complex, c);
                let mut l = 0;
                for b in balls {
                    let d2: f64 = (0..K::N).map(|a| (g[a] - b.centre[a]).powi(2)).sum();
                    if d2 < b.r * b.r {
                        l = b.phase;
                    }
                }
                changes.push((c, l));
            }
            complex.set_labels(&changes);
            Ok(vec![None; n])
        }
        Init::Labels { labels } => {
            let mut votes = vec![0u32; n];
            for &c in &ids {
                votes.iter_mut().for_each(|v| *v = 0);
                let pts = complex.cell_points(c);
                K::cell_pixels(image, &pts[..K::NV], &mut |p| {
                    votes[(labels[p] as usize).min(n - 1)] += 1;
                });
                let l = if votes.iter().all(|&v| v == 0) {
                    let g = centroid(complex, c);
                    labels[nearest_pixel(image, g)] as Label
                } else {
                    let (k, _) = votes
                        .iter()
                        .enumerate()
                        .max_by_key(|&(k, &v)| (v, usize::MAX - k))
                        .expect("n >= 2");
                    k as Label
                };
                changes.push((c, l.min(n as Label - 1)));
            }
            complex.set_labels(&changes);
            Ok(vec![None; n])
        }
    }
}

/// Linear index of the pixel/voxel containing `p` (clamped into the image).
pub fn nearest_pixel<P: Point>(image: &ImageView<'_>, p: P) -> usize {
    let mut idx = 0;
    let mut stride = 1;
    for (axis, &dim) in image.dims.iter().enumerate() {
        let c = if axis < 3 && dim > 1 {
            ((p[axis] / image.spacing[axis]).floor().max(0.0) as usize).min(dim - 1)
        } else {
            0
        };
        idx += c * stride;
        stride *= dim;
    }
    idx
}
