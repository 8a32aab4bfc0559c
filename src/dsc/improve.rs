//! Mesh improvement between moves: smoothing, flips, removal of degenerate cells.

use super::splits_made::SplitsMade;
use super::workspace::{RegionBuffers, SeedStars, WalkScratch};
use super::{DscParams, DscWorkspace, SizingField};
use crate::complex::{CellId, Complex, Rejection, VertexId};
use crate::dim::{Dim, D2, D3};
use crate::ops::{edge_settled, CollapseMode, ImproveMemo, JudgedTet, SmoothScratch, StarCache};
use rayon::prelude::*;
use serde::Serialize;
use smallvec::SmallVec;

/// A 3D region whose seeds number at least a this-th of the cells is
/// collected by one pass over the cells (a 3D star holds 20–30 cells, so
/// the stars of that many seeds visit every cell of the mesh a few times
/// over)...
const SEEDS_FOR_A_SCAN: usize = 8;
/// ...or a 128th, in a mesh of at least [`MESH_OUT_OF_CACHE_FROM`] cells:
/// there a star search meets its cells scattered in memory, at some 60 ns
/// each, while the pass reads every cell's corners in id order at a few ns
/// (the brain phantom at `--size 120` took 0.9× the time, its deform stage
/// 0.84×, in the same 73 iterations).
const SEEDS_FOR_A_SCAN_OUT_OF_CACHE: usize = 128;
/// The cells of a mesh whose arrays (32 bytes of corners and neighbours
/// per cell) outgrow the caches: 4 MiB of them.
const MESH_OUT_OF_CACHE_FROM: usize = 1 << 17;

/// Whether a 3D region of `seeds` seeds in a mesh of `cells` cells is
/// collected by one pass over the cells (see [`SEEDS_FOR_A_SCAN`]).
fn scan_for_region(seeds: usize, cells: usize) -> bool {
    let ratio = if cells >= MESH_OUT_OF_CACHE_FROM {
        SEEDS_FOR_A_SCAN_OUT_OF_CACHE
    } else {
        SEEDS_FOR_A_SCAN
    };
    seeds * ratio >= cells
}

/// A 3D region of at least this many seeds (and fewer than a scan takes)
/// has its seeds' stars searched on rayon's threads.
const PARALLEL_REGION_FROM: usize = 512;
/// Seeds per chunk of that search.
const REGION_CHUNK: usize = 128;
/// A 3D removal of degenerate cells over at least this many cells judges
/// them on rayon's threads first.
const JUDGE_AHEAD_FROM: usize = 4096;
/// About how many tetrahedra share a vertex of a graded 3D mesh: the
/// capacity a chunk's stars are collected in.
const CELLS_PER_STAR_3D: usize = 24;

/// The dimension-specific connectivity improvement (2D edge flips, 3D flips).
pub trait Connectivity: Dim {
    /// Improves the connectivity of the cells of `region` (flips, at most a
    /// few sweeps); returns the number of changes. Leaves `region` current
    /// if it still is.
    /// `memo` skips the tests whose answer is known (see [`ImproveMemo`]).
    fn improve_connectivity_in(
        complex: &mut Complex<Self>,
        region: &mut Region,
        params: &DscParams,
        memo: &mut ImproveMemo,
    ) -> usize;

    /// One improvement pass over the whole complex; returns the number of changes.
    fn improve_connectivity(complex: &mut Complex<Self>, params: &DscParams) -> usize {
        let mut memo = ImproveMemo::new();
        Self::improve_connectivity_in(complex, &mut Region::everything(), params, &mut memo)
    }
}

/// The cells an improvement works on: those around some seed vertices
/// ([`Complex::region_cells`]), or every cell. They are kept while they are
/// known to be current: smoothing moves vertices but keeps every cell and
/// star, and a flip sweep or a degenerate-cell removal that changed nothing
/// keeps them too, so the region is not walked again after each of them.
#[derive(Debug)]
pub struct Region<'s> {
    /// `None`: every live cell, in id order.
    seeds: Option<&'s [VertexId]>,
    buffers: RegionBuffers,
    current: bool,
}

impl<'s> Region<'s> {
    /// The cells around `seeds`.
    pub fn around(seeds: &'s [VertexId]) -> Self {
        Self::around_in(seeds, RegionBuffers::default())
    }

    /// The cells around `seeds`, collected into `buffers` (given back by
    /// [`into_buffers`](Self::into_buffers)).
    pub(crate) fn around_in(seeds: &'s [VertexId], mut buffers: RegionBuffers) -> Self {
        // (stars kept are of other seeds)
        buffers.stars.clear();
        Region {
            seeds: Some(seeds),
            buffers,
            current: false,
        }
    }

    /// Every cell.
    pub fn everything() -> Self {
        Region {
            seeds: None,
            buffers: RegionBuffers::default(),
            current: false,
        }
    }

    /// The cells, collected again unless they are current.
    pub fn cells<K: Connectivity>(&mut self, complex: &Complex<K>) -> &[CellId] {
        self.cells_kept(complex, None)
    }

    /// [`cells`](Self::cells), taking the 3D stars of the seeds from
    /// `kept` where they stand there and keeping those searched.
    pub(crate) fn cells_kept<K: Connectivity>(
        &mut self,
        complex: &Complex<K>,
        kept: Option<&mut StarCache>,
    ) -> &[CellId] {
        if !self.current {
            let b = &mut self.buffers;
            match self.seeds {
                Some(seeds) => complex.collect_region(seeds, b, kept),
                None => {
                    b.cells.clear();
                    b.cells.extend(complex.cell_ids());
                }
            }
            self.current = true;
        }
        &self.buffers.cells
    }

    /// Marks the cells stale: the connectivity changed.
    pub fn invalidate(&mut self) {
        self.current = false;
    }

    /// The buffers, for the next region.
    pub(crate) fn into_buffers(self) -> RegionBuffers {
        self.buffers
    }
}

impl Connectivity for D2 {
    /// Flips non-interface edges until the triangulation is locally Delaunay
    /// within each phase (bounded number of sweeps).
    fn improve_connectivity_in(
        complex: &mut Complex<D2>,
        region: &mut Region,
        _params: &DscParams,
        memo: &mut ImproveMemo,
    ) -> usize {
        memo.sync(complex);
        flip_sweeps(complex, region, memo)
    }
}

/// Flips until nothing changes (at most 8 sweeps) over the region's cells.
///
/// An edge that `memo` knows was tested since its quad last changed is not
/// tested again (it would not flip): a second sweep tests only around the
/// flips of the first, and later passes in the same deform only where
/// vertices moved. The flips made, and their order, are those of testing
/// every edge.
fn flip_sweeps(complex: &mut Complex<D2>, region: &mut Region, memo: &mut ImproveMemo) -> usize {
    let mut flips = 0;
    for _sweep in 0..8 {
        let mut changed = 0;
        for &c in region.cells(complex) {
            if complex.is_alive(c) && memo.quad_settled(complex, c) {
                continue;
            }
            let neighbours_below = complex.cell_capacity() as u32;
            let verdict = memo.settled_cell(complex, c);
            for i in 0..3 {
                if !complex.is_alive(c) {
                    break;
                }
                if verdict.is_some_and(|stamp| edge_settled(complex, c, i, stamp)) {
                    continue;
                }
                if let Ok(true) = complex.flip_if_better(c, i) {
                    changed += 1;
                }
            }
            if complex.is_alive(c) {
                memo.set_settled(complex, c, neighbours_below);
            }
        }
        flips += changed;
        if changed == 0 {
            break;
        }
        region.invalidate();
    }
    flips
}

impl Connectivity for D3 {
    /// Visits every tet of the region below `low_quality` and tries edge
    /// removal (3-2, 4-4 and larger rings) on its edges, then 2-3 flips on
    /// its facets, off the interface, accepting a flip only when the smallest
    /// quality of the tets involved increases (at most 4 sweeps). A tet
    /// whose flips `memo` knows were all refused, nothing around it having
    /// changed since, is not tried again (the same flips result).
    fn improve_connectivity_in(
        complex: &mut Complex<D3>,
        region: &mut Region,
        params: &DscParams,
        memo: &mut ImproveMemo,
    ) -> usize {
        memo.refused_flips.sync(complex, params.low_quality);
        memo.qualities.sync(complex);
        memo.not_poor.clear();
        memo.not_poor.resize(complex.cell_capacity(), false);
        let compactions = complex.compactions();
        let mut flips = 0;
        let mut poor = complex.take_list();
        let mut judged = std::mem::take(&mut memo.judged);
        for _sweep in 0..4 {
            debug_assert_eq!(complex.compactions(), compactions, "not_poor is by cell id");
            let mut changed = 0;
            // (flips move no vertex, so a tet's quality, read before the
            // sweep, holds while it lives)
            cells_below_quality(
                complex,
                region.cells(complex),
                params.low_quality,
                memo,
                &mut judged,
                &mut poor,
            );
            let refused = &mut memo.refused_flips;
            for &c in &poor {
                // (judged now: a flip earlier in the sweep may have changed
                // the tets around one refused before it)
                if refused.still_refused(complex, c) {
                    continue;
                }
                if complex
                    .improve_tet_remembering(c, 0.0, &mut memo.refused_edges, &memo.qualities)
                    .is_some()
                {
                    changed += 1;
                } else if complex.is_alive(c) {
                    refused.record(complex, c);
                }
            }
            flips += changed;
            if changed == 0 {
                break;
            }
            region.invalidate();
        }
        complex.give_back(poor);
        memo.judged = judged;
        flips
    }
}

/// Regions of fewer vertices have their stars searched for degenerate
/// cells on one thread.
const PARALLEL_STARS_FROM: usize = 4096;

/// Regions of fewer cells are searched for poor tets on one thread.
const PARALLEL_QUALITY_FROM: usize = 8192;

/// The live cells of `cells` whose quality is below `threshold`, in their
/// order, into `out` (judged on rayon's threads for a large region). A tet
/// whose flips `memo` knows to be refused is taken without its quality: it
/// was below the threshold then, and its corners have not moved. A tet an
/// earlier sweep of the same improvement found at or above the threshold
/// (`memo.not_poor`) is left without a look. Other tets' qualities come
/// from `memo` where no corner moved since it recorded them; those
/// computed now are recorded. `judged` is scratch.
fn cells_below_quality(
    complex: &Complex<D3>,
    cells: &[CellId],
    threshold: f64,
    memo: &mut ImproveMemo,
    judged: &mut Vec<JudgedTet>,
    out: &mut Vec<CellId>,
) {
    let known = &*memo;
    let judge = |&c: &CellId| -> Option<JudgedTet> {
        if !complex.is_alive(c) || known.not_poor.get(c.index()).is_some_and(|&fine| fine) {
            return None;
        }
        Some(if known.refused_flips.still_refused(complex, c) {
            JudgedTet::Refused(c)
        } else if let Some(q) = known.qualities.current(complex, c) {
            JudgedTet::Known(c, q)
        } else {
            JudgedTet::Computed(c, complex.quality(c))
        })
    };
    judged.clear();
    if cells.len() < PARALLEL_QUALITY_FROM {
        judged.extend(cells.iter().filter_map(judge));
    } else {
        judged.par_extend(cells.par_iter().filter_map(judge));
    }
    out.clear();
    for &tet in judged.iter() {
        let (c, poor) = match tet {
            JudgedTet::Refused(c) => (c, true),
            JudgedTet::Known(c, q) => (c, q < threshold),
            JudgedTet::Computed(c, q) => {
                memo.qualities.record(complex, c, q);
                (c, q < threshold)
            }
        };
        if poor {
            out.push(c);
        } else if let Some(fine) = memo.not_poor.get_mut(c.index()) {
            *fine = true;
        }
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

/// Layer `dsc`: mesh improvement (smoothing, flips, degenerate cells).
impl<K: Connectivity> Complex<K> {
    /// Smooths, flips, removes degenerate cells and smooths again, everywhere.
    pub fn improve(&mut self, params: &DscParams) -> ImproveStats {
        let all: Vec<VertexId> = self.vertex_ids().collect();
        self.improve_near(&all, params)
    }

    /// [`improve`](Self::improve) restricted to the cells around `seeds`: the
    /// deform loop passes the vertices it moved, so the cost follows the
    /// interface, not the mesh.
    pub fn improve_near(&mut self, seeds: &[VertexId], params: &DscParams) -> ImproveStats {
        self.improve_near_with(seeds, params, &mut DscWorkspace::new())
    }

    /// [`improve_near`](Self::improve_near) with a workspace kept across
    /// calls about this complex: its memo remembers what the improvement
    /// verified (see [`ImproveMemo`]), and its buffers are reused.
    pub(crate) fn improve_near_with(
        &mut self,
        seeds: &[VertexId],
        params: &DscParams,
        ws: &mut DscWorkspace<K>,
    ) -> ImproveStats {
        ws.memo.sync(self);
        ws.memo.sync_thresholds([
            params.degenerate_quality,
            params.degenerate_measure,
            params.degenerate_length,
            params.edge_length,
        ]);
        let mut stats = ImproveStats::default();
        let mut region = Region::around_in(seeds, std::mem::take(&mut ws.region));
        ws.memo.stars.sync(self);
        let cells = region.cells_kept(self, Some(&mut ws.memo.stars));
        self.region_vertices(cells, &mut ws.vertices, &mut ws.walk.vertex_marks);
        stats.smoothed += self.smooth_vertices_with(&ws.vertices, &mut ws.memo, &mut ws.smooth);
        stats.flips += K::improve_connectivity_in(self, &mut region, params, &mut ws.memo);
        let (safe, unsafe_, splits) = self.remove_degenerate_around(&mut region, params, ws);
        if safe + unsafe_ + splits > 0 {
            region.invalidate();
        }
        stats.safe_collapses += safe;
        stats.unsafe_collapses += unsafe_;
        stats.degenerate_splits += splits;
        stats.flips += K::improve_connectivity_in(self, &mut region, params, &mut ws.memo);
        stats.smoothed += self.smooth_vertices_with(&ws.vertices, &mut ws.memo, &mut ws.smooth);
        ws.region = region.into_buffers();
        stats
    }

    /// Removes the degenerate cells of `region` grown by one ring, if the
    /// memo does not show that there are none; returns the (safe, unsafe,
    /// split) counts.
    fn remove_degenerate_around(
        &mut self,
        region: &mut Region,
        params: &DscParams,
        ws: &mut DscWorkspace<K>,
    ) -> (usize, usize, usize) {
        let region_cells = region.cells(self);
        if !self.degenerate_near(region_cells, params, &ws.sizing, &mut ws.memo, &mut ws.walk) {
            return (0, 0, 0);
        }
        let cells = &mut ws.grown;
        cells.clear();
        cells.extend_from_slice(region_cells);
        let marks = &mut ws.grown_marks;
        marks.clear();
        marks.resize(self.cell_capacity(), false);
        for &c in cells.iter() {
            marks[c.index()] = true;
        }
        self.grow_region(cells, marks, &mut ws.walk);
        self.remove_degenerate_with(cells, params, &ws.sizing, &mut ws.walk)
    }

    /// The live cells around `seeds` (the union of their stars, each cell
    /// once): only there can a move have spoilt the mesh. `marks` is scratch.
    pub fn region_cells(&self, seeds: &[VertexId], out: &mut Vec<CellId>, marks: &mut Vec<bool>) {
        self.region_cells_with(seeds, out, marks, &mut Vec::new());
    }

    /// [`region_cells`](Self::region_cells) with a scratch star. In 3D a
    /// region of many seeds comes in cell id order rather than star by star.
    fn region_cells_with(
        &self,
        seeds: &[VertexId],
        out: &mut Vec<CellId>,
        marks: &mut Vec<bool>,
        star: &mut Vec<CellId>,
    ) {
        out.clear();
        marks.clear();
        if K::N == 3 && scan_for_region(seeds.len(), self.cell_count()) {
            // Many seeds (the interface of a folded volume is most of its
            // mesh): one pass over the cells in id order, each taken if a
            // corner is a seed, instead of a search of every seed's star.
            marks.resize(self.vertex_capacity(), false);
            for &v in seeds {
                marks[v.index()] = self.is_vertex_alive(v);
            }
            let marks = &marks[..];
            let touches_a_seed =
                |c: CellId| self.is_alive(c) && self.cell(c).iter().any(|w| marks[w.index()]);
            // (in id order on any number of threads)
            out.par_extend(
                (0..self.cell_capacity() as u32)
                    .into_par_iter()
                    .map(CellId::new)
                    .filter(|&c| touches_a_seed(c)),
            );
            return;
        }
        marks.resize(self.cell_capacity(), false);
        self.for_each_star(seeds, None, star, |cells| {
            for &c in cells {
                if !marks[c.index()] {
                    marks[c.index()] = true;
                    out.push(c);
                }
            }
        });
    }

    /// Hands `take` the star of every vertex of `seeds`, in seed order
    /// (empty for a dead one), copied from `kept` where it stands there. In
    /// 3D many seeds have their stars searched on rayon's threads first, a
    /// chunk of seeds each: the same stars in the same order. `star` is
    /// scratch.
    fn for_each_star(
        &self,
        seeds: &[VertexId],
        kept: Option<&StarCache>,
        star: &mut Vec<CellId>,
        mut take: impl FnMut(&[CellId]),
    ) {
        if K::N == 3 && seeds.len() >= PARALLEL_REGION_FROM && rayon::current_num_threads() > 1 {
            let stars: Vec<SeedStars> = seeds
                .par_chunks(REGION_CHUNK)
                .map_init(Vec::new, |star, chunk| {
                    let mut stars = SeedStars::default();
                    stars.cells.reserve(chunk.len() * CELLS_PER_STAR_3D);
                    for &v in chunk {
                        self.live_star_into(v, kept, star);
                        stars.push(star);
                    }
                    stars
                })
                .collect();
            for chunk in &stars {
                (0..chunk.ends.len()).for_each(|i| take(chunk.star(i)));
            }
            return;
        }
        for &v in seeds {
            self.live_star_into(v, kept, star);
            take(star);
        }
    }

    /// The star of `v` into `star` (copied from `kept` where it stands
    /// there); empty if `v` is dead.
    fn live_star_into(&self, v: VertexId, kept: Option<&StarCache>, star: &mut Vec<CellId>) {
        if !self.is_vertex_alive(v) {
            star.clear();
        } else if let Some(cells) = kept.and_then(|k| k.current(self, v)) {
            star.clear();
            star.extend_from_slice(cells);
        } else {
            self.star_into(v, star);
        }
    }

    /// The cells of a region around `seeds` into `b.cells`, as
    /// [`region_cells_with`](Self::region_cells_with) collects them. In 3D,
    /// where the region is collected star by star, the seeds' stars are
    /// kept (`b.stars`), and a later collection of the same region (after
    /// flips or collapses changed some cells) searches only the stars of
    /// the seeds around which a cell was created or removed since: the
    /// others would be found again cell for cell.
    ///
    /// A first collection takes the stars from `kept` where they stand
    /// there, and keeps there those it searched.
    fn collect_region(
        &self,
        seeds: &[VertexId],
        b: &mut RegionBuffers,
        kept: Option<&mut StarCache>,
    ) {
        if K::N != 3 || scan_for_region(seeds.len(), self.cell_count()) {
            b.stars.clear();
            self.region_cells_with(seeds, &mut b.cells, &mut b.marks, &mut b.star);
            return;
        }
        let now = (self.move_clock(), self.compactions());
        match b.stars.at {
            Some((clock, compactions)) if compactions == now.1 => {
                self.renew_seed_stars(seeds, clock, b);
            }
            _ => self.search_seed_stars(seeds, b, kept),
        }
        b.stars.at = Some(now);
        b.cells.clear();
        b.marks.clear();
        b.marks.resize(self.cell_capacity(), false);
        for &c in &b.stars.cells {
            if !b.marks[c.index()] {
                b.marks[c.index()] = true;
                b.cells.push(c);
            }
        }
    }

    /// The stars of `seeds` into `b.stars`: from `kept` where they stand
    /// there (read on the threads with the searches), the others searched
    /// and then kept there.
    fn search_seed_stars(
        &self,
        seeds: &[VertexId],
        b: &mut RegionBuffers,
        kept: Option<&mut StarCache>,
    ) {
        b.stars.clear();
        let stars = &mut b.stars;
        self.for_each_star(seeds, kept.as_deref(), &mut b.star, |star| stars.push(star));
        let Some(kept) = kept else {
            return;
        };
        for (i, &v) in seeds.iter().enumerate() {
            if self.is_vertex_alive(v) && kept.current(self, v).is_none() {
                kept.keep(self, v, b.stars.star(i));
            }
        }
    }

    /// `b.stars`, current at move clock `clock`, made current now: the
    /// star of each seed around which a cell was created or removed since
    /// is searched again, the others are kept.
    fn renew_seed_stars(&self, seeds: &[VertexId], clock: u64, b: &mut RegionBuffers) {
        let (old, new) = (&b.stars, &mut b.spare_stars);
        new.clear();
        for (i, &v) in seeds.iter().enumerate() {
            if !self.is_vertex_alive(v) {
                new.push(&[]);
            } else if self.cells_changed_at(v) <= clock {
                new.push(old.star(i));
            } else {
                self.star_into(v, &mut b.star);
                new.push(&b.star);
            }
        }
        std::mem::swap(&mut b.stars, &mut b.spare_stars);
    }

    /// Whether a cell sharing a vertex with `cells` (a cell of the region
    /// [`grow_region`](Self::grow_region) makes) is degenerate. Usually none
    /// is, and then removing degenerate cells there changes nothing: this
    /// answers that without listing the region, walking only the stars that
    /// changed since `memo` last found them free of degenerate cells.
    fn degenerate_near(
        &self,
        cells: &[CellId],
        params: &DscParams,
        sizing: &SizingField,
        memo: &mut ImproveMemo,
        walk: &mut WalkScratch,
    ) -> bool {
        self.region_vertices(cells, &mut walk.vertices, &mut walk.vertex_marks);
        // (the recorded qualities are read only about this complex as it
        // is numbered now)
        memo.qualities.sync(self);
        memo.stars.sync(self);
        let star_degenerate = |v: VertexId, star: &mut Vec<CellId>, memo: &ImproveMemo| {
            self.star_into(v, star);
            star.iter()
                .any(|&c| self.is_degenerate_remembered(c, params, sizing, memo))
        };
        if walk.vertices.len() < PARALLEL_STARS_FROM || rayon::current_num_threads() < 2 {
            // Neighbouring stars share most of their cells: each is measured
            // once (the search stops at the first degenerate one, so every
            // cell met again was found sound).
            walk.checked.start(self.cell_capacity());
            for &v in &walk.vertices {
                if memo.still_sound(self, v) {
                    continue;
                }
                memo.stars.star_into(self, v, &mut walk.star);
                for &c in &walk.star {
                    if walk.checked.contains(c) {
                        continue;
                    }
                    if self.is_degenerate_remembered(c, params, sizing, memo) {
                        return true;
                    }
                    walk.checked.insert(c);
                }
                memo.set_sound(self, v);
            }
            return false;
        }
        // Every star's answer at once (nothing changes meanwhile), then the
        // verdicts recorded in order up to the first degenerate star, as the
        // walk above records them.
        let memo_now = &*memo;
        let unsound = || {
            walk.vertices
                .par_iter()
                .filter(|&&v| !memo_now.still_sound(self, v))
                .count()
        };
        if K::N == 3 && scan_for_region(unsound(), self.cell_count()) {
            self.mark_degenerate_stars(params, sizing, memo_now, walk);
        } else {
            walk.degenerate
                .par_extend(walk.vertices.par_iter().map_init(Vec::new, |star, &v| {
                    !memo_now.still_sound(self, v) && star_degenerate(v, star, memo_now)
                }));
        }
        let mut found = false;
        for (&v, &degenerate) in walk.vertices.iter().zip(&walk.degenerate) {
            if memo.still_sound(self, v) {
                continue;
            }
            if degenerate {
                found = true;
                break;
            }
            memo.set_sound(self, v);
        }
        walk.degenerate.clear();
        found
    }

    /// Sets `walk.degenerate`, per vertex of `walk.vertices`, to whether it
    /// is not still sound (`memo`) and its star holds a degenerate cell, by
    /// one pass over the cells instead of a search of each star: when the
    /// vertices to judge are many (the interface of a folded volume is most
    /// of its mesh), their stars cover the cells about four times over (a
    /// tet lies in the star of each corner), so each cell is judged once
    /// here where the stars would judge it up to four times.
    fn mark_degenerate_stars(
        &self,
        params: &DscParams,
        sizing: &SizingField,
        memo: &ImproveMemo,
        walk: &mut WalkScratch,
    ) {
        let judged = &mut walk.vertex_marks;
        judged.clear();
        judged.resize(self.vertex_capacity(), false);
        for &v in &walk.vertices {
            judged[v.index()] = !memo.still_sound(self, v);
        }
        let judged = &judged[..];
        let degenerate = &mut walk.degenerate_cells;
        degenerate.clear();
        degenerate.par_extend(
            (0..self.cell_capacity() as u32)
                .into_par_iter()
                .map(CellId::new)
                .filter(|&c| {
                    self.is_alive(c)
                        && self.cell(c).iter().any(|w| judged[w.index()])
                        && self.is_degenerate_remembered(c, params, sizing, memo)
                }),
        );
        let in_a_degenerate_star = &mut walk.star_marks;
        in_a_degenerate_star.clear();
        in_a_degenerate_star.resize(self.vertex_capacity(), false);
        for &c in degenerate.iter() {
            for &w in self.cell(c) {
                in_a_degenerate_star[w.index()] = true;
            }
        }
        walk.degenerate.clear();
        walk.degenerate.extend(
            walk.vertices
                .iter()
                .map(|&v| judged[v.index()] && in_a_degenerate_star[v.index()]),
        );
    }

    /// The region grown by one ring: every cell sharing a vertex with `cells`.
    /// Squeezed cells between two meeting fronts need not touch a vertex that
    /// moved in this round, but they always touch one that shares a cell with it.
    fn grow_region(&self, cells: &mut Vec<CellId>, marks: &mut Vec<bool>, walk: &mut WalkScratch) {
        marks.resize(self.cell_capacity(), false);
        self.region_vertices(cells, &mut walk.vertices, &mut walk.vertex_marks);
        self.for_each_star(&walk.vertices, None, &mut walk.star, |star| {
            for &c in star {
                if !marks[c.index()] {
                    marks[c.index()] = true;
                    cells.push(c);
                }
            }
        });
    }

    /// The vertices of `cells` (each once). `marks` is scratch.
    fn region_vertices(&self, cells: &[CellId], out: &mut Vec<VertexId>, marks: &mut Vec<bool>) {
        out.clear();
        marks.clear();
        marks.resize(self.vertex_capacity(), false);
        for &c in cells {
            for &w in self.cell(c) {
                if !marks[w.index()] {
                    marks[w.index()] = true;
                    out.push(w);
                }
            }
        }
    }

    /// One Laplacian pass over the given vertices (interface vertices are skipped).
    pub fn smooth_vertices(&mut self, vertices: &[VertexId], memo: &mut ImproveMemo) -> usize {
        self.smooth_vertices_with(vertices, memo, &mut SmoothScratch::default())
    }

    /// [`smooth_vertices`](Self::smooth_vertices) with reused scratch space.
    fn smooth_vertices_with(
        &mut self,
        vertices: &[VertexId],
        memo: &mut ImproveMemo,
        scratch: &mut SmoothScratch<K>,
    ) -> usize {
        memo.sync(self);
        self.smooth_pass(vertices, scratch, memo)
    }

    /// Whether a cell is degenerate by quality, measure or edge length.
    pub fn is_degenerate(&self, c: CellId, params: &DscParams) -> bool {
        self.is_degenerate_sized(c, params, &SizingField::uniform())
    }

    /// [`is_degenerate`](Self::is_degenerate) with the measure and length
    /// thresholds taken at the target size `h` of the cell's centroid.
    pub fn is_degenerate_sized(&self, c: CellId, params: &DscParams, sizing: &SizingField) -> bool {
        self.is_degenerate_known(c, params, sizing, None)
    }

    /// [`is_degenerate_sized`](Self::is_degenerate_sized) with the
    /// quality of `c` if it is known (recorded while no corner moved since:
    /// the same bits as computing it).
    fn is_degenerate_known(
        &self,
        c: CellId,
        params: &DscParams,
        sizing: &SizingField,
        quality: Option<f64>,
    ) -> bool {
        // (the exact comparison, without the square root of the quality;
        // every test on one read of the corners)
        let pts = self.cell_points(c);
        let pts = &pts[..K::NV];
        let h = sizing.at_cell(pts, params.edge_length);
        let poor = match quality {
            Some(q) => q < params.degenerate_quality,
            None => !K::quality_oriented_at_least(pts, params.degenerate_quality),
        };
        if poor || K::signed_measure(pts) < params.degenerate_measure * K::regular_measure(h) {
            return true;
        }
        // (the square root is increasing, so the shortest length is the
        // root of the shortest squared length, bit for bit: one root, not six)
        let mut shortest_squared = f64::INFINITY;
        for i in 0..K::NV {
            for j in i + 1..K::NV {
                let d = pts[i] - pts[j];
                shortest_squared = shortest_squared.min(crate::dim::Point::dot(&d, &d));
            }
        }
        shortest_squared.sqrt() < params.degenerate_length * h
    }

    /// Whether `c` is degenerate ([`is_degenerate_sized`](Self::is_degenerate_sized)),
    /// with its quality from `memo` where recorded and current.
    fn is_degenerate_remembered(
        &self,
        c: CellId,
        params: &DscParams,
        sizing: &SizingField,
        memo: &ImproveMemo,
    ) -> bool {
        self.is_degenerate_known(c, params, sizing, memo.qualities.current(self, c))
    }

    /// Removes degenerate cells by collapsing their edges, shortest first: a
    /// safe collapse where one exists, otherwise an unsafe one (which may merge
    /// interfaces: the DSC's topology change). In 3D a degenerate tet that no
    /// collapse removes is split at its longest edge when that is longer than
    /// `L`; the removal neither collapses an edge at a vertex it made so nor
    /// splits a cell with such a corner again (no split–collapse cycles).
    /// Returns the (safe, unsafe, split) counts.
    pub fn remove_degenerate(&mut self, params: &DscParams) -> (usize, usize, usize) {
        let all: Vec<CellId> = self.cell_ids().collect();
        self.remove_degenerate_in(&all, params)
    }

    /// [`remove_degenerate`](Self::remove_degenerate) over the given cells.
    pub(crate) fn remove_degenerate_in(
        &mut self,
        cells: &[CellId],
        params: &DscParams,
    ) -> (usize, usize, usize) {
        self.remove_degenerate_with(
            cells,
            params,
            &SizingField::uniform(),
            &mut WalkScratch::default(),
        )
    }

    /// [`remove_degenerate_in`](Self::remove_degenerate_in) with reused scratch space.
    fn remove_degenerate_with(
        &mut self,
        cells: &[CellId],
        params: &DscParams,
        sizing: &SizingField,
        walk: &mut WalkScratch,
    ) -> (usize, usize, usize) {
        let straight_cos = params.straight_angle_deg.to_radians().cos();
        let (mut safe, mut unsafe_, mut splits) = (0, 0, 0);
        // A worklist: a collapse or split reshapes the star of the vertex it
        // keeps or makes, so that star is checked again. Since no collapse
        // undoes a split and no split cell is split again (`SplitsMade`), the
        // work is bounded by the region; the budget is a last guard only.
        let work = &mut walk.work;
        work.clear();
        work.extend_from_slice(cells);
        let star = &mut walk.star;
        let made = &mut walk.splits;
        made.clear();
        // A large region's cells are judged ahead on rayon's threads; a
        // verdict is taken while no corner of its cell has moved since.
        let (ahead, judged_at) = (&mut walk.ahead, self.move_clock());
        ahead.clear();
        if K::N == 3 && cells.len() >= JUDGE_AHEAD_FROM && rayon::current_num_threads() > 1 {
            ahead.par_extend(
                cells
                    .par_iter()
                    .map(|&c| self.is_alive(c) && self.is_degenerate_sized(c, params, sizing)),
            );
        }
        // The worklist's first `unpopped` entries are still the region's
        // cells in order (work is pushed and popped at the end only).
        let mut unpopped = ahead.len();
        let mut budget = 4 * cells.len() + 16;
        while let Some(c) = work.pop() {
            if budget == 0 {
                break;
            }
            budget -= 1;
            let verdict = (work.len() < unpopped).then(|| {
                unpopped = work.len();
                ahead[unpopped]
            });
            if !self.is_alive(c) {
                continue;
            }
            let degenerate = match verdict {
                Some(d) if self.cell(c).iter().all(|&w| self.moved_at(w) <= judged_at) => d,
                _ => self.is_degenerate_sized(c, params, sizing),
            };
            if !degenerate {
                continue;
            }
            let touched = match self.collapse_cell(c, params, straight_cos, made, star) {
                Some((mode, kept)) => {
                    match mode {
                        CollapseMode::Safe => safe += 1,
                        CollapseMode::Unsafe => unsafe_ += 1,
                    }
                    kept
                }
                // No collapse removes it; split its longest edge if longer
                // than h, unless a split of this removal made the cell.
                None if K::SPLITS_UNCOLLAPSIBLE && !made.holds_a_corner_of(self.cell(c)) => {
                    let (u, v) = self.longest_edge(c);
                    let h = sizing.at_cell(&self.cell_points(c)[..K::NV], params.edge_length);
                    let long =
                        crate::dim::Point::length(&(self.position(u) - self.position(v))) > h;
                    if !long {
                        continue;
                    }
                    match self.split_edge(u, v) {
                        Ok(m) => {
                            splits += 1;
                            made.record(m);
                            m
                        }
                        Err(_) => continue,
                    }
                }
                None => continue,
            };
            self.star_into(touched, star);
            work.extend_from_slice(star);
        }
        (safe, unsafe_, splits)
    }

    /// Tries to collapse one edge of `c`, shortest first, safe before unsafe,
    /// but none at a vertex the removal made by a split (`made`, see
    /// [`SplitsMade`]). `star` is scratch.
    fn collapse_cell(
        &mut self,
        c: CellId,
        params: &DscParams,
        straight_cos: f64,
        made: &SplitsMade,
        star: &mut Vec<CellId>,
    ) -> Option<(CollapseMode, VertexId)> {
        let mut edges = self.sorted_edges(c);
        edges.retain(|&mut (u, v)| !made.holds_an_end_of(u, v));
        // Where degenerate cells cluster, a collapse that removes one may leave
        // the surviving neighbours below the degenerate quality; it is still
        // accepted if it makes no surviving cell worse than the worst one there.
        let bounds: SmallVec<[f64; 6]> = edges
            .iter()
            .map(|&(u, v)| {
                params
                    .degenerate_quality
                    .min(self.worst_surviving_quality(u, v, star))
            })
            .collect();
        for mode in [CollapseMode::Safe, CollapseMode::Unsafe] {
            for (&(u, v), &bound) in edges.iter().zip(&bounds) {
                match self.collapse_edge(u, v, mode, bound, straight_cos) {
                    Ok(kept) => return Some((mode, kept)),
                    Err(Rejection::Stale) => return None,
                    Err(_) => {}
                }
            }
        }
        None
    }

    /// Worst quality of the cells around `u` or `v` that do not contain the edge
    /// `uv` (the cells a collapse of `uv` keeps, reshaped). `star` is scratch.
    fn worst_surviving_quality(&self, u: VertexId, v: VertexId, star: &mut Vec<CellId>) -> f64 {
        let mut worst: f64 = 1.0;
        for w in [u, v] {
            self.star_into(w, star);
            for &c in star.iter() {
                let cell = self.cell(c);
                if !(cell.contains(&u) && cell.contains(&v)) {
                    worst = worst.min(self.quality(c));
                }
            }
        }
        worst
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    /// The 3D region of a large seed set searched on rayon's threads is the
    /// one-thread loop's, cell for cell and in order, with seeds in any
    /// order and some repeated.
    #[test]
    fn a_large_region_is_the_same_on_one_and_two_threads() {
        let complex = Complex::<D3>::cuboid([30.0; 3], 1.5).unwrap();
        let vertices: Vec<VertexId> = complex.vertex_ids().collect();
        for count in [PARALLEL_REGION_FROM - 1, PARALLEL_REGION_FROM, 1500] {
            let mut seeds: Vec<VertexId> = vertices
                .iter()
                .rev()
                .step_by(3)
                .take(count)
                .copied()
                .collect();
            seeds.extend_from_within(..10);
            assert!(!scan_for_region(seeds.len(), complex.cell_count()));
            let region_on = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| {
                    let (mut out, mut marks) = (Vec::new(), Vec::new());
                    complex.region_cells(&seeds, &mut out, &mut marks);
                    out
                })
            };
            assert_eq!(region_on(1), region_on(2), "{count} seeds");
        }
    }

    /// The removal of degenerate cells over a region large enough to be
    /// judged ahead on rayon's threads leaves the mesh the one-thread
    /// removal leaves, vertex for vertex and cell for cell.
    #[test]
    fn degenerate_removal_is_the_same_on_one_and_two_threads() {
        use rand::{Rng, SeedableRng};
        let mut complex = Complex::<D3>::cuboid([18.0; 3], 1.5).unwrap();
        complex.label_by(|p| u32::from((p - nalgebra::Vector3::repeat(9.0)).norm() < 5.0));
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut star = Vec::new();
        let ids: Vec<VertexId> = complex.vertex_ids().collect();
        for v in ids {
            let jitter = nalgebra::Vector3::from_fn(|_, _| rng.random_range(-0.6..0.6));
            complex.move_towards(v, complex.position(v) + jitter, 1e-6, &mut star);
        }
        let mut params = DscParams::new::<D3>(1.5);
        params.degenerate_quality = 0.35;
        let cells: Vec<CellId> = complex.cell_ids().collect();
        assert!(cells.len() >= JUDGE_AHEAD_FROM, "{} cells", cells.len());
        let removed_on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut mesh = complex.clone();
            let counts = pool.install(|| mesh.remove_degenerate_in(&cells, &params));
            assert!(mesh.validate().is_empty());
            let positions: Vec<_> = mesh.vertex_ids().map(|v| mesh.position(v)).collect();
            let tets: Vec<_> = mesh
                .cell_ids()
                .map(|c| (mesh.cell(c).to_vec(), mesh.label(c)))
                .collect();
            (counts, positions, tets)
        };
        let one = removed_on(1);
        assert!(
            one.0 .0 + one.0 .1 + one.0 .2 > 20,
            "only {:?} removals",
            one.0
        );
        assert!(one == removed_on(2));
    }

    /// `degenerate_near` with one memo across rounds of moves answers what
    /// listing the grown region and testing every cell of it answers.
    #[test]
    fn degenerate_near_answers_like_the_grown_region() {
        let l = 4.0;
        let mut mesh = Complex::<D2>::rectangle(60.0, 52.0, l).unwrap();
        mesh.label_by(|p| u32::from((p - Vector2::new(30.0, 26.0)).norm() < 14.0));
        let mut params = DscParams::new::<D2>(l);
        // Strict, so that moves make degenerate cells often.
        params.degenerate_quality = 0.2;
        let mut memo = ImproveMemo::new();
        let mut star = Vec::new();
        let (mut yes, mut no) = (0, 0);
        for round in 0..40 {
            let ids: Vec<VertexId> = mesh.vertex_ids().collect();
            for (k, &v) in ids.iter().enumerate() {
                if (k + round) % 7 == 0 {
                    let p = mesh.position(v);
                    let d = Vector2::new((k as f64).sin(), (round as f64 + k as f64).cos());
                    mesh.move_towards(v, p + d * (0.5 * l), 1e-4 * l, &mut star);
                }
            }
            let seeds: Vec<VertexId> = ids.iter().copied().step_by(3 + round % 4).collect();
            let mut cells = Vec::new();
            mesh.region_cells(&seeds, &mut cells, &mut Vec::new());
            let mut grown = cells.clone();
            let mut marks = vec![false; mesh.cell_capacity()];
            for &c in &grown {
                marks[c.index()] = true;
            }
            mesh.grow_region(&mut grown, &mut marks, &mut WalkScratch::default());
            let fresh = grown.iter().any(|&c| mesh.is_degenerate(c, &params));
            assert_eq!(
                mesh.degenerate_near(
                    &cells,
                    &params,
                    &SizingField::uniform(),
                    &mut memo,
                    &mut WalkScratch::default()
                ),
                fresh,
                "round {round}"
            );
            if fresh {
                yes += 1;
                // Remove them, as the improvement would, so that later
                // rounds start sound.
                mesh.remove_degenerate_in(&grown, &params);
            } else {
                no += 1;
            }
        }
        assert!(
            yes >= 5 && no >= 5,
            "{yes} with, {no} without degenerate cells"
        );
    }
}
