//! Junction curves in 3D: edges lying in more than two interface triangles.
//!
//! Where three or more phases meet along a curve, or two sheets of one phase
//! touch along an edge, an edge carries more than two interface triangles. The
//! vertex classification ([`VertexKind`](super::VertexKind)) sees the first
//! case (three or more same-phase pieces in the star); a vertex can however
//! have a two-piece star and still sit on such an edge (the pieces meet again
//! elsewhere), which [`Complex::has_junction_edge`] detects: the segmentation
//! gives those vertices no region force, like any crossing where a phase repeats.

use super::{CellId, Complex, VertexId};
use crate::dim::{Dim, D3};
use smallvec::SmallVec;

/// Layer `complex`: junction edges (3D interfaces meeting along an edge).
impl<K: Dim> Complex<K> {
    /// Whether some edge at `v` lies in more than two interface facets (only
    /// possible in 3D: a junction curve or a non-manifold contact).
    pub fn has_junction_edge(&self, v: VertexId) -> bool {
        self.has_junction_edge_with(v, &mut Vec::new())
    }

    /// [`has_junction_edge`](Self::has_junction_edge); `star` is scratch.
    pub(crate) fn has_junction_edge_with(&self, v: VertexId, star: &mut Vec<CellId>) -> bool {
        if !K::EDGE_JUNCTIONS {
            return false;
        }
        self.star_into(v, star);
        // Interface facets at v, each seen from both sides: count per other vertex w
        // the facets containing the edge vw (every facet counted twice).
        let mut counts: SmallVec<[(VertexId, usize); 32]> = SmallVec::new();
        for &c in star.iter() {
            let cell = self.cell(c);
            for (i, &opposite) in cell.iter().enumerate() {
                if opposite == v || !self.is_interface_facet(c, i) {
                    continue;
                }
                for (j, &w) in cell.iter().enumerate() {
                    if j == i || w == v {
                        continue;
                    }
                    match counts.iter_mut().find(|e| e.0 == w) {
                        Some(e) => e.1 += 1,
                        None => counts.push((w, 1)),
                    }
                }
            }
        }
        counts.iter().any(|&(_, n)| n > 4)
    }
}

/// Layer `complex`: junction curves of a 3D complex.
impl Complex<D3> {
    /// Number of interface facets (triangles) containing the edge `uv`.
    pub fn interface_faces_at_edge(&self, u: VertexId, v: VertexId) -> usize {
        let mut star = Vec::new();
        let mut cells = Vec::new();
        self.cells_of_edge(u, v, &mut star, &mut cells);
        let mut twice = 0;
        for &c in &cells {
            let cell = self.cell(c);
            for (i, &opposite) in cell.iter().enumerate() {
                if opposite != u && opposite != v && self.is_interface_facet(c, i) {
                    twice += 1;
                }
            }
        }
        twice / 2
    }

    /// The junction curves: every edge lying in three or more interface
    /// triangles, each once with the lower vertex id first.
    pub fn junction_edges(&self) -> Vec<(VertexId, VertexId)> {
        let mut out = Vec::new();
        for (u, v) in self.interface_edges() {
            if self.class(u).on_interface()
                && self.class(v).on_interface()
                && self.interface_faces_at_edge(u, v) > 2
            {
                out.push((u, v));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::complex::{Label, VertexKind};
    use nalgebra::Vector3;

    #[test]
    fn three_phases_meet_along_a_junction_curve() {
        // A 12³ box cut by x = 6 and (for x > 6) y = 6: three phases meeting
        // along the line x = y = 6.
        let mut c = Complex::cuboid([12.0, 12.0, 12.0], 2.48).unwrap();
        c.label_by(|p| {
            if p.x < 6.0 {
                0
            } else if p.y < 6.0 {
                1
            } else {
                2
            }
        });
        let on_line: Vec<VertexId> = c
            .vertex_ids()
            .filter(|&v| {
                let p = c.position(v);
                p.x == 6.0 && p.y == 6.0 && p.z > 0.0 && p.z < 12.0
            })
            .collect();
        assert!(!on_line.is_empty());
        for &v in &on_line {
            assert_eq!(c.class(v).kind, VertexKind::Junction);
            assert!(c.has_junction_edge(v));
        }
        let curve = c.junction_edges();
        assert!(curve.len() >= on_line.len() - 1);
        for (u, v) in curve {
            let (p, q) = (c.position(u), c.position(v));
            assert!(p.x == 6.0 && p.y == 6.0 && q.x == 6.0 && q.y == 6.0);
            assert_eq!(c.interface_faces_at_edge(u, v), 3);
        }
        // A point of a sheet is not on a junction curve.
        let sheet = c
            .vertex_ids()
            .find(|&v| {
                let p = c.position(v);
                p.x == 6.0 && p.y > 8.0 && p.z > 2.0 && p.z < 10.0
            })
            .unwrap();
        assert_eq!(c.class(sheet).kind, VertexKind::Interface);
        assert!(!c.has_junction_edge(sheet));
    }

    #[test]
    fn a_two_phase_checkerboard_edge_is_a_junction_curve() {
        let mut c = Complex::cuboid([12.0, 12.0, 12.0], 2.48).unwrap();
        c.label_by(|p| ((p.x < 6.0) ^ (p.y < 6.0)) as Label);
        let v = c
            .vertex_ids()
            .find(|&v| c.position(v) == Vector3::new(6.0, 6.0, 6.0))
            .unwrap();
        assert!(c.has_junction_edge(v));
        assert!(!c.junction_edges().is_empty());
    }
}
