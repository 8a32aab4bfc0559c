//! The memo and buffers of `deform` and mesh improvement, kept across calls.
//!
//! The segmentation deforms once per iteration, and each deform improves the
//! mesh a dozen times. Keeping one workspace for the whole run means that,
//! once its buffers have grown to the size of the interface band, an
//! iteration's deform allocates nothing of its own (the local mesh
//! operations' few small buffers aside).

use super::refusals::RefusedCollapses;
use super::splits_made::SplitsMade;
use super::SizingField;
use crate::complex::{CellId, VertexId};
use crate::dim::Dim;
use crate::ops::FlatEnds;
use crate::ops::{ImproveMemo, SmoothScratch};

/// What [`Complex::deform_with`](crate::complex::Complex::deform_with) (and,
/// inside the crate, the improvement it runs) keeps between calls: the
/// improvement memo ([`ImproveMemo`]) and scratch buffers, whose contents
/// never outlive a call, and the coarsening collapses and 3D flips the mesh
/// refused, which do (they hold while the stars involved are unchanged, and
/// are forgotten when another complex, or a compaction they did not follow,
/// comes). `deform_with` starts by forgetting the memo, so any complex may
/// use the workspace there; improvement calls in a row must be about one
/// complex (the memo's verdicts are about its cells and vertices).
#[derive(Debug)]
pub struct DscWorkspace<K: Dim> {
    pub(super) memo: ImproveMemo,
    /// Vertices still on their way, those that moved in this round, and
    /// every vertex moved or created in the call.
    pub(super) pending: Vec<VertexId>,
    pub(super) movers: Vec<VertexId>,
    pub(super) touched: Vec<VertexId>,
    /// Interface edges, for resizing.
    pub(super) edges: Vec<(VertexId, VertexId)>,
    /// The improved region's cells, and its vertices (smoothed).
    pub(super) region: RegionBuffers,
    pub(super) vertices: Vec<VertexId>,
    /// The region grown by a ring, for the removal of degenerate cells.
    pub(super) grown: Vec<CellId>,
    pub(super) grown_marks: Vec<bool>,
    pub(super) walk: WalkScratch,
    pub(super) smooth: SmoothScratch<K>,
    /// The target edge length over the domain, read by resizing and the
    /// degenerate-cell thresholds (uniform unless set).
    pub(super) sizing: SizingField,
    /// The coarsening collapses the mesh refused, kept across calls (they
    /// follow the compactions; see [`RefusedCollapses`]).
    pub(super) refusals: RefusedCollapses,
    /// The resize's record of the interface vertices' flatness (emptied by
    /// every resize; kept for its buffer).
    pub(super) flat_ends: FlatEnds,
}

impl<K: Dim> DscWorkspace<K> {
    /// An empty workspace.
    pub fn new() -> Self {
        DscWorkspace {
            memo: ImproveMemo::new(),
            pending: Vec::new(),
            movers: Vec::new(),
            touched: Vec::new(),
            edges: Vec::new(),
            region: RegionBuffers::default(),
            vertices: Vec::new(),
            grown: Vec::new(),
            grown_marks: Vec::new(),
            walk: WalkScratch::default(),
            smooth: SmoothScratch::default(),
            sizing: SizingField::uniform(),
            refusals: RefusedCollapses::default(),
            flat_ends: FlatEnds::default(),
        }
    }
}

impl<K: Dim> DscWorkspace<K> {
    /// The sizing field the next deform and improvement read.
    pub fn sizing(&self) -> &SizingField {
        &self.sizing
    }

    /// Sets the sizing field; the memo's verdicts (about the old
    /// thresholds) are forgotten.
    pub fn set_sizing(&mut self, sizing: SizingField) {
        self.sizing = sizing;
        self.memo.forget();
    }

    /// [`set_sizing`](Self::set_sizing) to a copy of `sizing`, made in the
    /// buffer of the field it replaces (a caller that sets a field of the
    /// same grid every iteration allocates none).
    pub fn copy_sizing(&mut self, sizing: &SizingField) {
        self.sizing.clone_from(sizing);
        self.memo.forget();
    }
}

impl<K: Dim> Default for DscWorkspace<K> {
    fn default() -> Self {
        Self::new()
    }
}

/// Buffers of the walks over a region's vertices and their stars.
#[derive(Debug, Default)]
pub(crate) struct WalkScratch {
    pub(super) vertices: Vec<VertexId>,
    pub(super) vertex_marks: Vec<bool>,
    pub(super) star: Vec<CellId>,
    /// The worklist of degenerate-cell removal.
    pub(super) work: Vec<CellId>,
    /// The vertices the current degenerate-cell removal made by splits,
    /// which it does not collapse away.
    pub(super) splits: SplitsMade,
    /// Per cell of a large region whose degenerate cells are removed:
    /// whether it was degenerate when the removal began.
    pub(super) ahead: Vec<bool>,
    /// Per vertex of `vertices`: whether its star holds a degenerate cell.
    pub(super) degenerate: Vec<bool>,
    /// The degenerate cells found by one pass over the cells.
    pub(super) degenerate_cells: Vec<CellId>,
    /// Per vertex id: whether it is a corner of one of `degenerate_cells`.
    pub(super) star_marks: Vec<bool>,
    /// Cells found not degenerate by the current search for degenerate
    /// cells (see [`CheckedCells`]).
    pub(super) checked: CheckedCells,
}

/// The cells one search for degenerate cells has found sound, so that a
/// cell shared by the stars of several vertices is measured once. A cell
/// is marked with the search's number: starting a search forgets the last
/// one's marks without clearing the array.
#[derive(Debug, Default)]
pub(crate) struct CheckedCells {
    search: u32,
    marks: Vec<u32>,
}

impl CheckedCells {
    /// Starts a search over a complex of `cells` cell ids.
    pub(super) fn start(&mut self, cells: usize) {
        self.search = self.search.wrapping_add(1);
        if self.search == 0 {
            // (the numbers went round: no mark may look current)
            self.marks.iter_mut().for_each(|m| *m = 0);
            self.search = 1;
        }
        self.marks.resize(cells, 0);
    }

    /// Whether this search already found `c` sound.
    pub(super) fn contains(&self, c: CellId) -> bool {
        self.marks[c.index()] == self.search
    }

    /// Records that this search found `c` sound.
    pub(super) fn insert(&mut self, c: CellId) {
        self.marks[c.index()] = self.search;
    }
}

/// The buffers of a [`Region`](super::Region): its cells, their marks by
/// cell id, a star, and (3D, collected star by star) the seeds' stars.
#[derive(Debug, Default)]
pub(crate) struct RegionBuffers {
    pub(super) cells: Vec<CellId>,
    pub(super) marks: Vec<bool>,
    pub(super) star: Vec<CellId>,
    pub(super) stars: SeedStars,
    /// The next [`SeedStars`] while it is being built.
    pub(super) spare_stars: SeedStars,
}

/// The stars of a region's seeds, one after the other in seed order, and
/// when they were searched: a later collection of the same region searches
/// again only the seeds a cell around which was created or removed since
/// ([`Complex::cells_changed_at`](crate::complex::Complex::cells_changed_at)),
/// and takes the others' stars from here, where a search would find the
/// same cells in the same order.
#[derive(Debug, Default)]
pub(crate) struct SeedStars {
    /// The stars' cells, seed after seed (none for a dead seed).
    pub(super) cells: Vec<CellId>,
    /// Per seed, where its star ends in `cells`.
    pub(super) ends: Vec<u32>,
    /// The move clock and the compactions of the complex when the stars
    /// were current (`None`: nothing kept).
    pub(super) at: Option<(u64, u64)>,
}

impl SeedStars {
    /// Forgets the stars (keeps the capacity).
    pub(super) fn clear(&mut self) {
        self.cells.clear();
        self.ends.clear();
        self.at = None;
    }

    /// Appends the next seed's star.
    pub(super) fn push(&mut self, star: &[CellId]) {
        self.cells.extend_from_slice(star);
        self.ends.push(self.cells.len() as u32);
    }

    /// The star of seed `i`.
    pub(super) fn star(&self, i: usize) -> &[CellId] {
        let start = if i == 0 { 0 } else { self.ends[i - 1] as usize };
        &self.cells[start..self.ends[i] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::complex::Complex;
    use crate::dim::{Point, D2, D3};
    use crate::dsc::{Connectivity, Destinations, DscParams};
    use nalgebra::{Vector2, Vector3};

    /// Interface vertices move `step` away from the nearer of two centres:
    /// two regions grow into each other and merge (unsafe collapses, a
    /// topology change) over the rounds.
    fn growing<K: Connectivity>(
        mesh: &Complex<K>,
        centres: [K::Point; 2],
        step: f64,
    ) -> Destinations<K> {
        let mut dest = Destinations::new(mesh);
        for v in mesh.vertex_ids() {
            if !mesh.class(v).on_interface() {
                continue;
            }
            let p = mesh.position(v);
            let c = if (p - centres[0]).length() < (p - centres[1]).length() {
                centres[0]
            } else {
                centres[1]
            };
            let out = p - c;
            dest.set(v, mesh.constrain(v, p + out * (step / out.length())));
        }
        dest
    }

    /// One workspace kept across deforms gives, bit for bit, the meshes
    /// that a fresh workspace per deform gives, even when another complex
    /// uses it in between.
    fn kept_workspace_deforms_like_fresh_ones<K: Connectivity>(
        mut mesh: Complex<K>,
        centres: [K::Point; 2],
        l: f64,
        rounds: usize,
    ) {
        let params = DscParams::new::<K>(l);
        let mut kept = mesh.clone();
        let mut other = mesh.clone();
        let mut ws = DscWorkspace::new();
        let components = mesh.components(1);
        for round in 0..rounds {
            let dest = growing(&mesh, centres, 0.6 * l);
            let a = mesh.deform(&dest, &params);
            other.deform_with(&dest, &params, &mut ws);
            let b = kept.deform_with(&dest, &params, &mut ws);
            let (ma, mb) = (mesh.to_arrays(), kept.to_arrays());
            // (whole meshes: compared without printing them)
            assert!(ma.connectivity == mb.connectivity, "round {round}: cells");
            assert!(ma.labels == mb.labels, "round {round}: labels");
            assert!(ma.points == mb.points, "round {round}: positions");
            assert_eq!(a.improve, b.improve, "round {round}");
        }
        assert_eq!(components, 2);
        assert_eq!(mesh.components(1), 1, "the regions merged");
    }

    #[test]
    fn kept_workspace_deforms_like_fresh_ones_2d() {
        let l = 4.0;
        let centres = [Vector2::new(22.0, 30.0), Vector2::new(50.0, 30.0)];
        let mut mesh = Complex::<D2>::rectangle(72.0, 60.0, l).unwrap();
        mesh.label_by(|p| u32::from(centres.iter().any(|&c| (p - c).norm() < 9.0)));
        kept_workspace_deforms_like_fresh_ones(mesh, centres, l, 12);
    }

    #[test]
    fn kept_workspace_deforms_like_fresh_ones_3d() {
        let l = 4.0;
        let centres = [
            Vector3::new(8.0, 10.0, 10.0),
            Vector3::new(20.0, 10.0, 10.0),
        ];
        let mut mesh = Complex::<D3>::cuboid([28.0, 20.0, 20.0], l).unwrap();
        mesh.label_by(|p| u32::from(centres.iter().any(|&c| (p - c).norm() < 4.5)));
        kept_workspace_deforms_like_fresh_ones(mesh, centres, l, 4);
    }
}
