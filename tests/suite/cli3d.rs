//! `dsc-seg segment3d` on bad input: one clear error line, a non-zero exit,
//! no panic and nothing written. Volumes are tiny so this stays fast.

use crate::cli::{bin, empty_out, fails, tmp, SEGMENT3D};
use dsc_seg::io::{save_labels_tiff, save_nifti, Volume};
use std::path::{Path, PathBuf};

/// A noisy two-phase `n³` volume: a bright cube in the middle.
fn values(n: usize) -> Vec<u8> {
    let inside = |i: usize| i >= n / 4 && i < 3 * n / 4;
    let mut v = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let base = if inside(x) && inside(y) && inside(z) {
                    180
                } else {
                    70
                };
                v.push(base + ((x * 7 + y * 13 + z * 5) % 11) as u8 * 3);
            }
        }
    }
    v
}

fn write_tiff(dir: &Path, name: &str, dims: [usize; 3], data: &[u8]) -> PathBuf {
    let p = dir.join(name);
    save_labels_tiff(&p, dims, data, None).unwrap();
    p
}

/// The bytes of a valid little-endian float32 NIfTI-1 of the 12³ test volume.
fn nifti_bytes(dir: &Path) -> Vec<u8> {
    let data = values(12).iter().map(|&v| v as f32 / 255.0).collect();
    let p = dir.join("valid.nii");
    save_nifti(&p, &Volume::from_raw(12, 12, 12, data)).unwrap();
    std::fs::read(p).unwrap()
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p.to_str().unwrap().to_string()
}

/// Sets NIfTI `dim[i]` (little-endian i16 at byte 40 + 2i).
fn set_dim(bytes: &mut [u8], i: usize, v: i16) {
    bytes[40 + 2 * i..42 + 2 * i].copy_from_slice(&v.to_le_bytes());
}

#[test]
fn good_volume_segments() {
    // The control: the volume the other cases corrupt does segment.
    let d = tmp();
    let p = write_tiff(d.path(), "ok.tif", [12; 3], &values(12));
    let out = empty_out(&d);
    let o = bin()
        .arg("segment3d")
        .arg(&p)
        .args(["--max-iterations", "3", "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in SEGMENT3D.outputs {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let n = std::fs::read_dir(&out).unwrap().count();
    assert_eq!(n, SEGMENT3D.outputs.len(), "staging left behind");
}

#[test]
fn missing_or_unknown_file() {
    let d = tmp();
    let out = empty_out(&d);
    for p in [
        "/nonexistent/x.tif",
        "/nonexistent/x.nii",
        "/nonexistent/x.nii.gz",
    ] {
        fails(&SEGMENT3D, &[p], &out, "cannot read");
    }
    let raw = write(d.path(), "x.raw", b"data");
    fails(&SEGMENT3D, &[&raw], &out, "unknown file type");
}

#[test]
fn corrupt_nifti() {
    let d = tmp();
    let out = empty_out(&d);
    // 348 bytes of garbage: no valid sizeof_hdr in either byte order.
    let garbage: Vec<u8> = (0..348u32).map(|i| (i * 97 % 251) as u8 | 1).collect();
    let p = write(d.path(), "garbage.nii", &garbage);
    fails(&SEGMENT3D, &[&p], &out, "sizeof_hdr");
    let p = write(d.path(), "short.nii", &garbage[..100]);
    fails(&SEGMENT3D, &[&p], &out, "shorter than the 348-byte header");

    let valid = nifti_bytes(d.path());
    let mut magic = valid.clone();
    magic[344..348].copy_from_slice(b"xyz\0");
    let p = write(d.path(), "magic.nii", &magic);
    fails(&SEGMENT3D, &[&p], &out, "bad magic");
    // A valid sizeof_hdr with nonsense dimensions.
    for (i, v, needle) in [
        (0, 0, "dim[0] = 0"),
        (0, 99, "dim[0] = 99"),
        (2, -7, "negative"),
        (3, 0, "empty image"),
        (1, i16::MAX, "truncated"),
    ] {
        let mut b = valid.clone();
        set_dim(&mut b, i, v);
        let p = write(d.path(), &format!("dims_{i}_{v}.nii"), &b);
        fails(&SEGMENT3D, &[&p], &out, needle);
    }
    let mut four_d = valid.clone();
    set_dim(&mut four_d, 0, 4);
    set_dim(&mut four_d, 4, 5);
    let p = write(d.path(), "four_d.nii", &four_d);
    fails(&SEGMENT3D, &[&p], &out, "only 3-D");
    let mut datatype = valid.clone();
    datatype[70..72].copy_from_slice(&1234i16.to_le_bytes());
    let p = write(d.path(), "datatype.nii", &datatype);
    fails(&SEGMENT3D, &[&p], &out, "datatype 1234");
    let mut offset = valid.clone();
    offset[108..112].copy_from_slice(&f32::NAN.to_le_bytes());
    let p = write(d.path(), "offset.nii", &offset);
    fails(&SEGMENT3D, &[&p], &out, "vox_offset");
    // The data is shorter than the header says.
    let p = write(d.path(), "truncated.nii", &valid[..valid.len() - 100]);
    fails(&SEGMENT3D, &[&p], &out, "truncated");
}

#[test]
fn corrupt_nifti_gz() {
    let d = tmp();
    let out = empty_out(&d);
    let p = write(
        d.path(),
        "bad.nii.gz",
        b"\x1f\x8b\x08\0garbage, not deflate data",
    );
    fails(&SEGMENT3D, &[&p], &out, "bad gzip data");
    let mut gz = Vec::new();
    {
        use std::io::Write;
        let mut enc = flate2::write::GzEncoder::new(&mut gz, flate2::Compression::default());
        enc.write_all(&nifti_bytes(d.path())).unwrap();
        enc.finish().unwrap();
    }
    let p = write(d.path(), "cut.nii.gz", &gz[..gz.len() / 2]);
    fails(&SEGMENT3D, &[&p], &out, "bad gzip data");
}

#[test]
fn corrupt_tiff() {
    let d = tmp();
    let out = empty_out(&d);
    let p = write(d.path(), "garbage.tif", b"II*\0garbage garbage garbage");
    fails(&SEGMENT3D, &[&p], &out, "garbage.tif: malformed TIFF");
    let p = write(d.path(), "empty.tif", b"");
    fails(
        &SEGMENT3D,
        &[&p],
        &out,
        "empty.tif is not a readable image: the file is empty",
    );
    let good = write_tiff(d.path(), "good.tif", [12; 3], &values(12));
    let bytes = std::fs::read(good).unwrap();
    for cut in [8, 100, bytes.len() / 2, bytes.len() - 10] {
        let p = write(d.path(), &format!("cut{cut}.tif"), &bytes[..cut]);
        fails(
            &SEGMENT3D,
            &[&p],
            &out,
            &format!("cut{cut}.tif: malformed TIFF"),
        );
    }
}

#[test]
fn too_small_volumes() {
    let d = tmp();
    let out = empty_out(&d);
    let p = write_tiff(d.path(), "one.tif", [1, 1, 1], &[9]);
    fails(&SEGMENT3D, &[p.to_str().unwrap()], &out, "1×1×1 voxels");
    // A single slice is an image, not a volume: the error names the file
    // and the command that takes it.
    let p = write_tiff(d.path(), "slice.tif", [12, 12, 1], &values(12)[..144]);
    let line = fails(&SEGMENT3D, &[p.to_str().unwrap()], &out, "12×12×1 voxels");
    assert!(line.contains("slice.tif"), "{line}");
    assert!(line.contains("segment it with `dsc-seg segment`"), "{line}");
    // So is a PNG, which is not called a file of unknown type.
    let png = d.path().join("photo.png");
    image::GrayImage::from_pixel(12, 12, image::Luma([9]))
        .save(&png)
        .unwrap();
    let line = fails(
        &SEGMENT3D,
        &[png.to_str().unwrap()],
        &out,
        "photo.png is a 2D image",
    );
    assert!(line.contains("segment it with `dsc-seg segment`"), "{line}");
    let nz2 = write_tiff(d.path(), "two.tif", [1, 1, 2], &[9, 9]);
    fails(
        &SEGMENT3D,
        &[nz2.to_str().unwrap()],
        &out,
        "1×1×2 voxels; at least 2×2×2",
    );
    // A slice large enough for the half-resolution pass is named by its own
    // size, not the halved one.
    let side = 130;
    let slice: Vec<u8> = (0..side * side).map(|i| (i % 7) as u8).collect();
    let p = write_tiff(d.path(), "large_slice.tif", [side, side, 1], &slice);
    fails(&SEGMENT3D, &[p.to_str().unwrap()], &out, "130×130×1 voxels");
    let data = vec![0.5f32];
    let p = d.path().join("one.nii");
    save_nifti(&p, &Volume::from_raw(1, 1, 1, data)).unwrap();
    fails(&SEGMENT3D, &[p.to_str().unwrap()], &out, "1×1×1 voxels");
}

/// A stack of 1-bit pages (what tifffile writes for a boolean mask) is
/// refused by its bit depth, not called malformed.
#[test]
fn a_stack_of_one_bit_pages_is_refused_by_its_bit_depth() {
    let d = tmp();
    let p = d.path().join("mask.tif");
    std::fs::write(&p, one_bit_tiff(16, 3)).unwrap();
    let line = fails(
        &SEGMENT3D,
        &[p.to_str().unwrap()],
        &empty_out(&d),
        "1-bit samples",
    );
    assert!(!line.contains("malformed"), "{line}");
}

/// A little-endian TIFF of `pages` pages of `side`² pixels, 1 bit each
/// (black is zero), uncompressed, one strip a page, in stripes.
fn one_bit_tiff(side: u32, pages: u32) -> Vec<u8> {
    let row_bytes = side.div_ceil(8);
    let strip = vec![0b1010_1010u8; (row_bytes * side) as usize];
    let ifd_len = 2 + 9 * 12 + 4;
    let page_len = strip.len() as u32 + ifd_len;
    let mut b = b"II*\0".to_vec();
    // Each page's strip comes first, its IFD after it.
    b.extend((8 + strip.len() as u32).to_le_bytes());
    for k in 0..pages {
        let start = 8 + k * page_len;
        b.extend(&strip);
        let next = if k + 1 < pages {
            start + page_len + strip.len() as u32
        } else {
            0
        };
        let entries: [(u16, u16, u32); 9] = [
            (256, 4, side),               // ImageWidth
            (257, 4, side),               // ImageLength
            (258, 3, 1),                  // BitsPerSample
            (259, 3, 1),                  // Compression: none
            (262, 3, 1),                  // PhotometricInterpretation: black is zero
            (273, 4, start),              // StripOffsets
            (277, 3, 1),                  // SamplesPerPixel
            (278, 4, side),               // RowsPerStrip
            (279, 4, strip.len() as u32), // StripByteCounts
        ];
        b.extend(9u16.to_le_bytes());
        for (tag, kind, value) in entries {
            b.extend(tag.to_le_bytes());
            b.extend(kind.to_le_bytes());
            b.extend(1u32.to_le_bytes());
            b.extend(value.to_le_bytes()); // a SHORT sits in the low bytes
        }
        b.extend(next.to_le_bytes());
    }
    b
}

#[test]
fn constant_volumes() {
    let d = tmp();
    let out = empty_out(&d);
    let p = write_tiff(d.path(), "flat8.tif", [10; 3], &[77; 1000]);
    fails(&SEGMENT3D, &[p.to_str().unwrap()], &out, "constant");
    // 16 bit, one value everywhere.
    let p = d.path().join("flat16.tif");
    {
        use tiff::encoder::{colortype::Gray16, TiffEncoder};
        let mut enc = TiffEncoder::new(std::fs::File::create(&p).unwrap()).unwrap();
        for _ in 0..10 {
            enc.write_image::<Gray16>(10, 10, &[40_000u16; 100])
                .unwrap();
        }
    }
    fails(&SEGMENT3D, &[p.to_str().unwrap()], &out, "constant");
    let p = d.path().join("flat.nii.gz");
    save_nifti(&p, &Volume::from_raw(10, 10, 10, vec![0.25; 1000])).unwrap();
    fails(&SEGMENT3D, &[p.to_str().unwrap()], &out, "constant");
    // No finite sample at all.
    for (name, v) in [("nan.nii", f32::NAN), ("inf.nii.gz", f32::INFINITY)] {
        let p = d.path().join(name);
        save_nifti(&p, &Volume::from_raw(6, 6, 6, vec![v; 216])).unwrap();
        fails(
            &SEGMENT3D,
            &[p.to_str().unwrap()],
            &out,
            "216 of 216 samples are not finite",
        );
    }
    // One NaN voxel in a valid volume (a masked scan): refused, as in 2D,
    // rather than read as the darkest value.
    let mut data: Vec<f32> = values(12).iter().map(|&v| v as f32).collect();
    data[700] = f32::NAN;
    let p = d.path().join("one_nan.nii");
    save_nifti(&p, &Volume::from_raw(12, 12, 12, data)).unwrap();
    fails(
        &SEGMENT3D,
        &[p.to_str().unwrap()],
        &out,
        "1 of 1728 samples are not finite",
    );
    // Two values and three phases.
    let two: Vec<u8> = (0..1000)
        .map(|i| if i % 2 == 0 { 10 } else { 200 })
        .collect();
    let p = write_tiff(d.path(), "two.tif", [10; 3], &two);
    fails(
        &SEGMENT3D,
        &[p.to_str().unwrap(), "--phases", "3"],
        &out,
        "only 2 distinct intensities",
    );
}

#[test]
fn bad_numeric_options() {
    let d = tmp();
    let p = write_tiff(d.path(), "v.tif", [12; 3], &values(12));
    let p = p.to_str().unwrap();
    let out = empty_out(&d);
    for (opt, v, needle) in [
        ("--edge-length", "NaN", "positive number"),
        ("--edge-length", "inf", "positive number"),
        ("--edge-length", "-2", "positive number"),
        ("--edge-length", "0", "positive number"),
        ("--edge-length", "1e-9", "at least 1"),
        ("--edge-length", "1e9", "must not exceed"),
        ("--edge-length", "13", "must not exceed"),
        ("--rigidity", "nan", "rigidity"),
        ("--rigidity", "inf", "rigidity"),
        ("--rigidity", "-1", "rigidity"),
        ("--phases", "255", "between 2 and 64"),
        ("--phases", "1", "between 2 and 64"),
        ("--phases", "-3", "between 2 and 64"),
        ("--max-iterations", "0", "max_iterations"),
        ("--flip-interval", "0", "flip_interval"),
        ("--max-iterations", "-1", "--max-iterations"),
        ("--phases", "two", "--phases"),
        ("--init", "bogus", "possible values"),
    ] {
        fails(&SEGMENT3D, &[p, opt, v], &out, needle);
    }
    fails(
        &SEGMENT3D,
        &[p, "--no-such-option"],
        &out,
        "--no-such-option",
    );
}

/// Without a volume a phantom is generated: its size and noise are checked first.
#[test]
fn bad_phantom_options() {
    let d = tmp();
    let out = empty_out(&d);
    fails(
        &SEGMENT3D,
        &["--phantom-size", "0"],
        &out,
        "must lie in 8..=1024",
    );
    fails(
        &SEGMENT3D,
        &["--phantom-size", "100000"],
        &out,
        "must lie in 8..=1024",
    );
    fails(
        &SEGMENT3D,
        &["--phantom-noise", "nan"],
        &out,
        "non-negative",
    );
    fails(
        &SEGMENT3D,
        &["--phantom-noise", "inf"],
        &out,
        "non-negative",
    );
    fails(
        &SEGMENT3D,
        &["--phantom", "nope"],
        &out,
        "unknown 3D phantom",
    );
}

#[test]
fn bad_balls() {
    let d = tmp();
    let p = write_tiff(d.path(), "v.tif", [12; 3], &values(12));
    let p = p.to_str().unwrap();
    let out = empty_out(&d);
    fails(&SEGMENT3D, &[p, "--init", "balls"], &out, "--ball X,Y,Z,R");
    for (ball, needle) in [
        ("1,2,3", "expected X,Y,Z,R[,PHASE]"),
        ("a,b,c,d", "expected X,Y,Z,R[,PHASE]"),
        ("1,2,3,4,5,6", "expected X,Y,Z,R[,PHASE]"),
        ("6,6,6,2,1.5", "expected X,Y,Z,R[,PHASE]"),
        ("6,6,6,2,-1", "expected X,Y,Z,R[,PHASE]"),
        ("", "expected X,Y,Z,R[,PHASE]"),
        ("6,6,6,-2", "positive radius"),
        ("6,6,6,0", "positive radius"),
        ("nan,6,6,2", "finite numbers"),
        ("6,6,6,inf", "finite numbers"),
        ("6,6,6,2,7", "ball phase 7 is not below"),
    ] {
        fails(
            &SEGMENT3D,
            &[p, "--init", "balls", &format!("--ball={ball}")],
            &out,
            needle,
        );
    }
}

#[test]
fn bad_init_labels() {
    let d = tmp();
    let p = write_tiff(d.path(), "v.tif", [12; 3], &values(12));
    let p = p.to_str().unwrap();
    let out = empty_out(&d);
    fails(&SEGMENT3D, &[p, "--init", "labels"], &out, "--init-labels");
    let small = write_tiff(d.path(), "small.tif", [12, 12, 6], &[0; 864]);
    let small = small.to_str().unwrap();
    fails(
        &SEGMENT3D,
        &[p, "--init", "labels", "--init-labels", small],
        &out,
        "[12, 12, 6] voxels but the volume is [12, 12, 12]",
    );
    let many = write_tiff(d.path(), "many.tif", [12; 3], &[2; 1728]);
    let many = many.to_str().unwrap();
    fails(
        &SEGMENT3D,
        &[p, "--init", "labels", "--init-labels", many],
        &out,
        "below the number of phases",
    );
    fails(
        &SEGMENT3D,
        &[p, "--init", "labels", "--init-labels", "/nonexistent/l.tif"],
        &out,
        "cannot read",
    );
}

#[test]
fn unwritable_out() {
    let d = tmp();
    let p = write_tiff(d.path(), "v.tif", [12; 3], &values(12));
    let p = p.to_str().unwrap();
    let file = d.path().join("a_file");
    std::fs::write(&file, "x").unwrap();
    fails(&SEGMENT3D, &[p], &file, "not a directory");
    fails(&SEGMENT3D, &[p], &file.join("sub"), "output directory");
    #[cfg(unix)]
    if let Some(ro) = crate::cli::read_only_dir(d.path()) {
        fails(&SEGMENT3D, &[p], &ro, "permission denied");
        fails(&SEGMENT3D, &[p], &ro.join("sub"), "permission denied");
    }
}

#[test]
fn bad_slice_folders() {
    let d = tmp();
    let out = empty_out(&d);
    let empty = d.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    fails(
        &SEGMENT3D,
        &[empty.to_str().unwrap()],
        &out,
        "holds no slices",
    );
    // Only files that are not slices: still empty.
    std::fs::write(empty.join("notes.txt"), "not a slice").unwrap();
    std::fs::write(empty.join(".hidden.png"), "hidden").unwrap();
    fails(
        &SEGMENT3D,
        &[empty.to_str().unwrap()],
        &out,
        "holds no slices",
    );

    let mixed = d.path().join("mixed");
    std::fs::create_dir(&mixed).unwrap();
    let slice = |name: &str, w: u32| {
        image::GrayImage::from_fn(w, 12, |x, y| image::Luma([(x * 20 + y) as u8]))
            .save(mixed.join(name))
            .unwrap();
    };
    slice("s0.png", 12);
    slice("s1.png", 12);
    slice("s2.png", 10);
    fails(
        &SEGMENT3D,
        &[mixed.to_str().unwrap()],
        &out,
        "dimension mismatch",
    );
    std::fs::remove_file(mixed.join("s2.png")).unwrap();
    std::fs::write(mixed.join("s2.png"), "not a png").unwrap();
    fails(
        &SEGMENT3D,
        &[mixed.to_str().unwrap()],
        &out,
        "s2.png is not a readable image",
    );
}

/// A folder of colour slices is refused, as a TIFF stack of colour pages
/// is: its luminance would be segmented with nothing saying so (and here
/// the red ball is darker than its surroundings in luminance), while
/// slices of gray stored as RGB are gray.
#[test]
fn colour_slices_are_refused_and_gray_rgb_slices_read() {
    let d = tmp();
    let out = empty_out(&d);
    let folder = |name: &str, colour: fn(u8) -> [u8; 3]| {
        let dir = d.path().join(name);
        std::fs::create_dir(&dir).unwrap();
        for z in 0..6u32 {
            image::RgbImage::from_fn(12, 12, |x, y| {
                let inside =
                    (x as i32 - 6).pow(2) + (y as i32 - 6).pow(2) + (z as i32 - 3).pow(2) < 9;
                image::Rgb(colour(if inside {
                    200
                } else {
                    40 + ((x * 7 + y * 3 + z) % 11) as u8
                }))
            })
            .save(dir.join(format!("s{z}.png")))
            .unwrap();
        }
        dir
    };
    let red = folder("red_ball", |v| [v, 255 - v, 30]);
    let line = fails(&SEGMENT3D, &[red.to_str().unwrap()], &out, "in colour");
    assert!(line.contains("s0.png"), "{line}");
    let gray = folder("gray_as_rgb", |v| [v, v, v]);
    let o = bin()
        .args([
            "segment3d",
            gray.to_str().unwrap(),
            "--outputs",
            "report",
            "--quiet",
        ])
        .arg("--out")
        .arg(d.path().join("gray_out"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A volume of pure noise asked for two phases splits into specks of its
/// noise (cells of a few voxels follow the noise averaged over them, to
/// the pieces' centres): the run says the two are one region, on stderr
/// and in report.json, as a flat image's run does in 2D.
#[test]
fn a_flat_noisy_volume_split_in_two_is_said_to_be_one_region() {
    let d = tmp();
    let n = 24;
    let mut noise = vec![0.5f32; n * n * n];
    dsc_seg::phantom::noise::add_gaussian_noise(&mut noise, 0.1, 1);
    let p = d.path().join("flat.nii.gz");
    save_nifti(&p, &Volume::from_raw(n, n, n, noise)).unwrap();
    let out = d.path().join("o");
    let o = bin()
        .arg("segment3d")
        .arg(&p)
        .args(["--phases", "2", "--outputs", "report", "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let said = "phases 0 and 1 are specks with means closer than the noise and too few \
                pixels or voxels away from their edges";
    assert!(stderr.contains(&format!("warning: {said}")), "{stderr}");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    let warnings = report["warnings"].as_array().unwrap();
    assert!(
        warnings.iter().any(|w| w.as_str().unwrap().contains(said)),
        "{warnings:?}"
    );
}

/// A stack whose pages are RGB is refused as colour, and the message names
/// the likely cause: tifffile stores a (3, Y, X) grayscale array as one RGB
/// page unless told `photometric='minisblack'`.
#[test]
fn an_rgb_stack_is_refused_with_the_tifffile_hint() {
    let d = tmp();
    let out = empty_out(&d);
    let path = d.path().join("three_slices.tif");
    let file = std::fs::File::create(&path).unwrap();
    let mut tiff = tiff::encoder::TiffEncoder::new(file).unwrap();
    let pixels: Vec<u8> = (0..12 * 12 * 3).map(|i| (i % 251) as u8).collect();
    tiff.write_image::<tiff::encoder::colortype::RGB8>(12, 12, &pixels)
        .unwrap();
    let line = fails(
        &SEGMENT3D,
        &[path.to_str().unwrap()],
        &out,
        "colour type RGB(8)",
    );
    assert!(line.contains("photometric='minisblack'"), "{line}");
}
