//! Hyperstacks and time series: TIFFs whose pages are not the slices of one
//! volume.
//!
//! Fiji stores a hyperstack of C channels, Z slices and T frames as C·Z·T
//! pages back to back, saying so only in its `ImageJ=` description
//! (`channels=`, `slices=`, `frames=`); an OME-TIFF says so in its OME-XML
//! (`SizeC`, `SizeZ`, `SizeT`, see [`super::ome`]). Read page by page it
//! looks like one stack of C·Z·T slices, and segmenting that would mix
//! channels and time points into one "volume" without a word. The readers
//! refuse it instead, naming the extents, so the user picks one channel and
//! one time point.
//!
//! ImageJ pages that interleave two of these axes are refused, and so are
//! time points alone (`frames=T`, no slices: a time-lapse of one plane, which
//! Fiji and tifffile's `imwrite(..., imagej=True, metadata={'axes': 'TYX'})`
//! declare only for frames): segmented as a volume, time would be meshed as
//! depth, its interfaces smoothed across frames and measured in voxels of a
//! time step. A run of ImageJ channels alone is read as slices: tifffile's
//! `imwrite(..., imagej=True)` of a 3-D array without axes declares
//! `channels=N` for what its writer meant as N slices. OME-XML names its
//! axes, so there more than one channel or time point is refused.

use super::ome::OmeLayout;

/// The channels, slices and frames a TIFF's description declares (each 1
/// when not given).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Hyperstack {
    /// Channels (`channels=`, `SizeC`).
    pub channels: usize,
    /// Z slices (`slices=`, `SizeZ`).
    pub slices: usize,
    /// Time points (`frames=`, `SizeT`).
    pub frames: usize,
    /// Which description declares them.
    pub metadata: Metadata,
}

/// The description that declares a [`Hyperstack`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metadata {
    /// Fiji/ImageJ's `ImageJ=` description.
    ImageJ,
    /// An OME-TIFF's OME-XML.
    OmeXml,
}

impl Hyperstack {
    /// Reads the extents from a TIFF `ImageDescription`; `None` unless it is
    /// an `ImageJ=` description with more than one of at least two of them,
    /// or more than one time point (one run of slices or of channels is read
    /// as a stack).
    pub fn from_description(description: &str) -> Option<Self> {
        if !description.starts_with("ImageJ=") {
            return None;
        }
        let count = |key: &str| {
            description
                .lines()
                .find_map(|l| l.strip_prefix(key))
                .and_then(|v| v.trim().parse::<usize>().ok())
                .filter(|&n| n > 0)
                .unwrap_or(1)
        };
        let stack = Hyperstack {
            channels: count("channels="),
            slices: count("slices="),
            frames: count("frames="),
            metadata: Metadata::ImageJ,
        };
        let interleaved = [stack.channels, stack.slices, stack.frames]
            .iter()
            .filter(|&&n| n > 1)
            .count()
            > 1;
        (interleaved || stack.is_time_series()).then_some(stack)
    }

    /// Whether the pages are time points of one plane (no slices, one channel).
    pub fn is_time_series(&self) -> bool {
        self.frames > 1 && self.slices == 1 && self.channels == 1
    }

    /// The hyperstack the current TIFF page's description declares, if any:
    /// an ImageJ one (see [`Hyperstack::from_description`]), or an OME-TIFF
    /// whose first series has more than one channel or time point.
    pub fn of_tiff<R: std::io::Read + std::io::Seek>(
        dec: &mut tiff::decoder::Decoder<R>,
    ) -> Option<Self> {
        match dec.find_tag(tiff::tags::Tag::ImageDescription) {
            Ok(Some(tiff::decoder::ifd::Value::Ascii(d))) => {
                Self::from_description(&d).or_else(|| OmeLayout::from_description(&d)?.hyperstack())
            }
            _ => None,
        }
    }

    /// Why such a file is refused, and what to do instead; completes
    /// "`path` is …".
    pub fn refusal(&self) -> String {
        match (self.metadata, self.is_time_series()) {
            (Metadata::ImageJ, true) => format!(
                "an ImageJ time series of {}, not the slices of a volume: segment each \
                 time point as an image with `dsc-seg segment` (Fiji: Image › Stacks › \
                 Stack to Images, then save them to a folder), or, if the pages are Z \
                 slices, say so (Fiji: Image › Properties…, {} slices, 1 frame)",
                counted(self.frames, "time point"),
                self.frames
            ),
            (Metadata::OmeXml, true) => format!(
                "an OME-TIFF time series of {} (OME-XML), not the slices of a volume: \
                 segment each time point as an image with `dsc-seg segment` (Fiji: Image › \
                 Stacks › Stack to Images, then save them to a folder)",
                counted(self.frames, "time point")
            ),
            (Metadata::ImageJ, false) => format!(
                "an ImageJ hyperstack of {}; its pages are not one volume: save one channel \
                 at one time point (Fiji: Image › Duplicate…) and segment that",
                self.extents()
            ),
            (Metadata::OmeXml, false) => format!(
                "an OME-TIFF of {} (OME-XML); its pages are not one volume: save one channel \
                 at one time point as a file of its own (Fiji: Image › Duplicate…; tifffile: \
                 index `imread(file)` along the axes `TiffFile(file).series[0].axes` names, \
                 then `imwrite(..., ome=True)`) and segment that",
                self.extents()
            ),
        }
    }

    /// "2 channels × 30 slices × 1 time point".
    fn extents(&self) -> String {
        format!(
            "{} × {} × {}",
            counted(self.channels, "channel"),
            counted(self.slices, "slice"),
            counted(self.frames, "time point")
        )
    }
}

/// `n` and the noun, in the plural unless `n` is 1.
pub(super) fn counted(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_interleaved_axes_make_a_hyperstack() {
        let d = "ImageJ=1.11a\nimages=32\nchannels=2\nslices=8\nframes=2\nhyperstack=true\n";
        let h = Hyperstack::from_description(d).unwrap();
        assert_eq!((h.channels, h.slices, h.frames), (2, 8, 2));
        let t = "ImageJ=1.53t\nimages=12\nslices=4\nframes=3\n";
        assert_eq!(Hyperstack::from_description(t).unwrap().frames, 3);
    }

    /// tifffile's description of a `TYX` array (`imagej=True`): time points
    /// of one plane, refused by their own message.
    #[test]
    fn time_points_alone_are_a_time_series() {
        let t = "ImageJ=1.11a\nimages=5\nframes=5\nhyperstack=true\nmode=grayscale\nloop=false";
        let series = Hyperstack::from_description(t).unwrap();
        assert!(series.is_time_series());
        assert!(series.refusal().contains("time series of 5 time points"));
        let two_channels = "ImageJ=1.53t\nimages=10\nchannels=2\nframes=5\n";
        let h = Hyperstack::from_description(two_channels).unwrap();
        assert!(!h.is_time_series());
        assert!(h.refusal().contains("2 channels × 1 slice × 5 time points"));
    }

    #[test]
    fn one_run_of_pages_or_another_description_is_not_one() {
        let z = "ImageJ=1.11a\nimages=24\nslices=24\nunit=um\nspacing=2.0\n";
        assert_eq!(Hyperstack::from_description(z), None);
        // tifffile's description of a 3-D array written with imagej=True.
        let c = "ImageJ=1.11a\nimages=24\nchannels=24\nhyperstack=true\nmode=grayscale\n";
        assert_eq!(Hyperstack::from_description(c), None);
        assert_eq!(
            Hyperstack::from_description("{\"shape\": [2, 8, 32]}"),
            None
        );
        assert_eq!(
            Hyperstack::from_description("ImageJ=1.5\nchannels=1\n"),
            None
        );
    }
}
