//! One iteration of the 3D segmentation (integrate, flips, forces, deform) on
//! the 128³ two-balls phantom at the default edge length, after a few warm-up
//! iterations so the interface sits near the objects: with the uniform mesh
//! (`--uniform`),
//! and with the adaptive one started coarse (the 3D default).
//! Prints the tet counts. On the adaptive mesh, also the two per-iteration
//! passes timed alone: the cell statistics of every tet (rasterising and
//! summing, one thread; an iteration integrates only the tets that changed)
//! and the edge-length summary of `report.json`.
//! Peak memory: run the `segment3d` command under `/usr/bin/time -v`.

use criterion::{criterion_group, criterion_main, Criterion};
use dsc_seg::dim::D3;
use dsc_seg::phantom::shapes3d;
use dsc_seg::segment::integrate::cell_stats;
use dsc_seg::segment::{ImageView, SegmentParams, Segmentation};
use std::hint::black_box;

fn iteration_128(c: &mut Criterion) {
    let n = 128;
    let ph = shapes3d::two_balls(n, 0.1, 1);
    let mut group = c.benchmark_group("segment3d");
    group.sample_size(10);
    for adaptive in [false, true] {
        let view = ImageView::new_3d([n, n, n], &ph.image).unwrap();
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
        let mut seg = Segmentation::<D3>::new(view, params).unwrap();
        for _ in 0..3 {
            seg.step();
        }
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
            b.iter(|| seg.step());
        });
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
