//! Edge collapse: merge two vertices, removing the cells around their edge.
//!
//! ```text
//!      a                 a
//!     / \               /|
//!    u---v     ==>     u |      (v merged into u; the two cells on uv vanish)
//!     \ /               \|
//!      b                 b
//! ```
//! A *safe* collapse keeps the interface where it is: an interface vertex may
//! only move along its interface where that is straight, and two interface
//! vertices may only merge along an interface edge. An *unsafe* collapse may
//! merge interface vertices across a thin region: that is how the DSC changes
//! topology (two regions merge, a neck pinches).

use crate::complex::{CellId, Complex, Label, Rejection, VertexId, VertexKind};
use crate::dim::{Dim, Point};
use smallvec::SmallVec;

/// Whether a collapse must preserve the interface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CollapseMode {
    /// Keep the interface and its topology.
    Safe,
    /// Allow interface vertices to merge across a region (topology change).
    Unsafe,
}

/// A candidate outcome: `remove` merges into `keep`, which moves to `at`.
#[derive(Clone, Copy)]
struct Candidate<P> {
    keep: VertexId,
    remove: VertexId,
    at: P,
}

/// Whether the interfaces around vertices are flat to a straightness
/// `cos` ([`Complex::interface_is_flat`]), as found by the collapses of one
/// pass over a complex. The answer depends on the vertex's star alone (its
/// cells, their corners and labels, and the labels across its facets, which
/// are the star's too), so a verdict given at move clock `t` stands while
/// the star has not changed since ([`Complex::star_changed_at`]) and no
/// label has ([`Complex::relabels`]); a record about another complex, another
/// numbering or another straightness is forgotten.
#[derive(Clone, Debug, Default)]
pub(crate) struct FlatEnds {
    /// Per vertex id: the move clock of the verdict, and the verdict.
    verdicts: Vec<Option<(u64, bool)>>,
    /// The complex, numbering, labels and straightness the verdicts are about.
    about: Option<(u64, u64, u64, u64)>,
    straight_cos: f64,
}

impl FlatEnds {
    /// Forgets the verdicts unless they are about `complex` as it is now
    /// (its identity, compactions and labels) and the straightness `cos`.
    fn sync<K: Dim>(&mut self, complex: &Complex<K>, straight_cos: f64) {
        let about = Some((
            complex.identity(),
            complex.compactions(),
            complex.relabels(),
            straight_cos.to_bits(),
        ));
        if self.about != about {
            self.verdicts.clear();
            self.about = about;
            self.straight_cos = straight_cos;
        }
    }

    /// Forgets every verdict, keeping the buffer.
    pub(crate) fn forget(&mut self) {
        self.verdicts.clear();
        self.about = None;
    }

    /// Whether the interface around `w` is flat; `star` is scratch.
    fn is_flat<K: Dim>(
        &mut self,
        complex: &Complex<K>,
        w: VertexId,
        star: &mut Vec<CellId>,
    ) -> bool {
        if let Some(Some((t, flat))) = self.verdicts.get(w.index()) {
            if complex.star_changed_at(w) <= *t {
                return *flat;
            }
        }
        let flat = complex.interface_is_flat(w, self.straight_cos, star);
        if w.index() >= self.verdicts.len() {
            self.verdicts.resize(w.index() + 1, None);
        }
        self.verdicts[w.index()] = Some((complex.move_clock(), flat));
        flat
    }
}

/// One NaN per cell of `cells`: qualities not computed yet.
fn unknown_qualities(cells: &[CellId]) -> SmallVec<[f64; 64]> {
    SmallVec::from_elem(f64::NAN, cells.len())
}

/// Layer `ops`: edge collapses.
impl<K: Dim> Complex<K> {
    /// Collapses the edge `uv`, choosing which end survives and where (either end
    /// or the midpoint) to maximise the worst quality of the new cells, which must
    /// reach `min_quality`. Returns the surviving vertex.
    pub fn collapse_edge(
        &mut self,
        u: VertexId,
        v: VertexId,
        mode: CollapseMode,
        min_quality: f64,
        straight_cos: f64,
    ) -> Result<VertexId, Rejection> {
        if u == v || !self.is_vertex_alive(u) || !self.is_vertex_alive(v) {
            return Err(Rejection::Stale);
        }
        self.collapse_edge_remembering(
            (u, v),
            mode,
            min_quality,
            straight_cos,
            &mut FlatEnds::default(),
        )
    }

    /// [`collapse_edge`](Self::collapse_edge) taking the flatness of the
    /// ends' interfaces from `flat` where it still holds (see [`FlatEnds`]),
    /// for a pass of many collapses.
    pub(crate) fn collapse_edge_remembering(
        &mut self,
        (u, v): (VertexId, VertexId),
        mode: CollapseMode,
        min_quality: f64,
        straight_cos: f64,
        flat: &mut FlatEnds,
    ) -> Result<VertexId, Rejection> {
        if u == v || !self.is_vertex_alive(u) || !self.is_vertex_alive(v) {
            return Err(Rejection::Stale);
        }
        flat.sync(self, straight_cos);
        let mut lists = [(); 4].map(|_| self.take_list());
        let result = self.collapse_edge_with(u, v, mode, min_quality, flat, &mut lists);
        for list in lists {
            self.give_back(list);
        }
        result
    }

    /// [`collapse_edge`](Self::collapse_edge) with four empty lists for the
    /// stars of `u` and `v`, the cells of the edge, and other stars. The
    /// refusals come cheapest first (the link condition, a sort of the
    /// stars' corners, after the candidates' qualities: most collapses have
    /// no candidate, and then report `NoCandidate` even where the link
    /// fails too); any refusal leaves the complex unchanged.
    fn collapse_edge_with(
        &mut self,
        u: VertexId,
        v: VertexId,
        mode: CollapseMode,
        min_quality: f64,
        flat: &mut FlatEnds,
        lists: &mut [Vec<CellId>; 4],
    ) -> Result<VertexId, Rejection> {
        let [star_u, star_v, edge_cells, star] = lists;
        let (cu, cv) = (self.class(u), self.class(v));
        // Both ends on an interface: the edge's own cells and the two ends'
        // flatness decide whether a safe collapse has any candidate, before
        // the stars are searched (most such collapses have none).
        let ends_free = if mode == CollapseMode::Safe && cu.on_interface() && cv.on_interface() {
            Some(self.interface_ends_free(u, v, flat, star, edge_cells)?)
        } else {
            None
        };
        edge_cells.clear();
        self.star_into(u, star_u);
        self.star_into(v, star_v);
        edge_cells.extend(
            star_u
                .iter()
                .copied()
                .filter(|&c| self.cell(c).contains(&v)),
        );
        if edge_cells.is_empty() {
            return Err(Rejection::Stale);
        }
        let (pu, pv) = (self.position(u), self.position(v));
        let (free_u, free_v) = match ends_free {
            Some(free) => free,
            None => {
                // At most one end on an interface, or an unsafe collapse.
                let interface_edge = self.edge_on_interface(u, v, edge_cells);
                let mut free = |w: VertexId| -> bool {
                    match self.class(w).kind {
                        VertexKind::Interior => true,
                        _ if mode == CollapseMode::Unsafe => true,
                        VertexKind::Interface => interface_edge && flat.is_flat(self, w, star),
                        VertexKind::Junction => false,
                    }
                };
                (free(u), free(v))
            }
        };
        // Every candidate judges the same cells before the collapse; their
        // qualities are computed when a candidate first needs them.
        let (mut quality_u, mut quality_v) = (unknown_qualities(star_u), unknown_qualities(star_v));
        // At most three positions times two choices of the kept end.
        let mut candidates: SmallVec<[(f64, Candidate<K::Point>); 6]> = SmallVec::new();
        for at in [pu, pv, (pu + pv) * 0.5] {
            let on_faces = self.boundary_mask(&at);
            if on_faces & cu.boundary != cu.boundary || on_faces & cv.boundary != cv.boundary {
                continue;
            }
            if (at != pu && !free_u) || (at != pv && !free_v) {
                continue;
            }
            // Keeping either end at `at` makes the same cells: one judgement.
            let q = self.collapse_quality(
                (u, v, at),
                [
                    (&star_u[..], &mut quality_u[..]),
                    (&star_v[..], &mut quality_v[..]),
                ],
                min_quality,
            );
            if q >= min_quality && q > 0.0 {
                for (keep, remove) in [(u, v), (v, u)] {
                    candidates.push((q, Candidate { keep, remove, at }));
                }
            }
        }
        if candidates.is_empty() {
            return Err(Rejection::NoCandidate);
        }
        // (the link condition, a sort of the stars' corners, only for a
        // collapse with a candidate: most have none)
        self.check_link(u, v, star_u, star_v, edge_cells)?;
        // Best quality first; a candidate the cavity primitive rejects (e.g. a
        // domain-boundary facet that cannot be kept) falls through to the next.
        candidates.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut outcome = Err(Rejection::NoCandidate);
        for (_, cand) in candidates {
            let star_remove = if cand.keep == u { &*star_v } else { &*star_u };
            match self.apply_collapse(cand, star_remove, star) {
                Ok(()) => return Ok(cand.keep),
                Err(e) => outcome = Err(e),
            }
        }
        outcome
    }

    /// Worst quality of the cells around `keep` after merging `remove` into it at `at`
    /// (0 if any would invert). Cells that are already below `min_quality` before
    /// the collapse are not counted (they may stay degenerate, not invert): otherwise
    /// a chain of flat cells, e.g. a squeezed sliver between two merging fronts,
    /// blocks every collapse that would remove it. `stars` holds the stars of
    /// `keep` and `remove`, each with its cells' qualities before the collapse
    /// ([`qualities`](Self::qualities)): a cell whose corners all stay where
    /// they are keeps its quality (and its positive orientation), so only the
    /// cells that change are evaluated. Once a cell falls below `min_quality`
    /// the candidate fails whatever the others give: the worst so far, below
    /// `min_quality`, is returned without judging the rest. A quality before
    /// the collapse still unknown (NaN) is computed when first needed and
    /// kept for the other candidates.
    fn collapse_quality(
        &self,
        (keep, remove, at): (VertexId, VertexId, K::Point),
        stars: [(&[CellId], &mut [f64]); 2],
        min_quality: f64,
    ) -> f64 {
        let stays = |w: VertexId| self.position(w) == at;
        let (keep_stays, remove_stays) = (stays(keep), stays(remove));
        let mut worst: f64 = 1.0;
        for (star, before) in stars {
            for (&c, before) in star.iter().zip(before.iter_mut()) {
                let cell = self.cell(c);
                let (has_keep, has_remove) = (cell.contains(&keep), cell.contains(&remove));
                if has_keep && has_remove {
                    continue;
                }
                let moved = (has_keep && !keep_stays) || (has_remove && !remove_stays);
                // A moved cell that inverts refuses the collapse, whatever
                // its quality before.
                let after = moved.then(|| {
                    let mut pts = self.cell_points(c);
                    for (i, &w) in cell.iter().enumerate() {
                        if w == keep || w == remove {
                            pts[i] = at;
                        }
                    }
                    pts
                });
                if after
                    .as_ref()
                    .is_some_and(|pts| K::orient(&pts[..K::NV]) <= 0.0)
                {
                    return 0.0;
                }
                if self.quality_before(c, before) < min_quality {
                    continue;
                }
                let q = match after {
                    Some(pts) => K::quality_oriented(&pts[..K::NV]),
                    None => self.quality_before(c, before),
                };
                worst = worst.min(q);
                if worst < min_quality {
                    return worst;
                }
            }
        }
        worst
    }

    /// The quality of `c` before the collapse: `known` if it is not NaN,
    /// else computed and kept there.
    #[inline]
    fn quality_before(&self, c: CellId, known: &mut f64) -> f64 {
        if known.is_nan() {
            *known = self.quality(c);
        }
        *known
    }

    /// Whether each end of the interface-to-interface edge `uv` may move in a
    /// safe collapse (an interface vertex where its interface is flat, and
    /// only along an interface edge; a junction never), from the edge's
    /// cells (into `edge_cells`; `star` is scratch). Rejects the collapse
    /// when neither may: no candidate position is left, whatever the stars.
    fn interface_ends_free(
        &self,
        u: VertexId,
        v: VertexId,
        flat: &mut FlatEnds,
        star: &mut Vec<CellId>,
        edge_cells: &mut Vec<CellId>,
    ) -> Result<(bool, bool), Rejection> {
        self.cells_of_edge(u, v, star, edge_cells);
        if edge_cells.is_empty() {
            return Err(Rejection::Stale);
        }
        if !self.edge_on_interface(u, v, edge_cells) {
            return Err(Rejection::Constrained);
        }
        let mut free = |w: VertexId| {
            self.class(w).kind == VertexKind::Interface && flat.is_flat(self, w, star)
        };
        let ends = (free(u), free(v));
        // (two ends at one point would leave that point a candidate: cells
        // are positively oriented, so an edge is never that short)
        if ends == (false, false) && self.position(u) != self.position(v) {
            return Err(Rejection::NoCandidate);
        }
        Ok(ends)
    }

    /// Replaces the cells around `cand.remove` by the kept vertex's; `star` is scratch.
    fn apply_collapse(
        &mut self,
        cand: Candidate<K::Point>,
        star_remove: &[CellId],
        star: &mut Vec<CellId>,
    ) -> Result<(), Rejection> {
        let new: SmallVec<[(K::Cell, Label); 16]> = star_remove
            .iter()
            .filter(|&&c| !self.cell(c).contains(&cand.keep))
            .map(|&c| {
                let mut cell = K::cell(self.cell(c));
                for w in cell.as_mut() {
                    if *w == cand.remove {
                        *w = cand.keep;
                    }
                }
                (cell, self.label(c))
            })
            .collect();
        // (a removed vertex off the domain boundary: no facet is renamed or
        // glued, the cavity's boundary is the link of the removed vertex)
        let removed = self.class(cand.remove);
        let inside_one_phase = !self.class(cand.keep).on_interface()
            && !removed.on_interface()
            && !removed.on_boundary();
        let old_pos = self.position(cand.keep);
        self.set_position(cand.keep, cand.at);
        let result = self.replace_cells_merging(
            star_remove,
            &new,
            (cand.remove, cand.keep),
            inside_one_phase,
        );
        if result.is_err() {
            self.set_position(cand.keep, old_pos);
        } else if inside_one_phase {
            // Every label around is one phase's: only the kept vertex's
            // boundary mask (its position) may have changed.
            self.reclassify_vertices(&mut [cand.keep]);
        } else if removed.on_boundary() {
            // Domain-boundary facets were renamed and may have been glued:
            // the whole star of the kept vertex is classified again.
            self.star_into(cand.keep, star);
            self.reclassify_cells(star);
        }
        // Otherwise nothing is left to classify: the cavity classified every
        // corner of the new cells, the kept vertex among them, and every
        // vertex whose star lost or gained a cell is such a corner. Off the
        // domain boundary each edge from the removed vertex has cells around
        // it that do not hold the kept vertex (at most two of its three or
        // more tets do; one of its two triangles), and those become new cells.
        result
    }

    /// Link condition on vertices: every common neighbour of `u` and `v` must be
    /// a vertex of a cell containing the edge; and two boundary vertices may only
    /// merge along a boundary facet.
    fn check_link(
        &self,
        u: VertexId,
        v: VertexId,
        star_u: &[CellId],
        star_v: &[CellId],
        edge_cells: &[CellId],
    ) -> Result<(), Rejection> {
        let around_v = self.corners_of(star_v);
        let edge_link = self.corners_of(edge_cells);
        for &cu in star_u {
            for &w in self.cell(cu) {
                if w == u || w == v {
                    continue;
                }
                let adjacent_to_v = around_v.binary_search(&w).is_ok();
                if adjacent_to_v && edge_link.binary_search(&w).is_err() {
                    return Err(Rejection::NonManifold);
                }
            }
        }
        if self.class(u).on_boundary() && self.class(v).on_boundary() {
            let along_boundary = edge_cells.iter().any(|&c| {
                let cell = self.cell(c);
                self.neighbours(c)
                    .iter()
                    .enumerate()
                    .any(|(i, nb)| nb.is_none() && cell[i] != u && cell[i] != v)
            });
            if !along_boundary {
                return Err(Rejection::BoundaryPinch);
            }
        }
        Ok(())
    }

    /// The corners of `cells`, sorted, each once.
    fn corners_of(&self, cells: &[CellId]) -> SmallVec<[VertexId; 128]> {
        let mut corners: SmallVec<[VertexId; 128]> = cells
            .iter()
            .flat_map(|&c| self.cell(c).iter().copied())
            .collect();
        corners.sort_unstable();
        corners.dedup();
        corners
    }

    /// Whether the edge `uv` lies in an interface facet.
    fn edge_on_interface(&self, u: VertexId, v: VertexId, edge_cells: &[CellId]) -> bool {
        edge_cells.iter().any(|&c| {
            let cell = self.cell(c);
            (0..K::NV).any(|i| cell[i] != u && cell[i] != v && self.is_interface_facet(c, i))
        })
    }

    /// Whether the interface facets around `w` are nearly parallel (normals
    /// oriented from the lower to the higher label agree to `straight_cos`).
    /// `star` is scratch.
    pub(crate) fn interface_is_flat(
        &self,
        w: VertexId,
        straight_cos: f64,
        star: &mut Vec<CellId>,
    ) -> bool {
        self.star_into(w, star);
        let mut normals: SmallVec<[K::Point; 16]> = SmallVec::new();
        for &c in star.iter() {
            let cell = self.cell(c);
            let pts = self.cell_points(c);
            for (i, &corner) in cell.iter().enumerate() {
                if corner == w || !self.is_interface_facet(c, i) {
                    continue;
                }
                let nb = self.neighbours(c)[i].expect("interface facets are interior");
                if self.label(c) > self.label(nb) {
                    continue; // each facet once, seen from its lower-label side
                }
                normals.push(K::facet_normal(&pts[..K::NV], i));
            }
        }
        normals
            .iter()
            .all(|a| normals.iter().all(|b| a.dot(b) >= straight_cos))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::D3;
    use nalgebra::Vector3;
    use rand::{Rng, SeedableRng};

    /// The flatness record answers what a fresh evaluation answers, for every
    /// interface vertex, across collapses, moves and a relabelling.
    #[test]
    fn remembered_flatness_is_that_of_a_fresh_evaluation() {
        let mut complex = Complex::<D3>::cuboid([16.0; 3], 2.0).unwrap();
        complex.label_by(|p| u32::from(p.x < 8.0 || (p - Vector3::repeat(8.0)).norm() < 4.0));
        let straight_cos = 20f64.to_radians().cos();
        let mut flat = FlatEnds::default();
        let mut star = Vec::new();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut flat_seen, mut bent_seen) = (0, 0);
        for round in 0..6 {
            flat.sync(&complex, straight_cos);
            let interface: Vec<VertexId> = complex
                .vertex_ids()
                .filter(|&v| complex.class(v).kind == VertexKind::Interface)
                .collect();
            for &v in &interface {
                let fresh = complex.interface_is_flat(v, straight_cos, &mut star);
                assert_eq!(flat.is_flat(&complex, v, &mut star), fresh, "round {round}");
                (flat_seen, bent_seen) = if fresh {
                    (flat_seen + 1, bent_seen)
                } else {
                    (flat_seen, bent_seen + 1)
                };
            }
            // Change some stars: collapses and moves, and once a label.
            for &v in interface.iter().step_by(7) {
                let jitter = Vector3::from_fn(|_, _| rng.random_range(-0.4..0.4));
                complex.move_towards(v, complex.position(v) + jitter, 1e-6, &mut star);
            }
            for &v in interface.iter().skip(3).step_by(11) {
                let Some(c) = complex
                    .incident_cell(v)
                    .filter(|_| complex.is_vertex_alive(v))
                else {
                    continue;
                };
                if let Some(&w) = complex.cell(c).iter().find(|&&w| w != v) {
                    let _ = complex.collapse_edge_remembering(
                        (v, w),
                        CollapseMode::Safe,
                        0.1,
                        straight_cos,
                        &mut flat,
                    );
                }
            }
            if round == 3 {
                let c = complex.cell_ids().nth(100).unwrap();
                let label = complex.label(c);
                complex.set_label(c, 1 - label);
            }
        }
        assert!(
            flat_seen > 50 && bent_seen > 50,
            "{flat_seen} flat, {bent_seen} bent"
        );
    }
}
