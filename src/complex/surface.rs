//! Initial 3D complexes conforming to a closed triangle surface, built with
//! TetGen (feature `tetgen`; TetGen is AGPL-3, see `tetgen-sys`).
//!
//! The piecewise linear complex handed to TetGen is the volume box
//! `[0, nx]×[0, ny]×[0, nz]` (voxel `i` covers `[i, i + 1]`; the same frame as
//! `--ball`) as 12 triangles plus the user's surface, which must lie strictly
//! inside the box. TetGen meshes it with a radius-edge bound of
//! [`RADIUS_EDGE`] and a volume bound from the edge length L
//! ([`max_volume`]) and reports a region attribute per tetrahedron
//! (`-A`: one number per connected subdomain). Each subdomain then gets
//! phase 1 if it lies inside the surface and 0 otherwise: inside means an odd
//! winding number (the surface's orientation may be either way per
//! component, so a cavity between two nested shells is outside). We classify
//! subdomains rather than pass seed points because a point guaranteed to lie
//! strictly inside an arbitrary surface is as hard to find as the
//! classification itself; the attributes still carry the phases.
//!
//! TetGen may add Steiner points on the box faces; those within a relative
//! `1e-9` of a face are snapped onto it, since the complex recognises boundary
//! vertices by exact coordinates.

use crate::complex::{BuildError, Complex, VertexId};
use crate::dim::D3;
use crate::io::surface::TriangleSurface;
use nalgebra::Vector3;
use std::collections::{HashMap, HashSet};
use tetgen_sys::{tetrahedralize, Plc, Switches, TetgenError};
use thiserror::Error;

/// TetGen's radius-edge ratio bound (`-q1.5`): well-shaped tets (the DSC's
/// quality pass then has little to do) at a moderate number of Steiner points.
pub const RADIUS_EDGE: f64 = 1.5;

/// The volume of the regular tetrahedron with edge `l`, `l³/(6√2)`, times 2
/// (TetGen's quality tets stay well below the bound). Measured in the
/// icosphere test (L = 3, a radius-6 sphere whose own edges are ≈ 1.9):
/// mean tet edge 2.3, i.e. 0.77·L; not tuned further.
pub fn max_volume(l: f64) -> f64 {
    2.0 * l * l * l / (6.0 * std::f64::consts::SQRT_2)
}

/// Why a surface-conforming complex could not be built.
#[derive(Debug, Error)]
pub enum SurfaceInitError {
    /// A surface point is not strictly inside the volume box.
    #[error("surface point {point} at {coords:?} is not strictly inside the volume box [0, {dims:?}] (coordinates are in voxels)")]
    OutsideBox {
        /// Index of the point.
        point: usize,
        /// Its coordinates.
        coords: [f64; 3],
        /// The volume size.
        dims: [usize; 3],
    },
    /// Two triangles traverse a shared edge in the same direction.
    #[error("the surface's triangles are not consistently oriented (edge {0:?} is traversed twice in the same direction)")]
    Orientation([u32; 2]),
    /// The edge length is not positive and finite.
    #[error("edge length {0} must be positive and finite")]
    EdgeLength(f64),
    /// TetGen rejected the input (including the surface checks of `tetgen-sys`).
    #[error("TetGen: {0}")]
    Tetgen(#[from] TetgenError),
    /// TetGen's output did not make a valid complex.
    #[error("building the complex from TetGen's mesh: {0}")]
    Build(#[from] BuildError),
}

/// The winding number of the closed surface around `p` (solid angles of
/// Van Oosterom and Strackee, summed over the triangles, divided by 4π).
pub fn winding_number(surface: &TriangleSurface, p: [f64; 3]) -> f64 {
    let q = Vector3::from(p);
    let mut total = 0.0;
    for t in &surface.triangles {
        let [a, b, c] = t.map(|i| Vector3::from(surface.points[i as usize]) - q);
        let (la, lb, lc) = (a.norm(), b.norm(), c.norm());
        let num = a.dot(&b.cross(&c));
        let den = la * lb * lc + a.dot(&b) * lc + b.dot(&c) * la + c.dot(&a) * lb;
        total += 2.0 * num.atan2(den);
    }
    total / (4.0 * std::f64::consts::PI)
}

/// Whether `p` is inside the surface: an odd winding number.
pub fn inside(surface: &TriangleSurface, p: [f64; 3]) -> bool {
    (winding_number(surface, p).round().abs() as i64) % 2 == 1
}

/// The 8 corners and 12 triangles of the box `[0, size]`.
fn box_plc(size: [f64; 3]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let points = (0..8)
        .map(|i| {
            [
                if i & 1 != 0 { size[0] } else { 0.0 },
                if i & 2 != 0 { size[1] } else { 0.0 },
                if i & 4 != 0 { size[2] } else { 0.0 },
            ]
        })
        .collect();
    // Two triangles per face; corners indexed by bits (x, y, z).
    let quads: [[u32; 4]; 6] = [
        [0, 2, 6, 4], // x = 0
        [1, 5, 7, 3], // x = max
        [0, 4, 5, 1], // y = 0
        [2, 3, 7, 6], // y = max
        [0, 1, 3, 2], // z = 0
        [4, 6, 7, 5], // z = max
    ];
    let triangles = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    (points, triangles)
}

fn check_surface(surface: &TriangleSurface, dims: [usize; 3]) -> Result<(), SurfaceInitError> {
    for (i, p) in surface.points.iter().enumerate() {
        if !(0..3).all(|a| p[a] > 0.0 && p[a] < dims[a] as f64) {
            return Err(SurfaceInitError::OutsideBox {
                point: i,
                coords: *p,
                dims,
            });
        }
    }
    let mut seen = HashSet::with_capacity(surface.triangles.len() * 3);
    for t in &surface.triangles {
        for k in 0..3 {
            let e = [t[k], t[(k + 1) % 3]];
            if e[0] != e[1] && !seen.insert(e) {
                return Err(SurfaceInitError::Orientation(e));
            }
        }
    }
    Ok(())
}

/// Tetrahedralises the box of a `dims` volume together with `surface` at
/// edge length `l` and returns the complex, cells inside the surface labelled
/// 1 and the others 0. The surface must be closed, manifold, free of
/// self-intersections, consistently oriented and strictly inside the box.
pub fn complex_from_surface(
    surface: &TriangleSurface,
    dims: [usize; 3],
    l: f64,
) -> Result<Complex<D3>, SurfaceInitError> {
    if !(l.is_finite() && l > 0.0) {
        return Err(SurfaceInitError::EdgeLength(l));
    }
    check_surface(surface, dims)?;
    let size = dims.map(|d| d as f64);
    let (mut points, mut triangles) = box_plc(size);
    let offset = points.len() as u32;
    points.extend_from_slice(&surface.points);
    triangles.extend(surface.triangles.iter().map(|t| t.map(|i| i + offset)));
    let plc = Plc {
        points,
        triangles,
        regions: Vec::new(),
    };
    let switches = Switches {
        quality: Some(RADIUS_EDGE),
        max_volume: Some(max_volume(l)),
        region_attributes: true,
        ..Switches::default()
    };
    let mesh = tetrahedralize(&plc, &switches)?;

    // Snap near-boundary coordinates onto the box faces.
    let tol = 1e-9 * size.iter().copied().fold(0.0, f64::max);
    let points: Vec<Vector3<f64>> = mesh
        .points
        .iter()
        .map(|p| {
            let mut q = Vector3::from(*p);
            for a in 0..3 {
                if q[a].abs() <= tol {
                    q[a] = 0.0;
                } else if (q[a] - size[a]).abs() <= tol {
                    q[a] = size[a];
                }
            }
            q
        })
        .collect();

    // Phase per subdomain, from its largest tet's centroid.
    let mut largest: HashMap<i32, (f64, usize)> = HashMap::new();
    for (t, &attr) in mesh.tet_attributes.iter().enumerate() {
        let v = mesh.tet_volume(t);
        let e = largest.entry(attr).or_insert((v, t));
        if v > e.0 {
            *e = (v, t);
        }
    }
    let phase: HashMap<i32, u32> = largest
        .into_iter()
        .map(|(attr, (_, t))| {
            let c = mesh.tets[t]
                .iter()
                .fold(Vector3::zeros(), |s, &i| s + points[i as usize])
                / 4.0;
            (attr, u32::from(inside(surface, [c.x, c.y, c.z])))
        })
        .collect();
    let labels = if mesh.tet_attributes.len() == mesh.tets.len() {
        mesh.tet_attributes.iter().map(|a| phase[a]).collect()
    } else {
        // No attributes (cannot happen with `-A`): classify every tet.
        mesh.tets
            .iter()
            .map(|t| {
                let c = t
                    .iter()
                    .fold(Vector3::zeros(), |s, &i| s + points[i as usize])
                    / 4.0;
                u32::from(inside(surface, [c.x, c.y, c.z]))
            })
            .collect()
    };
    let cells = mesh.tets.iter().map(|t| t.map(VertexId)).collect();
    Ok(Complex::from_arrays(
        points,
        cells,
        labels,
        (Vector3::zeros(), Vector3::from(size)),
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An icosphere (subdivided icosahedron) of the given radius and centre.
    pub fn icosphere(centre: [f64; 3], r: f64, subdivisions: usize) -> TriangleSurface {
        let t = (1.0 + 5f64.sqrt()) / 2.0;
        let mut pts: Vec<Vector3<f64>> = [
            [-1.0, t, 0.0],
            [1.0, t, 0.0],
            [-1.0, -t, 0.0],
            [1.0, -t, 0.0],
            [0.0, -1.0, t],
            [0.0, 1.0, t],
            [0.0, -1.0, -t],
            [0.0, 1.0, -t],
            [t, 0.0, -1.0],
            [t, 0.0, 1.0],
            [-t, 0.0, -1.0],
            [-t, 0.0, 1.0],
        ]
        .iter()
        .map(|p| Vector3::from(*p).normalize())
        .collect();
        let mut tris: Vec<[u32; 3]> = vec![
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        for _ in 0..subdivisions {
            let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
            let mut midpoint = |a: u32, b: u32, pts: &mut Vec<Vector3<f64>>| {
                *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    pts.push(((pts[a as usize] + pts[b as usize]) / 2.0).normalize());
                    pts.len() as u32 - 1
                })
            };
            let mut next = Vec::with_capacity(tris.len() * 4);
            for [a, b, c] in tris {
                let ab = midpoint(a, b, &mut pts);
                let bc = midpoint(b, c, &mut pts);
                let ca = midpoint(c, a, &mut pts);
                next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
            }
            tris = next;
        }
        TriangleSurface {
            points: pts
                .iter()
                .map(|p| {
                    [
                        centre[0] + r * p.x,
                        centre[1] + r * p.y,
                        centre[2] + r * p.z,
                    ]
                })
                .collect(),
            triangles: tris,
        }
    }

    fn enclosed_volume(s: &TriangleSurface) -> f64 {
        s.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| Vector3::from(s.points[i as usize]));
                a.dot(&b.cross(&c)) / 6.0
            })
            .sum::<f64>()
            .abs()
    }

    #[test]
    fn icosphere_gives_a_valid_complex_with_the_enclosed_volume_in_phase_1() {
        let s = icosphere([12.0, 13.0, 11.0], 6.0, 2);
        let c = complex_from_surface(&s, [24, 26, 22], 3.0).unwrap();
        assert!(c.validate().is_empty(), "{:?}", c.validate());
        let (mut v1, mut total) = (0.0, 0.0);
        for t in c.cell_ids() {
            let m = c.measure(t);
            total += m;
            if c.label(t) == 1 {
                v1 += m;
            }
        }
        assert!((total - 24.0 * 26.0 * 22.0).abs() < 1e-6 * total);
        let want = enclosed_volume(&s);
        assert!(
            (v1 - want).abs() < 1e-6 * want,
            "phase 1 {v1}, enclosed {want}"
        );
        // Mean edge length near L.
        let (mut sum, mut n) = (0.0, 0);
        for t in c.cell_ids() {
            let p = c.cell_points(t);
            for i in 0..4 {
                for j in i + 1..4 {
                    sum += (p[i] - p[j]).norm();
                    n += 1;
                }
            }
        }
        let mean = sum / n as f64;
        eprintln!("L = 3: {} tets, mean edge {mean:.3}", c.cell_count());
        assert!((1.5..=4.5).contains(&mean), "mean edge {mean}");
    }

    #[test]
    fn nested_shells_leave_the_cavity_outside_and_bad_surfaces_are_refused() {
        let mut s = icosphere([10.0, 10.0, 10.0], 7.0, 1);
        let inner = icosphere([10.0, 10.0, 10.0], 3.5, 1);
        let off = s.points.len() as u32;
        s.points.extend_from_slice(&inner.points);
        s.triangles
            .extend(inner.triangles.iter().map(|t| t.map(|i| i + off)));
        let c = complex_from_surface(&s, [20, 20, 20], 2.5).unwrap();
        assert!(c.validate().is_empty());
        let v1: f64 = c
            .cell_ids()
            .filter(|&t| c.label(t) == 1)
            .map(|t| c.measure(t))
            .sum();
        let want = enclosed_volume(&icosphere([0.0; 3], 7.0, 1))
            - enclosed_volume(&icosphere([0.0; 3], 3.5, 1));
        assert!((v1 - want).abs() < 1e-6 * want, "{v1} vs {want}");

        let outside = icosphere([3.0, 10.0, 10.0], 4.0, 1);
        assert!(matches!(
            complex_from_surface(&outside, [20, 20, 20], 2.5),
            Err(SurfaceInitError::OutsideBox { .. })
        ));
        let mut flipped = icosphere([10.0, 10.0, 10.0], 4.0, 1);
        flipped.triangles[0].swap(0, 1);
        assert!(matches!(
            complex_from_surface(&flipped, [20, 20, 20], 2.5),
            Err(SurfaceInitError::Orientation(_))
        ));
        let mut open = icosphere([10.0, 10.0, 10.0], 4.0, 1);
        open.triangles.pop();
        assert!(matches!(
            complex_from_surface(&open, [20, 20, 20], 2.5),
            Err(SurfaceInitError::Tetgen(_))
        ));
    }
}
