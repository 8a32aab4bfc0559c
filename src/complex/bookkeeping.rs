//! What a [`Complex`](super::Complex) records besides the mesh: the clocks
//! and counters by which caches of other layers (the improvement memo, the
//! cell statistics cache) know what changed, the maps of the last
//! compaction, and spare lists that operations borrow instead of allocating.

use super::{CellId, VertexId};

/// The complex's clocks, counters, compaction maps and spare lists; private
/// to the complex, read through its methods.
#[derive(Clone, Debug, Default)]
pub(super) struct Bookkeeping {
    /// How many times [`Complex::compact`](super::Complex::compact) renumbered the complex.
    pub(super) compactions: u64,
    /// The old-to-new cell map of the last compaction.
    pub(super) last_cell_map: Vec<Option<CellId>>,
    /// The old-to-new vertex map of the last compaction.
    pub(super) last_vertex_map: Vec<Option<VertexId>>,
    /// Per vertex: the value of `move_clock` when it was created or last moved.
    pub(super) moved_at: Vec<u64>,
    /// Per vertex: the value of `move_clock` when its star last changed (a
    /// corner of it moved, a cell of it was created or removed).
    pub(super) star_changed_at: Vec<u64>,
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
            moved_at: vec![0; vertices],
            star_changed_at: vec![0; vertices],
            ..Self::default()
        }
    }
}
