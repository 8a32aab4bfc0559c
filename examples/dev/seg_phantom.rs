//! Segments the benchmark phantoms in-process and prints Dice and time
//! (a quick check while developing; `benches/compare/compare.py` is the reference).
//!
//! `cargo run --release --example seg_phantom -- [two_phase|four_phase|...] [size] [sigma] [L]`

use dsc_seg::dim::D2;
use dsc_seg::phantom::Phantom2Kind;
use dsc_seg::segment::{ImageView, SegmentParams, Segmentation};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let kind = Phantom2Kind::from_name(args.first().map_or("two_phase", |s| s)).unwrap();
    let size: usize = args.get(1).map_or(256, |s| s.parse().unwrap());
    let sigma: f64 = args.get(2).map_or(0.2, |s| s.parse().unwrap());
    let l: Option<f64> = args.get(3).map(|s| s.parse().unwrap());
    let ph = kind.generate(size, sigma, 1);
    let img = ImageView::new_2d(ph.width, ph.height, &ph.image).unwrap();
    let mut p = SegmentParams::new(ph.phases);
    p.edge_length = l;
    if let Ok(b) = std::env::var("RIG") {
        p.rigidity = b.parse().unwrap();
    }
    if let Ok(b) = std::env::var("LW") {
        p.length_weight = b.parse().unwrap();
    }
    if let Ok(b) = std::env::var("ELA") {
        p.elasticity = b.parse().unwrap();
    }
    if let Ok(b) = std::env::var("STEP") {
        p.step_fraction = b.parse().unwrap();
    }
    let mut s = Segmentation::<D2>::new(img, p).unwrap();
    let rep = s.run(|r| {
        if std::env::var("VERBOSE").is_ok() {
            eprintln!(
                "it {} E {:.2} flips {} disp {:.3} len {:.0} j {:?}",
                r.iteration, r.energy, r.flips, r.max_displacement, r.length, r.junctions
            )
        }
    });
    let lab = s.label_image();
    let k = ph.phases;
    if let Ok(out) = std::env::var("OUT") {
        let scale = (255 / (k - 1)) as u8;
        let mut buf: Vec<u8> = lab.iter().map(|&v| v * scale).collect();
        buf.extend(ph.image_u8());
        image::GrayImage::from_raw(ph.width as u32, 2 * ph.height as u32, buf)
            .unwrap()
            .save(out)
            .unwrap();
    }
    let mut dice = 0.0;
    for ph_k in 0..k as u8 {
        let tp = lab
            .iter()
            .zip(&ph.truth)
            .filter(|(a, b)| **a == ph_k && **b == ph_k)
            .count();
        let np = lab.iter().filter(|a| **a == ph_k).count();
        let nt = ph.truth.iter().filter(|a| **a == ph_k).count();
        dice += 2.0 * tp as f64 / (np + nt).max(1) as f64;
    }
    println!(
        "{} {} s{:.2} L={:.1} dice {:.4} iters {} conv {} time {:.3}s (deform {:.3}) cells {}",
        kind,
        size,
        sigma,
        rep.edge_length,
        dice / k as f64,
        rep.iterations,
        rep.converged,
        rep.times.total,
        rep.times.deform,
        rep.cells
    );
}
