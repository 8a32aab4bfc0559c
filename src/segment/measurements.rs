//! What a finished segmentation measures, in the input's physical units:
//! per phase its pixel/voxel count, area/volume (three estimates, below), mean and standard deviation
//! of the intensity (in the file's units when known) and number of connected
//! pieces; per pair of phases the interface length (2D) or area (3D); and the
//! triple junctions (2D: how many) or junction curves (3D: their length).
//!
//! Three area/volume estimates per phase: the partial-volume estimate
//! ([`partial_volume`](super::partial_volume), the one to use: band pixels
//! count by the fraction their intensity implies, so a blurred edge is
//! measured where its intensity integral puts it, whichever side the
//! segmentation drew it on), the count of labelled pixels/voxels times the
//! pixel/voxel size, and the mesh's.
//!
//! Counts, areas/volumes, intensities and pieces come from the label image
//! (each pixel/voxel counted once); the mesh area/volume of each phase (the
//! exact sum of its cells' measures, in physical units) and the interfaces
//! and junctions from the final mesh mapped into the world frame, so they are
//! lengths and areas in space whatever the voxel shape. The two area/volume
//! figures differ by the pixels/voxels the interface cuts (a fraction of the
//! interface's pixel layer), so they agree closely on any segmentation whose
//! phases are many pixels across.

use crate::complex::{Complex, Label, VertexKind};
use crate::dim::{D2, D3};
use crate::io::intensity::IntensityMap;
use crate::io::Frame;
use crate::segment::partial_volume::{estimates_in_parallel, partial_volume};
use serde::Serialize;
use std::fmt::Write as _;

/// One phase's figures.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PhaseRow {
    /// Output phase (value in the label image).
    pub phase: usize,
    /// Pixels/voxels labelled with it.
    pub count: usize,
    /// Partial-volume area (2D) or volume (3D) in the frame's unit
    /// squared/cubed (see [`partial_volume`](super::partial_volume)).
    pub partial_volume: f64,
    /// Standard error of [`PhaseRow::partial_volume`]: the noise's share and
    /// how far the estimate moves when the labels move by one pixel/voxel.
    pub partial_volume_se: f64,
    /// Area (2D) or volume (3D) in the frame's unit squared/cubed: the
    /// pixels/voxels labelled with it times the pixel area/voxel volume.
    pub count_measure: f64,
    /// Area (2D) or volume (3D) of the phase's mesh cells in the frame's
    /// unit (exact; `None` until [`Measurements::with_mesh_2d`] or
    /// [`with_mesh_3d`](Measurements::with_mesh_3d) adds it).
    pub mesh_measure: Option<f64>,
    /// Mean intensity (`None` for an empty phase).
    pub mean: Option<f64>,
    /// Standard deviation of the intensity (population).
    pub std: Option<f64>,
    /// Connected pieces (4-connected pixels in 2D, 6-connected voxels in 3D).
    pub components: usize,
}

/// The interface between two phases.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InterfaceRow {
    /// The lower output phase.
    pub phase: usize,
    /// The higher output phase.
    pub phase_other: usize,
    /// Length (2D) or area (3D) in the frame's unit.
    pub measure: f64,
}

/// Every figure of a segmentation (see the module documentation).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Measurements {
    /// The length unit (`"px"` when the input gave none).
    pub unit: String,
    /// Whether the intensities are the file's own values (`"file"`) or the
    /// loaded ones in `[0, 1]` (`"normalised"`).
    pub intensity_unit: &'static str,
    /// Per phase, in output order.
    pub phases: Vec<PhaseRow>,
    /// Per pair of phases that touch.
    pub interfaces: Vec<InterfaceRow>,
    /// 2D: mesh vertices where three or more phase pieces meet.
    pub triple_junctions: Option<usize>,
    /// 3D: total length of the junction curves (edges in three or more
    /// interface triangles).
    pub junction_length: Option<f64>,
    /// Where the intensities saturate (see [`Saturation`]).
    pub saturation: Saturation,
}

/// The intensities at which the input saturates (in the units of
/// [`Measurements::intensity_unit`]; `None`: that end does not), found as a
/// pile of pixels/voxels on the extreme value (clipping, or a noise-free
/// phase at the extreme, which needs no correction). The partial-volume
/// estimate corrects its fractions for the clipping there.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Saturation {
    /// The low end, when clipped.
    pub low: Option<f64>,
    /// The high end, when clipped.
    pub high: Option<f64>,
}

impl Measurements {
    /// The per-phase figures of `labels` (values `0..phases`, one per voxel
    /// of `frame`) over the loaded intensities `values`; interfaces and
    /// junctions are added by [`Measurements::with_mesh_2d`]/[`with_mesh_3d`](Measurements::with_mesh_3d).
    pub fn from_labels(
        labels: &[u8],
        values: &[f32],
        intensity: Option<IntensityMap>,
        frame: &Frame,
        phases: usize,
    ) -> Self {
        let map = intensity.unwrap_or(IntensityMap::IDENTITY);
        let mut sum = vec![0.0f64; phases];
        let mut count = vec![0usize; phases];
        for (&l, &v) in labels.iter().zip(values) {
            let l = l as usize;
            if l < phases {
                sum[l] += f64::from(v);
                count[l] += 1;
            }
        }
        let mean: Vec<Option<f64>> = (0..phases)
            .map(|p| (count[p] > 0).then(|| sum[p] / count[p] as f64))
            .collect();
        let mut sq = vec![0.0f64; phases];
        for (&l, &v) in labels.iter().zip(values) {
            if let Some(Some(m)) = mean.get(l as usize) {
                sq[l as usize] += (f64::from(v) - m).powi(2);
            }
        }
        let components = || count_components(labels, frame.dims, phases);
        let pv = || partial_volume(labels, values, frame.dims, phases);
        let (components, pv) = if estimates_in_parallel(frame.dims) {
            rayon::join(components, pv)
        } else {
            (components(), pv())
        };
        let voxel = frame.voxel_measure();
        let rows = (0..phases)
            .map(|p| PhaseRow {
                phase: p,
                count: count[p],
                partial_volume: pv.measure[p] * voxel,
                partial_volume_se: pv.standard_error[p] * voxel,
                count_measure: count[p] as f64 * voxel,
                mesh_measure: None,
                mean: mean[p].map(|m| map.original(m)),
                std: mean[p].map(|_| map.scale().abs() * (sq[p] / count[p] as f64).sqrt()),
                components: components[p],
            })
            .collect();
        Measurements {
            unit: frame.unit.clone(),
            intensity_unit: if intensity.is_some() {
                "file"
            } else {
                "normalised"
            },
            phases: rows,
            interfaces: Vec::new(),
            triple_junctions: None,
            junction_length: None,
            saturation: Saturation {
                low: pv.limits.low.map(|v| map.original(v)),
                high: pv.limits.high.map(|v| map.original(v)),
            },
        }
    }

    /// Adds the interface lengths and the triple junctions of a 2D mesh.
    pub fn with_mesh_2d(mut self, complex: &Complex<D2>, order: &[u8], frame: &Frame) -> Self {
        let lines = complex.interface_lines();
        let points = lines.world_points(frame);
        let sizes = lines
            .facets
            .iter()
            .map(|&[a, b]| distance(points[a as usize], points[b as usize]));
        self.interfaces = per_pair(&lines.phase, &lines.phase_other, sizes, order);
        self.set_mesh_measures(&complex.phase_measures(), order, frame);
        let junctions = complex
            .vertex_ids()
            .filter(|&v| complex.class(v).kind == VertexKind::Junction)
            .count();
        self.triple_junctions = Some(junctions);
        self
    }

    /// Adds the interface areas and the junction-curve length of a 3D mesh.
    pub fn with_mesh_3d(mut self, complex: &Complex<D3>, order: &[u8], frame: &Frame) -> Self {
        let surface = complex.interface_surface();
        let points = surface.world_points(frame);
        let sizes = surface.facets.iter().map(|t| {
            let [a, b, c] = t.map(|i| points[i as usize]);
            let u = sub(b, a);
            let v = sub(c, a);
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            0.5 * distance(n, [0.0; 3])
        });
        self.interfaces = per_pair(&surface.phase, &surface.phase_other, sizes, order);
        self.set_mesh_measures(&complex.phase_measures(), order, frame);
        let world = |v| {
            let p = complex.position(v);
            frame.domain_to_world([p.x, p.y, p.z])
        };
        let length = complex
            .junction_edges()
            .into_iter()
            .map(|(u, v)| distance(world(u), world(v)))
            .fold(0.0, |a, b| a + b);
        self.junction_length = Some(length);
        self
    }

    /// Sets each phase's mesh area/volume from the per-label cell measures
    /// of the mesh (`by_label`, in domain units), mapped to the world's units.
    fn set_mesh_measures(&mut self, by_label: &[f64], order: &[u8], frame: &Frame) {
        let used = if frame.dims[2] > 1 { 3 } else { 2 };
        let domain_voxel: f64 = frame.domain_scale[..used].iter().product();
        let to_world = frame.voxel_measure() / domain_voxel;
        for row in &mut self.phases {
            row.mesh_measure = Some(0.0);
        }
        for (label, &m) in by_label.iter().enumerate() {
            let phase = order.get(label).map_or(label, |&o| o as usize);
            if let Some(row) = self.phases.get_mut(phase) {
                row.mesh_measure = Some(row.mesh_measure.unwrap_or(0.0) + m * to_world);
            }
        }
    }

    /// `phases.csv`: one row per phase, measures in the frame's unit.
    pub fn phases_csv(&self, dimension: usize) -> String {
        let measure = if dimension == 2 { "area" } else { "volume" };
        let unit = format!("{}{dimension}", self.unit);
        let mut out = format!(
            "phase,count,pv_{measure}_{unit},pv_{measure}_se_{unit},count_{measure}_{unit},\
             mesh_{measure}_{unit},mean,std,components\n"
        );
        let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v}"));
        for r in &self.phases {
            let _ = writeln!(
                out,
                "{},{},{},{},{},{},{},{},{}",
                r.phase,
                r.count,
                r.partial_volume,
                r.partial_volume_se,
                r.count_measure,
                opt(r.mesh_measure),
                opt(r.mean),
                opt(r.std),
                r.components
            );
        }
        out
    }

    /// `interfaces.csv`: one row per pair of phases that touch.
    pub fn interfaces_csv(&self, dimension: usize) -> String {
        let measure = if dimension == 2 {
            format!("length_{}", self.unit)
        } else {
            format!("area_{}2", self.unit)
        };
        let mut out = format!("phase,phase_other,{measure}\n");
        for r in &self.interfaces {
            let _ = writeln!(out, "{},{},{}", r.phase, r.phase_other, r.measure);
        }
        out
    }
}

/// Sums `sizes` per unordered pair of output phases.
fn per_pair(
    a: &[Label],
    b: &[Label],
    sizes: impl Iterator<Item = f64>,
    order: &[u8],
) -> Vec<InterfaceRow> {
    let rank = |l: Label| order.get(l as usize).map_or(l as usize, |&o| o as usize);
    let mut pairs: std::collections::BTreeMap<(usize, usize), f64> = Default::default();
    for ((&la, &lb), s) in a.iter().zip(b).zip(sizes) {
        let (p, q) = (rank(la), rank(lb));
        *pairs.entry((p.min(q), p.max(q))).or_default() += s;
    }
    pairs
        .into_iter()
        .map(|((phase, phase_other), measure)| InterfaceRow {
            phase,
            phase_other,
            measure,
        })
        .collect()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = sub(a, b);
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

/// Connected pieces of each label (face neighbours), by union–find.
fn count_components(labels: &[u8], dims: [usize; 3], phases: usize) -> Vec<usize> {
    let [nx, ny, _] = dims;
    let mut parent: Vec<u32> = (0..labels.len() as u32).collect();
    fn find(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            let up = parent[parent[i as usize] as usize];
            parent[i as usize] = up;
            i = up;
        }
        i
    }
    for i in 0..labels.len() {
        let x = i % nx;
        let y = (i / nx) % ny;
        let z = i / (nx * ny);
        let neighbours = [
            (x > 0).then(|| i - 1),
            (y > 0).then(|| i - nx),
            (z > 0).then(|| i - nx * ny),
        ];
        for j in neighbours.into_iter().flatten() {
            if labels[j] == labels[i] {
                let (a, b) = (find(&mut parent, i as u32), find(&mut parent, j as u32));
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut out = vec![0; phases];
    for i in 0..labels.len() {
        if parent[i] == i as u32 && (labels[i] as usize) < phases {
            out[labels[i] as usize] += 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_areas_intensities_and_pieces() {
        // 6×4 image: two 2×2 squares of phase 1 apart, the rest phase 0.
        let mut labels = vec![0u8; 24];
        for &i in &[0, 1, 6, 7, 16, 17, 22, 23] {
            labels[i] = 1;
        }
        let values: Vec<f32> = labels.iter().map(|&l| 0.2 + 0.6 * l as f32).collect();
        let frame = Frame::image_rows_down(6, 4, [0.5, 2.0], "mm");
        let m =
            Measurements::from_labels(&labels, &values, Some(IntensityMap::unsigned(8)), &frame, 2);
        assert_eq!(m.phases[1].count, 8);
        assert_eq!(m.phases[1].count_measure, 8.0);
        // Sharp edges: the partial-volume estimate is the count.
        assert_eq!(m.phases[1].partial_volume, 8.0);
        assert_eq!(m.phases[1].components, 2);
        assert_eq!(m.phases[0].components, 1);
        assert!((m.phases[1].mean.unwrap() - 204.0).abs() < 1e-4);
        assert!(m.phases[1].std.unwrap() < 1e-4);
        // Counted whole, the squares move with their labels: grown or shrunk
        // by a pixel they gain or lose area, which the standard error says.
        assert!(m.phases[1].partial_volume_se > 1.0);
        let csv = m.phases_csv(2);
        assert!(
            csv.starts_with(
                "phase,count,pv_area_mm2,pv_area_se_mm2,count_area_mm2,mesh_area_mm2,mean,std,\
                 components\n0,16,16,"
            ),
            "{csv}"
        );
        let row: Vec<&str> = csv.lines().nth(2).unwrap().split(',').collect();
        assert_eq!(row[..3], ["1", "8", "8"], "{csv}");
        assert_eq!(row[4..6], ["8", ""], "{csv}");
        assert!(row[6].starts_with("204.0000"), "{csv}");
    }

    #[test]
    fn saturation_is_reported_in_the_files_units() {
        // A ramp of 1000 pixels clipped at 0.9 (10 % on it), never at 0.
        let values: Vec<f32> = (0..1000).map(|i| (i as f32 / 999.0).min(0.9)).collect();
        let labels: Vec<u8> = values.iter().map(|&v| u8::from(v > 0.5)).collect();
        let frame = Frame::image_rows_down(1000, 1, [1.0, 1.0], "px");
        let m = Measurements::from_labels(
            &labels,
            &values,
            Some(IntensityMap::unsigned(16)),
            &frame,
            2,
        );
        assert_eq!(m.saturation.low, None);
        let high = m.saturation.high.unwrap();
        assert!((high - 0.9 * 65535.0).abs() < 0.01, "{high}");
    }

    #[test]
    fn components_in_3d_use_face_neighbours() {
        // Two voxels touching only along an edge are two pieces.
        let mut labels = vec![0u8; 8];
        labels[0] = 1; // (0,0,0)
        labels[7] = 1; // (1,1,1)
        assert_eq!(count_components(&labels, [2, 2, 2], 2), vec![1, 2]);
    }
}
