//! The `dsc-seg` command: outputs on success, and one clear error line and a
//! non-zero exit for every kind of bad input (issue 3, must-show 4).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_dsc-seg"))
}

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
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

/// Runs `dsc-seg segment` with `args`, expects failure with a one-line
/// `error: ...` mentioning `needle`, and an output directory without outputs.
fn fails(args: &[&str], out: &Path, needle: &str) {
    let o: Output = bin()
        .arg("segment")
        .args(args)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "succeeded: {args:?}");
    assert!(err.starts_with("error: "), "stderr: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "stderr: {err}");
    assert!(
        err.to_lowercase().contains(&needle.to_lowercase()),
        "{args:?}: {err} lacks {needle:?}"
    );
    assert!(!err.contains("panicked"));
    if out.is_dir() {
        for f in [
            "labels.png",
            "overlay.png",
            "overlay.svg",
            "mesh.vtu",
            "report.json",
        ] {
            assert!(!out.join(f).exists(), "{f} written despite the error");
        }
        let leftovers: Vec<_> = std::fs::read_dir(out).unwrap().collect();
        assert!(leftovers.is_empty(), "left behind {leftovers:?}");
    }
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

#[test]
fn segment_without_image_runs_a_phantom() {
    let d = tmp();
    let out = d.path().join("p");
    let o = bin()
        .args([
            "segment",
            "--phantom",
            "two_phase",
            "--phantom-size",
            "96",
            "--quiet",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    let dice = report["truth_dice"].as_f64().unwrap();
    assert!(dice > 0.85, "dice {dice}");
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

#[test]
fn missing_file() {
    let d = tmp();
    fails(&["/nonexistent/x.png"], &d.path().join("o"), "cannot read");
}

#[test]
fn not_an_image() {
    let d = tmp();
    let p = d.path().join("text.png");
    std::fs::write(&p, "hello, not a picture").unwrap();
    fails(
        &[p.to_str().unwrap()],
        &d.path().join("o"),
        "not a readable image",
    );
}

#[test]
fn zero_size_image() {
    let d = tmp();
    // a PNG signature and an IHDR chunk declaring 0×0
    let mut bytes = vec![0x89, b'P', b'N', b'G', 0x0D, 0x0A, 0x1A, 0x0A];
    bytes.extend([0, 0, 0, 13]);
    bytes.extend(b"IHDR");
    bytes.extend([0, 0, 0, 0, 0, 0, 0, 0, 8, 0, 0, 0, 0]);
    bytes.extend([0, 0, 0, 0]);
    let p = d.path().join("empty.png");
    std::fs::write(&p, bytes).unwrap();
    fails(&[p.to_str().unwrap()], &d.path().join("o"), "image");
}

#[test]
fn one_pixel_image() {
    let d = tmp();
    let p = write_image(d.path(), 1, 1);
    fails(&[p.to_str().unwrap()], &d.path().join("o"), "at least 2×2");
}

#[test]
fn bad_edge_lengths() {
    let d = tmp();
    let p = write_image(d.path(), 32, 32);
    let p = p.to_str().unwrap();
    let out = d.path().join("o");
    fails(&[p, "--edge-length", "NaN"], &out, "edge length");
    fails(&[p, "--edge-length", "-2"], &out, "edge length");
    fails(&[p, "--edge-length", "0"], &out, "edge length");
    fails(&[p, "--edge-length", "33"], &out, "must not exceed");
}

#[test]
fn bad_phase_counts() {
    let d = tmp();
    let p = write_image(d.path(), 32, 32);
    let p = p.to_str().unwrap();
    let out = d.path().join("o");
    fails(&[p, "--phases", "1"], &out, "between 2 and 64");
    fails(&[p, "--phases", "65"], &out, "between 2 and 64");
    fails(&[p, "--phases", "-3"], &out, "between 2 and 64");
}

#[test]
fn bad_init_labels() {
    let d = tmp();
    let p = write_image(d.path(), 32, 32);
    let p = p.to_str().unwrap();
    let out = d.path().join("o");
    let small = write_labels(d.path(), 16, 32, 1);
    fails(
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
    fails(&[p, "--init", "labels"], &out, "--init-labels");
    fails(&[p, "--init", "disks"], &out, "--disk");
    fails(&[p, "--init", "disks", "--disk", "1,2"], &out, "X,Y,R");
    // a good label image works
    let ok = write_labels(d.path(), 32, 32, 1);
    let o = bin()
        .args([
            "segment",
            p,
            "--init",
            "labels",
            "--no-label-flips",
            "--quiet",
            "--init-labels",
        ])
        .arg(&ok)
        .arg("--out")
        .arg(d.path().join("good"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn unwritable_out() {
    let d = tmp();
    let p = write_image(d.path(), 32, 32);
    let file = d.path().join("a_file");
    std::fs::write(&file, "x").unwrap();
    fails(&[p.to_str().unwrap()], &file, "output directory");
    fails(
        &[p.to_str().unwrap()],
        &file.join("sub"),
        "output directory",
    );
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
