//! Property test: random smooth displacement fields on random multiphase labellings.

use crate::common::*;
use dsc_seg::complex::Complex;
use nalgebra::Vector2;
use proptest::prelude::*;

/// A smooth field: a sum of a few sinusoids with random wave vectors and phases.
#[derive(Clone, Debug)]
struct Field {
    waves: Vec<(f64, f64, f64, f64, f64)>, // (kx, ky, phase, ax, ay)
}

impl Field {
    fn at(&self, p: Vector2<f64>, t: f64) -> Vector2<f64> {
        let mut out = Vector2::zeros();
        for &(kx, ky, ph, ax, ay) in &self.waves {
            let s = (kx * p.x + ky * p.y + ph + t).sin();
            out += Vector2::new(ax, ay) * s;
        }
        out
    }
}

fn field() -> impl Strategy<Value = Field> {
    prop::collection::vec(
        (
            -0.15..0.15f64,
            -0.15..0.15f64,
            0.0..6.3f64,
            -1.0..1.0f64,
            -1.0..1.0f64,
        ),
        1..4,
    )
    .prop_map(|waves| Field { waves })
}

fn labelling() -> impl Strategy<Value = Vec<(f64, f64, f64)>> {
    prop::collection::vec((8.0..52.0f64, 8.0..52.0f64, 4.0..16.0f64), 1..5)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, ..ProptestConfig::default() })]

    /// 200 deform steps keep every invariant, every cell positive (exact) and
    /// the total area exact; validate() checks all three.
    #[test]
    fn random_smooth_fields_keep_the_complex_valid(disks_ in labelling(), f in field()) {
        let l = 4.0;
        let mut c = Complex::rectangle(60.0, 60.0, l).unwrap();
        c.label_by(|p| {
            let mut label = 0;
            for (k, &(x, y, r)) in disks_.iter().enumerate() {
                if (p - Vector2::new(x, y)).norm() < r {
                    label = (k % 3) as u32 + 1;
                }
            }
            label
        });
        let p = params(l);
        let scale = 0.3 * l / f.waves.iter().map(|w| w.3.abs() + w.4.abs()).sum::<f64>().max(1e-9);
        for step in 0..200 {
            let t = step as f64 * 0.05;
            let d = interface_field(&c, |_, q| f.at(q, t) * scale);
            c.deform(&d, &p);
            let findings = c.validate();
            prop_assert!(findings.is_empty(), "step {step}: {:?}", &findings[..findings.len().min(3)]);
        }
        let total: f64 = c.phase_measures().iter().sum();
        prop_assert!((total - 3600.0).abs() <= 1e-9 * 3600.0);
    }
}
