//! What mesh improvement already verified, so that repeated passes over the
//! same band skip the work whose answer cannot have changed.
//!
//! Within one `deform` call the improvement passes over the interface band
//! four times or more, and most of the band never changes. Two facts make
//! old answers reusable exactly: cells never change their vertices (an
//! operation replaces cells, and new cells get ids above every old one),
//! and every vertex move or creation advances the complex's move clock
//! ([`Complex::moved_at`]). An answer computed from some cells and vertices
//! at clock `t` holds while those cells are alive and none of those vertices
//! has moved since `t`. Smoothing's verdict on a vertex depends on its star
//! alone, so it is checked against [`Complex::star_changed_at`], which the
//! complex advances for every vertex around a move or a cell replacement:
//! no walk of the star is needed to skip it. Valid until the complex is
//! compacted (the ids change), so one memo serves one `deform` call (a
//! kept [`DscWorkspace`](crate::dsc::DscWorkspace) forgets it when the next
//! call starts, keeping only the arrays' capacity). The exceptions are the
//! 3D flips' refusals ([`RefusedFlips`]) and the tet qualities
//! ([`CellQualities`]), which follow the compactions and so hold across
//! calls.

use super::{CellQualities, CellStamps, JudgedTet, StarCache};
use crate::complex::{CellId, Complex, VertexId};
use crate::dim::{Dim, D2, D3};
use rustc_hash::FxHashMap;

/// A verdict: at move clock `clock`, when the cells alive had ids below `cells_below`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stamp {
    clock: u64,
    cells_below: u32,
}

/// The verdicts of smoothing and edge flips, per vertex and per cell id.
#[derive(Clone, Debug, Default)]
pub struct ImproveMemo {
    /// Per vertex: the move clock when smoothing last left it in place.
    kept: Vec<Option<u64>>,
    /// Per vertex: the move clock when its star last had no degenerate cell.
    sound: Vec<Option<u64>>,
    /// Per cell (2D): when all of its edges were last found not to flip.
    settled: Vec<Option<Stamp>>,
    /// Per tet (3D): when all of its flips were last refused; kept across
    /// calls (not forgotten by [`forget`](Self::forget)).
    pub(crate) refused_flips: RefusedFlips,
    /// Per edge (3D): when its removal was last refused; about the complex
    /// as numbered now (see [`RefusedEdges`]).
    pub(crate) refused_edges: RefusedEdges,
    /// Per tet (3D): its quality while no corner moves, read by the search
    /// for tets to flip; kept across calls like the refused flips.
    pub(crate) qualities: CellQualities,
    /// Scratch of the search for poor tets (its judgements, in order).
    pub(crate) judged: Vec<JudgedTet>,
    /// Per tet alive when a 3D connectivity improvement started: found at
    /// or above the flip threshold by one of its sweeps. Flips move no
    /// vertex, so such a tet stays there (and is never refused: only tets
    /// below are tried); the later sweeps skip it. Indexed by cell id:
    /// valid because nothing compacts the complex during an improvement
    /// and new cells take ids past the end (the vector is read with `get`).
    pub(crate) not_poor: Vec<bool>,
    /// 3D stars searched by smoothing and the search for degenerate cells,
    /// kept while no cell around their vertex changes (forgotten at every
    /// compaction).
    pub(crate) stars: StarCache,
    /// What the verdicts were given: the complex's compactions (the ids)
    /// and relabellings (the flip verdicts), the degenerate-cell thresholds
    /// (the `sound` verdicts).
    compactions: u64,
    relabels: u64,
    thresholds: [f64; 4],
}

impl ImproveMemo {
    /// An empty memo.
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets what no longer holds for `complex`: everything if it was
    /// compacted since (the ids changed), the flip verdicts if a label
    /// changed (an interface edge never flips). Every entry point of the
    /// improvement calls it, so a memo may be kept across calls.
    pub fn sync<K: Dim>(&mut self, complex: &Complex<K>) {
        if complex.compactions() != self.compactions {
            self.forget();
            self.compactions = complex.compactions();
        }
        if complex.relabels() != self.relabels {
            self.settled.clear();
            self.relabels = complex.relabels();
        }
    }

    /// Forgets every verdict given in this call (keeps the arrays'
    /// capacity). The refused flips and the qualities, which check the
    /// complex they are about themselves, stay.
    pub fn forget(&mut self) {
        self.kept.clear();
        self.sound.clear();
        self.settled.clear();
    }

    /// Carries the records kept across calls (the refused flips, the
    /// qualities) through the compaction `complex` just made.
    pub(crate) fn follow_compaction<K: Dim>(&mut self, complex: &Complex<K>) {
        self.refused_flips.follow_compaction(complex);
        self.qualities.follow_compaction(complex);
    }

    /// Forgets the degenerate-cell verdicts if they were given under other
    /// thresholds (`thresholds`: whatever the caller judges degeneracy by).
    pub(crate) fn sync_thresholds(&mut self, thresholds: [f64; 4]) {
        if thresholds != self.thresholds {
            self.sound.clear();
            self.thresholds = thresholds;
        }
    }

    /// Records that smoothing left `v` in place (`kept`) or moved it.
    pub(crate) fn set_kept<K: Dim>(&mut self, complex: &Complex<K>, v: VertexId, kept: bool) {
        let stamp = kept.then(|| complex.move_clock());
        put(&mut self.kept, v.index(), stamp);
    }

    /// Whether smoothing left `v` in place and its star has not changed
    /// since ([`Complex::star_changed_at`]): the same cells, the same
    /// corner positions, so the same verdict. Needs no walk of the star.
    #[inline]
    pub(crate) fn still_kept<K: Dim>(&self, complex: &Complex<K>, v: VertexId) -> bool {
        get(&self.kept, v.index()).is_some_and(|t| complex.star_changed_at(v) <= t)
    }

    /// Records that no cell of `v`'s star is degenerate now.
    pub(crate) fn set_sound<K: Dim>(&mut self, complex: &Complex<K>, v: VertexId) {
        put(&mut self.sound, v.index(), Some(complex.move_clock()));
    }

    /// Whether `v`'s star had no degenerate cell and has not changed since.
    #[inline]
    pub(crate) fn still_sound<K: Dim>(&self, complex: &Complex<K>, v: VertexId) -> bool {
        get(&self.sound, v.index()).is_some_and(|t| complex.star_changed_at(v) <= t)
    }

    /// Records that no edge of `c` flipped when tested against the cells
    /// with ids below `cells_below` (its neighbours then).
    pub(crate) fn set_settled(&mut self, complex: &Complex<D2>, c: CellId, cells_below: u32) {
        let stamp = Stamp {
            clock: complex.move_clock(),
            cells_below,
        };
        put(&mut self.settled, c.index(), Some(stamp));
    }

    /// Whether no edge of `c` flipped when last tested and nothing around
    /// has changed since: no corner of `c` has a changed star
    /// ([`Complex::star_changed_at`]), so `c`, its neighbours and their
    /// corners are as they were. Three loads instead of the per-edge test
    /// of [`settled_cell`](Self::settled_cell) and [`edge_settled`].
    #[inline]
    pub(crate) fn quad_settled(&self, complex: &Complex<D2>, c: CellId) -> bool {
        get(&self.settled, c.index()).is_some_and(|stamp| {
            complex
                .cell(c)
                .iter()
                .all(|&w| complex.star_changed_at(w) <= stamp.clock)
        })
    }

    /// The verdict on `c`'s edges if it still stands for `c` itself: `c` was
    /// settled and none of its corners has moved since. Each edge's verdict
    /// then also needs its neighbour unchanged ([`edge_settled`]).
    #[inline]
    pub(crate) fn settled_cell(&self, complex: &Complex<D2>, c: CellId) -> Option<Stamp> {
        get(&self.settled, c.index()).filter(|&stamp| unchanged_since(complex, c, stamp))
    }
}

/// Per tet: when every flip of [`Complex::improve_tet`](crate::complex::Complex::improve_tet) was last refused.
///
/// Most tets below the flip threshold lie on an interface, where no flip
/// may change the cells, and each improvement of the band tries all ten
/// of their flips again, several times per deform. Whether they are refused
/// depends on the tets around the tet's edges and across its facets, their
/// corner positions and labels: all within the stars of its four corners.
/// So a refusal at clock `t` stands while no corner's star has changed
/// since ([`Complex::star_changed_at`]) and no label has
/// ([`Complex::relabels`]). Exact: the improvement flips what it flips
/// without the record.
#[derive(Clone, Debug, Default)]
pub(crate) struct RefusedFlips {
    refused: CellStamps,
    relabels: u64,
    /// The quality below which the tets were tried (a tet recorded was
    /// below it, and stays so while its corners stay).
    low_quality: f64,
}

impl RefusedFlips {
    /// Forgets what does not hold for `complex` and tets tried below
    /// `low_quality`: everything if it is another complex, was renumbered
    /// by a compaction the record did not follow, a label changed or the
    /// threshold did.
    pub(crate) fn sync(&mut self, complex: &Complex<D3>, low_quality: f64) {
        if !self.refused.sync(complex)
            && (self.relabels != complex.relabels() || self.low_quality != low_quality)
        {
            self.refused.forget();
        }
        self.relabels = complex.relabels();
        self.low_quality = low_quality;
    }

    /// Records that every flip of `c` was refused now.
    pub(crate) fn record(&mut self, complex: &Complex<D3>, c: CellId) {
        self.refused.record(complex, c);
    }

    /// Whether every flip of `c` was refused and no corner's star has
    /// changed since: trying again would be refused again.
    #[inline]
    pub(crate) fn still_refused(&self, complex: &Complex<D3>, c: CellId) -> bool {
        self.refused.get(c).is_some_and(|t| {
            complex
                .cell(c)
                .iter()
                .all(|&w| complex.star_changed_at(w) <= t)
        })
    }

    /// Carries the record through the compaction `complex` just made.
    pub(crate) fn follow_compaction<K: Dim>(&mut self, complex: &Complex<K>) {
        self.refused.follow_compaction(complex);
    }
}

/// Per edge (3D): when its removal ([`Complex::improve_tet`](crate::complex::Complex::improve_tet)'s
/// first tries) was last refused.
///
/// Poor tets share edges, and a tet tried again because the star of one
/// corner changed tries all six edges again, most of them in rings nothing
/// touched. The verdict on the edge `uv` depends on the tets around it,
/// their corners' positions and their labels: all within the star of `u`.
/// So a refusal at clock `t` stands while the star of `u` has not changed
/// since ([`Complex::star_changed_at`]; both ends are checked) and no label
/// has ([`Complex::relabels`]). Exact: the same flips result. About one
/// complex as numbered now (forgotten at every compaction).
#[derive(Clone, Debug, Default)]
pub(crate) struct RefusedEdges {
    refused: FxHashMap<(VertexId, VertexId), u64>,
    /// The complex's identity, compactions and relabellings the refusals
    /// are about.
    about: Option<(u64, u64, u64)>,
}

impl RefusedEdges {
    /// Forgets the refusals unless they are about `complex` as it is now.
    pub(crate) fn sync(&mut self, complex: &Complex<D3>) {
        let about = Some((
            complex.identity(),
            complex.compactions(),
            complex.relabels(),
        ));
        if self.about != about {
            self.refused.clear();
            self.about = about;
        }
    }

    /// Whether the removal of the edge `uv` was refused and nothing around
    /// it has changed since: trying again would be refused again.
    #[inline]
    pub(crate) fn still_refused(&self, complex: &Complex<D3>, u: VertexId, v: VertexId) -> bool {
        self.refused
            .get(&edge_key(u, v))
            .is_some_and(|&t| complex.star_changed_at(u) <= t && complex.star_changed_at(v) <= t)
    }

    /// Records that the removal of the edge `uv` was refused now.
    pub(crate) fn record(&mut self, complex: &Complex<D3>, u: VertexId, v: VertexId) {
        self.refused.insert(edge_key(u, v), complex.move_clock());
    }
}

/// The key of the edge `uv`, the same from either end.
fn edge_key(u: VertexId, v: VertexId) -> (VertexId, VertexId) {
    (u.min(v), u.max(v))
}

/// Whether the edge of `c` opposite corner `i` was tested since its quad
/// last changed, given the verdict `stamp` on `c` ([`ImproveMemo::settled_cell`]):
/// the neighbour there existed then and none of its corners has moved
/// since. Testing it again would not flip it.
#[inline]
pub(crate) fn edge_settled(complex: &Complex<D2>, c: CellId, i: usize, stamp: Stamp) -> bool {
    complex.neighbours(c)[i].is_none_or(|nb| unchanged_since(complex, nb, stamp))
}

/// Whether cell `c` existed at the stamp and none of its corners moved since.
#[inline]
fn unchanged_since<K: Dim>(complex: &Complex<K>, c: CellId, stamp: Stamp) -> bool {
    c.raw() < stamp.cells_below
        && complex
            .cell(c)
            .iter()
            .all(|&w| complex.moved_at(w) <= stamp.clock)
}

#[inline]
fn get<T: Copy>(stamps: &[Option<T>], i: usize) -> Option<T> {
    stamps.get(i).copied().flatten()
}

fn put<T: Copy>(stamps: &mut Vec<Option<T>>, i: usize, stamp: Option<T>) {
    if i >= stamps.len() {
        stamps.resize(i + 1, None);
    }
    stamps[i] = stamp;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dsc::{Connectivity, Destinations, DscParams, Region};
    use nalgebra::Vector2;

    /// Flips and smoothing with one memo kept across rounds of vertex moves,
    /// flips and smoothing do exactly what they do without one: the same
    /// flips (same cells) and the same smoothing moves.
    #[test]
    fn memo_gives_the_answers_of_a_fresh_evaluation() {
        let l = 4.0;
        let mut mesh = Complex::<D2>::rectangle(60.0, 52.0, l).unwrap();
        mesh.label_by(|p| u32::from((p - Vector2::new(30.0, 26.0)).norm() < 14.0));
        let params = DscParams::new::<D2>(l);
        // An irregular start: a few deform steps (which compact).
        for step in 0..3 {
            let mut dest = Destinations::new(&mesh);
            for v in mesh.vertex_ids().collect::<Vec<_>>() {
                let p = mesh.position(v);
                let d = Vector2::new((p.y * 0.3 + step as f64).sin(), (p.x * 0.2).cos());
                dest.set(v, mesh.constrain(v, p + d * l * 0.4));
            }
            mesh.deform(&dest, &params);
        }
        let (mut fresh, mut memoised) = (mesh.clone(), mesh);
        let mut memo = ImproveMemo::new();
        let mut star = Vec::new();
        let mut total_flips = 0;
        for round in 0..24 {
            // Even rounds move every third vertex.
            for c in [&mut fresh, &mut memoised] {
                let ids: Vec<VertexId> = c.vertex_ids().collect();
                for (k, &v) in ids.iter().enumerate() {
                    if round % 2 == 0 && (k + round) % 3 == 0 {
                        let p = c.position(v);
                        let d = Vector2::new((k as f64).sin(), (round as f64 + k as f64).cos());
                        c.move_towards(v, p + d * (0.6 * l), 1e-4 * l, &mut star);
                    }
                }
            }
            // Flips only after a round of smoothing (odd rounds).
            if round % 2 == 1 {
                let a = D2::improve_connectivity(&mut fresh, &params);
                let b = D2::improve_connectivity_in(
                    &mut memoised,
                    &mut Region::everything(),
                    &params,
                    &mut memo,
                );
                assert_eq!(a, b, "round {round}: flips");
                total_flips += a;
            }
            let ids: Vec<VertexId> = fresh.vertex_ids().collect();
            let a = fresh.smooth_vertices(&ids, &mut ImproveMemo::new());
            let b = memoised.smooth_vertices(&ids, &mut memo);
            assert_eq!(a, b, "round {round}: smoothed");
            for &v in &ids {
                assert_eq!(fresh.position(v), memoised.position(v), "round {round}");
            }
            let cells = |c: &Complex<D2>| -> Vec<Vec<VertexId>> {
                c.cell_ids().map(|x| c.cell(x).to_vec()).collect()
            };
            assert_eq!(cells(&fresh), cells(&memoised), "round {round}");
        }
        assert!(total_flips > 20, "{total_flips} flips: too few to test");
    }

    /// A memo kept across calls forgets the flip verdicts when a label
    /// changes (an interface edge never flips: its cells were settled
    /// without testing it) and everything when the ids change.
    #[test]
    fn sync_forgets_what_labels_and_compactions_invalidate() {
        let l = 4.0;
        let mut mesh = Complex::<D2>::rectangle(40.0, 36.0, l).unwrap();
        let params = DscParams::new::<D2>(l);
        let mut memo = ImproveMemo::new();
        let settled = |memo: &ImproveMemo, mesh: &Complex<D2>| {
            mesh.cell_ids()
                .filter(|&c| memo.quad_settled(mesh, c))
                .count()
        };
        D2::improve_connectivity_in(&mut mesh, &mut Region::everything(), &params, &mut memo);
        let all: Vec<VertexId> = mesh.vertex_ids().collect();
        mesh.smooth_vertices(&all, &mut memo);
        let before = settled(&memo, &mesh);
        assert!(before > mesh.cell_count() / 2, "{before}");
        memo.sync(&mesh);
        assert_eq!(settled(&memo, &mesh), before, "nothing changed");
        let c = mesh.cell_ids().next().unwrap();
        mesh.set_label(c, 1);
        memo.sync(&mesh);
        assert_eq!(settled(&memo, &mesh), 0, "a label changed");
        assert!(all.iter().any(|&v| memo.still_kept(&mesh, v)));
        mesh.compact_in_place();
        memo.sync(&mesh);
        assert!(
            !all.iter().any(|&v| memo.still_kept(&mesh, v)),
            "the ids changed"
        );
    }

    /// The 3D flip sweeps over every tet, each tet below `low_quality`
    /// tried afresh: what [`Connectivity::improve_connectivity_in`] does
    /// for `D3` without a memo.
    fn flips_without_memo(mesh: &mut Complex<D3>, low_quality: f64) -> usize {
        let mut flips = 0;
        for _sweep in 0..4 {
            let poor: Vec<CellId> = mesh
                .cell_ids()
                .filter(|&c| mesh.quality(c) < low_quality)
                .collect();
            let changed = poor
                .into_iter()
                .filter(|&c| mesh.improve_tet(c, 0.0).is_some())
                .count();
            flips += changed;
            if changed == 0 {
                break;
            }
        }
        flips
    }

    /// 3D flips with one memo kept across rounds of moves, compactions and
    /// a relabelling (its refused flips follow the compactions) flip
    /// exactly the tets a fresh improvement flips, leaving the same cells.
    #[test]
    fn refused_flips_give_the_flips_of_a_fresh_evaluation() {
        use nalgebra::Vector3;
        let l = 4.0;
        let mut mesh = Complex::<D3>::cuboid([24.0, 20.0, 16.0], l).unwrap();
        let centre = Vector3::new(12.0, 10.0, 8.0);
        mesh.label_by(|p| u32::from((p - centre).norm() < 6.0));
        let mut params = DscParams::new::<D3>(l);
        // Demanding, so that most tets are tried and many flip.
        params.low_quality = 0.6;
        let (mut fresh, mut memoised) = (mesh.clone(), mesh);
        let mut memo = ImproveMemo::new();
        let mut star = Vec::new();
        let (mut total_flips, mut skipped) = (0, 0);
        for round in 0..8 {
            for c in [&mut fresh, &mut memoised] {
                let ids: Vec<VertexId> = c.vertex_ids().collect();
                for (k, &v) in ids.iter().enumerate() {
                    if (k + round) % 5 == 0 {
                        let p = c.position(v);
                        let d = Vector3::new(
                            (k as f64).sin(),
                            (round as f64 + k as f64).cos(),
                            (0.7 * k as f64).sin(),
                        );
                        c.move_towards(v, c.constrain(v, p + d * (0.5 * l)), 1e-4 * l, &mut star);
                    }
                }
                if round == 4 {
                    let first = c.cell_ids().next().unwrap();
                    c.set_label(first, 1 - c.label(first));
                }
            }
            // Two passes per round, as an improvement runs them.
            for _pass in 0..2 {
                let a = flips_without_memo(&mut fresh, params.low_quality);
                memo.refused_flips.sync(&memoised, params.low_quality);
                let known = memoised
                    .cell_ids()
                    .filter(|&c| memo.refused_flips.still_refused(&memoised, c))
                    .count();
                let b = D3::improve_connectivity_in(
                    &mut memoised,
                    &mut Region::everything(),
                    &params,
                    &mut memo,
                );
                assert_eq!(a, b, "round {round}: flips");
                total_flips += a;
                skipped += known;
            }
            let cells = |c: &Complex<D3>| -> Vec<Vec<VertexId>> {
                c.cell_ids().map(|x| c.cell(x).to_vec()).collect()
            };
            assert_eq!(cells(&fresh), cells(&memoised), "round {round}");
            // Every other round renumbers, as a deform's end does.
            if round % 2 == 1 {
                fresh.compact_in_place();
                memoised.compact_in_place();
                memo.follow_compaction(&memoised);
            }
            assert!(memoised.validate().is_empty(), "round {round}");
        }
        assert!(total_flips > 20, "{total_flips} flips: too few to test");
        assert!(skipped > 100, "{skipped} refusals reused: too few to test");
    }
}
