//! The same input and parameters give bit-identical outputs, across runs and
//! across thread counts.

use std::path::Path;
use std::process::Command;

fn segment(out: &Path, threads: &str) -> (Vec<u8>, Vec<u8>) {
    let status = Command::new(env!("CARGO_BIN_EXE_dsc-seg"))
        .args([
            "segment",
            "--phantom",
            "four_phase",
            "--phantom-size",
            "128",
            "--quiet",
            "--max-iterations",
            "60",
            "--out",
        ])
        .arg(out)
        .env("RAYON_NUM_THREADS", threads)
        .status()
        .expect("run dsc-seg");
    assert!(status.success());
    (
        std::fs::read(out.join("labels.png")).unwrap(),
        std::fs::read(out.join("mesh.vtu")).unwrap(),
    )
}

#[test]
fn outputs_are_bit_identical_across_runs_and_thread_counts() {
    let dir = tempfile::tempdir().unwrap();
    let one = segment(&dir.path().join("one"), "1");
    let two = segment(&dir.path().join("two"), "2");
    let again = segment(&dir.path().join("again"), "2");
    assert!(one.0 == two.0, "labels.png differs between 1 and 2 threads");
    assert!(one.1 == two.1, "mesh.vtu differs between 1 and 2 threads");
    assert!(two == again, "outputs differ between two identical runs");
}
