//! A complex as VTK files in the input's [`Frame`]: the mesh (`mesh.vtu`,
//! cell data `phase`) and the interface (`interface.vtp`: triangles in 3D,
//! line segments in 2D, cell data `phase` and `phase_other`, the phases on
//! the two sides, `phase` the lower mesh label; a 3D triangle is oriented
//! with its normal pointing from `phase` to `phase_other`). Points are
//! written in world coordinates ([`Frame::domain_to_world`]), where VTK's
//! readers place the input's pixels and voxels. Phases are written through
//! an `order` map (mesh label → output index, e.g. the driver's phases by
//! increasing mean). Where the frame mirrors (a negative determinant,
//! [`Frame::is_mirrored`]) every cell and interface triangle is written with
//! two corners swapped, so that cells stay positively oriented and normals
//! keep pointing from `phase` to `phase_other` in the world.

use super::{Complex, Label};
use crate::dim::{Dim, D2, D3};
use crate::io::{write_vtp, write_vtp_lines, write_vtu, CellArray, Cells, Frame, IoError};
use std::path::Path;

/// The interface of a complex as plain arrays: triangles (3D) or segments (2D).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Interface<const M: usize> {
    /// Vertex positions in the domain (only the interface vertices, renumbered).
    pub points: Vec<[f64; 3]>,
    /// The facets; in 3D oriented with the normal from `phase` to `phase_other`.
    pub facets: Vec<[u32; M]>,
    /// The lower phase of each facet.
    pub phase: Vec<Label>,
    /// The higher phase of each facet.
    pub phase_other: Vec<Label>,
}

/// The interface triangles of a 3D complex.
pub type InterfaceSurface = Interface<3>;
/// The interface segments of a 2D complex.
pub type InterfaceLines = Interface<2>;

impl<const M: usize> Interface<M> {
    /// The points in world coordinates.
    pub fn world_points(&self, frame: &Frame) -> Vec<[f64; 3]> {
        self.points
            .iter()
            .map(|&p| frame.domain_to_world(p))
            .collect()
    }

    /// Writes the interface as `.vtp` in `frame` with the cell data `phase`
    /// and `phase_other` through `order`.
    fn write(&self, path: &Path, order: &[u8], frame: &Frame) -> Result<(), IoError> {
        let phase: Vec<i32> = self.phase.iter().map(|&l| ordered(order, l)).collect();
        let other: Vec<i32> = self
            .phase_other
            .iter()
            .map(|&l| ordered(order, l))
            .collect();
        let data = [
            ("phase", CellArray::I32(&phase)),
            ("phase_other", CellArray::I32(&other)),
        ];
        let points = self.world_points(frame);
        let flat: Vec<u32> = self.facets.iter().flatten().copied().collect();
        match M {
            2 => {
                let segs: Vec<[u32; 2]> = flat.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
                write_vtp_lines(path, &points, &segs, &data)
            }
            _ => {
                let mut tris: Vec<[u32; 3]> =
                    flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
                if frame.is_mirrored() {
                    tris.iter_mut().for_each(|t| t.swap(1, 2));
                }
                write_vtp(path, &points, &tris, &data)
            }
        }
    }
}

fn ordered(order: &[u8], label: Label) -> i32 {
    order
        .get(label as usize)
        .map_or(label as i32, |&o| o as i32)
}

/// Collects interface facets with corners renumbered densely.
struct Collector<const M: usize> {
    index: Vec<u32>,
    out: Interface<M>,
}

impl<const M: usize> Collector<M> {
    fn new<K: Dim>(c: &Complex<K>) -> Self {
        Collector {
            index: vec![u32::MAX; c.vertex_capacity()],
            out: Interface {
                points: Vec::new(),
                facets: Vec::new(),
                phase: Vec::new(),
                phase_other: Vec::new(),
            },
        }
    }

    /// The dense index of vertex `v` at domain position `p`.
    fn vertex(&mut self, v: usize, p: [f64; 3]) -> u32 {
        if self.index[v] == u32::MAX {
            self.index[v] = self.out.points.len() as u32;
            self.out.points.push(p);
        }
        self.index[v]
    }
}

/// Layer `complex`: the mesh as a VTK file (one writer for both dimensions).
impl<K: Dim> Complex<K> {
    /// Writes the mesh as `.vtu` in `frame` with the cell data `phase`
    /// (`order[label]`; labels beyond `order` are written as they are).
    pub fn write_mesh_vtu(
        &self,
        path: impl AsRef<Path>,
        order: &[u8],
        frame: &Frame,
    ) -> Result<(), IoError> {
        let arrays = self.to_arrays();
        let phase: Vec<i32> = arrays.labels.iter().map(|&l| ordered(order, l)).collect();
        let points: Vec<[f64; 3]> = arrays
            .points
            .iter()
            .map(|&p| frame.domain_to_world(p))
            .collect();
        let mirrored = frame.is_mirrored();
        let (mut tris, mut tets);
        let cells = if K::N == 2 {
            tris = arrays.triangles();
            if mirrored {
                tris.iter_mut().for_each(|t| t.swap(1, 2));
            }
            Cells::Triangles(&tris)
        } else {
            tets = arrays.tetrahedra();
            if mirrored {
                tets.iter_mut().for_each(|t| t.swap(2, 3));
            }
            Cells::Tetrahedra(&tets)
        };
        write_vtu(path, &points, cells, &[("phase", CellArray::I32(&phase))])
    }
}

/// Layer `complex`: the 2D interface as VTK line segments.
impl Complex<D2> {
    /// The interface segments: every edge between two phases, once.
    pub fn interface_lines(&self) -> InterfaceLines {
        let mut col = Collector::<2>::new(self);
        for f in self.interface_facets() {
            let (lo, hi) = (f.a.min(f.b), f.a.max(f.b));
            let seg = [0, 1].map(|k| {
                let p = f.points[k];
                col.vertex(f.corners[k].index(), [p.x, p.y, 0.0])
            });
            col.out.facets.push(seg);
            col.out.phase.push(lo);
            col.out.phase_other.push(hi);
        }
        col.out
    }

    /// Writes the interface segments as `.vtp` in `frame` (see [`Interface`]).
    pub fn write_interface_vtp(
        &self,
        path: impl AsRef<Path>,
        order: &[u8],
        frame: &Frame,
    ) -> Result<(), IoError> {
        self.interface_lines().write(path.as_ref(), order, frame)
    }
}

/// Layer `complex`: the 3D interface as a VTK triangle surface.
impl Complex<D3> {
    /// The interface surface: every facet between two phases, once,
    /// oriented from the lower phase to the higher.
    pub fn interface_surface(&self) -> InterfaceSurface {
        let mut col = Collector::<3>::new(self);
        for f in self.interface_facets() {
            let (lo, hi) = (f.a.min(f.b), f.a.max(f.b));
            let mut tri = [0, 1, 2].map(|k| {
                let p = f.points[k];
                col.vertex(f.corners[k].index(), [p.x, p.y, p.z])
            });
            // The facet's normal points from phase `a` into `b`.
            let towards_higher = if f.a == lo { f.normal } else { -f.normal };
            let [p0, p1, p2] = f.points;
            if (p1 - p0).cross(&(p2 - p0)).dot(&towards_higher) < 0.0 {
                tri.swap(1, 2);
            }
            col.out.facets.push(tri);
            col.out.phase.push(lo);
            col.out.phase_other.push(hi);
        }
        col.out
    }

    /// Writes the interface surface as `.vtp` in `frame` (see [`Interface`]).
    pub fn write_interface_vtp(
        &self,
        path: impl AsRef<Path>,
        order: &[u8],
        frame: &Frame,
    ) -> Result<(), IoError> {
        self.interface_surface().write(path.as_ref(), order, frame)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn ball() -> Complex<D3> {
        let mut c = Complex::cuboid([12.0, 12.0, 12.0], 2.0).unwrap();
        c.label_by(|p| ((p - Vector3::new(6.0, 6.0, 6.0)).norm() < 3.5) as Label);
        c
    }

    #[test]
    fn the_interface_surface_is_closed_and_outward_oriented() {
        let c = ball();
        let s = c.interface_surface();
        assert!(!s.facets.is_empty());
        assert!(s.phase.iter().all(|&p| p == 0) && s.phase_other.iter().all(|&p| p == 1));
        // Oriented from phase 0 (outside) into phase 1: the enclosed signed
        // volume by the divergence theorem is minus the ball's volume.
        let mut vol = 0.0;
        let mut edges = std::collections::HashMap::new();
        for t in &s.facets {
            let [a, b, d] = t.map(|i| Vector3::from(s.points[i as usize]));
            vol += a.dot(&b.cross(&d)) / 6.0;
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        let inside = c.phase_measures()[1];
        assert!((vol + inside).abs() < 1e-9 * inside, "{vol} vs {inside}");
        // Closed and consistently oriented: each directed edge once, its reverse once.
        assert!(edges
            .iter()
            .all(|(&(u, v), &n)| n == 1 && edges.get(&(v, u)) == Some(&1)));
    }

    #[test]
    fn files_are_written() {
        let c = ball();
        let dir = tempfile::tempdir().unwrap();
        let frame = Frame::volume([12, 12, 12], [1.0; 3], "px");
        c.write_mesh_vtu(dir.path().join("mesh.vtu"), &[1, 0], &frame)
            .unwrap();
        c.write_interface_vtp(dir.path().join("interface.vtp"), &[1, 0], &frame)
            .unwrap();
        for name in ["mesh.vtu", "interface.vtp"] {
            let text = std::fs::read_to_string(dir.path().join(name)).unwrap();
            assert!(text.contains("Name=\"phase\""), "{name}");
        }
        let text = std::fs::read_to_string(dir.path().join("interface.vtp")).unwrap();
        assert!(text.contains("Name=\"phase_other\""));
    }
}
