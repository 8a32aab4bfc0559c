//! What the command line tells a user: warnings on stderr and in
//! `report.json`'s top-level `warnings`, errors that name the file and say
//! what is wrong in the file's terms, and the exit codes of the README (2
//! for options that do not parse or fit, 1 for a failed run).

use crate::cli::{bin, tmp};
use crate::common::save_f32_tiff;
use std::path::Path;
use std::process::Output;

fn run(args: &[&str], out: &Path) -> Output {
    bin()
        .args(args)
        .args(["--quiet", "--out"])
        .arg(out)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A run stopped at the iteration cap says so on stderr and in the report,
/// naming the option that raises the cap.
#[test]
fn a_run_at_the_iteration_cap_warns() {
    let d = tmp();
    let out = d.path().join("o");
    let args = [
        "segment",
        "--phantom-size",
        "64",
        "--max-iterations",
        "2",
        "--outputs",
        "report",
    ];
    let o = run(&args, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("warning: the run stopped at the iteration cap (2 iterations)"),
        "{}",
        stderr(&o)
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["converged"], false);
    let warnings = report["warnings"].as_array().expect("top-level warnings");
    assert!(
        warnings
            .iter()
            .any(|w| w.as_str().unwrap().contains("--max-iterations")),
        "{warnings:?}"
    );
}

/// A constant image's error gives the value as the file stores it (not
/// the loaded 1000/65535).
#[test]
fn a_constant_image_is_named_by_its_file_value() {
    let d = tmp();
    let path = d.path().join("c.png");
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(16, 16, vec![1000u16; 256])
        .unwrap()
        .save(&path)
        .unwrap();
    let o = run(&["segment", path.to_str().unwrap()], &d.path().join("o"));
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("every sample is 1000)"),
        "{}",
        stderr(&o)
    );
}

/// A 2D image with NaN samples is refused with its name and their count,
/// as a volume is.
#[test]
fn a_2d_image_with_nan_names_the_file_and_the_count() {
    let d = tmp();
    let path = d.path().join("nan.tif");
    let mut data = vec![0.0f32; 256];
    data[..128].fill(1.0);
    data[3] = f32::NAN;
    data[200] = f32::INFINITY;
    save_f32_tiff(&path, 16, &data);
    let o = run(&["segment", path.to_str().unwrap()], &d.path().join("o"));
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("nan.tif") && e.contains("2 of 256 samples"),
        "{e}"
    );
}

/// A NIfTI-2 file is refused as unsupported, not as malformed.
#[test]
fn a_nifti_2_file_is_named_as_such() {
    let d = tmp();
    let path = d.path().join("v.nii");
    let mut header = vec![0u8; 600];
    header[..4].copy_from_slice(&540i32.to_le_bytes());
    std::fs::write(&path, header).unwrap();
    let o = run(&["segment3d", path.to_str().unwrap()], &d.path().join("o"));
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("NIfTI-2") && !e.contains("malformed"), "{e}");
}

/// `segment3d --phases auto` is a usage error that says auto is for 2D.
#[test]
fn phases_auto_in_3d_is_a_usage_error_that_says_why() {
    let d = tmp();
    let o = run(&["segment3d", "--phases", "auto"], &d.path().join("o"));
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("2D images only"), "{}", stderr(&o));
}

/// An output list that does not parse exits 2, as the README says of
/// options that do not parse; so does a value out of its range, whether
/// checked on parsing, against the parameters' ranges once the input is
/// loaded, or by the phantom generator.
#[test]
fn bad_option_values_exit_2() {
    let d = tmp();
    for args in [
        &["segment", "--outputs", "foo"][..],
        &["segment3d", "--outputs", "overlay"][..],
        &["segment", "--phases", "99"][..],
        &["segment", "--phantom-size", "64", "--rigidity", "-1"][..],
        &["segment", "--phantom-size", "64", "--edge-length", "0"][..],
        &["segment", "--phantom-size", "64", "--step-fraction", "0.9"][..],
        &["segment", "--phantom-size", "4"][..],
        &["segment3d", "--phantom", "nope"][..],
        &["segment3d", "--phantom-size", "24", "--length-weight", "-1"][..],
        // --jobs matters only to batches, but 0 is refused for one input too.
        &["segment", "--phantom-size", "64", "--jobs", "0"][..],
        // A start shape outside the image would label nothing.
        &["segment", "--phantom-size", "64", "--disk", "500,500,10"][..],
        &["segment3d", "--phantom-size", "24", "--ball", "12,12,12,-2"][..],
        &[
            "segment3d",
            "--phantom-size",
            "24",
            "--finish-rigidity",
            "0",
        ][..],
    ] {
        let o = run(args, &d.path().join("o"));
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(!d.path().join("o").exists(), "{args:?} created --out");
    }
    for args in [
        &["phantom", "nope"][..],
        &["phantom", "two_phase", "--size", "4"][..],
        &["phantom3d", "torus", "--noise", "-1"][..],
    ] {
        let o = bin()
            .args(args)
            .arg("--out")
            .arg(d.path().join("o"))
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(!d.path().join("o").exists(), "{args:?} created --out");
    }
}

/// A 192² two-phase image whose noise is smoothed over a few pixels (as a
/// reconstructed CT or MRI slice's), of σ `sigma` after smoothing, levels
/// 0.4 and 0.6, as 16-bit PNG.
fn correlated_noise_image(path: &Path, sigma: f64) {
    const SIDE: usize = 192;
    let mut image: Vec<f32> = (0..SIDE * SIDE)
        .map(|i| {
            let (x, y) = ((i % SIDE) as f32 - 96.0, (i / SIDE) as f32 - 96.0);
            if x * x + y * y < 50.0 * 50.0 {
                0.6
            } else {
                0.4
            }
        })
        .collect();
    dsc_seg::phantom::noise::add_smoothed_noise_2d(&mut image, SIDE, sigma, 3, 5);
    let samples: Vec<u16> = image.iter().map(|&v| (v * 65535.0) as u16).collect();
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(SIDE as u32, SIDE as u32, samples)
        .unwrap()
        .save(path)
        .unwrap();
}

/// Noise in blobs of a few pixels, at a third of the gap between the
/// phases, is named on stderr and in the report; the same noise at a
/// twentieth of the gap is not (it cannot move a label).
#[test]
fn strong_correlated_noise_warns() {
    let d = tmp();
    for (sigma, warns) in [(0.07, true), (0.01, false)] {
        let image = d.path().join(format!("corr_{sigma}.png"));
        correlated_noise_image(&image, sigma);
        let out = d.path().join(format!("o_{sigma}"));
        let args = ["segment", image.to_str().unwrap(), "--outputs", "report"];
        let o = run(&args, &out);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(
            stderr(&o).contains("warning: the image's noise is spatially correlated"),
            warns,
            "σ {sigma}: {}",
            stderr(&o)
        );
        let report: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
        let rho = report["segmentation"]["intensity"]["noise_correlation"]
            .as_f64()
            .expect("a correlation figure");
        assert!(rho > 0.5, "σ {sigma}: {rho}");
        let named = report["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w.as_str().unwrap().contains("--length-weight"));
        assert_eq!(named, warns, "σ {sigma}: {}", report["warnings"]);
    }
}

/// `--phases auto` on pure noise keeps two phases and says once why they
/// are not two regions: its warning stands in for the run's own about a
/// lost phase, which would also speak of two phases "asked for".
#[test]
fn phases_auto_on_noise_warns_once() {
    let d = tmp();
    let n = 96;
    let mut noise = vec![0.5f32; n * n];
    dsc_seg::phantom::noise::add_gaussian_noise(&mut noise, 0.1, 1);
    let samples: Vec<u8> = noise.iter().map(|&v| (v * 255.0).round() as u8).collect();
    let image = d.path().join("noise.png");
    image::GrayImage::from_raw(n as u32, n as u32, samples)
        .unwrap()
        .save(&image)
        .unwrap();
    let out = d.path().join("o");
    let args = [
        "segment",
        image.to_str().unwrap(),
        "--phases",
        "auto",
        "--outputs",
        "report",
    ];
    let o = run(&args, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let printed: Vec<String> = stderr(&o)
        .lines()
        .filter(|l| l.starts_with("warning: "))
        .map(String::from)
        .collect();
    assert_eq!(printed.len(), 1, "{printed:?}");
    assert!(
        printed[0].contains("no two distinct regions"),
        "{printed:?}"
    );
    assert!(
        printed[0].contains("single phase: with two, "),
        "{printed:?}"
    );
    assert!(!printed[0].contains("asked for"), "{printed:?}");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(
        report["warnings"].as_array().unwrap().len(),
        1,
        "{report:?}"
    );
    assert_eq!(report["warnings"][0], printed[0]["warning: ".len()..]);
}

/// A 2×2 checkerboard: every cell of its mesh flips at every iteration,
/// which ran to the iteration cap. The run stops once its labels have
/// swapped for a few iterations, and the last line says so rather than
/// speak of the cap.
#[test]
fn a_run_whose_labels_swap_says_so_in_its_last_line() {
    let d = tmp();
    let image = d.path().join("checker.png");
    image::GrayImage::from_raw(2, 2, vec![0, 255, 255, 0])
        .unwrap()
        .save(&image)
        .unwrap();
    let out = d.path().join("o");
    // (without --quiet: the last line is the summary)
    let o = bin()
        .args([
            "segment",
            image.to_str().unwrap(),
            "--outputs",
            "report",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stderr(&o);
    assert!(text.contains("labels swapped between states"), "{text}");
    let last = text.lines().last().unwrap_or_default();
    assert!(
        last.starts_with("stopped with its labels swapping"),
        "{last}"
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["converged"], false);
    assert_eq!(report["segmentation"]["stop_reason"], "swapping_labels");
}
