//! The parts of a phase the trend must be seen in: its interior samples
//! split into connected pieces, each inside one block of the image.
//!
//! Light that falls off across the field shifts every part of a phase by
//! the same smooth trend, so the slope of the trend fitted over the whole
//! phase is seen again inside each part. A phase that holds objects of
//! different brightness (a photograph's sky and lawn in one phase, discs
//! of several intensities) gives the fit a trend from the steps between
//! them, which no part shows inside: the residuals are flat within the
//! parts. [`within_share`] is the slope of the residuals on the fitted
//! trend within the parts, the share of the trend they show.

use super::grid::Grid;
use super::interior::NOT_INTERIOR;
use std::ops::Range;

/// A sample fitted: its (x, y, z) indices, its residual (sample − the
/// phase's mean) and the part it lies in.
#[derive(Clone, Copy, Debug)]
pub(super) struct Sample {
    pub(super) at: [u32; 3],
    pub(super) residual: f64,
    pub(super) part: u32,
}

/// The interior samples on the grid, grouped by label, and how many parts
/// they fall into.
pub(super) struct PhaseSamples {
    pub(super) samples: Vec<Sample>,
    /// Per label, its samples' range in `samples`.
    pub(super) ranges: Vec<Range<usize>>,
    pub(super) parts: usize,
}

/// No part yet (a grid point not interior, or of a phase not fitted).
const NONE: u32 = u32::MAX;

/// Union-find over provisional part ids; each root is its set's smallest id.
struct Partition {
    parent: Vec<u32>,
    label: Vec<u8>,
}

impl Partition {
    fn find(&mut self, mut p: u32) -> u32 {
        while self.parent[p as usize] != p {
            let grand = self.parent[self.parent[p as usize] as usize];
            self.parent[p as usize] = grand;
            p = grand;
        }
        p
    }

    fn union(&mut self, a: u32, b: u32) -> u32 {
        let (ra, rb) = (self.find(a), self.find(b));
        let (low, high) = (ra.min(rb), ra.max(rb));
        self.parent[high as usize] = low;
        low
    }

    /// `part` (a sample's part so far, or [`NONE`]) joined with its
    /// neighbour's `neighbour` where that is of `label`.
    #[inline]
    fn join(&mut self, part: u32, neighbour: u32, label: u8) -> u32 {
        if neighbour == NONE || self.label[neighbour as usize] != label || neighbour == part {
            part
        } else if part == NONE {
            neighbour
        } else {
            self.union(part, neighbour)
        }
    }

    fn add(&mut self, label: u8) -> u32 {
        let p = self.parent.len() as u32;
        self.parent.push(p);
        self.label.push(label);
        p
    }

    /// Dense ids `0..n` of the sets, by their roots' order, and `n`.
    fn dense(&mut self) -> (Vec<u32>, usize) {
        let mut dense = vec![NONE; self.parent.len()];
        let mut n = 0;
        for p in 0..self.parent.len() as u32 {
            let root = self.find(p);
            dense[p as usize] = if root == p {
                n += 1;
                n as u32 - 1
            } else {
                dense[root as usize]
            };
        }
        (dense, n)
    }
}

/// The grid points of `grid` whose `interior` label (see
/// [`interior_labels`](super::interior::interior_labels)) has a mean in
/// `means`, with their residuals from `data`, each given the connected
/// part (along the grid's axes, within one block) it lies in.
pub(super) fn phase_samples(
    grid: &Grid,
    interior: &[u8],
    data: &[f32],
    means: &[Option<f64>],
) -> PhaseSamples {
    let [ex, ey, ez] = grid.extent;
    let [nx, ny, _] = grid.dims;
    let starts_block = |a: usize| -> Vec<bool> {
        (0..grid.extent[a])
            .map(|g| g > 0 && grid.block(a, g) != grid.block(a, g - 1))
            .collect()
    };
    let starts = [starts_block(0), starts_block(1), starts_block(2)];
    let mut slot = vec![NONE; grid.count()];
    let mut partition = Partition {
        parent: Vec::new(),
        label: Vec::new(),
    };
    let mut samples = Vec::with_capacity(grid.count());
    for gz in 0..ez {
        for gy in 0..ey {
            for gx in 0..ex {
                let at = grid.at([gx, gy, gz]);
                let i = (at[2] * ny + at[1]) * nx + at[0];
                let label = interior[i];
                let mean = match means.get(label as usize) {
                    Some(Some(m)) if label != NOT_INTERIOR => *m,
                    _ => continue,
                };
                let g = (gz * ey + gy) * ex + gx;
                let mut part = NONE;
                if gx > 0 && !starts[0][gx] {
                    part = partition.join(part, slot[g - 1], label);
                }
                if gy > 0 && !starts[1][gy] {
                    part = partition.join(part, slot[g - ex], label);
                }
                if gz > 0 && !starts[2][gz] {
                    part = partition.join(part, slot[g - ex * ey], label);
                }
                if part == NONE {
                    part = partition.add(label);
                }
                slot[g] = part;
                samples.push(Sample {
                    at: at.map(|c| c as u32),
                    residual: f64::from(data[i]) - mean,
                    part,
                });
            }
        }
    }
    let (dense, parts) = partition.dense();
    let labels: Vec<u8> = samples
        .iter()
        .map(|s| partition.label[s.part as usize])
        .collect();
    for s in &mut samples {
        s.part = dense[s.part as usize];
    }
    let (samples, ranges) = group_by_label(samples, &labels, means.len());
    PhaseSamples {
        samples,
        ranges,
        parts,
    }
}

/// `samples` reordered so that each of the `n` labels' (`labels`, one per
/// sample) come together, in the order they came; each label's range.
fn group_by_label(
    samples: Vec<Sample>,
    labels: &[u8],
    n: usize,
) -> (Vec<Sample>, Vec<Range<usize>>) {
    let mut count = vec![0usize; n];
    for &l in labels {
        count[l as usize] += 1;
    }
    let mut ranges = Vec::with_capacity(n);
    let mut start = 0;
    for c in &count {
        ranges.push(start..start + c);
        start += c;
    }
    let mut next: Vec<usize> = ranges.iter().map(|r| r.start).collect();
    let blank = Sample {
        at: [0; 3],
        residual: 0.0,
        part: NONE,
    };
    let mut grouped = vec![blank; samples.len()];
    for (s, &l) in samples.into_iter().zip(labels) {
        grouped[next[l as usize]] = s;
        next[l as usize] += 1;
    }
    (grouped, ranges)
}

/// The slope of `samples`' residuals on `trend` (the fitted trend's value
/// at each sample) within their parts (each part's means taken out of
/// both; `parts` bounds the parts' ids): about 1 where the trend is seen
/// inside the parts as over the whole phase, about 0 where it only joins
/// parts of different levels. 0 when no part spans any of the trend.
pub(super) fn within_share(samples: &[Sample], trend: &[f64], parts: usize) -> f64 {
    let centre = trend.iter().sum::<f64>() / trend.len().max(1) as f64;
    let mut sums = vec![(0.0f64, 0.0f64, 0.0f64); parts];
    let (mut tt, mut tr) = (0.0, 0.0);
    for (s, &t) in samples.iter().zip(trend) {
        let t = t - centre;
        let sum = &mut sums[s.part as usize];
        sum.0 += 1.0;
        sum.1 += t;
        sum.2 += s.residual;
        tt += t * t;
        tr += t * s.residual;
    }
    for &(n, t, r) in sums.iter().filter(|s| s.0 > 0.0) {
        tt -= t * t / n;
        tr -= t * r / n;
    }
    if tt > 0.0 {
        tr / tt
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_are_connected_and_cut_at_the_blocks() {
        // a 64 × 8 image, label 0 but for a column of label 1 at x = 20:
        // label 0 left of it and right of it are apart, and each is cut at
        // every eighth of the width and of the height (every row)
        let (w, h) = (64, 8);
        let interior: Vec<u8> = (0..w * h).map(|i| u8::from(i % w == 20)).collect();
        let data = vec![0.0f32; w * h];
        let grid = Grid::new([w, h, 1]);
        let found = phase_samples(&grid, &interior, &data, &[Some(0.0), None]);
        assert_eq!(found.ranges[0].len(), (w - 1) * h);
        assert!(found.ranges[1].is_empty(), "label 1 has no mean");
        let part_at = |x: u32| {
            found
                .samples
                .iter()
                .find(|s| s.at == [x, 3, 0])
                .unwrap()
                .part
        };
        assert_eq!(part_at(16), part_at(19));
        assert_ne!(part_at(19), part_at(21), "the column parts them");
        assert_ne!(part_at(15), part_at(16), "a block's edge at x = 16");
        assert_eq!(found.parts, 9 * 8, "8 × 8 blocks, a column of them split");
    }

    #[test]
    fn the_within_share_is_one_for_a_shared_slope_and_zero_for_steps() {
        // two parts of 10 samples, at positions 0..10 and 10..20
        let sample = |x: u32, residual: f64| Sample {
            at: [x, 0, 0],
            residual,
            part: u32::from(x >= 10),
        };
        let trend: Vec<f64> = (0..20).map(|x| x as f64).collect();
        let ramp: Vec<Sample> = (0..20).map(|x| sample(x, x as f64)).collect();
        assert!((within_share(&ramp, &trend, 2) - 1.0).abs() < 1e-12);
        let steps: Vec<Sample> = (0..20)
            .map(|x| sample(x, if x >= 10 { 15.0 } else { 5.0 }))
            .collect();
        assert!(within_share(&steps, &trend, 2).abs() < 1e-12);
    }
}
