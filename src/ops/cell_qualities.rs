//! Tet qualities remembered while no corner moves, so that the search for
//! poor tets does not compute again those of a band that did not change.
//!
//! Every improvement of the band lists the tets below the flip threshold
//! (twice per improvement, again after each sweep that flipped, in every
//! round of a deform and in every iteration), and computes the quality of
//! each tet of the band to do so, though most of the band's tets are as
//! they were. A cell never changes its corners (an operation replaces
//! cells, and new cells get new ids), and its quality depends on their
//! positions alone; every vertex move advances the complex's move clock
//! and stamps the vertex ([`Complex::moved_at`]). So a quality computed at
//! clock `t` stands while no corner has moved since: exact, the same bits.

use super::CellStamps;
use crate::complex::{CellId, Complex};
use crate::dim::Dim;

/// Per cell: its quality and the move clock when it was computed. Follows
/// the compactions, so it holds across deforms.
#[derive(Clone, Debug, Default)]
pub(crate) struct CellQualities {
    qualities: CellStamps<f64>,
}

impl CellQualities {
    /// Forgets everything unless it is about `complex` as it is numbered
    /// now (another complex, or a compaction not followed).
    pub(crate) fn sync<K: Dim>(&mut self, complex: &Complex<K>) {
        self.qualities.sync(complex);
    }

    /// The quality of `c` if it was recorded and no corner has moved
    /// since.
    #[inline]
    pub(crate) fn current<K: Dim>(&self, complex: &Complex<K>, c: CellId) -> Option<f64> {
        let (clock, quality) = self.qualities.get_value(c)?;
        complex
            .cell(c)
            .iter()
            .all(|&w| complex.moved_at(w) <= clock)
            .then_some(quality)
    }

    /// Records `quality`, computed now, for `c`.
    pub(crate) fn record<K: Dim>(&mut self, complex: &Complex<K>, c: CellId, quality: f64) {
        self.qualities.record_value(complex, c, quality);
    }

    /// Carries the record through the compaction `complex` just made.
    pub(crate) fn follow_compaction<K: Dim>(&mut self, complex: &Complex<K>) {
        self.qualities.follow_compaction(complex);
    }
}

/// How the search for poor tets judged one tet.
#[derive(Clone, Copy, Debug)]
pub(crate) enum JudgedTet {
    /// Its flips were all refused, nothing around having changed since.
    Refused(CellId),
    /// Its quality, recorded before and still current.
    Known(CellId, f64),
    /// Its quality, computed now.
    Computed(CellId, f64),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::complex::VertexId;
    use crate::dim::D3;
    use nalgebra::Vector3;

    /// A recorded quality stands, bit for bit, until a corner moves, and
    /// follows the compactions; a moved corner or another complex voids it.
    #[test]
    fn qualities_stand_until_a_corner_moves() {
        let l = 4.0;
        let mut mesh = Complex::<D3>::cuboid([20.0, 16.0, 16.0], l).unwrap();
        let mut record = CellQualities::default();
        record.sync(&mesh);
        for c in mesh.cell_ids().collect::<Vec<_>>() {
            record.record(&mesh, c, mesh.quality(c));
        }
        let mut star = Vec::new();
        for round in 0..6 {
            let start = mesh.move_clock();
            let ids: Vec<VertexId> = mesh.vertex_ids().collect();
            for (k, &v) in ids.iter().enumerate() {
                if (k + round) % 9 == 0 {
                    let p = mesh.position(v);
                    let d = Vector3::new((k as f64).sin(), (k as f64).cos(), 0.5);
                    mesh.move_towards(v, mesh.constrain(v, p + d * (0.3 * l)), 1e-4 * l, &mut star);
                }
            }
            let (mut current, mut voided) = (0, 0);
            for c in mesh.cell_ids().collect::<Vec<_>>() {
                let corner_moved = mesh.cell(c).iter().any(|&w| mesh.moved_at(w) > start);
                match record.current(&mesh, c) {
                    Some(q) => {
                        assert!(!corner_moved, "round {round}: a moved tet's quality stands");
                        assert_eq!(q.to_bits(), mesh.quality(c).to_bits(), "round {round}");
                        current += 1;
                    }
                    None => {
                        assert!(
                            corner_moved,
                            "round {round}: an unmoved tet's quality voided"
                        );
                        record.record(&mesh, c, mesh.quality(c));
                        voided += 1;
                    }
                }
            }
            assert!(
                current > 0 && voided > 0,
                "round {round}: {current} current, {voided} voided"
            );
            if round % 2 == 1 {
                mesh.compact_in_place();
                record.follow_compaction(&mesh);
            }
        }
        // Another complex (a clone) is not read against this record.
        let other = mesh.clone();
        record.sync(&other);
        assert!(other
            .cell_ids()
            .all(|c| record.current(&other, c).is_none()));
    }
}
