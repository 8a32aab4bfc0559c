//! Forces on interface vertices: the region forces of eqs. (5)–(7) integrated
//! along interface facets, and the rigidity (and optional elasticity) term of
//! eq. (2) traced along each phase boundary.
//!
//! For every interface facet between phases `i` (the cell) and `j` (its
//! neighbour) the image is sampled about every pixel; each sample's force
//! `f(I)·N_ij` (`N_ij` the facet's unit normal pointing from `i` into `j`) is
//! distributed to the facet's corners with the hat (barycentric) weights, and
//! each vertex's total is divided by its share of the facet measure, so the
//! result is a force per unit length/area: the hat-weighted average of `f`.
//!
//! Junctions ([`VertexKind::Junction`]) get the external force of eq. (7) only
//! when every phase around them occurs once (a triple junction); a crossing
//! where a phase occurs twice gets none and is resolved by its neighbours.
//! Eq. (7) is integrated over the junction's adjacent edges with the same hat
//! weights as the edge forces (a single sample at the junction point is very
//! noisy), either as the paper states it or per edge
//! ([`JunctionForce`]).

use super::image::ImageView;
use super::integrate::PhaseStats;
use super::params::{ForceModel, JunctionForce};
use super::raster::Raster;
use crate::complex::{CellId, Complex, InterfaceFacet, Label, VertexId, VertexKind};
use crate::dim::{Dim, Point};

/// Most phases tracked around one vertex; further ones are ignored.
const MAXP: usize = 6;

/// What a vertex is for the forces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ForceKind {
    /// Not on the interface: no force.
    #[default]
    Off,
    /// Between exactly two phases: eq. (6) (or eq. (5)).
    Interface,
    /// A junction where every surrounding region is a distinct phase: eq. (7).
    TripleJunction,
    /// A junction where some phase occurs twice: no external force.
    Crossing,
}

#[derive(Clone, Copy, Debug)]
struct Acc<P> {
    np: usize,
    phases: [Label; MAXP],
    /// Summed outward normals of each phase (junctions).
    normal: [P; MAXP],
    /// Eq. (7) weights of each phase, integrated with the hat weights.
    weight: [f64; MAXP],
    /// Number of boundary neighbours per phase (the umbrella's denominators).
    ncnt: [f64; MAXP],
    ext: P,
    share: f64,
}

impl<P: Point> Acc<P> {
    /// Empties the accumulator. The per-slot arrays are only read below
    /// `np` and are zeroed when a slot opens, so they are left as they are
    /// (every interface vertex is reset every iteration).
    fn reset(&mut self) {
        self.np = 0;
        self.ext = P::zero();
        self.share = 0.0;
    }
    fn slot_of(&self, l: Label) -> Option<usize> {
        self.phases[..self.np].iter().position(|&p| p == l)
    }
    fn slot(&mut self, l: Label) -> Option<usize> {
        if let Some(s) = self.slot_of(l) {
            return Some(s);
        }
        if self.np < MAXP {
            self.phases[self.np] = l;
            self.normal[self.np] = P::zero();
            self.weight[self.np] = 0.0;
            self.ncnt[self.np] = 0.0;
            self.np += 1;
            Some(self.np - 1)
        } else {
            None
        }
    }
}

/// One interface facet, kept between the passes.
#[derive(Clone, Copy, Debug)]
struct Facet {
    corners: [VertexId; 3],
    a: Label,
    b: Label,
    /// Per corner, its accumulator's slots of `a` and `b` (filled once the
    /// slots are final, for the boundary Laplacian).
    slots: [[Option<u8>; 2]; 3],
}

/// The force model and sampling.
#[derive(Clone, Copy, Debug)]
pub struct ForceSettings {
    /// Region force model.
    pub model: ForceModel,
    /// Triple-junction force (eq. 7 as the paper states it, or per edge).
    pub junction: JunctionForce,
    /// Sample spacing along facets, in samples (pixels/voxels; scaled by the
    /// image's sample step, so the work does not depend on the length unit).
    pub spacing: f64,
    /// Mean gaps below this count as equal means: no region force across them.
    pub equal_means: f64,
}

/// Per-vertex forces, with all scratch space kept between iterations.
#[derive(Clone, Debug, Default)]
pub struct ForceField<K: Dim> {
    /// Per vertex id: what it is for the forces.
    kinds: Vec<ForceKind>,
    /// Per vertex id: sums of the interface vertices (valid where `kinds` is not `Off`).
    acc: Vec<Acc<K::Point>>,
    /// External (region) force per vertex id, dimensionless for eq. (6).
    pub external: Vec<K::Point>,
    /// Bending term `−Δ(ΔX)` per vertex id (pixels), the direction of the
    /// rigidity force before its weight.
    pub bending: Vec<K::Point>,
    /// Umbrella `ΔX` per vertex id (pixels), the direction of the elasticity force.
    pub stretching: Vec<K::Point>,
    facets: Vec<Facet>,
    /// Vertices the boundary Laplacian acts on (on the interface, off the border).
    active: Vec<u32>,
    /// Per-vertex, per-phase neighbour sums of the boundary Laplacian.
    slot_sums: Vec<[K::Point; MAXP]>,
    scratch: Vec<K::Point>,
    star: Vec<CellId>,
    piece: Vec<usize>,
    stack: Vec<usize>,
    labels: Vec<Label>,
    /// Total measure of the interface (length in 2D), from the last computation.
    pub interface_measure: f64,
    /// Number of triple junctions and crossings seen in the last computation.
    pub junctions: (usize, usize),
}

impl<K: Raster> ForceField<K> {
    /// Empty scratch space.
    pub fn new() -> Self {
        ForceField {
            kinds: Vec::new(),
            acc: Vec::new(),
            external: Vec::new(),
            bending: Vec::new(),
            stretching: Vec::new(),
            facets: Vec::new(),
            active: Vec::new(),
            slot_sums: Vec::new(),
            scratch: Vec::new(),
            star: Vec::new(),
            piece: Vec::new(),
            stack: Vec::new(),
            labels: Vec::new(),
            interface_measure: 0.0,
            junctions: (0, 0),
        }
    }

    /// The force kind of `v` from the last computation.
    pub fn kind(&self, v: VertexId) -> ForceKind {
        self.kinds.get(v.index()).copied().unwrap_or(ForceKind::Off)
    }

    /// Pieces and distinct labels around `v` with the reusable buffers.
    fn classify(&mut self, complex: &Complex<K>, v: VertexId) -> ForceKind {
        let class = complex.class(v);
        match class.kind {
            VertexKind::Interior => return ForceKind::Off,
            // 3D: a two-piece star can still sit on an edge with more than two
            // interface triangles (two sheets of a phase touching): a crossing.
            VertexKind::Interface if complex.has_junction_edge_with(v, &mut self.star) => {
                return ForceKind::Crossing
            }
            VertexKind::Interface => return ForceKind::Interface,
            VertexKind::Junction => {}
        }
        complex.star_into(v, &mut self.star);
        self.piece.clear();
        self.piece.resize(self.star.len(), usize::MAX);
        let mut pieces = 0;
        for start in 0..self.star.len() {
            if self.piece[start] != usize::MAX {
                continue;
            }
            self.piece[start] = pieces;
            self.stack.clear();
            self.stack.push(start);
            while let Some(i) = self.stack.pop() {
                let c = self.star[i];
                let label = complex.label(c);
                for (local, nb) in complex.neighbours(c).iter().enumerate() {
                    let Some(nb) = *nb else { continue };
                    if complex.cell(c)[local] == v || complex.label(nb) != label {
                        continue;
                    }
                    if let Some(j) = self.star.iter().position(|&s| s == nb) {
                        if self.piece[j] == usize::MAX {
                            self.piece[j] = pieces;
                            self.stack.push(j);
                        }
                    }
                }
            }
            pieces += 1;
        }
        self.labels.clear();
        self.labels
            .extend(self.star.iter().map(|&c| complex.label(c)));
        self.labels.sort_unstable();
        self.labels.dedup();
        if pieces == self.labels.len() && pieces <= MAXP {
            ForceKind::TripleJunction
        } else {
            ForceKind::Crossing
        }
    }

    /// Computes the external, bending and stretching terms of every vertex of
    /// `complex`, in four stages: what each vertex is, the facets' region
    /// force and boundary neighbours, the smoothing directions, and each
    /// vertex's external force.
    pub fn compute(
        &mut self,
        complex: &Complex<K>,
        image: &ImageView<'_>,
        phases: &PhaseStats,
        s: &ForceSettings,
    ) {
        #[cfg(test)]
        tests::COMPUTATIONS.with(|c| c.set(c.get() + 1));
        self.classify_vertices(complex);
        self.integrate_facets(complex, image, phases, s);
        self.smoothing_directions(complex);
        self.resolve_external(s.junction);
    }

    /// Stage 1: every vertex's [`ForceKind`]; the accumulators of the
    /// interface vertices reset (junction slots in increasing label order,
    /// for eq. 7) and the output arrays zeroed.
    fn classify_vertices(&mut self, complex: &Complex<K>) {
        let nv = complex.vertex_capacity();
        let empty = Acc {
            np: 0,
            phases: [0; MAXP],
            normal: [K::Point::zero(); MAXP],
            weight: [0.0; MAXP],
            ncnt: [0.0; MAXP],
            ext: K::Point::zero(),
            share: 0.0,
        };
        self.acc.resize(nv, empty);
        for buf in [&mut self.external, &mut self.bending, &mut self.stretching] {
            buf.clear();
            buf.resize(nv, K::Point::zero());
        }
        self.junctions = (0, 0);
        self.kinds.clear();
        self.kinds.resize(nv, ForceKind::Off);
        for i in 0..nv {
            let v = VertexId(i as u32);
            if !complex.is_vertex_alive(v) {
                continue;
            }
            let kind = self.classify(complex, v);
            self.kinds[i] = kind;
            if kind == ForceKind::Off {
                // Only the interface's accumulators are read: the rest of
                // them (most) are not touched, nor reset.
                continue;
            }
            self.acc[i].reset();
            match kind {
                ForceKind::TripleJunction => {
                    self.junctions.0 += 1;
                    // slots in increasing label order, for eq. (7)
                    for k in 0..self.labels.len() {
                        let l = self.labels[k];
                        self.acc[i].slot(l);
                    }
                }
                ForceKind::Crossing => self.junctions.1 += 1,
                _ => {}
            }
        }
    }

    /// Stage 2, facet by facet along the interface: the interface measure,
    /// the facet's topology at its corners ([`add_facet_topology`](Self::add_facet_topology))
    /// and its region force ([`add_region_force`](Self::add_region_force)).
    fn integrate_facets(
        &mut self,
        complex: &Complex<K>,
        image: &ImageView<'_>,
        phases: &PhaseStats,
        s: &ForceSettings,
    ) {
        self.facets.clear();
        self.interface_measure = 0.0;
        // The sample spacing in the image's unit, once for every facet.
        let spacing = s.spacing * image.sample_step();
        for facet in complex.interface_facets() {
            self.interface_measure += facet.measure;
            self.add_facet_topology(&facet);
            self.add_region_force(&facet, image, phases, s, spacing);
        }
    }

    /// Records `facet` and adds, at its corners, the boundary neighbours of
    /// its two phases and, at triple junctions, its measure-weighted normal
    /// to each phase's outward normal.
    fn add_facet_topology(&mut self, facet: &InterfaceFacet<K::Point>) {
        let nf = K::N; // corners per facet
        let InterfaceFacet {
            a,
            b,
            corners,
            normal,
            measure: meas,
            ..
        } = *facet;
        self.facets.push(Facet {
            corners,
            a,
            b,
            slots: [[None; 2]; 3],
        });
        // neighbours along the boundaries of a and b
        #[allow(clippy::needless_range_loop)] // p, q index two parallel arrays
        for p in 0..nf {
            for q in 0..nf {
                if p == q {
                    continue;
                }
                let acc = &mut self.acc[corners[p].index()];
                for l in [a, b] {
                    if let Some(sl) = acc.slot(l) {
                        acc.ncnt[sl] += 1.0;
                    }
                }
            }
        }
        // outward normals per phase at junctions
        for corner in corners.iter().take(nf) {
            let acc = &mut self.acc[corner.index()];
            if self.kinds[corner.index()] == ForceKind::TripleJunction {
                if let Some(sa) = acc.slot(a) {
                    acc.normal[sa] += normal * meas;
                }
                if let Some(sb) = acc.slot(b) {
                    acc.normal[sb] -= normal * meas;
                }
            }
        }
    }

    /// The region force of eqs. (5)–(7) sampled every `spacing` (in the
    /// image's unit) along `facet` and spread
    /// over its corners with the hat weights: along the normal at two-phase
    /// vertices, as eq. (7) weights (or along the normal, per
    /// [`JunctionForce`]) at triple junctions. Nothing where the two phases'
    /// means are missing or equal.
    #[allow(clippy::needless_range_loop)] // corners and weights are indexed in pairs
    fn add_region_force(
        &mut self,
        facet: &InterfaceFacet<K::Point>,
        image: &ImageView<'_>,
        phases: &PhaseStats,
        s: &ForceSettings,
        spacing: f64,
    ) {
        let nf = K::N; // corners per facet
        let InterfaceFacet {
            a,
            b,
            corners,
            points: cpts,
            normal,
            ..
        } = *facet;
        let (Some(ma), Some(mb)) = (phases.mean_of(a), phases.mean_of(b)) else {
            return;
        };
        let gap = ma - mb;
        if gap.abs() < s.equal_means {
            return; // equal means: eq. (6) undefined, no region force
        }
        let (acc, kinds) = (&mut self.acc, &self.kinds);
        K::facet_samples(&cpts[..nf], spacing, &mut |p, w, ds| {
            let intensity = K::sample(image, p);
            let f = match s.model {
                ForceModel::Normalised => (2.0 * intensity - ma - mb) / gap,
                ForceModel::ChanVese => (2.0 * intensity - ma - mb) * gap,
            };
            for k in 0..nf {
                let wk = w[k] * ds;
                let ac = &mut acc[corners[k].index()];
                match kinds[corners[k].index()] {
                    ForceKind::Interface => {
                        ac.ext += normal * (f * wk);
                        ac.share += wk;
                    }
                    ForceKind::TripleJunction => {
                        ac.share += wk;
                        match s.junction {
                            JunctionForce::Paper => junction_weights(ac, phases, intensity, wk),
                            JunctionForce::EdgeLocal => ac.ext += normal * (f * wk),
                        }
                    }
                    _ => {}
                }
            }
        });
    }

    /// Stage 3: the umbrella `ΔX` and the bending direction `−Δ²X`, the
    /// boundary Laplacian applied once and twice to the positions.
    fn smoothing_directions(&mut self, complex: &Complex<K>) {
        self.fill_facet_slots();
        self.active.clear();
        for (i, &kind) in self.kinds.iter().enumerate() {
            if kind != ForceKind::Off && !complex.class(VertexId(i as u32)).on_boundary() {
                self.active.push(i as u32);
            }
        }
        let mut umbrella = std::mem::take(&mut self.stretching);
        self.boundary_laplacian(|i| complex.position(VertexId(i as u32)), &mut umbrella);
        let mut bending = std::mem::take(&mut self.bending);
        self.boundary_laplacian(|i| umbrella[i], &mut bending);
        for &i in &self.active {
            let i = i as usize;
            bending[i] = if bending[i].is_finite() {
                bending[i] * -1.0
            } else {
                K::Point::zero()
            };
            if !umbrella[i].is_finite() {
                umbrella[i] = K::Point::zero();
            }
        }
        self.stretching = umbrella;
        self.bending = bending;
    }

    /// Stage 4: each interface vertex's external force, its integrated
    /// region force over its share of the interface (eq. 6), or at a triple
    /// junction the eq. (7) weights along the phases' outward normals.
    fn resolve_external(&mut self, junction: JunctionForce) {
        for i in 0..self.kinds.len() {
            let acc = &self.acc[i];
            let mut f = K::Point::zero();
            // (Off first: the other vertices' accumulators are stale)
            match self.kinds[i] {
                ForceKind::Off => continue,
                ForceKind::Interface if acc.share > 0.0 => f += acc.ext * (1.0 / acc.share),
                ForceKind::TripleJunction
                    if acc.share > 0.0 && junction == JunctionForce::EdgeLocal =>
                {
                    f += acc.ext * (1.0 / acc.share)
                }
                ForceKind::TripleJunction if acc.share > 0.0 => {
                    for sl in 0..acc.np {
                        let n = acc.normal[sl];
                        let len = n.length();
                        if len > 0.0 && acc.weight[sl] > 0.0 {
                            f += n * (acc.weight[sl] / (acc.share * len));
                        }
                    }
                }
                _ => {}
            }
            if f.is_finite() {
                self.external[i] = f;
            }
        }
    }

    /// Looks up, once per computation, each facet corner's slots of the
    /// facet's two phases (the Laplacian runs a dozen times per iteration).
    fn fill_facet_slots(&mut self) {
        for f in &mut self.facets {
            for p in 0..K::N {
                let acc = &self.acc[f.corners[p].index()];
                f.slots[p] = [f.a, f.b].map(|l| acc.slot_of(l).map(|sl| sl as u8));
            }
        }
    }

    /// The sector-averaged Laplacian along the phase boundaries of the last
    /// computation, applied to the per-vertex field `input`: at every vertex
    /// off the domain border, the mean over the phases around it of (the
    /// average of `input` over its neighbours along that phase's boundary,
    /// minus its own value). Applied to the positions it is the umbrella `ΔX`
    /// of the elasticity term; applied to the umbrella, minus the bending
    /// direction. Written into `out` at those vertices only.
    fn boundary_laplacian(&mut self, input: impl Fn(usize) -> K::Point, out: &mut [K::Point]) {
        let nf = K::N;
        self.slot_sums
            .resize(self.acc.len(), [K::Point::zero(); MAXP]);
        for f in &self.facets {
            for c in &f.corners[..nf] {
                self.slot_sums[c.index()] = [K::Point::zero(); MAXP];
            }
        }
        for f in &self.facets {
            for p in 0..nf {
                let sums = &mut self.slot_sums[f.corners[p].index()];
                for q in (0..nf).filter(|&q| q != p) {
                    let x = input(f.corners[q].index());
                    for sl in f.slots[p].iter().flatten() {
                        sums[*sl as usize] += x;
                    }
                }
            }
        }
        for &i in &self.active {
            let i = i as usize;
            let (acc, sums, x) = (&self.acc[i], &self.slot_sums[i], input(i));
            let mut lap = K::Point::zero();
            let mut m = 0.0;
            for (&sum, &count) in sums.iter().zip(&acc.ncnt).take(acc.np) {
                if count > 0.0 {
                    lap += sum * (1.0 / count) - x;
                    m += 1.0;
                }
            }
            if m > 0.0 {
                out[i] = lap * (1.0 / m);
            }
        }
    }

    /// The bending operator `X ↦ −Δ²X` of the last computation applied to a
    /// displacement field (`out` is overwritten at the vertices it acts on
    /// and zeroed elsewhere). The bending direction is linear in the
    /// positions, so the driver can take several stable sub-steps of it per
    /// iteration (see [`crate::segment::model::ForceTerm::apply_to`]).
    pub fn apply_bending(&mut self, input: &[K::Point], out: &mut Vec<K::Point>) {
        let mut umbrella = std::mem::take(&mut self.scratch);
        umbrella.clear();
        umbrella.resize(input.len(), K::Point::zero());
        self.boundary_laplacian(|i| input[i], &mut umbrella);
        out.clear();
        out.resize(input.len(), K::Point::zero());
        self.boundary_laplacian(|i| umbrella[i], out);
        for &i in &self.active {
            out[i as usize] = out[i as usize] * -1.0;
        }
        self.scratch = umbrella;
    }

    /// The umbrella operator `X ↦ ΔX` applied to a displacement field, as
    /// [`apply_bending`](Self::apply_bending).
    pub fn apply_umbrella(&mut self, input: &[K::Point], out: &mut Vec<K::Point>) {
        out.clear();
        out.resize(input.len(), K::Point::zero());
        self.boundary_laplacian(|i| input[i], out);
    }
}

/// Eq. (7): of the phases around the junction, the two whose means bracket
/// `intensity` share the weight linearly in `intensity`; below (above) every
/// mean the lowest (highest) phase takes it all.
fn junction_weights<P: Point>(acc: &mut Acc<P>, phases: &PhaseStats, intensity: f64, wk: f64) {
    let mut below: Option<(usize, f64)> = None;
    let mut above: Option<(usize, f64)> = None;
    for sl in 0..acc.np {
        let Some(m) = phases.mean_of(acc.phases[sl]) else {
            continue;
        };
        if m <= intensity {
            if below.is_none_or(|(_, bm)| m > bm) {
                below = Some((sl, m));
            }
        } else if above.is_none_or(|(_, am)| m < am) {
            above = Some((sl, m));
        }
    }
    match (below, above) {
        (Some((lo, mlo)), Some((hi, mhi))) => {
            let t = (intensity - mlo) / (mhi - mlo);
            acc.weight[lo] += (1.0 - t) * wk;
            acc.weight[hi] += t * wk;
        }
        (Some((lo, _)), None) => acc.weight[lo] += wk,
        (None, Some((hi, _))) => acc.weight[hi] += wk,
        (None, None) => {}
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use std::cell::Cell;

    thread_local! {
        /// How many times [`super::ForceField::compute`] ran on this thread.
        pub(crate) static COMPUTATIONS: Cell<usize> = const { Cell::new(0) };
    }

    /// Computations of the paper's field on this thread so far.
    pub(crate) fn computations() -> usize {
        COMPUTATIONS.with(Cell::get)
    }
}
