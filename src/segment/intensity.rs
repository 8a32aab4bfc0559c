//! The input's intensity scale: extremes, a robust range, a noise estimate
//! and a histogram, all equivariant under `I ↦ a·I + b`.
//!
//! The segmentation's energy `Σ (I − c)² + ν·length` is only meaningful when
//! ν is measured in the data's own units: a 12-bit camera image stored as
//! 16 bits, a CT slice in Hounsfield units and the same image scaled to
//! `[0, 1]` must give the same labels. Everything the driver needs to make ν
//! and its thresholds relative to the data is computed here, once.

use super::image::ImageView;
use super::integrate::CellStats;
use super::noise_correlation::noise_correlation;
use super::rank_select::{from_order_key, keys_of_ranks};
use serde::Serialize;

/// Fraction of the samples left out at each end of the robust range.
pub const ROBUST_TAIL: f64 = 0.001;

/// Largest number of samples the quantiles and the noise estimate read (an
/// evenly strided subset of larger inputs).
pub const MAX_SAMPLES: usize = 1 << 20;

/// Number of histogram bins between the robust range's ends.
pub const HISTOGRAM_BINS: usize = 256;

/// Intensity figures of an image or volume, in the units of its samples.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct IntensityStats {
    /// Smallest sample.
    pub min: f64,
    /// Largest sample.
    pub max: f64,
    /// The [`ROBUST_TAIL`] quantile: the robust range's lower end.
    pub low: f64,
    /// The `1 −` [`ROBUST_TAIL`] quantile: the robust range's upper end.
    pub high: f64,
    /// Standard deviation of the noise, estimated from the differences of
    /// neighbouring samples along x (median absolute difference / (0.6745·√2),
    /// robust to edges); 0 for noise-free data.
    pub noise: f64,
    /// Whether [`noise`](Self::noise) leaves out the pairs with a sample at
    /// the extreme (minimum or maximum) that more samples hold: the input is
    /// mostly one exact value (a skull-stripped MRI, a CT outside its field
    /// of view, a registered image's padding), whose pairs would make the
    /// estimate 0, or pull it down, whatever the noise of the rest. Only
    /// where that extreme forms regions (padding) or every pair gives 0; a
    /// noise-free image still gives 0 from the rest (the flat interiors of
    /// its other phases).
    pub noise_excludes_extremes: bool,
    /// A lower bound of the correlation of neighbouring samples' noise
    /// (see [`noise_correlation`](super::noise_correlation)): about 0 for
    /// white noise, high for smoothed noise or texture; `None` for
    /// noise-free data.
    pub noise_correlation: Option<f64>,
}

impl IntensityStats {
    /// The figures of `image` (finite samples, at least one).
    pub fn of(image: &ImageView<'_>) -> Self {
        let (min, max) = image.range().unwrap_or((0.0, 0.0));
        let (low, high) = image
            .known_robust_range()
            .unwrap_or_else(|| robust_range(image.data, (min, max), MAX_SAMPLES));
        let (noise, pairs) = noise_sigma(image, (min as f32, max as f32));
        IntensityStats {
            min,
            max,
            low,
            high,
            noise,
            noise_excludes_extremes: pairs != SamplePairs::All,
            noise_correlation: noise_correlation(image, noise, pairs),
        }
    }

    /// The robust range `high − low` (never zero for a non-constant image):
    /// the intensity scale the length weight is measured against.
    pub fn scale(&self) -> f64 {
        let s = self.high - self.low;
        if s > 0.0 {
            s
        } else {
            (self.max - self.min).max(f64::MIN_POSITIVE)
        }
    }

    /// The histogram of `image` over the robust range (samples beyond it
    /// count in the end bins, so a few outliers cannot stretch the bins).
    pub fn histogram(&self, image: &ImageView<'_>) -> Histogram {
        let mut h = Histogram::empty(self.low, self.low + self.scale());
        h.add_samples(image.data);
        h
    }

    /// The histogram of the cells' mean intensities over the robust range,
    /// each cell weighted by its pixels (its sums go to the bin of its mean).
    /// A cell's mean has the noise of one pixel divided by the square root of
    /// its pixel count, so the classes of this histogram separate where the
    /// pixels' histogram is one blur of overlapping noise.
    pub fn cell_histogram(&self, cells: &[CellStats]) -> Histogram {
        let mut h = Histogram::empty(self.low, self.low + self.scale());
        for c in cells {
            if let Some(m) = c.mean() {
                h.add(m, c.count as f64, c.sum, c.sum_sq);
            }
        }
        h
    }
}

/// The bin of a sample `x` bin widths above the histogram's low end, the
/// end bins taking what lies beyond them (and a NaN the first): the cast
/// saturates, and for `x ≥ 0` truncates as `floor` would, without its call
/// (a library function on CPUs without SSE4.1).
fn bin_index(x: f64, bins: usize) -> usize {
    (x as usize).min(bins - 1)
}

/// The robust range of `data`, whose extremes are `range`: its
/// [`ROBUST_TAIL`] and `1 −` [`ROBUST_TAIL`] quantiles among at most
/// `max_samples` evenly strided samples, or the extremes where most samples
/// share one value.
pub fn robust_range(data: &[f32], range: (f64, f64), max_samples: usize) -> (f64, f64) {
    let [low, high] = strided_quantiles(data, [ROBUST_TAIL, 1.0 - ROBUST_TAIL], max_samples);
    if high <= low {
        range
    } else {
        (low, high)
    }
}

/// The quantiles `q` of every k-th sample of `data`, so that at most
/// `max_samples` are read (see [`quantiles`]).
fn strided_quantiles<const R: usize>(data: &[f32], q: [f64; R], max_samples: usize) -> [f64; R] {
    let stride = data.len().div_ceil(max_samples).max(1);
    if stride == 1 {
        quantiles(|| data.iter().copied(), q)
    } else {
        quantiles(|| data.iter().step_by(stride).copied(), q)
    }
}

/// The quantiles `q` of the samples `samples()` yields (see
/// [`keys_of_ranks`]), each the sample of rank `round((n − 1)·q)` among
/// the `n` samples in [`f32::total_cmp`]'s order; 0 for no samples.
fn quantiles<const R: usize, I: Iterator<Item = f32>>(
    samples: impl Fn() -> I,
    q: [f64; R],
) -> [f64; R] {
    keys_of_ranks(samples, |n| q.map(|q| rank(n, q)))
        .map_or([0.0; R], |keys| keys.map(|k| from_order_key(k) as f64))
}

/// The rank of the `q` quantile among `n` samples.
fn rank(n: usize, q: f64) -> usize {
    ((n - 1) as f64 * q).round() as usize
}

/// Which pairs of neighbouring samples the noise figures read.
///
/// A skull-stripped MRI is three quarters background at exactly one value,
/// so three quarters of its neighbouring pairs differ by exactly 0 and
/// their median says "noise-free" however noisy the brain is: the
/// duplicate-phase tolerance, the re-seeds and the noise correlation figure
/// then work as on a noise-free image (and padding over less than half the
/// image still pulls the median down). Where the extreme that more samples
/// hold is padding ([`is_padding`]), or when every pair gives 0, the pairs
/// with a sample at it (the mask's value; both extremes if they are held by
/// as many, so that `−I` gives what `I` gives) are left out. Only the one: on a noise-free image with blurred
/// edges, leaving out both extremes of two phases would leave the edges'
/// pairs alone, and their differences would read as noise; with the
/// dominant one left out, the other phase's flat interior still gives 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum SamplePairs {
    /// Every pair.
    All,
    /// The pairs with neither sample equal to either of the two values
    /// (the dominant extreme twice, or the minimum and the maximum).
    OffExtremes(f32, f32),
}

impl SamplePairs {
    fn admits(self, a: f32, b: f32) -> bool {
        match self {
            SamplePairs::All => true,
            SamplePairs::OffExtremes(low, high) => a != low && a != high && b != low && b != high,
        }
    }
}

/// Noise standard deviation from the median absolute difference of
/// neighbouring samples along x (for Gaussian noise on a piecewise-constant
/// image, `|I(x+1) − I(x)|` away from edges has median `0.6745·√2·σ`), and
/// the pairs it read: those off the dominant one of the `(min, max)`
/// extremes where that extreme is padding ([`is_padding`]) or where all
/// the pairs give 0 (see [`SamplePairs`]), else all of them.
fn noise_sigma(image: &ImageView<'_>, extremes: (f32, f32)) -> (f64, SamplePairs) {
    let off_extremes = off_dominant_extreme(image.data, extremes);
    if !is_padding(image, off_extremes) {
        let all = median_difference_sigma(image, SamplePairs::All);
        if all > 0.0 {
            return (all, SamplePairs::All);
        }
    }
    match median_difference_sigma(image, off_extremes) {
        s if s > 0.0 => (s, off_extremes),
        _ => (0.0, SamplePairs::All),
    }
}

/// Of the pairs whose first sample is at the left-out extreme, the share
/// whose second is too, from which that extreme is padding.
const PADDING_CONTIGUITY: f64 = 0.9;

/// The share of all pairs that must lie in the padding for it to count.
const PADDING_SHARE: f64 = 0.05;

/// Whether the samples at the extreme `off` leaves out are padding (a mask,
/// a CT's outside of its field of view): regions, so that nearly every
/// neighbour of such a sample along x is one too ([`PADDING_CONTIGUITY`]),
/// over a share of the image ([`PADDING_SHARE`]). A CT whose round field
/// of view leaves a fifth of the slice at −2048 has a fifth of its pairs
/// there, each differing by 0, and its noise read 0.73 of the truth (0.21
/// at 45 %). Noise clipped at an extreme is not padding: a clipped
/// sample's neighbour is clipped only as often as any sample is (half the
/// time for a phase at the extreme itself), so the phantoms' estimates,
/// whose dark phases are clipped at 0, stay as they were.
fn is_padding(image: &ImageView<'_>, off: SamplePairs) -> bool {
    let (mut first_out, mut both_out, mut pairs) = (0usize, 0usize, 0usize);
    for row in image.data.chunks_exact(image.dims[0].max(1)) {
        for (&a, &b) in row.iter().zip(row.iter().skip(1)) {
            pairs += 1;
            if !off.admits(a, a) {
                first_out += 1;
                both_out += usize::from(!off.admits(b, b));
            }
        }
    }
    both_out as f64 >= PADDING_CONTIGUITY * first_out as f64
        && both_out as f64 >= PADDING_SHARE * pairs as f64
        && both_out > 0
}

/// The pairs off the extreme of `(min, max)` that more of `data` holds
/// (off both when they are held by as many).
fn off_dominant_extreme(data: &[f32], (min, max): (f32, f32)) -> SamplePairs {
    let held_by = |v: f32| data.iter().filter(|&&x| x == v).count();
    match held_by(min).cmp(&held_by(max)) {
        std::cmp::Ordering::Greater => SamplePairs::OffExtremes(min, min),
        std::cmp::Ordering::Less => SamplePairs::OffExtremes(max, max),
        std::cmp::Ordering::Equal => SamplePairs::OffExtremes(min, max),
    }
}

/// The median of `|I(x+1) − I(x)|` over the admitted pairs, in units of
/// the noise's standard deviation; 0 without pairs.
fn median_difference_sigma(image: &ImageView<'_>, pairs: SamplePairs) -> f64 {
    let [median] = if pair_count(image, 1) <= MAX_SAMPLES {
        quantiles(|| abs_differences(image, 1, pairs), [0.5])
    } else {
        quantiles(
            || strided_abs_differences(image, 1, MAX_SAMPLES, pairs),
            [0.5],
        )
    };
    median / (0.6745 * std::f64::consts::SQRT_2)
}

/// The number of pairs of samples `lag` apart along x.
fn pair_count(image: &ImageView<'_>, lag: usize) -> usize {
    let w = image.dims[0];
    match w.saturating_sub(lag) {
        0 => 0,
        per_row => image.data.len() / w * per_row,
    }
}

/// `|I(x+lag) − I(x)|` along x over the admitted pairs, row by row: the
/// differences of [`strided_abs_differences`] when it takes every pair,
/// without its division per pair.
fn abs_differences<'i>(
    image: &'i ImageView<'_>,
    lag: usize,
    pairs: SamplePairs,
) -> impl Iterator<Item = f32> + 'i {
    image
        .data
        .chunks_exact(image.dims[0].max(1))
        .flat_map(move |row| {
            let far = row.get(lag..).unwrap_or(&[]);
            row.iter()
                .zip(far)
                .filter(move |&(&a, &b)| pairs.admits(a, b))
                .map(|(&a, &b)| (b - a).abs())
        })
}

/// `|I(x+lag) − I(x)|` along x, over every k-th pair so that at most
/// `most` are taken (none when no pair fits in a row), of those `pairs`
/// admits.
pub(super) fn strided_abs_differences<'i>(
    image: &'i ImageView<'_>,
    lag: usize,
    most: usize,
    pairs: SamplePairs,
) -> impl Iterator<Item = f32> + 'i {
    let w = image.dims[0];
    let per_row = w.saturating_sub(lag);
    let count = pair_count(image, lag);
    let stride = count.div_ceil(most).max(1);
    (0..count).step_by(stride).filter_map(move |i| {
        let p = (i / per_row) * w + i % per_row;
        let (a, b) = (image.data[p], image.data[p + lag]);
        pairs.admits(a, b).then(|| (b - a).abs())
    })
}

/// Counts, sums and sums of squares of the samples per bin: within-class
/// variances of classes made of whole bins are exact.
#[derive(Clone, Debug)]
pub struct Histogram {
    /// Lower edge of the first bin.
    pub low: f64,
    /// Bin width.
    pub width: f64,
    /// Samples per bin.
    pub count: Vec<f64>,
    /// Sum of the samples per bin.
    pub sum: Vec<f64>,
    /// Sum of the squared samples per bin.
    pub sum_sq: Vec<f64>,
}

impl Histogram {
    /// [`HISTOGRAM_BINS`] empty bins over `[low, high]` (`high > low`).
    pub fn empty(low: f64, high: f64) -> Self {
        let bins = HISTOGRAM_BINS;
        Histogram {
            low,
            width: (high - low) / bins as f64,
            count: vec![0.0; bins],
            sum: vec![0.0; bins],
            sum_sq: vec![0.0; bins],
        }
    }

    /// The histogram of `data` over `[low, high]` (`high > low`).
    pub fn new(data: &[f32], low: f64, high: f64) -> Self {
        let mut h = Self::empty(low, high);
        h.add_samples(data);
        h
    }

    /// Adds each sample of `data` as one count: as [`add`](Self::add) with
    /// count 1, in one loop over the samples (the image's whole histogram
    /// is a pass over its pixels).
    pub fn add_samples(&mut self, data: &[f32]) {
        let bins = self.count.len();
        let (low, width) = (self.low, self.width);
        let high = low + bins as f64 * width;
        let count = &mut self.count[..bins];
        let sum = &mut self.sum[..bins];
        let sum_sq = &mut self.sum_sq[..bins];
        for &v in data {
            let v = v as f64;
            let end = if v < low || v > high {
                v.clamp(low, high)
            } else {
                v
            };
            let b = bin_index((v - low) / width, bins);
            count[b] += 1.0;
            sum[b] += end;
            sum_sq[b] += end * end;
        }
    }

    /// Adds `count` samples with the given sums to the bin of `at`. Samples
    /// at a value outside the range count in the end bins as if they were
    /// at the range's end (winsorised): the class means and variances the
    /// thresholds are chosen by then stay within the range, where one
    /// saturated pixel of a 16-bit image that uses a small part of its range
    /// would otherwise hold most of the variance and take a class to itself.
    pub fn add(&mut self, at: f64, count: f64, sum: f64, sum_sq: f64) {
        let bins = self.count.len();
        let high = self.low + bins as f64 * self.width;
        let (sum, sum_sq) = if at < self.low || at > high {
            let end = at.clamp(self.low, high);
            (count * end, count * end * end)
        } else {
            (sum, sum_sq)
        };
        let b = bin_index((at - self.low) / self.width, bins);
        self.count[b] += count;
        self.sum[b] += sum;
        self.sum_sq[b] += sum_sq;
    }

    /// Number of bins.
    pub fn bins(&self) -> usize {
        self.count.len()
    }

    /// The intensity at the upper edge of bin `b`.
    pub fn upper_edge(&self, b: usize) -> f64 {
        self.low + (b + 1) as f64 * self.width
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The quantiles are the samples of their rank in
        /// `f32::total_cmp`'s order, bit for bit (negative zeros and
        /// infinities included).
        #[test]
        fn quantiles_by_key_are_the_ranked_samples(
            data in prop::collection::vec(
                prop_oneof![
                    -1e6f32..1e6,
                    Just(0.0f32),
                    Just(-0.0f32),
                    Just(f32::INFINITY),
                    Just(f32::NEG_INFINITY),
                ],
                1..400,
            ),
            q0 in 0.0f64..1.0,
            q1 in 0.0f64..1.0,
        ) {
            let (q0, q1) = (q0.min(q1), q0.max(q1));
            let mut sorted = data.clone();
            sorted.sort_by(f32::total_cmp);
            let expect = |q: f64| f64::from(sorted[rank(sorted.len(), q)]);
            let [a, b] = strided_quantiles(&data, [q0, q1], MAX_SAMPLES);
            prop_assert_eq!(a.to_bits(), expect(q0).to_bits());
            prop_assert_eq!(b.to_bits(), expect(q1).to_bits());
            let [c] = quantiles(|| data.iter().copied(), [q1]);
            prop_assert_eq!(c.to_bits(), expect(q1).to_bits());
        }

        /// The bin of a sample is `floor` of its offset in bin widths,
        /// clamped to the bins.
        #[test]
        fn bin_index_is_the_clamped_floor(x in -1e3f64..1e3) {
            let bins = HISTOGRAM_BINS;
            let expect = (x.floor().max(0.0) as usize).min(bins - 1);
            prop_assert_eq!(bin_index(x, bins), expect);
        }
    }

    /// The row-by-row differences are the strided ones when those take
    /// every pair, in the same order, of all pairs or those off two values.
    #[test]
    fn abs_differences_are_every_strided_pair() {
        let data: Vec<f32> = (0..7 * 5).map(|i| ((i * 37) % 11) as f32 * 0.1).collect();
        let image = ImageView::new_2d(7, 5, &data).unwrap();
        for lag in [1, 3, 6, 7] {
            for pairs in [SamplePairs::All, SamplePairs::OffExtremes(0.0, 0.5)] {
                let rows: Vec<f32> = abs_differences(&image, lag, pairs).collect();
                let strided: Vec<f32> =
                    strided_abs_differences(&image, lag, usize::MAX, pairs).collect();
                assert_eq!(rows, strided, "lag {lag}, {pairs:?}");
            }
            let all = abs_differences(&image, lag, SamplePairs::All).count();
            assert_eq!(all, pair_count(&image, lag), "lag {lag}");
        }
    }

    #[test]
    fn bin_index_sends_non_finite_offsets_to_the_end_bins() {
        assert_eq!(bin_index(f64::NAN, 8), 0);
        assert_eq!(bin_index(f64::NEG_INFINITY, 8), 0);
        assert_eq!(bin_index(f64::INFINITY, 8), 7);
    }

    #[test]
    fn stats_follow_an_affine_map() {
        let data: Vec<f32> = (0..10_000)
            .map(|i| ((i * 7919) % 1000) as f32 / 1000.0)
            .collect();
        let view = ImageView::new_2d(100, 100, &data).unwrap();
        let s = IntensityStats::of(&view);
        let mapped: Vec<f32> = data.iter().map(|&v| 300.0 * v - 20.0).collect();
        let view2 = ImageView::new_2d(100, 100, &mapped).unwrap();
        let t = IntensityStats::of(&view2);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-3 * b.abs().max(1.0);
        assert!(close(t.low, 300.0 * s.low - 20.0), "{t:?} {s:?}");
        assert!(close(t.high, 300.0 * s.high - 20.0));
        assert!(close(t.scale(), 300.0 * s.scale()));
        assert!(close(t.noise, 300.0 * s.noise));
    }

    /// A 200² image, three quarters exactly 0 (the mask) and a square of
    /// two levels under Gaussian noise of standard deviation 0.05.
    fn masked_square() -> Vec<f32> {
        let side = 200;
        let mut inside: Vec<f32> = (0..side * side)
            .map(|i| if i % side < 150 { 0.4 } else { 0.7 })
            .collect();
        crate::phantom::noise::add_gaussian_noise(&mut inside, 0.05, 7);
        (0..side * side)
            .map(|i| {
                let (x, y) = (i % side, i / side);
                if x >= 100 && y >= 100 {
                    inside[i]
                } else {
                    0.0
                }
            })
            .collect()
    }

    #[test]
    fn a_masked_image_reads_the_noise_inside_its_mask() {
        let data = masked_square();
        let s = IntensityStats::of(&ImageView::new_2d(200, 200, &data).unwrap());
        assert!(s.noise_excludes_extremes);
        assert!((s.noise - 0.05).abs() < 0.005, "{}", s.noise);
        assert!(s.noise_correlation.is_some_and(|rho| rho < 0.2), "{s:?}");
        // Negated, the mask is the maximum: the same figure.
        let negated: Vec<f32> = data.iter().map(|&v| -v).collect();
        let t = IntensityStats::of(&ImageView::new_2d(200, 200, &negated).unwrap());
        assert!(t.noise_excludes_extremes);
        assert!((t.noise - s.noise).abs() < 1e-6, "{} {}", t.noise, s.noise);
    }

    /// A CT-like 200² slice: air at −1000 and a disk of tissue at 40 under
    /// noise of standard deviation 26 inside a round field of view of
    /// radius `r`, −2048 outside it (a fifth of the slice at `r` 100).
    fn ct_slice(r: f64) -> Vec<f32> {
        let side = 200;
        let mut inside: Vec<f32> = (0..side * side)
            .map(|i| {
                let (x, y) = ((i % side) as f64 - 100.0, (i / side) as f64 - 100.0);
                if x.hypot(y) < 40.0 {
                    0.6
                } else {
                    0.2
                }
            })
            .collect();
        crate::phantom::noise::add_gaussian_noise(&mut inside, 0.01, 5);
        (0..side * side)
            .map(|i| {
                let (x, y) = ((i % side) as f64 - 100.0, (i / side) as f64 - 100.0);
                if x.hypot(y) < r {
                    -1000.0 + (inside[i] - 0.2) / 0.4 * 1040.0
                } else {
                    -2048.0
                }
            })
            .collect()
    }

    #[test]
    fn padding_outside_a_field_of_view_is_left_out() {
        // The noise: 0.01 of the 0.4 gap, 26 HU after the mapping.
        let truth = 0.01 / 0.4 * 1040.0;
        for r in [100.0, 80.0, 60.0] {
            let s = IntensityStats::of(&ImageView::new_2d(200, 200, &ct_slice(r)).unwrap());
            assert!(s.noise_excludes_extremes, "r {r}");
            assert!(
                (s.noise - truth).abs() < 0.1 * truth,
                "r {r}: {} against {truth}",
                s.noise
            );
        }
    }

    #[test]
    fn noise_clipped_at_an_extreme_is_not_padding() {
        // A dark phase at 0 under noise clipped at 0: half its samples are 0.
        let mut data: Vec<f32> = (0..200 * 200)
            .map(|i| if i % 200 < 120 { 0.0 } else { 0.6 })
            .collect();
        crate::phantom::noise::add_gaussian_noise(&mut data, 0.1, 3);
        let s = IntensityStats::of(&ImageView::new_2d(200, 200, &data).unwrap());
        assert!(!s.noise_excludes_extremes);
    }

    #[test]
    fn a_noise_free_image_with_blurred_edges_stays_noise_free() {
        // Two levels over a third and two thirds of each row, the edge a
        // ramp over 4 pixels: only the ramp's pairs differ.
        let ramp = |x: usize| ((x as f32 - 64.0) / 4.0).clamp(0.0, 1.0);
        let data: Vec<f32> = (0..200 * 200).map(|i| 0.3 + 0.4 * ramp(i % 200)).collect();
        let s = IntensityStats::of(&ImageView::new_2d(200, 200, &data).unwrap());
        assert_eq!((s.noise, s.noise_excludes_extremes), (0.0, false));
        assert_eq!(s.noise_correlation, None);
    }

    #[test]
    fn a_masked_noise_free_image_stays_noise_free() {
        let data: Vec<f32> = masked_square()
            .iter()
            .map(|&v| if v == 0.0 { 0.0 } else { 0.5 })
            .collect();
        let s = IntensityStats::of(&ImageView::new_2d(200, 200, &data).unwrap());
        assert_eq!((s.noise, s.noise_excludes_extremes), (0.0, false));
        assert_eq!(s.noise_correlation, None);
    }

    #[test]
    fn outliers_do_not_stretch_the_robust_range() {
        let mut data = vec![0.25f32; 100 * 100];
        for (i, v) in data.iter_mut().enumerate() {
            if (i % 100) >= 50 {
                *v = 0.5;
            }
        }
        data[17] = 60.0; // one hot pixel
        let view = ImageView::new_2d(100, 100, &data).unwrap();
        let s = IntensityStats::of(&view);
        assert_eq!(s.max, 60.0);
        assert_eq!((s.low, s.high), (0.25, 0.5));
        assert_eq!(s.noise, 0.0);
    }
}
