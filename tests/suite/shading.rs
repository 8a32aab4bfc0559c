//! A smooth trend of intensity inside the phases (uneven illumination, a
//! bias field) is reported: the two-phase phantom under a ramp of
//! illumination across the image, in 2D and 3D, comes out with a warning
//! and the trend in the report; the same images without the ramp, the
//! four-phase phantom, and discs of several brightnesses in one phase on a
//! flat background, do not.

use dsc_seg::io::{Image2, Volume};
use dsc_seg::phantom::shapes2d::{four_phase, two_phase};
use dsc_seg::phantom::shapes3d::two_balls;
use dsc_seg::pipeline::{segment_image, segment_volume, Provenance};
use dsc_seg::segment::shading::PhaseTrend;
use dsc_seg::segment::SegmentParams;

const SIDE: usize = 256;

/// `image` (x fastest, rows of `width`, `planes` of `width · height`)
/// multiplied by an illumination rising from `1 − a/2` to `1 + a/2` along
/// x (`along_z`: along z).
fn shaded(image: &[f32], [nx, ny, nz]: [usize; 3], a: f64, along_z: bool) -> Vec<f32> {
    image
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            let (pos, n) = if along_z {
                (i / (nx * ny), nz)
            } else {
                (i % nx, nx)
            };
            let factor = 1.0 + a * (pos as f64 / (n - 1) as f64 - 0.5);
            (f64::from(v) * factor) as f32
        })
        .collect()
}

fn warned(trends: &[PhaseTrend]) -> Vec<u8> {
    trends
        .iter()
        .filter(|t| t.warned)
        .map(|t| t.phase)
        .collect()
}

fn shading_warnings(warnings: &[String]) -> usize {
    warnings
        .iter()
        .filter(|w| w.contains("drifts smoothly"))
        .count()
}

#[test]
fn a_shaded_two_phase_image_is_warned_of() {
    let ph = two_phase(SIDE, 0.1, 1);
    let image = Image2::from_raw(SIDE, SIDE, shaded(&ph.image, [SIDE, SIDE, 1], 0.2, false));
    let seg = segment_image(&image, SegmentParams::new(2), Provenance::array(), true).unwrap();
    let trends = seg.summary.shading.as_ref().expect("looked for");
    eprintln!("{trends:?}");
    assert!(!warned(trends).is_empty(), "{trends:?}");
    let bright = &trends[1];
    // the bright phase (0.7) spans most of the width: 0.7 × 0.2 at most
    assert!(bright.trend > 0.07 && bright.trend < 0.15, "{bright:?}");
    assert!(bright.darkest_at[0] < bright.brightest_at[0], "{bright:?}");
    let warnings = &seg.summary.warnings;
    assert!(shading_warnings(warnings) >= 1, "{warnings:?}");
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("drifts smoothly") && w.contains("bias-field correction")),
        "{warnings:?}"
    );
}

#[test]
fn the_same_images_unshaded_are_not() {
    for noise in [0.1, 0.2] {
        for (ph, phases) in [
            (two_phase(SIDE, noise, 1), 2),
            (four_phase(SIDE, noise, 1), 4),
        ] {
            let image = Image2::from_raw(SIDE, SIDE, ph.image.clone());
            let params = SegmentParams::new(phases);
            let seg = segment_image(&image, params, Provenance::array(), true).unwrap();
            let trends = seg.summary.shading.as_ref().expect("looked for");
            assert_eq!(trends.len(), phases, "every phase judged: {trends:?}");
            assert!(warned(trends).is_empty(), "σ {noise}: {trends:?}");
            assert_eq!(shading_warnings(&seg.summary.warnings), 0);
        }
    }
}

#[test]
fn a_shaded_volume_is_warned_of_and_the_same_volume_unshaded_is_not() {
    let n = 48;
    let ph = two_balls(n, 0.1, 1);
    let run = |data: Vec<f32>| {
        let volume = Volume::from_raw(n, n, n, data);
        let params = SegmentParams::new_3d(2);
        segment_volume(&volume, params, Provenance::array(), None, true).unwrap()
    };
    let clean = run(ph.image.clone());
    let trends = clean.summary.shading.as_ref().expect("looked for");
    assert!(warned(trends).is_empty(), "{trends:?}");
    let seg = run(shaded(&ph.image, [n; 3], 0.4, true));
    let trends = seg.summary.shading.as_ref().expect("looked for");
    assert!(!warned(trends).is_empty(), "{trends:?}");
    let warnings = &seg.summary.warnings;
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("drifts smoothly") && w.contains("z = ")),
        "{warnings:?}"
    );
}

/// A `SIDE`² image of six discs of radius 24 on a flat background of 0.2:
/// three columns of discs at 0.55, 0.7 and 0.85 from left to right (one
/// phase of two), with uniform noise of ±0.1.
fn discs() -> Vec<f32> {
    let s = SIDE as f64;
    let mut state = 12345u64;
    let mut data = Vec::with_capacity(SIDE * SIDE);
    for y in 0..SIDE {
        for x in 0..SIDE {
            let (px, py) = (x as f64, y as f64);
            let column = (0..3).find(|&c| {
                let cx = s * (1.0 + 2.0 * c as f64) / 6.0;
                [s / 4.0, 3.0 * s / 4.0]
                    .iter()
                    .any(|cy| (px - cx).powi(2) + (py - cy).powi(2) < 24.0 * 24.0)
            });
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let noise = 0.2 * ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
            let level = column.map_or(0.2, |c| 0.55 + 0.15 * c as f64);
            data.push((level + noise) as f32);
        }
    }
    data
}

#[test]
fn discs_of_several_brightnesses_in_one_phase_are_not_warned_of() {
    let image = Image2::from_raw(SIDE, SIDE, discs());
    let seg = segment_image(&image, SegmentParams::new(2), Provenance::array(), true).unwrap();
    let trends = seg.summary.shading.as_ref().expect("looked for");
    let ones = &trends[1];
    // the discs' levels rise across the image: a trend over the whole
    // phase, but none inside a disc
    assert!(ones.ratio > 0.25 && ones.significance > 4.0, "{trends:?}");
    assert!(ones.within < 0.5, "{trends:?}");
    assert!(warned(trends).is_empty(), "{trends:?}");
    assert_eq!(shading_warnings(&seg.summary.warnings), 0);
}
