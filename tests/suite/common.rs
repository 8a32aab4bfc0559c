//! Helpers shared by the integration tests.

use dsc_seg::complex::{Complex, Complex2, Complex3, Label, VertexId};
use dsc_seg::dim::{Dim, D2};
use dsc_seg::dsc::{Destinations, DscParams};
use nalgebra::{Vector2, Vector3};
use std::collections::HashSet;
use std::path::Path;

/// A `size`×`size` square at edge length `l` with the cells inside the given
/// disks labelled 1, 2, … in order (later disks win).
pub fn disks(size: f64, l: f64, disks: &[(f64, f64, f64)]) -> Complex2 {
    let mut c = Complex::rectangle(size, size, l).unwrap();
    c.label_by(|p| {
        let mut label = 0;
        for (k, &(x, y, r)) in disks.iter().enumerate() {
            if (p - Vector2::new(x, y)).norm() < r {
                label = k as Label + 1;
            }
        }
        label
    });
    c
}

/// Asserts the complex is valid, printing the findings otherwise.
pub fn assert_valid<K: Dim>(c: &Complex<K>) {
    let findings = c.validate();
    assert!(
        findings.is_empty(),
        "validate() found {:?}",
        &findings[..findings.len().min(5)]
    );
}

/// Destinations `p + f(p)` for every interface vertex.
pub fn interface_field<K: Dim>(
    c: &Complex<K>,
    f: impl Fn(VertexId, K::Point) -> K::Point,
) -> Destinations<K> {
    let mut d = Destinations::new(c);
    for v in c.vertex_ids() {
        if c.class(v).on_interface() {
            let p = c.position(v);
            d.set(v, p + f(v, p));
        }
    }
    d
}

/// Minimum angles (degrees) of every triangle.
pub fn min_angles(c: &Complex2) -> Vec<f64> {
    c.cell_ids()
        .map(|t| D2::min_angle_of_quality(c.quality(t)))
        .collect()
}

/// Quality requirement of the foundation issue: no angle below 2°, and at
/// least 90% of triangles with minimum angle of at least 20°.
pub fn assert_quality(c: &Complex2) {
    let angles = min_angles(c);
    let worst = angles.iter().copied().fold(180.0, f64::min);
    let good = angles.iter().filter(|&&a| a >= 20.0).count() as f64 / angles.len() as f64;
    assert!(worst >= 2.0, "smallest angle {worst:.2}°");
    assert!(
        good >= 0.9,
        "only {:.1}% of triangles have min angle >= 20°",
        100.0 * good
    );
}

/// The DSC parameters for the tests.
pub fn params(l: f64) -> DscParams {
    DscParams::new::<D2>(l)
}

/// A box of the given size at edge length `l` with the cells inside the given
/// balls `(centre, radius)` labelled 1, 2, … in order (later balls win).
pub fn balls(size: [f64; 3], l: f64, balls: &[(Vector3<f64>, f64)]) -> Complex3 {
    let mut c = Complex::cuboid(size, l).unwrap();
    c.label_by(|p| {
        let mut label = 0;
        for (k, &(centre, r)) in balls.iter().enumerate() {
            if (p - centre).norm() < r {
                label = k as Label + 1;
            }
        }
        label
    });
    c
}

/// Euler characteristic V − E + F of the surface made of the interface
/// triangles between phases `a` and `b` (0 for a torus, 2 for a sphere).
pub fn interface_euler(c: &Complex3, a: Label, b: Label) -> i64 {
    let mut verts = HashSet::new();
    let mut edges = HashSet::new();
    let mut faces = 0i64;
    for t in c.cell_ids() {
        if c.label(t) != a {
            continue;
        }
        let cell = c.cell(t);
        for (i, nb) in c.neighbours(t).iter().enumerate() {
            if !nb.is_some_and(|nb| c.label(nb) == b) {
                continue;
            }
            faces += 1;
            let f: Vec<VertexId> = (0..4).filter(|&j| j != i).map(|j| cell[j]).collect();
            for x in 0..3 {
                verts.insert(f[x]);
                let (p, q) = (f[x], f[(x + 1) % 3]);
                edges.insert(if p < q { (p, q) } else { (q, p) });
            }
        }
    }
    verts.len() as i64 - edges.len() as i64 + faces
}

/// Quality figures of a complex: (min, 5th percentile, median, fraction below 0.3).
pub fn quality_summary<K: Dim>(c: &Complex<K>) -> (f64, f64, f64, f64) {
    let mut q: Vec<f64> = c.cell_ids().map(|t| c.quality(t)).collect();
    q.sort_by(f64::total_cmp);
    let low = q.iter().filter(|&&x| x < 0.3).count() as f64 / q.len() as f64;
    (q[0], q[q.len() / 20], q[q.len() / 2], low)
}

/// Writes a `size`×`size` float32 grayscale TIFF (Fiji's 32-bit type).
pub fn save_f32_tiff(path: &Path, size: usize, data: &[f32]) {
    tiff::encoder::TiffEncoder::new(std::fs::File::create(path).unwrap())
        .unwrap()
        .write_image::<tiff::encoder::colortype::Gray32Float>(size as u32, size as u32, data)
        .unwrap();
}
