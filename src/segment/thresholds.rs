//! Thresholds that split the histogram into `N` classes of least
//! within-class variance: the start of the default initialisation
//! ([`Init::Histogram`](super::params::Init::Histogram)).
//!
//! Up to [`EXACT_MAX_PHASES`] classes the split is exact: multi-level Otsu,
//! i.e. the minimum of `Σ_k Σ_{I ∈ class k} (I − m_k)²` over all splits of
//! the bins into contiguous classes, by dynamic programming in
//! `O(N·B²)` for `B` bins. Beyond, k-means with k-means++ seeding on the
//! histogram (a few deterministic restarts, the best kept). Both read the
//! histogram over the robust range, so a few outliers neither stretch the
//! bins nor get a class of their own unless they are numerous.

use super::intensity::Histogram;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

/// Largest number of classes split exactly (multi-Otsu); more use k-means++.
pub const EXACT_MAX_PHASES: usize = 8;

/// k-means++ restarts for many classes.
const KMEANS_RESTARTS: u64 = 8;

/// A split of the intensities into classes, ordered by increasing intensity.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Classes {
    /// `N − 1` increasing thresholds: class `k` holds `t_{k−1} ≤ I < t_k`.
    pub thresholds: Vec<f64>,
    /// Mean of each class (`None` for a class without samples).
    pub means: Vec<Option<f64>>,
    /// Samples per class.
    pub counts: Vec<f64>,
    /// Within-class sum of squared deviations.
    pub sse: f64,
}

impl Classes {
    /// The class of intensity `v`.
    pub fn class_of(&self, v: f64) -> usize {
        self.thresholds.partition_point(|&t| t <= v)
    }
}

/// The least-variance split of `hist` into `n ≥ 1` classes (exact for
/// `n ≤` [`EXACT_MAX_PHASES`]).
pub fn split_histogram(hist: &Histogram, n: usize) -> Classes {
    let starts = if n <= EXACT_MAX_PHASES {
        multi_otsu(hist, n)
    } else {
        kmeans(hist, n)
    };
    classes_from_starts(hist, &starts)
}

/// The smallest gap between the means of the least-variance split of `hist`
/// into `n ≥ 2` classes; `None` when fewer than two classes hold samples.
pub fn smallest_class_gap(hist: &Histogram, n: usize) -> Option<f64> {
    let means: Vec<f64> = split_histogram(hist, n)
        .means
        .into_iter()
        .flatten()
        .collect();
    means
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|&g| g > 0.0)
        .reduce(f64::min)
}

/// Prefix sums over the bins: `(count, sum, sum_sq)` of bins `0..b` at `b`.
struct Prefix {
    c: Vec<f64>,
    s: Vec<f64>,
    q: Vec<f64>,
}

impl Prefix {
    fn new(h: &Histogram) -> Self {
        let mut p = Prefix {
            c: vec![0.0],
            s: vec![0.0],
            q: vec![0.0],
        };
        for b in 0..h.bins() {
            p.c.push(p.c[b] + h.count[b]);
            p.s.push(p.s[b] + h.sum[b]);
            p.q.push(p.q[b] + h.sum_sq[b]);
        }
        p
    }

    /// `(count, sum, Σ(I − mean)²)` of bins `i..j`.
    fn class(&self, i: usize, j: usize) -> (f64, f64, f64) {
        let c = self.c[j] - self.c[i];
        let s = self.s[j] - self.s[i];
        let q = self.q[j] - self.q[i];
        let sse = if c > 0.0 {
            (q - s * s / c).max(0.0)
        } else {
            0.0
        };
        (c, s, sse)
    }
}

/// The first bin of each class after the first (`n − 1` increasing bins) of
/// the exact least-variance split, by dynamic programming.
fn multi_otsu(h: &Histogram, n: usize) -> Vec<usize> {
    let bins = h.bins();
    let n = n.clamp(1, bins);
    let p = Prefix::new(h);
    // best[k][j]: least SSE of bins 0..j in k + 1 classes; from[k][j]: start of the last.
    let mut best = vec![vec![f64::INFINITY; bins + 1]; n];
    let mut from = vec![vec![0usize; bins + 1]; n];
    for (j, b) in best[0].iter_mut().enumerate().skip(1) {
        *b = p.class(0, j).2;
    }
    for k in 1..n {
        for j in (k + 1)..=bins {
            for i in k..j {
                let e = best[k - 1][i] + p.class(i, j).2;
                if e < best[k][j] {
                    best[k][j] = e;
                    from[k][j] = i;
                }
            }
        }
    }
    let mut starts = vec![0; n - 1];
    let mut j = bins;
    for k in (1..n).rev() {
        starts[k - 1] = from[k][j];
        j = from[k][j];
    }
    starts
}

/// The first bin of each class after the first of a k-means split of the
/// bins (k-means++ seeding, Lloyd iterations; the best of a few seeded restarts).
fn kmeans(h: &Histogram, n: usize) -> Vec<usize> {
    let bins = h.bins();
    let value: Vec<f64> = (0..bins)
        .map(|b| {
            if h.count[b] > 0.0 {
                h.sum[b] / h.count[b]
            } else {
                h.low + (b as f64 + 0.5) * h.width
            }
        })
        .collect();
    let mut best: Option<(f64, Vec<usize>)> = None;
    for seed in 0..KMEANS_RESTARTS {
        let mut centres = seed_plus_plus(h, &value, n, seed);
        let mut starts = Vec::new();
        for _ in 0..100 {
            centres.sort_by(f64::total_cmp);
            starts = (1..centres.len())
                .map(|k| {
                    let mid = 0.5 * (centres[k - 1] + centres[k]);
                    value.partition_point(|&v| v < mid)
                })
                .collect();
            let new = class_centres(h, &starts, &centres);
            if new == centres {
                break;
            }
            centres = new;
        }
        let sse = classes_from_starts(h, &starts).sse;
        if best.as_ref().is_none_or(|(e, _)| sse < *e) {
            best = Some((sse, starts));
        }
    }
    best.map(|(_, s)| s).unwrap_or_default()
}

/// k-means++ seeding on the bins, weighted by their counts.
fn seed_plus_plus(h: &Histogram, value: &[f64], n: usize, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let total: f64 = h.count.iter().sum();
    let pick = |rng: &mut ChaCha8Rng, weights: &[f64], sum: f64| -> usize {
        let mut r = rng.random::<f64>() * sum;
        for (b, &w) in weights.iter().enumerate() {
            r -= w;
            if r <= 0.0 && w > 0.0 {
                return b;
            }
        }
        weights.iter().rposition(|&w| w > 0.0).unwrap_or(0)
    };
    let mut centres = vec![value[pick(&mut rng, &h.count, total)]];
    while centres.len() < n {
        let d2: Vec<f64> = (0..h.bins())
            .map(|b| {
                let d = centres
                    .iter()
                    .map(|c| (value[b] - c).abs())
                    .fold(f64::INFINITY, f64::min);
                h.count[b] * d * d
            })
            .collect();
        let sum: f64 = d2.iter().sum();
        if sum <= 0.0 {
            // Fewer distinct values than classes: spread the rest evenly.
            let c = h.low + h.width * h.bins() as f64 * centres.len() as f64 / n as f64;
            centres.push(c);
        } else {
            centres.push(value[pick(&mut rng, &d2, sum)]);
        }
    }
    centres
}

/// The mean of each class given by `starts` (the old centre for an empty class).
fn class_centres(h: &Histogram, starts: &[usize], old: &[f64]) -> Vec<f64> {
    let p = Prefix::new(h);
    let edges = class_edges(h.bins(), starts);
    edges
        .windows(2)
        .zip(old)
        .map(|(w, &o)| {
            let (c, s, _) = p.class(w[0], w[1]);
            if c > 0.0 {
                s / c
            } else {
                o
            }
        })
        .collect()
}

/// `0, starts…, bins`.
fn class_edges(bins: usize, starts: &[usize]) -> Vec<usize> {
    let mut e = Vec::with_capacity(starts.len() + 2);
    e.push(0);
    e.extend_from_slice(starts);
    e.push(bins);
    e
}

/// The classes of a split at `starts`: means, counts, SSE, and thresholds
/// half-way between the neighbouring occupied bins' means across each
/// split (so a split inside a run of empty bins lies in the middle of the gap).
fn classes_from_starts(h: &Histogram, starts: &[usize]) -> Classes {
    let p = Prefix::new(h);
    let edges = class_edges(h.bins(), starts);
    let mut means = Vec::new();
    let mut counts = Vec::new();
    let mut sse = 0.0;
    for w in edges.windows(2) {
        let (c, s, e) = p.class(w[0], w[1]);
        means.push((c > 0.0).then(|| s / c));
        counts.push(c);
        sse += e;
    }
    let bin_mean = |b: usize| h.sum[b] / h.count[b];
    let thresholds = starts
        .iter()
        .map(|&s| {
            let below = (0..s).rev().find(|&b| h.count[b] > 0.0);
            let above = (s..h.bins()).find(|&b| h.count[b] > 0.0);
            match (below, above) {
                (Some(a), Some(b)) => 0.5 * (bin_mean(a) + bin_mean(b)),
                _ => h.low + s as f64 * h.width,
            }
        })
        .collect();
    Classes {
        thresholds,
        means,
        counts,
        sse,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hist(data: &[f32]) -> Histogram {
        let lo = data.iter().copied().fold(f32::INFINITY, f32::min) as f64;
        let hi = data.iter().copied().fold(f32::NEG_INFINITY, f32::max) as f64;
        Histogram::new(data, lo, hi)
    }

    /// Three clusters of given sizes around 0, 1 and 5.
    fn clusters() -> Vec<f32> {
        let mut d = Vec::new();
        for i in 0..300 {
            d.push((i % 7) as f32 * 0.01);
        }
        for i in 0..100 {
            d.push(1.0 + (i % 5) as f32 * 0.01);
        }
        for i in 0..50 {
            d.push(5.0 + (i % 3) as f32 * 0.01);
        }
        d
    }

    #[test]
    fn multi_otsu_finds_the_clusters() {
        let h = hist(&clusters());
        let c = split_histogram(&h, 3);
        assert_eq!(c.counts, vec![300.0, 100.0, 50.0]);
        assert!(c.thresholds[0] > 0.06 && c.thresholds[0] < 1.0, "{c:?}");
        assert!(c.thresholds[1] > 1.04 && c.thresholds[1] < 5.0, "{c:?}");
        assert_eq!(c.class_of(0.5), if 0.5 < c.thresholds[0] { 0 } else { 1 });
        assert_eq!(c.class_of(6.0), 2);
    }

    #[test]
    fn multi_otsu_is_the_least_variance_split() {
        // Against brute force over every pair of split bins.
        let data: Vec<f32> = (0..2000)
            .map(|i| ((i * 7919 % 997) as f32 / 997.0).powi(3))
            .collect();
        let h = hist(&data);
        let p = Prefix::new(&h);
        let bins = h.bins();
        let mut brute = f64::INFINITY;
        for a in 1..bins {
            for b in a + 1..bins {
                brute = brute.min(p.class(0, a).2 + p.class(a, b).2 + p.class(b, bins).2);
            }
        }
        let c = split_histogram(&h, 3);
        assert!((c.sse - brute).abs() <= 1e-9 * brute, "{} {brute}", c.sse);
    }

    #[test]
    fn kmeans_splits_many_clusters_and_is_deterministic() {
        let mut d = Vec::new();
        for k in 0..12 {
            for i in 0..100 {
                d.push(k as f32 + (i % 5) as f32 * 0.02);
            }
        }
        let h = hist(&d);
        let c = split_histogram(&h, 12);
        assert_eq!(c.counts, vec![100.0; 12], "{c:?}");
        assert_eq!(c, split_histogram(&h, 12));
    }
}
