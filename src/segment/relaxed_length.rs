//! The length a staircase border of small cells will have once the
//! interface has relaxed (2D).
//!
//! A region made of small triangles has a jagged border: on the staggered
//! lattice a straight boundary becomes a zigzag up to about twice its
//! length. The forces smooth it within a few iterations, so a decision that
//! weighs the border's length (a cluster flip) must weigh the relaxed one.
//! The estimate: the border's vertex chains smoothed by Taubin's λ|μ filter
//! (which removes the zigzag without shrinking the shape, unlike plain
//! Laplacian smoothing), and never below the perimeter of a disk of the
//! region's area (no relaxation makes a border shorter than that).

use crate::complex::{Complex, VertexId};
use crate::dim::Dim;

/// Taubin's shrinking step.
const LAMBDA: f64 = 0.5;
/// Taubin's inflating step (|μ| slightly above λ).
const MU: f64 = -0.53;
/// λ|μ pairs: enough to flatten a zigzag of one or two cells.
const ROUNDS: usize = 4;

/// Scratch space of the estimate, kept between calls.
#[derive(Clone, Debug, Default)]
pub struct BorderRelaxation {
    vertices: Vec<VertexId>,
    /// Per vertex: its chain neighbours (at most two are used).
    links: Vec<([u32; 2], u8)>,
    points: Vec<[f64; 2]>,
    next: Vec<[f64; 2]>,
}

impl BorderRelaxation {
    /// The relaxed length of the border `edges` (2D vertex pairs) of a
    /// region of `area` over its length now, in `(0, 1]`; 1 in 3D or for an
    /// empty border.
    pub fn fraction<K: Dim>(
        &mut self,
        complex: &Complex<K>,
        edges: &[[VertexId; 2]],
        area: f64,
    ) -> f64 {
        if K::N != 2 || edges.is_empty() {
            return 1.0;
        }
        self.collect(complex, edges);
        let now = self.length(edges);
        if now <= 0.0 {
            return 1.0;
        }
        for _ in 0..ROUNDS {
            self.smooth(LAMBDA);
            self.smooth(MU);
        }
        let disk = 2.0 * (std::f64::consts::PI * area.max(0.0)).sqrt();
        (self.length(edges).max(disk) / now).min(1.0)
    }

    /// The border's vertices, their positions and chain neighbours.
    fn collect<K: Dim>(&mut self, complex: &Complex<K>, edges: &[[VertexId; 2]]) {
        self.vertices.clear();
        self.vertices.extend(edges.iter().flatten().copied());
        self.vertices.sort_unstable();
        self.vertices.dedup();
        self.points.clear();
        self.points.extend(self.vertices.iter().map(|&v| {
            let p = complex.position(v);
            [p[0], p[1]]
        }));
        self.links.clear();
        self.links.resize(self.vertices.len(), ([0; 2], 0));
        for e in edges {
            let (a, b) = (self.slot(e[0]), self.slot(e[1]));
            for (from, to) in [(a, b), (b, a)] {
                let (links, n) = &mut self.links[from];
                if (*n as usize) < 2 {
                    links[*n as usize] = to as u32;
                }
                *n = n.saturating_add(1);
            }
        }
    }

    fn slot(&self, v: VertexId) -> usize {
        self.vertices.binary_search(&v).expect("a border vertex")
    }

    /// One smoothing step of factor `f` of vertices on a simple chain
    /// (exactly two border neighbours; the others stay).
    fn smooth(&mut self, f: f64) {
        self.next.clone_from(&self.points);
        for (i, &(links, n)) in self.links.iter().enumerate() {
            if n != 2 {
                continue;
            }
            let (a, b) = (
                self.points[links[0] as usize],
                self.points[links[1] as usize],
            );
            let p = self.points[i];
            for k in 0..2 {
                self.next[i][k] = p[k] + f * (0.5 * (a[k] + b[k]) - p[k]);
            }
        }
        std::mem::swap(&mut self.points, &mut self.next);
    }

    fn length(&self, edges: &[[VertexId; 2]]) -> f64 {
        edges
            .iter()
            .map(|e| {
                let (a, b) = (self.points[self.slot(e[0])], self.points[self.slot(e[1])]);
                (a[0] - b[0]).hypot(a[1] - b[1])
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::D2;

    /// The border of the cells of a fine lattice inside a long rectangle
    /// at an angle to the lattice: the staircase is longer than the
    /// rectangle's perimeter, the relaxed estimate close to it.
    #[test]
    fn a_staircase_relaxes_to_about_the_smooth_length() {
        let mesh = Complex::<D2>::rectangle(64.0, 64.0, 1.5).unwrap();
        let inside = |c| {
            let pts = mesh.cell_points(c);
            let g = (pts[0] + pts[1] + pts[2]) / 3.0;
            let (dx, dy) = (g.x - 32.0, g.y - 32.0);
            let (sin, cos) = 20f64.to_radians().sin_cos();
            (dx * cos + dy * sin).abs() < 15.0 && (dy * cos - dx * sin).abs() < 3.0
        };
        let mut edges = Vec::new();
        let mut area = 0.0;
        for c in mesh.cell_ids().filter(|&c| inside(c)) {
            area += D2::signed_measure(&mesh.cell_points(c)[..3]);
            for (f, nb) in mesh.neighbours(c).iter().enumerate() {
                if nb.is_none_or(|nb| !inside(nb)) {
                    let v = mesh.cell(c);
                    edges.push([v[(f + 1) % 3], v[(f + 2) % 3]]);
                }
            }
        }
        let jagged: f64 = edges
            .iter()
            .map(|e| (mesh.position(e[0]) - mesh.position(e[1])).norm())
            .sum();
        let smooth = 2.0 * (30.0 + 6.0);
        assert!(jagged > 1.2 * smooth, "the premise: {jagged} vs {smooth}");
        let relaxed = BorderRelaxation::default().fraction(&mesh, &edges, area) * jagged;
        assert!(
            (relaxed - smooth).abs() < 0.15 * smooth,
            "relaxed {relaxed}, smooth {smooth}, jagged {jagged}"
        );
    }
}
