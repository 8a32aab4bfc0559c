//! One channel at one time point of a multi-channel or time-lapse TIFF
//! (`--channel C`, `--time-point T`): only its pages are segmented, found
//! by the page order the file declares (ImageJ: channels, then slices,
//! then time points; OME-XML: its `DimensionOrder`), at the file's voxel
//! size, and `report.json` says which. Every channel and time point of
//! these files holds a square in a place of its own, so the labels show
//! which pages were read. An index beyond the file's extent, and a choice
//! for an input without such pages, are refused in one line.

use crate::cli::{bin, empty_out, fails, tmp, SEGMENT, SEGMENT3D};
use crate::ome_tiff::{ome_document, ome_series_in, write_tiff};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// Pixels of a plane: 40 × 40.
const SIDE: usize = 40;

/// Where channel `c` at time point `t` (of 2 × 2) holds its bright
/// square: one quadrant each.
fn square_of(c: usize, t: usize) -> [usize; 2] {
    [4 + 20 * c, 4 + 20 * t]
}

/// The value of pixel `(x, y)` of channel `c` at time point `t`: bright
/// (200) in its 12-pixel square, dark (60) elsewhere, with a small texture.
fn pattern(x: usize, y: usize, c: usize, t: usize) -> u8 {
    let [x0, y0] = square_of(c, t);
    let inside = (x0..x0 + 12).contains(&x) && (y0..y0 + 12).contains(&y);
    let level = if inside { 200 } else { 60 };
    level + ((x * 7 + y * 13) % 11) as u8 * 2
}

/// Slice, channel and time point of `page` when the pages run through the
/// axes in `order` (`"ZCT"`: slices fastest), of `[nz, nc, nt]` entries.
fn coordinates(order: &str, [nz, nc, nt]: [usize; 3], page: usize) -> [usize; 3] {
    let mut rest = page;
    let mut at = [0; 3];
    for axis in order.chars() {
        let (slot, extent) = match axis {
            'Z' => (0, nz),
            'C' => (1, nc),
            _ => (2, nt),
        };
        at[slot] = rest % extent;
        rest /= extent;
    }
    at
}

/// Writes the pages of `[nz, nc, nt]` in `order`, each its channel's and
/// time point's [`pattern`], the first page carrying `description`.
fn write_pages(path: &Path, order: &str, extents: [usize; 3], description: &str) {
    let pages = extents.iter().product();
    write_tiff(path, [SIDE, SIDE, pages], description, None, |x, y, p| {
        let [_, c, t] = coordinates(order, extents, p);
        pattern(x, y, c, t)
    });
}

/// An ImageJ hyperstack of `[nz, nc, nt]` 40 × 40 planes, slices 2 µm apart.
fn imagej_stack(dir: &Path, name: &str, [nz, nc, nt]: [usize; 3]) -> PathBuf {
    let path = dir.join(name);
    let description = format!(
        "ImageJ=1.54f\nimages={}\nchannels={nc}\nslices={nz}\nframes={nt}\nhyperstack=true\n\
         unit=micron\nspacing=2.0\n",
        nz * nc * nt
    );
    write_pages(&path, "CZT", [nz, nc, nt], &description);
    path
}

/// An OME-TIFF of `[nz, nc, nt]` 40 × 40 planes in `DimensionOrder`
/// `order`, of 0.5 × 0.5 × 2 µm voxels.
fn ome_stack(dir: &Path, name: &str, order: &str, [nz, nc, nt]: [usize; 3]) -> PathBuf {
    let path = dir.join(name);
    let sizes = "PhysicalSizeX=\"0.5\" PhysicalSizeY=\"0.5\" PhysicalSizeZ=\"2.0\"";
    let series = ome_series_in(order, 0, 0, [SIDE, SIDE, nz, nc, nt], sizes);
    let axes = order.strip_prefix("XY").unwrap();
    write_pages(&path, axes, [nz, nc, nt], &ome_document(&[series]));
    path
}

/// Runs `dsc-seg SUB INPUT --phases 2 ARGS`, expects success, and returns
/// the report and whether each pixel (of every slice, slices one after
/// another) was labelled bright.
fn segment(sub: &str, input: &Path, args: &[&str], out: &Path) -> (Value, Vec<bool>) {
    let o = bin()
        .arg(sub)
        .arg(input)
        .args([
            "--phases",
            "2",
            "--quiet",
            "--outputs",
            "labels,report",
            "--out",
        ])
        .arg(out)
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{sub} {args:?}: {err}");
    let report = serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap());
    let labels = dsc_seg::io::Volume::load(out.join("labels.tif")).unwrap();
    let bright = labels.data().iter().map(|&v| v > 0.0).collect();
    (report.unwrap(), bright)
}

/// The fraction of `bright` (planes one after another) that agrees with
/// channel `c` at time point `t`'s square.
fn agreement(bright: &[bool], c: usize, t: usize) -> f64 {
    let plane = SIDE * SIDE;
    let agree = bright
        .iter()
        .enumerate()
        .filter(|&(i, &b)| {
            let (x, y) = (i % plane % SIDE, i % plane / SIDE);
            b == (pattern(x, y, c, t) >= 200)
        })
        .count();
    agree as f64 / bright.len() as f64
}

/// Asserts that `bright` is channel `c` at time point `t` and none of the
/// other three.
fn assert_segmented(bright: &[bool], [c, t]: [usize; 2], what: &str) {
    for (oc, ot) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
        let a = agreement(bright, oc, ot);
        if (oc, ot) == (c, t) {
            assert!(a > 0.97, "{what}: channel {c} at {t} agrees on {a}");
        } else {
            assert!(a < 0.9, "{what}: channel {oc} at {ot} agrees on {a}");
        }
    }
}

/// ImageJ's pages run through channels, then slices, then time points:
/// each choice of a 2 × 6 × 2 hyperstack segments that channel's six
/// slices at that time point, at ImageJ's slice spacing.
#[test]
fn segment3d_reads_one_channel_at_one_time_point_of_an_imagej_hyperstack() {
    let d = tmp();
    let input = imagej_stack(d.path(), "hyper.tif", [6, 2, 2]);
    for [c, t] in [[1, 0], [0, 1]] {
        let (ct, tt) = (c.to_string(), t.to_string());
        let args = ["--channel", &ct, "--time-point", &tt];
        let (report, bright) = segment("segment3d", &input, &args, &d.path().join(&ct));
        assert_segmented(&bright, [c, t], "ImageJ");
        assert_eq!(report["frame"]["dims"], json!([40, 40, 6]));
        assert_eq!(report["frame"]["spacing"][2], json!(2.0));
        assert_eq!(report["input"]["channel"], json!(c));
        assert_eq!(report["input"]["time_point"], json!(t));
    }
}

/// An OME-TIFF's pages run through the axes in its `DimensionOrder`: the
/// same choice reads other pages in each order, and the voxel size is the
/// OME-XML's.
#[test]
fn segment3d_follows_the_ome_dimension_order() {
    let d = tmp();
    for order in ["XYZCT", "XYCZT", "XYTZC"] {
        let input = ome_stack(d.path(), &format!("{order}.ome.tif"), order, [5, 2, 2]);
        let args = ["--channel", "1", "--time-point", "1"];
        let (report, bright) = segment("segment3d", &input, &args, &d.path().join(order));
        assert_segmented(&bright, [1, 1], order);
        assert_eq!(
            report["frame"]["spacing"],
            json!([0.5, 0.5, 2.0]),
            "{order}"
        );
        assert_eq!(report["frame"]["dims"], json!([40, 40, 5]));
        assert_eq!(report["input"]["channel"], json!(1));
        assert_eq!(report["warnings"], json!([]), "{order}");
    }
}

/// `segment` reads the one page of a choice of planes: a channel at a
/// time point of an OME-TIFF (whose order decides which page that is), and
/// a time point of an ImageJ time series.
#[test]
fn segment_reads_one_plane_of_an_ome_tiff_or_a_time_series() {
    let d = tmp();
    for order in ["XYCTZ", "XYTCZ"] {
        let input = ome_stack(d.path(), &format!("{order}.ome.tif"), order, [1, 2, 2]);
        let args = ["--channel", "0", "--time-point", "1"];
        let (report, bright) = segment("segment", &input, &args, &d.path().join(order));
        assert_segmented(&bright, [0, 1], order);
        assert_eq!(report["frame"]["spacing"][0], json!(0.5));
        assert_eq!(report["input"]["time_point"], json!(1));
        assert_eq!(report["input"]["colour"], json!("gray"));
    }
    // Time points of one plane: channel 0's, at each time point.
    let lapse = d.path().join("lapse.tif");
    let description = "ImageJ=1.54f\nimages=2\nframes=2\nhyperstack=true\n";
    write_pages(&lapse, "TZC", [1, 1, 2], description);
    let (report, bright) = segment(
        "segment",
        &lapse,
        &["--time-point", "1"],
        &d.path().join("l"),
    );
    assert_segmented(&bright, [0, 1], "time series");
    assert_eq!(report["input"]["channel"], Value::Null);
}

/// An index beyond the file's extent is refused by both commands, naming
/// the extents; index 0 of an axis of one entry is accepted.
#[test]
fn an_index_beyond_the_extent_is_refused_naming_it() {
    let d = tmp();
    let input = imagej_stack(d.path(), "hyper.tif", [6, 2, 2]);
    let path = input.to_str().unwrap();
    let said = "hyper.tif: --channel 2 is out of range: it holds 2 channels × 6 slices × 2 \
                time points (0-based: --channel 0 to 1)";
    let args = [path, "--channel", "2", "--time-point", "0"];
    fails(&SEGMENT3D, &args, &empty_out(&d), said);
    let one_time = ome_stack(d.path(), "one_time.ome.tif", "XYZCT", [5, 2, 1]);
    let path = one_time.to_str().unwrap();
    let args = [path, "--channel", "1", "--time-point", "1"];
    let said = "--time-point 1 is out of range: it holds 2 channels × 5 slices × 1 time point \
                (0-based: --time-point 0 only)";
    fails(&SEGMENT3D, &args, &d.path().join("o2"), said);
    let args = ["--channel", "1", "--time-point", "0"];
    let (_, bright) = segment("segment3d", &one_time, &args, &d.path().join("o3"));
    assert_segmented(&bright, [1, 0], "one time point");
    let plane = ome_stack(d.path(), "plane.ome.tif", "XYZCT", [1, 2, 1]);
    let args = [plane.to_str().unwrap(), "--channel", "3"];
    fails(
        &SEGMENT,
        &args,
        &d.path().join("o4"),
        "--channel 3 is out of range",
    );
}

/// Without a choice, a file of several channels and time points is
/// refused as before, its one line naming the options that choose; a
/// choice of one axis where both have several entries asks for the other.
#[test]
fn the_refusal_names_the_options_that_choose() {
    let d = tmp();
    let input = imagej_stack(d.path(), "hyper.tif", [6, 2, 2]);
    let path = input.to_str().unwrap();
    let said = "segment one channel at one time point as a volume with `dsc-seg segment3d` \
                and --channel C --time-point T (0-based: C from 0 to 1, T from 0 to 1)";
    fails(&SEGMENT3D, &[path], &empty_out(&d), said);
    fails(&SEGMENT, &[path], &d.path().join("o2"), said);
    let args = [path, "--channel", "1"];
    let said = "--channel 1 chooses part of it, choose with --channel C --time-point T";
    fails(&SEGMENT3D, &args, &d.path().join("o3"), said);
    let args = [path, "--time-point", "5"];
    let said = "--time-point 5 is out of range";
    fails(&SEGMENT3D, &args, &d.path().join("o4"), said);
    let planes = imagej_stack(d.path(), "planes.tif", [1, 2, 3]);
    let said = "as an image with `dsc-seg segment` and --channel C --time-point T";
    fails(
        &SEGMENT3D,
        &[planes.to_str().unwrap()],
        &d.path().join("o5"),
        said,
    );
}

/// `--channel` of a file of one channel is a colour channel; a choice it
/// still lacks is asked for naming the options as given.
#[test]
fn a_colour_channel_of_a_time_series_names_the_options_given() {
    let d = tmp();
    let lapse = imagej_stack(d.path(), "lapse.tif", [1, 1, 4]);
    let args = [lapse.to_str().unwrap(), "--channel", "0"];
    let said = "4 time points: --channel 0 chooses part of it, choose with --time-point T";
    fails(&SEGMENT, &args, &empty_out(&d), said);
}

/// A choice of pages with no file to choose from (the built-in phantom)
/// is a usage error, not ignored.
#[test]
fn a_choice_without_an_input_file_is_refused() {
    let d = tmp();
    let said = "--time-point 3 chooses a plane of an image file";
    fails(&SEGMENT, &["--time-point", "3"], &empty_out(&d), said);
    let said = "--channel 0 chooses a plane of an image file";
    fails(&SEGMENT, &["--channel", "0"], &d.path().join("o2"), said);
}

/// A choice for an input without pages to choose from (a NIfTI, a PNG,
/// a phantom) is refused; so is a choice that is not what the command
/// reads (several slices for `segment`, one plane for `segment3d`), with
/// a pointer to the command that reads it.
#[test]
fn a_choice_the_input_cannot_give_is_refused() {
    let d = tmp();
    let nifti = d.path().join("volume.nii.gz");
    let data: Vec<f32> = (0..8 * 8 * 4).map(|i| (i % 5) as f32).collect();
    dsc_seg::io::save_nifti(&nifti, &dsc_seg::io::Volume::from_raw(8, 8, 4, data)).unwrap();
    let args = [nifti.to_str().unwrap(), "--channel", "0"];
    fails(
        &SEGMENT3D,
        &args,
        &empty_out(&d),
        "--channel 0 chooses pages of a",
    );
    let png = d.path().join("plane.png");
    image::GrayImage::from_fn(16, 16, |x, y| image::Luma([(x * 9 + y) as u8]))
        .save(&png)
        .unwrap();
    let args = [png.to_str().unwrap(), "--time-point", "0"];
    let said = "plane.png is not a TIFF";
    fails(&SEGMENT, &args, &d.path().join("o2"), said);
    fails(
        &SEGMENT3D,
        &["--channel", "0"],
        &d.path().join("o3"),
        "is not a TIFF",
    );

    let stack = ome_stack(d.path(), "stack.ome.tif", "XYZCT", [5, 2, 1]);
    let args = [stack.to_str().unwrap(), "--channel", "1"];
    let said = "at --channel 1 holds 5 slices: a volume, segment it with `dsc-seg segment3d \
                --channel 1`";
    fails(&SEGMENT, &args, &d.path().join("o4"), said);
    let plane = ome_stack(d.path(), "plane.ome.tif", "XYZCT", [1, 2, 2]);
    let args = [
        plane.to_str().unwrap(),
        "--channel",
        "1",
        "--time-point",
        "0",
    ];
    let said = "is one plane of 40×40 pixels: a 2D image, segment it with `dsc-seg segment \
                --channel 1 --time-point 0`";
    fails(&SEGMENT3D, &args, &d.path().join("o5"), said);
}

/// A description whose extents multiply beyond what a file can hold (a
/// crafted or corrupt one: the product wraps around to 0 pages) is refused
/// in one line, before anything is allocated for its slices.
#[test]
fn extents_beyond_any_file_are_refused() {
    let d = tmp();
    let path = d.path().join("absurd.tif");
    let description = "ImageJ=1.54f\nimages=2\nchannels=2147483648\nslices=8589934592\n\
                       hyperstack=true\n";
    write_tiff(&path, [SIDE, SIDE, 2], description, None, |x, y, _| {
        pattern(x, y, 0, 0)
    });
    let file = path.to_str().unwrap();
    let said = "declares 2147483648 channels × 8589934592 slices × 1 time point: more pages";
    fails(&SEGMENT3D, &[file, "--channel", "0"], &empty_out(&d), said);
    fails(
        &SEGMENT,
        &[file, "--channel", "1"],
        &d.path().join("o2"),
        said,
    );
    let ome = d.path().join("absurd.ome.tif");
    let series = "<Image ID=\"Image:0\"><Pixels ID=\"Pixels:0\" DimensionOrder=\"XYZCT\" \
                  Type=\"uint8\" SizeX=\"40\" SizeY=\"40\" SizeZ=\"8589934592\" SizeC=\"2\" \
                  SizeT=\"9223372036854775808\"><TiffData IFD=\"0\"/></Pixels></Image>"
        .to_string();
    write_tiff(
        &ome,
        [SIDE, SIDE, 2],
        &ome_document(&[series]),
        None,
        |x, y, _| pattern(x, y, 0, 0),
    );
    let file = ome.to_str().unwrap();
    let said = "more pages than any file holds";
    fails(
        &SEGMENT3D,
        &[file, "--channel", "0"],
        &d.path().join("o3"),
        said,
    );
    fails(
        &SEGMENT,
        &[file, "--channel", "0"],
        &d.path().join("o4"),
        said,
    );
}

/// Writes `frames` RGB 40 × 40 pages, an ImageJ time series.
fn rgb_time_series(path: &Path, frames: usize) {
    use tiff::encoder::{colortype::RGB8, TiffEncoder};
    let file = std::fs::File::create(path).unwrap();
    let mut enc = TiffEncoder::new(std::io::BufWriter::new(file)).unwrap();
    let description = format!("ImageJ=1.54f\nimages={frames}\nframes={frames}\n");
    for t in 0..frames {
        let mut page = enc.new_image::<RGB8>(SIDE as u32, SIDE as u32).unwrap();
        if t == 0 {
            let tag = tiff::tags::Tag::ImageDescription;
            page.encoder().write_tag(tag, description.as_str()).unwrap();
        }
        let data: Vec<u8> = (0..SIDE * SIDE * 3)
            .map(|i| pattern(i / 3 % SIDE, i / 3 / SIDE, 0, t.min(1)))
            .collect();
        page.write_data(&data).unwrap();
    }
}

/// Every page of a colour time series is read by one reader: the first
/// time point is refused as the third is, and the refusal without a choice
/// does not advise a choice that is refused in turn.
#[test]
fn colour_pages_are_refused_alike_at_every_time_point() {
    let d = tmp();
    let lapse = d.path().join("rgb_lapse.tif");
    rgb_time_series(&lapse, 3);
    let file = lapse.to_str().unwrap();
    let said = "--channel and --time-point read grayscale pages only";
    for t in ["0", "2"] {
        let out = d.path().join(format!("o{t}"));
        fails(&SEGMENT, &[file, "--time-point", t], &out, said);
    }
    let line = fails(&SEGMENT, &[file], &empty_out(&d), said);
    assert!(!line.contains("--time-point T"), "{line}");
    fails(&SEGMENT3D, &[file], &d.path().join("o3"), said);
}
