//! Per-cell verdicts kept across deforms: the move clock at which each was
//! given (and, for some records, a value computed then), about one complex
//! as its cells are numbered, carried through every compaction so that they
//! outlive the deform that gave them.

use crate::complex::{CellId, Complex};
use crate::dim::Dim;

/// Per cell id, the move clock of a verdict and a value given with it (`()`
/// for a bare verdict), about one complex: its identity and compactions
/// (which number its cells). Kept across deforms by following every
/// compaction ([`follow_compaction`](Self::follow_compaction)).
#[derive(Clone, Debug)]
pub(crate) struct CellStamps<T: Copy = ()> {
    stamps: Vec<Option<(u64, T)>>,
    about: Option<(u64, u64)>,
}

impl<T: Copy> Default for CellStamps<T> {
    fn default() -> Self {
        CellStamps {
            stamps: Vec::new(),
            about: None,
        }
    }
}

impl<T: Copy> CellStamps<T> {
    /// Forgets every stamp unless they are about `complex` as it is
    /// numbered now; returns whether they were forgotten.
    pub(crate) fn sync<K: Dim>(&mut self, complex: &Complex<K>) -> bool {
        let about = Some((complex.identity(), complex.compactions()));
        if self.about == about {
            return false;
        }
        self.forget();
        self.about = about;
        true
    }

    /// Forgets every stamp (keeps the capacity).
    pub(crate) fn forget(&mut self) {
        self.stamps.clear();
    }

    /// Stamps `c` with the move clock now and `value`.
    pub(crate) fn record_value<K: Dim>(&mut self, complex: &Complex<K>, c: CellId, value: T) {
        if c.index() >= self.stamps.len() {
            self.stamps.resize(c.index() + 1, None);
        }
        self.stamps[c.index()] = Some((complex.move_clock(), value));
    }

    /// The stamp of `c` and its value, if any.
    #[inline]
    pub(crate) fn get_value(&self, c: CellId) -> Option<(u64, T)> {
        self.stamps.get(c.index()).copied().flatten()
    }

    /// The stamp of `c`, if any.
    #[inline]
    pub(crate) fn get(&self, c: CellId) -> Option<u64> {
        self.get_value(c).map(|(clock, _)| clock)
    }

    /// Carries the stamps through the compaction `complex` just made (its
    /// cell map); forgets them if they were about another complex or missed
    /// a compaction.
    pub(crate) fn follow_compaction<K: Dim>(&mut self, complex: &Complex<K>) {
        if self.about.is_none_or(|(identity, compactions)| {
            identity != complex.identity() || compactions + 1 != complex.compactions()
        }) {
            self.forget();
            self.about = None;
            return;
        }
        let map = &complex.last_cell_map()[..self.stamps.len().min(complex.last_cell_map().len())];
        if complex.last_compaction_reordered() {
            // A permutation: the stamps move into a fresh array.
            let mut moved = vec![None; complex.cell_count()];
            for (old, new) in map.iter().enumerate() {
                if let Some(new) = new {
                    moved[new.index()] = self.stamps[old];
                }
            }
            self.stamps = moved;
        } else {
            // New ids are dense and in the old ids' order, never above them:
            // forward copies are safe, and the first `live` entries are written.
            for (old, new) in map.iter().enumerate() {
                if let Some(new) = new {
                    self.stamps[new.index()] = self.stamps[old];
                }
            }
            let live = map.iter().flatten().count();
            self.stamps.truncate(live);
        }
        self.about = Some((complex.identity(), complex.compactions()));
    }
}

impl CellStamps {
    /// Stamps `c` with the move clock now.
    pub(crate) fn record<K: Dim>(&mut self, complex: &Complex<K>, c: CellId) {
        self.record_value(complex, c, ());
    }
}
