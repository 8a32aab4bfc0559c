//! 3D topological flips: the 2-3 flip (facet removal) and edge removal (the 3-2
//! flip for a ring of three tets, the 4-4 flip for a ring of four, and the
//! general case up to [`MAX_RING`] tets), all off the interface.
//!
//! ```text
//!  2-3: two tets on facet abd, apexes p, q     edge removal: the k tets around uv
//!          p                                          u
//!         /|\            three tets                  /|\     ring w0..w(k-1) around uv is
//!        a-+-d   ==>     around the new   ==>       w-+-w    triangulated; each triangle t
//!         \|/            edge pq                     \|/     gives the tets (t, u) and (t, v)
//!          q                                          v
//! ```
//! Every flip goes through the cavity-replacement primitive, which checks
//! orientation exactly and that the new tets glue into the same cavity
//! boundary, so an invalid flip (a non-convex configuration) is simply rejected.
//! The interface is never touched: the cells involved all carry the same label
//! and the cavity boundary is kept.

use super::memo::RefusedEdges;
use super::CellQualities;
use crate::complex::{CellId, Complex, Label, Rejection, VertexId};
use crate::dim::{Dim, D3};
use nalgebra::Vector3;
use smallvec::SmallVec;

/// A ring of vertices around an edge, on the stack for every ring edge
/// removal accepts (and most it sees).
type Ring = SmallVec<[VertexId; 16]>;

/// Largest ring of tets around an edge that edge removal will retriangulate.
pub const MAX_RING: usize = 7;

/// What a successful flip did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flip3 {
    /// Two tets sharing a facet became three around a new edge.
    TwoThree,
    /// The `k` tets around an edge became `2k − 4` tets without it (k = 3: the 3-2 flip, k = 4: 4-4).
    EdgeRemoval(usize),
}

fn tet_quality(p: [Vector3<f64>; 4]) -> f64 {
    D3::quality(&p)
}

/// The apexes of a ring's best triangulation: `apex(a, c)` is the apex of
/// the triangle on the side `a..c` of the sub-polygon `a..=c`.
struct Splits([[usize; MAX_RING]; MAX_RING]);

impl Splits {
    fn apex(&self, a: usize, c: usize) -> usize {
        self.0[a][c]
    }

    /// The triangles `(a, b, c)` of the triangulation of a ring of `k`
    /// vertices, from the whole polygon's down.
    fn triangles(&self, k: usize) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        let mut stack: SmallVec<[(usize, usize); MAX_RING]> = SmallVec::new();
        stack.push((0, k - 1));
        std::iter::from_fn(move || loop {
            let (a, c) = stack.pop()?;
            if c >= a + 2 {
                let b = self.apex(a, c);
                stack.push((a, b));
                stack.push((b, c));
                return Some((a, b, c));
            }
        })
    }
}

/// The two tets a triangle `(a, b, c)` of the ring forms with `v` and `u`
/// (`t` maps a ring index to its vertex or point).
fn ring_tets<T: Copy>(
    t: impl Fn(usize) -> T,
    (a, b, c): (usize, usize, usize),
    u: T,
    v: T,
) -> [[T; 4]; 2] {
    [[t(a), t(b), t(c), v], [t(b), t(a), t(c), u]]
}

/// The retriangulation of the ring `w` around the edge `uv` whose smallest
/// tet quality is largest (Klincsek's dynamic programme), if that quality
/// exceeds `floor`. The programme runs on the quality formula alone,
/// without the exact orientation test of each of its up to 70 tets; the
/// tets of a choice above `floor` then take the test, and only if one
/// fails does the programme run again with exact qualities. The formula
/// differs from the exact quality only on a tet the test finds inverted or
/// flat, where it may round to a hair above 0 (it is never below, see
/// [`D3::quality_oriented`](crate::dim::Dim::quality_oriented)): a choice
/// at or under `floor` is under it exactly too, and a choice free of such
/// tets is the exact programme's choice.
fn best_retriangulation(
    w: &[Vector3<f64>],
    pu: Vector3<f64>,
    pv: Vector3<f64>,
    floor: f64,
) -> Option<Splits> {
    let (best, split) = klincsek(w, pu, pv, floor, |p| D3::quality_oriented(&p));
    if best <= floor {
        return None;
    }
    let oriented = split
        .triangles(w.len())
        .flat_map(|t| ring_tets(|i| w[i], t, pu, pv))
        .all(|p| D3::orient(&p) > 0.0);
    if oriented {
        return Some(split);
    }
    let (best, split) = klincsek(w, pu, pv, floor, tet_quality);
    (best > floor).then_some(split)
}

/// Klincsek's programme over the ring `w` with the tet quality `quality`,
/// for the caller that wants the best triangulation only if its smallest
/// quality exceeds `floor`: the returned quality exceeds `floor` exactly
/// when the full programme's does, and then both, and the triangles, are
/// the full programme's.
///
/// An apex `b` of the sub-polygon `a..=c` gives the smallest of the two
/// sides' best and its triangle's two tets. The tets' qualities, most of
/// the work, are computed only while that can still beat the sub-polygon's
/// best so far and `floor`: a candidate at or under the best so far never
/// replaces it, and one at or under `floor` makes every triangulation
/// through it fail the caller. So a sub-polygon's best above `floor` comes
/// out exact, with the full programme's apex (the first of the largest);
/// one at or under `floor` comes out at or under it too (possibly lower),
/// and no triangulation above `floor` holds such a sub-polygon.
fn klincsek(
    w: &[Vector3<f64>],
    pu: Vector3<f64>,
    pv: Vector3<f64>,
    floor: f64,
    quality: impl Fn([Vector3<f64>; 4]) -> f64,
) -> (f64, Splits) {
    let k = w.len();
    // best[a][c]: best smallest quality triangulating the sub-polygon a..=c; split[a][c]: its apex.
    let mut best = [[f64::INFINITY; MAX_RING]; MAX_RING];
    let mut split = [[0usize; MAX_RING]; MAX_RING];
    // Index arithmetic over the interval table reads more plainly than iterators.
    #[allow(clippy::needless_range_loop)]
    for len in 2..k {
        for a in 0..k - len {
            let c = a + len;
            let mut top: f64 = -1.0;
            for b in a + 1..c {
                let bar = top.max(floor);
                let sides = best[a][b].min(best[b][c]);
                if sides <= bar {
                    continue;
                }
                let [with_v, with_u] = ring_tets(|i| w[i], (a, b, c), pu, pv);
                let q_v = quality(with_v);
                if q_v <= bar {
                    continue;
                }
                let q = sides.min(q_v).min(quality(with_u));
                if q > top {
                    top = q;
                    split[a][c] = b;
                }
            }
            best[a][c] = top;
        }
    }
    (best[0][k - 1], Splits(split))
}

/// For an edge at the local corners `iu` and `iv` of a tet: the other two
/// local corners `i < j`, and whether `(iu, iv, i, j)` is an even
/// permutation of the corners (then the tet's corners in the order (u, v,
/// corner `i`, corner `j`) are positively oriented, as the tet is).
fn edge_frame(iu: usize, iv: usize) -> (usize, usize, bool) {
    debug_assert!(
        iu != iv && iu < 4 && iv < 4,
        "an edge has two distinct corners"
    );
    let mut others = (0..4).filter(|&k| k != iu && k != iv);
    let (i, j) = (others.next().unwrap_or(0), others.next().unwrap_or(0));
    let order = [iu, iv, i, j];
    let mut inversions = 0;
    for a in 0..4 {
        for b in a + 1..4 {
            inversions += usize::from(order[a] > order[b]);
        }
    }
    (i, j, inversions % 2 == 0)
}

/// Layer `ops`: 3D flips (2-3, 3-2, edge removal).
impl Complex<D3> {
    /// The 2-3 flip of the facet opposite local vertex `i` of `c`: replaces `c`
    /// and its neighbour across that facet (which must carry the same label) by
    /// three tets around the edge joining the two apexes, if the smallest quality
    /// of the three exceeds the smallest quality of the two by more than `margin`.
    ///
    /// Rejected ([`Rejection::Constrained`]) on an interface or domain-boundary
    /// facet, [`Rejection::LowQuality`] when it would not improve, and
    /// [`Rejection::WouldInvert`] when the two tets do not form a convex pair.
    pub fn flip_23(&mut self, c: CellId, i: usize, margin: f64) -> Result<Flip3, Rejection> {
        self.flip_23_known(c, i, margin, &CellQualities::default())
    }

    /// [`flip_23`](Self::flip_23) reading the qualities of the two tets
    /// from `known` where it has them current. The three new tets are
    /// judged on the quality formula first, which is never below the exact
    /// quality: a flip it refuses is refused exactly too, and only the
    /// others take the exact orientation tests.
    fn flip_23_known(
        &mut self,
        c: CellId,
        i: usize,
        margin: f64,
        known: &CellQualities,
    ) -> Result<Flip3, Rejection> {
        if !self.is_alive(c) || i >= 4 {
            return Err(Rejection::Stale);
        }
        let Some(nb) = self.neighbours(c)[i] else {
            return Err(Rejection::Constrained);
        };
        let label: Label = self.label(c);
        if self.label(nb) != label {
            return Err(Rejection::Constrained);
        }
        let cell: [VertexId; 4] = D3::cell(self.cell(c));
        let q = *self
            .cell(nb)
            .iter()
            .find(|w| !cell.contains(w))
            .ok_or(Rejection::Stale)?;
        // Replacing each facet vertex of `c` by `q` gives the three tets around
        // the edge (apex of c, q); all positive iff the pair is convex there.
        let mut new: SmallVec<[([VertexId; 4], Label); 3]> = SmallVec::new();
        for j in 0..4 {
            if j != i {
                let mut t = cell;
                t[j] = q;
                new.push((t, label));
            }
        }
        let floor = self
            .known_quality(c, known)
            .min(self.known_quality(nb, known))
            + margin;
        let new_q = |quality: fn(&[Vector3<f64>]) -> f64| {
            new.iter()
                .map(|(t, _)| quality(&t.map(|v| self.position(v))))
                .fold(1.0, f64::min)
        };
        if new_q(D3::quality_oriented) <= floor || new_q(D3::quality) <= floor {
            return Err(Rejection::LowQuality);
        }
        self.replace_cells(&[c, nb], &new)?;
        Ok(Flip3::TwoThree)
    }

    /// The ring of vertices around the edge `uv`, oriented so that every tet
    /// `(u, v, w_k, w_{k+1})` is positive, and the tets of the ring. `None` when
    /// the ring is open (the edge lies on the domain boundary) or not a simple cycle.
    pub fn edge_ring(&self, u: VertexId, v: VertexId) -> Option<(Vec<VertexId>, Vec<CellId>)> {
        let mut tets = Vec::new();
        self.cells_of_edge(u, v, &mut Vec::new(), &mut tets);
        let ring = self.ring_of_edge(u, v, &tets)?;
        Some((ring.to_vec(), tets))
    }

    /// The ring of the edge `uv` whose tets are `tets` (in any order):
    /// see [`edge_ring`](Self::edge_ring).
    fn ring_of_edge(&self, u: VertexId, v: VertexId, tets: &[CellId]) -> Option<Ring> {
        if tets.len() < 3 {
            return None;
        }
        // Directed ring edges x -> y with (u, v, x, y) positive.
        let mut next: SmallVec<[(VertexId, VertexId); 16]> = SmallVec::new();
        for &t in tets.iter() {
            let cell = self.cell(t);
            let iu = cell.iter().position(|&w| w == u)?;
            let iv = cell.iter().position(|&w| w == v)?;
            let (i, j, even) = edge_frame(iu, iv);
            let (x, y) = (cell[i], cell[j]);
            next.push(if even { (x, y) } else { (y, x) });
        }
        let mut ring = Ring::new();
        let mut cur = next[0].0;
        for _ in 0..tets.len() {
            ring.push(cur);
            let mut steps = next.iter().filter(|e| e.0 == cur);
            match (steps.next(), steps.next()) {
                (Some(step), None) => cur = step.1,
                _ => return None,
            }
        }
        if cur != ring[0] {
            return None;
        }
        let mut sorted = ring.clone();
        sorted.sort_unstable();
        sorted.dedup();
        (sorted.len() == ring.len()).then_some(ring)
    }

    /// Removes the edge `uv` (off the interface, inside the domain, with at most
    /// [`MAX_RING`] tets around it) by the best retriangulation of its ring
    /// (Klincsek's dynamic programme maximising the smallest quality), if that
    /// beats the smallest quality of the ring's tets by more than `margin`.
    ///
    /// Rejected ([`Rejection::Constrained`]) when a tet around the edge carries
    /// another label, the ring is open or too large; [`Rejection::LowQuality`]
    /// when no retriangulation improves.
    pub fn remove_edge(
        &mut self,
        u: VertexId,
        v: VertexId,
        margin: f64,
    ) -> Result<Flip3, Rejection> {
        if u == v || !self.is_vertex_alive(u) || !self.is_vertex_alive(v) {
            return Err(Rejection::Stale);
        }
        let (mut star, mut tets) = (self.take_list(), self.take_list());
        self.cells_of_edge(u, v, &mut star, &mut tets);
        let result = self.remove_ring_edge(u, v, margin, &tets, &CellQualities::default());
        self.give_back(star);
        self.give_back(tets);
        result
    }

    /// [`remove_edge`](Self::remove_edge) of the edge `uv` of the tet `c`:
    /// its ring is found by turning around the edge from `c`, with no search
    /// of the star of `u`.
    fn remove_edge_of(
        &mut self,
        (c, u, v): (CellId, VertexId, VertexId),
        margin: f64,
        known: &CellQualities,
    ) -> Result<Flip3, Rejection> {
        let mut tets = self.take_list();
        self.turn_around_edge(u, v, c, &mut tets);
        let result = self.remove_ring_edge(u, v, margin, &tets, known);
        self.give_back(tets);
        result
    }

    /// [`remove_edge`](Self::remove_edge) with the tets around the edge,
    /// their qualities read from `known` where it has them current.
    fn remove_ring_edge(
        &mut self,
        u: VertexId,
        v: VertexId,
        margin: f64,
        tets: &[CellId],
        known: &CellQualities,
    ) -> Result<Flip3, Rejection> {
        // (labels first: the ring of an edge on the interface is not needed)
        let label = self.label(*tets.first().ok_or(Rejection::Constrained)?);
        if tets.iter().any(|&t| self.label(t) != label) {
            return Err(Rejection::Constrained);
        }
        // (a ring has as many vertices as the edge has tets: a larger one is
        // refused without walking it)
        if tets.len() > MAX_RING {
            return Err(Rejection::Constrained);
        }
        let ring = self
            .ring_of_edge(u, v, tets)
            .ok_or(Rejection::Constrained)?;
        let k = ring.len();
        let old_q = tets
            .iter()
            .map(|&t| self.known_quality(t, known))
            .fold(1.0, f64::min);
        let (pu, pv) = (self.position(u), self.position(v));
        let w: SmallVec<[Vector3<f64>; MAX_RING]> =
            ring.iter().map(|&x| self.position(x)).collect();
        let split =
            best_retriangulation(&w, pu, pv, old_q + margin).ok_or(Rejection::LowQuality)?;
        let new: SmallVec<[([VertexId; 4], Label); 2 * MAX_RING]> = split
            .triangles(k)
            .flat_map(|t| ring_tets(|i| ring[i], t, u, v))
            .map(|tet| (tet, label))
            .collect();
        self.replace_cells(tets, &new)?;
        Ok(Flip3::EdgeRemoval(k))
    }

    /// Tries to improve one low-quality tet: first removing each of its edges,
    /// then 2-3 flipping each of its facets. Returns the flip that succeeded.
    pub fn improve_tet(&mut self, c: CellId, margin: f64) -> Option<Flip3> {
        self.improve_tet_remembering(
            c,
            margin,
            &mut RefusedEdges::default(),
            &CellQualities::default(),
        )
    }

    /// The quality of `c`: from `known` if it has it current (the same
    /// bits), else computed.
    fn known_quality(&self, c: CellId, known: &CellQualities) -> f64 {
        known.current(self, c).unwrap_or_else(|| self.quality(c))
    }

    /// [`improve_tet`](Self::improve_tet) skipping the edge removals
    /// `refused` knows would be refused again (and recording the new
    /// refusals), and reading the tets' qualities from `known` where it has
    /// them current, for the improvement that tries many tets; `refused`
    /// must be about tries with this `margin`.
    pub(crate) fn improve_tet_remembering(
        &mut self,
        c: CellId,
        margin: f64,
        refused: &mut RefusedEdges,
        known: &CellQualities,
    ) -> Option<Flip3> {
        if !self.is_alive(c) {
            return None;
        }
        refused.sync(self);
        let cell: [VertexId; 4] = D3::cell(self.cell(c));
        for a in 0..4 {
            for b in a + 1..4 {
                let (u, v) = (cell[a], cell[b]);
                if refused.still_refused(self, u, v) {
                    continue;
                }
                match self.remove_edge_of((c, u, v), margin, known) {
                    Ok(f) => return Some(f),
                    Err(_) => refused.record(self, u, v),
                }
            }
        }
        for i in 0..4 {
            if let Ok(f) = self.flip_23_known(c, i, margin, known) {
                return Some(f);
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two tets on the facet (0,1,2) with apexes 3 above and 4 below: the
    /// 2-3 flip creates the edge 3-4; the 3-2 flip on that edge undoes it.
    fn bipyramid(flat: f64) -> Complex<D3> {
        let pts = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(4.0, 0.0, 0.0),
            Vector3::new(0.0, 4.0, 0.0),
            Vector3::new(1.2, 1.2, flat),
            Vector3::new(1.2, 1.2, -flat),
        ];
        // A box-filling complex is needed for validate(); here we check counts and measure only.
        let cells = vec![
            [VertexId(0), VertexId(1), VertexId(2), VertexId(3)],
            [VertexId(0), VertexId(2), VertexId(1), VertexId(4)],
        ];
        Complex::from_arrays(
            pts,
            cells,
            vec![0, 0],
            (Vector3::new(0.0, 0.0, -5.0), Vector3::new(5.0, 5.0, 5.0)),
        )
        .unwrap()
    }

    #[test]
    fn two_three_then_three_two_conserve_volume() {
        let mut c = bipyramid(0.3); // flat: the two tets are poor, the three are better
        let vol: f64 = c.cell_ids().map(|t| c.measure(t)).sum();
        let first = c.cell_ids().next().unwrap();
        let i = (0..4).find(|&i| c.neighbours(first)[i].is_some()).unwrap();
        assert_eq!(c.flip_23(first, i, 0.0), Ok(Flip3::TwoThree));
        assert_eq!(c.cell_count(), 3);
        let vol2: f64 = c.cell_ids().map(|t| c.measure(t)).sum();
        assert!((vol - vol2).abs() < 1e-12);
        let (ring, _) = c.edge_ring(VertexId(3), VertexId(4)).unwrap();
        assert_eq!(ring.len(), 3);
        // Undoing cannot improve the minimum: rejected as LowQuality.
        assert_eq!(
            c.remove_edge(VertexId(3), VertexId(4), 0.0),
            Err(Rejection::LowQuality)
        );
        assert_eq!(
            c.remove_edge(VertexId(3), VertexId(4), -1.0),
            Ok(Flip3::EdgeRemoval(3))
        );
        assert_eq!(c.cell_count(), 2);
    }

    /// Klincsek's programme on the exact quality without skipping any apex:
    /// what `best_retriangulation` must decide as.
    // Index arithmetic over the interval table reads more plainly than iterators.
    #[allow(clippy::needless_range_loop)]
    fn full_klincsek(w: &[Vector3<f64>], pu: Vector3<f64>, pv: Vector3<f64>) -> (f64, Splits) {
        let k = w.len();
        let mut best = [[f64::INFINITY; MAX_RING]; MAX_RING];
        let mut split = [[0usize; MAX_RING]; MAX_RING];
        for len in 2..k {
            for a in 0..k - len {
                let c = a + len;
                let mut top = -1.0;
                for b in a + 1..c {
                    let [with_v, with_u] = ring_tets(|i| w[i], (a, b, c), pu, pv);
                    let q = best[a][b]
                        .min(best[b][c])
                        .min(tet_quality(with_v))
                        .min(tet_quality(with_u));
                    if q > top {
                        top = q;
                        split[a][c] = b;
                    }
                }
                best[a][c] = top;
            }
        }
        (best[0][k - 1], Splits(split))
    }

    /// The formula-first programme decides as the exact one: the same
    /// verdict against the floor and the same triangles, on random rings
    /// (convex and not, some with corners pushed onto the edge's line).
    #[test]
    fn best_retriangulation_chooses_as_the_exact_programme() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (pu, pv) = (Vector3::new(0.0, 0.0, 1.0), Vector3::new(0.0, 0.0, -1.0));
        for _ in 0..5000 {
            let k = rng.random_range(3..=MAX_RING);
            let mut w: Vec<Vector3<f64>> = (0..k)
                .map(|i| {
                    let angle =
                        std::f64::consts::TAU * (i as f64 + rng.random::<f64>() * 0.8) / k as f64;
                    let r = if rng.random::<f64>() < 0.1 {
                        1e-9
                    } else {
                        0.3 + rng.random::<f64>()
                    };
                    Vector3::new(r * angle.cos(), r * angle.sin(), rng.random::<f64>() - 0.5)
                })
                .collect();
            // A corner on the segment of its neighbours, up to rounding:
            // tets whose sign only the exact test knows.
            if rng.random::<f64>() < 0.5 {
                let i = rng.random_range(1..k - 1);
                let t = rng.random::<f64>();
                w[i] = w[i - 1] * t + w[i + 1] * (1.0 - t);
            }
            // (0 as in the flips, against a ring whose worst tet is flat)
            let floor = if rng.random::<f64>() < 0.3 {
                0.0
            } else {
                rng.random::<f64>() * 0.5 - 0.1
            };
            let (best, exact) = full_klincsek(&w, pu, pv);
            let fast = best_retriangulation(&w, pu, pv, floor);
            assert_eq!(fast.is_some(), best > floor, "ring {w:?}, floor {floor}");
            if let Some(fast) = fast {
                let triangles: Vec<_> = fast.triangles(k).collect();
                assert_eq!(triangles, exact.triangles(k).collect::<Vec<_>>());
            }
        }
    }

    #[test]
    fn non_convex_pair_is_not_flipped() {
        // Apexes far to the side: the segment 3-4 misses the shared facet.
        let mut c = bipyramid(0.3);
        c.set_position(VertexId(3), Vector3::new(-1.0, -1.0, 0.3));
        c.set_position(VertexId(4), Vector3::new(-1.0, -1.0, -0.3));
        let first = c.cell_ids().next().unwrap();
        let i = (0..4).find(|&i| c.neighbours(first)[i].is_some()).unwrap();
        assert!(c.flip_23(first, i, -1.0).is_err());
        assert_eq!(c.cell_count(), 2);
    }
}
