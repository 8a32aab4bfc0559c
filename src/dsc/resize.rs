//! Resizing after a deform: keep interface edges and cells near the target size.

use super::refusals::RefusedCollapses;
use super::{DscParams, SizingField};
use crate::complex::{CellId, Complex, VertexId};
use crate::dim::{Dim, Point};
use crate::ops::{CollapseMode, FlatEnds};
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
    /// Interior edges collapsed for being short against a graded sizing
    /// field (coarsening; never with the uniform field).
    pub interior_collapses: usize,
}

/// With a graded sizing field, the passes of large-cell splits one resize
/// may run (each halves a cell about; the uniform field runs one).
const REFINE_PASSES: usize = 3;

/// Layer `dsc`: resizing (split long, collapse short edges and cells).
impl<K: Connectivity> Complex<K> {
    /// Splits long and collapses short interface edges, splits large and
    /// collapses small cells, against the average edge length `L` of
    /// `params` everywhere. The vertices it creates or moves are appended to
    /// `touched`, so that the caller can improve the mesh around them.
    pub fn resize(&mut self, params: &DscParams, touched: &mut Vec<VertexId>) -> ResizeStats {
        self.resize_sized(params, &SizingField::uniform(), touched)
    }

    /// [`resize`](Self::resize) against the target size `h` of `sizing`,
    /// read at each edge's midpoint and each cell's centroid. A graded field
    /// also coarsens: interior edges (no end on an interface) shorter than
    /// `coarsen_length·h` are collapsed where the collapse is safe.
    pub fn resize_sized(
        &mut self,
        params: &DscParams,
        sizing: &SizingField,
        touched: &mut Vec<VertexId>,
    ) -> ResizeStats {
        self.resize_with(
            params,
            sizing,
            touched,
            &mut Vec::new(),
            &mut RefusedCollapses::default(),
            &mut FlatEnds::default(),
        )
    }

    /// [`resize_sized`](Self::resize_sized) listing the interface edges into
    /// `edges` (scratch), skipping the coarsening collapses `refusals` knows
    /// would be refused again (and recording the new refusals), and keeping
    /// the interface vertices' flatness, asked again by many collapses, in
    /// `flat` (emptied first; its buffer is kept, so that a warm iteration
    /// does not allocate).
    pub(super) fn resize_with(
        &mut self,
        params: &DscParams,
        sizing: &SizingField,
        touched: &mut Vec<VertexId>,
        edges: &mut Vec<(VertexId, VertexId)>,
        refusals: &mut RefusedCollapses,
        flat: &mut FlatEnds,
    ) -> ResizeStats {
        let mut stats = ResizeStats::default();
        let straight_cos = params.straight_angle_deg.to_radians().cos();
        flat.forget();
        self.interface_edges_into(edges);
        for &(u, v) in edges.iter() {
            if self
                .edge_against_size(u, v, params, sizing)
                .is_some_and(|(len, h)| len > params.max_length * h)
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
                .edge_against_size(u, v, params, sizing)
                .is_some_and(|(len, h)| len < params.min_length * h)
                && self
                    .collapse_edge_remembering(
                        (u, v),
                        CollapseMode::Safe,
                        params.min_quality,
                        straight_cos,
                        flat,
                    )
                    .is_ok()
            {
                stats.interface_collapses += 1;
            }
        }
        let passes = if sizing.is_uniform() {
            1
        } else {
            REFINE_PASSES
        };
        let mut judged = None;
        for pass in 0..passes {
            let splits = stats.cell_splits;
            judged = Some(self.resize_cells(
                params,
                sizing,
                (pass == 0).then_some(&mut *flat),
                judged.as_ref(),
                touched,
                &mut stats,
            ));
            if stats.cell_splits == splits {
                break;
            }
        }
        if !sizing.is_uniform() {
            stats.interior_collapses = self.coarsen_interior(params, sizing, touched, refusals);
        }
        stats
    }

    /// One pass over the cells: those larger than `max_measure·A(h)` are
    /// split at their longest edge; with `collapse_small` (the flatness
    /// record of the pass's collapses), those smaller than
    /// `min_measure·A(h)` are collapsed at their shortest edge. After
    /// a pass (`before`), a later pass, which only splits, passes over the
    /// cells that one left in place unchanged (they are not large: their
    /// measure and `h` at their centroid are those it judged) but for those
    /// whose split failed. Returns what this pass judged.
    fn resize_cells(
        &mut self,
        params: &DscParams,
        sizing: &SizingField,
        mut collapse_small: Option<&mut FlatEnds>,
        before: Option<&JudgedPass>,
        touched: &mut Vec<VertexId>,
        stats: &mut ResizeStats,
    ) -> JudgedPass {
        let straight_cos = params.straight_angle_deg.to_radians().cos();
        let uniform_bounds = (
            params.measure::<K>(params.max_measure),
            params.measure::<K>(params.min_measure),
        );
        let end = self.cell_capacity();
        let mut judged = JudgedPass {
            clock: self.move_clock(),
            end,
            failed_splits: Vec::new(),
        };
        for c in 0..end {
            let c = CellId::new(c as u32);
            if !self.is_alive(c) {
                continue;
            }
            if let Some(before) = before {
                if before.left_alone(self, c) {
                    continue;
                }
            }
            let m = self.measure(c);
            let (max_measure, min_measure) = if sizing.is_uniform() {
                uniform_bounds
            } else {
                let h = sizing.at_cell(&self.cell_points(c)[..K::NV], params.edge_length);
                let a = K::regular_measure(h);
                (params.max_measure * a, params.min_measure * a)
            };
            if m > max_measure {
                let (u, v) = self.longest_edge(c);
                match self.split_edge(u, v) {
                    Ok(m) => {
                        touched.push(m);
                        stats.cell_splits += 1;
                    }
                    Err(_) => judged.failed_splits.push(c),
                }
            } else if let Some(flat) = collapse_small.as_deref_mut().filter(|_| m < min_measure) {
                let (u, v) = self.shortest_edge(c);
                if let Ok(k) = self.collapse_edge_remembering(
                    (u, v),
                    CollapseMode::Safe,
                    params.min_quality,
                    straight_cos,
                    flat,
                ) {
                    touched.push(k);
                    stats.cell_collapses += 1;
                }
            }
        }
        judged
    }

    /// Collapses, safely, the shortest edge of each cell without an
    /// interface vertex whose length is below `coarsen_length·h`; returns
    /// how many collapsed. A collapse `refusals` knows would be refused is
    /// not tried again.
    fn coarsen_interior(
        &mut self,
        params: &DscParams,
        sizing: &SizingField,
        touched: &mut Vec<VertexId>,
        refusals: &mut RefusedCollapses,
    ) -> usize {
        let straight_cos = params.straight_angle_deg.to_radians().cos();
        refusals.sync(self, params.min_quality, straight_cos);
        let mut collapses = 0;
        let end = self.cell_capacity();
        for c in 0..end {
            let c = CellId::new(c as u32);
            if !self.is_alive(c) || self.cell(c).iter().any(|&v| self.class(v).on_interface()) {
                continue;
            }
            let (u, v) = self.shortest_edge(c);
            if refusals.still_refused(self, c, (u, v)) {
                continue;
            }
            let Some((len, h)) = self.edge_against_size(u, v, params, sizing) else {
                continue;
            };
            if len < params.coarsen_length * h {
                match self.collapse_edge(u, v, CollapseMode::Safe, params.min_quality, straight_cos)
                {
                    Ok(k) => {
                        touched.push(k);
                        collapses += 1;
                    }
                    Err(_) => refusals.record(self, c),
                }
            }
        }
        collapses
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
        for (c, i) in self.interface_facet_ids() {
            let cell = self.cell(c);
            for a in 0..K::NV {
                for b in a + 1..K::NV {
                    if a != i && b != i {
                        let (u, v) = (cell[a], cell[b]);
                        edges.push(if u < v { (u, v) } else { (v, u) });
                    }
                }
            }
        }
        edges.sort_unstable();
        edges.dedup();
    }

    /// The length of the edge `uv` and the target size at its midpoint,
    /// if both ends are alive.
    fn edge_against_size(
        &self,
        u: VertexId,
        v: VertexId,
        params: &DscParams,
        sizing: &SizingField,
    ) -> Option<(f64, f64)> {
        if !(self.is_vertex_alive(u) && self.is_vertex_alive(v)) {
            return None;
        }
        let (a, b) = (self.position(u), self.position(v));
        Some(((a - b).length(), sizing.at_edge(a, b, params.edge_length)))
    }
}

/// What one pass of [`resize_cells`](Complex::resize_cells) judged: the
/// cells below `end`, at move clock `clock`, and the cells whose split failed.
struct JudgedPass {
    clock: u64,
    end: usize,
    failed_splits: Vec<CellId>,
}

impl JudgedPass {
    /// Whether the pass judged `c` and left it in place without trying a
    /// split that failed, and no corner of it has moved since.
    fn left_alone<K: Dim>(&self, complex: &Complex<K>, c: CellId) -> bool {
        c.index() < self.end
            && complex
                .cell(c)
                .iter()
                .all(|&w| complex.moved_at(w) <= self.clock)
            && self.failed_splits.binary_search(&c).is_err()
    }
}
