//! Inputs a new user brings: a NIfTI of one slice, images with an alpha
//! channel, label images of any sample type, and inputs the segmentation
//! refuses. Each gives a correct result or one error line naming its file.

use crate::cli::{bin, empty_out, fails, tmp, SEGMENT, SEGMENT3D};
use crate::common::save_f32_tiff;
use dsc_seg::io::{save_nifti, FrameSource, Volume};
use std::path::{Path, PathBuf};

/// Row-major `w × h` samples of a noisy bright disk (180) on a dark ground (70).
fn disk(w: u32, h: u32) -> Vec<u8> {
    let mut v = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let (dx, dy) = (x as f64 - w as f64 / 2.0, y as f64 - h as f64 / 2.0);
            let inside = dx * dx + dy * dy < (w.min(h) as f64 / 4.0).powi(2);
            v.push(if inside { 180 } else { 70 } + ((x * 7 + y * 13) % 11) as u8 * 3);
        }
    }
    v
}

/// Runs `dsc-seg ARGS --out OUT --quiet`, expects success, and returns the
/// report and stderr.
fn succeeds(args: &[&str], out: &Path) -> (serde_json::Value, String) {
    let o = bin()
        .args(args)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{args:?}: {err}");
    let report = std::fs::read(out.join("report.json")).unwrap();
    (serde_json::from_slice(&report).unwrap(), err)
}

/// A NIfTI one slice thick, placed by an affine that flips x and moves the
/// origin, is a 2D image to `segment`: its disk is found, and every output
/// is in the header's frame (pixel size, flip, origin); `segment3d` refuses
/// it in one line naming the file and the command that takes it.
#[test]
fn a_single_slice_nifti_is_a_2d_image() {
    let d = tmp();
    let p = d.path().join("slice.nii.gz");
    let affine = [
        [-0.5, 0.0, 0.0, 20.0],
        [0.0, 0.7, 0.0, -3.0],
        [0.0, 0.0, 2.0, 5.0],
    ];
    let data = disk(40, 30).iter().map(|&v| f32::from(v)).collect();
    let slice = Volume::from_raw(40, 30, 1, data)
        .with_spacing([0.5, 0.7, 2.0])
        .with_affine(affine, FrameSource::NiftiSform);
    save_nifti(&p, &slice).unwrap();
    let input = p.to_str().unwrap();

    let out = d.path().join("run");
    let (report, _) = succeeds(&["segment", input], &out);
    let frame = &report["frame"];
    assert_eq!(frame["dims"], serde_json::json!([40, 30, 1]));
    assert_eq!(
        frame["spacing"],
        serde_json::json!([0.5, 0.699999988079071, 2.0])
    );
    assert_eq!(frame["unit"], "mm");
    assert_eq!(frame["source"], "nifti_sform");
    assert_eq!(
        frame["index_to_world"][0],
        serde_json::json!([-0.5, 0.0, 0.0, 20.0])
    );
    assert_eq!(frame["index_to_world"][2][3], 5.0);
    let means = report["input"]["phase_means"].as_array().unwrap();
    assert!((means[0].as_f64().unwrap() - 85.0).abs() < 5.0, "{means:?}");
    assert!(
        (means[1].as_f64().unwrap() - 195.0).abs() < 5.0,
        "{means:?}"
    );
    let labels = image::open(out.join("labels.png")).unwrap().to_luma8();
    assert_eq!(labels.dimensions(), (40, 30));
    assert_eq!(labels.get_pixel(20, 15)[0], 1);
    assert_eq!(labels.get_pixel(1, 1)[0], 0);
    // labels.nii.gz: the same labels on the input's header (shape, affine).
    let map = Volume::load(out.join("labels.nii.gz")).unwrap();
    assert_eq!(map.dims(), [40, 30, 1]);
    assert_eq!(
        serde_json::json!(map.frame().index_to_world),
        frame["index_to_world"]
    );
    let phases: Vec<u8> = map
        .data()
        .iter()
        .map(|&v| (v * 255.0).round() as u8)
        .collect();
    assert_eq!(phases, labels.into_raw());
    // The disk's area, 7.5² π pixels, in mm² of the header's pixels.
    let area = report["phases"]["phases"][1]["count_measure"]
        .as_f64()
        .unwrap();
    let expected = std::f64::consts::PI * 7.5 * 7.5 * 0.5 * 0.7;
    assert!(
        (area / expected - 1.0).abs() < 0.1,
        "{area} mm² vs {expected}"
    );

    // --spacing replaces the pixel size; the origin stays where it was.
    let out = d.path().join("respaced");
    let (report, _) = succeeds(&["segment", input, "--spacing", "1,1"], &out);
    let a = &report["frame"]["index_to_world"];
    assert_eq!(a[0], serde_json::json!([-1.0, 0.0, 0.0, 20.0]));
    assert_eq!(a[1][3], -3.0);
    let map = Volume::load(out.join("labels.nii.gz")).unwrap();
    assert_eq!(map.frame().index_to_world[0], [-1.0, 0.0, 0.0, 20.0]);
    let [sx, sy, _] = map.spacing();
    assert!(
        (sx - 1.0).abs() < 1e-6 && (sy - 1.0).abs() < 1e-6,
        "{sx} {sy}"
    );

    let message = fails(&SEGMENT3D, &[input], &empty_out(&d), "dsc-seg segment`");
    assert!(
        message.contains("slice.nii.gz is 40×30×1 voxels"),
        "{message}"
    );
}

/// An RGBA PNG of the disk, its top-left `transparent` pixels with alpha 0.
fn rgba(dir: &Path, name: &str, transparent: u32) -> PathBuf {
    let p = dir.join(name);
    let gray = disk(32, 32);
    image::RgbaImage::from_fn(32, 32, |x, y| {
        let v = gray[(y * 32 + x) as usize];
        let alpha = if y * 32 + x < transparent { 0 } else { 255 };
        image::Rgba([v, v, v, alpha])
    })
    .save(&p)
    .unwrap();
    p
}

/// Pixels that are not fully opaque are segmented by their colour values
/// and the run says so, with their count, on stderr and in the report; a
/// fully opaque alpha, or the alpha channel taken itself, says nothing.
#[test]
fn transparent_pixels_are_named_in_a_warning() {
    let d = tmp();
    let partly = rgba(d.path(), "cutout.png", 40);
    let (report, err) = succeeds(&["segment", partly.to_str().unwrap()], &d.path().join("a"));
    let expected = "40 of the 1024 pixels of";
    assert!(err.contains(&format!("warning: {expected}")), "{err}");
    assert!(
        err.contains("not fully opaque (40 fully transparent)"),
        "{err}"
    );
    let warnings = report["warnings"].as_array().unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.as_str().unwrap().starts_with(expected)),
        "{warnings:?}"
    );

    let opaque = rgba(d.path(), "opaque.png", 0);
    let (_, err) = succeeds(&["segment", opaque.to_str().unwrap()], &d.path().join("b"));
    assert!(!err.contains("not fully opaque"), "{err}");
    let (_, err) = succeeds(
        &["segment", partly.to_str().unwrap(), "--channel", "3"],
        &d.path().join("c"),
    );
    assert!(!err.contains("not fully opaque"), "{err}");

    // 16-bit gray + alpha: alpha below 65535 counts; --channel 1 is its alpha.
    let p = d.path().join("gray_alpha16.png");
    let gray = disk(32, 32);
    image::ImageBuffer::<image::LumaA<u16>, _>::from_fn(32, 32, |x, y| {
        let alpha = if y < 2 { 30_000 } else { 65_535 };
        image::LumaA([u16::from(gray[(y * 32 + x) as usize]) * 256, alpha])
    })
    .save(&p)
    .unwrap();
    let (_, err) = succeeds(&["segment", p.to_str().unwrap()], &d.path().join("e"));
    assert!(err.contains("64 of the 1024 pixels"), "{err}");
    assert!(err.contains("(0 fully transparent)"), "{err}");
    assert!(err.contains("--channel 1"), "{err}");
}

/// Inputs the segmentation cannot take give one error line naming the file:
/// a constant image, one too small to mesh, fewer values than phases, a
/// constant volume.
#[test]
fn input_errors_name_the_file() {
    let d = tmp();
    let out = empty_out(&d);
    let save = |name: &str, w: u32, h: u32, f: &dyn Fn(u32, u32) -> u8| {
        let p = d.path().join(name);
        image::GrayImage::from_fn(w, h, |x, y| image::Luma([f(x, y)]))
            .save(&p)
            .unwrap();
        p.to_str().unwrap().to_string()
    };
    let flat = save("flat.png", 16, 16, &|_, _| 100);
    fails(&SEGMENT, &[&flat], &out, "flat.png: the image is constant");
    let dot = save("dot.png", 1, 1, &|_, _| 100);
    fails(&SEGMENT, &[&dot], &out, "dot.png: the image is 1×1 pixels");
    let two = save("two_levels.png", 16, 16, &|x, _| {
        if x < 8 {
            50
        } else {
            200
        }
    });
    fails(
        &SEGMENT,
        &[&two, "--phases", "4"],
        &out,
        "two_levels.png: the image has only 2 distinct intensities",
    );
    let volume = d.path().join("flat.tif");
    dsc_seg::io::save_labels_tiff(&volume, [8, 8, 8], &[7; 512], None).unwrap();
    fails(
        &SEGMENT3D,
        &[volume.to_str().unwrap()],
        &out,
        "flat.tif: the image is constant",
    );
}

/// A label image's values are its phases as the file stores them: a
/// 16-bit PNG's 1 is phase 1 (it was read as 1/65535 of the 8-bit range,
/// phase 0), a float TIFF's 1.0 is phase 1 (it was read as 255); a colour
/// image, whose luminance no one painted, is refused.
#[test]
fn init_labels_are_read_as_the_file_stores_them() {
    let d = tmp();
    let image = d.path().join("disk.png");
    image::GrayImage::from_raw(32, 32, disk(32, 32))
        .unwrap()
        .save(&image)
        .unwrap();
    let image = image.to_str().unwrap();
    let out = empty_out(&d);
    let half = |x: u32| u16::from(x >= 16);

    let sixteen = d.path().join("labels16.png");
    image::ImageBuffer::<image::Luma<u16>, _>::from_fn(32, 32, |x, _| image::Luma([2 * half(x)]))
        .save(&sixteen)
        .unwrap();
    fails(
        &SEGMENT,
        &[image, "--init-labels", sixteen.to_str().unwrap()],
        &out,
        "labels16.png use label 2, but labels must be below the number of phases (2): give \
         --phases 3 to use them all",
    );

    let float = d.path().join("labels.tif");
    let values: Vec<f32> = (0..32 * 32).map(|i| f32::from(half(i % 32))).collect();
    save_f32_tiff(&float, 32, &values);
    let float = float.to_str().unwrap();
    succeeds(
        &[
            "segment",
            image,
            "--init-labels",
            float,
            "--max-iterations",
            "2",
        ],
        &d.path().join("float"),
    );
    let fraction: Vec<f32> = values.iter().map(|v| v * 0.5).collect();
    let halves = d.path().join("halves.tif");
    save_f32_tiff(&halves, 32, &fraction);
    fails(
        &SEGMENT,
        &[image, "--init-labels", halves.to_str().unwrap()],
        &out,
        "hold the value 0.5, which is not a phase number",
    );

    let colour = d.path().join("painted.png");
    image::RgbImage::from_fn(32, 32, |x, _| image::Rgb([255 * half(x) as u8, 0, 0]))
        .save(&colour)
        .unwrap();
    fails(
        &SEGMENT,
        &[image, "--init-labels", colour.to_str().unwrap()],
        &out,
        "painted.png are a colour image",
    );
}

/// Writes `indices` (row-major `w × h`) as an indexed PNG with `palette` (RGB triples).
fn save_indexed_png(path: &Path, (w, h): (u32, u32), palette: &[u8], indices: &[u8]) {
    let mut encoder = png::Encoder::new(std::fs::File::create(path).unwrap(), w, h);
    encoder.set_color(png::ColorType::Indexed);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_palette(palette.to_vec());
    let mut writer = encoder.write_header().unwrap();
    writer.write_image_data(indices).unwrap();
}

/// A PNG whose palette holds only grays is a gray image: no note that it
/// is segmented as a luminance, `input.colour` gray, its values exactly the
/// grays; as `--init-labels`, its grays are the phases.
#[test]
fn a_palette_of_grays_is_a_gray_image() {
    let d = tmp();
    let grays: Vec<u8> = (0..=255u8).flat_map(|v| [v, v, v]).collect();
    let p = d.path().join("palette.png");
    save_indexed_png(&p, (32, 32), &grays, &disk(32, 32));
    let out = d.path().join("run");
    let (report, err) = succeeds(&["segment", p.to_str().unwrap()], &out);
    assert!(!err.contains("luminance"), "{err}");
    assert_eq!(report["input"]["colour"], "gray");
    assert_eq!(report["input"]["min"], 70.0);
    assert_eq!(report["input"]["max"], 210.0);

    let labels = d.path().join("labels.png");
    let halves: Vec<u8> = (0..32 * 32).map(|i| u8::from(i % 32 >= 16)).collect();
    save_indexed_png(&labels, (32, 32), &grays, &halves);
    let args = ["segment", p.to_str().unwrap(), "--init-labels"];
    succeeds(
        &[
            &args[..],
            &[labels.to_str().unwrap(), "--max-iterations", "2"],
        ]
        .concat(),
        &d.path().join("labelled"),
    );
}

/// A file of 0 bytes is said to be empty, not truncated, by both commands.
#[test]
fn an_empty_file_is_said_to_be_empty() {
    let d = tmp();
    let p = d.path().join("nothing.png");
    std::fs::write(&p, b"").unwrap();
    fails(
        &SEGMENT,
        &[p.to_str().unwrap()],
        &empty_out(&d),
        "nothing.png is not a readable image: the file is empty (0 bytes)",
    );
    for name in ["nothing.tif", "nothing.nii.gz"] {
        let p = d.path().join(name);
        std::fs::write(&p, b"").unwrap();
        let needle = format!("{name} is not a readable image: the file is empty (0 bytes)");
        let out = d.path().join(format!("out_{name}"));
        fails(&SEGMENT3D, &[p.to_str().unwrap()], &out, &needle);
    }
}

/// An animated GIF is a sequence, not one image: refused rather than
/// segmented as its first frame; a GIF of one frame is an image.
#[test]
fn an_animated_gif_is_refused() {
    let d = tmp();
    let save = |name: &str, frames: usize| {
        let p = d.path().join(name);
        let mut encoder = image::codecs::gif::GifEncoder::new(std::fs::File::create(&p).unwrap());
        for k in 0..frames {
            let gray = disk(32, 32);
            let rgba = image::RgbaImage::from_fn(32, 32, |x, y| {
                let v = gray[(y * 32 + x) as usize] / (k as u8 + 1);
                image::Rgba([v, v, v, 255])
            });
            encoder.encode_frame(image::Frame::new(rgba)).unwrap();
        }
        drop(encoder);
        p
    };
    let animated = save("movie.gif", 3);
    fails(
        &SEGMENT,
        &[animated.to_str().unwrap()],
        &empty_out(&d),
        "movie.gif is an animation of 2 or more frames",
    );
    let still = save("still.gif", 1);
    succeeds(
        &["segment", still.to_str().unwrap()],
        &d.path().join("still"),
    );
}

/// A NIfTI label map's values are its phases whatever its type: a float
/// (or int16) map of 0 and 1 was stretched to 0 and 255 and refused.
#[test]
fn a_nifti_label_map_is_read_as_stored() {
    let d = tmp();
    let n = 12;
    let inside = |i: usize| (n / 4..3 * n / 4).contains(&i);
    let cube = |x, y, z| u8::from(inside(x) && inside(y) && inside(z));
    let mut values = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                values.push(70 + 110 * cube(x, y, z) + ((x * 7 + y * 13 + z * 5) % 11) as u8 * 3);
            }
        }
    }
    let volume = d.path().join("cube.tif");
    dsc_seg::io::save_labels_tiff(&volume, [n; 3], &values, None).unwrap();
    let volume = volume.to_str().unwrap();
    let label_map = |name: &str, phase: f32| {
        let p = d.path().join(name);
        let labels = Volume::from_fn(n, n, n, |x, y, z| phase * f32::from(cube(x, y, z)));
        save_nifti(&p, &labels).unwrap();
        p.to_str().unwrap().to_string()
    };
    let ones = label_map("ones.nii.gz", 1.0);
    succeeds(
        &[
            "segment3d",
            volume,
            "--init-labels",
            &ones,
            "--max-iterations",
            "2",
        ],
        &d.path().join("run"),
    );
    let twos = label_map("twos.nii.gz", 2.0);
    fails(
        &SEGMENT3D,
        &[volume, "--init-labels", &twos],
        &empty_out(&d),
        "twos.nii.gz use label 2, but labels must be below the number of phases (2)",
    );
}
