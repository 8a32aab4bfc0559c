//! Label flips: cells that fit another phase better change label.
//!
//! Two phases: a cell flips when its mean is closer to the other phase's mean
//! (the paper's rule). More phases: every pixel of the cell votes for the
//! phase with the nearest mean and the cell takes the dominant phase (the
//! paper's rule, robust to cells that straddle a boundary).
//!
//! With the guard on (the default) the rules propose and the piecewise-constant
//! Mumford–Shah energy decides: a cell is relabelled to the rule's candidate or
//! to a neighbouring cell's phase only if that lowers `Σ(I − m)² + ν·length`
//! (exactly computable from the cell's sums), visiting the cells one after the
//! other (an ICM sweep, which cannot raise the energy or oscillate). Under
//! noise the bare rules turn every noisy cell into a speck of another phase;
//! the guard removes such specks instead. With the guard off the paper's rules
//! apply unchanged.

use super::image::ImageView;
use super::integrate::{CellStats, PhaseStats};
use super::raster::Raster;
use crate::complex::{CellId, Complex, Label};
use rayon::prelude::*;

/// Scratch space of the flip step, kept between iterations.
#[derive(Clone, Debug, Default)]
pub struct Flipper {
    /// Pixel-dominant phase per cell (multiphase rule), `None` for no pixels.
    dominant: Vec<Option<Label>>,
    /// Per cell: whether the component walk has reached it.
    seen: Vec<bool>,
    stack: Vec<CellId>,
    members: Vec<CellId>,
    /// Per neighbouring label of the current component: shared interface measure.
    shared: Vec<(Label, f64)>,
    changes: Vec<(CellId, Label)>,
    /// Per pixel: whether a cell flip has relabelled it (see `once` of [`Flipper::flip`]).
    flipped: Vec<bool>,
    /// Scratch: the pixels of the cell being decided.
    pixels: Vec<usize>,
    /// Scratch: the known phase means, with their labels.
    order: Vec<(f64, Label)>,
}

impl Flipper {
    /// Empty scratch space.
    pub fn new() -> Self {
        Self::default()
    }

    /// Decides and applies the flips; returns how many cells changed label.
    ///
    /// `nu` is the length weight of the energy (intensity² per unit length);
    /// with `guard` off the paper's rules apply unchanged, with it on a flip
    /// must also lower `data + nu·length` (evaluated with the labels as they
    /// are when the cell is visited, so the sweep never raises the energy).
    ///
    /// With `once`, every pixel is relabelled by a cell flip at most once per
    /// run: a cell whose pixels have been flipped before (half of them or more)
    /// keeps its label, and its boundary is left to the interface motion. Under
    /// strong noise the cells along an interface hold one or two pixels each,
    /// whose means fall on the wrong side often enough that every flip round
    /// relabels some of them, mostly away from the true boundary; the
    /// rigidity then smooths the bump back and the next round flips it again,
    /// so the run never settles (3D, σ = 0.2). Remembering the pixels, which outlive the
    /// remeshed cells, breaks that cycle; cells over pixels no flip has touched
    /// (new regions, specks) flip as before.
    #[allow(clippy::too_many_arguments)]
    pub fn flip<K: Raster>(
        &mut self,
        complex: &mut Complex<K>,
        image: &ImageView<'_>,
        cells: &[CellStats],
        phases: &PhaseStats,
        nu: f64,
        guard: bool,
        once: bool,
    ) -> usize {
        let rule = FlipRule::new(image, cells, phases, nu, guard);
        match self.prepare(complex, rule) {
            Some(rule) => self.sweep_from(complex, &rule, once, 0),
            None => 0,
        }
    }

    /// [`flip`](Self::flip) with these arguments right after
    /// [`first_flip`](Self::first_flip) answered `first` on the same state
    /// (the labels, cell statistics and means unchanged, and no other call
    /// of this `Flipper` between): the same flips, the sweep starting at
    /// `first` (no cell before it flips, as none has flipped before it) and
    /// reading the means' order and the pixel-dominant phases that
    /// `first_flip` prepared; nothing to do where `first` is `None`.
    #[allow(clippy::too_many_arguments)]
    pub fn flip_after_first<K: Raster>(
        &mut self,
        complex: &mut Complex<K>,
        image: &ImageView<'_>,
        cells: &[CellStats],
        phases: &PhaseStats,
        nu: f64,
        guard: bool,
        once: bool,
        first: Option<u32>,
    ) -> usize {
        let Some(first) = first else { return 0 };
        let rule = FlipRule::new(image, cells, phases, nu, guard);
        self.sweep_from(complex, &rule, once, first)
    }

    /// The sweep of [`flip`](Self::flip) over the cells from id `start` on
    /// (after [`prepare`](Self::prepare)); returns how many changed label.
    fn sweep_from<K: Raster>(
        &mut self,
        complex: &mut Complex<K>,
        rule: &FlipRule<'_, '_>,
        once: bool,
        start: u32,
    ) -> usize {
        let image = rule.image;
        if once && self.flipped.len() != image.len() {
            self.flipped.clear();
            self.flipped.resize(image.len(), false);
        }
        let mut flips = 0;
        for i in start..complex.cell_capacity() as u32 {
            let c = CellId::new(i);
            let Some(t) = self.target(complex, rule, c) else {
                continue;
            };
            if once {
                if !self.first_flip_of_pixels(complex, image, c) {
                    continue;
                }
                for &p in &self.pixels {
                    self.flipped[p] = true;
                }
            }
            complex.set_label(c, t);
            flips += 1;
        }
        flips
    }

    /// Whether [`flip`](Self::flip) with these arguments would relabel a
    /// cell, decided without changing any label: the sweep up to its first
    /// flip (before it, every cell sees the labels as they are now).
    #[allow(clippy::too_many_arguments)]
    pub fn would_flip<K: Raster>(
        &mut self,
        complex: &Complex<K>,
        image: &ImageView<'_>,
        cells: &[CellStats],
        phases: &PhaseStats,
        nu: f64,
        guard: bool,
        once: bool,
    ) -> bool {
        self.first_flip(complex, image, cells, phases, nu, guard, once)
            .is_some()
    }

    /// The id of the first cell [`flip`](Self::flip) with these arguments
    /// would relabel, decided without changing any label (the sweep up to
    /// its first flip, before which every cell sees the labels as they are
    /// now); `None` where it would relabel none.
    #[allow(clippy::too_many_arguments)]
    pub fn first_flip<K: Raster>(
        &mut self,
        complex: &Complex<K>,
        image: &ImageView<'_>,
        cells: &[CellStats],
        phases: &PhaseStats,
        nu: f64,
        guard: bool,
        once: bool,
    ) -> Option<u32> {
        let rule = self.prepare(complex, FlipRule::new(image, cells, phases, nu, guard))?;
        (0..complex.cell_capacity() as u32).find(|&i| {
            let c = CellId::new(i);
            self.target(complex, &rule, c).is_some()
                && (!once || self.first_flip_of_pixels(complex, image, c))
        })
    }

    /// Orders the known means and, for more than two phases, finds each
    /// cell's pixel-dominant phase; gives the rule back, or `None` if fewer
    /// than two means are known (nothing can flip).
    fn prepare<'r, 'a, K: Raster>(
        &mut self,
        complex: &Complex<K>,
        rule: FlipRule<'r, 'a>,
    ) -> Option<FlipRule<'r, 'a>> {
        self.order.clear();
        for (k, m) in rule.phases.mean.iter().enumerate() {
            if let Some(m) = *m {
                self.order.push((m, k as Label));
            }
        }
        if self.order.len() < 2 {
            return None;
        }
        self.dominant.clear();
        self.dominant.resize(complex.cell_capacity(), None);
        if rule.phases.mean.len() > 2 {
            let (order, image, cells) = (&self.order, rule.image, rule.cells);
            self.dominant.par_iter_mut().enumerate().for_each(|(i, w)| {
                let c = CellId::new(i as u32);
                if !complex.is_alive(c) || cells[i].count == 0 {
                    return;
                }
                let mut votes = [0u32; 64];
                let pts = complex.cell_points(c);
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
                let own = complex.label(c);
                let vown = order
                    .iter()
                    .position(|&(_, l)| l == own)
                    .map_or(0, |k| votes[k]);
                let (kbest, &vbest) = votes[..order.len()]
                    .iter()
                    .enumerate()
                    .max_by_key(|&(_, v)| *v)
                    .expect("at least two known phases");
                if vbest > vown {
                    *w = Some(order[kbest].1);
                }
            });
        }
        Some(rule)
    }

    /// The label cell `c` flips to, given the labels as they are now (after
    /// [`prepare`](Self::prepare)). Inlined into the sweeps: most cells lie
    /// inside a phase, with no candidate, and are decided here at the cost of
    /// a few loads; the others go to [`judge`](Self::judge).
    #[inline(always)]
    fn target<K: Raster>(
        &self,
        complex: &Complex<K>,
        rule: &FlipRule<'_, '_>,
        c: CellId,
    ) -> Option<Label> {
        if !complex.is_alive(c) {
            return None;
        }
        let phases = rule.phases;
        let st = &rule.cells[c.index()];
        let mt = st.mean()?;
        let own = complex.label(c);
        let m_own = phases.mean_of(own)?;
        let candidate = if phases.mean.len() == 2 {
            let other = 1 - own.min(1);
            match phases.mean_of(other) {
                Some(m_other) if (mt - m_other).abs() < (mt - m_own).abs() => Some(other),
                _ => None,
            }
        } else {
            self.dominant[c.index()]
        };
        if !rule.guard {
            return candidate;
        }
        // Nothing to consider (most cells: inside a phase, no candidate).
        // (a live cell of label `own`: its interface bit tells whether a
        // neighbour has another label)
        if candidate.is_none() && !complex.meets_other_label(c) {
            return None;
        }
        Self::judge(complex, rule, c, own, m_own, candidate)
    }

    /// The guard's decision for cell `c` of label `own` (phase mean
    /// `m_own`): the rule's `candidate` or a neighbouring cell's phase,
    /// whichever lowers the energy most, if any does.
    #[inline(never)]
    fn judge<K: Raster>(
        complex: &Complex<K>,
        rule: &FlipRule<'_, '_>,
        c: CellId,
        own: Label,
        m_own: f64,
        candidate: Option<Label>,
    ) -> Option<Label> {
        let st = rule.cells[c.index()];
        let base = st.sse(m_own);
        let sides = CellSides::of(complex, c);
        let mut best: Option<(f64, Label)> = None;
        let mut consider = |l: Label| {
            if l == own {
                return;
            }
            let Some(m) = rule.phases.mean_of(l) else {
                return;
            };
            let de = st.sse(m) - base + rule.nu * sides.added_length(own, l);
            if de < 0.0 && best.is_none_or(|(b, _)| de < b) {
                best = Some((de, l));
            }
        };
        if let Some(t) = candidate {
            consider(t);
        }
        // (tested here first: most cells are inside a phase)
        for l in sides.labels[..K::NV].iter().flatten() {
            if *l != own {
                consider(*l);
            }
        }
        best.map(|(_, l)| l)
    }

    /// With `once`: whether fewer than half of `c`'s pixels (listed in
    /// `pixels`) have been relabelled by a cell flip before.
    fn first_flip_of_pixels<K: Raster>(
        &mut self,
        complex: &Complex<K>,
        image: &ImageView<'_>,
        c: CellId,
    ) -> bool {
        self.pixels.clear();
        let pts = complex.cell_points(c);
        K::cell_pixels(image, &pts[..K::NV], &mut |p| self.pixels.push(p));
        // (before the first flip of a run nothing was flipped: no record yet)
        let seen = self
            .pixels
            .iter()
            .filter(|&&p| self.flipped.get(p).is_some_and(|&f| f))
            .count();
        2 * seen < self.pixels.len()
    }
}

/// The inputs of one cell-flip sweep.
struct FlipRule<'r, 'a> {
    image: &'r ImageView<'a>,
    cells: &'r [CellStats],
    phases: &'r PhaseStats,
    nu: f64,
    guard: bool,
}

impl<'r, 'a> FlipRule<'r, 'a> {
    fn new(
        image: &'r ImageView<'a>,
        cells: &'r [CellStats],
        phases: &'r PhaseStats,
        nu: f64,
        guard: bool,
    ) -> Self {
        FlipRule {
            image,
            cells,
            phases,
            nu,
            guard,
        }
    }
}

impl Flipper {
    /// Component flips: every connected same-phase region is relabelled as a
    /// whole to the neighbouring phase that lowers `data + ν·length` most, if
    /// any does. This removes what single-cell flips cannot: thin bands of an
    /// intermediate phase along blurred edges between two other phases (each
    /// band cell alone changes no length) and specks of a few cells. Returns
    /// the number of cells relabelled.
    pub fn component_flips<K: Raster>(
        &mut self,
        complex: &mut Complex<K>,
        cells: &[CellStats],
        phases: &PhaseStats,
        nu: f64,
    ) -> usize {
        self.component_changes(complex, cells, phases, nu);
        if !self.changes.is_empty() {
            complex.set_labels(&self.changes);
        }
        self.changes.len()
    }

    /// [`component_flips`](Self::component_flips) right after
    /// [`would_flip_components`](Self::would_flip_components) on the same
    /// state (the labels, cell statistics and means unchanged, and no other
    /// call of this `Flipper` between): applies the relabelling that call
    /// listed instead of finding it again.
    pub fn component_flips_listed<K: Raster>(&mut self, complex: &mut Complex<K>) -> usize {
        if !self.changes.is_empty() {
            complex.set_labels(&self.changes);
        }
        self.changes.len()
    }

    /// Whether [`component_flips`](Self::component_flips) would relabel a
    /// cell; changes no label.
    pub fn would_flip_components<K: Raster>(
        &mut self,
        complex: &Complex<K>,
        cells: &[CellStats],
        phases: &PhaseStats,
        nu: f64,
    ) -> bool {
        self.component_changes(complex, cells, phases, nu);
        !self.changes.is_empty()
    }

    /// Lists in `changes` the relabelling of [`component_flips`](Self::component_flips)
    /// (every decision is made on the labels as they are now).
    fn component_changes<K: Raster>(
        &mut self,
        complex: &Complex<K>,
        cells: &[CellStats],
        phases: &PhaseStats,
        nu: f64,
    ) {
        self.changes.clear();
        if nu <= 0.0 {
            return;
        }
        let cap = complex.cell_capacity();
        self.seen.clear();
        self.seen.resize(cap, false);
        let (mut stack, mut members) = (
            std::mem::take(&mut self.stack),
            std::mem::take(&mut self.members),
        );
        stack.clear();
        members.clear();
        stack.reserve(cap);
        members.reserve(cap);
        for i in 0..cap as u32 {
            let start = CellId::new(i);
            if self.seen[i as usize] || !complex.is_alive(start) {
                continue;
            }
            let own = complex.label(start);
            self.seen[i as usize] = true;
            stack.clear();
            members.clear();
            self.shared.clear();
            stack.push(start);
            let mut acc = CellStats::default();
            while let Some(c) = stack.pop() {
                members.push(c);
                let st = &cells[c.index()];
                acc.sum += st.sum;
                acc.sum_sq += st.sum_sq;
                acc.count += st.count;
                // Corners only for the cells on the component's border.
                let mut pts = None;
                for (f, nb) in complex.neighbours(c).iter().enumerate() {
                    let Some(nb) = *nb else { continue };
                    let l = complex.label(nb);
                    if l == own {
                        if !self.seen[nb.index()] {
                            self.seen[nb.index()] = true;
                            stack.push(nb);
                        }
                    } else {
                        let pts = pts.get_or_insert_with(|| complex.cell_points(c));
                        let m = K::facet_measure(&pts[..K::NV], f);
                        match self.shared.iter_mut().find(|(x, _)| *x == l) {
                            Some(e) => e.1 += m,
                            None => self.shared.push((l, m)),
                        }
                    }
                }
            }
            let Some(m_own) = phases.mean_of(own) else {
                continue;
            };
            let base = acc.sse(m_own);
            let mut best: Option<(f64, Label)> = None;
            for &(l, len) in &self.shared {
                let Some(m) = phases.mean_of(l) else { continue };
                let de = acc.sse(m) - base - nu * len;
                if de < 0.0 && best.is_none_or(|(b, _)| de < b) {
                    best = Some((de, l));
                }
            }
            if let Some((_, l)) = best {
                self.changes.extend(members.iter().map(|&c| (c, l)));
            }
        }
        (self.stack, self.members) = (stack, members);
    }
}

/// The sides of one cell as the guard weighs them: per local index, the
/// label of the neighbour across the facet opposite it (`None` on the domain
/// border) and that facet's measure. Taken once per judged cell: every
/// label the guard considers reads the same facets.
struct CellSides {
    labels: [Option<Label>; 4],
    measures: [f64; 4],
}

impl CellSides {
    /// The sides of cell `c` of `cx`.
    fn of<K: Raster>(cx: &Complex<K>, c: CellId) -> Self {
        let pts = cx.cell_points(c);
        let mut sides = CellSides {
            labels: [None; 4],
            measures: [0.0; 4],
        };
        for (i, nb) in cx.neighbours(c).iter().enumerate() {
            if let Some(nb) = *nb {
                sides.labels[i] = Some(cx.label(nb));
                sides.measures[i] = K::facet_measure(&pts[..K::NV], i);
            }
        }
        sides
    }

    /// Interface length/area that relabelling the cell from `own` to `new`
    /// adds (negative if it removes more than it adds), ignoring
    /// simultaneous flips.
    fn added_length(&self, own: Label, new: Label) -> f64 {
        let mut d = 0.0;
        for (l, m) in self.labels.iter().zip(&self.measures) {
            match *l {
                Some(l) if l == own => d += m,
                Some(l) if l == new => d -= m,
                _ => {}
            }
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::D2;
    use crate::segment::integrate::integrate_cells;
    use nalgebra::Vector2;

    /// The predictions answer whether the sweeps change a label: a bright
    /// disk labelled right (no flip), with a dark speck labelled like the
    /// disk (its cells, and then the speck as a component, flip).
    #[test]
    fn predictions_answer_whether_the_sweeps_flip() {
        let (w, h) = (64usize, 64usize);
        let centre = Vector2::new(32.0, 32.0);
        let pixels: Vec<f32> = (0..w * h)
            .map(|i| {
                let p = Vector2::new((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
                if (p - centre).norm() < 18.0 {
                    0.8
                } else {
                    0.2
                }
            })
            .collect();
        let image = ImageView::new_2d(w, h, &pixels).unwrap();
        for speck in [0.0, 4.0] {
            let mut mesh = Complex::<D2>::rectangle(w as f64, h as f64, 3.0).unwrap();
            let inner = Vector2::new(52.0, 10.0);
            mesh.label_by(|p| u32::from((p - centre).norm() < 18.0 || (p - inner).norm() < speck));
            let mut cells = Vec::new();
            integrate_cells(&mesh, &image, &mut cells);
            let mut phases = PhaseStats::new(2);
            phases.update(&mesh, &cells);
            for guard in [false, true] {
                let mut flipper = Flipper::new();
                let would = flipper.would_flip(&mesh, &image, &cells, &phases, 0.05, guard, false);
                let flipped = flipper.flip(
                    &mut mesh.clone(),
                    &image,
                    &cells,
                    &phases,
                    0.05,
                    guard,
                    false,
                );
                assert_eq!(would, flipped > 0, "speck {speck}, guard {guard}");
            }
            let would = Flipper::new().would_flip_components(&mesh, &cells, &phases, 0.05);
            let flipped = Flipper::new().component_flips(&mut mesh.clone(), &cells, &phases, 0.05);
            assert_eq!(would, flipped > 0, "speck {speck}: components");
            assert_eq!(
                flipped > 0,
                speck > 0.0,
                "speck {speck}: the test's premise"
            );
        }
    }
}
