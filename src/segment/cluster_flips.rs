//! Cluster flips: connected groups of cells that all fit another phase
//! better are relabelled together when that lowers the energy.
//!
//! The guarded cell flips of [`flips`](super::flips) decide one cell at a
//! time. Where the mesh is refined (adaptive resolution) a thin line or a
//! small blob covers many small cells, each of which holds a few pixels: a
//! flip of one of them alone adds more interface length than its pixels gain
//! in the data term, so none flips and the structure stays unlabelled
//! although labelling all of it would lower the energy. Here every maximal
//! connected set of cells with the same label whose means are all nearest
//! the same other phase (a *cluster*) is considered as a whole: it is
//! relabelled if `Σ(I − m)² + ν·length` falls, counting only the cluster's
//! border (facets between its cells do not change). Clusters are decided one
//! after the other on the labels as they are then (an ICM sweep over
//! clusters, which cannot raise the energy).
//!
//! A cluster that borders a third phase (neither its own nor the one it
//! fits) is left alone: between two phases a cluster nearest a third is
//! the band of intermediate values a blurred edge leaves, which the
//! component flips remove, and flipping it would undo them every other
//! iteration. A cluster inside its phase is structure no interface has
//! reached yet; one that borders the phase it fits is a gap in it (two ends
//! of a thin line that almost meet), where relabelling it removes the
//! border it shares with that phase (2D; in 3D only clusters inside their
//! phase are considered).
//!
//! The border of a cluster of small cells is a staircase, up to twice as
//! long as the interface it becomes once the forces have relaxed it; in 2D
//! its length change is counted at the relaxed length
//! ([`relaxed_length`](super::relaxed_length)), or a line of small cells
//! would never pay for its border.

use super::integrate::{CellStats, PhaseStats};
use super::raster::Raster;
use super::relaxed_length::BorderRelaxation;
use crate::complex::{CellId, Complex, Label, VertexId};

/// Scratch space of the cluster flips, kept between iterations.
#[derive(Clone, Debug, Default)]
pub struct ClusterFlipper {
    /// Per cell: the phase whose mean is nearest the cell's (`None`: its own,
    /// or no pixels).
    nearer: Vec<Option<Label>>,
    /// Per cell: whether it has been put in a cluster this sweep.
    visited: Vec<bool>,
    stack: Vec<CellId>,
    members: Vec<CellId>,
    changes: Vec<(CellId, Label)>,
    /// The current cluster's border facets (2D: edges), as vertex pairs.
    border: Vec<[VertexId; 2]>,
    relax: BorderRelaxation,
}

/// A cluster's total statistics and its energy change if relabelled.
struct Cluster {
    own: Label,
    target: Label,
    stats: CellStats,
    /// Interface length (area in 3D) the relabelling adds (negative: removes).
    added_length: f64,
    /// Whether it borders a cell of a third phase (neither its own nor the
    /// target).
    borders_third_phase: bool,
    /// Whether it borders a cell of the phase it fits.
    borders_target: bool,
}

impl ClusterFlipper {
    /// Empty scratch space.
    pub fn new() -> Self {
        Self::default()
    }

    /// Relabels every cluster whose relabelling lowers `data + nu·length`;
    /// returns how many cells changed label.
    pub fn flip<K: Raster>(
        &mut self,
        complex: &mut Complex<K>,
        cells: &[CellStats],
        phases: &PhaseStats,
        nu: f64,
    ) -> usize {
        if !self.find_nearer(complex, cells, phases) {
            return 0;
        }
        let mut next = 0;
        let mut flipped = 0;
        while let Some(target) = self.next_flip(complex, cells, phases, nu, &mut next) {
            self.changes.clear();
            self.changes
                .extend(self.members.iter().map(|&c| (c, target)));
            complex.set_labels(&self.changes);
            flipped += self.members.len();
        }
        flipped
    }

    /// Whether [`flip`](Self::flip) would relabel a cell; changes no label
    /// (the sweep up to its first flip, before which every cluster sees the
    /// labels as they are now).
    pub fn would_flip<K: Raster>(
        &mut self,
        complex: &Complex<K>,
        cells: &[CellStats],
        phases: &PhaseStats,
        nu: f64,
    ) -> bool {
        self.find_nearer(complex, cells, phases)
            && self.next_flip(complex, cells, phases, nu, &mut 0).is_some()
    }

    /// The next cluster, from cell id `next` on, whose relabelling lowers the
    /// energy: its cells in `members` and the label they take.
    fn next_flip<K: Raster>(
        &mut self,
        complex: &Complex<K>,
        cells: &[CellStats],
        phases: &PhaseStats,
        nu: f64,
        next: &mut u32,
    ) -> Option<Label> {
        while (*next as usize) < complex.cell_capacity() {
            let start = CellId::new(*next);
            *next += 1;
            if self.visited[start.index()] || self.nearer[start.index()].is_none() {
                continue;
            }
            let cluster = self.grow(complex, cells, start);
            // Gaps are joined in 2D, where the adaptive sizing refines the
            // pinches that leave them; 3D keeps to clusters inside a phase.
            if cluster.borders_third_phase || (cluster.borders_target && K::N != 2) {
                continue;
            }
            let (Some(m_own), Some(m_target)) =
                (phases.mean_of(cluster.own), phases.mean_of(cluster.target))
            else {
                continue;
            };
            let relaxed = self
                .relax
                .fraction(complex, &self.border, cluster.stats.count as f64);
            let de = cluster.stats.sse(m_target) - cluster.stats.sse(m_own)
                + nu * relaxed * cluster.added_length;
            if de < 0.0 {
                return Some(cluster.target);
            }
        }
        None
    }

    /// Fills `nearer`; `false` if fewer than two phase means are known.
    fn find_nearer<K: Raster>(
        &mut self,
        complex: &Complex<K>,
        cells: &[CellStats],
        phases: &PhaseStats,
    ) -> bool {
        let means: Vec<(f64, Label)> = phases
            .mean
            .iter()
            .enumerate()
            .filter_map(|(k, m)| m.map(|m| (m, k as Label)))
            .collect();
        if means.len() < 2 {
            return false;
        }
        let cap = complex.cell_capacity();
        self.visited.clear();
        self.visited.resize(cap, false);
        self.nearer.clear();
        self.nearer.resize(cap, None);
        for c in complex.cell_ids() {
            let Some(mean) = cells[c.index()].mean() else {
                continue;
            };
            let nearest = means
                .iter()
                .min_by(|a, b| (a.0 - mean).abs().total_cmp(&(b.0 - mean).abs()))
                .map(|&(_, l)| l);
            if nearest != Some(complex.label(c)) {
                self.nearer[c.index()] = nearest;
            }
        }
        true
    }

    /// The maximal cluster containing `start` (its cells in `members`).
    fn grow<K: Raster>(
        &mut self,
        complex: &Complex<K>,
        cells: &[CellStats],
        start: CellId,
    ) -> Cluster {
        let own = complex.label(start);
        let target = self.nearer[start.index()].expect("a candidate cell");
        let mut cluster = Cluster {
            own,
            target,
            stats: CellStats::default(),
            added_length: 0.0,
            borders_third_phase: false,
            borders_target: false,
        };
        self.members.clear();
        self.border.clear();
        self.stack.clear();
        self.visited[start.index()] = true;
        self.stack.push(start);
        while let Some(c) = self.stack.pop() {
            self.members.push(c);
            let st = cells[c.index()];
            cluster.stats.sum += st.sum;
            cluster.stats.sum_sq += st.sum_sq;
            cluster.stats.count += st.count;
            let pts = complex.cell_points(c);
            for (f, nb) in complex.neighbours(c).iter().enumerate() {
                let inside = nb.is_some_and(|nb| {
                    complex.label(nb) == own && self.nearer[nb.index()] == Some(target)
                });
                if !inside && K::N == 2 {
                    let v = complex.cell(c);
                    self.border.push([v[(f + 1) % 3], v[(f + 2) % 3]]);
                }
                let Some(nb) = *nb else { continue };
                let l = complex.label(nb);
                if inside {
                    if !self.visited[nb.index()] {
                        self.visited[nb.index()] = true;
                        self.stack.push(nb);
                    }
                } else if l == own {
                    cluster.added_length += K::facet_measure(&pts[..K::NV], f);
                } else if l == target {
                    cluster.borders_target = true;
                    cluster.added_length -= K::facet_measure(&pts[..K::NV], f);
                } else {
                    cluster.borders_third_phase = true;
                }
            }
        }
        cluster
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::D2;
    use crate::segment::flips::Flipper;
    use crate::segment::image::ImageView;
    use crate::segment::integrate::integrate_cells;
    use nalgebra::Vector2;

    /// A bright line 4 px wide on a fine mesh, labelled as the dark
    /// background: no single cell flips (each would add more length than its
    /// pixels gain), the line as one cluster does, and nothing else does.
    #[test]
    fn a_thin_line_of_small_cells_flips_as_one_cluster() {
        let (w, h) = (64usize, 64usize);
        let centre = Vector2::new(20.0, 32.0);
        let in_disk = |p: Vector2<f64>| (p - centre).norm() < 10.0;
        let in_line = |p: Vector2<f64>| (p.y - 32.0).abs() < 2.0 && p.x > 36.0 && p.x < 60.0;
        let pixels: Vec<f32> = (0..w * h)
            .map(|i| {
                let p = Vector2::new((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
                if in_disk(p) || in_line(p) {
                    0.8
                } else {
                    0.2
                }
            })
            .collect();
        let image = ImageView::new_2d(w, h, &pixels).unwrap();
        let mut mesh = Complex::<D2>::rectangle(w as f64, h as f64, 1.5).unwrap();
        mesh.label_by(|p| u32::from(in_disk(p)));
        let mut cells = Vec::new();
        integrate_cells(&mesh, &image, &mut cells);
        let mut phases = PhaseStats::new(2);
        phases.update(&mesh, &cells);
        let nu = 0.3;
        // The guarded cell flips settle the disk's border but leave the line.
        let mut flipper = Flipper::new();
        while flipper.flip(&mut mesh, &image, &cells, &phases, nu, true, false) > 0 {}
        let line_cells = |mesh: &Complex<D2>, label: Label| {
            mesh.cell_ids()
                .filter(|&c| {
                    let pts = mesh.cell_points(c);
                    let centroid = (pts[0] + pts[1] + pts[2]) / 3.0;
                    (centroid.y - 32.0).abs() < 1.0 && centroid.x > 38.0 && centroid.x < 58.0
                })
                .all(|c| mesh.label(c) == label)
        };
        assert!(
            line_cells(&mesh, 0),
            "the premise: no cell flip labels the line"
        );
        let mut clusters = ClusterFlipper::new();
        assert!(clusters.would_flip(&mesh, &cells, &phases, nu));
        let flipped = clusters.flip(&mut mesh, &cells, &phases, nu);
        assert!(flipped > 20, "{flipped} cells flipped");
        assert!(line_cells(&mesh, 1), "the line is labelled");
        for c in mesh.cell_ids() {
            let pts = mesh.cell_points(c);
            let centroid = (pts[0] + pts[1] + pts[2]) / 3.0;
            let far = (centroid - centre).norm() > 12.0
                && ((centroid.y - 32.0).abs() > 4.0 || centroid.x < 34.0 || centroid.x > 62.0);
            if far {
                assert_eq!(mesh.label(c), 0, "cell at {centroid:?}");
            }
        }
    }
}
