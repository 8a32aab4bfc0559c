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
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SizingField {
    grid: Option<SizeGrid>,
}

/// Samples of a graded field: one value per grid cell of side `spacing`,
/// x fastest, then y, then z (one layer in 2D).
#[derive(Clone, Debug, PartialEq)]
struct SizeGrid {
    origin: [f64; 3],
    spacing: f64,
    dims: [usize; 3],
    values: Vec<f64>,
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
        if let Some(g) = &mut self.grid {
            g.limit_gradation(rate);
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
                let t = ((p[a] - self.origin[a]) / self.spacing).floor();
                // NaN and out-of-range clamp into the grid.
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
    /// padded with one layer of `+∞` on every side of each axis swept, so
    /// that every neighbour is a fixed index offset and no bounds are
    /// checked (a neighbour in the padding lowers nothing: the result is
    /// that of sweeping the grid alone).
    fn limit_gradation(&mut self, rate: f64) {
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
        let mut padded = vec![f64::INFINITY; px * py * pz];
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
        let rows: Vec<usize> = (0..nz)
            .flat_map(|z| (0..ny).map(move |y| (y, z)))
            .map(|(y, z)| at(0, y, z))
            .collect();
        let mut row = vec![0.0; nx];
        // Forward: each sample from its earlier neighbours, rows in order.
        for &start in &rows {
            sweep_row(&padded, &mut row, start, &across, 1);
            let mut last = f64::INFINITY;
            for v in row.iter_mut() {
                *v = v.min(last + along);
                last = *v;
            }
            padded[start..start + nx].copy_from_slice(&row);
        }
        // Backward: each sample from its later neighbours (mirrored offsets).
        for &start in rows.iter().rev() {
            sweep_row(&padded, &mut row, start, &across, -1);
            let mut last = f64::INFINITY;
            for v in row.iter_mut().rev() {
                *v = v.min(last + along);
                last = *v;
            }
            padded[start..start + nx].copy_from_slice(&row);
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

    #[test]
    fn padded_sweeps_give_the_bounds_checked_result_bit_for_bit() {
        let mut state = 12345u64;
        let mut random = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
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

    #[test]
    fn points_outside_clamp_into_the_grid() {
        let mut f = SizingField::constant(&[0.0, 0.0], &[10.0, 10.0], 2, 2.5, 9.0);
        f.lower(&Vector2::new(-3.0, 100.0), 1.0);
        assert_eq!(f.at(&Vector2::new(0.0, 10.0), 0.0), 1.0);
        assert_eq!(f.at(&Vector2::new(f64::NAN, 9.9), 0.0), 1.0);
    }
}
