//! 3D phantoms with more than two phases, whose phases meet along junction
//! curves (edges where three phases meet) and at points where four meet.
//! Same grid convention as [`super::shapes3d`]: voxel `i` of an `n`-voxel
//! axis has normalised centre `(i + 0.5) / n`, x fastest.

use super::{Phantom3, RenderOptions, FOUR_PHASE_LEVELS};

/// Phase levels of [`three_phase`]: background, left ball, right ball.
pub const THREE_PHASE_LEVELS: [f64; 3] = [0.2, 0.5, 0.8];

/// Radius (normalised) of each ball of [`three_phase_labels`].
pub const THREE_PHASE_RADIUS: f64 = 0.24;

fn label_map3(n: usize, f: impl Fn(f64, f64, f64) -> u8) -> Vec<u8> {
    let c: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) / n as f64).collect();
    let mut out = Vec::with_capacity(n * n * n);
    for &z in &c {
        for &y in &c {
            for &x in &c {
                out.push(f(x, y, z));
            }
        }
    }
    out
}

fn inside_ball(p: [f64; 3], centre: [f64; 3], r: f64) -> bool {
    let d: f64 = (0..3).map(|k| (p[k] - centre[k]).powi(2)).sum();
    d < r * r
}

/// Ground truth of [`three_phase`]: two overlapping balls of radius
/// `0.24·n` whose centres are `0.3·n` apart on the x axis; the right ball
/// (phase 2) takes their overlap, the left one is phase 1. The three phases
/// meet along the circle where the two spheres intersect.
pub fn three_phase_labels(n: usize) -> Vec<u8> {
    let r = THREE_PHASE_RADIUS;
    label_map3(n, |x, y, z| {
        let p = [x, y, z];
        if inside_ball(p, [0.65, 0.5, 0.5], r) {
            2
        } else if inside_ball(p, [0.35, 0.5, 0.5], r) {
            1
        } else {
            0
        }
    })
}

/// Ground truth of [`four_phase`]: a centred ball of radius `0.36·n` cut
/// into three wedges around a tilted axis (phases 1, 2, 3 by angle, of
/// 100°, 120° and 140°) on a background (phase 0). The wedges meet along a
/// junction line inside the ball; each pair of wedges meets the background
/// along an arc of the sphere, and the four phases meet at the two points
/// where the line leaves the ball.
pub fn four_phase_labels(n: usize) -> Vec<u8> {
    // An orthonormal frame (u, v) of the plane normal to the tilted axis
    // (0, sin t, cos t), t = 0.3 rad.
    let (s, c) = 0.3f64.sin_cos();
    let u = [1.0, 0.0, 0.0];
    let v = [0.0, c, -s];
    label_map3(n, |x, y, z| {
        let p = [x - 0.5, y - 0.5, z - 0.5];
        if p.iter().map(|a| a * a).sum::<f64>() >= 0.36 * 0.36 {
            return 0;
        }
        let pu: f64 = (0..3).map(|k| p[k] * u[k]).sum();
        let pv: f64 = (0..3).map(|k| p[k] * v[k]).sum();
        let angle = pv.atan2(pu).to_degrees().rem_euclid(360.0);
        if angle < 100.0 {
            1
        } else if angle < 220.0 {
            2
        } else {
            3
        }
    })
}

/// Three phases: two overlapping balls of different intensity on a
/// background (levels [`THREE_PHASE_LEVELS`]).
pub fn three_phase(n: usize, noise_sigma: f64, seed: u64) -> Phantom3 {
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom3::from_labels([n, n, n], three_phase_labels(n), &THREE_PHASE_LEVELS, &opts)
}

/// Four phases: a ball of three wedges on a background (levels
/// [`FOUR_PHASE_LEVELS`] by phase index).
pub fn four_phase(n: usize, noise_sigma: f64, seed: u64) -> Phantom3 {
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom3::from_labels([n, n, n], four_phase_labels(n), &FOUR_PHASE_LEVELS, &opts)
}
