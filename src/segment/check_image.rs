//! The input as the checks after a run read it: smoothed by a Gaussian of
//! [`CHECK_SMOOTHING`] pixel or voxel, made once and shared.
//!
//! The absorbed-phase check ([`super::absorbed`]) and the missed-object check
//! ([`super::missed_objects`]) both ask what the image looks like where
//! single noisy samples do not count, and both read the same smoothed copy.
//! A 2D run makes it during its setup, on the second thread while the first
//! thread reads the image's figures (the blur needs none of them; the setup
//! is otherwise sequential, and at 256² the blur is a tenth of a run); a 3D
//! run makes it when a check first asks, after the iterations, so that the
//! copy does not add to the memory of the run itself.

use std::sync::OnceLock;

use super::image::ImageView;
use crate::phantom::blur::gaussian_blur_3d;

/// Standard deviation, in pixels or voxels, of the checks' smoothing: it
/// takes most of the noise's scatter out and keeps layers a voxel thick.
pub const CHECK_SMOOTHING: f64 = 1.0;

/// The smoothed copy of one image, made on first use.
#[derive(Clone, Debug, Default)]
pub struct CheckImage(OnceLock<Vec<f32>>);

impl CheckImage {
    /// `image` smoothed by [`CHECK_SMOOTHING`]: made now if it was not
    /// yet. `image` must be the one every call passes.
    pub fn of(&self, image: &ImageView<'_>) -> &[f32] {
        self.0.get_or_init(|| {
            let [nx, ny, nz] = image.dims;
            gaussian_blur_3d(image.data, nx, ny, nz, CHECK_SMOOTHING)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_copy_is_made_once_and_is_the_blur() {
        let data: Vec<f32> = (0..64).map(|i| if i % 8 < 4 { 0.0 } else { 1.0 }).collect();
        let view = ImageView::new_2d(8, 8, &data).unwrap();
        let check = CheckImage::default();
        let first = check.of(&view).as_ptr();
        assert_eq!(check.of(&view).as_ptr(), first, "made once");
        assert_eq!(
            check.of(&view),
            gaussian_blur_3d(&data, 8, 8, 1, CHECK_SMOOTHING).as_slice()
        );
        // the step softened, its sides kept
        assert!(check.of(&view)[3] > 0.0 && check.of(&view)[3] < 0.5);
        assert!(check.of(&view)[0] < 1e-3);
    }
}
