//! The 2D job: an image file (PNG, TIFF, JPEG, ...) or a built-in phantom,
//! segmented with the triangle DSC into `labels.png`, overlays, `mesh.vtu`
//! and `report.json`.

use super::input_summary::{with_file_values, InputSummary};
use super::{
    add_frame_and_phases, check_phantom, check_result, clamp_input, labels_of_samples, mean_dice,
    run_with_progress, ClampedInput, GroundTruth, Job, JobTimes, Provenance, RunReport, Source,
};
use crate::dim::D2;
use crate::error::{Error, Result};
use crate::io::intensity::IntensityMap;
use crate::io::ome::OmeLayout;
use crate::io::resolution::{image_frame_and_warnings, is_tiff};
use crate::io::selection::{Selection, TiffPages};
use crate::io::{save_gray8_png, Colour, Frame, Image2, IoError, Overlay, Volume};
use crate::phantom::{self, Phantom2Kind};
use crate::segment::auto::{choose_phases, PhaseChoice};
use crate::segment::measurements::Measurements;
use crate::segment::{ImageView, Init, SegmentParams, SegmentReport, Segmentation};
use crate::segmented::{Outputs, Render, Segmented};
use crate::staging::Staging;
use serde::Serialize;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A segmentation job.
#[derive(Clone, Debug)]
pub struct SegmentJob {
    /// The input.
    pub source: Source,
    /// The output directory (created if missing).
    pub out: PathBuf,
    /// Segmentation parameters. For `Init::Labels` the labels are loaded from
    /// [`SegmentJob::init_labels`].
    pub params: SegmentParams,
    /// Label image for `Init::Labels`.
    pub init_labels: Option<PathBuf>,
    /// The files to write.
    pub outputs: Outputs,
    /// No progress bar.
    pub quiet: bool,
    /// Segment this channel of a multi-channel TIFF (an ImageJ hyperstack
    /// or OME-TIFF of several channels), or of a colour image instead of
    /// its luminance (see [`load_image_selected`]).
    pub channel: Option<usize>,
    /// Segment this time point of a time-lapse TIFF (see
    /// [`load_image_selected`]).
    pub time_point: Option<usize>,
    /// Pixel size (x, y) to use instead of the file's.
    pub spacing: Option<[f64; 2]>,
}

/// The 2D report: the shared fields, the image size and the input's units.
#[derive(Serialize)]
struct Report<'a> {
    #[serde(flatten)]
    run: RunReport<'a>,
    width: usize,
    height: usize,
    input: InputSummary,
    /// The trials of `--phases auto`.
    phase_choice: Option<PhaseChoice>,
}

/// The image's values in the file's units (8/16-bit integers as stored,
/// floats as they are), the units of `report.json`'s means.
fn in_file_units(image: &Image2) -> Vec<f32> {
    let t = image.sample_type();
    image
        .data()
        .iter()
        .map(|&v| t.to_original(f64::from(v)) as f32)
        .collect()
}

/// The image as the overlay shows it: values outside `[0,1]` (float or
/// signed data) mapped linearly onto `[0,1]`, other images unchanged.
fn display_image<'i>(image: &'i Image2, report: &SegmentReport) -> std::borrow::Cow<'i, Image2> {
    let (lo, hi) = (report.intensity.min, report.intensity.max);
    if lo >= 0.0 && hi <= 1.0 || hi <= lo {
        return std::borrow::Cow::Borrowed(image);
    }
    let data = image
        .data()
        .iter()
        .map(|&v| ((v as f64 - lo) / (hi - lo)) as f32)
        .collect();
    std::borrow::Cow::Owned(Image2::from_raw(image.width(), image.height(), data))
}

/// The final mesh as the overlay and VTK writers want it: 2D points,
/// triangles, and each triangle's phase ranked by increasing mean.
fn overlay_arrays(seg: &Segmentation<'_, D2>) -> (Vec<[f64; 2]>, Vec<[u32; 3]>, Vec<u32>) {
    let order = seg.phase_order();
    let arrays = seg.complex().to_arrays();
    let phase = arrays
        .labels
        .iter()
        .map(|&l| order[(l as usize).min(order.len() - 1)] as u32)
        .collect();
    (arrays.points_2d(), arrays.triangles(), phase)
}

/// Sides of the 2D phantoms.
const PHANTOM2_SIZES: RangeInclusive<usize> = 8..=8192;

/// The 2D phantom `name`, once its name, side and noise are checked.
pub(crate) fn phantom2(name: &str, size: usize, noise: f64) -> Result<Phantom2Kind> {
    let kind = Phantom2Kind::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Phantom2Kind::ALL.iter().map(|k| k.name()).collect();
        Error::Usage(format!(
            "unknown phantom {name:?} (one of {})",
            names.join(", ")
        ))
    })?;
    check_phantom("phantom", size, noise, PHANTOM2_SIZES)?;
    Ok(kind)
}

/// Loads a label image: each pixel's value as the file stores it is its
/// phase (8 or 16 bits, or whole-numbered floats). A colour image is
/// refused: its luminance would be read as labels that no one painted.
fn load_labels(path: &Path, width: usize, height: usize, phases: usize) -> Result<Vec<u8>> {
    let img = Image2::load(path)?;
    if img.colour() == Colour::Luminance {
        return Err(Error::Usage(format!(
            "init labels {} are a colour image; give a grayscale image whose values are the \
             phases 0..N-1",
            path.display()
        )));
    }
    if img.width() != width || img.height() != height {
        return Err(Error::Usage(format!(
            "init labels {} are {}×{} but the image is {}×{}",
            path.display(),
            img.width(),
            img.height(),
            width,
            height
        )));
    }
    let sample_type = img.sample_type();
    let map = IntensityMap::of_sample_type(sample_type);
    let stored = img
        .data()
        .iter()
        .map(|&v| map.original_sample(f64::from(v), sample_type));
    labels_of_samples(stored, phases, path)
}

/// Writes a PNG of the segmentation's current mesh over `image` (the image
/// it segments): interfaces in the phase colours, cells ordered by phase
/// mean as in [`Segmentation::label_image`]. For examples and frame recording.
pub fn save_overlay_png(
    seg: &Segmentation<'_, D2>,
    image: &Image2,
    draw_mesh: bool,
    path: impl AsRef<Path>,
) -> Result<()> {
    let (points, tris, phase) = overlay_arrays(seg);
    Overlay::new(image, &points, &tris, &phase)
        .with_mesh(draw_mesh)
        .to_png(path)?;
    Ok(())
}

/// Loads (or generates) a 2D input, with the phantom's ground truth.
pub fn load_image(source: &Source) -> Result<(Image2, Option<GroundTruth>)> {
    load_image_channel(source, None)
}

/// [`load_image`], taking channel `channel` of a colour image file instead
/// of its luminance (a note on stderr says when the luminance is taken).
pub fn load_image_channel(
    source: &Source,
    channel: Option<usize>,
) -> Result<(Image2, Option<GroundTruth>)> {
    let selection = Selection {
        channel,
        time_point: None,
    };
    load_image_selected(source, selection)
}

/// [`load_image`] of one channel at one time point: of a TIFF, the plane
/// `selection` chooses of its pages (of a TIFF of several channels, the
/// page of that channel at that time point; a choice that leaves several
/// slices is refused with a pointer to `segment3d`); of any other image
/// file, and of a TIFF of one channel, `selection.channel` is a colour
/// channel, and a time point is refused where the file has none.
pub fn load_image_selected(
    source: &Source,
    selection: Selection,
) -> Result<(Image2, Option<GroundTruth>)> {
    let channel = selection.channel;
    match source {
        Source::File(path) if is_tiff(path) && !selection.is_empty() => {
            Ok((load_tiff_plane(path, selection)?, None))
        }
        Source::File(path) if selection.time_point.is_some() => Err(Error::Usage(format!(
            "--time-point chooses a time point of a time-lapse TIFF (an ImageJ hyperstack or \
             an OME-TIFF); {} is not a TIFF",
            path.display()
        ))),
        Source::File(path) if crate::io::volume::is_nifti(path) => {
            Ok((load_nifti_slice(path, channel)?, None))
        }
        Source::File(path) => {
            refuse_stacks(path)?;
            refuse_animations(path)?;
            let image = Image2::load_channel(path, channel)?;
            if image.colour() == Colour::Luminance {
                eprintln!(
                    "note: {} is a colour image; it is segmented as its luminance \
                     (Rec. 709 weights of R, G, B; --channel K takes one channel)",
                    path.display()
                );
            }
            Ok((image, None))
        }
        Source::Phantom {
            name,
            size,
            noise,
            seed,
        } => {
            let kind = phantom2(name, *size, *noise)?;
            let ph = kind.generate(*size, *noise, *seed);
            let truth = GroundTruth {
                labels: ph.truth,
                phases: ph.phases,
            };
            Ok((Image2::from_raw(ph.width, ph.height, ph.image), Some(truth)))
        }
        Source::Array => Err(Error::Usage(
            "an in-memory image has no file to load".into(),
        )),
    }
}

/// A NIfTI file one slice thick (`nz = 1`, or a 2D NIfTI) as a 2D image
/// in the header's frame (pixel size, orientation and origin, as NIfTI
/// readers place it); a NIfTI of several slices is a volume, refused with a
/// pointer to `segment3d`. Its one channel is channel 0.
fn load_nifti_slice(path: &Path, channel: Option<usize>) -> Result<Image2> {
    let volume = Volume::load_nifti(path)?;
    let Some(image) = volume.to_slice_image() else {
        return Err(Error::Usage(format!(
            "{} is a NIfTI {}",
            path.display(),
            not_a_z_slice(volume.dims())
        )));
    };
    one_channel(image, channel, path)
}

/// Why a NIfTI of `dims` voxels is not a slice `segment` reads: a volume,
/// for `segment3d`; or a slice one voxel thick along x or y (sagittal,
/// coronal), which `segment3d` cannot mesh either, so the way out is to
/// make its thin axis the third (by a cyclic permutation of the axes, which
/// keeps their handedness, so no left-right flip).
fn not_a_z_slice([nx, ny, nz]: [usize; 3]) -> String {
    let thin_axis = match (nx, ny) {
        (1, n) if n > 1 => Some(("x", "y z x")),
        (n, 1) if n > 1 => Some(("y", "z x y")),
        _ => None,
    };
    match thin_axis {
        Some((axis, swap)) if nz > 1 => format!(
            "slice of {nx}×{ny}×{nz} voxels, one voxel thick along {axis}: `segment` reads a \
             slice one voxel thick along the third axis, `segment3d` a volume at least 2 \
             voxels thick; make its thin axis the third (e.g. `fslswapdim IN {swap} OUT`)"
        ),
        _ => format!(
            "volume of {nx}×{ny}×{nz} voxels: `segment` reads 2D images, \
             segment it with `dsc-seg segment3d`"
        ),
    }
}

/// An animated GIF or PNG is a sequence of images: `segment` would read its
/// first frame only, so it is refused, naming its frames.
fn refuse_animations(path: &Path) -> Result<()> {
    use image::{ImageFormat, ImageReader};
    let Ok(reader) = ImageReader::open(path).and_then(ImageReader::with_guessed_format) else {
        return Ok(()); // the loader reports it
    };
    let format = reader.format();
    let file = std::io::BufReader::new(reader.into_inner());
    let frames = match format {
        Some(ImageFormat::Gif) => gif_frames(file),
        Some(ImageFormat::Png) => png::Decoder::new(file)
            .read_info()
            .ok()
            .and_then(|r| r.info().animation_control.map(|a| a.num_frames.to_string())),
        _ => None,
    };
    match frames {
        Some(n) if n != "1" => Err(Error::Usage(format!(
            "{} is an animation of {n} frames: `segment` reads one image; save the frame \
             to segment as a file of its own",
            path.display()
        ))),
        _ => Ok(()),
    }
}

/// The frames of a GIF as the refusal names them: `"1"`, or `"2 or more"`
/// (only the first two are decoded to tell).
fn gif_frames<R: std::io::BufRead + std::io::Seek>(file: R) -> Option<String> {
    use image::AnimationDecoder;
    let gif = image::codecs::gif::GifDecoder::new(file).ok()?;
    let frames = gif.into_frames().take(2).filter(|f| f.is_ok()).count();
    Some(if frames > 1 {
        "2 or more".into()
    } else {
        "1".into()
    })
}

/// A multi-page TIFF is a volume (or a hyperstack, refused by both readers):
/// `segment` would read its first page only. Of an OME-TIFF, only the
/// first series counts, and its pages must be those its OME-XML declares.
fn refuse_stacks(path: &Path) -> Result<()> {
    if !crate::io::resolution::is_tiff(path) {
        return Ok(());
    }
    let Ok(file) = std::fs::File::open(path) else {
        return Ok(()); // the loader reports it
    };
    let Ok(mut dec) = tiff::decoder::Decoder::new(std::io::BufReader::new(file)) else {
        return Ok(());
    };
    if let Some(stack) = crate::io::hyperstack::Hyperstack::of_tiff(&mut dec) {
        return Err(Error::Usage(format!(
            "{} is {}",
            path.display(),
            stack.refusal_of(&mut dec)
        )));
    }
    let ome = OmeLayout::of_tiff(&mut dec);
    let mut pages = 1usize;
    while dec.more_images() && dec.next_image().is_ok() {
        pages += 1;
    }
    let mut in_series = "";
    if let Some(ome) = ome {
        if let Some(reason) = ome.page_mismatch(pages) {
            return Err(Error::Usage(format!("{} is {reason}", path.display())));
        }
        if ome.series > 1 {
            (pages, in_series) = (ome.pages(), " in its first series");
        }
    }
    if pages > 1 {
        return Err(Error::Usage(format!(
            "{} has {pages} pages{in_series}: a multi-page TIFF is a volume, segment it with \
             `dsc-seg segment3d`",
            path.display()
        )));
    }
    Ok(())
}

/// The plane of a TIFF that `selection` chooses: of a file of several
/// channels (an ImageJ hyperstack, an OME-TIFF), the page of that channel
/// at that time point; of a file of one, `selection.channel` is a colour
/// channel: of one page, as for any image; of several, read alike, of
/// grayscale pages only, whose one channel is 0. A choice that leaves
/// several slices is a volume, refused with a pointer to `segment3d`.
fn load_tiff_plane(path: &Path, selection: Selection) -> Result<Image2> {
    let file = std::fs::File::open(path).map_err(|e| IoError::unreadable(path, e))?;
    let mut dec = tiff::decoder::Decoder::new(std::io::BufReader::new(file))
        .map_err(|e| crate::io::volume::tiff_error(path, e))?;
    let layout = TiffPages::of_tiff(&mut dec, path)?;
    let (pages_chosen, colour) = match layout.channels() {
        1 => (
            Selection {
                channel: None,
                ..selection
            },
            selection.channel,
        ),
        _ => (selection, None),
    };
    let pages = pages_chosen.pages_as_asked(&layout, path, selection)?;
    let [page] = pages[..] else {
        return Err(Error::Usage(format!(
            "{} at {} holds {} slices: a volume, segment it with `{}`",
            path.display(),
            selection.options(),
            pages.len(),
            format!("dsc-seg segment3d {}", pages_chosen.options()).trim_end()
        )));
    };
    // A file of one page is one image, read as any (colour, Orientation);
    // the pages of any other are read alike (see `colour_page`).
    let image = match layout.count {
        1 => Image2::load_channel(path, colour)?,
        _ => one_channel(Image2::load_tiff_page(path, page)?, colour, path)?,
    };
    Ok(image.with_selection(pages_chosen))
}

/// A gray image as its channel `colour` (`None`: as it is); it has only
/// channel 0.
fn one_channel(image: Image2, colour: Option<usize>, path: &Path) -> Result<Image2> {
    match colour {
        None => Ok(image),
        Some(0) => Ok(image.with_colour(Colour::Channel(0))),
        Some(k) => Err(IoError::NoChannel {
            path: path.to_path_buf(),
            channel: k,
            channels: 1,
        }
        .into()),
    }
}

/// `params` with the labels of `Init::Labels` loaded from `init_labels`
/// (a label image of `width × height`).
pub fn with_init_labels(
    mut params: SegmentParams,
    init_labels: Option<&Path>,
    (width, height): (usize, usize),
) -> Result<SegmentParams> {
    if let Init::Labels { labels } = &mut params.init {
        let path = init_labels
            .ok_or_else(|| Error::Usage("--init labels needs --init-labels PNG".into()))?;
        *labels = load_labels(path, width, height, params.phases)?;
    }
    Ok(params)
}

impl Job for SegmentJob {
    type Input = Image2;
    const THREE_D: bool = false;

    fn source(&self) -> &Source {
        &self.source
    }

    fn init_labels(&self) -> Option<&Path> {
        self.init_labels.as_deref()
    }

    fn out(&self) -> &Path {
        &self.out
    }

    fn outputs(&self) -> &Outputs {
        &self.outputs
    }

    fn load(&self) -> Result<(Image2, Option<GroundTruth>)> {
        let selection = Selection {
            channel: self.channel,
            time_point: self.time_point,
        };
        if !selection.is_empty() && !matches!(self.source, Source::File(_)) {
            return Err(Error::Usage(format!(
                "{} chooses a plane of an image file",
                selection.options()
            )));
        }
        let (image, truth) = load_image_selected(&self.source, selection)?;
        Ok((image.with_spacing(self.spacing), truth))
    }

    fn params_for(&self, image: &Image2) -> Result<SegmentParams> {
        with_init_labels(self.params.clone(), self.init_labels(), image.dims())
    }

    fn segment_then<T>(
        &self,
        image: &Image2,
        params: SegmentParams,
        provenance: Provenance,
        ready: impl FnOnce() -> Result<T>,
    ) -> Result<(Segmented, T)> {
        segment_image_then(image, params, provenance, self.quiet, ready)
    }
}

/// Runs a segmentation job and writes its outputs (all: `labels.png`,
/// `overlay.png`, `overlay.svg`, `mesh.vtu` and `report.json`) into the
/// output directory.
pub fn run_segment(job: &SegmentJob) -> Result<SegmentReport> {
    job.run()
}

/// Segments an image held in memory (the parameters' `Init::Labels`, if
/// any, already loaded): the labels, the final mesh and the report.
pub fn segment_image(
    image: &Image2,
    params: SegmentParams,
    provenance: Provenance,
    quiet: bool,
) -> Result<Segmented> {
    segment_image_then(image, params, provenance, quiet, || Ok(())).map(|(s, ())| s)
}

/// [`segment_image`], calling `ready` once the input and parameters are
/// validated, before the run (to check the output directory first).
pub(crate) fn segment_image_then<T>(
    image: &Image2,
    params: SegmentParams,
    provenance: Provenance,
    quiet: bool,
    ready: impl FnOnce() -> Result<T>,
) -> Result<(Segmented, T)> {
    let (w, h) = image.dims();
    let t_seg = Instant::now();
    // A file or an array has values of its own; a phantom has only [0, 1].
    let intensity = match &provenance.source {
        Source::File(_) | Source::Array => Some(IntensityMap::of_sample_type(image.sample_type())),
        Source::Phantom { .. } => None,
    };
    let file_value = |v: f32| match intensity {
        Some(map) => map.original_sample(f64::from(v), image.sample_type()),
        None => f64::from(v),
    };
    let ClampedInput {
        data: clamped,
        outlier_extremes,
        robust_range,
    } = clamp_input(image.data(), [w, h, 1], file_value, "pixels");
    let data = clamped.as_ref().map_or(image.data(), |(c, _)| c.as_slice());
    let mut view = ImageView::new_2d(w, h, data)
        .ok_or_else(|| Error::Usage("image buffer does not match its size".into()))?;
    if let Some(range) = robust_range {
        view = view.with_robust_range(range);
    }
    let file_values = |e| with_file_values(e, intensity, image.sample_type());
    let mut params = params;
    let phase_choice = match params.auto_phases {
        Some(max) => {
            params.validate(w, h)?;
            let choice =
                choose_phases::<D2>(view, max, |n| params.with_phases(n)).map_err(file_values)?;
            params = params.with_phases(choice.phases);
            Some(choice)
        }
        None => None,
    };
    let mut seg = Segmentation::<D2>::new(view, params.clone()).map_err(file_values)?;
    let ready = ready()?;

    let mut report = run_with_progress(&mut seg, params.max_iterations, quiet)?;
    let segment = t_seg.elapsed().as_secs_f64();
    if phase_choice
        .as_ref()
        .is_some_and(|c| c.floor_warning().is_some())
    {
        // The choice's warning says why two phases are not two regions.
        let lost = std::mem::take(&mut report.lost_phase_warnings);
        report.warnings.retain(|w| !lost.contains(w));
    }
    let (frame, size_warnings) = input_frame(image, &provenance.source);
    if let Source::File(path) = &provenance.source {
        let series = is_tiff(path)
            .then(|| OmeLayout::of_file(path)?.series_warning(path))
            .flatten();
        let alpha = image.transparency().warning(path, w * h);
        report
            .warnings
            .splice(0..0, series.into_iter().chain(alpha).chain(size_warnings));
    }
    if let Some((_, warning)) = &clamped {
        report.warnings.insert(0, warning.clone());
    }
    report
        .warnings
        .extend(phase_choice.iter().flat_map(PhaseChoice::warnings));

    let labels = seg.label_image();
    check_result(
        &seg,
        &view,
        &labels,
        intensity.map_or(1.0, |m| m.scale()),
        &mut report,
    );
    let (points, tris, phase) = overlay_arrays(&seg);
    let truth_dice = provenance
        .truth
        .as_ref()
        .map(|t| mean_dice(&labels, &t.labels, t.phases));
    let times = JobTimes {
        load: provenance.load_seconds,
        segment,
        write: 0.0,
    };
    let run = RunReport::new(
        "dsc-seg",
        (&provenance.source, provenance.init_labels.as_deref()),
        &seg,
        &report,
        times,
        truth_dice,
    );
    let input = InputSummary::new(
        (image.sample_type(), image.colour(), image.selection()),
        intensity,
        (&report, outlier_extremes),
        &run.ordered_means,
    );
    let rep = Report {
        run,
        width: w,
        height: h,
        input,
        phase_choice,
    };
    let mut report_json = serde_json::to_value(&rep).map_err(|e| Error::Usage(e.to_string()))?;
    let order = seg.phase_order();
    // (the samples the segmentation saw: an outlier it clamped would count
    // in the partial-volume estimate as a large fraction of a phase)
    let measurements = Measurements::from_labels(&labels, data, intensity, &frame, params.phases)
        .with_mesh_2d(seg.complex(), &order, &frame);
    add_frame_and_phases(&mut report_json, &frame, &measurements)?;
    let shown = display_image(image, &report).into_owned();
    let result = Segmented {
        dims: vec![w, h],
        labels,
        vertices: points.iter().flatten().copied().collect(),
        cells: tris.iter().flatten().copied().collect(),
        cell_phases: phase.iter().map(|&p| p as u8).collect(),
        summary: report,
        report: report_json,
        frame,
        measurements,
        render: Render::Image {
            shown,
            values: in_file_units(image),
            complex: Box::new(seg.complex().clone()),
            order,
            nifti_header: label_header(image),
        },
        tiff_labels: matches!(&provenance.source, Source::File(path) if is_tiff(path)),
    };
    Ok((result, ready))
}

/// The frame of an image from `source`: a NIfTI slice's placement, else
/// the file's pixel size (see [`image_frame_and_warnings`]), replaced by the
/// image's own when it has one (`--spacing`); with the warnings of reading
/// the file's pixel size when it is used.
fn input_frame(image: &Image2, source: &Source) -> (Frame, Vec<String>) {
    let (w, h) = image.dims();
    let (frame, warnings) = match (image.placement(), source) {
        (Some(placed), _) => (placed.clone(), Vec::new()),
        (None, Source::File(path)) => image_frame_and_warnings(path, w, h),
        (None, _) => (Frame::image_rows_up(w, h, [1.0, 1.0], "px"), Vec::new()),
    };
    let (mut frame, warnings) = match image.spacing() {
        Some([sx, sy]) => (frame.respaced([sx, sy, frame.spacing[2]]), Vec::new()),
        None => (frame, warnings),
    };
    if let Some(unit) = image.unit() {
        frame.unit = unit.to_string();
    }
    (frame, warnings)
}

/// The header of a NIfTI slice's `labels.nii.gz`: the input's, its pixel
/// size replaced by `--spacing` (as the frame's, so that both agree).
fn label_header(image: &Image2) -> Option<Vec<u8>> {
    let mut header = image.nifti_header()?.to_vec();
    if let (Some([sx, sy]), Some(placed)) = (image.spacing(), image.placement()) {
        let ratio = [sx / placed.spacing[0], sy / placed.spacing[1], 1.0];
        crate::io::volume::rescale_nifti_axes(&mut header, ratio);
    }
    Some(header)
}

/// Writes phantom `name` (`NAME.png`, ground truth `NAME_gt.png` with phase
/// `k` as `k·255/(N−1)`, and `NAME_labels.png` with raw phase
/// indices) into `out`; fig6 also gets `NAME_init.png` (its two initial
/// regions as labels, for `--init labels`). Returns the file names written.
pub fn run_phantom(
    name: &str,
    size: usize,
    noise: f64,
    seed: u64,
    out: &Path,
) -> Result<Vec<String>> {
    let kind = phantom2(name, size, noise)?;
    let stage = Staging::new(out)?;
    let ph = kind.generate(size, noise, seed);
    let base = kind.name();
    let dir = stage.path();
    let mut names = vec![
        format!("{base}.png"),
        format!("{base}_gt.png"),
        format!("{base}_labels.png"),
    ];
    save_gray8_png(dir.join(&names[0]), size, size, &ph.image_u8())?;
    save_gray8_png(dir.join(&names[1]), size, size, &ph.truth_gray())?;
    save_gray8_png(dir.join(&names[2]), size, size, &ph.truth)?;
    if kind == Phantom2Kind::Fig6 {
        names.push(format!("{base}_init.png"));
        save_gray8_png(
            dir.join(&names[3]),
            size,
            size,
            &phantom::fig6_initial_labels(size),
        )?;
    }
    let refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    stage.publish(out, &refs)?;
    Ok(names)
}
