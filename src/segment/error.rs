//! What can go wrong in a segmentation run.

use crate::complex::BuildError;
use thiserror::Error;

/// Bad input or an impossible configuration (never a panic, never a NaN).
#[derive(Debug, Error)]
pub enum SegmentError {
    /// The image has no pixels.
    #[error("the image is empty")]
    EmptyImage,
    /// The image is too small to hold a mesh: its size and the smallest
    /// size, e.g. `1×1×1 voxels` and `2×2×2`.
    #[error("the image is {0}; at least {1} is needed")]
    ImageTooSmall(String, &'static str),
    /// A sample is NaN or infinite.
    #[error("the image contains a non-finite value")]
    NonFinite,
    /// All pixels have the same value: there is nothing to separate.
    #[error("the image is constant (every sample is {0}); there is nothing to segment")]
    ConstantImage(f64),
    /// Fewer distinct intensities than phases.
    #[error("the image has only {distinct} distinct intensities, fewer than the {phases} phases asked for")]
    TooFewIntensities {
        /// Distinct values found.
        distinct: usize,
        /// Phases asked for.
        phases: usize,
    },
    /// The number of phases is out of range.
    #[error("the number of phases must be between 2 and 64, not {0}")]
    Phases(usize),
    /// A bad edge length (`{:?}` keeps 1e-9 and 1e300 short).
    #[error("edge length {0:?}: {1}")]
    EdgeLength(f64, String),
    /// Another parameter is out of range: its name, value and valid range.
    #[error("parameter {} = {} is out of range: {}", .0, short_number(*.1), .2)]
    Param(&'static str, f64, &'static str),
    /// Eq. (5) is defined for two phases only.
    #[error("the Chan–Vese force (eq. 5) needs exactly 2 phases, not {0}")]
    ChanVeseNeedsTwoPhases(usize),
    /// A bad initialisation from the input (a label image that does not fit).
    #[error("initialisation: {0}")]
    Init(String),
    /// A bad initialisation from an option's value: a disk or ball that is
    /// not a shape, names no phase or lies outside the image, a start that
    /// cannot choose the number of phases.
    #[error("initialisation: {0}")]
    InitOption(String),
    /// The mesh could not be built.
    #[error("mesh: {0}")]
    Build(#[from] BuildError),
}

impl SegmentError {
    /// Whether the error is a parameter's value out of its range (the
    /// number of phases, the edge length, a weight or fraction), as opposed
    /// to an input that cannot be segmented: the command line exits 2 for
    /// these, as for options that do not parse.
    pub fn is_parameter(&self) -> bool {
        matches!(
            self,
            SegmentError::Phases(_)
                | SegmentError::EdgeLength(..)
                | SegmentError::Param(..)
                | SegmentError::ChanVeseNeedsTwoPhases(_)
                | SegmentError::InitOption(_)
        )
    }
}

/// `v` as a user typed it: a whole number without a decimal point (a count
/// such as `max_iterations = 0`), any other the shortest way that reads
/// back exactly (`{:?}` keeps 1e-9 and 1e300 short).
fn short_number(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v:.0}")
    } else {
        format!("{v:?}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_print_as_typed() {
        let said = |v: f64| SegmentError::Param("p", v, "r").to_string();
        assert_eq!(said(0.0), "parameter p = 0 is out of range: r");
        assert_eq!(said(-2.0), "parameter p = -2 is out of range: r");
        assert_eq!(said(0.5), "parameter p = 0.5 is out of range: r");
        assert_eq!(said(1e-9), "parameter p = 1e-9 is out of range: r");
        assert_eq!(said(1e300), "parameter p = 1e300 is out of range: r");
    }
}
