//! How loaded intensities map back to the file's own values.

use serde::Serialize;

use super::image2::SampleType;

/// `original = low + (high − low) · loaded`: loaded intensities lie in
/// `[0, 1]` (8-bit data divided by 255, 16-bit by 65535, anything else
/// stretched from its minimum and maximum) or are the file's values as they
/// are (2D float and signed images: [`IntensityMap::IDENTITY`]), and
/// measurements report the file's units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct IntensityMap {
    /// The original value of a loaded 0.
    low: f64,
    /// The original value of a loaded 1 (kept apart from the scale so
    /// that the top of a stretched range maps back exactly).
    high: f64,
}

impl IntensityMap {
    /// Loaded values are the original ones.
    pub const IDENTITY: IntensityMap = IntensityMap {
        low: 0.0,
        high: 1.0,
    };

    /// Unsigned integers of `bits` bits divided by their maximum.
    pub fn unsigned(bits: u32) -> Self {
        IntensityMap {
            low: 0.0,
            high: ((1u64 << bits) - 1) as f64,
        }
    }

    /// Values stretched from `[lo, hi]` to `[0, 1]` (a constant volume: `lo`).
    pub fn stretched(lo: f64, hi: f64) -> Self {
        IntensityMap {
            low: lo,
            high: hi.max(lo),
        }
    }

    /// The map of samples of `sample_type` as the 2D image readers load
    /// them: 8/16-bit unsigned divided by their maximum, every other type
    /// kept as stored.
    pub fn of_sample_type(sample_type: SampleType) -> Self {
        match sample_type {
            SampleType::Uint8 => IntensityMap::unsigned(8),
            SampleType::Uint16 => IntensityMap::unsigned(16),
            SampleType::Int | SampleType::Float => IntensityMap::IDENTITY,
        }
    }

    /// Whether loaded values are the original ones.
    pub fn is_identity(&self) -> bool {
        *self == IntensityMap::IDENTITY
    }

    /// The original range of a loaded unit step.
    pub fn scale(&self) -> f64 {
        self.high - self.low
    }

    /// The original value of a loaded one.
    pub fn original(&self, loaded: f64) -> f64 {
        self.low + self.scale() * loaded
    }

    /// The original value of a loaded sample, exactly as the file holds it:
    /// the ends of the loaded range give the ends of the original one
    /// without rounding error, and integer samples are rounded back to
    /// the integers they were.
    pub fn original_sample(&self, loaded: f64, sample_type: SampleType) -> f64 {
        let v = if self.is_identity() {
            loaded
        } else if loaded == 0.0 {
            self.low
        } else if loaded == 1.0 {
            self.high
        } else {
            self.original(loaded)
        };
        match sample_type {
            SampleType::Float => v,
            SampleType::Uint8 | SampleType::Uint16 | SampleType::Int => v.round(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ends_of_a_stretched_range_map_back_exactly() {
        let (lo, hi) = (-1009.1298258161181, 1348.4731943662143);
        let map = IntensityMap::stretched(lo, hi);
        assert_ne!(map.original(1.0), hi, "lo + (hi − lo) rounds here");
        assert_eq!(map.original_sample(1.0, SampleType::Float), hi);
        assert_eq!(map.original_sample(0.0, SampleType::Float), lo);
    }

    #[test]
    fn integer_samples_map_back_to_integers() {
        let loaded = f64::from(1234.0f32 / 65535.0);
        let map = IntensityMap::unsigned(16);
        assert_ne!(map.original(loaded), 1234.0);
        assert_eq!(map.original_sample(loaded, SampleType::Uint16), 1234.0);
    }
}
