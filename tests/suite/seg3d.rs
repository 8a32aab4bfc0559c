//! The 3D region forces driving the 3D DSC on the built-in phantoms: a
//! minimal two-phase loop (range-bisection start, eq. (6) forces, step of at
//! most a fraction of L, voxel-dominant flips) until the driver of the
//! `segment` module takes over. A smoke test of the 3D pieces at 32³ and
//! L = 4 (coarse: the torus tube is 7 voxels across): Dice must improve on the
//! initialisation and exceed 0.85. The Dice table (64³/128³, ≥ 0.95)
//! belongs to the full `segment3d` driver.

use crate::common::*;
use dsc_seg::complex::{Complex, Complex3, Label};
use dsc_seg::dim::D3;
use dsc_seg::dsc::{Destinations, DscParams};
use dsc_seg::phantom::{shapes3d, Phantom3};
use dsc_seg::segment::region3d::VoxelGrid;
use std::time::Instant;

/// Dice of phase 1 between the complex's voxel labels and the truth.
fn dice(c: &Complex3, ph: &Phantom3) -> f64 {
    let owners = c.voxel_owners([ph.nx, ph.ny, ph.nz]);
    let (mut both, mut a, mut b) = (0usize, 0usize, 0usize);
    for (o, &t) in owners.iter().zip(&ph.truth) {
        let seg = o.is_some_and(|c0| c.label(c0) == 1);
        let truth = t == 1;
        both += (seg && truth) as usize;
        a += seg as usize;
        b += truth as usize;
    }
    2.0 * both as f64 / (a + b) as f64
}

fn segment(ph: &Phantom3, l: f64, iterations: usize, flips_every: usize) -> (Complex3, f64, f64) {
    let dims = [ph.nx, ph.ny, ph.nz];
    let grid = VoxelGrid::new(&ph.image, dims).unwrap();
    let mut c = Complex::cuboid(dims.map(|n| n as f64), l).unwrap();
    // Range bisection: cells brighter than the middle of the range start in phase 1.
    let (lo, hi) = ph
        .image
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    let mid = 0.5 * (lo + hi) as f64;
    let sums = c.cell_sums(&grid);
    let changes: Vec<_> = c
        .cell_ids()
        .filter(|t| sums[t.index()].1 > 0 && sums[t.index()].0 / sums[t.index()].1 as f64 > mid)
        .map(|t| (t, 1 as Label))
        .collect();
    c.set_labels(&changes);
    let initial = dice(&c, ph);
    let p = DscParams::new::<D3>(l);
    for it in 0..iterations {
        let means = c.phase_means(&grid);
        let forces = c.region_forces(&grid, &means, 1.0);
        let max = c
            .vertex_ids()
            .filter(|&v| c.class(v).on_interface())
            .map(|v| forces[v.index()].norm())
            .fold(0.0, f64::max);
        if max == 0.0 {
            break;
        }
        let dt = 0.2 * l / max;
        let mut d = Destinations::new(&c);
        for v in c.vertex_ids() {
            if c.class(v).on_interface() {
                d.set(v, c.position(v) + forces[v.index()] * dt);
            }
        }
        c.deform(&d, &p);
        assert_valid(&c);
        if flips_every > 0 && it % flips_every == flips_every - 1 {
            let means = c.phase_means(&grid);
            let flips = c.dominant_phase_changes(&grid, &means);
            c.set_labels(&flips);
        }
    }
    let score = dice(&c, ph);
    (c, initial, score)
}

#[test]
fn region_forces_segment_the_3d_phantoms() {
    for (name, ph) in [
        ("two balls", shapes3d::two_balls(32, 0.1, 1)),
        ("torus", shapes3d::torus(32, 0.1, 2)),
        ("hollow sphere", shapes3d::hollow_sphere(32, 0.1, 3)),
    ] {
        let start = Instant::now();
        let (c, initial, score) = segment(&ph, 4.0, 20, 0);
        let (qmin, p5, median, low) = quality_summary(&c);
        eprintln!(
            "{name} 32³: Dice {initial:.4} -> {score:.4}, {} tets, quality min {qmin:.3} p5 {p5:.3} median {median:.3} ({:.1}% < 0.3), components {}, {:.2?}",
            c.cell_count(),
            100.0 * low,
            c.components(1),
            start.elapsed()
        );
        assert!(score > initial, "{name}: Dice {initial} -> {score}");
        assert!(score > 0.85, "{name}: Dice {score}");
    }
}
