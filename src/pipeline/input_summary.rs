//! The `input` block of `report.json`, the same in 2D and 3D: how the input
//! stored its samples, its value range and the final phase means in the
//! file's own units (HU for CT), the means also on `[0, 1]`, and the unit of
//! every other intensity of the report.

use crate::io::intensity::IntensityMap;
use crate::io::selection::Selection;
use crate::io::{Colour, SampleType};
use crate::segment::{SegmentError, SegmentReport};
use serde::Serialize;

/// Intensities as the file holds them (8/16-bit integers as stored, floats
/// and signed integers as they are, e.g. HU).
pub(crate) const FILE_UNIT: &str = "file";
/// Intensities on `[0, 1]`: 8-bit values ÷ 255, 16-bit ÷ 65535, any other
/// type stretched from its minimum to its maximum.
pub(crate) const NORMALISED_UNIT: &str = "normalised";

/// The `input` block of `report.json`.
#[derive(Serialize)]
pub(crate) struct InputSummary {
    /// How the file or array stored its samples (`float` for phantoms).
    sample_type: SampleType,
    /// Gray samples, the luminance of colour ones, or one channel (volumes: gray).
    colour: Colour,
    /// The channel and time point of a multi-channel or time-lapse TIFF
    /// that were segmented (`channel`, `time_point`: `--channel`,
    /// `--time-point`, 0-based; `null` when not chosen, and `channel` also
    /// when `--channel` took a colour channel, which `colour` names).
    #[serde(flatten)]
    selection: Selection,
    /// The unit of `min`, `max` and `phase_means`: [`FILE_UNIT`], or
    /// [`NORMALISED_UNIT`] for a phantom (an array's values count as a file's).
    intensity_unit: &'static str,
    /// The smallest sample, exactly as stored (an outlier the segmentation
    /// clamped included).
    min: f64,
    /// The largest sample, exactly as stored (likewise).
    max: f64,
    /// The final phase means by output value (0, 1, ...; ascending), in
    /// `intensity_unit`; `null` for a phase with no cell.
    phase_means: Vec<Option<f64>>,
    /// The same means on `[0, 1]` ([`NORMALISED_UNIT`]).
    phase_means_normalised: Vec<Option<f64>>,
    /// The unit of the report's other intensities (`final_means`,
    /// `ordered_means`, `segmentation`'s intensity figures, thresholds and
    /// means): [`FILE_UNIT`] where the loader keeps the file's values (2D
    /// float and signed images, folders of such slices), else [`NORMALISED_UNIT`].
    loaded_unit: &'static str,
}

impl InputSummary {
    /// The summary of an input of `sample_type` and `colour`, the pages
    /// `selection` of its file, whose loaded values map back to the file's
    /// by `map` (`None`: no file), from the run's `report`, the extremes
    /// of the outliers it clamped (loaded values; `None`: none) and its
    /// final means by output value, `ordered_means`. Loaded file values
    /// (2D float and signed images) are stretched to the normalised means
    /// over the range the segmentation saw, without the outliers it
    /// clamped: one hot pixel would squeeze them all towards 0 (a volume
    /// of such samples is loaded normalised already, over its whole range).
    pub(crate) fn new(
        (sample_type, colour, selection): (SampleType, Colour, Selection),
        map: Option<IntensityMap>,
        (report, outlier_extremes): (&SegmentReport, Option<(f32, f32)>),
        ordered_means: &[Option<f64>],
    ) -> Self {
        let (lo, hi) = (report.intensity.min, report.intensity.max);
        let (stored_lo, stored_hi) = outlier_extremes.map_or((lo, hi), |(low, high)| {
            (lo.min(f64::from(low)), hi.max(f64::from(high)))
        });
        let loaded_unit = match map {
            Some(m) if m.is_identity() => FILE_UNIT,
            _ => NORMALISED_UNIT,
        };
        let to_file = map.unwrap_or(IntensityMap::IDENTITY);
        // Loaded values already on [0, 1] stay; loaded file values are
        // stretched from their range, as the volume readers stretch them.
        let to_normalised = |v: f64| match loaded_unit {
            NORMALISED_UNIT => v,
            _ if hi > lo => (v - lo) / (hi - lo),
            _ => 0.0,
        };
        InputSummary {
            sample_type,
            colour,
            selection,
            intensity_unit: if map.is_some() {
                FILE_UNIT
            } else {
                NORMALISED_UNIT
            },
            min: to_file.original_sample(stored_lo, sample_type),
            max: to_file.original_sample(stored_hi, sample_type),
            phase_means: ordered_means
                .iter()
                .map(|m| m.map(|m| to_file.original(m)))
                .collect(),
            phase_means_normalised: ordered_means.iter().map(|m| m.map(to_normalised)).collect(),
            loaded_unit,
        }
    }
}

/// `error` with a constant image's value in the file's units (the
/// segmentation sees the loaded values: 0.5 for a 16-bit image of 32768s).
pub(crate) fn with_file_values(
    error: SegmentError,
    map: Option<IntensityMap>,
    sample_type: SampleType,
) -> SegmentError {
    match (error, map) {
        (SegmentError::ConstantImage(v), Some(map)) => {
            SegmentError::ConstantImage(map.original_sample(v, sample_type))
        }
        (error, _) => error,
    }
}
