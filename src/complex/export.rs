//! Plain arrays of a complex, for writers and renderers that know nothing of the mesh types.

use super::{Complex, Label};
use crate::dim::Dim;

/// Dense copies of the live vertices, cells and labels, renumbered `0..n`.
#[derive(Clone, Debug, Default)]
pub struct MeshArrays {
    /// Vertex positions padded to 3D (z = 0 in 2D), ready for VTK.
    pub points: Vec<[f64; 3]>,
    /// Cell connectivity, `N + 1` vertex indices per cell, flattened.
    pub connectivity: Vec<u32>,
    /// Phase label per cell.
    pub labels: Vec<Label>,
}

/// Layer `complex`: export as plain arrays.
impl<K: Dim> Complex<K> {
    /// Copies the live part of the complex into dense arrays (ids renumbered in order).
    pub fn to_arrays(&self) -> MeshArrays {
        let mut index = vec![u32::MAX; self.vertex_capacity()];
        let mut out = MeshArrays::default();
        for v in self.vertex_ids() {
            index[v.index()] = out.points.len() as u32;
            let p = self.position(v);
            let mut q = [0.0; 3];
            for (axis, x) in q.iter_mut().enumerate().take(K::N) {
                *x = p[axis];
            }
            out.points.push(q);
        }
        for c in self.cell_ids() {
            out.connectivity
                .extend(self.cell(c).iter().map(|v| index[v.index()]));
            out.labels.push(self.label(c));
        }
        out
    }
}

impl MeshArrays {
    /// The 2D points (dropping z).
    pub fn points_2d(&self) -> Vec<[f64; 2]> {
        self.points.iter().map(|p| [p[0], p[1]]).collect()
    }
    /// The cells as triangles (2D complexes only).
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        self.connectivity
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect()
    }
    /// The cells as tetrahedra (3D complexes only).
    pub fn tetrahedra(&self) -> Vec<[u32; 4]> {
        self.connectivity
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect()
    }
}
