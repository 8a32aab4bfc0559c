//! What a [`Complex`](super::Complex) records besides the mesh: the clocks
//! and counters by which caches of other layers (the improvement memo, the
//! cell statistics cache) know what changed, the maps of the last
//! compaction, and spare lists that operations borrow instead of allocating.

use super::{CellId, VertexId};
use std::sync::atomic::{AtomicU64, Ordering};

/// The complex's clocks, counters, compaction maps and spare lists; private
/// to the complex, read through its methods.
#[derive(Debug, Default)]
pub(super) struct Bookkeeping {
    /// Distinct for every complex built or cloned in the process, so that a
    /// record kept across calls (stamped with this complex's clocks) is
    /// never read against another complex whose clocks happen to agree.
    pub(super) identity: u64,
    /// How many times [`Complex::compact`](super::Complex::compact) renumbered the complex.
    pub(super) compactions: u64,
    /// The old-to-new cell map of the last compaction.
    pub(super) last_cell_map: Vec<Option<CellId>>,
    /// The old-to-new vertex map of the last compaction.
    pub(super) last_vertex_map: Vec<Option<VertexId>>,
    /// Whether the last compaction also renumbered spatially (its maps are
    /// then a permutation, not order-keeping).
    pub(super) last_compaction_reordered: bool,
    /// How many of the first cells lie in the order of the last spatial
    /// renumbering (the rest were appended since).
    pub(super) ordered_cells: usize,
    /// Whether spatial renumbering is held off for now
    /// ([`Complex::hold_spatial_renumbering`](super::Complex::hold_spatial_renumbering)).
    pub(super) renumbering_held: bool,
    /// Per vertex: the value of `move_clock` when it was created or last moved.
    pub(super) moved_at: Vec<u64>,
    /// Per vertex: the value of `move_clock` when its star last changed (a
    /// corner of it moved, a cell of it was created or removed).
    pub(super) star_changed_at: Vec<u64>,
    /// Per vertex: the value of `move_clock` when a cell of its star was
    /// last created or removed (moves leave it: a star search from the
    /// vertex finds the same cells in the same order while it stands).
    pub(super) cells_changed_at: Vec<u64>,
    /// Counts vertex moves and creations and cell replacements.
    pub(super) move_clock: u64,
    /// Cleared lists that operations borrow
    /// ([`Complex::take_list`](super::Complex::take_list)), so that a move,
    /// collapse or split allocates nothing once they have grown.
    pub(super) spare_lists: Vec<Vec<CellId>>,
    /// Counts the calls that changed labels.
    pub(super) relabels: u64,
}

impl Bookkeeping {
    /// The records of a fresh complex with `vertices` vertices: every clock
    /// at zero, no compaction yet.
    pub(super) fn new(vertices: usize) -> Self {
        Self {
            identity: fresh_identity(),
            moved_at: vec![0; vertices],
            star_changed_at: vec![0; vertices],
            cells_changed_at: vec![0; vertices],
            ..Self::default()
        }
    }
}

impl Bookkeeping {
    /// Makes the complex another one from now on, for a change that moves
    /// every vertex without stamping the clocks: no record kept against the
    /// old identity is read against the new geometry.
    pub(super) fn renew_identity(&mut self) {
        self.identity = fresh_identity();
    }
}

/// A clone is another complex from then on: its own identity, the same
/// records.
impl Clone for Bookkeeping {
    fn clone(&self) -> Self {
        Self {
            identity: fresh_identity(),
            compactions: self.compactions,
            last_cell_map: self.last_cell_map.clone(),
            last_vertex_map: self.last_vertex_map.clone(),
            last_compaction_reordered: self.last_compaction_reordered,
            ordered_cells: self.ordered_cells,
            renumbering_held: self.renumbering_held,
            moved_at: self.moved_at.clone(),
            star_changed_at: self.star_changed_at.clone(),
            cells_changed_at: self.cells_changed_at.clone(),
            move_clock: self.move_clock,
            spare_lists: self.spare_lists.clone(),
            relabels: self.relabels,
        }
    }
}

/// A number no complex of this process had before.
fn fresh_identity() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}
