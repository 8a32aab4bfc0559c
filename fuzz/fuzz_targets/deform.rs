//! Random displacement fields, label changes and parameters on small
//! complexes; `validate()` must stay green after every deform.
#![no_main]

use arbitrary::Arbitrary;
use dsc_seg::complex::Complex;
use dsc_seg::dim::D2;
use dsc_seg::dsc::{Destinations, DscParams};
use libfuzzer_sys::fuzz_target;
use nalgebra::Vector2;

#[derive(Arbitrary, Debug)]
struct Input {
    size: u8,
    edge: u8,
    disks: Vec<(u8, u8, u8, u8)>,
    steps: Vec<Step>,
}

#[derive(Arbitrary, Debug)]
struct Step {
    waves: Vec<(i8, i8, u8, i8, i8)>,
    amplitude: u8,
    relabel: Option<(u16, u8)>,
}

fuzz_target!(|input: Input| {
    let size = 16.0 + (input.size % 64) as f64;
    let l = 2.0 + (input.edge % 8) as f64;
    let Ok(mut c) = Complex::rectangle(size, size, l) else { return };
    c.label_by(|p| {
        let mut label = 0;
        for &(x, y, r, k) in input.disks.iter().take(6) {
            let centre = Vector2::new(x as f64 / 255.0 * size, y as f64 / 255.0 * size);
            if (p - centre).norm() < r as f64 / 255.0 * size * 0.5 {
                label = (k % 4) as u32;
            }
        }
        label
    });
    let params = DscParams::new::<D2>(l);
    for step in input.steps.iter().take(20) {
        if let Some((cell, label)) = step.relabel {
            let ids: Vec<_> = c.cell_ids().collect();
            if !ids.is_empty() {
                c.set_label(ids[cell as usize % ids.len()], (label % 4) as u32);
            }
        }
        let amplitude = (step.amplitude as f64 / 255.0) * 2.0 * l;
        let mut d = Destinations::new(&c);
        for v in c.vertex_ids() {
            if !c.class(v).on_interface() {
                continue;
            }
            let p = c.position(v);
            let mut u = Vector2::zeros();
            for &(kx, ky, ph, ax, ay) in step.waves.iter().take(4) {
                let s = (kx as f64 * 0.02 * p.x + ky as f64 * 0.02 * p.y + ph as f64 * 0.1).sin();
                u += Vector2::new(ax as f64, ay as f64) / 128.0 * s;
            }
            d.set(v, p + u * amplitude);
        }
        c.deform(&d, &params);
        let findings = c.validate();
        assert!(findings.is_empty(), "{:?}", &findings[..findings.len().min(3)]);
    }
});
