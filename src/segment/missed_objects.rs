//! Objects the result left out: regions of the image that look like one
//! phase, lie inside another and hold none of the first phase's labels.
//!
//! The length term removes structures narrower than the width its weight
//! sets, and the mesh cannot hold one much smaller than its cells; on a
//! micrograph of small bright spots that removes every spot of a few pixels
//! while the phase lives on in the larger ones, so no lost-phase check
//! fires. This check looks for such objects in the data itself: the image,
//! smoothed by a Gaussian of [`CHECK_SMOOTHING`] pixel to keep single noisy
//! pixels out ([`CheckImage`](super::check_image::CheckImage)), is classified pixel by pixel to the nearest final phase
//! mean; a connected region (faces shared) of one class `c` that holds no
//! pixel labelled `c`, whose pixels and neighbours all carry one other
//! label `j`, and whose neighbours look like `j` or like the blur between
//! `c` and `j`, is a candidate. It counts as a missed object when its mean
//! intensity, unsmoothed, lies nearer `c`'s mean than `j`'s and differs from
//! `j`'s by at least [`MIN_SIGNIFICANCE`] standard errors of the noise.
//!
//! A cluster of noise that crosses the midpoint in the smoothed image also
//! has an unsmoothed mean leaning towards `c`, so the significance, which
//! grows with the square root of the region's size, is the guard: it keeps
//! out the clusters the noise makes, which are small where the two means
//! lie far apart in units of the smoothed noise. Hence the other limits:
//! phases closer than [`MIN_GAP`] smoothed-noise deviations are not judged
//! (there the classes follow the noise); correlated noise (a neighbour
//! correlation `ρ`, measured with the noise, at most [`MAX_CORRELATION`])
//! widens the noise by `1/√(1 − ρ)` and shrinks the region's independent
//! samples by `(1 − ρ)/(1 + ρ)`, so that the gap and the significance
//! grow stricter as the noise grows smoother. A region touching several
//! labels (the band a blurred edge leaves between two phases) or beside a
//! third class (a corner the length term rounded off) is not counted.
//!
//! A region beside a core labelled with its class is the rim of an object
//! the labels kept: the rims of one core (of at most [`MAX_CORE`] samples;
//! a rim broken by the corners of a square core is several regions) are
//! gathered, and where the core holds under [`SHRUNK_SHARE`] of the object
//! it counts as kept smaller than it looks (a spot of a few cells whose
//! area comes out too small; [`MissedObjects::labelled`]).

use super::check_image::CHECK_SMOOTHING;
use super::image::ImageView;
use serde::Serialize;

/// How many standard errors of the noise a region's mean must lie from the
/// enclosing phase's mean to count.
pub const MIN_SIGNIFICANCE: f64 = 8.0;

/// How many standard deviations of the smoothed image's noise two phases'
/// means must lie apart for its classes to tell them apart: at 6 a pixel
/// of one crosses the midpoint with probability 0.13 %, at 3 with 6.7 %,
/// and such clusters of noise grow large enough to pass the significance.
pub const MIN_GAP: f64 = 6.0;

/// The share of an object's samples (those that look like its phase) below
/// which its label counts as shrunk: a spot of three pixels' radius labelled
/// as a 3×3 square holds a third; the boundaries of kept objects, where the
/// label and the smoothed image disagree by a pixel, hold far more.
pub const SHRUNK_SHARE: f64 = 2.0 / 3.0;

/// Fewest samples a region holds to count: one or two samples that look
/// like another phase are a hot or dead pixel (clamped as an outlier, it
/// still looks brighter than its phase) or a speck of noise, which no mesh
/// keeps and no option brings back.
pub const MIN_SAMPLES: usize = 3;

/// The largest neighbour correlation the noise is taken to have (a
/// correlation of 1 would make every region's samples one).
pub const MAX_CORRELATION: f64 = 0.95;

/// The noise the check weighs regions against: the run's estimate.
#[derive(Clone, Copy, Debug)]
pub struct Noise {
    /// Standard deviation from neighbouring samples' differences.
    pub sigma: f64,
    /// Neighbour correlation (`None`: not measured, taken as 0).
    pub correlation: Option<f64>,
}

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
    /// The largest one's (its labelled core with it).
    pub largest: usize,
    /// The largest one's centre, in pixel or voxel indices (x, y, z).
    pub largest_at: [f64; 3],
    /// Of their pixels or voxels, those labelled as the phase they look
    /// like: 0 for objects left out, under [`SHRUNK_SHARE`] of
    /// `pixels + labelled` for objects the labels kept smaller than they
    /// look (a core of a few cells).
    pub labelled: usize,
}

impl MissedObjects {
    /// The warning a user reads; `three_d` names voxels, and `adaptive`
    /// (the run's mesh) the option that gives it finer cells.
    pub fn warning(&self, three_d: bool, adaptive: bool) -> String {
        let (samples, at) = if three_d {
            let [x, y, z] = self.largest_at;
            ("voxels", format!("x = {x:.0}, y = {y:.0}, z = {z:.0}"))
        } else {
            let [x, y, _] = self.largest_at;
            ("pixels", format!("x = {x:.0}, y = {y:.0}"))
        };
        let finer = finer_cells(three_d, adaptive);
        if self.labelled > 0 {
            return self.shrunk_warning(samples, &at, finer);
        }
        let (what, them) = if self.count == 1 {
            (
                format!(
                    "1 object that looks like phase {} ({} {samples} centred at {at}) is",
                    self.phase, self.pixels
                ),
                "it",
            )
        } else {
            (
                format!(
                    "{} objects that look like phase {} ({} {samples} in all, the largest {} \
                     centred at {at}) are",
                    self.count, self.phase, self.pixels, self.largest
                ),
                "them",
            )
        };
        format!(
            "{what} labelled phase {}, which surrounds {them}: smaller or narrower than the \
             length weight and the mesh keep ({finer} may keep {them})",
            self.within
        )
    }

    /// The warning of objects the labels kept smaller than they look.
    fn shrunk_warning(&self, samples: &str, at: &str, finer: &str) -> String {
        let total = self.pixels + self.labelled;
        let (what, it, its) = if self.count == 1 {
            (
                format!(
                    "1 object that looks like phase {} ({total} {samples} centred at {at}) is \
                     labelled smaller than it looks",
                    self.phase
                ),
                "it",
                "its area is",
            )
        } else {
            (
                format!(
                    "{} objects that look like phase {} ({total} {samples} in all, the largest \
                     {} centred at {at}) are labelled smaller than they look",
                    self.count, self.phase, self.largest
                ),
                "them",
                "their areas are",
            )
        };
        format!(
            "{what}: {} of the {total} {samples} carry phase {}, the rest phase {}, so {its} \
             underestimated (objects of a few cells; {finer} may keep more of {it})",
            self.labelled, self.phase, self.within
        )
    }
}

/// The options that keep smaller objects, for a warning: a lower length
/// weight, and finer cells where the data asks for them. On the uniform 2D
/// mesh the adaptive one comes first: it refines where a cell's pixels are
/// not explained by its phase, so on the `thin` phantom at 512² (σ 0.1) it
/// left 660 pixels of such objects out with 6 274 triangles, where the
/// uniform mesh left 2 422 out at the default L = 8 px and 1 650 at
/// L = 4 px with 38 034 triangles.
fn finer_cells(three_d: bool, adaptive: bool) -> &'static str {
    match (adaptive, three_d) {
        (true, _) => "a lower --length-weight or --min-edge-length",
        (false, false) => "--adaptive, a lower --length-weight or a lower --edge-length",
        (false, true) => {
            "the adaptive mesh (without --uniform), a lower --length-weight or a lower \
             --edge-length"
        }
    }
}

/// The missed objects of `labels` (output labels) over `image`, which the
/// checks read as `smoothed`
/// ([`CheckImage`](super::check_image::CheckImage)), given each output
/// label's final mean in increasing order (`None`: an empty phase) and the
/// noise; one entry per (phase, enclosing phase) pair, in label order.
pub fn missed_objects(
    image: &ImageView<'_>,
    smoothed: &[f32],
    labels: &[u8],
    means: &[Option<f64>],
    noise: Noise,
) -> Vec<MissedObjects> {
    let present = present_means(means);
    let (rho, independent) = correlation_and_share(noise.correlation);
    if present.len() < 2 || labels.len() != image.data.len() || smoothed.len() != labels.len() {
        return Vec::new();
    }
    // (a clean image's noise is 0: a floor well below any contrast)
    let span = present.last().map_or(0.0, |l| l.1) - present[0].1;
    let sigma = (noise.sigma / (1.0 - rho).sqrt()).max(1e-3 * span.abs());
    if !sigma.is_finite() || sigma <= 0.0 {
        return Vec::new();
    }
    let smoothed_sigma = sigma * smoothing_attenuation(image.dims);
    let class: Vec<u8> = smoothed
        .iter()
        .map(|&v| nearest(&present, v as f64))
        .collect();
    let mut found: Vec<MissedObjects> = Vec::new();
    let mut seen = vec![false; labels.len()];
    let mut stack = Vec::new();
    let judge = Judge { sigma, independent };
    let mut cores = Cores::default();
    for start in 0..labels.len() {
        // (a region holding its class's label is no object: only samples
        // labelled otherwise than they look start or join one)
        if seen[start] || class[start] == labels[start] {
            continue;
        }
        let c = class[start];
        let region = grow(start, &class, labels, image, &mut seen, &mut stack);
        let Some(j) = region.enclosing else {
            continue;
        };
        let (Some(mc), Some(mj)) = (means[c as usize], means[j as usize]) else {
            continue;
        };
        if (mc - mj).abs() < MIN_GAP * smoothed_sigma {
            continue;
        }
        match region.own {
            // (the rim of a core labelled `c`: judged with the core's other rims)
            Some(at) => cores.add_rim(at, labels, image.dims, (c, j), region),
            None => {
                if looks_like_c(&region, (mc, mj), &judge) {
                    record(&mut found, (c, j), &region, 0);
                }
            }
        }
    }
    for (core, rim) in cores.rims() {
        let core = *core;
        let (c, j) = rim.phases;
        let (Some(mc), Some(mj)) = (means[c as usize], means[j as usize]) else {
            continue;
        };
        let shrunk = (core as f64) < SHRUNK_SHARE * (core + rim.region.count) as f64;
        if shrunk && looks_like_c(&rim.region, (mc, mj), &judge) {
            record(&mut found, (c, j), &rim.region, core);
        }
    }
    found.sort_by_key(|m| (m.phase, m.within, m.labelled > 0));
    found
}

/// The labels whose final mean is known, with their means (`means` holds
/// one per output label, `None` for an empty phase).
pub(crate) fn present_means(means: &[Option<f64>]) -> Vec<(u8, f64)> {
    means
        .iter()
        .enumerate()
        .filter_map(|(l, m)| m.map(|m| (l as u8, m)))
        .collect()
}

/// The noise's neighbour correlation `ρ` as the checks take it (none: 0; at
/// most [`MAX_CORRELATION`]) and the share of a region's samples that count
/// as independent, `(1 − ρ)/(1 + ρ)`.
pub(crate) fn correlation_and_share(correlation: Option<f64>) -> (f64, f64) {
    let rho = correlation.unwrap_or(0.0).clamp(0.0, MAX_CORRELATION);
    (rho, (1.0 - rho) / (1.0 + rho))
}

/// Whether `region`, of at least [`MIN_SAMPLES`], has an unsmoothed mean
/// nearer `mc` than `mj` and at least [`MIN_SIGNIFICANCE`] standard errors
/// from `mj`.
fn looks_like_c(region: &Region, (mc, mj): (f64, f64), noise: &Judge) -> bool {
    if region.count < MIN_SAMPLES {
        return false;
    }
    let n = region.count as f64;
    let mean = region.sum / n;
    let nearer_c = (mean - mc).abs() < (mean - mj).abs();
    nearer_c && (mean - mj).abs() * (n * noise.independent).sqrt() / noise.sigma >= MIN_SIGNIFICANCE
}

/// The factor by which the smoothing lowers white noise's standard
/// deviation: `(4π σ²)^(−d/4)` over the `d` axes longer than one sample.
fn smoothing_attenuation(dims: [usize; 3]) -> f64 {
    let axes = dims.iter().filter(|&&n| n > 1).count() as f64;
    (4.0 * std::f64::consts::PI * CHECK_SMOOTHING * CHECK_SMOOTHING).powf(-axes / 4.0)
}

/// The label among `present` whose mean is nearest `v`.
fn nearest(present: &[(u8, f64)], v: f64) -> u8 {
    present
        .iter()
        .min_by(|a, b| (a.1 - v).abs().total_cmp(&(b.1 - v).abs()))
        .map_or(0, |p| p.0)
}

/// A connected region of one class: its size, unsmoothed sum and centre,
/// and the one label around it ([`grow`]).
struct Region {
    count: usize,
    sum: f64,
    centre_sum: [f64; 3],
    enclosing: Option<u8>,
    /// A neighbour of its class labelled with it: the region is the rim of
    /// an object the labels kept, whole or smaller.
    own: Option<usize>,
}

/// Grows the face-connected region of `start`'s class `c` among the samples
/// not labelled `c` (and marks it seen). Its `enclosing` label `j` is the
/// one its pixels and their neighbours outside it carry (but for those
/// labelled `c`, the core the labels kept, if any: `own`), or
/// `None` if they carry several, if it is `c`, or if a
/// neighbour's class lies outside the range from `c` to `j`
/// (classes are in the order of their means): a lost object's neighbours
/// look like `j` or like the blur between the two, while a region next to
/// a brighter or darker class is the rim of something else.
fn grow(
    start: usize,
    class: &[u8],
    labels: &[u8],
    image: &ImageView<'_>,
    seen: &mut [bool],
    stack: &mut Vec<usize>,
) -> Region {
    let dims = image.dims;
    let c = class[start];
    let mut single: Option<u8> = None;
    let mut mixed = false;
    let mut own = None;
    let (mut lowest, mut highest) = (c, c);
    let mut note = |l: u8| match single {
        None => single = Some(l),
        Some(s) if s != l => mixed = true,
        Some(_) => {}
    };
    let mut region = Region {
        count: 0,
        sum: 0.0,
        centre_sum: [0.0; 3],
        enclosing: None,
        own: None,
    };
    seen[start] = true;
    stack.push(start);
    while let Some(i) = stack.pop() {
        region.count += 1;
        region.sum += f64::from(image.data[i]);
        let (x, y, z) = (
            i % dims[0],
            (i / dims[0]) % dims[1],
            i / (dims[0] * dims[1]),
        );
        for (s, v) in region.centre_sum.iter_mut().zip([x, y, z]) {
            *s += v as f64;
        }
        note(labels[i]);
        for n in face_neighbours(i, dims).into_iter().flatten() {
            if labels[n] == c {
                own = own.or(Some(n));
            } else if class[n] == c {
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
    region.enclosing = single
        .filter(|&j| !mixed && j != c)
        .filter(|&j| lowest >= c.min(j) && highest <= c.max(j));
    region.own = own;
    region
}

/// The up to six face neighbours of linear index `i` in a volume of `dims`
/// (four in 2D).
pub(crate) fn face_neighbours(i: usize, [nx, ny, nz]: [usize; 3]) -> [Option<usize>; 6] {
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

/// The noise a region's mean is judged against: its standard deviation
/// and the share of a region's samples that count as independent.
struct Judge {
    sigma: f64,
    independent: f64,
}

/// Largest core (samples labelled as the phase its rims look like) judged
/// for a shrunk object: objects of a few cells; a larger core is a kept
/// object's, and its boundary's disagreements with the smoothed image are
/// not counted.
pub const MAX_CORE: usize = 4096;

/// The cores the labels kept that regions of their own class surround (the
/// rims of objects the labels kept smaller than they look), each with its
/// size and its rims gathered: a rim broken by the corners of a square
/// core is one object's.
#[derive(Default)]
struct Cores {
    /// Per sample (made at the first rim): [`UNEXPLORED`], [`LARGE`] for a
    /// sample of a core larger than [`MAX_CORE`], or the index of its core.
    /// A dense array rather than a map: the rims along a large object's
    /// boundary explore up to [`MAX_CORE`] samples each before they meet
    /// the samples marked large, and hashing them cost as much as half the
    /// segmentation of a 256² image.
    core_of: Vec<u32>,
    /// Per core: its size, its rims together, and whether they agree on
    /// the phases.
    cores: Vec<(usize, Option<Rim>, bool)>,
    /// Scratch: the samples of the core being explored.
    explored: Vec<usize>,
    /// Scratch: the samples still to grow from.
    stack: Vec<usize>,
}

/// [`Cores::core_of`] of a sample no core holds yet.
const UNEXPLORED: u32 = u32::MAX;

/// [`Cores::core_of`] of a sample of a core larger than [`MAX_CORE`].
const LARGE: u32 = u32::MAX - 1;

/// The rims of one core, merged.
struct Rim {
    /// The phase they look like and the one that labels them.
    phases: (u8, u8),
    region: Region,
}

impl Cores {
    /// Adds `region`, a rim of class `phases.0` inside `phases.1`, to the
    /// core that holds sample `at`.
    fn add_rim(
        &mut self,
        at: usize,
        labels: &[u8],
        dims: [usize; 3],
        phases: (u8, u8),
        region: Region,
    ) {
        let Some(k) = self.core(at, labels, dims) else {
            return;
        };
        let (_, rim, agree) = &mut self.cores[k];
        match rim {
            None => *rim = Some(Rim { phases, region }),
            Some(r) if r.phases == phases => {
                r.region.count += region.count;
                r.region.sum += region.sum;
                for (a, b) in r.region.centre_sum.iter_mut().zip(region.centre_sum) {
                    *a += b;
                }
            }
            Some(_) => *agree = false,
        }
    }

    /// The index of the core holding `at` (the face-connected samples
    /// labelled as it is), explored now if it was not; `None` for a core
    /// larger than [`MAX_CORE`].
    fn core(&mut self, at: usize, labels: &[u8], dims: [usize; 3]) -> Option<usize> {
        if self.core_of.is_empty() {
            self.core_of = vec![UNEXPLORED; labels.len()];
        }
        match self.core_of[at] {
            UNEXPLORED => {}
            LARGE => return None,
            k => return Some(k as usize),
        }
        let k = self.cores.len() as u32;
        let large = self.explore(at, k, labels, dims);
        if large {
            for &i in &self.explored {
                self.core_of[i] = LARGE;
            }
            return None;
        }
        self.cores.push((self.explored.len(), None, true));
        Some(k as usize)
    }

    /// Marks the core holding `at` (labelled as it is) with index `k`,
    /// listing its samples in `explored`; stops, returning true, once it
    /// proves larger than [`MAX_CORE`] or meets a sample of such a core.
    fn explore(&mut self, at: usize, k: u32, labels: &[u8], dims: [usize; 3]) -> bool {
        let l = labels[at];
        self.explored.clear();
        self.stack.clear();
        self.core_of[at] = k;
        self.explored.push(at);
        self.stack.push(at);
        while let Some(i) = self.stack.pop() {
            for n in face_neighbours(i, dims).into_iter().flatten() {
                if labels[n] != l || self.core_of[n] == k {
                    continue;
                }
                if self.core_of[n] == LARGE || self.explored.len() >= MAX_CORE {
                    return true;
                }
                self.core_of[n] = k;
                self.explored.push(n);
                self.stack.push(n);
            }
        }
        false
    }

    /// Each core with rims that agree on their phases: its size and rims.
    fn rims(&self) -> impl Iterator<Item = (&usize, &Rim)> {
        self.cores
            .iter()
            .filter(|(_, _, agree)| *agree)
            .filter_map(|(size, rim, _)| rim.as_ref().map(|r| (size, r)))
    }
}

/// Adds `region`, an object of `phase` inside `within` whose core the labels
/// kept (`labelled` samples; 0: left out), to `found`.
fn record(
    found: &mut Vec<MissedObjects>,
    (phase, within): (u8, u8),
    region: &Region,
    labelled: usize,
) {
    let centre = region.centre_sum.map(|s| s / region.count as f64);
    let shrunk = labelled > 0;
    let entry = match found
        .iter_mut()
        .find(|m| m.phase == phase && m.within == within && (m.labelled > 0) == shrunk)
    {
        Some(m) => m,
        None => {
            found.push(MissedObjects {
                phase,
                within,
                count: 0,
                pixels: 0,
                largest: 0,
                largest_at: centre,
                labelled: 0,
            });
            found.last_mut().expect("just pushed")
        }
    };
    entry.count += 1;
    entry.pixels += region.count;
    entry.labelled += labelled;
    let size = region.count + labelled;
    if size > entry.largest {
        entry.largest = size;
        entry.largest_at = centre;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::segment::check_image::CheckImage;

    /// [`missed_objects`] with the checks' smoothed copy made here.
    fn missed(
        image: &ImageView<'_>,
        labels: &[u8],
        means: &[Option<f64>],
        noise: Noise,
    ) -> Vec<MissedObjects> {
        missed_objects(image, CheckImage::default().of(image), labels, means, noise)
    }

    fn white(sigma: f64) -> Noise {
        Noise {
            sigma,
            correlation: Some(0.0),
        }
    }

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
        let found = missed(&view, &labels, &[Some(0.2), Some(0.8)], white(0.03));
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!((found[0].phase, found[0].within, found[0].count), (1, 0, 4));
        let uniform = found[0].warning(false, false);
        assert!(
            uniform.contains("4 objects that look like phase 1"),
            "{uniform}"
        );
        // the uniform mesh points to the adaptive one, which points to its
        // smallest cells
        assert!(
            uniform.contains("(--adaptive, a lower --length-weight"),
            "{uniform}"
        );
        let adaptive = found[0].warning(false, true);
        assert!(
            adaptive.contains("--min-edge-length") && !adaptive.contains("--adaptive"),
            "{adaptive}"
        );
    }

    #[test]
    fn spots_labelled_as_themselves_are_not_and_their_centres_alone_are_shrunk() {
        let (data, centres) = spots();
        let view = ImageView::new_2d(64, 64, &data).unwrap();
        let means = [Some(0.2), Some(0.8)];
        let mut labels = vec![0u8; data.len()];
        for &(cx, cy) in &centres {
            for y in cy - 1..=cy + 1 {
                for x in cx - 1..=cx + 1 {
                    labels[y * 64 + x] = 1;
                }
            }
        }
        let found = missed(&view, &labels, &means, white(0.03));
        assert!(found.is_empty(), "{found:?}");
        // only each spot's centre labelled: kept, but smaller than it looks
        let mut centres_only = vec![0u8; data.len()];
        for &(cx, cy) in &centres {
            centres_only[cy * 64 + cx] = 1;
        }
        let found = missed(&view, &centres_only, &means, white(0.03));
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!((found[0].phase, found[0].within), (1, 0));
        assert_eq!((found[0].count, found[0].labelled), (4, 4));
        let warning = found[0].warning(false, false);
        assert!(
            warning.starts_with("4 objects that look like phase 1")
                && warning.contains("labelled smaller than they look: 4 of the"),
            "{warning}"
        );
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
        let found = missed(&view, &labels, &[Some(0.1), Some(0.9)], white(0.02));
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!((found[0].phase, found[0].within, found[0].count), (1, 0, 1));
    }

    /// Three columns of levels 0, 0.5 (a one-pixel band at x = 10) and 1,
    /// 21 × 16 pixels, labelled 0 up to column `last_zero` and 2 after it:
    /// what the check finds.
    fn band_labelled_to(last_zero: usize) -> Vec<MissedObjects> {
        let (w, h) = (21, 16);
        let data: Vec<f32> = (0..w * h)
            .map(|i| match i % w {
                x if x < 10 => 0.0,
                10 => 0.5,
                _ => 1.0,
            })
            .collect();
        let labels: Vec<u8> = (0..w * h)
            .map(|i| if i % w <= last_zero { 0 } else { 2 })
            .collect();
        let view = ImageView::new_2d(w, h, &data).unwrap();
        let means = [Some(0.0), Some(0.5), Some(1.0)];
        missed(&view, &labels, &means, white(0.01))
    }

    #[test]
    fn a_band_between_two_phases_is_not_an_object() {
        // The band labelled as its left neighbour: it touches both labels.
        let found = band_labelled_to(10);
        assert!(found.is_empty(), "{found:?}");
    }

    #[test]
    fn a_band_labelled_as_one_side_is_the_rim_of_the_other() {
        // The band and the right side's first column labelled as the left
        // side: the band touches one label only, but beside it lies a
        // brighter class than either phase it joins.
        let found = band_labelled_to(11);
        assert!(found.iter().all(|m| m.phase != 1), "{found:?}");
    }

    #[test]
    fn a_clean_image_is_judged_and_smooth_noise_asks_more() {
        let (data, _) = spots();
        let view = ImageView::new_2d(64, 64, &data).unwrap();
        let labels = vec![0u8; data.len()];
        let means = [Some(0.2), Some(0.8)];
        let clean = missed(&view, &labels, &means, white(0.0));
        assert_eq!(clean.first().map(|m| m.count), Some(4), "{clean:?}");
        // The same noise, correlated, hides spots a tenth as contrasted.
        let faint: Vec<f32> = data.iter().map(|&v| 0.2 + (v - 0.2) / 10.0).collect();
        let view = ImageView::new_2d(64, 64, &faint).unwrap();
        let means = [Some(0.2), Some(0.26)];
        assert_eq!(missed(&view, &labels, &means, white(0.003)).len(), 1);
        let correlated = Noise {
            sigma: 0.003,
            correlation: Some(0.9),
        };
        assert!(missed(&view, &labels, &means, correlated).is_empty());
    }
}
