//! Integration of the image over the cells: per-cell sums, per-phase means.

use super::image::ImageView;
use super::raster::Raster;
use crate::complex::{CellId, Complex, Label};
use crate::dim::Dim;
use rayon::prelude::*;
use serde::Serialize;

/// Sum, sum of squares and number of the pixels whose centre lies in a cell.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CellStats {
    /// Sum of the intensities.
    pub sum: f64,
    /// Sum of the squared intensities.
    pub sum_sq: f64,
    /// Number of pixels.
    pub count: u32,
}

impl CellStats {
    /// Mean intensity, `None` for a cell that covers no pixel centre.
    pub fn mean(&self) -> Option<f64> {
        (self.count > 0).then(|| self.sum / self.count as f64)
    }
    /// Sum of squared deviations from `m`: `Σ (I − m)²`.
    pub fn sse(&self, m: f64) -> f64 {
        (self.sum_sq - 2.0 * m * self.sum + self.count as f64 * m * m).max(0.0)
    }
}

/// Fills `out` (indexed by cell id; dead cells get zeros) with the statistics
/// of every live cell, in parallel. `out` is reused: it only grows.
pub fn integrate_cells<K: Raster>(
    complex: &Complex<K>,
    image: &ImageView<'_>,
    out: &mut Vec<CellStats>,
) {
    out.clear();
    out.resize(complex.cell_capacity(), CellStats::default());
    let corners = |i: usize| {
        let c = CellId(i as u32);
        complex.is_alive(c).then(|| complex.cell_points(c))
    };
    out.par_chunks_mut(2)
        .enumerate()
        .for_each_init(PairScratch::default, |scratch, (k, pair)| {
            let b = (pair.len() == 2).then(|| corners(2 * k + 1)).flatten();
            fill_pair::<K>(image, pair, [corners(2 * k), b], scratch);
        });
}

/// A cell's corners when it was last integrated (`None`: not cached).
type CachedCorners<K> = Option<[<K as Dim>::Point; 4]>;

/// Cell statistics kept between iterations, so that only the cells that
/// changed are integrated again.
///
/// A cell's statistics depend on nothing but its corner positions (and the
/// image): a cell whose corners are bit for bit those it had at the previous
/// call keeps its statistics, every other live cell is integrated afresh.
/// The result is therefore identical to [`integrate_cells`]; an unchanged
/// cell costs one comparison instead of a rasterisation. Cells far from the
/// interface never move, so after the first iterations only the band the
/// interface sweeps is integrated.
#[derive(Clone, Debug)]
pub struct CellCache<K: Dim> {
    /// Corners at the last integration, per cell id.
    corners: Vec<CachedCorners<K>>,
    /// The image the cache was filled from (address and length).
    image: (usize, usize),
    /// [`Complex::compactions`] at the last call.
    generation: u64,
    /// Scratch: the cells to integrate, with their ordering key.
    changed: Vec<(u64, CellId)>,
    /// Scratch: their statistics, in that order.
    fresh: Vec<CellStats>,
    scratch: PairScratch,
}

impl<K: Raster> Default for CellCache<K> {
    fn default() -> Self {
        Self::new()
    }
}

impl<K: Raster> CellCache<K> {
    /// An empty cache.
    pub fn new() -> Self {
        CellCache {
            corners: Vec::new(),
            image: (0, 0),
            generation: 0,
            changed: Vec::new(),
            fresh: Vec::new(),
            scratch: PairScratch::default(),
        }
    }

    /// Fills `out` (indexed by cell id; dead cells get zeros) exactly as
    /// [`integrate_cells`] does, re-integrating only the live cells whose
    /// corners changed since the last call (all of them if `image` is not
    /// the image of the last call). `out` must be the vector the previous
    /// call filled. Returns the number of cells integrated.
    pub fn integrate(
        &mut self,
        complex: &Complex<K>,
        image: &ImageView<'_>,
        out: &mut Vec<CellStats>,
    ) -> usize {
        let key = (image.data.as_ptr() as usize, image.data.len());
        let cap = complex.cell_capacity();
        let generation = complex.compactions();
        if key != self.image
            || out.len() != self.corners.len()
            || generation < self.generation
            || generation > self.generation + 1
        {
            self.corners.clear();
            out.clear();
            self.image = key;
        } else if generation == self.generation + 1 {
            // One compaction since the last call: carry every cached cell to
            // its new id (whatever it holds there is checked below anyway).
            // Compaction keeps the order, so new ids never exceed old ones
            // and the entries move forward in place.
            let map = complex.last_cell_map();
            let mut kept = 0;
            for (old, new) in map.iter().enumerate().take(self.corners.len()) {
                if let Some(new) = new {
                    self.corners[new.index()] = self.corners[old];
                    out[new.index()] = out[old];
                    kept = new.index() + 1;
                }
            }
            self.corners.truncate(kept);
            out.truncate(kept);
        }
        self.generation = generation;
        out.resize(cap, CellStats::default());
        self.corners.resize(cap, None);
        self.find_changed(complex, out);
        self.integrate_changed(image, out);
        self.changed.len()
    }

    /// Lists the live cells whose corners changed (recording their new
    /// corners) with their [`spatial_key`]; zeroes the statistics of dead
    /// cells. In parallel only for a large complex (see [`PARALLEL_BATCH`]).
    fn find_changed(&mut self, complex: &Complex<K>, out: &mut [CellStats]) {
        self.changed.clear();
        let check = |(i, (s, k)): (usize, (&mut CellStats, &mut CachedCorners<K>))| {
            let c = CellId(i as u32);
            if !complex.is_alive(c) {
                *s = CellStats::default();
                *k = None;
                return None;
            }
            let pts = complex.cell_points(c);
            if k.is_some_and(|old| same_corners::<K>(&old, &pts)) {
                return None;
            }
            *k = Some(pts);
            Some((spatial_key::<K>(&pts), c))
        };
        if out.len() >= 8 * PARALLEL_BATCH {
            let cells = out.par_iter_mut().zip(self.corners.par_iter_mut());
            self.changed.par_extend(cells.enumerate().filter_map(check));
        } else {
            let cells = out.iter_mut().zip(self.corners.iter_mut());
            self.changed.extend(cells.enumerate().filter_map(check));
        }
    }

    /// Integrates the changed cells in image order and stores their
    /// statistics. Each cell's sums are its own, so the order changes no
    /// bit; image order makes neighbouring cells share the image rows they
    /// read, which id order (new cells are scattered along the interface)
    /// fetched again from memory for every cell. Threads only pay for a
    /// large batch: waking them costs more than the few thousand cells of
    /// a typical step (measured, 2 cores).
    fn integrate_changed(&mut self, image: &ImageView<'_>, out: &mut [CellStats]) {
        self.changed.sort_unstable_by_key(|&(key, _)| key);
        self.fresh.clear();
        self.fresh.resize(self.changed.len(), CellStats::default());
        let corners = &self.corners;
        let fill = |scratch: &mut PairScratch,
                    (stats, ids): (&mut [CellStats], &[(u64, CellId)])| {
            let pair = [0, 1].map(|j| ids.get(j).and_then(|&(_, c)| corners[c.index()]));
            fill_pair::<K>(image, stats, pair, scratch);
        };
        if self.changed.len() >= PARALLEL_BATCH {
            self.fresh
                .par_chunks_mut(2)
                .zip(self.changed.par_chunks(2))
                .for_each_init(PairScratch::default, fill);
        } else {
            for chunk in self.fresh.chunks_mut(2).zip(self.changed.chunks(2)) {
                fill(&mut self.scratch, chunk);
            }
        }
        for (&(_, c), &st) in self.changed.iter().zip(&self.fresh) {
            out[c.index()] = st;
        }
    }
}

/// Cells to integrate from which threads pay off.
const PARALLEL_BATCH: usize = 8192;

/// Orders cells by the position of their first corner along the last two
/// axes: pixel row then column in 2D, slice then row in 3D. Any order gives
/// the same statistics; this one reads the image nearly in memory order.
#[inline]
fn spatial_key<K: Dim>(pts: &[K::Point; 4]) -> u64 {
    let coord = |axis: usize| pts[0][axis].clamp(0.0, u32::MAX as f64) as u64;
    (coord(K::N - 1) << 32) | coord(K::N - 2)
}

/// Whether the first `NV` corners are bit-for-bit equal.
#[inline]
fn same_corners<K: Dim>(a: &[K::Point; 4], b: &[K::Point; 4]) -> bool {
    a[..K::NV]
        .iter()
        .zip(&b[..K::NV])
        .all(|(p, q)| (0..K::N).all(|i| p[i].to_bits() == q[i].to_bits()))
}

/// The statistics of the pixels whose centre lies in the cell with the given
/// corners: row spans summed as contiguous slices, in increasing pixel order
/// (so the sums are bit-identical to a pixel-by-pixel loop).
#[inline]
pub fn cell_stats<K: Raster>(image: &ImageView<'_>, corners: &[K::Point]) -> CellStats {
    let (mut sum, mut sum_sq, mut count) = (0.0f64, 0.0f64, 0usize);
    K::cell_spans(image, corners, &mut |a, b| {
        (sum, sum_sq) = accumulate((sum, sum_sq), &image.data[a..b]);
        count += b - a;
    });
    CellStats {
        sum,
        sum_sq,
        count: count as u32,
    }
}

/// Adds `values`, in order, to a running sum and sum of squares. The sums
/// are passed by value: kept in registers for the loop (a closure holding
/// them by reference stored and reloaded them on every pixel).
#[inline(always)]
fn accumulate((mut sum, mut sum_sq): (f64, f64), values: &[f32]) -> (f64, f64) {
    for &v in values {
        let v = v as f64;
        sum += v;
        sum_sq += v * v;
    }
    (sum, sum_sq)
}

/// Pixels of one cell [`cell_stats_pair`] gathers; larger cells are summed in place.
pub const GATHER: usize = 256;

/// Scratch space of [`cell_stats_pair`]: room for two cells' pixels.
#[derive(Clone, Debug)]
pub struct PairScratch(Vec<f32>);

impl Default for PairScratch {
    fn default() -> Self {
        PairScratch(vec![0.0; 2 * GATHER])
    }
}

/// The statistics of two cells, each bit for bit what [`cell_stats`] gives.
///
/// A cell's sums are chains of dependent additions (their order fixes the
/// bits), so summing one cell waits on the adder's latency at every pixel.
/// Here each cell's pixels are first copied, in order, into a buffer, and
/// the two buffers are summed in one loop: two independent chains keep the
/// adder busy. A cell with more than [`GATHER`] pixels is summed in place.
pub fn cell_stats_pair<K: Raster>(
    image: &ImageView<'_>,
    a: &[K::Point],
    b: &[K::Point],
    scratch: &mut PairScratch,
) -> [CellStats; 2] {
    let (buf_a, buf_b) = scratch.0.split_at_mut(GATHER);
    let (Some(na), Some(nb)) = (gather::<K>(image, a, buf_a), gather::<K>(image, b, buf_b)) else {
        return [cell_stats::<K>(image, a), cell_stats::<K>(image, b)];
    };
    let (pa, pb) = (&buf_a[..na], &buf_b[..nb]);
    let n = na.min(nb);
    let (mut sa, mut qa, mut sb, mut qb) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (&x, &y) in pa[..n].iter().zip(&pb[..n]) {
        let (x, y) = (x as f64, y as f64);
        sa += x;
        qa += x * x;
        sb += y;
        qb += y * y;
    }
    let (sa, qa) = accumulate((sa, qa), &pa[n..]);
    let (sb, qb) = accumulate((sb, qb), &pb[n..]);
    [(sa, qa, na), (sb, qb, nb)].map(|(sum, sum_sq, count)| CellStats {
        sum,
        sum_sq,
        count: count as u32,
    })
}

/// Fills `out` (one or two entries) with the statistics of the cells with
/// the given corners (`None`: leave the entry as it is).
fn fill_pair<K: Raster>(
    image: &ImageView<'_>,
    out: &mut [CellStats],
    corners: [Option<[K::Point; 4]>; 2],
    scratch: &mut PairScratch,
) {
    match corners {
        [Some(a), Some(b)] => {
            let [sa, sb] = cell_stats_pair::<K>(image, &a[..K::NV], &b[..K::NV], scratch);
            out[0] = sa;
            out[1] = sb;
        }
        [a, b] => {
            for (o, c) in out.iter_mut().zip([a, b]) {
                if let Some(c) = c {
                    *o = cell_stats::<K>(image, &c[..K::NV]);
                }
            }
        }
    }
}

/// Copies the cell's pixels, in index order, to the front of `buf`;
/// `None` if they do not fit.
fn gather<K: Raster>(
    image: &ImageView<'_>,
    corners: &[K::Point],
    buf: &mut [f32],
) -> Option<usize> {
    let mut n = 0;
    let mut fits = true;
    K::cell_spans(image, corners, &mut |start, end| {
        let len = end - start;
        if fits && n + len <= buf.len() {
            buf[n..n + len].copy_from_slice(&image.data[start..end]);
            n += len;
        } else {
            fits = false;
        }
    });
    fits.then_some(n)
}

/// Per-phase totals and means.
#[derive(Clone, Debug, Default, Serialize)]
pub struct PhaseStats {
    /// Pixel count of each phase.
    pub count: Vec<u64>,
    /// Intensity sum of each phase.
    pub sum: Vec<f64>,
    /// Current mean of each phase. A phase without pixels keeps its previous
    /// mean (or `None` if it never had one), so it can be revived by flips.
    pub mean: Vec<Option<f64>>,
}

impl PhaseStats {
    /// Empty statistics for `phases` phases.
    pub fn new(phases: usize) -> Self {
        PhaseStats {
            count: vec![0; phases],
            sum: vec![0.0; phases],
            mean: vec![None; phases],
        }
    }

    /// Recomputes counts, sums and means from per-cell statistics and the
    /// current labels. Phases left without pixels keep their previous mean.
    pub fn update<K: Raster>(&mut self, complex: &Complex<K>, cells: &[CellStats]) {
        self.count.iter_mut().for_each(|c| *c = 0);
        self.sum.iter_mut().for_each(|s| *s = 0.0);
        for c in complex.cell_ids() {
            let l = complex.label(c) as usize;
            if l < self.count.len() {
                self.count[l] += cells[c.index()].count as u64;
                self.sum[l] += cells[c.index()].sum;
            }
        }
        for k in 0..self.count.len() {
            if self.count[k] > 0 {
                self.mean[k] = Some(self.sum[k] / self.count[k] as f64);
            }
        }
    }

    /// Mean of phase `l` (`None` if it never had pixels).
    pub fn mean_of(&self, l: Label) -> Option<f64> {
        self.mean.get(l as usize).copied().flatten()
    }

    /// Number of phases that currently cover at least one pixel.
    pub fn present(&self) -> usize {
        self.count.iter().filter(|&&c| c > 0).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::D2;
    use crate::dsc::{Destinations, DscParams};
    use nalgebra::Vector2;

    /// A `w`×`h` image of scrambled values in `[0, 1)`.
    fn scrambled(w: usize, h: usize, step: usize, modulus: usize) -> Vec<f32> {
        (0..w * h)
            .map(|i| ((i * step % modulus) as f32) / modulus as f32)
            .collect()
    }

    /// Two cells summed together give, bit for bit, what each gives alone:
    /// cells of unequal sizes, empty ones, and ones too large to gather.
    #[test]
    fn pairs_sum_like_single_cells() {
        let (w, h) = (90usize, 70usize);
        let data = scrambled(w, h, 7919, 1013);
        let image = ImageView::new_2d(w, h, &data).unwrap();
        let mut scratch = PairScratch::default();
        let mut state = 0x2545f4914f6cdd1du64;
        let mut rnd = |scale: f64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * scale
        };
        let mut gathered_too_large = false;
        for _ in 0..5000 {
            let size = if rnd(1.0) < 0.1 { 60.0 } else { 8.0 };
            let mut tri = || -> Vec<Vector2<f64>> {
                let (x, y) = (rnd(w as f64), rnd(h as f64));
                (0..3)
                    .map(|_| Vector2::new(x + rnd(size), y + rnd(size)))
                    .collect()
            };
            let (a, b) = (tri(), tri());
            let pair = cell_stats_pair::<D2>(&image, &a, &b, &mut scratch);
            let single = [cell_stats::<D2>(&image, &a), cell_stats::<D2>(&image, &b)];
            assert_eq!(pair, single, "{a:?} {b:?}");
            gathered_too_large |= single.iter().any(|s| s.count as usize > GATHER);
        }
        assert!(gathered_too_large);
    }

    /// A complex large enough for the parallel scan and integration.
    #[test]
    fn large_batches_give_the_same_statistics_in_parallel() {
        let (w, h) = (400usize, 300usize);
        let data = scrambled(w, h, 31, 997);
        let image = ImageView::new_2d(w, h, &data).unwrap();
        let mesh = Complex::<D2>::rectangle(w as f64, h as f64, 1.5).unwrap();
        assert!(mesh.cell_count() >= 8 * PARALLEL_BATCH);
        let (mut cached, mut full) = (Vec::new(), Vec::new());
        let n = CellCache::<D2>::new().integrate(&mesh, &image, &mut cached);
        integrate_cells(&mesh, &image, &mut full);
        assert_eq!(n, mesh.cell_count());
        assert_eq!(cached, full);
    }

    #[test]
    fn cached_integration_equals_full_integration() {
        let (w, h) = (96usize, 80usize);
        let data = scrambled(w, h, 7919, 1013);
        let image = ImageView::new_2d(w, h, &data).unwrap();
        let l = 6.0;
        let mut mesh = Complex::<D2>::rectangle(w as f64, h as f64, l).unwrap();
        let params = DscParams::new::<D2>(l);
        let mut cache = CellCache::<D2>::new();
        let mut cached = Vec::new();
        let mut full = Vec::new();
        let first = cache.integrate(&mesh, &image, &mut cached);
        integrate_cells(&mesh, &image, &mut full);
        assert_eq!(cached, full);
        assert_eq!(first, mesh.cell_count());
        assert_eq!(cache.integrate(&mesh, &image, &mut cached), 0);
        for round in 0..4 {
            let mut dest = Destinations::new(&mesh);
            let centre = Vector2::new(w as f64 / 2.0, h as f64 / 2.0);
            for v in mesh.vertex_ids().collect::<Vec<_>>() {
                let p = mesh.position(v);
                let d = p - centre;
                if d.norm() < 20.0 + 5.0 * round as f64 {
                    dest.set(v, mesh.constrain(v, p + d * 0.15));
                }
            }
            mesh.deform(&dest, &params);
            let n = cache.integrate(&mesh, &image, &mut cached);
            integrate_cells(&mesh, &image, &mut full);
            assert_eq!(cached, full, "round {round}");
            assert!(n > 0 && n < mesh.cell_count(), "round {round}: {n}");
        }
    }
}
