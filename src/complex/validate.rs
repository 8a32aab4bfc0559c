//! `validate()`: a linear-time check of every invariant of the complex.

use super::{CellId, Complex, VertexId};
use crate::dim::{Dim, Point};
use serde::Serialize;

/// One broken invariant found by [`Complex::validate`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Finding {
    /// `a` names `b` as neighbour across a facet but `b` does not name `a` back across the same facet.
    AsymmetricNeighbour {
        /// The cell whose pointer is not returned.
        cell: CellId,
        /// Its local facet index.
        facet: usize,
    },
    /// A neighbour pointer refers to a removed cell.
    DeadNeighbour {
        /// The cell holding the pointer.
        cell: CellId,
    },
    /// A cell is not positively oriented (exact predicate).
    InvertedCell {
        /// The cell.
        cell: CellId,
    },
    /// A cell lists the same vertex twice or a removed vertex.
    BadCellVertices {
        /// The cell.
        cell: CellId,
    },
    /// A boundary facet (no neighbour) does not lie on the domain box.
    OpenFacetInside {
        /// The cell.
        cell: CellId,
        /// Its local facet index.
        facet: usize,
    },
    /// A vertex's stored class differs from the one its star implies.
    StaleClass {
        /// The vertex.
        vertex: VertexId,
    },
    /// A vertex's incident cell does not contain it, or its star misses cells that contain it.
    BadStar {
        /// The vertex.
        vertex: VertexId,
    },
    /// A live vertex used by no cell.
    OrphanVertex {
        /// The vertex.
        vertex: VertexId,
    },
    /// A vertex lies outside the domain box or has a non-finite coordinate.
    VertexOutsideDomain {
        /// The vertex.
        vertex: VertexId,
    },
    /// The cells do not add up to the domain's measure.
    MeasureMismatch {
        /// Sum of the cells' measures.
        total: f64,
        /// Measure of the domain box.
        expected: f64,
    },
    /// The live-element counters disagree with the arrays.
    CountMismatch,
    /// A cell's interface bit ([`Complex::meets_other_label`]) differs
    /// from what its neighbours' labels say.
    StaleInterfaceMark {
        /// The cell.
        cell: CellId,
    },
}

/// Layer `complex`: validation of every invariant.
impl<K: Dim> Complex<K> {
    /// Checks every invariant in time linear in the size of the complex and
    /// returns what is broken (empty when the complex is valid).
    pub fn validate(&self) -> Vec<Finding> {
        let mut findings = Vec::new();
        let mut uses = vec![0u32; self.positions.len()];
        let mut total = 0.0;
        let mut live = 0;
        for c in self.cell_ids() {
            live += 1;
            let verts = self.cell(c);
            let dup = (0..K::NV).any(|i| (i + 1..K::NV).any(|j| verts[i] == verts[j]));
            if dup || verts.iter().any(|v| !self.is_vertex_alive(*v)) {
                findings.push(Finding::BadCellVertices { cell: c });
                continue;
            }
            for v in verts {
                uses[v.index()] += 1;
            }
            let p = self.cell_points(c);
            if K::orient(&p[..K::NV]) <= 0.0 {
                findings.push(Finding::InvertedCell { cell: c });
            }
            total += K::signed_measure(&p[..K::NV]);
            for (i, nb) in self.neighbours(c).iter().enumerate() {
                match nb {
                    Some(nb) if !self.is_alive(*nb) => {
                        findings.push(Finding::DeadNeighbour { cell: c })
                    }
                    Some(nb) => {
                        let key = super::cavity::facet_key(verts, i);
                        let back = self.neighbours(*nb).iter().enumerate().any(|(j, b)| {
                            *b == Some(c) && super::cavity::facet_key(self.cell(*nb), j) == key
                        });
                        if !back {
                            findings.push(Finding::AsymmetricNeighbour { cell: c, facet: i });
                        }
                    }
                    None => {
                        let on_box = (0..K::N).any(|axis| {
                            let on = |bound: f64| {
                                (0..K::NV).filter(|&j| j != i).all(|j| p[j][axis] == bound)
                            };
                            on(self.domain_min[axis]) || on(self.domain_max[axis])
                        });
                        if !on_box {
                            findings.push(Finding::OpenFacetInside { cell: c, facet: i });
                        }
                    }
                }
            }
        }
        if live != self.live_cells {
            findings.push(Finding::CountMismatch);
        }
        for i in 0..self.slots.len() {
            let cell = CellId::new(i as u32);
            if self.meets_other_label(cell) != self.meets_other_label_now(cell) {
                findings.push(Finding::StaleInterfaceMark { cell });
            }
        }
        let mut live_vertices = 0;
        let mut star = Vec::new();
        for v in self.vertex_ids() {
            live_vertices += 1;
            let p = self.positions[v.index()];
            let inside = p.is_finite()
                && (0..K::N).all(|a| p[a] >= self.domain_min[a] && p[a] <= self.domain_max[a]);
            if !inside {
                findings.push(Finding::VertexOutsideDomain { vertex: v });
            }
            if uses[v.index()] == 0 {
                findings.push(Finding::OrphanVertex { vertex: v });
                continue;
            }
            let start = self.vertex_cell[v.index()].expect("live vertex");
            if !self.is_alive(start) || !self.cell(start).contains(&v) {
                findings.push(Finding::BadStar { vertex: v });
                continue;
            }
            self.star_into(v, &mut star);
            if star.len() != uses[v.index()] as usize {
                findings.push(Finding::BadStar { vertex: v });
                continue;
            }
            if self.compute_class(v) != self.classes[v.index()] {
                findings.push(Finding::StaleClass { vertex: v });
            }
        }
        if live_vertices != self.live_vertices {
            findings.push(Finding::CountMismatch);
        }
        let expected = self.domain_measure();
        if (total - expected).abs() > 1e-9 * expected {
            findings.push(Finding::MeasureMismatch { total, expected });
        }
        findings
    }
}
