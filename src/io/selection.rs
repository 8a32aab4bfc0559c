//! One channel at one time point of a multi-channel or time-lapse TIFF.
//!
//! An ImageJ hyperstack or an OME-TIFF of several channels or time points
//! is not one image or volume (see [`super::hyperstack`]); `--channel C`
//! and `--time-point T` (both 0-based, as tifffile and Bio-Formats count:
//! Fiji's C1 is `--channel 0`) choose the one to segment, and only its pages are
//! read: its slices, in order, from the page order the file declares
//! (ImageJ: channels fastest, then slices, then time points; OME-XML: its
//! `DimensionOrder`). An axis of one entry needs no choice, and 0 is then
//! the only index there is; an axis of several entries needs one once any
//! choice is made. An index beyond the file's extent is refused, naming
//! the extents.

use std::io::{Read, Seek};
use std::path::Path;

use serde::Serialize;

use super::error::IoError;
use super::hyperstack::{counted, Hyperstack, Metadata, PageOrder};
use super::ome::{too_many_pages, OmeLayout};

/// The channel and time point chosen of a TIFF's pages (`None`: not
/// chosen).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Selection {
    /// The channel (`--channel`), 0-based.
    pub channel: Option<usize>,
    /// The time point (`--time-point`), 0-based.
    pub time_point: Option<usize>,
}

impl Selection {
    /// Whether nothing is chosen.
    pub fn is_empty(&self) -> bool {
        self.channel.is_none() && self.time_point.is_none()
    }

    /// The options as given: "--channel 1 --time-point 0".
    pub fn options(&self) -> String {
        let channel = self.channel.map(|c| format!("--channel {c}"));
        let time = self.time_point.map(|t| format!("--time-point {t}"));
        [channel, time]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// The pages of the chosen channel at the chosen time point, slice by
    /// slice, of the TIFF at `path` laid out as `pages` says.
    pub fn pages_of(&self, pages: &TiffPages, path: &Path) -> Result<Vec<usize>, IoError> {
        self.pages_as_asked(pages, path, *self)
    }

    /// [`Selection::pages_of`] where the user `asked` for more than this
    /// selection of pages (`--channel` taken as a colour channel of a file
    /// of one channel): the refusals name the options as given.
    pub fn pages_as_asked(
        &self,
        pages: &TiffPages,
        path: &Path,
        asked: Selection,
    ) -> Result<Vec<usize>, IoError> {
        self.pages(pages, asked)
            .map_err(|reason| IoError::NotInFile {
                path: path.to_path_buf(),
                reason,
            })
    }

    /// [`Selection::pages_as_asked`], the error completing "`path`: …".
    /// Both indices are checked against their extents first, so an index
    /// out of range is named even when the other axis lacks a choice.
    fn pages(&self, pages: &TiffPages, asked: Selection) -> Result<Vec<usize>, String> {
        let stack = pages.stack();
        if stack.slices > pages.count {
            return Err(format!(
                "it declares {} in {}: which pages are which cannot be told",
                stack.extents(),
                counted(pages.count, "page")
            ));
        }
        in_range(self.channel, stack.channels, "channel", &stack)?;
        in_range(self.time_point, stack.frames, "time-point", &stack)?;
        let channel = index(self.channel, stack.channels, asked, &stack)?;
        let time = index(self.time_point, stack.frames, asked, &stack)?;
        (0..stack.slices)
            .map(|z| stack.page(z, channel, time))
            .collect::<Option<Vec<usize>>>()
            .ok_or_else(|| {
                format!(
                    "its OME-XML gives no valid DimensionOrder (such as XYZCT) for its {}: \
                     which page holds which channel, slice and time point cannot be told",
                    stack.extents()
                )
            })
    }
}

/// Refuses an index `chosen` beyond an axis of `extent` entries (`option`:
/// `channel` or `time-point`), naming the range.
fn in_range(
    chosen: Option<usize>,
    extent: usize,
    option: &str,
    stack: &Hyperstack,
) -> Result<(), String> {
    match chosen {
        Some(i) if i >= extent => Err(format!(
            "--{option} {i} is out of range: it holds {} (0-based: {})",
            stack.extents(),
            match extent {
                1 => format!("--{option} 0 only"),
                n => format!("--{option} 0 to {}", n - 1),
            }
        )),
        _ => Ok(()),
    }
}

/// The index chosen along an axis of `extent` entries (within it, see
/// [`in_range`]): 0 when not chosen and the axis has one entry; refused
/// when not chosen along an axis of several, naming the options `asked`.
fn index(
    chosen: Option<usize>,
    extent: usize,
    asked: Selection,
    stack: &Hyperstack,
) -> Result<usize, String> {
    match chosen {
        None if extent > 1 => Err(format!(
            "it holds {}: {} chooses part of it, choose with {}",
            stack.extents(),
            asked.options(),
            stack.options_to_choose()
        )),
        None => Ok(0),
        Some(i) => Ok(i),
    }
}

/// A TIFF's pages as its description lays them out: the extents an
/// ImageJ or OME-XML description declares (whatever they are: a run of
/// slices too), and how many pages the file holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TiffPages {
    /// The declared extents; `None`: no such description, every page a slice.
    pub declared: Option<Hyperstack>,
    /// The pages of the file (of an OME-TIFF of several series, those of
    /// its first).
    pub count: usize,
}

impl TiffPages {
    /// Reads the layout of the TIFF at `path` from the first page's
    /// description and counts the pages (leaving the decoder at the last);
    /// refuses pages unlike those declared (fewer than an ImageJ
    /// description's, or not the OME-XML's).
    pub fn of_tiff<R: Read + Seek>(
        dec: &mut tiff::decoder::Decoder<R>,
        path: &Path,
    ) -> Result<Self, IoError> {
        Self::read(dec).map_err(|reason| IoError::NotOneVolume {
            path: path.to_path_buf(),
            reason,
        })
    }

    /// [`TiffPages::of_tiff`], the error completing "`path` is …".
    fn read<R: Read + Seek>(dec: &mut tiff::decoder::Decoder<R>) -> Result<Self, String> {
        let description = match dec.find_tag(tiff::tags::Tag::ImageDescription) {
            Ok(Some(tiff::decoder::ifd::Value::Ascii(d))) => d,
            _ => String::new(),
        };
        let imagej = Hyperstack::declared_by_imagej(&description);
        let ome = OmeLayout::from_description(&description);
        let mut count = 1usize;
        while dec.more_images() && dec.next_image().is_ok() {
            count += 1;
        }
        if let Some(ome) = ome {
            if let Some(reason) = ome.page_mismatch(count) {
                return Err(reason);
            }
            count = ome.pages();
        }
        let declared = imagej.or(ome.map(|o| o.extents));
        if let Some(stack) = imagej {
            let Some(declared) = stack.pages() else {
                return Err(too_many_pages("an ImageJ TIFF whose description", &stack));
            };
            if declared > count {
                return Err(format!(
                    "an ImageJ TIFF of {} whose description declares {} for {}: which pages \
                     are which cannot be told",
                    counted(count, "page"),
                    counted(declared, "page"),
                    stack.extents()
                ));
            }
        }
        Ok(TiffPages { declared, count })
    }

    /// The declared extents, or every page a slice of one channel at one
    /// time point (its `metadata` then unused).
    fn stack(&self) -> Hyperstack {
        self.declared.unwrap_or(Hyperstack {
            channels: 1,
            slices: self.count,
            frames: 1,
            metadata: Metadata::ImageJ,
            order: Some(PageOrder::IMAGEJ),
        })
    }

    /// How many channels the pages hold (1 without a description).
    pub fn channels(&self) -> usize {
        self.stack().channels
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stack(channels: usize, slices: usize, frames: usize, order: &str) -> TiffPages {
        TiffPages {
            declared: Some(Hyperstack {
                channels,
                slices,
                frames,
                metadata: Metadata::OmeXml,
                order: PageOrder::from_dimension_order(order),
            }),
            count: channels * slices * frames,
        }
    }

    impl Selection {
        /// The pages as chosen, asked for as they are.
        fn on(&self, pages: &TiffPages) -> Result<Vec<usize>, String> {
            self.pages(pages, *self)
        }
    }

    fn choose(channel: Option<usize>, time_point: Option<usize>) -> Selection {
        Selection {
            channel,
            time_point,
        }
    }

    #[test]
    fn the_chosen_slices_in_the_declared_order() {
        let s = stack(2, 3, 2, "XYZCT");
        assert_eq!(choose(Some(1), Some(1)).on(&s), Ok(vec![9, 10, 11]));
        let s = stack(2, 3, 2, "XYCZT");
        assert_eq!(choose(Some(1), Some(0)).on(&s), Ok(vec![1, 3, 5]));
        let s = stack(2, 3, 2, "XYTCZ");
        assert_eq!(choose(Some(0), Some(1)).on(&s), Ok(vec![1, 5, 9]));
    }

    #[test]
    fn an_axis_of_one_entry_takes_index_zero_only() {
        let s = stack(3, 4, 1, "XYZCT");
        assert_eq!(choose(Some(2), None).on(&s), Ok(vec![8, 9, 10, 11]));
        assert_eq!(choose(Some(2), Some(0)).on(&s), Ok(vec![8, 9, 10, 11]));
        let e = choose(Some(2), Some(1)).on(&s).unwrap_err();
        assert!(
            e.starts_with("--time-point 1 is out of range: it holds 3 channels × 4 slices × 1 time point (0-based: --time-point 0 only)"),
            "{e}"
        );
        let e = choose(Some(3), None).on(&s).unwrap_err();
        assert!(e.contains("(0-based: --channel 0 to 2)"), "{e}");
        let plain = TiffPages {
            declared: None,
            count: 5,
        };
        assert_eq!(choose(Some(0), Some(0)).on(&plain), Ok(vec![0, 1, 2, 3, 4]));
        assert!(choose(Some(1), None).on(&plain).is_err());
    }

    #[test]
    fn an_axis_of_several_entries_needs_a_choice() {
        let s = stack(2, 3, 4, "XYZCT");
        let e = choose(Some(1), None).on(&s).unwrap_err();
        assert!(
            e.contains("--channel 1 chooses part of it, choose with --channel C --time-point T"),
            "{e}"
        );
        let e = choose(None, Some(5)).on(&s).unwrap_err();
        assert!(e.starts_with("--time-point 5 is out of range"), "{e}");
        let as_colour = choose(None, None).pages(&s, choose(Some(0), None));
        assert!(
            as_colour
                .unwrap_err()
                .contains(": --channel 0 chooses part of it"),
            "the options as given"
        );
    }

    #[test]
    fn pages_without_an_order_are_not_told_apart() {
        let s = stack(2, 3, 1, "");
        assert!(choose(Some(1), None)
            .on(&s)
            .unwrap_err()
            .contains("no valid DimensionOrder"));
        let s = stack(2, 1, 1, "");
        assert_eq!(choose(Some(1), None).on(&s), Ok(vec![1]));
    }
}
