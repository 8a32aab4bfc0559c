//! Integration of the image over the cells: per-cell sums, per-phase means.

use super::image::ImageView;
use super::raster::Raster;
use crate::complex::{CellId, Complex, Label};
use crate::dim::Dim;
use rayon::prelude::*;
use serde::Serialize;
use spin_join::SpinHelper;

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
        let c = CellId::new(i as u32);
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
pub(crate) struct CellCache<K: Dim> {
    /// Corners at the last integration, per cell id.
    corners: Vec<CachedCorners<K>>,
    /// The previous call's corners and statistics, read while the current
    /// ones are written (double buffering: one pass both carries the cache
    /// across a compaction and finds the changed cells).
    old_corners: Vec<CachedCorners<K>>,
    old_stats: Vec<CellStats>,
    /// Scratch: for each cell id, its id at the previous call.
    previous_id: Vec<u32>,
    /// The image the cache was filled from (address and length).
    image: (usize, usize),
    /// [`Complex::compactions`] at the last call.
    generation: u64,
    /// Scratch of the two halves of a call (see [`SpinHelper`]).
    halves: [Refresh; 2],
}

/// Scratch of one range of cells: the changed ones with their rows
/// ([`first_corner_row`]), their statistics, a pair buffer, and the
/// buffers of [`order_by_row`].
#[derive(Clone, Debug, Default)]
struct Refresh {
    changed: Vec<(u32, CellId)>,
    fresh: Vec<CellStats>,
    scratch: PairScratch,
    by_row: RowOrder,
}

/// Marks a cell id without an entry at the previous call.
const NO_ENTRY: u32 = u32::MAX;

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
            old_corners: Vec::new(),
            old_stats: Vec::new(),
            previous_id: Vec::new(),
            image: (0, 0),
            generation: 0,
            halves: Default::default(),
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
        self.integrate_on(&SpinHelper::none(), complex, image, out)
    }

    /// [`integrate`](Self::integrate), sharing the work with `helper`'s
    /// thread (the same statistics, bit for bit).
    pub fn integrate_on(
        &mut self,
        helper: &SpinHelper,
        complex: &Complex<K>,
        image: &ImageView<'_>,
        out: &mut Vec<CellStats>,
    ) -> usize {
        // A spatial renumbering permutes the ids: the entries cannot follow
        // it by forward moves in place.
        if helper.is_threaded()
            || complex.cell_capacity() >= 8 * PARALLEL_BATCH
            || complex.last_compaction_reordered()
        {
            self.integrate_double_buffered(helper, complex, image, out)
        } else {
            self.integrate_in_place(complex, image, out)
        }
    }

    /// On one thread: the entries are carried across a compaction in place
    /// (forward moves), then checked and refreshed in place.
    fn integrate_in_place(
        &mut self,
        complex: &Complex<K>,
        image: &ImageView<'_>,
        out: &mut Vec<CellStats>,
    ) -> usize {
        let key = (image.data.as_ptr() as usize, image.data.len());
        let generation = complex.compactions();
        if !self.continues(key, generation, out) {
            self.corners.clear();
            out.clear();
            self.image = key;
        } else if generation == self.generation + 1 {
            let mut kept = 0;
            let map = complex.last_cell_map();
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
        let cap = complex.cell_capacity();
        out.resize(cap, CellStats::default());
        self.corners.resize(cap, None);
        let r = &mut self.halves[0];
        r.changed.clear();
        for (i, (k, s)) in self.corners.iter_mut().zip(out.iter_mut()).enumerate() {
            let c = CellId::new(i as u32);
            if !complex.is_alive(c) {
                (*k, *s) = (None, CellStats::default());
                continue;
            }
            let pts = complex.cell_points(c);
            if k.is_some_and(|before| same_corners::<K>(&before, &pts)) {
                continue;
            }
            *k = Some(pts);
            r.changed.push((first_corner_row::<K>(&pts), c));
        }
        r.by_row.order(&mut r.changed);
        r.integrate::<K>(image, &self.corners, 0);
        r.store(out, 0)
    }

    /// Whether the entries of the last call can be carried to this one:
    /// the same image, `out` the vector that call filled, and at most one
    /// compaction of the complex since.
    fn continues(&self, key: (usize, usize), generation: u64, out: &[CellStats]) -> bool {
        key == self.image
            && out.len() == self.corners.len()
            && generation >= self.generation
            && generation <= self.generation + 1
    }

    /// With the helper (or rayon's threads, for a large complex): the last
    /// call's entries are read from one pair of buffers while this call's
    /// are written to the other, so that one pass carries them across a
    /// compaction and finds the changed cells, in two halves.
    fn integrate_double_buffered(
        &mut self,
        helper: &SpinHelper,
        complex: &Complex<K>,
        image: &ImageView<'_>,
        out: &mut Vec<CellStats>,
    ) -> usize {
        let key = (image.data.as_ptr() as usize, image.data.len());
        let continues = self.continues(key, complex.compactions(), out);
        std::mem::swap(&mut self.corners, &mut self.old_corners);
        std::mem::swap(out, &mut self.old_stats);
        self.map_previous_ids(complex, key, continues);
        let cap = complex.cell_capacity();
        // Every entry is written by the scan below: no need to clear.
        out.resize(cap, CellStats::default());
        self.corners.resize(cap, None);
        let old = Previous::<K> {
            corners: &self.old_corners,
            stats: &self.old_stats,
            id: &self.previous_id,
        };
        if cap >= 8 * PARALLEL_BATCH {
            // Large (3D, first integrations of large images): rayon's
            // threads, block by block.
            let blocks = out.par_chunks_mut(PARALLEL_BATCH);
            let corners = self.corners.par_chunks_mut(PARALLEL_BATCH);
            return blocks
                .zip(corners)
                .enumerate()
                .map_init(Refresh::default, |r, (b, (stats, corners))| {
                    let first = b * PARALLEL_BATCH;
                    r.scan(complex, &old, first, corners, stats);
                    r.integrate::<K>(image, corners, first);
                    r.store(stats, first)
                })
                .sum();
        }
        // Two threads: each scans half of the ids, then each integrates half
        // of all the changed cells (they gather unevenly: new cells have
        // high ids).
        let mid = cap / 2;
        let (stats_lo, stats_hi) = out.split_at_mut(mid);
        let (corners_lo, corners_hi) = self.corners.split_at_mut(mid);
        let [lo, hi] = &mut self.halves;
        helper.join(
            || lo.scan(complex, &old, 0, corners_lo, stats_lo),
            || hi.scan(complex, &old, mid, corners_hi, stats_hi),
        );
        lo.changed.append(&mut hi.changed);
        let split = lo.changed.len() / 4 * 2;
        hi.changed.extend_from_slice(&lo.changed[split..]);
        lo.changed.truncate(split);
        let corners = &self.corners;
        helper.join(
            || lo.integrate::<K>(image, corners, 0),
            || hi.integrate::<K>(image, corners, 0),
        );
        lo.store(out, 0) + hi.store(out, 0)
    }

    /// Fills `previous_id`: each current cell id's id at the last call
    /// (through the compaction since, if any), or [`NO_ENTRY`] for every
    /// cell unless the last call `continues` here.
    fn map_previous_ids(&mut self, complex: &Complex<K>, key: (usize, usize), continues: bool) {
        let generation = complex.compactions();
        let known = self.old_corners.len();
        self.previous_id.clear();
        self.previous_id.resize(complex.cell_capacity(), NO_ENTRY);
        if !continues {
            self.image = key;
        } else if generation == self.generation + 1 {
            for (old, new) in complex.last_cell_map().iter().enumerate().take(known) {
                if let Some(new) = new {
                    self.previous_id[new.index()] = old as u32;
                }
            }
        } else {
            let n = known.min(self.previous_id.len());
            for (i, p) in self.previous_id[..n].iter_mut().enumerate() {
                *p = i as u32;
            }
        }
        self.generation = generation;
    }
}

/// The cache's entries at the previous call, and where each cell was then.
struct Previous<'a, K: Dim> {
    corners: &'a [CachedCorners<K>],
    stats: &'a [CellStats],
    id: &'a [u32],
}

impl Refresh {
    /// Carries the previous statistics of the cells `first..first +
    /// stats.len()` whose corners did not change and lists the others,
    /// by row ([`RowOrder`]; any order gives the same sums; rows make
    /// neighbouring cells share the rows they read).
    fn scan<K: Raster>(
        &mut self,
        complex: &Complex<K>,
        old: &Previous<'_, K>,
        first: usize,
        corners: &mut [CachedCorners<K>],
        stats: &mut [CellStats],
    ) {
        self.changed.clear();
        for (j, (k, s)) in corners.iter_mut().zip(stats.iter_mut()).enumerate() {
            let c = CellId::new((first + j) as u32);
            if !complex.is_alive(c) {
                (*k, *s) = (None, CellStats::default());
                continue;
            }
            let pts = complex.cell_points(c);
            *k = Some(pts);
            let was = old.id[c.index()] as usize;
            match old.corners.get(was) {
                Some(Some(before)) if same_corners::<K>(before, &pts) => *s = old.stats[was],
                // (integrated later)
                _ => self.changed.push((first_corner_row::<K>(&pts), c)),
            }
        }
        self.by_row.order(&mut self.changed);
    }

    /// Integrates the listed cells; `corners` holds the entry of cell
    /// `first + i` at `i`.
    fn integrate<K: Raster>(
        &mut self,
        image: &ImageView<'_>,
        corners: &[CachedCorners<K>],
        first: usize,
    ) {
        self.fresh.clear();
        self.fresh.resize(self.changed.len(), CellStats::default());
        for (out, ids) in self.fresh.chunks_mut(2).zip(self.changed.chunks(2)) {
            let pair = [0, 1].map(|j| ids.get(j).and_then(|&(_, c)| corners[c.index() - first]));
            fill_pair::<K>(image, out, pair, &mut self.scratch);
        }
    }

    /// Stores the integrated statistics (cell `first + i` at `i`); returns
    /// how many.
    fn store(&self, stats: &mut [CellStats], first: usize) -> usize {
        for (&(_, c), &st) in self.changed.iter().zip(&self.fresh) {
            stats[c.index() - first] = st;
        }
        self.changed.len()
    }
}

/// Cells per block of rayon's share of a large integration.
const PARALLEL_BATCH: usize = 8192;

/// The pixel row (2D; the slice in 3D) of a cell's first corner: cells
/// integrated in this order read the image nearly in memory order. Any
/// order gives the same statistics (each cell's pixels are summed on their
/// own).
#[inline]
fn first_corner_row<K: Dim>(pts: &[K::Point; 4]) -> u32 {
    pts[0][K::N - 1].clamp(0.0, u32::MAX as f64) as u32
}

/// Buffers of a counting sort of cells by row.
#[derive(Clone, Debug, Default)]
struct RowOrder {
    /// Per row: the place of its first cell in the order.
    starts: Vec<u32>,
    /// The cells in order.
    sorted: Vec<(u32, CellId)>,
}

impl RowOrder {
    /// Orders `cells` by row, keeping their order within a row: linear in
    /// the cells and the rows (a comparison sort of row and column took
    /// 4.0 M instructions over a 256² two-phase run's integrations, most
    /// of them in the first, of every cell; this order 0.9 M).
    fn order(&mut self, cells: &mut Vec<(u32, CellId)>) {
        let Some(last_row) = cells.iter().map(|&(row, _)| row).max() else {
            return;
        };
        self.starts.clear();
        self.starts.resize(last_row as usize + 2, 0);
        for &(row, _) in cells.iter() {
            self.starts[row as usize + 1] += 1;
        }
        for r in 1..self.starts.len() {
            self.starts[r] += self.starts[r - 1];
        }
        self.sorted.clear();
        self.sorted.resize(cells.len(), (0, CellId::new(0)));
        for &(row, c) in cells.iter() {
            let place = &mut self.starts[row as usize];
            self.sorted[*place as usize] = (row, c);
            *place += 1;
        }
        std::mem::swap(cells, &mut self.sorted);
    }
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

/// Scratch space of [`cell_stats_pair`]: the two cells' row spans.
#[derive(Clone, Debug, Default)]
pub(crate) struct PairScratch(Vec<(usize, usize)>, Vec<(usize, usize)>);

/// The statistics of two cells, each bit for bit what [`cell_stats`] gives.
///
/// A cell's sums are chains of dependent additions (their order fixes the
/// bits), so summing one cell waits on the adder's latency at every pixel.
/// Here the two cells' rows are summed side by side, row `k` of one with
/// row `k` of the other: two independent chains keep the adder busy, each
/// cell's pixels still in its own order.
pub(crate) fn cell_stats_pair<K: Raster>(
    image: &ImageView<'_>,
    a: &[K::Point],
    b: &[K::Point],
    scratch: &mut PairScratch,
) -> [CellStats; 2] {
    let PairScratch(rows_a, rows_b) = scratch;
    for (rows, corners) in [(&mut *rows_a, a), (&mut *rows_b, b)] {
        rows.clear();
        K::cell_spans(image, corners, &mut |start, end| rows.push((start, end)));
    }
    let data = image.data;
    let (mut sa, mut qa, mut sb, mut qb) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    // Row k of each cell side by side (each cell's pixels still in order:
    // its row k's tail is summed before its row k + 1).
    for (&(a0, a1), &(b0, b1)) in rows_a.iter().zip(rows_b.iter()) {
        let (ra, rb) = (&data[a0..a1], &data[b0..b1]);
        let n = ra.len().min(rb.len());
        for (&x, &y) in ra[..n].iter().zip(&rb[..n]) {
            let (x, y) = (x as f64, y as f64);
            sa += x;
            qa += x * x;
            sb += y;
            qb += y * y;
        }
        (sa, qa) = accumulate((sa, qa), &ra[n..]);
        (sb, qb) = accumulate((sb, qb), &rb[n..]);
    }
    let k = rows_a.len().min(rows_b.len());
    for &(s, e) in &rows_a[k..] {
        (sa, qa) = accumulate((sa, qa), &data[s..e]);
    }
    for &(s, e) in &rows_b[k..] {
        (sb, qb) = accumulate((sb, qb), &data[s..e]);
    }
    let count = |rows: &[(usize, usize)]| rows.iter().map(|&(s, e)| e - s).sum::<usize>() as u32;
    [
        CellStats {
            sum: sa,
            sum_sq: qa,
            count: count(rows_a),
        },
        CellStats {
            sum: sb,
            sum_sq: qb,
            count: count(rows_b),
        },
    ]
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
        assert!(
            cells.len() >= complex.cell_capacity(),
            "a statistic per cell id"
        );
        // (slices of one length: the loop indexes them without checks)
        let phases = self.count.len();
        let (count, sum) = (&mut self.count[..phases], &mut self.sum[..phases]);
        for (label, st) in complex.label_slots().zip(cells) {
            let Some(l) = label.map(|l| l as usize).filter(|&l| l < phases) else {
                continue;
            };
            count[l] += st.count as u64;
            sum[l] += st.sum;
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
    /// cells of unequal sizes and row counts, empty ones, and large ones.
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
        let mut saw_large = false;
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
            saw_large |= single.iter().any(|s| s.count > 256);
        }
        assert!(saw_large);
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
        // Both ways: on one thread, and shared with a helper thread.
        // Three ways: on one thread (entries kept in place), shared with a
        // helper thread (double-buffered), and switching between the two.
        let mut caches = [(); 3].map(|_| CellCache::<D2>::new());
        let helpers = [SpinHelper::none(), SpinHelper::with_thread().unwrap()];
        let mut calls = 0;
        let mut integrate = |mesh: &Complex<D2>, cached: &mut [Vec<CellStats>; 3]| {
            let [a, b, c] = cached;
            let n = caches[0].integrate_on(&helpers[0], mesh, &image, a);
            assert_eq!(caches[1].integrate_on(&helpers[1], mesh, &image, b), n);
            assert_eq!(
                caches[2].integrate_on(&helpers[calls % 2], mesh, &image, c),
                n
            );
            calls += 1;
            assert_eq!(a, b);
            assert_eq!(a, c);
            n
        };
        let mut cached = [Vec::new(), Vec::new(), Vec::new()];
        let mut full = Vec::new();
        let first = integrate(&mesh, &mut cached);
        integrate_cells(&mesh, &image, &mut full);
        assert_eq!(cached[0], full);
        assert_eq!(first, mesh.cell_count());
        assert_eq!(integrate(&mesh, &mut cached), 0);
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
            let n = integrate(&mesh, &mut cached);
            integrate_cells(&mesh, &image, &mut full);
            assert_eq!(cached[0], full, "round {round}");
            assert!(n > 0 && n < mesh.cell_count(), "round {round}: {n}");
        }
    }

    /// In 3D the compactions sometimes renumber spatially (a permutation,
    /// not an order-keeping map): the cache on one thread and the one
    /// shared with a helper still give the full integration's statistics.
    #[test]
    fn cached_integration_follows_spatial_renumbering() {
        use crate::dim::D3;
        use nalgebra::Vector3;
        let dims = [30usize, 27, 24];
        let data = scrambled(dims[0] * dims[1], dims[2], 7919, 1013);
        let image = ImageView::new_3d(dims, &data).unwrap();
        let l = 3.0;
        let size = dims.map(|d| d as f64);
        let mut mesh = Complex::<D3>::cuboid(size, l).unwrap();
        let params = DscParams::new::<D3>(l);
        let mut caches = [(); 2].map(|_| CellCache::<D3>::new());
        let helpers = [SpinHelper::none(), SpinHelper::with_thread().unwrap()];
        let mut cached = [Vec::new(), Vec::new()];
        let mut full = Vec::new();
        let mut reordered = [0, 0];
        let centre = Vector3::new(15.0, 13.5, 12.0);
        for round in 0..10 {
            if round > 0 {
                let mut dest = Destinations::new(&mesh);
                for v in mesh.vertex_ids().collect::<Vec<_>>() {
                    let p = mesh.position(v);
                    let d = p - centre;
                    if d.norm() < 4.0 + 1.5 * round as f64 {
                        dest.set(v, mesh.constrain(v, p + d * 0.3));
                    }
                }
                mesh.deform(&dest, &params);
                reordered[usize::from(mesh.last_compaction_reordered())] += 1;
            }
            for (cache, (helper, out)) in caches.iter_mut().zip(helpers.iter().zip(&mut cached)) {
                cache.integrate_on(helper, &mesh, &image, out);
            }
            integrate_cells(&mesh, &image, &mut full);
            assert_eq!(cached[0], full, "round {round}");
            assert_eq!(cached[1], full, "round {round}");
        }
        assert!(
            reordered[0] > 0 && reordered[1] > 0,
            "compactions kept the order / renumbered: {reordered:?}"
        );
    }
}
