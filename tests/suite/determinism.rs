//! The same input and parameters give bit-identical outputs, across runs and
//! across thread counts.

use std::path::Path;
use std::process::Command;

/// Runs `dsc-seg` with `args` on `threads` rayon threads; returns the bytes
/// of `labels` and `mesh.vtu`.
fn run(args: &[&str], labels: &str, out: &Path, threads: &str) -> (Vec<u8>, Vec<u8>) {
    let status = Command::new(env!("CARGO_BIN_EXE_dsc-seg"))
        .args(args)
        .args(["--quiet", "--out"])
        .arg(out)
        .env("RAYON_NUM_THREADS", threads)
        .status()
        .expect("run dsc-seg");
    assert!(status.success());
    (
        std::fs::read(out.join(labels)).unwrap(),
        std::fs::read(out.join("mesh.vtu")).unwrap(),
    )
}

/// Runs `args` on 1 thread, on 2 threads and on 2 threads again: the labels
/// file `labels` and `mesh.vtu` must be the same bytes every time.
fn assert_bit_identical(args: &[&str], labels: &str) {
    let dir = tempfile::tempdir().unwrap();
    let one = run(args, labels, &dir.path().join("one"), "1");
    let two = run(args, labels, &dir.path().join("two"), "2");
    let again = run(args, labels, &dir.path().join("again"), "2");
    assert!(one.0 == two.0, "{labels} differs between 1 and 2 threads");
    assert!(one.1 == two.1, "mesh.vtu differs between 1 and 2 threads");
    assert!(two == again, "outputs differ between two identical runs");
}

#[test]
fn outputs_are_bit_identical_across_runs_and_thread_counts() {
    assert_bit_identical(
        &[
            "segment",
            "--phantom",
            "four_phase",
            "--phantom-size",
            "128",
            "--max-iterations",
            "60",
        ],
        "labels.png",
    );
}

/// The 3D default (adaptive, coarse start) on the four-phase volume, whose
/// junction curves and graded mesh exercise every parallel section.
#[test]
fn volume_outputs_are_bit_identical_across_runs_and_thread_counts() {
    assert_bit_identical(
        &[
            "segment3d",
            "--phantom",
            "four_phase",
            "--phantom-size",
            "40",
            "--phantom-noise",
            "0.2",
            "--phases",
            "4",
            "--max-iterations",
            "25",
        ],
        "labels.tif",
    );
}
