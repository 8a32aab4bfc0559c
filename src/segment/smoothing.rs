//! The image the region force samples: in 2D, under noise, a copy smoothed
//! by a Gaussian whose width follows the noise against the phase contrast.
//!
//! The normalised region force of eq. (6) at a point of the interface is
//! `(2I − m_a − m_b)/(m_a − m_b)`: a pixel at a phase mean pushes by 1, and
//! the noise of one pixel by `r = 2σ̂/Δ` (σ̂ the noise, Δ the smallest gap
//! between phase means). A vertex averages the samples along its own edges
//! only, a handful of them on the mesh's L-pixel edges, so where `r` nears 1
//! the interfaces follow the noise: the errors are roughness spread along
//! every boundary. Smoothing the sampled image with a Gaussian of standard
//! deviation `s` pixels also averages across the interface and divides the
//! noise of a sample by about `2√π·s`, while it leaves the force's zero where
//! it was along a straight edge between two plateaus (the smoothed step still
//! crosses the midpoint of its two levels at the edge). What it costs is
//! detail of about `s`: corners rounded, structures narrower than about `2s`
//! thinned. So the width grows with the force noise and is zero on images
//! whose noise is small against their contrast (photographs), where that
//! detail is what the segmentation is for.
//!
//! Only the region force samples the smoothed copy: the cell statistics, the
//! phase means, the label flips and the energy read the input. So the
//! adaptive mesh, whose refinement asks where cells' pixels are not
//! explained by their phase means, still finds the lines and blobs of 3–5 px
//! the input holds; sampling the smoothed copy there too raised its Dice on
//! every noisy phantom of the benchmark sets and found as many of the thin
//! phantom's blobs over noise seeds 1–3 (`benches/RESULTS.md`, "Adaptive
//! resolution").

use super::image::ImageView;
use crate::phantom::blur::gaussian_blur_2d;

/// Force noise `2σ̂/Δ` below which the force samples the input as it is.
pub const SMOOTHING_FROM_NOISE: f64 = 0.3;

/// The Gaussian's standard deviation in pixels per unit of force noise.
pub const SMOOTHING_PER_NOISE: f64 = 1.0;

/// Widest smoothing, in pixels.
pub const SMOOTHING_LIMIT: f64 = 2.0;

/// The standard deviation, in pixels, of the Gaussian the region force's
/// image is smoothed with, for an image whose noise `noise` (σ̂) is
/// `noise/gap` of the smallest gap between its phase means: 0 where the force
/// noise `2σ̂/Δ` is below [`SMOOTHING_FROM_NOISE`], else
/// [`SMOOTHING_PER_NOISE`] pixels per unit of it, at most
/// [`SMOOTHING_LIMIT`].
pub fn force_smoothing(noise: f64, gap: f64) -> f64 {
    if !(gap > 0.0 && noise.is_finite()) {
        return 0.0;
    }
    let force_noise = 2.0 * noise / gap;
    if force_noise < SMOOTHING_FROM_NOISE {
        return 0.0;
    }
    (SMOOTHING_PER_NOISE * force_noise).min(SMOOTHING_LIMIT)
}

/// The image the region force samples: the input, or a smoothed copy of a
/// 2D input.
#[derive(Clone, Debug, Default)]
pub struct ForceImage {
    /// The smoothed samples (empty: the input as it is).
    smoothed: Vec<f32>,
    /// The Gaussian's standard deviation in pixels (0: none).
    sigma: f64,
}

impl ForceImage {
    /// `image` smoothed by a Gaussian of standard deviation `sigma` pixels
    /// (2D; a volume, or `sigma` 0, is sampled as it is).
    pub fn smoothed(image: &ImageView<'_>, sigma: f64) -> Self {
        if sigma.is_nan() || sigma <= 0.0 || image.dims[2] != 1 {
            return ForceImage::default();
        }
        ForceImage {
            smoothed: gaussian_blur_2d(image.data, image.dims[0], image.dims[1], sigma),
            sigma,
        }
    }

    /// The Gaussian's standard deviation in pixels (0: the input as it is).
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// What the force samples of `image`: the smoothed copy if it was made
    /// from an image of this size, else `image` itself.
    pub fn view<'s>(&'s self, image: &ImageView<'s>) -> ImageView<'s> {
        if self.smoothed.len() == image.data.len() {
            image.with_data(&self.smoothed)
        } else {
            *image
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_width_follows_the_force_noise() {
        // photographs: noise a few percent of the contrast, no smoothing
        assert_eq!(force_smoothing(0.01, 0.2), 0.0);
        assert_eq!(force_smoothing(0.02, 0.2), 0.0);
        // the two-phase phantom at σ 0.1 (gap 0.4): half a pixel
        assert!((force_smoothing(0.1, 0.4) - 0.5).abs() < 1e-12);
        // four means 0.1 apart at σ 0.25: capped
        assert_eq!(force_smoothing(0.25, 0.1), SMOOTHING_LIMIT);
        // nothing known: none
        assert_eq!(force_smoothing(0.1, 0.0), 0.0);
        assert_eq!(force_smoothing(f64::NAN, 0.4), 0.0);
    }

    #[test]
    fn smoothing_keeps_a_straight_edge_where_it_was() {
        // a vertical step between 0.2 and 0.8 at x = 8 (pixels 0..8 dark)
        let (w, h) = (16, 6);
        let data: Vec<f32> = (0..w * h)
            .map(|i| if i % w < 8 { 0.2 } else { 0.8 })
            .collect();
        let view = ImageView::new_2d(w, h, &data).unwrap();
        let force = ForceImage::smoothed(&view, 1.5);
        let smoothed = force.view(&view);
        for y in 0..h {
            let row = &smoothed.data[y * w..(y + 1) * w];
            // symmetric about the edge: the pixels either side of it
            // average to the midpoint of the two levels
            assert!((row[7] + row[8] - 1.0).abs() < 1e-6, "{row:?}");
            assert!(row[7] < 0.5 && row[8] > 0.5, "{row:?}");
            // and the plateaus far from it are kept
            assert!((row[0] - 0.2).abs() < 1e-6 && (row[15] - 0.8).abs() < 1e-6);
        }
    }

    #[test]
    fn smoothing_lowers_the_noise() {
        // a checkerboard of ±1: the worst noise a pixel grid holds
        let (w, h) = (32, 32);
        let data: Vec<f32> = (0..w * h)
            .map(|i| if (i % w + i / w) % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let view = ImageView::new_2d(w, h, &data).unwrap();
        let force = ForceImage::smoothed(&view, 1.0);
        let smoothed = force.view(&view).data;
        // (away from the border, whose repeated pixels break the pattern)
        let largest = (4..h - 4)
            .flat_map(|y| (4..w - 4).map(move |x| y * w + x))
            .fold(0f32, |m, i| m.max(smoothed[i].abs()));
        assert!(largest < 0.01, "{largest}");
        assert_eq!(force.sigma(), 1.0);
    }

    #[test]
    fn no_width_or_a_volume_samples_the_input() {
        let data = vec![0.5f32, 0.1, 0.9, 0.3];
        let view = ImageView::new_2d(2, 2, &data).unwrap();
        let none = ForceImage::smoothed(&view, 0.0);
        assert_eq!(none.view(&view).data, &data[..]);
        assert_eq!(none.sigma(), 0.0);
        let volume = ImageView::new_3d([1, 2, 2], &data).unwrap();
        let as_is = ForceImage::smoothed(&volume, 1.0);
        assert_eq!(as_is.view(&volume).data, &data[..]);
    }

    #[test]
    fn the_result_does_not_depend_on_the_thread_count() {
        let (w, h) = (40, 30);
        let data: Vec<f32> = (0..w * h).map(|i| ((i * 7919) % 101) as f32).collect();
        let view = ImageView::new_2d(w, h, &data).unwrap();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| ForceImage::smoothed(&view, 1.3));
        let many = ForceImage::smoothed(&view, 1.3);
        assert_eq!(one.view(&view).data, many.view(&view).data);
    }
}
