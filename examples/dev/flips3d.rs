//! Diagnoses the label flips of a 3D run: which cells flip at each flip
//! iteration (voxel count, on the interface or not, towards or away from the
//! ground truth), how often each voxel changes label over the run, and the
//! per-iteration quantities of the stopping rule.
//!
//! `cargo run --release --example flips3d -- [two_balls|torus|hollow_sphere] [size] [sigma] [max_iterations]`
//! (environment `FLIP_INTERVAL=k` and `FLIP_ONCE=0|1` override the 3D defaults).

use dsc_seg::complex::{Complex3, Label};
use dsc_seg::dim::D3;
use dsc_seg::phantom::Phantom3Kind;
use dsc_seg::pipeline::mean_dice;
use dsc_seg::segment::{
    ImageView, IterationState, LabelRule, Models, Raster, SegmentParams, Segmentation,
};
use std::sync::{Arc, Mutex};

/// The ground truth and per-voxel flip counts, shared with the wrapper.
struct Log {
    truth: Vec<u8>,
    voxel_flips: Vec<u16>,
}

/// Runs the wrapped rule and reports what it changed.
struct Watch {
    inner: Box<dyn LabelRule<D3>>,
    log: Arc<Mutex<Log>>,
}

impl LabelRule<D3> for Watch {
    fn name(&self) -> &str {
        "watch"
    }

    fn relabel(&mut self, complex: &mut Complex3, state: &IterationState<'_, '_>) -> usize {
        // labels before the rule (Label::MAX for dead slots)
        let mut before = vec![Label::MAX; complex.cell_capacity()];
        for c in complex.cell_ids() {
            before[c.index()] = complex.label(c);
        }
        // interface cells before the rule
        let mut on_interface = vec![false; before.len()];
        for c in complex.cell_ids() {
            on_interface[c.index()] = complex
                .neighbours(c)
                .iter()
                .flatten()
                .any(|nb| before[nb.index()] != before[c.index()]);
        }
        let n = self.inner.relabel(complex, state);
        if n == 0 {
            return 0;
        }
        let mut log = self.log.lock().unwrap();
        // histogram buckets by voxel count: 0, 1-2, 3-5, 6-10, >10
        let mut by_size = [0usize; 5];
        let (mut iface, mut toward, mut away, mut mixed) = (0, 0, 0, 0);
        let mut refl = 0;
        let mut vox = Vec::new();
        for c in complex.cell_ids() {
            let i = c.index();
            let b = before.get(i).copied().unwrap_or(Label::MAX);
            if b == Label::MAX || complex.label(c) == b {
                continue;
            }
            let st = state.cells[i];
            let k = match st.count {
                0 => 0,
                1..=2 => 1,
                3..=5 => 2,
                6..=10 => 3,
                _ => 4,
            };
            by_size[k] += 1;
            if on_interface[i] {
                iface += 1;
            }
            vox.clear();
            let pts = complex.cell_points(c);
            D3::cell_pixels(state.image, &pts[..4], &mut |p| vox.push(p));
            // truth label of the new phase: phase with the larger mean is 1
            let m_new = state.phases.mean_of(complex.label(c)).unwrap_or(0.0);
            let m_old = state.phases.mean_of(b).unwrap_or(0.0);
            let new_is_bright = m_new > m_old;
            let bright = vox.iter().filter(|&&p| log.truth[p] == 1).count();
            let frac = if vox.is_empty() {
                0.5
            } else {
                bright as f64 / vox.len() as f64
            };
            let agree = if new_is_bright { frac } else { 1.0 - frac };
            if agree > 0.99 {
                toward += 1;
            } else if agree < 0.01 {
                away += 1;
            } else {
                mixed += 1;
            }
            for &p in &vox {
                if log.voxel_flips[p] > 0 {
                    refl += 1;
                }
                log.voxel_flips[p] += 1;
            }
        }
        eprintln!(
            "  {} at it {}: {n} flips; voxels 0/1-2/3-5/6-10/>10: {:?}; on interface {iface}; \
             toward truth {toward}, away {away}, straddling {mixed}; voxels flipped before {refl}",
            self.inner.name(),
            state.iteration,
            by_size
        );
        n
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let kind = Phantom3Kind::from_name(args.first().map_or("two_balls", |s| s)).unwrap();
    let size: usize = args.get(1).map_or(64, |s| s.parse().unwrap());
    let sigma: f64 = args.get(2).map_or(0.2, |s| s.parse().unwrap());
    let ph = kind.generate(size, sigma, 1);
    let mut params = SegmentParams::new_3d(2);
    if let Some(m) = args.get(3) {
        params.max_iterations = m.parse().unwrap();
    }
    if let Ok(k) = std::env::var("FLIP_ONCE") {
        params.flip_once = k == "1";
    }
    if let Ok(k) = std::env::var("FLIP_INTERVAL") {
        params.flip_interval = k.parse().unwrap();
    }
    let log = Arc::new(Mutex::new(Log {
        truth: ph.truth.clone(),
        voxel_flips: vec![0; ph.truth.len()],
    }));
    let mut models = Models::<D3>::paper(&params);
    models.rules = std::mem::take(&mut models.rules)
        .into_iter()
        .map(|inner| {
            Box::new(Watch {
                inner,
                log: log.clone(),
            }) as Box<dyn LabelRule<D3>>
        })
        .collect();
    let view = ImageView::new_3d([ph.nx, ph.ny, ph.nz], &ph.image).unwrap();
    let mut seg = Segmentation::with_models(view, params, models).unwrap();
    let t0 = std::time::Instant::now();
    let rep = seg.run_until(|s, r| {
        // the two parts of the displacement, in units of L, as the driver scales them
        let Some(field) = s.paper_field() else {
            return dsc_seg::segment::Flow::Stop;
        };
        let f = field.field();
        let l = s.dsc_params().edge_length;
        let norm = |v: &[nalgebra::Vector3<f64>]| v.iter().map(|x| x.norm()).fold(0.0, f64::max);
        let fmax = norm(&f.external);
        let scale = s.step_fraction() * l / fmax.max(1.0);
        let k = (scale * s.params().rigidity / l).min(0.2);
        eprintln!(
            "it {} E {:.3} data {:.3} area {:.1} flips {} disp {:.4} (external {:.4}, bending {:.4}, step {:.4})",
            r.iteration,
            r.energy,
            r.data_energy,
            r.length,
            r.flips,
            r.max_displacement,
            fmax * scale / l,
            norm(&f.bending) * k / l,
            s.step_fraction()
        );
        if s.converged() {
            dsc_seg::segment::Flow::Stop
        } else {
            dsc_seg::segment::Flow::Continue
        }
    });
    let dice = mean_dice(&seg.label_image(), &ph.truth, 2);
    let log = log.lock().unwrap();
    let mut hist = [0usize; 6];
    for &f in &log.voxel_flips {
        hist[(f as usize).min(5)] += 1;
    }
    println!(
        "{} {size}³ σ {sigma}: Dice {dice:.4}, {} iterations, converged {}, {} tets, {:.1} s; \
         voxels flipped 0/1/2/3/4/5+ times: {:?}",
        kind.name(),
        rep.iterations,
        rep.converged,
        rep.cells,
        t0.elapsed().as_secs_f64(),
        hist
    );
}
