//! Batch runs of the command line: several inputs or folders into
//! `--out/<stem>/` with a summary table, bad inputs in their rows, complete
//! outputs skipped, output choice, shards, and clean interruption.

use crate::cli::{bin, tmp};
use std::path::{Path, PathBuf};
use std::process::Output;

/// A noisy two-phase PNG of side `size` (a bright disk at a seed-dependent place).
fn write_disk(dir: &Path, name: &str, size: u32, seed: u32) -> PathBuf {
    let p = dir.join(name);
    let c = size as f64 * (0.4 + 0.05 * (seed % 4) as f64);
    image::GrayImage::from_fn(size, size, |x, y| {
        let (dx, dy) = (x as f64 - c, y as f64 - c);
        let inside = dx * dx + dy * dy < (size as f64 / 4.0).powi(2);
        let noise = ((x * 7 + y * 13 + seed * 5) % 11) as u8 * 3;
        image::Luma([if inside { 180 } else { 70 } + noise])
    })
    .save(&p)
    .unwrap();
    p
}

fn run(args: &[&str], inputs: &[&Path], out: &Path) -> Output {
    bin()
        .arg("segment")
        .args(inputs)
        .arg("--out")
        .arg(out)
        .args(args)
        .output()
        .unwrap()
}

/// The summary table's rows (header first) as fields.
fn summary(path: &Path) -> Vec<Vec<String>> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_path(path)
        .unwrap();
    r.records()
        .map(|rec| rec.unwrap().iter().map(str::to_string).collect())
        .collect()
}

fn row<'a>(rows: &'a [Vec<String>], name: &str) -> &'a [String] {
    rows.iter().find(|r| r[0] == name).unwrap()
}

/// Every staging folder or temporary file (`.dsc-seg-staging-*`,
/// `.dsc-seg-tmp-*`) under `dir`.
fn staging_left(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return found;
    };
    for e in entries.flatten() {
        let p = e.path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if name.starts_with(".dsc-seg-staging-") || name.starts_with(".dsc-seg-tmp-") {
            found.push(p.clone());
        }
        if p.is_dir() {
            found.extend(staging_left(&p));
        }
    }
    found
}

const OUTPUTS_2D: [&str; 5] = [
    "labels.png",
    "overlay.png",
    "overlay.svg",
    "mesh.vtu",
    "report.json",
];

#[test]
fn folder_with_a_corrupt_file_runs_the_others_and_skips_them_next_time() {
    let d = tmp();
    let folder = d.path().join("images");
    std::fs::create_dir(&folder).unwrap();
    for (i, name) in ["a.png", "b.png", "c.png"].iter().enumerate() {
        write_disk(&folder, name, 48, i as u32);
    }
    std::fs::write(folder.join("broken.png"), b"not a png at all").unwrap();
    std::fs::write(folder.join("notes.txt"), b"not an image").unwrap();
    let out = d.path().join("out");

    let missing = d.path().join("missing.png");
    let first = run(&["--quiet", "--jobs", "2"], &[&folder, &missing], &out);
    let err = String::from_utf8_lossy(&first.stderr);
    assert_eq!(first.status.code(), Some(1), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("2 of 5 inputs failed"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for stem in ["a", "b", "c"] {
        for f in OUTPUTS_2D {
            assert!(out.join(stem).join(f).is_file(), "{stem}/{f} missing");
        }
    }
    assert!(!out.join("broken").join("labels.png").exists());
    assert!(staging_left(&out).is_empty(), "{:?}", staging_left(&out));
    let rows = summary(&out.join("summary.csv"));
    assert_eq!(
        rows[0],
        [
            "name",
            "input",
            "phases",
            "iterations",
            "converged",
            "seconds",
            "status",
            "error",
            "warnings"
        ]
    );
    assert_eq!(rows.len(), 6);
    let broken = row(&rows, "broken");
    assert_eq!(broken[6], "error");
    assert!(broken[7].contains("broken.png"), "{broken:?}");
    let missing_row = row(&rows, "missing");
    assert_eq!(missing_row[6], "error");
    assert!(missing_row[7].contains("missing.png"), "{missing_row:?}");
    for stem in ["a", "b", "c"] {
        let r = row(&rows, stem);
        assert_eq!((r[2].as_str(), r[6].as_str()), ("2", "done"), "{r:?}");
        assert!(r[3].parse::<usize>().unwrap() > 0);
    }

    // The batch's labels are those of a single run of the same image.
    let single = d.path().join("single");
    let o = run(&["--quiet"], &[&folder.join("b.png")], &single);
    assert!(o.status.success());
    assert_eq!(
        std::fs::read(single.join("labels.png")).unwrap(),
        std::fs::read(out.join("b/labels.png")).unwrap()
    );

    // Again: the complete ones are skipped (their files untouched).
    let stamp = |p: PathBuf| std::fs::metadata(p).unwrap().modified().unwrap();
    let before = stamp(out.join("a/mesh.vtu"));
    let second = run(&["--quiet"], &[&folder, &missing], &out);
    assert_eq!(second.status.code(), Some(1));
    let rows = summary(&out.join("summary.csv"));
    for stem in ["a", "b", "c"] {
        assert_eq!(row(&rows, stem)[6], "skipped");
        assert_eq!(row(&rows, stem)[2], "2");
    }
    assert_eq!(row(&rows, "broken")[6], "error");
    assert_eq!(stamp(out.join("a/mesh.vtu")), before);

    // Other options or --force redo them.
    let third = run(&["--quiet", "--max-iterations", "3"], &[&folder], &out);
    assert_eq!(third.status.code(), Some(1));
    let rows = summary(&out.join("summary.csv"));
    assert_eq!(row(&rows, "a")[6], "done");
    assert_eq!(row(&rows, "a")[3], "3");
    let fourth = run(
        &["--quiet", "--max-iterations", "3", "--force"],
        &[&folder.join("a.png")],
        &out,
    );
    // One file is a single run, not a batch: its outputs go into --out itself.
    assert!(fourth.status.success());
    assert!(out.join("labels.png").is_file());
}

#[test]
fn outputs_shards_and_clashing_names() {
    let d = tmp();
    let a = write_disk(d.path(), "a.png", 40, 1);
    let b = write_disk(d.path(), "b.png", 40, 2);
    let out = d.path().join("out");
    let o = run(
        &["--quiet", "--outputs", "labels,report", "--shard", "1/2"],
        &[&a, &b],
        &out,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        !out.join("a").exists(),
        "shard 1/2 takes the second input only"
    );
    assert!(out.join("b/labels.png").is_file());
    assert!(out.join("b/report.json").is_file());
    assert!(!out.join("b/mesh.vtu").exists());
    assert!(!out.join("b/overlay.png").exists());
    let rows = summary(&out.join("summary-1-of-2.csv"));
    assert_eq!(rows.len(), 2);

    let other = d.path().join("other");
    std::fs::create_dir(&other).unwrap();
    let a2 = write_disk(&other, "a.png", 40, 3);
    // Two inputs named alike: each folder's name tells them apart.
    let named = d.path().join("named");
    let o = run(&["--quiet", "--outputs", "report"], &[&a, &a2], &named);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let holder = d.path().file_name().unwrap().to_string_lossy().into_owned();
    assert!(named.join(format!("{holder}_a/report.json")).is_file());
    assert!(named.join("other_a/report.json").is_file());
    let rows = summary(&named.join("summary.csv"));
    assert_eq!(row(&rows, "other_a")[6], "done");
    for bad in [
        ["--outputs", "labels,overlay3"],
        ["--shard", "2/2"],
        ["--jobs", "0"],
    ] {
        let o = run(&bad, &[&a, &b], &d.path().join("bad"));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{bad:?}");
        assert!(
            err.starts_with("error: ") && err.contains(bad[1]),
            "{bad:?}: {err}"
        );
        assert!(!d.path().join("bad").join("a").exists());
    }
}

#[test]
fn batch_of_volumes() {
    let d = tmp();
    let vols = d.path().join("vols");
    let o = bin()
        .args(["phantom3d", "two_balls", "--size", "16", "--out"])
        .arg(&vols)
        .output()
        .unwrap();
    assert!(o.status.success());
    std::fs::write(vols.join("zz_broken.tif"), b"II*\0garbage").unwrap();
    let out = d.path().join("out");
    let o = bin()
        .args([
            "segment3d",
            "--quiet",
            "--max-iterations",
            "4",
            "--outputs",
            "labels",
        ])
        .arg(&vols)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let rows = summary(&out.join("summary.csv"));
    assert_eq!(rows.len(), 4, "{rows:?}");
    assert_eq!(row(&rows, "two_balls")[6], "done");
    assert_eq!(row(&rows, "two_balls_labels")[6], "done");
    assert_eq!(row(&rows, "zz_broken")[6], "error");
    assert!(out.join("two_balls/labels.tif").is_file());
    assert!(!out.join("two_balls/mesh.vtu").exists());
}

/// Ctrl-C (SIGINT) in the middle of a batch and SIGTERM in the middle of a
/// single run remove every staging folder and leave no half-written output;
/// the exit code is 128 + the signal's number, as a shell reports it.
#[cfg(unix)]
#[test]
fn interrupted_runs_leave_no_staging_folders() {
    let d = tmp();
    let folder = d.path().join("images");
    std::fs::create_dir(&folder).unwrap();
    for i in 0..8 {
        write_disk(&folder, &format!("i{i}.png"), 160, i);
    }
    for (batch, signal, code) in [(true, "-INT", 130), (false, "-TERM", 143)] {
        let out = d.path().join(format!("out_{batch}"));
        let mut cmd = bin();
        cmd.arg("segment").arg("--quiet").arg("--out").arg(&out);
        if batch {
            cmd.arg(&folder).args(["--jobs", "2"]);
        } else {
            cmd.args(["--phantom-size", "512", "--max-iterations", "100000"]);
        }
        let child = cmd.stderr(std::process::Stdio::piped()).spawn().unwrap();
        let started = std::time::Instant::now();
        while staging_left(&out).is_empty() {
            assert!(started.elapsed().as_secs() < 60, "no staging folder seen");
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        let kill = std::process::Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status()
            .unwrap();
        assert!(kill.success());
        let finished = child.wait_with_output().unwrap();
        let status = finished.status;
        let stderr = String::from_utf8_lossy(&finished.stderr);
        if status.code() == Some(code) {
            // A batch says that what it finished is kept for the next call.
            assert_eq!(
                stderr.contains("finished inputs kept"),
                batch,
                "batch {batch}: {stderr}"
            );
        }
        if !batch && status.code() == Some(code) {
            // The run created --out and wrote nothing into it: it is gone.
            assert!(!out.exists(), "an empty {out:?} was left behind");
            continue;
        }
        let left = staging_left(&out);
        assert!(left.is_empty(), "batch {batch}: left {left:?}");
        if status.code() == Some(code) {
            // Every output folder is complete or holds no output at all.
            for e in std::fs::read_dir(&out).unwrap().flatten() {
                if e.path().is_dir() {
                    let n = OUTPUTS_2D
                        .iter()
                        .filter(|f| e.path().join(f).exists())
                        .count();
                    assert!(
                        n == 0 || n == OUTPUTS_2D.len(),
                        "{:?}: {n} outputs",
                        e.path()
                    );
                }
            }
        } else {
            // The run finished before the signal arrived.
            assert!(status.success(), "{status:?}");
        }
    }
}

/// NIfTI volumes in a batch give `labels.nii.gz`, a second call skips them,
/// and `--spacing` applies to every input (and is part of what is skipped).
#[test]
fn a_batch_of_nifti_volumes_with_a_voxel_size_is_skipped_when_complete() {
    use dsc_seg::io::{save_nifti, Volume};
    let d = tmp();
    let vols = d.path().join("vols");
    std::fs::create_dir(&vols).unwrap();
    for (name, r) in [("a.nii.gz", 4.0), ("b.nii", 5.0)] {
        let ball = Volume::from_fn(16, 16, 12, |i, j, k| {
            let d2 = (i as f64 - 8.0).powi(2) + (j as f64 - 8.0).powi(2) + (k as f64 - 6.0).powi(2);
            if d2 < r * r {
                0.8
            } else {
                0.2
            }
        });
        save_nifti(vols.join(name), &ball).unwrap();
    }
    let out = d.path().join("out");
    let call = |spacing: &str| {
        bin()
            .args(["segment3d", "--quiet", "--max-iterations", "4"])
            .args(["--outputs", "labels,phases,report", "--spacing", spacing])
            .arg(&vols)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap()
    };
    let first = call("1,1,2");
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    for stem in ["a", "b"] {
        assert!(out.join(stem).join("labels.nii.gz").is_file());
        assert!(!out.join(stem).join("labels.tif").exists());
        let report: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join(stem).join("report.json")).unwrap())
                .unwrap();
        assert_eq!(
            report["frame"]["spacing"],
            serde_json::json!([1.0, 1.0, 2.0])
        );
    }
    let second = call("1,1,2");
    assert!(second.status.success());
    let rows = summary(&out.join("summary.csv"));
    assert_eq!(row(&rows, "a")[6], "skipped", "{rows:?}");
    assert_eq!(row(&rows, "b")[6], "skipped", "{rows:?}");
    let third = call("1,1,1");
    assert!(third.status.success());
    let rows = summary(&out.join("summary.csv"));
    assert_eq!(row(&rows, "a")[6], "done", "{rows:?}");
}

/// A folder given to `segment` takes its NIfTI slices too (segmented as 2D
/// images, labels in a NIfTI with the header), and names the NIfTI volumes
/// it leaves to `segment3d` on stderr, rather than passing over either in
/// silence; a volume beside an image of the same stem is no clash, and a
/// slice one voxel thick along x gets its row with the way to reorient it.
#[test]
fn a_folder_of_nifti_slices_is_segmented_and_its_volumes_named() {
    use dsc_seg::io::{save_nifti, Volume};
    let d = tmp();
    let folder = d.path().join("slices");
    std::fs::create_dir(&folder).unwrap();
    let square = |nz| {
        Volume::from_fn(24, 20, nz, |i, j, _| {
            let inside = (6..18).contains(&i) && (5..15).contains(&j);
            let jitter = ((i * 7 + j * 13) % 5) as f32 * 0.02;
            if inside {
                0.8 - jitter
            } else {
                0.2 + jitter
            }
        })
    };
    save_nifti(folder.join("slice.nii.gz"), &square(1)).unwrap();
    save_nifti(folder.join("photo.nii"), &square(6)).unwrap();
    let sagittal = Volume::from_fn(
        1,
        20,
        24,
        |_, j, k| if j < 10 && k < 12 { 0.8 } else { 0.2 },
    );
    save_nifti(folder.join("sagittal.nii"), &sagittal).unwrap();
    write_disk(&folder, "photo.png", 32, 1);
    let out = d.path().join("out");
    let o = run(&["--quiet", "--outputs", "labels,report"], &[&folder], &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("photo.nii are NIfTI volumes") && err.contains("segment3d"),
        "{err}"
    );
    let rows = summary(&out.join("summary.csv"));
    assert_eq!(rows.len(), 4, "{rows:?}");
    // a slice one voxel thick along x is listed; its row says how to reorient it
    let sagittal = row(&rows, "sagittal");
    assert_eq!(sagittal[6], "error", "{rows:?}");
    assert!(sagittal[7].contains("fslswapdim"), "{sagittal:?}");
    assert_eq!(row(&rows, "slice")[6], "done", "{rows:?}");
    assert_eq!(row(&rows, "photo")[6], "done", "{rows:?}");
    assert!(row(&rows, "photo")[1].ends_with("photo.png"), "{rows:?}");
    assert!(out.join("slice").join("labels.nii.gz").is_file());
}

/// With `--phases auto` each row gives the count its run chose.
#[test]
fn rows_give_the_phase_count_auto_chose() {
    let d = tmp();
    let images = d.path().join("images");
    let o = bin()
        .args(["phantom", "four_phase", "--size", "96", "--out"])
        .arg(&images)
        .output()
        .unwrap();
    assert!(o.status.success());
    for f in ["four_phase_gt.png", "four_phase_labels.png"] {
        std::fs::remove_file(images.join(f)).unwrap();
    }
    write_disk(&images, "disk.png", 48, 1);
    let out = d.path().join("out");
    let o = run(
        &[
            "--quiet",
            "--phases",
            "auto",
            "--max-phases",
            "5",
            "--outputs",
            "report",
        ],
        &[&images],
        &out,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = summary(&out.join("summary.csv"));
    for stem in ["four_phase", "disk"] {
        let report: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join(stem).join("report.json")).unwrap())
                .unwrap();
        let chosen = report["params"]["phases"].as_u64().unwrap().to_string();
        assert_eq!(row(&rows, stem)[2], chosen, "{stem}");
    }
    assert_ne!(row(&rows, "four_phase")[2], "2", "not the default count");
}

#[test]
fn rows_carry_the_warnings_of_their_runs() {
    let d = tmp();
    let images = d.path().join("images");
    std::fs::create_dir_all(&images).unwrap();
    write_disk(&images, "disk.png", 64, 1);
    let out = d.path().join("out");
    // A two-phase disk asked for four phases: the run warns that phases are empty.
    let o = run(
        &["--phases", "4", "--outputs", "labels,report"],
        &[&images],
        &out,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = summary(&out.join("summary.csv"));
    let warnings = &row(&rows, "disk")[8];
    assert!(warnings.contains("covers no pixel"), "{warnings:?}");
    // The warnings name phases as labels.png numbers them.
    let labels = image::open(out.join("disk").join("labels.png"))
        .unwrap()
        .into_luma8();
    // An empty phase has no mean: `null` in every list of means, not the
    // mean it had before it emptied.
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("disk").join("report.json")).unwrap())
            .unwrap();
    for phase in 0..4u8 {
        let named = warnings.contains(&format!("phase {phase} covers no pixel"));
        let present = labels.pixels().any(|p| p[0] == phase);
        assert_ne!(named, present, "phase {phase}: {warnings:?}");
        for means in [&report["final_means"], &report["input"]["phase_means"]] {
            let mean = &means[phase as usize];
            assert_eq!(mean.is_null(), !present, "phase {phase}: mean {mean}");
        }
    }
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("disk: converged") && stderr.contains("warning:"),
        "{stderr}"
    );
}

#[test]
fn a_folder_without_images_is_an_error() {
    let d = tmp();
    let empty = d.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    std::fs::write(empty.join("notes.txt"), "not an image").unwrap();
    let out = d.path().join("out");
    let o = run(&[], &[&empty], &out);
    assert_eq!(o.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("holds no image"), "{stderr}");
    assert!(!out.exists(), "nothing written");
}

/// A folder's subfolders of images are not segmented with it, and the
/// command line says which they are; a file named twice (alone and through
/// its folder) is one input, not a clash of output names.
#[test]
fn subfolders_left_out_are_named_and_a_file_named_twice_runs_once() {
    let d = tmp();
    let folder = d.path().join("images");
    let day = folder.join("day2");
    std::fs::create_dir_all(&day).unwrap();
    std::fs::create_dir(folder.join("empty")).unwrap();
    let a = write_disk(&folder, "a.png", 40, 0);
    write_disk(&day, "b.png", 40, 1);
    let out = d.path().join("out");

    let done = run(&["--quiet"], &[&folder, &a], &out);
    let err = String::from_utf8_lossy(&done.stderr);
    assert!(done.status.success(), "{err}");
    let note = err.lines().find(|l| l.starts_with("note:")).expect(&err);
    assert!(note.contains(&day.display().to_string()), "{note}");
    assert!(!note.contains("empty"), "{note}");
    let rows = summary(&out.join("summary.csv"));
    assert_eq!(rows.len(), 2, "{rows:?}");
    assert_eq!(row(&rows, "a")[6], "done");

    // Named as an input, however spelt, the subfolder is segmented and not noted.
    let roundabout = folder.join("..").join("images").join("day2");
    let done = run(
        &["--quiet"],
        &[&folder, &roundabout],
        &d.path().join("out2"),
    );
    let err = String::from_utf8_lossy(&done.stderr);
    assert!(done.status.success() && !err.contains("note:"), "{err}");
    assert_eq!(summary(&d.path().join("out2").join("summary.csv")).len(), 3);

    // A folder segmented into itself: its output folders hold result
    // images, not images left out, the second time as the first.
    let own = d.path().join("own");
    std::fs::create_dir(&own).unwrap();
    write_disk(&own, "c.png", 40, 2);
    for _ in 0..2 {
        let done = run(&["--quiet", "--force"], &[&own], &own);
        let err = String::from_utf8_lossy(&done.stderr);
        assert!(done.status.success() && !err.contains("note:"), "{err}");
    }
    assert!(own.join("c").join("labels.png").is_file());
}
