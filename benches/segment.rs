//! Segmentation benchmarks (speed issue): (a) the image statistics of one
//! iteration next to a plain sum over the same image, so their ratio is
//! measured; (b) the forces of one iteration; (d) full segmentations of the
//! peers' phantoms.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use dsc_seg::bench::CellCache;
use dsc_seg::complex::Complex;
use dsc_seg::dim::D2;
use dsc_seg::phantom::shapes2d;
use dsc_seg::segment::integrate::integrate_cells;
use dsc_seg::segment::{default_edge_length, ImageView, SegmentParams, Segmentation};
use spin_join::SpinHelper;
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
    one_iteration_cached(&mut group, &image);
    group.finish();
}

/// Iterations run before the measured state: past the first large moves,
/// the interface still sweeping.
const WARM_UP_ITERATIONS: usize = 10;

/// A 512² two-phase segmentation after [`WARM_UP_ITERATIONS`] steps.
fn mid_run<'a>(image: ImageView<'a>) -> Segmentation<'a, D2> {
    let mut seg = Segmentation::<D2>::new(image, SegmentParams::new(2)).unwrap();
    for _ in 0..WARM_UP_ITERATIONS {
        seg.step();
    }
    seg
}

/// The statistics of one real iteration as the driver computes them: a cache
/// filled on the mesh before a step, integrating the mesh after it (only
/// the cells the step moved or created are rasterised).
fn one_iteration_cached(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    image: &ImageView<'_>,
) {
    let mut seg = mid_run(*image);
    let before = seg.complex().clone();
    seg.step();
    let after = seg.complex();
    let (mut cache, mut cells) = (CellCache::<D2>::new(), Vec::new());
    cache.integrate(&before, image, &mut cells);
    let n = cache.clone().integrate(after, image, &mut cells.clone());
    eprintln!(
        "one_iteration_cached: {n} of {} cells integrated",
        after.cell_count()
    );
    group.bench_function("one_iteration_cached", |b| {
        b.iter_batched(
            || (cache.clone(), cells.clone()),
            |(mut cache, mut cells)| {
                cache.integrate(after, image, &mut cells);
                (cache, cells)
            },
            BatchSize::LargeInput,
        )
    });
    // As the driver does it: shared with the hot helper thread.
    let helper = SpinHelper::new();
    group.bench_function("one_iteration_on_helper", |b| {
        b.iter_batched(
            || (cache.clone(), cells.clone()),
            |(mut cache, mut cells)| {
                cache.integrate_on(&helper, after, image, &mut cells);
                (cache, cells)
            },
            BatchSize::LargeInput,
        )
    });
}

/// The force stage of one iteration (region force, rigidity, every term,
/// the destinations) on the 512² two-phase state mid-run. Each call also
/// integrates, through the cache, a mesh that has not moved (the
/// `cached_unchanged` cost).
fn forces(c: &mut Criterion) {
    let p = shapes2d::two_phase(512, 0.2, 1);
    let image = ImageView::new_2d(p.width, p.height, &p.image).unwrap();
    let mut seg = mid_run(image);
    seg.compute_forces();
    let mut group = c.benchmark_group("forces_512");
    group.bench_function("one_iteration", |b| b.iter(|| seg.compute_forces()));
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

criterion_group!(benches, statistics, forces, full_runs);
criterion_main!(benches);
