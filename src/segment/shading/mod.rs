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
//! the reach of an edge's blur; `interior`), taken on a grid of at most
//! [`MAX_FIT_SAMPLES`] (`grid`), are fitted by a quadratic polynomial of
//! the position (least squares, `fit`; a ramp and a vignette are both in
//! it). The fitted trend's spread over the phase's samples (the 1st to the
//! 99th percentile of its values) is weighed against the gap between the
//! phase's mean and the nearest other mean: where it reaches
//! [`MIN_TREND_RATIO`] of the gap, lies beyond the noise of the fit by
//! [`MIN_SIGNIFICANCE`] and is seen inside the phase's parts (`parts`),
//! the run warns.
//!
//! A texture is not a polynomial of low order and adds to the residual the
//! fit leaves rather than to the trend. Objects of different brightness in
//! one phase (a photograph's sky and lawn, cells of several intensities)
//! do give the fit a trend, from the steps between them; but light that
//! varies across the field changes the intensity inside every object as
//! well, at the slope the fit found. So the phase's interior samples are
//! cut into connected parts, each inside one of [`BLOCKS`] blocks of the
//! image (8 along each axis in 2D, 4 in 3D), and the residuals are
//! regressed on the fitted trend within the parts (each part's mean taken
//! out): a trend of light gives a slope near 1, steps between objects a
//! slope near 0. A phase is warned of only where that slope reaches
//! [`MIN_WITHIN_SHARE`].
//!
//! The thresholds come from measurement (`benches/RESULTS.md`, "Uneven
//! illumination"): on the clean benchmark phantoms the ratio reaches 0.49
//! where the close phases leave few interior samples, but the significance
//! stays at or under 2; every ramp of illumination of a tenth of the
//! intensity or more, and scikit-image's `page`, reach both, and in each
//! of those 2D runs a phase warned of shows the trend inside its parts with
//! a slope of 0.72 or more (0.65 or more on the 3D ramps, whose parts are
//! fewer voxels across). Photographs whose phases join objects of
//! different brightness reach the ratio and the significance but not the
//! slope; a smooth gradient inside the regions of a phase (a sky, a lit
//! wall) is a trend of light, and is warned of.

mod fit;
mod grid;
mod interior;
mod parts;

use super::image::ImageView;
use super::missed_objects::{correlation_and_share, present_means};
use fit::fit_trend;
use grid::Grid;
use interior::interior_labels;
use parts::{phase_samples, within_share};
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

/// Blocks the image is cut into for the parts a trend must be seen in, as
/// many along every axis (8 × 8 in 2D, 4 × 4 × 4 in 3D): a part then spans
/// enough of a trend of light to show its slope against the noise, in a
/// volume as in an image, and the steps between objects that touch fall
/// mostly between parts.
pub const BLOCKS: usize = 64;

/// The least slope of the residuals on the fitted trend within the parts
/// for a warning: at least half the trend is seen inside the parts. The
/// phases warned of on the shaded benchmark phantoms give 0.51 or more
/// (median 0.98); a photograph's phase joining sky and lawn gives 0.01,
/// six discs of three levels in one phase 0.04.
pub const MIN_WITHIN_SHARE: f64 = 0.5;

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
    /// The slope of the residuals on the trend within the phase's parts
    /// (connected, each inside one of [`BLOCKS`] blocks of the image): about 1 for a trend of light, about 0 for steps between
    /// objects of different brightness.
    pub within: f64,
    /// Where the trend is lowest (its 1st percentile), in pixel or voxel
    /// indices (x, y, z).
    pub darkest_at: [f64; 3],
    /// Where it is highest (its 99th percentile).
    pub brightest_at: [f64; 3],
    /// Whether the run warns of it ([`MIN_TREND_RATIO`],
    /// [`MIN_SIGNIFICANCE`], [`MIN_WITHIN_SHARE`]).
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
             illumination or a bias field, which one mean per phase cannot follow, so parts of the image may carry the wrong \
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
    let found = phase_samples(&grid, &interior, image.data, means);
    let (_, independent) = correlation_and_share(noise.correlation);
    let mut trends = Vec::new();
    for &(phase, mean) in &present {
        let samples = &found.samples[found.ranges[phase as usize].clone()];
        if samples.len() < MIN_FIT_SAMPLES {
            continue;
        }
        let Some(fit) = fit_trend(&grid, samples, independent) else {
            continue;
        };
        let within = within_share(samples, &fit.values, found.parts);
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
            within,
            darkest_at: fit.low_at,
            brightest_at: fit.high_at,
            warned: ratio >= MIN_TREND_RATIO
                && fit.significance >= MIN_SIGNIFICANCE
                && within >= MIN_WITHIN_SHARE,
        });
    }
    trends
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

    /// A `side`² image of six discs in one phase (label 1) on a flat
    /// background of 0.2 (label 0): three columns of discs at 0.55, 0.7 and
    /// 0.85 from left to right, plus `ramp` times x/side and uniform noise
    /// of ±0.1; its labels.
    fn discs(side: usize, ramp: f64) -> (Vec<f32>, Vec<u8>) {
        let s = side as f64;
        let r2 = (s / 10.0).powi(2);
        let mut state = 12345u64;
        let mut data = Vec::with_capacity(side * side);
        let mut labels = Vec::with_capacity(side * side);
        for y in 0..side {
            for x in 0..side {
                let (px, py) = (x as f64, y as f64);
                let column = (0..3).find(|&c| {
                    let cx = s * (1.0 + 2.0 * c as f64) / 6.0;
                    [s / 4.0, 3.0 * s / 4.0]
                        .iter()
                        .any(|cy| (px - cx).powi(2) + (py - cy).powi(2) < r2)
                });
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let noise = 0.2 * ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
                let level = column.map_or(0.2, |c| 0.55 + 0.15 * c as f64);
                data.push((level + ramp * px / s + noise) as f32);
                labels.push(u8::from(column.is_some()));
            }
        }
        (data, labels)
    }

    #[test]
    fn discs_of_different_brightness_in_one_phase_are_not_a_trend() {
        let side = 192;
        let (data, labels) = discs(side, 0.0);
        let view = ImageView::new_2d(side, side, &data).unwrap();
        let noise = FitNoise {
            correlation: Some(0.0),
        };
        let found = phase_trends(&view, &labels, &[Some(0.2), Some(0.7)], noise, 1.0);
        let ones = &found[1];
        // the fit over the whole phase follows the discs' levels, ...
        assert!(ones.ratio > 0.5 && ones.significance > 20.0, "{found:?}");
        // ... which no disc shows inside
        assert!(ones.within.abs() < 0.25, "{found:?}");
        assert!(found.iter().all(|t| !t.warned), "{found:?}");
        // light rising across the image is seen in the background
        let (data, labels) = discs(side, 0.3);
        let view = ImageView::new_2d(side, side, &data).unwrap();
        let found = phase_trends(&view, &labels, &[Some(0.35), Some(0.85)], noise, 1.0);
        let background = &found[0];
        assert!(
            background.warned && (background.within - 1.0).abs() < 0.1,
            "{found:?}"
        );
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
