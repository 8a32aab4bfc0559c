//! How far each cell lies from every other phase, measured through its own
//! phase: the distance from the cell's centroid to the nearest interface
//! facet the cell's phase shares with phase `q`, reached by walking cells of
//! the cell's own label only, up to a given reach.
//!
//! Walking only through the own phase makes the figure the depth of the
//! cell inside its phase towards `q`: for a cell of a layer of phase `p`
//! between phases `a` and `b`, `d_a + d_b` is the layer's thickness there
//! (between two parallel planes, exactly, wherever the centroid lies).
//!
//! The distances are propagated as in a vector distance transform: every
//! cell carries, per phase, the facet nearest it that has been found, and
//! hands it to its same-label neighbours, which measure their own exact
//! distance to that facet (Dijkstra order, so each cell keeps the nearest of
//! the facets offered to it). Cells further than the reach are left
//! unmeasured.

use crate::complex::{CellId, Complex, Label};
use crate::dim::{Dim, Point};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// A facet: the side of `cell` opposite its local corner `opposite`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct FacetRef {
    cell: CellId,
    opposite: u8,
}

/// Per cell and phase, the distance to that phase's nearest facet (see the
/// module documentation); kept between calls as scratch space.
#[derive(Clone, Debug, Default)]
pub struct PhaseDistances {
    phases: usize,
    /// `phases` entries per cell id: the distance, infinite when not
    /// reached.
    distance: Vec<f64>,
    /// The facet each finite distance was measured to.
    source: Vec<Option<FacetRef>>,
    /// Dijkstra queue: (distance bits, cell, phase, facet).
    queue: BinaryHeap<Reverse<(u64, CellId, Label, FacetRef)>>,
}

impl PhaseDistances {
    /// Empty scratch space.
    pub fn new() -> Self {
        Self::default()
    }

    /// Measures every cell's distance to each of the `phases` phases, up to
    /// `reach` (in the mesh's units).
    pub fn measure<K: Dim>(&mut self, complex: &Complex<K>, phases: usize, reach: f64) {
        self.phases = phases;
        let entries = complex.cell_capacity() * phases;
        self.distance.clear();
        self.distance.resize(entries, f64::INFINITY);
        self.source.clear();
        self.source.resize(entries, None);
        self.queue.clear();
        self.seed_interface_cells(complex, reach);
        while let Some(Reverse((bits, c, q, facet))) = self.queue.pop() {
            if f64::from_bits(bits) > self.distance[self.slot(c, q)] {
                continue;
            }
            let own = complex.label(c);
            for nb in complex.neighbours(c).iter().flatten() {
                if complex.label(*nb) == own {
                    self.offer(complex, *nb, q, facet, reach);
                }
            }
        }
    }

    /// The distance of cell `c` to phase `q` through `c`'s own phase; `None`
    /// beyond the reach (or for `c`'s own phase).
    pub fn to_phase(&self, c: CellId, q: Label) -> Option<f64> {
        let d = self.distance[self.slot(c, q)];
        d.is_finite().then_some(d)
    }

    fn slot(&self, c: CellId, q: Label) -> usize {
        c.index() * self.phases + q as usize
    }

    /// Every cell with a facet on another phase measures its distance to it.
    fn seed_interface_cells<K: Dim>(&mut self, complex: &Complex<K>, reach: f64) {
        for c in complex.cell_ids() {
            let own = complex.label(c);
            for (i, nb) in complex.neighbours(c).iter().enumerate() {
                let Some(nb) = *nb else { continue };
                let q = complex.label(nb);
                if q != own && (q as usize) < self.phases {
                    let facet = FacetRef {
                        cell: c,
                        opposite: i as u8,
                    };
                    self.offer(complex, c, q, facet, reach);
                }
            }
        }
    }

    /// Cell `c` measures its distance to `facet` of phase `q`, keeps it if
    /// it is the nearest yet and within reach, and queues it to hand on.
    fn offer<K: Dim>(
        &mut self,
        complex: &Complex<K>,
        c: CellId,
        q: Label,
        facet: FacetRef,
        reach: f64,
    ) {
        let slot = self.slot(c, q);
        if self.source[slot] == Some(facet) {
            return;
        }
        let d = distance_to_facet(complex, facet, centroid(complex, c));
        if d <= reach && d < self.distance[slot] {
            self.distance[slot] = d;
            self.source[slot] = Some(facet);
            self.queue.push(Reverse((d.to_bits(), c, q, facet)));
        }
    }
}

/// The centroid of cell `c`.
pub fn centroid<K: Dim>(complex: &Complex<K>, c: CellId) -> K::Point {
    let pts = complex.cell_points(c);
    let mut sum = K::Point::zero();
    for p in &pts[..K::NV] {
        sum += *p;
    }
    sum * (1.0 / K::NV as f64)
}

/// Distance from `x` to the facet (segment in 2D, triangle in 3D).
fn distance_to_facet<K: Dim>(complex: &Complex<K>, facet: FacetRef, x: K::Point) -> f64 {
    let pts = complex.cell_points(facet.cell);
    let mut corners = (0..K::NV)
        .filter(|&k| k != facet.opposite as usize)
        .map(|k| pts[k]);
    let a = corners.next().expect("a facet has N corners");
    let b = corners.next().expect("a facet has N corners");
    let closest = match corners.next() {
        Some(c) => closest_on_triangle(x, a, b, c),
        None => closest_on_segment(x, a, b),
    };
    (x - closest).length()
}

/// The point of segment `ab` nearest `x`.
fn closest_on_segment<P: Point>(x: P, a: P, b: P) -> P {
    let ab = b - a;
    let len2 = ab.dot(&ab);
    if len2 == 0.0 {
        return a;
    }
    a + ab * ((x - a).dot(&ab) / len2).clamp(0.0, 1.0)
}

/// The point of triangle `abc` nearest `x` (by the triangle's Voronoi
/// regions: a corner, an edge, or the inside).
fn closest_on_triangle<P: Point>(x: P, a: P, b: P, c: P) -> P {
    let (ab, ac, ax) = (b - a, c - a, x - a);
    let (d1, d2) = (ab.dot(&ax), ac.dot(&ax));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bx = x - b;
    let (d3, d4) = (ab.dot(&bx), ac.dot(&bx));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cx = x - c;
    let (d5, d6) = (ab.dot(&cx), ac.dot(&cx));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::D3;
    use nalgebra::Vector3;

    #[test]
    fn the_nearest_point_of_a_triangle_is_found_in_each_region() {
        let (a, b, c) = (
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(4.0, 0.0, 0.0),
            Vector3::new(0.0, 4.0, 0.0),
        );
        let near = |x: Vector3<f64>| closest_on_triangle(x, a, b, c);
        assert_eq!(
            near(Vector3::new(1.0, 1.0, 3.0)),
            Vector3::new(1.0, 1.0, 0.0)
        );
        assert_eq!(near(Vector3::new(-1.0, -1.0, 2.0)), a);
        assert_eq!(
            near(Vector3::new(2.0, -3.0, 0.0)),
            Vector3::new(2.0, 0.0, 0.0)
        );
        assert_eq!(
            near(Vector3::new(3.0, 3.0, 0.0)),
            Vector3::new(2.0, 2.0, 0.0)
        );
        assert_eq!(near(Vector3::new(6.0, -1.0, 1.0)), b);
    }

    /// A slab of phase 1 four units thick between phases 0 and 2, on a Kuhn
    /// mesh of grid spacing 2 (edge length 2.48): inside it, the distances
    /// to the two sides add up to the thickness.
    #[test]
    fn the_distances_across_a_layer_add_up_to_its_thickness() {
        let mut mesh = Complex::<D3>::cuboid([16.0, 16.0, 16.0], 2.48).unwrap();
        mesh.label_by(|p| match p.z {
            z if z < 6.0 => 0,
            z if z < 10.0 => 1,
            _ => 2,
        });
        let mut distances = PhaseDistances::new();
        distances.measure(&mesh, 3, 5.0);
        let mut layer_cells = 0;
        for c in mesh.cell_ids().filter(|&c| mesh.label(c) == 1) {
            let z = centroid(&mesh, c).z;
            let (d0, d2) = (distances.to_phase(c, 0), distances.to_phase(c, 2));
            let (d0, d2) = (d0.expect("within reach"), d2.expect("within reach"));
            assert!((d0 - (z - 6.0)).abs() < 1e-9, "{d0} at z = {z}");
            assert!((d0 + d2 - 4.0).abs() < 1e-9, "{d0} + {d2}");
            layer_cells += 1;
        }
        assert!(layer_cells > 0);
        let deep = mesh
            .cell_ids()
            .find(|&c| centroid(&mesh, c).z < 1.0)
            .unwrap();
        assert_eq!(distances.to_phase(deep, 1), None, "beyond the reach");
    }
}
