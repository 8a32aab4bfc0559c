//! OME-TIFF inputs, as microscopes, Bio-Formats and tifffile write them:
//! the physical pixel/voxel size of the OME-XML in the first page's
//! description is the frame of every output, ahead of the plain resolution
//! tags; an OME-XML whose sizes cannot be used falls back to the tags with
//! one warning line naming the file. Several channels or time points are
//! refused, naming the extents and the options that choose one of each
//! (`tests/suite/channels.rs`); of several series the first is segmented,
//! with a warning; pages the OME-XML does not declare are refused.

use crate::cli::{bin, empty_out, fails, tmp, SEGMENT, SEGMENT3D};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use tiff::encoder::{colortype::Gray8, Rational, TiffEncoder};
use tiff::tags::{ResolutionUnit, Tag};

/// Stands for the micro sign while the description is written: the TIFF
/// encoder writes ASCII only, while OME-XML writers store "µm" as UTF-8.
const MICRO: &str = "~~";

/// OME-XML whose `Pixels` element has the attributes `sizes` (e.g.
/// `PhysicalSizeX="0.5"`), "µm" written as [`MICRO`].
fn ome_xml(nx: usize, ny: usize, nz: usize, sizes: &str) -> String {
    ome_document(&[ome_series(0, 0, [nx, ny, nz, 1, 1], sizes)])
}

/// An OME document of these `Image` elements (series), as tifffile writes it.
pub(crate) fn ome_document(images: &[String]) -> String {
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\
         <OME xmlns=\"http://www.openmicroscopy.org/Schemas/OME/2016-06\" \
         Creator=\"tifffile.py 2026.3.3\">{}</OME>",
        images.concat()
    )
}

/// Series `i` of an OME document, `[SizeX, SizeY, SizeZ, SizeC, SizeT]`
/// in tifffile's order (`XYZCT`: slices fastest), its `Pixels` with the
/// attributes `sizes` and its pages from IFD `first_page` on.
fn ome_series(i: usize, first_page: usize, extents: [usize; 5], sizes: &str) -> String {
    ome_series_in("XYZCT", i, first_page, extents, sizes)
}

/// [`ome_series`] of pages in the `DimensionOrder` `order`.
pub(crate) fn ome_series_in(
    order: &str,
    i: usize,
    first_page: usize,
    extents: [usize; 5],
    sizes: &str,
) -> String {
    let [nx, ny, nz, nc, nt] = extents;
    let channels: String = (0..nc)
        .map(|c| format!("<Channel ID=\"Channel:{i}:{c}\" SamplesPerPixel=\"1\"/>"))
        .collect();
    format!(
        "<Image ID=\"Image:{i}\" Name=\"Image{i}\">\
         <Pixels ID=\"Pixels:{i}\" DimensionOrder=\"{order}\" Type=\"uint8\" SizeX=\"{nx}\" \
         SizeY=\"{ny}\" SizeZ=\"{nz}\" SizeC=\"{nc}\" SizeT=\"{nt}\" {sizes}>{channels}\
         <TiffData IFD=\"{first_page}\" PlaneCount=\"{}\"/></Pixels></Image>",
        nz * nc * nt
    )
}

/// Writes `nz` pages of `nx × ny` 8-bit samples from `value(x, y, z)`, the
/// first page carrying `description` ([`MICRO`] becoming "µm"'s UTF-8
/// micro sign) and, with `resolution`, every page the resolution tags of
/// that unit at that many pixels per unit (tifffile writes unit NONE beside
/// its OME-XML; without them the encoder writes 1 pixel per unit NONE).
pub(crate) fn write_tiff(
    path: &Path,
    [nx, ny, nz]: [usize; 3],
    description: &str,
    resolution: Option<(ResolutionUnit, u32)>,
    value: impl Fn(usize, usize, usize) -> u8,
) {
    let mut bytes = Vec::new();
    {
        let mut enc = TiffEncoder::new(std::io::Cursor::new(&mut bytes)).unwrap();
        for z in 0..nz {
            let mut page = enc.new_image::<Gray8>(nx as u32, ny as u32).unwrap();
            if z == 0 {
                page.encoder()
                    .write_tag(Tag::ImageDescription, description)
                    .unwrap();
            }
            if let Some((unit, n)) = resolution {
                page.resolution(unit, Rational { n, d: 1 });
            }
            let data: Vec<u8> = (0..nx * ny).map(|i| value(i % nx, i / nx, z)).collect();
            page.write_data(&data).unwrap();
        }
    }
    // Same length: the description's byte count and every offset hold.
    let micro = "µ".as_bytes();
    assert_eq!(MICRO.len(), micro.len());
    for i in 0..bytes.len().saturating_sub(1) {
        if &bytes[i..i + 2] == MICRO.as_bytes() {
            bytes[i..i + 2].copy_from_slice(micro);
        }
    }
    std::fs::write(path, bytes).unwrap();
}

/// Resolution tags of unit NONE at `n` pixels per unit.
fn none(n: u32) -> (ResolutionUnit, u32) {
    (ResolutionUnit::None, n)
}

/// Voxels of the stacks: 40 × 40 × 12.
const DIMS: [usize; 3] = [40, 40, 12];
/// A ball of radius 7 µm at (10, 10, 12) µm in voxels of 0.5 × 0.5 × 2 µm.
const RADIUS: f64 = 7.0;

/// A bright ball (200) on a dark ground (60) with a small texture, in
/// voxels of 0.5 × 0.5 × 2 µm.
fn ball(x: usize, y: usize, z: usize) -> u8 {
    let c = [
        (x as f64 + 0.5) * 0.5,
        (y as f64 + 0.5) * 0.5,
        (z as f64 + 0.5) * 2.0,
    ];
    let r2 = (c[0] - 10.0).powi(2) + (c[1] - 10.0).powi(2) + (c[2] - 12.0).powi(2);
    let level = if r2 < RADIUS * RADIUS { 200 } else { 60 };
    level + ((x * 7 + y * 13 + z * 5) % 11) as u8 * 2
}

/// An OME-TIFF stack of [`ball`] whose `Pixels` has the attributes `sizes`.
fn ball_stack(dir: &Path, name: &str, sizes: &str, per_unit: Option<u32>) -> PathBuf {
    let path = dir.join(name);
    let [nx, ny, nz] = DIMS;
    let resolution = per_unit.map(none);
    write_tiff(&path, DIMS, &ome_xml(nx, ny, nz, sizes), resolution, ball);
    path
}

/// Runs `dsc-seg SUB INPUT ARGS --quiet --out OUT`, expects success, and
/// returns the report and stderr.
fn run(sub: &str, input: &Path, args: &[&str], out: &Path) -> (Value, String) {
    let o = bin()
        .arg(sub)
        .arg(input)
        .args(args)
        .args(["--quiet", "--out"])
        .arg(out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{}: {err}", input.display());
    let report = std::fs::read(out.join("report.json")).unwrap();
    (serde_json::from_slice(&report).unwrap(), err)
}

/// The ball's volume by its voxel count, in the frame's cubic unit.
fn ball_measure(report: &Value) -> f64 {
    report["phases"]["phases"][1]["count_measure"]
        .as_f64()
        .unwrap()
}

/// 0.5 × 0.5 × 2 µm voxels from the OME-XML reach the report, the
/// measurements and `image.vti`, with the resolution tags of unit NONE
/// that tifffile writes beside them (2 pixels per unit: 0.5 × 0.5 × 1 "px"
/// read alone) or without any; the default unit (µm) as well.
#[test]
fn an_ome_tiff_stack_is_segmented_in_its_voxel_size() {
    let d = tmp();
    let sizes = format!(
        "PhysicalSizeX=\"0.5\" PhysicalSizeXUnit=\"{MICRO}m\" PhysicalSizeY=\"0.5\" \
         PhysicalSizeYUnit=\"{MICRO}m\" PhysicalSizeZ=\"2.0\" PhysicalSizeZUnit=\"{MICRO}m\""
    );
    let plain = ball_stack(d.path(), "plain.ome.tif", &sizes, None);
    let tagged = ball_stack(d.path(), "tagged.ome.tif", &sizes, Some(2));
    let default_unit = ball_stack(
        d.path(),
        "default_unit.ome.tif",
        "PhysicalSizeX=\"0.5\" PhysicalSizeY=\"0.5\" PhysicalSizeZ=\"2\"",
        Some(1),
    );
    let ball = 4.0 / 3.0 * std::f64::consts::PI * RADIUS.powi(3);
    for input in [plain, tagged, default_unit] {
        let out = input.with_extension("out");
        let (report, err) = run("segment3d", &input, &["--phases", "2"], &out);
        let frame = &report["frame"];
        assert_eq!(frame["spacing"], json!([0.5, 0.5, 2.0]), "{input:?}");
        assert_eq!(frame["unit"], "um", "{input:?}");
        assert_eq!(frame["source"], "ome_xml", "{input:?}");
        assert_eq!(frame["domain_scale"], json!([0.5, 0.5, 2.0]), "{input:?}");
        assert_eq!(report["warnings"], json!([]), "{input:?}: {err}");
        let measure = ball_measure(&report);
        assert!(
            (measure / ball - 1.0).abs() < 0.1,
            "{input:?}: {measure} µm³ vs {ball}"
        );
        let vti = std::fs::read_to_string(out.join("image.vti")).unwrap();
        assert!(vti.contains("Spacing=\"0.5 0.5 2.0\""), "{input:?}");
    }
}

/// Sizes in nanometres, and axes in different units, come in the unit of x.
#[test]
fn ome_sizes_in_nanometres_convert() {
    let d = tmp();
    let input = ball_stack(
        d.path(),
        "nm.ome.tif",
        &format!(
            "PhysicalSizeX=\"500\" PhysicalSizeXUnit=\"nm\" PhysicalSizeY=\"500\" \
             PhysicalSizeYUnit=\"nm\" PhysicalSizeZ=\"2\" PhysicalSizeZUnit=\"{MICRO}m\""
        ),
        Some(1),
    );
    let (report, _) = run("segment3d", &input, &["--phases", "2"], &d.path().join("o"));
    assert_eq!(report["frame"]["spacing"], json!([500.0, 500.0, 2000.0]));
    assert_eq!(report["frame"]["unit"], "nm");
    let ball = 4.0 / 3.0 * std::f64::consts::PI * (RADIUS * 1000.0).powi(3);
    let measure = ball_measure(&report);
    assert!(
        (measure / ball - 1.0).abs() < 0.1,
        "{measure} nm³ vs {ball}"
    );
}

/// A stack whose OME-XML gives x and y but no z: its slices are 1 µm
/// apart, as without ImageJ's `spacing=`, and a warning says so; with
/// `--spacing` the file's sizes are not used and nothing is said.
#[test]
fn an_ome_tiff_stack_without_a_z_size_says_so() {
    let d = tmp();
    let input = ball_stack(
        d.path(),
        "no_z.ome.tif",
        "PhysicalSizeX=\"0.5\" PhysicalSizeY=\"0.5\"",
        Some(2),
    );
    let (report, err) = run("segment3d", &input, &["--phases", "2"], &d.path().join("a"));
    assert_eq!(report["frame"]["spacing"], json!([0.5, 0.5, 1.0]));
    assert_eq!(report["frame"]["unit"], "um");
    let said =
        "no_z.ome.tif: its OME-XML gives no PhysicalSizeZ: its slices are taken as 1 um apart";
    assert!(
        err.contains(&format!("warning: {}", input.display())),
        "{err}"
    );
    assert!(err.contains(said), "{err}");
    let warnings = report["warnings"].as_array().unwrap();
    assert!(
        warnings.iter().any(|w| w.as_str().unwrap().contains(said)),
        "{warnings:?}"
    );
    let args = ["--phases", "2", "--spacing", "0.5,0.5,2"];
    let (report, err) = run("segment3d", &input, &args, &d.path().join("b"));
    assert_eq!(report["frame"]["spacing"], json!([0.5, 0.5, 2.0]));
    assert!(!err.contains("OME-XML"), "{err}");
}

/// OME-XML that is not well-formed, or gives sizes that are no lengths,
/// falls back to the resolution tags (or to no size) with one warning line
/// naming the file; the run goes on.
#[test]
fn unusable_ome_xml_falls_back_with_a_warning() {
    let d = tmp();
    let [nx, ny, nz] = DIMS;
    let whole = ome_xml(nx, ny, nz, "PhysicalSizeX=\"0.5\" PhysicalSizeY=\"0.5\"");
    let cut = &whole[..whole.find("PhysicalSizeY").unwrap()];
    let cases = [
        ("cut.ome.tif", cut.to_string(), "is not well-formed XML"),
        (
            "zero.ome.tif",
            ome_xml(nx, ny, nz, "PhysicalSizeX=\"0\" PhysicalSizeZ=\"2\""),
            "gives PhysicalSizeX=\"0\", not a positive length",
        ),
        (
            "nan.ome.tif",
            ome_xml(nx, ny, nz, "PhysicalSizeX=\"NaN\" PhysicalSizeY=\"0.5\""),
            "gives PhysicalSizeX=\"NaN\", not a positive length",
        ),
        (
            "pixel.ome.tif",
            ome_xml(
                nx,
                ny,
                nz,
                "PhysicalSizeX=\"1\" PhysicalSizeXUnit=\"pixel\" PhysicalSizeY=\"1\"",
            ),
            "gives PhysicalSizeXUnit=\"pixel\", not a length unit",
        ),
    ];
    for (name, description, reason) in cases {
        let input = d.path().join(name);
        write_tiff(&input, DIMS, &description, Some(none(2)), ball);
        let (report, err) = run(
            "segment3d",
            &input,
            &["--phases", "2"],
            &input.with_extension("out"),
        );
        // What the resolution tags of unit NONE alone give.
        assert_eq!(report["frame"]["spacing"], json!([0.5, 0.5, 1.0]), "{name}");
        assert_eq!(report["frame"]["unit"], "px", "{name}");
        assert_eq!(report["frame"]["source"], "tiff_resolution", "{name}");
        let line = format!(
            "warning: {}: its OME-XML description {reason}",
            input.display()
        );
        assert!(err.contains(&line), "{name}: {err}");
        assert!(
            err.contains("its TIFF resolution tags are read instead, which give no length unit"),
            "{name}: {err}"
        );
        assert_eq!(report["warnings"].as_array().unwrap().len(), 1, "{name}");
        assert!(!err.contains("panicked"), "{name}: {err}");
    }
    // Resolution tags in a length unit (200 pixels per cm) are read instead.
    let input = d.path().join("cut_per_cm.ome.tif");
    let per_cm = (ResolutionUnit::Centimeter, 200);
    write_tiff(&input, DIMS, cut, Some(per_cm), ball);
    let (report, err) = run("segment3d", &input, &["--phases", "2"], &d.path().join("u"));
    assert_eq!(report["frame"]["spacing"], json!([0.05, 0.05, 1.0]));
    assert_eq!(report["frame"]["unit"], "mm");
    let instead = "the pixel size is read from its TIFF resolution tags instead (0.05 × 0.05 mm)";
    assert!(err.contains(instead), "{err}");
}

/// A one-plane OME-TIFF gives `segment` its pixel size (0.25 × 0.5 µm, over
/// resolution tags of unit NONE), in the report, the measurements and
/// `labels.png`'s `pHYs`; its malformed OME-XML falls back with a warning.
#[test]
fn a_2d_ome_tiff_gives_its_pixel_size() {
    let d = tmp();
    let (w, h) = (48usize, 40usize);
    // A disk of radius 5 µm at (6, 10) µm in pixels of 0.25 × 0.5 µm.
    let disk = |x: usize, y: usize, _| {
        let (px, py) = ((x as f64 + 0.5) * 0.25, (y as f64 + 0.5) * 0.5);
        let inside = (px - 6.0).powi(2) + (py - 10.0).powi(2) < 25.0;
        (if inside { 190 } else { 70 }) + ((x * 7 + y * 13) % 11) as u8 * 3
    };
    let sizes = format!(
        "PhysicalSizeX=\"0.25\" PhysicalSizeXUnit=\"{MICRO}m\" PhysicalSizeY=\"0.5\" \
         PhysicalSizeYUnit=\"{MICRO}m\""
    );
    let input = d.path().join("plane.ome.tif");
    write_tiff(
        &input,
        [w, h, 1],
        &ome_xml(w, h, 1, &sizes),
        Some(none(1)),
        disk,
    );
    let out = d.path().join("a");
    let (report, err) = run("segment", &input, &[], &out);
    let frame = &report["frame"];
    assert_eq!(frame["spacing"], json!([0.25, 0.5, 1.0]));
    assert_eq!(frame["unit"], "um");
    assert_eq!(frame["source"], "ome_xml");
    assert_eq!(report["warnings"], json!([]), "{err}");
    let area = ball_measure(&report);
    let expected = std::f64::consts::PI * 25.0;
    assert!(
        (area / expected - 1.0).abs() < 0.1,
        "{area} µm² vs {expected}"
    );
    // labels.png: 4 and 2 pixels per µm.
    let file = std::fs::File::open(out.join("labels.png")).unwrap();
    let reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let dims = reader.info().pixel_dims.expect("a pHYs chunk");
    assert_eq!((dims.xppu, dims.yppu), (4_000_000, 2_000_000));

    let cut = ome_xml(w, h, 1, &sizes);
    let cut = &cut[..cut.len() - 10];
    let input = d.path().join("cut_plane.ome.tif");
    write_tiff(&input, [w, h, 1], cut, Some(none(1)), disk);
    let (report, err) = run("segment", &input, &[], &d.path().join("b"));
    assert_eq!(report["frame"]["spacing"], json!([1.0, 1.0, 1.0]));
    assert_eq!(report["frame"]["source"], "tiff_resolution");
    let line = format!(
        "warning: {}: its OME-XML description is not well-formed XML",
        input.display()
    );
    assert!(err.contains(&line), "{err}");
}

/// The sizes of [`ball`]'s voxels, in µm.
const BALL_SIZES: &str = "PhysicalSizeX=\"0.5\" PhysicalSizeY=\"0.5\" PhysicalSizeZ=\"2.0\"";

/// Writes `pages` pages of [`ball`]'s planes (page `p` is plane `p % 12`)
/// to `name` in `dir`, described by `description`.
fn ball_pages(dir: &Path, name: &str, pages: usize, description: &str) -> PathBuf {
    let path = dir.join(name);
    let [nx, ny, nz] = DIMS;
    let plane = |x, y, p| ball(x, y, p % nz);
    write_tiff(&path, [nx, ny, pages], description, None, plane);
    path
}

/// The OME-XML of one series of [`ball`]'s planes with these slices,
/// channels and time points.
fn ball_series([nz, nc, nt]: [usize; 3]) -> String {
    let [nx, ny, _] = DIMS;
    ome_document(&[ome_series(0, 0, [nx, ny, nz, nc, nt], BALL_SIZES)])
}

/// A z-stack of two channels is 24 pages, not a volume of 24 slices: both
/// commands refuse it in one line naming its extents and where they were
/// read, `segment` without pointing to `segment3d`.
#[test]
fn an_ome_tiff_of_two_channels_is_refused_by_both_commands() {
    let d = tmp();
    let input = ball_pages(
        d.path(),
        "two_channels.ome.tif",
        24,
        &ball_series([12, 2, 1]),
    );
    let args = [input.to_str().unwrap()];
    let said = "two_channels.ome.tif is an OME-TIFF of 2 channels × 12 slices × 1 time point \
                (OME-XML); its pages are not one volume: segment one channel at one time point \
                as a volume with `dsc-seg segment3d` and --channel C (0-based: C from 0 to 1)";
    fails(&SEGMENT3D, &args, &empty_out(&d), said);
    fails(&SEGMENT, &args, &d.path().join("o2"), said);
}

/// Three time points of a z-stack, and three of one plane (a time-lapse),
/// are refused by both commands, naming the time points.
#[test]
fn an_ome_tiff_of_three_time_points_is_refused_by_both_commands() {
    let d = tmp();
    let stacks = ball_pages(d.path(), "stacks.ome.tif", 36, &ball_series([12, 1, 3]));
    let args = [stacks.to_str().unwrap()];
    let extents = "an OME-TIFF of 1 channel × 12 slices × 3 time points (OME-XML)";
    fails(&SEGMENT3D, &args, &empty_out(&d), extents);
    fails(&SEGMENT, &args, &d.path().join("o2"), extents);
    let lapse = ball_pages(d.path(), "lapse.ome.tif", 3, &ball_series([1, 1, 3]));
    let args = [lapse.to_str().unwrap()];
    let series = "lapse.ome.tif is an OME-TIFF time series of 3 time points (OME-XML), not \
                  the slices of a volume: segment one time point as an image with `dsc-seg \
                  segment` and --time-point T (0-based: T from 0 to 2)";
    fails(&SEGMENT3D, &args, &d.path().join("o3"), series);
    fails(&SEGMENT, &args, &d.path().join("o4"), series);
}

/// A stack that says `SizeC="1" SizeT="1"` is read as before: its 12
/// slices in its voxel size, nothing said.
#[test]
fn an_ome_tiff_of_one_channel_and_time_point_is_one_volume() {
    let d = tmp();
    let input = ball_pages(d.path(), "one.ome.tif", 12, &ball_series([12, 1, 1]));
    let (report, err) = run("segment3d", &input, &["--phases", "2"], &d.path().join("o"));
    assert_eq!(report["frame"]["dims"], json!([40, 40, 12]));
    assert_eq!(report["frame"]["spacing"], json!([0.5, 0.5, 2.0]));
    assert_eq!(report["frame"]["source"], "ome_xml");
    assert_eq!(report["warnings"], json!([]), "{err}");
}

/// A file of two series (a stack of 12 slices, then 4 other pages) is
/// segmented as its first series, in its voxel size, with a warning on
/// stderr and in the report; `segment` takes a first series of one plane
/// the same way.
#[test]
fn of_two_ome_series_the_first_is_segmented_with_a_warning() {
    let d = tmp();
    let [nx, ny, nz] = DIMS;
    let other = "PhysicalSizeX=\"1\" PhysicalSizeY=\"1\"";
    let two = ome_document(&[
        ome_series(0, 0, [nx, ny, nz, 1, 1], BALL_SIZES),
        ome_series(1, nz, [nx, ny, 4, 1, 1], other),
    ]);
    let input = ball_pages(d.path(), "two_series.ome.tif", nz + 4, &two);
    let (report, err) = run("segment3d", &input, &["--phases", "2"], &d.path().join("a"));
    assert_eq!(report["frame"]["dims"], json!([40, 40, 12]));
    assert_eq!(report["frame"]["spacing"], json!([0.5, 0.5, 2.0]));
    let said = format!(
        "warning: {}: its OME-XML describes 2 series; only the first (12 slices) is segmented",
        input.display()
    );
    assert!(err.contains(&said), "{err}");
    let warnings = report["warnings"].as_array().unwrap();
    assert!(
        warnings[0]
            .as_str()
            .unwrap()
            .contains("only the first (12 slices)"),
        "{warnings:?}"
    );

    let planes = ome_document(&[
        ome_series(0, 0, [nx, ny, 1, 1, 1], BALL_SIZES),
        ome_series(1, 1, [nx, ny, 1, 1, 1], other),
    ]);
    let input = d.path().join("two_planes.ome.tif");
    let middle = |x, y, _| ball(x, y, 6);
    write_tiff(&input, [nx, ny, 2], &planes, None, middle);
    let (report, err) = run("segment", &input, &["--phases", "2"], &d.path().join("b"));
    assert_eq!(report["frame"]["spacing"], json!([0.5, 0.5, 1.0]));
    assert!(
        err.contains("describes 2 series; only the first (1 slice)"),
        "{err}"
    );
    let warnings = report["warnings"].as_array().unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.as_str().unwrap().contains("2 series")),
        "{warnings:?}"
    );
}

/// Pages that are not those the OME-XML declares (more than its one
/// series, or fewer than its first) are refused by both commands.
#[test]
fn ome_tiff_pages_unlike_the_declared_ones_are_refused() {
    let d = tmp();
    let more = ball_pages(d.path(), "more.ome.tif", 15, &ball_series([12, 1, 1]));
    let args = [more.to_str().unwrap()];
    let said = "more.ome.tif is an OME-TIFF of 15 pages whose OME-XML declares 12 pages for \
                1 channel × 12 slices × 1 time point";
    fails(&SEGMENT3D, &args, &empty_out(&d), said);
    fails(&SEGMENT, &args, &d.path().join("o2"), said);
    let fewer = ball_pages(d.path(), "fewer.ome.tif", 10, &ball_series([12, 1, 1]));
    let args = [fewer.to_str().unwrap()];
    fails(
        &SEGMENT3D,
        &args,
        &d.path().join("o3"),
        "of 10 pages whose OME-XML declares 12",
    );
}
