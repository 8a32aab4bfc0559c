//! One iteration of the 3D segmentation (integrate, flips, forces, deform) on
//! the 128³ two-balls phantom at the default edge length: with the uniform
//! mesh (`--uniform`), and with the adaptive one started coarse (the 3D
//! default). Every sample times the same iteration, the fourth, of a fresh
//! run (built and stepped three times outside the timing): a run stepped on
//! from sample to sample would time later and later iterations, and the
//! uniform mesh, started at L on the objects, settles within a dozen (a
//! handful of vertices left to move) while the adaptive one, started coarse,
//! still travels; the two figures would not time the same work.
//! Prints the tet counts and, per mesh, the work of the timed iteration
//! (vertices asked to move, tets integrated again). On the adaptive mesh,
//! also the two per-iteration passes timed alone: the cell statistics of
//! every tet (rasterising and summing, one thread; an iteration integrates
//! only the tets that changed) and the edge-length summary of `report.json`.
//! Peak memory: run the `segment3d` command under `/usr/bin/time -v`.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use dsc_seg::complex::Complex3;
use dsc_seg::dim::D3;
use dsc_seg::phantom::shapes3d;
use dsc_seg::segment::integrate::cell_stats;
use dsc_seg::segment::{ImageView, SegmentParams, Segmentation};
use nalgebra::Vector3;
use std::collections::HashSet;
use std::hint::black_box;

/// The vertices of `after` at a position no vertex of `before` has (moved
/// or new), and its tets whose corners are not those of a tet of `before`
/// (the tets whose statistics an iteration computes again): the work one
/// iteration leaves for the next, whatever the compaction renumbered.
fn changed_since(before: &Complex3, after: &Complex3) -> (usize, usize) {
    let bits = |p: Vector3<f64>| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    let corners = |mesh: &Complex3, c| mesh.cell_points(c).map(bits);
    let positions: HashSet<_> = before
        .vertex_ids()
        .map(|v| bits(before.position(v)))
        .collect();
    let tets: HashSet<_> = before.cell_ids().map(|c| corners(before, c)).collect();
    let vertices = after
        .vertex_ids()
        .filter(|&v| !positions.contains(&bits(after.position(v))))
        .count();
    let cells = after
        .cell_ids()
        .filter(|&c| !tets.contains(&corners(after, c)))
        .count();
    (vertices, cells)
}

/// Iterations run before the timed one.
const WARM_UP_ITERATIONS: usize = 3;

fn iteration_128(c: &mut Criterion) {
    let n = 128;
    let ph = shapes3d::two_balls(n, 0.1, 1);
    let view = ImageView::new_3d([n, n, n], &ph.image).unwrap();
    let mut group = c.benchmark_group("segment3d");
    group.sample_size(10);
    for adaptive in [false, true] {
        // Flips on every iteration, so that every measured step is a full one
        // (the 3D default tries them only every `flip_interval` iterations).
        // Without the coarse pass: the measured iterations start from the
        // box mesh, as they always did.
        let mut params = SegmentParams {
            flip_interval: 1,
            coarse_pass: false,
            ..SegmentParams::new_3d(2)
        };
        params.sizing.adaptive = adaptive;
        params.sizing.coarse_start = adaptive;
        let warmed_up = || {
            let mut seg = Segmentation::<D3>::new(view, params.clone()).unwrap();
            for _ in 0..WARM_UP_ITERATIONS {
                seg.step();
            }
            seg
        };
        let mut seg = warmed_up();
        let mesh = if adaptive { "adaptive" } else { "uniform" };
        eprintln!(
            "128³ two balls, {mesh}: {} tets, {} vertices, L = {}",
            seg.complex().cell_count(),
            seg.complex().vertex_count(),
            seg.dsc_params().edge_length
        );
        let name = if adaptive {
            "one iteration, 128³, adaptive"
        } else {
            "one iteration, 128³"
        };
        group.bench_function(name, |b| {
            b.iter_batched(
                warmed_up,
                |mut seg| {
                    let record = seg.step();
                    (seg, record)
                },
                BatchSize::PerIteration,
            );
        });
        let before = seg.complex().clone();
        let record = seg.step();
        let (vertices, tets) = changed_since(&before, seg.complex());
        eprintln!(
            "128³ two balls, {mesh}, iteration {}: {vertices} of {} vertices moved or new, \
             {tets} of {} tets changed or new (each integrated again in the next iteration)",
            record.iteration,
            seg.complex().vertex_count(),
            seg.complex().cell_count(),
        );
        if adaptive {
            let mesh = seg.complex();
            group.bench_function("cell statistics of every tet, 128³, adaptive", |b| {
                b.iter(|| {
                    for c in mesh.cell_ids() {
                        black_box(cell_stats::<D3>(&view, &mesh.cell_points(c)));
                    }
                });
            });
            group.bench_function("edge-length summary, 128³, adaptive", |b| {
                b.iter(|| black_box(mesh.edge_length_summary()));
            });
        }
    }
    group.finish();
}

criterion_group!(benches, iteration_128);
criterion_main!(benches);
