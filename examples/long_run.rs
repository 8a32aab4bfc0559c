//! Long-run reliability: thousands of iterations with label flips on, on pure
//! noise and on a real photograph, checking after every iteration that the
//! complex is valid, that no coordinate is NaN, and that the mesh size stays
//! bounded. Writes the vertex/cell-count curve as CSV into `out/long_run/`.
//!
//! ```sh
//! cargo run --release --example long_run -- 2000
//! ```

use dsc_seg::dim::{Point, D2};
use dsc_seg::io::Image2;
use dsc_seg::segment::{ImageView, SegmentParams, Segmentation};
use rand::{Rng, SeedableRng};
use std::error::Error;
use std::fmt::Write as _;

fn main() -> Result<(), Box<dyn Error>> {
    let iterations: usize = std::env::args()
        .nth(1)
        .map(|a| a.parse())
        .transpose()?
        .unwrap_or(2000);
    let out = std::path::Path::new("out/long_run");
    std::fs::create_dir_all(out)?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
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
        let mut seg = Segmentation::<D2>::new(image, SegmentParams::new(phases))?;
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
                return Err(
                    format!("{name}: iteration {}: non-finite value", rec.iteration).into(),
                );
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
            "{name}: {iterations} iterations in {:.1} s, validate() green throughout, cells {min_cells}..{max_cells}, peak RSS {} MiB",
            start.elapsed().as_secs_f64(),
            peak_rss_mib()
        );
    }
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
