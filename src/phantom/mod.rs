//! Synthetic test images with ground truth ("phantoms"), as plain data.
//!
//! Every phantom is a label image (the ground truth) rendered to
//! intensities by mapping each phase to a level, a Gaussian edge blur
//! ([`blur`]), additive Gaussian noise from a seeded ChaCha RNG, clipping to
//! `[0, 1]` and (by default) 8-bit quantisation ([`noise`]). These are the
//! benchmark phantoms of `benches/compare` (written by `dsc-seg phantom`).
//!
//! Geometry is defined in normalised coordinates: pixel `i` of an `n`-pixel
//! axis has centre `(i + 0.5) / n`, so `size` scales every shape.
//! [`shapes2d::two_phase`] and [`shapes2d::four_phase`] agree pixel for
//! pixel with a NumPy transcription of the same shapes (tests below), so
//! Python peers may generate them too.
//!
//! This module depends on no other module of the crate.

pub mod blur;
pub mod brain3d;
pub mod hard2d;
pub mod junctions3d;
pub mod noise;
pub mod shapes2d;
pub mod shapes3d;
pub mod thin;

pub use shapes2d::{
    fig3_seed, fig6_initial_labels, fig6_initial_regions, InitRegion, Phantom2Kind,
};
pub use shapes3d::Phantom3Kind;

/// Default Gaussian edge blur in pixels.
pub const DEFAULT_BLUR_PX: f64 = 1.5;

/// Phase levels of the two-phase phantoms.
pub const TWO_PHASE_LEVELS: [f64; 2] = [0.3, 0.7];

/// Phase levels of the four-phase phantoms.
pub const FOUR_PHASE_LEVELS: [f64; 4] = [0.2, 0.4, 0.6, 0.8];

/// How a label image is turned into an intensity image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// Gaussian blur standard deviation in pixels (0 = none).
    pub blur_px: f64,
    /// Standard deviation of the additive Gaussian noise (0 = none).
    pub noise_sigma: f64,
    /// Seed of the ChaCha noise RNG.
    pub seed: u64,
    /// Round intensities to the 8-bit grid `k / 255` (as the phantoms' PNGs are).
    pub quantize_8bit: bool,
}

impl RenderOptions {
    /// The benchmark phantoms' rendering: [`DEFAULT_BLUR_PX`] blur and 8-bit quantisation.
    pub fn new(noise_sigma: f64, seed: u64) -> Self {
        Self {
            blur_px: DEFAULT_BLUR_PX,
            noise_sigma,
            seed,
            quantize_8bit: true,
        }
    }
}

/// A disk in pixel coordinates (`x` column, `y` row, pixel `i` has centre
/// `i + 0.5`), used for seeds and initial regions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    /// Centre column in pixels.
    pub x: f64,
    /// Centre row in pixels.
    pub y: f64,
    /// Radius in pixels.
    pub r: f64,
}

impl Disk {
    /// Whether the centre of pixel `(i, j)` (column, row) lies inside.
    pub fn contains_pixel(&self, i: usize, j: usize) -> bool {
        let dx = i as f64 + 0.5 - self.x;
        let dy = j as f64 + 0.5 - self.y;
        dx * dx + dy * dy < self.r * self.r
    }
}

/// A 2D phantom: intensity image and ground-truth phase per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Phantom2 {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major intensities in `[0, 1]`.
    pub image: Vec<f32>,
    /// Row-major ground-truth phase index per pixel (`0..phases`).
    pub truth: Vec<u8>,
    /// Number of phases.
    pub phases: usize,
}

impl Phantom2 {
    /// Renders a label image: phase `k` gets intensity `levels[k]`, then blur,
    /// noise, clipping and optional quantisation per `opts`.
    pub fn from_labels(
        width: usize,
        height: usize,
        truth: Vec<u8>,
        levels: &[f64],
        opts: &RenderOptions,
    ) -> Self {
        let base = levels_to_image(&truth, levels);
        Self::from_base(width, height, base, truth, levels.len(), opts)
    }

    /// Renders an arbitrary noise-free `f64` base image (blur, noise, clip,
    /// quantise per `opts`) and pairs it with the given ground truth.
    pub fn from_base(
        width: usize,
        height: usize,
        base: Vec<f64>,
        truth: Vec<u8>,
        phases: usize,
        opts: &RenderOptions,
    ) -> Self {
        assert_eq!(
            truth.len(),
            width * height,
            "truth size does not match dimensions"
        );
        let image = render(base, [width, height, 1], opts);
        Self {
            width,
            height,
            image,
            truth,
            phases,
        }
    }

    /// Row-major index of pixel `(x, y)`.
    pub fn index(&self, x: usize, y: usize) -> usize {
        y * self.width + x
    }

    /// Number of pixels of each phase.
    pub fn phase_counts(&self) -> Vec<usize> {
        phase_counts(&self.truth, self.phases)
    }

    /// Fraction of pixels of each phase.
    pub fn phase_fractions(&self) -> Vec<f64> {
        fractions(&self.truth, self.phases)
    }

    /// The image as 8-bit gray values (`rint(v · 255)`).
    pub fn image_u8(&self) -> Vec<u8> {
        self.image.iter().map(|&v| noise::to_u8(v as f64)).collect()
    }

    /// The truth as 8-bit gray values spread over `0..=255` as in
    /// `*_gt.png` (phase `k` ↦ `k · (255 / (phases - 1))`).
    pub fn truth_gray(&self) -> Vec<u8> {
        truth_gray(&self.truth, self.phases)
    }
}

/// A 3D phantom: intensity volume and ground-truth phase per voxel
/// (x fastest, then y, then z).
#[derive(Clone, Debug, PartialEq)]
pub struct Phantom3 {
    /// Extent along x.
    pub nx: usize,
    /// Extent along y.
    pub ny: usize,
    /// Extent along z.
    pub nz: usize,
    /// Intensities in `[0, 1]`, index `x + nx·(y + ny·z)`.
    pub image: Vec<f32>,
    /// Ground-truth phase index per voxel (`0..phases`).
    pub truth: Vec<u8>,
    /// Number of phases.
    pub phases: usize,
}

impl Phantom3 {
    /// Renders a label volume: phase `k` gets intensity `levels[k]`, then
    /// blur, noise, clipping and optional quantisation per `opts`.
    pub fn from_labels(
        dims: [usize; 3],
        truth: Vec<u8>,
        levels: &[f64],
        opts: &RenderOptions,
    ) -> Self {
        let [nx, ny, nz] = dims;
        assert_eq!(
            truth.len(),
            nx * ny * nz,
            "truth size does not match dimensions"
        );
        let image = render(levels_to_image(&truth, levels), dims, opts);
        Self {
            nx,
            ny,
            nz,
            image,
            truth,
            phases: levels.len(),
        }
    }

    /// Renders an arbitrary noise-free `f64` base volume (blur, noise,
    /// clip, quantise per `opts`) and pairs it with the given ground truth.
    pub fn from_base(
        dims: [usize; 3],
        base: Vec<f64>,
        truth: Vec<u8>,
        phases: usize,
        opts: &RenderOptions,
    ) -> Self {
        let [nx, ny, nz] = dims;
        assert_eq!(
            truth.len(),
            nx * ny * nz,
            "truth size does not match dimensions"
        );
        let image = render(base, dims, opts);
        Self {
            nx,
            ny,
            nz,
            image,
            truth,
            phases,
        }
    }

    /// Linear index of voxel `(x, y, z)`.
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        x + self.nx * (y + self.ny * z)
    }

    /// Number of voxels of each phase.
    pub fn phase_counts(&self) -> Vec<usize> {
        phase_counts(&self.truth, self.phases)
    }

    /// Fraction of voxels of each phase.
    pub fn phase_fractions(&self) -> Vec<f64> {
        fractions(&self.truth, self.phases)
    }
}

fn levels_to_image(truth: &[u8], levels: &[f64]) -> Vec<f64> {
    truth.iter().map(|&l| levels[l as usize]).collect()
}

fn render(mut img: Vec<f64>, dims: [usize; 3], opts: &RenderOptions) -> Vec<f32> {
    if opts.blur_px > 0.0 {
        img = blur::gaussian_blur_3d_f64(&img, dims[0], dims[1], dims[2], opts.blur_px);
    }
    noise::add_gaussian_noise_f64(&mut img, opts.noise_sigma, opts.seed);
    if opts.quantize_8bit {
        img.iter()
            .map(|&v| noise::to_u8(v) as f32 / 255.0)
            .collect()
    } else {
        img.iter().map(|&v| v as f32).collect()
    }
}

fn phase_counts(truth: &[u8], phases: usize) -> Vec<usize> {
    let mut c = vec![0usize; phases];
    for &l in truth {
        c[l as usize] += 1;
    }
    c
}

fn fractions(truth: &[u8], phases: usize) -> Vec<f64> {
    let n = truth.len().max(1) as f64;
    phase_counts(truth, phases)
        .into_iter()
        .map(|c| c as f64 / n)
        .collect()
}

/// Phase labels as 8-bit gray values, `k ↦ k · (255 / max(phases - 1, 1))`
/// (the `*_gt.png` of `dsc-seg phantom`).
pub fn truth_gray(truth: &[u8], phases: usize) -> Vec<u8> {
    let step = 255 / phases.saturating_sub(1).max(1);
    truth.iter().map(|&l| (l as usize * step) as u8).collect()
}

#[cfg(test)]
mod tests {
    use super::shapes2d::*;
    use super::shapes3d::*;
    use super::*;

    /// Number of 4-connected (2D) / 6-connected (3D) components of `phase`.
    fn components(truth: &[u8], dims: [usize; 3], phase: u8) -> usize {
        let [nx, ny, nz] = dims;
        let mut seen = vec![false; truth.len()];
        let mut count = 0;
        for start in 0..truth.len() {
            if seen[start] || truth[start] != phase {
                continue;
            }
            count += 1;
            seen[start] = true;
            let mut stack = vec![start];
            while let Some(i) = stack.pop() {
                let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
                let mut nb = Vec::with_capacity(6);
                if x > 0 {
                    nb.push(i - 1);
                }
                if x + 1 < nx {
                    nb.push(i + 1);
                }
                if y > 0 {
                    nb.push(i - nx);
                }
                if y + 1 < ny {
                    nb.push(i + nx);
                }
                if z > 0 {
                    nb.push(i - nx * ny);
                }
                if z + 1 < nz {
                    nb.push(i + nx * ny);
                }
                for j in nb {
                    if !seen[j] && truth[j] == phase {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
        count
    }

    fn fnv1a(data: &[u8]) -> u64 {
        data.iter().fold(0xcbf29ce484222325u64, |h, &b| {
            (h ^ b as u64).wrapping_mul(0x100000001b3)
        })
    }

    /// Values computed with `two_phase_labels(64)` / `four_phase_labels(64)`
    /// of a NumPy transcription of the shapes (numpy 2.4.6): per-phase counts, an
    /// FNV-1a hash of the row-major label bytes and a few (row, col) labels.
    #[test]
    fn geometry_matches_numpy_at_64() {
        let two = two_phase_labels(64);
        assert_eq!(phase_counts(&two, 2), vec![3162, 934]);
        assert_eq!(fnv1a(&two), 0xb6f5debc57c57fc9);
        let four = four_phase_labels(64);
        assert_eq!(phase_counts(&four, 4), vec![2444, 607, 560, 485]);
        assert_eq!(fnv1a(&four), 0x7c1985e5c037810d);
        let pts = [
            (0, 0),
            (13, 13),
            (45, 15),
            (45, 4),
            (17, 42),
            (11, 42),
            (47, 47),
            (46, 46),
        ];
        let want_two = [0, 1, 1, 0, 0, 0, 1, 1];
        let want_four = [0, 3, 1, 0, 1, 1, 1, 1];
        for (k, &(r, c)) in pts.iter().enumerate() {
            assert_eq!(two[r * 64 + c], want_two[k], "two_phase ({r},{c})");
            assert_eq!(four[r * 64 + c], want_four[k], "four_phase ({r},{c})");
        }
    }

    /// FNV-1a of the noise-free 8-bit renders, from
    /// the NumPy render (levels, `scipy.ndimage.gaussian_filter` with σ = 1.5 px
    /// and `mode="nearest"`, no noise, `rint(v · 255)`; SciPy 1.17.1); the
    /// blur reproduces SciPy's summation order, so even the 76.5 / 178.5
    /// rounding ties of the 0.3 / 0.7 levels come out the same.
    #[test]
    fn noise_free_render_matches_scipy_at_64() {
        let two = two_phase(64, 0.0, 0).image_u8();
        assert_eq!(fnv1a(&two), 0xf5b41368d0d5da6f);
        assert_eq!((two[0], two[20 * 64 + 20]), (77, 77));
        let four = four_phase(64, 0.0, 0).image_u8();
        assert_eq!(fnv1a(&four), 0x519feffa3b6d5139);
        assert_eq!((four[0], four[20 * 64 + 20]), (51, 137));
    }

    #[test]
    fn phantoms_are_deterministic_per_seed() {
        for kind in Phantom2Kind::ALL {
            let a = kind.generate(96, 0.1, 5);
            let b = kind.generate(96, 0.1, 5);
            let c = kind.generate(96, 0.1, 6);
            assert_eq!(a, b, "{kind}");
            assert_eq!(a.truth, c.truth, "{kind}");
            assert_ne!(a.image, c.image, "{kind}");
            assert_eq!(a.phases, kind.phases());
            assert_eq!((a.width, a.height, a.image.len()), (96, 96, 96 * 96));
            assert!(a.image.iter().all(|v| (0.0..=1.0).contains(v)));
        }
        for kind in Phantom3Kind::ALL {
            assert_eq!(
                kind.generate(24, 0.1, 1),
                kind.generate(24, 0.1, 1),
                "{kind}"
            );
        }
    }

    #[test]
    fn phase_fractions_are_sensible() {
        for kind in Phantom2Kind::ALL {
            let p = kind.generate(128, 0.0, 0);
            let f = p.phase_fractions();
            assert!((f.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            assert!(f.iter().all(|&v| v > 0.01 && v < 0.9), "{kind}: {f:?}");
            assert!(p.truth.iter().all(|&l| (l as usize) < p.phases));
        }
        for kind in Phantom3Kind::ALL {
            let f = kind.generate(32, 0.0, 0).phase_fractions();
            assert!(f[1] > 0.03 && f[1] < 0.5, "{kind}: {f:?}");
        }
    }

    #[test]
    fn noise_free_render_hits_levels_and_noise_has_sigma() {
        let p = two_phase(128, 0.0, 0);
        let q = two_phase(128, 0.1, 3);
        // pixel (row 26, col 26) is deep inside the disk (phase 1)
        let i = p.index(26, 26);
        assert_eq!(p.truth[i], 1);
        assert_eq!(p.image[i], 178.0 / 255.0);
        let diffs: Vec<f64> = p
            .image
            .iter()
            .zip(&q.image)
            .map(|(a, b)| (b - a) as f64)
            .collect();
        let var = diffs.iter().map(|d| d * d).sum::<f64>() / diffs.len() as f64;
        assert!((var.sqrt() - 0.1).abs() < 0.01, "noise std {}", var.sqrt());
    }

    #[test]
    fn names_round_trip() {
        for kind in Phantom2Kind::ALL {
            assert_eq!(Phantom2Kind::from_name(kind.name()), Some(kind));
        }
        for kind in Phantom3Kind::ALL {
            assert_eq!(Phantom3Kind::from_name(kind.name()), Some(kind));
        }
        assert_eq!(
            Phantom2Kind::from_name("Two-Phase"),
            Some(Phantom2Kind::TwoPhase)
        );
        assert_eq!(Phantom2Kind::from_name("fig7"), None);
    }

    #[test]
    fn topology_of_2d_figures() {
        let n = 128;
        let d = [n, n, 1];
        // fig2: holes (background components besides the outside)
        let f2 = fig2_labels(n);
        assert!(components(&f2, d, 0) >= 5);
        // fig3: one object with one hole; the seed lies in it
        let f3 = fig3_labels(n);
        assert_eq!(components(&f3, d, 1), 1);
        assert_eq!(components(&f3, d, 0), 2);
        let seed = fig3_seed(n);
        for j in 0..n {
            for i in 0..n {
                if seed.contains_pixel(i, j) {
                    assert_eq!(f3[j * n + i], 1);
                }
            }
        }
        // fig4: triple junctions (2x2 blocks with three phases)
        let f4 = fig4_labels(n);
        let triples = (0..n - 1)
            .flat_map(|j| (0..n - 1).map(move |i| (i, j)))
            .filter(|&(i, j)| {
                let mut v = [
                    f4[j * n + i],
                    f4[j * n + i + 1],
                    f4[(j + 1) * n + i],
                    f4[(j + 1) * n + i + 1],
                ];
                v.sort_unstable();
                v.windows(2).filter(|w| w[0] != w[1]).count() >= 2
            })
            .count();
        assert!(triples >= 5, "{triples}");
        // fig5: every detail disk is present at 256 (10 + 2 gray objects)
        let f5 = fig5_labels(256);
        let d5 = [256, 256, 1];
        assert_eq!(components(&f5, d5, 1), 2);
        assert_eq!(components(&f5, d5, 2), 6);
        assert_eq!(components(&f5, d5, 0), 6);
        // fig6: initial regions inside the band, separated by the phase-2 disk
        let f6 = fig6_labels(n);
        let init = fig6_initial_labels(n);
        assert!(init.iter().zip(&f6).all(|(&a, &t)| a == 0 || t == 1));
        assert_eq!(components(&init, d, 1), 2);
        assert_eq!(components(&f6, d, 1), 1);
        assert_eq!(f6[(n / 2) * n + n / 2], 2);
    }

    #[test]
    fn topology_of_3d_phantoms() {
        let n = 40;
        let d = [n, n, n];
        let balls = two_balls_labels(n);
        assert_eq!(components(&balls, d, 1), 2);
        // exactly two voxel layers of background between the balls on the axis
        let row = &balls[n * (n / 2 + n * (n / 2))..][..n];
        let gap = row
            .iter()
            .skip_while(|&&v| v == 0)
            .skip_while(|&&v| v == 1)
            .take_while(|&&v| v == 0)
            .count();
        assert_eq!(gap, 2);
        let torus = torus_labels(n);
        assert_eq!(components(&torus, d, 1), 1);
        assert_eq!(components(&torus, d, 0), 1);
        let shell = hollow_sphere_labels(n);
        assert_eq!(components(&shell, d, 1), 1);
        assert_eq!(components(&shell, d, 0), 2);
    }

    /// Whether three distinct phases meet around some voxel corner (a 2×2×2
    /// block holding all of `phases`): a junction curve passes there.
    fn phases_meet(labels: &[u8], d: [usize; 3], phases: &[u8]) -> bool {
        let at = |x: usize, y: usize, z: usize| labels[x + d[0] * (y + d[1] * z)];
        (0..d[2] - 1).any(|z| {
            (0..d[1] - 1).any(|y| {
                (0..d[0] - 1).any(|x| {
                    let block: Vec<u8> = (0..8)
                        .map(|c| at(x + (c & 1), y + (c >> 1 & 1), z + (c >> 2)))
                        .collect();
                    phases.iter().all(|p| block.contains(p))
                })
            })
        })
    }

    #[test]
    fn multiphase_3d_phantoms_have_connected_phases_and_junctions() {
        use super::brain3d::{brain_dims, brain_labels};
        use super::junctions3d::{four_phase_labels, three_phase_labels};
        let n = 40;
        let d = [n, n, n];
        let three = three_phase_labels(n);
        for phase in 0..3 {
            assert_eq!(components(&three, d, phase), 1, "three_phase {phase}");
        }
        assert!(phases_meet(&three, d, &[0, 1, 2]));
        let four = four_phase_labels(n);
        for phase in 0..4 {
            assert_eq!(components(&four, d, phase), 1, "four_phase {phase}");
        }
        for triple in [[1, 2, 3], [0, 1, 2], [0, 2, 3], [0, 1, 3]] {
            assert!(phases_meet(&four, d, &triple), "{triple:?}");
        }
        assert!(phases_meet(&four, d, &[0, 1, 2, 3]));
        let size = 64;
        let bd = brain_dims(size);
        assert_eq!(bd, [54, 64, 51]);
        assert_eq!(brain_dims(190), [160, 190, 150]);
        let brain = brain_labels(size);
        assert_eq!(brain.len(), bd.iter().product::<usize>());
        let f = fractions(&brain, 4);
        assert!(f.iter().all(|&v| v > 0.05), "{f:?}");
        // The white matter is one folded piece; grey matter meets the
        // background and the CSF where gyri reach the outline.
        assert_eq!(components(&brain, bd, 3), 1);
        assert!(phases_meet(&brain, bd, &[0, 1, 2]));
        let biased = super::brain3d::brain(size, 0.0, 0);
        let white: Vec<f32> = (0..brain.len())
            .filter(|&i| brain[i] == 3)
            .map(|i| biased.image[i])
            .collect();
        let (lo, hi) = white
            .iter()
            .fold((1f32, 0f32), |(a, b), &v| (a.min(v), b.max(v)));
        assert!(
            hi - lo > 0.1,
            "the bias field spreads white matter: {lo}..{hi}"
        );
    }
}
