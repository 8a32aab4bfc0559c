//! The 3D DSC's required behaviours: topology changes of balls and
//! a torus, `validate()` after every deform, the tet quality distribution.

use crate::common::*;
use dsc_seg::complex::Complex3;
use dsc_seg::dim::D3;
use dsc_seg::dsc::DscParams;
use nalgebra::Vector3;
use std::time::Instant;

fn params3(l: f64) -> DscParams {
    DscParams::new::<D3>(l)
}

fn report(name: &str, step: usize, c: &Complex3) {
    let (min, p5, median, low) = quality_summary(c);
    eprintln!(
        "{name} step {step}: {} tets, quality min {min:.3} p5 {p5:.3} median {median:.3}, {:.1}% below 0.3",
        c.cell_count(),
        100.0 * low
    );
}

/// Asserts the quality the improvement loop must deliver: no degenerate tet left.
fn assert_quality3(c: &Complex3, p: &DscParams) {
    let (min, _, _, low) = quality_summary(c);
    assert!(
        min >= p.degenerate_quality,
        "degenerate tet left: q = {min}"
    );
    assert!(low < 0.2, "{:.1}% of tets below 0.3", 100.0 * low);
}

#[test]
fn two_balls_pushed_together_merge() {
    let start = Instant::now();
    let l = 4.0;
    let mut c = balls(
        [40.0, 28.0, 28.0],
        l,
        &[
            (Vector3::new(11.0, 14.0, 14.0), 7.0),
            (Vector3::new(29.0, 14.0, 14.0), 7.0),
        ],
    );
    c.label_by(|q| {
        let a = (q - Vector3::new(11.0, 14.0, 14.0)).norm() < 7.0;
        let b = (q - Vector3::new(29.0, 14.0, 14.0)).norm() < 7.0;
        (a || b) as u32
    });
    let p = params3(l);
    assert_valid(&c);
    assert_eq!(c.components(1), 2);
    let mut steps = 0;
    for step in 0..30 {
        if c.components(1) == 1 {
            break;
        }
        let d = interface_field(&c, |_, q| {
            Vector3::new(if q.x < 20.0 { 0.4 * l } else { -0.4 * l }, 0.0, 0.0)
        });
        let r = c.deform(&d, &p);
        eprintln!("merge step {step}: {:?}", r.improve);
        assert_valid(&c);
        assert_quality3(&c, &p);
        steps = step + 1;
    }
    report("merge", steps, &c);
    assert_eq!(c.components(1), 1, "balls never merged");
    assert_eq!(c.components(0), 1);
    eprintln!("merge: {steps} deforms, {:.2?}", start.elapsed());
}

#[test]
fn a_shrinking_ball_disappears() {
    let start = Instant::now();
    let l = 4.0;
    let centre = Vector3::new(16.0, 16.0, 16.0);
    let mut c = balls([32.0, 32.0, 32.0], l, &[(centre, 9.0)]);
    let p = params3(l);
    assert_valid(&c);
    let v0 = c.phase_measures()[1];
    let mut steps = 0;
    for step in 0..40 {
        if c.cells_with_label(1) == 0 {
            break;
        }
        let d = interface_field(&c, |_, q| {
            let r = q - centre;
            if r.norm() < 1e-9 {
                Vector3::zeros()
            } else {
                -r.normalize() * (0.5 * l).min(r.norm())
            }
        });
        c.deform(&d, &p);
        assert_valid(&c);
        assert_quality3(&c, &p);
        steps = step + 1;
        if step == 0 {
            assert!(c.phase_measures()[1] < v0, "the ball did not shrink");
        }
    }
    report("shrink", steps, &c);
    assert_eq!(c.cells_with_label(1), 0, "ball never vanished");
    eprintln!("shrink: {steps} deforms, {:.2?}", start.elapsed());
}

/// A solid torus around the vertical axis through the box centre.
fn torus(size: [f64; 3], l: f64, major: f64, minor: f64) -> Complex3 {
    let mut c = balls(size, l, &[]);
    let (cx, cy, cz) = (size[0] / 2.0, size[1] / 2.0, size[2] / 2.0);
    c.label_by(|q| {
        let rho = ((q.x - cx).powi(2) + (q.y - cy).powi(2)).sqrt();
        ((rho - major).powi(2) + (q.z - cz).powi(2) < minor * minor) as u32
    });
    c
}

#[test]
fn a_torus_keeps_its_hole_under_a_small_smooth_field() {
    let start = Instant::now();
    let l = 3.0;
    let size = [40.0, 40.0, 24.0];
    let mut c = torus(size, l, 10.0, 4.5);
    let p = params3(l);
    assert_valid(&c);
    assert_eq!(c.components(1), 1);
    assert_eq!(
        interface_euler(&c, 0, 1),
        0,
        "initial interface is not a torus"
    );
    report("torus", 0, &c);
    for k in 0..8 {
        let phase = k as f64 * 0.4;
        let d = interface_field(&c, |_, q| {
            Vector3::new(
                (q.y / 9.0 + phase).sin(),
                (q.z / 9.0 + phase).cos(),
                (q.x / 9.0 + phase).sin(),
            ) * (0.25 * l)
        });
        c.deform(&d, &p);
        assert_valid(&c);
        assert_quality3(&c, &p);
        assert_eq!(c.components(1), 1, "torus broke at step {k}");
        assert_eq!(
            interface_euler(&c, 0, 1),
            0,
            "torus lost its hole at step {k}"
        );
    }
    report("torus", 8, &c);
    eprintln!("torus smooth field: {:.2?}", start.elapsed());
}

#[test]
fn a_torus_closes_when_its_tube_is_inflated_into_the_hole() {
    let start = Instant::now();
    let l = 3.0;
    let size = [40.0, 40.0, 24.0];
    let (cx, cy) = (20.0, 20.0);
    let major = 10.0;
    let mut c = torus(size, l, major, 4.5);
    let p = params3(l);
    assert_eq!(interface_euler(&c, 0, 1), 0);
    let mut steps = 0;
    for step in 0..40 {
        if interface_euler(&c, 0, 1) == 2 {
            break;
        }
        // The inner half of the tube swells towards the axis; the outer half stays.
        let d = interface_field(&c, |_, q| {
            let r = Vector3::new(q.x - cx, q.y - cy, 0.0);
            let rho = r.norm();
            if rho < major && rho > 1e-9 {
                -r / rho * (0.4 * l).min(rho)
            } else {
                Vector3::zeros()
            }
        });
        c.deform(&d, &p);
        assert_valid(&c);
        assert_quality3(&c, &p);
        assert_eq!(c.components(1), 1);
        steps = step + 1;
    }
    report("torus closing", steps, &c);
    assert_eq!(interface_euler(&c, 0, 1), 2, "the hole never closed");
    // Where the hole pinches shut first, a sliver of the outside phase can be
    // left trapped for a while (the inner wall closes at several heights at once).
    eprintln!(
        "torus closing: {steps} deforms, outside phase in {} piece(s), {:.2?}",
        c.components(0),
        start.elapsed()
    );
}

#[test]
fn flips_raise_the_quality_of_a_jittered_mesh() {
    // Random interior jitter makes slivers; one improvement pass must remove the
    // degenerate ones and leave fewer low-quality tets.
    use rand::{Rng, SeedableRng};
    let l = 4.0;
    let mut c = balls(
        [24.0, 24.0, 24.0],
        l,
        &[(Vector3::new(12.0, 12.0, 12.0), 6.0)],
    );
    let p = params3(l);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut star = Vec::new();
    let ids: Vec<_> = c.vertex_ids().collect();
    for v in ids {
        if c.class(v).on_boundary() {
            continue;
        }
        let q = c.position(v)
            + Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ) * (0.6 * l);
        c.move_towards(v, q, p.tolerance(), &mut star);
    }
    assert_valid(&c);
    let before = quality_summary(&c);
    let stats = c.improve(&p);
    assert_valid(&c);
    let after = quality_summary(&c);
    eprintln!("jitter: before {before:?} after {after:?}, {stats:?}");
    assert!(stats.flips > 0);
    assert!(after.3 < before.3, "low-quality fraction did not drop");
    assert!(after.0 >= p.degenerate_quality);
}
