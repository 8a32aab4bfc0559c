//! How phases meet at a vertex: the classification the region forces need
//! (the paper's eqs. (6) and (7)), and in 3D the junction curves.
//!
//! A vertex where only distinct phases meet (a triple junction in 2D, a point
//! of a junction curve in 3D where three or more different phases meet) gets
//! the combined force of eq. (7); one where a phase occurs in two separate
//! pieces of its star (a two-phase checkerboard corner, two sheets of one phase
//! touching along an edge) gets no external force: its neighbours resolve it.

use super::{CellId, Complex, Label, VertexId};
use crate::dim::{Dim, Point, D3};

/// The phases around a vertex, as the region forces need them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PhaseContact {
    /// Off the interface: one phase all around.
    Interior(Label),
    /// On an interface between exactly two phases (lower label first): eq. (6).
    TwoPhase(Label, Label),
    /// A junction where each same-phase piece of the star is a different phase
    /// (labels increasing): eq. (7) with these phases.
    Distinct(Vec<Label>),
    /// A junction where some phase occurs in two or more pieces, or (3D) an
    /// edge at the vertex carries more than two interface faces with only two
    /// phases: no external force.
    Repeated,
}

impl<K: Dim> Complex<K> {
    /// Classifies the phases around `v` (see [`PhaseContact`]).
    pub fn phase_contact(&self, v: VertexId) -> PhaseContact {
        let mut labels = Vec::new();
        self.labels_around(v, &mut labels);
        let pieces = self.count_phase_pieces(v);
        match (labels.len(), pieces) {
            (0, _) => PhaseContact::Interior(0),
            (1, _) => PhaseContact::Interior(labels[0]),
            (n, p) if p > n => PhaseContact::Repeated,
            (2, _) if self.has_junction_edge(v) => PhaseContact::Repeated,
            (2, _) => PhaseContact::TwoPhase(labels[0], labels[1]),
            _ => PhaseContact::Distinct(labels),
        }
    }

    /// Whether some edge at `v` lies in more than two interface facets (only
    /// possible in 3D: a junction curve or a non-manifold contact).
    pub fn has_junction_edge(&self, v: VertexId) -> bool {
        if K::N < 3 {
            return false;
        }
        let mut star = Vec::new();
        self.star_into(v, &mut star);
        // Interface facets at v, each seen from both sides: count per other vertex w
        // the facets containing the edge vw (every facet counted twice).
        let mut counts: Vec<(VertexId, usize)> = Vec::new();
        for &c in &star {
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

    /// For each phase around `v`, the unit normal pointing away from that phase:
    /// the area-weighted mean of the outward normals of its interface facets at
    /// `v` (the `N_k` of eq. (7)). Phases without an interface facet at `v`
    /// (an interior vertex) are left out. `out` is cleared first.
    pub fn phase_normals(&self, v: VertexId, out: &mut Vec<(Label, K::Point)>) {
        out.clear();
        let mut star: Vec<CellId> = Vec::new();
        self.star_into(v, &mut star);
        for &c in &star {
            let cell = self.cell(c);
            let pts = self.cell_points(c);
            for (i, &opposite) in cell.iter().enumerate() {
                if opposite == v || !self.is_interface_facet(c, i) {
                    continue;
                }
                // Facet normal pointing out of `c`, i.e. away from c's phase.
                let n = K::facet_normal(&pts[..K::NV], i) * K::facet_measure(&pts[..K::NV], i);
                let label = self.label(c);
                match out.iter_mut().find(|e| e.0 == label) {
                    Some(e) => e.1 += n,
                    None => out.push((label, n)),
                }
            }
        }
        for (_, n) in out.iter_mut() {
            let len = n.length();
            if len > 0.0 {
                *n = *n * (1.0 / len);
            }
        }
        out.sort_unstable_by_key(|e| e.0);
    }
}

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
    use crate::complex::VertexKind;
    use nalgebra::Vector3;

    /// A 12³ box cut by the planes x = 6 and (for x > 6) y = 6: three phases
    /// meeting along the line x = y = 6.
    fn three_phases() -> Complex<D3> {
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
        c
    }

    #[test]
    fn three_phases_meet_along_a_junction_curve() {
        let c = three_phases();
        let on_line: Vec<VertexId> = c
            .vertex_ids()
            .filter(|&v| {
                let p = c.position(v);
                p.x == 6.0 && p.y == 6.0 && p.z > 0.0 && p.z < 12.0
            })
            .collect();
        assert!(!on_line.is_empty());
        let mut normals = Vec::new();
        for &v in &on_line {
            assert_eq!(c.class(v).kind, VertexKind::Junction);
            assert_eq!(c.phase_contact(v), PhaseContact::Distinct(vec![0, 1, 2]));
            c.phase_normals(v, &mut normals);
            assert_eq!(normals.len(), 3);
            // Phase 0 lies at x < 6: its normal points towards +x.
            assert!(normals[0].1.x > 0.5, "{normals:?}");
            // Phase 1 lies at x > 6, y < 6: away from it is -x / +y.
            assert!(normals[1].1.y > 0.0 && normals[1].1.x < 0.0);
        }
        let curve = c.junction_edges();
        assert!(curve.len() >= on_line.len() - 1);
        for (u, v) in curve {
            let (p, q) = (c.position(u), c.position(v));
            assert!(p.x == 6.0 && p.y == 6.0 && q.x == 6.0 && q.y == 6.0);
        }
        // Points of the sheets are two-phase.
        let sheet = c
            .vertex_ids()
            .find(|&v| {
                let p = c.position(v);
                p.x == 6.0 && p.y > 8.0 && p.z > 2.0 && p.z < 10.0
            })
            .unwrap();
        assert_eq!(c.phase_contact(sheet), PhaseContact::TwoPhase(0, 2));
    }

    #[test]
    fn a_two_phase_checkerboard_edge_has_no_force() {
        let mut c = Complex::cuboid([12.0, 12.0, 12.0], 2.48).unwrap();
        c.label_by(|p| ((p.x < 6.0) ^ (p.y < 6.0)) as Label);
        let v = c
            .vertex_ids()
            .find(|&v| {
                let p = c.position(v);
                p == Vector3::new(6.0, 6.0, 6.0)
            })
            .unwrap();
        assert_eq!(c.phase_contact(v), PhaseContact::Repeated);
        assert!(c.has_junction_edge(v));
        assert!(!c.junction_edges().is_empty());
    }
}
