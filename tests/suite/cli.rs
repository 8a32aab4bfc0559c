//! The `dsc-seg` command: outputs on success, and one clear error line and a
//! non-zero exit for every kind of bad input.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub(crate) fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_dsc-seg"))
}

pub(crate) fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

/// An existing, empty `--out`, so that `fails` checks that nothing lands in it.
pub(crate) fn empty_out(d: &tempfile::TempDir) -> PathBuf {
    let out = d.path().join("o");
    std::fs::create_dir(&out).unwrap();
    out
}

/// A small noisy two-phase PNG (a bright disk).
fn write_image(dir: &Path, w: u32, h: u32) -> PathBuf {
    let p = dir.join(format!("img_{w}x{h}.png"));
    let img = image::GrayImage::from_fn(w, h, |x, y| {
        let (dx, dy) = (x as f64 - w as f64 / 2.0, y as f64 - h as f64 / 2.0);
        let inside = dx * dx + dy * dy < (w.min(h) as f64 / 4.0).powi(2);
        let noise = ((x * 7 + y * 13) % 11) as u8 * 3;
        image::Luma([if inside { 180 } else { 70 } + noise])
    });
    img.save(&p).unwrap();
    p
}

fn write_labels(dir: &Path, w: u32, h: u32, value: u8) -> PathBuf {
    let p = dir.join(format!("labels_{w}x{h}_{value}.png"));
    image::GrayImage::from_fn(w, h, |x, _| {
        image::Luma([if x < w / 2 { 0 } else { value }])
    })
    .save(&p)
    .unwrap();
    p
}

/// A subcommand and the outputs it writes on success.
pub(crate) struct Sub {
    pub name: &'static str,
    pub outputs: &'static [&'static str],
}

pub(crate) const SEGMENT: Sub = Sub {
    name: "segment",
    outputs: &[
        "labels.png",
        "overlay.png",
        "overlay.svg",
        "mesh.vtu",
        "interface.vtp",
        "image.vti",
        "scene.vtm",
        "scene.pvd",
        "phases.csv",
        "interfaces.csv",
        "report.json",
    ],
};

pub(crate) const SEGMENT3D: Sub = Sub {
    name: "segment3d",
    outputs: &[
        "labels.tif",
        "mesh.vtu",
        "interface.vtp",
        "image.vti",
        "scene.vtm",
        "scene.pvd",
        "phases.csv",
        "interfaces.csv",
        "report.json",
    ],
};

/// Runs `dsc-seg SUB ARGS --out OUT --quiet`, expects failure with exactly one
/// stderr line `error: ...` mentioning `needle` (no panic), and an output
/// directory holding none of the outputs and nothing else. Returns the line.
pub(crate) fn fails(sub: &Sub, args: &[&str], out: &Path, needle: &str) -> String {
    let o: Output = bin()
        .arg(sub.name)
        .args(args)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    eprintln!("{} {args:?} -> {}", sub.name, err.trim_end());
    assert!(!o.status.success(), "succeeded: {args:?}");
    assert!(err.starts_with("error: "), "stderr: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "stderr: {err}");
    assert!(
        err.to_lowercase().contains(&needle.to_lowercase()),
        "{args:?}: {err} lacks {needle:?}"
    );
    assert!(!err.contains("panicked"), "{err}");
    if out.is_dir() {
        for f in sub.outputs {
            assert!(!out.join(f).exists(), "{f} written despite the error");
        }
        let leftovers: Vec<_> = std::fs::read_dir(out).unwrap().collect();
        assert!(leftovers.is_empty(), "left behind {leftovers:?}");
    }
    err
}

/// `dsc-seg segment FILE` on the image file at `file`, in `d`, fails as
/// [`fails`] checks, with `needle` in its one error line.
fn segment_fails_on(d: &tempfile::TempDir, file: &Path, needle: &str) -> String {
    fails(&SEGMENT, &[file.to_str().unwrap()], &empty_out(d), needle)
}

/// `dsc-seg segment` on a file named `name` holding `bytes` fails as
/// [`fails`] checks, with `needle` in its one error line.
fn segment_fails_on_bytes(name: &str, bytes: &[u8], needle: &str) -> String {
    let d = tmp();
    let p = d.path().join(name);
    std::fs::write(&p, bytes).unwrap();
    segment_fails_on(&d, &p, needle)
}

/// A directory this process cannot write into (mode 0o555), or `None` when
/// permissions are not enforced (as for root), where the case cannot be tested.
#[cfg(unix)]
pub(crate) fn read_only_dir(parent: &Path) -> Option<PathBuf> {
    use std::os::unix::fs::PermissionsExt;
    let d = parent.join("read_only");
    std::fs::create_dir(&d).unwrap();
    std::fs::set_permissions(&d, std::fs::Permissions::from_mode(0o555)).unwrap();
    let probe = d.join("probe");
    if std::fs::write(&probe, "x").is_ok() {
        std::fs::remove_file(&probe).unwrap();
        eprintln!("permissions not enforced (root?): read-only --out not tested");
        return None;
    }
    Some(d)
}

#[test]
fn segment_writes_every_output() {
    let d = tmp();
    let img = write_image(d.path(), 64, 48);
    let out = d.path().join("out");
    let o = bin()
        .args(["segment"])
        .arg(&img)
        .arg("--out")
        .arg(&out)
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        o.stderr.is_empty(),
        "--quiet printed {:?}",
        String::from_utf8_lossy(&o.stderr)
    );
    for f in [
        "labels.png",
        "overlay.png",
        "overlay.svg",
        "mesh.vtu",
        "report.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let labels = image::open(out.join("labels.png")).unwrap();
    assert_eq!((labels.width(), labels.height()), (64, 48));
    let l8 = labels.to_luma8();
    assert!(l8.pixels().all(|p| p[0] < 2));
    assert_eq!(l8.get_pixel(32, 24)[0], 1, "the bright disk is phase 1");
    assert_eq!(l8.get_pixel(1, 1)[0], 0);
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    for key in [
        "params",
        "iterations",
        "converged",
        "final_means",
        "energy",
        "flips",
        "times",
        "vertices",
        "cells",
    ] {
        assert!(report.get(key).is_some(), "report lacks {key}");
    }
    assert!(report["times"]["segment"].as_f64().unwrap() > 0.0);
    let vtu = std::fs::read_to_string(out.join("mesh.vtu")).unwrap();
    assert!(vtu.contains("phase"));
}

/// Runs `dsc-seg` with `args` and `--quiet --out DIR` and returns its report.
fn report_of_run(args: &[&str]) -> serde_json::Value {
    let d = tmp();
    let out = d.path().join("p");
    let o = bin()
        .args(args)
        .args(["--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap()
}

#[test]
fn segment_without_image_runs_a_phantom() {
    let report = report_of_run(&["segment", "--phantom", "two_phase", "--phantom-size", "96"]);
    let dice = report["truth_dice"].as_f64().unwrap();
    assert!(dice > 0.85, "dice {dice}");
}

/// A 3D phantom without `--phases` is segmented into its own number of
/// phases (the four-phase volume ran with 2 and lost half its phases
/// silently).
#[test]
fn segment3d_phantom_takes_its_number_of_phases() {
    let report = report_of_run(&[
        "segment3d",
        "--phantom",
        "four_phase",
        "--phantom-size",
        "24",
        "--max-iterations",
        "1",
        "--outputs",
        "report",
    ]);
    assert_eq!(report["params"]["phases"], 4);
}

#[test]
fn phantom_subcommand_writes_image_and_truth() {
    let d = tmp();
    let o = bin()
        .args([
            "phantom", "fig6", "--size", "32", "--noise", "0.1", "--seed", "3", "--out",
        ])
        .arg(d.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "fig6.png",
        "fig6_gt.png",
        "fig6_labels.png",
        "fig6_init.png",
    ] {
        assert!(d.path().join(f).is_file(), "{f}");
    }
    let o = bin()
        .args(["phantom", "nope", "--out"])
        .arg(d.path())
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).starts_with("error: unknown phantom"));
}

/// An input in the output folder under an output's name (`labels.png`
/// segmented into its own folder) is refused before any work, and left as
/// it was; another image in the same folder is segmented there.
#[test]
fn an_input_named_as_an_output_is_not_replaced() {
    let d = tmp();
    let input = d.path().join("labels.png");
    std::fs::rename(write_image(d.path(), 40, 32), &input).unwrap();
    let before = std::fs::read(&input).unwrap();
    let o = bin()
        .args(["segment", "--quiet", "--out"])
        .arg(d.path())
        .arg(&input)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("would replace its input"), "{err}");
    assert_eq!(std::fs::read(&input).unwrap(), before);
    assert!(!d.path().join("report.json").exists());
    let other = write_image(d.path(), 40, 32);
    let o = bin()
        .args(["segment", "--quiet", "--outputs", "report", "--out"])
        .arg(d.path())
        .arg(&other)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read(&input).unwrap(), before);
    // A label file given by another spelling of its path is spared too.
    let labels = write_labels(d.path(), 40, 32, 1);
    let out = d.path().join("sub");
    std::fs::create_dir(&out).unwrap();
    let spared = out.join("labels.png");
    std::fs::rename(&labels, &spared).unwrap();
    let roundabout = out.join("..").join("sub").join("labels.png");
    let o = bin()
        .args(["segment", "--quiet", "--init-labels"])
        .arg(&roundabout)
        .arg("--out")
        .arg(&out)
        .arg(&other)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("would replace its label file"), "{err}");
}

/// A two-phase image segmented into more phases than it holds: the phases
/// that end empty come after the others, so the labels are 0 and 1 and the
/// report's means are those of phases 0 and 1, the rest `null` (ranked by
/// the mean an empty phase keeps for the flips, the bright phase was
/// written as 3 of 4).
#[test]
fn empty_phases_are_numbered_last() {
    let d = tmp();
    let input = write_image(d.path(), 64, 64);
    let out = d.path().join("out");
    let o = bin()
        .args([
            "segment",
            "--quiet",
            "--phases",
            "4",
            "--outputs",
            "labels,report",
            "--out",
        ])
        .arg(&out)
        .arg(&input)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    let means = report["ordered_means"].as_array().unwrap();
    assert!(means[0].is_number() && means[1].is_number(), "{means:?}");
    assert!(means[2].is_null() && means[3].is_null(), "{means:?}");
    let labels = image::open(out.join("labels.png")).unwrap().into_luma8();
    let mut values: Vec<u8> = labels.pixels().map(|p| p[0]).collect();
    values.sort_unstable();
    values.dedup();
    assert_eq!(values, [0, 1]);
}

#[test]
fn missing_file() {
    let d = tmp();
    fails(
        &SEGMENT,
        &["/nonexistent/x.png"],
        &empty_out(&d),
        "cannot read",
    );
}

#[test]
fn not_an_image() {
    segment_fails_on_bytes("text.png", b"hello, not a picture", "not a readable image");
}

#[test]
fn zero_size_image() {
    // a PNG signature and an IHDR chunk declaring 0×0
    let mut bytes = vec![0x89, b'P', b'N', b'G', 0x0D, 0x0A, 0x1A, 0x0A];
    bytes.extend([0, 0, 0, 13]);
    bytes.extend(b"IHDR");
    bytes.extend([0, 0, 0, 0, 0, 0, 0, 0, 8, 0, 0, 0, 0]);
    bytes.extend([0, 0, 0, 0]);
    segment_fails_on_bytes("empty.png", &bytes, "image");
}

#[test]
fn truncated_png() {
    let d = tmp();
    let bytes = std::fs::read(write_image(d.path(), 32, 32)).unwrap();
    segment_fails_on_bytes(
        "cut.png",
        &bytes[..bytes.len() / 2],
        "cut.png is not a readable image",
    );
}

#[test]
fn corrupt_tiff_header() {
    // Little-endian TIFF magic, then a first-IFD offset far past the end.
    segment_fails_on_bytes(
        "bad.tif",
        b"II*\0\xff\xff\xff\x7fgarbage",
        "bad.tif is not a readable image",
    );
}

/// A 16-bit image with one value everywhere has nothing to separate.
#[test]
fn constant_16_bit_png() {
    let d = tmp();
    let p = d.path().join("flat16.png");
    image::ImageBuffer::<image::Luma<u16>, _>::from_pixel(24, 24, image::Luma([40_000u16]))
        .save(&p)
        .unwrap();
    segment_fails_on(&d, &p, "constant");
}

#[test]
fn one_pixel_image() {
    let d = tmp();
    let p = write_image(d.path(), 1, 1);
    segment_fails_on(&d, &p, "at least 2×2");
}

#[test]
fn bad_edge_lengths() {
    let d = tmp();
    let p = write_image(d.path(), 32, 32);
    let p = p.to_str().unwrap();
    let out = empty_out(&d);
    fails(&SEGMENT, &[p, "--edge-length", "NaN"], &out, "edge length");
    fails(&SEGMENT, &[p, "--edge-length", "-2"], &out, "edge length");
    fails(&SEGMENT, &[p, "--edge-length", "0"], &out, "edge length");
    fails(
        &SEGMENT,
        &[p, "--edge-length", "33"],
        &out,
        "must not exceed",
    );
    fails(
        &SEGMENT,
        &[p, "--edge-length", "inf"],
        &out,
        "positive number",
    );
    fails(
        &SEGMENT,
        &[p, "--edge-length", "1e-9"],
        &out,
        "at least 1 pixel",
    );
    fails(
        &SEGMENT,
        &[p, "--edge-length", "1e9"],
        &out,
        "must not exceed",
    );
}

/// NaN, infinite and out-of-range values of every float option, and absurd
/// counts, are refused before any work.
#[test]
fn bad_numeric_options() {
    let d = tmp();
    let p = write_image(d.path(), 32, 32);
    let p = p.to_str().unwrap();
    let out = empty_out(&d);
    for opt in [
        "--rigidity",
        "--elasticity",
        "--step-fraction",
        "--length-weight",
    ] {
        let name = opt.trim_start_matches("--").replace('-', "_");
        for v in ["NaN", "inf", "-inf", "-1", "1e300"] {
            if v == "1e300" && opt != "--step-fraction" {
                continue; // a huge weight is allowed, only pointless
            }
            fails(&SEGMENT, &[p, opt, v], &out, &name);
        }
    }
    fails(
        &SEGMENT,
        &[p, "--max-iterations", "0"],
        &out,
        "max_iterations",
    );
    // Values clap cannot parse get the same one-line error.
    fails(
        &SEGMENT,
        &[p, "--max-iterations", "-1"],
        &out,
        "--max-iterations",
    );
    fails(&SEGMENT, &[p, "--phases", "two"], &out, "--phases");
    fails(&SEGMENT, &[p, "--init", "bogus"], &out, "possible values");
    fails(&SEGMENT, &[p, "--no-such-option"], &out, "--no-such-option");
}

/// Phantom sizes and noise are checked before a phantom is generated.
#[test]
fn bad_phantom_options() {
    let d = tmp();
    let out = empty_out(&d);
    fails(
        &SEGMENT,
        &["--phantom-size", "0"],
        &out,
        "must lie in 8..=8192",
    );
    fails(
        &SEGMENT,
        &["--phantom-size", "100000"],
        &out,
        "must lie in 8..=8192",
    );
    fails(&SEGMENT, &["--phantom-noise", "NaN"], &out, "non-negative");
    fails(&SEGMENT, &["--phantom-noise=-0.1"], &out, "non-negative");
    fails(&SEGMENT, &["--phantom", "nope"], &out, "unknown phantom");
}

#[test]
fn bad_phase_counts() {
    let d = tmp();
    let p = write_image(d.path(), 32, 32);
    let p = p.to_str().unwrap();
    let out = empty_out(&d);
    fails(&SEGMENT, &[p, "--phases", "1"], &out, "between 2 and 64");
    fails(&SEGMENT, &[p, "--phases", "65"], &out, "between 2 and 64");
    fails(&SEGMENT, &[p, "--phases", "-3"], &out, "between 2 and 64");
    fails(&SEGMENT, &[p, "--phases", "255"], &out, "between 2 and 64");
}

#[test]
fn bad_init_labels() {
    let d = tmp();
    let p = write_image(d.path(), 32, 32);
    let p = p.to_str().unwrap();
    let out = empty_out(&d);
    let small = write_labels(d.path(), 16, 32, 1);
    fails(
        &SEGMENT,
        &[
            p,
            "--init",
            "labels",
            "--init-labels",
            small.to_str().unwrap(),
        ],
        &out,
        "32",
    );
    let many = write_labels(d.path(), 32, 32, 2);
    fails(
        &SEGMENT,
        &[
            p,
            "--init",
            "labels",
            "--init-labels",
            many.to_str().unwrap(),
        ],
        &out,
        "below the number of phases",
    );
    fails(&SEGMENT, &[p, "--init", "labels"], &out, "--init-labels");
    fails(&SEGMENT, &[p, "--init", "disks"], &out, "--disk");
    fails(
        &SEGMENT,
        &[p, "--init", "disks", "--disk", "1,2"],
        &out,
        "X,Y,R",
    );
    // a good label image works, and --init-labels alone implies --init labels
    let ok = write_labels(d.path(), 32, 32, 1);
    let ok = ok.to_str().unwrap();
    let given = ["--init-labels", ok];
    fails(
        &SEGMENT,
        &[p, "--init", "histogram", given[0], ok],
        &out,
        "--init labels",
    );
    fails(
        &SEGMENT,
        &[p, "--disk", "8,8,4", given[0], ok],
        &out,
        "two different starts",
    );
    for args in [&["--init", "labels"][..], &[]] {
        let o = bin()
            .args(["segment", p, "--no-label-flips", "--quiet"])
            .args(args)
            .args(given)
            .arg("--out")
            .arg(d.path().join("good"))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let report = std::fs::read(d.path().join("good/report.json")).unwrap();
        let report: serde_json::Value = serde_json::from_slice(&report).unwrap();
        let init = &report["params"]["init"];
        assert!(
            init.get("labels").is_some(),
            "{args:?}: started from {init}"
        );
    }
}

#[test]
fn unwritable_out() {
    let d = tmp();
    let p = write_image(d.path(), 32, 32);
    let file = d.path().join("a_file");
    std::fs::write(&file, "x").unwrap();
    fails(&SEGMENT, &[p.to_str().unwrap()], &file, "output directory");
    fails(
        &SEGMENT,
        &[p.to_str().unwrap()],
        &file.join("sub"),
        "output directory",
    );
    #[cfg(unix)]
    if let Some(ro) = read_only_dir(d.path()) {
        fails(&SEGMENT, &[p.to_str().unwrap()], &ro, "permission denied");
        fails(
            &SEGMENT,
            &[p.to_str().unwrap()],
            &ro.join("sub"),
            "permission denied",
        );
    }
}

/// A cube surface `[lo, hi]³` as an OFF file (12 consistently oriented triangles).
fn write_cube_off(dir: &Path, lo: f64, hi: f64) -> PathBuf {
    let p = dir.join("cube.off");
    let mut s = String::from("OFF\n8 12 0\n");
    for i in 0..8 {
        let c = |bit: usize| if i & bit != 0 { hi } else { lo };
        s += &format!("{} {} {}\n", c(1), c(2), c(4));
    }
    for q in [
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ] {
        s += &format!(
            "3 {} {} {}\n3 {} {} {}\n",
            q[0], q[1], q[2], q[0], q[2], q[3]
        );
    }
    std::fs::write(&p, s).unwrap();
    p
}

/// `segment3d --init-surface`: with the `tetgen` feature the run starts from
/// a TetGen mesh conforming to the surface; without it, one clear error line.
#[test]
fn segment3d_init_surface() {
    let d = tmp();
    let o = bin()
        .args([
            "phantom3d",
            "two_balls",
            "--size",
            "24",
            "--noise",
            "0.05",
            "--out",
        ])
        .arg(d.path())
        .output()
        .unwrap();
    assert!(o.status.success());
    let surface = write_cube_off(d.path(), 5.0, 19.0);
    let out = d.path().join("out");
    let o = bin()
        .arg("segment3d")
        .arg(d.path().join("two_balls.tif"))
        .arg("--init-surface")
        .arg(&surface)
        .args(["--max-iterations", "5", "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    if cfg!(feature = "tetgen") {
        assert!(o.status.success(), "{err}");
        let rep: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
        assert!(rep["init_surface"].as_str().unwrap().ends_with("cube.off"));
        assert!(rep["cells"].as_u64().unwrap() > 100);
        // A surface outside the box is refused with a clear message.
        let bad = write_cube_off(d.path(), -1.0, 10.0);
        let o = bin()
            .arg("segment3d")
            .arg(d.path().join("two_balls.tif"))
            .arg("--init-surface")
            .arg(&bad)
            .args(["--quiet", "--out"])
            .arg(d.path().join("bad"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success());
        assert!(
            err.starts_with("error: ") && err.contains("inside the volume box"),
            "{err}"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    } else {
        assert!(!o.status.success());
        assert!(err.starts_with("error: "), "{err}");
        assert!(err.contains("--features tetgen"), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(!out.join("report.json").exists());
    }
}

/// Parse errors are one line too, but asking for help (or giving no command)
/// still gets clap's full text.
#[test]
fn help_and_parse_errors() {
    let o = bin().output().unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("Usage: dsc-seg"));
    let o = bin().args(["segment3d", "--help"]).output().unwrap();
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("--edge-length"));
    let o = bin().args(["segment3d", "--phases", "2"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        err.trim_end(),
        "error: the following required arguments were not provided: --out <OUT> (see --help)"
    );
}

#[test]
fn disks_imply_their_init_and_must_touch_the_image() {
    let d = tmp();
    let img = write_image(d.path(), 32, 32);
    let img = img.to_str().unwrap();
    let out = empty_out(&d);
    fails(&SEGMENT, &[img, "--disk", "100,100,5"], &out, "outside");
    fails(
        &SEGMENT,
        &[img, "--init", "range", "--disk", "16,16,6"],
        &out,
        "--init disks",
    );
    // --disk alone starts from the disk.
    let o = bin()
        .args(["segment", img, "--disk", "16,16,6", "--max-iterations", "3"])
        .args(["--quiet", "--outputs", "report", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report = std::fs::read_to_string(out.join("report.json")).unwrap();
    let report: serde_json::Value = serde_json::from_str(&report).unwrap();
    assert!(
        report["params"]["init"].get("disks").is_some(),
        "{}",
        report["params"]["init"]
    );
}

#[test]
fn a_tiff_stack_given_to_segment_points_to_segment3d() {
    let d = tmp();
    let p = d.path().join("stack.tif");
    let data: Vec<u8> = (0..3 * 16 * 16).map(|i| (i % 7 * 30) as u8).collect();
    dsc_seg::io::save_labels_tiff(&p, [16, 16, 3], &data, None).unwrap();
    segment_fails_on(&d, &p, "segment3d");
}

#[test]
fn a_nifti_given_to_segment_points_to_segment3d() {
    let d = tmp();
    let p = d.path().join("volume.nii.gz");
    let data: Vec<f32> = (0..4 * 4 * 3).map(|i| (i % 5) as f32).collect();
    dsc_seg::io::save_nifti(&p, &dsc_seg::io::Volume::from_raw(4, 4, 3, data)).unwrap();
    segment_fails_on(
        &d,
        &p,
        "volume.nii.gz is a NIfTI volume of 4×4×3 voxels: `segment` reads 2D images, \
         segment it with `dsc-seg segment3d`",
    );
}

/// A sagittal slice (one voxel thick along x) is neither a slice `segment`
/// reads nor a volume `segment3d` meshes: `segment` says how to make it one
/// rather than pointing to `segment3d`, which refuses it as too thin.
#[test]
fn a_nifti_slice_thin_along_x_is_not_sent_to_segment3d() {
    let d = tmp();
    let p = d.path().join("sagittal.nii.gz");
    let data: Vec<f32> = (0..8 * 8).map(|i| (i % 5) as f32).collect();
    dsc_seg::io::save_nifti(&p, &dsc_seg::io::Volume::from_raw(1, 8, 8, data)).unwrap();
    let message = segment_fails_on(&d, &p, "thin axis the third");
    assert!(message.contains("one voxel thick along x"), "{message}");
    assert!(message.contains("fslswapdim IN y z x OUT"), "{message}");
    assert!(!message.contains("segment it with"), "{message}");
}

/// Writes `pages` 16×16 8-bit pages to `path`, the first carrying the
/// ImageJ description `desc` (as Fiji or tifffile would).
fn write_imagej_pages(path: &std::path::Path, desc: &str, pages: u8) {
    use tiff::encoder::{colortype, TiffEncoder};
    let mut enc = TiffEncoder::new(std::fs::File::create(path).unwrap()).unwrap();
    for page in 0..pages {
        let mut image = enc.new_image::<colortype::Gray8>(16, 16).unwrap();
        if page == 0 {
            let tag = tiff::tags::Tag::ImageDescription;
            image.encoder().write_tag(tag, desc).unwrap();
        }
        let data: Vec<u8> = (0..256u32).map(|i| (i % 5 * 40) as u8 + page).collect();
        image.write_data(&data).unwrap();
    }
}

/// A two-channel, two-slice ImageJ hyperstack is four pages, but not a
/// volume: both commands refuse it, naming its extents, rather than pointing
/// `segment`'s user to `segment3d` (which would take the channels for slices).
#[test]
fn an_imagej_hyperstack_is_refused_by_both_commands() {
    let d = tmp();
    let p = d.path().join("two_channels.tif");
    let desc = "ImageJ=1.11a\nimages=4\nchannels=2\nslices=2\nhyperstack=true\n";
    write_imagej_pages(&p, desc, 4);
    let input = [p.to_str().unwrap()];
    let extents = "2 channels × 2 slices × 1 time point";
    let out = empty_out(&d);
    fails(&SEGMENT, &input, &out, extents);
    fails(&SEGMENT3D, &input, &out, extents);
}

/// Five time points of one plane, as tifffile writes a `TYX` array with
/// `imagej=True`: not a volume (time would be meshed as depth), so both
/// commands refuse it as a time series, `segment` without pointing to
/// `segment3d`.
#[test]
fn an_imagej_time_series_is_refused_by_both_commands() {
    let d = tmp();
    let p = d.path().join("time_lapse.tif");
    let desc = "ImageJ=1.11a\nimages=5\nframes=5\nhyperstack=true\nmode=grayscale\nloop=false";
    write_imagej_pages(&p, desc, 5);
    let input = [p.to_str().unwrap()];
    let out = empty_out(&d);
    let said = "an ImageJ time series of 5 time points";
    let from_3d = fails(&SEGMENT3D, &input, &out, said);
    let from_2d = fails(&SEGMENT, &input, &out, said);
    assert!(from_3d.contains("time_lapse.tif is an ImageJ"), "{from_3d}");
    assert!(from_2d.contains("time_lapse.tif is an ImageJ"), "{from_2d}");
    assert!(!from_2d.contains("segment3d"), "{from_2d}");
}

#[test]
fn a_colour_image_is_said_to_be_segmented_as_its_luminance() {
    let d = tmp();
    let p = d.path().join("rgb.png");
    image::RgbImage::from_fn(32, 32, |x, y| {
        let inside = (x as i32 - 16).pow(2) + (y as i32 - 16).pow(2) < 64;
        let noise = ((x * 7 + y * 13) % 11) as u8 * 3;
        image::Rgb(if inside {
            [200, 60 + noise, 40]
        } else {
            [30, 90 + noise, 160]
        })
    })
    .save(&p)
    .unwrap();
    let o = bin()
        .arg("segment")
        .arg(&p)
        .args([
            "--max-iterations",
            "3",
            "--quiet",
            "--outputs",
            "labels",
            "--out",
        ])
        .arg(empty_out(&d))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("luminance"));

    // --channel 2 takes the blue channel: the disk is phase 0 (darker), no note.
    let out = d.path().join("run1");
    let o = bin()
        .arg("segment")
        .arg(&p)
        .args([
            "--channel",
            "2",
            "--quiet",
            "--outputs",
            "labels,report",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("luminance"));
    let labels = image::open(out.join("labels.png")).unwrap().to_luma8();
    assert_eq!(labels.get_pixel(16, 16)[0], 0);
    assert_eq!(labels.get_pixel(2, 2)[0], 1);
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(
        report["input"]["colour"],
        serde_json::json!({ "channel": 2 })
    );
    // Means in the blue channel's units: 40 inside, 160 outside.
    let means = report["input"]["phase_means"].as_array().unwrap();
    assert!((means[0].as_f64().unwrap() - 40.0).abs() < 5.0, "{means:?}");

    let message = fails(
        &SEGMENT,
        &["--channel", "4", p.to_str().unwrap()],
        &d.path().join("run2"),
        "channel",
    );
    assert!(
        message.contains("has no channel 4: it has 3 (0 to 2)"),
        "{message}"
    );
}

#[test]
fn pixel_size_from_spacing_and_tiff_resolution_reaches_the_outputs() {
    let d = tmp();
    let png = write_image(d.path(), 40, 30);
    let out = d.path().join("run3");
    let o = bin()
        .arg("segment")
        .arg(&png)
        .args([
            "--spacing",
            "0.5,0.25",
            "--max-iterations",
            "3",
            "--quiet",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.join("phases.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .map(|v| v.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    let total: f64 = rows.iter().map(|r| r[2]).sum();
    assert!((total - 40.0 * 30.0 * 0.125).abs() < 1e-9, "{csv}");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(
        report["frame"]["spacing"],
        serde_json::json!([0.5, 0.25, 1.0])
    );
    assert_eq!(report["frame"]["source"], "given");
    // A PNG's bottom row stays at y = 0, as vtkPNGReader would place it with
    // that spacing; the given sizes have no unit, so the neutral one.
    assert_eq!(report["frame"]["index_to_world"][1][3], 29.0 * 0.25);
    assert_eq!(report["frame"]["unit"], "unit");
    assert!(csv.starts_with("phase,count,pv_area_unit2,"), "{csv}");
    assert!(
        !out.join("labels.tif").exists(),
        "a PNG input gives labels.png only"
    );
    fails(
        &SEGMENT,
        &["--spacing", "1,0", png.to_str().unwrap()],
        &d.path().join("run4"),
        "2 positive numbers X,Y",
    );

    // A TIFF with resolution tags (200 pixels per cm): labels.tif keeps them.
    let tif = d.path().join("scan.tif");
    {
        use tiff::encoder::{colortype::Gray8, Rational, TiffEncoder};
        use tiff::tags::ResolutionUnit;
        let gray = image::open(&png).unwrap().to_luma8();
        let mut enc = TiffEncoder::new(std::fs::File::create(&tif).unwrap()).unwrap();
        let mut page = enc.new_image::<Gray8>(40, 30).unwrap();
        page.resolution(ResolutionUnit::Centimeter, Rational { n: 200, d: 1 });
        page.write_data(gray.as_raw()).unwrap();
    }
    let out = d.path().join("run5");
    let o = bin()
        .arg("segment")
        .arg(&tif)
        .args([
            "--max-iterations",
            "3",
            "--quiet",
            "--outputs",
            "labels,report",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let frame = |path: &Path| dsc_seg::io::resolution::image_frame(path, 40, 30);
    let labels = out.join("labels.tif");
    assert_eq!(frame(&labels).spacing, frame(&tif).spacing);
    assert_eq!(frame(&labels).unit, "mm");
    assert!((frame(&labels).spacing[0] - 0.05).abs() < 1e-12);
    let png_labels = image::open(out.join("labels.png")).unwrap().to_luma8();
    let tif_labels = image::open(&labels).unwrap().to_luma8();
    assert_eq!(png_labels.as_raw(), tif_labels.as_raw());
}

/// A rerun with fewer outputs into the same folder names the files it left
/// from the earlier run (it does not delete them: they may be the user's).
#[test]
fn a_rerun_with_fewer_outputs_names_the_earlier_files() {
    let d = tmp();
    let png = write_image(d.path(), 40, 30);
    let out = d.path().join("out");
    let run = |outputs: &str| {
        let o = bin()
            .arg("segment")
            .arg(&png)
            .args([
                "--quiet",
                "--max-iterations",
                "2",
                "--outputs",
                outputs,
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    assert!(!run("all").contains("note:"));
    let second = run("labels,report");
    assert!(
        second.contains("note: ") && second.contains("overlay.png") && second.contains("mesh.vtu"),
        "{second}"
    );
    assert!(
        !second.contains("labels.png") && !second.contains("report.json"),
        "{second}"
    );
    assert!(out.join("overlay.png").is_file(), "not deleted");
}
