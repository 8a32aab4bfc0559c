//! A phase that shrank to a band along the edge between two others.
//!
//! A blurred edge between two phases passes through every level between
//! theirs, so a phase whose mean falls between them can end as a layer
//! thinner than a voxel along that edge, holding the blurred voxels rather
//! than a region of its own. That is how a 3D run loses a thin class (a 4 mm
//! fat ring between air and soft tissue): the class starts as, or drifts to,
//! the blur of the air/tissue edge, its mean between the two, and the ring
//! itself merges into the tissue. The run then has fewer distinct phases
//! than asked while no phase is empty and no two means coincide.
//!
//! [`band_phases`] finds such a phase: its mean lies strictly between the
//! means of the two phases it borders most, and it is thinner than a voxel
//! (its volume over its boundary's area; a real layer of two voxels measures
//! one), or thinner than [`SHRUNK_THICKNESS`] voxels while holding less than
//! [`KEPT_FRACTION`] of the voxels its initial threshold range held.

use super::integrate::PhaseStats;
use super::raster::Raster;
use crate::complex::{Complex, Label};

/// A phase ending with fewer than this fraction of the voxels its initial
/// threshold range held has lost its class (a phase's voxels and its range's
/// differ by the noise that crosses the thresholds, a fraction of either).
pub const KEPT_FRACTION: f64 = 0.25;

/// A shrunk phase is a band only when thinner than this many voxels: under
/// strong noise a threshold range holds several times its class's voxels
/// (the middle phase of the 64³ three-phase volume at σ = 0.2 keeps a fifth
/// of its range's, as a region about four voxels thick).
pub const SHRUNK_THICKNESS: f64 = 2.0;

/// The voxels of `data` within each class of `thresholds` (ascending): the
/// count of class `k` is that of values in `[t_{k-1}, t_k)`.
pub fn range_counts(data: &[f32], thresholds: &[f64]) -> Vec<u64> {
    let mut counts = vec![0u64; thresholds.len() + 1];
    for &v in data {
        let k = thresholds.partition_point(|&t| t <= f64::from(v));
        counts[k] += 1;
    }
    counts
}

/// The voxel geometry that a phase's thickness is measured against.
#[derive(Clone, Copy, Debug)]
pub struct VoxelSize {
    /// A voxel's measure (area in 2D, volume in 3D) in domain units.
    pub measure: f64,
    /// A voxel's smallest side in domain units.
    pub smallest_side: f64,
}

/// A phase found as a band: its label and the bordering phase whose mean is
/// nearer its own (the one its cells would join).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Band {
    /// The band's phase.
    pub phase: Label,
    /// The neighbour it is nearer by mean.
    pub nearer: Label,
}

/// The phases of `complex` that are bands along the edge between two others
/// (see the module's documentation). `range_counts` is per label (empty when
/// the initialisation drew no thresholds).
pub fn band_phases<K: Raster>(
    complex: &Complex<K>,
    phases: &PhaseStats,
    range_counts: &[u64],
    voxel: VoxelSize,
) -> Vec<Band> {
    let n = phases.count.len();
    let shared = shared_interface(complex, n);
    (0..n)
        .filter(|&k| phases.count[k] > 0)
        .filter(|&k| {
            let boundary: f64 = shared[k].iter().sum();
            let thickness = phases.count[k] as f64 * voxel.measure / boundary;
            let shrunk = range_counts
                .get(k)
                .is_some_and(|&r| (phases.count[k] as f64) < KEPT_FRACTION * r as f64);
            thickness < voxel.smallest_side
                || (shrunk && thickness < SHRUNK_THICKNESS * voxel.smallest_side)
        })
        .filter_map(|k| {
            between_neighbours(phases, &shared[k], k).map(|nearer| Band {
                phase: k as Label,
                nearer,
            })
        })
        .collect()
}

/// Per phase, the interface measure it shares with each other phase.
fn shared_interface<K: Raster>(complex: &Complex<K>, n: usize) -> Vec<Vec<f64>> {
    let mut shared = vec![vec![0.0; n]; n];
    for f in complex.interface_facets() {
        let (a, b) = (f.a as usize, f.b as usize);
        if a < n && b < n {
            shared[a][b] += f.measure;
            shared[b][a] += f.measure;
        }
    }
    shared
}

/// The neighbour nearer by mean when phase `k`'s mean lies strictly between
/// the means of the two phases it shares most interface with (`shared`).
fn between_neighbours(phases: &PhaseStats, shared: &[f64], k: usize) -> Option<Label> {
    let mut partners: Vec<usize> = (0..shared.len()).filter(|&j| shared[j] > 0.0).collect();
    partners.sort_by(|&x, &y| shared[y].total_cmp(&shared[x]));
    let (&first, &second) = (partners.first()?, partners.get(1)?);
    let (m, a, b) = (phases.mean[k]?, phases.mean[first]?, phases.mean[second]?);
    if !(a.min(b) < m && m < a.max(b)) {
        return None;
    }
    let nearer = if (m - a).abs() <= (m - b).abs() {
        first
    } else {
        second
    };
    Some(nearer as Label)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_counts_split_at_the_thresholds() {
        let data = [0.0, 0.1, 0.25, 0.5, 0.6, 0.9, 1.0];
        assert_eq!(range_counts(&data, &[0.25, 0.75]), vec![2, 3, 2]);
    }

    fn three_phases(means: [f64; 3]) -> PhaseStats {
        let mut phases = PhaseStats::new(3);
        phases.count = vec![100, 10, 100];
        phases.mean = means.iter().map(|&m| Some(m)).collect();
        phases
    }

    #[test]
    fn a_phase_between_its_two_neighbours_is_a_band() {
        let shared = [4.0, 0.0, 6.0];
        let phases = three_phases([0.0, 0.4, 1.0]);
        assert_eq!(between_neighbours(&phases, &shared, 1), Some(0));
        let phases = three_phases([0.0, 1.2, 1.0]);
        assert_eq!(between_neighbours(&phases, &shared, 1), None);
        assert_eq!(between_neighbours(&phases, &[0.0, 0.0, 6.0], 1), None);
    }
}
