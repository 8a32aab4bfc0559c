//! One `deform` call on a 100k-triangle complex: every interface vertex moves
//! 0.3·L in a smooth direction field. Reports time per call; divide by the
//! printed number of moved vertices for the time per vertex.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use dsc_seg::complex::Complex;
use dsc_seg::dim::D2;
use dsc_seg::dsc::{Destinations, DscParams};
use nalgebra::Vector2;

fn deform_100k(c: &mut Criterion) {
    let l = 4.0;
    let size = 830.0;
    let mut mesh = Complex::rectangle(size, size, l).unwrap();
    // A grid of disks in two phases: plenty of interface.
    mesh.label_by(|p| {
        let cell = Vector2::new((p.x / 60.0).floor(), (p.y / 60.0).floor());
        let centre = cell * 60.0 + Vector2::new(30.0, 30.0);
        if (p - centre).norm() < 20.0 {
            1 + ((cell.x + cell.y) as u32 % 2)
        } else {
            0
        }
    });
    let params = DscParams::new::<D2>(l);
    let mut dest = Destinations::new(&mesh);
    let mut moved = 0;
    for v in mesh.vertex_ids() {
        if mesh.class(v).on_interface() {
            let p = mesh.position(v);
            let dir = Vector2::new((p.y / 37.0).sin(), (p.x / 41.0).cos()).normalize();
            dest.set(v, p + dir * 0.3 * l);
            moved += 1;
        }
    }
    eprintln!(
        "{} triangles, {} interface vertices moved per call",
        mesh.cell_count(),
        moved
    );
    c.bench_function("deform_100k_triangles", |b| {
        b.iter_batched(
            || mesh.clone(),
            |mut m| m.deform(&dest, &params),
            BatchSize::LargeInput,
        )
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = deform_100k
}
criterion_main!(benches);
