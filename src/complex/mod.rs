//! The simplicial complex: connectivity, labels, classification and validation.
//!
//! Each cell stores its `N + 1` vertices (positively oriented) and the neighbour
//! across the facet opposite each of them (the CGAL/TetGen layout); each vertex
//! stores one incident cell. Facets and edges stay implicit. This module knows
//! nothing of images or forces. Complexes are built from arrays, as box meshes
//! (`build.rs`), or, with the `tetgen` feature, conforming to a closed
//! surface (the `surface` module, TetGen).

mod bookkeeping;
mod build;
mod cavity;
mod class;
mod export;
mod interface;
mod interface_cells;
mod junction;
mod measure;
mod reorder;
mod seen;
mod slot;
mod stretch;
#[cfg(feature = "tetgen")]
pub mod surface;
mod validate;
pub mod vtk;

pub use crate::ids::{CellId, Label, VertexId};
pub use build::BuildError;
pub use cavity::Rejection;
pub use class::{VertexClass, VertexKind};
pub use export::MeshArrays;
pub use interface::{InterfaceFacet, InterfaceFacets};
pub use validate::Finding;

use crate::dim::{Dim, Point, D2, D3};
use bookkeeping::Bookkeeping;
use slot::Slot;

/// A labelled simplicial complex filling an axis-aligned box (the image domain).
///
/// Its operations are documented in blocks named by the layer that adds
/// them: `complex` (storage, connectivity, construction, classes,
/// measures, the interface, validation, VTK files), `ops` (local mesh
/// operations: moves, flips, collapses, splits, smoothing), `dsc` (the
/// deformation and the improvement and resizing around it) and `segment`
/// (voxel ownership).
#[derive(Clone, Debug)]
pub struct Complex<K: Dim> {
    positions: Vec<K::Point>,
    /// One incident live cell per vertex; `None` for a removed vertex.
    vertex_cell: Vec<Option<CellId>>,
    classes: Vec<VertexClass>,
    /// Per cell id: its corners and neighbours (one record, see [`Slot`]).
    slots: Vec<Slot<K>>,
    labels: Vec<Label>,
    alive: Vec<bool>,
    /// The live cells with a neighbour of another label (see
    /// `interface_cells.rs`).
    interface_cells: interface_cells::CellBits,
    live_cells: usize,
    live_vertices: usize,
    domain_min: K::Point,
    domain_max: K::Point,
    /// Clocks, counters, the last compaction's maps and spare lists: what
    /// the complex records for the caches of other layers and lends to
    /// operations, apart from the mesh itself.
    book: Bookkeeping,
}

/// A triangle complex.
pub type Complex2 = Complex<D2>;
/// A tetrahedral complex.
pub type Complex3 = Complex<D3>;

/// Layer `complex`: storage and connectivity: positions, cells, labels,
/// neighbours, stars, counts and ids.
impl<K: Dim> Complex<K> {
    /// Position of a vertex.
    #[inline]
    pub fn position(&self, v: VertexId) -> K::Point {
        self.positions[v.index()]
    }
    /// Vertices of a cell.
    #[inline]
    pub fn cell(&self, c: CellId) -> &[VertexId] {
        self.slots[c.index()].corners.as_ref()
    }
    /// Neighbours of a cell, opposite each local vertex.
    #[inline]
    pub fn neighbours(&self, c: CellId) -> &[Option<CellId>] {
        self.slots[c.index()].neighbours.as_ref()
    }
    /// Phase label of a cell.
    #[inline]
    pub fn label(&self, c: CellId) -> Label {
        self.labels[c.index()]
    }
    /// Classification of a vertex (kept current by every operation).
    #[inline]
    pub fn class(&self, v: VertexId) -> VertexClass {
        self.classes[v.index()]
    }
    /// Whether a cell id refers to a live cell.
    #[inline]
    pub fn is_alive(&self, c: CellId) -> bool {
        self.alive[c.index()]
    }
    /// Whether a vertex id refers to a live vertex.
    #[inline]
    pub fn is_vertex_alive(&self, v: VertexId) -> bool {
        self.vertex_cell[v.index()].is_some()
    }
    /// Number of live cells.
    pub fn cell_count(&self) -> usize {
        self.live_cells
    }
    /// Number of live vertices.
    pub fn vertex_count(&self) -> usize {
        self.live_vertices
    }
    /// Upper bound of vertex ids (length of per-vertex arrays).
    pub fn vertex_capacity(&self) -> usize {
        self.positions.len()
    }
    /// Upper bound of cell ids (length of per-cell arrays).
    pub fn cell_capacity(&self) -> usize {
        self.slots.len()
    }
    /// Live cell ids.
    pub fn cell_ids(&self) -> impl Iterator<Item = CellId> + '_ {
        (0..self.slots.len() as u32)
            .map(CellId::new)
            .filter(|c| self.alive[c.index()])
    }
    /// Per cell id, in order: the cell's label, `None` for a dead cell. Zipped
    /// with a per-cell array, it sums over the live cells in one pass over
    /// flat arrays, without an id lookup per cell.
    pub fn label_slots(&self) -> impl Iterator<Item = Option<Label>> + '_ {
        self.alive
            .iter()
            .zip(&self.labels)
            .map(|(&alive, &label)| alive.then_some(label))
    }
    /// Live vertex ids.
    pub fn vertex_ids(&self) -> impl Iterator<Item = VertexId> + '_ {
        (0..self.positions.len() as u32)
            .map(VertexId)
            .filter(|v| self.vertex_cell[v.index()].is_some())
    }
    /// The domain box `(min, max)`.
    pub fn domain(&self) -> (K::Point, K::Point) {
        (self.domain_min, self.domain_max)
    }
    /// Corner positions of a cell.
    pub fn cell_points(&self, c: CellId) -> [K::Point; 4] {
        let mut out = [K::Point::zero(); 4];
        for (o, v) in out.iter_mut().zip(self.cell(c)) {
            *o = self.positions[v.index()];
        }
        out
    }
    /// Signed area/volume of a cell.
    pub fn measure(&self, c: CellId) -> f64 {
        K::signed_measure(&self.cell_points(c)[..K::NV])
    }
    /// Quality in `[0, 1]` of a cell (see [`Dim::quality`]); every cell is
    /// positively oriented (exactly), so the orientation test is not
    /// repeated ([`Dim::quality_oriented`]).
    pub fn quality(&self, c: CellId) -> f64 {
        K::quality_oriented(&self.cell_points(c)[..K::NV])
    }
    /// Whether the facet opposite local vertex `i` of `c` separates two phases.
    pub fn is_interface_facet(&self, c: CellId, i: usize) -> bool {
        match self.neighbours(c)[i] {
            Some(nb) => self.labels[nb.index()] != self.labels[c.index()],
            None => false,
        }
    }
    /// Local index of vertex `v` in cell `c`.
    pub fn local_index(&self, c: CellId, v: VertexId) -> Option<usize> {
        self.cell(c).iter().position(|&w| w == v)
    }
    /// One live cell incident to `v`.
    pub fn incident_cell(&self, v: VertexId) -> Option<CellId> {
        self.vertex_cell[v.index()]
    }

    /// Collects the cells incident to `v` into `out` (cleared first), by walking
    /// across facets that contain `v`: breadth-first from its stored cell.
    pub fn star_into(&self, v: VertexId, out: &mut Vec<CellId>) {
        if K::STAR_IS_FAN {
            self.fan_into(v, out);
        } else {
            self.star_by_search(v, out);
        }
    }

    /// The breadth-first walk of [`star_into`](Self::star_into).
    fn star_by_search(&self, v: VertexId, out: &mut Vec<CellId>) {
        self.star_search_until(v, out, |_| false);
    }

    /// The breadth-first walk of [`star_into`](Self::star_into), stopped at
    /// the first cell collected for which `found` holds (returned; `out`
    /// then holds the cells collected so far).
    fn star_search_until(
        &self,
        v: VertexId,
        out: &mut Vec<CellId>,
        found: impl Fn(CellId) -> bool,
    ) -> Option<CellId> {
        out.clear();
        let start = self.vertex_cell[v.index()]?;
        let mut seen = seen::SeenCells::new();
        seen.insert(start, out);
        out.push(start);
        let mut next = 0;
        while next < out.len() {
            let c = out[next];
            if found(c) {
                return Some(c);
            }
            next += 1;
            let verts = self.cell(c);
            for (i, nb) in self.neighbours(c).iter().enumerate() {
                if verts[i] == v {
                    continue;
                }
                if let Some(nb) = *nb {
                    if seen.insert(nb, out) {
                        out.push(nb);
                    }
                }
            }
        }
        None
    }

    /// The 2D star is a fan: every cell has two edges through `v`, so the
    /// breadth-first search is two walks leaving the start cell on either
    /// side, taking turns. Walking them directly gives the same cells in the
    /// same order (callers' floating-point sums depend on it) with no
    /// membership test but at the start: the star is the hottest query of
    /// 2D mesh improvement.
    fn fan_into(&self, v: VertexId, out: &mut Vec<CellId>) {
        out.clear();
        let Some(start) = self.vertex_cell[v.index()] else {
            return;
        };
        out.push(start);
        // Each front: the cell to step from and the cell it was reached from.
        let mut fronts = [None, None];
        let mut opened = 0;
        let verts = self.cell(start);
        for (i, nb) in self.neighbours(start).iter().enumerate() {
            if let (false, Some(nb)) = (verts[i] == v, *nb) {
                if !out.contains(&nb) {
                    out.push(nb);
                    fronts[opened] = Some((nb, start));
                    opened += 1;
                }
            }
        }
        // The last cell each walk took (the start before its first step):
        // a walk has closed the fan when its next cell is the other walk's
        // last, since the cells taken form one arc around `v` ending there.
        let mut ends = [start; 2];
        for (end, front) in ends.iter_mut().zip(&fronts) {
            if let Some((c, _)) = *front {
                *end = c;
            }
        }
        while fronts.iter().any(Option::is_some) {
            for k in 0..2 {
                if let Some((c, from)) = fronts[k] {
                    fronts[k] = self.fan_step(v, c, from, ends[1 - k]);
                    if let Some((next, _)) = fronts[k] {
                        out.push(next);
                        ends[k] = next;
                    }
                }
            }
        }
    }

    /// One step of a fan walk: the cell beyond `c` (across its edge through
    /// `v` that does not lead back to `from`) and `c`, unless the walk is at
    /// the border or closed (the cell beyond is `closing`, the other walk's
    /// last cell).
    #[inline]
    fn fan_step(
        &self,
        v: VertexId,
        c: CellId,
        from: CellId,
        closing: CellId,
    ) -> Option<(CellId, CellId)> {
        let verts = self.cell(c);
        for (i, nb) in self.neighbours(c).iter().enumerate() {
            if let (false, Some(nb)) = (verts[i] == v, *nb) {
                if nb != from {
                    return (nb != closing).then_some((nb, c));
                }
            }
        }
        None
    }

    /// Collects the vertices adjacent to `v` (its link vertices) into `out`.
    pub fn neighbours_of_vertex(
        &self,
        v: VertexId,
        star: &mut Vec<CellId>,
        out: &mut Vec<VertexId>,
    ) {
        self.star_into(v, star);
        out.clear();
        for &c in star.iter() {
            for &w in self.cell(c) {
                if w != v && !out.contains(&w) {
                    out.push(w);
                }
            }
        }
    }

    /// Collects the live cells containing both `u` and `v` into `out`: in
    /// 2D from the fan of `u`; in 3D by searching the star of `u` only until
    /// a cell of the edge turns up, then turning around the edge from cell
    /// to cell across the facets that hold it (the ring of a 3D edge holds
    /// 4–7 tets, the star of a vertex 20–30).
    pub fn cells_of_edge(
        &self,
        u: VertexId,
        v: VertexId,
        star: &mut Vec<CellId>,
        out: &mut Vec<CellId>,
    ) {
        out.clear();
        if K::STAR_IS_FAN {
            self.star_into(u, star);
            out.extend(star.iter().copied().filter(|&c| self.cell(c).contains(&v)));
            return;
        }
        if let Some(first) = self.star_search_until(u, star, |c| self.cell(c).contains(&v)) {
            self.turn_around_edge(u, v, first, out);
        }
    }

    /// The cells around the edge `uv` from `first` (which holds it), in
    /// turning order: one way round until the ring closes, or, where it
    /// meets the domain boundary, both ways from `first`. A caller that
    /// knows a cell of the edge turns from it rather than searching the
    /// star of `u` for one (3D only: in 2D an edge's cells are its fan's).
    pub(crate) fn turn_around_edge(
        &self,
        u: VertexId,
        v: VertexId,
        first: CellId,
        out: &mut Vec<CellId>,
    ) {
        out.clear();
        out.push(first);
        // The facets of a cell that hold the edge are those opposite its
        // two other corners.
        let exits = |c: CellId| {
            let verts = self.cell(c);
            let mut facing = (0..verts.len()).filter(|&i| verts[i] != u && verts[i] != v);
            let nbs = self.neighbours(c);
            let a = facing.next().and_then(|i| nbs[i]);
            let b = facing.next().and_then(|i| nbs[i]);
            (a, b)
        };
        let (ahead, behind) = exits(first);
        for start in [ahead, behind] {
            let (mut from, mut at) = (first, start);
            while let Some(c) = at {
                if c == first || out.len() > self.live_cells {
                    return;
                }
                out.push(c);
                let (a, b) = exits(c);
                let step = if a == Some(from) { b } else { a };
                (from, at) = (c, step);
            }
        }
    }

    /// Sets the label of one cell and reclassifies its vertices.
    pub fn set_label(&mut self, c: CellId, label: Label) {
        if self.labels[c.index()] != label {
            self.book.relabels += 1;
            self.labels[c.index()] = label;
            self.remark_interface_cells_around(c);
            self.reclassify_cells(&[c]);
        }
    }

    /// Sets many labels at once (one reclassification pass).
    pub fn set_labels(&mut self, changes: &[(CellId, Label)]) {
        self.book.relabels += 1;
        for &(c, l) in changes {
            self.labels[c.index()] = l;
        }
        for &(c, _) in changes {
            self.remark_interface_cells_around(c);
        }
        let cells: Vec<CellId> = changes.iter().map(|&(c, _)| c).collect();
        self.reclassify_cells(&cells);
    }

    /// Moves a vertex without any check. Callers must keep every cell positive
    /// ([`Complex::move_towards`](crate::ops) does).
    pub(crate) fn set_position(&mut self, v: VertexId, p: K::Point) {
        let mut star = self.take_list();
        self.star_into(v, &mut star);
        self.set_position_in_star(v, p, &star);
        self.give_back(star);
    }

    /// [`set_position`](Self::set_position) for a caller that holds the
    /// cells of `v`'s star (`star`, in any order): the vertex move and the
    /// smoothing move have just searched it to test the move, and a second
    /// search would find the same cells.
    pub(crate) fn set_position_in_star(&mut self, v: VertexId, p: K::Point, star: &[CellId]) {
        self.positions[v.index()] = p;
        self.book.move_clock += 1;
        self.book.moved_at[v.index()] = self.book.move_clock;
        // Every vertex sharing a cell with `v` has a changed star.
        for &c in star {
            self.mark_star_changed(c);
        }
    }

    /// An empty list of cells from the spares (a new one if none is left);
    /// [`give_back`](Self::give_back) returns it.
    pub(crate) fn take_list(&mut self) -> Vec<CellId> {
        self.book.spare_lists.pop().unwrap_or_default()
    }

    /// Returns a list taken by [`take_list`](Self::take_list) to the spares.
    pub(crate) fn give_back(&mut self, mut list: Vec<CellId>) {
        list.clear();
        self.book.spare_lists.push(list);
    }

    /// Records that the stars of `c`'s corners changed now.
    #[inline]
    pub(crate) fn mark_star_changed(&mut self, c: CellId) {
        let clock = self.book.move_clock;
        for k in 0..K::NV {
            let w = self.slots[c.index()].corners.as_ref()[k];
            self.book.star_changed_at[w.index()] = clock;
        }
    }

    /// Records that the stars of `c`'s corners changed now, by a cell
    /// created or removed (see [`cells_changed_at`](Self::cells_changed_at)).
    #[inline]
    pub(crate) fn mark_star_cells_changed(&mut self, c: CellId) {
        self.mark_star_changed(c);
        let clock = self.book.move_clock;
        for k in 0..K::NV {
            let w = self.slots[c.index()].corners.as_ref()[k];
            self.book.cells_changed_at[w.index()] = clock;
        }
    }

    /// A counter that advances with every vertex move or creation and every
    /// replacement of cells: a result computed from positions at clock `t`
    /// still holds for the vertices whose [`moved_at`](Self::moved_at) is at
    /// most `t`, and one computed from a vertex's star for the vertices
    /// whose [`star_changed_at`](Self::star_changed_at) is.
    pub fn move_clock(&self) -> u64 {
        self.book.move_clock
    }

    /// A counter of the calls that changed labels ([`set_label`](Self::set_label),
    /// [`set_labels`](Self::set_labels), [`label_by`](Self::label_by)): a
    /// result that depends on labels holds while it is unchanged.
    pub fn relabels(&self) -> u64 {
        self.book.relabels
    }

    /// The [`move_clock`](Self::move_clock) when the star of `v` last
    /// changed: `v` or a vertex sharing a cell with it moved, or a cell
    /// around `v` was created or removed.
    #[inline]
    pub fn star_changed_at(&self, v: VertexId) -> u64 {
        self.book.star_changed_at[v.index()]
    }

    /// The [`move_clock`](Self::move_clock) when a cell around `v` was last
    /// created or removed (moves do not count): while it is at most `t`,
    /// the star of `v` holds the cells, and a star search from `v` finds
    /// them in the order, that it did at `t` (the search reads only those
    /// cells, their neighbours across facets through `v`, and the stored
    /// cell of `v`, which changes only with a cell around it).
    #[inline]
    pub fn cells_changed_at(&self, v: VertexId) -> u64 {
        self.book.cells_changed_at[v.index()]
    }

    /// The [`move_clock`](Self::move_clock) when `v` was created or last moved.
    #[inline]
    pub fn moved_at(&self, v: VertexId) -> u64 {
        self.book.moved_at[v.index()]
    }

    /// The largest label in use plus one.
    pub fn label_count(&self) -> usize {
        self.cell_ids()
            .map(|c| self.labels[c.index()] as usize + 1)
            .max()
            .unwrap_or(0)
    }

    /// Removes dead vertices and cells and renumbers the rest densely, returning
    /// the old-to-new vertex and cell maps. Invalidates every id held outside.
    pub fn compact(&mut self) -> (Vec<Option<VertexId>>, Vec<Option<CellId>>) {
        self.compact_in_place();
        (
            self.book.last_vertex_map.clone(),
            self.book.last_cell_map.clone(),
        )
    }

    /// [`Complex::compact`]: the arrays are compacted in place, without
    /// allocating (live entries keep their relative order, exactly as
    /// `compact` numbers them), and the maps are kept in
    /// [`Complex::last_cell_map`] and [`Complex::last_vertex_map`]. The
    /// deform loop calls this every iteration. In 3D, once a quarter of the
    /// cells were appended since the last time, it then also renumbers both
    /// in spatial order into new arrays (`reorder.rs`; see
    /// [`Complex::last_compaction_reordered`]): the order is then spatial,
    /// and the maps compose both steps.
    ///
    /// In the compaction itself the entries below the first dead vertex
    /// (cell) keep their index: an
    /// iteration's edge flips replace a few cells and kill no vertex, so
    /// usually no vertex moves and half of the cells stay where they are.
    /// Those are not copied, and of their references only the ones past
    /// the kept prefixes are looked up in the maps.
    pub fn compact_in_place(&mut self) {
        let mut vmap = std::mem::take(&mut self.book.last_vertex_map);
        let mut cmap = std::mem::take(&mut self.book.last_cell_map);
        let kept_vertices = self
            .vertex_cell
            .iter()
            .position(Option::is_none)
            .unwrap_or(self.vertex_cell.len());
        let kept_cells = self
            .alive
            .iter()
            .position(|&a| !a)
            .unwrap_or(self.alive.len());
        let vertices = (self.vertex_cell.len(), kept_vertices);
        let n = renumber(&mut vmap, vertices, VertexId, |i| {
            self.vertex_cell[i].is_some()
        });
        let ordered = self.ordered_survivors(kept_cells);
        let cells = (self.alive.len(), kept_cells);
        let m = renumber(&mut cmap, cells, CellId::new, |i| self.alive[i]);
        let kept = (kept_vertices, kept_cells);
        self.carry_vertices(&vmap, &cmap, kept, n as usize);
        self.carry_cells(&vmap, &cmap, kept, m as usize);
        self.book.last_vertex_map = vmap;
        self.book.last_cell_map = cmap;
        self.book.compactions += 1;
        self.book.ordered_cells = ordered;
        self.book.last_compaction_reordered = self.reorder_due(ordered, m as usize);
        if self.book.last_compaction_reordered {
            self.reorder_spatially();
            self.book.ordered_cells = m as usize;
        }
    }

    /// Whether the last compaction renumbered spatially as well: its maps
    /// then permute the ids instead of keeping their order, and a per-cell
    /// or per-vertex record cannot follow them by forward copies in place.
    pub fn last_compaction_reordered(&self) -> bool {
        self.book.last_compaction_reordered
    }

    /// The vertex half of [`compact_in_place`](Self::compact_in_place): the
    /// vertices from `kept_vertices` on move down to their new index, and
    /// every vertex's cell is renumbered where it lies from `kept_cells` on;
    /// `n` vertices stay.
    fn carry_vertices(
        &mut self,
        vmap: &[Option<VertexId>],
        cmap: &[Option<CellId>],
        (kept_vertices, kept_cells): (usize, usize),
        n: usize,
    ) {
        // A kept vertex stays; its cell may have moved.
        for cell in &mut self.vertex_cell[..kept_vertices] {
            if let Some(c) = *cell {
                if c.index() >= kept_cells {
                    *cell = cmap[c.index()];
                }
            }
        }
        // Forward copies: the new index never exceeds the old one.
        for (i, new) in vmap.iter().enumerate().skip(kept_vertices) {
            if let Some(new) = *new {
                let k = new.index();
                self.positions[k] = self.positions[i];
                self.book.moved_at[k] = self.book.moved_at[i];
                self.book.star_changed_at[k] = self.book.star_changed_at[i];
                self.book.cells_changed_at[k] = self.book.cells_changed_at[i];
                self.classes[k] = self.classes[i];
                self.vertex_cell[k] = self.vertex_cell[i].and_then(|c| cmap[c.index()]);
            }
        }
        self.positions.truncate(n);
        self.book.moved_at.truncate(n);
        self.book.star_changed_at.truncate(n);
        self.book.cells_changed_at.truncate(n);
        self.classes.truncate(n);
        self.vertex_cell.truncate(n);
    }

    /// The cell half of [`compact_in_place`](Self::compact_in_place): a cell
    /// below `kept_cells` stays and has only its references past the kept
    /// prefixes renumbered; the cells from `kept_cells` on move down to
    /// their new index; `m` cells stay.
    fn carry_cells(
        &mut self,
        vmap: &[Option<VertexId>],
        cmap: &[Option<CellId>],
        (kept_vertices, kept_cells): (usize, usize),
        m: usize,
    ) {
        let vertices_moved = kept_vertices < vmap.len();
        for i in 0..kept_cells {
            if vertices_moved {
                for v in self.slots[i].corners.as_mut() {
                    if v.index() >= kept_vertices {
                        *v = vmap[v.index()].expect("live cell references a live vertex");
                    }
                }
            }
            for nb in self.slots[i].neighbours.as_mut() {
                if let Some(c) = *nb {
                    if c.index() >= kept_cells {
                        *nb = cmap[c.index()];
                    }
                }
            }
        }
        for (i, new) in cmap.iter().enumerate().skip(kept_cells) {
            if let Some(new) = *new {
                let k = new.index();
                let mut slot = self.slots[i];
                for v in slot.corners.as_mut() {
                    *v = vmap[v.index()].expect("live cell references a live vertex");
                }
                for c in slot.neighbours.as_mut() {
                    *c = c.and_then(|c| cmap[c.index()]);
                }
                self.slots[k] = slot;
                self.labels[k] = self.labels[i];
                let mark = self.interface_cells.contains(i);
                self.interface_cells.set(k, mark);
            }
        }
        self.interface_cells.resize(m);
        self.slots.truncate(m);
        self.labels.truncate(m);
        self.alive.truncate(m);
        self.alive[kept_cells.min(m)..].fill(true);
    }

    /// The old-to-new vertex map of the last [`Complex::compact`] (empty
    /// before the first).
    pub fn last_vertex_map(&self) -> &[Option<VertexId>] {
        &self.book.last_vertex_map
    }

    /// A number distinct for every complex built or cloned in the process:
    /// records about one complex kept across calls check it before
    /// trusting its clocks.
    pub(crate) fn identity(&self) -> u64 {
        self.book.identity
    }

    /// How many times [`Complex::compact`] has renumbered this complex (lets
    /// per-cell caches follow the renumbering, see [`Complex::last_cell_map`]).
    pub fn compactions(&self) -> u64 {
        self.book.compactions
    }

    /// The old-to-new cell map of the last [`Complex::compact`] (empty before
    /// the first).
    pub fn last_cell_map(&self) -> &[Option<CellId>] {
        &self.book.last_cell_map
    }
}

/// Fills `map` with the old-to-new numbering (ids made by `id`) of `len`
/// entries whose first `kept` are all live (they keep their index) and the
/// rest live where `live` says; returns how many are live.
fn renumber<Id>(
    map: &mut Vec<Option<Id>>,
    (len, kept): (usize, usize),
    id: fn(u32) -> Id,
    live: impl Fn(usize) -> bool,
) -> u32 {
    map.clear();
    map.extend((0..kept as u32).map(|i| Some(id(i))));
    let mut next = kept as u32;
    map.extend((kept..len).map(|i| {
        live(i).then(|| {
            next += 1;
            id(next - 1)
        })
    }));
    next
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dsc::{Destinations, DscParams};
    use nalgebra::Vector2;

    /// What a compaction must give: the live vertices and cells renumbered
    /// densely in their old order (a live entry's new id is its rank among
    /// the live ones), each cell with its corners, label and neighbours
    /// renumbered so. Checked on a mesh whose first dead vertex and cell lie
    /// in its middle (a collapse there) and which grew at its end (a split),
    /// and on one with no dead entry at all.
    #[test]
    fn compaction_renumbers_live_entries_by_rank() {
        let mut c = Complex::<D2>::rectangle(40.0, 32.0, 4.0).unwrap();
        c.label_by(|p| u32::from(p.x > 21.0));
        let middle = c.cell_count() / 2;
        let [u, v, ..] = *c.cell(CellId::new(middle as u32)) else {
            unreachable!()
        };
        c.collapse_edge(u, v, crate::ops::CollapseMode::Unsafe, 0.0, 1.0)
            .unwrap();
        let last = CellId::new(c.cell_capacity() as u32 - 1);
        let [a, b, ..] = *c.cell(last) else {
            unreachable!()
        };
        c.split_edge(a, b).unwrap();
        // (the test's premise: dead entries before the last live ones)
        assert!(c.vertex_count() < c.vertex_capacity() && c.cell_count() < c.cell_capacity());
        assert!(c.is_vertex_alive(VertexId(c.vertex_capacity() as u32 - 1)));
        for round in ["dead entries in the middle", "no dead entry"] {
            let rank = |alive: &dyn Fn(usize) -> bool, n: usize| {
                let mut next = 0u32;
                (0..n)
                    .map(|i| {
                        alive(i).then(|| {
                            next += 1;
                            next - 1
                        })
                    })
                    .collect::<Vec<_>>()
            };
            let vrank = rank(
                &|i| c.is_vertex_alive(VertexId(i as u32)),
                c.vertex_capacity(),
            );
            let crank = rank(&|i| c.is_alive(CellId::new(i as u32)), c.cell_capacity());
            let expected: Vec<_> = c
                .cell_ids()
                .map(|x| {
                    let corners: Vec<u32> = c
                        .cell(x)
                        .iter()
                        .map(|w| vrank[w.index()].unwrap())
                        .collect();
                    let neighbours: Vec<Option<u32>> = c
                        .neighbours(x)
                        .iter()
                        .map(|nb| nb.map(|nb| crank[nb.index()].unwrap()))
                        .collect();
                    (corners, neighbours, c.label(x))
                })
                .collect();
            let positions: Vec<_> = c.vertex_ids().map(|w| c.position(w)).collect();
            c.compact_in_place();
            let got: Vec<_> = c
                .cell_ids()
                .map(|x| {
                    let corners: Vec<u32> = c.cell(x).iter().map(|w| w.0).collect();
                    let neighbours: Vec<Option<u32>> = c
                        .neighbours(x)
                        .iter()
                        .map(|nb| nb.map(|nb| nb.raw()))
                        .collect();
                    (corners, neighbours, c.label(x))
                })
                .collect();
            assert_eq!(got, expected, "{round}");
            assert_eq!(c.cell_capacity(), expected.len(), "{round}");
            let moved: Vec<_> = c.vertex_ids().map(|w| c.position(w)).collect();
            assert_eq!(moved, positions, "{round}");
            assert!(c.validate().is_empty(), "{round}: {:?}", c.validate());
        }
    }

    /// The fan walk gives the breadth-first star cell for cell, in order, and
    /// the same number of phase pieces as the search, for every vertex
    /// (interior, border, corner, interface, junction) of a three-phase mesh
    /// deformed, flipped, collapsed and split by many DSC steps.
    #[test]
    fn fan_walk_equals_breadth_first_search() {
        let l = 4.0;
        let mut c = Complex::<D2>::rectangle(48.0, 40.0, l).unwrap();
        // Three phases meeting at junctions, and touching the border.
        c.label_by(|p| {
            u32::from((p - Vector2::new(22.0, 19.0)).norm() < 11.0)
                + 2 * u32::from(p.x > 30.0 && p.y < 25.0)
        });
        let params = DscParams::new::<D2>(l);
        let (mut fan, mut bfs) = (Vec::new(), Vec::new());
        for step in 0..60 {
            let mut dest = Destinations::new(&c);
            for v in c.vertex_ids().collect::<Vec<_>>() {
                let p = c.position(v);
                let t = step as f64 * 0.3;
                let d = Vector2::new((p.y * 0.21 + t).sin(), (p.x * 0.17 - t).cos());
                dest.set(v, c.constrain(v, p + d * (0.4 * l)));
            }
            c.deform(&dest, &params);
            for v in c.vertex_ids() {
                c.fan_into(v, &mut fan);
                c.star_by_search(v, &mut bfs);
                assert_eq!(fan, bfs, "step {step}, vertex {v:?}");
                assert_eq!(
                    c.fan_phase_pieces(v),
                    Some(c.phase_pieces_by_search(v, &mut Vec::new())),
                    "step {step}, vertex {v:?}"
                );
            }
        }
    }
}
