//! Pixel sizes stored in image files: the PNG `pHYs` chunk, the TIFF
//! resolution tags and Fiji/ImageJ's metadata. Read separately from the
//! pixels, so that every decoder can ignore them.

use std::fs::File;
use std::io::{BufReader, Read, Seek};
use std::path::Path;

use super::frame::{Frame, FrameSource};

/// A physical pixel/voxel size and its unit.
#[derive(Clone, Debug, PartialEq)]
pub struct Resolution {
    /// Size along x, y, z (z = 1 unless the file gives it).
    pub spacing: [f64; 3],
    /// Length unit (`"mm"`, `"um"`, …).
    pub unit: String,
}

/// The frame of a 2D image file as VTK's readers show it: TIFF rows
/// downwards, every other format rows upwards (see [`Frame`]), with the
/// file's pixel size when it has one.
pub fn image_frame(path: &Path, width: usize, height: usize) -> Frame {
    let tiff = is_tiff(path);
    let res = if tiff {
        File::open(path)
            .ok()
            .and_then(|f| tiff::decoder::Decoder::new(BufReader::new(f)).ok())
            .and_then(|mut d| tiff_resolution(&mut d))
    } else {
        png_resolution(path)
    };
    let (spacing, unit, source) = match res {
        Some(r) => {
            let source = if tiff {
                FrameSource::TiffResolution
            } else {
                FrameSource::PngPhys
            };
            ([r.spacing[0], r.spacing[1]], r.unit, source)
        }
        None => ([1.0, 1.0], "px".to_string(), FrameSource::Default),
    };
    let frame = if tiff {
        Frame::image_rows_down(width, height, spacing, &unit)
    } else {
        Frame::image_rows_up(width, height, spacing, &unit)
    };
    frame.with_source(source)
}

/// Whether the file name says TIFF.
pub fn is_tiff(path: &Path) -> bool {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .is_some_and(|e| e == "tif" || e == "tiff")
}

/// The `pHYs` chunk of a PNG in metres, as millimetres; `None` without one
/// or with an unspecified unit (an aspect ratio only).
fn png_resolution(path: &Path) -> Option<Resolution> {
    let file = File::open(path).ok()?;
    let reader = png::Decoder::new(BufReader::new(file)).read_info().ok()?;
    let dims = reader.info().pixel_dims?;
    if dims.unit != png::Unit::Meter || dims.xppu == 0 || dims.yppu == 0 {
        return None;
    }
    Some(Resolution {
        spacing: [1000.0 / dims.xppu as f64, 1000.0 / dims.yppu as f64, 1.0],
        unit: "mm".into(),
    })
}

/// The pixel size of the current TIFF page: x/y from `XResolution`/
/// `YResolution` (pixels per unit; inches and centimetres become mm, as
/// `vtkTIFFReader` does), and for Fiji/ImageJ files the unit and z step
/// from the `ImageJ=` description (`unit=`, `spacing=`). `None` when the
/// page has no usable resolution.
pub fn tiff_resolution<R: Read + Seek>(dec: &mut tiff::decoder::Decoder<R>) -> Option<Resolution> {
    use tiff::decoder::ifd::Value;
    use tiff::tags::Tag;
    let valid = |v: f64| v.is_finite() && v > 0.0;
    let per_unit = |dec: &mut tiff::decoder::Decoder<R>, tag| match dec.find_tag(tag) {
        Ok(Some(Value::Rational(n, d))) if n > 0 => Some(f64::from(d) / f64::from(n)),
        _ => None,
    };
    let x = per_unit(dec, Tag::XResolution).filter(|&v| valid(v))?;
    let y = per_unit(dec, Tag::YResolution)
        .filter(|&v| valid(v))
        .unwrap_or(x);
    let desc = match dec.find_tag(Tag::ImageDescription) {
        Ok(Some(Value::Ascii(d))) if d.starts_with("ImageJ=") => Some(d),
        _ => None,
    };
    let field = |key: &str| {
        desc.as_deref()?
            .lines()
            .find_map(|l| l.strip_prefix(key))
            .map(|v| v.trim().to_string())
    };
    // TIFF's default unit is the inch; ImageJ writes "none" and names its own.
    let imagej = field("unit=").map(|u| imagej_unit(&u));
    let (scale, unit) = match (dec.find_tag_unsigned::<u16>(Tag::ResolutionUnit), imagej) {
        (Ok(Some(3)), _) => (10.0, "mm".to_string()),
        (Ok(Some(1)), u) | (Ok(None), u @ Some(_)) => (1.0, u.unwrap_or_else(|| "px".into())),
        _ => (25.4, "mm".to_string()),
    };
    let z = field("spacing=")
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|&v| valid(v))
        .map_or(1.0, |v| v * scale);
    Some(Resolution {
        spacing: [x * scale, y * scale, z],
        unit,
    })
}

/// Millimetres in one `unit` (a [`Resolution`]'s short form), or `None`
/// for a unit that is not a length (`"px"`) or not known.
pub fn millimetres_per(unit: &str) -> Option<f64> {
    match unit {
        "mm" => Some(1.0),
        "um" => Some(1e-3),
        "nm" => Some(1e-6),
        "cm" => Some(10.0),
        "m" => Some(1e3),
        "inch" => Some(25.4),
        _ => None,
    }
}

/// ImageJ's unit names in short form.
fn imagej_unit(u: &str) -> String {
    match u {
        "micron" | "\\u00B5m" | "µm" | "um" => "um".into(),
        "pixel" | "" => "px".into(),
        other => other.into(),
    }
}
