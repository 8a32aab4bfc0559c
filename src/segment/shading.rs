//! A smooth trend of intensity inside the phases: uneven illumination, an
//! MRI bias field, a microscope's vignetting.
//!
//! The data term fits one constant mean per phase. Where the illumination
//! falls off across a photographed page, a phase's intensity drifts over
//! the image by as much as the gap between two phases' means, and the
//! result labels the dark side of the page as print; no other check sees
//! it, as every phase is a region of its own mean. This one looks at what
//! the means leave: per phase, the residuals (sample − the phase's final
//! mean) of its samples away from its interfaces (those whose box of
//! [`INTERIOR_RADIUS`] samples each way carries its label alone, out of
//! the reach of an edge's blur), taken on a grid of at most
//! [`MAX_FIT_SAMPLES`], are fitted by a quadratic polynomial of the
//! position (least squares; a ramp and a vignette are both in it). The
//! fitted trend's spread over the phase's samples (the 1st to the 99th
//! percentile of its values) is weighed against the gap between the
//! phase's mean and the nearest other mean: where it reaches
//! [`MIN_TREND_RATIO`] of the gap, and lies beyond the noise of the fit by
//! [`MIN_SIGNIFICANCE`], the run warns. A texture, an object of another
//! intensity inside the phase or a second class the phase holds are not a
//! polynomial of low order, and add to the residual the fit leaves rather
//! than to the trend; a phase that holds two classes side by side is a
//! trend (more phases are then the remedy the warning names beside the
//! correction of the illumination).
//!
//! The thresholds come from measurement (`benches/RESULTS.md`, "Uneven
//! illumination"): on the clean benchmark phantoms the ratio reaches 0.49
//! where the close phases leave few interior samples, but the significance
//! stays at or under 2; every ramp of illumination of a tenth of the
//! intensity or more, and scikit-image's `page`, reach both. Photographs
//! of scenes reach them too: their phases hold objects of different
//! brightness in different places, which a low-order polynomial follows as
//! well as it follows light.

use super::image::ImageView;
use super::missed_objects::{correlation_and_share, present_means};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// Samples each way (along every axis) within which a sample must carry no
/// label but its own to be fitted: twice the benchmark phantoms' blur of
/// 1.5 pixels, beyond which an edge moves a sample by under 3 % of the
/// contrast.
pub const INTERIOR_RADIUS: usize = 3;

/// Most grid points the check visits: a larger image or volume is taken on
/// a coarser grid, so that the check costs little next to the run.
pub const MAX_FIT_SAMPLES: usize = 1 << 16;

/// Fewest interior samples a phase needs to be judged (a quadratic in 3D
/// has ten coefficients).
pub const MIN_FIT_SAMPLES: usize = 200;

/// The share of the gap to the nearest other phase mean that the trend's
/// spread must reach to be reported: the phase's samples at either end of
/// the trend then lie an eighth of the gap nearer a neighbouring mean, and
/// the noise carries many more of them across the midpoint. The shaded
/// phantoms that stayed under it lost at most 0.003 of their Dice.
pub const MIN_TREND_RATIO: f64 = 0.25;

/// How many times the trend's root-mean-square must exceed what the fit's
/// residual noise alone gives it: noise alone gives a ratio whose square is
/// a χ² of `p − 1` degrees of freedom over `p − 1` (`p` the polynomial's
/// coefficients), above 2 with a probability of 0.1 % in 2D; 4 has a
/// margin of two over the largest the clean phantoms give.
pub const MIN_SIGNIFICANCE: f64 = 4.0;

/// The percentile at each end of the trend's values that its spread leaves
/// out (a quadratic's values at a few far samples of the phase).
const SPREAD_PERCENTILE: f64 = 0.01;

/// The trend fitted inside one phase.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PhaseTrend {
    /// The phase (output label, by increasing mean).
    pub phase: u8,
    /// Interior samples fitted.
    pub samples: usize,
    /// The fitted trend's spread over those samples (its 1st to 99th
    /// percentile), in the file's units.
    pub trend: f64,
    /// The gap between the phase's mean and the nearest other phase's, in
    /// the file's units.
    pub gap: f64,
    /// The phase whose mean is nearest.
    pub nearest: u8,
    /// `trend / gap`.
    pub ratio: f64,
    /// The share of the residuals' variance the trend explains.
    pub explained: f64,
    /// The trend's root-mean-square over what the fit's residual noise
    /// alone would give it.
    pub significance: f64,
    /// Where the trend is lowest (its 1st percentile), in pixel or voxel
    /// indices (x, y, z).
    pub darkest_at: [f64; 3],
    /// Where it is highest (its 99th percentile).
    pub brightest_at: [f64; 3],
    /// Whether the run warns of it ([`MIN_TREND_RATIO`],
    /// [`MIN_SIGNIFICANCE`]).
    pub warned: bool,
}

impl PhaseTrend {
    /// The warning a user reads; `three_d` gives places in 3D.
    pub fn warning(&self, three_d: bool) -> String {
        let at = |p: [f64; 3]| {
            if three_d {
                format!("x = {:.0}, y = {:.0}, z = {:.0}", p[0], p[1], p[2])
            } else {
                format!("x = {:.0}, y = {:.0}", p[0], p[1])
            }
        };
        format!(
            "phase {}'s intensity drifts smoothly by {} across the image (darker near {}, \
             brighter near {}), {:.2} of the gap of {} between its mean and phase {}'s: uneven \
             illumination, a bias field or regions of different brightness in one phase, which \
             one mean per phase cannot follow, so parts of the image may carry the wrong \
             phase; correct the illumination first (divide by a heavily blurred copy of the \
             image; N4 bias-field correction for an MRI) or try more phases",
            self.phase,
            significant(self.trend),
            at(self.darkest_at),
            at(self.brightest_at),
            self.ratio,
            significant(self.gap),
            self.nearest,
        )
    }
}

/// `v` to three significant digits (no exponent for the values a file
/// holds).
fn significant(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.digits$}")
}

/// The noise the fit's residuals are weighed with.
#[derive(Clone, Copy, Debug)]
pub struct FitNoise {
    /// Neighbour correlation of the image's noise (`None`: taken as 0; at
    /// most [`MAX_CORRELATION`](super::missed_objects::MAX_CORRELATION)),
    /// which thins the fit's independent samples.
    pub correlation: Option<f64>,
}

/// The trend of every present phase of `labels` (output labels) over
/// `image`, given each output label's final mean in increasing order
/// (`None`: an empty phase); `scale` turns a difference of loaded values
/// into the file's units. Phases with fewer than [`MIN_FIT_SAMPLES`]
/// interior samples are left out; nothing with fewer than two present
/// phases.
pub fn phase_trends(
    image: &ImageView<'_>,
    labels: &[u8],
    means: &[Option<f64>],
    noise: FitNoise,
    scale: f64,
) -> Vec<PhaseTrend> {
    let present = present_means(means);
    if present.len() < 2 || labels.len() != image.data.len() {
        return Vec::new();
    }
    let grid = Grid::new(image.dims);
    let interior = interior_labels(labels, image.dims);
    let mut per_phase: Vec<Vec<Sample>> = vec![Vec::new(); means.len()];
    for (at, i) in grid.points() {
        let l = interior[i];
        if let Some(Some(mean)) = means.get(l as usize) {
            per_phase[l as usize].push(Sample {
                at: at.map(|c| c as u32),
                residual: f64::from(image.data[i]) - mean,
            });
        }
    }
    let (_, independent) = correlation_and_share(noise.correlation);
    let mut trends = Vec::new();
    for &(phase, mean) in &present {
        let samples = &per_phase[phase as usize];
        if samples.len() < MIN_FIT_SAMPLES {
            continue;
        }
        let Some(fit) = fit_trend(&grid, samples, independent) else {
            continue;
        };
        let (nearest, gap) = present
            .iter()
            .filter(|p| p.0 != phase)
            .map(|p| (p.0, (p.1 - mean).abs()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("two phases present");
        let ratio = if gap > 0.0 {
            fit.spread / gap
        } else {
            f64::INFINITY
        };
        trends.push(PhaseTrend {
            phase,
            samples: samples.len(),
            trend: fit.spread * scale,
            gap: gap * scale,
            nearest,
            ratio,
            explained: fit.explained,
            significance: fit.significance,
            darkest_at: fit.low_at,
            brightest_at: fit.high_at,
            warned: ratio >= MIN_TREND_RATIO && fit.significance >= MIN_SIGNIFICANCE,
        });
    }
    trends
}

/// Marks a sample that is not interior in [`interior_labels`].
const NOT_INTERIOR: u8 = u8::MAX;

/// Per sample of `labels` (on the grid `dims`): its label where every
/// sample within [`INTERIOR_RADIUS`] of it along each axis (a box, cut at
/// the image's border) carries it, else [`NOT_INTERIOR`]. The box is
/// uniform exactly when each line of it is, so one sweep per axis decides
/// it: a few operations per sample.
fn interior_labels(labels: &[u8], dims: [usize; 3]) -> Vec<u8> {
    let mut key = labels.to_vec();
    let mut line = Vec::new();
    for axis in 0..3 {
        if dims[axis] > 1 {
            uniform_windows(&mut key, dims, axis, &mut line);
        }
    }
    key
}

/// Along every line of `key` parallel to `axis`, keeps a value whose window
/// of [`INTERIOR_RADIUS`] each way (cut at the ends) holds it alone, and
/// sets the others to [`NOT_INTERIOR`].
fn uniform_windows(key: &mut [u8], dims: [usize; 3], axis: usize, line: &mut Vec<u8>) {
    let r = INTERIOR_RADIUS;
    let step = [1, dims[0], dims[0] * dims[1]][axis];
    let n = dims[axis];
    let mut across = dims;
    across[axis] = 1;
    for c in 0..across[2] {
        for b in 0..across[1] {
            for a in 0..across[0] {
                let start = a + dims[0] * (b + dims[1] * c);
                line.clear();
                line.extend((0..n).map(|k| key[start + k * step]));
                let mut run = 0;
                while run < n {
                    let v = line[run];
                    let end = run + line[run..].iter().take_while(|&&w| w == v).count();
                    for k in run..end {
                        let inside = k.saturating_sub(r) >= run && (k + r).min(n - 1) < end;
                        key[start + k * step] = if inside { v } else { NOT_INTERIOR };
                    }
                    run = end;
                }
            }
        }
    }
}

/// The grid of samples the check visits, and positions on it.
struct Grid {
    dims: [usize; 3],
    /// The step between visited samples along every axis.
    stride: usize,
    /// Per axis longer than one sample (in order), each index's coordinate
    /// scaled to `[-1, 1]` over the image.
    scaled: Vec<(usize, Vec<f64>)>,
}

/// A sample fitted: its (x, y, z) indices and its residual.
#[derive(Clone, Copy)]
struct Sample {
    at: [u32; 3],
    residual: f64,
}

impl Grid {
    /// The grid over an image of `dims`: every sample, or every `stride`-th
    /// along each axis so that at most [`MAX_FIT_SAMPLES`] are visited.
    fn new(dims: [usize; 3]) -> Self {
        let visited = |s: usize| dims.iter().map(|n| n.div_ceil(s)).product::<usize>();
        let mut stride = 1;
        while visited(stride) > MAX_FIT_SAMPLES {
            stride += 1;
        }
        let scaled = (0..3)
            .filter(|&a| dims[a] > 1)
            .map(|a| {
                let n = dims[a];
                let scale = (0..n)
                    .map(|c| 2.0 * c as f64 / (n - 1) as f64 - 1.0)
                    .collect();
                (a, scale)
            })
            .collect();
        Grid {
            dims,
            stride,
            scaled,
        }
    }

    /// The points visited: (x, y, z) and linear index.
    fn points(&self) -> impl Iterator<Item = ([usize; 3], usize)> + '_ {
        let [nx, ny, nz] = self.dims;
        let s = self.stride;
        let offset = move |n: usize| (n - 1) % s / 2;
        (offset(nz)..nz).step_by(s).flat_map(move |z| {
            (offset(ny)..ny).step_by(s).flat_map(move |y| {
                (offset(nx)..nx)
                    .step_by(s)
                    .map(move |x| ([x, y, z], (z * ny + y) * nx + x))
            })
        })
    }

    /// The quadratic monomials of position at `at` (1, the coordinates,
    /// their products and squares), each coordinate scaled to `[-1, 1]`
    /// over the image; axes one sample long are left out. The first
    /// [`Grid::terms`] entries are set.
    fn basis(&self, at: [u32; 3]) -> [f64; MAX_TERMS] {
        let mut u = [0.0; 3];
        for (k, (a, scale)) in self.scaled.iter().enumerate() {
            u[k] = scale[at[*a] as usize];
        }
        let axes = self.scaled.len();
        let mut out = [0.0; MAX_TERMS];
        out[0] = 1.0;
        out[1..=axes].copy_from_slice(&u[..axes]);
        let mut k = axes + 1;
        for a in 0..axes {
            for b in a..axes {
                out[k] = u[a] * u[b];
                k += 1;
            }
        }
        out
    }

    /// How many monomials [`Grid::basis`] sets: 6 in 2D, 10 in 3D.
    fn terms(&self) -> usize {
        let axes = self.scaled.len();
        1 + axes + axes * (axes + 1) / 2
    }
}

/// The most monomials of a quadratic in three coordinates.
const MAX_TERMS: usize = 10;

/// A phase's fitted trend.
struct Fit {
    /// Its spread (1st to 99th percentile of its values over the samples).
    spread: f64,
    /// Its root-mean-square over what noise alone would give it.
    significance: f64,
    /// The share of the residuals' variance it explains.
    explained: f64,
    /// The positions of its values at those percentiles.
    low_at: [f64; 3],
    high_at: [f64; 3],
}

/// Least-squares quadratic fit of the residuals of `samples`; `independent` is the share of them counted as independent.
/// `None` when the fit is degenerate (too few distinct positions).
fn fit_trend(grid: &Grid, samples: &[Sample], independent: f64) -> Option<Fit> {
    let p = grid.terms();
    let mut normal = [[0.0; MAX_TERMS]; MAX_TERMS];
    let mut rhs = [0.0; MAX_TERMS];
    let bases: Vec<[f64; MAX_TERMS]> = samples.iter().map(|s| grid.basis(s.at)).collect();
    for (phi, &Sample { residual: r, .. }) in bases.iter().zip(samples) {
        for a in 0..p {
            rhs[a] += phi[a] * r;
            for b in a..p {
                normal[a][b] += phi[a] * phi[b];
            }
        }
    }
    let normal = DMatrix::<f64>::from_fn(p, p, |a, b| normal[a.min(b)][a.max(b)]);
    let rhs = DVector::<f64>::from_column_slice(&rhs[..p]);
    let coefficients = normal.svd(true, true).solve(&rhs, 1e-9).ok()?;
    let mut values = Vec::with_capacity(samples.len());
    let mut residual_ss = 0.0;
    for (phi, &Sample { at, residual: r }) in bases.iter().zip(samples) {
        let t: f64 = (0..p).map(|a| phi[a] * coefficients[a]).sum();
        residual_ss += (r - t) * (r - t);
        values.push((t, at));
    }
    let n = samples.len() as f64;
    let mean = values.iter().map(|v| v.0).sum::<f64>() / n;
    let trend_ss: f64 = values.iter().map(|v| (v.0 - mean).powi(2)).sum();
    let residual_var = residual_ss / (n - p as f64).max(1.0);
    // (noise alone gives the p − 1 non-constant terms a sum of squares of
    // (p − 1)·σ², over the samples that count as independent)
    let noise_ss = (p - 1) as f64 * residual_var / independent.max(1e-3);
    let significance = if noise_ss > 0.0 {
        (trend_ss / noise_ss).sqrt()
    } else if trend_ss > 0.0 {
        f64::INFINITY
    } else {
        0.0
    };
    let k = ((values.len() - 1) as f64 * SPREAD_PERCENTILE).round() as usize;
    let by_value = |a: &(f64, [u32; 3]), b: &(f64, [u32; 3])| a.0.total_cmp(&b.0);
    let low = *values.select_nth_unstable_by(k, by_value).1;
    let high_rank = values.len() - 1 - k;
    let high = *values[k..]
        .select_nth_unstable_by(high_rank - k, by_value)
        .1;
    let explained = trend_ss / (trend_ss + residual_ss).max(f64::MIN_POSITIVE);
    Some(Fit {
        spread: (high.0 - low.0).max(0.0),
        significance,
        explained,
        low_at: low.1.map(f64::from),
        high_at: high.1.map(f64::from),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `side`² two-phase image: a bright disk of 0.7 on 0.3, plus `ramp`
    /// times x/side and a deterministic ripple of ±0.02; its labels.
    fn disk(side: usize, ramp: f64) -> (Vec<f32>, Vec<u8>) {
        let mut data = Vec::with_capacity(side * side);
        let mut labels = Vec::with_capacity(side * side);
        let c = side as f64 / 2.0;
        for y in 0..side {
            for x in 0..side {
                let inside = (x as f64 - c).powi(2) + (y as f64 - c).powi(2) < (c / 2.0).powi(2);
                let ripple = 0.02 * (((x * 7919 + y * 104729) % 13) as f64 / 6.0 - 1.0);
                let level = if inside { 0.7 } else { 0.3 };
                data.push((level + ramp * x as f64 / side as f64 + ripple) as f32);
                labels.push(u8::from(inside));
            }
        }
        (data, labels)
    }

    fn trends(data: &[f32], labels: &[u8], side: usize) -> Vec<PhaseTrend> {
        let view = ImageView::new_2d(side, side, data).unwrap();
        let noise = FitNoise {
            correlation: Some(0.0),
        };
        phase_trends(&view, labels, &[Some(0.3), Some(0.7)], noise, 1.0)
    }

    #[test]
    fn a_flat_image_has_no_trend_and_a_ramp_is_measured() {
        let (data, labels) = disk(96, 0.0);
        let flat = trends(&data, &labels, 96);
        assert_eq!(flat.len(), 2);
        assert!(flat.iter().all(|t| t.ratio < 0.05 && !t.warned), "{flat:?}");
        let (data, labels) = disk(96, 0.2);
        let ramp = trends(&data, &labels, 96);
        // the background spans nearly the whole width: a spread near 0.2
        let background = &ramp[0];
        assert!(
            (background.trend - 0.2).abs() < 0.03 && background.warned,
            "{ramp:?}"
        );
        assert!(background.darkest_at[0] < 10.0 && background.brightest_at[0] > 85.0);
        let warning = background.warning(false);
        assert!(
            warning.starts_with("phase 0's intensity drifts smoothly by 0.19"),
            "{warning}"
        );
    }

    #[test]
    fn interior_samples_are_those_of_a_uniform_box() {
        // a 20 × 12 image: label 1 in a 3-wide column at x = 10..13
        let (w, h) = (20, 12);
        let labels: Vec<u8> = (0..w * h)
            .map(|i| u8::from((10..13).contains(&(i % w))))
            .collect();
        let interior = interior_labels(&labels, [w, h, 1]);
        for i in 0..w * h {
            let x = i % w;
            // the box test, sample by sample
            let (y, r) = (i / w, INTERIOR_RADIUS);
            let uniform = (y.saturating_sub(r)..(y + r + 1).min(h)).all(|yy| {
                (x.saturating_sub(r)..(x + r + 1).min(w)).all(|xx| labels[yy * w + xx] == labels[i])
            });
            let expected = if uniform { labels[i] } else { NOT_INTERIOR };
            assert_eq!(interior[i], expected, "x = {x}, y = {y}");
        }
        assert_eq!(
            interior[5 * w + 2],
            0,
            "3 from the border, 7 from the column"
        );
        assert_eq!(interior[5 * w + 6], 0);
        assert_eq!(interior[5 * w + 7], NOT_INTERIOR);
        assert!(
            (0..w * h).all(|i| interior[i] != 1),
            "the column is too narrow"
        );
    }

    #[test]
    fn a_large_image_is_taken_on_a_coarser_grid() {
        let grid = Grid::new([1024, 1024, 1]);
        assert_eq!(grid.stride, 4);
        assert!(grid.points().count() <= MAX_FIT_SAMPLES);
        let grid = Grid::new([100, 100, 100]);
        assert!(grid.points().count() <= MAX_FIT_SAMPLES && grid.stride == 3);
    }

    #[test]
    fn a_volume_with_a_bias_is_measured_in_three_dimensions() {
        let n = 40;
        let mut data = Vec::new();
        let mut labels = Vec::new();
        for z in 0..n {
            for _y in 0..n {
                for x in 0..n {
                    let bright = x >= n / 2;
                    let level = if bright { 0.7 } else { 0.3 };
                    data.push((level * (1.0 + 0.6 * z as f64 / n as f64)) as f32);
                    labels.push(u8::from(bright));
                }
            }
        }
        let view = ImageView::new_3d([n; 3], &data).unwrap();
        let noise = FitNoise { correlation: None };
        let found = phase_trends(&view, &labels, &[Some(0.4), Some(0.9)], noise, 1.0);
        assert_eq!(found.len(), 2);
        assert!(found.iter().all(|t| t.warned), "{found:?}");
        assert!(found[1].warning(true).contains("z = "));
    }
}
