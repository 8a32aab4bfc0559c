//! The dimension-specific part of the segmentation: which pixels a cell
//! covers, where to sample a facet, and how to interpolate the image.
//!
//! Everything else in [`crate::segment`] is written once against [`Raster`],
//! implemented for triangles over pixels ([`D2`](crate::dim::D2), [`d2`]) and
//! tetrahedra over voxels ([`D3`](crate::dim::D3), [`d3`]).

use super::image::ImageView;
use crate::complex::{BuildError, Complex};
use crate::dim::Dim;
use crate::dsc::Connectivity;

pub mod d2;
pub mod d3;

/// Image access for cells and facets of dimension `Self`.
///
/// Contract for [`Raster::cell_pixels`]: over a complex that tiles the image
/// domain, every pixel/voxel is visited by exactly one cell (centre rule with
/// half-open boundaries computed identically by the two cells sharing a facet).
pub trait Raster: Connectivity {
    /// Calls `visit(start, end)` for every run of pixels/voxels whose centres
    /// lie in the cell with the given `NV` corners: the linear indices
    /// `start..end` are contiguous in memory (one image row, or part of one),
    /// so callers can sum slices `&data[start..end]` in a tight loop. Runs are
    /// non-empty and come in increasing index order.
    fn cell_spans(
        image: &ImageView<'_>,
        corners: &[Self::Point],
        visit: &mut impl FnMut(usize, usize),
    );

    /// Calls `visit(index)` for the linear index of every pixel/voxel whose
    /// centre lies in the cell with the given `NV` corners (in increasing
    /// order; the pixels of [`Raster::cell_spans`] one by one).
    #[inline]
    fn cell_pixels(image: &ImageView<'_>, corners: &[Self::Point], visit: &mut impl FnMut(usize)) {
        Self::cell_spans(image, corners, &mut |a, b| (a..b).for_each(&mut *visit));
    }

    /// Samples the facet with the given `N` corners about every `spacing`
    /// units: calls `visit(point, weights, measure)` where `weights` are the
    /// barycentric (hat) weights of the point over the facet corners and
    /// `measure` the part of the facet's length/area the sample stands for.
    fn facet_samples(
        corners: &[Self::Point],
        spacing: f64,
        visit: &mut impl FnMut(Self::Point, &[f64], f64),
    );

    /// The image interpolated (bi-/trilinearly between sample centres, clamped
    /// at the border) at a point of the domain.
    fn sample(image: &ImageView<'_>, p: Self::Point) -> f64;

    /// The centre of the pixel/voxel with the given linear index.
    fn pixel_centre(image: &ImageView<'_>, index: usize) -> Self::Point;

    /// A complex filling the image domain `[0, dims]` at edge length `l`,
    /// every cell labelled 0.
    fn box_complex(image: &ImageView<'_>, l: f64) -> Result<Complex<Self>, BuildError>;
}

/// The dimension's point type, for generic code that names it.
pub type PointOf<K> = <K as Dim>::Point;
