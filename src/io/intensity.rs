//! How loaded intensities map back to the file's own values.

use serde::Serialize;

/// `original = offset + scale · loaded`: loaded intensities lie in `[0, 1]`
/// (8-bit data divided by 255, 16-bit by 65535, anything else stretched
/// from its minimum and maximum), and measurements report the file's units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct IntensityMap {
    /// The original value of a loaded 0.
    pub offset: f64,
    /// The original range of a loaded unit step.
    pub scale: f64,
}

impl IntensityMap {
    /// Loaded values are the original ones.
    pub const IDENTITY: IntensityMap = IntensityMap {
        offset: 0.0,
        scale: 1.0,
    };

    /// Unsigned integers of `bits` bits divided by their maximum.
    pub fn unsigned(bits: u32) -> Self {
        IntensityMap {
            offset: 0.0,
            scale: ((1u64 << bits) - 1) as f64,
        }
    }

    /// Values stretched from `[lo, hi]` to `[0, 1]` (a constant volume: `lo`).
    pub fn stretched(lo: f64, hi: f64) -> Self {
        IntensityMap {
            offset: lo,
            scale: if hi > lo { hi - lo } else { 0.0 },
        }
    }

    /// The map of a 2D image file as the image decoder loads it: 8-bit
    /// samples (gray or colour) divided by 255, 16-bit by 65535; `None`
    /// for other sample types or a file that does not open.
    pub fn of_image_file(path: &std::path::Path) -> Option<Self> {
        use image::ImageDecoder as _;
        let reader = image::ImageReader::open(path)
            .ok()?
            .with_guessed_format()
            .ok()?;
        use image::ColorType as C;
        match reader.into_decoder().ok()?.color_type() {
            C::L8 | C::La8 | C::Rgb8 | C::Rgba8 => Some(IntensityMap::unsigned(8)),
            C::L16 | C::La16 | C::Rgb16 | C::Rgba16 => Some(IntensityMap::unsigned(16)),
            _ => None,
        }
    }

    /// The original value of a loaded one.
    pub fn original(&self, loaded: f64) -> f64 {
        self.offset + self.scale * loaded
    }
}
