//! The cells a 3D star search has already collected: a small open-addressing
//! hash set on the stack, so that the membership test of every facet of every
//! star cell is a probe or two instead of a scan of the list.

use crate::ids::CellId;

/// Slots of the table (a power of two).
const SLOTS: usize = 128;
/// The table takes at most this many cells (a load of one half); a larger
/// star (rare: 3D stars hold 20–30 tets) is answered by scanning the list.
const CAPACITY: usize = SLOTS / 2;
/// An empty slot: no cell has this index (ids are below `u32::MAX`).
const EMPTY: u32 = u32::MAX;

/// The membership set of one star search.
pub(super) struct SeenCells {
    slots: [u32; SLOTS],
    len: usize,
}

impl SeenCells {
    pub(super) fn new() -> Self {
        SeenCells {
            slots: [EMPTY; SLOTS],
            len: 0,
        }
    }

    /// Whether `c` was inserted; `list` holds every cell inserted so far, in
    /// case the table overflowed.
    #[inline]
    pub(super) fn contains(&self, c: CellId, list: &[CellId]) -> bool {
        if self.len >= CAPACITY {
            return list.contains(&c);
        }
        let mut slot = home(c);
        loop {
            match self.slots[slot] {
                EMPTY => return false,
                s if s == c.raw() => return true,
                _ => slot = (slot + 1) % SLOTS,
            }
        }
    }

    /// Records `c` (not yet inserted); ignored once the table is full, after
    /// which [`contains`](Self::contains) scans the list.
    #[inline]
    pub(super) fn insert(&mut self, c: CellId) {
        if self.len >= CAPACITY {
            return;
        }
        self.len += 1;
        if self.len == CAPACITY {
            return;
        }
        let mut slot = home(c);
        while self.slots[slot] != EMPTY {
            slot = (slot + 1) % SLOTS;
        }
        self.slots[slot] = c.raw();
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
            assert!(!seen.contains(c, &list));
            seen.insert(c);
            list.push(c);
            assert!(seen.contains(c, &list));
            assert!(list.iter().all(|&d| seen.contains(d, &list)));
            assert!(!seen.contains(CellId::new(200_000 + i), &list));
        }
    }
}
