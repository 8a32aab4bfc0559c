//! The sizing field: random graded fields with random deformations keep the
//! complex valid and the field's gradation bound, in 2D and 3D; a graded
//! field grades the mesh.

use crate::common::*;
use dsc_seg::complex::Complex;
use dsc_seg::dim::{Dim, Point, D2, D3};
use dsc_seg::dsc::{Connectivity, Destinations, DscParams, DscWorkspace, SizingField};
use nalgebra::Vector3;
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const L: f64 = 4.0;

fn point<K: Dim>(coords: &[f64]) -> K::Point {
    let mut p = K::Point::zero();
    for a in 0..K::N {
        p[a] = coords[a];
    }
    p
}

fn bounds<K: Dim>(c: &Complex<K>) -> (Vec<f64>, Vec<f64>) {
    let (lo, hi) = c.domain();
    (
        (0..K::N).map(|a| lo[a]).collect(),
        (0..K::N).map(|a| hi[a]).collect(),
    )
}

/// A field between `0.4·L` and `3·L`, lowered at a few random points and
/// graded with a random rate; returns it and the rate.
fn random_field<K: Dim>(c: &Complex<K>, rng: &mut ChaCha8Rng) -> (SizingField, f64) {
    let (lo, hi) = bounds(c);
    let rate = rng.random_range(0.3..1.0);
    let mut f = SizingField::constant(&lo, &hi, K::N, 0.5 * L, rng.random_range(L..3.0 * L));
    for _ in 0..rng.random_range(1..5) {
        let q: Vec<f64> = (0..K::N).map(|a| rng.random_range(lo[a]..hi[a])).collect();
        f.lower(&point::<K>(&q), rng.random_range(0.4 * L..L));
    }
    f.limit_gradation(rate);
    (f, rate)
}

/// Random smooth interface displacements, deformed against a random graded
/// field: `validate()` green and the total measure exact after every call.
fn graded_deforms_stay_valid<K: Connectivity>(mut c: Complex<K>, seed: u64, calls: usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (field, rate) = random_field(&c, &mut rng);
    assert!(field.gradation_excess(rate) < 1e-9, "gradation bound");
    let params = DscParams::new::<K>(L);
    let total = c.domain_measure();
    let mut ws = DscWorkspace::new();
    ws.set_sizing(field);
    for call in 0..calls {
        let omega: Vec<f64> = (0..K::N).map(|_| rng.random_range(-0.3..0.3)).collect();
        let amp: Vec<f64> = (0..K::N).map(|_| rng.random_range(-0.8..0.8)).collect();
        let phase = rng.random_range(0.0..std::f64::consts::TAU);
        let (omega, amp) = (point::<K>(&omega), point::<K>(&amp) * L);
        let d = interface_field(&c, |_, p| amp * (omega.dot(&p) + phase).sin());
        c.deform_with(&d, &params, &mut ws);
        let findings = c.validate();
        assert!(
            findings.is_empty(),
            "seed {seed} call {call}: {:?}",
            &findings[..findings.len().min(3)]
        );
        let sum: f64 = c.phase_measures().iter().sum();
        assert!(
            (sum - total).abs() <= 1e-9 * total,
            "measure {sum} != {total}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 8, ..ProptestConfig::default() })]

    #[test]
    fn random_graded_fields_keep_the_2d_complex_valid(seed in any::<u64>()) {
        let c = disks(48.0, L, &[(24.0, 24.0, 10.0), (10.0, 36.0, 5.0)]);
        graded_deforms_stay_valid::<D2>(c, seed, 12);
    }

    #[test]
    fn random_graded_fields_keep_the_3d_complex_valid(seed in any::<u64>()) {
        let c = balls([24.0, 24.0, 24.0], L, &[(Vector3::new(12.0, 12.0, 12.0), 6.5)]);
        graded_deforms_stay_valid::<D3>(c, seed, 3);
    }
}

/// Resizing against a field fine on the left and coarse on the right, with
/// nothing moving, leaves the left half's cells smaller than the right's.
fn field_grades_the_mesh<K: Connectivity>(mut c: Complex<K>, passes: usize) -> (f64, f64) {
    let (lo, hi) = bounds(&c);
    let mid = 0.5 * (lo[0] + hi[0]);
    let mut field = SizingField::constant(&lo, &hi, K::N, 0.5 * L, 2.5 * L);
    let step = 0.25 * L;
    let mut q = lo.clone();
    // Lower the whole left half to L/4: walk its grid.
    loop {
        field.lower(&point::<K>(&q), 0.25 * L);
        let mut a = 0;
        loop {
            q[a] += step;
            let end = if a == 0 { mid } else { hi[a] };
            if q[a] < end {
                break;
            }
            q[a] = lo[a];
            a += 1;
            if a == K::N {
                break;
            }
        }
        if a == K::N {
            break;
        }
    }
    field.limit_gradation(0.5);
    let params = DscParams::new::<K>(L);
    let mut ws = DscWorkspace::new();
    ws.set_sizing(field);
    let none = Destinations::new(&c);
    for _ in 0..passes {
        c.deform_with(&none, &params, &mut ws);
        assert_valid(&c);
    }
    let (mut left, mut right) = ((0.0, 0usize), (0.0, 0usize));
    for cell in c.cell_ids() {
        let pts = c.cell_points(cell);
        let x: f64 = pts[..K::NV].iter().map(|p| p[0]).sum::<f64>() / K::NV as f64;
        let side = if x < mid - 2.0 * L {
            &mut left
        } else if x > mid + 4.0 * L {
            &mut right
        } else {
            continue;
        };
        side.0 += c.measure(cell);
        side.1 += 1;
    }
    (left.0 / left.1 as f64, right.0 / right.1 as f64)
}

#[test]
fn a_graded_field_grades_the_2d_mesh() {
    let c = Complex::<D2>::rectangle(96.0, 48.0, L).unwrap();
    let (left, right) = field_grades_the_mesh(c, 6);
    // Cells split above 5·A(h) and collapse below 0.2·A(h) or at edges
    // under 0.6·h: from L/4 to 2.5·L the targets differ 100 times in area.
    assert!(
        right > 8.0 * left,
        "mean cell area left {left}, right {right}"
    );
}

#[test]
fn a_graded_field_grades_the_3d_mesh() {
    let c = Complex::<D3>::cuboid([64.0, 24.0, 24.0], L).unwrap();
    let (left, right) = field_grades_the_mesh(c, 4);
    assert!(
        right > 4.0 * left,
        "mean tet volume left {left}, right {right}"
    );
}

/// A workspace kept across graded deforms (which remembers the coarsening
/// collapses the mesh refused, across compactions) gives, bit for bit, the
/// meshes of a fresh workspace per deform, which tries every collapse; a
/// clone deformed in between with the same workspace does not confuse it.
fn kept_workspace_coarsens_like_fresh_ones<K: Connectivity>(
    c: Complex<K>,
    seed: u64,
    calls: usize,
) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (field, _) = random_field(&c, &mut rng);
    let params = DscParams::new::<K>(L);
    let (mut fresh, mut kept) = (c.clone(), c);
    let mut ws = DscWorkspace::new();
    ws.set_sizing(field.clone());
    let mut interior_collapses = 0;
    for call in 0..calls {
        let omega: Vec<f64> = (0..K::N).map(|_| rng.random_range(-0.3..0.3)).collect();
        let amp: Vec<f64> = (0..K::N).map(|_| rng.random_range(-0.6..0.6)).collect();
        let (omega, amp) = (point::<K>(&omega), point::<K>(&amp) * L);
        let d = interface_field(&kept, |_, p| amp * omega.dot(&p).sin());
        if call % 3 == 2 {
            // Another complex through the same workspace.
            kept.clone().deform_with(&d, &params, &mut ws);
        }
        let mut once = DscWorkspace::new();
        once.set_sizing(field.clone());
        let a = fresh.deform_with(&d, &params, &mut once);
        let b = kept.deform_with(&d, &params, &mut ws);
        assert_eq!(a.resize, b.resize, "seed {seed} call {call}");
        let (ma, mb) = (fresh.to_arrays(), kept.to_arrays());
        assert!(
            ma.connectivity == mb.connectivity,
            "seed {seed} call {call}: cells"
        );
        assert!(ma.points == mb.points, "seed {seed} call {call}: positions");
        interior_collapses += b.resize.interior_collapses;
    }
    assert!(interior_collapses > 0, "seed {seed}: nothing coarsened");
}

#[test]
fn kept_workspace_coarsens_like_fresh_ones_2d() {
    for seed in 0..4 {
        let c = disks(48.0, L, &[(24.0, 24.0, 10.0), (10.0, 36.0, 5.0)]);
        kept_workspace_coarsens_like_fresh_ones::<D2>(c, seed, 10);
    }
}

#[test]
fn kept_workspace_coarsens_like_fresh_ones_3d() {
    for seed in 0..3 {
        let c = balls(
            [28.0, 24.0, 24.0],
            L,
            &[(Vector3::new(12.0, 12.0, 12.0), 6.5)],
        );
        kept_workspace_coarsens_like_fresh_ones::<D3>(c, seed, 6);
    }
}
