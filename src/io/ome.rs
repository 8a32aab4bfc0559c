//! How an OME-TIFF lays out its pages, as its OME-XML says.
//!
//! Microscopes, Bio-Formats and tifffile store the OME-XML in the first
//! page's description. Its first `Image` element is the first series; the
//! `Pixels` element inside gives that series' extents: `SizeZ` slices,
//! `SizeC` channels and `SizeT` time points, stored as `SizeZ·SizeC·SizeT`
//! pages from the first one on, interleaved in the order `DimensionOrder`
//! names (read into [`Hyperstack::order`], which picks one channel at one
//! time point out of them). A file may hold further series after it, one
//! `Image` element each.
//!
//! Read page by page, channels and time points would pass for slices, and
//! further series for more of them. The readers refuse several channels or
//! time points unless one of each is chosen (as ImageJ hyperstacks, see
//! [`Hyperstack`] and [`super::selection`]), read only the
//! first series, saying so, and refuse a file whose page count is not what
//! its OME-XML declares.

use std::io::{Read, Seek};
use std::path::Path;

use roxmltree::{Document, Node};

use super::hyperstack::{counted, Hyperstack, Metadata, PageOrder};

/// The OME-XML document of a TIFF description: `None` when the description
/// is not OME-XML (no XML whose root is `OME`), `Some(Err(why))` when it
/// looks like OME-XML but is not well-formed (`why` completes "its OME-XML
/// description …").
pub fn document(description: &str) -> Option<Result<Document<'_>, String>> {
    let text = description.trim_start();
    if !text.starts_with('<') {
        return None;
    }
    match Document::parse(text) {
        Ok(doc) if doc.root_element().tag_name().name() == "OME" => Some(Ok(doc)),
        Ok(_) => None,
        Err(e) if text.contains("<OME") => Some(Err(format!("is not well-formed XML ({e})"))),
        Err(_) => None,
    }
}

/// The `Pixels` element of the first series.
pub fn first_pixels<'a, 'i>(doc: &'a Document<'i>) -> Option<Node<'a, 'i>> {
    doc.descendants()
        .find(|n| n.is_element() && n.tag_name().name() == "Pixels")
}

/// The pages of an OME-TIFF as its OME-XML lays them out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OmeLayout {
    /// Channels, slices and time points of the first series. Its channels
    /// count pages: a colour channel (`SamplesPerPixel` of 3, an RGB page)
    /// is one.
    pub extents: Hyperstack,
    /// How many series the file describes (`Image` elements).
    pub series: usize,
}

impl OmeLayout {
    /// The layout an OME-XML description declares; `None` when the
    /// description is not well-formed OME-XML or has no `Pixels` element
    /// (the pages are then read as they come).
    pub fn from_description(description: &str) -> Option<Self> {
        let doc = document(description)?.ok()?;
        let pixels = first_pixels(&doc)?;
        let size = |name: &str| {
            pixels
                .attribute(name)
                .and_then(|v| v.trim().parse::<usize>().ok())
                .filter(|&n| n > 0)
                .unwrap_or(1)
        };
        let series = doc
            .root_element()
            .children()
            .filter(|n| n.is_element() && n.tag_name().name() == "Image")
            .count();
        Some(OmeLayout {
            extents: Hyperstack {
                channels: channel_pages(pixels, size("SizeC")),
                slices: size("SizeZ"),
                frames: size("SizeT"),
                metadata: Metadata::OmeXml,
                order: pixels
                    .attribute("DimensionOrder")
                    .and_then(PageOrder::from_dimension_order),
            },
            series: series.max(1),
        })
    }

    /// The layout the current TIFF page's description declares, if any.
    pub fn of_tiff<R: Read + Seek>(dec: &mut tiff::decoder::Decoder<R>) -> Option<Self> {
        match dec.find_tag(tiff::tags::Tag::ImageDescription) {
            Ok(Some(tiff::decoder::ifd::Value::Ascii(d))) => Self::from_description(&d),
            _ => None,
        }
    }

    /// The layout of the TIFF file at `path`, if its first page declares one.
    pub fn of_file(path: &Path) -> Option<Self> {
        let file = std::fs::File::open(path).ok()?;
        let mut dec = tiff::decoder::Decoder::new(std::io::BufReader::new(file)).ok()?;
        Self::of_tiff(&mut dec)
    }

    /// The pages of the first series; `usize::MAX` when its extents
    /// multiply beyond a `usize`, which no file holds, so
    /// [`OmeLayout::page_mismatch`] refuses it.
    pub fn pages(&self) -> usize {
        self.extents.pages().unwrap_or(usize::MAX)
    }

    /// The extents to refuse: those of a first series of more than one
    /// channel or time point, which is not one volume (nor one image).
    pub fn hyperstack(&self) -> Option<Hyperstack> {
        let e = self.extents;
        (e.channels > 1 || e.frames > 1).then_some(e)
    }

    /// Why a file of `pages` pages is refused when they are not what the
    /// OME-XML declares: fewer than the first series', or, with one series,
    /// more (`None` when they agree). Completes "`path` is …".
    pub fn page_mismatch(&self, pages: usize) -> Option<String> {
        let Some(declared) = self.extents.pages() else {
            return Some(too_many_pages("an OME-TIFF whose OME-XML", &self.extents));
        };
        let agree = if self.series > 1 {
            pages >= declared
        } else {
            pages == declared
        };
        if agree {
            return None;
        }
        let e = &self.extents;
        Some(format!(
            "an OME-TIFF of {} whose OME-XML declares {} for {} × {} × {}{}: which pages \
             are which cannot be told; save it again (Fiji, Bio-Formats or tifffile) so that \
             its OME-XML describes its pages",
            counted(pages, "page"),
            counted(declared, "page"),
            counted(e.channels, "channel"),
            counted(e.slices, "slice"),
            counted(e.frames, "time point"),
            if self.series > 1 {
                " in its first series"
            } else {
                ""
            }
        ))
    }

    /// The warning that only the first of several series is read, naming
    /// `path`; `None` for a file of one series.
    pub fn series_warning(&self, path: &Path) -> Option<String> {
        (self.series > 1).then(|| {
            format!(
                "{}: its OME-XML describes {} series; only the first ({}) is segmented \
                 (save another as a file of its own to segment it)",
                path.display(),
                self.series,
                counted(self.extents.slices, "slice"),
            )
        })
    }
}

/// The pages per slice and time point that `size_c` channels take: one per
/// channel, but one for all the samples of a page (`SamplesPerPixel` of the
/// first `Channel`, 3 for RGB pages) when they divide `size_c`.
fn channel_pages(pixels: Node<'_, '_>, size_c: usize) -> usize {
    let samples = pixels
        .children()
        .find(|n| n.is_element() && n.tag_name().name() == "Channel")
        .and_then(|c| c.attribute("SamplesPerPixel"))
        .and_then(|v| v.trim().parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or(1);
    if size_c % samples == 0 {
        size_c / samples
    } else {
        size_c
    }
}

/// Why a description declaring `extents` is refused when they multiply
/// beyond a `usize`: no file holds that many pages, and counting them would
/// wrap around. Completes "`path` is …"; `what` names the description.
pub(super) fn too_many_pages(what: &str, extents: &Hyperstack) -> String {
    format!(
        "{what} declares {}: more pages than any file holds, so its description is \
         corrupt",
        extents.extents()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// OME-XML of `images` series, each with these `Pixels` attributes.
    fn ome(attributes: &str, images: usize) -> String {
        let image = format!(
            "<Image ID=\"Image:0\"><Pixels ID=\"Pixels:0\" SizeX=\"4\" SizeY=\"4\" \
             {attributes}><Channel ID=\"Channel:0:0\" SamplesPerPixel=\"1\"/></Pixels></Image>"
        );
        format!(
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\
             <OME xmlns=\"http://www.openmicroscopy.org/Schemas/OME/2016-06\">{}</OME>",
            image.repeat(images)
        )
    }

    fn layout(attributes: &str, images: usize) -> OmeLayout {
        OmeLayout::from_description(&ome(attributes, images)).unwrap()
    }

    #[test]
    fn the_first_series_extents_and_the_series_count() {
        let l = layout(
            r#"DimensionOrder="XYCZT" SizeZ="30" SizeC="2" SizeT="1""#,
            1,
        );
        let e = l.extents;
        assert_eq!((e.channels, e.slices, e.frames), (2, 30, 1));
        assert_eq!((l.series, l.pages()), (1, 60));
        assert_eq!(l.hyperstack(), Some(e));
        let l = layout(r#"SizeZ="12" SizeC="1" SizeT="1""#, 3);
        assert_eq!((l.series, l.pages(), l.hyperstack()), (3, 12, None));
        // Sizes not given are 1.
        assert_eq!(layout("", 1).pages(), 1);
    }

    #[test]
    fn rgb_pages_are_one_channel() {
        let rgb = ome(r#"SizeZ="1" SizeC="3" SizeT="1""#, 1)
            .replace("SamplesPerPixel=\"1\"", "SamplesPerPixel=\"3\"");
        let l = OmeLayout::from_description(&rgb).unwrap();
        assert_eq!((l.extents.channels, l.hyperstack()), (1, None));
    }

    #[test]
    fn page_counts_must_be_what_is_declared() {
        let one = layout(r#"SizeZ="12""#, 1);
        assert_eq!(one.page_mismatch(12), None);
        let more = one.page_mismatch(15).unwrap();
        assert!(more.starts_with("an OME-TIFF of 15 pages whose OME-XML declares 12 pages"));
        assert!(one.page_mismatch(10).is_some());
        let two = layout(r#"SizeZ="12""#, 2);
        assert_eq!(two.page_mismatch(20), None);
        assert!(two
            .page_mismatch(11)
            .unwrap()
            .contains("in its first series"));
        let warning = two.series_warning(Path::new("a.ome.tif")).unwrap();
        assert!(warning.starts_with("a.ome.tif: its OME-XML describes 2 series; only the first"));
        assert_eq!(one.series_warning(Path::new("a.ome.tif")), None);
    }

    #[test]
    fn other_descriptions_declare_no_layout() {
        assert_eq!(
            OmeLayout::from_description("ImageJ=1.54f\nslices=3\n"),
            None
        );
        assert_eq!(OmeLayout::from_description("<OME><Image/></OME>"), None);
        assert_eq!(OmeLayout::from_description("<OME><Pixels SizeZ="), None);
    }
}
