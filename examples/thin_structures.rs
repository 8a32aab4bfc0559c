//! Thin and small structures with the uniform and the adaptive mesh.
//!
//! Segments the `thin` phantom (lines and arcs 2, 3 and 4 px wide, disks of
//! radius 2–5 px inside and cut by the border, a ring with a 2-px slit, a
//! star) at 256² and 512², noise σ 0.1 and 0.2, with the defaults (the
//! uniform mesh) and with `adaptive` on, and prints per structure its recall
//! and the number of pieces it came out in, plus the cells, the iterations
//! ("cap": stopped at the iteration cap, not converged) and the time.
//! A second table says what the energy itself, at the adaptive run's phase
//! means and length weight, makes of each structure after the blur: whether
//! a line gains more per unit of length than its two sides cost, a blob more
//! than its perimeter, and whether the slit's pixels fall below the midpoint
//! between the means at all. Its last rows do the same at the phantom's
//! own levels (0.3 / 0.7) and the ν they give (`w·0.4²/2`): what the
//! energy makes of the structures when the phase means are the true ones.
//!
//! `cargo run --release --example thin_structures [-- LENGTH_WEIGHT [SEED]]`
//! (the length weight `w` of `--length-weight`, default: the default; the
//! noise seed, default 1)

use dsc_seg::dim::D2;
use dsc_seg::phantom::thin::{components, score, structures, thin};
use dsc_seg::phantom::TWO_PHASE_LEVELS;
use dsc_seg::segment::{ImageView, SegmentParams, Segmentation};
use std::time::Instant;

fn main() {
    let length_weight: Option<f64> = std::env::args().nth(1).map(|a| {
        a.parse()
            .expect("the argument is the length weight, a number")
    });
    let seed: u64 = std::env::args().nth(2).map_or(1, |a| {
        a.parse()
            .expect("the second argument is the noise seed, a whole number")
    });
    println!("| size | σ | mesh | cells | iterations | s | lines ≥3 px (recall, pieces) | line2 | arcs ≥3 px | arc2 | blobs r≥3 found | border r≥3 found | blob2 / border2 | slit open | star recall |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut balance = Vec::new();
    let mut at_levels = Vec::new();
    for size in [256, 512] {
        let clean = thin(size, 0.0, 1).image;
        let [low, high] = TWO_PHASE_LEVELS;
        let w = length_weight.unwrap_or(SegmentParams::new(2).length_weight);
        let nu = w * (high - low).powi(2) / 2.0;
        at_levels.push(format!(
            "| {size} | levels | {low:.3} / {high:.3} | {nu:.3} | {} |",
            energy_balance(&clean, size, (low, high), nu)
        ));
        for sigma in [0.1, 0.2] {
            let ph = thin(size, sigma, seed);
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
                let report = seg.run(|_| {});
                let secs = t.elapsed().as_secs_f64();
                if adaptive {
                    let means = &seg.phases().mean;
                    let m = (means[0].unwrap_or(0.3), means[1].unwrap_or(0.7));
                    let nu = seg.length_weight_abs();
                    balance.push(format!(
                        "| {size} | {sigma} | {:.3} / {:.3} | {nu:.3} | {} |",
                        m.0,
                        m.1,
                        energy_balance(&clean, size, m, nu)
                    ));
                }
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
                    "| {size} | {sigma} | {} | {} | {}{} | {secs:.3} | {} {} | {} | {} {} | {} | {}/3 | {}/3 | {}/{} | {} | {:.2} |",
                    if adaptive { "adaptive" } else { "uniform" },
                    seg.complex().cell_count(),
                    report.iterations,
                    if report.converged { "" } else { " (cap)" },
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
    println!();
    println!("| size | σ | means | ν | line2 gain | line3 gain | line4 gain | 2ν | blob3 net | blob4 net | blob5 net | slit brightest column / midpoint |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for row in balance.into_iter().chain(at_levels) {
        println!("{row}");
    }
}

/// What the energy at the run's means `m` and length weight `nu` makes of
/// each thin structure, from the noise-free rendering `clean`: the best
/// labelling of a line's cross-section gains `Σ 2·(m₁ − m₀)·(I − mid)` over
/// its pixels above the midpoint per unit of length and costs `2ν` (its two
/// sides); the best disk of foreground about a blob's centre nets its gain
/// minus `ν` times its perimeter; the slit stays open only if every column
/// of it has a pixel below the midpoint. Returns the Markdown cells.
fn energy_balance(clean: &[f32], size: usize, m: (f64, f64), nu: f64) -> String {
    let (m0, m1) = m;
    let mid = 0.5 * (m0 + m1);
    let gain = |i: f32| 2.0 * (m1 - m0) * (i as f64 - mid);
    let structures = structures(size);
    let mask_of = |name: &str| {
        &structures
            .iter()
            .find(|s| s.name == name)
            .expect("structure")
            .mask
    };
    let mut cells = Vec::new();
    for w in [2, 3, 4] {
        // The middle column of the line, and its rows there.
        let mask = mask_of(&format!("line{w}"));
        let columns: Vec<usize> = (0..size)
            .filter(|&x| (0..size).any(|y| mask[y * size + x]))
            .collect();
        let x = columns[columns.len() / 2];
        let rows: Vec<usize> = (0..size).filter(|&y| mask[y * size + x]).collect();
        let centre = rows[rows.len() / 2];
        let per_length: f64 = (centre.saturating_sub(8)..(centre + 8).min(size))
            .map(|y| gain(clean[y * size + x]).max(0.0))
            .sum();
        cells.push(format!("{per_length:.3}"));
    }
    cells.push(format!("{:.3}", 2.0 * nu));
    for r in [3, 4, 5] {
        let mask = mask_of(&format!("blob{r}"));
        let inside: Vec<usize> = (0..size * size).filter(|&p| mask[p]).collect();
        let n = inside.len() as f64;
        let cx = inside.iter().map(|&p| (p % size) as f64 + 0.5).sum::<f64>() / n;
        let cy = inside.iter().map(|&p| (p / size) as f64 + 0.5).sum::<f64>() / n;
        let best = (1..=80)
            .map(|k| {
                let rho = 0.1 * k as f64;
                let (lo_x, hi_x) = (
                    (cx - rho).floor().max(0.0) as usize,
                    ((cx + rho).ceil() as usize).min(size),
                );
                let (lo_y, hi_y) = (
                    (cy - rho).floor().max(0.0) as usize,
                    ((cy + rho).ceil() as usize).min(size),
                );
                let mut g = 0.0;
                for y in lo_y..hi_y {
                    for x in lo_x..hi_x {
                        if (x as f64 + 0.5 - cx).hypot(y as f64 + 0.5 - cy) < rho {
                            g += gain(clean[y * size + x]);
                        }
                    }
                }
                g - nu * std::f64::consts::TAU * rho
            })
            .fold(f64::NEG_INFINITY, f64::max);
        cells.push(format!("{best:+.2}"));
    }
    // The slit (the pixels between two rows of the ring): a path through
    // it is only as open as its brightest column, each column as dark as
    // its darkest slit pixel.
    let ring = mask_of("slit_ring");
    let in_slit = |p: usize| {
        !ring[p]
            && p >= 2 * size
            && ring[p - 2 * size]
            && ring.get(p + 2 * size).copied().unwrap_or(false)
    };
    let mut darkest_by_column = vec![f64::INFINITY; size];
    for p in (0..size * size).filter(|&p| in_slit(p)) {
        let column = &mut darkest_by_column[p % size];
        *column = column.min(clean[p] as f64);
    }
    let bottleneck = darkest_by_column
        .into_iter()
        .filter(|v| v.is_finite())
        .fold(f64::NEG_INFINITY, f64::max);
    cells.push(format!("{bottleneck:.3} / {mid:.3}"));
    cells.join(" | ")
}
