//! Partial-volume area/volume of each phase: an estimate of how much of the
//! image each phase fills that does not depend on where the segmentation
//! drew the interface within the blurred edge.
//!
//! An imaging system blurs an edge over a few pixels/voxels, and blurring
//! keeps the integral of the intensity. A pixel near the interface between
//! phases `a` and `b` whose intensity is `v` therefore holds the fraction
//! `f = (v − μ_b) / (μ_a − μ_b)` of phase `a` (and `1 − f` of `b`), where
//! `μ_a`, `μ_b` are the phases' plateau intensities. Summed over a band
//! around the interface these fractions give the area each phase truly
//! covers there, unbiased for any edge blur the band contains and for
//! zero-mean noise (the fractions are not clipped to `[0, 1]`, so the noise
//! averages out instead of being folded to one side). Pixels away from any
//! interface count whole for their label.
//!
//! * **Band.** A pixel/voxel is in the band when another label lies within
//!   [`BAND_HALF_WIDTH`] pixels/voxels of it (a cube/square window); the
//!   band thus reaches that far on both sides of the segmented interface,
//!   twice the standard deviation of a 1.5-pixel Gaussian blur.
//!
//!   Why that width: for a straight edge blurred by a Gaussian of standard
//!   deviation `σ_b`, a band reaching `w` pixels to both sides of an
//!   interface drawn `s` pixels off the true edge misses `2·s·Q(w/σ_b)`
//!   pixels per pixel of edge length (to first order in `s`; `Q` the normal
//!   tail), while the noise adds `2·w·(σ/Δ)²` to the variance per pixel of
//!   length (`σ` the noise, `Δ` the contrast). At `σ_b` = 1.5 the band misses
//!   50 % of the labels' offset at `w` = 1, 18 % at 2, 4.6 % at 3 and 0.8 % at
//!   4, so 3 is the narrowest band that is nearly independent of where the
//!   labels put the edge. A narrower band would not buy much either: the
//!   Cramér–Rao bound on an edge's position under that blur, from the
//!   intensities alone, is `2·√π·σ_b·(σ/Δ)²` ≈ `5.3·(σ/Δ)²` per pixel of
//!   length against the band's `6·(σ/Δ)²`, 6 % in standard deviation. A phase
//!   whose interface is `P` pixels long (3D: `P` voxel faces in area) is
//!   therefore uncertain by at least about `√(5.3·P)·σ/Δ` pixels/voxels
//!   whatever the estimator, unless it trusts the labels, whose errors come
//!   from the same noise.
//! * **Plateaus.** `μ_p` is the mean intensity of phase `p`'s deepest pixels:
//!   those with no other label within [`PLATEAU_DEPTH`] pixels, together with
//!   shallower layers, deepest first, until they hold [`PLATEAU_SAMPLES`]
//!   pixels (a thin phase's centre), never inside the band. A phase with
//!   no pixel beyond the band has no plateau.
//! * **Fallback to the count.** Where the window holds three or more phases
//!   (junctions, slivers), where one of the two phases has no plateau, or
//!   where the two plateaus coincide, the pixel counts whole for its label.
//! * **Saturation.** Where the data are clipped at the ends of their range
//!   (an 8-bit photograph at 0 and 255, a CT at −1024 HU, the benchmark
//!   phantoms at 0 and 1: [`Limits`]), a pixel holding the fraction `f` of
//!   `a`, whose unclipped intensity is `μ(f) = μ_b + f·(μ_a − μ_b)` plus
//!   noise of standard deviation `σ`, has the expectation `g(μ(f))`, with
//!   `g(μ) = E[clip(μ + σZ)]` (see [`censored`](super::censored)); the
//!   plateaus are `g(μ_a)` and `g(μ_b)`. Within about two `σ` of a limit `g`
//!   bends, so the linear fraction's expectation is `f + c(f)/(g(μ_a) −
//!   g(μ_b))`, where `c(f) = g(μ(f)) − [(1 − f)·g(μ_b) + f·g(μ_a)]` is `g`'s
//!   departure from its chord. Every band pixel between the two phases then
//!   carries the same sign of error: at levels 0.6/0.8 and `σ` = 0.2 under a
//!   limit at 1, `c(½)` = 0.0033 against a contrast of 0.185, about 0.05
//!   pixel per pixel of interface length (0.3 % of a phase of the 256²
//!   four-phase benchmark image). The estimate subtracts `c(f̃)` from each
//!   band pixel's intensity before taking its fraction, so that the
//!   expectation is the straight line again: `μ_a`, `μ_b` and the noise's
//!   `σ` per phase come from the maximum-likelihood fit of a Gaussian
//!   censored at the limits to the plateau pixels (a pixel on a limit says
//!   only that its unclipped value lies beyond it); `f̃` is the fraction at
//!   which `g` equals the mean of the pixel's 3×3(×3) window (the noise
//!   `σ` interpolated between the two phases'). The window mean is enough:
//!   `c` is small and smooth (at the levels above its slope along `g` is
//!   at most a tenth), so the window's noise (`σ/3`) and the blur's
//!   curvature across three pixels move the correction little, and the
//!   pixel's own noise enters it only through a ninth of the window. In the unit test below
//!   (stripes at 0.6/0.8, `σ` = 0.2, the same noise clipped and unclipped)
//!   clipping adds 0.052 pixel per pixel of interface to the brighter phase
//!   and the corrected estimate is within 4 % of that of the unclipped
//!   data. Without a limit `c` is zero and nothing changes. Two phases
//!   placed symmetrically between two limits (levels 0.3/0.7 in `[0, 1]`)
//!   have a `c` odd about `f = ½`, so a straight edge is unbiased even
//!   uncorrected. The reported plateaus stay the clipped means;
//!   [`PartialVolume::latent`] has the fitted levels.
//!
//! The standard error reported with each estimate has two shares, added in
//! quadrature:
//!
//! * **Noise.** `Σ σ² / (μ_a − μ_b)²` over the band pixels the phase takes
//!   part in (`σ²` the mean of the two plateaus' intensity variances), plus
//!   the plateau means' sampling error carried through the fractions.
//! * **Where the segmentation drew the interfaces.** The band follows the
//!   labels, and so does everything counted whole (junction windows, pixels
//!   beyond the band), and the labels come from the same noisy data: over
//!   noise seeds the estimate varies more than its noise share (the root
//!   mean square of error / noise share reached 2.0 on the benchmark
//!   phantoms). A label image places an interface to a pixel, so this share
//!   is the estimate's change when the labels move by one pixel: half the
//!   difference between the estimate with phase `p` grown by one pixel
//!   (every pixel with `p` in its 3×3(×3) window becomes `p`) and with it
//!   shrunk by one (each of its pixels with another label in the window takes
//!   the lowest such label). For an ideal estimate that share is zero; here
//!   it is what leaks past the band's edge of a 1.5-pixel blur and what the
//!   junction windows count whole.
//!
//! Distances are counted in pixels/voxels (as the blur is), whatever their
//! physical size; the result is in pixels/voxels, scaled by the caller.

use super::censored::{fit_censored, CensoredSample, Curvature, Gaussian, Limits};
use rayon::prelude::*;

/// How far the band reaches from the segmented interface, in pixels/voxels.
pub const BAND_HALF_WIDTH: u8 = 3;
/// Depth (pixels/voxels from any other label) of the pixels that estimate a
/// phase's plateau intensity when the phase is thick enough.
pub const PLATEAU_DEPTH: u8 = BAND_HALF_WIDTH + 3;
/// Pixels a plateau is taken over when the phase has them: its layers are
/// added deepest first until they hold this many (the mean of 4000 noisy
/// pixels is within about σ/63 of the plateau).
pub const PLATEAU_SAMPLES: usize = 4000;
/// Phases the per-pixel label sets can hold (one bit each); with more, every
/// pixel counts for its label.
const MAX_PHASES: usize = 16;

/// Partial-volume estimates per phase, in pixels/voxels.
#[derive(Clone, Debug, PartialEq)]
pub struct PartialVolume {
    /// Estimated area/volume of each phase, in pixels/voxels.
    pub measure: Vec<f64>,
    /// Standard error of each estimate, in pixels/voxels: the noise's share
    /// and the labels' one-pixel share (see the module documentation).
    pub standard_error: Vec<f64>,
    /// Plateau intensity of each phase (`None`: no pixel beyond the band).
    pub plateau: Vec<Option<f64>>,
    /// Latent (unclipped) level of each phase behind its plateau: the
    /// plateau itself where the data do not saturate.
    pub latent: Vec<Option<f64>>,
    /// Where the intensities saturate.
    pub limits: Limits,
}

/// The partial-volume area/volume of each phase of `labels` (values below
/// `phases`, x fastest, `dims` = `[nx, ny, nz]`, `nz = 1` in 2D) over the
/// intensities `values`.
pub fn partial_volume(
    labels: &[u8],
    values: &[f32],
    dims: [usize; 3],
    phases: usize,
) -> PartialVolume {
    if !(2..=MAX_PHASES).contains(&phases) {
        return counted(labels, phases);
    }
    with_limits(labels, values, dims, phases, Limits::detect(values))
}

/// [`partial_volume`] with the saturation limits given.
fn with_limits(
    labels: &[u8],
    values: &[f32],
    dims: [usize; 3],
    phases: usize,
    limits: Limits,
) -> PartialVolume {
    let image = Intensities::new(values, dims, limits);
    // (each estimate reads the labels and the image only: the same figures
    // on any number of threads)
    let main = || noise_only(labels, &image, phases);
    let shifts = || one_pixel_shift(labels, &image, phases);
    let (mut estimate, shift) = if estimates_in_parallel(dims) {
        rayon::join(main, shifts)
    } else {
        (main(), shifts())
    };
    for (se, s) in estimate.standard_error.iter_mut().zip(shift) {
        *se = se.hypot(s);
    }
    estimate
}

/// A phase's plateau intensity and how many pixels/voxels it was taken over.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlateauMean {
    /// The mean intensity.
    pub mean: f64,
    /// Pixels/voxels it was taken over (at most [`PLATEAU_SAMPLES`], unless
    /// one layer holds more).
    pub samples: usize,
}

/// The plateau intensity of each phase of `labels` (as in
/// [`partial_volume`]): the mean over its pixels beyond the band, deepest
/// first; `None` for a phase without such pixels (or with more than
/// 16 phases, where no plateau is taken).
pub fn phase_plateaus(
    labels: &[u8],
    values: &[f32],
    dims: [usize; 3],
    phases: usize,
) -> Vec<Option<PlateauMean>> {
    if !(2..=MAX_PHASES).contains(&phases) {
        return vec![None; phases];
    }
    let (_, depth) = band_and_depth(labels, dims, phases);
    plateaus(labels, values, &depth, phases, &Limits::NONE)
        .iter()
        .map(|p| {
            p.map(|p| PlateauMean {
                mean: p.mean,
                samples: p.samples,
            })
        })
        .collect()
}

/// Whether the whole-image estimates run on rayon's threads: for a 2D
/// image, where they took more instructions than the segmentation itself;
/// not for a volume, where they are under 2 % of a 128³ run and each
/// concurrent pass holds about 4 bytes per voxel (the 4.5-million-voxel
/// brain phantom peaked at 721 MB with them in parallel, 652 MB without).
pub fn estimates_in_parallel(dims: [usize; 3]) -> bool {
    dims[2] <= 1
}

/// How much each phase's estimate moves when its labels move by one pixel:
/// half the difference between the estimates with the phase grown and
/// shrunk by one pixel (see the module documentation). The `2·phases`
/// estimates are independent whole-image passes, taken on rayon's threads
/// in 2D ([`estimates_in_parallel`]; each with its own copy of the labels);
/// they are most of the time the measurements take after a run, more than
/// the 2D segmentation itself on a 512² four-phase image. With two phases,
/// growing one is shrinking the other (a pixel of phase 1 next to phase 0
/// goes to 0 either way), so two passes give all four estimates.
fn one_pixel_shift(labels: &[u8], image: &Intensities, phases: usize) -> Vec<f64> {
    let sets = window_sets(labels, image.dims, phases);
    if phases == 2 {
        let grown = || moved_measures(labels, &sets, image, 2, (0, true));
        let shrunk = || moved_measures(labels, &sets, image, 2, (0, false));
        let (grown_0, shrunk_0) = if estimates_in_parallel(image.dims) {
            rayon::join(grown, shrunk)
        } else {
            (grown(), shrunk())
        };
        // phase 1 grown is phase 0 shrunk, and the other way round
        return vec![
            0.5 * (grown_0[0] - shrunk_0[0]).abs(),
            0.5 * (shrunk_0[1] - grown_0[1]).abs(),
        ];
    }
    each_phase_shift(labels, &sets, image, phases)
}

/// [`one_pixel_shift`] with a pass for each phase grown and each shrunk.
fn each_phase_shift(labels: &[u8], sets: &[u16], image: &Intensities, phases: usize) -> Vec<f64> {
    let moves: Vec<(usize, bool)> = (0..phases).flat_map(|p| [(p, true), (p, false)]).collect();
    let estimate =
        |&(p, grow): &(usize, bool)| moved_measures(labels, sets, image, phases, (p, grow))[p];
    let estimates: Vec<f64> = if estimates_in_parallel(image.dims) {
        moves.par_iter().map(estimate).collect()
    } else {
        moves.iter().map(estimate).collect()
    };
    estimates
        .chunks_exact(2)
        .map(|pair| 0.5 * (pair[0] - pair[1]).abs())
        .collect()
}

/// The estimate of each of `phases` phases (noise share only) with phase
/// `p` grown (`grow`) or shrunk by one pixel.
fn moved_measures(
    labels: &[u8],
    sets: &[u16],
    image: &Intensities,
    phases: usize,
    (p, grow): (usize, bool),
) -> Vec<f64> {
    let mut moved = vec![0u8; labels.len()];
    if grow {
        grown_into(labels, sets, p as u8, &mut moved);
    } else {
        shrunk_into(labels, sets, p as u8, &mut moved);
    }
    noise_only(&moved, image, phases).measure
}

/// Each pixel's set of labels (one bit each) within one pixel of it.
fn window_sets(labels: &[u8], dims: [usize; 3], phases: usize) -> Vec<u16> {
    let mut sets = label_sets(labels, phases);
    grow_by_one(&mut sets, dims);
    sets
}

/// `labels` with phase `p` grown by one pixel, written into `out`.
fn grown_into(labels: &[u8], sets: &[u16], p: u8, out: &mut [u8]) {
    for ((o, &l), &set) in out.iter_mut().zip(labels).zip(sets) {
        *o = if set & (1 << p) != 0 { p } else { l };
    }
}

/// `labels` with phase `p` shrunk by one pixel (a pixel of `p` with another
/// label in its window takes the lowest such label), written into `out`.
fn shrunk_into(labels: &[u8], sets: &[u16], p: u8, out: &mut [u8]) {
    for ((o, &l), &set) in out.iter_mut().zip(labels).zip(sets) {
        let others = set & !(1 << p);
        *o = if l == p && others != 0 {
            others.trailing_zeros() as u8
        } else {
            l
        };
    }
}

/// The intensities the estimate reads: the values, the grid, the
/// saturation limits and, where the data saturate, each pixel's local mean.
struct Intensities<'a> {
    values: &'a [f32],
    dims: [usize; 3],
    limits: Limits,
    /// The 3×3(×3) mean around each pixel (empty without saturation).
    local_mean: Vec<f32>,
}

impl<'a> Intensities<'a> {
    fn new(values: &'a [f32], dims: [usize; 3], limits: Limits) -> Self {
        let local_mean = if limits.any() {
            box_mean(values, dims)
        } else {
            Vec::new()
        };
        Intensities {
            values,
            dims,
            limits,
            local_mean,
        }
    }

    /// What clipping adds to band pixel `i` mixing `a` and `b` (0 without
    /// saturation): the table's excess at the pixel's local mean.
    fn curvature(&self, tables: &[Option<Curvature>], pair: usize, i: usize) -> f64 {
        match (&tables[pair], self.local_mean.get(i)) {
            (Some(table), Some(&m)) => table.at(f64::from(m)),
            _ => 0.0,
        }
    }
}

/// The estimate with the noise share of the standard error only.
fn noise_only(labels: &[u8], image: &Intensities, phases: usize) -> PartialVolume {
    let (band, depth) = band_and_depth(labels, image.dims, phases);
    let plateaus = plateaus(labels, image.values, &depth, phases, &image.limits);
    let tables = curvature_tables(&plateaus, &image.limits);
    let mut measure = vec![0.0f64; phases];
    let mut variance = vec![0.0f64; phases];
    // slope[a * phases + p]: how phase a's estimate moves with plateau p.
    let mut slope = vec![0.0f64; phases * phases];
    for (i, ((&label, &value), &set)) in labels.iter().zip(image.values).zip(&band).enumerate() {
        let own = label as usize;
        if own >= phases {
            continue;
        }
        match mixed_pair(set, &plateaus) {
            Some((a, b)) => {
                let (pa, pb) = (plateaus[a].unwrap(), plateaus[b].unwrap());
                let contrast = pa.mean - pb.mean;
                let excess = image.curvature(&tables, a * phases + b, i);
                let f = (f64::from(value) - excess - pb.mean) / contrast;
                measure[a] += f;
                measure[b] += 1.0 - f;
                let noise = 0.5 * (pa.variance + pb.variance) / (contrast * contrast);
                variance[a] += noise;
                variance[b] += noise;
                // ∂f/∂μ_a = −f/Δ, ∂f/∂μ_b = (f − 1)/Δ; phase b's share moves oppositely.
                slope[a * phases + a] -= f / contrast;
                slope[a * phases + b] += (f - 1.0) / contrast;
                slope[b * phases + a] += f / contrast;
                slope[b * phases + b] -= (f - 1.0) / contrast;
            }
            None => measure[own] += 1.0,
        }
    }
    // The plateaus' own sampling error adds to the band's noise.
    for (a, v) in variance.iter_mut().enumerate() {
        for (p, plateau) in plateaus.iter().enumerate() {
            if let Some(q) = plateau {
                *v += slope[a * phases + p].powi(2) * q.variance / q.samples as f64;
            }
        }
    }
    PartialVolume {
        measure,
        standard_error: variance.into_iter().map(f64::sqrt).collect(),
        plateau: plateaus.iter().map(|p| p.map(|p| p.mean)).collect(),
        latent: plateaus.iter().map(|p| p.map(|p| p.latent.mean)).collect(),
        limits: image.limits,
    }
}

/// Per ordered pair `a * phases + b` (`a < b`, both with plateaus), the
/// table of what clipping adds to their mixtures; all `None` without
/// saturation.
fn curvature_tables(plateaus: &[Option<Plateau>], limits: &Limits) -> Vec<Option<Curvature>> {
    let phases = plateaus.len();
    let mut tables = vec![None; phases * phases];
    if !limits.any() {
        return tables;
    }
    for a in 0..phases {
        for b in a + 1..phases {
            if let (Some(pa), Some(pb)) = (plateaus[a], plateaus[b]) {
                tables[a * phases + b] = Some(Curvature::new(pa.latent, pb.latent, limits));
            }
        }
    }
    tables
}

/// The mean of each pixel's 3×3(×3) window (the part inside the grid),
/// one axis at a time. The sums are made in place (8 bytes a pixel, a
/// volume of 256³ voxels among them) and the window's size is counted, not
/// stored: the product over the axes of the pixel and its neighbours
/// inside the grid.
fn box_mean(values: &[f32], dims: [usize; 3]) -> Vec<f32> {
    let mut sum: Vec<f64> = values.iter().map(|&v| f64::from(v)).collect();
    let strides = [1, dims[0], dims[0] * dims[1]];
    for (axis, &stride) in strides.iter().enumerate() {
        if dims[axis] > 1 {
            add_neighbours(&mut sum, stride, dims[axis]);
        }
    }
    sum.iter()
        .enumerate()
        .map(|(i, s)| (s / window_size(i, dims)) as f32)
        .collect()
}

/// Adds to each entry of `field` its two neighbours `stride` entries before
/// and after it along an axis of `extent` entries (those inside the grid),
/// as they were before this pass, in that order. The lines along the axis
/// are `stride` entries apart; the one before is kept in a copy, the one
/// after is not yet changed.
fn add_neighbours(field: &mut [f64], stride: usize, extent: usize) {
    let mut previous = vec![0.0; stride];
    let mut current = vec![0.0; stride];
    for block in field.chunks_mut(stride * extent) {
        for k in 0..extent {
            let (line, after) = block[k * stride..].split_at_mut(stride);
            current.copy_from_slice(line);
            for (j, v) in line.iter_mut().enumerate() {
                if k > 0 {
                    *v += previous[j];
                }
                if k + 1 < extent {
                    *v += after[j];
                }
            }
            std::mem::swap(&mut previous, &mut current);
        }
    }
}

/// How many pixels of the grid `dims` the 3×3(×3) window around pixel `i`
/// holds.
fn window_size(i: usize, dims: [usize; 3]) -> f64 {
    let at = [
        i % dims[0],
        (i / dims[0]) % dims[1],
        i / (dims[0] * dims[1]),
    ];
    (0..3)
        .filter(|&a| dims[a] > 1)
        .map(|a| 1 + usize::from(at[a] > 0) + usize::from(at[a] + 1 < dims[a]))
        .product::<usize>() as f64
}

/// Every pixel counted for its label (no partial-volume model applies).
fn counted(labels: &[u8], phases: usize) -> PartialVolume {
    let mut measure = vec![0.0; phases];
    for &l in labels {
        if let Some(m) = measure.get_mut(l as usize) {
            *m += 1.0;
        }
    }
    PartialVolume {
        measure,
        standard_error: vec![0.0; phases],
        plateau: vec![None; phases],
        latent: vec![None; phases],
        limits: Limits::NONE,
    }
}

/// The two phases a band pixel with window label set `set` mixes, when the
/// model applies: exactly two labels, both with plateaus that differ.
fn mixed_pair(set: u16, plateaus: &[Option<Plateau>]) -> Option<(usize, usize)> {
    // Exactly two bits: one left once the lowest is cleared (without
    // `count_ones`, a loop of instructions on CPUs without `popcnt`).
    let rest = set & set.wrapping_sub(1);
    if rest == 0 || rest & rest.wrapping_sub(1) != 0 {
        return None;
    }
    let a = set.trailing_zeros() as usize;
    let b = rest.trailing_zeros() as usize;
    let (pa, pb) = (plateaus.get(a)?.as_ref()?, plateaus.get(b)?.as_ref()?);
    let contrast = (pa.mean - pb.mean).abs();
    let scale = pa.mean.abs().max(pb.mean.abs()).max(f64::MIN_POSITIVE);
    (contrast > 1e-9 * scale).then_some((a, b))
}

/// A phase's plateau: mean and variance of its deepest pixels' intensities.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Plateau {
    mean: f64,
    variance: f64,
    /// Pixels the mean was taken over.
    samples: usize,
    /// The Gaussian behind the clipped values (the mean and standard
    /// deviation themselves without saturation).
    latent: Gaussian,
}

/// Per pixel, the set of labels (one bit each; labels from `phases` up have
/// none) within [`BAND_HALF_WIDTH`] of it, and its depth: how many pixels lie
/// between it and the nearest other label (Chebyshev distance − 1), capped at
/// [`PLATEAU_DEPTH`] (no other label within that distance).
fn band_and_depth(labels: &[u8], dims: [usize; 3], phases: usize) -> (Vec<u16>, Vec<u8>) {
    let mut sets = label_sets(labels, phases);
    // The sets only grow with the reach, so a pixel's depth is the number
    // of reaches at which its set still holds one label at most (a set of
    // two or more has a bit left once its lowest is cleared): counted
    // without a branch, so that the loop vectorises.
    let mut depth = vec![0u8; labels.len()];
    let mut band = Vec::new();
    for reach in 1..=PLATEAU_DEPTH {
        grow_by_one(&mut sets, dims);
        for (d, &s) in depth.iter_mut().zip(&sets) {
            *d += u8::from(s & s.wrapping_sub(1) == 0);
        }
        if reach == BAND_HALF_WIDTH {
            band = sets.clone();
        }
    }
    (band, depth)
}

/// Each pixel's own label as a one-bit set (labels from `phases` up: none).
fn label_sets(labels: &[u8], phases: usize) -> Vec<u16> {
    labels
        .iter()
        .map(|&l| if usize::from(l) < phases { 1 << l } else { 0 })
        .collect()
}

/// Replaces each pixel's label set by the union over its 3×3(×3) window,
/// one axis at a time, in place (a copy of one line or slice at a time).
fn grow_by_one(sets: &mut [u16], dims: [usize; 3]) {
    let [nx, ny, _] = dims;
    let mut copy = vec![0u16; nx];
    for row in sets.chunks_exact_mut(nx) {
        grow_row(row, &mut copy);
    }
    // Along y within each z slice (lines of nx), then along z (slices of nx·ny).
    for (line, lines) in [(nx, ny), (nx * ny, sets.len() / (nx * ny))] {
        for block in sets.chunks_exact_mut(line * lines) {
            grow_lines(block, line);
        }
    }
}

/// ORs each element of `row` with its two neighbours' original values;
/// `copy` is scratch of the row's length. Written without a dependency
/// from one element to the next, so that the compiler vectorises it.
fn grow_row(row: &mut [u16], copy: &mut [u16]) {
    let n = row.len();
    if n < 2 {
        return;
    }
    copy.copy_from_slice(row);
    for ((r, &own), &after) in row.iter_mut().zip(&*copy).zip(&copy[1..]) {
        *r = own | after;
    }
    for (r, &before) in row[1..].iter_mut().zip(&*copy) {
        *r |= before;
    }
}

/// ORs each `line`-long line of `block` with its two neighbouring lines'
/// original values.
fn grow_lines(block: &mut [u16], line: usize) {
    let lines = block.len() / line;
    if lines < 2 {
        return;
    }
    let mut before = vec![0u16; line];
    let mut own = vec![0u16; line];
    for k in 0..lines {
        let (head, tail) = block.split_at_mut((k + 1) * line);
        let current = &mut head[k * line..];
        own.copy_from_slice(current);
        for (c, &b) in current.iter_mut().zip(&before) {
            *c |= b;
        }
        if let Some(after) = tail.get(..line) {
            for (c, &a) in current.iter_mut().zip(after) {
                *c |= a;
            }
        }
        std::mem::swap(&mut before, &mut own);
    }
}

/// Each phase's plateau from its deepest pixels (see the module
/// documentation), with its latent Gaussian fitted to the pixels censored at
/// `limits`.
fn plateaus(
    labels: &[u8],
    values: &[f32],
    depth: &[u8],
    phases: usize,
    limits: &Limits,
) -> Vec<Option<Plateau>> {
    let layers = PLATEAU_DEPTH as usize + 1;
    // Per phase and depth: the layer's censored sample.
    let mut acc = vec![CensoredSample::default(); phases * layers];
    for ((&l, &v), &d) in labels.iter().zip(values).zip(depth) {
        if let Some(a) = acc.get_mut(l as usize * layers + d as usize) {
            a.add(f64::from(v), limits);
        }
    }
    (0..phases)
        .map(|p| {
            let mut total = CensoredSample::default();
            for d in (BAND_HALF_WIDTH as usize..layers).rev() {
                total.merge(&acc[p * layers + d]);
                if total.len() >= PLATEAU_SAMPLES {
                    break;
                }
            }
            (!total.is_empty()).then(|| {
                let (mean, variance) = total.clipped_moments(limits);
                Plateau {
                    mean,
                    variance,
                    samples: total.len(),
                    latent: fit_censored(&total, limits),
                }
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_counts_pixels_to_the_other_label() {
        // A 12-pixel row: 0 0 0 0 0 0 | 1 1 1 1 1 1.
        let labels: Vec<u8> = (0..12).map(|i| u8::from(i >= 6)).collect();
        let (band, depth) = band_and_depth(&labels, [12, 1, 1], 2);
        assert_eq!(depth, vec![5, 4, 3, 2, 1, 0, 0, 1, 2, 3, 4, 5]);
        let mixed: Vec<bool> = band.iter().map(|s| s.count_ones() == 2).collect();
        let expect: Vec<bool> = (0..12).map(|i| (3..9).contains(&i)).collect();
        assert_eq!(mixed, expect);
    }

    #[test]
    fn label_sets_and_depths_match_a_direct_window_search() {
        // Pseudo-random labels 0..3 (and an out-of-range 7) in a 9×7×6 volume.
        let dims = [9usize, 7, 6];
        let n = dims.iter().product::<usize>();
        let mut state = 12345u32;
        let labels: Vec<u8> = (0..n)
            .map(|_| {
                state = state.wrapping_mul(1_103_515_245).wrapping_add(12345);
                match (state >> 16) % 23 {
                    0 => 7,
                    r if r < 3 => 1 + (r as u8 % 2),
                    _ => 0,
                }
            })
            .collect();
        let (band, depth) = band_and_depth(&labels, dims, 3);
        let at = |x: usize, y: usize, z: usize| labels[x + dims[0] * (y + dims[1] * z)];
        let window = |x: usize, y: usize, z: usize, r: usize| {
            let mut set = 0u16;
            for zz in z.saturating_sub(r)..(z + r + 1).min(dims[2]) {
                for yy in y.saturating_sub(r)..(y + r + 1).min(dims[1]) {
                    for xx in x.saturating_sub(r)..(x + r + 1).min(dims[0]) {
                        let l = at(xx, yy, zz);
                        if l < 3 {
                            set |= 1 << l;
                        }
                    }
                }
            }
            set
        };
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    let i = x + dims[0] * (y + dims[1] * z);
                    assert_eq!(band[i], window(x, y, z, BAND_HALF_WIDTH as usize));
                    let expect = (1..=PLATEAU_DEPTH as usize)
                        .find(|&r| window(x, y, z, r).count_ones() > 1)
                        .map_or(PLATEAU_DEPTH, |r| r as u8 - 1);
                    assert_eq!(depth[i], expect, "({x}, {y}, {z})");
                }
            }
        }
    }

    #[test]
    fn a_blurred_edge_gives_its_true_area_wherever_the_labels_cut_it() {
        // Phase 1 fills x < 40.3 of a 100-pixel row (repeated over 5 rows):
        // the pixel at x = 40 is 0.3 phase 1; a 3-pixel box blur spreads the
        // edge over pixels 39-41 (integral preserved). The labels cut it one
        // pixel before, at or two pixels after the truth.
        let (nx, ny) = (100usize, 5usize);
        let edge = 40.3;
        let cover = |x: f64| (edge - x).clamp(0.0, 1.0);
        let blurred = |i: usize| {
            let x = i as f64;
            (-1..=1).map(|o| cover(x + o as f64)).sum::<f64>() / 3.0
        };
        let row: Vec<f32> = (0..nx).map(|i| (0.2 + 0.6 * blurred(i)) as f32).collect();
        let values: Vec<f32> = (0..ny).flat_map(|_| row.clone()).collect();
        for cut in [39usize, 40, 42] {
            let labels: Vec<u8> = (0..nx * ny).map(|i| u8::from(i % nx < cut)).collect();
            let pv = partial_volume(&labels, &values, [nx, ny, 1], 2);
            assert!(
                (pv.measure[1] - edge * ny as f64).abs() < 1e-3,
                "{cut}: {pv:?}"
            );
            assert!((pv.measure[0] + pv.measure[1] - (nx * ny) as f64).abs() < 1e-6);
            assert!((pv.plateau[1].unwrap() - 0.8).abs() < 1e-6);
        }
    }

    #[test]
    fn three_phases_in_a_window_count_by_label() {
        // Three stripes each 2 pixels wide: every window holds three labels.
        let labels: Vec<u8> = (0..6).map(|i| (i / 2) as u8).collect();
        let values = vec![0.5f32; 6];
        let pv = partial_volume(&labels, &values, [6, 1, 1], 3);
        assert_eq!(pv.measure, vec![2.0, 2.0, 2.0]);
        // Counted whole, each stripe moves with its labels: grown by a pixel
        // on each open side, shrunk as much (the end stripes have one side).
        assert_eq!(pv.standard_error, vec![1.0, 2.0, 1.0]);
    }

    #[test]
    fn a_phase_without_plateau_falls_back_to_counting() {
        // A one-pixel phase 1 in a row of phase 0: no plateau for 1.
        let mut labels = vec![0u8; 30];
        labels[15] = 1;
        let values: Vec<f32> = labels.iter().map(|&l| 0.3 + 0.4 * f32::from(l)).collect();
        let pv = partial_volume(&labels, &values, [30, 1, 1], 2);
        assert_eq!(pv.plateau[1], None);
        assert_eq!(pv.measure, vec![29.0, 1.0]);
    }

    /// A 256×96 image of vertical stripes 16 pixels wide (phase 1 from
    /// x = 8 on, every other stripe), blurred by 1.5 pixels, at levels
    /// `low`/`high`, with seeded Gaussian noise: its labels and the
    /// unclipped intensities.
    fn noisy_stripes(
        low: f64,
        high: f64,
        sigma: f64,
        seed: u64,
    ) -> (Vec<u8>, Vec<f32>, [usize; 3]) {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let (nx, ny) = (256usize, 96usize);
        let labels: Vec<u8> = (0..nx * ny)
            .map(|i| u8::from((i % nx + 8) / 16 % 2 == 1))
            .collect();
        let sharp: Vec<f32> = labels
            .iter()
            .map(|&l| (low + (high - low) * f64::from(l)) as f32)
            .collect();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let values = crate::phantom::blur::gaussian_blur_2d(&sharp, nx, ny, 1.5)
            .into_iter()
            .map(|v| {
                let n: f64 = StandardNormal.sample(&mut rng);
                (f64::from(v) + sigma * n) as f32
            })
            .collect();
        (labels, values, [nx, ny, 1])
    }

    #[test]
    fn two_phases_take_their_four_shifted_estimates_from_two_passes() {
        let (mut labels, values, dims) = noisy_stripes(0.3, 0.7, 0.1, 3);
        // ragged edges, so that growing and shrinking move different pixels
        for i in (0..labels.len()).step_by(37) {
            labels[i] ^= 1;
        }
        let image = Intensities::new(&values, dims, Limits::detect(&values));
        let sets = window_sets(&labels, dims, 2);
        let shortcut = one_pixel_shift(&labels, &image, 2);
        let every_pass = each_phase_shift(&labels, &sets, &image, 2);
        assert!(shortcut[0] > 0.0 && shortcut[1] > 0.0, "{shortcut:?}");
        assert_eq!(shortcut, every_pass);
    }

    #[test]
    fn clipped_intensities_give_the_unclipped_area() {
        // Levels 0.6/0.8 at σ 0.2 clipped to [0, 1]: 16 % of phase 1 and
        // 2 % of phase 0 on the top limit. The same noise unclipped is the
        // reference; what clipping changes is a bias, the same every seed.
        let mut biased = 0.0;
        let mut corrected = 0.0;
        let seeds = 4;
        for seed in 1..=seeds {
            let (labels, unclipped, dims) = noisy_stripes(0.6, 0.8, 0.2, seed);
            let clipped: Vec<f32> = unclipped.iter().map(|v| v.clamp(0.0, 1.0)).collect();
            let limits = Limits::detect(&clipped);
            // A few pixels of phase 0 reach 0: too few to make it a limit.
            assert_eq!((limits.low, limits.high), (None, Some(1.0)));
            assert_eq!(Limits::detect(&unclipped), Limits::NONE);
            let reference = partial_volume(&labels, &unclipped, dims, 2).measure[1];
            let linear = with_limits(&labels, &clipped, dims, 2, Limits::NONE).measure[1];
            let pv = partial_volume(&labels, &clipped, dims, 2);
            biased += (linear - reference) / seeds as f64;
            corrected += (pv.measure[1] - reference) / seeds as f64;
            let latent = pv.latent[1].unwrap();
            assert!((latent - 0.8).abs() < 0.01, "{latent}");
            // The clipped plateau is g(0.8) = 0.783.
            let plateau = pv.plateau[1].unwrap();
            assert!((plateau - 0.783).abs() < 0.005, "{plateau}");
        }
        // 16 interfaces 96 pixels long: the linear fractions give phase 1
        // about 0.05 pixel too much per pixel of interface.
        let interface = 16.0 * 96.0;
        assert!(biased > 0.03 * interface, "{biased}");
        assert!(
            corrected.abs() < 0.1 * biased.abs(),
            "{corrected} vs {biased}"
        );
    }

    #[test]
    fn unclipped_intensities_are_left_alone() {
        // Levels 0.3/0.7 at σ 0.06, quantised to 8 bits but never clipped:
        // no limit is found and the estimate is the linear one.
        let (labels, values, dims) = noisy_stripes(0.3, 0.7, 0.06, 7);
        let quantised: Vec<f32> = values
            .iter()
            .map(|&v| (v * 255.0).round() / 255.0)
            .collect();
        assert!(quantised.iter().all(|v| (0.0..=1.0).contains(v)));
        assert_eq!(Limits::detect(&quantised), Limits::NONE);
        let pv = partial_volume(&labels, &quantised, dims, 2);
        assert_eq!(pv, with_limits(&labels, &quantised, dims, 2, Limits::NONE));
        assert_eq!(pv.latent, pv.plateau);
    }

    /// The window means with every pass's sums and counts in arrays of
    /// their own (what [`box_mean`] computes in place).
    fn box_mean_by_copies(values: &[f32], dims: [usize; 3]) -> Vec<f32> {
        let mut sum: Vec<f64> = values.iter().map(|&v| f64::from(v)).collect();
        let mut count = vec![1.0f64; values.len()];
        let strides = [1, dims[0], dims[0] * dims[1]];
        for (axis, &stride) in strides.iter().enumerate() {
            if dims[axis] < 2 {
                continue;
            }
            for field in [&mut sum, &mut count] {
                let before = field.clone();
                for (i, v) in field.iter_mut().enumerate() {
                    let at = (i / stride) % dims[axis];
                    if at > 0 {
                        *v += before[i - stride];
                    }
                    if at + 1 < dims[axis] {
                        *v += before[i + stride];
                    }
                }
            }
        }
        sum.iter()
            .zip(&count)
            .map(|(s, c)| (s / c) as f32)
            .collect()
    }

    #[test]
    fn box_mean_in_place_is_the_mean_by_copies_to_the_bit() {
        for dims in [
            [1, 1, 1],
            [5, 1, 1],
            [1, 6, 1],
            [4, 3, 1],
            [4, 3, 2],
            [1, 1, 5],
            [7, 2, 5],
        ] {
            let n = dims.iter().product::<usize>();
            let values: Vec<f32> = (0..n).map(|i| ((i * 7919) % 113) as f32 / 9.0).collect();
            let bits = |v: Vec<f32>| v.into_iter().map(f32::to_bits).collect::<Vec<_>>();
            assert_eq!(
                bits(box_mean(&values, dims)),
                bits(box_mean_by_copies(&values, dims)),
                "{dims:?}"
            );
        }
    }

    #[test]
    fn box_mean_averages_the_window_inside_the_grid() {
        let dims = [4usize, 3, 2];
        let values: Vec<f32> = (0..24).map(|i| (i * i % 7) as f32).collect();
        let mean = box_mean(&values, dims);
        let at = |x: usize, y: usize, z: usize| values[x + 4 * (y + 3 * z)];
        for z in 0..2usize {
            for y in 0..3usize {
                for x in 0..4usize {
                    let mut window = Vec::new();
                    for zz in z.saturating_sub(1)..(z + 2).min(2) {
                        for yy in y.saturating_sub(1)..(y + 2).min(3) {
                            for xx in x.saturating_sub(1)..(x + 2).min(4) {
                                window.push(at(xx, yy, zz));
                            }
                        }
                    }
                    let expect = window.iter().sum::<f32>() / window.len() as f32;
                    assert!((mean[x + 4 * (y + 3 * z)] - expect).abs() < 1e-5);
                }
            }
        }
    }
}
