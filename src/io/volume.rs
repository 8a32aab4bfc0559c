//! 3D grayscale volumes: TIFF stacks, folders of slices and NIfTI-1.
//!
//! # Layout and coordinates
//!
//! A [`Volume`] of `nx × ny × nz` voxels stores `data[x + nx * (y + ny * z)]`
//! (x fastest, then y, then z). The continuous convention is the 3D analogue
//! of [`crate::io::image2`]: the domain is `[0,nx] × [0,ny] × [0,nz]` in voxel
//! units, voxel `(x,y,z)` covers `[x,x+1) × [y,y+1) × [z,z+1)` and its value
//! sits at the centre `(x+0.5, y+0.5, z+0.5)`. For a TIFF stack or a folder
//! of slices, `x` is the column, `y` the row (growing downwards) and `z` the
//! page/slice index; a NIfTI volume keeps its stored axis order. The
//! physical voxel size ([`Volume::spacing`], [`Volume::unit`]) and the
//! placement in the world ([`Volume::frame`]: the NIfTI affine, or
//! `index · spacing`) come with the volume; the segmentation works in
//! `index · spacing` lengths (see [`crate::io::frame`]).
//!
//! NIfTI-1 is read and its label maps written here rather than through the
//! `nifti` crate: that crate's affine needs nalgebra 0.35 (this crate is on
//! 0.34, so both would be built) and its writer ndarray, while the header
//! fields needed are few; the label map copies the input's header byte for
//! byte, so its geometry cannot drift from the input's.
//!
//! # Intensities
//!
//! Values are `f32` in `[0,1]`: unsigned 8-bit data is divided by 255 and
//! unsigned 16-bit data by 65535. Every other sample type (signed integers,
//! 32-bit integers, floats, or NIfTI data with a non-trivial
//! `scl_slope`/`scl_inter`) is mapped linearly by the data's own minimum and
//! maximum to `[0,1]` (a constant volume becomes all zeros; NaNs become 0;
//! data without a single finite sample is an error).
//! Slices loaded from a folder follow [`Image2::load`] per slice.

use std::cmp::Ordering;
use std::fs::File;
use std::io::{BufReader, Cursor, Read};
use std::path::{Path, PathBuf};

use super::atomic::{write_atomic, write_bytes_atomic};
use super::error::{io_reason, IoError, Result};
use super::frame::{Affine, Frame, FrameSource};
use super::hyperstack::Hyperstack;
use super::image2::{lerp_nodes, Colour, Image2, SampleType};
use super::intensity::IntensityMap;
use super::ome::OmeLayout;
use super::resolution::{tiff_sizes, Resolution};
use super::selection::{Selection, TiffPages};

/// A 3D grayscale volume (x fastest, then y, then z) with intensities in
/// `[0,1]` and a physical voxel spacing; see the module documentation.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    nx: usize,
    ny: usize,
    nz: usize,
    data: Vec<f32>,
    spacing: [f64; 3],
    unit: String,
    /// Loaded to original intensities, when known.
    intensity: Option<IntensityMap>,
    /// How the file stored its samples ([`SampleType::Float`] in memory).
    sample_type: SampleType,
    /// Index to world (a NIfTI affine); `None`: `index · spacing`.
    affine: Option<Affine>,
    source: FrameSource,
    /// The 348-byte header of a NIfTI input, the template of its label map.
    nifti_header: Option<Vec<u8>>,
    /// Warnings of reading the voxel size (see [`Volume::size_warnings`]).
    size_warnings: Vec<String>,
    /// That only the first series was read (see [`Volume::series_warning`]).
    series_warning: Option<String>,
    /// The channel and time point read of a hyperstack (see
    /// [`Volume::selection`]).
    selection: Selection,
}

impl Volume {
    /// Wraps `data` (`data[x + nx * (y + ny * z)]`) as a volume with unit
    /// spacing.
    ///
    /// # Panics
    /// If `data.len() != nx * ny * nz` (a programming error).
    pub fn from_raw(nx: usize, ny: usize, nz: usize, data: Vec<f32>) -> Self {
        assert_eq!(
            data.len(),
            nx * ny * nz,
            "Volume::from_raw: {} values for {nx}x{ny}x{nz}",
            data.len()
        );
        Volume {
            nx,
            ny,
            nz,
            data,
            spacing: [1.0; 3],
            unit: "px".into(),
            intensity: None,
            sample_type: SampleType::Float,
            affine: None,
            source: FrameSource::Default,
            nifti_header: None,
            size_warnings: Vec::new(),
            series_warning: None,
            selection: Selection::default(),
        }
    }

    /// Builds a volume by evaluating `f(x, y, z)` at every voxel.
    pub fn from_fn(
        nx: usize,
        ny: usize,
        nz: usize,
        mut f: impl FnMut(usize, usize, usize) -> f32,
    ) -> Self {
        let mut data = Vec::with_capacity(nx * ny * nz);
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    data.push(f(x, y, z));
                }
            }
        }
        Self::from_raw(nx, ny, nz, data)
    }

    /// Returns the volume with the given physical voxel size (x, y, z).
    pub fn with_spacing(mut self, spacing: [f64; 3]) -> Self {
        self.spacing = spacing;
        self
    }

    /// Returns the volume with the given length unit of its spacing.
    pub fn with_unit(mut self, unit: &str) -> Self {
        self.unit = unit.to_string();
        self
    }

    /// Returns the volume placed in the world by `affine` (index to world).
    pub fn with_affine(mut self, affine: Affine, source: FrameSource) -> Self {
        self.affine = Some(affine);
        self.source = source;
        self
    }

    /// Returns the volume with voxels of size `spacing` instead of the
    /// file's: the axes keep their world directions and voxel 0 its place.
    pub fn respaced(mut self, spacing: [f64; 3]) -> Self {
        let ratio: [f64; 3] = std::array::from_fn(|c| spacing[c] / self.spacing[c]);
        if let Some(a) = &mut self.affine {
            for row in a.iter_mut() {
                for (c, v) in row.iter_mut().take(3).enumerate() {
                    *v *= ratio[c];
                }
            }
        }
        if let Some(h) = &mut self.nifti_header {
            rescale_nifti_axes(h, ratio);
        }
        self.spacing = spacing;
        self.source = FrameSource::Given;
        self.unit = crate::io::frame::given_unit(&self.unit).to_string();
        // The file's voxel size is not used: what was said of it is moot.
        self.size_warnings.clear();
        self
    }

    /// What reading the file's voxel size left to say, one line each naming
    /// the file: an OME-TIFF whose OME-XML could not be used, or that gives
    /// no `PhysicalSizeZ` for its slices. Empty once [`Volume::respaced`].
    pub fn size_warnings(&self) -> &[String] {
        &self.size_warnings
    }

    /// That only the first series of an OME-TIFF of several was read, one
    /// line naming the file.
    pub fn series_warning(&self) -> Option<&str> {
        self.series_warning.as_deref()
    }

    /// The channel and time point of a TIFF's pages this volume holds, as
    /// chosen (empty: not chosen; see [`Volume::load_tiff_selected`]).
    pub fn selection(&self) -> Selection {
        self.selection
    }

    /// The header of the NIfTI file this volume was read from.
    pub fn nifti_header(&self) -> Option<&[u8]> {
        self.nifti_header.as_deref()
    }

    /// Where the voxels sit in the world (see [`Frame`]).
    pub fn frame(&self) -> Frame {
        let dims = self.dims();
        let frame = match self.affine {
            Some(a) => Frame::volume_affine(dims, self.spacing, &self.unit, a),
            None => Frame::volume(dims, self.spacing, &self.unit),
        };
        frame.with_source(self.source)
    }

    /// How the loaded intensities map back to the file's (`None`: unknown).
    pub fn intensity(&self) -> Option<IntensityMap> {
        self.intensity
    }

    /// Returns the volume with a known map back to the file's intensities.
    pub fn with_intensity(mut self, map: IntensityMap) -> Self {
        self.intensity = Some(map);
        self
    }

    /// How the file stored its samples ([`SampleType::Float`] for volumes
    /// built in memory).
    pub fn sample_type(&self) -> SampleType {
        self.sample_type
    }

    /// Returns the volume with the sample type of the file it came from.
    pub fn with_sample_type(mut self, sample_type: SampleType) -> Self {
        self.sample_type = sample_type;
        self
    }

    /// The length unit of [`Volume::spacing`] (`"px"` when unknown).
    pub fn unit(&self) -> &str {
        &self.unit
    }

    /// Loads a volume, choosing the reader from the path:
    /// a directory is read as a stack of 2D slices ([`Volume::load_slices`]),
    /// `.nii`/`.nii.gz` as NIfTI-1 ([`Volume::load_nifti`]) and `.tif`/`.tiff`
    /// as a multi-page TIFF stack ([`Volume::load_tiff`]).
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        Self::load_selected(path, Selection::default())
    }

    /// [`Volume::load`] of one channel at one time point of a TIFF
    /// ([`Volume::load_tiff_selected`]); a choice for any other input, which
    /// has neither, is refused.
    pub fn load_selected(path: impl AsRef<Path>, selection: Selection) -> Result<Self> {
        let path = path.as_ref();
        let tiff = !path.is_dir() && super::resolution::is_tiff(path);
        if !selection.is_empty() && !tiff {
            return Err(IoError::NotInFile {
                path: path.to_path_buf(),
                reason: format!(
                    "{} chooses pages of a TIFF, and this is not one",
                    selection.options()
                ),
            });
        }
        if path.is_dir() {
            return Self::load_slices(path);
        }
        super::image2::refuse_empty_file(path)?;
        if is_nifti(path) {
            Self::load_nifti(path)
        } else if tiff {
            Self::load_tiff_selected(path, selection)
        } else {
            Err(IoError::UnknownType {
                path: path.to_path_buf(),
                reason: "expected a directory of slices, .tif/.tiff or .nii/.nii.gz".into(),
            })
        }
    }

    /// Loads a multi-page grayscale TIFF (8/16/32-bit integer or 32/64-bit
    /// float samples, one page per z slice) as written by Fiji/ImageJ or
    /// tifffile. All pages must have the same size. The spacing is taken
    /// from an OME-TIFF's OME-XML or the resolution tags and Fiji/ImageJ
    /// metadata when present (unit spacing otherwise; see
    /// [`tiff_sizes`]).
    ///
    /// A hyperstack of several channels or time points (ImageJ's or an
    /// OME-TIFF's, see [`Hyperstack`]) is refused. Of an OME-TIFF only the
    /// first series is read ([`Volume::series_warning`] says so when there
    /// are more), and one whose page count is not what its OME-XML declares
    /// is refused.
    pub fn load_tiff(path: impl AsRef<Path>) -> Result<Self> {
        Self::load_tiff_selected(path, Selection::default())
    }

    /// [`Volume::load_tiff`] of one channel at one time point of a
    /// hyperstack: only the pages of `selection` are read, in slice order
    /// (see [`Selection`]); the voxel size is read as for any stack. An
    /// empty selection reads as [`Volume::load_tiff`] does.
    pub fn load_tiff_selected(path: impl AsRef<Path>, selection: Selection) -> Result<Self> {
        let path = path.as_ref();
        let file = File::open(path).map_err(|e| IoError::unreadable(path, e))?;
        let bad = |e| tiff_error(path, e);
        let mut dec = tiff::decoder::Decoder::new(BufReader::new(file)).map_err(bad)?;
        let sizes = tiff_sizes(&mut dec, path);
        let ome = OmeLayout::of_tiff(&mut dec);
        let mut pages = PageStack::new();
        if selection.is_empty() {
            if let Some(stack) = Hyperstack::of_tiff(&mut dec) {
                return Err(IoError::NotOneVolume {
                    path: path.to_path_buf(),
                    reason: stack.refusal_of(&mut dec),
                });
            }
            loop {
                pages.push(&mut dec, path)?;
                let series_read = ome.as_ref().is_some_and(|o| pages.nz == o.pages());
                if series_read || !dec.more_images() {
                    break;
                }
                dec.next_image().map_err(bad)?;
            }
            if let Some(ome) = &ome {
                refuse_unlike_ome(path, ome, pages.nz, &mut dec)?;
            }
        } else {
            let layout = TiffPages::of_tiff(&mut dec, path)?;
            for page in selection.pages_of(&layout, path)? {
                dec.seek_to_image(page).map_err(bad)?;
                pages.push(&mut dec, path)?;
            }
        }
        let PageStack {
            raw,
            sample_type,
            nx,
            ny,
            nz,
        } = pages;
        let (data, intensity) = raw.normalise().map_err(|samples| IoError::NonFinite {
            path: path.to_path_buf(),
            samples,
        })?;
        let resolution = sizes.resolution.as_ref();
        let unit = resolution.map_or("px".into(), |r| r.unit.clone());
        let mut size_warnings = sizes.warnings;
        if nz > 1 && sizes.source == FrameSource::OmeXml && !sizes.z_given {
            size_warnings.push(format!(
                "{}: its OME-XML gives no PhysicalSizeZ: its slices are taken as 1 {unit} apart \
                 (--spacing X,Y,Z gives the voxel size)",
                path.display()
            ));
        }
        Ok(Volume {
            nx,
            ny,
            nz,
            data,
            intensity: Some(intensity),
            sample_type,
            spacing: resolution.map_or([1.0; 3], |r| r.spacing),
            unit,
            affine: None,
            nifti_header: None,
            source: sizes.source,
            size_warnings,
            series_warning: ome.and_then(|o| o.series_warning(path)),
            selection,
        })
    }

    /// Loads a directory of 2D slices (any format [`Image2::load`] reads),
    /// sorted in natural filename order (`s2.png` before `s10.png`); hidden
    /// files and files with non-image extensions are skipped. All slices must
    /// have the same size and sample type, and be gray: a colour slice is
    /// refused, as a colour page of a TIFF stack is, since a volume has no
    /// channel to choose and its luminance can invert the contrast sought.
    pub fn load_slices(dir: impl AsRef<Path>) -> Result<Self> {
        const EXTS: &[&str] = &[
            "png", "jpg", "jpeg", "tif", "tiff", "gif", "bmp", "pgm", "ppm", "pnm", "pbm", "pam",
        ];
        let dir = dir.as_ref();
        let mut files: Vec<PathBuf> = Vec::new();
        for entry in std::fs::read_dir(dir).map_err(|e| IoError::unreadable(dir, e))? {
            let p = entry.map_err(|e| IoError::unreadable(dir, e))?.path();
            let name = p.file_name().unwrap_or_default().to_string_lossy();
            let ext = p
                .extension()
                .map(|e| e.to_string_lossy().to_ascii_lowercase())
                .unwrap_or_default();
            if p.is_file() && !name.starts_with('.') && EXTS.contains(&ext.as_str()) {
                files.push(p);
            }
        }
        if files.is_empty() {
            return Err(IoError::NoSlices {
                path: dir.to_path_buf(),
                extensions: EXTS.join(", "),
            });
        }
        files.sort_by(|a, b| natural_cmp(&a.to_string_lossy(), &b.to_string_lossy()));
        let mut data = Vec::new();
        let (mut nx, mut ny) = (0, 0);
        let mut sample_type = SampleType::Float;
        for (z, f) in files.iter().enumerate() {
            let im = Image2::load(f)?;
            if im.colour() != Colour::Gray {
                return Err(IoError::Unsupported {
                    path: f.clone(),
                    reason: "the slice is in colour; the slices of a volume must be grayscale: \
                             save them as gray images or as one channel of each"
                        .into(),
                });
            }
            if z == 0 {
                (nx, ny) = im.dims();
                sample_type = im.sample_type();
            } else if im.sample_type() != sample_type {
                return Err(IoError::Unsupported {
                    path: f.clone(),
                    reason: format!(
                        "slice has {:?} samples, first slice {} has {sample_type:?}: \
                         the slices of a volume must share one sample type",
                        im.sample_type(),
                        files[0].display()
                    ),
                });
            } else if im.dims() != (nx, ny) {
                return Err(IoError::DimensionMismatch {
                    path: f.clone(),
                    reason: format!(
                        "slice is {}x{}, first slice {} is {nx}x{ny}",
                        im.width(),
                        im.height(),
                        files[0].display()
                    ),
                });
            }
            data.extend_from_slice(im.data());
        }
        // Each slice is loaded as a 2D image is: its map back to the file's
        // values is that of its sample type.
        Ok(Self::from_raw(nx, ny, files.len(), data)
            .with_intensity(IntensityMap::of_sample_type(sample_type))
            .with_sample_type(sample_type))
    }

    /// Loads a single-file NIfTI-1 volume (`.nii`, or gzip-compressed
    /// `.nii.gz`), either endianness, with datatype uint8, int8, int16,
    /// uint16, int32, uint32, float32 or float64. `scl_slope`/`scl_inter`
    /// are applied, and the voxel axes are used as stored. The frame is the
    /// sform if its code is set, else the qform, else `pixdim` alone; the
    /// spacing is the length of the affine's columns, the unit from
    /// `xyzt_units` (mm when unset). Dimensions beyond the third must be 1.
    pub fn load_nifti(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let mut bytes = std::fs::read(path).map_err(|e| IoError::unreadable(path, e))?;
        if bytes.starts_with(&[0x1f, 0x8b]) {
            let mut out = Vec::new();
            flate2::read::MultiGzDecoder::new(&bytes[..])
                .read_to_end(&mut out)
                .map_err(|e| IoError::MalformedNifti {
                    path: path.to_path_buf(),
                    reason: format!("bad gzip data: {e}"),
                })?;
            bytes = out;
        }
        parse_nifti(path, &bytes)
    }

    /// A volume one voxel thick (a NIfTI slice) as the 2D image it is:
    /// its samples as the 2D readers load them (8/16-bit unsigned scaled to
    /// `[0, 1]`, every other type in the file's values), placed in the world
    /// by the volume's frame; `None` for a volume of several slices.
    pub fn to_slice_image(&self) -> Option<Image2> {
        if self.nz != 1 {
            return None;
        }
        let t = self.sample_type;
        let map = self.intensity.unwrap_or(IntensityMap::IDENTITY);
        let data = if map == IntensityMap::of_sample_type(t) {
            self.data.clone()
        } else {
            self.data
                .iter()
                .map(|&v| map.original_sample(f64::from(v), t) as f32)
                .collect()
        };
        let frame = self.frame();
        let placement = Frame::image_affine(
            self.nx,
            self.ny,
            frame.spacing,
            &frame.unit,
            frame.index_to_world,
        )
        .with_source(frame.source);
        Some(
            Image2::from_raw(self.nx, self.ny, data)
                .with_sample_type(t)
                .with_placement(placement, self.nifti_header()),
        )
    }

    /// Number of voxels along x.
    pub fn nx(&self) -> usize {
        self.nx
    }

    /// Number of voxels along y.
    pub fn ny(&self) -> usize {
        self.ny
    }

    /// Number of voxels along z.
    pub fn nz(&self) -> usize {
        self.nz
    }

    /// `[nx, ny, nz]`.
    pub fn dims(&self) -> [usize; 3] {
        [self.nx, self.ny, self.nz]
    }

    /// Physical voxel size along x, y, z (1 when unknown).
    pub fn spacing(&self) -> [f64; 3] {
        self.spacing
    }

    /// The voxel values, `data[x + nx * (y + ny * z)]`.
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// Mutable access to the voxel values.
    pub fn data_mut(&mut self) -> &mut [f32] {
        &mut self.data
    }

    /// Consumes the volume and returns its voxel values.
    pub fn into_data(self) -> Vec<f32> {
        self.data
    }

    /// The linear index of voxel `(x, y, z)`.
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        x + self.nx * (y + self.ny * z)
    }

    /// The value of voxel `(x, y, z)`.
    ///
    /// # Panics
    /// If the voxel is outside the volume.
    pub fn get(&self, x: usize, y: usize, z: usize) -> f32 {
        assert!(
            x < self.nx && y < self.ny && z < self.nz,
            "voxel ({x},{y},{z}) outside"
        );
        self.data[self.index(x, y, z)]
    }

    /// Trilinear interpolation at the continuous point `(x, y, z)` (voxel
    /// units) with voxel centres as nodes, clamped at the border.
    pub fn trilinear(&self, x: f64, y: f64, z: f64) -> f32 {
        let (i0, i1, tx) = lerp_nodes(x, self.nx);
        let (j0, j1, ty) = lerp_nodes(y, self.ny);
        let (k0, k1, tz) = lerp_nodes(z, self.nz);
        let v = |i, j, k| self.data[self.index(i, j, k)];
        let lx = |j, k| v(i0, j, k) * (1.0 - tx) + v(i1, j, k) * tx;
        let ly = |k| lx(j0, k) * (1.0 - ty) + lx(j1, k) * ty;
        ly(k0) * (1.0 - tz) + ly(k1) * tz
    }
}

/// Raw samples collected while reading a TIFF stack.
enum Samples {
    U8(Vec<u8>),
    U16(Vec<u16>),
    F64(Vec<f64>),
}

impl Samples {
    fn len(&self) -> usize {
        match self {
            Samples::U8(v) => v.len(),
            Samples::U16(v) => v.len(),
            Samples::F64(v) => v.len(),
        }
    }

    /// Refused when a sample is not finite (see [`min_max_normalise`]).
    fn normalise(self) -> std::result::Result<(Vec<f32>, IntensityMap), NonFiniteSamples> {
        match self {
            Samples::U8(v) => Ok((
                v.into_iter().map(|s| s as f32 / 255.0).collect(),
                IntensityMap::unsigned(8),
            )),
            Samples::U16(v) => Ok((
                v.into_iter().map(|s| s as f32 / 65535.0).collect(),
                IntensityMap::unsigned(16),
            )),
            Samples::F64(v) => min_max_normalise(&v),
        }
    }
}

/// The pages of a TIFF stack read so far: their samples, in the type of
/// the first, and their size.
struct PageStack {
    raw: Samples,
    sample_type: SampleType,
    nx: usize,
    ny: usize,
    /// Pages read.
    nz: usize,
}

impl PageStack {
    fn new() -> Self {
        PageStack {
            raw: Samples::U8(Vec::new()),
            sample_type: SampleType::Uint8,
            nx: 0,
            ny: 0,
            nz: 0,
        }
    }

    /// Appends the decoder's current page as the next slice: a grayscale
    /// page of the first page's size and sample type.
    fn push<R: Read + std::io::Seek>(
        &mut self,
        dec: &mut tiff::decoder::Decoder<R>,
        path: &Path,
    ) -> Result<()> {
        let bad = |e| tiff_error(path, e);
        let nz = self.nz;
        let (w, h) = dec.dimensions().map_err(bad)?;
        let (w, h) = (w as usize, h as usize);
        if nz == 0 {
            (self.nx, self.ny) = (w, h);
            if w == 0 || h == 0 {
                return Err(IoError::empty(path, &[w, h]));
            }
        } else if (w, h) != (self.nx, self.ny) {
            return Err(IoError::DimensionMismatch {
                path: path.to_path_buf(),
                reason: format!("page {nz} is {w}x{h}, page 0 is {}x{}", self.nx, self.ny),
            });
        }
        refuse_non_gray_page(dec.colortype().map_err(bad)?, nz, path)?;
        let page = dec.read_image().map_err(bad)?;
        if nz == 0 {
            self.sample_type = tiff_sample_type(&page);
        }
        if !self.append(page) {
            return Err(IoError::Unsupported {
                path: path.to_path_buf(),
                reason: format!("page {nz} has a different or unsupported sample type"),
            });
        }
        self.nz += 1;
        if self.raw.len() != self.nx * self.ny * self.nz {
            return Err(IoError::MalformedTiff {
                path: path.to_path_buf(),
                reason: format!("page {nz} holds the wrong number of samples"),
            });
        }
        Ok(())
    }

    /// Appends a decoded page's samples; false when its type does not go
    /// with the first page's or cannot be converted.
    fn append(&mut self, page: tiff::decoder::DecodingResult) -> bool {
        use tiff::decoder::DecodingResult;
        let first = self.nz == 0;
        match (&mut self.raw, page) {
            (Samples::U8(v), DecodingResult::U8(p)) if first || !v.is_empty() => {
                v.extend(p);
                true
            }
            (Samples::U16(v), DecodingResult::U16(p)) => {
                v.extend(p);
                true
            }
            (Samples::F64(v), p) if !first => append_f64(v, p),
            (_, DecodingResult::U16(p)) if first => {
                self.raw = Samples::U16(p);
                true
            }
            (_, p) if first => {
                let mut v = Vec::new();
                let ok = append_f64(&mut v, p);
                self.raw = Samples::F64(v);
                ok
            }
            _ => false,
        }
    }
}

/// Refuses page `nz` of a stack unless it is grayscale of 8 bits or more.
fn refuse_non_gray_page(colour: tiff::ColorType, nz: usize, path: &Path) -> Result<()> {
    match colour {
        // Packed samples of under a byte (a 1-bit bilevel mask, 2- or
        // 4-bit gray).
        tiff::ColorType::Gray(bits) if bits < 8 => Err(IoError::Unsupported {
            path: path.to_path_buf(),
            reason: format!(
                "page {nz} has {bits}-bit samples{}; save the stack with 8-bit samples",
                if bits == 1 { " (a bilevel image)" } else { "" }
            ),
        }),
        tiff::ColorType::Gray(_) => Ok(()),
        other => Err(IoError::Unsupported {
            path: path.to_path_buf(),
            reason: format!(
                "page {nz} has colour type {other:?}, expected grayscale{}",
                colour_stack_hint(other)
            ),
        }),
    }
}

/// A TIFF decoder's error as the error of reading `path`.
pub(crate) fn tiff_error(path: &Path, e: tiff::TiffError) -> IoError {
    IoError::MalformedTiff {
        path: path.to_path_buf(),
        reason: match e {
            tiff::TiffError::IoError(io) => io_reason(&io),
            e => e.to_string(),
        },
    }
}

/// Refuses an OME-TIFF whose pages are not those its OME-XML declares,
/// `read` of them read (the first series', or all there are when fewer): of
/// one series, the pages after it are counted, and there must be none.
fn refuse_unlike_ome<R: Read + std::io::Seek>(
    path: &Path,
    ome: &OmeLayout,
    read: usize,
    dec: &mut tiff::decoder::Decoder<R>,
) -> Result<()> {
    let mut pages = read;
    if ome.series == 1 {
        while dec.more_images() && dec.next_image().is_ok() {
            pages += 1;
        }
    }
    match ome.page_mismatch(pages) {
        Some(reason) => Err(IoError::NotOneVolume {
            path: path.to_path_buf(),
            reason,
        }),
        None => Ok(()),
    }
}

/// The sample type of a decoded TIFF page.
fn tiff_sample_type(page: &tiff::decoder::DecodingResult) -> SampleType {
    use tiff::decoder::DecodingResult as D;
    match page {
        D::U8(_) => SampleType::Uint8,
        D::U16(_) => SampleType::Uint16,
        D::F16(_) | D::F32(_) | D::F64(_) => SampleType::Float,
        _ => SampleType::Int,
    }
}

/// Appends a decoded TIFF page of any non-8/16-bit-unsigned type as `f64`;
/// returns false for types we cannot convert.
fn append_f64(v: &mut Vec<f64>, page: tiff::decoder::DecodingResult) -> bool {
    use tiff::decoder::DecodingResult as D;
    match page {
        D::U8(p) => v.extend(p.into_iter().map(f64::from)),
        D::U16(p) => v.extend(p.into_iter().map(f64::from)),
        D::U32(p) => v.extend(p.into_iter().map(f64::from)),
        D::U64(p) => v.extend(p.into_iter().map(|s| s as f64)),
        D::I8(p) => v.extend(p.into_iter().map(f64::from)),
        D::I16(p) => v.extend(p.into_iter().map(f64::from)),
        D::I32(p) => v.extend(p.into_iter().map(f64::from)),
        D::I64(p) => v.extend(p.into_iter().map(|s| s as f64)),
        D::F16(p) => v.extend(p.into_iter().map(|s| f64::from(s.to_f32()))),
        D::F32(p) => v.extend(p.into_iter().map(f64::from)),
        D::F64(p) => v.extend(p),
        #[allow(unreachable_patterns)]
        _ => return false,
    }
    true
}

/// Maps values linearly so that the minimum becomes 0 and the maximum 1;
/// constant data becomes 0. Refuses data with a NaN or infinite sample: no
/// intensity is known there, and mapping it to any value (the lowest, say)
/// would pass a guess off as data. 2D images are refused alike.
pub fn min_max_normalise(
    v: &[f64],
) -> std::result::Result<(Vec<f32>, IntensityMap), NonFiniteSamples> {
    let non_finite = v.iter().filter(|s| !s.is_finite()).count();
    if non_finite > 0 || v.is_empty() {
        return Err(NonFiniteSamples {
            count: non_finite,
            total: v.len(),
        });
    }
    let (lo, hi) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &s| {
            (lo.min(s), hi.max(s))
        });
    let range = hi - lo;
    let data = v
        .iter()
        .map(|&s| {
            if range <= 0.0 {
                0.0
            } else {
                ((s - lo) / range).clamp(0.0, 1.0) as f32
            }
        })
        .collect();
    Ok((data, IntensityMap::stretched(lo, hi)))
}

/// Why [`min_max_normalise`] refused its data: how many of the samples are
/// NaN or infinite.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NonFiniteSamples {
    /// Samples that are NaN or infinite.
    pub count: usize,
    /// All samples.
    pub total: usize,
}

impl std::fmt::Display for NonFiniteSamples {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.total == 0 {
            return write!(f, "no samples");
        }
        write!(
            f,
            "{} of {} samples are not finite numbers (NaN or infinite); replace them \
             (for example with the background's value) before segmenting",
            self.count, self.total
        )
    }
}

/// Compares strings in natural order: runs of ASCII digits compare by
/// numeric value, everything else character by character.
pub(crate) fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (mut a, mut b) = (a.as_bytes(), b.as_bytes());
    loop {
        match (a.first(), b.first()) {
            (None, None) => return Ordering::Equal,
            (None, Some(_)) => return Ordering::Less,
            (Some(_), None) => return Ordering::Greater,
            (Some(x), Some(y)) if x.is_ascii_digit() && y.is_ascii_digit() => {
                let da = a.iter().take_while(|c| c.is_ascii_digit()).count();
                let db = b.iter().take_while(|c| c.is_ascii_digit()).count();
                let (na, nb) = (&a[..da], &b[..db]);
                // Compare numerically without overflow: strip leading zeros,
                // then by length, then lexicographically.
                let strip = |s: &[u8]| {
                    let z = s.iter().take_while(|&&c| c == b'0').count();
                    s[z..].to_vec()
                };
                let (sa, sb) = (strip(na), strip(nb));
                let ord = sa
                    .len()
                    .cmp(&sb.len())
                    .then_with(|| sa.cmp(&sb))
                    .then_with(|| da.cmp(&db));
                if ord != Ordering::Equal {
                    return ord;
                }
                a = &a[da..];
                b = &b[db..];
            }
            (Some(x), Some(y)) => {
                if x != y {
                    return x.cmp(y);
                }
                a = &a[1..];
                b = &b[1..];
            }
        }
    }
}

/// Size of a NIfTI-1 header.
const NIFTI_HDR: usize = 348;

/// Whether the NIfTI-1 file at `path` is a volume (more than one voxel
/// along each of its three axes, or more than one along a fourth), read
/// from its header alone; `None` if the header cannot be read. A folder of
/// images lists its slices for `segment` (one thick along x or y too, whose
/// row then says how to reorient it) and leaves the volumes to `segment3d`
/// without reading them whole.
pub fn nifti_is_volume(path: &Path) -> Option<bool> {
    use std::io::Read;
    let file = std::fs::File::open(path).ok()?;
    let mut header = [0u8; NIFTI_HDR];
    let gz = path.to_string_lossy().to_ascii_lowercase().ends_with(".gz");
    if gz {
        flate2::read::MultiGzDecoder::new(file)
            .read_exact(&mut header)
            .ok()?;
    } else {
        std::io::BufReader::new(file).read_exact(&mut header).ok()?;
    }
    let le = i32::from_le_bytes(header[0..4].try_into().ok()?) == NIFTI_HDR as i32;
    let dim = |k: usize| {
        let a = [header[40 + 2 * k], header[41 + 2 * k]];
        if le {
            i16::from_le_bytes(a)
        } else {
            i16::from_be_bytes(a)
        }
    };
    let rank = dim(0).clamp(0, 7) as usize;
    let thick = |k: usize| k <= rank && dim(k) > 1;
    Some((1..=3).all(thick) || (4..=rank).any(thick))
}

/// The sample type of NIfTI `datatype` (checked by the caller); `scaled`
/// samples (`scl_slope`, `scl_inter`) are real numbers whatever their type.
fn nifti_sample_type(datatype: i16, scaled: bool) -> SampleType {
    match (datatype, scaled) {
        (_, true) | (16 | 64, _) => SampleType::Float,
        (2, false) => SampleType::Uint8,
        (512, false) => SampleType::Uint16,
        _ => SampleType::Int,
    }
}

/// Parses a decompressed single-file NIfTI-1 image.
fn parse_nifti(path: &Path, b: &[u8]) -> Result<Volume> {
    let bad = |reason: String| IoError::MalformedNifti {
        path: path.to_path_buf(),
        reason,
    };
    if b.len() < NIFTI_HDR {
        return Err(bad(format!(
            "file has {} bytes, shorter than the 348-byte header",
            b.len()
        )));
    }
    let le = match (
        i32::from_le_bytes(b[0..4].try_into().expect("4 bytes")),
        i32::from_be_bytes(b[0..4].try_into().expect("4 bytes")),
    ) {
        (348, _) => true,
        (_, 348) => false,
        (540, _) | (_, 540) => {
            return Err(IoError::Unsupported {
                path: path.to_path_buf(),
                reason: "NIfTI-2 (540-byte header) is not supported; save the volume as \
                         NIfTI-1 (e.g. nibabel's Nifti1Image, or FSL's fslchfiletype NIFTI_GZ)"
                    .into(),
            })
        }
        (v, _) => return Err(bad(format!("sizeof_hdr is {v}, expected 348"))),
    };
    let i16_at = |o: usize| {
        let a = [b[o], b[o + 1]];
        if le {
            i16::from_le_bytes(a)
        } else {
            i16::from_be_bytes(a)
        }
    };
    let f32_at = |o: usize| {
        let a = [b[o], b[o + 1], b[o + 2], b[o + 3]];
        if le {
            f32::from_le_bytes(a)
        } else {
            f32::from_be_bytes(a)
        }
    };
    match &b[344..348] {
        b"n+1\0" => {}
        b"ni1\0" => return Err(bad("two-file NIfTI (.hdr/.img) is not supported".into())),
        m => return Err(bad(format!("bad magic {m:?}, expected \"n+1\""))),
    }
    let dim: Vec<i16> = (0..8).map(|i| i16_at(40 + 2 * i)).collect();
    let ndim = dim[0];
    if !(1..=7).contains(&ndim) {
        return Err(bad(format!("dim[0] = {ndim}, expected 1..7")));
    }
    let ndim = ndim as usize;
    let mut n = [1usize; 3];
    for (i, d) in dim[1..=ndim].iter().enumerate() {
        if *d < 0 {
            return Err(bad(format!("dim[{}] = {d} is negative", i + 1)));
        }
        if i < 3 {
            n[i] = *d as usize;
        } else if *d > 1 {
            return Err(IoError::Unsupported {
                path: path.to_path_buf(),
                reason: format!(
                    "{ndim}-D NIfTI with dim[{}] = {d}; only 3-D is supported",
                    i + 1
                ),
            });
        }
    }
    if n.contains(&0) {
        return Err(IoError::empty(path, &n));
    }
    let datatype = i16_at(70);
    let bitpix = i16_at(72);
    let (bytes_per, expected_bitpix) = match datatype {
        2 | 256 => (1, 8),
        4 | 512 => (2, 16),
        8 | 16 | 768 => (4, 32),
        64 => (8, 64),
        t => {
            return Err(IoError::Unsupported {
                path: path.to_path_buf(),
                reason: format!("NIfTI datatype {t}"),
            })
        }
    };
    if bitpix != expected_bitpix {
        return Err(bad(format!(
            "bitpix {bitpix} does not match datatype {datatype}"
        )));
    }
    let vox_offset = f32_at(108);
    if !vox_offset.is_finite() || vox_offset < NIFTI_HDR as f32 || vox_offset.fract() != 0.0 {
        return Err(bad(format!("vox_offset {vox_offset} is invalid")));
    }
    let start = vox_offset as usize;
    let count = n[0]
        .checked_mul(n[1])
        .and_then(|v| v.checked_mul(n[2]))
        .ok_or_else(|| bad("dimensions overflow".into()))?;
    let end = count
        .checked_mul(bytes_per)
        .and_then(|v| v.checked_add(start))
        .ok_or_else(|| bad("dimensions overflow".into()))?;
    if b.len() < end {
        return Err(bad(format!(
            "truncated: {} data bytes expected at offset {start}, file has {}",
            end - start,
            b.len()
        )));
    }
    let raw = &b[start..end];
    let slope = f32_at(112);
    let inter = f32_at(116);
    // NIfTI: scl_slope == 0 means "no scaling".
    let scaled = slope != 0.0 && slope.is_finite() && (slope != 1.0 || inter != 0.0);
    let chunks = raw.chunks_exact(bytes_per);
    let (data, intensity): (Vec<f32>, IntensityMap) = match (datatype, scaled) {
        (2, false) => (
            raw.iter().map(|&s| s as f32 / 255.0).collect(),
            IntensityMap::unsigned(8),
        ),
        (512, false) => (
            chunks
                .map(|c| {
                    let a = [c[0], c[1]];
                    let v = if le {
                        u16::from_le_bytes(a)
                    } else {
                        u16::from_be_bytes(a)
                    };
                    v as f32 / 65535.0
                })
                .collect(),
            IntensityMap::unsigned(16),
        ),
        _ => {
            let values: Vec<f64> = chunks
                .map(|c| {
                    let v = decode_sample(datatype, c, le);
                    if scaled {
                        slope as f64 * v + inter as f64
                    } else {
                        v
                    }
                })
                .collect();
            min_max_normalise(&values).map_err(|samples| IoError::NonFinite {
                path: path.to_path_buf(),
                samples,
            })?
        }
    };
    // Axes beyond `dim[0]` do not exist in the file: unit spacing.
    let sp = |i: usize| {
        let s = f32_at(76 + 4 * i).abs() as f64;
        if i <= ndim && s.is_finite() && s > 0.0 {
            s
        } else {
            1.0
        }
    };
    let (affine, source) = nifti_affine(&f32_at, &i16_at, [sp(1), sp(2), sp(3)]);
    let spacing = std::array::from_fn(|c| {
        let len = (0..3).map(|r| affine[r][c].powi(2)).sum::<f64>().sqrt();
        if len.is_finite() && len > 0.0 {
            len
        } else {
            1.0
        }
    });
    let mut volume = Volume::from_raw(n[0], n[1], n[2], data)
        .with_spacing(spacing)
        .with_unit(nifti_unit(b[123]))
        .with_intensity(intensity)
        .with_sample_type(nifti_sample_type(datatype, scaled))
        .with_affine(affine, source);
    volume.nifti_header = Some(b[..NIFTI_HDR].to_vec());
    Ok(volume)
}

/// The index-to-world affine of a NIfTI-1 header: the sform when its code
/// is set, else the qform (quaternion, offsets, `pixdim` and the `qfac`
/// sign in `pixdim[0]`), else `pixdim` alone (NIfTI's "method 1"). A form
/// that cannot place voxels (a NaN, or axes that collapse: a zero or
/// singular matrix, as some converters write) is passed over for the next;
/// `report.json`'s frame source says which was used.
fn nifti_affine(
    f32_at: &dyn Fn(usize) -> f32,
    i16_at: &dyn Fn(usize) -> i16,
    pixdim: [f64; 3],
) -> (Affine, FrameSource) {
    let f = |o: usize| f64::from(f32_at(o));
    if i16_at(254) > 0 {
        let a: Affine = std::array::from_fn(|r| std::array::from_fn(|c| f(280 + 16 * r + 4 * c)));
        if places_voxels(&a) {
            return (a, FrameSource::NiftiSform);
        }
    }
    if i16_at(252) > 0 {
        let (b, c, d) = (f(256), f(260), f(264));
        let a = (1.0 - (b * b + c * c + d * d)).max(0.0).sqrt();
        let rot = [
            [
                a * a + b * b - c * c - d * d,
                2.0 * (b * c - a * d),
                2.0 * (b * d + a * c),
            ],
            [
                2.0 * (b * c + a * d),
                a * a + c * c - b * b - d * d,
                2.0 * (c * d - a * b),
            ],
            [
                2.0 * (b * d - a * c),
                2.0 * (c * d + a * b),
                a * a + d * d - b * b - c * c,
            ],
        ];
        let qfac = if f(76) < 0.0 { -1.0 } else { 1.0 };
        let scale = [pixdim[0], pixdim[1], pixdim[2] * qfac];
        let offset = [f(268), f(272), f(276)];
        let q: Affine = std::array::from_fn(|r| {
            [
                rot[r][0] * scale[0],
                rot[r][1] * scale[1],
                rot[r][2] * scale[2],
                offset[r],
            ]
        });
        if places_voxels(&q) {
            return (q, FrameSource::NiftiQform);
        }
    }
    let diag: Affine =
        std::array::from_fn(|r| std::array::from_fn(|c| if c == r { pixdim[r] } else { 0.0 }));
    (diag, FrameSource::NiftiPixdim)
}

/// Scales the voxel axes of a NIfTI-1 header by `ratio`, as
/// [`Volume::respaced`] does to the affine: `pixdim[1..=3]` (the qform's
/// scale) and the sform's first three columns, so that a label map written
/// from this header lines up with the respaced volume, not the file's grid.
pub(crate) fn rescale_nifti_axes(header: &mut [u8], ratio: [f64; 3]) {
    let le = i32::from_le_bytes(header[0..4].try_into().expect("4 bytes")) == NIFTI_HDR as i32;
    let mut scale = |o: usize, r: f64| {
        let bytes: [u8; 4] = header[o..o + 4].try_into().expect("4 bytes");
        let v = if le {
            f32::from_le_bytes(bytes)
        } else {
            f32::from_be_bytes(bytes)
        };
        let v = (f64::from(v) * r) as f32;
        header[o..o + 4].copy_from_slice(&if le { v.to_le_bytes() } else { v.to_be_bytes() });
    };
    for (c, &r) in ratio.iter().enumerate() {
        scale(80 + 4 * c, r);
        for row in 0..3 {
            scale(280 + 16 * row + 4 * c, r);
        }
    }
}

/// Whether `a` maps voxels to distinct places: finite, and its three axes
/// span space (the determinant is not negligible against the product of
/// the axes' lengths).
fn places_voxels(a: &Affine) -> bool {
    let column = |c: usize| [a[0][c], a[1][c], a[2][c]];
    let length = |v: [f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let (x, y, z) = (column(0), column(1), column(2));
    let det = x[0] * (y[1] * z[2] - y[2] * z[1]) - y[0] * (x[1] * z[2] - x[2] * z[1])
        + z[0] * (x[1] * y[2] - x[2] * y[1]);
    let scale = length(x) * length(y) * length(z);
    a.iter().flatten().all(|v| v.is_finite()) && scale > 0.0 && det.abs() > 1e-6 * scale
}

/// The spatial unit of `xyzt_units` (unknown is read as mm, as most tools do).
fn nifti_unit(xyzt_units: u8) -> &'static str {
    match xyzt_units & 0x07 {
        1 => "m",
        3 => "um",
        _ => "mm",
    }
}

/// Saves `labels` (x fastest, the input's voxel order) as a NIfTI-1 label
/// map with the geometry of `reference` (a 348-byte NIfTI-1 header, e.g.
/// [`Volume::nifti_header`]): the header is copied, so the shape, axis
/// order, qform/sform codes and affines, units and endianness are the
/// input's, and only the data type (uint8), scaling (none), display range
/// and intent (labels) change. Gzip-compressed if the name ends in `.gz`.
pub fn save_labels_nifti(
    path: impl AsRef<Path>,
    reference: &[u8],
    labels: &[u8],
    phases: usize,
) -> Result<()> {
    let path = path.as_ref();
    if reference.len() != NIFTI_HDR {
        return Err(IoError::invalid(
            path,
            "the reference NIfTI header is not 348 bytes",
        ));
    }
    let le = i32::from_le_bytes(reference[0..4].try_into().expect("4 bytes")) == 348;
    let mut h = reference.to_vec();
    let put16 = |h: &mut Vec<u8>, o: usize, v: i16| {
        h[o..o + 2].copy_from_slice(&if le { v.to_le_bytes() } else { v.to_be_bytes() })
    };
    let put32 = |h: &mut Vec<u8>, o: usize, v: f32| {
        h[o..o + 4].copy_from_slice(&if le { v.to_le_bytes() } else { v.to_be_bytes() })
    };
    put16(&mut h, 68, 1002); // intent: NIFTI_INTENT_LABEL
    put16(&mut h, 70, 2); // uint8
    put16(&mut h, 72, 8);
    put32(&mut h, 108, NIFTI_HDR as f32 + 4.0);
    put32(&mut h, 112, 1.0);
    put32(&mut h, 116, 0.0);
    put32(&mut h, 124, phases.saturating_sub(1) as f32); // cal_max
    put32(&mut h, 128, 0.0); // cal_min
    h.extend_from_slice(&[0; 4]); // no extensions
    h.extend_from_slice(labels);
    write_nifti_bytes(path, &h)
}

/// Decodes one NIfTI sample of `datatype` from its bytes.
/// Whether the file name says NIfTI (`.nii`, `.nii.gz`), as [`Volume::load`] decides.
pub fn is_nifti(path: &Path) -> bool {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    name.ends_with(".nii") || name.ends_with(".nii.gz")
}

/// Writes a whole NIfTI file atomically, gzip-compressed when `path` ends in `.gz`.
fn write_nifti_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    let gz = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"));
    if gz {
        write_atomic(path, |w| {
            let mut enc = flate2::write::GzEncoder::new(w, flate2::Compression::default());
            std::io::Write::write_all(&mut enc, bytes)?;
            enc.finish().map(|_| ())
        })
    } else {
        write_bytes_atomic(path, bytes)
    }
}

fn decode_sample(datatype: i16, c: &[u8], le: bool) -> f64 {
    macro_rules! num {
        ($t:ty) => {{
            let a = c.try_into().expect("sample size");
            (if le {
                <$t>::from_le_bytes(a)
            } else {
                <$t>::from_be_bytes(a)
            }) as f64
        }};
    }
    match datatype {
        2 => c[0] as f64,
        256 => c[0] as i8 as f64,
        4 => num!(i16),
        512 => num!(u16),
        8 => num!(i32),
        768 => num!(u32),
        16 => num!(f32),
        64 => num!(f64),
        _ => unreachable!("datatype checked by the caller"),
    }
}

/// Builds a little-endian single-file NIfTI-1 header (datatype float32).
fn nifti_header_f32(dims: [usize; 3], spacing: [f64; 3], affine: Option<&Affine>) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    let dim: [i16; 8] = [
        3,
        dims[0] as i16,
        dims[1] as i16,
        dims[2] as i16,
        1,
        1,
        1,
        1,
    ];
    for (i, d) in dim.iter().enumerate() {
        h[40 + 2 * i..42 + 2 * i].copy_from_slice(&d.to_le_bytes());
    }
    h[70..72].copy_from_slice(&16i16.to_le_bytes());
    h[72..74].copy_from_slice(&32i16.to_le_bytes());
    let pixdim: [f32; 8] = [
        1.0,
        spacing[0] as f32,
        spacing[1] as f32,
        spacing[2] as f32,
        1.0,
        1.0,
        1.0,
        1.0,
    ];
    for (i, p) in pixdim.iter().enumerate() {
        h[76 + 4 * i..80 + 4 * i].copy_from_slice(&p.to_le_bytes());
    }
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[112..116].copy_from_slice(&1f32.to_le_bytes());
    h[344..348].copy_from_slice(b"n+1\0");
    if let Some(a) = affine {
        h[123] = 2; // millimetres
        h[254..256].copy_from_slice(&2i16.to_le_bytes()); // sform: aligned
        for (r, row) in a.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                let o = 280 + 16 * r + 4 * c;
                h[o..o + 4].copy_from_slice(&(*v as f32).to_le_bytes());
            }
        }
    }
    h
}

/// Saves a volume as a little-endian float32 NIfTI-1 file (gzip-compressed
/// if the name ends in `.gz`), atomically, with the spacing in `pixdim` and
/// the volume's affine, if it has one, as the sform (code 2, millimetres).
/// Intended for inspecting intermediate results in other tools.
pub fn save_nifti(path: impl AsRef<Path>, volume: &Volume) -> Result<()> {
    let path = path.as_ref();
    if volume.dims().iter().any(|&d| d > i16::MAX as usize) {
        return Err(IoError::invalid(
            path,
            "NIfTI-1 dimensions are limited to 32767",
        ));
    }
    let mut bytes = nifti_header_f32(volume.dims(), volume.spacing, volume.affine.as_ref());
    bytes.reserve(4 * volume.data.len());
    for v in &volume.data {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    write_nifti_bytes(path, &bytes)
}

/// Saves `labels` (`dims = [nx, ny, nz]`, x fastest as in [`Volume`]) as a
/// multi-page 8-bit grayscale TIFF with one page per z slice, atomically.
/// Fiji/ImageJ and tifffile open it as a stack. With a `resolution`, every
/// page carries it as Fiji/ImageJ does: pixels per unit in
/// `XResolution`/`YResolution` and `unit=`/`spacing=` in an `ImageJ=`
/// description (read back by [`Volume::load_tiff`] and `vtkTIFFReader`).
///
/// The pixels of all pages are one contiguous block, as ImageJ writes its
/// stacks: ImageJ (and tifffile) read an `ImageJ=` stack of `images=N` as N
/// planes back to back from the first page's data, ignoring the other pages'
/// directories. Every page still points at its own plane, so readers that
/// follow the directories (libtiff, VTK) read the same stack.
pub fn save_labels_tiff(
    path: impl AsRef<Path>,
    dims: [usize; 3],
    labels: &[u8],
    resolution: Option<&Resolution>,
) -> Result<()> {
    let path = path.as_ref();
    let [nx, ny, nz] = dims;
    if labels.len() != nx * ny * nz {
        return Err(IoError::invalid(
            path,
            format!("{} labels for a {nx}x{ny}x{nz} volume", labels.len()),
        ));
    }
    if nx == 0 || ny == 0 || nz == 0 {
        return Err(IoError::invalid(path, "empty volume"));
    }
    let (w, h) = match (u32::try_from(nx), u32::try_from(ny)) {
        (Ok(w), Ok(h)) => (w, h),
        _ => return Err(IoError::invalid(path, "slice too large for TIFF")),
    };
    let mut buf = Cursor::new(Vec::new());
    let enc_err = |e: tiff::TiffError| IoError::write(path, std::io::Error::other(e));
    {
        let mut enc = tiff::encoder::TiffEncoder::new(&mut buf).map_err(enc_err)?;
        let mut first = enc.image_directory().map_err(enc_err)?;
        let start = first.write_data(labels).map_err(enc_err)?;
        let page_bytes = (nx * ny) as u64;
        let page = StackPage {
            width: w,
            height: h,
            resolution,
            slices: nz,
        };
        page.write_tags(&mut first, start).map_err(enc_err)?;
        first.finish().map_err(enc_err)?;
        for z in 1..nz as u64 {
            let mut dir = enc.image_directory().map_err(enc_err)?;
            page.write_tags(&mut dir, start + z * page_bytes)
                .map_err(enc_err)?;
            dir.finish().map_err(enc_err)?;
        }
    }
    write_bytes_atomic(path, buf.get_ref())
}

/// The directory of one page of an 8-bit stack written by [`save_labels_tiff`].
struct StackPage<'a> {
    width: u32,
    height: u32,
    resolution: Option<&'a Resolution>,
    slices: usize,
}

impl StackPage<'_> {
    /// Writes the page's tags: one uncompressed strip of 8-bit gray pixels at
    /// `strip_offset`, and the resolution if there is one.
    fn write_tags<W: std::io::Write + std::io::Seek>(
        &self,
        dir: &mut tiff::encoder::DirectoryEncoder<'_, W, tiff::encoder::TiffKindStandard>,
        strip_offset: u64,
    ) -> tiff::TiffResult<()> {
        use tiff::tags::{PhotometricInterpretation, ResolutionUnit, Tag};
        let offset = u32::try_from(strip_offset).map_err(|_| tiff::TiffError::LimitsExceeded)?;
        dir.write_tag(Tag::ImageWidth, self.width)?;
        dir.write_tag(Tag::ImageLength, self.height)?;
        dir.write_tag(Tag::BitsPerSample, 8u16)?;
        dir.write_tag(Tag::Compression, 1u16)?;
        dir.write_tag(
            Tag::PhotometricInterpretation,
            PhotometricInterpretation::BlackIsZero.to_u16(),
        )?;
        dir.write_tag(Tag::StripOffsets, offset)?;
        dir.write_tag(Tag::SamplesPerPixel, 1u16)?;
        dir.write_tag(Tag::RowsPerStrip, self.height)?;
        let strip_bytes = self
            .width
            .checked_mul(self.height)
            .ok_or(tiff::TiffError::LimitsExceeded)?;
        dir.write_tag(Tag::StripByteCounts, strip_bytes)?;
        match self.resolution {
            Some(r) => {
                dir.write_tag(
                    Tag::ImageDescription,
                    imagej_description(self.slices, r).as_str(),
                )?;
                dir.write_tag(Tag::XResolution, rational(1.0 / r.spacing[0]))?;
                dir.write_tag(Tag::YResolution, rational(1.0 / r.spacing[1]))?;
                dir.write_tag(Tag::ResolutionUnit, ResolutionUnit::None.to_u16())?;
            }
            None => {
                dir.write_tag(Tag::XResolution, rational(1.0))?;
                dir.write_tag(Tag::YResolution, rational(1.0))?;
                dir.write_tag(Tag::ResolutionUnit, ResolutionUnit::None.to_u16())?;
            }
        }
        Ok(())
    }
}

/// Fiji/ImageJ's description of a stack of `nz` slices with this resolution.
fn imagej_description(nz: usize, r: &Resolution) -> String {
    let unit = if r.unit == "um" { "micron" } else { &r.unit };
    format!(
        "ImageJ=1.11a\nimages={nz}\nslices={nz}\nunit={unit}\nspacing={}\nloop=false\n",
        r.spacing[2]
    )
}

/// A positive number as a TIFF rational (about nine significant digits).
fn rational(v: f64) -> tiff::encoder::Rational {
    let d = (1e9 / v.max(1.0)).clamp(1.0, u32::MAX as f64).round() as u32;
    let n = (v * f64::from(d)).round().clamp(1.0, u32::MAX as f64) as u32;
    tiff::encoder::Rational { n, d }
}

/// What a stack refused for its colour pages may be: tifffile writes a
/// grayscale array of 3 or 4 slices, or of 3 or 4 columns, as RGB(A)
/// pages unless told otherwise.
fn colour_stack_hint(colour: tiff::ColorType) -> &'static str {
    match colour {
        tiff::ColorType::RGB(_) | tiff::ColorType::RGBA(_) => {
            " (a grayscale volume of 3 or 4 slices saved by tifffile is stored as colour \
             unless written with photometric='minisblack')"
        }
        _ => "",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Builds a NIfTI-1 file in either endianness with arbitrary raw data.
    fn nifti_bytes(le: bool, dims: &[i16], datatype: i16, bitpix: i16, data: &[u8]) -> Vec<u8> {
        let mut h = vec![0u8; 352];
        let put16 = |h: &mut Vec<u8>, o: usize, v: i16| {
            h[o..o + 2].copy_from_slice(&if le { v.to_le_bytes() } else { v.to_be_bytes() })
        };
        let put32f = |h: &mut Vec<u8>, o: usize, v: f32| {
            h[o..o + 4].copy_from_slice(&if le { v.to_le_bytes() } else { v.to_be_bytes() })
        };
        h[0..4].copy_from_slice(&if le {
            348i32.to_le_bytes()
        } else {
            348i32.to_be_bytes()
        });
        put16(&mut h, 40, dims.len() as i16);
        for (i, d) in dims.iter().enumerate() {
            put16(&mut h, 42 + 2 * i, *d);
        }
        put16(&mut h, 70, datatype);
        put16(&mut h, 72, bitpix);
        put32f(&mut h, 80, 0.5);
        put32f(&mut h, 84, 0.25);
        put32f(&mut h, 88, 2.0);
        put32f(&mut h, 108, 352.0);
        h[344..348].copy_from_slice(b"n+1\0");
        h.extend_from_slice(data);
        h
    }

    #[test]
    fn natural_order() {
        let mut v = vec!["s10.png", "s2.png", "s1.png", "s02.png", "a.png"];
        v.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(v, ["a.png", "s1.png", "s2.png", "s02.png", "s10.png"]);
    }

    #[test]
    fn trilinear_nodes_and_clamp() {
        let v = Volume::from_fn(3, 2, 2, |x, y, z| (x + 10 * y + 100 * z) as f32);
        assert_eq!(v.trilinear(0.5, 0.5, 0.5), 0.0);
        assert_eq!(v.trilinear(2.5, 1.5, 1.5), 112.0);
        assert!((v.trilinear(1.0, 1.0, 1.0) - 55.5).abs() < 1e-4);
        assert_eq!(v.trilinear(-3.0, 9.0, 9.0), 110.0);
    }

    #[test]
    fn nifti_both_endiannesses_and_types() {
        let dir = tempfile::tempdir().unwrap();
        for le in [true, false] {
            // int16 with negative values -> min/max normalised.
            let vals: [i16; 4] = [-100, 0, 100, 300];
            let data: Vec<u8> = vals
                .iter()
                .flat_map(|v| if le { v.to_le_bytes() } else { v.to_be_bytes() })
                .collect();
            let p = dir.path().join(format!("i16_{le}.nii"));
            std::fs::write(&p, nifti_bytes(le, &[2, 2, 1], 4, 16, &data)).unwrap();
            let v = Volume::load(&p).unwrap();
            assert_eq!(v.dims(), [2, 2, 1]);
            assert_eq!(v.data(), &[0.0, 0.25, 0.5, 1.0]);
            assert_eq!(v.spacing(), [0.5, 0.25, 2.0]);

            // uint16 -> divided by 65535.
            let data: Vec<u8> = [0u16, 65535]
                .iter()
                .flat_map(|v| if le { v.to_le_bytes() } else { v.to_be_bytes() })
                .collect();
            let p = dir.path().join(format!("u16_{le}.nii"));
            std::fs::write(&p, nifti_bytes(le, &[1, 1, 2], 512, 16, &data)).unwrap();
            let v = Volume::load(&p).unwrap();
            assert_eq!(v.dims(), [1, 1, 2]);
            assert_eq!(v.data(), &[0.0, 1.0]);
            assert_eq!(v.spacing(), [0.5, 0.25, 2.0]);
        }
        // uint8 and float64, 4-D with a trailing 1.
        let p = dir.path().join("u8.nii");
        std::fs::write(&p, nifti_bytes(true, &[3, 1, 1, 1], 2, 8, &[0, 51, 255])).unwrap();
        assert_eq!(Volume::load(&p).unwrap().data(), &[0.0, 0.2, 1.0]);
        let d: Vec<u8> = [1.0f64, 3.0].iter().flat_map(|v| v.to_le_bytes()).collect();
        let p = dir.path().join("f64.nii");
        std::fs::write(&p, nifti_bytes(true, &[2], 64, 64, &d)).unwrap();
        let v = Volume::load(&p).unwrap();
        assert_eq!(v.data(), &[0.0, 1.0]);
        // pixdim of axes beyond dim[0] is ignored.
        assert_eq!(v.spacing(), [0.5, 1.0, 1.0]);
    }

    #[test]
    fn nifti_roundtrip_gz() {
        let dir = tempfile::tempdir().unwrap();
        let v = Volume::from_fn(4, 3, 2, |x, y, z| (x + 4 * y + 12 * z) as f32 / 23.0)
            .with_spacing([0.5, 1.5, 3.0]);
        for name in ["v.nii", "v.nii.gz"] {
            let p = dir.path().join(name);
            save_nifti(&p, &v).unwrap();
            let w = Volume::load(&p).unwrap();
            assert_eq!(w.dims(), v.dims());
            assert_eq!(w.spacing(), v.spacing());
            for (a, b) in w.data().iter().zip(v.data()) {
                assert!((a - b).abs() < 1e-6);
            }
        }
        let raw = std::fs::read(dir.path().join("v.nii.gz")).unwrap();
        let t = dir.path().join("t.nii.gz");
        std::fs::write(&t, &raw[..raw.len() / 2]).unwrap();
        assert!(matches!(
            Volume::load(&t),
            Err(IoError::MalformedNifti { .. })
        ));
    }

    /// `--spacing` on a NIfTI input: the label map written from the
    /// respaced volume's header has the new voxel size, whether the file
    /// places its voxels by sform or by qform.
    #[test]
    fn a_respaced_nifti_writes_labels_on_the_new_grid() {
        let dir = tempfile::tempdir().unwrap();
        let affine: Affine = [
            [-0.5, 0.0, 0.0, 30.0],
            [0.0, 0.5, 0.0, -12.0],
            [0.0, 0.0, 2.0, 5.0],
        ];
        let v = Volume::from_fn(4, 3, 2, |x, _, _| x as f32 / 3.0)
            .with_spacing([0.5, 0.5, 2.0])
            .with_affine(affine, FrameSource::NiftiSform);
        let p = dir.path().join("v.nii");
        save_nifti(&p, &v).unwrap();
        let mut qform_only = std::fs::read(&p).unwrap();
        qform_only[252..254].copy_from_slice(&1i16.to_le_bytes());
        qform_only[254..256].copy_from_slice(&0i16.to_le_bytes());
        // A half turn about z (quaternion (0, 0, 1)) with qfac -1 (z flipped),
        // offsets as the sform's.
        for (o, q) in [
            (256, 0.0f32),
            (260, 0.0),
            (264, 1.0),
            (268, 30.0),
            (272, -12.0),
            (276, 5.0),
        ] {
            qform_only[o..o + 4].copy_from_slice(&q.to_le_bytes());
        }
        qform_only[76..80].copy_from_slice(&(-1f32).to_le_bytes());
        let q = dir.path().join("q.nii");
        std::fs::write(&q, &qform_only).unwrap();
        for input in [p, q] {
            let respaced = Volume::load(&input).unwrap().respaced([1.0, 1.0, 1.0]);
            let labels = dir.path().join("labels.nii.gz");
            save_labels_nifti(&labels, respaced.nifti_header().unwrap(), &[1; 24], 2).unwrap();
            let written = Volume::load(&labels).unwrap();
            assert_eq!(written.spacing(), [1.0; 3], "{input:?}");
            let (a, b) = (
                written.frame().index_to_world,
                respaced.frame().index_to_world,
            );
            for (ra, rb) in a.iter().zip(&b) {
                for (x, y) in ra.iter().zip(rb) {
                    assert!((x - y).abs() < 1e-5, "{input:?}: {a:?} against {b:?}");
                }
            }
        }
    }

    /// An sform that collapses the axes (all zero, as some converters
    /// write with the code still set) is passed over for `pixdim`.
    #[test]
    fn a_singular_sform_is_passed_over() {
        let dir = tempfile::tempdir().unwrap();
        let v = Volume::from_fn(4, 3, 2, |x, _, _| x as f32 / 3.0)
            .with_spacing([0.5, 0.5, 2.0])
            .with_affine(
                [
                    [0.5, 0.0, 0.0, 1.0],
                    [0.0, 0.5, 0.0, 2.0],
                    [0.0, 0.0, 2.0, 3.0],
                ],
                FrameSource::NiftiSform,
            );
        let p = dir.path().join("v.nii");
        save_nifti(&p, &v).unwrap();
        assert_eq!(
            Volume::load(&p).unwrap().frame().source,
            FrameSource::NiftiSform
        );
        let mut bytes = std::fs::read(&p).unwrap();
        // The third axis collapses onto the first: x and z map to one line.
        for (o, value) in [(288, 0.5f32), (304, 0.0), (320, 0.0)] {
            bytes[o..o + 4].copy_from_slice(&value.to_le_bytes());
        }
        std::fs::write(&p, &bytes).unwrap();
        let frame = Volume::load(&p).unwrap().frame();
        assert_eq!(frame.source, FrameSource::NiftiPixdim);
        assert_eq!(frame.spacing, [0.5, 0.5, 2.0]);
    }

    #[test]
    fn nifti_malformed_headers() {
        let dir = tempfile::tempdir().unwrap();
        let good = nifti_bytes(true, &[2, 2, 2], 2, 8, &[0; 8]);
        let cases: Vec<(&str, Vec<u8>)> = vec![
            ("short", good[..100].to_vec()),
            ("truncated_data", good[..good.len() - 1].to_vec()),
            ("bad_sizeof", {
                let mut b = good.clone();
                b[0] = 0;
                b
            }),
            ("bad_magic", {
                let mut b = good.clone();
                b[344] = b'x';
                b
            }),
            ("bad_bitpix", nifti_bytes(true, &[2, 2, 2], 2, 16, &[0; 8])),
            ("bad_type", nifti_bytes(true, &[2, 2, 2], 1, 1, &[0; 8])),
            ("neg_dim", nifti_bytes(true, &[2, -2, 2], 2, 8, &[0; 8])),
            ("zero_dim", nifti_bytes(true, &[2, 0, 2], 2, 8, &[0; 8])),
            ("four_d", nifti_bytes(true, &[1, 1, 1, 2], 2, 8, &[0; 2])),
            ("bad_offset", {
                let mut b = good.clone();
                b[108..112].copy_from_slice(&10f32.to_le_bytes());
                b
            }),
        ];
        for (name, bytes) in cases {
            let p = dir.path().join(format!("{name}.nii"));
            std::fs::write(&p, bytes).unwrap();
            let e = Volume::load(&p).expect_err(name);
            assert!(e.to_string().contains(name), "{name}: {e}");
        }
    }

    #[test]
    fn tiff_stack_roundtrip_and_types() {
        let dir = tempfile::tempdir().unwrap();
        let labels: Vec<u8> = (0..3 * 2 * 4).map(|i| (i * 10) as u8).collect();
        let p = dir.path().join("labels.tif");
        save_labels_tiff(&p, [3, 2, 4], &labels, None).unwrap();
        let v = Volume::load(&p).unwrap();
        assert_eq!(v.dims(), [3, 2, 4]);
        for (a, b) in v.data().iter().zip(&labels) {
            assert!((a * 255.0 - *b as f32).abs() < 1e-3);
        }

        // 16-bit and float32 stacks, as tifffile/Fiji write them.
        use tiff::encoder::{colortype, TiffEncoder};
        let p16 = dir.path().join("s16.tif");
        let mut enc = TiffEncoder::new(File::create(&p16).unwrap()).unwrap();
        enc.write_image::<colortype::Gray16>(2, 1, &[0, 65535])
            .unwrap();
        enc.write_image::<colortype::Gray16>(2, 1, &[65535, 0])
            .unwrap();
        drop(enc);
        assert_eq!(Volume::load(&p16).unwrap().data(), &[0.0, 1.0, 1.0, 0.0]);
        let pf = dir.path().join("f32.tiff");
        let mut enc = TiffEncoder::new(File::create(&pf).unwrap()).unwrap();
        enc.write_image::<colortype::Gray32Float>(2, 1, &[-1.0, 0.0])
            .unwrap();
        enc.write_image::<colortype::Gray32Float>(2, 1, &[1.0, 3.0])
            .unwrap();
        drop(enc);
        let v = Volume::load(&pf).unwrap();
        assert_eq!(v.dims(), [2, 1, 2]);
        assert_eq!(v.data(), &[0.0, 0.25, 0.5, 1.0]);

        // Mismatched page sizes.
        let pm = dir.path().join("mismatch.tif");
        let mut enc = TiffEncoder::new(File::create(&pm).unwrap()).unwrap();
        enc.write_image::<colortype::Gray8>(2, 1, &[0, 1]).unwrap();
        enc.write_image::<colortype::Gray8>(1, 2, &[0, 1]).unwrap();
        drop(enc);
        assert!(matches!(
            Volume::load(&pm),
            Err(IoError::DimensionMismatch { .. })
        ));
    }

    /// ImageJ reads an `ImageJ=` stack as `images=N` planes back to back
    /// from the first page's strip; every page must also point at its own.
    #[test]
    fn tiff_stack_pixels_are_contiguous_as_imagej_reads_them() {
        use tiff::decoder::Decoder;
        use tiff::tags::Tag;
        let dir = tempfile::tempdir().unwrap();
        let (nx, ny, nz) = (5usize, 3usize, 4usize);
        let labels: Vec<u8> = (0..nx * ny * nz).map(|i| (i % 7) as u8).collect();
        let p = dir.path().join("labels.tif");
        let r = Resolution {
            spacing: [0.5, 0.5, 2.0],
            unit: "um".into(),
        };
        save_labels_tiff(&p, [nx, ny, nz], &labels, Some(&r)).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        let mut decoder = Decoder::new(Cursor::new(&bytes)).unwrap();
        let first = decoder.get_tag_u32(Tag::StripOffsets).unwrap() as usize;
        assert_eq!(&bytes[first..first + labels.len()], &labels[..]);
        for z in 1..nz {
            decoder.next_image().unwrap();
            let offset = decoder.get_tag_u32(Tag::StripOffsets).unwrap() as usize;
            assert_eq!(offset, first + z * nx * ny);
        }
        assert!(!decoder.more_images());
    }

    /// A NaN in a well-formed file is the data's problem, not the file's:
    /// the error says what is wrong with the samples, not "malformed".
    #[test]
    fn non_finite_samples_are_not_called_a_malformed_file() {
        use tiff::encoder::{colortype, TiffEncoder};
        let dir = tempfile::tempdir().unwrap();
        let mut data = vec![1.0f32; 8];
        data[3] = f32::NAN;
        let nii = dir.path().join("nan.nii.gz");
        save_nifti(&nii, &Volume::from_raw(2, 2, 2, data.clone())).unwrap();
        let tif = dir.path().join("nan.tif");
        let mut enc = TiffEncoder::new(File::create(&tif).unwrap()).unwrap();
        for page in data.chunks(4) {
            enc.write_image::<colortype::Gray32Float>(2, 2, page)
                .unwrap();
        }
        drop(enc);
        for p in [nii, tif] {
            let e = Volume::load(&p).unwrap_err();
            assert!(matches!(e, IoError::NonFinite { .. }), "{e}");
            assert!(!e.to_string().contains("malformed"), "{e}");
            assert!(
                e.to_string().contains("1 of 8 samples are not finite"),
                "{e}"
            );
        }
    }

    /// Fiji's hyperstack of 2 channels × 2 slices × 2 frames is 8 pages:
    /// read as one stack it would be a "volume" of interleaved channels.
    #[test]
    fn tiff_hyperstack_is_refused_naming_its_extents() {
        use tiff::encoder::{colortype, TiffEncoder};
        use tiff::tags::Tag;
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("hyper.tif");
        let mut enc = TiffEncoder::new(File::create(&p).unwrap()).unwrap();
        let desc = "ImageJ=1.11a\nimages=8\nchannels=2\nslices=2\nframes=2\nhyperstack=true\n";
        for page in 0..8u8 {
            let mut image = enc.new_image::<colortype::Gray8>(2, 2).unwrap();
            if page == 0 {
                image
                    .encoder()
                    .write_tag(Tag::ImageDescription, desc)
                    .unwrap();
            }
            image.write_data(&[page; 4]).unwrap();
        }
        drop(enc);
        let e = Volume::load(&p).unwrap_err();
        assert!(matches!(e, IoError::NotOneVolume { .. }), "{e}");
        assert!(
            e.to_string()
                .contains("2 channels × 2 slices × 2 time points"),
            "{e}"
        );
        // Channel 1 at time point 1: pages 4 + 1 and 4 + 2 + 1.
        let chosen = Selection {
            channel: Some(1),
            time_point: Some(1),
        };
        let v = Volume::load_tiff_selected(&p, chosen).unwrap();
        assert_eq!((v.dims(), v.selection()), ([2, 2, 2], chosen));
        assert_eq!(v.get(0, 0, 0) * 255.0, 5.0);
        assert_eq!(v.get(1, 1, 1) * 255.0, 7.0);
        let beyond = Selection {
            time_point: Some(2),
            ..chosen
        };
        let e = Volume::load_tiff_selected(&p, beyond).unwrap_err();
        assert!(matches!(e, IoError::NotInFile { .. }), "{e}");
    }

    #[test]
    fn tiff_truncated_and_corrupt() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("ok.tif");
        save_labels_tiff(&p, [8, 8, 3], &[7; 192], None).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        for cut in [0, 4, 8, 100, bytes.len() - 10] {
            let t = dir.path().join(format!("cut{cut}.tif"));
            std::fs::write(&t, &bytes[..cut]).unwrap();
            let e = Volume::load(&t).unwrap_err();
            assert!(e.to_string().contains(&format!("cut{cut}.tif")), "{e}");
        }
        let g = dir.path().join("garbage.tif");
        std::fs::write(&g, b"II*\0garbage garbage garbage").unwrap();
        assert!(Volume::load(&g).is_err());
    }

    #[test]
    fn slice_folder_in_natural_order() {
        let dir = tempfile::tempdir().unwrap();
        for z in [1usize, 2, 10] {
            let p = dir.path().join(format!("slice{z}.png"));
            crate::io::image2::save_gray8_png(&p, 2, 1, &[z as u8, 0]).unwrap();
        }
        std::fs::write(dir.path().join("notes.txt"), b"ignored").unwrap();
        let v = Volume::load(dir.path()).unwrap();
        assert_eq!(v.dims(), [2, 1, 3]);
        let firsts: Vec<f32> = (0..3).map(|z| v.get(0, 0, z) * 255.0).collect();
        assert_eq!(firsts, [1.0, 2.0, 10.0]);

        crate::io::image2::save_gray8_png(dir.path().join("slice11.png"), 1, 1, &[0]).unwrap();
        assert!(matches!(
            Volume::load(dir.path()),
            Err(IoError::DimensionMismatch { .. })
        ));
        let empty = tempfile::tempdir().unwrap();
        assert!(matches!(
            Volume::load(empty.path()),
            Err(IoError::NoSlices { .. })
        ));
        assert!(matches!(
            Volume::load(dir.path().join("x.raw")),
            Err(IoError::UnknownType { .. })
        ));
    }

    /// Cross-check against files written by tifffile and nibabel; see
    /// `.ci/io_fixtures.py` (run with `DSC_SEG_IO_FIXTURES=DIR ... --ignored`).
    #[test]
    #[ignore = "needs fixtures from .ci/io_fixtures.py"]
    fn external_fixtures() {
        let dir = PathBuf::from(
            std::env::var_os("DSC_SEG_IO_FIXTURES").expect("set DSC_SEG_IO_FIXTURES"),
        );
        let manifest: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("manifest.json")).unwrap()).unwrap();
        let manifest = manifest.as_object().unwrap();
        assert!(!manifest.is_empty());
        for (name, want) in manifest {
            let v = Volume::load(dir.join(name)).unwrap_or_else(|e| panic!("{e}"));
            let dims: Vec<usize> = want["dims"]
                .as_array()
                .unwrap()
                .iter()
                .map(|d| d.as_u64().unwrap() as usize)
                .collect();
            assert_eq!(v.dims().to_vec(), dims, "{name}");
            let spacing: Vec<f64> = want["spacing"]
                .as_array()
                .unwrap()
                .iter()
                .map(|d| d.as_f64().unwrap())
                .collect();
            for (a, b) in v.spacing().iter().zip(&spacing) {
                assert!((a - b).abs() < 1e-5, "{name}: spacing {:?}", v.spacing());
            }
            let data = want["data"].as_array().unwrap();
            assert_eq!(data.len(), v.data().len(), "{name}");
            for (i, (a, b)) in v.data().iter().zip(data).enumerate() {
                let b = b.as_f64().unwrap();
                assert!((*a as f64 - b).abs() < 1e-5, "{name}[{i}]: {a} vs {b}");
            }
            println!("ok {name}: {:?} spacing {:?}", v.dims(), v.spacing());
        }
        let (nx, ny, nz) = (5, 4, 3);
        let labels: Vec<u8> = (0..nz)
            .flat_map(|z| {
                (0..ny).flat_map(move |y| (0..nx).map(move |x| ((x + 2 * y + 3 * z) % 256) as u8))
            })
            .collect();
        save_labels_tiff(dir.join("rust_labels.tif"), [nx, ny, nz], &labels, None).unwrap();
        let vol = Volume::from_fn(nx, ny, nz, |x, y, z| (x + 10 * y + 100 * z) as f32 / 1000.0)
            .with_spacing([0.5, 0.75, 2.0]);
        save_nifti(dir.join("rust_volume.nii.gz"), &vol).unwrap();
    }
}
