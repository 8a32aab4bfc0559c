//! Objects the result left out: regions of the image that look like one
//! phase, lie inside another and hold none of the first phase's labels.
//!
//! The length term removes structures narrower than the width its weight
//! sets, and the mesh cannot hold one much smaller than its cells; on a
//! micrograph of small bright spots that removes every spot of a few pixels
//! while the phase lives on in the larger ones, so no lost-phase check
//! fires. This check looks for such objects in the data itself: the image,
//! smoothed by a Gaussian of [`SMOOTHING`] pixels to keep single noisy
//! pixels out, is classified pixel by pixel to the nearest final phase
//! mean; a connected region (faces shared) of one class `c` that holds no
//! pixel labelled `c`, and whose pixels and neighbours all carry one other
//! label `j`, is a candidate. It counts as a missed object when its mean
//! intensity, unsmoothed, lies nearer `c`'s mean than `j`'s and differs from
//! `j`'s by at least [`MIN_SIGNIFICANCE`] standard errors of the noise: a
//! cluster of noise rarely does both. A region touching several labels (the
//! band a blurred edge leaves between two phases) is not counted: the
//! absorbed- and band-phase checks judge those. Nor are phases whose means
//! lie closer than [`MIN_GAP`] standard deviations of the smoothed noise:
//! there the classes follow the noise.

use super::image::ImageView;
use crate::phantom::blur::gaussian_blur_3d;
use serde::Serialize;

/// Standard deviation, in pixels or voxels, of the smoothing before the
/// pixels are classified.
pub const SMOOTHING: f64 = 1.0;

/// How many standard errors of the noise a region's mean must lie from the
/// enclosing phase's mean to count.
pub const MIN_SIGNIFICANCE: f64 = 8.0;

/// How many standard deviations of the smoothed image's noise two phases'
/// means must lie apart for its classes to tell them apart: closer means
/// leave noise clusters of one inside the other (at half the gap a quarter
/// of the pixels cross), and their unsmoothed means lean the same way.
pub const MIN_GAP: f64 = 6.0;

/// Objects of phase `phase` left inside phase `within` (output labels,
/// ordered by increasing mean).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MissedObjects {
    /// The phase the objects look like.
    pub phase: u8,
    /// The phase that holds them.
    pub within: u8,
    /// How many objects.
    pub count: usize,
    /// Their pixels or voxels in all.
    pub pixels: usize,
    /// The largest one's.
    pub largest: usize,
}

impl MissedObjects {
    /// The warning a user reads.
    pub fn warning(&self) -> String {
        format!(
            "{} objects that look like phase {} ({} pixels or voxels in all, the largest {}) \
             are labelled phase {}, which surrounds them: they are smaller than the length \
             weight and the edge length keep (lower --length-weight or --edge-length to keep them)",
            self.count, self.phase, self.pixels, self.largest, self.within
        )
    }
}

/// The missed objects of `labels` (output labels) over `image`, given each
/// output label's final mean (`None`: an empty phase) and the noise's
/// standard deviation; one entry per (phase, enclosing phase) pair, in
/// label order.
pub fn missed_objects(
    image: &ImageView<'_>,
    labels: &[u8],
    means: &[Option<f64>],
    noise: f64,
) -> Vec<MissedObjects> {
    let present: Vec<(u8, f64)> = means
        .iter()
        .enumerate()
        .filter_map(|(l, m)| m.map(|m| (l as u8, m)))
        .collect();
    let noise_measured = noise.is_finite() && noise > 0.0;
    if present.len() < 2 || !noise_measured || labels.len() != image.data.len() {
        return Vec::new();
    }
    let [nx, ny, nz] = image.dims;
    let smoothed_noise = noise * smoothing_attenuation(image.dims);
    let smoothed = gaussian_blur_3d(image.data, nx, ny, nz, SMOOTHING);
    let class: Vec<u8> = smoothed
        .iter()
        .map(|&v| nearest(&present, v as f64))
        .collect();
    let mut found: Vec<MissedObjects> = Vec::new();
    let mut seen = vec![false; labels.len()];
    let mut stack = Vec::new();
    let mut region = Vec::new();
    for start in 0..labels.len() {
        if seen[start] {
            continue;
        }
        region.clear();
        let c = class[start];
        let Some(j) = grow(
            start,
            &class,
            labels,
            image.dims,
            &mut seen,
            &mut stack,
            &mut region,
        ) else {
            continue;
        };
        let (Some(mc), Some(mj)) = (means[c as usize], means[j as usize]) else {
            continue;
        };
        if (mc - mj).abs() < MIN_GAP * smoothed_noise {
            continue;
        }
        let n = region.len() as f64;
        let mean = region.iter().map(|&i| image.data[i] as f64).sum::<f64>() / n;
        let nearer_c = (mean - mc).abs() < (mean - mj).abs();
        let significance = (mean - mj).abs() * n.sqrt() / noise;
        if nearer_c && significance >= MIN_SIGNIFICANCE {
            record(&mut found, c, j, region.len());
        }
    }
    found.sort_by_key(|m| (m.phase, m.within));
    found
}

/// The factor by which the smoothing lowers white noise's standard
/// deviation: `(4π σ²)^(−d/4)` over the `d` axes longer than one sample.
fn smoothing_attenuation(dims: [usize; 3]) -> f64 {
    let axes = dims.iter().filter(|&&n| n > 1).count() as f64;
    (4.0 * std::f64::consts::PI * SMOOTHING * SMOOTHING).powf(-axes / 4.0)
}

/// The label among `present` whose mean is nearest `v`.
fn nearest(present: &[(u8, f64)], v: f64) -> u8 {
    present
        .iter()
        .min_by(|a, b| (a.1 - v).abs().total_cmp(&(b.1 - v).abs()))
        .map_or(0, |p| p.0)
}

/// Grows the face-connected region of `start`'s class `c` into `region`
/// (and marks it seen); returns the one label `j` its pixels and their
/// neighbours outside it carry, or `None` if they carry several, if it is
/// `c`, or if a neighbour's class lies outside the range from `c` to `j`:
/// a lost object's neighbours look like `j` or like the blur between the
/// two, while a region next to a brighter or darker class is the rim of
/// something else (a corner the length term rounded off).
fn grow(
    start: usize,
    class: &[u8],
    labels: &[u8],
    dims: [usize; 3],
    seen: &mut [bool],
    stack: &mut Vec<usize>,
    region: &mut Vec<usize>,
) -> Option<u8> {
    let c = class[start];
    let mut single: Option<u8> = None;
    let mut mixed = false;
    let (mut lowest, mut highest) = (c, c);
    let mut note = |l: u8| match single {
        None => single = Some(l),
        Some(s) if s != l => mixed = true,
        Some(_) => {}
    };
    seen[start] = true;
    stack.push(start);
    while let Some(i) = stack.pop() {
        region.push(i);
        note(labels[i]);
        for n in face_neighbours(i, dims).into_iter().flatten() {
            if class[n] == c {
                if !seen[n] {
                    seen[n] = true;
                    stack.push(n);
                }
            } else {
                note(labels[n]);
                lowest = lowest.min(class[n]);
                highest = highest.max(class[n]);
            }
        }
    }
    let j = single.filter(|&j| !mixed && j != c)?;
    (lowest >= c.min(j) && highest <= c.max(j)).then_some(j)
}

/// The up to six face neighbours of linear index `i` in a volume of `dims`
/// (four in 2D).
fn face_neighbours(i: usize, [nx, ny, nz]: [usize; 3]) -> [Option<usize>; 6] {
    let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
    let plane = nx * ny;
    [
        (x > 0).then(|| i - 1),
        (x + 1 < nx).then(|| i + 1),
        (y > 0).then(|| i - nx),
        (y + 1 < ny).then(|| i + nx),
        (z > 0).then(|| i - plane),
        (z + 1 < nz).then(|| i + plane),
    ]
}

/// Adds one object of `pixels` to the (phase, within) entry of `found`.
fn record(found: &mut Vec<MissedObjects>, phase: u8, within: u8, pixels: usize) {
    match found
        .iter_mut()
        .find(|m| m.phase == phase && m.within == within)
    {
        Some(m) => {
            m.count += 1;
            m.pixels += pixels;
            m.largest = m.largest.max(pixels);
        }
        None => found.push(MissedObjects {
            phase,
            within,
            count: 1,
            pixels,
            largest: pixels,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 64² background at 0.2 with bright 3×3 squares at 0.8, noise-free
    /// but for a deterministic ripple of ±0.05.
    fn spots() -> (Vec<f32>, Vec<(usize, usize)>) {
        let side = 64;
        let centres = vec![(10, 10), (30, 12), (50, 40), (20, 50)];
        let mut data: Vec<f32> = (0..side * side)
            .map(|i| 0.2 + 0.05 * ((i * 7919 % 13) as f32 / 6.0 - 1.0))
            .collect();
        for &(cx, cy) in &centres {
            for y in cy - 1..=cy + 1 {
                for x in cx - 1..=cx + 1 {
                    data[y * side + x] = 0.8;
                }
            }
        }
        (data, centres)
    }

    #[test]
    fn spots_labelled_as_background_are_found() {
        let (data, _) = spots();
        let view = ImageView::new_2d(64, 64, &data).unwrap();
        let labels = vec![0u8; data.len()];
        let found = missed_objects(&view, &labels, &[Some(0.2), Some(0.8)], 0.03);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!((found[0].phase, found[0].within, found[0].count), (1, 0, 4));
        assert!(found[0]
            .warning()
            .contains("4 objects that look like phase 1"));
    }

    #[test]
    fn spots_labelled_as_themselves_are_not() {
        let (data, centres) = spots();
        let view = ImageView::new_2d(64, 64, &data).unwrap();
        let mut labels = vec![0u8; data.len()];
        for &(cx, cy) in &centres {
            labels[cy * 64 + cx] = 1;
        }
        let found = missed_objects(&view, &labels, &[Some(0.2), Some(0.8)], 0.03);
        assert!(found.is_empty(), "{found:?}");
    }

    #[test]
    fn a_cube_in_a_volume_is_found_through_its_faces() {
        // A 3×3×3 bright cube in a 12³ volume, labelled as the background,
        // and one labelled as itself.
        let n = 12;
        let index = |x: usize, y: usize, z: usize| (z * n + y) * n + x;
        let mut data = vec![0.1f32; n * n * n];
        let mut labels = vec![0u8; data.len()];
        for z in 2..5 {
            for y in 2..5 {
                for x in 2..5 {
                    data[index(x, y, z)] = 0.9;
                    data[index(x + 5, y + 5, z + 5)] = 0.9;
                    labels[index(x + 5, y + 5, z + 5)] = 1;
                }
            }
        }
        let view = ImageView::new_3d([n; 3], &data).unwrap();
        let found = missed_objects(&view, &labels, &[Some(0.1), Some(0.9)], 0.02);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!((found[0].phase, found[0].within, found[0].count), (1, 0, 1));
    }

    #[test]
    fn a_band_between_two_phases_is_not_an_object() {
        // Three columns of levels 0, 0.5 (a one-pixel band) and 1, the band
        // labelled as its left neighbour: it touches both other labels.
        let (w, h) = (21, 16);
        let data: Vec<f32> = (0..w * h)
            .map(|i| match i % w {
                x if x < 10 => 0.0,
                10 => 0.5,
                _ => 1.0,
            })
            .collect();
        let labels: Vec<u8> = (0..w * h)
            .map(|i| if i % w <= 10 { 0 } else { 2 })
            .collect();
        let view = ImageView::new_2d(w, h, &data).unwrap();
        let found = missed_objects(&view, &labels, &[Some(0.0), Some(0.5), Some(1.0)], 0.01);
        assert!(found.is_empty(), "{found:?}");
    }
}
