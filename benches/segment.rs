//! Segmentation benchmarks (speed issue): (a) the image statistics of one
//! iteration next to a plain sum over the same image, so their ratio is
//! measured; (d) full segmentations of the peers' phantoms.

use criterion::{criterion_group, criterion_main, Criterion};
use dsc_seg::complex::Complex;
use dsc_seg::dim::D2;
use dsc_seg::phantom::shapes2d;
use dsc_seg::segment::integrate::{integrate_cells, CellCache};
use dsc_seg::segment::{default_edge_length, ImageView, SegmentParams, Segmentation};
use std::hint::black_box;

fn statistics(c: &mut Criterion) {
    let p = shapes2d::two_phase(512, 0.2, 1);
    let image = ImageView::new_2d(p.width, p.height, &p.image).unwrap();
    let l = default_edge_length(p.width, p.height, p.phases);
    let mesh = Complex::rectangle(p.width as f64, p.height as f64, l).unwrap();
    let mut cells = Vec::new();
    let mut group = c.benchmark_group("statistics_512");
    group.bench_function("plain_sum", |b| {
        b.iter(|| {
            let (mut s, mut s2) = (0.0f64, 0.0f64);
            for &v in black_box(&p.image) {
                let v = v as f64;
                s += v;
                s2 += v * v;
            }
            (s, s2)
        })
    });
    // The rasteriser alone, one thread: where integration spends its time.
    group.bench_function("spans_only", |b| {
        use dsc_seg::segment::raster::Raster;
        b.iter(|| {
            let mut n = 0usize;
            for c in mesh.cell_ids() {
                let pts = mesh.cell_points(c);
                D2::cell_spans(&image, &pts[..3], &mut |a, b| n += b - a);
            }
            n
        })
    });
    group.bench_function("integrate_cells", |b| {
        b.iter(|| integrate_cells(&mesh, &image, &mut cells))
    });
    // The steady state of the cache: nothing moved, every cell is compared
    // and none integrated (the bound for the cells away from the interface).
    let mut cache = CellCache::<D2>::new();
    cache.integrate(&mesh, &image, &mut cells);
    group.bench_function("cached_unchanged", |b| {
        b.iter(|| cache.integrate(&mesh, &image, &mut cells))
    });
    group.finish();
}

fn full_runs(c: &mut Criterion) {
    let mut group = c.benchmark_group("segmentation");
    group.sample_size(10);
    for (name, p, phases) in [
        ("two_phase_512_s0.2", shapes2d::two_phase(512, 0.2, 1), 2),
        (
            "four_phase_1024_s0.2",
            shapes2d::four_phase(1024, 0.2, 1),
            4,
        ),
    ] {
        let image = ImageView::new_2d(p.width, p.height, &p.image).unwrap();
        group.bench_function(name, |b| {
            b.iter(|| {
                let mut seg = Segmentation::<D2>::new(image, SegmentParams::new(phases)).unwrap();
                seg.run(|_| {})
            })
        });
    }
    group.finish();
}

criterion_group!(benches, statistics, full_runs);
criterion_main!(benches);
