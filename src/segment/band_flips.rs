//! Blurred-band flips: a layer of an intermediate phase that a blurred edge
//! leaves between two other phases is given back to them.
//!
//! A blurred edge between phases `a` and `b` runs through every level in
//! between. Where a phase `p` has its mean between theirs, the band of the
//! edge whose values lie nearest `m_p` is about two samples wide (for a
//! Gaussian blur of 1.5 samples and `m_p` midway), and the piecewise-constant
//! energy pays for labelling it `p`: at levels 0.2/0.5/0.8 the band's data
//! term falls by 0.088 per unit of interface, more than the second interface
//! costs at the 3D length weight (`ν` = 0.054). So a thin layer of `p` forms
//! along the edge, which neither the energy-guarded flips nor the forces
//! remove (they lower that energy), and where its pieces lie is decided by
//! the noise. Under the model of a blurred edge the band is the edge itself
//! and explains the data as well without the layer.
//!
//! A cell of phase `p` is taken for such a band when phases `a` and `b` lie
//! on either side of it in intensity (`m_a < m_p < m_b`) and the layer is
//! thinner there than [`BAND_MARGIN`] times the width of the band a blurred
//! `a|b` edge leaves between the levels of `a` and `b`: the offsets where
//! `m_a + (m_b − m_a)·Φ(d/σ_b)` is nearer a mean between theirs than to
//! either, `σ_b·(Φ⁻¹(hi) − Φ⁻¹(lo))`. The layer's thickness at the cell is
//! the sum of its centroid's distances to `a` and to `b` through `p`
//! ([`PhaseDistances`]), and the blur `σ_b` is estimated from the data
//! ([`EdgeProfile`]). Of several such pairs the widest in intensity is
//! taken (a stack of two intermediate layers along an edge between the
//! darkest and the brightest phase goes back to those two). The cell goes
//! to `a` if its mean is below `(m_a + m_b)/2`, where a blurred `a|b` edge
//! lies, else to `b`, and the forces then place that edge.
//!
//! A layer of `p` that is real but as thin as the band is given away too:
//! under that blur its voxels cannot tell it from the edge (the band of a
//! real layer 1 sample thick is 2.14 samples wide at 1.5 samples of blur,
//! against 2.02 for none; 2.50 at 2 samples thick).
//!
//! Nothing is decided until the interface facets are about `L` in size
//! (their mean area at most [`RESOLVED_FACET_RATIO`] times a regular cell's
//! facet): on a coarse start mesh the interfaces are staircases of large
//! cells, which the edge profile would take for blur.

use super::censored::normal_quantile;
use super::edge_blur::{EdgeProfile, PROFILE_REACH};
use super::image::ImageView;
use super::integrate::{CellStats, PhaseStats};
use super::phase_distance::PhaseDistances;
use super::raster::Raster;
use crate::complex::{CellId, Complex, Label};

/// A layer thinner than this many times the band of a blurred edge is taken
/// for that band. The layers the band leaves are about as thick as the
/// band, but real layers as thin are given away too, so the margin is a
/// compromise: on the 64³ three- and four-phase phantoms (noise seed 1,
/// σ = 0.1 and 0.2) the mean Dice is 0.9510–0.9562 and 0.9200–0.9342
/// without the flips, 0.9744–0.9779 and 0.9474–0.9651 at 0.7 and
/// 0.9784–0.9852 and 0.9617–0.9699 at 1.25; on the brain phantom, whose
/// cerebrospinal fluid and grey matter are real layers that thin in places,
/// 0.9664 without, 0.9658 at 0.85, 0.9646 at 1.0 and 0.9617 at 1.25.
pub const BAND_MARGIN: f64 = 0.7;

/// The interfaces count as resolved once their facets' mean measure is at
/// most this many times a regular cell's facet at `L`.
pub const RESOLVED_FACET_RATIO: f64 = 2.0;

/// Scratch space of the blurred-band flips, kept between iterations.
#[derive(Clone, Debug, Default)]
pub struct BandFlipper {
    distances: PhaseDistances,
    /// The known phase means in increasing order, with their labels.
    order: Vec<(f64, Label)>,
    changes: Vec<(CellId, Label)>,
    /// The blur estimated by the last search, in the mesh's units.
    blur: Option<f64>,
}

/// What a search reads.
pub struct BandInputs<'r, 'a> {
    /// The image.
    pub image: &'r ImageView<'a>,
    /// Per-cell sums, indexed by cell id.
    pub cells: &'r [CellStats],
    /// The phase means.
    pub phases: &'r PhaseStats,
    /// The edge length `L` at the interfaces.
    pub edge_length: f64,
}

impl BandFlipper {
    /// Empty scratch space.
    pub fn new() -> Self {
        Self::default()
    }

    /// Gives every cell of a blurred band back to the phases on its sides;
    /// returns how many cells changed label.
    pub fn flip<K: Raster>(&mut self, complex: &mut Complex<K>, inputs: &BandInputs) -> usize {
        self.find_bands(complex, inputs);
        complex.set_labels(&self.changes);
        self.changes.len()
    }

    /// Whether [`flip`](Self::flip) would relabel a cell; changes no label.
    pub fn would_flip<K: Raster>(&mut self, complex: &Complex<K>, inputs: &BandInputs) -> bool {
        self.find_bands(complex, inputs);
        !self.changes.is_empty()
    }

    /// The edge blur the last search estimated (mesh units), if it got that
    /// far.
    pub fn blur(&self) -> Option<f64> {
        self.blur
    }

    /// Lists in `changes` every band cell with the label it takes.
    fn find_bands<K: Raster>(&mut self, complex: &Complex<K>, inputs: &BandInputs) {
        self.changes.clear();
        self.blur = None;
        self.order.clear();
        for (k, m) in inputs.phases.mean.iter().enumerate() {
            if let Some(m) = *m {
                self.order.push((m, k as Label));
            }
        }
        self.order.sort_by(|x, y| x.0.total_cmp(&y.0));
        if self.order.len() < 3 || !interfaces_resolved(complex, inputs.edge_length) {
            return;
        }
        let reach = PROFILE_REACH * inputs.image.sample_step();
        self.distances
            .measure(complex, inputs.phases.mean.len(), reach);
        let profile = EdgeProfile::measure(complex, inputs.image, inputs.phases, &self.distances);
        let Some(blur) = profile.blur(inputs.image) else {
            return;
        };
        self.blur = Some(blur);
        for c in complex.cell_ids() {
            if let Some(target) = self.band_target(complex, inputs.cells, c, blur) {
                self.changes.push((c, target));
            }
        }
    }

    /// The phase cell `c` goes back to if it lies in a blurred band.
    fn band_target<K: Raster>(
        &self,
        complex: &Complex<K>,
        cells: &[CellStats],
        c: CellId,
        blur: f64,
    ) -> Option<Label> {
        let own = complex.label(c);
        let rank = self.order.iter().position(|&(_, l)| l == own)?;
        let mut widest: Option<(usize, usize)> = None;
        for low in 0..rank {
            let Some(d_low) = self.distances.to_phase(c, self.order[low].1) else {
                continue;
            };
            for high in rank + 1..self.order.len() {
                let Some(d_high) = self.distances.to_phase(c, self.order[high].1) else {
                    continue;
                };
                let thin = d_low + d_high <= BAND_MARGIN * self.band_width(low, high, blur);
                let wider = widest.is_none_or(|(l, h)| {
                    self.order[high].0 - self.order[low].0 > self.order[h].0 - self.order[l].0
                });
                if thin && wider {
                    widest = Some((low, high));
                }
            }
        }
        let (low, high) = widest?;
        let ((m_low, l_low), (m_high, l_high)) = (self.order[low], self.order[high]);
        let below_edge = match cells[c.index()].mean() {
            Some(mean) => mean < 0.5 * (m_low + m_high),
            None => self.distances.to_phase(c, l_low) <= self.distances.to_phase(c, l_high),
        };
        Some(if below_edge { l_low } else { l_high })
    }

    /// Width of the band of a blurred edge between the phases of ranks
    /// `low` and `high` whose values are nearer a mean between theirs.
    fn band_width(&self, low: usize, high: usize, blur: f64) -> f64 {
        let (m_low, m_high) = (self.order[low].0, self.order[high].0);
        let fraction = |m: f64| (m - m_low) / (m_high - m_low);
        let lo = fraction(0.5 * (m_low + self.order[low + 1].0));
        let hi = fraction(0.5 * (self.order[high - 1].0 + m_high));
        blur * (normal_quantile(hi) - normal_quantile(lo))
    }
}

/// Whether the interface facets are about `edge_length` in size (see
/// [`RESOLVED_FACET_RATIO`]).
fn interfaces_resolved<K: Raster>(complex: &Complex<K>, edge_length: f64) -> bool {
    let (mut total, mut count) = (0.0, 0usize);
    for facet in complex.interface_facets() {
        total += facet.measure;
        count += 1;
    }
    // A regular cell's facet: an edge (2D) or an equilateral triangle (3D).
    let regular = if K::N == 2 {
        edge_length
    } else {
        3f64.sqrt() / 4.0 * edge_length * edge_length
    };
    count > 0 && total / (count as f64) <= RESOLVED_FACET_RATIO * regular
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::D3;
    use crate::phantom::blur::gaussian_blur_3d;
    use crate::segment::integrate::integrate_cells;
    use nalgebra::Vector3;

    const N: usize = 24;
    /// The edge length of a Kuhn mesh on a grid of unit spacing, whose
    /// facets lie on the planes of whole voxels.
    const UNIT_GRID: f64 = 1.24;

    /// A `N³` volume of the levels `level(point)` blurred by 1.5 voxels.
    fn blurred(level: impl Fn(Vector3<f64>) -> f32) -> Vec<f32> {
        let sharp: Vec<f32> = (0..N * N * N)
            .map(|i| {
                let (x, y, z) = (i % N, (i / N) % N, i / (N * N));
                level(Vector3::new(x as f64, y as f64, z as f64).add_scalar(0.5))
            })
            .collect();
        gaussian_blur_3d(&sharp, N, N, N, 1.5)
    }

    /// The band flipper's changes on a mesh of unit grid labelled by `label`.
    fn band_changes(data: &[f32], label: impl Fn(Vector3<f64>) -> Label) -> Vec<(CellId, Label)> {
        let image = ImageView::new_3d([N; 3], data).unwrap();
        let mut mesh = Complex::<D3>::cuboid([N as f64; 3], UNIT_GRID).unwrap();
        mesh.label_by(label);
        let mut cells = Vec::new();
        integrate_cells(&mesh, &image, &mut cells);
        let mut phases = PhaseStats::new(3);
        phases.update(&mesh, &cells);
        let inputs = BandInputs {
            image: &image,
            cells: &cells,
            phases: &phases,
            edge_length: UNIT_GRID,
        };
        let mut flipper = BandFlipper::new();
        let would = flipper.would_flip(&mesh, &inputs);
        let changes = flipper.flip(&mut mesh, &inputs);
        assert_eq!(would, changes > 0);
        let blur = flipper.blur().expect("clean edges to measure the blur on");
        assert!((blur - 1.5).abs() < 0.25, "blur {blur}");
        flipper.changes.clone()
    }

    /// A blurred edge between levels 0.2 and 0.8 at z = 12, labelled with a
    /// one-voxel layer of the middle phase just above it where x > 12: the
    /// layer goes back to the two sides, its cells that hold voxels (all
    /// brighter than the edge's midpoint) to phase 2.
    #[test]
    fn a_layer_along_a_blurred_edge_goes_back_to_its_sides() {
        let data = blurred(|p| if p.z < 12.0 { 0.2 } else { 0.8 });
        let label = |p: Vector3<f64>| match p.z {
            z if p.x > 12.0 && (12.0..13.0).contains(&z) => 1,
            z if z < 12.0 => 0,
            _ => 2,
        };
        let changes = band_changes(&data, label);
        let mut mesh = Complex::<D3>::cuboid([N as f64; 3], UNIT_GRID).unwrap();
        mesh.label_by(label);
        let layer = mesh.cell_ids().filter(|&c| mesh.label(c) == 1).count();
        assert!(layer > 0, "the premise: a layer");
        assert_eq!(changes.len(), layer, "every layer cell changes");
        let (image, cells) = (ImageView::new_3d([N; 3], &data).unwrap(), &mut Vec::new());
        integrate_cells(&mesh, &image, cells);
        for (c, to) in changes {
            if cells[c.index()].count > 0 {
                assert_eq!(to, 2, "cell {c:?}");
            }
        }
    }

    /// A real layer of the middle level, six voxels thick, between the
    /// other two: nothing changes.
    #[test]
    fn a_layer_thicker_than_the_blur_stays() {
        let level = |z: f64| match z {
            z if z < 9.0 => 0,
            z if z < 15.0 => 1,
            _ => 2,
        };
        let data = blurred(|p| [0.2, 0.5, 0.8][level(p.z)]);
        assert!(band_changes(&data, |p| level(p.z) as Label).is_empty());
    }
}
