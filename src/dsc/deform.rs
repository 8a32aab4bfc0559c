//! `deform`: move vertices towards destinations, improving the mesh between rounds.

use super::improve::ImproveStats;
use super::resize::ResizeStats;
use super::{Connectivity, DscParams, DscWorkspace, SizingField};
use crate::complex::{CellId, Complex, VertexId};
use crate::dim::Dim;
use crate::dim::Point;
use crate::ops::{CollapseMode, MoveOutcome};
use serde::Serialize;

/// Destinations for some vertices, indexed by vertex id.
#[derive(Clone, Debug)]
pub struct Destinations<K: Dim> {
    targets: Vec<Option<K::Point>>,
}

impl<K: Dim> Destinations<K> {
    /// No destinations, sized for `complex`.
    pub fn new(complex: &Complex<K>) -> Self {
        Destinations {
            targets: vec![None; complex.vertex_capacity()],
        }
    }
    /// Sets the destination of `v`.
    pub fn set(&mut self, v: VertexId, p: K::Point) {
        if v.index() >= self.targets.len() {
            self.targets.resize(v.index() + 1, None);
        }
        self.targets[v.index()] = Some(p);
    }
    /// The destination of `v`, if any.
    pub fn get(&self, v: VertexId) -> Option<K::Point> {
        self.targets.get(v.index()).copied().flatten()
    }
    /// Removes every destination (keeps the allocation).
    pub fn clear(&mut self) {
        self.targets.iter_mut().for_each(|t| *t = None);
    }
    /// Vertices that have a destination.
    pub fn len(&self) -> usize {
        self.targets.iter().filter(|t| t.is_some()).count()
    }
    /// Whether no vertex has a destination.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// What one `deform` call did.
#[derive(Clone, Debug, Default, Serialize)]
pub struct DeformReport {
    /// Move-and-improve rounds run.
    pub rounds: usize,
    /// Vertices that reached their destination.
    pub arrived: usize,
    /// Vertices that stopped short (blocked, collapsed away or out of rounds); not an error.
    pub stopped_short: usize,
    /// Vertices headed for the domain border that were merged onto it (see `snap_to_border`).
    pub snapped: usize,
    /// Improvement counts, summed over rounds and the final resize.
    pub improve: ImproveStats,
    /// Resize counts.
    pub resize: ResizeStats,
}

/// Layer `dsc`: the deformation (move, improve, resize, compact).
impl<K: Connectivity> Complex<K> {
    /// The DSC deformation: each vertex
    /// with a destination moves as far as it can without inverting a cell, one
    /// vertex at a time; the mesh is improved; this repeats until every vertex has
    /// arrived or `max_rounds` is reached; then the mesh is resized and improved,
    /// and finally compacted (ids held from before the call are invalid after it).
    pub fn deform(&mut self, destinations: &Destinations<K>, params: &DscParams) -> DeformReport {
        self.deform_with(destinations, params, &mut DscWorkspace::new())
    }

    /// [`deform`](Self::deform) with a workspace kept across calls (as the
    /// segmentation does, once per iteration): the same result, without
    /// allocating once the workspace's buffers have grown.
    pub fn deform_with(
        &mut self,
        destinations: &Destinations<K>,
        params: &DscParams,
        ws: &mut DscWorkspace<K>,
    ) -> DeformReport {
        let mut report = DeformReport::default();
        let tol = params.tolerance();
        // The verdicts of the last call are about cells and vertices that
        // the compaction ending it renumbered (or about another complex).
        ws.memo.forget();
        let mut pending = std::mem::take(&mut ws.pending);
        let mut movers = std::mem::take(&mut ws.movers);
        let mut touched = std::mem::take(&mut ws.touched);
        let mut star = self.take_list();
        pending.clear();
        pending.extend(
            (0..destinations.targets.len() as u32)
                .map(VertexId)
                .filter(|&v| destinations.get(v).is_some() && self.is_vertex_alive(v)),
        );
        let requested = pending.len();
        touched.clear();
        touched.extend_from_slice(&pending);
        while !pending.is_empty() && report.rounds < params.max_rounds {
            report.rounds += 1;
            movers.clear();
            movers.extend_from_slice(&pending);
            pending.retain(|&v| {
                if !self.is_vertex_alive(v) {
                    return false;
                }
                let dest = destinations
                    .get(v)
                    .expect("pending vertices have destinations");
                match self.move_towards(v, dest, tol, &mut star) {
                    MoveOutcome::Arrived => {
                        report.arrived += 1;
                        false
                    }
                    MoveOutcome::Partial(_) | MoveOutcome::Blocked => true,
                }
            });
            report.snapped +=
                self.snap_to_border(&mut pending, destinations, params, &ws.sizing, &mut star);
            add(
                &mut report.improve,
                self.improve_near_with(&movers, params, ws),
            );
        }
        report.stopped_short = requested - report.arrived - report.snapped;
        report.resize = self.resize_with(
            params,
            &ws.sizing,
            &mut touched,
            &mut ws.edges,
            &mut ws.refusals,
            &mut ws.flat_ends,
        );
        touched.retain(|&v| self.is_vertex_alive(v));
        add(
            &mut report.improve,
            self.improve_near_with(&touched, params, ws),
        );
        self.give_back(star);
        self.compact_in_place();
        ws.refusals.follow_compaction(self);
        ws.memo.follow_compaction(self);
        (ws.pending, ws.movers, ws.touched) = (pending, movers, touched);
        report
    }
}

/// Layer `dsc`: snapping vertices to the domain border.
impl<K: Connectivity> Complex<K> {
    /// A vertex heading for a box face is blocked by the thin cells between it
    /// and the face: it may only go half-way to them, so it would approach the
    /// border forever (the paper's Fig. 5 artifact). Once it is closer than
    /// `min_length·h` to the face, merge it with the nearest interior vertex on
    /// that face (an unsafe collapse placed on the face), so the interface
    /// reaches the border and then slides along it. Returns how many snapped.
    fn snap_to_border(
        &mut self,
        pending: &mut Vec<VertexId>,
        destinations: &Destinations<K>,
        params: &DscParams,
        sizing: &SizingField,
        star: &mut Vec<CellId>,
    ) -> usize {
        let (lo, hi) = self.domain();
        let mut snapped = 0;
        pending.retain(|&v| {
            if !self.is_vertex_alive(v) {
                return false;
            }
            let target = self.constrain(
                v,
                destinations
                    .get(v)
                    .expect("pending vertices have destinations"),
            );
            let p = self.position(v);
            let reach = params.min_length * sizing.at(&p, params.edge_length);
            let here = self.class(v).boundary;
            let mut face = None;
            for axis in 0..K::N {
                for (bit, bound) in [(2 * axis, lo[axis]), (2 * axis + 1, hi[axis])] {
                    if target[axis] == bound
                        && here & (1 << bit) == 0
                        && (p[axis] - bound).abs() < reach
                    {
                        face = Some(1u8 << bit);
                    }
                }
            }
            let Some(face) = face else { return true };
            self.star_into(v, star);
            let mut best: Option<(f64, VertexId)> = None;
            for &c in star.iter() {
                for &w in self.cell(c) {
                    let class = self.class(w);
                    if w != v && class.boundary & face != 0 && !class.on_interface() {
                        let d = (self.position(w) - p).length();
                        if best.is_none_or(|(bd, _)| d < bd) {
                            best = Some((d, w));
                        }
                    }
                }
            }
            let Some((_, w)) = best else { return true };
            let snap =
                self.collapse_edge(v, w, CollapseMode::Unsafe, params.degenerate_quality, 1.0);
            if snap.is_ok() {
                snapped += 1;
            }
            snap.is_err()
        });
        snapped
    }
}

fn add(total: &mut ImproveStats, s: ImproveStats) {
    total.smoothed += s.smoothed;
    total.flips += s.flips;
    total.safe_collapses += s.safe_collapses;
    total.unsafe_collapses += s.unsafe_collapses;
    total.degenerate_splits += s.degenerate_splits;
}
