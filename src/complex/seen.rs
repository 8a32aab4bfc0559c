//! The cells a 3D star search has already collected: a small open-addressing
//! hash set on the stack, so that the membership test of every facet of every
//! star cell is a probe or two instead of a scan of the list.

use crate::ids::CellId;

/// Slots of the table (a power of two).
const SLOTS: usize = 128;
/// The table takes the first this many cells (a load of at most one half);
/// a larger star (rare: 3D stars hold 20–30 tets) is answered by scanning
/// the list.
const CAPACITY: usize = SLOTS / 2;
/// An empty slot: no cell has this index (ids are below `u32::MAX`).
const EMPTY: u32 = u32::MAX;

/// The membership set of one star search.
pub(super) struct SeenCells {
    slots: [u32; SLOTS],
}

impl SeenCells {
    pub(super) fn new() -> Self {
        SeenCells {
            slots: [EMPTY; SLOTS],
        }
    }

    /// Records `c` unless it was recorded before; returns whether it is
    /// new. `list` holds every cell recorded so far, in order (the search's
    /// output): the table holds its first [`CAPACITY`] cells, and from then
    /// on the list is scanned. One probe sequence both tests and records.
    #[inline]
    pub(super) fn insert(&mut self, c: CellId, list: &[CellId]) -> bool {
        if list.len() >= CAPACITY {
            return !list.contains(&c);
        }
        let mut slot = home(c);
        loop {
            match self.slots[slot] {
                EMPTY => {
                    self.slots[slot] = c.raw();
                    return true;
                }
                s if s == c.raw() => return false,
                _ => slot = (slot + 1) % SLOTS,
            }
        }
    }
}

/// The first slot probed for `c` (Fibonacci hashing of the index).
#[inline]
fn home(c: CellId) -> usize {
    (c.raw().wrapping_mul(0x9E37_79B9) >> (32 - SLOTS.trailing_zeros())) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn answers_as_the_list_does_below_and_above_capacity() {
        let mut seen = SeenCells::new();
        let mut list = Vec::new();
        for i in 0..3 * CAPACITY as u32 {
            let c = CellId::new(i * 7919 % 100_003);
            assert!(seen.insert(c, &list));
            list.push(c);
            assert!(list.iter().all(|&d| !seen.insert(d, &list)));
        }
    }
}
