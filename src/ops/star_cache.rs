//! Stars of 3D vertices kept while no cell around them is created or
//! removed.
//!
//! An improvement searches the star of a vertex several times: smoothing
//! before and after the flips, the search for degenerate cells between
//! them, and all of these again in the next round of the same deform, where
//! the forces moved vertices but replaced no cell. A star search finds the
//! same cells in the same order while [`Complex::cells_changed_at`] of its
//! vertex stands, so the cells it found are kept (in one arena, per vertex
//! its range) and copied out again instead of searched.

use crate::complex::{CellId, Complex, VertexId};
use crate::dim::Dim;

/// Where a vertex's star lies in the arena, and the move clock when it was
/// searched.
#[derive(Clone, Copy, Debug)]
struct Kept {
    start: u32,
    end: u32,
    at: u64,
}

/// The stars kept, about one complex as its cells are numbered (forgotten
/// at every compaction).
#[derive(Clone, Debug, Default)]
pub(crate) struct StarCache {
    kept: Vec<Option<Kept>>,
    cells: Vec<CellId>,
    about: Option<(u64, u64)>,
}

/// The arena is emptied once it holds this many cells per vertex of the
/// complex (stale stars pile up between compactions).
const CELLS_PER_VERTEX: usize = 64;

impl StarCache {
    /// Forgets every star unless they are about `complex` as it is
    /// numbered now (another complex, or a compaction since).
    pub(crate) fn sync<K: Dim>(&mut self, complex: &Complex<K>) {
        let about = Some((complex.identity(), complex.compactions()));
        if self.about != about || self.cells.len() > CELLS_PER_VERTEX * complex.vertex_capacity() {
            self.kept.clear();
            self.cells.clear();
            self.about = about;
        }
    }

    /// The star of `v` into `out`, as [`Complex::star_into`] gives it: the
    /// kept cells while they stand, else searched (and kept). In 2D, where
    /// the star is a fan walked without a search, always walked.
    pub(crate) fn star_into<K: Dim>(
        &mut self,
        complex: &Complex<K>,
        v: VertexId,
        out: &mut Vec<CellId>,
    ) {
        if K::STAR_IS_FAN {
            complex.star_into(v, out);
            return;
        }
        if let Some(star) = self.current(complex, v) {
            out.clear();
            out.extend_from_slice(star);
            return;
        }
        complex.star_into(v, out);
        self.keep(complex, v, out);
    }

    /// The kept star of `v`, if there is one and it stands.
    #[inline]
    pub(crate) fn current<K: Dim>(&self, complex: &Complex<K>, v: VertexId) -> Option<&[CellId]> {
        let kept = self.kept.get(v.index()).copied().flatten()?;
        let star = (complex.cells_changed_at(v) <= kept.at)
            .then(|| &self.cells[kept.start as usize..kept.end as usize]);
        debug_assert!(
            star.is_none_or(|star| star == fresh_star(complex, v)),
            "the kept star of {v:?} stands but differs from its search: an operation \
             created or removed cells around it without marking its star changed"
        );
        star
    }

    /// Keeps `star`, the star of `v` searched now.
    pub(crate) fn keep<K: Dim>(&mut self, complex: &Complex<K>, v: VertexId, star: &[CellId]) {
        let start = self.cells.len() as u32;
        self.cells.extend_from_slice(star);
        if v.index() >= self.kept.len() {
            self.kept.resize(v.index() + 1, None);
        }
        self.kept[v.index()] = Some(Kept {
            start,
            end: self.cells.len() as u32,
            at: complex.move_clock(),
        });
    }
}

/// The star of `v` searched now: what a kept star must equal while it stands
/// (compared in debug builds only).
fn fresh_star<K: Dim>(complex: &Complex<K>, v: VertexId) -> Vec<CellId> {
    let mut star = Vec::new();
    complex.star_into(v, &mut star);
    star
}
