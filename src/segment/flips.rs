//! Label flips: cells that fit another phase better change label.
//!
//! Two phases: a cell flips when its mean is closer to the other phase's mean
//! (the paper's rule). More phases: every pixel of the cell votes for the
//! phase with the nearest mean and the cell takes the dominant phase (the
//! paper's rule, robust to cells that straddle a boundary).
//!
//! Both rules are guarded by the Mumford–Shah length term: a flip must lower
//! the data term by more than `ν ×` the interface length it adds (for the
//! pixel-vote rule the data term is counted in votes × gap²), so a lone noisy
//! cell does not turn into a speck of another phase. With `ν = 0` the rules
//! are exactly the paper's.

use super::image::ImageView;
use super::integrate::{CellStats, PhaseStats};
use super::raster::Raster;
use crate::complex::{CellId, Complex, Label};
use rayon::prelude::*;

/// Scratch space of the flip step, kept between iterations.
#[derive(Clone, Debug, Default)]
pub struct Flipper {
    wanted: Vec<Option<Label>>,
    changes: Vec<(CellId, Label)>,
}

impl Flipper {
    /// Empty scratch space.
    pub fn new() -> Self {
        Self::default()
    }

    /// Decides and applies the flips; returns how many cells changed label.
    /// `nu` is the length weight of the energy (intensity² per unit length).
    pub fn flip<K: Raster>(
        &mut self,
        complex: &mut Complex<K>,
        image: &ImageView<'_>,
        cells: &[CellStats],
        phases: &PhaseStats,
        nu: f64,
    ) -> usize {
        let n = phases.mean.len();
        let cx: &Complex<K> = complex;
        self.wanted.clear();
        self.wanted.resize(cx.cell_capacity(), None);
        // sorted known means, for the per-pixel nearest-mean vote
        let mut order: [(f64, Label); 64] = [(0.0, 0); 64];
        let mut known = 0;
        for (k, m) in phases.mean.iter().enumerate() {
            if let Some(m) = *m {
                order[known] = (m, k as Label);
                known += 1;
            }
        }
        if known < 2 {
            return 0;
        }
        let order = &order[..known];
        self.wanted.par_iter_mut().enumerate().for_each(|(i, w)| {
            let c = CellId(i as u32);
            if !cx.is_alive(c) {
                return;
            }
            let st = cells[i];
            let Some(mt) = st.mean() else { return };
            let own = cx.label(c);
            let Some(m_own) = phases.mean_of(own) else {
                return;
            };
            let target = if n == 2 {
                let other = 1 - own.min(1);
                let Some(m_other) = phases.mean_of(other) else {
                    return;
                };
                if (mt - m_other).abs() >= (mt - m_own).abs() {
                    return;
                }
                let gain = st.sse(m_own) - st.sse(m_other);
                (gain > nu * added_length(cx, c, own, other)).then_some(other)
            } else {
                let mut votes = [0u32; 64];
                let pts = cx.cell_points(c);
                K::cell_pixels(image, &pts[..K::NV], &mut |p| {
                    let v = image.data[p] as f64;
                    let mut best = 0;
                    let mut bd = f64::INFINITY;
                    for (k, &(m, _)) in order.iter().enumerate() {
                        let d = (v - m).abs();
                        if d < bd {
                            bd = d;
                            best = k;
                        }
                    }
                    votes[best] += 1;
                });
                let (kbest, &vbest) = votes[..known]
                    .iter()
                    .enumerate()
                    .max_by_key(|&(_, v)| *v)
                    .expect("at least two known phases");
                let (m_new, new) = order[kbest];
                if new == own {
                    return;
                }
                let vown = order
                    .iter()
                    .position(|&(_, l)| l == own)
                    .map_or(0, |k| votes[k]);
                if vbest <= vown {
                    return;
                }
                let gap2 = (m_new - m_own) * (m_new - m_own);
                let gain = (vbest - vown) as f64 * gap2;
                (gain > nu * added_length(cx, c, own, new)).then_some(new)
            };
            *w = target;
        });
        self.changes.clear();
        for (i, w) in self.wanted.iter().enumerate() {
            if let Some(l) = *w {
                self.changes.push((CellId(i as u32), l));
            }
        }
        if !self.changes.is_empty() {
            complex.set_labels(&self.changes);
        }
        self.changes.len()
    }
}

/// Interface length/area that relabelling `c` from `own` to `new` adds
/// (negative if it removes more than it adds), ignoring simultaneous flips.
fn added_length<K: Raster>(cx: &Complex<K>, c: CellId, own: Label, new: Label) -> f64 {
    let pts = cx.cell_points(c);
    let mut d = 0.0;
    for (i, nb) in cx.neighbours(c).iter().enumerate() {
        let Some(nb) = *nb else { continue };
        let l = cx.label(nb);
        if l == own {
            d += K::facet_measure(&pts[..K::NV], i);
        } else if l == new {
            d -= K::facet_measure(&pts[..K::NV], i);
        }
    }
    d
}
