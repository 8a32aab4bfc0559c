//! Helpers shared by the integration tests.

use dsc_seg::complex::{Complex, Complex2, Label, VertexId};
use dsc_seg::dim::{Dim, D2};
use dsc_seg::dsc::{Destinations, DscParams};
use nalgebra::Vector2;

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
pub fn interface_field(
    c: &Complex2,
    f: impl Fn(VertexId, Vector2<f64>) -> Vector2<f64>,
) -> Destinations<D2> {
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
