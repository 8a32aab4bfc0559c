//! Small files for the committed figures: palette PNGs and delta-coded GIFs.
//!
//! The panels are a noisy gray image with a few line colours, so a palette
//! (NeuQuant) of at most 255 colours loses nothing visible and the PNG's
//! row filters compress the 2× upscaled pixels well. GIF frames share one
//! global palette and store only the pixels that changed since the previous
//! frame (the rest transparent), which keeps an evolution of a hundred
//! frames well under a megabyte.

use crate::io::{write_atomic, IoError};
use image::RgbaImage;
use std::collections::HashMap;
use std::path::Path;

/// A palette for `images` with at most `colors` (≤ 255) entries, and a
/// mapping of every pixel of `images` to it.
struct Palette {
    rgb: Vec<u8>,
    quant: color_quant::NeuQuant,
    cache: HashMap<[u8; 3], u8>,
}

impl Palette {
    fn new(images: &[&RgbaImage], colors: usize) -> Self {
        let mut sample = Vec::new();
        for im in images {
            for p in im.pixels() {
                sample.extend_from_slice(&[p[0], p[1], p[2], 255]);
            }
        }
        let quant = color_quant::NeuQuant::new(10, colors.clamp(2, 255), &sample);
        Palette {
            rgb: quant.color_map_rgb(),
            quant,
            cache: HashMap::new(),
        }
    }

    fn index(&mut self, image: &RgbaImage) -> Vec<u8> {
        image
            .pixels()
            .map(|p| {
                let key = [p[0], p[1], p[2]];
                *self
                    .cache
                    .entry(key)
                    .or_insert_with(|| self.quant.index_of(&[key[0], key[1], key[2], 255]) as u8)
            })
            .collect()
    }
}

/// Saves `image` as an 8-bit palette PNG with at most `colors` colours, atomically.
pub fn save_palette_png(
    path: impl AsRef<Path>,
    image: &RgbaImage,
    colors: usize,
) -> Result<(), IoError> {
    let path = path.as_ref();
    let mut pal = Palette::new(&[image], colors);
    let idx = pal.index(image);
    write_atomic(path, |w| {
        let mut enc = png::Encoder::new(w, image.width(), image.height());
        enc.set_color(png::ColorType::Indexed);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_palette(pal.rgb.clone());
        enc.set_compression(png::Compression::High);
        let mut wr = enc.write_header().map_err(std::io::Error::other)?;
        wr.write_image_data(&idx).map_err(std::io::Error::other)?;
        wr.finish().map_err(std::io::Error::other)
    })
}

/// Saves `frames` (same size) as a looping GIF with one global palette of 255
/// colours, each frame after the first storing only its changed pixels;
/// `delays_cs[i]` is frame `i`'s delay in centiseconds (the last value repeats).
pub fn save_delta_gif(
    path: impl AsRef<Path>,
    frames: &[RgbaImage],
    delays_cs: &[u16],
) -> Result<(), IoError> {
    let path = path.as_ref();
    let Some(first) = frames.first() else {
        return Err(IoError::invalid(path, "no frames"));
    };
    let (w, h) = first.dimensions();
    if frames.iter().any(|f| f.dimensions() != (w, h)) || w > 65535 || h > 65535 {
        return Err(IoError::invalid(
            path,
            "frames differ in size or are too large",
        ));
    }
    let sample: Vec<&RgbaImage> = [0, frames.len() / 2, frames.len() - 1]
        .iter()
        .map(|&i| &frames[i])
        .collect();
    let mut pal = Palette::new(&sample, 255);
    let mut global = pal.rgb.clone();
    global.resize(256 * 3, 0);
    const TRANSPARENT: u8 = 255;
    let indexed: Vec<Vec<u8>> = frames.iter().map(|f| pal.index(f)).collect();
    write_atomic(path, |out| {
        let mut enc =
            gif::Encoder::new(out, w as u16, h as u16, &global).map_err(std::io::Error::other)?;
        enc.set_repeat(gif::Repeat::Infinite)
            .map_err(std::io::Error::other)?;
        let mut prev: Option<&Vec<u8>> = None;
        for (i, cur) in indexed.iter().enumerate() {
            let delay = *delays_cs.get(i).or(delays_cs.last()).unwrap_or(&10);
            let mut frame = gif::Frame {
                delay,
                dispose: gif::DisposalMethod::Keep,
                ..gif::Frame::default()
            };
            match prev {
                None => {
                    frame.width = w as u16;
                    frame.height = h as u16;
                    frame.buffer = std::borrow::Cow::Borrowed(cur);
                }
                Some(p) => {
                    // Bounding box of the changed pixels (at least one pixel).
                    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
                    for (k, (a, b)) in p.iter().zip(cur.iter()).enumerate() {
                        if a != b {
                            let (x, y) = (k as u32 % w, k as u32 / w);
                            x0 = x0.min(x);
                            y0 = y0.min(y);
                            x1 = x1.max(x + 1);
                            y1 = y1.max(y + 1);
                        }
                    }
                    if x1 <= x0 {
                        (x0, y0, x1, y1) = (0, 0, 1, 1);
                    }
                    let mut buf = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
                    for y in y0..y1 {
                        for x in x0..x1 {
                            let k = (y * w + x) as usize;
                            buf.push(if p[k] == cur[k] { TRANSPARENT } else { cur[k] });
                        }
                    }
                    frame.left = x0 as u16;
                    frame.top = y0 as u16;
                    frame.width = (x1 - x0) as u16;
                    frame.height = (y1 - y0) as u16;
                    frame.transparent = Some(TRANSPARENT);
                    frame.buffer = std::borrow::Cow::Owned(buf);
                }
            }
            enc.write_frame(&frame).map_err(std::io::Error::other)?;
            prev = Some(cur);
        }
        Ok(())
    })
}
