//! The sizing field `h(x)`: the target edge length at each point of the domain.
//!
//! Resizing (split long, collapse short), the degenerate-cell thresholds and
//! the border snap read `h` at the cell, edge or vertex they judge, in place
//! of the one average edge length `L` of [`DscParams`](super::DscParams). The
//! uniform field (the default) answers `L` everywhere, so that every
//! threshold is computed exactly as with `L` alone: the paper's uniform mesh.
//!
//! A graded field is stored on a regular grid over the domain (piecewise
//! constant per grid cell), built by lowering a constant maximum towards
//! finer targets where the caller wants detail, then limited in gradation:
//! `h(a) ≤ h(b) + g·d(a, b)` between grid neighbours at distance `d`, so that
//! neighbouring mesh cells of size about `h` differ by at most a factor of
//! about `1 + g`, which keeps cells well shaped where the resolution changes.

use crate::dim::Point;

/// The target edge length over the domain: uniform (the average edge length
/// `L` of the parameters) or graded on a grid.
#[derive(Debug, Default, PartialEq)]
pub struct SizingField {
    grid: Option<SizeGrid>,
}

/// `clone_from` copies into the samples' buffer when both fields have one
/// (the derived `Clone` would allocate a new one).
impl Clone for SizingField {
    fn clone(&self) -> Self {
        SizingField {
            grid: self.grid.clone(),
        }
    }

    fn clone_from(&mut self, source: &Self) {
        self.grid.clone_from(&source.grid);
    }
}

/// Samples of a graded field: one value per grid cell of side `spacing`,
/// x fastest, then y, then z (one layer in 2D).
#[derive(Debug, PartialEq)]
struct SizeGrid {
    origin: [f64; 3],
    spacing: f64,
    dims: [usize; 3],
    values: Vec<f64>,
}

impl Clone for SizeGrid {
    fn clone(&self) -> Self {
        SizeGrid {
            values: self.values.clone(),
            ..*self
        }
    }

    fn clone_from(&mut self, source: &Self) {
        self.origin = source.origin;
        self.spacing = source.spacing;
        self.dims = source.dims;
        self.values.clone_from(&source.values);
    }
}

impl SizingField {
    /// The uniform field: `h(x) = L` everywhere.
    pub fn uniform() -> Self {
        SizingField { grid: None }
    }

    /// A graded field over the box `[lo, hi]` (the first `n` coordinates,
    /// `n` = 2 or 3) at grid spacing `spacing`, equal to `h_max` everywhere
    /// until lowered by [`lower`](Self::lower).
    ///
    /// # Panics
    /// If `spacing` or `h_max` is not a positive finite number, `n` is not 2
    /// or 3, or the box is empty.
    pub fn constant(lo: &[f64], hi: &[f64], n: usize, spacing: f64, h_max: f64) -> Self {
        assert!(n == 2 || n == 3, "a sizing field is 2D or 3D");
        assert!(spacing.is_finite() && spacing > 0.0, "bad grid spacing");
        assert!(h_max.is_finite() && h_max > 0.0, "bad maximum size");
        let mut origin = [0.0; 3];
        let mut dims = [1; 3];
        for a in 0..n {
            assert!(hi[a] > lo[a], "empty box");
            origin[a] = lo[a];
            dims[a] = ((hi[a] - lo[a]) / spacing).ceil().max(1.0) as usize;
        }
        let count = dims.iter().product();
        SizingField {
            grid: Some(SizeGrid {
                origin,
                spacing,
                dims,
                values: vec![h_max; count],
            }),
        }
    }

    /// Whether this is the uniform field.
    pub fn is_uniform(&self) -> bool {
        self.grid.is_none()
    }

    /// `h` at point `p`; `uniform` (the parameters' `L`) for the uniform field.
    #[inline]
    pub fn at<P: Point>(&self, p: &P, uniform: f64) -> f64 {
        match &self.grid {
            None => uniform,
            Some(g) => g.values[g.index_of(p)],
        }
    }

    /// `h` at the midpoint of `a` and `b`.
    #[inline]
    pub fn at_edge<P: Point>(&self, a: P, b: P, uniform: f64) -> f64 {
        if self.grid.is_none() {
            return uniform;
        }
        self.at(&((a + b) * 0.5), uniform)
    }

    /// `h` at the centroid of the corners `pts`.
    #[inline]
    pub fn at_cell<P: Point>(&self, pts: &[P], uniform: f64) -> f64 {
        if self.grid.is_none() {
            return uniform;
        }
        let mut c = P::zero();
        for &p in pts {
            c += p;
        }
        self.at(&(c * (1.0 / pts.len() as f64)), uniform)
    }

    /// Lowers `h` to at most `h` in the grid cell holding `p` (no effect on
    /// the uniform field).
    pub fn lower<P: Point>(&mut self, p: &P, h: f64) {
        if let Some(g) = &mut self.grid {
            let i = g.index_of(p);
            if h < g.values[i] {
                g.values[i] = h;
            }
        }
    }

    /// Sets every sample to `h` (no effect on the uniform field).
    pub fn fill(&mut self, h: f64) {
        if let Some(g) = &mut self.grid {
            g.values.fill(h);
        }
    }

    /// Lowers every sample to at most the matching sample of `other` (a
    /// field on the same grid; otherwise nothing happens).
    pub fn lower_to(&mut self, other: &SizingField) {
        if let (Some(g), Some(o)) = (&mut self.grid, &other.grid) {
            if g.dims == o.dims && g.spacing == o.spacing && g.origin == o.origin {
                for (v, &w) in g.values.iter_mut().zip(&o.values) {
                    *v = v.min(w);
                }
            }
        }
    }

    /// Limits the gradation: afterwards `h(a) ≤ h(b) + rate·d(a, b)` for
    /// every two grid neighbours (axis, face- and body-diagonal) at distance
    /// `d`, by lowering values only (a chamfer distance transform: one
    /// forward and one backward sweep).
    pub fn limit_gradation(&mut self, rate: f64) {
        self.limit_gradation_with(rate, &mut Vec::new());
    }

    /// [`limit_gradation`](Self::limit_gradation) sweeping in `scratch`
    /// (kept by a caller that limits a field of this size again and again,
    /// so that no grid-sized buffer is allocated each time).
    pub fn limit_gradation_with(&mut self, rate: f64, scratch: &mut Vec<f64>) {
        if let Some(g) = &mut self.grid {
            g.limit_gradation(rate, scratch);
        }
    }

    /// The largest `h(a) − h(b) − rate·d(a, b)` over grid neighbours: at
    /// most rounding error once [`limit_gradation`](Self::limit_gradation)
    /// ran with `rate`. 0 for the uniform field.
    pub fn gradation_excess(&self, rate: f64) -> f64 {
        let Some(g) = &self.grid else { return 0.0 };
        let mut worst = f64::NEG_INFINITY;
        g.for_each_neighbour_pair(|i, j, d| {
            let excess = g.values[i] - g.values[j] - rate * d;
            worst = worst.max(excess).max(g.values[j] - g.values[i] - rate * d);
        });
        worst.max(0.0)
    }

    /// Smallest and largest sample (`None` for the uniform field).
    pub fn range(&self) -> Option<(f64, f64)> {
        self.grid.as_ref().map(|g| {
            g.values
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                    (lo.min(v), hi.max(v))
                })
        })
    }
}

/// Lowers each sample of the row of `padded` starting at `start` (copied
/// into `row`) to its neighbour at each of `across` (index offset times
/// `sign`, in another row) plus that neighbour's step.
fn sweep_row(padded: &[f64], row: &mut [f64], start: usize, across: &[(isize, f64)], sign: isize) {
    let n = row.len();
    row.copy_from_slice(&padded[start..start + n]);
    for &(delta, step) in across {
        let from = start.wrapping_add_signed(sign * delta);
        for (v, &w) in row.iter_mut().zip(&padded[from..from + n]) {
            *v = v.min(w + step);
        }
    }
}

/// The neighbour offsets of a forward sweep (those earlier in x-fastest
/// order): 4 in 2D (of the 8-neighbourhood), 13 in 3D (of the 26).
fn forward_offsets(three_d: bool) -> Vec<[isize; 3]> {
    let mut out = Vec::new();
    let zs: &[isize] = if three_d { &[-1, 0, 1] } else { &[0] };
    for &dz in zs {
        for dy in -1..=1isize {
            for dx in -1..=1isize {
                let key = (dz, dy, dx);
                if key < (0, 0, 0) {
                    out.push([dx, dy, dz]);
                }
            }
        }
    }
    out
}

impl SizeGrid {
    #[inline]
    fn index_of<P: Point>(&self, p: &P) -> usize {
        let mut index = 0;
        let mut stride = 1;
        for a in 0..3 {
            if self.dims[a] > 1 {
                let t = (p[a] - self.origin[a]) / self.spacing;
                // The cast truncates, which is the floor of a non-negative
                // `t` (without the call to `floor` the baseline x86-64
                // target makes); NaN and out-of-range clamp into the grid.
                let k = if t >= 0.0 { t as usize } else { 0 };
                index += k.min(self.dims[a] - 1) * stride;
            }
            stride *= self.dims[a];
        }
        index
    }

    fn three_d(&self) -> bool {
        self.dims[2] > 1
    }

    /// Calls `f(i, j, d)` for every pair of neighbouring samples `j` before
    /// `i` (each pair once), `d` their distance.
    fn for_each_neighbour_pair(&self, mut f: impl FnMut(usize, usize, f64)) {
        let offsets = forward_offsets(self.three_d());
        let [nx, ny, nz] = self.dims;
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let i = x + nx * (y + ny * z);
                    for o in &offsets {
                        if let Some(j) = self.offset(x, y, z, *o) {
                            f(i, j, self.offset_length(o));
                        }
                    }
                }
            }
        }
    }

    fn offset(&self, x: usize, y: usize, z: usize, o: [isize; 3]) -> Option<usize> {
        let [nx, ny, nz] = self.dims;
        let xs = x.checked_add_signed(o[0]).filter(|&v| v < nx)?;
        let ys = y.checked_add_signed(o[1]).filter(|&v| v < ny)?;
        let zs = z.checked_add_signed(o[2]).filter(|&v| v < nz)?;
        Some(xs + nx * (ys + ny * zs))
    }

    fn offset_length(&self, o: &[isize; 3]) -> f64 {
        let sq: isize = o.iter().map(|&v| v * v).sum();
        self.spacing * (sq as f64).sqrt()
    }

    /// The chamfer sweeps of [`SizingField::limit_gradation`], on a copy
    /// (in `padded`) with one layer of `+∞` on every side of each axis
    /// swept, so that every neighbour is a fixed index offset and no bounds
    /// are checked (a neighbour in the padding lowers nothing: the result is
    /// that of sweeping the grid alone). Each row is swept only over the
    /// samples the gradation can lower ([`SweepSpans`]): the others keep
    /// the field's maximum, which is also what the full sweep leaves there.
    fn limit_gradation(&mut self, rate: f64, padded: &mut Vec<f64>) {
        let offsets = forward_offsets(self.three_d());
        let steps: Vec<f64> = offsets
            .iter()
            .map(|o| rate * self.offset_length(o))
            .collect();
        let [nx, ny, nz] = self.dims;
        // The axes the offsets step along: x and y, and z in 3D.
        let oz = usize::from(self.three_d());
        let (px, py, pz) = (nx + 2, ny + 2, nz + 2 * oz);
        let (ox, oy) = (1, 1);
        padded.clear();
        padded.resize(px * py * pz, f64::INFINITY);
        let at = |x: usize, y: usize, z: usize| (x + ox) + px * ((y + oy) + py * (z + oz));
        for z in 0..nz {
            for y in 0..ny {
                let row = nx * (y + ny * z);
                let start = at(0, y, z);
                padded[start..start + nx].copy_from_slice(&self.values[row..row + nx]);
            }
        }
        // The neighbour one step back along x is the only one in the same
        // row: every other is in a row the sweep finished, so the row takes
        // their minimum element-wise (vectorised), then runs along x. The
        // result is the minimum of the same values as taking the
        // neighbours one sample at a time (min is exact and commutative).
        let mut along = 0.0;
        let mut across: Vec<(isize, f64)> = Vec::new();
        for (o, &s) in offsets.iter().zip(&steps) {
            if o[1] == 0 && o[2] == 0 {
                along = s;
            } else {
                across.push((o[0] + px as isize * (o[1] + py as isize * o[2]), s));
            }
        }
        let smallest_step = steps.iter().copied().fold(f64::INFINITY, f64::min);
        let spans = SweepSpans::of(self, smallest_step);
        // (row start in `padded`, the span's first sample and length)
        let rows: Vec<(usize, usize, usize)> = (0..nz)
            .flat_map(|z| (0..ny).map(move |y| (y, z)))
            .filter_map(|(y, z)| {
                let (lo, hi) = spans.row(y, z)?;
                Some((at(lo, y, z), lo, hi - lo))
            })
            .collect();
        let mut row = vec![0.0; nx];
        // Forward: each sample from its earlier neighbours, rows in order.
        for &(start, _, n) in &rows {
            let row = &mut row[..n];
            sweep_row(padded, row, start, &across, 1);
            let mut last = f64::INFINITY;
            for v in row.iter_mut() {
                *v = v.min(last + along);
                last = *v;
            }
            padded[start..start + n].copy_from_slice(row);
        }
        // Backward: each sample from its later neighbours (mirrored offsets).
        for &(start, _, n) in rows.iter().rev() {
            let row = &mut row[..n];
            sweep_row(padded, row, start, &across, -1);
            let mut last = f64::INFINITY;
            for v in row.iter_mut().rev() {
                *v = v.min(last + along);
                last = *v;
            }
            padded[start..start + n].copy_from_slice(row);
        }
        for z in 0..nz {
            for y in 0..ny {
                let row = nx * (y + ny * z);
                let start = at(0, y, z);
                self.values[row..row + nx].copy_from_slice(&padded[start..start + nx]);
            }
        }
    }
}

/// Per row of a grid, the samples the chamfer sweeps may lower: those within
/// `reach` steps (in each axis) of a sample below the field's maximum.
///
/// Why this is exact: the sweeps give each sample the minimum over paths of
/// neighbour steps from some sample `s` of `h(s)` plus the steps' lengths
/// times the rate, each at least `smallest_step`, added one after another
/// (rounding is monotone, so a path's sum never falls below its start).
/// A sample at the maximum further than `reach` steps from every lower
/// sample is reached from those only by paths that sum above the maximum,
/// and from samples at the maximum only by sums at least the maximum: it
/// keeps the maximum, in both sweeps, which is what it holds unswept.
/// Rows are spans (the hull of the samples near lower ones in the row), so
/// a span may include samples that stay at the maximum: sweeping them
/// computes what the full sweep computes there.
struct SweepSpans {
    dims: [usize; 3],
    /// Per row (y fastest, then z): the span's first sample and end, or
    /// `None` for a row the sweeps leave alone.
    spans: Vec<Option<(usize, usize)>>,
}

impl SweepSpans {
    fn of(grid: &SizeGrid, smallest_step: f64) -> Self {
        let [nx, ny, nz] = grid.dims;
        let (lo, hi) = grid
            .values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        // Two steps beyond the bound, far more than rounding can take back.
        let steps = ((hi - lo) / smallest_step).ceil() + 2.0;
        let reach = if steps.is_finite() && steps < (nx.max(ny).max(nz)) as f64 {
            steps as usize
        } else {
            nx.max(ny).max(nz)
        };
        // The samples below the maximum, as a span per row ...
        let mut spans: Vec<Option<(usize, usize)>> = grid
            .values
            .chunks_exact(nx)
            .map(|row| {
                let first = row.iter().position(|&v| v < hi)?;
                let last = row.iter().rposition(|&v| v < hi)?;
                Some((first.saturating_sub(reach), (last + reach + 1).min(nx)))
            })
            .collect();
        // ... grown by `reach` rows along y, then along z.
        spans = grow_rows(&spans, reach, [ny, nz], false);
        if nz > 1 {
            spans = grow_rows(&spans, reach, [ny, nz], true);
        }
        SweepSpans {
            dims: grid.dims,
            spans,
        }
    }

    /// The span `[first, end)` of row `(y, z)`, if it is swept.
    fn row(&self, y: usize, z: usize) -> Option<(usize, usize)> {
        self.spans[y + self.dims[1] * z]
    }
}

/// Each row's span becomes the hull of the spans of the rows within
/// `reach` of it along y (`along_z` false) or z, rows indexed y fastest
/// (`ny` of them), then z (`nz`).
fn grow_rows(
    spans: &[Option<(usize, usize)>],
    reach: usize,
    [ny, nz]: [usize; 2],
    along_z: bool,
) -> Vec<Option<(usize, usize)>> {
    let index = |y: usize, z: usize| y + ny * z;
    let mut grown = vec![None; spans.len()];
    for z in 0..nz {
        for y in 0..ny {
            let (i, count) = if along_z { (z, nz) } else { (y, ny) };
            let window = i.saturating_sub(reach)..(i + reach + 1).min(count);
            grown[index(y, z)] = window
                .filter_map(|j| spans[if along_z { index(y, j) } else { index(j, z) }])
                .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)));
        }
    }
    grown
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Vector2, Vector3};

    #[test]
    fn uniform_answers_the_edge_length() {
        let f = SizingField::uniform();
        assert!(f.is_uniform());
        assert_eq!(f.at(&Vector2::new(3.0, 4.0), 7.5), 7.5);
        assert_eq!(f.gradation_excess(0.1), 0.0);
    }

    #[test]
    fn lowered_point_is_graded_around_it_2d() {
        let mut f = SizingField::constant(&[0.0, 0.0], &[40.0, 20.0], 2, 1.0, 16.0);
        f.lower(&Vector2::new(10.5, 10.5), 2.0);
        f.limit_gradation(0.5);
        assert_eq!(f.at(&Vector2::new(10.5, 10.5), 0.0), 2.0);
        assert_eq!(f.at(&Vector2::new(14.5, 10.5), 0.0), 4.0);
        assert_eq!(f.at(&Vector2::new(39.5, 0.5), 0.0), 16.0);
        assert!(f.gradation_excess(0.5) < 1e-12);
        assert_eq!(f.range(), Some((2.0, 16.0)));
    }

    #[test]
    fn lowered_point_is_graded_around_it_3d() {
        let mut f = SizingField::constant(&[0.0; 3], &[16.0, 16.0, 16.0], 3, 2.0, 12.0);
        f.lower(&Vector3::new(8.0, 8.0, 8.0), 1.0);
        f.limit_gradation(1.0);
        assert_eq!(f.at(&Vector3::new(8.0, 8.0, 8.0), 0.0), 1.0);
        assert_eq!(f.at(&Vector3::new(8.0, 8.0, 12.0), 0.0), 5.0);
        let diag = f.at(&Vector3::new(10.0, 10.0, 10.0), 0.0);
        assert!((diag - (1.0 + 2.0 * 3f64.sqrt())).abs() < 1e-12);
        assert!(f.gradation_excess(1.0) < 1e-12);
    }

    /// The sweeps as first written, testing every neighbour against the
    /// grid's bounds.
    fn reference_sweeps(g: &mut SizeGrid, rate: f64) {
        let offsets = forward_offsets(g.three_d());
        let [nx, ny, _] = g.dims;
        let n = g.values.len();
        let order: Vec<usize> = (0..n).chain((0..n).rev()).collect();
        for (pass, &i) in order.iter().enumerate() {
            let sign = if pass < n { 1 } else { -1 };
            let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
            for o in &offsets {
                let o = [sign * o[0], sign * o[1], sign * o[2]];
                if let Some(j) = g.offset(x, y, z, o) {
                    g.values[i] = g.values[i].min(g.values[j] + rate * g.offset_length(&o));
                }
            }
        }
    }

    /// Reproducible draws in [0, 1).
    fn uniform_draws(seed: u64) -> impl FnMut() -> f64 {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        move || rng.random::<f64>()
    }

    #[test]
    fn padded_sweeps_give_the_bounds_checked_result_bit_for_bit() {
        let mut random = uniform_draws(12345);
        let boxes: [(&[f64], usize); 5] = [
            (&[13.0, 7.0], 2),
            (&[1.0, 9.0], 2),
            (&[9.0, 6.0, 5.0], 3),
            (&[1.0, 8.0, 7.0], 3),
            (&[6.0, 5.0, 1.0], 3),
        ];
        for (hi, n) in boxes {
            let mut f = SizingField::constant(&[0.0; 3][..n], hi, n, 1.0, 20.0);
            let g = f.grid.as_mut().unwrap();
            for v in &mut g.values {
                *v = 1.0 + 19.0 * random();
            }
            let mut expected = g.clone();
            reference_sweeps(&mut expected, 0.7);
            f.limit_gradation(0.7);
            assert_eq!(
                f.grid.as_ref().unwrap().values,
                expected.values,
                "box {hi:?}"
            );
            assert!(f.gradation_excess(0.7) < 1e-12);
        }
    }

    /// Fields at their maximum but for a few lowered samples, as the
    /// adaptive sizing makes them: the sweeps over the spans near the
    /// lowered samples give the full sweeps' result bit for bit, however
    /// far the lowered values reach (rate and depth vary).
    #[test]
    fn sweeps_near_lowered_samples_give_the_full_result_bit_for_bit() {
        let mut random = uniform_draws(987654321);
        let boxes: [(&[f64], usize); 4] = [
            (&[61.0, 37.0], 2),
            (&[23.0, 29.0, 31.0], 3),
            (&[40.0, 6.0, 17.0], 3),
            (&[5.0, 33.0, 2.0], 3),
        ];
        let mut sparse = 0;
        for (hi, n) in boxes {
            for (rate, lowered) in [(1.0, 3), (0.5, 12), (2.5, 40), (0.05, 2)] {
                let mut f = SizingField::constant(&[0.0; 3][..n], hi, n, 1.0, 20.0);
                let g = f.grid.as_mut().unwrap();
                for _ in 0..lowered {
                    let i = (random() * g.values.len() as f64) as usize;
                    g.values[i] = 12.0 + 7.0 * random();
                }
                let mut expected = g.clone();
                reference_sweeps(&mut expected, rate);
                f.limit_gradation(rate);
                let got = &f.grid.as_ref().unwrap().values;
                assert_eq!(got, &expected.values, "box {hi:?}, rate {rate}");
                sparse += usize::from(got.contains(&20.0));
            }
        }
        assert!(
            sparse >= 10,
            "{sparse} of 16 fields keep samples at the maximum"
        );
    }

    #[test]
    fn points_outside_clamp_into_the_grid() {
        let mut f = SizingField::constant(&[0.0, 0.0], &[10.0, 10.0], 2, 2.5, 9.0);
        f.lower(&Vector2::new(-3.0, 100.0), 1.0);
        assert_eq!(f.at(&Vector2::new(0.0, 10.0), 0.0), 1.0);
        assert_eq!(f.at(&Vector2::new(f64::NAN, 9.9), 0.0), 1.0);
    }
}
