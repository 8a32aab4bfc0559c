//! 3D two-phase phantoms on an `n³` grid (levels 0.3/0.7, 1.5 voxel blur,
//! noise, 8-bit quantisation), and [`Phantom3Kind`], every 3D phantom by
//! name (with those of [`super::junctions3d`] and [`super::brain3d`]).
//! Voxel `i` has normalised centre `(i + 0.5) / n`; storage is x fastest.

use super::brain3d::brain;
use super::junctions3d::{four_phase, three_phase};
use super::{Phantom3, RenderOptions, TWO_PHASE_LEVELS};

#[inline]
fn sq(v: f64) -> f64 {
    v * v
}

/// Evaluates `f(x, y, z)` at the normalised centre of every voxel of an
/// `n³` grid (x fastest).
fn label_map3(n: usize, f: impl Fn(f64, f64, f64) -> bool) -> Vec<u8> {
    let c: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) / n as f64).collect();
    let mut out = Vec::with_capacity(n * n * n);
    for &z in &c {
        for &y in &c {
            for &x in &c {
                out.push(f(x, y, z) as u8);
            }
        }
    }
    out
}

/// Radius (normalised) of each ball of [`two_balls`].
pub const TWO_BALLS_RADIUS: f64 = 0.22;

/// Ground truth of [`two_balls`]: two balls of radius `0.22·n` on the x
/// axis through the centre whose surfaces are 2 voxels apart.
pub fn two_balls_labels(n: usize) -> Vec<u8> {
    let r = TWO_BALLS_RADIUS;
    let gap = 2.0 / n as f64;
    let dx = r + 0.5 * gap;
    label_map3(n, |x, y, z| {
        let yz = sq(y - 0.5) + sq(z - 0.5);
        sq(x - (0.5 - dx)) + yz < sq(r) || sq(x - (0.5 + dx)) + yz < sq(r)
    })
}

/// Ground truth of [`torus`]: axis along z, major radius `0.28·n`, minor
/// radius `0.11·n`, centred.
pub fn torus_labels(n: usize) -> Vec<u8> {
    label_map3(n, |x, y, z| {
        let rho = (sq(x - 0.5) + sq(y - 0.5)).sqrt();
        sq(rho - 0.28) + sq(z - 0.5) < sq(0.11)
    })
}

/// Ground truth of [`hollow_sphere`]: a centred spherical shell with inner
/// radius `0.22·n` and outer radius `0.36·n`.
pub fn hollow_sphere_labels(n: usize) -> Vec<u8> {
    label_map3(n, |x, y, z| {
        let r2 = sq(x - 0.5) + sq(y - 0.5) + sq(z - 0.5);
        r2 < sq(0.36) && r2 >= sq(0.22)
    })
}

fn render3(n: usize, truth: Vec<u8>, noise_sigma: f64, seed: u64) -> Phantom3 {
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom3::from_labels([n, n, n], truth, &TWO_PHASE_LEVELS, &opts)
}

/// Two balls 2 voxels apart (topology test: must not merge).
pub fn two_balls(n: usize, noise_sigma: f64, seed: u64) -> Phantom3 {
    render3(n, two_balls_labels(n), noise_sigma, seed)
}

/// A solid torus (genus one).
pub fn torus(n: usize, noise_sigma: f64, seed: u64) -> Phantom3 {
    render3(n, torus_labels(n), noise_sigma, seed)
}

/// A spherical shell (a closed cavity inside the object).
pub fn hollow_sphere(n: usize, noise_sigma: f64, seed: u64) -> Phantom3 {
    render3(n, hollow_sphere_labels(n), noise_sigma, seed)
}

/// The 3D phantoms by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Phantom3Kind {
    /// [`two_balls`].
    TwoBalls,
    /// [`torus`].
    Torus,
    /// [`hollow_sphere`].
    HollowSphere,
    /// [`three_phase`]: three phases meeting along a junction curve.
    ThreePhase,
    /// [`four_phase`]: four phases, junction curves and points.
    FourPhase,
    /// [`brain`]: four classes in folded layers with a bias field
    /// (`size` is the longest side; `160 × 190 × 150` at 190).
    Brain,
}

impl Phantom3Kind {
    /// Every kind, in order.
    pub const ALL: [Phantom3Kind; 6] = [
        Self::TwoBalls,
        Self::Torus,
        Self::HollowSphere,
        Self::ThreePhase,
        Self::FourPhase,
        Self::Brain,
    ];

    /// The command-line name (`two_balls`, `torus`, `hollow_sphere`,
    /// `three_phase`, `four_phase`, `brain`).
    pub fn name(self) -> &'static str {
        match self {
            Self::TwoBalls => "two_balls",
            Self::Torus => "torus",
            Self::HollowSphere => "hollow_sphere",
            Self::ThreePhase => "three_phase",
            Self::FourPhase => "four_phase",
            Self::Brain => "brain",
        }
    }

    /// Parses a name as printed by [`Self::name`] (`-` is accepted for `_`).
    pub fn from_name(name: &str) -> Option<Self> {
        let n = name.trim().to_ascii_lowercase().replace('-', "_");
        Self::ALL.into_iter().find(|k| k.name() == n)
    }

    /// Number of phases.
    pub fn phases(self) -> usize {
        match self {
            Self::TwoBalls | Self::Torus | Self::HollowSphere => 2,
            Self::ThreePhase => 3,
            Self::FourPhase | Self::Brain => 4,
        }
    }

    /// Generates the phantom (`n³`, or longest side `n` for the brain;
    /// noise `noise_sigma`, RNG `seed`).
    pub fn generate(self, n: usize, noise_sigma: f64, seed: u64) -> Phantom3 {
        match self {
            Self::TwoBalls => two_balls(n, noise_sigma, seed),
            Self::Torus => torus(n, noise_sigma, seed),
            Self::HollowSphere => hollow_sphere(n, noise_sigma, seed),
            Self::ThreePhase => three_phase(n, noise_sigma, seed),
            Self::FourPhase => four_phase(n, noise_sigma, seed),
            Self::Brain => brain(n, noise_sigma, seed),
        }
    }
}

impl std::fmt::Display for Phantom3Kind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
