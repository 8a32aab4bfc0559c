//! Probe: the generic driver on one 3D phantom (not part of the deliverables).
use dsc_seg::dim::D3;
use dsc_seg::phantom::Phantom3Kind;
use dsc_seg::pipeline::mean_dice;
use dsc_seg::segment::{ImageView, SegmentParams, Segmentation};
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let kind = Phantom3Kind::from_name(&a[1]).unwrap();
    let n: usize = a[2].parse().unwrap();
    let noise: f64 = a[3].parse().unwrap();
    let lw: f64 = a[4].parse().unwrap();
    let ph = kind.generate(n, noise, 1);
    let view = ImageView::new_3d([n, n, n], &ph.image).unwrap();
    let mut p = SegmentParams::new(2);
    p.length_weight = lw;
    let t = std::time::Instant::now();
    let mut seg = Segmentation::<D3>::new(view, p).unwrap();
    let r = seg.run(|_| {});
    let dice = mean_dice(&seg.label_image(), &ph.truth, 2);
    println!(
        "{} {n}³ noise {noise} lw {lw}: Dice {dice:.4}, {} it, conv {}, {} tets, L {}, {:.2?}",
        a[1],
        r.iterations,
        r.converged,
        r.cells,
        r.edge_length,
        t.elapsed()
    );
}
