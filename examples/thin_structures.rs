//! Thin and small structures with the uniform and the adaptive mesh.
//!
//! Segments the `thin` phantom (lines and arcs 2, 3 and 4 px wide, disks of
//! radius 2–5 px inside and cut by the border, a ring with a 2-px slit, a
//! star) at 256² and 512², noise σ 0.1 and 0.2, with the defaults (the
//! uniform mesh) and with `adaptive` on, and prints per structure its recall
//! and the number of pieces it came out in, plus the cells, Dice and time.
//!
//! `cargo run --release --example thin_structures [-- LENGTH_WEIGHT]`
//! (the length weight `w` of `--length-weight`; default: the default)

use dsc_seg::dim::D2;
use dsc_seg::phantom::thin::{components, score, thin};
use dsc_seg::segment::{ImageView, SegmentParams, Segmentation};
use std::time::Instant;

fn main() {
    let length_weight: Option<f64> = std::env::args().nth(1).map(|a| {
        a.parse()
            .expect("the argument is the length weight, a number")
    });
    println!("| size | σ | mesh | cells | s | lines ≥3 px (recall, pieces) | line2 | arcs ≥3 px | arc2 | blobs r≥3 found | border r≥3 found | blob2 / border2 | slit open | star recall |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for size in [256, 512] {
        for sigma in [0.1, 0.2] {
            let ph = thin(size, sigma, 1);
            for adaptive in [false, true] {
                let view = ImageView::new_2d(size, size, &ph.image).expect("image");
                let mut params = SegmentParams::new(2);
                if adaptive {
                    params.use_adaptive_mesh();
                }
                if let Some(w) = length_weight {
                    params.length_weight = w;
                }
                let t = Instant::now();
                let mut seg = Segmentation::<D2>::new(view, params).expect("segmentation");
                seg.run(|_| {});
                let secs = t.elapsed().as_secs_f64();
                let labels = seg.label_image();
                let scores = score(&labels, size, 1);
                let get = |name: &str| scores.iter().find(|s| s.name == name).expect("structure");
                let pair = |name: &str| {
                    let s = get(name);
                    format!("{:.2}/{}", s.recall, s.components)
                };
                let found = |prefix: &str, radii: &[u32]| {
                    radii
                        .iter()
                        .filter(|r| get(&format!("{prefix}{r}")).recall >= 0.5)
                        .count()
                };
                let background: Vec<bool> = labels.iter().map(|&l| l == 0).collect();
                println!(
                    "| {size} | {sigma} | {} | {} | {secs:.3} | {} {} | {} | {} {} | {} | {}/3 | {}/3 | {}/{} | {} | {:.2} |",
                    if adaptive { "adaptive" } else { "uniform" },
                    seg.complex().cell_count(),
                    pair("line3"),
                    pair("line4"),
                    pair("line2"),
                    pair("arc3"),
                    pair("arc4"),
                    pair("arc2"),
                    found("blob", &[3, 4, 5]),
                    found("border", &[3, 4, 5]),
                    found("blob", &[2]),
                    found("border", &[2]),
                    if components(&background, size) == 1 { "yes" } else { "no" },
                    get("star").recall,
                );
            }
        }
    }
}
