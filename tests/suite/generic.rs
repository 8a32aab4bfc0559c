//! Generic tests run for both dimensions: each law is written once as a
//! function generic over the dimension and instantiated for `D2` and `D3`.

use crate::common::*;
use dsc_seg::complex::{Complex, Label, VertexId};
use dsc_seg::dim::{Dim, Point, D2, D3};
use dsc_seg::dsc::{Connectivity, Destinations, DscParams};
use dsc_seg::ops::CollapseMode;
use nalgebra::{Vector2, Vector3};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// What the generic suite needs to know about a dimension: a small two-phase
/// test complex and random vectors.
trait TestDim: Connectivity {
    /// Edge length of the sample complex.
    const L: f64;
    /// A small box with a round inclusion of phase 1.
    fn sample() -> Complex<Self>;
    /// A vector with coordinates uniform in `[-s, s]`.
    fn random_vector(rng: &mut ChaCha8Rng, s: f64) -> Self::Point;
}

impl TestDim for D2 {
    const L: f64 = 4.0;
    fn sample() -> Complex<D2> {
        disks(48.0, Self::L, &[(24.0, 24.0, 10.0)])
    }
    fn random_vector(rng: &mut ChaCha8Rng, s: f64) -> Vector2<f64> {
        Vector2::new(rng.random_range(-s..s), rng.random_range(-s..s))
    }
}

impl TestDim for D3 {
    const L: f64 = 4.0;
    fn sample() -> Complex<D3> {
        balls(
            [24.0, 24.0, 24.0],
            Self::L,
            &[(Vector3::new(12.0, 12.0, 12.0), 6.5)],
        )
    }
    fn random_vector(rng: &mut ChaCha8Rng, s: f64) -> Vector3<f64> {
        Vector3::new(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        )
    }
}

fn params_for<K: Dim>() -> DscParams {
    DscParams::new::<K>(4.0)
}

fn assert_measures_close(a: &[f64], b: &[f64], what: &str) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert!(
            (x - y).abs() <= 1e-9 * x.abs().max(1.0),
            "{what}: phase measure {x} -> {y}"
        );
    }
}

fn validates_on_construction<K: TestDim>() {
    let c = K::sample();
    assert_valid(&c);
    assert_eq!(c.components(1), 1);
    let total: f64 = c.phase_measures().iter().sum();
    assert!((total - c.domain_measure()).abs() <= 1e-9 * c.domain_measure());
}

fn move_towards_never_inverts<K: TestDim>() {
    let mut c = K::sample();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut star = Vec::new();
    let tol = params_for::<K>().tolerance();
    for _round in 0..3 {
        let ids: Vec<VertexId> = c.vertex_ids().collect();
        for v in ids {
            let dest = c.position(v) + K::random_vector(&mut rng, 2.0 * K::L);
            c.move_towards(v, dest, tol, &mut star);
        }
        // Every cell stays positive (exact), nothing else breaks.
        assert_valid(&c);
    }
}

fn split_edge_conserves_phase_measures<K: TestDim>() {
    let mut c = K::sample();
    let before = c.phase_measures();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let cells: Vec<_> = c.cell_ids().collect();
    let mut done = 0;
    for _ in 0..200 {
        let t = cells[rng.random_range(0..cells.len())];
        if !c.is_alive(t) {
            continue;
        }
        let cell = c.cell(t).to_vec();
        let (a, b) = (rng.random_range(0..K::NV), rng.random_range(0..K::NV));
        if a == b {
            continue;
        }
        if c.split_edge(cell[a], cell[b]).is_ok() {
            done += 1;
            assert_measures_close(&before, &c.phase_measures(), "split_edge");
        }
    }
    assert!(done > 50, "only {done} splits succeeded");
    assert_valid(&c);
}

fn safe_collapse_of_non_interface_edges_conserves_phase_measures<K: TestDim>() {
    let mut c = K::sample();
    let p = params_for::<K>();
    let straight_cos = p.straight_angle_deg.to_radians().cos();
    let before = c.phase_measures();
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let mut star = Vec::new();
    let mut edge_cells = Vec::new();
    let mut done = 0;
    for _ in 0..300 {
        let cells: Vec<_> = c.cell_ids().collect();
        let t = cells[rng.random_range(0..cells.len())];
        let cell = c.cell(t).to_vec();
        let (a, b) = (rng.random_range(0..K::NV), rng.random_range(0..K::NV));
        if a == b {
            continue;
        }
        let (u, v) = (cell[a], cell[b]);
        // Non-interface edge: every cell around it carries the same label.
        c.cells_of_edge(u, v, &mut star, &mut edge_cells);
        let label: Label = c.label(edge_cells[0]);
        if edge_cells.iter().any(|&e| c.label(e) != label) {
            continue;
        }
        if c.collapse_edge(u, v, CollapseMode::Safe, p.degenerate_quality, straight_cos)
            .is_ok()
        {
            done += 1;
            assert_measures_close(&before, &c.phase_measures(), "collapse_edge");
        }
    }
    assert!(done > 10, "only {done} collapses succeeded");
    assert_valid(&c);
}

/// The positions of a complex's vertices, and its cells with their labels.
type Snapshot<P> = (Vec<P>, Vec<(Vec<VertexId>, Label)>);

/// The positions, cells and labels of `c`, to compare two complexes.
fn snapshot<K: Dim>(c: &Complex<K>) -> Snapshot<K::Point> {
    let positions = c.vertex_ids().map(|v| c.position(v)).collect();
    let cells = c
        .cell_ids()
        .map(|t| (c.cell(t).to_vec(), c.label(t)))
        .collect();
    (positions, cells)
}

/// Safe collapses of edges between two interface vertices (most have no
/// candidate, and are refused before the stars are searched): a refusal
/// leaves the complex as it was, a collapse leaves it valid, and both occur.
/// On the sample's round inclusion and on a flat interface (the sample
/// cut by the plane through a middle vertex normal to the first axis).
fn safe_collapse_between_interface_vertices_is_refused_cleanly<K: TestDim>() {
    let round = K::sample();
    let mut flat = round.clone();
    let mut xs: Vec<f64> = flat.vertex_ids().map(|v| flat.position(v)[0]).collect();
    xs.sort_by(f64::total_cmp);
    let cut = xs[xs.len() / 2];
    flat.label_by(|p| u32::from(p[0] < cut));
    let (mut collapsed, mut refused) = (0, 0);
    for c in [round, flat] {
        let (done, kept) = collapse_between_interface_vertices(&c);
        collapsed += done;
        refused += kept;
    }
    assert!(
        collapsed > 0 && refused > collapsed,
        "{collapsed} collapsed, {refused} refused"
    );
}

/// Tries the safe collapse of every edge of `c` between two interface
/// vertices on a copy; asserts that a refusal leaves the copy as it was and
/// a collapse leaves it valid. Returns (collapsed, refused).
fn collapse_between_interface_vertices<K: TestDim>(c: &Complex<K>) -> (usize, usize) {
    let p = params_for::<K>();
    let straight_cos = p.straight_angle_deg.to_radians().cos();
    let before = snapshot(c);
    let mut edges = Vec::new();
    for t in c.cell_ids() {
        let cell = c.cell(t);
        for a in 0..K::NV {
            for b in a + 1..K::NV {
                let (u, v) = (cell[a], cell[b]);
                if c.class(u).on_interface() && c.class(v).on_interface() {
                    edges.push((u.min(v), u.max(v)));
                }
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    let (mut collapsed, mut refused) = (0, 0);
    for (u, v) in edges {
        let mut after = c.clone();
        match after.collapse_edge(u, v, CollapseMode::Safe, p.min_quality, straight_cos) {
            Ok(_) => {
                collapsed += 1;
                assert_valid(&after);
            }
            Err(_) => {
                refused += 1;
                assert!(
                    snapshot(&after) == before,
                    "a refused collapse changed the complex"
                );
            }
        }
    }
    (collapsed, refused)
}

macro_rules! for_both_dimensions {
    ($($name:ident),* $(,)?) => {
        mod d2 {
            $(#[test] fn $name() { super::$name::<dsc_seg::dim::D2>() })*
        }
        mod d3 {
            $(#[test] fn $name() { super::$name::<dsc_seg::dim::D3>() })*
        }
    };
}

for_both_dimensions!(
    validates_on_construction,
    move_towards_never_inverts,
    split_edge_conserves_phase_measures,
    safe_collapse_of_non_interface_edges_conserves_phase_measures,
    safe_collapse_between_interface_vertices_is_refused_cleanly,
);

/// Interface destinations `p + Σ a_k sin(ω_k·p + φ_k)`: a random smooth field.
fn smooth_field<K: Dim>(c: &Complex<K>, modes: &[(K::Point, K::Point, f64)]) -> Destinations<K> {
    interface_field(c, |_, p| {
        let mut d = K::Point::zero();
        for (amplitude, omega, phase) in modes {
            d += *amplitude * (omega.dot(&p) + phase).sin();
        }
        d
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// Random smooth displacement fields over several deform calls in 3D keep
    /// `validate()` green and the total volume exact.
    #[test]
    fn random_smooth_fields_keep_the_3d_complex_valid(
        seed in any::<u64>(),
        amplitude in 0.2f64..1.2,
        calls in 2usize..4,
    ) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut c = D3::sample();
        let p = params_for::<D3>();
        let total = c.domain_measure();
        for _ in 0..calls {
            let modes: Vec<_> = (0..3)
                .map(|_| {
                    (
                        D3::random_vector(&mut rng, amplitude * D3::L),
                        D3::random_vector(&mut rng, 0.3),
                        rng.random_range(0.0..std::f64::consts::TAU),
                    )
                })
                .collect();
            let d = smooth_field(&c, &modes);
            c.deform(&d, &p);
            let findings = c.validate();
            prop_assert!(findings.is_empty(), "validate() found {:?}", &findings[..findings.len().min(5)]);
            let sum: f64 = c.phase_measures().iter().sum();
            prop_assert!((sum - total).abs() <= 1e-9 * total, "volume {sum} != {total}");
        }
    }
}
