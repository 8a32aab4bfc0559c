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
        let mut seen = vec![false; self.cell_capacity()];
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
    ///
    /// Linear in the cells (the segmentation reports it every adaptive
    /// iteration): each edge is listed at its lower-numbered end, and a
    /// vertex's list is deduplicated by stamping the other ends, without
    /// sorting the edges; the median is a selection.
    pub fn edge_length_summary(&self) -> [f64; 3] {
        let higher = self.edges_by_lower_end();
        let mut stamp = vec![u32::MAX; self.vertex_capacity()];
        let mut lengths = Vec::with_capacity(higher.ends.len() / 2);
        for u in 0..self.vertex_capacity() {
            let ends = &higher.ends[higher.start[u] as usize..higher.start[u + 1] as usize];
            for &v in ends {
                if stamp[v as usize] != u as u32 {
                    stamp[v as usize] = u as u32;
                    let (pu, pv) = (
                        self.position(VertexId(u as u32)),
                        self.position(VertexId(v)),
                    );
                    lengths.push((pu - pv).length());
                }
            }
        }
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

    /// Every cell's edges, listed at their lower-numbered end (an edge once
    /// per cell holding it), in compressed rows.
    fn edges_by_lower_end(&self) -> EdgeLists {
        let n = self.vertex_capacity();
        let mut start = vec![0u32; n + 1];
        let each_edge = |visit: &mut dyn FnMut(usize, u32)| {
            for c in self.cell_ids() {
                let cell = self.cell(c);
                for i in 0..K::NV {
                    for j in i + 1..K::NV {
                        let (u, v) = (cell[i].0.min(cell[j].0), cell[i].0.max(cell[j].0));
                        visit(u as usize, v);
                    }
                }
            }
        };
        each_edge(&mut |u, _| start[u + 1] += 1);
        for u in 0..n {
            start[u + 1] += start[u];
        }
        let mut next = start.clone();
        let mut ends = vec![0u32; start[n] as usize];
        each_edge(&mut |u, v| {
            ends[next[u] as usize] = v;
            next[u] += 1;
        });
        EdgeLists { start, ends }
    }
}

/// Per vertex `u`, the other ends `ends[start[u]..start[u + 1]]` of the
/// edges whose lower-numbered end is `u` (with repeats).
struct EdgeLists {
    start: Vec<u32>,
    ends: Vec<u32>,
}

#[cfg(test)]
mod tests {
    use crate::complex::Complex;
    use crate::dim::{Dim, Point, D2, D3};

    /// The summary by sorting every cell's edges, as a reference.
    fn sorted_summary<K: Dim>(c: &Complex<K>) -> [f64; 3] {
        let mut edges = Vec::new();
        for id in c.cell_ids() {
            let cell = c.cell(id);
            for i in 0..K::NV {
                for j in i + 1..K::NV {
                    edges.push((cell[i].min(cell[j]), cell[i].max(cell[j])));
                }
            }
        }
        edges.sort_unstable();
        edges.dedup();
        let mut lengths: Vec<f64> = edges
            .iter()
            .map(|&(u, v)| (c.position(u) - c.position(v)).length())
            .collect();
        lengths.sort_unstable_by(f64::total_cmp);
        [
            lengths[0],
            lengths[lengths.len() / 2],
            lengths[lengths.len() - 1],
        ]
    }

    /// Graded meshes (cells of several sizes, ids out of spatial order
    /// after the deformations) in both dimensions: the same smallest,
    /// median and largest edge as sorting the edges.
    #[test]
    fn edge_length_summary_counts_each_edge_once() {
        use crate::dsc::{Destinations, DscParams};
        use nalgebra::{Vector2, Vector3};
        let mut flat = Complex::<D2>::rectangle(40.0, 30.0, 3.0).unwrap();
        let mut solid = Complex::<D3>::cuboid([12.0, 10.0, 9.0], 2.0).unwrap();
        for round in 0..3 {
            let mut dest = Destinations::new(&flat);
            for v in flat.vertex_ids().collect::<Vec<_>>() {
                let p = flat.position(v);
                let q = p + (p - Vector2::new(20.0, 15.0)) * 0.1;
                dest.set(v, flat.constrain(v, q));
            }
            flat.deform(&dest, &DscParams::new::<D2>(3.0));
            let mut dest = Destinations::new(&solid);
            for v in solid.vertex_ids().collect::<Vec<_>>() {
                let p = solid.position(v);
                let q = p + (p - Vector3::new(6.0, 5.0, 4.5)) * (0.05 * round as f64);
                dest.set(v, solid.constrain(v, q));
            }
            solid.deform(&dest, &DscParams::new::<D3>(2.0));
            assert_eq!(flat.edge_length_summary(), sorted_summary(&flat));
            assert_eq!(solid.edge_length_summary(), sorted_summary(&solid));
        }
        let [lo, _, hi] = solid.edge_length_summary();
        assert!(lo < hi);
    }
}
