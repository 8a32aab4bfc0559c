//! The paper's region forces on a tetrahedral complex over a voxel volume:
//! per-phase means by exact voxel ownership, eq. (6) integrated over the
//! interface triangles by quadrature, eq. (7) at distinct-phase junctions
//! (points of junction curves), the surface-area regulariser, and the
//! voxel-dominant label flip.
//!
//! Voxel convention as in [`voxel3d`](super::voxel3d): voxel `(i, j, k)` has
//! its centre at `(i + ½, j + ½, k + ½)`; data are x-fastest.

use super::voxel3d::{tet_voxels, triangle_quadrature};
use crate::complex::{CellId, Complex, Label, PhaseContact, VertexId};
use crate::dim::{Dim, D3};
use nalgebra::Vector3;
use rayon::prelude::*;

/// A grayscale volume borrowed as a flat x-fastest slice.
#[derive(Clone, Copy, Debug)]
pub struct VoxelGrid<'a> {
    data: &'a [f32],
    dims: [usize; 3],
}

impl<'a> VoxelGrid<'a> {
    /// Wraps `data` of `dims[0]·dims[1]·dims[2]` voxels; `None` if the sizes disagree or a dimension is 0.
    pub fn new(data: &'a [f32], dims: [usize; 3]) -> Option<Self> {
        (dims.iter().all(|&d| d > 0) && data.len() == dims[0] * dims[1] * dims[2])
            .then_some(VoxelGrid { data, dims })
    }
    /// Grid size in voxels.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }
    /// Value of voxel `(i, j, k)`.
    #[inline]
    pub fn at(&self, i: usize, j: usize, k: usize) -> f64 {
        self.data[i + self.dims[0] * (j + self.dims[1] * k)] as f64
    }
    /// Trilinear interpolation between voxel centres, clamped at the border.
    pub fn sample(&self, p: Vector3<f64>) -> f64 {
        let mut i0 = [0usize; 3];
        let mut i1 = [0usize; 3];
        let mut t = [0.0; 3];
        for axis in 0..3 {
            let n = self.dims[axis];
            let x = (p[axis] - 0.5).clamp(0.0, (n - 1) as f64);
            let f = x.floor();
            i0[axis] = f as usize;
            i1[axis] = (i0[axis] + 1).min(n - 1);
            t[axis] = x - f;
        }
        let mut out = 0.0;
        for corner in 0..8 {
            let pick = |axis: usize| corner >> axis & 1 == 1;
            let mut w = 1.0;
            let mut idx = [0usize; 3];
            for axis in 0..3 {
                if pick(axis) {
                    w *= t[axis];
                    idx[axis] = i1[axis];
                } else {
                    w *= 1.0 - t[axis];
                    idx[axis] = i0[axis];
                }
            }
            if w != 0.0 {
                out += w * self.at(idx[0], idx[1], idx[2]);
            }
        }
        out
    }
}

/// Force per unit area of eq. (6) for intensity `i` on an interface from phase
/// mean `mi` towards phase mean `mj` (positive: phase `i` expands). Zero when
/// the two means coincide.
pub fn normalised_force(i: f64, mi: f64, mj: f64) -> f64 {
    let d = mi - mj;
    if d.abs() < 1e-12 {
        0.0
    } else {
        (2.0 * i - mi - mj) / d
    }
}

/// Eq. (7) at a junction where the distinct `phases` meet with outward normals
/// `normals` (same order): of the phases whose means bracket `i`, each
/// contributes its normal weighted linearly in `i`; outside the range of the
/// means the nearest phase alone expands.
pub fn junction_force(i: f64, phases: &[(Label, Vector3<f64>)], means: &[f64]) -> Vector3<f64> {
    let mut below: Option<(f64, Vector3<f64>)> = None;
    let mut above: Option<(f64, Vector3<f64>)> = None;
    for &(label, n) in phases {
        let m = means[label as usize];
        if m <= i && below.is_none_or(|(b, _)| m > b) {
            below = Some((m, n));
        }
        if m > i && above.is_none_or(|(a, _)| m < a) {
            above = Some((m, n));
        }
    }
    match (below, above) {
        (Some((m1, n1)), Some((m2, n2))) => {
            n1 * ((m2 - i) / (m2 - m1)) + n2 * ((i - m1) / (m2 - m1))
        }
        (Some((_, n)), None) | (None, Some((_, n))) => n,
        (None, None) => Vector3::zeros(),
    }
}

/// Per-cell voxel statistics: `(sum of intensities, voxel count)`.
pub type CellSums = Vec<(f64, usize)>;

impl Complex<D3> {
    /// Sum and count of the voxels each cell owns (indexed by cell id; dead
    /// cells get zeros). Every voxel is counted exactly once over the complex.
    pub fn cell_sums(&self, grid: &VoxelGrid) -> CellSums {
        let ids: Vec<CellId> = self.cell_ids().collect();
        let stats: Vec<(CellId, f64, usize)> = ids
            .par_iter()
            .map(|&c| {
                let (mut sum, mut n) = (0.0, 0usize);
                tet_voxels(&self.cell_points(c), grid.dims(), |i, j, k| {
                    sum += grid.at(i, j, k);
                    n += 1;
                });
                (c, sum, n)
            })
            .collect();
        let mut out = vec![(0.0, 0); self.cell_capacity()];
        for (c, s, n) in stats {
            out[c.index()] = (s, n);
        }
        out
    }

    /// Mean intensity of every phase (indexed by label; `NaN` for a phase
    /// that owns no voxel).
    pub fn phase_means(&self, grid: &VoxelGrid) -> Vec<f64> {
        let sums = self.cell_sums(grid);
        let mut acc = vec![(0.0, 0usize); self.label_count()];
        for c in self.cell_ids() {
            let (s, n) = sums[c.index()];
            let e = &mut acc[self.label(c) as usize];
            e.0 += s;
            e.1 += n;
        }
        acc.iter()
            .map(|&(s, n)| if n == 0 { f64::NAN } else { s / n as f64 })
            .collect()
    }

    /// The region force at every interface vertex (indexed by vertex id):
    /// eq. (6) integrated over each interface triangle with about one sample per
    /// voxel (`spacing` in voxels), normal from the cell's phase to its
    /// neighbour's, distributed by barycentric weights and divided by the
    /// vertex's area share (a force per unit area). At distinct-phase junctions
    /// eq. (7) replaces it (intensity sampled at the vertex); repeated-phase
    /// junctions get no force.
    pub fn region_forces(
        &self,
        grid: &VoxelGrid,
        means: &[f64],
        spacing: f64,
    ) -> Vec<Vector3<f64>> {
        let n = self.vertex_capacity();
        let mut force = vec![Vector3::zeros(); n];
        let mut share = vec![0.0; n];
        for c in self.cell_ids() {
            let cell = self.cell(c);
            let pts = self.cell_points(c);
            let li = self.label(c);
            for (f, nb) in self.neighbours(c).iter().enumerate() {
                let Some(nb) = *nb else { continue };
                let lj = self.label(nb);
                // Each interface triangle once, from its lower-label side.
                if lj == li || li > lj {
                    continue;
                }
                let (mi, mj) = (means[li as usize], means[lj as usize]);
                if !(mi.is_finite() && mj.is_finite()) {
                    continue;
                }
                let normal = D3::facet_normal(&pts[..], f);
                let corners: Vec<usize> = (0..4).filter(|&k| k != f).collect();
                let tri = [pts[corners[0]], pts[corners[1]], pts[corners[2]]];
                let mut acc = [0.0; 3];
                let mut area = [0.0; 3];
                triangle_quadrature(&tri, spacing, |s| {
                    let value = normalised_force(grid.sample(s.position), mi, mj);
                    for k in 0..3 {
                        acc[k] += s.weight * s.barycentric[k] * value;
                        area[k] += s.weight * s.barycentric[k];
                    }
                });
                for k in 0..3 {
                    let v = cell[corners[k]];
                    force[v.index()] += normal * acc[k];
                    share[v.index()] += area[k];
                }
            }
        }
        let mut normals = Vec::new();
        for v in self.vertex_ids() {
            let i = v.index();
            if share[i] > 0.0 {
                force[i] /= share[i];
            }
            match self.phase_contact(v) {
                PhaseContact::Distinct(_) => {
                    self.phase_normals(v, &mut normals);
                    force[i] = junction_force(grid.sample(self.position(v)), &normals, means);
                }
                PhaseContact::Repeated => force[i] = Vector3::zeros(),
                _ => {}
            }
        }
        force
    }

    /// Gradient of the interface area with respect to the position of `v`
    /// (sum over the interface triangles at `v`); `−gradient` is the
    /// mean-curvature (surface-area) regularising force.
    pub fn interface_area_gradient(&self, v: VertexId) -> Vector3<f64> {
        let mut star = Vec::new();
        self.star_into(v, &mut star);
        let mut g = Vector3::zeros();
        for &c in &star {
            let cell = self.cell(c);
            let pts = self.cell_points(c);
            let li = self.label(c);
            for (f, nb) in self.neighbours(c).iter().enumerate() {
                let Some(nb) = *nb else { continue };
                if cell[f] == v || self.label(nb) <= li {
                    continue; // each interface triangle once
                }
                let others: Vec<Vector3<f64>> = (0..4)
                    .filter(|&k| k != f && cell[k] != v)
                    .map(|k| pts[k])
                    .collect();
                let p = self.position(v);
                let (a, b) = (others[0], others[1]);
                // d|T|/dp = ½ |ab| · (unit vector in the plane, perpendicular to ab, towards p).
                let ab = b - a;
                let ap = p - a;
                let h = ap - ab * (ap.dot(&ab) / ab.norm_squared());
                let hn = h.norm();
                if hn > 0.0 {
                    g += h * (0.5 * ab.norm() / hn);
                }
            }
        }
        g
    }

    /// The voxel-dominant label flip (the paper's multiphase rule): each voxel
    /// votes for the phase with the nearest mean, and a cell whose dominant
    /// phase differs from its label is returned with that phase. Phases with
    /// undefined (NaN) means get no votes; cells owning no voxel are left alone.
    pub fn dominant_phase_changes(&self, grid: &VoxelGrid, means: &[f64]) -> Vec<(CellId, Label)> {
        let ids: Vec<CellId> = self.cell_ids().collect();
        ids.par_iter()
            .filter_map(|&c| {
                let mut votes = vec![0usize; means.len()];
                tet_voxels(&self.cell_points(c), grid.dims(), |i, j, k| {
                    let x = grid.at(i, j, k);
                    let nearest = means
                        .iter()
                        .enumerate()
                        .filter(|(_, m)| m.is_finite())
                        .min_by(|a, b| (x - a.1).abs().total_cmp(&(x - b.1).abs()))
                        .map(|(l, _)| l);
                    if let Some(l) = nearest {
                        votes[l] += 1;
                    }
                });
                let current = self.label(c) as usize;
                let (best, &count) = votes
                    .iter()
                    .enumerate()
                    .max_by_key(|&(l, &n)| (n, l == current))?;
                (count > 0 && best != current && count > votes[current])
                    .then_some((c, best as Label))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 16³ volume: intensity 1 inside a ball of radius 5 at the centre, 0 outside.
    fn ball_volume() -> (Vec<f32>, [usize; 3]) {
        let n = 16;
        let mut data = vec![0f32; n * n * n];
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let p = Vector3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5);
                    if (p - Vector3::new(8.0, 8.0, 8.0)).norm() < 5.0 {
                        data[i + n * (j + n * k)] = 1.0;
                    }
                }
            }
        }
        (data, [n, n, n])
    }

    #[test]
    fn trilinear_sampling_hits_voxel_values_at_centres() {
        let data: Vec<f32> = (0..24).map(|x| x as f32).collect();
        let g = VoxelGrid::new(&data, [2, 3, 4]).unwrap();
        assert_eq!(g.sample(Vector3::new(1.5, 2.5, 3.5)), 23.0);
        assert_eq!(g.sample(Vector3::new(1.0, 0.5, 0.5)), 0.5);
        assert!(VoxelGrid::new(&data, [2, 3, 5]).is_none());
    }

    #[test]
    fn every_voxel_is_counted_once_in_the_means() {
        let (data, dims) = ball_volume();
        let g = VoxelGrid::new(&data, dims).unwrap();
        let mut c = Complex::cuboid([16.0, 16.0, 16.0], 3.0).unwrap();
        c.label_by(|p| ((p - Vector3::new(8.0, 8.0, 8.0)).norm() < 5.0) as Label);
        let sums = c.cell_sums(&g);
        let total: usize = sums.iter().map(|s| s.1).sum();
        assert_eq!(total, 16 * 16 * 16);
        let sum: f64 = sums.iter().map(|s| s.0).sum();
        let expected: f64 = data.iter().map(|&x| x as f64).sum();
        assert!((sum - expected).abs() < 1e-9);
        let means = c.phase_means(&g);
        assert!(means[0] < 0.2 && means[1] > 0.8, "{means:?}");
    }

    #[test]
    fn region_forces_push_a_small_ball_outwards() {
        // The labelled ball (radius 3) is smaller than the bright ball (radius 5):
        // with means 0 outside and 1 inside, the interface must move outwards.
        let (data, dims) = ball_volume();
        let g = VoxelGrid::new(&data, dims).unwrap();
        let centre = Vector3::new(8.0, 8.0, 8.0);
        let mut c = Complex::cuboid([16.0, 16.0, 16.0], 2.0).unwrap();
        c.label_by(|p| ((p - centre).norm() < 3.0) as Label);
        let f = c.region_forces(&g, &[0.0, 1.0], 1.0);
        // On the staircase surface the vertex normals scatter around the radial
        // direction: every force points outwards, and on average clearly so.
        let (mut n, mut mean) = (0, 0.0);
        for v in c.vertex_ids() {
            if c.class(v).on_interface() {
                let out = (c.position(v) - centre).normalize();
                let radial = f[v.index()].dot(&out);
                assert!(radial > 0.0, "force {:?}", f[v.index()]);
                assert!(f[v.index()].norm() <= 1.0 + 1e-9);
                mean += radial;
                n += 1;
            }
        }
        assert!(n > 10);
        assert!(
            mean / n as f64 > 0.5,
            "mean outward force {}",
            mean / n as f64
        );
        // And the area gradient points outwards too (the regulariser shrinks it).
        let v = c.vertex_ids().find(|&v| c.class(v).on_interface()).unwrap();
        let out = c.position(v) - centre;
        assert!(c.interface_area_gradient(v).dot(&out) > 0.0);
    }

    #[test]
    fn junction_force_weights_the_bracketing_phases() {
        let x = Vector3::new(1.0, 0.0, 0.0);
        let y = Vector3::new(0.0, 1.0, 0.0);
        let z = Vector3::new(0.0, 0.0, 1.0);
        let means = [0.0, 0.5, 1.0];
        let phases = [(0, x), (1, y), (2, z)];
        let f = junction_force(0.25, &phases, &means);
        assert!((f - (x * 0.5 + y * 0.5)).norm() < 1e-12);
        assert!((junction_force(1.0, &phases, &means) - z).norm() < 1e-12);
        assert!((junction_force(-1.0, &phases, &means) - x).norm() < 1e-12);
    }

    #[test]
    fn dominant_rule_relabels_cells_inside_the_bright_ball() {
        let (data, dims) = ball_volume();
        let g = VoxelGrid::new(&data, dims).unwrap();
        let c = Complex::cuboid([16.0, 16.0, 16.0], 3.0).unwrap();
        let changes = c.dominant_phase_changes(&g, &[0.0, 1.0]);
        assert!(!changes.is_empty());
        for (cell, label) in changes {
            assert_eq!(label, 1);
            let p = c.cell_points(cell);
            let centroid = (p[0] + p[1] + p[2] + p[3]) / 4.0;
            assert!((centroid - Vector3::new(8.0, 8.0, 8.0)).norm() < 6.5);
        }
    }
}
