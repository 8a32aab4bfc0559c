//! A 3D complex as VTK files: the tetrahedral mesh (`mesh.vtu`, cell data
//! `phase`) and the interface surface (`interface.vtp`, cell data `phase` and
//! `phase_other`: the phases on the two sides of each triangle, `phase` the
//! lower mesh label, the triangle oriented with its normal pointing from
//! `phase` to `phase_other`). Phases are written through an `order` map (mesh
//! label → output index, e.g. the driver's phases by increasing mean).

use crate::complex::{Complex, Label};
use crate::dim::{Dim, D3};
use crate::io::{write_vtp, write_vtu, CellArray, Cells, IoError};
use std::path::Path;

/// The interface triangles of a 3D complex as plain arrays.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InterfaceSurface {
    /// Vertex positions (only the interface vertices, renumbered).
    pub points: Vec<[f64; 3]>,
    /// Triangles, oriented with the normal from `phase` to `phase_other`.
    pub triangles: Vec<[u32; 3]>,
    /// The lower phase of each triangle.
    pub phase: Vec<Label>,
    /// The higher phase of each triangle.
    pub phase_other: Vec<Label>,
}

fn ordered(order: &[u8], label: Label) -> i32 {
    order
        .get(label as usize)
        .map_or(label as i32, |&o| o as i32)
}

impl Complex<D3> {
    /// The interface surface: every facet between two phases, once.
    pub fn interface_surface(&self) -> InterfaceSurface {
        let mut index = vec![u32::MAX; self.vertex_capacity()];
        let mut out = InterfaceSurface::default();
        for c in self.cell_ids() {
            let li = self.label(c);
            let cell = self.cell(c);
            let pts = self.cell_points(c);
            for (f, nb) in self.neighbours(c).iter().enumerate() {
                let Some(nb) = *nb else { continue };
                let lj = self.label(nb);
                if lj <= li {
                    continue;
                }
                let mut tri = [0u32; 3];
                let corners: Vec<usize> = (0..4).filter(|&k| k != f).collect();
                for (slot, &k) in tri.iter_mut().zip(&corners) {
                    let v = cell[k];
                    if index[v.index()] == u32::MAX {
                        index[v.index()] = out.points.len() as u32;
                        let p = self.position(v);
                        out.points.push([p.x, p.y, p.z]);
                    }
                    *slot = index[v.index()];
                }
                // Orient the triangle so that its normal leaves `c` (phase li -> lj).
                let (a, b, d) = (pts[corners[0]], pts[corners[1]], pts[corners[2]]);
                let n = (b - a).cross(&(d - a));
                if n.dot(&(D3::facet_normal(&pts[..], f))) < 0.0 {
                    tri.swap(1, 2);
                }
                out.triangles.push(tri);
                out.phase.push(li);
                out.phase_other.push(lj);
            }
        }
        out
    }

    /// Writes the tetrahedral mesh as `.vtu` with the cell data `phase`
    /// (`order[label]`; labels beyond `order` are written as they are).
    pub fn write_mesh_vtu(&self, path: impl AsRef<Path>, order: &[u8]) -> Result<(), IoError> {
        let arrays = self.to_arrays();
        let phase: Vec<i32> = arrays.labels.iter().map(|&l| ordered(order, l)).collect();
        write_vtu(
            path,
            &arrays.points,
            Cells::Tetrahedra(&arrays.tetrahedra()),
            &[("phase", CellArray::I32(&phase))],
        )
    }

    /// Writes the interface surface as `.vtp` with the cell data `phase` and
    /// `phase_other` (see [`InterfaceSurface`]);
    /// (`order[label]` as for [`write_mesh_vtu`](Self::write_mesh_vtu)).
    pub fn write_interface_vtp(&self, path: impl AsRef<Path>, order: &[u8]) -> Result<(), IoError> {
        let s = self.interface_surface();
        let phase: Vec<i32> = s.phase.iter().map(|&l| ordered(order, l)).collect();
        let other: Vec<i32> = s.phase_other.iter().map(|&l| ordered(order, l)).collect();
        write_vtp(
            path,
            &s.points,
            &s.triangles,
            &[
                ("phase", CellArray::I32(&phase)),
                ("phase_other", CellArray::I32(&other)),
            ],
        )
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
        assert!(!s.triangles.is_empty());
        assert!(s.phase.iter().all(|&p| p == 0) && s.phase_other.iter().all(|&p| p == 1));
        // Oriented from phase 0 (outside) into phase 1: the enclosed signed
        // volume by the divergence theorem is minus the ball's volume.
        let mut vol = 0.0;
        let mut edges = std::collections::HashMap::new();
        for t in &s.triangles {
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
        c.write_mesh_vtu(dir.path().join("mesh.vtu"), &[1, 0])
            .unwrap();
        c.write_interface_vtp(dir.path().join("interface.vtp"), &[1, 0])
            .unwrap();
        for name in ["mesh.vtu", "interface.vtp"] {
            let text = std::fs::read_to_string(dir.path().join(name)).unwrap();
            assert!(text.contains("Name=\"phase\""), "{name}");
        }
        let text = std::fs::read_to_string(dir.path().join("interface.vtp")).unwrap();
        assert!(text.contains("Name=\"phase_other\""));
    }
}
