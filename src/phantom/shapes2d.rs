//! 2D phantoms: the benchmark phantoms (`two_phase`, `four_phase`) and
//! inputs in the style of the ICPR 2014 DSC multiphase-segmentation figures.
//!
//! All geometry is in normalised coordinates with pixel centres at
//! `(i + 0.5) / size` (x = column, y = row, y pointing down), so `size`
//! scales everything. Every generator has the signature
//! `fn(size, noise_sigma, seed) -> Phantom2` and uses
//! [`RenderOptions::new`] (1.5 px blur, 8-bit quantisation).

use super::{Disk, Phantom2, RenderOptions, FOUR_PHASE_LEVELS, TWO_PHASE_LEVELS};

/// Levels of the three-phase figure phantoms `fig5` (dark, gray, light).
pub const FIG5_LEVELS: [f64; 3] = [0.2, 0.5, 0.8];

/// Levels of `fig6`: background, the band grown from the initial regions,
/// and the enclosed/third phase.
pub const FIG6_LEVELS: [f64; 3] = [0.2, 0.8, 0.5];

#[inline]
pub(super) fn sq(v: f64) -> f64 {
    v * v
}

/// Evaluates `f(x, y)` at the normalised centre of every pixel of an
/// `n × n` grid, row-major.
pub(super) fn label_map(n: usize, f: impl Fn(f64, f64) -> u8) -> Vec<u8> {
    let c: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) / n as f64).collect();
    let mut out = Vec::with_capacity(n * n);
    for &y in &c {
        for &x in &c {
            out.push(f(x, y));
        }
    }
    out
}

/// Ground truth of the two-phase benchmark phantom (0 background, 1
/// foreground): disk, annulus, plate with a square and a round hole, two
/// squares touching at one corner, rotated ellipse, thin bar.
// Comparisons are written as in the NumPy transcription (strict or not) so that
// both give the same pixels.
#[allow(clippy::manual_range_contains)]
pub fn two_phase_labels(n: usize) -> Vec<u8> {
    let th = 30f64.to_radians();
    let (ct, st) = (th.cos(), th.sin());
    label_map(n, |x, y| {
        let mut fg = sq(x - 0.20) + sq(y - 0.20) < sq(0.11);
        let r2 = sq(x - 0.70) + sq(y - 0.24);
        fg |= r2 < sq(0.17) && r2 > sq(0.08);
        let plate = (x - 0.26).abs() < 0.17 && (y - 0.66).abs() < 0.13;
        let hole1 = (x - 0.18).abs() < 0.05 && (y - 0.66).abs() < 0.05;
        let hole2 = sq(x - 0.34) + sq(y - 0.66) < sq(0.05);
        fg |= plate && !hole1 && !hole2;
        let s = 0.12;
        let q1 = x > 0.73 - s && x < 0.73 && y > 0.73 - s && y < 0.73;
        let q2 = x >= 0.73 && x < 0.73 + s && y >= 0.73 && y < 0.73 + s;
        fg |= q1 || q2;
        let u = (x - 0.55) * ct + (y - 0.92) * st;
        let v = -(x - 0.55) * st + (y - 0.92) * ct;
        fg |= sq(u / 0.10) + sq(v / 0.04) < 1.0;
        fg |= (x - 0.93).abs() < 0.01 && y > 0.45 && y < 0.85;
        fg as u8
    })
}

/// Ground truth of the four-phase benchmark phantom (phases 0..=3): a disk
/// cut into three 120° sectors, a square partly covered by a disk, three
/// stripes on background, and a ring around a core.
// Comparisons are written as in the NumPy transcription (strict or not) so that
// both give the same pixels.
#[allow(clippy::manual_range_contains)]
pub fn four_phase_labels(n: usize) -> Vec<u8> {
    label_map(n, |x, y| {
        let mut lab = 0u8;
        let (cx, cy, r) = (0.30, 0.30, 0.22);
        if sq(x - cx) + sq(y - cy) < sq(r) {
            let deg = (y - cy).atan2(x - cx) * (180.0 / std::f64::consts::PI);
            let ang = (deg + 360.0 + 90.0) % 360.0;
            lab = if ang < 120.0 {
                1
            } else if ang < 240.0 {
                2
            } else {
                3
            };
        }
        if (x - 0.70).abs() < 0.13 && (y - 0.28).abs() < 0.13 {
            lab = 1;
        }
        if sq(x - 0.82) + sq(y - 0.40) < sq(0.11) {
            lab = 3;
        }
        let blk = y > 0.62 && y < 0.90;
        if blk && x > 0.10 && x < 0.20 {
            lab = 3;
        }
        if blk && x >= 0.20 && x < 0.30 {
            lab = 1;
        }
        if blk && x >= 0.30 && x < 0.40 {
            lab = 2;
        }
        let r2 = sq(x - 0.72) + sq(y - 0.76);
        if r2 < sq(0.15) {
            lab = 2;
        }
        if r2 < sq(0.07) {
            lab = 1;
        }
        lab
    })
}

/// The two-phase benchmark phantom: [`two_phase_labels`] with levels
/// (0.3, 0.7), 1.5 px blur, noise, 8-bit quantisation.
pub fn two_phase(size: usize, noise_sigma: f64, seed: u64) -> Phantom2 {
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom2::from_labels(size, size, two_phase_labels(size), &TWO_PHASE_LEVELS, &opts)
}

/// The four-phase benchmark phantom: [`four_phase_labels`] with levels
/// (0.2, 0.4, 0.6, 0.8), 1.5 px blur, noise, 8-bit quantisation.
pub fn four_phase(size: usize, noise_sigma: f64, seed: u64) -> Phantom2 {
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom2::from_labels(
        size,
        size,
        four_phase_labels(size),
        &FOUR_PHASE_LEVELS,
        &opts,
    )
}

/// Ground truth of [`fig2`]: a 3×3 checkerboard (four crossings where
/// squares touch only at corners), a disk with two holes, an annulus and a
/// square frame.
pub fn fig2_labels(n: usize) -> Vec<u8> {
    label_map(n, |x, y| {
        // checkerboard: cells of 0.14 from (0.06, 0.06); (i + j) even is foreground
        let (o, c) = (0.06, 0.14);
        let mut fg = false;
        if x > o && x < o + 3.0 * c && y > o && y < o + 3.0 * c {
            let i = ((x - o) / c) as usize;
            let j = ((y - o) / c) as usize;
            fg = (i + j) % 2 == 0;
        }
        // disk with two round holes
        let disk = sq(x - 0.76) + sq(y - 0.26) < sq(0.19);
        let h1 = sq(x - 0.70) + sq(y - 0.22) < sq(0.05);
        let h2 = sq(x - 0.83) + sq(y - 0.32) < sq(0.045);
        fg |= disk && !h1 && !h2;
        // annulus
        let r2 = sq(x - 0.27) + sq(y - 0.75);
        fg |= r2 < sq(0.17) && r2 > sq(0.08);
        // square frame
        let (ax, ay) = ((x - 0.74).abs(), (y - 0.74).abs());
        fg |= ax.max(ay) < 0.17 && ax.max(ay) >= 0.08;
        fg as u8
    })
}

/// Fig. 2 style two-phase image with crossings and holes (levels 0.3/0.7).
pub fn fig2(size: usize, noise_sigma: f64, seed: u64) -> Phantom2 {
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom2::from_labels(size, size, fig2_labels(size), &TWO_PHASE_LEVELS, &opts)
}

/// Ground truth of [`fig3`]: a vertical trunk from the bottom that splits
/// into two curved branches (the halves of a thick ring) whose ends meet
/// at the top. Grown from [`fig3_seed`] in the trunk, the two branch fronts
/// meet at the top and merge, enclosing a background hole.
pub fn fig3_labels(n: usize) -> Vec<u8> {
    label_map(n, |x, y| {
        let r2 = sq(x - 0.5) + sq(y - 0.40);
        let ring = r2 < sq(0.28) && r2 > sq(0.15);
        let trunk = (x - 0.5).abs() < 0.065 && y > 0.55 && y < 0.92;
        (ring || trunk) as u8
    })
}

/// Fig. 3 style branched object on background (levels 0.3/0.7).
pub fn fig3(size: usize, noise_sigma: f64, seed: u64) -> Phantom2 {
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom2::from_labels(size, size, fig3_labels(size), &TWO_PHASE_LEVELS, &opts)
}

/// Recommended seed disk for [`fig3`], in pixels: inside the trunk,
/// centre `(0.5, 0.82)·size`, radius `0.04·size`.
pub fn fig3_seed(size: usize) -> Disk {
    let s = size as f64;
    Disk {
        x: 0.5 * s,
        y: 0.82 * s,
        r: 0.04 * s,
    }
}

/// Ground truth of [`fig4`] (phases 0..=3, 0 is background): a disk cut into
/// three unequal sectors meeting at an off-centre triple junction, a phase-1
/// disk overlapping a phase-2 square, a phase-3 strip capped by a phase-1
/// disk, and a block split diagonally into phases 3 and 2.
pub fn fig4_labels(n: usize) -> Vec<u8> {
    label_map(n, |x, y| {
        let mut lab = 0u8;
        if sq(x - 0.33) + sq(y - 0.35) < sq(0.25) {
            let deg = (y - 0.40).atan2(x - 0.36).to_degrees();
            let a = (deg + 360.0) % 360.0;
            lab = if (20.0..150.0).contains(&a) {
                1
            } else if (150.0..265.0).contains(&a) {
                2
            } else {
                3
            };
        }
        if (x - 0.74).abs() < 0.15 && (y - 0.74).abs() < 0.15 {
            lab = 2;
        }
        if sq(x - 0.62) + sq(y - 0.62) < sq(0.12) {
            lab = 1;
        }
        if x > 0.62 && x < 0.95 && y > 0.10 && y < 0.24 {
            lab = 3;
        }
        if sq(x - 0.70) + sq(y - 0.30) < sq(0.09) {
            lab = 1;
        }
        if x > 0.08 && x < 0.40 && y > 0.68 && y < 0.92 {
            lab = if x + y < 1.05 { 3 } else { 2 };
        }
        lab
    })
}

/// Fig. 4 style four-phase image with triple junctions (levels 0.2..0.8).
pub fn fig4(size: usize, noise_sigma: f64, seed: u64) -> Phantom2 {
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom2::from_labels(size, size, fig4_labels(size), &FOUR_PHASE_LEVELS, &opts)
}

/// Diameters (normalised) of the small detail disks of [`fig5`]; at size
/// 256 they are 5.1, 7.7, 10.2, 12.8 and 15.4 px.
pub const FIG5_DETAIL_DIAMETERS: [f64; 5] = [0.02, 0.03, 0.04, 0.05, 0.06];

/// Signed horizontal offset from the wavy dark/light boundary of [`fig5`].
fn fig5_offset(x: f64, y: f64) -> f64 {
    x - (0.5 + 0.06 * (2.0 * std::f64::consts::PI * y).sin())
}

/// Half-width of the smooth dark-to-light ramp of [`fig5`] (normalised).
const FIG5_RAMP: f64 = 0.05;

/// Labels and base intensities of [`fig5`]; the truth puts the dark/light
/// boundary at the middle of the ramp.
fn fig5_parts(n: usize) -> (Vec<u8>, Vec<f64>) {
    let [dark, _, light] = FIG5_LEVELS;
    let c: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) / n as f64).collect();
    let mut lab = Vec::with_capacity(n * n);
    let mut base = Vec::with_capacity(n * n);
    for &y in &c {
        for &x in &c {
            let d = fig5_offset(x, y);
            let t = ((d + FIG5_RAMP) / (2.0 * FIG5_RAMP)).clamp(0.0, 1.0);
            let s = t * t * (3.0 - 2.0 * t);
            let mut l = if d < 0.0 { 0u8 } else { 2 };
            let mut v = dark + (light - dark) * s;
            let mut paint = |hit: bool, phase: u8| {
                if hit {
                    l = phase;
                    v = FIG5_LEVELS[phase as usize];
                }
            };
            // gray objects, one on each side
            paint(sq(x - 0.25) + sq(y - 0.25) < sq(0.12), 1);
            paint((x - 0.81).abs() < 0.09 && (y - 0.765).abs() < 0.115, 1);
            // small details: light disks on the dark side, dark disks on the light side
            for (k, dia) in FIG5_DETAIL_DIAMETERS.iter().enumerate() {
                let r = 0.5 * dia;
                let yl = [0.48, 0.58, 0.69, 0.80, 0.91][k];
                paint(sq(x - 0.20) + sq(y - yl) < sq(r), 2);
                let yr = [0.10, 0.19, 0.28, 0.38, 0.50][k];
                paint(sq(x - 0.82) + sq(y - yr) < sq(r), 0);
            }
            lab.push(l);
            base.push(v);
        }
    }
    (lab, base)
}

/// Ground truth of [`fig5`] (0 dark, 1 gray, 2 light).
pub fn fig5_labels(n: usize) -> Vec<u8> {
    fig5_parts(n).0
}

/// Fig. 5 style three-phase image: dark (left) and light (right) halves
/// that blend smoothly across a wavy boundary over `0.1·size` pixels (so a
/// three-phase segmentation shows a thin gray band there), two gray
/// objects, and small detail disks of diameters [`FIG5_DETAIL_DIAMETERS`]
/// (at size 256: 5–15 px, so a mesh of edge length 15 misses the smaller
/// ones while edge length 10 can resolve the 10–13 px ones).
pub fn fig5(size: usize, noise_sigma: f64, seed: u64) -> Phantom2 {
    let (truth, base) = fig5_parts(size);
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom2::from_base(size, size, base, truth, 3, &opts)
}

/// A user-given initial region: a disk and the phase it starts as.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InitRegion {
    /// The region, in pixels.
    pub disk: Disk,
    /// Phase index the region is initialised with.
    pub phase: u8,
}

/// Ground truth of [`fig6`] (0 background, 1 band, 2 third phase): a long
/// capsule-shaped band of phase 1 with a phase-2 disk inside its middle,
/// and a separate phase-2 disk.
pub fn fig6_labels(n: usize) -> Vec<u8> {
    label_map(n, |x, y| {
        let mut lab = 0u8;
        // capsule around the segment (0.22, 0.5)-(0.78, 0.5), radius 0.17
        let px = x.clamp(0.22, 0.78);
        if sq(x - px) + sq(y - 0.5) < sq(0.17) {
            lab = 1;
        }
        if sq(x - 0.5) + sq(y - 0.5) < sq(0.08) {
            lab = 2;
        }
        if sq(x - 0.80) + sq(y - 0.16) < sq(0.08) {
            lab = 2;
        }
        lab
    })
}

/// Fig. 6 style three-phase image (levels [`FIG6_LEVELS`]) for region
/// growing from [`fig6_initial_regions`]: the two regions grow along the
/// band, meet above and below the enclosed phase-2 disk and merge.
pub fn fig6(size: usize, noise_sigma: f64, seed: u64) -> Phantom2 {
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom2::from_labels(size, size, fig6_labels(size), &FIG6_LEVELS, &opts)
}

/// The two initial regions of [`fig6`], both phase 1, in pixels: disks at
/// `(0.30, 0.50)·size` and `(0.70, 0.50)·size` with radius `0.06·size`.
pub fn fig6_initial_regions(size: usize) -> [InitRegion; 2] {
    let s = size as f64;
    [0.30, 0.70].map(|cx| InitRegion {
        disk: Disk {
            x: cx * s,
            y: 0.5 * s,
            r: 0.06 * s,
        },
        phase: 1,
    })
}

/// The initial regions of [`fig6`] as a row-major label image (0 elsewhere).
pub fn fig6_initial_labels(size: usize) -> Vec<u8> {
    let regions = fig6_initial_regions(size);
    let mut out = vec![0u8; size * size];
    for j in 0..size {
        for i in 0..size {
            for r in &regions {
                if r.disk.contains_pixel(i, j) {
                    out[j * size + i] = r.phase;
                }
            }
        }
    }
    out
}

/// The 2D phantoms by name (for `dsc-seg phantom NAME`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Phantom2Kind {
    /// [`two_phase`] (benchmark geometry).
    TwoPhase,
    /// [`four_phase`] (benchmark geometry).
    FourPhase,
    /// [`fig2`]: crossings and holes.
    Fig2,
    /// [`fig3`]: branched object for region growing.
    Fig3,
    /// [`fig4`]: four phases with triple junctions.
    Fig4,
    /// [`fig5`]: smooth blend and small details.
    Fig5,
    /// [`fig6`]: three phases, two merging initial regions.
    Fig6,
    /// [`hard2d::three_close`](super::hard2d::three_close): means 0.35 / 0.5 / 0.65.
    ThreeClose,
    /// [`hard2d::four_close`](super::hard2d::four_close): means 0.1 apart.
    FourClose,
    /// [`two_phase`] with 0.5 % salt-and-pepper specks.
    TwoPhaseSpecks,
    /// [`four_phase`] with 0.5 % salt-and-pepper specks.
    FourPhaseSpecks,
    /// [`hard2d::disks`](super::hard2d::disks) with 2 to 6 phases (`disks2` … `disks6`).
    Disks(u8),
    /// [`thin`](super::thin::thin): lines, arcs, small blobs, a slit, a star.
    Thin,
}

impl Phantom2Kind {
    /// Every kind, in order.
    pub const ALL: [Phantom2Kind; 17] = [
        Self::TwoPhase,
        Self::FourPhase,
        Self::Fig2,
        Self::Fig3,
        Self::Fig4,
        Self::Fig5,
        Self::Fig6,
        Self::ThreeClose,
        Self::FourClose,
        Self::TwoPhaseSpecks,
        Self::FourPhaseSpecks,
        Self::Disks(2),
        Self::Disks(3),
        Self::Disks(4),
        Self::Disks(5),
        Self::Disks(6),
        Self::Thin,
    ];

    /// The command-line name (`two_phase`, `four_phase`, `fig2`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Self::TwoPhase => "two_phase",
            Self::FourPhase => "four_phase",
            Self::Fig2 => "fig2",
            Self::Fig3 => "fig3",
            Self::Fig4 => "fig4",
            Self::Fig5 => "fig5",
            Self::Fig6 => "fig6",
            Self::ThreeClose => "three_close",
            Self::FourClose => "four_close",
            Self::TwoPhaseSpecks => "two_phase_specks",
            Self::FourPhaseSpecks => "four_phase_specks",
            Self::Disks(2) => "disks2",
            Self::Disks(3) => "disks3",
            Self::Disks(4) => "disks4",
            Self::Disks(5) => "disks5",
            Self::Disks(_) => "disks6",
            Self::Thin => "thin",
        }
    }

    /// Parses a name as printed by [`Self::name`] (`-` is accepted for `_`).
    pub fn from_name(name: &str) -> Option<Self> {
        let n = name.trim().to_ascii_lowercase().replace('-', "_");
        Self::ALL.into_iter().find(|k| k.name() == n)
    }

    /// Number of phases of the phantom.
    pub fn phases(self) -> usize {
        match self {
            Self::TwoPhase | Self::Fig2 | Self::Fig3 | Self::TwoPhaseSpecks | Self::Thin => 2,
            Self::FourPhase | Self::Fig4 | Self::FourClose | Self::FourPhaseSpecks => 4,
            Self::Fig5 | Self::Fig6 | Self::ThreeClose => 3,
            Self::Disks(n) => n.clamp(2, 6) as usize,
        }
    }

    /// Generates the phantom (`size × size`, noise `noise_sigma`, RNG `seed`).
    pub fn generate(self, size: usize, noise_sigma: f64, seed: u64) -> Phantom2 {
        use super::hard2d;
        let f = match self {
            Self::ThreeClose => hard2d::three_close,
            Self::FourClose => hard2d::four_close,
            Self::TwoPhaseSpecks => hard2d::two_phase_specks,
            Self::FourPhaseSpecks => hard2d::four_phase_specks,
            Self::Disks(_) => return hard2d::disks(size, self.phases(), noise_sigma, seed),
            Self::TwoPhase => two_phase,
            Self::FourPhase => four_phase,
            Self::Fig2 => fig2,
            Self::Fig3 => fig3,
            Self::Fig4 => fig4,
            Self::Fig5 => fig5,
            Self::Fig6 => fig6,
            Self::Thin => super::thin::thin,
        };
        f(size, noise_sigma, seed)
    }
}

impl std::fmt::Display for Phantom2Kind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
