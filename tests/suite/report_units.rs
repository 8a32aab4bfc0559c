//! `report.json` says the unit of every intensity it gives: the `input`
//! block has the same shape in 2D and 3D (sample type, exact value range and
//! phase means in the file's units, the means also on `[0, 1]`, and the unit
//! of the report's other intensities), and the per-phase measurements are
//! labelled with the unit they are in.

use crate::cli::{bin, tmp};
use crate::common::save_f32_tiff;
use serde_json::Value;
use std::path::Path;

/// A `size²` image: a centred square at `inside`, the rest at `outside`,
/// plus a small deterministic texture of amplitude `texture`.
fn square(size: usize, outside: f64, inside: f64, texture: f64) -> Vec<f64> {
    (0..size * size)
        .map(|i| {
            let (x, y) = (i % size, i / size);
            let q = size / 4;
            let level = if (q..size - q).contains(&x) && (q..size - q).contains(&y) {
                inside
            } else {
                outside
            };
            level + texture * (((x * 7 + y * 13) % 5) as f64 - 2.0) / 2.0
        })
        .collect()
}

fn save_u16_png(path: &Path, size: usize, data: &[f64]) {
    let data: Vec<u16> = data.iter().map(|&v| v.round() as u16).collect();
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(size as u32, size as u32, data)
        .unwrap()
        .save(path)
        .unwrap();
}

/// Runs `dsc-seg ARGS --quiet --outputs report --out OUT` and reads the report.
fn report(args: &[&std::ffi::OsStr], out: &Path) -> Value {
    let o = bin()
        .args(args)
        .args(["--quiet", "--outputs", "report", "--out"])
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap()
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|m| m.as_f64().unwrap())
        .collect()
}

/// A float TIFF is loaded as it is: its means are in its own units, and
/// every part of the report says so (they were labelled "normalised").
#[test]
fn a_float_tiff_reports_its_means_in_its_own_units_and_says_so() {
    let d = tmp();
    let path = d.path().join("f.tif");
    let data: Vec<f32> = square(32, 0.0, 1000.0, 20.0)
        .iter()
        .map(|&v| v as f32)
        .collect();
    save_f32_tiff(&path, 32, &data);
    let r = report(&["segment".as_ref(), path.as_os_str()], &d.path().join("o"));
    let input = &r["input"];
    assert_eq!(input["sample_type"], "float");
    assert_eq!(input["intensity_unit"], "file");
    assert_eq!(input["loaded_unit"], "file");
    assert_eq!(r["phases"]["intensity_unit"], "file");
    let means = floats(&input["phase_means"]);
    assert!(
        means[0].abs() < 20.0 && (means[1] - 1000.0).abs() < 20.0,
        "{means:?}"
    );
    let phase_means: Vec<f64> = r["phases"]["phases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["mean"].as_f64().unwrap())
        .collect();
    assert_eq!(phase_means, means);
    let normalised = floats(&input["phase_means_normalised"]);
    assert!(
        normalised[0] < 0.05 && normalised[1] > 0.95,
        "{normalised:?}"
    );
}

/// A folder of 16-bit PNG slices is a volume in the slices' units (its
/// means were the values ÷ 65535, labelled "normalised").
#[test]
fn a_folder_of_16_bit_slices_reports_its_means_in_its_own_units() {
    let d = tmp();
    let dir = d.path().join("slices");
    std::fs::create_dir(&dir).unwrap();
    let n = 16;
    for z in 0..n {
        let inside = if (4..12).contains(&z) {
            30_000.0
        } else {
            10_000.0
        };
        save_u16_png(
            &dir.join(format!("s{z:02}.png")),
            n,
            &square(n, 10_000.0, inside, 200.0),
        );
    }
    let r = report(
        &["segment3d".as_ref(), dir.as_os_str()],
        &d.path().join("o"),
    );
    let input = &r["input"];
    assert_eq!(input["sample_type"], "uint16");
    assert_eq!(input["intensity_unit"], "file");
    assert_eq!(input["loaded_unit"], "normalised");
    assert_eq!(r["phases"]["intensity_unit"], "file");
    // The extremes exactly as stored (not 9799.99999... from value ÷ 65535).
    assert_eq!(input["min"].as_f64(), Some(9_800.0));
    assert_eq!(input["max"].as_f64(), Some(30_200.0));
    let means = floats(&input["phase_means"]);
    assert!((means[0] - 10_000.0).abs() < 50.0, "{means:?}");
    assert!((means[1] - 30_000.0).abs() < 50.0, "{means:?}");
}

/// The `input` block has the same fields in 2D and in 3D.
#[test]
fn the_input_block_has_one_shape_in_2d_and_3d() {
    let d = tmp();
    let keys = |v: &Value| -> Vec<String> { v.as_object().unwrap().keys().cloned().collect() };
    let r2 = report(
        &["segment", "--phantom-size", "32"].map(std::ffi::OsStr::new),
        &d.path().join("o2"),
    );
    let r3 = report(
        &["segment3d", "--phantom-size", "16", "--max-iterations", "5"].map(std::ffi::OsStr::new),
        &d.path().join("o3"),
    );
    assert_eq!(keys(&r2["input"]), keys(&r3["input"]));
    for key in ["sample_type", "intensity_unit", "loaded_unit", "min", "max"] {
        assert!(r3["input"].get(key).is_some(), "3D input lacks {key}");
    }
}

/// A 16-bit image's range is given exactly as stored.
#[test]
fn a_16_bit_image_reports_its_exact_range() {
    let d = tmp();
    let path = d.path().join("i.png");
    save_u16_png(&path, 32, &square(32, 1000.0, 1234.0, 0.0));
    let r = report(&["segment".as_ref(), path.as_os_str()], &d.path().join("o"));
    assert_eq!(r["input"]["min"].as_f64(), Some(1000.0));
    assert_eq!(r["input"]["max"].as_f64(), Some(1234.0));
}

/// The report's `final_means` are those of the label values 0, 1, ...
/// (ascending), whatever the mesh's own label numbers: here the initial
/// label 0 is the bright half, so it is written as value 1.
#[test]
fn final_means_are_ordered_like_the_labels() {
    let d = tmp();
    let (w, h) = (32u32, 32u32);
    let image =
        image::GrayImage::from_fn(w, h, |x, _| image::Luma([if x < 16 { 200 } else { 50 }]));
    let init = image::GrayImage::from_fn(w, h, |x, _| image::Luma([u8::from(x >= 16)]));
    let (img, labels) = (d.path().join("i.png"), d.path().join("l.png"));
    image.save(&img).unwrap();
    init.save(&labels).unwrap();
    let r = report(
        &[
            "segment".as_ref(),
            img.as_os_str(),
            "--init-labels".as_ref(),
            labels.as_os_str(),
        ],
        &d.path().join("o"),
    );
    assert_eq!(
        r["phase_order"],
        serde_json::json!([1, 0]),
        "{}",
        r["phase_order"]
    );
    let means = floats(&r["final_means"]);
    assert!(means[0] < means[1], "{means:?}");
    assert_eq!(means, floats(&r["ordered_means"]));
}

/// labels.png keeps the pixel size of a PNG input's `pHYs` chunk.
#[test]
fn labels_png_keeps_the_input_pixel_size() {
    let d = tmp();
    let path = d.path().join("phys.png");
    {
        let file = std::fs::File::create(&path).unwrap();
        let mut encoder = png::Encoder::new(file, 32, 32);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_pixel_dims(Some(png::PixelDimensions {
            xppu: 2000,
            yppu: 4000,
            unit: png::Unit::Meter,
        }));
        let pixels: Vec<u8> = square(32, 50.0, 200.0, 4.0)
            .iter()
            .map(|&v| v as u8)
            .collect();
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(&pixels).unwrap();
    }
    assert_eq!(labels_png_pixels_per_metre(&path), (2000, 4000));
}

/// Segments `input` (labels only) and reads labels.png's `pHYs` chunk:
/// pixels per metre along x and y.
fn labels_png_pixels_per_metre(input: &Path) -> (u32, u32) {
    let out = input.with_extension("out");
    let o = bin()
        .args(["segment", "--quiet", "--outputs", "labels", "--out"])
        .arg(&out)
        .arg(input)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let file = std::fs::File::open(out.join("labels.png")).unwrap();
    let reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let dims = reader.info().pixel_dims.expect("a pHYs chunk");
    assert_eq!(dims.unit, png::Unit::Meter);
    (dims.xppu, dims.yppu)
}

/// labels.png carries a micrometre pixel size too: an ImageJ TIFF at 4
/// pixels per micron gets 4 000 000 pixels per metre.
#[test]
fn labels_png_keeps_a_micrometre_pixel_size() {
    use tiff::encoder::{colortype::Gray8, Rational, TiffEncoder};
    use tiff::tags::{ResolutionUnit, Tag};
    let d = tmp();
    let path = d.path().join("micrograph.tif");
    {
        let pixels: Vec<u8> = square(32, 50.0, 200.0, 4.0)
            .iter()
            .map(|&v| v as u8)
            .collect();
        let mut enc = TiffEncoder::new(std::fs::File::create(&path).unwrap()).unwrap();
        let mut page = enc.new_image::<Gray8>(32, 32).unwrap();
        page.encoder()
            .write_tag(Tag::ImageDescription, "ImageJ=1.54f\nunit=micron\n")
            .unwrap();
        page.resolution(ResolutionUnit::None, Rational { n: 4, d: 1 });
        page.write_data(&pixels).unwrap();
    }
    assert_eq!(labels_png_pixels_per_metre(&path), (4_000_000, 4_000_000));
}
