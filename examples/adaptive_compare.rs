//! The uniform and the adaptive mesh side by side on the benchmark phantoms.
//!
//! For the two- and four-phase phantoms at 256² and 512², noise σ 0.1 and
//! 0.2 (seed 1), runs the segmentation with the defaults (the uniform mesh at
//! L) and with `adaptive` on, and prints the mean Dice, the final cell count,
//! the iterations and the segmentation time of each (one run each, one after
//! the other: compare the times within a row).
//!
//! `cargo run --release --example adaptive_compare`

use dsc_seg::dim::D2;
use dsc_seg::phantom::Phantom2Kind;
use dsc_seg::pipeline::mean_dice;
use dsc_seg::segment::{ImageView, SegmentParams, Segmentation};
use std::time::Instant;

fn main() {
    println!("| phantom | size | σ | uniform Dice | adaptive Dice | uniform cells | adaptive cells | ratio | uniform iterations | adaptive iterations | uniform s | adaptive s |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for kind in [Phantom2Kind::TwoPhase, Phantom2Kind::FourPhase] {
        for size in [256, 512] {
            for sigma in [0.1, 0.2] {
                let ph = kind.generate(size, sigma, 1);
                let mut row = Vec::new();
                for adaptive in [false, true] {
                    let view = ImageView::new_2d(size, size, &ph.image).expect("image");
                    let mut params = SegmentParams::new(ph.phases);
                    if adaptive {
                        params.use_adaptive_mesh();
                    }
                    let t = Instant::now();
                    let mut seg = Segmentation::<D2>::new(view, params).expect("segmentation");
                    let report = seg.run(|_| {});
                    let secs = t.elapsed().as_secs_f64();
                    let dice = mean_dice(&seg.label_image(), &ph.truth, ph.phases);
                    row.push((dice, report.cells, report.iterations, secs));
                }
                let (u, a) = (row[0], row[1]);
                println!(
                    "| {kind} | {size} | {sigma} | {:.4} | {:.4} | {} | {} | {:.2} | {} | {} | {:.3} | {:.3} |",
                    u.0,
                    a.0,
                    u.1,
                    a.1,
                    u.1 as f64 / a.1 as f64,
                    u.2,
                    a.2,
                    u.3,
                    a.3
                );
            }
        }
    }
}
