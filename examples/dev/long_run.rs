//! Long-run reliability: many iterations with label flips on, checking after
//! every iteration that the complex is valid, that no coordinate or energy is
//! NaN, and that the mesh size stays bounded. 2D: pure noise and a real
//! photograph (default 2000 iterations); 3D: a noisy two-balls phantom and pure
//! noise (default 300 iterations, flips tried every iteration rather than the
//! 3D default of every 20, for the most topology changes). Writes the
//! vertex/cell-count curve as CSV into `out/long_run/`.
//!
//! ```sh
//! cargo run --release --example long_run -- 2d 2000
//! cargo run --release --example long_run -- 3d 300
//! ```

use dsc_seg::dim::{Point, D2, D3};
use dsc_seg::io::Image2;
use dsc_seg::phantom::shapes3d;
use dsc_seg::segment::{ImageView, Raster, SegmentParams, Segmentation};
use rand::{Rng, SeedableRng};
use std::error::Error;
use std::fmt::Write as _;
use std::path::Path;

type Res = Result<(), Box<dyn Error>>;

fn main() -> Res {
    let mut dim = "2d".to_string();
    let mut iterations = None;
    for a in std::env::args().skip(1) {
        match a.as_str() {
            "2d" | "3d" => dim = a,
            n => {
                iterations = Some(
                    n.parse::<usize>()
                        .map_err(|_| "usage: long_run [2d|3d] [N]")?,
                )
            }
        }
    }
    let out = Path::new("out/long_run");
    std::fs::create_dir_all(out)?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    if dim == "3d" {
        let iterations = iterations.unwrap_or(300);
        let n = 32;
        let balls = shapes3d::two_balls(n, 0.2, 7);
        let noise: Vec<f32> = (0..24 * 24 * 24).map(|_| rng.random::<f32>()).collect();
        // Flips every iteration, and a cell may flip a voxel back: the most
        // label churn (with the 3D default `flip_once` the noise volume
        // settles into one phase after three iterations and nothing moves).
        let params = SegmentParams {
            flip_interval: 1,
            flip_once: false,
            ..SegmentParams::new_3d(2)
        };
        for (name, side, data) in [("two_balls_32", n, &balls.image), ("noise_24", 24, &noise)] {
            let image = ImageView::new_3d([side; 3], data).ok_or("volume size")?;
            let seg = Segmentation::<D3>::new(image, params.clone())?;
            run(name, seg, iterations, out)?;
        }
    } else {
        let iterations = iterations.unwrap_or(2000);
        let noise: Vec<f32> = (0..128 * 128).map(|_| rng.random::<f32>()).collect();
        let camera = Image2::load(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/camera_256.png"
        ))?;
        let cases: [(&str, usize, usize, &[f32], usize); 2] = [
            ("noise_128", 128, 128, &noise, 2),
            (
                "camera_256",
                camera.width(),
                camera.height(),
                camera.data(),
                3,
            ),
        ];
        for (name, w, h, data, phases) in cases {
            let image = ImageView::new_2d(w, h, data).ok_or("image size")?;
            let seg = Segmentation::<D2>::new(image, SegmentParams::new(phases))?;
            run(name, seg, iterations, out)?;
        }
    }
    Ok(())
}

/// Steps `seg` `iterations` times, failing at the first invalid complex or
/// non-finite value; writes `out/NAME.csv` and prints one summary line.
fn run<K: Raster>(name: &str, mut seg: Segmentation<'_, K>, iterations: usize, out: &Path) -> Res {
    let mut csv = String::from("iteration,vertices,cells,energy,flips\n");
    let (mut min_cells, mut max_cells) = (usize::MAX, 0);
    let start = std::time::Instant::now();
    for _ in 0..iterations {
        let rec = seg.step();
        let c = seg.complex();
        let findings = c.validate();
        if !findings.is_empty() {
            return Err(
                format!("{name}: iteration {}: {:?}", rec.iteration, &findings[..1]).into(),
            );
        }
        if c.vertex_ids().any(|v| !c.position(v).is_finite()) || !rec.energy.is_finite() {
            return Err(format!("{name}: iteration {}: non-finite value", rec.iteration).into());
        }
        min_cells = min_cells.min(c.cell_count());
        max_cells = max_cells.max(c.cell_count());
        writeln!(
            csv,
            "{},{},{},{},{}",
            rec.iteration,
            c.vertex_count(),
            c.cell_count(),
            rec.energy,
            rec.flips
        )?;
    }
    std::fs::write(out.join(format!("{name}.csv")), csv)?;
    println!(
        "{name}: {iterations} iterations in {:.1} s, validate() green throughout, cells {min_cells}..{max_cells} (last {}), peak RSS {} MiB",
        start.elapsed().as_secs_f64(),
        seg.complex().cell_count(),
        peak_rss_mib()
    );
    Ok(())
}

/// Peak resident set size of this process (Linux), for the memory-flat check.
fn peak_rss_mib() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .map(str::to_owned)
        })
        .and_then(|l| {
            l.split_whitespace()
                .nth(1)
                .and_then(|kb| kb.parse::<u64>().ok())
        })
        .map_or(0, |kb| kb / 1024)
}
