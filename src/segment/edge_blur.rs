//! The blur of the image's edges, estimated from the data along the
//! segmented interfaces.
//!
//! An imaging system spreads an edge between phases `a` and `b` over a few
//! samples: across it the intensity runs `m_a + (m_b − m_a)·Φ(d/σ_b)` for a
//! Gaussian blur of standard deviation `σ_b` (`d` the signed distance from
//! the edge, `Φ` the normal distribution function). Sampled along the unit
//! normal of every interface facet and averaged over many facets, the
//! fraction `(I − m_a)/(m_b − m_a)` shows that profile with the noise
//! averaged out; `σ_b` is the one that fits it best.
//!
//! * Only the odd part of each facet's profile is used,
//!   `(f(d) − f(−d))/2 = Φ(d/σ_b) − ½`: a facet a little off the true edge
//!   shifts the profile, which changes the odd part only to second order.
//! * Only facets with no third phase within the profile's reach on either
//!   side count (measured by [`PhaseDistances`]): elsewhere the profile
//!   runs into that phase's level (junctions, thin layers).
//! * The fit is by least squares over the sampled offsets (half a sample
//!   apart, out to [`PROFILE_REACH`] samples), not by the profile's moments,
//!   which the cut at the reach would bias for wide blurs.
//! * The profile's amplitude is fitted too: the phase means include the
//!   phases' shares of the blurred bands, so they lie inside the plateaus'
//!   levels and the fractions overshoot ½ (with the amplitude fixed at 1
//!   the 64³ phantoms, blurred by 1.5 voxels, gave 1.26–1.40).

use super::censored::normal_cdf;
use super::integrate::PhaseStats;
use super::phase_distance::PhaseDistances;
use super::raster::Raster;
use super::ImageView;
use crate::complex::Complex;
use crate::dim::Point;

/// How far each facet's profile is sampled to either side, in samples
/// (pixels/voxels): a blur of 1.5 samples has reached 99.6 % of its step
/// there.
pub const PROFILE_REACH: f64 = 4.0;

/// Samples per unit of offset along the profile (every half sample).
const STEPS_PER_SAMPLE: usize = 2;

/// The least interface measure (in samples², 2D: samples) the clean facets
/// must cover for an estimate: below it the average profile is still noise.
const LEAST_MEASURE: f64 = 50.0;

/// The average odd profile of the clean interface facets, as offsets (in
/// the mesh's units) and the value `Φ(d/σ_b) − ½` they show.
#[derive(Clone, Debug, Default)]
pub struct EdgeProfile {
    offsets: Vec<f64>,
    sums: Vec<f64>,
    weight: f64,
}

impl EdgeProfile {
    /// Samples every clean interface facet of `complex` (no phase but its
    /// two within `distances`' reach, which should be at least the
    /// profile's, [`PROFILE_REACH`] samples).
    pub fn measure<K: Raster>(
        complex: &Complex<K>,
        image: &ImageView<'_>,
        phases: &PhaseStats,
        distances: &PhaseDistances,
    ) -> Self {
        let step = image.sample_step() / STEPS_PER_SAMPLE as f64;
        let n = (PROFILE_REACH as usize) * STEPS_PER_SAMPLE;
        let mut profile = EdgeProfile {
            offsets: (1..=n).map(|j| j as f64 * step).collect(),
            sums: vec![0.0; n],
            weight: 0.0,
        };
        for facet in complex.interface_facets() {
            let (Some(m_a), Some(m_b)) = (phases.mean_of(facet.a), phases.mean_of(facet.b)) else {
                continue;
            };
            let neighbour = complex.neighbours(facet.cell)[facet.opposite].expect("interface");
            let third_phase_near = (0..phases.mean.len() as u32)
                .filter(|&q| q != facet.a && q != facet.b)
                .any(|q| {
                    distances.to_phase(facet.cell, q).is_some()
                        || distances.to_phase(neighbour, q).is_some()
                });
            if third_phase_near || m_a == m_b {
                continue;
            }
            let mut centre = K::Point::zero();
            for p in &facet.points[..K::N] {
                centre += *p;
            }
            let centre = centre * (1.0 / K::N as f64);
            let fraction =
                |d: f64| (K::sample(image, centre + facet.normal * d) - m_a) / (m_b - m_a);
            for (sum, &d) in profile.sums.iter_mut().zip(&profile.offsets) {
                *sum += facet.measure * 0.5 * (fraction(d) - fraction(-d));
            }
            profile.weight += facet.measure;
        }
        profile
    }

    /// The blur's standard deviation (in the mesh's units) that fits the
    /// profile best; `None` when the clean facets are too few.
    pub fn blur(&self, image: &ImageView<'_>) -> Option<f64> {
        let sample = image.sample_step();
        let unit_measure = sample.powi(image.dims.iter().filter(|&&d| d > 1).count() as i32 - 1);
        if self.weight < LEAST_MEASURE * unit_measure {
            return None;
        }
        Some(golden_section_min(
            |sigma| self.misfit(sigma),
            0.05 * sample,
            PROFILE_REACH * sample,
        ))
    }
}

impl EdgeProfile {
    /// The least-squares misfit of `A·(Φ(d/σ) − ½)` to the profile at
    /// `σ = sigma`, at its best amplitude `A`.
    fn misfit(&self, sigma: f64) -> f64 {
        let shape: Vec<f64> = self
            .offsets
            .iter()
            .map(|&d| normal_cdf(d / sigma) - 0.5)
            .collect();
        let observed = self.sums.iter().map(|s| s / self.weight);
        let (mut sy, mut ss) = (0.0, 0.0);
        for (g, y) in shape.iter().zip(observed.clone()) {
            sy += g * y;
            ss += g * g;
        }
        let amplitude = sy / ss;
        shape
            .iter()
            .zip(observed)
            .map(|(g, y)| (y - amplitude * g).powi(2))
            .sum()
    }
}

/// The minimiser of `f` on `[lo, hi]` (golden-section search, to a
/// thousandth of the interval).
fn golden_section_min(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    let ratio = (5f64.sqrt() - 1.0) / 2.0;
    let tolerance = 1e-3 * (hi - lo);
    let mut x1 = hi - ratio * (hi - lo);
    let mut x2 = lo + ratio * (hi - lo);
    let (mut f1, mut f2) = (f(x1), f(x2));
    while hi - lo > tolerance {
        if f1 <= f2 {
            hi = x2;
            (x2, f2) = (x1, f1);
            x1 = hi - ratio * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            (x1, f1) = (x2, f2);
            x2 = lo + ratio * (hi - lo);
            f2 = f(x2);
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::D3;
    use crate::phantom::blur::gaussian_blur_3d;

    /// Two slabs blurred by a Gaussian of 1.5 voxels and segmented exactly
    /// at their edge: the estimate is that blur.
    #[test]
    fn the_blur_of_a_segmented_edge_is_recovered() {
        let n = 24usize;
        let edge = 12.0;
        let sharp: Vec<f32> = (0..n * n * n)
            .map(|i| {
                if ((i / (n * n)) as f64) + 0.5 < edge {
                    0.2
                } else {
                    0.8
                }
            })
            .collect();
        for blur in [1.0, 1.5, 2.0] {
            let data = gaussian_blur_3d(&sharp, n, n, n, blur);
            let image = ImageView::new_3d([n, n, n], &data).unwrap();
            let mut mesh = Complex::<D3>::cuboid([n as f64; 3], 3.0).unwrap();
            mesh.label_by(|p| u32::from(p.z > edge));
            let mut cells = Vec::new();
            crate::segment::integrate::integrate_cells(&mesh, &image, &mut cells);
            let mut phases = PhaseStats::new(2);
            phases.update(&mesh, &cells);
            // (the plateau means, as a segmentation of the two slabs has)
            phases.mean = vec![Some(0.2), Some(0.8)];
            let mut distances = PhaseDistances::new();
            distances.measure(&mesh, 2, PROFILE_REACH);
            let estimate = EdgeProfile::measure(&mesh, &image, &phases, &distances)
                .blur(&image)
                .expect("enough facets");
            assert!(
                (estimate - blur).abs() < 0.05 * blur,
                "{estimate} for {blur}"
            );
        }
    }
}
