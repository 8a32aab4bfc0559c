//! NumPy arrays to the library's images and volumes, with the intensities
//! the file readers would give the same samples: unsigned 8-bit divided by
//! 255, unsigned 16-bit by 65535; floating-point images kept as they are in
//! 2D (as a float TIFF); every other type, and floating-point volumes, mapped
//! by their own minimum and maximum to `[0, 1]` (as the volume reader does).

use dsc_seg::io::{min_max_normalise, Image2, Volume};
use numpy::{PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// How a sample type maps to intensities.
enum Samples {
    /// Already the intensities.
    Direct(Vec<f32>),
    /// To be mapped by their range.
    Raw(Vec<f64>),
}

/// The samples of `array` in C order, with its shape.
fn samples(array: &Bound<'_, PyAny>, three_d: bool) -> PyResult<(Vec<usize>, Samples)> {
    macro_rules! scaled {
        ($t:ty, $scale:expr) => {
            if let Ok(a) = array.extract::<PyReadonlyArrayDyn<'_, $t>>() {
                let data = a.as_array().iter().map(|&s| s as f32 / $scale).collect();
                return Ok((a.shape().to_vec(), Samples::Direct(data)));
            }
        };
    }
    macro_rules! float {
        ($t:ty) => {
            if let Ok(a) = array.extract::<PyReadonlyArrayDyn<'_, $t>>() {
                let shape = a.shape().to_vec();
                if three_d {
                    let raw = a.as_array().iter().map(|&s| s as f64).collect();
                    return Ok((shape, Samples::Raw(raw)));
                }
                let data: Vec<f32> = a.as_array().iter().map(|&s| s as f32).collect();
                if data.iter().any(|s| !s.is_finite()) {
                    return Err(PyValueError::new_err("image holds NaN or infinite values"));
                }
                return Ok((shape, Samples::Direct(data)));
            }
        };
    }
    macro_rules! ranged {
        ($($t:ty),*) => {$(
            if let Ok(a) = array.extract::<PyReadonlyArrayDyn<'_, $t>>() {
                let raw = a.as_array().iter().map(|&s| s as f64).collect();
                return Ok((a.shape().to_vec(), Samples::Raw(raw)));
            }
        )*};
    }
    scaled!(u8, 255.0);
    scaled!(u16, 65535.0);
    float!(f32);
    float!(f64);
    ranged!(i8, i16, i32, i64, u32, u64);
    let dtype = array
        .getattr("dtype")
        .map(|d| d.to_string())
        .unwrap_or_else(|_| "unknown".into());
    Err(PyValueError::new_err(format!(
        "unsupported array type {dtype}: expected an integer or floating-point array"
    )))
}

/// The intensities of `samples`.
fn intensities(samples: Samples) -> PyResult<Vec<f32>> {
    match samples {
        Samples::Direct(v) => Ok(v),
        Samples::Raw(v) => min_max_normalise(&v)
            .map(|(samples, _)| samples)
            .map_err(|e| PyValueError::new_err(e.to_string())),
    }
}

/// A 2D array (rows × columns) as an image.
pub fn image(array: &Bound<'_, PyAny>) -> PyResult<Image2> {
    let (shape, s) = samples(array, false)?;
    Ok(Image2::from_raw(shape[1], shape[0], intensities(s)?))
}

/// A 3D array (slices × rows × columns) as a volume.
pub fn volume(array: &Bound<'_, PyAny>) -> PyResult<Volume> {
    let (shape, s) = samples(array, true)?;
    Ok(Volume::from_raw(
        shape[2],
        shape[1],
        shape[0],
        intensities(s)?,
    ))
}
