//! Choosing the number of phases (`--phases auto`).
//!
//! The segmentation is run with 2, 3, … phases and the largest count whose
//! result is a *piecewise-constant fit with every phase real* is kept, the
//! runs stopping at the first count that fails. A phase is not real when
//!
//! - it is lost: empty, or its mean duplicates another's within the noise
//!   ([`reseed`](super::reseed); re-seeding is tried first), which is what
//!   an extra phase becomes on a region of one true phase: the two halves of
//!   one phase have the same mean up to noise;
//! - it is a band along edges: blurred or partial-volume edges have
//!   intermediate values, and a spare phase settles on them as a strip a
//!   few pixels wide. Its *thickness* (area over boundary length in 2D,
//!   volume over boundary area in 3D; half the width of a strip, a quarter
//!   of the diameter of a disk) is below [`MIN_THICKNESS`] pixels, and it
//!   lies *between* two phases: at least [`BAND_SIDE_SHARE`] of its
//!   boundary borders phases of lower mean and as much borders phases of
//!   higher mean, as a strip along the edge between them does. A thin phase
//!   that borders only darker (or only brighter) phases, such as small
//!   bright spots, cannot be made of their blurred edges, which hold values
//!   between them; it is judged by its plateau (below);
//! - it has no plateau of its own: the phases' *plateau* intensities, the
//!   means over their pixels beyond the blur of every edge
//!   ([`phase_plateaus`]), must all differ by more than the duplicate
//!   tolerance, and every phase but the darkest and the brightest must have
//!   such pixels. Blur lowers the mean of a small or thin object of one true
//!   phase (a 5-px bar, the smallest disk) enough at low noise for it to
//!   pass as a phase of its own; its plateau is the true phase's, or it has
//!   none. Blur mixes towards the middle, so it makes no phase darker or
//!   brighter than all the others: those two need no plateau.
//!
//! Both tests are scale-free, so the choice does not depend on the
//! intensities' units, and both follow from the piecewise-constant model:
//! its phases are regions of constant mean, and the model with one more
//! phase is kept only if the data support a new constant region.

use super::driver::StopReason;
use super::error::SegmentError;
use super::image::ImageView;
use super::integrate::PhaseStats;
use super::params::SegmentParams;
use super::partial_volume::phase_plateaus;
use super::raster::Raster;
use super::reseed::plateau_twins;
use super::Segmentation;
use crate::complex::{Complex, Label};
use serde::Serialize;

/// Default largest number of phases tried.
pub const DEFAULT_MAX_PHASES: usize = 8;

/// Thinnest phase (area over boundary length, pixels) a result may have;
/// thinner phases are bands along blurred edges.
pub const MIN_THICKNESS: f64 = 2.5;

/// The least share of a band's boundary on each side of its mean: a strip
/// along the edge between two phases borders each of them over about half
/// of its boundary (a ring around a small disk over less on the inside).
pub const BAND_SIDE_SHARE: f64 = 0.25;

/// One tried phase count.
#[derive(Clone, Debug, Serialize)]
pub struct PhaseTrial {
    /// The number of phases.
    pub phases: usize,
    /// Whether every phase of the result is real.
    pub accepted: bool,
    /// Why not, when not (`None` exactly when accepted). Two phases are
    /// kept even when not accepted, as the fewest there are: the choice's
    /// warnings say so.
    pub reason: Option<String>,
    /// Whether the run converged (its stopping rule met).
    pub converged: bool,
    /// Whether the run stopped at the iteration cap: it is judged as it
    /// stood, and the choice warns (a run whose labels kept swapping did
    /// not converge either, but ran out of nothing).
    pub stopped_at_cap: bool,
    /// Thickness of the thinnest phase that lies between two others (see
    /// the module documentation), in pixels; infinite (`null` in the
    /// report) when none does.
    pub thinnest: f64,
    /// Data term `Σ (I − m)²` of the result.
    pub data_energy: f64,
    /// Iterations of the run.
    pub iterations: usize,
}

/// The outcome of [`choose_phases`].
#[derive(Clone, Debug, Serialize)]
pub struct PhaseChoice {
    /// The chosen number of phases.
    pub phases: usize,
    /// The largest number tried.
    pub max_phases: usize,
    /// Every run, in order.
    pub trials: Vec<PhaseTrial>,
}

impl PhaseChoice {
    /// What the user must know about the choice: it stopped at the cap
    /// ([`cap_warning`](Self::cap_warning)) or at the floor
    /// ([`floor_warning`](Self::floor_warning)).
    pub fn warnings(&self) -> Vec<String> {
        self.cap_warning()
            .into_iter()
            .chain(self.floor_warning())
            .chain(self.unconverged_warning())
            .collect()
    }

    /// A warning when a trial the choice rests on (a count up to the chosen
    /// one) stopped at the iteration cap: its phases were judged before the
    /// run converged, so the choice may not be the data's.
    pub fn unconverged_warning(&self) -> Option<String> {
        let counts: Vec<String> = self
            .trials
            .iter()
            .filter(|t| t.phases <= self.phases && t.stopped_at_cap)
            .map(|t| t.phases.to_string())
            .collect();
        (!counts.is_empty()).then(|| {
            format!(
                "--phases auto judged the run with {} phases at the iteration cap, before it \
                 converged: the choice may change with a higher --max-iterations",
                counts.join(", ")
            )
        })
    }

    /// A warning when two phases, the fewest there are, failed the tests of
    /// regions: two is taken because one is no segmentation, not because
    /// the data show two (pure noise, or a smooth ramp, split anywhere).
    /// It says why the two failed, so it stands in for the run's own
    /// warnings of a lost phase (which would also speak of two phases
    /// "asked for").
    pub fn floor_warning(&self) -> Option<String> {
        let first = self.trials.first()?;
        let reason = first.reason.as_ref()?;
        (self.phases == 2 && first.phases == 2).then(|| {
            format!(
                "--phases auto found no two distinct regions, so the image may hold a \
                 single phase: with two, {reason}"
            )
        })
    }

    /// A warning when the choice is the largest count tried and that count
    /// was accepted: the search stopped at the cap, not at the data, so the
    /// image may hold more phases, or be no piecewise-constant image at all
    /// (a ramp or shading passes every test of a region at every count).
    pub fn cap_warning(&self) -> Option<String> {
        let last = self.trials.last()?;
        (last.accepted && last.phases == self.max_phases).then(|| {
            format!(
                "--phases auto took the largest count tried ({}): the image may hold more \
                 phases, or vary smoothly rather than in regions; a larger --max-phases tries \
                 more (--phases N fixes the count)",
                self.max_phases
            )
        })
    }
}

/// Runs the segmentation of `image` with `params(n)` for n = 2, 3, … up to
/// `max_phases` and returns the largest n whose phases are all real (see the
/// module documentation), with every trial. Counts above the image's distinct
/// values are not tried.
pub fn choose_phases<K: Raster>(
    image: ImageView<'_>,
    max_phases: usize,
    params: impl Fn(usize) -> SegmentParams,
) -> Result<PhaseChoice, SegmentError> {
    if max_phases < 2 {
        return Err(SegmentError::Phases(max_phases));
    }
    let distinct = image.distinct_values(max_phases);
    let mut trials: Vec<PhaseTrial> = Vec::new();
    let mut chosen = 2;
    for n in 2..=max_phases.min(distinct.max(2)) {
        let mut seg = Segmentation::<K>::new(image, params(n))?;
        let report = seg.run(|_| {});
        let thinnest = thinnest_band(seg.complex(), seg.phases());
        // (a vestige, a phase of fewer samples than one cell holds, is no
        // region either: the run's own end-of-run check says so too)
        let mut lost = seg.lost_phases();
        lost.extend(seg.vestige_phases(&lost));
        let reason = if let Some(l) = lost.first() {
            Some(l.describe(&seg.phase_order()))
        } else if thinnest < MIN_THICKNESS {
            Some(format!(
                "a phase is {thinnest:.2} px thick (a band along edges, not a region)"
            ))
        } else {
            shared_plateau(&seg.label_image(), image, n, seg.duplicate_tolerance())
        };
        let accepted = reason.is_none();
        // Two phases are the fewest: kept even when not accepted.
        let kept = accepted || n == 2;
        trials.push(PhaseTrial {
            phases: n,
            accepted,
            reason,
            converged: report.converged,
            stopped_at_cap: report.stop_reason == StopReason::MaxIterations,
            thinnest,
            data_energy: report.history.last().map_or(f64::NAN, |r| r.data_energy),
            iterations: report.iterations,
        });
        if !kept {
            break;
        }
        chosen = n;
    }
    Ok(PhaseChoice {
        phases: chosen,
        max_phases,
        trials,
    })
}

/// Why the phases of `labels` are not all distinct regions by their
/// plateaus (see the module documentation), or `None` when they are.
fn shared_plateau(
    labels: &[u8],
    image: ImageView<'_>,
    phases: usize,
    tolerance: f64,
) -> Option<String> {
    let plateaus: Vec<Option<f64>> = phase_plateaus(labels, image.data, image.dims, phases)
        .iter()
        .map(|p| p.map(|p| p.mean))
        .collect();
    // The darkest and the brightest phase (labels rank the phases by mean)
    // cannot be blurred copies of others: blur mixes towards the middle.
    let between = |k: usize| k > 0 && k + 1 < phases;
    let no_plateau = (0..phases).find(|&k| plateaus[k].is_none() && between(k));
    if let Some(k) = no_plateau {
        return Some(format!(
            "phase {k} has no pixel beyond the blur of its edges (a thin structure or a band)"
        ));
    }
    plateau_twins(&plateaus, tolerance).first().map(|&(a, b)| {
        let (pa, pb) = (plateaus[a].unwrap_or(f64::NAN), plateaus[b].unwrap_or(f64::NAN));
        format!(
            "phases {a} and {b} have the same plateau ({pa:.6} and {pb:.6}) within the noise: one phase whose parts differ by blur"
        )
    })
}

/// A phase's boundary (the domain border excluded), split by the side of
/// its mean the phase across it lies on.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Boundary {
    /// Measure of the boundary with phases of lower mean.
    below: f64,
    /// Measure of the boundary with phases of higher (or equal) mean.
    above: f64,
}

impl Boundary {
    fn total(&self) -> f64 {
        self.below + self.above
    }

    /// Whether it borders darker and brighter phases as a band between
    /// them does: each over at least [`BAND_SIDE_SHARE`] of it.
    fn lies_between(&self) -> bool {
        self.below.min(self.above) >= BAND_SIDE_SHARE * self.total()
    }
}

/// Each phase's [`Boundary`] on the final mesh, by the phases' `means`.
fn phase_boundaries<K: Raster>(complex: &Complex<K>, means: &[Option<f64>]) -> Vec<Boundary> {
    let mut boundary = vec![Boundary::default(); means.len()];
    let mean = |l: Label| means.get(l as usize).copied().flatten();
    for f in complex.interface_facets() {
        for (own, other) in [(f.a, f.b), (f.b, f.a)] {
            let (Some(m), Some(n), Some(b)) =
                (mean(own), mean(other), boundary.get_mut(own as usize))
            else {
                continue;
            };
            if n < m {
                b.below += f.measure;
            } else {
                b.above += f.measure;
            }
        }
    }
    boundary
}

/// The smallest ratio of a phase's pixel count to the measure of its
/// boundary, over the phases that lie between two others (at least
/// [`BAND_SIDE_SHARE`] of the boundary against darker phases and as much
/// against brighter ones); infinite when none does.
pub fn thinnest_band<K: Raster>(complex: &Complex<K>, phases: &PhaseStats) -> f64 {
    phase_boundaries(complex, &phases.mean)
        .iter()
        .zip(&phases.count)
        .filter(|(b, &c)| c > 0 && b.total() > 0.0 && b.lies_between())
        .map(|(b, &c)| c as f64 / b.total())
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trial(phases: usize, converged: bool, stopped_at_cap: bool) -> PhaseTrial {
        PhaseTrial {
            phases,
            accepted: true,
            reason: None,
            converged,
            stopped_at_cap,
            thinnest: f64::INFINITY,
            data_energy: 0.0,
            iterations: 10,
        }
    }

    /// Only a trial that ran out of iterations is said to have: one whose
    /// labels kept swapping did not converge either, but was not cut short.
    #[test]
    fn the_cap_warning_names_only_trials_stopped_at_the_cap() {
        let choice = |trials| PhaseChoice {
            phases: 3,
            max_phases: 4,
            trials,
        };
        let swapping = choice(vec![trial(2, true, false), trial(3, false, false)]);
        assert_eq!(swapping.unconverged_warning(), None);
        let capped = choice(vec![
            trial(2, false, true),
            trial(3, true, false),
            trial(4, false, true),
        ]);
        let warning = capped.unconverged_warning().expect("a warning");
        assert!(
            warning.contains("with 2 phases at the iteration cap"),
            "{warning}"
        );
    }
}
