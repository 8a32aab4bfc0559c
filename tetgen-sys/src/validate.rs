//! Input validation with exact geometric predicates.
//!
//! Debian's TetGen 1.5.0 may crash instead of reporting an error on invalid
//! input, so everything TetGen cannot handle is rejected here first.

use crate::{check_volume, Plc, TetgenError};

type P = [f64; 3];

/// Largest accepted coordinate magnitude: keeps the exact predicates of the
/// `robust` crate far away from overflow.
const MAX_COORD: f64 = 1e100;

/// Checks that `plc` is something TetGen can safely tetrahedralise.
///
/// In order, it checks:
/// 1. there is at least one point and one triangle, and the counts fit
///    TetGen's `int` indices;
/// 2. every coordinate is finite with magnitude at most `1e100`;
/// 3. every triangle index is in range;
/// 4. no triangle is degenerate (repeated vertex, or zero area, tested
///    exactly);
/// 5. no two points have identical coordinates and every point is used;
/// 6. no two triangles have the same vertex set;
/// 7. every edge is shared by exactly two triangles (closed, edge-manifold);
/// 8. no two triangles intersect, except that triangles sharing an edge may
///    meet only in that edge and triangles sharing one vertex only in that
///    vertex (exact predicates; a uniform grid prunes the candidate pairs);
/// 9. every region has a finite seed that lies strictly inside the domain
///    (inside some shell of the surface, not on it; TetGen 1.5.0 segfaults on
///    seeds outside the surface) and a valid volume bound.
///
/// # Errors
///
/// The first violated condition, as the matching [`TetgenError`] variant.
pub fn validate_plc(plc: &Plc) -> Result<(), TetgenError> {
    let pts = &plc.points;
    let tris = &plc.triangles;
    if pts.is_empty() || tris.is_empty() {
        return Err(TetgenError::EmptyInput);
    }
    let limit = i32::MAX as usize / 5;
    if pts.len() > limit || tris.len() > limit || plc.regions.len() > limit {
        return Err(TetgenError::TooLarge(format!(
            "{} points, {} triangles, {} regions (at most {limit} each)",
            pts.len(),
            tris.len(),
            plc.regions.len()
        )));
    }
    for (i, p) in pts.iter().enumerate() {
        if !p.iter().all(|x| x.is_finite() && x.abs() <= MAX_COORD) {
            return Err(TetgenError::InvalidCoordinate { point: i });
        }
    }
    for (t, tri) in tris.iter().enumerate() {
        for &i in tri {
            if i as usize >= pts.len() {
                return Err(TetgenError::IndexOutOfRange {
                    triangle: t,
                    index: i,
                    num_points: pts.len(),
                });
            }
        }
    }
    for (t, &[a, b, c]) in tris.iter().enumerate() {
        if a == b
            || b == c
            || a == c
            || projection_axis(pts[a as usize], pts[b as usize], pts[c as usize]).is_none()
        {
            return Err(TetgenError::DegenerateTriangle { triangle: t });
        }
    }
    check_points(plc)?;
    check_duplicate_triangles(tris)?;
    check_manifold_edges(tris)?;
    check_self_intersections(pts, tris)?;
    check_regions(plc)
}

/// No duplicate coordinates, no unused points.
fn check_points(plc: &Plc) -> Result<(), TetgenError> {
    // `+ 0.0` turns -0.0 into +0.0 so equal coordinates sort together.
    let key = |i: usize| plc.points[i].map(|x| x + 0.0);
    let mut order: Vec<usize> = (0..plc.points.len()).collect();
    order.sort_by(|&i, &j| {
        let (a, b) = (key(i), key(j));
        a[0].total_cmp(&b[0])
            .then(a[1].total_cmp(&b[1]))
            .then(a[2].total_cmp(&b[2]))
            .then(i.cmp(&j))
    });
    for w in order.windows(2) {
        if key(w[0]) == key(w[1]) {
            return Err(TetgenError::DuplicatePoint {
                first: w[0].min(w[1]),
                second: w[0].max(w[1]),
            });
        }
    }
    let mut used = vec![false; plc.points.len()];
    for tri in &plc.triangles {
        for &i in tri {
            used[i as usize] = true;
        }
    }
    if let Some(point) = used.iter().position(|&u| !u) {
        return Err(TetgenError::UnusedPoint { point });
    }
    Ok(())
}

fn sorted3(t: [u32; 3]) -> [u32; 3] {
    let mut s = t;
    s.sort_unstable();
    s
}

fn check_duplicate_triangles(tris: &[[u32; 3]]) -> Result<(), TetgenError> {
    let mut keyed: Vec<([u32; 3], usize)> = tris
        .iter()
        .enumerate()
        .map(|(i, &t)| (sorted3(t), i))
        .collect();
    keyed.sort_unstable();
    for w in keyed.windows(2) {
        if w[0].0 == w[1].0 {
            return Err(TetgenError::DuplicateTriangle {
                first: w[0].1,
                second: w[1].1,
            });
        }
    }
    Ok(())
}

fn check_manifold_edges(tris: &[[u32; 3]]) -> Result<(), TetgenError> {
    let mut edges: Vec<[u32; 2]> = Vec::with_capacity(3 * tris.len());
    for &[a, b, c] in tris {
        for (u, v) in [(a, b), (b, c), (c, a)] {
            edges.push([u.min(v), u.max(v)]);
        }
    }
    edges.sort_unstable();
    let mut start = 0;
    while start < edges.len() {
        let mut end = start + 1;
        while end < edges.len() && edges[end] == edges[start] {
            end += 1;
        }
        if end - start != 2 {
            return Err(TetgenError::NonManifoldEdge {
                edge: edges[start],
                count: end - start,
            });
        }
        start = end;
    }
    Ok(())
}

fn check_regions(plc: &Plc) -> Result<(), TetgenError> {
    for (r, region) in plc.regions.iter().enumerate() {
        let invalid = |reason: String| TetgenError::InvalidRegion { region: r, reason };
        let s = region.seed;
        if !s.iter().all(|x| x.is_finite() && x.abs() <= MAX_COORD) {
            return Err(invalid(format!(
                "seed {s:?} must be finite with |x| <= 1e100"
            )));
        }
        if let Some(v) = region.max_volume {
            check_volume(v).map_err(invalid)?;
        }
        for (t, &tri) in plc.triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|i| plc.points[i as usize]);
            if point_in_triangle(s, a, b, c) {
                return Err(invalid(format!("seed {s:?} lies on triangle {t}")));
            }
        }
        match inside_domain(plc, s) {
            Some(true) => {}
            Some(false) => {
                return Err(invalid(format!(
                    "seed {s:?} lies outside the surface (TetGen 1.5.0 crashes on such seeds)"
                )))
            }
            None => {
                return Err(invalid(format!(
                    "could not classify seed {s:?} as inside or outside the surface"
                )))
            }
        }
    }
    Ok(())
}

/// Whether `s` (not on the surface) lies in the domain TetGen meshes: the
/// union of the interiors of the surface's connected components (shells).
///
/// Uses exact ray-crossing parity per shell along a segment from `s` to a
/// point beyond the bounding box. If the segment touches an edge, a vertex or
/// lies in a triangle's plane, another direction is tried. `None` if every
/// try was degenerate (practically impossible).
fn inside_domain(plc: &Plc, s: P) -> Option<bool> {
    let pts = &plc.points;
    let tris = &plc.triangles;

    // Shells: connected components of points joined by triangle edges.
    let mut parent: Vec<usize> = (0..pts.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for t in tris {
        let r0 = root(&mut parent, t[0] as usize);
        for &i in &t[1..] {
            let r = root(&mut parent, i as usize);
            parent[r] = r0;
        }
    }
    let shell: Vec<usize> = tris
        .iter()
        .map(|t| root(&mut parent, t[0] as usize))
        .collect();

    let mut lo = pts[0];
    let mut hi = pts[0];
    for p in pts {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let span = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max).max(1.0);
    // Small deterministic pseudo-random sequence for the ray targets.
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    'attempt: for _ in 0..64 {
        // A target beyond the bounding box in +x, hence outside every shell.
        let q = [
            hi[0].max(s[0]) + span * (1.0 + next()),
            lo[1] + span * (3.0 * next() - 1.0),
            lo[2] + span * (3.0 * next() - 1.0),
        ];
        let mut odd = vec![false; pts.len()];
        for (t, tri) in tris.iter().enumerate() {
            let [a, b, c] = tri.map(|i| pts[i as usize]);
            match crossing(s, q, a, b, c) {
                Crossing::Miss => {}
                Crossing::Cross => odd[shell[t]] ^= true,
                Crossing::Degenerate => continue 'attempt,
            }
        }
        return Some(odd.iter().any(|&o| o));
    }
    None
}

enum Crossing {
    Miss,
    Cross,
    Degenerate,
}

/// Classifies how the segment `sq` meets triangle `abc`, where neither `s`
/// nor `q` lies on the triangle.
fn crossing(s: P, q: P, a: P, b: P, c: P) -> Crossing {
    let os = orient3d(a, b, c, s);
    let oq = orient3d(a, b, c, q);
    if os == 0.0 && oq == 0.0 {
        return Crossing::Degenerate;
    }
    // Meets the plane at most in an endpoint, which is off the triangle.
    if os == 0.0 || oq == 0.0 || (os > 0.0) == (oq > 0.0) {
        return Crossing::Miss;
    }
    let s1 = orient3d(s, q, a, b);
    let s2 = orient3d(s, q, b, c);
    let s3 = orient3d(s, q, c, a);
    let neg = s1 < 0.0 || s2 < 0.0 || s3 < 0.0;
    let pos = s1 > 0.0 || s2 > 0.0 || s3 > 0.0;
    if neg && pos {
        Crossing::Miss
    } else if s1 == 0.0 || s2 == 0.0 || s3 == 0.0 {
        Crossing::Degenerate
    } else {
        Crossing::Cross
    }
}

// ---------------------------------------------------------------------------
// Exact predicates
// ---------------------------------------------------------------------------

fn c3(p: P) -> robust::Coord3D<f64> {
    robust::Coord3D {
        x: p[0],
        y: p[1],
        z: p[2],
    }
}

/// Shewchuk's exact orient3d: positive if `d` lies *below* the plane through
/// `a, b, c` (where `a, b, c` appear counter-clockwise from above), i.e. the
/// negative of the right-handed signed volume.
pub(crate) fn orient3d(a: P, b: P, c: P, d: P) -> f64 {
    robust::orient3d(c3(a), c3(b), c3(c), c3(d))
}

/// Projects `p` onto the coordinate plane orthogonal to `axis`.
fn proj(p: P, axis: usize) -> robust::Coord<f64> {
    let (x, y) = match axis {
        0 => (p[1], p[2]),
        1 => (p[2], p[0]),
        _ => (p[0], p[1]),
    };
    robust::Coord { x, y }
}

fn orient2(a: P, b: P, c: P, axis: usize) -> f64 {
    robust::orient2d(proj(a, axis), proj(b, axis), proj(c, axis))
}

/// An axis along which the triangle projects to a non-degenerate triangle,
/// or `None` if the points are collinear (the three projected orientations
/// are exactly the components of `(b - a) × (c - a)`).
fn projection_axis(a: P, b: P, c: P) -> Option<usize> {
    (0..3).find(|&axis| orient2(a, b, c, axis) != 0.0)
}

/// True if `x` is zero or has the same sign as the non-zero `s`.
fn agrees(x: f64, s: f64) -> bool {
    x == 0.0 || (x > 0.0) == (s > 0.0)
}

/// Whether `p` (in the plane of the triangle) lies in the closed triangle.
fn point_in_triangle_2d(p: P, a: P, b: P, c: P, axis: usize) -> bool {
    let d1 = orient2(a, b, p, axis);
    let d2 = orient2(b, c, p, axis);
    let d3 = orient2(c, a, p, axis);
    let neg = d1 < 0.0 || d2 < 0.0 || d3 < 0.0;
    let pos = d1 > 0.0 || d2 > 0.0 || d3 > 0.0;
    !(neg && pos)
}

/// Whether `p` lies in the closed 3-D triangle `abc` (non-degenerate).
fn point_in_triangle(p: P, a: P, b: P, c: P) -> bool {
    for k in 0..3 {
        let lo = a[k].min(b[k]).min(c[k]);
        let hi = a[k].max(b[k]).max(c[k]);
        if p[k] < lo || p[k] > hi {
            return false;
        }
    }
    if orient3d(a, b, c, p) != 0.0 {
        return false;
    }
    let axis = projection_axis(a, b, c).expect("non-degenerate triangle");
    point_in_triangle_2d(p, a, b, c, axis)
}

/// For `r` collinear with `p, q`: whether `r` lies on the closed segment.
fn on_segment_2d(p: P, q: P, r: P, axis: usize) -> bool {
    let (p, q, r) = (proj(p, axis), proj(q, axis), proj(r, axis));
    p.x.min(q.x) <= r.x && r.x <= p.x.max(q.x) && p.y.min(q.y) <= r.y && r.y <= p.y.max(q.y)
}

/// Closed segment–segment intersection in the projection along `axis`.
fn segments_intersect_2d(p: P, q: P, r: P, s: P, axis: usize) -> bool {
    let d1 = orient2(p, q, r, axis);
    let d2 = orient2(p, q, s, axis);
    let d3 = orient2(r, s, p, axis);
    let d4 = orient2(r, s, q, axis);
    let straddles = |x: f64, y: f64| (x > 0.0 && y < 0.0) || (x < 0.0 && y > 0.0);
    if straddles(d1, d2) && straddles(d3, d4) {
        return true;
    }
    (d1 == 0.0 && on_segment_2d(p, q, r, axis))
        || (d2 == 0.0 && on_segment_2d(p, q, s, axis))
        || (d3 == 0.0 && on_segment_2d(r, s, p, axis))
        || (d4 == 0.0 && on_segment_2d(r, s, q, axis))
}

/// Whether the closed segment `pq` meets the closed, non-degenerate triangle
/// `abc`.
fn segment_meets_triangle(p: P, q: P, a: P, b: P, c: P) -> bool {
    let op = orient3d(a, b, c, p);
    let oq = orient3d(a, b, c, q);
    if (op > 0.0 && oq > 0.0) || (op < 0.0 && oq < 0.0) {
        return false;
    }
    if op == 0.0 && oq == 0.0 {
        let axis = projection_axis(a, b, c).expect("non-degenerate triangle");
        return point_in_triangle_2d(p, a, b, c, axis)
            || point_in_triangle_2d(q, a, b, c, axis)
            || segments_intersect_2d(p, q, a, b, axis)
            || segments_intersect_2d(p, q, b, c, axis)
            || segments_intersect_2d(p, q, c, a, axis);
    }
    // The segment reaches the plane in exactly one point; it lies in the
    // triangle iff the line pq does not pass strictly outside any edge.
    let s1 = orient3d(p, q, a, b);
    let s2 = orient3d(p, q, b, c);
    let s3 = orient3d(p, q, c, a);
    let neg = s1 < 0.0 || s2 < 0.0 || s3 < 0.0;
    let pos = s1 > 0.0 || s2 > 0.0 || s3 > 0.0;
    !(neg && pos)
}

/// Whether the ray from vertex `v` of triangle `v c d` towards `a` enters the
/// triangle, i.e. the segment `va` meets the triangle in more than `v`.
fn direction_in_corner(v: P, a: P, c: P, d: P) -> bool {
    if orient3d(v, c, d, a) != 0.0 {
        return false;
    }
    let axis = projection_axis(v, c, d).expect("non-degenerate triangle");
    let s = orient2(v, c, d, axis);
    agrees(orient2(v, c, a, axis), s) && agrees(orient2(v, a, d, axis), s)
}

/// Whether two distinct, non-degenerate surface triangles intersect in more
/// than what they share combinatorially (a common vertex or edge). Points
/// with distinct indices are assumed to be distinct.
fn triangles_conflict(pts: &[P], t1: [u32; 3], t2: [u32; 3]) -> bool {
    let p = |i: u32| pts[i as usize];
    let shared: Vec<u32> = t1.iter().copied().filter(|i| t2.contains(i)).collect();
    match shared.len() {
        0 => {
            let [a, b, c] = t1.map(p);
            let [d, e, f] = t2.map(p);
            [(a, b), (b, c), (c, a)]
                .iter()
                .any(|&(x, y)| segment_meets_triangle(x, y, d, e, f))
                || [(d, e), (e, f), (f, d)]
                    .iter()
                    .any(|&(x, y)| segment_meets_triangle(x, y, a, b, c))
        }
        1 => {
            let v = shared[0];
            let others = |t: [u32; 3]| {
                let o: Vec<u32> = t.iter().copied().filter(|&i| i != v).collect();
                (p(o[0]), p(o[1]))
            };
            let pv = p(v);
            let (a, b) = others(t1);
            let (c, d) = others(t2);
            segment_meets_triangle(a, b, pv, c, d)
                || segment_meets_triangle(c, d, pv, a, b)
                || direction_in_corner(pv, a, c, d)
                || direction_in_corner(pv, b, c, d)
                || direction_in_corner(pv, c, a, b)
                || direction_in_corner(pv, d, a, b)
        }
        2 => {
            // Non-coplanar triangles sharing an edge meet only in that edge;
            // coplanar ones overlap iff the free vertices are on the same side.
            let (u, w) = (p(shared[0]), p(shared[1]));
            let free = |t: [u32; 3]| p(*t.iter().find(|i| !shared.contains(i)).unwrap());
            let (a, b) = (free(t1), free(t2));
            if orient3d(u, w, a, b) != 0.0 {
                return false;
            }
            let axis = projection_axis(u, w, a).expect("non-degenerate triangle");
            let sa = orient2(u, w, a, axis);
            let sb = orient2(u, w, b, axis);
            (sa > 0.0) == (sb > 0.0)
        }
        _ => true,
    }
}

// ---------------------------------------------------------------------------
// Broad phase
// ---------------------------------------------------------------------------

struct Grid {
    lo: P,
    h: f64,
    dims: [usize; 3],
}

impl Grid {
    fn cell(&self, x: f64, k: usize) -> usize {
        let c = ((x - self.lo[k]) / self.h).floor();
        if c <= 0.0 {
            0
        } else {
            (c as usize).min(self.dims[k] - 1)
        }
    }

    fn range(&self, b: &(P, P)) -> ([usize; 3], [usize; 3]) {
        let lo = [0, 1, 2].map(|k| self.cell(b.0[k], k));
        let hi = [0, 1, 2].map(|k| self.cell(b.1[k], k));
        (lo, hi)
    }
}

fn check_self_intersections(pts: &[P], tris: &[[u32; 3]]) -> Result<(), TetgenError> {
    let boxes: Vec<(P, P)> = tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| pts[i as usize]);
            let lo = [0, 1, 2].map(|k| a[k].min(b[k]).min(c[k]));
            let hi = [0, 1, 2].map(|k| a[k].max(b[k]).max(c[k]));
            (lo, hi)
        })
        .collect();
    let mut lo = boxes[0].0;
    let mut hi = boxes[0].1;
    let mut size_sum = 0.0;
    for (l, h) in &boxes {
        for k in 0..3 {
            lo[k] = lo[k].min(l[k]);
            hi[k] = hi[k].max(h[k]);
        }
        size_sum += (0..3).map(|k| h[k] - l[k]).fold(0.0, f64::max);
    }
    let n = tris.len();
    let max_cells = 4 * n + 8;
    let mut h = (size_sum / n as f64).max(f64::MIN_POSITIVE);
    let dims = loop {
        let dims = [0, 1, 2].map(|k| (((hi[k] - lo[k]) / h).ceil() as usize).clamp(1, max_cells));
        if dims
            .iter()
            .try_fold(1usize, |acc, &d| acc.checked_mul(d))
            .is_some_and(|c| c <= max_cells)
        {
            break dims;
        }
        h *= 1.5;
    };
    let grid = Grid { lo, h, dims };
    let index = |c: [usize; 3]| (c[2] * dims[1] + c[1]) * dims[0] + c[0];
    let num_cells = dims[0] * dims[1] * dims[2];

    // Bucket triangles into cells (CSR layout).
    let ranges: Vec<([usize; 3], [usize; 3])> = boxes.iter().map(|b| grid.range(b)).collect();
    let for_cells = |r: &([usize; 3], [usize; 3]), f: &mut dyn FnMut(usize)| {
        for z in r.0[2]..=r.1[2] {
            for y in r.0[1]..=r.1[1] {
                for x in r.0[0]..=r.1[0] {
                    f(index([x, y, z]));
                }
            }
        }
    };
    let mut start = vec![0usize; num_cells + 1];
    for r in &ranges {
        for_cells(r, &mut |c| start[c + 1] += 1);
    }
    for c in 0..num_cells {
        start[c + 1] += start[c];
    }
    let mut fill = start.clone();
    let mut entries = vec![0usize; start[num_cells]];
    for (t, r) in ranges.iter().enumerate() {
        for_cells(r, &mut |c| {
            entries[fill[c]] = t;
            fill[c] += 1;
        });
    }

    let overlap = |i: usize, j: usize| {
        let (a, b) = (&boxes[i], &boxes[j]);
        (0..3).all(|k| a.0[k] <= b.1[k] && b.0[k] <= a.1[k])
    };
    let mut found: Option<(usize, usize)> = None;
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let c = index([x, y, z]);
                let cell = &entries[start[c]..start[c + 1]];
                for (k, &i) in cell.iter().enumerate() {
                    for &j in &cell[k + 1..] {
                        if !overlap(i, j) {
                            continue;
                        }
                        // Test each pair once: in the first cell they share.
                        let first = [0, 1, 2].map(|d| ranges[i].0[d].max(ranges[j].0[d]));
                        if first != [x, y, z] {
                            continue;
                        }
                        if triangles_conflict(pts, tris[i], tris[j]) {
                            let pair = (i.min(j), i.max(j));
                            if found.map_or(true, |f| pair < f) {
                                found = Some(pair);
                            }
                        }
                    }
                }
            }
        }
    }
    match found {
        Some((first, second)) => Err(TetgenError::SelfIntersection { first, second }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_through_triangle() {
        let (a, b, c) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        assert!(segment_meets_triangle(
            [0.2, 0.2, -1.0],
            [0.2, 0.2, 1.0],
            a,
            b,
            c
        ));
        assert!(!segment_meets_triangle(
            [0.8, 0.8, -1.0],
            [0.8, 0.8, 1.0],
            a,
            b,
            c
        ));
        // Touching the edge counts.
        assert!(segment_meets_triangle(
            [0.5, 0.5, -1.0],
            [0.5, 0.5, 1.0],
            a,
            b,
            c
        ));
        // Coplanar crossing.
        assert!(segment_meets_triangle(
            [-1.0, 0.2, 0.0],
            [2.0, 0.2, 0.0],
            a,
            b,
            c
        ));
        assert!(!segment_meets_triangle(
            [-1.0, 2.0, 0.0],
            [2.0, 2.0, 0.0],
            a,
            b,
            c
        ));
    }

    #[test]
    fn shared_vertex_and_edge_cases() {
        let pts = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.5, 0.5, 1.0],
        ];
        // Opposite corners meeting in vertex 0: fine.
        assert!(!triangles_conflict(&pts, [0, 1, 2], [0, 3, 4]));
        // Coplanar overlapping corners at vertex 0.
        assert!(triangles_conflict(&pts, [0, 1, 2], [0, 5, 3]));
        // Flat fold over shared edge 1-2: 0 and 5 on opposite sides -> fine.
        assert!(!triangles_conflict(&pts, [0, 1, 2], [1, 2, 5]));
        // Folded back onto itself: 0 and 3... use [1, 2, 3]? 3 is on 0's side.
        assert!(triangles_conflict(&pts, [0, 1, 2], [1, 2, 3]));
        // Non-coplanar sharing an edge.
        assert!(!triangles_conflict(&pts, [0, 1, 2], [1, 2, 6]));
    }
}
