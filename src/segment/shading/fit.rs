//! The least-squares quadratic fit of one phase's residuals, its spread
//! and its significance.

use super::grid::Grid;
use super::parts::Sample;
use super::SPREAD_PERCENTILE;
use nalgebra::{DMatrix, DVector};

/// A phase's fitted trend.
pub(super) struct Fit {
    /// Its spread (1st to 99th percentile of its values over the samples).
    pub(super) spread: f64,
    /// Its root-mean-square over what noise alone would give it.
    pub(super) significance: f64,
    /// The share of the residuals' variance it explains.
    pub(super) explained: f64,
    /// The positions of its values at those percentiles.
    pub(super) low_at: [f64; 3],
    pub(super) high_at: [f64; 3],
    /// Its value at each sample.
    pub(super) values: Vec<f64>,
}

/// Least-squares quadratic fit of the residuals of `samples`; `independent`
/// is the share of them counted as independent. `None` when the fit is
/// degenerate (too few distinct positions).
pub(super) fn fit_trend(grid: &Grid, samples: &[Sample], independent: f64) -> Option<Fit> {
    match grid.axes() {
        1 => fit_terms::<3>(grid, samples, independent),
        2 => fit_terms::<6>(grid, samples, independent),
        _ => fit_terms::<10>(grid, samples, independent),
    }
}

/// [`fit_trend`] with the `P` monomials of the grid's axes.
fn fit_terms<const P: usize>(grid: &Grid, samples: &[Sample], independent: f64) -> Option<Fit> {
    let coefficients = solve::<P>(grid, samples)?;
    let mut values = Vec::with_capacity(samples.len());
    let mut residual_ss = 0.0;
    for s in samples {
        let phi = grid.basis::<P>(s.at);
        let t: f64 = (0..P).map(|a| phi[a] * coefficients[a]).sum();
        residual_ss += (s.residual - t) * (s.residual - t);
        values.push(t);
    }
    let n = samples.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let trend_ss: f64 = values.iter().map(|v| (v - mean).powi(2)).sum();
    let residual_var = residual_ss / (n - P as f64).max(1.0);
    // (noise alone gives the P − 1 non-constant terms a sum of squares of
    // (P − 1)·σ², over the samples that count as independent)
    let noise_ss = (P - 1) as f64 * residual_var / independent.max(1e-3);
    let significance = if noise_ss > 0.0 {
        (trend_ss / noise_ss).sqrt()
    } else if trend_ss > 0.0 {
        f64::INFINITY
    } else {
        0.0
    };
    let (low, high) = percentiles(&values);
    let place = |v: f64| {
        let i = values.iter().position(|&t| t == v).expect("a value");
        samples[i].at.map(f64::from)
    };
    Some(Fit {
        spread: (high - low).max(0.0),
        significance,
        explained: trend_ss / (trend_ss + residual_ss).max(f64::MIN_POSITIVE),
        low_at: place(low),
        high_at: place(high),
        values,
    })
}

/// The coefficients of the least-squares fit of the residuals of
/// `samples` by the `P` monomials of their positions.
fn solve<const P: usize>(grid: &Grid, samples: &[Sample]) -> Option<DVector<f64>> {
    let mut normal = [[0.0; P]; P];
    let mut rhs = [0.0; P];
    for s in samples {
        let phi = grid.basis::<P>(s.at);
        for a in 0..P {
            rhs[a] += phi[a] * s.residual;
            for b in a..P {
                normal[a][b] += phi[a] * phi[b];
            }
        }
    }
    let normal = DMatrix::<f64>::from_fn(P, P, |a, b| normal[a.min(b)][a.max(b)]);
    let rhs = DVector::<f64>::from_column_slice(&rhs);
    normal.svd(true, true).solve(&rhs, 1e-9).ok()
}

/// The values at the [`SPREAD_PERCENTILE`] and at its complement of
/// `values` (not empty).
fn percentiles(values: &[f64]) -> (f64, f64) {
    let mut sorted = values.to_vec();
    let k = ((sorted.len() - 1) as f64 * SPREAD_PERCENTILE).round() as usize;
    let low = *sorted.select_nth_unstable_by(k, f64::total_cmp).1;
    let high_rank = sorted.len() - 1 - k;
    let high = *sorted[k..]
        .select_nth_unstable_by(high_rank - k, f64::total_cmp)
        .1;
    (low, high)
}
