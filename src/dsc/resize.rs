//! Resizing after a deform: keep interface edges and cells near the target size.

use super::DscParams;
use crate::complex::{CellId, Complex, VertexId};
use crate::dim::Point;
use crate::ops::CollapseMode;
use serde::Serialize;

use super::Connectivity;

/// Counts of what one resize did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ResizeStats {
    /// Interface edges split for being long.
    pub interface_splits: usize,
    /// Interface edges collapsed for being short.
    pub interface_collapses: usize,
    /// Large cells split at their longest edge.
    pub cell_splits: usize,
    /// Small cells collapsed.
    pub cell_collapses: usize,
}

impl<K: Connectivity> Complex<K> {
    /// Splits long and collapses short interface edges, splits large and
    /// collapses small cells. The vertices it creates or moves are appended to
    /// `touched`, so that the caller can improve the mesh around them.
    pub fn resize(&mut self, params: &DscParams, touched: &mut Vec<VertexId>) -> ResizeStats {
        self.resize_with(params, touched, &mut Vec::new())
    }

    /// [`resize`](Self::resize) listing the interface edges into `edges` (scratch).
    pub(super) fn resize_with(
        &mut self,
        params: &DscParams,
        touched: &mut Vec<VertexId>,
        edges: &mut Vec<(VertexId, VertexId)>,
    ) -> ResizeStats {
        let mut stats = ResizeStats::default();
        let l = params.edge_length;
        let straight_cos = params.straight_angle_deg.to_radians().cos();
        self.interface_edges_into(edges);
        for &(u, v) in edges.iter() {
            if self
                .edge_length_if_alive(u, v)
                .is_some_and(|len| len > params.max_length * l)
            {
                if let Ok(m) = self.split_edge(u, v) {
                    touched.push(m);
                    stats.interface_splits += 1;
                }
            }
        }
        // A failed split leaves the cells as they were: without splits the
        // interface edges stand.
        if stats.interface_splits > 0 {
            self.interface_edges_into(edges);
        }
        for &(u, v) in edges.iter() {
            if self
                .edge_length_if_alive(u, v)
                .is_some_and(|len| len < params.min_length * l)
                && self
                    .collapse_edge(u, v, CollapseMode::Safe, params.min_quality, straight_cos)
                    .is_ok()
            {
                stats.interface_collapses += 1;
            }
        }
        let max_measure = params.measure::<K>(params.max_measure);
        let min_measure = params.measure::<K>(params.min_measure);
        let end = self.cell_capacity();
        for c in 0..end {
            let c = CellId(c as u32);
            if !self.is_alive(c) {
                continue;
            }
            let m = self.measure(c);
            if m > max_measure {
                let (u, v) = self.longest_edge(c);
                if let Ok(m) = self.split_edge(u, v) {
                    touched.push(m);
                    stats.cell_splits += 1;
                }
            } else if m < min_measure {
                let (u, v) = self.shortest_edge(c);
                if let Ok(k) =
                    self.collapse_edge(u, v, CollapseMode::Safe, params.min_quality, straight_cos)
                {
                    touched.push(k);
                    stats.cell_collapses += 1;
                }
            }
        }
        stats
    }

    /// Every edge lying in an interface facet, each once.
    pub fn interface_edges(&self) -> Vec<(VertexId, VertexId)> {
        let mut edges = Vec::new();
        self.interface_edges_into(&mut edges);
        edges
    }

    /// [`interface_edges`](Self::interface_edges) into `edges` (cleared first).
    pub fn interface_edges_into(&self, edges: &mut Vec<(VertexId, VertexId)>) {
        edges.clear();
        for c in self.cell_ids() {
            let cell = self.cell(c);
            for i in 0..K::NV {
                let Some(nb) = self.neighbours(c)[i] else {
                    continue;
                };
                if nb < c || self.label(nb) == self.label(c) {
                    continue;
                }
                for a in 0..K::NV {
                    for b in a + 1..K::NV {
                        if a != i && b != i {
                            let (u, v) = (cell[a], cell[b]);
                            edges.push(if u < v { (u, v) } else { (v, u) });
                        }
                    }
                }
            }
        }
        edges.sort_unstable();
        edges.dedup();
    }

    fn edge_length_if_alive(&self, u: VertexId, v: VertexId) -> Option<f64> {
        (self.is_vertex_alive(u) && self.is_vertex_alive(v))
            .then(|| (self.position(u) - self.position(v)).length())
    }
}
