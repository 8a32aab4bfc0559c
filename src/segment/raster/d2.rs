//! The 2D rasteriser: the pixels whose centres lie in a triangle, as
//! contiguous row spans (a fast path for small triangles, a general one for
//! the rest), facet sampling along segments and bilinear interpolation.

use super::Raster;
use crate::complex::{BuildError, Complex};
use crate::dim::D2;
use crate::segment::image::ImageView;
use nalgebra::Vector2;

/// `x.ceil() as i64` without a call to libm's `ceil` (the baseline x86-64
/// target has no `roundsd`, so `f64::ceil` is a function call per row): the
/// same integer for every `x`, NaN (0) and out-of-range values (saturated)
/// included.
#[inline(always)]
fn ceil_i64(x: f64) -> i64 {
    let t = x as i64; // truncates toward zero, saturating; NaN -> 0
    if (t as f64) < x {
        t.saturating_add(1)
    } else {
        t
    }
}

/// `⌈v⌉` for `0 <= v <= 2^50` (callers clamp), without a float-to-integer
/// conversion: adding `1.5·2^52` rounds `v` to the nearest integer `r` in the
/// low bits of the sum (exactly; the sum stays in `[2^52, 2^53)`), and
/// `⌈v⌉ = r + (r < v)`.
#[inline(always)]
fn ceil_small(v: f64) -> i64 {
    const M: f64 = 6_755_399_441_055_744.0; // 1.5 · 2^52
    let s = v + M;
    let r = s - M;
    s.to_bits().wrapping_sub(M.to_bits()) as i64 + i64::from(r < v)
}

/// The reference (kept for the tests; [`RowEdge`] does the same arithmetic):
/// the x where the edge `a`–`b` crosses the line `y = yc`, computed from the
/// edge's endpoints in a canonical order so that the two triangles sharing the
/// edge get bit-identical results.
#[cfg(test)]
fn edge_x(a: Vector2<f64>, b: Vector2<f64>, yc: f64) -> f64 {
    let (p, q) = if (a.y, a.x) <= (b.y, b.x) {
        (a, b)
    } else {
        (b, a)
    };
    p.x + (yc - p.y) * (q.x - p.x) / (q.y - p.y)
}

/// An edge prepared for `edge_x`-identical crossings: endpoints in the
/// canonical order, differences computed once.
#[derive(Clone, Copy)]
struct RowEdge {
    px: f64,
    py: f64,
    dx: f64,
    dy: f64,
}

impl RowEdge {
    #[inline(always)]
    fn new(a: Vector2<f64>, b: Vector2<f64>) -> Self {
        let (p, q) = if (a.y, a.x) <= (b.y, b.x) {
            (a, b)
        } else {
            (b, a)
        };
        RowEdge {
            px: p.x,
            py: p.y,
            dx: q.x - p.x,
            dy: q.y - p.y,
        }
    }

    /// The edge from `p` to `q` where `(p.y, p.x) <= (q.y, q.x)` is known.
    #[inline(always)]
    fn sorted(p: Vector2<f64>, q: Vector2<f64>) -> Self {
        RowEdge {
            px: p.x,
            py: p.y,
            dx: q.x - p.x,
            dy: q.y - p.y,
        }
    }

    /// Same operations, in the same order, as `edge_x`.
    #[inline(always)]
    fn x(&self, yc: f64) -> f64 {
        self.px + (yc - self.py) * self.dx / self.dy
    }
}

/// Whether [`sorted_spans`] gives exactly [`general_spans`]'s runs for these
/// corners: every coordinate finite and below `1e300` in magnitude. Then no
/// coordinate difference overflows and no crossing `x` is NaN, so the order
/// in which two crossings are compared, and the tie order of the corner
/// sort with it, cannot change a run; and every row between the first and
/// the last passes the half-open row tests (see [`sorted_spans`]).
#[inline(always)]
fn fast_path_applies(c: &[Vector2<f64>; 3]) -> bool {
    const BOUND: f64 = 1e300;
    c.iter()
        .fold(true, |ok, p| ok & (p.x.abs() < BOUND) & (p.y.abs() < BOUND))
}

/// The runs of a triangle whose corners pass [`fast_path_applies`], with no
/// per-row tests: bit for bit [`general_spans`].
///
/// With corners `a`, `b`, `t` sorted by `y`, row `j` (centre `yc = j + 0.5`)
/// meets the triangle for `j0 <= j < j1`, `j0 = ⌈ymin − 0.5⌉`,
/// `j1 = ⌈ymax − 0.5⌉` (clamped to the image): for finite `y` the
/// subtraction `y − 0.5` is exact whenever it decides a row in the image
/// (`0.5 < y < 2^52`), so `ymin <= yc < ymax` holds on exactly those rows.
/// For the same reason the rows below `jm = ⌈ymid − 0.5⌉` are exactly those
/// with `yc < ymid`: the lower short edge `a`–`b` is active there, the
/// upper one `b`–`t` from `jm` on, the long edge `a`–`t` on all. An edge
/// with distinct end heights has its lower end first in the sorted order,
/// the canonical order of [`RowEdge`]; one with equal heights has no rows.
#[inline(always)]
fn sorted_spans(w: i64, h: i64, c: &[Vector2<f64>; 3], visit: &mut impl FnMut(usize, usize)) {
    let [a, b, t] = sort_by_y(c);
    // Clamping before the ceiling is clamping after it (`⌈⌉` is monotone and
    // 0, h are integers), and keeps j0 <= jm <= j1 (the heights are sorted).
    let row = |y: f64| ceil_small((y - 0.5).clamp(0.0, h as f64));
    let (j0, jm, j1) = (row(a.y), row(b.y), row(t.y));
    let long = RowEdge::sorted(a, t);
    rows_between(w, &long, &RowEdge::sorted(a, b), j0, jm, visit);
    rows_between(w, &long, &RowEdge::sorted(b, t), jm, j1, visit);
}

/// The corners in increasing `y` (ties in any order), by three
/// compare-exchanges that compile to selects rather than branches.
#[inline(always)]
fn sort_by_y(c: &[Vector2<f64>; 3]) -> [Vector2<f64>; 3] {
    let swap = |p: Vector2<f64>, q: Vector2<f64>| if q.y < p.y { (q, p) } else { (p, q) };
    let (a, b) = swap(c[0], c[1]);
    let (b, t) = swap(b, c[2]);
    let (a, b) = swap(a, b);
    [a, b, t]
}

/// The runs of rows `j0..j1`, crossed by the edges `e` and `f`.
#[inline(always)]
fn rows_between(
    w: i64,
    e: &RowEdge,
    f: &RowEdge,
    j0: i64,
    j1: i64,
    visit: &mut impl FnMut(usize, usize),
) {
    let mut row = j0 * w;
    // As in `sorted_spans`, clamping to [0, w] before the ceiling is the
    // `max(0)`/`min(w)` after it, for the ends of every non-empty run.
    let col = |x: f64| ceil_small((x - 0.5).clamp(0.0, w as f64));
    for j in j0..j1 {
        let yc = j as f64 + 0.5;
        // `col` is monotone, so ordering the columns orders the crossings
        // (`if x0 <= x1 { (x0, x1) } else { (x1, x0) }` for NaN-free x).
        let (c0, c1) = (col(e.x(yc)), col(f.x(yc)));
        let (i0, i1) = (c0.min(c1), c0.max(c1));
        if i0 < i1 {
            visit((row + i0) as usize, (row + i1) as usize);
        }
        row += w;
    }
}

/// Pixel-centre rule for any corners (NaN and infinities included): the
/// reference arithmetic with the half-open tests on every row.
fn general_spans(w: i64, h: i64, c: &[Vector2<f64>; 3], visit: &mut impl FnMut(usize, usize)) {
    // Corners sorted by y (ties in any order: an edge with equal end
    // heights is never active, as the half-open test makes it).
    let (mut a, mut b, mut t) = (c[0], c[1], c[2]);
    if b.y < a.y {
        std::mem::swap(&mut a, &mut b);
    }
    if t.y < b.y {
        std::mem::swap(&mut b, &mut t);
        if b.y < a.y {
            std::mem::swap(&mut a, &mut b);
        }
    }
    let (ymin, ymid, ymax) = (a.y, b.y, t.y);
    let j0 = ceil_i64(ymin - 0.5).max(0);
    let j1 = ceil_i64(ymax - 0.5).min(h); // exclusive
    if j0 >= j1 {
        return;
    }
    let long = RowEdge::new(a, t);
    let lower = RowEdge::new(a, b);
    let upper = RowEdge::new(b, t);
    let mut row = j0 * w;
    for j in j0..j1 {
        let yc = j as f64 + 0.5;
        // Active edges on the row (`lo <= yc < hi`): the long edge on
        // [ymin, ymax), the lower short one on [ymin, ymid), the upper
        // one on [ymid, ymax) -- exactly two on every row of the range.
        if ymin <= yc && yc < ymax {
            let x0 = long.x(yc);
            let x1 = if yc < ymid { lower.x(yc) } else { upper.x(yc) };
            let (xl, xr) = if x0 <= x1 { (x0, x1) } else { (x1, x0) };
            let i0 = ceil_i64(xl - 0.5).max(0);
            let i1 = ceil_i64(xr - 0.5).min(w);
            if i0 < i1 {
                visit((row + i0) as usize, (row + i1) as usize);
            }
        }
        row += w;
    }
}

impl Raster for D2 {
    /// Pixel-centre rule by scanlines: row `j` (centre `yc = j + 0.5`) meets
    /// the triangle if `ymin <= yc < ymax`; an edge is active on the row when
    /// `ylo <= yc < yhi` (exactly two edges are then); the pixels with centre
    /// in `[xl, xr)` belong to the triangle. Shared edges give identical `x`,
    /// so each pixel is counted exactly once over a tiling.
    ///
    /// The three edges are prepared once per triangle (corners sorted by
    /// `y`: the long edge is active on every row, the lower short edge below
    /// the middle corner, the upper one from it on), and each row is one
    /// contiguous span. The arithmetic per edge and row is exactly
    /// `edge_x`'s, so the result is bit-identical to testing the three
    /// edges on every row.
    ///
    /// Corners of ordinary size take `sorted_spans` (no per-row tests,
    /// no float-to-integer conversions); others the same rule with every
    /// test in place (`general_spans`). Both give the same runs where both
    /// apply (`fast_path_equals_the_general_path`); the bound on `w` and `h`
    /// keeps `ceil_small`'s range.
    fn cell_spans(image: &ImageView<'_>, c: &[Vector2<f64>], visit: &mut impl FnMut(usize, usize)) {
        let (w, h) = (image.dims[0] as i64, image.dims[1] as i64);
        let c = [c[0], c[1], c[2]];
        if w.max(h) <= 1 << 50 && fast_path_applies(&c) {
            sorted_spans(w, h, &c, visit);
        } else {
            general_spans(w, h, &c, visit);
        }
    }

    #[inline]
    fn facet_samples(
        c: &[Vector2<f64>],
        spacing: f64,
        visit: &mut impl FnMut(Vector2<f64>, &[f64], f64),
    ) {
        let d = c[1] - c[0];
        let len = d.norm();
        let n = ((len / spacing).ceil() as usize).max(1);
        let ds = len / n as f64;
        for k in 0..n {
            let t = (k as f64 + 0.5) / n as f64;
            visit(c[0] + d * t, &[1.0 - t, t], ds);
        }
    }

    #[inline]
    fn sample(image: &ImageView<'_>, p: Vector2<f64>) -> f64 {
        let (w, h) = (image.dims[0], image.dims[1]);
        let x = (p.x - 0.5).clamp(0.0, (w - 1) as f64);
        let y = (p.y - 0.5).clamp(0.0, (h - 1) as f64);
        // (truncation is the floor of these non-negative values, without
        // libm's `floor` call per sample)
        let x0 = (x as usize).min(w.saturating_sub(2));
        let y0 = (y as usize).min(h.saturating_sub(2));
        let x1 = (x0 + 1).min(w - 1);
        let y1 = (y0 + 1).min(h - 1);
        let fx = x - x0 as f64;
        let fy = y - y0 as f64;
        let v = |i: usize, j: usize| image.data[j * w + i] as f64;
        let top = v(x0, y0) * (1.0 - fx) + v(x1, y0) * fx;
        let bot = v(x0, y1) * (1.0 - fx) + v(x1, y1) * fx;
        top * (1.0 - fy) + bot * fy
    }

    fn pixel_centre(image: &ImageView<'_>, index: usize) -> Vector2<f64> {
        let w = image.dims[0];
        Vector2::new((index % w) as f64 + 0.5, (index / w) as f64 + 0.5)
    }

    fn box_complex(image: &ImageView<'_>, l: f64) -> Result<Complex<D2>, BuildError> {
        Complex::rectangle(image.dims[0] as f64, image.dims[1] as f64, l)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ceil_i64_matches_ceil() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1e-300,
            -1e-300,
            2.5,
            -2.5,
            1e15 + 0.5,
            9.1e18,
            9.3e18,
            -9.3e18,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        let mut s = 0x9e3779b97f4a7c15u64;
        for _ in 0..100_000 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            xs.push((s >> 11) as f64 / (1u64 << 53) as f64 * 4096.0 - 2048.0);
        }
        for k in -100..100 {
            let k = k as f64 * 0.5;
            xs.extend([k, k - 1e-12, k + 1e-12]);
        }
        for x in xs {
            assert_eq!(ceil_i64(x), x.ceil() as i64, "{x}");
        }
    }

    /// The reference: every row tests the three edges (the rasteriser
    /// before the spans), one pixel at a time.
    fn reference(w: i64, h: i64, c: &[Vector2<f64>]) -> Vec<usize> {
        let mut out = Vec::new();
        let ymin = c[0].y.min(c[1].y).min(c[2].y);
        let ymax = c[0].y.max(c[1].y).max(c[2].y);
        let j0 = ((ymin - 0.5).ceil() as i64).max(0);
        let j1 = ((ymax - 0.5).ceil() as i64).min(h);
        for j in j0..j1 {
            let yc = j as f64 + 0.5;
            let mut xs = [0.0f64; 2];
            let mut n = 0;
            for e in 0..3 {
                let (a, b) = (c[e], c[(e + 1) % 3]);
                let (lo, hi) = if a.y <= b.y { (a.y, b.y) } else { (b.y, a.y) };
                if lo <= yc && yc < hi && n < 2 {
                    xs[n] = edge_x(a, b, yc);
                    n += 1;
                }
            }
            if n < 2 {
                continue;
            }
            let (xl, xr) = if xs[0] <= xs[1] {
                (xs[0], xs[1])
            } else {
                (xs[1], xs[0])
            };
            let i0 = ((xl - 0.5).ceil() as i64).max(0);
            let i1 = ((xr - 0.5).ceil() as i64).min(w);
            for i in i0..i1 {
                out.push((j * w + i) as usize);
            }
        }
        out
    }

    #[test]
    fn ceil_small_matches_ceil() {
        let mut xs = vec![
            0.0,
            -0.0,
            1e-300,
            0.5,
            1.0,
            2.5,
            1125899906842623.5,
            2f64.powi(50),
        ];
        let mut s = 0x9e3779b97f4a7c15u64;
        for _ in 0..100_000 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let u = (s >> 11) as f64 / (1u64 << 53) as f64;
            xs.push(u * 4096.0);
            xs.push(u * 2f64.powi(50));
        }
        for k in 0..400 {
            let k = k as f64 * 0.5;
            xs.extend([k, k + 1e-12, (k - 1e-12).max(0.0)]);
        }
        for x in xs {
            assert_eq!(ceil_small(x), x.ceil() as i64, "{x}");
        }
    }

    /// A rasteriser under test: image width and height, corners, visitor.
    type Spans = fn(i64, i64, &[Vector2<f64>; 3], &mut dyn FnMut(usize, usize));

    /// The runs of `spans` for corners `c` on a `w × h` image, as pairs.
    fn runs(spans: Spans, w: i64, h: i64, c: &[Vector2<f64>; 3]) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        spans(w, h, c, &mut |a, b| out.push((a, b)));
        out
    }

    #[test]
    fn fast_path_equals_the_general_path() {
        let (w, h) = (23i64, 19i64);
        let mut s = 0x853c49e6748fea9bu64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        // Coordinates on the half-pixel grid (ties of rows, columns and
        // corner heights), off it, outside the image and far away.
        let coord = |r: u64, extent: f64| {
            let u = (r >> 11) as f64 / (1u64 << 53) as f64;
            match r % 8 {
                0..=2 => ((u * 1.4 - 0.2) * extent * 2.0).round() / 2.0,
                3 => (u - 0.5) * 1e12,
                4 => (u - 0.5) * 1e299,
                5 => [0.5, 1.0, -0.5, extent - 0.5, extent][(r >> 3) as usize % 5],
                _ => (u * 1.4 - 0.2) * extent,
            }
        };
        let fast = |w, h, c: &[Vector2<f64>; 3], v: &mut dyn FnMut(usize, usize)| {
            sorted_spans(w, h, c, &mut |a, b| v(a, b))
        };
        let general = |w, h, c: &[Vector2<f64>; 3], v: &mut dyn FnMut(usize, usize)| {
            general_spans(w, h, c, &mut |a, b| v(a, b))
        };
        for _ in 0..200_000 {
            let mut c = [Vector2::zeros(); 3];
            for p in &mut c {
                *p = Vector2::new(coord(next(), w as f64), coord(next(), h as f64));
            }
            if next() % 4 == 0 {
                c[2].y = c[next() as usize % 2].y; // a flat edge
            }
            assert!(fast_path_applies(&c));
            let want = runs(general, w, h, &c);
            for perm in [
                [0, 1, 2],
                [0, 2, 1],
                [1, 0, 2],
                [1, 2, 0],
                [2, 0, 1],
                [2, 1, 0],
            ] {
                let p = perm.map(|i| c[i]);
                assert_eq!(runs(fast, w, h, &p), want, "{p:?}");
            }
        }
    }

    /// Corners out of the fast path's bound go to the general path (the
    /// rasteriser as it was before the fast path, NaN handling included).
    #[test]
    fn non_finite_and_huge_corners_take_the_general_path() {
        let (w, h) = (9usize, 7usize);
        let data = vec![0.0f32; w * h];
        let image = ImageView::new_2d(w, h, &data).unwrap();
        let odd = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e308, -1e300];
        let plain = [0.5, 3.0, 6.5, 8.0];
        for &x in odd.iter().chain(&plain) {
            for &y in odd.iter().chain(&plain) {
                for k in 0..3 {
                    let mut c = [
                        Vector2::new(0.0, 0.0),
                        Vector2::new(8.5, 2.0),
                        Vector2::new(3.0, 6.5),
                    ];
                    c[k] = Vector2::new(x, y);
                    let finite = [x, y].iter().all(|v| v.abs() < 1e300);
                    assert_eq!(fast_path_applies(&c), finite, "{c:?}");
                    let mut got = Vec::new();
                    <D2 as Raster>::cell_spans(&image, &c, &mut |a, b| got.push((a, b)));
                    let mut want = Vec::new();
                    general_spans(w as i64, h as i64, &c, &mut |a, b| want.push((a, b)));
                    assert_eq!(got, want, "{c:?}");
                }
            }
        }
    }

    #[test]
    fn spans_match_the_three_edge_scanline() {
        let (w, h) = (37usize, 29usize);
        let data = vec![0.0f32; w * h];
        let image = ImageView::new_2d(w, h, &data).unwrap();
        let mut s = 0x2545f4914f6cdd1du64;
        let mut rnd = |scale: f64| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let r = (s >> 11) as f64 / (1u64 << 53) as f64 * scale - 0.1 * scale;
            // Half of the coordinates on the pixel-centre and pixel-edge grid.
            if s & 1 == 0 {
                (r * 2.0).round() / 2.0
            } else {
                r
            }
        };
        for _ in 0..20_000 {
            let c: Vec<Vector2<f64>> = (0..3)
                .map(|_| Vector2::new(rnd(w as f64 * 1.2), rnd(h as f64 * 1.2)))
                .collect();
            let mut got = Vec::new();
            <D2 as Raster>::cell_pixels(&image, &c, &mut |p| got.push(p));
            assert_eq!(got, reference(w as i64, h as i64, &c), "{c:?}");
        }
    }
}
