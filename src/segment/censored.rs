//! Intensities clipped at the ends of their range (saturation): the
//! censored-Gaussian model the partial-volume estimate uses to stay
//! unbiased where the data saturate.
//!
//! A detector or an encoding saturates: an 8-bit photograph stores
//! `clip(μ + n, 0, 255)`, a CT is clipped at −1024 HU, the benchmark
//! phantoms at 0 and 1. A pixel whose noise-free intensity is `μ`, with
//! Gaussian noise of standard deviation `σ`, then has the expectation
//!
//! ```text
//! g(μ) = E[clip(μ + σZ, lo, hi)]
//!      = μ + (lo − μ)·Φ(a) + σ·φ(a) − (μ − hi)·Q(b) − σ·φ(b),   a = (lo − μ)/σ, b = (hi − μ)/σ
//! ```
//!
//! (`Φ` the normal distribution function, `Q = 1 − Φ`, `φ` the density; a
//! missing limit drops its terms), a curve that bends towards the limit
//! within about two `σ` of it and is the identity far from it.
//!
//! * **Limits.** An end of the intensities is a saturation limit when at
//!   least [`SATURATED_FRACTION`] of the pixels/voxels sit exactly on the
//!   extreme value, more than [`PILE_RATIO`] times as many as on the next
//!   value inward: clipping piles a whole tail of the noise onto it, which
//!   unclipped data (one extreme pixel, a thin quantised tail, a few
//!   evenly held levels) do not.
//! * **A phase's latent level.** The mean of a phase's clipped pixels
//!   estimates `g(μ)`, not `μ`. The maximum-likelihood fit of a Gaussian
//!   censored at the limits (the Tobit model: a pixel on a limit says only
//!   that its latent value lies beyond it) recovers `μ` and `σ` from the
//!   same pixels; [`fit_censored`] runs the expectation–maximisation
//!   iteration on the pixels' sufficient statistics.

/// Fraction of the pixels/voxels that must hold exactly the extreme value
/// for that end to count as a saturation limit. A Gaussian tail of 3σ
/// clipped off a phase covering a tenth of the image puts 0.013 % there;
/// a level within 2σ of the limit, 2.3 % of the phase.
pub const SATURATED_FRACTION: f64 = 1e-3;

/// How many times the next value inward an extreme value must hold to be
/// a limit: clipping piles a whole tail onto the extreme, while coarsely
/// quantised or textured data hold about as much on their extreme value as
/// next to it.
pub const PILE_RATIO: usize = 2;

/// Fewest pixels inside the limits for which a censored fit is attempted;
/// below that (a phase all on a limit, or nearly), its level is its mean.
const MIN_INSIDE: usize = 8;

/// A value and how many of a set hold it (`==`: a `-0.0` and a `0.0` both).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Held {
    /// The first of the equal values by [`f32::total_cmp`] (`-0.0` before
    /// `0.0`), as `Iterator::min_by(f32::total_cmp)` gives it.
    value: f32,
    count: usize,
}

impl Held {
    fn new(value: f32) -> Self {
        Held { value, count: 1 }
    }

    /// Counts `v`, equal to the value held.
    fn hold(&mut self, v: f32) {
        self.count += 1;
        if v.total_cmp(&self.value).is_lt() {
            self.value = v;
        }
    }
}

/// The lowest value of a set of finite values seen one at a time, and the
/// lowest of those above it, each with how many hold it.
#[derive(Clone, Copy, Debug, Default)]
struct LowEnd {
    extreme: Option<Held>,
    next: Option<Held>,
}

impl LowEnd {
    fn add(&mut self, v: f32) {
        match &mut self.extreme {
            None => self.extreme = Some(Held::new(v)),
            Some(e) if v < e.value => {
                // (the old lowest is below every other value above `v`)
                self.next = Some(*e);
                *e = Held::new(v);
            }
            Some(e) if v == e.value => e.hold(v),
            Some(_) => match &mut self.next {
                Some(n) if v > n.value => {}
                Some(n) if v == n.value => n.hold(v),
                _ => self.next = Some(Held::new(v)),
            },
        }
    }
}

/// The saturation limits of a set of intensities.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Limits {
    /// The lowest value, when the data saturate there.
    pub low: Option<f64>,
    /// The highest value, when the data saturate there.
    pub high: Option<f64>,
}

impl Limits {
    /// No saturation.
    pub const NONE: Limits = Limits {
        low: None,
        high: None,
    };

    /// The limits of `values`: each extreme value held by at least
    /// [`SATURATED_FRACTION`] of them and by more than [`PILE_RATIO`] times
    /// as many as the next value inward.
    pub fn detect(values: &[f32]) -> Limits {
        // (one pass for both ends: the seven passes of min, max, their
        // counts and their next values inward were a tenth of the
        // measurements after a 2048² run; the high end is the low end of
        // the negated values, which reverses `f32::total_cmp` exactly)
        let (mut low, mut high) = (LowEnd::default(), LowEnd::default());
        for &v in values.iter().filter(|v| v.is_finite()) {
            low.add(v);
            high.add(-v);
        }
        let (Some(min), Some(max)) = (low.extreme, high.extreme) else {
            return Limits::NONE;
        };
        if min.value == -max.value {
            return Limits::NONE;
        }
        let needed = (SATURATED_FRACTION * values.len() as f64).max(2.0);
        let piled = |end: Held, next: Option<Held>| {
            end.count as f64 >= needed && end.count > PILE_RATIO * next.map_or(0, |n| n.count)
        };
        Limits {
            low: piled(min, low.next).then_some(f64::from(min.value)),
            high: piled(max, high.next).then_some(f64::from(-max.value)),
        }
    }

    /// Whether either end saturates.
    pub fn any(&self) -> bool {
        self.low.is_some() || self.high.is_some()
    }

    /// Which side of the limits `v` lies on: below or on the low limit,
    /// inside, on or above the high one.
    pub fn side(&self, v: f64) -> Side {
        if self.low.is_some_and(|lo| v <= lo) {
            Side::Low
        } else if self.high.is_some_and(|hi| v >= hi) {
            Side::High
        } else {
            Side::Inside
        }
    }

    /// `g(μ)`: the expectation of `clip(μ + σZ)` at these limits.
    pub fn clipped_mean(&self, mu: f64, sigma: f64) -> f64 {
        if sigma <= 0.0 {
            let above_low = self.low.map_or(mu, |lo| mu.max(lo));
            return self.high.map_or(above_low, |hi| above_low.min(hi));
        }
        let mut g = mu;
        if let Some(lo) = self.low {
            let a = (lo - mu) / sigma;
            g += (lo - mu) * normal_cdf(a) + sigma * normal_pdf(a);
        }
        if let Some(hi) = self.high {
            let b = (hi - mu) / sigma;
            g -= (mu - hi) * normal_cdf(-b) + sigma * normal_pdf(b);
        }
        g
    }
}

/// Where a value lies against the [`Limits`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// On or below the low limit.
    Low,
    /// Strictly between the limits.
    Inside,
    /// On or above the high limit.
    High,
}

/// Sufficient statistics of a censored sample: the pixels inside the
/// limits (count, sum, sum of squares) and how many sit on each limit.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CensoredSample {
    /// Pixels strictly inside the limits.
    pub inside: usize,
    /// Sum of their values.
    pub sum: f64,
    /// Sum of their squares.
    pub sum_sq: f64,
    /// Pixels on the low limit.
    pub low: usize,
    /// Pixels on the high limit.
    pub high: usize,
}

impl CensoredSample {
    /// Adds one value.
    pub fn add(&mut self, v: f64, limits: &Limits) {
        match limits.side(v) {
            Side::Low => self.low += 1,
            Side::High => self.high += 1,
            Side::Inside => {
                self.inside += 1;
                self.sum += v;
                self.sum_sq += v * v;
            }
        }
    }

    /// Adds another sample's statistics.
    pub fn merge(&mut self, other: &CensoredSample) {
        self.inside += other.inside;
        self.sum += other.sum;
        self.sum_sq += other.sum_sq;
        self.low += other.low;
        self.high += other.high;
    }

    /// All pixels counted.
    pub fn len(&self) -> usize {
        self.inside + self.low + self.high
    }

    /// Whether no pixel was counted.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Mean and population variance of the recorded (clipped) values.
    pub fn clipped_moments(&self, limits: &Limits) -> (f64, f64) {
        let n = self.len().max(1) as f64;
        let lo = limits.low.unwrap_or(0.0);
        let hi = limits.high.unwrap_or(0.0);
        let sum = self.sum + self.low as f64 * lo + self.high as f64 * hi;
        let sum_sq = self.sum_sq + self.low as f64 * lo * lo + self.high as f64 * hi * hi;
        let mean = sum / n;
        (mean, (sum_sq / n - mean * mean).max(0.0))
    }
}

/// A Gaussian's mean and standard deviation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gaussian {
    /// Mean.
    pub mean: f64,
    /// Standard deviation.
    pub sd: f64,
}

/// The maximum-likelihood Gaussian of a sample censored at `limits` (the
/// Tobit model), by expectation–maximisation: each pixel on a limit stands
/// for the Gaussian's tail beyond it, whose first two moments replace its
/// value until the mean and standard deviation settle. Without censored
/// pixels, or with fewer than a handful inside the limits (nothing to fit
/// a spread from), it is the sample's own mean and standard deviation.
pub fn fit_censored(sample: &CensoredSample, limits: &Limits) -> Gaussian {
    let (mean, variance) = sample.clipped_moments(limits);
    let mut fit = Gaussian {
        mean,
        sd: variance.sqrt(),
    };
    if sample.low + sample.high == 0 || sample.inside < MIN_INSIDE || fit.sd <= 0.0 {
        return fit;
    }
    let n = sample.len() as f64;
    for _ in 0..2000 {
        let (mut sum, mut sum_sq) = (sample.sum, sample.sum_sq);
        let Gaussian { mean: mu, sd: s } = fit;
        if let (Some(lo), true) = (limits.low, sample.low > 0) {
            // Moments of X given X < lo: μ − σλ and μ² + σ² − σλ(lo + μ).
            let a = (lo - mu) / s;
            let lambda = normal_pdf(a) / normal_cdf(a).max(f64::MIN_POSITIVE);
            sum += sample.low as f64 * (mu - s * lambda);
            sum_sq += sample.low as f64 * (mu * mu + s * s - s * lambda * (lo + mu));
        }
        if let (Some(hi), true) = (limits.high, sample.high > 0) {
            // Moments of X given X > hi: μ + σλ and μ² + σ² + σλ(hi + μ).
            let b = (hi - mu) / s;
            let lambda = normal_pdf(b) / normal_cdf(-b).max(f64::MIN_POSITIVE);
            sum += sample.high as f64 * (mu + s * lambda);
            sum_sq += sample.high as f64 * (mu * mu + s * s + s * lambda * (hi + mu));
        }
        let mean = sum / n;
        let next = Gaussian {
            mean,
            sd: (sum_sq / n - mean * mean).max(0.0).sqrt(),
        };
        let settled = (next.mean - mu).abs() <= 1e-12 * (1.0 + mu.abs())
            && (next.sd - s).abs() <= 1e-12 * (1.0 + s);
        if !(next.sd > 0.0 && next.mean.is_finite()) {
            break;
        }
        fit = next;
        if settled {
            break;
        }
    }
    fit
}

/// Points of the [`Curvature`] tables.
const TABLE_POINTS: usize = 65;

/// What clipping adds to a pixel mixing two phases, beyond the straight
/// line between the phases' clipped means: over the fraction `f` of phase
/// `a`, `c(f) = g(μ(f)) − (1 − f)·g(μ_b) − f·g(μ_a)` with `μ(f) = μ_b +
/// f·(μ_a − μ_b)` and the noise's standard deviation interpolated alike;
/// tabulated against `g(μ(f))` so that a local mean of clipped intensities
/// finds it.
#[derive(Clone, Debug, PartialEq)]
pub struct Curvature {
    /// `g(μ(f))` at evenly spaced `f` from 0 to 1, made monotone.
    clipped: Vec<f64>,
    /// `c(f)` at the same points.
    excess: Vec<f64>,
}

impl Curvature {
    /// The table between phase `b` (fraction 0) and phase `a` (fraction 1).
    pub fn new(a: Gaussian, b: Gaussian, limits: &Limits) -> Curvature {
        let at = |f: f64| {
            let mu = b.mean + f * (a.mean - b.mean);
            let sd = b.sd + f * (a.sd - b.sd);
            limits.clipped_mean(mu, sd)
        };
        let (g0, g1) = (at(0.0), at(1.0));
        let step = 1.0 / (TABLE_POINTS - 1) as f64;
        let mut clipped = Vec::with_capacity(TABLE_POINTS);
        let mut excess = Vec::with_capacity(TABLE_POINTS);
        let rising = g1 >= g0;
        for k in 0..TABLE_POINTS {
            let f = k as f64 * step;
            let g = at(f);
            excess.push(g - (g0 + f * (g1 - g0)));
            // Keep the table monotone (it is, unless the two noise levels
            // differ wildly) so that it can be searched.
            let g = match clipped.last() {
                Some(&last) if rising => g.max(last),
                Some(&last) => g.min(last),
                None => g,
            };
            clipped.push(g);
        }
        Curvature { clipped, excess }
    }

    /// `c` at the mixture whose clipped mean is `local_mean` (0 beyond the
    /// two phases' own clipped means).
    pub fn at(&self, local_mean: f64) -> f64 {
        let (first, last) = (self.clipped[0], self.clipped[TABLE_POINTS - 1]);
        if first == last {
            return 0.0;
        }
        // Position along the table, rising from 0 to 1.
        let u = (local_mean - first) / (last - first);
        if !(u > 0.0 && u < 1.0) {
            return 0.0;
        }
        let rank = |g: f64| (g - first) / (last - first);
        let k = self.clipped[1..].partition_point(|&g| rank(g) < u);
        let (r0, r1) = (rank(self.clipped[k]), rank(self.clipped[k + 1]));
        let t = if r1 > r0 { (u - r0) / (r1 - r0) } else { 0.0 };
        self.excess[k] + t * (self.excess[k + 1] - self.excess[k])
    }
}

/// The standard normal density.
fn normal_pdf(x: f64) -> f64 {
    (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

/// The standard normal distribution function.
pub(super) fn normal_cdf(x: f64) -> f64 {
    0.5 * libm::erfc(-x / std::f64::consts::SQRT_2)
}

/// The `q`-quantile of the standard normal distribution (`Φ⁻¹(q)`, by
/// bisection; `q` in `(0, 1)`).
pub(super) fn normal_quantile(q: f64) -> f64 {
    let (mut lo, mut hi) = (-12.0, 12.0);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if normal_cdf(mid) < q {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_quantile_inverts_the_distribution_function() {
        for q in [0.01, 0.25, 0.5, 0.75, 0.9] {
            assert!((normal_cdf(normal_quantile(q)) - q).abs() < 1e-12, "{q}");
        }
        assert!((normal_quantile(0.75) - 0.674_489_75).abs() < 1e-6);
    }

    /// Deterministic standard normal quantiles for `n` evenly spaced levels.
    fn normal_sample(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| normal_quantile((i as f64 + 0.5) / n as f64))
            .collect()
    }

    #[test]
    fn clipped_mean_matches_a_clipped_sample() {
        let limits = Limits {
            low: Some(0.0),
            high: Some(1.0),
        };
        let z = normal_sample(20_000);
        for (mu, sigma) in [(0.2, 0.2), (0.8, 0.2), (0.5, 0.4), (-0.1, 0.3), (0.5, 0.0)] {
            let sample: f64 = z
                .iter()
                .map(|z| (mu + sigma * z).clamp(0.0, 1.0))
                .sum::<f64>()
                / z.len() as f64;
            let g = limits.clipped_mean(mu, sigma);
            assert!((g - sample).abs() < 1e-4, "{mu} {sigma}: {g} vs {sample}");
        }
        // Far from the limits g is the identity; without limits always.
        assert!((limits.clipped_mean(0.5, 0.05) - 0.5).abs() < 1e-12);
        assert_eq!(Limits::NONE.clipped_mean(7.0, 3.0), 7.0);
    }

    #[test]
    fn the_censored_fit_recovers_the_latent_gaussian() {
        let limits = Limits {
            low: Some(0.0),
            high: Some(1.0),
        };
        let z = normal_sample(20_000);
        for (mu, sigma) in [(0.2, 0.2), (0.85, 0.15), (0.05, 0.1)] {
            let mut sample = CensoredSample::default();
            for z in &z {
                sample.add((mu + sigma * z).clamp(0.0, 1.0), &limits);
            }
            assert!(sample.low + sample.high > 0);
            let (clipped, _) = sample.clipped_moments(&limits);
            assert!((clipped - mu).abs() > 0.005, "{mu}: no bias to remove");
            let fit = fit_censored(&sample, &limits);
            assert!((fit.mean - mu).abs() < 2e-3, "{mu}: {fit:?}");
            assert!((fit.sd - sigma).abs() < 2e-3, "{sigma}: {fit:?}");
        }
    }

    /// [`Limits::detect`] as it was first written, pass by pass: the
    /// reference of the one-pass scan.
    fn detect_pass_by_pass(values: &[f32]) -> Limits {
        let finite = || values.iter().copied().filter(|v| v.is_finite());
        let (Some(min), Some(max)) = (
            finite().min_by(f32::total_cmp),
            finite().max_by(f32::total_cmp),
        ) else {
            return Limits::NONE;
        };
        if min == max {
            return Limits::NONE;
        }
        let count = |x: f32| finite().filter(|&v| v == x).count();
        let needed = (SATURATED_FRACTION * values.len() as f64).max(2.0);
        let piled = |end: f32, next: Option<f32>| {
            let held = count(end);
            held as f64 >= needed && held > PILE_RATIO * next.map_or(0, count)
        };
        let above_min = finite().filter(|&v| v > min).min_by(f32::total_cmp);
        let below_max = finite().filter(|&v| v < max).max_by(f32::total_cmp);
        Limits {
            low: piled(min, above_min).then_some(f64::from(min)),
            high: piled(max, below_max).then_some(f64::from(max)),
        }
    }

    /// A few levels (signed zeros, infinities and NaN among them), drawn
    /// with piles on either end now and then.
    fn level() -> impl Strategy<Value = f32> {
        prop_oneof![
            4 => (-3i32..=3).prop_map(|i| i as f32 * 0.5),
            1 => Just(-0.0f32),
            1 => Just(f32::NAN),
            1 => Just(f32::INFINITY),
            1 => Just(f32::NEG_INFINITY),
            2 => -2.0f32..2.0,
        ]
    }

    proptest! {
        #[test]
        fn one_pass_limits_are_the_pass_by_pass_ones(values in prop::collection::vec(level(), 0..60)) {
            let (fast, slow) = (Limits::detect(&values), detect_pass_by_pass(&values));
            // (bit for bit: a -0.0 limit must stay -0.0)
            prop_assert_eq!(fast.low.map(f64::to_bits), slow.low.map(f64::to_bits));
            prop_assert_eq!(fast.high.map(f64::to_bits), slow.high.map(f64::to_bits));
        }
    }

    #[test]
    fn limits_need_a_pile_of_pixels_on_the_extreme() {
        // A ramp: every value once, no saturation.
        let ramp: Vec<f32> = (0..1000).map(|i| i as f32 / 999.0).collect();
        assert_eq!(Limits::detect(&ramp), Limits::NONE);
        // Clipped at the top: 5 % on the maximum.
        let clipped: Vec<f32> = ramp.iter().map(|&v| v.min(0.95)).collect();
        let limits = Limits::detect(&clipped);
        assert_eq!(limits.low, None);
        assert_eq!(limits.high, Some(f64::from(0.95f32)));
        assert_eq!(Limits::detect(&[0.5; 10]), Limits::NONE);
        // Eleven levels held evenly (a coarse texture): no pile.
        let levels: Vec<f32> = (0..1100).map(|i| (i % 11) as f32).collect();
        assert_eq!(Limits::detect(&levels), Limits::NONE);
        // The same with a tenth of the values clipped onto the top level.
        let piled: Vec<f32> = levels
            .iter()
            .enumerate()
            .map(|(i, &v)| if i % 10 == 0 { 10.0 } else { v })
            .collect();
        assert_eq!(Limits::detect(&piled).high, Some(10.0));
    }

    #[test]
    fn the_curvature_vanishes_at_the_phases_and_without_limits() {
        let limits = Limits {
            low: Some(0.0),
            high: Some(1.0),
        };
        let a = Gaussian { mean: 0.8, sd: 0.2 };
        let b = Gaussian { mean: 0.6, sd: 0.2 };
        let table = Curvature::new(a, b, &limits);
        let (gb, ga) = (limits.clipped_mean(0.6, 0.2), limits.clipped_mean(0.8, 0.2));
        assert_eq!(table.at(gb), 0.0);
        assert_eq!(table.at(ga), 0.0);
        // Halfway in the latent intensity: g bends below the chord towards
        // the high limit.
        let mid = limits.clipped_mean(0.7, 0.2);
        let expect = mid - 0.5 * (ga + gb);
        assert!(expect > 0.002, "{expect}");
        assert!((table.at(mid) - expect).abs() < 1e-5);
        let flat = Curvature::new(a, b, &Limits::NONE);
        assert!(flat.at(0.7).abs() < 1e-12);
    }
}
