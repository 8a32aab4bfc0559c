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
//!
//! One channel at one time point can be chosen instead (`--channel`,
//! `--time-point`, see [`super::selection`]); [`Hyperstack::page`] says
//! which page holds each of its slices, from the order the pages run
//! through the axes ([`PageOrder`]).

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
    /// How the pages run through the axes; `None` when the OME-XML names
    /// no valid `DimensionOrder` (the pages can then be told apart only
    /// when at most one axis has more than one entry).
    pub order: Option<PageOrder>,
}

/// An axis of a hyperstack's pages besides the plane's own two.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// Z slices.
    Z,
    /// Channels.
    C,
    /// Time points.
    T,
}

/// The order in which a hyperstack's pages run through its axes, the
/// fastest first: page `p` of ImageJ's `[C, Z, T]` order is channel
/// `p mod C` of slice `(p div C) mod Z` at time point `p div (C·Z)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PageOrder(pub [Axis; 3]);

impl PageOrder {
    /// ImageJ's hyperstacks: channels fastest, then slices, then time points.
    pub const IMAGEJ: PageOrder = PageOrder([Axis::C, Axis::Z, Axis::T]);

    /// An OME `DimensionOrder` (`XYZCT`, `XYCZT`, ...: `X`, `Y`, then Z, C
    /// and T in the order the pages run through them); `None` for anything
    /// else.
    pub fn from_dimension_order(order: &str) -> Option<Self> {
        let rest = order.trim().strip_prefix("XY")?;
        let axes: Vec<Axis> = rest
            .chars()
            .map(|a| match a {
                'Z' => Some(Axis::Z),
                'C' => Some(Axis::C),
                'T' => Some(Axis::T),
                _ => None,
            })
            .collect::<Option<_>>()?;
        let all = [Axis::Z, Axis::C, Axis::T];
        match axes[..] {
            [a, b, c] if all.iter().all(|x| [a, b, c].contains(x)) => Some(PageOrder([a, b, c])),
            _ => None,
        }
    }
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
        Self::declared_by_imagej(description)
            .filter(|stack| stack.is_interleaved() || stack.is_time_series())
    }

    /// The extents an `ImageJ=` description declares, whatever they are
    /// (a run of slices, or of channels, too); `None` for any other
    /// description.
    pub fn declared_by_imagej(description: &str) -> Option<Self> {
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
        Some(Hyperstack {
            channels: count("channels="),
            slices: count("slices="),
            frames: count("frames="),
            metadata: Metadata::ImageJ,
            order: Some(PageOrder::IMAGEJ),
        })
    }

    /// Whether more than one of the axes has more than one entry.
    fn is_interleaved(&self) -> bool {
        [self.channels, self.slices, self.frames]
            .iter()
            .filter(|&&n| n > 1)
            .count()
            > 1
    }

    /// How many pages the extents take; `None` when that is more than a
    /// `usize` counts (a crafted or corrupt description: no file holds them).
    pub fn pages(&self) -> Option<usize> {
        self.channels
            .checked_mul(self.slices)?
            .checked_mul(self.frames)
    }

    /// The page holding slice `z` of channel `c` at time point `t` (each
    /// within its extent); `None` when the page order is unknown and more
    /// than one axis has more than one entry.
    pub fn page(&self, z: usize, c: usize, t: usize) -> Option<usize> {
        // With one axis of several entries, any order runs through it alone.
        let order = match self.order {
            Some(order) => order,
            None if !self.is_interleaved() => PageOrder::IMAGEJ,
            None => return None,
        };
        let (mut page, mut stride) = (0, 1);
        for axis in order.0 {
            let (index, extent) = match axis {
                Axis::Z => (z, self.slices),
                Axis::C => (c, self.channels),
                Axis::T => (t, self.frames),
            };
            page += index * stride;
            stride *= extent;
        }
        Some(page)
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

    /// [`Hyperstack::refusal`] of the TIFF `dec` reads (at its first
    /// page): of colour pages, which `--channel` and `--time-point` do not
    /// read (see [`colour_page`]), it advises converting them instead.
    pub fn refusal_of<R: std::io::Read + std::io::Seek>(
        &self,
        dec: &mut tiff::decoder::Decoder<R>,
    ) -> String {
        match dec.colortype().ok().and_then(colour_page) {
            Some(colour) => format!(
                "{} of {} in {colour} pages: its pages are not one image or volume, and \
                 --channel and --time-point read grayscale pages only; save it as grayscale \
                 first (Fiji: Image › Type › 8-bit)",
                match self.metadata {
                    Metadata::ImageJ => "an ImageJ TIFF",
                    Metadata::OmeXml => "an OME-TIFF",
                },
                self.extents()
            ),
            None => self.refusal(),
        }
    }

    /// Why such a file is refused, and what to do instead; completes
    /// "`path` is …".
    pub fn refusal(&self) -> String {
        match (self.metadata, self.is_time_series()) {
            (Metadata::ImageJ, true) => format!(
                "an ImageJ time series of {}, not the slices of a volume: segment one time \
                 point as an image with `dsc-seg segment` and {}, or, if the pages are Z \
                 slices, say so (Fiji: Image › Properties…, {} slices, 1 frame)",
                counted(self.frames, "time point"),
                self.options_to_choose(),
                self.frames
            ),
            (Metadata::OmeXml, true) => format!(
                "an OME-TIFF time series of {} (OME-XML), not the slices of a volume: \
                 segment one time point as an image with `dsc-seg segment` and {}",
                counted(self.frames, "time point"),
                self.options_to_choose()
            ),
            (metadata, false) => format!(
                "{} of {}{}; its pages are not one volume: segment one channel at one time \
                 point {} and {}",
                match metadata {
                    Metadata::ImageJ => "an ImageJ hyperstack",
                    Metadata::OmeXml => "an OME-TIFF",
                },
                self.extents(),
                match metadata {
                    Metadata::ImageJ => "",
                    Metadata::OmeXml => " (OME-XML)",
                },
                self.command(),
                self.options_to_choose()
            ),
        }
    }

    /// The command that reads one channel at one time point, so that the
    /// refusal's advice is not refused in turn: a plane for `segment`,
    /// slices for `segment3d`.
    fn command(&self) -> &'static str {
        if self.slices == 1 {
            "as an image with `dsc-seg segment`"
        } else {
            "as a volume with `dsc-seg segment3d`"
        }
    }

    /// The options that choose one channel at one time point of these
    /// extents and their ranges, naming only the axes of more than one
    /// entry: "--channel C --time-point T (0-based: C from 0 to 1, T from 0
    /// to 4)".
    pub fn options_to_choose(&self) -> String {
        let axes: Vec<(String, String)> = [
            (self.channels, "channel", "C"),
            (self.frames, "time-point", "T"),
        ]
        .into_iter()
        .filter(|&(n, _, _)| n > 1)
        .map(|(n, name, letter)| {
            (
                format!("--{name} {letter}"),
                format!("{letter} from 0 to {}", n - 1),
            )
        })
        .collect();
        let (options, ranges): (Vec<String>, Vec<String>) = axes.into_iter().unzip();
        format!("{} (0-based: {})", options.join(" "), ranges.join(", "))
    }

    /// "2 channels × 30 slices × 1 time point".
    pub fn extents(&self) -> String {
        format!(
            "{} × {} × {}",
            counted(self.channels, "channel"),
            counted(self.slices, "slice"),
            counted(self.frames, "time point")
        )
    }
}

/// The colour type of a TIFF page (`"RGB(8)"`) unless it is grayscale.
/// The pages of a multi-page TIFF are read by one reader, of grayscale
/// pages only: were page 0 read as any image (colour as luminance, turned
/// upright by its Orientation tag) and the others not, one time point of a
/// colour time series would be read and the next refused, and its channels
/// would come out turned against each other.
pub fn colour_page(colour: tiff::ColorType) -> Option<String> {
    match colour {
        tiff::ColorType::Gray(_) => None,
        other => Some(format!("{other:?}")),
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
        assert!(h
            .refusal()
            .contains("as an image with `dsc-seg segment` and --channel C"));
        let d = "ImageJ=1.53t\nimages=20\nchannels=2\nslices=2\nframes=5\n";
        let volumes = Hyperstack::from_description(d).unwrap().refusal();
        assert!(volumes.contains("as a volume with `dsc-seg segment3d` and --channel C"));
        assert!(
            h.refusal()
                .contains("--channel C --time-point T (0-based: C from 0 to 1, T from 0 to 4)"),
            "{}",
            h.refusal()
        );
        assert!(series
            .refusal()
            .contains("`dsc-seg segment` and --time-point T (0-based: T from 0 to 4)"));
    }

    /// ImageJ's pages run through channels, then slices, then time points.
    #[test]
    fn imagej_pages_run_through_channels_first() {
        let d = "ImageJ=1.11a\nimages=24\nchannels=2\nslices=3\nframes=4\n";
        let h = Hyperstack::from_description(d).unwrap();
        assert_eq!(h.pages(), Some(24));
        assert_eq!(h.page(0, 1, 0), Some(1));
        assert_eq!(h.page(2, 0, 0), Some(4));
        assert_eq!(h.page(1, 1, 3), Some(3 * 6 + 2 + 1));
    }

    /// OME's `DimensionOrder` names the axes from the fastest.
    #[test]
    fn dimension_orders_name_the_fastest_axis_first() {
        let order = |s: &str| PageOrder::from_dimension_order(s);
        assert_eq!(order("XYZCT"), Some(PageOrder([Axis::Z, Axis::C, Axis::T])));
        assert_eq!(order("XYTCZ"), Some(PageOrder([Axis::T, Axis::C, Axis::Z])));
        for bad in ["", "XYZC", "XYZZT", "YXZCT", "XYZCTT"] {
            assert_eq!(order(bad), None, "{bad}");
        }
        let mut h = Hyperstack {
            channels: 2,
            slices: 3,
            frames: 4,
            metadata: Metadata::OmeXml,
            order: order("XYZCT"),
        };
        assert_eq!(h.page(2, 1, 3), Some(2 + 3 + 3 * 6));
        h.order = order("XYCZT");
        assert_eq!(h.page(2, 1, 3), Some(1 + 2 * 2 + 3 * 6));
        h.order = None;
        assert_eq!(h.page(2, 1, 3), None);
        h.frames = 1;
        h.channels = 1;
        assert_eq!(h.page(2, 0, 0), Some(2));
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
