//! The one primitive behind every local mesh operation: replace a set of cells
//! (a cavity) by new cells filling the same region.
//!
//! Split, collapse and every flip are expressed as "these old cells go, these new
//! cells come". The primitive checks that the new cells are positively oriented
//! (exact predicate) and that their facets glue into a manifold exactly along the
//! cavity's boundary, then rewires the neighbours. A collapse that violates the
//! link condition shows up here as an unmatched or over-matched facet, so no
//! operation can silently break the complex.

use super::{CellId, Complex, Label, Slot, VertexId};
use crate::dim::{Dim, Point};
use serde::Serialize;
use smallvec::SmallVec;

/// Facets of a cavity kept on the stack: enough for every 2D operation and
/// the 3D flips; larger 3D cavities (collapses, splits) spill to the heap.
const INLINE: usize = 32;

/// Why a local operation was not carried out. Rejections are normal control flow.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Rejection {
    /// A resulting cell would be inverted or degenerate.
    WouldInvert,
    /// The new cells do not glue into a manifold along the cavity boundary
    /// (e.g. the link condition of a collapse fails).
    NonManifold,
    /// Two boundary vertices not joined by a boundary facet: collapsing would pinch the domain.
    BoundaryPinch,
    /// The operation would change the interface where that is not allowed
    /// (safe mode), or move a fixed vertex.
    Constrained,
    /// The result would be below the required quality.
    LowQuality,
    /// The element no longer exists or the request does not describe one.
    Stale,
    /// No position or configuration satisfies the geometric constraints.
    NoCandidate,
}

/// Sorted facet key: the facet's vertex ids, padded with `u32::MAX`.
pub(crate) type FacetKey = [u32; 3];

pub(crate) fn facet_key(cell: &[VertexId], opposite: usize) -> FacetKey {
    let mut key = [u32::MAX; 3];
    let mut n = 0;
    for (i, v) in cell.iter().enumerate() {
        if i != opposite {
            key[n] = v.0;
            n += 1;
        }
    }
    key[..n].sort_unstable();
    key
}

/// `key` with `removed` replaced by `kept`, or `None` if it then repeats a vertex.
fn rename_key(key: FacetKey, removed: VertexId, kept: VertexId) -> Option<FacetKey> {
    if key.contains(&kept.0) {
        return None;
    }
    let mut renamed = key.map(|v| if v == removed.0 { kept.0 } else { v });
    renamed.sort_unstable();
    Some(renamed)
}

/// Cavity-boundary facets that coincide after a rename: each pair is glued
/// (returned as `(key, a, b)`) and taken out of the list; three or more, or two
/// domain-boundary facets, cannot be glued.
type Glued = SmallVec<[(FacetKey, Option<CellId>, Option<CellId>); 4]>;
/// Which vertices a replacement classifies again.
#[derive(Clone, Copy, Debug)]
enum Reclassify {
    /// Every corner of the new cells (the label field or positions may have changed).
    AllCorners,
    /// Only the vertices the new cells add (the label field is kept).
    NewVertices,
    /// None (the label field is kept; the caller classifies a vertex it moved).
    Nothing,
}

type Outside = SmallVec<[(FacetKey, Option<CellId>, bool); INLINE]>;
fn glue_coinciding(outside: &mut Outside) -> Result<Glued, Rejection> {
    let mut glued = Glued::new();
    let mut k = 0;
    while k + 1 < outside.len() {
        if outside[k].0 != outside[k + 1].0 {
            k += 1;
            continue;
        }
        let (key, a, _) = outside[k];
        let b = outside[k + 1].1;
        if (k + 2 < outside.len() && outside[k + 2].0 == key) || (a.is_none() && b.is_none()) {
            return Err(Rejection::NonManifold);
        }
        glued.push((key, a, b));
        outside.drain(k..k + 2);
    }
    Ok(glued)
}

/// A facet of a new cell that no other new cell shares (see [`pair_facets`]).
const LONE: u32 = u32::MAX;
/// The second of two facets of new cells with one key.
const SECOND: u32 = u32::MAX - 1;
/// An empty slot of [`pair_facets`]' table.
const NO_FACET: u32 = u32::MAX;

/// The facets of the new cells, `(key, new cell, local index)`, grouped by
/// key through a small open-addressing table (a facet is shared by two new
/// cells or lies on the cavity boundary): per facet, [`LONE`], [`SECOND`],
/// or, for the first of two, the index of the other. A key held by three
/// facets is not a manifold. Every pair and every lone facet is what sorting
/// the facets by key finds, in another order, and the replacement does not
/// depend on the order (each sets its own neighbour slots); the sort was a
/// tenth of a 3D mesh improvement's instructions.
fn pair_facets(
    facets: &[(FacetKey, usize, usize)],
) -> Result<SmallVec<[u32; 4 * INLINE]>, Rejection> {
    let size = (2 * facets.len()).next_power_of_two().max(16);
    let mask = size - 1;
    let mut table: SmallVec<[u32; 8 * INLINE]> = SmallVec::from_elem(NO_FACET, size);
    let mut partners: SmallVec<[u32; 4 * INLINE]> = SmallVec::with_capacity(facets.len());
    for (f, (key, _, _)) in facets.iter().enumerate() {
        let mut slot = key_hash(key) & mask;
        loop {
            let first = table[slot];
            if first == NO_FACET {
                table[slot] = f as u32;
                partners.push(LONE);
                break;
            }
            if facets[first as usize].0 == *key {
                if partners[first as usize] != LONE {
                    return Err(Rejection::NonManifold);
                }
                partners[first as usize] = f as u32;
                partners.push(SECOND);
                break;
            }
            slot = (slot + 1) & mask;
        }
    }
    Ok(partners)
}

/// A hash of a facet key (multiplicative, one odd constant per id).
#[inline]
fn key_hash(key: &FacetKey) -> usize {
    let h = key[0].wrapping_mul(0x9E37_79B9)
        ^ key[1].wrapping_mul(0x85EB_CA6B)
        ^ key[2].wrapping_mul(0xC2B2_AE35);
    (h ^ (h >> 15)) as usize
}

/// Layer `complex`: the cavity primitive behind every mesh operation.
impl<K: Dim> Complex<K> {
    /// Adds an unattached vertex (it becomes live when a new cell uses it).
    pub(crate) fn add_vertex(&mut self, p: K::Point) -> VertexId {
        let id = VertexId(self.positions.len() as u32);
        self.positions.push(p);
        self.book.move_clock += 1;
        self.book.moved_at.push(self.book.move_clock);
        self.book.star_changed_at.push(self.book.move_clock);
        self.book.cells_changed_at.push(self.book.move_clock);
        self.vertex_cell.push(None);
        self.classes.push(super::VertexClass {
            kind: super::VertexKind::Interior,
            boundary: 0,
        });
        id
    }

    /// Whether all the given (vertex tuple) cells are positively oriented at current positions.
    pub(crate) fn all_positive(&self, cells: &[(K::Cell, Label)]) -> bool {
        cells.iter().all(|(cell, _)| {
            let mut p = [K::Point::zero(); 4];
            for (o, v) in p.iter_mut().zip(cell.as_ref()) {
                *o = self.positions[v.index()];
            }
            K::orient(&p[..K::NV]) > 0.0
        })
    }

    /// Replaces the cells `old` by `new` (whose ids are the next ones, in
    /// order). On rejection nothing changes.
    ///
    /// For retriangulations that keep the label field: at every point of the
    /// cavity a new cell carries the label the old cell there carried (a flip
    /// inside one phase, an edge split), and no vertex moves. A vertex's class
    /// is the number of same-label pieces of its star, which are the pieces of
    /// a small sphere around it cut by the interface facets through it (the
    /// star is star-shaped, every cell being positively oriented), so it
    /// depends on the label field near the vertex alone: the vertices already
    /// there keep their classes, and only the new ones are classified.
    pub(crate) fn replace_cells(
        &mut self,
        old: &[CellId],
        new: &[(K::Cell, Label)],
    ) -> Result<(), Rejection> {
        self.replace_cells_then(old, new, None, Reclassify::NewVertices)
    }

    /// [`replace_cells`](Self::replace_cells) for a collapse of `merge = (removed, kept)`:
    /// facets of the cavity boundary that contain the removed vertex (only
    /// domain-boundary facets can) are renamed to the kept vertex; one that then
    /// has a repeated vertex has degenerated and vanishes, and two that then
    /// coincide are glued to each other (a facet outside the cavity may thereby
    /// become a domain-boundary facet).
    ///
    /// `inside_one_phase`: the removed and the kept vertex are both off every
    /// interface and the removed one off the domain boundary, so their stars
    /// carry one label, and so does their union before and after (bounded by
    /// the same facets, none renamed): the label field is kept,
    /// and of all the vertices only the kept one, which moved, is classified
    /// again (by the caller, once it is in place). Otherwise every corner of
    /// the new cells is.
    pub(crate) fn replace_cells_merging(
        &mut self,
        old: &[CellId],
        new: &[(K::Cell, Label)],
        merge: (VertexId, VertexId),
        inside_one_phase: bool,
    ) -> Result<(), Rejection> {
        let reclassify = if inside_one_phase {
            Reclassify::Nothing
        } else {
            Reclassify::AllCorners
        };
        self.replace_cells_then(old, new, Some(merge), reclassify)
    }

    /// The replacement, then the classes of the vertices `reclassify` names.
    fn replace_cells_then(
        &mut self,
        old: &[CellId],
        new: &[(K::Cell, Label)],
        merge: Option<(VertexId, VertexId)>,
        reclassify: Reclassify,
    ) -> Result<(), Rejection> {
        if old.iter().any(|&c| !self.is_alive(c)) {
            return Err(Rejection::Stale);
        }
        if !self.all_positive(new) {
            return Err(Rejection::WouldInvert);
        }
        // Facets on the cavity boundary, with the cell outside (None: domain
        // boundary); the cells outside are the only ones whose neighbours
        // change (`around`).
        let mut outside = Outside::new();
        let mut around: SmallVec<[CellId; INLINE]> = SmallVec::new();
        for &c in old {
            for i in 0..K::NV {
                let nb = self.neighbours(c)[i];
                if nb.is_none_or(|n| !old.contains(&n)) {
                    around.extend(nb);
                    let key = facet_key(self.cell(c), i);
                    match merge {
                        Some((removed, kept)) if key.contains(&removed.0) => {
                            if let Some(renamed) = rename_key(key, removed, kept) {
                                outside.push((renamed, nb, false));
                            }
                        }
                        _ => outside.push((key, nb, false)),
                    }
                }
            }
        }
        outside.sort_unstable_by_key(|e| e.0);
        let glued = glue_coinciding(&mut outside)?;
        // Facets of the new cells: (key, new cell index, local index).
        let mut facets: SmallVec<[(FacetKey, usize, usize); INLINE]> = SmallVec::new();
        for (j, (cell, _)) in new.iter().enumerate() {
            for i in 0..K::NV {
                facets.push((facet_key(cell.as_ref(), i), j, i));
            }
        }
        let partners = pair_facets(&facets)?;
        let mut links: SmallVec<[K::Neighbours; INLINE / 2]> =
            SmallVec::from_elem(K::no_neighbours(), new.len());
        let base = self.slots.len() as u32;
        // (new j, local i, outside index)
        let mut external: SmallVec<[(usize, usize, usize); INLINE]> = SmallVec::new();
        for (&(key, j1, i1), &partner) in facets.iter().zip(&partners) {
            match partner {
                SECOND => {}
                LONE => {
                    let Ok(pos) = outside.binary_search_by_key(&key, |e| e.0) else {
                        return Err(Rejection::NonManifold);
                    };
                    if outside[pos].2 {
                        return Err(Rejection::NonManifold);
                    }
                    outside[pos].2 = true;
                    external.push((j1, i1, pos));
                }
                partner => {
                    let (_, j2, i2) = facets[partner as usize];
                    if j1 == j2 {
                        return Err(Rejection::NonManifold);
                    }
                    links[j1].as_mut()[i1] = Some(CellId::new(base + j2 as u32));
                    links[j2].as_mut()[i2] = Some(CellId::new(base + j1 as u32));
                }
            }
        }
        if outside.iter().any(|e| !e.2) {
            return Err(Rejection::NonManifold);
        }
        // Commit.
        self.book.move_clock += 1;
        for &c in old {
            self.alive[c.index()] = false;
            self.mark_star_cells_changed(c);
        }
        self.live_cells -= old.len();
        for &(j, i, pos) in &external {
            let (key, nb, _) = outside[pos];
            links[j].as_mut()[i] = nb;
            if let Some(nb) = nb {
                let local = (0..K::NV)
                    .find(|&l| facet_key(self.cell(nb), l) == key)
                    .expect("outside cell shares the facet");
                self.slots[nb.index()].neighbours.as_mut()[local] =
                    Some(CellId::new(base + j as u32));
            }
        }
        for (key, a, b) in glued {
            for (cell, other) in [(a, b), (b, a)] {
                if let Some(cell) = cell {
                    let local = (0..K::NV)
                        .find(|&l| facet_key(self.cell(cell), l) == key)
                        .expect("glued cell has the facet");
                    self.slots[cell.index()].neighbours.as_mut()[local] = other;
                }
            }
        }
        for (j, (cell, label)) in new.iter().enumerate() {
            let id = CellId::new(base + j as u32);
            self.slots.push(Slot::new(*cell, links[j]));
            self.labels.push(*label);
            self.alive.push(true);
            self.mark_star_cells_changed(id);
            for &v in cell.as_ref() {
                if self.vertex_cell[v.index()].is_none() {
                    self.live_vertices += 1;
                }
                self.vertex_cell[v.index()] = Some(id);
            }
        }
        self.live_cells += new.len();
        self.remark_interface_cells_of_cavity(old, base..base + new.len() as u32, &around);
        // Vertices whose recorded cell died and that no new cell uses.
        for &c in old {
            for i in 0..K::NV {
                let v = self.slots[c.index()].corners.as_ref()[i];
                if self.vertex_cell[v.index()].is_some_and(|vc| !self.alive[vc.index()]) {
                    let replacement = old
                        .iter()
                        .flat_map(|&o| self.slots[o.index()].neighbours.as_ref().iter().flatten())
                        .copied()
                        .find(|&n| self.alive[n.index()] && self.cell(n).contains(&v));
                    if replacement.is_none() {
                        self.live_vertices -= 1;
                    }
                    self.vertex_cell[v.index()] = replacement;
                }
            }
        }
        match reclassify {
            Reclassify::AllCorners => {
                let fresh: SmallVec<[CellId; INLINE / 2]> =
                    (base..base + new.len() as u32).map(CellId::new).collect();
                self.reclassify_cells(&fresh);
            }
            Reclassify::NewVertices => {
                let mut added: SmallVec<[VertexId; 4]> = new
                    .iter()
                    .flat_map(|(cell, _)| cell.as_ref().iter().copied())
                    .filter(|v| {
                        !old.iter()
                            .any(|&c| self.slots[c.index()].corners.as_ref().contains(v))
                    })
                    .collect();
                self.reclassify_vertices(&mut added);
            }
            Reclassify::Nothing => {}
        }
        Ok(())
    }
}
