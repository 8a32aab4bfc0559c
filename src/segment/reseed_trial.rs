//! A re-seed of a phase judged a band, on trial until the next flip round.
//!
//! A phase judged lost as a band along the edge between two others
//! ([`super::band_phase`]) may be a real region: the test reads the phase's
//! thickness from the mesh's interface measure, which a noisy early
//! interface inflates, so a wedge four voxels thick of a small volume under
//! strong noise measures under two. Merging such a phase into its twin and
//! splitting another gives two phases that share one region and a
//! fragmented split whose interface the run never smooths away: the energy
//! rises and the run does not recover. An empty phase, or two phases with
//! one mean, is a fact of the statistics; a band is a judgement on geometry,
//! so the driver tests a band's re-seed by its energy. It keeps the state
//! before the re-seed ([`ReseedTrial`]); at the next flip round the
//! re-seeded state must have a lower Mumford–Shah energy (data plus the
//! pre-re-seed length weight times the interface measure) than the state
//! before it, or the driver restores that state and does not re-seed those
//! labels again ([`ReseedTrial::improved`]): a band that then empties is the
//! same lost class, and the run's warning says so.

use super::adaptive::AdaptiveSizing;
use super::raster::Raster;
use crate::complex::{Complex, Label};

/// The state a round of re-seeds that included a band started from, and
/// what the driver restores if the re-seeded state does not lower the
/// energy.
#[derive(Clone, Debug)]
pub struct ReseedTrial<K: Raster> {
    /// The complex, labels included, before the merges and splits.
    pub complex: Complex<K>,
    /// The adaptive sizing before the re-seed.
    pub adaptive: Option<AdaptiveSizing>,
    /// Mumford–Shah energy of that state with `length_weight`.
    pub energy: f64,
    /// The length weight ν before the re-seed (the re-seed measures it
    /// again from the new means); both states are weighed with it.
    pub length_weight: f64,
    /// The labels re-seeded as bands: not re-seeded again if the trial
    /// fails.
    pub bands: Vec<Label>,
    /// Re-seeds the round made.
    pub reseeds: usize,
    /// Each phase's count of voxels in its initial threshold range before
    /// the re-seed (a re-seeded label's no longer applies).
    pub initial_range_counts: Vec<u64>,
    /// The run's stopping and step state before the re-seed.
    pub progress: RunProgress,
}

/// The counters of the step size and the stopping rule, which a re-seed
/// starts over.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunProgress {
    /// The step fraction.
    pub step: f64,
    /// The lowest energy so far.
    pub best_energy: f64,
    /// Iterations since the step was last halved or a new low reached.
    pub stalled: usize,
    /// Iterations since the last new low.
    pub since_new_low: usize,
    /// Where the settle rate's measure of the energy's fall begins.
    pub fall_origin: usize,
    /// Quiet iterations in a row.
    pub quiet_iterations: usize,
    /// Whether a quiet flip round came on a plateau.
    pub quiet_round_on_plateau: bool,
}

impl<K: Raster> ReseedTrial<K> {
    /// Whether the re-seeded state, of data energy `data` and interface
    /// measure `length`, has a lower energy than the state before the
    /// re-seed, both weighed with that state's length weight.
    pub fn improved(&self, data: f64, length: f64) -> bool {
        data + self.length_weight * length < self.energy
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::D2;

    fn trial(energy: f64, length_weight: f64) -> ReseedTrial<D2> {
        ReseedTrial {
            complex: Complex::<D2>::rectangle(4.0, 4.0, 2.0).unwrap(),
            adaptive: None,
            energy,
            length_weight,
            bands: vec![1],
            reseeds: 1,
            initial_range_counts: Vec::new(),
            progress: RunProgress {
                step: 0.1,
                best_energy: energy,
                stalled: 0,
                since_new_low: 0,
                fall_origin: 0,
                quiet_iterations: 0,
                quiet_round_on_plateau: false,
            },
        }
    }

    #[test]
    fn a_reseed_is_kept_only_if_it_lowers_the_energy_at_the_old_weight() {
        let t = trial(100.0, 0.5);
        assert!(t.improved(80.0, 39.0));
        assert!(!t.improved(80.0, 40.0));
        assert!(!t.improved(120.0, 0.0));
    }
}
