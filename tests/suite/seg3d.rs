//! The generic segmentation driver in 3D (`Raster for D3`) on the built-in
//! 3D phantoms: Dice against the ground truth, `validate()` at the end.

use crate::common::*;
use dsc_seg::dim::D3;
use dsc_seg::phantom::shapes3d;
use dsc_seg::pipeline::mean_dice;
use dsc_seg::segment::{ImageView, SegmentParams, Segmentation};
use std::time::Instant;

#[test]
fn the_driver_segments_two_balls() {
    check("two balls", shapes3d::two_balls(32, 0.1, 1));
}

#[test]
fn the_driver_segments_a_torus() {
    check("torus", shapes3d::torus(32, 0.1, 2));
}

#[test]
fn the_driver_segments_a_hollow_sphere() {
    check("hollow sphere", shapes3d::hollow_sphere(32, 0.1, 3));
}

fn check(name: &str, ph: dsc_seg::phantom::Phantom3) {
    {
        let start = Instant::now();
        let view = ImageView::new_3d([ph.nx, ph.ny, ph.nz], &ph.image).unwrap();
        let mut params = SegmentParams::new_3d(2);
        params.max_iterations = 60;
        let mut seg = Segmentation::<D3>::new(view, params).unwrap();
        let report = seg.run(|_| {});
        assert_valid(seg.complex());
        let dice = mean_dice(&seg.label_image(), &ph.truth, 2);
        let (qmin, p5, median, low) = quality_summary(seg.complex());
        eprintln!(
            "{name} 32³ (L = {}): mean Dice {dice:.4} after {} iterations ({}), {} tets, \
             quality min {qmin:.3} p5 {p5:.3} median {median:.3} ({:.1}% < 0.3), {:.2?}",
            report.edge_length,
            report.iterations,
            if report.converged { "converged" } else { "cap" },
            report.cells,
            100.0 * low,
            start.elapsed()
        );
        assert!(dice > 0.9, "{name}: mean Dice {dice}");
    }
}

/// `min_move`: vertices asked to move less than `min_move·L` stay where
/// they are, while the iteration still reports the largest requested move
/// (the stopping rule's motion). On the uniform mesh nothing else changes
/// the vertices, so a threshold above every move leaves the mesh as it was.
#[test]
fn vertices_asked_to_move_less_than_min_move_stay() {
    let ph = shapes3d::two_balls(24, 0.1, 1);
    let positions_after_one_step = |min_move: f64| {
        let view = ImageView::new_3d([ph.nx, ph.ny, ph.nz], &ph.image).unwrap();
        let mut params = SegmentParams::new_3d(2);
        params.sizing.adaptive = false;
        params.sizing.coarse_start = false;
        params.min_move = min_move;
        let mut seg = Segmentation::<D3>::new(view, params).unwrap();
        let before: Vec<_> = positions(seg.complex());
        let record = seg.step();
        assert!(record.max_displacement > 0.0, "the forces ask for motion");
        (before, positions(seg.complex()), record.max_displacement)
    };
    let (before, after, largest) = positions_after_one_step(0.0);
    assert_ne!(before, after, "without a threshold the interfaces move");
    let (before, after, reported) = positions_after_one_step(largest * 1.01);
    assert_eq!(
        before, after,
        "no vertex was asked to move as far as the threshold"
    );
    assert_eq!(reported, largest, "the reported motion is every vertex's");
}

fn positions(c: &dsc_seg::complex::Complex<D3>) -> Vec<[f64; 3]> {
    c.vertex_ids()
        .map(|v| {
            let p = c.position(v);
            [p.x, p.y, p.z]
        })
        .collect()
}
