//! Construction: from arrays, regular box meshes at an edge length, and (2D)
//! meshes conforming to user polygons.

use super::bookkeeping::Bookkeeping;
use super::cavity::{facet_key, FacetKey};
use super::{CellId, Complex, Label, Slot, VertexClass, VertexId, VertexKind};
use crate::dim::{Dim, Point, D2, D3};
use nalgebra::{Vector2, Vector3};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};
use thiserror::Error;

/// Why a complex could not be built from the given data.
#[derive(Debug, Error, PartialEq)]
pub enum BuildError {
    /// The domain box is empty, inverted or not finite.
    #[error("the domain box must have finite, positive extent")]
    BadDomain,
    /// The edge length is not a positive finite number or too large for the domain.
    #[error("edge length {0} must be positive, finite and no larger than the domain")]
    BadEdgeLength(f64),
    /// A cell references a vertex that does not exist.
    #[error("cell {cell} references vertex {vertex}, but there are only {count} vertices")]
    VertexOutOfRange {
        /// The cell index.
        cell: usize,
        /// The bad vertex index.
        vertex: u32,
        /// The number of vertices.
        count: usize,
    },
    /// A cell is degenerate (zero measure) or a point is not finite.
    #[error("cell {0} is degenerate")]
    Degenerate(usize),
    /// More than two cells share one facet.
    #[error("facet shared by more than two cells (cell {0})")]
    NonManifold(usize),
    /// The cells and labels arrays differ in length.
    #[error("{cells} cells but {labels} labels")]
    LabelCount {
        /// Number of cells.
        cells: usize,
        /// Number of labels.
        labels: usize,
    },
    /// A polygon had fewer than three points or a non-finite coordinate.
    #[error("polygon {0} needs at least three finite points")]
    BadPolygon(usize),
    /// The triangulator rejected the input (e.g. crossing constraint edges).
    #[error("triangulation failed: {0}")]
    Triangulation(String),
}

/// Layer `complex`: construction from arrays and labelling.
impl<K: Dim> Complex<K> {
    /// Builds a complex from vertex positions, cells and labels inside the box
    /// `[min, max]`. Negatively oriented cells are reoriented; degenerate cells,
    /// out-of-range indices and non-manifold facets are rejected.
    pub fn from_arrays(
        points: Vec<K::Point>,
        cells: Vec<K::Cell>,
        labels: Vec<Label>,
        domain: (K::Point, K::Point),
    ) -> Result<Self, BuildError> {
        let mut complex = Self::unclassified(points, cells, labels, domain)?;
        complex.reclassify_all();
        Ok(complex)
    }

    /// [`from_arrays`](Self::from_arrays) with every vertex classed
    /// interior and on no box face, for the caller to classify.
    fn unclassified(
        points: Vec<K::Point>,
        mut cells: Vec<K::Cell>,
        labels: Vec<Label>,
        domain: (K::Point, K::Point),
    ) -> Result<Self, BuildError> {
        let (min, max) = domain;
        if !(0..K::N).all(|a| min[a].is_finite() && max[a].is_finite() && max[a] > min[a]) {
            return Err(BuildError::BadDomain);
        }
        if cells.len() != labels.len() {
            return Err(BuildError::LabelCount {
                cells: cells.len(),
                labels: labels.len(),
            });
        }
        for (ci, cell) in cells.iter_mut().enumerate() {
            for &v in cell.as_ref() {
                if v.index() >= points.len() {
                    return Err(BuildError::VertexOutOfRange {
                        cell: ci,
                        vertex: v.0,
                        count: points.len(),
                    });
                }
            }
            let mut p = [K::Point::zero(); 4];
            for (o, v) in p.iter_mut().zip(cell.as_ref()) {
                *o = points[v.index()];
                if !o.is_finite() {
                    return Err(BuildError::Degenerate(ci));
                }
            }
            let o = K::orient(&p[..K::NV]);
            if o == 0.0 {
                return Err(BuildError::Degenerate(ci));
            }
            if o < 0.0 {
                cell.as_mut().swap(0, 1);
            }
        }
        let n_cells = cells.len();
        let neighbours = glue_facets::<K>(&cells, points.len())?;
        let mut vertex_cell = vec![None; points.len()];
        for (ci, cell) in cells.iter().enumerate() {
            for &v in cell.as_ref() {
                vertex_cell[v.index()] = Some(CellId::new(ci as u32));
            }
        }
        let live_vertices = vertex_cell.iter().filter(|c| c.is_some()).count();
        let n_points = points.len();
        let mut complex = Complex {
            positions: points,
            vertex_cell,
            classes: vec![
                VertexClass {
                    kind: VertexKind::Interior,
                    boundary: 0
                };
                n_points
            ],
            slots: cells
                .into_iter()
                .zip(neighbours)
                .map(|(corners, neighbours)| Slot::new(corners, neighbours))
                .collect(),
            labels,
            alive: vec![true; n_cells],
            interface_cells: Default::default(),
            live_cells: n_cells,
            live_vertices,
            domain_min: min,
            domain_max: max,
            book: Bookkeeping::new(n_points),
        };
        // Built meshes come in grid (or TetGen's) order, local enough.
        complex.book.ordered_cells = n_cells;
        complex.remark_all_interface_cells();
        Ok(complex)
    }

    /// Recomputes every vertex class.
    pub fn reclassify_all(&mut self) {
        let mut star = self.take_list();
        for v in 0..self.positions.len() {
            let v = VertexId(v as u32);
            if self.is_vertex_alive(v) {
                self.classes[v.index()] = self.compute_class_with(v, &mut star);
            }
        }
        self.give_back(star);
    }

    /// Classes every vertex as [`from_arrays`](Self::from_arrays) would
    /// for a mesh of one phase whose vertex stars are each one piece (a
    /// triangulation of the box): interior, on the box faces its position
    /// lies on. No star is walked. Only for such meshes (the box
    /// constructions' lattices): one phase is checked in debug builds, the
    /// stars' being one piece is the caller's to know.
    fn classify_one_phase(&mut self) {
        debug_assert!(self.labels.iter().all(|&l| l == self.labels[0]));
        for v in 0..self.positions.len() {
            if self.vertex_cell[v].is_some() {
                self.classes[v] = VertexClass {
                    kind: VertexKind::Interior,
                    boundary: self.boundary_mask(&self.positions[v]),
                };
            }
        }
    }

    /// Relabels every cell with `f(cell centroid)` (used by initialisations).
    pub fn label_by(&mut self, mut f: impl FnMut(K::Point) -> Label) {
        let ids: Vec<CellId> = self.cell_ids().collect();
        self.book.relabels += 1;
        for c in ids {
            let p = self.cell_points(c);
            let mut centroid = K::Point::zero();
            for q in &p[..K::NV] {
                centroid += *q;
            }
            self.labels[c.index()] = f(centroid * (1.0 / K::NV as f64));
        }
        self.remark_all_interface_cells();
        self.reclassify_all();
    }
}

/// The neighbour across every facet. Each facet is looked for among the
/// facets met before it with the same smallest vertex (a vertex holds a few;
/// their room is laid out by a counting sort): it is glued to the one it
/// matches, or else kept for a later one. The look is linear in that
/// vertex's facets, so a vertex of very high valence (a fan of thousands of
/// cells given to `from_arrays`) costs the square of its valence; the
/// meshes built here hold at most a few dozen per vertex. A facet held by more than two
/// cells is rejected (non-manifold): of such facets, the one with the
/// smallest key, naming its third cell.
fn glue_facets<K: Dim>(
    cells: &[K::Cell],
    vertices: usize,
) -> Result<Vec<K::Neighbours>, BuildError> {
    let facets = || {
        cells.iter().enumerate().flat_map(|(ci, cell)| {
            (0..K::NV).map(move |i| (facet_key(cell.as_ref(), i), ci as u32, i as u8))
        })
    };
    // The facets whose smallest vertex is v are met in room[start[v]..end[v]].
    let mut start = vec![0usize; vertices + 1];
    for (key, _, _) in facets() {
        start[key[0] as usize + 1] += 1;
    }
    for v in 0..vertices {
        start[v + 1] += start[v];
    }
    let mut end = start.clone();
    let mut room = vec![MetFacet::default(); start[vertices]];
    let mut neighbours = vec![K::no_neighbours(); cells.len()];
    let mut non_manifold: Option<(FacetKey, u32)> = None;
    for (key, cell, i) in facets() {
        let v = key[0] as usize;
        let met = &mut room[start[v]..end[v]];
        match met.iter_mut().find(|m| m.key == key) {
            Some(m) if m.glued => {
                if non_manifold.is_none_or(|(worst, _)| key < worst) {
                    non_manifold = Some((key, cell));
                }
            }
            Some(m) => {
                m.glued = true;
                neighbours[m.cell as usize].as_mut()[m.opposite as usize] = Some(CellId::new(cell));
                neighbours[cell as usize].as_mut()[i as usize] = Some(CellId::new(m.cell));
            }
            None => {
                room[end[v]] = MetFacet {
                    key,
                    cell,
                    opposite: i,
                    glued: false,
                };
                end[v] += 1;
            }
        }
    }
    match non_manifold {
        Some((_, cell)) => Err(BuildError::NonManifold(cell as usize)),
        None => Ok(neighbours),
    }
}

/// A facet [`glue_facets`] met first: its key, its cell and the local index
/// of the corner opposite it, and whether a second cell was glued to it.
#[derive(Clone, Copy, Default)]
struct MetFacet {
    key: FacetKey,
    cell: u32,
    opposite: u8,
    glued: bool,
}

/// The vertices and inner triangles of a spade triangulation, numbered as
/// spade numbers them.
fn spade_arrays<T: Triangulation<Vertex = Point2<f64>>>(
    t: &T,
) -> (Vec<Vector2<f64>>, Vec<[VertexId; 3]>) {
    let pos = t
        .vertices()
        .map(|v| Vector2::new(v.position().x, v.position().y))
        .collect();
    let cells = t
        .inner_faces()
        .map(|f| f.vertices().map(|v| VertexId(v.fix().index() as u32)))
        .collect();
    (pos, cells)
}

fn check_edge_length(l: f64, extent: f64) -> Result<(), BuildError> {
    if !(l.is_finite() && l > 0.0 && l <= extent) {
        return Err(BuildError::BadEdgeLength(l));
    }
    Ok(())
}

fn spade_error(e: impl std::fmt::Display) -> BuildError {
    BuildError::Triangulation(e.to_string())
}

/// Layer `complex`: construction of the 2D box meshes.
impl Complex<D2> {
    /// A near-equilateral triangulation of `[0,w]×[0,h]` with average edge
    /// length close to `l`: staggered rows of points plus exact points on the
    /// border, triangulated strip by strip. Every cell gets label 0.
    ///
    /// The result is the Delaunay triangulation of these points, with the
    /// vertices and cells numbered exactly as spade's incremental Delaunay
    /// triangulation numbers them (which this function used before: a test
    /// compares the two cell for cell), so segmentations are unchanged; built
    /// directly it costs a few per cent of what the incremental insertion
    /// (slowed by the lattice's co-circular points) did.
    pub fn rectangle(w: f64, h: f64, l: f64) -> Result<Self, BuildError> {
        if !(w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0) {
            return Err(BuildError::BadDomain);
        }
        check_edge_length(l, w.min(h))?;
        let (points, cells) = staggered_lattice(w, h, l);
        let labels = vec![0; cells.len()];
        let domain = (Vector2::zeros(), Vector2::new(w, h));
        let mut complex = Self::unclassified(points, cells, labels, domain)?;
        complex.classify_one_phase();
        Ok(complex)
    }

    /// A triangulation of `[0,w]×[0,h]` at edge length `l` that conforms to the
    /// given closed polygons (each a list of points; consecutive points and the
    /// last-to-first pair are constraint edges), refined by spade's constrained
    /// Delaunay refinement. Cells are labelled by `label_of(centroid)`, typically
    /// the index of the polygon containing the centroid.
    pub fn conforming(
        w: f64,
        h: f64,
        l: f64,
        polygons: &[Vec<Vector2<f64>>],
        label_of: impl FnMut(Vector2<f64>) -> Label,
    ) -> Result<Self, BuildError> {
        let base = Self::rectangle(w, h, l)?;
        let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
            ConstrainedDelaunayTriangulation::new();
        let clamp = |p: Vector2<f64>| Point2::new(p.x.clamp(0.0, w), p.y.clamp(0.0, h));
        for (pi, poly) in polygons.iter().enumerate() {
            if poly.len() < 3 || poly.iter().any(|p| !p.is_finite()) {
                return Err(BuildError::BadPolygon(pi));
            }
            let pts: Vec<Point2<f64>> = poly.iter().map(|&p| clamp(p)).collect();
            let mut handles = Vec::with_capacity(pts.len());
            for p in pts {
                handles.push(cdt.insert(p).map_err(spade_error)?);
            }
            for i in 0..handles.len() {
                let (a, b) = (handles[i], handles[(i + 1) % handles.len()]);
                if a != b && cdt.can_add_constraint(a, b) {
                    cdt.add_constraint(a, b);
                }
            }
        }
        // Background points away from the constraints keep the target density.
        let min_gap = 0.5 * l;
        for v in base.vertex_ids() {
            let p = base.position(v);
            let q = Point2::new(p.x, p.y);
            let on_border = base.class(v).on_boundary();
            let near = polygons.iter().flatten().any(|c| (c - p).norm() < min_gap)
                || polygons
                    .iter()
                    .any(|poly| dist_to_polyline(p, poly) < min_gap);
            if on_border || !near {
                cdt.insert(q).map_err(spade_error)?;
            }
        }
        let params = spade::RefinementParameters::<f64>::new()
            .with_angle_limit(spade::AngleLimit::from_deg(25.0))
            .with_max_allowed_area(2.0 * D2::regular_measure(l))
            .keep_constraint_edges()
            .with_max_additional_vertices(2_000_000);
        cdt.refine(params);
        let (pos, cells) = spade_arrays(&cdt);
        let labels = vec![0; cells.len()];
        let mut complex =
            Self::from_arrays(pos, cells, labels, (Vector2::zeros(), Vector2::new(w, h)))?;
        complex.label_by(label_of);
        Ok(complex)
    }
}

fn dist_to_polyline(p: Vector2<f64>, poly: &[Vector2<f64>]) -> f64 {
    let mut best = f64::INFINITY;
    for i in 0..poly.len() {
        let a = poly[i];
        let b = poly[(i + 1) % poly.len()];
        let ab = b - a;
        let t = if ab.norm_squared() > 0.0 {
            ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        best = best.min((a + ab * t - p).norm());
    }
    best
}

/// Ratio of the mean edge length of the Kuhn subdivision to its grid spacing
/// (edges along axes, face diagonals and the body diagonal, each shared by a
/// different number of tets: measured, see the test below).
const KUHN_MEAN_EDGE_PER_SPACING: f64 = 1.24;

/// Layer `complex`: construction of the 3D box meshes.
impl Complex<D3> {
    /// A Kuhn (Freudenthal) tetrahedralisation of the box `[0,size]` at average
    /// edge length close to `l`: each grid cube split into six tets around its
    /// main diagonal, conforming across cubes. Every cell gets label 0.
    pub fn cuboid(size: [f64; 3], l: f64) -> Result<Self, BuildError> {
        if !size.iter().all(|s| s.is_finite() && *s > 0.0) {
            return Err(BuildError::BadDomain);
        }
        check_edge_length(l, size.iter().copied().fold(f64::INFINITY, f64::min))?;
        let spacing = l / KUHN_MEAN_EDGE_PER_SPACING;
        let n: Vec<usize> = size
            .iter()
            .map(|s| ((s / spacing).round() as usize).max(1))
            .collect();
        let coord = |axis: usize, i: usize| {
            if i == n[axis] {
                size[axis]
            } else {
                i as f64 * size[axis] / n[axis] as f64
            }
        };
        let index = |i: usize, j: usize, k: usize| (i + (n[0] + 1) * (j + (n[1] + 1) * k)) as u32;
        let mut points = Vec::with_capacity((n[0] + 1) * (n[1] + 1) * (n[2] + 1));
        for k in 0..=n[2] {
            for j in 0..=n[1] {
                for i in 0..=n[0] {
                    points.push(Vector3::new(coord(0, i), coord(1, j), coord(2, k)));
                }
            }
        }
        const PERMS: [[usize; 3]; 6] = [
            [0, 1, 2],
            [0, 2, 1],
            [1, 0, 2],
            [1, 2, 0],
            [2, 0, 1],
            [2, 1, 0],
        ];
        let mut cells = Vec::with_capacity(6 * n[0] * n[1] * n[2]);
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    for perm in PERMS {
                        let mut c = [i, j, k];
                        let mut tet = [VertexId(index(i, j, k)); 4];
                        for (step, &axis) in perm.iter().enumerate() {
                            c[axis] += 1;
                            tet[step + 1] = VertexId(index(c[0], c[1], c[2]));
                        }
                        cells.push(tet);
                    }
                }
            }
        }
        let labels = vec![0; cells.len()];
        Self::from_arrays(
            points,
            cells,
            labels,
            (Vector3::zeros(), Vector3::from(size)),
        )
    }
}

/// The points and cells of [`Complex::rectangle`]: rows `dy ≈ L·√3/2`
/// apart, odd rows shifted by half a spacing and closed by points on the
/// left and right border; the last row lies on `y = h` unshifted.
fn staggered_lattice(w: f64, h: f64, l: f64) -> (Vec<Vector2<f64>>, Vec<[VertexId; 3]>) {
    let rows = ((h / (l * 3f64.sqrt() / 2.0)).round() as usize).max(1);
    let cols = ((w / l).round() as usize).max(1);
    let (dy, dx) = (h / rows as f64, w / cols as f64);
    let shifted = |j: usize| j % 2 == 1 && j != rows;
    let mut points = Vec::new();
    let mut row_start = Vec::with_capacity(rows + 1);
    for j in 0..=rows {
        row_start.push(points.len() as u32);
        let y = if j == rows { h } else { j as f64 * dy };
        if shifted(j) {
            points.push(Vector2::new(0.0, y));
            points.extend((0..cols).map(|i| Vector2::new((i as f64 + 0.5) * dx, y)));
            points.push(Vector2::new(w, y));
        } else {
            points.extend((0..=cols).map(|i| {
                let x = if i == cols { w } else { i as f64 * dx };
                Vector2::new(x, y)
            }));
        }
    }
    let mut cells = Vec::with_capacity(2 * rows * (cols + 1));
    for j in 0..rows {
        let (b, t) = (row_start[j], row_start[j + 1]);
        strip(&mut cells, b, t, cols as u32, shifted(j), shifted(j + 1));
    }
    let cells = cells.into_iter().map(|c| c.map(VertexId)).collect();
    (points, cells)
}

/// The cells between the row starting at vertex `b` and the row above it
/// starting at `t` (`c` spacings per row), left to right, each with its
/// corners in the order the incremental Delaunay triangulation gave them.
fn strip(cells: &mut Vec<[u32; 3]>, b: u32, t: u32, c: u32, b_shifted: bool, t_shifted: bool) {
    if t_shifted {
        // A plain row below a shifted one.
        cells.push([t, b, t + 1]);
        for i in 0..c {
            cells.push([b + i + 1, t + i + 1, b + i]);
            if i + 1 < c {
                cells.push([t + i + 1, b + i + 1, t + i + 2]);
            }
        }
        cells.push([t + c + 1, t + c, b + c]);
    } else if b_shifted {
        // A shifted row below a plain one.
        cells.push([t, b, b + 1]);
        for i in 0..c {
            if i > 0 {
                cells.push([b + i + 1, t + i, b + i]);
            }
            cells.push([t + i, b + i + 1, t + i + 1]);
        }
        cells.push([b + c + 1, t + c, b + c]);
    } else {
        // Two plain rows (the top strip of an odd number of rows): squares,
        // cut along the diagonal from lower right to upper left.
        cells.push([t, b, b + 1]);
        for i in 0..c {
            if i > 0 {
                cells.push([b + i + 1, t + i, b + i]);
            }
            if i + 1 < c {
                cells.push([t + i, b + i + 1, t + i + 1]);
            }
        }
        cells.push([t + c, t + c - 1, b + c]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mean_edge<K: Dim>(c: &Complex<K>) -> f64 {
        let (mut sum, mut n) = (0.0, 0usize);
        for cell in c.cell_ids() {
            let p = c.cell_points(cell);
            for i in 0..K::NV {
                for j in i + 1..K::NV {
                    sum += (p[i] - p[j]).length();
                    n += 1;
                }
            }
        }
        sum / n as f64
    }

    #[test]
    fn rectangle_has_the_requested_mean_edge_length_and_area() {
        let c = Complex::rectangle(100.0, 60.0, 5.0).unwrap();
        let m = mean_edge(&c);
        assert!((m - 5.0).abs() < 0.5, "mean edge {m}");
        let area: f64 = c.cell_ids().map(|x| c.measure(x)).sum();
        assert!((area - 6000.0).abs() < 1e-6);
        assert!(c.validate().is_empty());
    }

    /// spade's incremental Delaunay triangulation of points whose convex hull
    /// is the domain box (what [`Complex::rectangle`] used before).
    fn delaunay(points: &[Vector2<f64>], domain: (Vector2<f64>, Vector2<f64>)) -> Complex<D2> {
        let mut dt: spade::DelaunayTriangulation<Point2<f64>> = spade::DelaunayTriangulation::new();
        for p in points {
            dt.insert(Point2::new(p.x, p.y)).unwrap();
        }
        let (pos, cells) = spade_arrays(&dt);
        let labels = vec![0; cells.len()];
        Complex::from_arrays(pos, cells, labels, domain).unwrap()
    }

    /// The direct construction is spade's Delaunay triangulation of the same
    /// points, numbered the same way (so segmentations did not change when
    /// it replaced the incremental insertion): even and odd row counts,
    /// integer and fractional sizes, one column and many.
    #[test]
    fn rectangle_is_the_delaunay_triangulation_numbered_as_before() {
        let sizes: [f64; 9] = [2.0, 7.0, 8.0, 20.0, 31.5, 48.0, 63.0, 100.0, 129.25];
        let lengths = [1.0, 1.7, 3.0, 4.0, 6.5, 8.0, 15.0];
        let mut compared = 0;
        for w in sizes {
            for h in sizes {
                for l in lengths {
                    if l > w.min(h) {
                        continue;
                    }
                    let (points, cells) = staggered_lattice(w, h, l);
                    let domain = (Vector2::zeros(), Vector2::new(w, h));
                    let reference = delaunay(&points, domain);
                    let direct = Complex::rectangle(w, h, l).unwrap();
                    assert_eq!(direct.positions, reference.positions, "{w}×{h}, L {l}");
                    let corners = |c: &Complex<D2>| -> Vec<_> {
                        c.slots.iter().map(|slot| slot.corners).collect()
                    };
                    assert_eq!(corners(&direct), corners(&reference), "{w}×{h}, L {l}");
                    assert_eq!(direct.classes, reference.classes, "{w}×{h}, L {l}");
                    assert!(direct.validate().is_empty(), "{w}×{h}, L {l}");
                    assert_eq!(cells.len(), reference.slots.len());
                    compared += 1;
                }
            }
        }
        assert!(compared > 300, "{compared}");
    }

    #[test]
    fn cuboid_has_the_requested_mean_edge_length_and_volume() {
        let c = Complex::cuboid([20.0, 20.0, 20.0], 3.0).unwrap();
        let m = mean_edge(&c);
        assert!((m - 3.0).abs() < 0.3, "mean edge {m}");
        let vol: f64 = c.cell_ids().map(|x| c.measure(x)).sum();
        assert!((vol - 8000.0).abs() < 1e-6);
        assert!(c.validate().is_empty());
    }

    #[test]
    fn a_facet_of_three_cells_is_rejected() {
        let points = vec![
            Vector2::new(0.0, 0.0),
            Vector2::new(1.0, 0.0),
            Vector2::new(0.5, 1.0),
            Vector2::new(0.5, -1.0),
            Vector2::new(0.5, 2.0),
        ];
        let cells = [[0, 1, 2], [0, 1, 3], [0, 1, 4]]
            .map(|c| c.map(VertexId))
            .to_vec();
        let domain = (Vector2::new(0.0, -1.0), Vector2::new(1.0, 2.0));
        let built = Complex::<D2>::from_arrays(points, cells, vec![0; 3], domain);
        assert!(matches!(built, Err(BuildError::NonManifold(_))));
    }

    #[test]
    fn bad_edge_lengths_are_rejected() {
        assert!(Complex::rectangle(10.0, 10.0, 0.0).is_err());
        assert!(Complex::rectangle(10.0, 10.0, f64::NAN).is_err());
        assert!(Complex::rectangle(10.0, 10.0, 11.0).is_err());
        assert!(Complex::cuboid([10.0, 10.0, 10.0], -1.0).is_err());
    }

    #[test]
    fn conforming_mesh_follows_a_square_polygon() {
        let square = vec![
            Vector2::new(10.0, 10.0),
            Vector2::new(30.0, 10.0),
            Vector2::new(30.0, 30.0),
            Vector2::new(10.0, 30.0),
        ];
        let inside =
            |p: Vector2<f64>| (p.x > 10.0 && p.x < 30.0 && p.y > 10.0 && p.y < 30.0) as Label;
        let c = Complex::conforming(40.0, 40.0, 4.0, &[square], inside).unwrap();
        assert!(c.validate().is_empty());
        let areas = c.phase_measures();
        assert!((areas[1] - 400.0).abs() < 1e-6, "inside area {}", areas[1]);
    }
}
