//! The 2D DSC engine's required behaviours.

use crate::common::*;
use dsc_seg::complex::VertexKind;
use nalgebra::Vector2;

#[test]
fn rigid_translation_of_a_disk_preserves_area_and_shape() {
    let l = 4.0;
    let mut c = disks(100.0, l, &[(40.0, 50.0, 15.0)]);
    let p = params(l);
    let area0 = c.phase_measures()[1];
    for _ in 0..10 {
        let d = interface_field(&c, |_, _| Vector2::new(0.3 * l, 0.0));
        let report = c.deform(&d, &p);
        assert_valid(&c);
        assert_quality(&c);
        assert!(report.rounds >= 1);
        assert_eq!(c.components(1), 1);
        assert_eq!(c.components(0), 1);
    }
    let area1 = c.phase_measures()[1];
    assert!(
        (area1 - area0).abs() / area0 < 0.01,
        "area {area0} -> {area1}"
    );
    // The centroid moved by 3L.
    let centroid: Vector2<f64> = c
        .cell_ids()
        .filter(|&t| c.label(t) == 1)
        .map(|t| {
            let q = c.cell_points(t);
            (q[0] + q[1] + q[2]) / 3.0 * c.measure(t)
        })
        .sum::<Vector2<f64>>()
        / area1;
    assert!(
        (centroid.x - (40.0 + 3.0 * l)).abs() < 0.3,
        "centroid {centroid:?}"
    );
}

#[test]
fn a_shrinking_disk_disappears() {
    let l = 4.0;
    let mut c = disks(80.0, l, &[(40.0, 40.0, 12.0)]);
    let p = params(l);
    let centre = Vector2::new(40.0, 40.0);
    for step in 0..60 {
        if c.cells_with_label(1) == 0 {
            break;
        }
        let d = interface_field(&c, |_, q| {
            let r = q - centre;
            if r.norm() < 1e-9 {
                Vector2::zeros()
            } else {
                -r.normalize() * (0.5 * l).min(r.norm())
            }
        });
        c.deform(&d, &p);
        assert_valid(&c);
        assert_quality(&c);
        assert!(
            step < 59,
            "disk never vanished: {} cells left",
            c.cells_with_label(1)
        );
    }
    assert_eq!(c.cells_with_label(1), 0);
}

#[test]
fn two_disks_pushed_together_merge() {
    let l = 4.0;
    let mut c = disks(120.0, l, &[(40.0, 60.0, 14.0), (80.0, 60.0, 14.0)]);
    c.label_by(|q| {
        let a = (q - Vector2::new(40.0, 60.0)).norm() < 14.0;
        let b = (q - Vector2::new(80.0, 60.0)).norm() < 14.0;
        (a || b) as u32
    });
    let p = params(l);
    assert_eq!(c.components(1), 2);
    for _ in 0..40 {
        if c.components(1) == 1 {
            break;
        }
        let d = interface_field(&c, |_, q| {
            Vector2::new(if q.x < 60.0 { 0.4 * l } else { -0.4 * l }, 0.0)
        });
        c.deform(&d, &p);
        assert_valid(&c);
        assert_quality(&c);
    }
    assert_eq!(c.components(1), 1);
}

#[test]
fn a_pinched_dumbbell_splits() {
    let l = 4.0;
    let mut c = Complex2Builder::dumbbell(l);
    let p = params(l);
    assert_eq!(c.components(1), 1);
    for _ in 0..40 {
        if c.components(1) == 2 {
            break;
        }
        // Squeeze the neck vertically towards y = 50.
        let d = interface_field(&c, |_, q| {
            let weight = (1.0 - (q.x - 60.0).abs() / 12.0).max(0.0);
            let dy = (50.0 - q.y).signum() * 0.4 * l * weight;
            Vector2::new(0.0, dy)
        });
        c.deform(&d, &p);
        assert_valid(&c);
        assert_quality(&c);
    }
    assert_eq!(c.components(1), 2);
}

#[test]
fn a_triple_junction_persists_under_a_smooth_field() {
    let l = 4.0;
    let mut c = disks(100.0, l, &[]);
    c.label_by(|q| {
        if (q - Vector2::new(50.0, 50.0)).norm() > 30.0 {
            0
        } else if q.x < 50.0 {
            1
        } else {
            2
        }
    });
    let p = params(l);
    let junctions = |c: &dsc_seg::complex::Complex2| {
        c.vertex_ids()
            .filter(|&v| c.class(v).kind == VertexKind::Junction)
            .count()
    };
    assert!(junctions(&c) >= 2);
    for k in 0..10 {
        let phase = k as f64 * 0.3;
        let d = interface_field(&c, |_, q| {
            Vector2::new((q.y / 15.0 + phase).sin(), (q.x / 15.0 + phase).cos()) * (0.3 * l)
        });
        c.deform(&d, &p);
        assert_valid(&c);
        assert_quality(&c);
        assert!(junctions(&c) >= 2, "junctions lost at step {k}");
        assert_eq!(c.components(1), 1);
        assert_eq!(c.components(2), 1);
    }
}

/// Builders for shapes that are not disks.
struct Complex2Builder;

impl Complex2Builder {
    /// Two disks joined by a neck of half-width 5 along y = 50.
    fn dumbbell(l: f64) -> dsc_seg::complex::Complex2 {
        let mut c = disks(120.0, l, &[]);
        c.label_by(|q| {
            let left = (q - Vector2::new(30.0, 50.0)).norm() < 18.0;
            let right = (q - Vector2::new(90.0, 50.0)).norm() < 18.0;
            let neck = q.x > 30.0 && q.x < 90.0 && (q.y - 50.0).abs() < 6.0;
            (left || right || neck) as u32
        });
        c
    }
}

#[test]
fn interfaces_slide_along_the_image_border() {
    let l = 4.0;
    let mut c = disks(100.0, l, &[(20.0, 50.0, 12.0)]);
    let p = params(l);
    let area0 = c.phase_measures()[1];
    // Push the left half of the disk into the border (the right half stays).
    for _ in 0..8 {
        let d = interface_field(&c, |_, q| {
            Vector2::new(if q.x < 20.0 { -0.4 * l } else { 0.0 }, 0.0)
        });
        c.deform(&d, &p);
        assert_valid(&c);
    }
    assert!(c.phase_measures()[1] > 0.5 * area0);
    // The object now touches the border: interface vertices lie on x = 0 ...
    let on_border: Vec<_> = c
        .vertex_ids()
        .filter(|&v| c.class(v).on_interface() && c.position(v).x == 0.0)
        .collect();
    let min_x = c
        .vertex_ids()
        .filter(|&v| c.class(v).on_interface())
        .map(|v| c.position(v).x)
        .fold(f64::INFINITY, f64::min);
    assert!(
        on_border.len() >= 2,
        "interface never reached the border: {} on it, min x {min_x}, area {:?}",
        on_border.len(),
        c.phase_measures()
    );
    // ... and they keep sliding along it when pushed sideways.
    let y0: Vec<f64> = on_border.iter().map(|&v| c.position(v).y).collect();
    let mut d = dsc_seg::dsc::Destinations::new(&c);
    for &v in &on_border {
        d.set(v, c.position(v) + Vector2::new(-1.0, 0.5 * l));
    }
    c.deform(&d, &p);
    assert_valid(&c);
    let moved = c
        .vertex_ids()
        .filter(|&v| c.class(v).on_interface() && c.position(v).x == 0.0)
        .map(|v| c.position(v).y)
        .filter(|y| !y0.contains(y))
        .count();
    assert!(moved >= 1, "border vertices did not slide");
}

#[test]
fn an_unreachable_destination_is_reported_not_an_error() {
    let l = 4.0;
    let mut c = disks(60.0, l, &[(30.0, 30.0, 10.0)]);
    let mut p = params(l);
    p.max_rounds = 3;
    // Ask one interface vertex to jump far across the disk in one call.
    let v = c.vertex_ids().find(|&v| c.class(v).on_interface()).unwrap();
    let mut d = dsc_seg::dsc::Destinations::new(&c);
    let target = Vector2::new(60.0, 60.0) - c.position(v);
    d.set(v, target);
    let report = c.deform(&d, &p);
    assert_valid(&c);
    assert_eq!(report.arrived + report.stopped_short, 1);
    assert_eq!(report.stopped_short, 1);
}
