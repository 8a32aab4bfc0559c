//! The DSC on its own, without an image: three regions in two phases are
//! pushed together until they merge, while a third phase keeps its triple
//! junctions. Writes frames and an animated GIF into `out/topology/`.
//!
//! ```sh
//! cargo run --release --example topology_demo
//! ```

use dsc_seg::complex::{Complex, VertexKind};
use dsc_seg::dim::D2;
use dsc_seg::dsc::{Destinations, DscParams};
use dsc_seg::io::{save_gif, Image2, Overlay};
use nalgebra::Vector2;
use std::error::Error;

fn main() -> Result<(), Box<dyn Error>> {
    let out = std::path::Path::new("out/topology");
    std::fs::create_dir_all(out)?;
    let (w, h, l) = (200.0, 120.0, 6.0);
    let disk = |cx: f64, cy: f64, r: f64| -> Vec<Vector2<f64>> {
        let n = (std::f64::consts::TAU * r / l).ceil() as usize;
        (0..n)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / n as f64;
                Vector2::new(cx + r * t.cos(), cy + r * t.sin())
            })
            .collect()
    };
    let polygons = [
        disk(55.0, 70.0, 28.0),
        disk(145.0, 70.0, 28.0),
        disk(100.0, 28.0, 20.0),
    ];
    let mut mesh = Complex::conforming(w, h, l, &polygons, |p| {
        let left = (p - Vector2::new(55.0, 70.0)).norm() < 28.0;
        let right = (p - Vector2::new(145.0, 70.0)).norm() < 28.0;
        let top = (p - Vector2::new(100.0, 28.0)).norm() < 20.0;
        if top {
            2
        } else if left || right {
            1
        } else {
            0
        }
    })?;
    let background = Image2::from_fn(w as usize, h as usize, |x, _| {
        0.35 + 0.3 * x as f32 / w as f32
    });
    let params = DscParams::new::<D2>(l);
    let mut frames = Vec::new();
    for step in 0..=24 {
        if step % 4 == 0 {
            let arrays = mesh.to_arrays();
            let (points, triangles) = (arrays.points_2d(), arrays.triangles());
            let overlay =
                Overlay::new(&background, &points, &triangles, &arrays.labels).with_scale(4.0);
            overlay.to_png(out.join(format!("step_{step:03}.png")))?;
            frames.push(overlay.to_rgba_image());
        }
        // The two phase-1 disks translate towards each other and merge; the
        // merged body then meets the phase-2 disk and forms triple junctions.
        let mut dest = Destinations::new(&mesh);
        let mut around = Vec::new();
        for v in mesh.vertex_ids() {
            mesh.labels_around(v, &mut around);
            if !mesh.class(v).on_interface() || !around.contains(&1) {
                continue;
            }
            let p = mesh.position(v);
            let shift = if p.x < 100.0 { 0.35 * l } else { -0.35 * l };
            dest.set(v, p + Vector2::new(shift, -0.1 * l));
        }
        let report = mesh.deform(&dest, &params);
        let junctions = mesh
            .vertex_ids()
            .filter(|&v| mesh.class(v).kind == VertexKind::Junction)
            .count();
        println!(
            "step {step:2}: phase-1 components {}, phase-2 cells {:4}, junctions {junctions:2}, unsafe collapses {}",
            mesh.components(1),
            mesh.cells_with_label(2),
            report.improve.unsafe_collapses
        );
        assert!(mesh.validate().is_empty());
    }
    save_gif(out.join("topology.gif"), &frames, 200)?;
    // The distribution of smallest angles after all that deformation.
    let mut bins = [0usize; 6];
    for c in mesh.cell_ids() {
        let angle = D2::min_angle_of_quality(mesh.quality(c));
        bins[((angle / 10.0) as usize).min(5)] += 1;
    }
    let total = mesh.cell_count() as f64;
    println!(
        "smallest-angle distribution over {} triangles:",
        mesh.cell_count()
    );
    for (i, n) in bins.iter().enumerate() {
        println!(
            "  {:2}–{:2}°: {:5.1}%",
            10 * i,
            10 * i + 10,
            100.0 * *n as f64 / total
        );
    }
    println!("wrote {}", out.display());
    Ok(())
}
