//! Mesh improvement between moves: smoothing, flips, removal of degenerate cells.

use super::DscParams;
use crate::complex::{CellId, Complex, Rejection, VertexId};
use crate::dim::{Dim, D2, D3};
use crate::ops::CollapseMode;
use serde::Serialize;

/// The dimension-specific connectivity improvement (2D edge flips, 3D flips).
pub trait Connectivity: Dim {
    /// One improvement pass over the whole complex; returns the number of changes.
    fn improve_connectivity(complex: &mut Complex<Self>, params: &DscParams) -> usize;
}

impl Connectivity for D2 {
    /// Flips non-interface edges until the triangulation is locally Delaunay
    /// within each phase (bounded number of sweeps).
    fn improve_connectivity(complex: &mut Complex<D2>, _params: &DscParams) -> usize {
        let mut flips = 0;
        for _sweep in 0..8 {
            let mut changed = 0;
            let end = complex.cell_capacity();
            for c in 0..end {
                let c = CellId(c as u32);
                for i in 0..3 {
                    if !complex.is_alive(c) {
                        break;
                    }
                    if let Ok(true) = complex.flip_if_better(c, i) {
                        changed += 1;
                    }
                }
            }
            flips += changed;
            if changed == 0 {
                break;
            }
        }
        flips
    }
}

impl Connectivity for D3 {
    /// Visits every tet below `low_quality` and tries edge removal (3-2, 4-4 and
    /// larger rings) on its edges, then 2-3 flips on its facets, off the
    /// interface, accepting a flip only when the smallest quality of the tets
    /// involved increases (bounded number of sweeps).
    fn improve_connectivity(complex: &mut Complex<D3>, params: &DscParams) -> usize {
        let mut flips = 0;
        for _sweep in 0..4 {
            let mut changed = 0;
            let end = complex.cell_capacity();
            for c in 0..end {
                let c = CellId(c as u32);
                if !complex.is_alive(c) || complex.quality(c) >= params.low_quality {
                    continue;
                }
                if complex.improve_tet(c, 0.0).is_some() {
                    changed += 1;
                }
            }
            flips += changed;
            if changed == 0 {
                break;
            }
        }
        flips
    }
}

/// Counts of what one improvement did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ImproveStats {
    /// Vertices moved by smoothing.
    pub smoothed: usize,
    /// Connectivity changes (flips).
    pub flips: usize,
    /// Collapses that kept the interface.
    pub safe_collapses: usize,
    /// Collapses that merged interface vertices (topology may change).
    pub unsafe_collapses: usize,
    /// Degenerate tets that no collapse could remove, split at their longest edge (3D only).
    pub degenerate_splits: usize,
}

impl<K: Connectivity> Complex<K> {
    /// Smooths, flips, removes degenerate cells and smooths again.
    pub fn improve(&mut self, params: &DscParams) -> ImproveStats {
        let mut stats = ImproveStats::default();
        stats.smoothed += self.smooth_all();
        stats.flips += K::improve_connectivity(self, params);
        let (safe, unsafe_, splits) = self.remove_degenerate(params);
        stats.safe_collapses += safe;
        stats.unsafe_collapses += unsafe_;
        stats.degenerate_splits += splits;
        stats.flips += K::improve_connectivity(self, params);
        stats.smoothed += self.smooth_all();
        stats
    }

    /// One Laplacian pass over every non-interface vertex.
    pub fn smooth_all(&mut self) -> usize {
        let mut star = Vec::new();
        let mut moved = 0;
        for v in 0..self.vertex_capacity() {
            if self.smooth_vertex(VertexId(v as u32), &mut star) {
                moved += 1;
            }
        }
        moved
    }

    /// Whether a cell is degenerate by quality, measure or edge length.
    pub fn is_degenerate(&self, c: CellId, params: &DscParams) -> bool {
        if self.quality(c) < params.degenerate_quality
            || self.measure(c) < params.measure::<K>(params.degenerate_measure)
        {
            return true;
        }
        let (a, b) = self.shortest_edge(c);
        crate::dim::Point::length(&(self.position(a) - self.position(b)))
            < params.degenerate_length * params.edge_length
    }

    /// Removes degenerate cells by collapsing their edges, shortest first: a
    /// safe collapse where one exists, otherwise an unsafe one (which may merge
    /// interfaces: the DSC's topology change). In 3D a degenerate tet that no
    /// collapse removes is split at its longest edge when that is longer than `L`.
    /// Returns the (safe, unsafe, split) counts.
    pub fn remove_degenerate(&mut self, params: &DscParams) -> (usize, usize, usize) {
        let straight_cos = params.straight_angle_deg.to_radians().cos();
        let (mut safe, mut unsafe_, mut splits) = (0, 0, 0);
        for _sweep in 0..4 {
            let mut changed = false;
            let end = self.cell_capacity();
            for c in 0..end {
                let c = CellId(c as u32);
                if !self.is_alive(c) || !self.is_degenerate(c, params) {
                    continue;
                }
                match self.collapse_cell(c, params, straight_cos) {
                    Some(CollapseMode::Safe) => safe += 1,
                    Some(CollapseMode::Unsafe) => unsafe_ += 1,
                    None if K::N == 3 => {
                        let (u, v) = self.longest_edge(c);
                        let long =
                            crate::dim::Point::length(&(self.position(u) - self.position(v)))
                                > params.edge_length;
                        if !(long && self.split_edge(u, v).is_ok()) {
                            continue;
                        }
                        splits += 1;
                    }
                    None => continue,
                }
                changed = true;
            }
            if !changed {
                break;
            }
        }
        (safe, unsafe_, splits)
    }

    /// Tries to collapse one edge of `c`, shortest first, safe before unsafe.
    fn collapse_cell(
        &mut self,
        c: CellId,
        params: &DscParams,
        straight_cos: f64,
    ) -> Option<CollapseMode> {
        let edges = self.edges_by_length(c);
        for mode in [CollapseMode::Safe, CollapseMode::Unsafe] {
            for &(u, v) in &edges {
                match self.collapse_edge(u, v, mode, params.degenerate_quality, straight_cos) {
                    Ok(_) => return Some(mode),
                    Err(Rejection::Stale) => return None,
                    Err(_) => {}
                }
            }
        }
        None
    }
}
