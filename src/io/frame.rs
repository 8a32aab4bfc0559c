//! The physical frame of an image or volume: how big its pixels/voxels are
//! and where they sit in the world, so that every output lines up with the
//! input in the viewers that read it.
//!
//! Three coordinate systems meet here:
//!
//! - **index**: voxel `(i, j, k)` has its centre at `(i, j, k)`;
//! - **domain**: where the mesh lives. Voxel `(i, j, k)` covers
//!   `[i, i+1)·s_x × [j, j+1)·s_y × [k, k+1)·s_z` and has its centre at
//!   `((i+0.5)·s_x, …)`, with `s` the frame's [`Frame::domain_scale`] (the
//!   spacing in 3D, so that the DSC works in physical lengths; 1 in 2D);
//! - **world**: where the input's readers place the voxel centres: the NIfTI
//!   affine (sform, else qform, else `pixdim`), for TIFF `index · spacing` (as
//!   `vtkTIFFReader`), for PNG and other 2D images `index · spacing` with the
//!   rows counted upwards from the bottom row (as `vtkPNGReader`).

use serde::Serialize;

/// A 3×4 affine map (rows of `[linear | translation]`).
pub type Affine = [[f64; 4]; 3];

/// Where a frame's spacing and placement came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameSource {
    /// Nothing in the file: unit spacing.
    Default,
    /// PNG `pHYs` chunk.
    PngPhys,
    /// TIFF `XResolution`/`YResolution` tags (and ImageJ's `spacing=` in 3D).
    TiffResolution,
    /// An OME-TIFF's OME-XML description (`PhysicalSizeX`/`Y`/`Z`).
    OmeXml,
    /// NIfTI sform.
    NiftiSform,
    /// NIfTI qform.
    NiftiQform,
    /// NIfTI `pixdim` only (both form codes 0).
    NiftiPixdim,
    /// Set on the command line (`--spacing`).
    Given,
}

impl FrameSource {
    /// Whether the frame is a NIfTI header's.
    pub fn is_nifti(self) -> bool {
        matches!(
            self,
            FrameSource::NiftiSform | FrameSource::NiftiQform | FrameSource::NiftiPixdim
        )
    }
}

/// How the world axes relate to the index axes (see the module documentation).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Frame {
    /// Voxels along x, y, z (`z = 1` for a 2D image).
    pub dims: [usize; 3],
    /// Physical size of a voxel along each index axis, in [`Frame::unit`].
    pub spacing: [f64; 3],
    /// The length unit of the spacing and world coordinates (`"mm"`, `"um"`,
    /// …; `"px"` when the file gives none).
    pub unit: String,
    /// What the mesh coordinates count per voxel (see the module documentation).
    pub domain_scale: [f64; 3],
    /// Index coordinates to world coordinates.
    pub index_to_world: Affine,
    /// Where the spacing and placement came from.
    pub source: FrameSource,
}

impl Frame {
    /// A 2D image as `vtkPNGReader` shows it: x to the right, rows upwards
    /// from the bottom row (row 0 of the file at `y = (h−1)·s_y`).
    pub fn image_rows_up(width: usize, height: usize, spacing: [f64; 2], unit: &str) -> Self {
        let [sx, sy] = spacing;
        let a = [
            [sx, 0.0, 0.0, 0.0],
            [0.0, -sy, 0.0, (height as f64 - 1.0) * sy],
            [0.0, 0.0, 1.0, 0.0],
        ];
        Frame::pixel_domain([width, height, 1], [sx, sy, 1.0], unit, a)
    }

    /// A 2D image as `vtkTIFFReader` shows it: `world = index · spacing`.
    pub fn image_rows_down(width: usize, height: usize, spacing: [f64; 2], unit: &str) -> Self {
        let [sx, sy] = spacing;
        Frame::pixel_domain(
            [width, height, 1],
            [sx, sy, 1.0],
            unit,
            diagonal([sx, sy, 1.0]),
        )
    }

    /// A 2D image placed in the world by `index_to_world` (the affine of a
    /// NIfTI file one slice thick); `spacing` is the pixel size and the
    /// slice's thickness. The mesh works in pixel units, as for every 2D image.
    pub fn image_affine(
        width: usize,
        height: usize,
        spacing: [f64; 3],
        unit: &str,
        index_to_world: Affine,
    ) -> Self {
        Frame::pixel_domain([width, height, 1], spacing, unit, index_to_world)
    }

    /// A 2D frame whose mesh works in pixel units.
    fn pixel_domain(dims: [usize; 3], spacing: [f64; 3], unit: &str, a: Affine) -> Self {
        Frame {
            dims,
            spacing,
            unit: unit.to_string(),
            domain_scale: [1.0; 3],
            index_to_world: a,
            source: FrameSource::Default,
        }
    }

    /// A volume whose world coordinates are `index · spacing` (TIFF stacks,
    /// folders of slices, phantoms); the mesh works in the same lengths.
    pub fn volume(dims: [usize; 3], spacing: [f64; 3], unit: &str) -> Self {
        Frame::volume_affine(dims, spacing, unit, diagonal(spacing))
    }

    /// A volume placed in the world by `index_to_world` (a NIfTI affine);
    /// `spacing` is the voxel size (the lengths of the affine's columns).
    pub fn volume_affine(dims: [usize; 3], spacing: [f64; 3], unit: &str, a: Affine) -> Self {
        Frame {
            dims,
            spacing,
            unit: unit.to_string(),
            domain_scale: spacing,
            index_to_world: a,
            source: FrameSource::Default,
        }
    }

    /// The same frame, its origin recorded as coming from `source`.
    pub fn with_source(mut self, source: FrameSource) -> Self {
        self.source = source;
        self
    }

    /// Replaces the spacing (e.g. from `--spacing`), keeping each world
    /// axis's direction and the world position of voxel 0 (of a volume) or
    /// of the image's corner pixel at the world origin (2D: the bottom-left
    /// pixel of a PNG as `vtkPNGReader` places it, the first of a TIFF).
    pub fn respaced(&self, spacing: [f64; 3]) -> Self {
        let mut f = self.clone();
        for (c, &s) in spacing.iter().enumerate() {
            let ratio = s / self.spacing[c];
            for row in &mut f.index_to_world {
                row[c] *= ratio;
            }
            if self.dims[2] == 1 && !self.source.is_nifti() {
                // A PNG's or TIFF's offset is its flip, (h−1)·s_y: it scales
                // too (a NIfTI slice keeps its origin, as a volume does).
                f.index_to_world[c][3] *= ratio;
            }
        }
        if self.dims[2] > 1 || self.domain_scale != [1.0; 3] {
            // A volume: the mesh works in physical lengths.
            f.domain_scale = spacing;
        }
        f.spacing = spacing;
        f.source = FrameSource::Given;
        f.unit = given_unit(&self.unit).to_string();
        f
    }

    /// The index coordinates of a domain point (a 2D image's points, at
    /// `z = 0`, stay in the plane of its one slice).
    pub fn domain_to_index(&self, p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|c| {
            if self.dims[c] == 1 {
                0.0
            } else {
                p[c] / self.domain_scale[c] - 0.5
            }
        })
    }

    /// The world coordinates of index coordinates.
    pub fn index_to_world(&self, q: [f64; 3]) -> [f64; 3] {
        self.index_to_world
            .map(|r| r[0] * q[0] + r[1] * q[1] + r[2] * q[2] + r[3])
    }

    /// The world coordinates of a domain point (a mesh vertex).
    pub fn domain_to_world(&self, p: [f64; 3]) -> [f64; 3] {
        self.index_to_world(self.domain_to_index(p))
    }

    /// Whether the index-to-world map reverses orientation (its linear part
    /// has a negative determinant): a PNG's rows counted upwards, a NIfTI
    /// affine with one axis flipped (radiological order). A cell positively
    /// oriented in the mesh is then negatively oriented in the world, so the
    /// VTK writers swap two of its corners (see [`Complex::write_mesh_vtu`](crate::complex::Complex::write_mesh_vtu)).
    pub fn is_mirrored(&self) -> bool {
        let [a, b, c] = self.index_to_world.map(|r| [r[0], r[1], r[2]]);
        let det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0]);
        det < 0.0
    }

    /// Physical area (2D) or volume (3D) of one pixel/voxel.
    pub fn voxel_measure(&self) -> f64 {
        if self.dims[2] > 1 {
            self.spacing.iter().product()
        } else {
            self.spacing[0] * self.spacing[1]
        }
    }

    /// Whether the input carried no physical size (unit spacing, no unit).
    pub fn is_unitless(&self) -> bool {
        self.unit == "px"
    }

    /// The world position of voxel `(0,0,0)` and the unit world directions
    /// of the index axes (columns), as VTK's image data `Origin`/`Direction`.
    pub fn origin_and_direction(&self) -> ([f64; 3], [[f64; 3]; 3]) {
        let a = &self.index_to_world;
        let origin = [a[0][3], a[1][3], a[2][3]];
        let mut dir = [[0.0; 3]; 3];
        for c in 0..3 {
            let len = (0..3).map(|r| a[r][c] * a[r][c]).sum::<f64>().sqrt();
            for (r, row) in dir.iter_mut().enumerate() {
                row[c] = if len > 0.0 { a[r][c] / len } else { 0.0 };
            }
        }
        (origin, dir)
    }
}

/// The affine scaling each axis by `s`.
fn diagonal(s: [f64; 3]) -> Affine {
    [
        [s[0], 0.0, 0.0, 0.0],
        [0.0, s[1], 0.0, 0.0],
        [0.0, 0.0, s[2], 0.0],
    ]
}

/// The length unit of sizes given with `--spacing` on an input without a
/// physical size: they are no longer pixels, and no unit is known.
pub const NEUTRAL_UNIT: &str = "unit";

/// The unit of sizes given for an input whose unit was `unit`: the file's
/// own when it has one, else [`NEUTRAL_UNIT`].
pub fn given_unit(unit: &str) -> &str {
    if unit == "px" {
        NEUTRAL_UNIT
    } else {
        unit
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_up_puts_the_first_row_on_top() {
        let f = Frame::image_rows_up(6, 4, [1.0, 1.0], "px");
        // The centre of pixel (1, 0) is at domain (1.5, 0.5).
        assert_eq!(f.domain_to_world([1.5, 0.5, 0.0]), [1.0, 3.0, 0.0]);
        let g = Frame::image_rows_down(6, 4, [0.1, 0.2], "mm");
        assert_eq!(g.domain_to_world([1.5, 0.5, 0.0]), [0.1, 0.0, 0.0]);
        assert!((g.voxel_measure() - 0.02).abs() < 1e-15);
    }

    #[test]
    fn a_frame_mirrors_where_its_determinant_is_negative() {
        assert!(Frame::image_rows_up(6, 4, [1.0, 1.0], "px").is_mirrored());
        assert!(!Frame::image_rows_down(6, 4, [1.0, 1.0], "px").is_mirrored());
        assert!(!Frame::volume([4, 4, 4], [1.0, 1.0, 3.0], "mm").is_mirrored());
        let flip_x = [
            [-1.0, 0.0, 0.0, 10.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 3.0, 0.0],
        ];
        assert!(Frame::volume_affine([4, 4, 4], [1.0, 1.0, 3.0], "mm", flip_x).is_mirrored());
        let flip_x_and_y = [
            [-1.0, 0.0, 0.0, 10.0],
            [0.0, -1.0, 0.0, 0.0],
            [0.0, 0.0, 3.0, 0.0],
        ];
        assert!(
            !Frame::volume_affine([4, 4, 4], [1.0, 1.0, 3.0], "mm", flip_x_and_y).is_mirrored()
        );
    }

    #[test]
    fn volumes_work_in_physical_lengths() {
        let a = [
            [-0.5, 0.0, 0.0, 10.0],
            [0.0, 0.5, 0.0, -3.0],
            [0.0, 0.0, 2.0, 7.0],
        ];
        let f = Frame::volume_affine([8, 8, 4], [0.5, 0.5, 2.0], "mm", a);
        // Voxel (2, 3, 1): domain centre (1.25, 1.75, 3.0).
        assert_eq!(f.domain_to_world([1.25, 1.75, 3.0]), [9.0, -1.5, 9.0]);
        let (o, d) = f.origin_and_direction();
        assert_eq!(o, [10.0, -3.0, 7.0]);
        assert_eq!(d[0][0], -1.0);
        let g = f.respaced([1.0, 1.0, 1.0]);
        assert_eq!(g.domain_to_world([3.5, 4.5, 1.5]), [7.0, 1.0, 8.0]);
        assert_eq!(g.source, FrameSource::Given);
        assert_eq!(g.unit, "mm");
        let unitless = Frame::image_rows_up(6, 4, [1.0, 1.0], "px").respaced([0.5, 0.25, 1.0]);
        assert_eq!(unitless.unit, NEUTRAL_UNIT);
        // As the same image read with that spacing: the bottom row at y = 0.
        assert_eq!(unitless, {
            let mut f = Frame::image_rows_up(6, 4, [0.5, 0.25], NEUTRAL_UNIT);
            f.source = FrameSource::Given;
            f
        });
    }
}
