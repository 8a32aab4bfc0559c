//! Phases the evolution loses: detection, and a new start for them.
//!
//! With `N` phases asked for, the evolution can end with a phase that covers
//! no pixel, or with two phases whose means coincide (both holding a mix of
//! the same two true phases, e.g. 0.390 and 0.391 on an image with means 0.35
//! and 0.5), or, in 3D with three or more phases, with a phase that is only
//! the blur of the edge between two others ([`super::band_phase`]). Either
//! way the result has fewer than `N` distinct phases while the stopping rule
//! sees nothing wrong. [`lost_phases`] finds the first two, the driver the
//! bands; it then merges a duplicate or a band into its twin and re-seeds the lost label by
//! splitting the phase whose cells away from the interfaces have means that
//! hold the most structure beyond noise ([`split_most_structured_phase`]) at
//! the least-variance threshold of its cell means, and warns when it cannot. A band's re-seed is kept only if it lowers
//! the energy by the next flip round ([`super::reseed_trial`]).

use super::integrate::{CellStats, PhaseStats};
use super::intensity::Histogram;
use super::raster::Raster;
use super::thresholds::split_histogram;
use crate::complex::{CellId, Complex, Label};
use serde::Serialize;

/// A phase the run has lost.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LostPhase {
    /// The phase covers no pixel.
    Empty(Label),
    /// The phase's mean lies within the tolerance of its twin's (the twin
    /// has at least as many pixels).
    Duplicate {
        /// The smaller of the two phases.
        phase: Label,
        /// The phase it duplicates.
        twin: Label,
    },
    /// The phase shrank to a band along the edge between two others, its
    /// mean between theirs, thinner than a voxel, or than two while holding a
    /// fraction of the voxels its initial threshold range held ([`super::band_phase`];
    /// runs with blurred-band flips only).
    Band {
        /// The band's phase.
        phase: Label,
        /// The bordering phase whose mean is nearer the band's.
        twin: Label,
    },
    /// The phase holds fewer pixels or voxels than one regular cell at the
    /// edge length: a label the mesh cannot carry as a region (reported at
    /// the end of a run, never re-seeded).
    Vestige {
        /// The phase.
        phase: Label,
        /// Its pixels or voxels.
        count: u64,
    },
    /// The phase holds under a quarter of the pixels or voxels that look
    /// like it ([`super::absorbed`]): a class of the image went to its
    /// neighbours (reported at the end of a run, never re-seeded).
    Absorbed {
        /// The phase.
        phase: Label,
        /// Its pixels or voxels.
        count: u64,
        /// The pixels or voxels of the smoothed image in the middle half of
        /// its nearest-mean range.
        looks_like: u64,
    },
    /// Away from the blur of every edge the phase and its twin have the
    /// same intensity within the noise ([`plateau_twins`]): one region that
    /// noise or blur divides, not two. Their means can still differ by more
    /// than the noise, since each holds the pixels on its own side of the
    /// split (a flat image asked for two phases splits at its mean, into
    /// phases a third of the noise apart). Reported at the end of a run,
    /// never re-seeded.
    SharedPlateau {
        /// The smaller of the two phases.
        phase: Label,
        /// The phase whose plateau it shares.
        twin: Label,
    },
    /// The phase and its twin are specks: their means are closer than the
    /// noise and neither has enough pixels or voxels beyond the blur of its
    /// edges to measure a plateau ([`speckled_pairs`]), so nothing shows two
    /// regions rather than one that noise divides. Cells of a few voxels
    /// split a flat 3D volume so: each piece holds the side of the noise
    /// its cells' means took, to its centre. Reported at the end of a run,
    /// never re-seeded.
    Speckled {
        /// The smaller of the two phases.
        phase: Label,
        /// The other.
        twin: Label,
    },
}

impl LostPhase {
    /// The label that is lost.
    pub fn label(&self) -> Label {
        match *self {
            LostPhase::Empty(l)
            | LostPhase::Duplicate { phase: l, .. }
            | LostPhase::Band { phase: l, .. }
            | LostPhase::Vestige { phase: l, .. }
            | LostPhase::Absorbed { phase: l, .. }
            | LostPhase::SharedPlateau { phase: l, .. }
            | LostPhase::Speckled { phase: l, .. } => l,
        }
    }

    /// One line for a user, naming phases as `labels.png` numbers them:
    /// `order` maps a mesh label to its output phase (by increasing mean,
    /// the empty ones last; [`Segmentation::phase_order`](super::Segmentation::phase_order)).
    /// The mesh's own labels mean nothing to a user, and means on the
    /// loaded scale are not the file's units (`report.json` has those).
    pub fn describe(&self, order: &[u8]) -> String {
        let phase = |l: Label| order.get(l as usize).map_or(l, |&p| Label::from(p));
        match *self {
            LostPhase::Empty(l) => format!(
                "phase {} covers no pixel or voxel (the label image has no value {0})",
                phase(l)
            ),
            LostPhase::Duplicate { phase: a, twin: b } => {
                let (lo, hi) = (phase(a).min(phase(b)), phase(a).max(phase(b)));
                format!(
                    "phases {lo} and {hi} have the same mean within the noise \
                     (report.json phases gives their means)"
                )
            }
            LostPhase::Band { phase: a, twin: b } => format!(
                "phase {} ends as a band along the edges of phase {}, its mean between \
                 its two neighbours', thinner than a voxel or than two holding under a \
                 quarter of the voxels of its initial threshold range (the blur of an \
                 edge: a thin class of the image may have been lost)",
                phase(a),
                phase(b)
            ),
            LostPhase::Vestige { phase: l, count } => format!(
                "phase {} holds only {count} pixels or voxels, fewer than one cell of the \
                 mesh (a vestige, not a region)",
                phase(l)
            ),
            LostPhase::Absorbed {
                phase: l,
                count,
                looks_like,
            } => format!(
                "phase {} holds only {count} pixels or voxels against {looks_like} that \
                 look like it (in the image smoothed by one pixel, nearer its mean than a \
                 quarter of the way to its neighbours'): a class of the image went to its \
                 neighbours, thinner than the length weight's width or the cells (a lower \
                 --length-weight or --edge-length, or finer voxels, may keep it)",
                phase(l)
            ),
            LostPhase::SharedPlateau { phase: a, twin: b } => {
                let (lo, hi) = (phase(a).min(phase(b)), phase(a).max(phase(b)));
                format!(
                    "phases {lo} and {hi} have the same intensity away from their edges, \
                     within the noise: one region divided by noise or blur, not two"
                )
            }
            LostPhase::Speckled { phase: a, twin: b } => {
                let (lo, hi) = (phase(a).min(phase(b)), phase(a).max(phase(b)));
                format!(
                    "phases {lo} and {hi} are specks with means closer than the noise and \
                     too few pixels or voxels away from their edges to tell them apart: one \
                     region divided by noise, not two"
                )
            }
        }
    }
}

/// Whether [`lost_phases`] would find any, without allocating (the driver
/// asks on every flip iteration).
pub fn any_lost(phases: &PhaseStats, tolerance: f64) -> bool {
    let n = phases.count.len();
    (0..n).any(|a| {
        phases.count[a] == 0
            || (a + 1..n).any(|b| {
                phases.count[b] > 0
                    && matches!((phases.mean[a], phases.mean[b]),
                        (Some(ma), Some(mb)) if (ma - mb).abs() < tolerance)
            })
    })
}

/// The empty phases, then the duplicates: present phases whose means
/// differ by less than `tolerance` from the next one up (each phase listed
/// at most once).
pub fn lost_phases(phases: &PhaseStats, tolerance: f64) -> Vec<LostPhase> {
    let mut lost: Vec<LostPhase> = (0..phases.count.len())
        .filter(|&k| phases.count[k] == 0)
        .map(|k| LostPhase::Empty(k as Label))
        .collect();
    let mut present: Vec<(f64, usize)> = (0..phases.count.len())
        .filter(|&k| phases.count[k] > 0)
        .filter_map(|k| phases.mean[k].map(|m| (m, k)))
        .collect();
    present.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut i = 0;
    while i + 1 < present.len() {
        let ((ma, a), (mb, b)) = (present[i], present[i + 1]);
        if mb - ma < tolerance {
            let (phase, twin) = if phases.count[a] <= phases.count[b] {
                (a, b)
            } else {
                (b, a)
            };
            lost.push(LostPhase::Duplicate {
                phase: phase as Label,
                twin: twin as Label,
            });
            i += 2;
        } else {
            i += 1;
        }
    }
    lost
}

/// The pairs of phases whose `plateaus` (each phase's mean over its pixels
/// beyond the blur of every edge, `None` without such pixels;
/// [`super::partial_volume::phase_plateaus`]) differ by less than
/// `tolerance`, adjacent in plateau order, each phase in at most one pair.
///
/// The plateau is the piecewise-constant model's level of a region; the mean
/// is not, since it also holds the edges' blur and, where noise divides a
/// region, the side of the noise each phase took.
pub fn plateau_twins(plateaus: &[Option<f64>], tolerance: f64) -> Vec<(usize, usize)> {
    adjacent_pairs(plateaus, |(pa, _), (pb, _)| pb - pa < tolerance)
}

/// The pairs of phases, adjacent in the order of their `values` (`None`:
/// left out), that `close` accepts (given each side's value and index, the
/// lower first), taken greedily from the lowest so that each phase is in at
/// most one pair.
fn adjacent_pairs(
    values: &[Option<f64>],
    close: impl Fn((f64, usize), (f64, usize)) -> bool,
) -> Vec<(usize, usize)> {
    let mut sorted: Vec<(f64, usize)> = values
        .iter()
        .enumerate()
        .filter_map(|(k, v)| v.map(|v| (v, k)))
        .collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut pairs = Vec::new();
    let mut i = 0;
    while i + 1 < sorted.len() {
        if close(sorted[i], sorted[i + 1]) {
            pairs.push((sorted[i].1, sorted[i + 1].1));
            i += 2;
        } else {
            i += 1;
        }
    }
    pairs
}

/// The pairs of present phases (adjacent by their `means`, indexed as
/// `plateau_samples`) that nothing shows to be two regions: their means
/// differ by less than the `noise`, and neither has a plateau measured well
/// enough to compare within the duplicate `tolerance` ([`plateau_twins`]):
/// fewer than `(2·noise/tolerance)²` pixels or voxels beyond the blur of its
/// edges, where the plateau's standard error `noise/√n` exceeds half the
/// tolerance. A region's plateau needs seven pixels or voxels across;
/// regions that thin with a contrast under the noise are specks of it.
/// Each phase in at most one pair.
pub fn speckled_pairs(
    means: &[Option<f64>],
    plateau_samples: &[usize],
    noise: f64,
    tolerance: f64,
) -> Vec<(usize, usize)> {
    let measured = |k: usize| {
        let n = plateau_samples[k] as f64;
        n > 0.0 && noise / n.sqrt() <= 0.5 * tolerance
    };
    adjacent_pairs(means, |(ma, a), (mb, b)| {
        mb - ma < noise && !measured(a) && !measured(b)
    })
}

/// The phases present in fewer pixels or voxels than `cell` (one regular
/// cell at the edge length, in pixels or voxels) and not in `listed`.
pub fn vestiges(count: &[u64], cell: f64, listed: &[LostPhase]) -> Vec<LostPhase> {
    (0..count.len())
        .filter(|&k| count[k] > 0 && (count[k] as f64) < cell)
        .filter(|&k| !listed.iter().any(|l| l.label() as usize == k))
        .map(|k| LostPhase::Vestige {
            phase: k as Label,
            count: count[k],
        })
        .collect()
}

/// Gives every cell of phase `from` the label `to`.
pub fn merge_phase<K: Raster>(complex: &mut Complex<K>, from: Label, to: Label) {
    let changes: Vec<(CellId, Label)> = complex
        .cell_ids()
        .filter(|&c| complex.label(c) == from)
        .map(|c| (c, to))
        .collect();
    complex.set_labels(&changes);
}

/// Splits the phase that holds the most unexplained structure in two at the
/// least-variance threshold of its cells' means, and gives the cells above
/// the threshold the (empty) label `into`. Returns false when no phase's
/// split explains more than noise would (the image holds no further phase).
///
/// Which phase: the one whose split lowers the data energy most *beyond
/// what splitting noise gives* (ranked by `SplitRank`). Cell means scatter by the
/// noise alone (a cell of `n` pixels by `σ²/n`), so any phase's cells split
/// at a threshold lower the energy by about `2/π · σ²` per cell even when
/// the phase is one true phase; a phase that merges two true phases lowers
/// it by up to `n·(gap/2)²` more per cell. The largest phase (most often the
/// background) has the largest energy but mostly noise, and splitting it
/// gives two phases with the same mean, a duplicate again, while the merged
/// pair stays merged.
///
/// Which cells: those away from every interface (no corner shared with a
/// cell that has a corner on one). A cell across a blurred edge holds both
/// phases' pixels, and its mean lies anywhere between theirs; beside an
/// edge of high contrast such cells spread a phase's cell means far more
/// than a merged pair of close phases does, and splitting them only makes
/// the band along the edge again (on a CT slice whose lungs, 150 HU above
/// clipped air, had merged with it, every re-seed split the body's and the
/// bone's edges and became such a band, and the lungs stayed air). The
/// one-class sum of squares is taken about the mean of the cells judged,
/// not the phase's, which the edge cells pull. Where no phase's cells away
/// from the interfaces split beyond noise, all cells are judged: in a
/// small volume nearly every tet touches an interface or a neighbour that
/// does (judged away from them alone, the three- and four-phase volumes
/// of `benches/small_volumes.py` mostly went without the re-seeds that
/// kept their phases: 28 of the 60 runs warned instead of 11, mean Dice
/// 0.797 instead of 0.902).
pub fn split_most_structured_phase<K: Raster>(
    complex: &mut Complex<K>,
    cells: &[CellStats],
    phases: &PhaseStats,
    into: Label,
    (low, high): (f64, f64),
    noise: f64,
) -> bool {
    let Some((worst, threshold)) =
        most_structured_split(complex, cells, phases, into, (low, high), noise)
    else {
        return false;
    };
    let changes: Vec<(CellId, Label)> = complex
        .cell_ids()
        .filter(|&c| complex.label(c) as usize == worst)
        .filter(|&c| cells[c.index()].mean().is_some_and(|m| m >= threshold))
        .map(|c| (c, into))
        .collect();
    if changes.is_empty() {
        return false;
    }
    complex.set_labels(&changes);
    true
}

/// What the best two-class split of Gaussian noise lowers its sum of squares
/// by, as a fraction of it: `2/π` (each class's mean sits `σ·√(2/π)` from the
/// common mean).
const NOISE_SPLIT_GAIN: f64 = std::f64::consts::FRAC_2_PI;

/// The phase (other than `into`) whose least-variance split of the means of
/// its cells away from the interfaces gains most per cell relative to what
/// splitting noise gains (`2/π · σ²` per cell), with its threshold; `None`
/// when no split gains more than that.
fn most_structured_split<K: Raster>(
    complex: &Complex<K>,
    cells: &[CellStats],
    phases: &PhaseStats,
    into: Label,
    (low, high): (f64, f64),
    noise: f64,
) -> Option<(usize, f64)> {
    let ranges = cell_mean_ranges(complex, cells, phases.count.len(), (low, high));
    let near = near_interface(complex);
    let away = |c: CellId| !complex.cell(c).iter().any(|v| near[v.index()]);
    let split = |judged: &dyn Fn(CellId) -> bool| {
        best_split(complex, cells, phases, into, &ranges, noise, judged)
    };
    split(&away).or_else(|| split(&|_| true))
}

/// The phase (other than `into`) whose least-variance split of the means of
/// its `judged` cells ranks first ([`SplitRank`]) among those that gain more
/// per cell than splitting noise gains, with its threshold; `None` when no
/// split gains more than that.
fn best_split<K: Raster>(
    complex: &Complex<K>,
    cells: &[CellStats],
    phases: &PhaseStats,
    into: Label,
    ranges: &[(f64, f64)],
    noise: f64,
    judged: &dyn Fn(CellId) -> bool,
) -> Option<(usize, f64)> {
    let n = phases.count.len();
    let mut hists: Vec<Histogram> = ranges
        .iter()
        .map(|&(lo, hi)| Histogram::empty(lo, hi))
        .collect();
    // (the pooled pixels of each phase's cells judged, whose sum of squares
    // about their own mean is the one-class split's)
    let mut pooled = vec![CellStats::default(); n];
    let mut cell_count = vec![0usize; n];
    for c in complex.cell_ids() {
        let l = complex.label(c) as usize;
        if l >= n || l == into as usize || phases.mean[l].is_none() || !judged(c) {
            continue;
        }
        let s = &cells[c.index()];
        if let Some(m) = s.mean() {
            hists[l].add(m, s.count as f64, s.sum, s.sum_sq);
            pooled[l].sum += s.sum;
            pooled[l].sum_sq += s.sum_sq;
            pooled[l].count += s.count;
            cell_count[l] += 1;
        }
    }
    let mut best: Option<(SplitRank, usize, f64)> = None;
    for (k, hist) in hists.iter().enumerate() {
        if cell_count[k] < 2 {
            continue;
        }
        let classes = split_histogram(hist, 2);
        if classes.counts.contains(&0.0) {
            continue;
        }
        let one_class = pooled[k].mean().map_or(0.0, |m| pooled[k].sse(m));
        // Gain per cell in units of what splitting noise gains: a wrong
        // noise estimate scales every phase's score alike, so the choice
        // does not depend on it (clipped 8-bit noise reads 20 % low).
        let per_cell = (one_class - classes.sse) / cell_count[k] as f64;
        let score = per_cell / (NOISE_SPLIT_GAIN * noise * noise).max(f64::MIN_POSITIVE);
        let rank = SplitRank::of(score, cell_count[k]);
        if score > 1.0 && best.is_none_or(|(b, _, _)| rank > b) {
            best = Some((rank, k, classes.thresholds[0]));
        }
    }
    best.map(|(_, k, t)| (k, t))
}

/// How a phase's split ranks among the phases': first those whose cells
/// gain more than twice what splitting noise gains, by the total excess
/// over that, then the others by their gain per cell.
///
/// Why the total: two phases that each merge two classes gain alike per
/// cell, and the one with more cells lowers the energy more (three close
/// levels started from the range split: the per-cell ranking split a merged
/// pair of 139 cells before one of 3 638 and lost a class). Why twice: a
/// noise estimate that reads low (clipped 8-bit noise reads 20 % low, its
/// split's gain then 1.56 times the estimate's) gives a large phase of
/// noise alone a total excess over once that grows with its cells, and the
/// background was split again and again.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
enum SplitRank {
    /// Gain per cell at most twice the noise's: the ratio.
    Weak(f64),
    /// The total gain beyond twice the noise's, in units of the noise's
    /// gain per cell.
    Strong(f64),
}

impl SplitRank {
    fn of(score: f64, cells: usize) -> Self {
        if score > 2.0 {
            SplitRank::Strong((score - 2.0) * cells as f64)
        } else {
            SplitRank::Weak(score)
        }
    }
}

/// Per vertex slot: whether the vertex is a corner of a cell with a corner
/// on an interface.
fn near_interface<K: Raster>(complex: &Complex<K>) -> Vec<bool> {
    let mut near = vec![false; complex.vertex_capacity()];
    for c in complex.cell_ids() {
        let corners = complex.cell(c);
        if corners.iter().any(|&v| complex.class(v).on_interface()) {
            for v in corners {
                near[v.index()] = true;
            }
        }
    }
    near
}

/// Per label below `n`: the range its cells' means span, widened to hold
/// the image's robust range `(low, high)` where they lie within it. A
/// phase's split must see its cells at their own means: a bright object of
/// under [`ROBUST_TAIL`](super::intensity::ROBUST_TAIL) of the samples lies
/// beyond the robust range, and a histogram over that range counts its
/// cells at the range's end, where splitting them off gains less than
/// splitting the phase's noise (an 8×8 square at 255 on a 100 plateau was
/// lost so, the two halves of the plateau swapping labels every iteration).
fn cell_mean_ranges<K: Raster>(
    complex: &Complex<K>,
    cells: &[CellStats],
    n: usize,
    (low, high): (f64, f64),
) -> Vec<(f64, f64)> {
    let mut ranges = vec![(low, high); n];
    for c in complex.cell_ids() {
        let l = complex.label(c) as usize;
        if let (Some(range), Some(m)) = (ranges.get_mut(l), cells[c.index()].mean()) {
            *range = (range.0.min(m), range.1.max(m));
        }
    }
    ranges
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The message is the same in 2D and 3D: it must not name a 2D output.
    #[test]
    fn an_empty_phase_is_described_without_naming_a_2d_file() {
        let text = LostPhase::Empty(1).describe(&[0, 1]);
        assert!(text.contains("phase 1 covers no pixel or voxel"), "{text}");
        assert!(!text.contains("labels.png"), "{text}");
    }

    /// Plateaus closer than the tolerance pair up with their neighbour in
    /// plateau order, each phase once; phases without a plateau are skipped.
    #[test]
    fn phases_pair_up_by_close_plateaus() {
        let plateaus = [
            Some(0.50),
            Some(0.10),
            None,
            Some(0.52),
            Some(0.53),
            Some(0.90),
        ];
        assert_eq!(plateau_twins(&plateaus, 0.05), vec![(0, 3)]);
        assert_eq!(plateau_twins(&plateaus, 0.025), vec![(0, 3)]);
        assert_eq!(plateau_twins(&plateaus, 0.015), vec![(3, 4)]);
        assert!(plateau_twins(&plateaus, 0.01).is_empty());
        assert!(plateau_twins(&[Some(0.5), None], 1.0).is_empty());
    }

    /// Specks: means within the noise, no plateau measured to half the
    /// tolerance (σ 0.1, tolerance 0.03: 45 samples and more measure one).
    #[test]
    fn speckled_pairs_need_close_means_and_no_measured_plateau() {
        let means = [Some(0.46), Some(0.52), Some(0.9)];
        assert_eq!(speckled_pairs(&means, &[8, 0, 0], 0.1, 0.03), vec![(0, 1)]);
        assert!(speckled_pairs(&means, &[45, 0, 0], 0.1, 0.03).is_empty());
        assert!(speckled_pairs(&means, &[8, 0, 0], 0.05, 0.03).is_empty());
        assert!(speckled_pairs(&[Some(0.46), None], &[0, 0], 0.1, 0.03).is_empty());
    }

    /// A phase of one voxel is a vestige where a cell holds more; an empty
    /// phase is not (it is lost already), nor a phase already listed.
    #[test]
    fn phases_smaller_than_a_cell_are_vestiges() {
        let count = [38_456, 1_694, 70_441, 1];
        let found = vestiges(&count, 3.2, &[]);
        assert_eq!(found, vec![LostPhase::Vestige { phase: 3, count: 1 }]);
        assert!(vestiges(&count, 0.5, &[]).is_empty());
        assert!(vestiges(&count, 3.2, &[LostPhase::Empty(3)]).is_empty());
        assert!(vestiges(&[10, 0], 3.2, &[]).is_empty());
        let text = found[0].describe(&[0, 1, 2, 3]);
        assert!(
            text.contains("phase 3 holds only 1 pixels or voxels"),
            "{text}"
        );
    }

    fn stats(count: &[u64], mean: &[f64]) -> PhaseStats {
        PhaseStats {
            count: count.to_vec(),
            sum: count
                .iter()
                .zip(mean)
                .map(|(&c, &m)| c as f64 * m)
                .collect(),
            mean: mean.iter().map(|&m| Some(m)).collect(),
        }
    }

    #[test]
    fn empty_and_duplicate_phases_are_found() {
        let p = stats(&[100, 0, 50, 70], &[0.39, 0.2, 0.391, 0.7]);
        assert_eq!(
            lost_phases(&p, 0.01),
            vec![
                LostPhase::Empty(1),
                LostPhase::Duplicate { phase: 2, twin: 0 }
            ]
        );
        assert!(any_lost(&p, 0.01));
        let distinct = stats(&[10, 10, 10], &[0.35, 0.45, 0.55]);
        assert!(lost_phases(&distinct, 0.05).is_empty());
        assert!(!any_lost(&distinct, 0.05));
        assert!(any_lost(&distinct, 0.2));
    }
}
