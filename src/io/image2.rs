//! 2D grayscale images with a continuous-coordinate convention.
//!
//! # Coordinate convention
//!
//! An image of `W × H` pixels covers the continuous domain `[0,W] × [0,H]`.
//! Pixel `(x, y)` (column `x`, row `y`) covers the unit square
//! `[x, x+1) × [y, y+1)` and its value is attached to the pixel centre
//! `(x + 0.5, y + 0.5)`. The `y` axis grows downwards, i.e. it is the row
//! index, exactly as in the file. Mesh vertices, [`Image2::bilinear`] and the
//! figure renderer in [`crate::io::render`] all use this convention, so a mesh
//! whose corners are `(0,0)` and `(W,H)` covers the image exactly.
//!
//! # Intensities
//!
//! Values are `f32`: 8-bit samples are divided by 255, 16-bit samples by
//! 65535 (so both lie in `[0,1]`), and floating-point and signed or 32-bit
//! integer samples (TIFF: Fiji's 32-bit type, CT in Hounsfield units) are kept
//! as they are, negative values included. [`Image2::sample_type`] says which,
//! and [`SampleType::to_original`] maps a value back to the file's units.
//! Colour images are reduced to luminance with the Rec. 709 weights
//! `0.2126 R + 0.7152 G + 0.0722 B`, applied to the stored (gamma-encoded)
//! values; one whose every pixel is gray (a palette of grays, as GIFs and
//! some PNGs store them) is read as the gray image it is. Alpha is not used, and pixels that are not fully opaque are
//! counted ([`Transparency`]) for the run to say so. [`Image2::load_channel`]
//! takes one channel instead; [`Image2::colour`] says which was done.
//!
//! # Orientation
//!
//! A JPEG or TIFF whose EXIF orientation asks for a rotation or a mirror is
//! turned upright on reading, as photo viewers show it, so every output lines
//! up with the picture the user sees (VTK's own readers do not apply EXIF, so
//! in ParaView such an output lines up with the upright picture, not the
//! sensor's rows).

use std::fs::File;
use std::io::{self, BufReader, Write};
use std::path::Path;

use image::{DynamicImage, ImageDecoder, ImageError, ImageFormat, ImageReader, ImageResult};
use serde::Serialize;

use super::atomic::write_atomic;
use super::error::{io_reason, IoError, Result};
use super::frame::Frame;
use super::selection::Selection;

/// Rec. 709 luminance weights for R, G, B.
const REC709: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// How the samples of an image were stored, and the factor that maps the
/// loaded values back to the stored ones.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SampleType {
    /// 8-bit unsigned integers (loaded ÷ 255).
    Uint8,
    /// 16-bit unsigned integers (loaded ÷ 65535).
    Uint16,
    /// Any other integer type (signed or 32/64-bit), kept as is.
    Int,
    /// Floating point, kept as is.
    Float,
}

impl SampleType {
    /// The stored value of a loaded value `v`.
    pub fn to_original(self, v: f64) -> f64 {
        match self {
            SampleType::Uint8 => v * 255.0,
            SampleType::Uint16 => v * 65535.0,
            SampleType::Int | SampleType::Float => v,
        }
    }
}

/// How a loaded image's gray values came from the file's samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Colour {
    /// Grayscale samples (or an array), taken as they are.
    Gray,
    /// Colour samples reduced to their Rec. 709 luminance.
    Luminance,
    /// One channel of the samples (0 = red or gray, 1 = green or alpha of a
    /// gray image, 2 = blue, 3 = alpha).
    Channel(usize),
}

/// A row-major grayscale image (8/16-bit data scaled to `[0,1]`, other
/// types as stored); see the module documentation for the coordinate convention.
#[derive(Clone, Debug, PartialEq)]
pub struct Image2 {
    width: usize,
    height: usize,
    data: Vec<f32>,
    sample_type: SampleType,
    colour: Colour,
    spacing: Option<[f64; 2]>,
    unit: Option<String>,
    placement: Option<Box<Placement>>,
    transparency: Transparency,
    /// The channel and time point of a TIFF's pages this image is (see
    /// [`Image2::selection`]).
    selection: Selection,
}

/// Where a NIfTI slice sits in the world, and its header, the template of
/// its label map.
#[derive(Clone, Debug, PartialEq)]
struct Placement {
    frame: Frame,
    nifti_header: Option<Vec<u8>>,
}

/// The pixels of an image file with an alpha channel that are not fully
/// opaque, when the image is segmented by its colour or gray values.
///
/// Their alpha is not used: the segmentation has no notion of a pixel that
/// is not there, and compositing over a background would invent the values
/// it segments. A transparent pixel's colour values are what the file
/// holds (often the picture under a mask, or black), so it is segmented by
/// them, and the run says so (a `warning:` and `report.json`'s `warnings`)
/// with these counts; `--channel` on the alpha channel segments the alpha
/// itself. Zero counts (no alpha, or every pixel opaque): nothing to say.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Transparency {
    /// Pixels whose alpha is below full opacity.
    pub not_opaque: usize,
    /// Of those, the pixels whose alpha is 0.
    pub transparent: usize,
    /// The index of the alpha channel (`--channel`): 1 gray+alpha, 3 RGBA.
    pub alpha_channel: usize,
}

impl Transparency {
    /// The counts of a decoded image (zero without an alpha channel).
    fn of(img: &DynamicImage) -> Self {
        let alphas: Box<dyn Iterator<Item = f32> + '_> = match img {
            DynamicImage::ImageLumaA8(b) => Box::new(b.pixels().map(|p| p[1] as f32 / 255.0)),
            DynamicImage::ImageLumaA16(b) => Box::new(b.pixels().map(|p| p[1] as f32 / 65535.0)),
            DynamicImage::ImageRgba8(b) => Box::new(b.pixels().map(|p| p[3] as f32 / 255.0)),
            DynamicImage::ImageRgba16(b) => Box::new(b.pixels().map(|p| p[3] as f32 / 65535.0)),
            DynamicImage::ImageRgba32F(b) => Box::new(b.pixels().map(|p| p[3])),
            _ => return Transparency::default(),
        };
        let mut t = Transparency {
            alpha_channel: usize::from(img.color().channel_count()) - 1,
            ..Transparency::default()
        };
        for a in alphas {
            t.not_opaque += usize::from(a < 1.0);
            t.transparent += usize::from(a <= 0.0);
        }
        t
    }

    /// The warning for `count` pixels of `path`, `None` when all are opaque.
    pub fn warning(&self, path: &Path, count: usize) -> Option<String> {
        (self.not_opaque > 0).then(|| {
            format!(
                "{} of the {count} pixels of {} are not fully opaque ({} fully transparent); \
                 the alpha channel is not used, so they are segmented by their {} values \
                 (--channel {} segments the alpha channel itself)",
                self.not_opaque,
                path.display(),
                self.transparent,
                if self.alpha_channel == 1 {
                    "gray"
                } else {
                    "colour"
                },
                self.alpha_channel
            )
        })
    }
}

impl Image2 {
    /// Wraps row-major `data` (`data[y * width + x]`) as an image.
    ///
    /// # Panics
    /// If `data.len() != width * height`: this is a programming error, not
    /// a file problem.
    pub fn from_raw(width: usize, height: usize, data: Vec<f32>) -> Self {
        assert_eq!(
            data.len(),
            width * height,
            "Image2::from_raw: {} values for a {width}x{height} image",
            data.len()
        );
        Image2 {
            width,
            height,
            data,
            sample_type: SampleType::Float,
            colour: Colour::Gray,
            spacing: None,
            unit: None,
            placement: None,
            transparency: Transparency::default(),
            selection: Selection::default(),
        }
    }

    /// Builds an image by evaluating `f(x, y)` at every pixel (column `x`,
    /// row `y`); handy for synthetic test images.
    pub fn from_fn(width: usize, height: usize, mut f: impl FnMut(usize, usize) -> f32) -> Self {
        let mut data = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                data.push(f(x, y));
            }
        }
        Image2 {
            width,
            height,
            data,
            sample_type: SampleType::Float,
            colour: Colour::Gray,
            spacing: None,
            unit: None,
            placement: None,
            transparency: Transparency::default(),
            selection: Selection::default(),
        }
    }

    /// Loads any image the `image` crate decodes (PNG, JPEG, TIFF, GIF, BMP,
    /// PNM), 8 or 16 bit or float, gray or colour, converting it to
    /// luminance as described in the module documentation. Grayscale TIFFs
    /// the `image` crate refuses (32-bit float as Fiji writes them, signed
    /// or 32-bit integers) are read with the `tiff` crate, first page only.
    ///
    /// Corrupt or truncated files give an error, never a panic; so does a
    /// NaN or infinite sample (with the count of such samples), as for volumes.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        Self::decode(path)?.refuse_non_finite(path)
    }

    /// `self`, or the error naming `path` and the count of its samples that
    /// are NaN or infinite.
    fn refuse_non_finite(self, path: &Path) -> Result<Self> {
        let count = self.data.iter().filter(|v| !v.is_finite()).count();
        if count == 0 {
            return Ok(self);
        }
        Err(IoError::NonFinite {
            path: path.to_path_buf(),
            samples: super::volume::NonFiniteSamples {
                count,
                total: self.data.len(),
            },
        })
    }

    /// [`load`](Self::load) without the check of the samples.
    fn decode(path: &Path) -> Result<Self> {
        refuse_empty_file(path)?;
        let reader = ImageReader::open(path)
            .map_err(|e| IoError::unreadable(path, e))?
            .with_guessed_format()
            .map_err(|e| IoError::unreadable(path, e))?;
        let is_tiff = reader.format() == Some(ImageFormat::Tiff);
        match decode_upright(reader) {
            Ok(img) => Self::from_dynamic(path, img),
            Err(ImageError::Unsupported(_)) if is_tiff => Self::load_gray_tiff(path, None),
            Err(e) => Err(image_error(path, e)),
        }
    }

    /// Page `page` (0-based) of a grayscale TIFF, its samples scaled as
    /// [`load`](Self::load) scales them: one plane of a hyperstack (see
    /// [`super::selection`]). A colour page is refused, page 0 too: every
    /// page of a selection is read alike (see
    /// [`super::hyperstack::colour_page`]).
    pub fn load_tiff_page(path: impl AsRef<Path>, page: usize) -> Result<Self> {
        let path = path.as_ref();
        refuse_empty_file(path)?;
        Self::load_gray_tiff(path, Some(page))?.refuse_non_finite(path)
    }

    /// Page `selected` (`None`: the first, read as the whole file) of a
    /// grayscale TIFF of any integer or float sample type; 8/16-bit unsigned
    /// samples are scaled as [`load`](Self::load) scales them, every other
    /// type is kept as stored.
    fn load_gray_tiff(path: &Path, selected: Option<usize>) -> Result<Self> {
        let page = selected.unwrap_or(0);
        use tiff::decoder::{Decoder, DecodingResult as D};
        let bad = |e: tiff::TiffError| IoError::MalformedTiff {
            path: path.to_path_buf(),
            reason: match e {
                tiff::TiffError::IoError(io) => io_reason(&io),
                e => e.to_string(),
            },
        };
        let file = std::fs::File::open(path).map_err(|e| IoError::unreadable(path, e))?;
        let mut dec = Decoder::new(io::BufReader::new(file)).map_err(bad)?;
        if page > 0 {
            dec.seek_to_image(page).map_err(bad)?;
        }
        let (w, h) = dec.dimensions().map_err(bad)?;
        let (width, height) = (w as usize, h as usize);
        if width == 0 || height == 0 {
            return Err(IoError::empty(path, &[width, height]));
        }
        if let Some(colour) = super::hyperstack::colour_page(dec.colortype().map_err(bad)?) {
            let reason = match selected {
                None => format!("TIFF colour type {colour}; expected grayscale"),
                Some(_) => format!(
                    "TIFF colour type {colour}: --channel and --time-point read grayscale \
                     pages only; save it as grayscale first (Fiji: Image › Type › 8-bit)"
                ),
            };
            return Err(IoError::Unsupported {
                path: path.to_path_buf(),
                reason,
            });
        }
        let (data, sample_type): (Vec<f32>, SampleType) = match dec.read_image().map_err(bad)? {
            D::U8(p) => (
                p.iter().map(|&v| v as f32 / 255.0).collect(),
                SampleType::Uint8,
            ),
            D::U16(p) => (
                p.iter().map(|&v| v as f32 / 65535.0).collect(),
                SampleType::Uint16,
            ),
            D::U32(p) => (as_f32(path, p.iter().map(|&v| v as f64))?, SampleType::Int),
            D::U64(p) => (as_f32(path, p.iter().map(|&v| v as f64))?, SampleType::Int),
            D::I8(p) => (p.iter().map(|&v| v as f32).collect(), SampleType::Int),
            D::I16(p) => (p.iter().map(|&v| v as f32).collect(), SampleType::Int),
            D::I32(p) => (as_f32(path, p.iter().map(|&v| v as f64))?, SampleType::Int),
            D::I64(p) => (as_f32(path, p.iter().map(|&v| v as f64))?, SampleType::Int),
            D::F16(p) => (p.iter().map(|v| v.to_f32()).collect(), SampleType::Float),
            D::F32(p) => (p, SampleType::Float),
            D::F64(p) => (as_f32(path, p.iter().copied())?, SampleType::Float),
        };
        if data.len() != width * height {
            return Err(IoError::MalformedTiff {
                path: path.to_path_buf(),
                reason: format!("{} samples for a {width}x{height} page", data.len()),
            });
        }
        Ok(Image2 {
            width,
            height,
            data,
            sample_type,
            colour: Colour::Gray,
            spacing: None,
            unit: None,
            placement: None,
            transparency: Transparency::default(),
            selection: Selection::default(),
        })
    }

    /// Loads channel `channel` of an image file (0..channels: gray or R, G,
    /// B, then alpha), 8/16-bit samples scaled as [`load`](Self::load)
    /// scales them; `None` loads as [`load`](Self::load) does. A channel the
    /// file does not have is an error that says how many it has.
    pub fn load_channel(path: impl AsRef<Path>, channel: Option<usize>) -> Result<Self> {
        let path = path.as_ref();
        let Some(k) = channel else {
            return Self::load(path);
        };
        Self::decode_channel(path, k)?.refuse_non_finite(path)
    }

    /// [`load_channel`](Self::load_channel) of channel `k`, without the
    /// check of the samples.
    fn decode_channel(path: &Path, k: usize) -> Result<Self> {
        refuse_empty_file(path)?;
        let reader = ImageReader::open(path)
            .map_err(|e| IoError::unreadable(path, e))?
            .with_guessed_format()
            .map_err(|e| IoError::unreadable(path, e))?;
        let is_tiff = reader.format() == Some(ImageFormat::Tiff);
        let img = match decode_upright(reader) {
            Ok(img) => img,
            // Grayscale TIFFs of other sample types have their one channel.
            Err(ImageError::Unsupported(_)) if is_tiff && k == 0 => {
                return Ok(Self::load_gray_tiff(path, None)?.with_colour(Colour::Channel(0)))
            }
            Err(e) => return Err(image_error(path, e)),
        };
        let channels = usize::from(img.color().channel_count());
        if k >= channels {
            return Err(IoError::NoChannel {
                path: path.to_path_buf(),
                channel: k,
                channels,
            });
        }
        // As RGBA: a gray image's value is R and its alpha is A.
        let index = if channels <= 2 && k == 1 { 3 } else { k };
        let bits = img.color().bytes_per_pixel() / img.color().channel_count();
        let (width, height) = (img.width() as usize, img.height() as usize);
        let (data, sample_type): (Vec<f32>, SampleType) = match bits {
            1 => (
                img.to_rgba8()
                    .pixels()
                    .map(|p| p[index] as f32 / 255.0)
                    .collect(),
                SampleType::Uint8,
            ),
            2 => (
                img.to_rgba16()
                    .pixels()
                    .map(|p| p[index] as f32 / 65535.0)
                    .collect(),
                SampleType::Uint16,
            ),
            _ => (
                img.to_rgba32f().pixels().map(|p| p[index]).collect(),
                SampleType::Float,
            ),
        };
        if width == 0 || height == 0 {
            return Err(IoError::empty(path, &[width, height]));
        }
        let transparency = match Transparency::of(&img) {
            t if t.alpha_channel == k => Transparency::default(),
            t => t,
        };
        Ok(Image2 {
            width,
            height,
            data,
            sample_type,
            colour: Colour::Channel(k),
            spacing: None,
            unit: None,
            placement: None,
            transparency,
            selection: Selection::default(),
        })
    }

    /// Converts a decoded [`DynamicImage`] (`path` is only used in errors).
    pub(crate) fn from_dynamic(path: &Path, img: DynamicImage) -> Result<Self> {
        let (width, height) = (img.width() as usize, img.height() as usize);
        if width == 0 || height == 0 {
            return Err(IoError::empty(path, &[width, height]));
        }
        // A palette of grays (a GIF, a PNG saved with a palette) decodes as
        // colour: its gray values are taken as they are, not as a luminance.
        let colour = if img.color().has_color() && !is_gray_valued(&img) {
            Colour::Luminance
        } else {
            Colour::Gray
        };
        let lum = |r: f32, g: f32, b: f32| match colour {
            Colour::Luminance => REC709[0] * r + REC709[1] * g + REC709[2] * b,
            _ => r,
        };
        let sample_type = match img.color().bytes_per_pixel() / img.color().channel_count() {
            1 => SampleType::Uint8,
            2 => SampleType::Uint16,
            _ => SampleType::Float,
        };
        let transparency = Transparency::of(&img);
        let data: Vec<f32> = match img {
            DynamicImage::ImageLuma8(b) => b.pixels().map(|p| p[0] as f32 / 255.0).collect(),
            DynamicImage::ImageLumaA8(b) => b.pixels().map(|p| p[0] as f32 / 255.0).collect(),
            DynamicImage::ImageLuma16(b) => b.pixels().map(|p| p[0] as f32 / 65535.0).collect(),
            DynamicImage::ImageLumaA16(b) => b.pixels().map(|p| p[0] as f32 / 65535.0).collect(),
            DynamicImage::ImageRgb8(b) => b
                .pixels()
                .map(|p| lum(p[0] as f32, p[1] as f32, p[2] as f32) / 255.0)
                .collect(),
            DynamicImage::ImageRgba8(b) => b
                .pixels()
                .map(|p| lum(p[0] as f32, p[1] as f32, p[2] as f32) / 255.0)
                .collect(),
            DynamicImage::ImageRgb16(b) => b
                .pixels()
                .map(|p| lum(p[0] as f32, p[1] as f32, p[2] as f32) / 65535.0)
                .collect(),
            DynamicImage::ImageRgba16(b) => b
                .pixels()
                .map(|p| lum(p[0] as f32, p[1] as f32, p[2] as f32) / 65535.0)
                .collect(),
            DynamicImage::ImageRgb32F(b) => b.pixels().map(|p| lum(p[0], p[1], p[2])).collect(),
            DynamicImage::ImageRgba32F(b) => b.pixels().map(|p| lum(p[0], p[1], p[2])).collect(),
            other => {
                return Err(IoError::Unsupported {
                    path: path.to_path_buf(),
                    reason: format!("pixel type {:?}", other.color()),
                })
            }
        };
        Ok(Image2 {
            width,
            height,
            data,
            sample_type,
            colour,
            spacing: None,
            unit: None,
            placement: None,
            transparency,
            selection: Selection::default(),
        })
    }

    /// How the samples were stored ([`SampleType::Float`] for images built in memory).
    pub fn sample_type(&self) -> SampleType {
        self.sample_type
    }

    /// How the gray values came from the file's samples.
    pub fn colour(&self) -> Colour {
        self.colour
    }

    /// The pixel size given for the image (x, y), overriding the file's;
    /// `None` keeps the file's (see `io::resolution`).
    pub fn spacing(&self) -> Option<[f64; 2]> {
        self.spacing
    }

    /// The image with the given pixel size (see [`Image2::spacing`]).
    pub fn with_spacing(mut self, spacing: Option<[f64; 2]>) -> Self {
        self.spacing = spacing;
        self
    }

    /// The length unit given for the image's pixel size, overriding the
    /// file's (an array's, which has none); `None` keeps the file's, or
    /// `"unit"` for a size given to an image without one.
    pub fn unit(&self) -> Option<&str> {
        self.unit.as_deref()
    }

    /// The image with the given length unit (see [`Image2::unit`]).
    pub fn with_unit(mut self, unit: Option<String>) -> Self {
        self.unit = unit;
        self
    }

    /// The file's pixels that are not fully opaque (see [`Transparency`]).
    pub fn transparency(&self) -> Transparency {
        self.transparency
    }

    /// Where the file places the image in the world, when its reader knows
    /// it beyond the pixel size (a NIfTI slice's affine); `None`: the
    /// frame follows from the file's format (see `io::resolution`).
    pub fn placement(&self) -> Option<&Frame> {
        self.placement.as_deref().map(|p| &p.frame)
    }

    /// The header of the NIfTI file the image is the slice of: its label
    /// map is written with it, so that it overlays the input.
    pub fn nifti_header(&self) -> Option<&[u8]> {
        self.placement.as_deref()?.nifti_header.as_deref()
    }

    /// The image placed in the world by `frame` (see [`Image2::placement`]),
    /// the slice of the NIfTI file with `nifti_header`, if any.
    pub fn with_placement(mut self, frame: Frame, nifti_header: Option<&[u8]>) -> Self {
        self.placement = Some(Box::new(Placement {
            frame,
            nifti_header: nifti_header.map(<[u8]>::to_vec),
        }));
        self
    }

    /// The channel and time point of a multi-channel or time-lapse TIFF
    /// this image is, as chosen (empty: not chosen).
    pub fn selection(&self) -> Selection {
        self.selection
    }

    /// The image marked as `selection` of its file's pages.
    pub fn with_selection(mut self, selection: Selection) -> Self {
        self.selection = selection;
        self
    }

    /// The image with its [`Colour`] set to `colour`.
    pub fn with_colour(mut self, colour: Colour) -> Self {
        self.colour = colour;
        self
    }

    /// The image with its sample type set (e.g. for data loaded elsewhere).
    pub fn with_sample_type(mut self, sample_type: SampleType) -> Self {
        self.sample_type = sample_type;
        self
    }

    /// Number of columns `W`.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Number of rows `H`.
    pub fn height(&self) -> usize {
        self.height
    }

    /// `(width, height)`.
    pub fn dims(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The row-major pixel values, `data[y * width + x]`.
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// Mutable access to the row-major pixel values.
    pub fn data_mut(&mut self) -> &mut [f32] {
        &mut self.data
    }

    /// Consumes the image and returns its row-major pixel values.
    pub fn into_data(self) -> Vec<f32> {
        self.data
    }

    /// The value of pixel (column `x`, row `y`).
    ///
    /// # Panics
    /// If the pixel is outside the image.
    pub fn get(&self, x: usize, y: usize) -> f32 {
        assert!(x < self.width && y < self.height, "pixel ({x},{y}) outside");
        self.data[y * self.width + x]
    }

    /// Bilinear interpolation at the continuous point `(x, y)`, with pixel
    /// centres `(i + 0.5, j + 0.5)` as nodes. Outside the centre grid (the
    /// outer half pixel and beyond) the coordinates are clamped, so the value
    /// is constant along the border normal; non-finite inputs are clamped too.
    pub fn bilinear(&self, x: f64, y: f64) -> f32 {
        let (i0, i1, tx) = lerp_nodes(x, self.width);
        let (j0, j1, ty) = lerp_nodes(y, self.height);
        let w = self.width;
        let d = &self.data;
        let top = d[j0 * w + i0] * (1.0 - tx) + d[j0 * w + i1] * tx;
        let bot = d[j1 * w + i0] * (1.0 - tx) + d[j1 * w + i1] * tx;
        top * (1.0 - ty) + bot * ty
    }

    /// Saves the image as an 8-bit grayscale PNG (values clamped to `[0,1]`
    /// and rounded), atomically.
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<()> {
        save_image_png(path, self)
    }
}

/// For a continuous coordinate `c` on an axis of `n` pixels, returns the two
/// neighbouring pixel-centre indices and the interpolation weight of the
/// second, with clamping at the border. Shared with [`crate::io::volume`].
pub(crate) fn lerp_nodes(c: f64, n: usize) -> (usize, usize, f32) {
    debug_assert!(n > 0);
    let max = (n - 1) as f64;
    // `f64::clamp` propagates NaN; map it to the first node instead.
    let u = if c.is_nan() {
        0.0
    } else {
        (c - 0.5).clamp(0.0, max)
    };
    let i0 = u.floor() as usize;
    let i1 = (i0 + 1).min(n - 1);
    (i0, i1, (u - i0 as f64) as f32)
}

/// An error naming `path` if it is a file of 0 bytes (an interrupted copy
/// or download), which the decoders would only call truncated.
pub(crate) fn refuse_empty_file(path: &Path) -> Result<()> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() && m.len() == 0 => Err(IoError::NotAnImage {
            path: path.to_path_buf(),
            reason: "the file is empty (0 bytes)".into(),
        }),
        _ => Ok(()),
    }
}

/// Whether every pixel of a colour image has equal red, green and blue
/// values (a gray image stored with a palette or as RGB).
fn is_gray_valued(img: &DynamicImage) -> bool {
    fn equal<T: PartialEq>(p: &[T]) -> bool {
        p[0] == p[1] && p[1] == p[2]
    }
    match img {
        DynamicImage::ImageRgb8(b) => b.pixels().all(|p| equal(&p.0)),
        DynamicImage::ImageRgba8(b) => b.pixels().all(|p| equal(&p.0)),
        DynamicImage::ImageRgb16(b) => b.pixels().all(|p| equal(&p.0)),
        DynamicImage::ImageRgba16(b) => b.pixels().all(|p| equal(&p.0)),
        DynamicImage::ImageRgb32F(b) => b.pixels().all(|p| equal(&p.0)),
        DynamicImage::ImageRgba32F(b) => b.pixels().all(|p| equal(&p.0)),
        _ => false,
    }
}

/// Decodes an image the way viewers show it: a JPEG or TIFF photograph
/// whose EXIF orientation says "rotate" or "mirror" (every phone camera
/// held upright writes one) is turned upright, so the labels and the
/// overlay line up with the picture the user sees rather than with the
/// sensor's rows.
fn decode_upright(reader: ImageReader<BufReader<File>>) -> ImageResult<DynamicImage> {
    let mut decoder = reader.into_decoder()?;
    let orientation = decoder.orientation()?;
    let mut image = DynamicImage::from_decoder(decoder)?;
    image.apply_orientation(orientation);
    Ok(image)
}

/// Maps an `image` crate error to an [`IoError`] naming `path`.
pub(crate) fn image_error(path: &Path, e: ImageError) -> IoError {
    match e {
        ImageError::Unsupported(u) => IoError::Unsupported {
            path: path.to_path_buf(),
            reason: u.to_string(),
        },
        ImageError::IoError(io) if io.kind() != io::ErrorKind::UnexpectedEof => {
            IoError::unreadable(path, io)
        }
        ImageError::IoError(io) => IoError::NotAnImage {
            path: path.to_path_buf(),
            reason: io_reason(&io),
        },
        other => IoError::NotAnImage {
            path: path.to_path_buf(),
            reason: other.to_string(),
        },
    }
}

/// The largest rounding to `f32` that a 2D image's samples may take, as a
/// fraction of their range: a thousandth, finer than any phase contrast
/// worth segmenting and far coarser than `f32`'s own 2⁻²⁴ of the magnitude
/// on ordinary data.
const MAX_F32_ROUNDING: f64 = 1e-3;

/// Samples of a wider type (32/64-bit integers, 64-bit floats) as the
/// `f32`s an image keeps, in the file's own values. Refused, with the reason,
/// when rounding them to `f32` moves a sample by more than a thousandth of
/// their range (`MAX_F32_ROUNDING`), as it does for values far from zero that
/// vary little (a 32-bit count offset by 2²⁶, a 64-bit float of 1 ± 10⁻⁶):
/// the image would be segmented, and its range and phase means
/// reported, as a coarser (or even constant) image than the file or array
/// holds. Non-finite samples are left to the check that names them.
pub fn wide_samples_as_f32(
    samples: impl Iterator<Item = f64> + Clone,
) -> std::result::Result<Vec<f32>, String> {
    let finite = samples.clone().filter(|v| v.is_finite());
    let (lo, hi) = finite
        .clone()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    let rounding = finite
        .map(|v| (v - v as f32 as f64).abs())
        .fold(0.0, f64::max);
    if hi > lo && rounding > MAX_F32_ROUNDING * (hi - lo) {
        return Err(format!(
            "its samples ({lo} to {hi}) need more precision than the 32-bit floats an \
             image is segmented in keep at their magnitude (rounding moves them by up \
             to {rounding}, {:.2} % of their range); subtract an offset such as the \
             minimum first",
            100.0 * rounding / (hi - lo)
        ));
    }
    Ok(samples.map(|v| v as f32).collect())
}

/// [`wide_samples_as_f32`] of a file's samples, refused as an unsupported
/// image naming `path`.
fn as_f32(path: &Path, samples: impl Iterator<Item = f64> + Clone) -> Result<Vec<f32>> {
    wide_samples_as_f32(samples).map_err(|reason| IoError::Unsupported {
        path: path.to_path_buf(),
        reason,
    })
}

/// Saves `pixels` (row-major, `width * height` bytes) as an 8-bit grayscale
/// PNG, atomically (see [`crate::io::write_atomic`]).
pub fn save_gray8_png(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    pixels: &[u8],
) -> Result<()> {
    let path = path.as_ref();
    check_gray8_size(path, (width, height), pixels)?;
    encode_png_atomic(path, width, height, pixels, image::ExtendedColorType::L8)
}

/// Refuses `pixels` that are not one byte per pixel of a `width × height`
/// image, naming the file it was to be written to.
fn check_gray8_size(path: &Path, (width, height): (usize, usize), pixels: &[u8]) -> Result<()> {
    if pixels.len() == width * height {
        return Ok(());
    }
    Err(IoError::invalid(
        path,
        format!("{} bytes for a {width}x{height} image", pixels.len()),
    ))
}

/// [`save_gray8_png`] with the pixel size `spacing_mm` (x, y, millimetres)
/// in the PNG's `pHYs` chunk (pixels per metre, rounded), as the input image
/// had it, so that viewers and [`image_frame`](super::resolution::image_frame)
/// read the labels at the input's scale.
pub fn save_gray8_png_with_pixel_size(
    path: impl AsRef<Path>,
    (width, height): (usize, usize),
    pixels: &[u8],
    spacing_mm: [f64; 2],
) -> Result<()> {
    let path = path.as_ref();
    check_gray8_size(path, (width, height), pixels)?;
    let (w, h) = match (u32::try_from(width), u32::try_from(height)) {
        (Ok(w), Ok(h)) => (w, h),
        _ => return Err(IoError::invalid(path, "image too large for PNG")),
    };
    let per_metre = |mm: f64| (1000.0 / mm).round().clamp(1.0, f64::from(u32::MAX)) as u32;
    write_atomic(path, |out: &mut dyn Write| {
        let mut encoder = png::Encoder::new(out, w, h);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_pixel_dims(Some(png::PixelDimensions {
            xppu: per_metre(spacing_mm[0]),
            yppu: per_metre(spacing_mm[1]),
            unit: png::Unit::Meter,
        }));
        let mut writer = encoder.write_header().map_err(io::Error::other)?;
        writer.write_image_data(pixels).map_err(io::Error::other)?;
        writer.finish().map_err(io::Error::other)
    })
}

/// Saves an [`Image2`] as an 8-bit grayscale PNG (values clamped to `[0,1]`,
/// scaled by 255 and rounded), atomically.
pub fn save_image_png(path: impl AsRef<Path>, image: &Image2) -> Result<()> {
    let bytes: Vec<u8> = image.data.iter().map(|&v| unit_to_u8(v)).collect();
    save_gray8_png(path, image.width, image.height, &bytes)
}

/// Converts a `[0,1]` intensity to a byte (clamped, rounded; NaN maps to 0).
pub(crate) fn unit_to_u8(v: f32) -> u8 {
    if v.is_nan() {
        0
    } else {
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    }
}

/// PNG-encodes raw pixel bytes of the given colour type into `path`
/// atomically.
pub(crate) fn encode_png_atomic(
    path: &Path,
    width: usize,
    height: usize,
    pixels: &[u8],
    color: image::ExtendedColorType,
) -> Result<()> {
    use image::ImageEncoder;
    let (w, h) = match (u32::try_from(width), u32::try_from(height)) {
        (Ok(w), Ok(h)) => (w, h),
        _ => return Err(IoError::invalid(path, "image too large for PNG")),
    };
    write_atomic(path, |out: &mut dyn Write| {
        image::codecs::png::PngEncoder::new(out)
            .write_image(pixels, w, h, color)
            .map_err(io::Error::other)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> Image2 {
        Image2::from_fn(4, 3, |x, y| (x + 10 * y) as f32)
    }

    #[test]
    fn bilinear_hits_pixel_centres_and_interpolates() {
        let im = ramp();
        assert_eq!(im.bilinear(0.5, 0.5), 0.0);
        assert_eq!(im.bilinear(3.5, 2.5), 23.0);
        assert!((im.bilinear(1.0, 0.5) - 0.5).abs() < 1e-6);
        assert!((im.bilinear(2.0, 1.0) - 6.5).abs() < 1e-6);
        // Clamped at and beyond the border.
        assert_eq!(im.bilinear(0.0, 0.0), 0.0);
        assert_eq!(im.bilinear(-5.0, 100.0), 20.0);
        assert_eq!(im.bilinear(4.0, 3.0), 23.0);
        assert_eq!(im.bilinear(f64::NAN, 0.5), 0.0);
    }

    /// A big-endian EXIF block with one entry: Orientation (tag 0x0112) = `value`.
    fn exif_orientation(value: u16) -> Vec<u8> {
        let mut exif = b"MM\0\x2a\0\0\0\x08\0\x01\x01\x12\0\x03\0\0\0\x01".to_vec();
        exif.extend_from_slice(&value.to_be_bytes());
        exif.extend_from_slice(&[0, 0, 0, 0, 0, 0]);
        exif
    }

    #[test]
    fn jpeg_exif_orientation_is_applied() {
        use image::ImageEncoder;
        let dir = tempfile::tempdir().unwrap();
        // 16 × 8 sensor rows: the left half dark, the right half bright.
        let pixels: Vec<u8> = (0..8 * 16)
            .map(|i| if i % 16 < 8 { 0 } else { 255 })
            .collect();
        let save = |name: &str, orientation: Option<u16>| {
            let path = dir.path().join(name);
            let mut bytes = Vec::new();
            let mut encoder = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 100);
            if let Some(value) = orientation {
                encoder.set_exif_metadata(exif_orientation(value)).unwrap();
            }
            encoder
                .write_image(&pixels, 16, 8, image::ExtendedColorType::L8)
                .unwrap();
            std::fs::write(&path, bytes).unwrap();
            path
        };
        let plain = Image2::load(save("plain.jpg", None)).unwrap();
        assert_eq!(plain.dims(), (16, 8));
        assert!(plain.get(2, 4) < 0.1 && plain.get(13, 4) > 0.9);
        // 6: the camera was turned, the picture is the sensor rotated 90°
        // clockwise: 8 wide, 16 high, the bright half at the bottom.
        let turned = Image2::load(save("turned.jpg", Some(6))).unwrap();
        assert_eq!(turned.dims(), (8, 16));
        assert!(turned.get(4, 2) < 0.1 && turned.get(4, 13) > 0.9);
        let channel = Image2::load_channel(save("turned_c.jpg", Some(6)), Some(0)).unwrap();
        assert_eq!(channel.dims(), (8, 16));
        // 3: upside down, the bright half on the left.
        let upside_down = Image2::load(save("half.jpg", Some(3))).unwrap();
        assert_eq!(upside_down.dims(), (16, 8));
        assert!(upside_down.get(2, 4) > 0.9 && upside_down.get(13, 4) < 0.1);
    }

    #[test]
    fn png_roundtrip_8_and_16_bit_and_colour() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("g8.png");
        save_gray8_png(&p, 3, 2, &[0, 51, 255, 102, 153, 204]).unwrap();
        let im = Image2::load(&p).unwrap();
        assert_eq!(im.dims(), (3, 2));
        assert!((im.get(1, 0) - 0.2).abs() < 1e-6);
        assert_eq!(im.get(2, 0), 1.0);
        assert!((im.get(2, 1) - 0.8).abs() < 1e-6);

        let p16 = dir.path().join("g16.png");
        image::ImageBuffer::<image::Luma<u16>, _>::from_raw(2, 1, vec![0u16, 65535])
            .unwrap()
            .save(&p16)
            .unwrap();
        let im = Image2::load(&p16).unwrap();
        assert_eq!(im.data(), &[0.0, 1.0]);

        let prgb = dir.path().join("rgb.png");
        image::RgbImage::from_raw(2, 1, vec![255, 0, 0, 0, 255, 0])
            .unwrap()
            .save(&prgb)
            .unwrap();
        let im = Image2::load(&prgb).unwrap();
        assert!((im.get(0, 0) - 0.2126).abs() < 1e-6);
        assert!((im.get(1, 0) - 0.7152).abs() < 1e-6);
    }

    #[test]
    fn truncated_and_garbage_files_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("ok.png");
        let im = Image2::from_fn(32, 32, |x, y| ((x * y) % 7) as f32 / 7.0);
        im.save_png(&p).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        for cut in [0, 8, 20, 40, bytes.len() / 2, bytes.len() - 5] {
            let t = dir.path().join(format!("cut{cut}.png"));
            std::fs::write(&t, &bytes[..cut]).unwrap();
            let e = Image2::load(&t).unwrap_err();
            assert!(e.to_string().contains(&format!("cut{cut}.png")), "{e}");
        }
        let g = dir.path().join("garbage.png");
        std::fs::write(&g, b"this is not an image at all").unwrap();
        assert!(Image2::load(&g).is_err());
        let missing = Image2::load(dir.path().join("missing.png")).unwrap_err();
        assert!(matches!(missing, IoError::Unreadable { .. }));
    }

    /// A 32-bit integer or 64-bit float TIFF whose samples `f32` cannot
    /// tell apart at their magnitude is refused with the figures and what to
    /// do; the same variation nearer zero, or a wide range at that
    /// magnitude, is read exactly as stored.
    #[test]
    fn wide_samples_that_f32_would_coarsen_are_refused() {
        use tiff::encoder::{colortype, TiffEncoder};
        let dir = tempfile::tempdir().unwrap();
        let tiff = |name: &str| dir.path().join(name);
        let write_u32 = |name: &str, data: &[u32]| {
            TiffEncoder::new(std::fs::File::create(tiff(name)).unwrap())
                .unwrap()
                .write_image::<colortype::Gray32>(4, 4, data)
                .unwrap();
        };
        let write_f64 = |name: &str, data: &[f64]| {
            TiffEncoder::new(std::fs::File::create(tiff(name)).unwrap())
                .unwrap()
                .write_image::<colortype::Gray64Float>(4, 4, data)
                .unwrap();
        };
        let counts: Vec<u32> = (0..16).map(|i| i * 16).collect();
        let offset: Vec<u32> = counts.iter().map(|c| c + (1 << 26) + 1).collect();
        write_u32("offset.tif", &offset);
        let e = Image2::load(tiff("offset.tif")).unwrap_err().to_string();
        assert!(
            e.contains("more precision") && e.contains("67108865"),
            "{e}"
        );
        write_u32("near_zero.tif", &counts);
        let img = Image2::load(tiff("near_zero.tif")).unwrap();
        assert_eq!(img.data[15], 240.0);
        let wide: Vec<u32> = (0..16).map(|i| i * (1 << 27) + 1).collect();
        write_u32("wide.tif", &wide);
        assert!(Image2::load(tiff("wide.tif")).is_ok());
        let almost_one: Vec<f64> = (0..16).map(|i| 1.0 + i as f64 * 1e-9).collect();
        write_f64("almost_one.tif", &almost_one);
        let e = Image2::load(tiff("almost_one.tif"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("more precision"), "{e}");
        let ordinary: Vec<f64> = (0..16).map(|i| i as f64 * 0.1 - 0.5).collect();
        write_f64("ordinary.tif", &ordinary);
        assert!(Image2::load(tiff("ordinary.tif")).is_ok());
    }

    #[test]
    fn save_checks_length() {
        let dir = tempfile::tempdir().unwrap();
        assert!(save_gray8_png(dir.path().join("x.png"), 2, 2, &[0; 3]).is_err());
    }
}
