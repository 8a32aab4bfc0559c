//! NumPy arrays to the library's images and volumes, loaded as the file
//! readers load the same samples, with the array's type and the map back to
//! its values, so that `report.json` gives the input's range and the phase
//! means in the array's own units (HU for a CT array): unsigned 8-bit
//! divided by 255, unsigned 16-bit by 65535; in 2D every other type kept as
//! it is (as a float or signed TIFF); in 3D every other type mapped by its
//! own minimum and maximum to `[0, 1]` (as the volume reader does).

use dsc_seg::io::intensity::IntensityMap;
use dsc_seg::io::{
    min_max_normalise, wide_samples_as_f32, Image2, NonFiniteSamples, SampleType, Volume,
};
use numpy::{PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// An array's samples as loaded, with how it stored them.
struct Loaded {
    /// The array's shape (slowest axis first).
    shape: Vec<usize>,
    /// The loaded intensities in C order.
    data: Vec<f32>,
    /// The array's element type, as a file's sample type.
    sample_type: SampleType,
    /// Loaded intensities back to the array's values.
    map: IntensityMap,
}

/// How the samples of an element type are loaded.
enum Loading {
    /// Divided by the type's maximum (`bits` bits, unsigned).
    Unsigned(u32),
    /// Kept as they are in 2D, stretched by their range in 3D.
    AsStored,
}

/// The samples of `array` as loaded.
fn load(array: &Bound<'_, PyAny>, three_d: bool) -> PyResult<Loaded> {
    macro_rules! try_types {
        ($(($t:ty, $sample_type:expr, $loading:expr)),*) => {$(
            if let Ok(a) = array.extract::<PyReadonlyArrayDyn<'_, $t>>() {
                let shape = a.shape().to_vec();
                let samples = a.as_array();
                let samples = samples.iter().map(|&s| s as f64);
                return match $loading {
                    Unsigned(bits) => Ok(unsigned(shape, samples, bits, $sample_type)),
                    AsStored => as_stored(shape, samples.collect(), $sample_type, three_d),
                };
            }
        )*};
    }
    use Loading::{AsStored, Unsigned};
    use SampleType::{Float, Int, Uint16, Uint8};
    try_types!(
        (u8, Uint8, Unsigned(8)),
        (u16, Uint16, Unsigned(16)),
        (f32, Float, AsStored),
        (f64, Float, AsStored),
        (i8, Int, AsStored),
        (i16, Int, AsStored),
        (i32, Int, AsStored),
        (i64, Int, AsStored),
        (u32, Int, AsStored),
        (u64, Int, AsStored)
    );
    let dtype = array
        .getattr("dtype")
        .map(|d| d.to_string())
        .unwrap_or_else(|_| "unknown".into());
    Err(PyValueError::new_err(format!(
        "unsupported array type {dtype}: expected an integer or floating-point array"
    )))
}

/// Unsigned `bits`-bit samples divided by the type's maximum, straight to
/// `f32` (a 256³ uint8 volume never exists as 64-bit floats).
fn unsigned(
    shape: Vec<usize>,
    samples: impl Iterator<Item = f64>,
    bits: u32,
    sample_type: SampleType,
) -> Loaded {
    let map = IntensityMap::unsigned(bits);
    let scale = map.scale();
    Loaded {
        shape,
        data: samples.map(|s| (s / scale) as f32).collect(),
        sample_type,
        map,
    }
}

/// Float and signed or wide samples: kept as they are in 2D (refused where
/// not finite or where `f32` would round them), stretched by their range in
/// 3D.
fn as_stored(
    shape: Vec<usize>,
    raw: Vec<f64>,
    sample_type: SampleType,
    three_d: bool,
) -> PyResult<Loaded> {
    let (data, map) = if three_d {
        min_max_normalise(&raw).map_err(|e| PyValueError::new_err(e.to_string()))?
    } else {
        let count = raw.iter().filter(|s| !s.is_finite()).count();
        if count > 0 {
            let refused = NonFiniteSamples {
                count,
                total: raw.len(),
            };
            return Err(PyValueError::new_err(refused.to_string()));
        }
        let data = wide_samples_as_f32(raw.iter().copied())
            .map_err(|reason| PyValueError::new_err(format!("the array: {reason}")))?;
        (data, IntensityMap::IDENTITY)
    };
    Ok(Loaded {
        shape,
        data,
        sample_type,
        map,
    })
}

/// A 2D array (rows × columns) as an image of the array's sample type.
pub fn image(array: &Bound<'_, PyAny>) -> PyResult<Image2> {
    let a = load(array, false)?;
    Ok(Image2::from_raw(a.shape[1], a.shape[0], a.data).with_sample_type(a.sample_type))
}

/// A 3D array (slices × rows × columns) as a volume of the array's sample
/// type, with the map back to its values.
pub fn volume(array: &Bound<'_, PyAny>) -> PyResult<Volume> {
    let a = load(array, true)?;
    let [nz, ny, nx] = [a.shape[0], a.shape[1], a.shape[2]];
    Ok(Volume::from_raw(nx, ny, nz, a.data)
        .with_sample_type(a.sample_type)
        .with_intensity(a.map))
}
