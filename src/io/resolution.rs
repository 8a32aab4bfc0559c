//! Pixel sizes stored in image files: the PNG `pHYs` chunk, the TIFF
//! resolution tags, Fiji/ImageJ's metadata and the OME-XML of an OME-TIFF.
//! Read separately from the pixels, so that every decoder can ignore them.

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
    image_frame_and_warnings(path, width, height).0
}

/// [`image_frame`], with the warnings of reading the pixel size (an OME-XML
/// description whose sizes cannot be used, see [`TiffSizes::warnings`]).
pub fn image_frame_and_warnings(path: &Path, width: usize, height: usize) -> (Frame, Vec<String>) {
    let tiff = is_tiff(path);
    let (res, source, warnings) = if tiff {
        let sizes = File::open(path)
            .ok()
            .and_then(|f| tiff::decoder::Decoder::new(BufReader::new(f)).ok())
            .map(|mut d| tiff_sizes(&mut d, path))
            .unwrap_or_default();
        (sizes.resolution, sizes.source, sizes.warnings)
    } else {
        (png_resolution(path), FrameSource::PngPhys, Vec::new())
    };
    let (spacing, unit, source) = match res {
        Some(r) => ([r.spacing[0], r.spacing[1]], r.unit, source),
        None => ([1.0, 1.0], "px".to_string(), FrameSource::Default),
    };
    let frame = if tiff {
        Frame::image_rows_down(width, height, spacing, &unit)
    } else {
        Frame::image_rows_up(width, height, spacing, &unit)
    };
    (frame.with_source(source), warnings)
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

/// The pixel size of a TIFF page as [`tiff_sizes`] reads it.
#[derive(Clone, Debug, PartialEq)]
pub struct TiffSizes {
    /// The pixel/voxel size; `None` when the page has no usable one.
    pub resolution: Option<Resolution>,
    /// Where it came from: [`FrameSource::OmeXml`],
    /// [`FrameSource::TiffResolution`] (the resolution tags and ImageJ's
    /// description), or [`FrameSource::Default`] without one.
    pub source: FrameSource,
    /// Whether the z step is the file's (ImageJ's `spacing=`, OME's
    /// `PhysicalSizeZ`) rather than 1 in the unit of x and y.
    pub z_given: bool,
    /// One line each, naming the file: why an OME-XML description's sizes
    /// were not used (malformed XML, a size that is not a positive length,
    /// a unit that is not a length) and what was read instead.
    pub warnings: Vec<String>,
}

impl Default for TiffSizes {
    fn default() -> Self {
        TiffSizes {
            resolution: None,
            source: FrameSource::Default,
            z_given: false,
            warnings: Vec::new(),
        }
    }
}

/// The pixel size of the current TIFF page of `path`.
///
/// An OME-TIFF's OME-XML description (`PhysicalSizeX`/`Y`/`Z` of its first
/// `Pixels` element, each in its `PhysicalSize…Unit`, micrometres when not
/// given) comes first: x or y alone stands for both, and without
/// `PhysicalSizeZ` the z step is 1 (as without ImageJ's `spacing=`).
/// Otherwise, or when the OME-XML cannot be used (with a warning), the
/// tags: x/y from `XResolution`/`YResolution` (pixels per unit; inches and
/// centimetres become mm, as `vtkTIFFReader` does), and for Fiji/ImageJ
/// files the unit and z step from the `ImageJ=` description (`unit=`,
/// `spacing=`).
pub fn tiff_sizes<R: Read + Seek>(dec: &mut tiff::decoder::Decoder<R>, path: &Path) -> TiffSizes {
    let description = description(dec);
    let tags = tag_resolution(dec, description.as_deref());
    let from_tags = |warnings: Vec<String>| {
        let source = if tags.is_some() {
            FrameSource::TiffResolution
        } else {
            FrameSource::Default
        };
        let z_given = tags.as_ref().is_some_and(|t| t.1);
        TiffSizes {
            resolution: tags.clone().map(|t| t.0),
            source,
            z_given,
            warnings,
        }
    };
    let fallback = |why: &str| {
        let instead = match &tags {
            Some((r, _)) if r.unit != "px" => format!(
                "the pixel size is read from its TIFF resolution tags instead ({} × {} {})",
                r.spacing[0], r.spacing[1], r.unit
            ),
            Some(_) => "its TIFF resolution tags are read instead, which give no length unit \
                        (--spacing gives the size)"
                .into(),
            None => "no pixel size is read (--spacing gives one)".into(),
        };
        from_tags(vec![format!(
            "{}: its OME-XML description {why}; {instead}",
            path.display()
        )])
    };
    match description.as_deref().and_then(ome_sizes) {
        None => from_tags(Vec::new()),
        Some(Err(why)) => fallback(&why),
        Some(Ok(OmeSizes {
            sizes: [x, y, z],
            unit,
        })) => match (x.or(y), y.or(x)) {
            (Some(x), Some(y)) => TiffSizes {
                resolution: Some(Resolution {
                    spacing: [x, y, z.unwrap_or(1.0)],
                    unit,
                }),
                source: FrameSource::OmeXml,
                z_given: z.is_some(),
                warnings: Vec::new(),
            },
            _ if z.is_some() => {
                fallback("gives PhysicalSizeZ but neither PhysicalSizeX nor PhysicalSizeY")
            }
            // OME-XML without physical sizes (tifffile's when given none).
            _ => from_tags(Vec::new()),
        },
    }
}

/// The page's `ImageDescription`, if it has one.
fn description<R: Read + Seek>(dec: &mut tiff::decoder::Decoder<R>) -> Option<String> {
    match dec.find_tag(tiff::tags::Tag::ImageDescription) {
        Ok(Some(tiff::decoder::ifd::Value::Ascii(d))) => Some(d),
        _ => None,
    }
}

/// The pixel size from the page's tags and ImageJ description (see
/// [`tiff_sizes`]), `None` when the page has no usable resolution; and
/// whether the z step came from the description (ImageJ's `spacing=`).
fn tag_resolution<R: Read + Seek>(
    dec: &mut tiff::decoder::Decoder<R>,
    description: Option<&str>,
) -> Option<(Resolution, bool)> {
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
    let desc = description.filter(|d| d.starts_with("ImageJ="));
    let field = |key: &str| {
        desc?
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
        .map(|v| v * scale);
    Some((
        Resolution {
            spacing: [x * scale, y * scale, z.unwrap_or(1.0)],
            unit,
        },
        z.is_some(),
    ))
}

/// The physical pixel sizes an OME-XML description gives.
#[derive(Clone, Debug, PartialEq)]
pub struct OmeSizes {
    /// `PhysicalSizeX`, `PhysicalSizeY`, `PhysicalSizeZ` in [`OmeSizes::unit`]
    /// (`None` where not given).
    pub sizes: [Option<f64>; 3],
    /// Their length unit in short form (`"um"`, `"nm"`, …): that of the
    /// first size given, the others converted to it.
    pub unit: String,
}

/// The physical sizes of the first `Pixels` element of an OME-XML
/// description. `None` when the description is not OME-XML (no XML whose
/// root is `OME`); `Some(Err(why))` when it is but its sizes cannot be used:
/// it is not well-formed, has no `Pixels` element, or gives a size that is
/// not a positive number or a unit that is not a length (`why` completes
/// "its OME-XML description …").
pub fn ome_sizes(description: &str) -> Option<Result<OmeSizes, String>> {
    let doc = match super::ome::document(description)? {
        Ok(doc) => doc,
        Err(why) => return Some(Err(why)),
    };
    let Some(pixels) = super::ome::first_pixels(&doc) else {
        return Some(Err("has no Pixels element".into()));
    };
    const AXES: [(&str, &str); 3] = [
        ("PhysicalSizeX", "PhysicalSizeXUnit"),
        ("PhysicalSizeY", "PhysicalSizeYUnit"),
        ("PhysicalSizeZ", "PhysicalSizeZUnit"),
    ];
    let mut given = [None; 3];
    for (c, (size, unit)) in AXES.iter().enumerate() {
        let Some(value) = pixels.attribute(*size) else {
            continue;
        };
        let v = match value.trim().parse::<f64>() {
            Ok(v) if v.is_finite() && v > 0.0 => v,
            _ => {
                return Some(Err(format!(
                    "gives {size}=\"{value}\", not a positive length"
                )))
            }
        };
        // OME's default length unit is the micrometre.
        let name = pixels.attribute(*unit).unwrap_or("µm");
        let Some((short, factor)) = ome_length_unit(name) else {
            return Some(Err(format!(
                "gives {unit}=\"{name}\", not a length unit read here (m, cm, mm, µm, nm, pm, \
                 Å or in)"
            )));
        };
        given[c] = Some((v * factor, short));
    }
    let unit = given.iter().flatten().map(|g| g.1).next().unwrap_or("um");
    let sizes = given.map(|g| g.map(|(v, u)| convert(v, u, unit)));
    Some(Ok(OmeSizes {
        sizes,
        unit: unit.to_string(),
    }))
}

/// An OME length unit (`UnitsLength`) as a short unit that
/// [`millimetres_per`] knows and the factor into it; `None` for units that
/// are not lengths (`"pixel"`) or not read here.
fn ome_length_unit(name: &str) -> Option<(&'static str, f64)> {
    Some(match name.trim() {
        "m" => ("m", 1.0),
        "cm" => ("cm", 1.0),
        "mm" => ("mm", 1.0),
        // The micro sign, the Greek mu, and the ASCII spellings.
        "\u{b5}m" | "\u{3bc}m" | "um" | "micron" => ("um", 1.0),
        "nm" => ("nm", 1.0),
        "pm" => ("nm", 1e-3),
        // The Latin letter and the Ångström sign.
        "\u{c5}" | "\u{212b}" => ("nm", 0.1),
        "in" | "inch" => ("inch", 1.0),
        _ => return None,
    })
}

/// `v` in unit `from` as a length in unit `to` (both known to
/// [`millimetres_per`]); a power-of-ten ratio is applied exactly, so that
/// 2 µm is 2000 nm rather than 2000.0000000000002.
fn convert(v: f64, from: &str, to: &str) -> f64 {
    let (Some(a), Some(b)) = (millimetres_per(from), millimetres_per(to)) else {
        return v;
    };
    let ratio = a / b;
    let exponent = ratio.log10().round() as i32;
    if (ratio / 10f64.powi(exponent) - 1.0).abs() < 1e-9 {
        if exponent >= 0 {
            v * 10f64.powi(exponent)
        } else {
            v / 10f64.powi(-exponent)
        }
    } else {
        v * ratio
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A minimal OME-XML with these `Pixels` attributes.
    fn ome(attributes: &str) -> String {
        format!(
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\
             <OME xmlns=\"http://www.openmicroscopy.org/Schemas/OME/2016-06\">\
             <Image ID=\"Image:0\"><Pixels ID=\"Pixels:0\" SizeX=\"4\" {attributes}/>\
             </Image></OME>"
        )
    }

    fn sizes(attributes: &str) -> OmeSizes {
        ome_sizes(&ome(attributes)).unwrap().unwrap()
    }

    fn why(attributes: &str) -> String {
        ome_sizes(&ome(attributes)).unwrap().unwrap_err()
    }

    #[test]
    fn ome_sizes_default_to_micrometres_and_take_x_s_unit() {
        let s = sizes(r#"PhysicalSizeX="0.5" PhysicalSizeY="0.5" PhysicalSizeZ="2.0""#);
        assert_eq!(s.sizes, [Some(0.5), Some(0.5), Some(2.0)]);
        assert_eq!(s.unit, "um");
        let s = sizes(
            r#"PhysicalSizeX="0.5" PhysicalSizeXUnit="μm" PhysicalSizeZ="2000" PhysicalSizeZUnit="nm""#,
        );
        assert_eq!(s.sizes, [Some(0.5), None, Some(2.0)]);
        assert_eq!(s.unit, "um");
        let s = sizes(
            r#"PhysicalSizeX="500" PhysicalSizeXUnit="nm" PhysicalSizeY="5" PhysicalSizeYUnit="Å" PhysicalSizeZ="2" PhysicalSizeZUnit="µm""#,
        );
        assert_eq!(s.sizes, [Some(500.0), Some(0.5), Some(2000.0)]);
        assert_eq!(s.unit, "nm");
        let s = sizes(
            r#"PhysicalSizeX="0.1" PhysicalSizeXUnit="mm" PhysicalSizeZ="0.05" PhysicalSizeZUnit="cm""#,
        );
        assert_eq!(s.sizes, [Some(0.1), None, Some(0.5)]);
        assert_eq!(s.unit, "mm");
        let s = sizes(r#"PhysicalSizeX="0.01" PhysicalSizeXUnit="in""#);
        assert_eq!((s.sizes[0], s.unit.as_str()), (Some(0.01), "inch"));
        assert_eq!(sizes("").sizes, [None; 3]);
    }

    #[test]
    fn sizes_that_are_no_lengths_are_refused_with_the_reason() {
        for bad in ["0", "-0.5", "NaN", "inf", "", "half"] {
            let reason = why(&format!(r#"PhysicalSizeX="{bad}""#));
            assert_eq!(
                reason,
                format!(r#"gives PhysicalSizeX="{bad}", not a positive length"#)
            );
        }
        let reason = why(r#"PhysicalSizeX="1" PhysicalSizeXUnit="pixel""#);
        assert!(reason.starts_with(r#"gives PhysicalSizeXUnit="pixel", not a length unit"#));
        let reason = why(r#"PhysicalSizeZ="1" PhysicalSizeZUnit="reference frame""#);
        assert!(reason.contains("PhysicalSizeZUnit"), "{reason}");
    }

    #[test]
    fn malformed_or_other_descriptions() {
        let whole = ome(r#"PhysicalSizeX="0.5""#);
        let cut = &whole[..whole.len() - 12];
        assert!(ome_sizes(cut)
            .unwrap()
            .unwrap_err()
            .starts_with("is not well-formed XML ("));
        let no_pixels = "<OME><Image ID=\"Image:0\"/></OME>";
        assert_eq!(
            ome_sizes(no_pixels),
            Some(Err("has no Pixels element".to_string()))
        );
        // Not OME-XML: ImageJ's description, other XML, plain text.
        assert_eq!(ome_sizes("ImageJ=1.54f\nunit=micron\nspacing=2\n"), None);
        assert_eq!(
            ome_sizes("<Metadata><Pixels PhysicalSizeX=\"1\"/></Metadata>"),
            None
        );
        assert_eq!(ome_sizes("<not xml"), None);
        assert_eq!(ome_sizes("{\"shape\": [2, 8, 32]}"), None);
    }

    #[test]
    fn unit_conversions_by_powers_of_ten_are_exact() {
        assert_eq!(convert(2.0, "um", "nm"), 2000.0);
        assert_eq!(convert(500.0, "nm", "um"), 0.5);
        assert_eq!(convert(3.0, "cm", "um"), 30_000.0);
        assert_eq!(convert(1.0, "inch", "mm"), 25.4);
    }
}
