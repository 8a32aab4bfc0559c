//! A borrowed view of a scalar image or volume, the input of the segmentation.

/// A row-major scalar image (2D) or volume (3D): `x` fastest, then `y`, then `z`.
///
/// Pixel `(x, y)` covers `[x, x+1) × [y, y+1)` of the complex's domain and has
/// its centre at `(x + 0.5, y + 0.5)`; `y` is the row index. A 2D image has
/// `dims[2] == 1`. A volume may have a physical voxel size
/// ([`ImageView::with_spacing`]): voxel `(x, y, z)` then covers
/// `[x, x+1)·s_x × [y, y+1)·s_y × [z, z+1)·s_z` and the complex, its edge
/// length and every length and area of the segmentation are physical.
#[derive(Clone, Copy, Debug)]
pub struct ImageView<'a> {
    /// Extent in pixels/voxels along each axis.
    pub dims: [usize; 3],
    /// The samples, `dims[0] · dims[1] · dims[2]` of them.
    pub data: &'a [f32],
    /// Size of a voxel along x, y, z in the complex's units (1 for 2D images).
    pub spacing: [f64; 3],
    /// The robust range of `data` where the caller has selected it already
    /// ([`ImageView::with_robust_range`]), with the samples it was given for.
    robust_range: Option<KnownRange>,
}

/// A robust range given with a view, and the samples it was given for (their
/// address and count): `data` is a public field, and a range carried over to
/// other samples must not be read as theirs.
#[derive(Clone, Copy, Debug)]
struct KnownRange {
    range: (f64, f64),
    address: usize,
    len: usize,
}

impl KnownRange {
    fn of(data: &[f32], range: (f64, f64)) -> Self {
        KnownRange {
            range,
            address: data.as_ptr() as usize,
            len: data.len(),
        }
    }

    fn holds_for(&self, data: &[f32]) -> bool {
        self.address == data.as_ptr() as usize && self.len == data.len()
    }
}

impl<'a> ImageView<'a> {
    /// A 2D view; `None` when `data.len() != width · height`.
    pub fn new_2d(width: usize, height: usize, data: &'a [f32]) -> Option<Self> {
        (width.checked_mul(height) == Some(data.len())).then_some(ImageView {
            dims: [width, height, 1],
            data,
            spacing: [1.0; 3],
            robust_range: None,
        })
    }

    /// A 3D view of `nx × ny × nz` voxels (x fastest); `None` when the sizes disagree.
    pub fn new_3d(dims: [usize; 3], data: &'a [f32]) -> Option<Self> {
        (dims[0]
            .checked_mul(dims[1])
            .and_then(|a| a.checked_mul(dims[2]))
            == Some(data.len()))
        .then_some(ImageView {
            dims,
            data,
            spacing: [1.0; 3],
            robust_range: None,
        })
    }

    /// The view of a volume with voxels of the given size (positive and
    /// finite; `None` otherwise).
    pub fn with_spacing(self, spacing: [f64; 3]) -> Option<Self> {
        spacing
            .iter()
            .all(|s| s.is_finite() && *s > 0.0)
            .then_some(ImageView { spacing, ..self })
    }

    /// The view of the same samples with their robust range
    /// ([`robust_range`](super::intensity::robust_range) of `data` among at
    /// most [`MAX_SAMPLES`](super::intensity::MAX_SAMPLES), over their
    /// extremes) given: the outlier clamp selects it before the
    /// segmentation, whose intensity figures then read it instead of
    /// selecting the same quantiles again.
    pub fn with_robust_range(self, range: (f64, f64)) -> Self {
        ImageView {
            robust_range: Some(KnownRange::of(self.data, range)),
            ..self
        }
    }

    /// The robust range given by [`with_robust_range`](Self::with_robust_range),
    /// while the view still holds the samples it was given for (`None` once
    /// `data` is replaced).
    pub fn known_robust_range(&self) -> Option<(f64, f64)> {
        self.robust_range
            .filter(|known| known.holds_for(self.data))
            .map(|known| known.range)
    }

    /// A view of other samples `data` on the same grid (a smoothed copy):
    /// nothing known of them.
    pub fn with_data<'b>(&self, data: &'b [f32]) -> ImageView<'b> {
        ImageView {
            dims: self.dims,
            data,
            spacing: self.spacing,
            robust_range: None,
        }
    }

    /// The size of one sample step ([`sample_step`](super::params::sample_step)):
    /// lengths counted in samples are this many units of the spacing.
    pub fn sample_step(&self) -> f64 {
        super::params::sample_step(self.dims, self.spacing)
    }

    /// The domain's extent along each axis (`dims · spacing`).
    pub fn extent(&self) -> [f64; 3] {
        std::array::from_fn(|a| self.dims[a] as f64 * self.spacing[a])
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.dims[0]
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.dims[1]
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// Whether the image has no samples.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// The value of pixel `(x, y)` of a 2D image.
    #[inline]
    pub fn at(&self, x: usize, y: usize) -> f32 {
        self.data[y * self.dims[0] + x]
    }

    /// Smallest and largest sample (`None` if empty or any sample is not finite).
    pub fn range(&self) -> Option<(f64, f64)> {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for &v in self.data {
            if !v.is_finite() {
                return None;
            }
            lo = lo.min(v as f64);
            hi = hi.max(v as f64);
        }
        (lo <= hi).then_some((lo, hi))
    }

    /// Number of distinct sample values, counting at most `cap`.
    pub fn distinct_values(&self, cap: usize) -> usize {
        let mut seen: Vec<u32> = Vec::new();
        for &v in self.data {
            let b = v.to_bits();
            if !seen.contains(&b) {
                seen.push(b);
                if seen.len() >= cap {
                    break;
                }
            }
        }
        seen.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_given_robust_range_holds_only_for_its_samples() {
        let (a, b) = (vec![0.0f32; 16], vec![1.0f32; 16]);
        let view = ImageView::new_2d(4, 4, &a)
            .unwrap()
            .with_robust_range((0.1, 0.9));
        assert_eq!(view.known_robust_range(), Some((0.1, 0.9)));
        let scaled = view.with_spacing([2.0, 2.0, 1.0]).unwrap();
        assert_eq!(scaled.known_robust_range(), Some((0.1, 0.9)));
        let mut swapped = view;
        swapped.data = &b;
        assert_eq!(swapped.known_robust_range(), None);
        assert_eq!(view.with_data(&a).known_robust_range(), None);
    }
}
