//! How far a step moves the interface across itself, the motion the 2D
//! stopping rule measures.
//!
//! The bending term of eq. (2) also slides interface vertices *along* the
//! interface, evening out their spacing: on a straight side of the 512²
//! two-phase phantom, vertices crept along the side by 0.1 px per iteration
//! for 30 iterations after every pixel had its final label, and the 0.05 px
//! rule waited for them. Such motion moves no pixel across the interface;
//! only the component of a step along the interface's normal does.

use crate::complex::{CellId, Complex, VertexId};
use crate::dim::{Dim, Point};

/// How far moving `v` by `d` moves the interface across itself: in 2D, for a
/// vertex with exactly two interface edges, the component of `d` normal to
/// the chord between its two interface neighbours (the tangent of a curve
/// sampled at its vertices); the whole `|d|` elsewhere (off the interface,
/// at junctions, in 3D). `star` is scratch space.
pub(crate) fn across_interface<K: Dim>(
    complex: &Complex<K>,
    v: VertexId,
    d: K::Point,
    star: &mut Vec<CellId>,
) -> f64 {
    if K::N != 2 {
        return d.length();
    }
    let Some([a, b]) = interface_neighbours(complex, v, star) else {
        return d.length();
    };
    let chord = complex.position(b) - complex.position(a);
    let chord2 = chord.dot(&chord);
    if chord2 == 0.0 {
        return d.length();
    }
    (d - chord * (d.dot(&chord) / chord2)).length()
}

/// The two ends of the interface edges at `v` (2D), if it has exactly two.
fn interface_neighbours<K: Dim>(
    complex: &Complex<K>,
    v: VertexId,
    star: &mut Vec<CellId>,
) -> Option<[VertexId; 2]> {
    complex.star_into(v, star);
    let mut found: [Option<VertexId>; 2] = [None, None];
    for &c in star.iter() {
        let (cell, across) = (complex.cell(c), complex.neighbours(c));
        for (j, &w) in cell.iter().enumerate() {
            if w == v {
                continue;
            }
            // The edge (v, w) is the facet opposite the cell's third corner.
            let third = (0..3).find(|&k| k != j && cell[k] != v)?;
            let Some(other) = across[third] else { continue };
            if complex.label(other) == complex.label(c) || found.contains(&Some(w)) {
                continue;
            }
            match found {
                [None, _] => found[0] = Some(w),
                [Some(_), None] => found[1] = Some(w),
                _ => return None,
            }
        }
    }
    match found {
        [Some(a), Some(b)] => Some([a, b]),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::D2;
    use nalgebra::Vector2;

    /// The box mesh of a 16² domain, phase 1 below the line y = 8.
    fn two_phases() -> Complex<D2> {
        let mut c = Complex::<D2>::rectangle(16.0, 16.0, 4.0).expect("mesh");
        let below: Vec<CellId> = c
            .cell_ids()
            .filter(|&cell| {
                let pts = c.cell_points(cell);
                (pts[0].y + pts[1].y + pts[2].y) / 3.0 < 8.0
            })
            .collect();
        for cell in below {
            c.set_label(cell, 1);
        }
        c
    }

    /// An interface vertex away from the border, and its two interface neighbours' chord.
    fn interface_vertex(c: &Complex<D2>) -> (VertexId, Vector2<f64>) {
        let mut star = Vec::new();
        for v in c.vertex_ids() {
            let p = c.position(v);
            if p.x > 4.0 && p.x < 12.0 {
                if let Some([a, b]) = interface_neighbours(c, v, &mut star) {
                    return (v, c.position(b) - c.position(a));
                }
            }
        }
        panic!("no interior interface vertex")
    }

    #[test]
    fn sliding_along_the_interface_does_not_cross_it() {
        let c = two_phases();
        let (v, chord) = interface_vertex(&c);
        let mut star = Vec::new();
        let along = chord.normalize() * 0.3;
        assert!(across_interface(&c, v, along, &mut star) < 1e-12);
        let normal = Vector2::new(-chord.y, chord.x).normalize() * 0.3;
        assert!((across_interface(&c, v, normal, &mut star) - 0.3).abs() < 1e-12);
        let oblique = along + normal;
        assert!((across_interface(&c, v, oblique, &mut star) - 0.3).abs() < 1e-12);
    }

    #[test]
    fn off_the_interface_the_whole_step_counts() {
        let c = two_phases();
        let mut star = Vec::new();
        let inside = c
            .vertex_ids()
            .find(|&v| c.position(v).y > 12.0 && c.position(v).y < 16.0)
            .expect("a vertex in the upper phase");
        let d = Vector2::new(0.3, 0.4);
        assert_eq!(across_interface(&c, inside, d, &mut star), 0.5);
    }
}
