//! Per-phase measures and connected components.

use super::{CellId, Complex, Label, VertexId};
use crate::dim::{Dim, Point};

/// Layer `complex`: measures (phase areas or volumes, qualities, edge lengths).
impl<K: Dim> Complex<K> {
    /// Total area (2D) or volume (3D) of each phase, indexed by label.
    pub fn phase_measures(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.label_count()];
        for c in self.cell_ids() {
            out[self.label(c) as usize] += self.measure(c);
        }
        out
    }

    /// Measure of the whole domain box.
    pub fn domain_measure(&self) -> f64 {
        (0..K::N)
            .map(|a| self.domain_max[a] - self.domain_min[a])
            .product()
    }

    /// Number of connected components (through shared facets) of the cells labelled `label`.
    pub fn components(&self, label: Label) -> usize {
        let mut seen = vec![false; self.cells.len()];
        let mut stack: Vec<CellId> = Vec::new();
        let mut count = 0;
        for c in self.cell_ids() {
            if seen[c.index()] || self.label(c) != label {
                continue;
            }
            count += 1;
            seen[c.index()] = true;
            stack.push(c);
            while let Some(x) = stack.pop() {
                for nb in self.neighbours(x).iter().flatten() {
                    if !seen[nb.index()] && self.label(*nb) == label {
                        seen[nb.index()] = true;
                        stack.push(*nb);
                    }
                }
            }
        }
        count
    }

    /// Number of live cells with the given label.
    pub fn cells_with_label(&self, label: Label) -> usize {
        self.cell_ids().filter(|&c| self.label(c) == label).count()
    }

    /// Smallest, median and largest edge length (each edge once); zeros
    /// for a complex without cells.
    pub fn edge_length_summary(&self) -> [f64; 3] {
        let mut edges: Vec<(VertexId, VertexId)> = Vec::with_capacity(3 * self.cell_count());
        for c in self.cell_ids() {
            let cell = self.cell(c);
            for i in 0..K::NV {
                for j in i + 1..K::NV {
                    let (u, v) = (cell[i], cell[j]);
                    edges.push(if u < v { (u, v) } else { (v, u) });
                }
            }
        }
        edges.sort_unstable();
        edges.dedup();
        let mut lengths: Vec<f64> = edges
            .iter()
            .map(|&(u, v)| (self.position(u) - self.position(v)).length())
            .collect();
        if lengths.is_empty() {
            return [0.0; 3];
        }
        let mid = lengths.len() / 2;
        let median = *lengths.select_nth_unstable_by(mid, f64::total_cmp).1;
        let (lo, hi) = lengths
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &l| (a.min(l), b.max(l)));
        [lo, median, hi]
    }
}
