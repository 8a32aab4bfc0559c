//! The DSC's thresholds, all derived from the one user parameter: the average edge length.

use crate::dim::Dim;

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// A parameter outside its meaningful range.
#[derive(Debug, Error, PartialEq)]
#[error("invalid parameter {name} = {value}: {why}")]
pub struct ParamError {
    /// The parameter's name.
    pub name: &'static str,
    /// The offending value.
    pub value: f64,
    /// What the value must satisfy.
    pub why: &'static str,
}

/// Thresholds of the deformable simplicial complex. Lengths are multiples of
/// the average edge length `L`, measures multiples of the regular cell's
/// measure `A(L)`, qualities in `[0, 1]` (see [`Dim::quality`]). The defaults are
/// those of the original 2D and 3D DSC libraries (Misztal, Bærentzen et al.).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DscParams {
    /// Average edge length `L`, the one user parameter (pixels/voxels).
    pub edge_length: f64,
    /// Cells below this quality are degenerate and removed (2D: a 2° smallest angle; 3D: 0.02).
    pub degenerate_quality: f64,
    /// A collapse is safe only if the cells it creates reach this quality (2D: a 10° smallest angle; 3D: 0.3).
    pub min_quality: f64,
    /// Cells below this quality are improved by flips (3D: 2-3 flips and edge
    /// removal, 0.3); 2D flips every non-Delaunay edge and ignores it.
    pub low_quality: f64,
    /// Interface edges longer than this times `L` are split.
    pub max_length: f64,
    /// Interface edges shorter than this times `L` are collapsed where the interface is straight.
    pub min_length: f64,
    /// Edges shorter than this times `L` are degenerate.
    pub degenerate_length: f64,
    /// With a graded sizing field, interior edges shorter than this times the
    /// target size `h` are collapsed (coarsening towards `h`).
    #[serde(default = "default_coarsen_length")]
    pub coarsen_length: f64,
    /// Cells larger than this times `A(L)` get their longest edge split.
    pub max_measure: f64,
    /// Cells smaller than this times `A(L)` are collapsed when safe.
    pub min_measure: f64,
    /// Cells smaller than this times `A(L)` are degenerate.
    pub degenerate_measure: f64,
    /// A vertex this close (times `L`) to its destination has arrived.
    pub move_tolerance: f64,
    /// Largest angle (degrees) between consecutive interface facets at a vertex
    /// that still counts as straight/flat, so the vertex may be collapsed away.
    pub straight_angle_deg: f64,
    /// Most move-and-improve rounds per deform call.
    pub max_rounds: usize,
}

/// An equilateral cell of edge `0.6·h` still has `0.36·A(h)`, above the
/// small-cell threshold, so a coarsened cell is not collapsed again at once.
fn default_coarsen_length() -> f64 {
    0.6
}

impl DscParams {
    /// The defaults for dimension `K` at average edge length `edge_length`.
    pub fn new<K: Dim>(edge_length: f64) -> Self {
        let quality = K::quality_defaults();
        DscParams {
            edge_length,
            degenerate_quality: quality.degenerate,
            min_quality: quality.minimum,
            low_quality: 0.3,
            max_length: 2.0,
            min_length: 0.5,
            degenerate_length: 0.1,
            coarsen_length: default_coarsen_length(),
            max_measure: 5.0,
            min_measure: 0.2,
            degenerate_measure: 0.04,
            move_tolerance: 1e-4,
            straight_angle_deg: quality.straight_angle_deg,
            max_rounds: 10,
        }
    }

    /// Checks every value; the first violation is returned.
    pub fn validate(&self) -> Result<(), ParamError> {
        let check = |name: &'static str, value: f64, ok: bool, why: &'static str| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(ParamError { name, value, why })
            }
        };
        let l = self.edge_length;
        check("edge_length", l, l > 0.0, "must be a positive number")?;
        check(
            "degenerate_quality",
            self.degenerate_quality,
            (0.0..1.0).contains(&self.degenerate_quality),
            "must lie in [0, 1)",
        )?;
        check(
            "min_quality",
            self.min_quality,
            self.min_quality >= self.degenerate_quality && self.min_quality < 1.0,
            "must lie in [degenerate_quality, 1)",
        )?;
        check(
            "low_quality",
            self.low_quality,
            (0.0..=1.0).contains(&self.low_quality),
            "must lie in [0, 1]",
        )?;
        check(
            "max_length",
            self.max_length,
            self.max_length > 2.0 * self.min_length,
            "must exceed twice min_length, or splits and collapses undo each other",
        )?;
        check(
            "min_length",
            self.min_length,
            self.min_length > self.degenerate_length,
            "must exceed degenerate_length",
        )?;
        check(
            "coarsen_length",
            self.coarsen_length,
            self.coarsen_length >= 0.0 && 2.0 * self.coarsen_length < self.max_length,
            "must lie in [0, max_length / 2), or coarsening undoes splits",
        )?;
        check(
            "degenerate_length",
            self.degenerate_length,
            self.degenerate_length >= 0.0,
            "must be >= 0",
        )?;
        check(
            "max_measure",
            self.max_measure,
            self.max_measure > 2.0 * self.min_measure,
            "must exceed twice min_measure",
        )?;
        check(
            "min_measure",
            self.min_measure,
            self.min_measure >= self.degenerate_measure,
            "must be >= degenerate_measure",
        )?;
        check(
            "degenerate_measure",
            self.degenerate_measure,
            self.degenerate_measure >= 0.0,
            "must be >= 0",
        )?;
        check(
            "move_tolerance",
            self.move_tolerance,
            self.move_tolerance > 0.0 && self.move_tolerance < 0.1,
            "must lie in (0, 0.1)",
        )?;
        check(
            "straight_angle_deg",
            self.straight_angle_deg,
            (0.0..90.0).contains(&self.straight_angle_deg),
            "must lie in [0, 90)",
        )?;
        check(
            "max_rounds",
            self.max_rounds as f64,
            self.max_rounds >= 1,
            "must be at least 1",
        )?;
        Ok(())
    }

    /// Absolute move tolerance.
    pub fn tolerance(&self) -> f64 {
        self.move_tolerance * self.edge_length
    }
    /// Absolute measure threshold `factor · A(L)`.
    pub fn measure<K: Dim>(&self, factor: f64) -> f64 {
        factor * K::regular_measure(self.edge_length)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::{D2, D3};

    #[test]
    fn defaults_are_valid_in_both_dimensions() {
        assert_eq!(DscParams::new::<D2>(10.0).validate(), Ok(()));
        assert_eq!(DscParams::new::<D3>(4.0).validate(), Ok(()));
    }

    #[test]
    fn nonsense_is_rejected() {
        for l in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(DscParams::new::<D2>(l).validate().is_err());
        }
        let mut p = DscParams::new::<D2>(5.0);
        p.max_length = 0.9;
        assert!(p.validate().is_err());
    }
}
