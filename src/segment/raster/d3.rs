//! The 3D rasteriser: which voxels a tetrahedron owns (the voxel-centre
//! rule, every voxel counted exactly once over a complex), quadrature over
//! interface triangles and trilinear interpolation.
//!
//! Convention: a volume of `nx × ny × nz` voxels occupies the box
//! `[0, nx] × [0, ny] × [0, nz]`; voxel `(i, j, k)` has its centre at
//! `(i + ½, j + ½, k + ½)`.
//!
//! A voxel belongs to the tet whose closed region contains its centre. Centres
//! on a shared facet, edge or vertex are decided by simulation of simplicity:
//! the centre is nudged by `(ε, ε², ε³)` and the tet containing the nudged
//! point wins. For a facet through the centre that amounts to the lexicographic
//! sign of the facet's inward normal, evaluated exactly with 2D orientation
//! predicates on the three coordinate-plane projections, so the rule never
//! depends on rounding and each centre inside the domain has exactly one owner.

use super::Raster;
use crate::complex::{BuildError, CellId, Complex};
use crate::dim::D3;
use crate::segment::image::ImageView;
use nalgebra::Vector3;

fn c2(a: f64, b: f64) -> robust::Coord<f64> {
    robust::Coord { x: a, y: b }
}

fn c3(p: &Vector3<f64>) -> robust::Coord3D<f64> {
    robust::Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

/// Sign of `det[b-a, c-a, p-a]` (exact).
fn orient(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>, p: &Vector3<f64>) -> f64 {
    -robust::orient3d(c3(a), c3(b), c3(c), c3(p))
}

/// Whether `(b-a)×(c-a)` is lexicographically positive (x, then y, then z
/// component; exact: each component is a 2D orientation of a projection).
fn normal_lex_positive(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> bool {
    let x = robust::orient2d(c2(a.y, a.z), c2(b.y, b.z), c2(c.y, c.z));
    if x != 0.0 {
        return x > 0.0;
    }
    let y = robust::orient2d(c2(a.z, a.x), c2(b.z, b.x), c2(c.z, c.x));
    if y != 0.0 {
        return y > 0.0;
    }
    robust::orient2d(c2(a.x, a.y), c2(b.x, b.y), c2(c.x, c.y)) > 0.0
}

/// Whether the positively oriented tet `t` owns the point `p` under the
/// voxel-centre rule (closed tet, ties broken by simulation of simplicity).
pub fn tet_owns(t: &[Vector3<f64>; 4], p: &Vector3<f64>) -> bool {
    // The facets opposite each corner, ordered so that det[b-a, c-a, x-a] > 0
    // for x on the inner side (the same sign as the corner itself).
    let facets = [
        (&t[1], &t[3], &t[2]),
        (&t[0], &t[2], &t[3]),
        (&t[0], &t[3], &t[1]),
        (&t[0], &t[1], &t[2]),
    ];
    facets.iter().all(|&(a, b, c)| {
        let s = orient(a, b, c, p);
        // On the plane: the nudge (ε, ε², ε³) points inwards iff the inward
        // normal (b-a)×(c-a) is lexicographically positive.
        s > 0.0 || (s == 0.0 && normal_lex_positive(a, b, c))
    })
}

/// One facet of [`tet_voxels`]'s tet with what the floating-point filter of
/// its orientation needs.
struct FilteredFacet {
    a: Vector3<f64>,
    b: Vector3<f64>,
    c: Vector3<f64>,
    /// `(b-a)×(c-a)`, rounded.
    n: Vector3<f64>,
    /// Per component the sum of the magnitudes of the two products of `n`'s
    /// component (the permanent's coefficients).
    perm: Vector3<f64>,
}

impl FilteredFacet {
    fn new(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> Self {
        let (u, v) = (b - a, c - a);
        FilteredFacet {
            a: *a,
            b: *b,
            c: *c,
            n: u.cross(&v),
            perm: Vector3::new(
                (u.y * v.z).abs() + (u.z * v.y).abs(),
                (u.z * v.x).abs() + (u.x * v.z).abs(),
                (u.x * v.y).abs() + (u.y * v.x).abs(),
            ),
        }
    }

    /// [`tet_owns`]'s test for this facet: `n·(p-a)` decides when it exceeds
    /// its rounding error bound, the exact predicate otherwise. Forward error
    /// analysis of the rounded differences, cross and dot products gives
    /// `|n·(p-a) - det| ≤ 8u·perm·|p-a|` (u = 2⁻⁵³, to first order); the bound
    /// used is twice that (`4·EPSILON = 8u`, times 2), plus a floor for
    /// underflow, so the sign taken is always the exact one.
    #[inline]
    fn inner(&self, p: &Vector3<f64>) -> bool {
        let w = p - self.a;
        let s = self.n.x * w.x + self.n.y * w.y + self.n.z * w.z;
        let perm = self.perm.x * w.x.abs() + self.perm.y * w.y.abs() + self.perm.z * w.z.abs();
        let bound = 8.0 * f64::EPSILON * perm + 1e-300;
        if s > bound {
            return true;
        }
        if s < -bound {
            return false;
        }
        let s = orient(&self.a, &self.b, &self.c, p);
        s > 0.0 || (s == 0.0 && normal_lex_positive(&self.a, &self.b, &self.c))
    }
}

/// The centre of voxel `v` in the domain: `(v + 0.5) · spacing`.
#[inline]
pub fn voxel_centre(v: [usize; 3], spacing: [f64; 3]) -> Vector3<f64> {
    Vector3::new(
        (v[0] as f64 + 0.5) * spacing[0],
        (v[1] as f64 + 0.5) * spacing[1],
        (v[2] as f64 + 0.5) * spacing[2],
    )
}

/// Calls `f(i, j, k)` for every voxel of an `dims` grid whose centre the
/// positively oriented tet `t` owns (see [`tet_owns`]), in x-fastest order:
/// the voxels of [`tet_rows`] one by one.
pub fn tet_voxels(
    t: &[Vector3<f64>; 4],
    dims: [usize; 3],
    spacing: [f64; 3],
    mut f: impl FnMut(usize, usize, usize),
) {
    tet_rows(t, dims, spacing, |j, k, xs| xs.for_each(|i| f(i, j, k)));
}

/// Calls `f(j, k, first..end)` for every row `(j, k)` of an `dims` grid in
/// which the positively oriented tet `t` owns voxel centres (see
/// [`tet_owns`]): the owned centres of the row are `first..end`. Rows come
/// in increasing `(k, j)` order, so the voxels come in increasing linear
/// index.
///
/// The same decisions as [`tet_owns`] on every centre, faster. Every facet's
/// condition along a row is a half-line (the tie rule depends on the facet
/// only), so the owned centres of a row are contiguous. A small tet's rows
/// are scanned centre by centre, each facet's orientation evaluated in
/// floating point with a certified error bound (`FilteredFacet::inner`,
/// exact near the plane), a row stopping at its first centre outside after
/// one inside. A larger tet's rows are cut by the facet planes directly
/// (`RowCutter`): where each plane crosses the row is computed in floating
/// point with an error bound, the centres beyond the bounds are inside, and
/// only a centre within the bound of a plane (on it, say) is tested exactly.
/// Integration spends most of its time here.
pub fn tet_rows(
    t: &[Vector3<f64>; 4],
    dims: [usize; 3],
    spacing: [f64; 3],
    mut f: impl FnMut(usize, usize, std::ops::Range<usize>),
) {
    let Some((lo, hi)) = voxel_box(t, dims, spacing) else {
        return;
    };
    // The facets in tet_owns's order.
    let facets = [
        FilteredFacet::new(&t[1], &t[3], &t[2]),
        FilteredFacet::new(&t[0], &t[2], &t[3]),
        FilteredFacet::new(&t[0], &t[3], &t[1]),
        FilteredFacet::new(&t[0], &t[1], &t[2]),
    ];
    let owns = |i: usize, j: usize, k: usize| {
        let p = voxel_centre([i, j, k], spacing);
        facets.iter().all(|fc| fc.inner(&p))
    };
    let box_voxels = (0..3).map(|a| hi[a] + 1 - lo[a]).product::<usize>();
    if box_voxels <= SMALL_BOX {
        for k in lo[2]..=hi[2] {
            for j in lo[1]..=hi[1] {
                let mut run: Option<(usize, usize)> = None;
                for i in lo[0]..=hi[0] {
                    if owns(i, j, k) {
                        run = Some((run.map_or(i, |r| r.0), i + 1));
                    } else if run.is_some() {
                        break;
                    }
                }
                if let Some((first, end)) = run {
                    f(j, k, first..end);
                }
            }
        }
        return;
    }
    let cutter = RowCutter::new(&facets, lo, hi, spacing);
    for k in lo[2]..=hi[2] {
        for j in lo[1]..=hi[1] {
            let y = (j as f64 + 0.5) * spacing[1];
            let z = (k as f64 + 0.5) * spacing[2];
            let Some(cut) = cutter.cut(y, z) else {
                continue;
            };
            let sure = |i: usize| cut.surely_inside((i as f64 + 0.5) * spacing[0]);
            let outside = |i: usize| (cut.exact_everywhere || !sure(i)) && !owns(i, j, k);
            let (mut first, mut last) = (cut.first, cut.last);
            while first <= last && outside(first) {
                first += 1;
            }
            while last > first && outside(last) {
                last -= 1;
            }
            if first <= last {
                f(j, k, first..last + 1);
            }
        }
    }
}

/// Tets whose box holds at most this many voxel centres are scanned centre
/// by centre; larger ones are cut row by row ([`RowCutter`]).
const SMALL_BOX: usize = 64;

/// The index box of the voxel centres that may lie in `t` (`None`: none do).
fn voxel_box(
    t: &[Vector3<f64>; 4],
    dims: [usize; 3],
    spacing: [f64; 3],
) -> Option<([usize; 3], [usize; 3])> {
    let mut lo = [0usize; 3];
    let mut hi = [0usize; 3];
    for axis in 0..3 {
        let s = spacing[axis];
        let min = t.iter().map(|p| p[axis]).fold(f64::INFINITY, f64::min) / s;
        let max = t.iter().map(|p| p[axis]).fold(f64::NEG_INFINITY, f64::max) / s;
        // Centres c = i + 0.5 with min <= c <= max; with a spacing the
        // division may round, so one more voxel each side (the facet tests
        // decide).
        let margin = if s == 1.0 { 0.0 } else { 1.0 };
        lo[axis] = (min - 0.5 - margin).ceil().max(0.0) as usize;
        let top = (max - 0.5 + margin).floor();
        if top < 0.0 {
            return None;
        }
        hi[axis] = (top as usize).min(dims[axis].saturating_sub(1));
        if lo[axis] > hi[axis] {
            return None;
        }
    }
    Some((lo, hi))
}

/// Where a facet plane crosses the rows of [`tet_rows`]: `x = α + β·y +
/// γ·z`, within `±δ` of the exact crossing; or, for a plane (nearly)
/// parallel to the rows, its orientation along a row, `r = n.y·(y − a.y) +
/// n.z·(z − a.z)`, within `±δ` of the exact value anywhere in the box.
#[derive(Clone, Copy, Debug)]
enum Crossing {
    /// The tet lies at `x` above the crossing (`n.x > 0`).
    Lower {
        alpha: f64,
        beta: f64,
        gamma: f64,
        delta: f64,
    },
    /// The tet lies at `x` below the crossing (`n.x < 0`).
    Upper {
        alpha: f64,
        beta: f64,
        gamma: f64,
        delta: f64,
    },
    /// The orientation barely changes along a row.
    Level {
        ny: f64,
        nz: f64,
        ay: f64,
        az: f64,
        delta: f64,
    },
}

/// The rows of a tet's box cut by its four facet planes ([`Crossing`]).
///
/// The error bounds: [`FilteredFacet::inner`]'s bound on the rounded
/// orientation, `8ε·(perm·|p − a|)`, is taken at the box's farthest corner
/// from the facet and doubled, and so is the rounding of the crossing's own
/// formula; a crossing `x` then lies within `δ = bound/|n.x|` of the exact
/// one. A plane whose `δ` exceeds a sixteenth of a voxel is treated as
/// level.
struct RowCutter {
    crossings: [Crossing; 4],
    /// The box's index range along `x`.
    lo: usize,
    hi: usize,
    /// The voxel size along `x`.
    sx: f64,
}

/// One row cut by [`RowCutter::cut`]: the centres outside `first..=last`
/// are surely outside the tet; those inside are surely inside, unless
/// within `±δ` of a crossing (or, with `exact_everywhere`, anywhere).
struct RowCut {
    first: usize,
    last: usize,
    /// The largest lower crossing plus its `δ` and the smallest upper
    /// crossing minus its `δ`: surely inside strictly between.
    inside_from: f64,
    inside_to: f64,
    /// A level plane passes too near the row to tell its side: every
    /// centre is tested.
    exact_everywhere: bool,
}

impl RowCut {
    fn surely_inside(&self, x: f64) -> bool {
        x > self.inside_from && x < self.inside_to
    }
}

impl RowCutter {
    fn new(facets: &[FilteredFacet; 4], lo: [usize; 3], hi: [usize; 3], spacing: [f64; 3]) -> Self {
        let centre = |axis: usize, i: usize| (i as f64 + 0.5) * spacing[axis];
        let crossings = facets.each_ref().map(|fc| {
            // Per axis the largest |p − a| over the box's centres.
            let w: [f64; 3] = std::array::from_fn(|axis| {
                let (a, b) = (centre(axis, lo[axis]), centre(axis, hi[axis]));
                (a - fc.a[axis]).abs().max((b - fc.a[axis]).abs())
            });
            let far: [f64; 3] = std::array::from_fn(|axis| {
                centre(axis, lo[axis])
                    .abs()
                    .max(centre(axis, hi[axis]).abs())
            });
            let (n, perm) = (fc.n, fc.perm);
            let orientation_bound = 16.0
                * f64::EPSILON
                * (0..3)
                    .map(|axis| (perm[axis] + n[axis].abs()) * w[axis])
                    .sum::<f64>()
                + 1e-300;
            let (beta, gamma) = (-n.y / n.x, -n.z / n.x);
            let alpha = fc.a.x - beta * fc.a.y - gamma * fc.a.z;
            let formula_bound = 16.0
                * f64::EPSILON
                * (alpha.abs()
                    + fc.a.x.abs()
                    + 2.0 * beta.abs() * (far[1] + fc.a.y.abs())
                    + 2.0 * gamma.abs() * (far[2] + fc.a.z.abs()));
            let delta = orientation_bound / n.x.abs() + formula_bound;
            if delta.is_finite() && delta < spacing[0] / 16.0 {
                if n.x > 0.0 {
                    Crossing::Lower {
                        alpha,
                        beta,
                        gamma,
                        delta,
                    }
                } else {
                    Crossing::Upper {
                        alpha,
                        beta,
                        gamma,
                        delta,
                    }
                }
            } else {
                Crossing::Level {
                    ny: n.y,
                    nz: n.z,
                    ay: fc.a.y,
                    az: fc.a.z,
                    delta: orientation_bound + n.x.abs() * w[0],
                }
            }
        });
        RowCutter {
            crossings,
            lo: lo[0],
            hi: hi[0],
            sx: spacing[0],
        }
    }

    /// The row at `(y, z)` cut by the planes (`None`: it holds no centre
    /// of the tet).
    fn cut(&self, y: f64, z: f64) -> Option<RowCut> {
        let (mut outside_below, mut inside_from) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        let (mut outside_above, mut inside_to) = (f64::INFINITY, f64::INFINITY);
        let mut exact_everywhere = false;
        for crossing in &self.crossings {
            match *crossing {
                Crossing::Lower {
                    alpha,
                    beta,
                    gamma,
                    delta,
                } => {
                    let x = alpha + beta * y + gamma * z;
                    outside_below = outside_below.max(x - delta);
                    inside_from = inside_from.max(x + delta);
                }
                Crossing::Upper {
                    alpha,
                    beta,
                    gamma,
                    delta,
                } => {
                    let x = alpha + beta * y + gamma * z;
                    outside_above = outside_above.min(x + delta);
                    inside_to = inside_to.min(x - delta);
                }
                Crossing::Level {
                    ny,
                    nz,
                    ay,
                    az,
                    delta,
                } => {
                    let r = ny * (y - ay) + nz * (z - az);
                    if r < -delta {
                        return None;
                    }
                    exact_everywhere |= r <= delta;
                }
            }
        }
        // Centre i sits at (i + ½)·sx: the first at or above
        // `outside_below`, the last at or below `outside_above`.
        let first = ceil_index(outside_below / self.sx - 0.5).max(self.lo as i64);
        let last = floor_index(outside_above / self.sx - 0.5).min(self.hi as i64);
        (first <= last).then_some(RowCut {
            first: first as usize,
            last: last as usize,
            inside_from,
            inside_to,
            exact_everywhere,
        })
    }
}

/// `⌈v⌉` as an index (saturating at the ends of `i64`), without a libm call.
#[inline]
fn ceil_index(v: f64) -> i64 {
    let t = v as i64;
    t.saturating_add(i64::from((t as f64) < v))
}

/// `⌊v⌋` as an index (saturating at the ends of `i64`), without a libm call.
#[inline]
fn floor_index(v: f64) -> i64 {
    let t = v as i64;
    t.saturating_sub(i64::from((t as f64) > v))
}

/// One quadrature point of a triangle: position, barycentric weights of the
/// three corners, and the area it stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleSample {
    /// The point.
    pub position: Vector3<f64>,
    /// Barycentric coordinates with respect to the triangle's corners (sum 1).
    pub barycentric: [f64; 3],
    /// The area this sample integrates (the weights sum to the triangle's area).
    pub weight: f64,
}

/// Gaussian quadrature over a triangle with about one sample per `spacing²` of
/// area: the triangle is cut into `m²` similar sub-triangles (`m` the longest
/// edge over `spacing`, rounded up) and the degree-2 three-point rule is used in each.
/// Integrates polynomials of degree two exactly; `f` receives every sample.
pub fn triangle_quadrature(
    corners: &[Vector3<f64>; 3],
    spacing: f64,
    mut f: impl FnMut(TriangleSample),
) {
    let [a, b, c] = *corners;
    let longest = (b - a).norm().max((c - b).norm()).max((a - c).norm());
    let m = ((longest / spacing).ceil() as usize).clamp(1, 64);
    let area = 0.5 * (b - a).cross(&(c - a)).norm();
    let sub_weight = area / (m * m) as f64 / 3.0;
    let mf = m as f64;
    // The degree-2 rule: the three points with barycentric (2/3, 1/6, 1/6) and permutations.
    const RULE: [[f64; 3]; 3] = [
        [2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0],
        [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
        [1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0],
    ];
    let mut emit = |s: [[f64; 2]; 3]| {
        // s: the sub-triangle's corners in the (β, γ) parameter plane.
        for r in RULE {
            let beta = r[0] * s[0][0] + r[1] * s[1][0] + r[2] * s[2][0];
            let gamma = r[0] * s[0][1] + r[1] * s[1][1] + r[2] * s[2][1];
            let alpha = 1.0 - beta - gamma;
            f(TriangleSample {
                position: a * alpha + b * beta + c * gamma,
                barycentric: [alpha, beta, gamma],
                weight: sub_weight,
            });
        }
    };
    for i in 0..m {
        for j in 0..m - i {
            let (x, y) = (i as f64 / mf, j as f64 / mf);
            let d = 1.0 / mf;
            emit([[x, y], [x + d, y], [x, y + d]]);
            if i + j + 1 < m {
                emit([[x + d, y], [x + d, y + d], [x, y + d]]);
            }
        }
    }
}

/// Layer `segment`: which voxels a tetrahedron owns.
impl Complex<D3> {
    /// For every voxel of a `dims` grid the tet that owns its centre, in
    /// x-fastest order (`None` only for voxels outside the complex's domain).
    pub fn voxel_owners(&self, dims: [usize; 3]) -> Vec<Option<CellId>> {
        let mut out = vec![None; dims[0] * dims[1] * dims[2]];
        for c in self.cell_ids() {
            let p = self.cell_points(c);
            tet_voxels(&p, dims, [1.0; 3], |i, j, k| {
                out[i + dims[0] * (j + dims[1] * k)] = Some(c);
            });
        }
        out
    }
}

impl Raster for D3 {
    /// Voxel-centre rule with ties broken by simulation of simplicity
    /// ([`tet_rows`]): each voxel of a tiling is visited exactly once,
    /// whatever lies on shared facets, edges or vertices; one span per row.
    fn cell_spans(image: &ImageView<'_>, c: &[Vector3<f64>], visit: &mut impl FnMut(usize, usize)) {
        let [nx, ny, _] = image.dims;
        let t = [c[0], c[1], c[2], c[3]];
        tet_rows(&t, image.dims, image.spacing, |j, k, xs| {
            let row = nx * (j + ny * k);
            visit(row + xs.start, row + xs.end)
        });
    }

    /// Degree-2 Gaussian quadrature on about `spacing²`-sized sub-triangles
    /// ([`triangle_quadrature`]).
    fn facet_samples(
        c: &[Vector3<f64>],
        spacing: f64,
        visit: &mut impl FnMut(Vector3<f64>, &[f64], f64),
    ) {
        let t = [c[0], c[1], c[2]];
        triangle_quadrature(&t, spacing, |s| visit(s.position, &s.barycentric, s.weight));
    }

    fn sample(image: &ImageView<'_>, p: Vector3<f64>) -> f64 {
        let mut lower = [0usize; 3];
        let mut upper = [0usize; 3];
        let mut t = [0.0; 3];
        for axis in 0..3 {
            let n = image.dims[axis];
            let x = (p[axis] / image.spacing[axis] - 0.5).clamp(0.0, (n - 1) as f64);
            // (truncation: the floor of a non-negative value)
            lower[axis] = (x as usize).min(n - 1);
            upper[axis] = (lower[axis] + 1).min(n - 1);
            t[axis] = x - lower[axis] as f64;
        }
        let [nx, ny, _] = image.dims;
        let voxel = |i: usize, j: usize, k: usize| image.data[i + nx * (j + ny * k)] as f64;
        let [xs, ys, zs] = [0, 1, 2].map(|axis| [lower[axis], upper[axis]]);
        let [wx, wy, wz] = t.map(|t| [1.0 - t, t]);
        // The eight corners x fastest, each weight the product of its
        // axes' in x, y, z order; a corner of weight 0 is skipped (its
        // voxel is outside the interpolation's cell at a border).
        let mut out = 0.0;
        for (&k, &fz) in zs.iter().zip(&wz) {
            for (&j, &fy) in ys.iter().zip(&wy) {
                for (&i, &fx) in xs.iter().zip(&wx) {
                    let w = fx * fy * fz;
                    if w != 0.0 {
                        out += w * voxel(i, j, k);
                    }
                }
            }
        }
        out
    }

    fn pixel_centre(image: &ImageView<'_>, index: usize) -> Vector3<f64> {
        let [nx, ny, _] = image.dims;
        let [sx, sy, sz] = image.spacing;
        Vector3::new(
            ((index % nx) as f64 + 0.5) * sx,
            (((index / nx) % ny) as f64 + 0.5) * sy,
            ((index / (nx * ny)) as f64 + 0.5) * sz,
        )
    }

    fn box_complex(image: &ImageView<'_>, l: f64) -> Result<Complex<D3>, BuildError> {
        Complex::cuboid(image.extent(), l)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::complex::VertexId;

    /// Counts, for every voxel, how many tets claim it.
    fn claims(c: &Complex<D3>, dims: [usize; 3]) -> Vec<u32> {
        claims_spaced(c, dims, [1.0; 3])
    }

    fn claims_spaced(c: &Complex<D3>, dims: [usize; 3], spacing: [f64; 3]) -> Vec<u32> {
        let mut n = vec![0u32; dims[0] * dims[1] * dims[2]];
        for t in c.cell_ids() {
            tet_voxels(&c.cell_points(t), dims, spacing, |i, j, k| {
                n[i + dims[0] * (j + dims[1] * k)] += 1;
            });
        }
        n
    }

    #[test]
    fn centres_on_shared_edges_are_counted_once() {
        // Spacing 1: every voxel centre lies on the main diagonal of its Kuhn
        // cube, the edge shared by all six tets of the cube.
        let c = Complex::cuboid([8.0, 8.0, 8.0], 1.24).unwrap();
        assert_eq!(c.cell_count(), 6 * 8 * 8 * 8);
        assert!(claims(&c, [8, 8, 8]).iter().all(|&n| n == 1));
    }

    #[test]
    fn centres_on_shared_vertices_are_counted_once() {
        // Spacing ½: every voxel centre is a grid vertex shared by 24 tets.
        let c = Complex::cuboid([6.0, 5.0, 4.0], 0.62).unwrap();
        assert!(claims(&c, [6, 5, 4]).iter().all(|&n| n == 1));
    }

    #[test]
    fn centres_are_counted_once_in_a_deformed_complex() {
        use rand::{Rng, SeedableRng};
        let mut c = Complex::cuboid([12.0, 10.0, 9.0], 2.0).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut star = Vec::new();
        let ids: Vec<VertexId> = c.vertex_ids().collect();
        for v in ids {
            // Snap some vertices onto voxel centres, jitter the rest.
            let p = c.position(v);
            let q = if rng.random_bool(0.5) {
                p.map(|x| x.floor() + 0.5)
            } else {
                p + Vector3::new(
                    rng.random_range(-0.8..0.8),
                    rng.random_range(-0.8..0.8),
                    rng.random_range(-0.8..0.8),
                )
            };
            c.move_towards(v, q, 1e-6, &mut star);
        }
        assert!(c.validate().is_empty());
        let n = claims(&c, [12, 10, 9]);
        assert!(n.iter().all(|&k| k == 1), "counts {:?}", {
            let mut h = [0usize; 4];
            n.iter().for_each(|&k| h[(k as usize).min(3)] += 1);
            h
        });
        let owners = c.voxel_owners([12, 10, 9]);
        assert!(owners.iter().all(Option::is_some));
    }

    #[test]
    fn anisotropic_voxel_centres_are_counted_once() {
        use rand::{Rng, SeedableRng};
        // 10 × 8 × 6 voxels of 0.3 × 0.7 × 2.1: the domain is 3 × 5.6 × 12.6.
        let spacing = [0.3, 0.7, 2.1];
        let dims = [10, 8, 6];
        let mut c = Complex::cuboid([3.0, 5.6, 12.6], 1.5).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut star = Vec::new();
        let ids: Vec<VertexId> = c.vertex_ids().collect();
        for v in ids {
            // Snap some vertices onto voxel centres, jitter the rest.
            let p = c.position(v);
            let q = if rng.random_bool(0.5) {
                let idx = std::array::from_fn(|a| (p[a] / spacing[a]).floor().max(0.0) as usize);
                voxel_centre(idx, spacing)
            } else {
                p + Vector3::new(
                    rng.random_range(-0.2..0.2),
                    rng.random_range(-0.4..0.4),
                    rng.random_range(-1.0..1.0),
                )
            };
            c.move_towards(v, q, 1e-6, &mut star);
        }
        assert!(c.validate().is_empty());
        let n = claims_spaced(&c, dims, spacing);
        assert!(n.iter().all(|&k| k == 1));
    }

    #[test]
    fn tet_voxels_decides_as_tet_owns() {
        // Random tets with corners on voxel centres, on planes through them,
        // on shared coordinates (facets parallel to the rows) or anywhere,
        // with cubic and anisotropic voxels: the row scan claims exactly the
        // centres tet_owns does.
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let dims = [9, 8, 7];
        for spacing in [[1.0; 3], [0.3, 0.7, 2.1]] {
            let extent: [f64; 3] = std::array::from_fn(|a| dims[a] as f64 * spacing[a]);
            let mut tested = 0;
            while tested < 3000 {
                let mut t = [Vector3::zeros(); 4];
                for p in &mut t {
                    *p = Vector3::from_fn(|a, _| rng.random_range(0.0..extent[a]));
                    let on_centre =
                        |x: f64, a: usize| ((x / spacing[a]).floor() + 0.5) * spacing[a];
                    match rng.random_range(0..3) {
                        0 => *p = Vector3::from_fn(|a, _| on_centre(p[a], a)),
                        1 => p.x = on_centre(p.x, 0),
                        _ => {}
                    }
                }
                if rng.random_bool(0.2) {
                    // Two corners share y and z: a facet parallel to the rows.
                    (t[1].y, t[1].z) = (t[0].y, t[0].z);
                }
                let o = orient(&t[0], &t[1], &t[2], &t[3]);
                if o == 0.0 {
                    continue;
                }
                if o < 0.0 {
                    t.swap(0, 1);
                }
                let mut fast = Vec::new();
                tet_voxels(&t, dims, spacing, |i, j, k| fast.push((i, j, k)));
                let mut brute = Vec::new();
                for k in 0..dims[2] {
                    for j in 0..dims[1] {
                        for i in 0..dims[0] {
                            if tet_owns(&t, &voxel_centre([i, j, k], spacing)) {
                                brute.push((i, j, k));
                            }
                        }
                    }
                }
                assert_eq!(fast, brute, "tet {t:?}, spacing {spacing:?}");
                tested += 1;
            }
        }
    }

    #[test]
    fn index_rounding_matches_floor_and_ceil_and_saturates() {
        for v in [-2.5, -2.0, -0.5, -0.0, 0.0, 0.3, 1.0, 7.999, 1e13 + 0.5] {
            assert_eq!(ceil_index(v), v.ceil() as i64, "{v}");
            assert_eq!(floor_index(v), v.floor() as i64, "{v}");
        }
        for v in [f64::INFINITY, 1e300] {
            assert_eq!((ceil_index(v), floor_index(v)), (i64::MAX, i64::MAX));
            assert_eq!((ceil_index(-v), floor_index(-v)), (i64::MIN, i64::MIN));
        }
    }

    #[test]
    fn quadrature_integrates_quadratics_exactly() {
        let t = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(3.0, 0.5, 0.2),
            Vector3::new(0.4, 2.0, 1.0),
        ];
        let f = |p: Vector3<f64>| 1.0 + p.x * p.y - 2.0 * p.z * p.z + p.y;
        let integrate = |spacing: f64| {
            let mut sum = 0.0;
            let mut weights = 0.0;
            let mut bary_ok = true;
            triangle_quadrature(&t, spacing, |s| {
                sum += s.weight * f(s.position);
                weights += s.weight;
                let back =
                    t[0] * s.barycentric[0] + t[1] * s.barycentric[1] + t[2] * s.barycentric[2];
                bary_ok &= (back - s.position).norm() < 1e-12;
            });
            assert!(bary_ok);
            (sum, weights)
        };
        let area = 0.5 * (t[1] - t[0]).cross(&(t[2] - t[0])).norm();
        let (coarse, w1) = integrate(10.0);
        let (fine, w2) = integrate(0.3);
        assert!((w1 - area).abs() < 1e-12 && (w2 - area).abs() < 1e-12);
        assert!(
            (coarse - fine).abs() < 1e-10 * coarse.abs(),
            "{coarse} vs {fine}"
        );
    }

    /// Trilinear interpolation written corner by corner, each weight
    /// built axis by axis: the definition [`D3::sample`] evaluates with its
    /// loops unrolled.
    fn sample_by_corners(image: &ImageView<'_>, p: Vector3<f64>) -> f64 {
        let mut i0 = [0usize; 3];
        let mut i1 = [0usize; 3];
        let mut t = [0.0; 3];
        for axis in 0..3 {
            let n = image.dims[axis];
            let x = (p[axis] / image.spacing[axis] - 0.5).clamp(0.0, (n - 1) as f64);
            i0[axis] = (x as usize).min(n - 1);
            i1[axis] = (i0[axis] + 1).min(n - 1);
            t[axis] = x - i0[axis] as f64;
        }
        let [nx, ny, _] = image.dims;
        let mut out = 0.0;
        for corner in 0..8usize {
            let mut w = 1.0;
            let mut idx = [0usize; 3];
            for axis in 0..3 {
                let upper = corner >> axis & 1 == 1;
                w *= if upper { t[axis] } else { 1.0 - t[axis] };
                idx[axis] = if upper { i1[axis] } else { i0[axis] };
            }
            if w != 0.0 {
                out += w * image.data[idx[0] + nx * (idx[1] + ny * idx[2])] as f64;
            }
        }
        out
    }

    #[test]
    fn trilinear_samples_are_the_corner_sums_to_the_bit() {
        use rand::{Rng, SeedableRng};
        let dims = [7, 5, 6];
        let data: Vec<f32> = (0..7 * 5 * 6)
            .map(|i| ((i * 7919) % 1009) as f32 / 1009.0 - 0.3)
            .collect();
        let spaced = ImageView::new_3d(dims, &data)
            .unwrap()
            .with_spacing([1.0, 0.7, 1.3])
            .unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for image in [ImageView::new_3d(dims, &data).unwrap(), spaced] {
            let extent = [0, 1, 2].map(|a| dims[a] as f64 * image.spacing[a]);
            for n in 0..4000 {
                // inside, on voxel centres and beyond the border
                let p = Vector3::from_fn(|a, _| match n % 4 {
                    0 => (rng.random_range(0..dims[a]) as f64 + 0.5) * image.spacing[a],
                    1 => rng.random_range(-1.0..extent[a] + 1.0),
                    _ => rng.random_range(0.0..extent[a]),
                });
                assert_eq!(
                    D3::sample(&image, p).to_bits(),
                    sample_by_corners(&image, p).to_bits(),
                    "at {p:?}"
                );
            }
        }
    }
}
