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
use crate::complex::{
    CellId, Complex, InterfaceFacet, InterfaceFacets, Label, VertexId, VertexKind,
};
use crate::dim::{Dim, Point};
use rayon::prelude::*;

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

/// Marks a vertex without sums in [`ForceField::acc`] (not on the interface).
const NO_ACC: u32 = u32::MAX;

/// The sums of vertex `v` in `acc` (`acc_of` its index there), if it has
/// any.
fn acc_at<'a, P>(acc: &'a mut [Acc<P>], acc_of: &[u32], v: VertexId) -> Option<&'a mut Acc<P>> {
    acc.get_mut(*acc_of.get(v.index())? as usize)
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
    /// Per vertex id: the index in `acc` of an interface vertex's sums
    /// ([`NO_ACC`] where `kinds` is `Off`).
    acc_of: Vec<u32>,
    /// The sums of the interface vertices, in increasing vertex id: only
    /// they have any, so the memory follows the interface, not the mesh.
    acc: Vec<Acc<K::Point>>,
    /// The interface vertices (`kinds` not `Off`), in increasing id: the
    /// vertex of each entry of `acc`, so that the later stages pass over
    /// the interface rather than over every vertex.
    interface: Vec<u32>,
    /// External (region) force per vertex id, dimensionless for eq. (6).
    pub external: Vec<K::Point>,
    /// Bending term `−Δ(ΔX)` per vertex id (pixels), the direction of the
    /// rigidity force before its weight.
    pub bending: Vec<K::Point>,
    /// Umbrella `ΔX` per vertex id (pixels), the direction of the elasticity force.
    pub stretching: Vec<K::Point>,
    facets: Vec<Facet>,
    /// The image samples of the facets, taken ahead on several threads.
    sampled: FacetSamples<K::Point>,
    /// Vertices the boundary Laplacian acts on (on the interface, off the border).
    active: Vec<u32>,
    /// The boundary Laplacian's neighbours ([`BoundaryNeighbours`]).
    neighbours: BoundaryNeighbours,
    scratch: Vec<K::Point>,
    classify: ClassifyScratch,
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
            acc_of: Vec::new(),
            acc: Vec::new(),
            interface: Vec::new(),
            external: Vec::new(),
            bending: Vec::new(),
            stretching: Vec::new(),
            facets: Vec::new(),
            sampled: FacetSamples::default(),
            active: Vec::new(),
            neighbours: BoundaryNeighbours::default(),
            scratch: Vec::new(),
            classify: ClassifyScratch::default(),
            interface_measure: 0.0,
            junctions: (0, 0),
        }
    }

    /// The force kind of `v` from the last computation.
    pub fn kind(&self, v: VertexId) -> ForceKind {
        self.kinds.get(v.index()).copied().unwrap_or(ForceKind::Off)
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

    /// Stage 1: every vertex's [`ForceKind`]; an empty accumulator for each
    /// interface vertex (junction slots in increasing label order, for
    /// eq. 7) and the output arrays zeroed.
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
        self.acc.clear();
        self.interface.clear();
        self.acc_of.clear();
        self.acc_of.resize(nv, NO_ACC);
        for buf in [&mut self.external, &mut self.bending, &mut self.stretching] {
            buf.clear();
            buf.resize(nv, K::Point::zero());
        }
        self.junctions = (0, 0);
        self.kinds.clear();
        self.kinds.resize(nv, ForceKind::Off);
        let classify_into = |sc: &mut ClassifyScratch, (i, kind): (usize, &mut ForceKind)| {
            let v = VertexId(i as u32);
            if complex.is_vertex_alive(v) {
                *kind = classify_vertex(complex, v, sc);
            }
        };
        if K::N == 3 && rayon::current_num_threads() > 1 {
            // (each vertex's kind alone: the same kinds on any number of threads)
            self.kinds
                .par_iter_mut()
                .enumerate()
                .for_each_init(ClassifyScratch::default, classify_into);
        } else {
            let sc = &mut self.classify;
            self.kinds
                .iter_mut()
                .enumerate()
                .for_each(|entry| classify_into(sc, entry));
        }
        for i in 0..nv {
            let kind = self.kinds[i];
            if kind == ForceKind::Off {
                continue;
            }
            self.acc_of[i] = self.acc.len() as u32;
            self.acc.push(empty);
            self.interface.push(i as u32);
            match kind {
                ForceKind::TripleJunction => {
                    self.junctions.0 += 1;
                    // slots in increasing label order, for eq. (7)
                    let labels = self.classify.star_labels(complex, VertexId(i as u32));
                    let acc = self.acc.last_mut().expect("just pushed");
                    for &l in labels {
                        acc.slot(l);
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
        if K::N == 3 && rayon::current_num_threads() > 1 {
            self.integrate_facets_sampled_ahead(complex, image, phases, s, spacing);
            return;
        }
        let mut samples = std::mem::take(&mut self.sampled.samples);
        for facet in complex.interface_facets() {
            self.interface_measure += facet.measure;
            self.add_facet_topology(&facet);
            samples.clear();
            if let Some(means) = region_means(&facet, phases, s) {
                sample_facet::<K>(&facet, image, spacing, &mut samples);
                self.add_region_force(&facet, means, &samples, phases, s);
            }
        }
        self.sampled.samples = samples;
    }

    /// [`integrate_facets`](Self::integrate_facets) with the image sampled
    /// ahead, block by block of facets, on rayon's threads (3D, where the
    /// samples of a large interface are most of the forces' time). The
    /// samples are those the facets take one after the other and they are
    /// added in the same order, so the forces are the same to the bit on any
    /// number of threads.
    fn integrate_facets_sampled_ahead(
        &mut self,
        complex: &Complex<K>,
        image: &ImageView<'_>,
        phases: &PhaseStats,
        s: &ForceSettings,
        spacing: f64,
    ) {
        let mut sampled = std::mem::take(&mut self.sampled);
        let mut listed = complex.interface_facets();
        loop {
            sampled.list_block(&mut listed);
            if sampled.block.is_empty() {
                break;
            }
            sampled.sample_block::<K>(image, phases, s, spacing);
            for (facet, samples) in sampled.block_samples() {
                self.interface_measure += facet.measure;
                self.add_facet_topology(facet);
                if let Some(means) = region_means(facet, phases, s) {
                    self.add_region_force(facet, means, samples, phases, s);
                }
            }
        }
        self.sampled = sampled;
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
                let Some(acc) = acc_at(&mut self.acc, &self.acc_of, corners[p]) else {
                    continue;
                };
                for l in [a, b] {
                    if let Some(sl) = acc.slot(l) {
                        acc.ncnt[sl] += 1.0;
                    }
                }
            }
        }
        // outward normals per phase at junctions
        for corner in corners.iter().take(nf) {
            if self.kinds[corner.index()] == ForceKind::TripleJunction {
                let acc = &mut self.acc[self.acc_of[corner.index()] as usize];
                if let Some(sa) = acc.slot(a) {
                    acc.normal[sa] += normal * meas;
                }
                if let Some(sb) = acc.slot(b) {
                    acc.normal[sb] -= normal * meas;
                }
            }
        }
    }

    /// The region force of eqs. (5)–(7) at the image `samples` of `facet`
    /// (see [`sample_facet`]), spread over its corners with the hat
    /// weights: along the normal at two-phase vertices, as eq. (7) weights
    /// (or along the normal, per [`JunctionForce`]) at triple junctions.
    /// `means` are the two phases' means ([`region_means`]).
    #[allow(clippy::needless_range_loop)] // corners and weights are indexed in pairs
    fn add_region_force(
        &mut self,
        facet: &InterfaceFacet<K::Point>,
        (ma, mb): (f64, f64),
        samples: &[FacetSample],
        phases: &PhaseStats,
        s: &ForceSettings,
    ) {
        let nf = K::N; // corners per facet
        let InterfaceFacet {
            corners, normal, ..
        } = *facet;
        let gap = ma - mb;
        let (acc, acc_of, kinds) = (&mut self.acc, &self.acc_of, &self.kinds);
        for sample in samples {
            let intensity = sample.intensity;
            let f = match s.model {
                ForceModel::Normalised => (2.0 * intensity - ma - mb) / gap,
                ForceModel::ChanVese => (2.0 * intensity - ma - mb) * gap,
            };
            for k in 0..nf {
                let wk = sample.weights[k] * sample.ds;
                let kind = kinds[corners[k].index()];
                if kind == ForceKind::Off {
                    continue;
                }
                let ac = &mut acc[acc_of[corners[k].index()] as usize];
                match kind {
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
        }
    }

    /// Stage 3: the umbrella `ΔX` and the bending direction `−Δ²X`, the
    /// boundary Laplacian applied once and twice to the positions.
    fn smoothing_directions(&mut self, complex: &Complex<K>) {
        self.fill_facet_slots();
        self.active.clear();
        for &i in &self.interface {
            if !complex.class(VertexId(i)).on_boundary() {
                self.active.push(i);
            }
        }
        self.neighbours
            .list(&self.facets, &self.acc_of, self.acc.len(), K::N);
        self.neighbours
            .stencils(&self.active, &self.acc_of, &self.acc);
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
        for (acc, &i) in self.acc.iter().zip(&self.interface) {
            let i = i as usize;
            let mut f = K::Point::zero();
            match self.kinds[i] {
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
                let acc = self.acc_of[f.corners[p].index()];
                f.slots[p] = match self.acc.get(acc as usize) {
                    Some(acc) => [f.a, f.b].map(|l| acc.slot_of(l).map(|sl| sl as u8)),
                    None => [None; 2],
                };
            }
        }
    }

    /// The sector-averaged Laplacian along the phase boundaries of the last
    /// computation, applied to the per-vertex field `input`: at every vertex
    /// off the domain border, the mean over the phases around it of (the
    /// average of `input` over its neighbours along that phase's boundary,
    /// minus its own value). Applied to the positions it is the umbrella `ΔX`
    /// of the elasticity term; applied to the umbrella, minus the bending
    /// direction. Written into `out` at those vertices only. Each phase's
    /// neighbours are summed in the order the facets list them
    /// ([`BoundaryNeighbours`]).
    fn boundary_laplacian(&self, input: impl Fn(usize) -> K::Point, out: &mut [K::Point]) {
        let nb = &self.neighbours;
        for st in &nb.stencils {
            let x = input(st.vertex as usize);
            let mut lap = K::Point::zero();
            let mut sum = K::Point::zero();
            for t in &nb.terms[st.first as usize..(st.first + st.terms) as usize] {
                // (a repeated list has the sum of the term before)
                if !t.repeats {
                    sum = K::Point::zero();
                    for &q in &nb.list[t.start as usize..t.end as usize] {
                        sum += input(q as usize);
                    }
                }
                lap += sum * t.inv_count - x;
            }
            out[st.vertex as usize] = lap * st.inv_terms;
        }
    }

    /// Lists into `out` the vertices the smoothing directions and operators
    /// of the last computation act on (on the interface, off the domain
    /// border, in increasing id): [`bending`](Self::bending),
    /// [`stretching`](Self::stretching) and the outputs of
    /// [`apply_bending`](Self::apply_bending) and
    /// [`apply_umbrella`](Self::apply_umbrella) are `+0` at every other vertex.
    pub fn smoothed_vertices_into(&self, out: &mut Vec<u32>) {
        out.clear();
        out.extend_from_slice(&self.active);
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

/// The neighbours of every interface vertex along each phase's boundary,
/// for the boundary Laplacian, listed once per force computation (the
/// Laplacian runs a dozen times per iteration, on the same facets): the
/// other corners of each facet at the vertex, under the slots of the
/// facet's two phases, in the facets' order, so that each slot's sum adds
/// the same terms in the same order as a pass over the facets would.
#[derive(Clone, Debug, Default)]
struct BoundaryNeighbours {
    /// Where the list of (interface vertex `a`, slot `sl`) starts, at
    /// `a·MAXP + sl` (and ends, at the next entry).
    starts: Vec<u32>,
    /// The neighbours' vertex indices, list after list.
    list: Vec<u32>,
    /// Scratch: the next place of each list while it is filled.
    cursor: Vec<u32>,
    /// The Laplacian of each active vertex with a neighbour, in order.
    stencils: Vec<Stencil>,
    /// Their phases' terms, stencil after stencil.
    terms: Vec<SlotTerm>,
}

/// The boundary Laplacian at one vertex: its terms (`first..first +
/// terms` in [`BoundaryNeighbours::terms`]) and 1 / their number.
#[derive(Clone, Copy, Debug)]
struct Stencil {
    vertex: u32,
    first: u32,
    terms: u32,
    inv_terms: f64,
}

/// One phase's term of a vertex's boundary Laplacian: its neighbours
/// (`start..end` in [`BoundaryNeighbours::list`]), 1 / their count, and
/// whether they are the term before's (a vertex between two phases has the
/// same neighbours along both: their sum is taken once, the same bits).
#[derive(Clone, Copy, Debug)]
struct SlotTerm {
    start: u32,
    end: u32,
    inv_count: f64,
    repeats: bool,
}

impl BoundaryNeighbours {
    /// Lists the neighbours along `facets` (their slots filled) of the
    /// `vertices` interface vertices (`acc_of`: a vertex's index among
    /// them), `nf` corners per facet.
    fn list(&mut self, facets: &[Facet], acc_of: &[u32], vertices: usize, nf: usize) {
        self.starts.clear();
        self.starts.resize(vertices * MAXP + 1, 0);
        Self::each_pair(facets, acc_of, nf, |at, _| self.starts[at + 1] += 1);
        for k in 1..self.starts.len() {
            self.starts[k] += self.starts[k - 1];
        }
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.starts);
        self.list.clear();
        self.list
            .resize(*self.starts.last().unwrap_or(&0) as usize, 0);
        let (cursor, list) = (&mut self.cursor, &mut self.list);
        Self::each_pair(facets, acc_of, nf, |at, q| {
            list[cursor[at] as usize] = q;
            cursor[at] += 1;
        });
    }

    /// Writes the stencil of each vertex of `active` (its index among the
    /// interface vertices in `acc_of`, its sums in `acc`; after
    /// [`list`](Self::list)): a term per phase with boundary neighbours,
    /// `1 / count` of them; a vertex without any gets no stencil (the
    /// Laplacian leaves it).
    fn stencils<P: Point>(&mut self, active: &[u32], acc_of: &[u32], acc: &[Acc<P>]) {
        self.stencils.clear();
        self.terms.clear();
        for &i in active {
            let a = acc_of[i as usize] as usize;
            let first = self.terms.len();
            for (sl, &count) in acc[a].ncnt.iter().enumerate().take(acc[a].np) {
                if count > 0.0 {
                    let at = a * MAXP + sl;
                    let (start, end) = (self.starts[at], self.starts[at + 1]);
                    let repeats = self.terms.len() > first && {
                        let t = self.terms[self.terms.len() - 1];
                        self.list[t.start as usize..t.end as usize]
                            == self.list[start as usize..end as usize]
                    };
                    self.terms.push(SlotTerm {
                        start,
                        end,
                        inv_count: 1.0 / count,
                        repeats,
                    });
                }
            }
            let terms = self.terms.len() - first;
            if terms > 0 {
                self.stencils.push(Stencil {
                    vertex: i,
                    first: first as u32,
                    terms: terms as u32,
                    inv_terms: 1.0 / terms as f64,
                });
            }
        }
    }

    /// Calls `visit(a·MAXP + sl, q)` for every facet (in order), every
    /// corner `p` with sums (interface vertex `a`), every other corner `q`
    /// and each slot `sl` of the facet's phases at `p`.
    fn each_pair(facets: &[Facet], acc_of: &[u32], nf: usize, mut visit: impl FnMut(usize, u32)) {
        for f in facets {
            for p in 0..nf {
                let a = acc_of[f.corners[p].index()];
                if a == NO_ACC {
                    continue;
                }
                for q in (0..nf).filter(|&q| q != p) {
                    for sl in f.slots[p].iter().flatten() {
                        visit(
                            a as usize * MAXP + *sl as usize,
                            f.corners[q].index() as u32,
                        );
                    }
                }
            }
        }
    }
}

/// The buffers of [`classify_vertex`].
#[derive(Clone, Debug, Default)]
struct ClassifyScratch {
    star: Vec<CellId>,
    piece: Vec<usize>,
    stack: Vec<usize>,
    labels: Vec<Label>,
}

impl ClassifyScratch {
    /// The distinct labels of the cells around `v`, in increasing order.
    fn star_labels<K: Dim>(&mut self, complex: &Complex<K>, v: VertexId) -> &[Label] {
        complex.star_into(v, &mut self.star);
        self.labels_of_star(complex)
    }

    /// The distinct labels of the cells in `star`, in increasing order.
    fn labels_of_star<K: Dim>(&mut self, complex: &Complex<K>) -> &[Label] {
        self.labels.clear();
        self.labels
            .extend(self.star.iter().map(|&c| complex.label(c)));
        self.labels.sort_unstable();
        self.labels.dedup();
        &self.labels
    }
}

/// What `v` is for the forces: off the interface, between two phases, a
/// triple junction (as many same-label pieces around it as distinct
/// labels, at most [`MAXP`]) or a crossing.
fn classify_vertex<K: Dim>(
    complex: &Complex<K>,
    v: VertexId,
    sc: &mut ClassifyScratch,
) -> ForceKind {
    let class = complex.class(v);
    match class.kind {
        VertexKind::Interior => return ForceKind::Off,
        // 3D: a two-piece star can still sit on an edge with more than two
        // interface triangles (two sheets of a phase touching): a crossing.
        VertexKind::Interface if complex.has_junction_edge_with(v, &mut sc.star) => {
            return ForceKind::Crossing
        }
        VertexKind::Interface => return ForceKind::Interface,
        VertexKind::Junction => {}
    }
    complex.star_into(v, &mut sc.star);
    sc.piece.clear();
    sc.piece.resize(sc.star.len(), usize::MAX);
    let mut pieces = 0;
    for start in 0..sc.star.len() {
        if sc.piece[start] != usize::MAX {
            continue;
        }
        sc.piece[start] = pieces;
        sc.stack.clear();
        sc.stack.push(start);
        while let Some(i) = sc.stack.pop() {
            let c = sc.star[i];
            let label = complex.label(c);
            for (local, nb) in complex.neighbours(c).iter().enumerate() {
                let Some(nb) = *nb else { continue };
                if complex.cell(c)[local] == v || complex.label(nb) != label {
                    continue;
                }
                if let Some(j) = sc.star.iter().position(|&s| s == nb) {
                    if sc.piece[j] == usize::MAX {
                        sc.piece[j] = pieces;
                        sc.stack.push(j);
                    }
                }
            }
        }
        pieces += 1;
    }
    let labels = sc.labels_of_star(complex).len();
    if pieces == labels && pieces <= MAXP {
        ForceKind::TripleJunction
    } else {
        ForceKind::Crossing
    }
}

/// The means of `facet`'s two phases, or `None` where one is missing or
/// the two are equal (eq. 6 undefined: no region force across the facet).
fn region_means<P: Point>(
    facet: &InterfaceFacet<P>,
    phases: &PhaseStats,
    s: &ForceSettings,
) -> Option<(f64, f64)> {
    let (ma, mb) = (phases.mean_of(facet.a)?, phases.mean_of(facet.b)?);
    let equal = (ma - mb).abs() < s.equal_means;
    (!equal).then_some((ma, mb))
}

/// One image sample of an interface facet: the interpolated intensity, the
/// hat weights of the facet's corners at the sample and the measure the
/// sample stands for.
#[derive(Clone, Copy, Debug, Default)]
struct FacetSample {
    intensity: f64,
    weights: [f64; 3],
    ds: f64,
}

/// Appends the image samples of `facet`, every `spacing` along it (in the
/// image's unit), to `out`.
fn sample_facet<K: Raster>(
    facet: &InterfaceFacet<K::Point>,
    image: &ImageView<'_>,
    spacing: f64,
    out: &mut Vec<FacetSample>,
) {
    K::facet_samples(&facet.points[..K::N], spacing, &mut |p, w, ds| {
        let mut weights = [0.0; 3];
        weights[..w.len()].copy_from_slice(w);
        out.push(FacetSample {
            intensity: K::sample(image, p),
            weights,
            ds,
        });
    });
}

/// Interface facets listed in blocks and their image samples, taken on
/// rayon's threads a block at a time (a block bounds the memory the samples
/// take: a 3D facet of a few voxels² has a few dozen).
#[derive(Clone, Debug)]
struct FacetSamples<P> {
    /// The facets of the current block, in the order of
    /// [`Complex::interface_facets`].
    block: Vec<InterfaceFacet<P>>,
    /// Per chunk of the block, the samples of its facets one after the other.
    chunks: Vec<SampledChunk>,
    /// The serial path's samples of one facet.
    samples: Vec<FacetSample>,
}

impl<P> Default for FacetSamples<P> {
    fn default() -> Self {
        FacetSamples {
            block: Vec::new(),
            chunks: Vec::new(),
            samples: Vec::new(),
        }
    }
}

/// The samples of consecutive facets and where each facet's end.
#[derive(Clone, Debug, Default)]
struct SampledChunk {
    samples: Vec<FacetSample>,
    ends: Vec<usize>,
}

/// Facets per block of [`FacetSamples`].
const FACET_BLOCK: usize = 1024;
/// Facets per chunk, the unit of work of one thread.
const FACET_CHUNK: usize = 64;

impl<P: Point> FacetSamples<P> {
    /// Lists the next block of facets from `facets` (empty at the end).
    fn list_block<K: Dim<Point = P>>(&mut self, facets: &mut InterfaceFacets<'_, K>) {
        self.block.clear();
        self.block.extend(facets.by_ref().take(FACET_BLOCK));
    }

    /// Samples the facets of the block whose phases have distinct means,
    /// chunk by chunk on rayon's threads.
    fn sample_block<K: Raster<Point = P>>(
        &mut self,
        image: &ImageView<'_>,
        phases: &PhaseStats,
        s: &ForceSettings,
        spacing: f64,
    ) {
        let chunks = self.block.len().div_ceil(FACET_CHUNK);
        if self.chunks.len() < chunks {
            self.chunks.resize(chunks, SampledChunk::default());
        }
        self.block
            .par_chunks(FACET_CHUNK)
            .zip(self.chunks.par_iter_mut())
            .for_each(|(facets, chunk)| {
                chunk.samples.clear();
                chunk.ends.clear();
                for facet in facets {
                    if region_means(facet, phases, s).is_some() {
                        sample_facet::<K>(facet, image, spacing, &mut chunk.samples);
                    }
                    chunk.ends.push(chunk.samples.len());
                }
            });
    }

    /// Each facet of the block with its samples, in order.
    fn block_samples(&self) -> impl Iterator<Item = (&InterfaceFacet<P>, &[FacetSample])> + '_ {
        self.block
            .chunks(FACET_CHUNK)
            .zip(&self.chunks)
            .flat_map(|(facets, chunk)| {
                facets.iter().enumerate().map(move |(i, facet)| {
                    let start = if i == 0 { 0 } else { chunk.ends[i - 1] };
                    (facet, &chunk.samples[start..chunk.ends[i]])
                })
            })
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
    use super::*;
    use crate::dim::D3;
    use std::cell::Cell;

    /// The forces of a 24³ box meshed at edge length 1.5 holding three
    /// phases (a ball cut in two halves on a background: more than one block
    /// of facets, triple junctions along the cut's rim), on `threads` threads.
    fn forces_on(threads: usize) -> ForceField<D3> {
        let n = 24;
        let mut complex = Complex::<D3>::cuboid([n as f64; 3], 1.5).unwrap();
        let centre = n as f64 / 2.0;
        let changes: Vec<(CellId, Label)> = complex
            .cell_ids()
            .filter_map(|c| {
                let points = complex.cell_points(c);
                let mid = (points[0] + points[1] + points[2] + points[3]) * 0.25;
                let inside = (mid - nalgebra::Vector3::repeat(centre)).norm() < 7.0;
                inside.then_some((c, if mid.x < centre { 1 } else { 2 }))
            })
            .collect();
        complex.set_labels(&changes);
        let voxels: Vec<f32> = (0..n * n * n)
            .map(|i| ((i * 7919) % 1009) as f32 / 1009.0)
            .collect();
        let image = ImageView::new_3d([n, n, n], &voxels).unwrap();
        let mut phases = PhaseStats::new(3);
        phases.mean = vec![Some(0.2), Some(0.5), Some(0.8)];
        let settings = ForceSettings {
            model: ForceModel::Normalised,
            junction: JunctionForce::Paper,
            spacing: 0.5,
            equal_means: 1e-6,
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut field = ForceField::new();
            field.compute(&complex, &image, &phases, &settings);
            field
        })
    }

    #[test]
    fn forces_are_the_same_bits_on_one_and_two_threads() {
        let (one, two) = (forces_on(1), forces_on(2));
        assert!(
            one.facets.len() > FACET_BLOCK,
            "{} facets",
            one.facets.len()
        );
        assert!(one.junctions.0 > 0, "no triple junction");
        let bits = |f: &ForceField<D3>| -> Vec<u64> {
            [&f.external, &f.bending, &f.stretching]
                .iter()
                .flat_map(|field| field.iter().flat_map(|p| p.iter().map(|x| x.to_bits())))
                .collect()
        };
        assert!(one.external.iter().any(|p| p.norm() > 0.0));
        assert_eq!(one.kinds, two.kinds);
        assert_eq!(one.junctions, two.junctions);
        assert_eq!(
            one.interface_measure.to_bits(),
            two.interface_measure.to_bits()
        );
        assert_eq!(bits(&one), bits(&two));
    }

    thread_local! {
        /// How many times [`super::ForceField::compute`] ran on this thread.
        pub(crate) static COMPUTATIONS: Cell<usize> = const { Cell::new(0) };
    }

    /// Computations of the paper's field on this thread so far.
    pub(crate) fn computations() -> usize {
        COMPUTATIONS.with(Cell::get)
    }
}
