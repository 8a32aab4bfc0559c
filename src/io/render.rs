//! Paper-style overlay figures: the image in gray, the triangle mesh in thin
//! light lines and the phase interfaces in bold colours; PNG, SVG and
//! animated GIF output.
//!
//! Geometry uses the convention of [`crate::io::image2`]: a mesh point
//! `(x, y)` is in image pixel units with `y` downwards, so `(0,0)`–`(W,H)`
//! spans the image. The output is the image upscaled by [`Overlay::scale`]
//! with nearest-neighbour sampling (each image pixel becomes a crisp block).
//!
//! Interfaces are computed from the triangles and their labels (see
//! [`interface_edges`]): an edge is an interface when the two triangles
//! sharing it carry different labels. The outer boundary of the mesh is not
//! an interface. Each interface edge is drawn in the colour of the *higher*
//! of its two phases ([`phase_color`]), over a thin dark halo so that it reads
//! on both bright and dark image regions; with phase 0 as background, every
//! object is thus outlined in its own colour.
//!
//! [`Overlay::readable`] (the command line's `overlay.png`) adds translucent
//! phase fills, draws each interface as two strokes in the colours of its two
//! phases, and a legend (swatches with the phase numbers); the default scale
//! keeps the longest side at most 2048 px.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

/// The RGBA frame type produced by [`Overlay::to_rgba_image`] and consumed
/// by [`save_gif`] (re-exported from the `image` crate for convenience).
pub use image::RgbaImage;
use image::{Delay, Frame};
use tiny_skia::{LineCap, LineJoin, Paint, PathBuilder, Pixmap, Stroke, Transform};

use super::atomic::{write_atomic, write_bytes_atomic};
use super::error::{IoError, Result};
use super::image2::{encode_png_atomic, unit_to_u8, Image2};

/// Colour-blind-safe palette (Okabe–Ito, then extra distinct hues) indexed
/// by phase, cycling for phases beyond its length.
const PALETTE: [[u8; 3]; 10] = [
    [0x56, 0xB4, 0xE9], // sky blue
    [0xD5, 0x5E, 0x00], // vermillion
    [0x00, 0x9E, 0x73], // bluish green
    [0xE6, 0x9F, 0x00], // orange
    [0x00, 0x72, 0xB2], // blue
    [0xCC, 0x79, 0xA7], // reddish purple
    [0xF0, 0xE4, 0x42], // yellow
    [0x8C, 0x56, 0x4B], // brown
    [0x7F, 0x3C, 0x8D], // purple
    [0x11, 0xA5, 0x79], // teal
];

/// Output width the default scale aims for (at least), in pixels.
const TARGET_WIDTH: f32 = 768.0;

/// The longest side the default scale allows, in output pixels: a long
/// thin image is shrunk to fit rather than blown up to its width's scale.
const MAX_SIDE: f32 = 2048.0;

/// The display colour (sRGB) of a phase, shared by all figures so that a
/// phase has the same colour everywhere.
pub fn phase_color(phase: u32) -> [u8; 3] {
    PALETTE[phase as usize % PALETTE.len()]
}

/// A mesh edge separating two different phases.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InterfaceEdge {
    /// The two end points (indices into the point array), smaller first.
    pub vertices: [u32; 2],
    /// The two phases on either side, smaller first.
    pub phases: [u32; 2],
}

/// Finds the interface edges of a labelled triangle mesh: edges shared by
/// two triangles whose labels differ, sorted by vertices. Edges on the mesh
/// boundary (one triangle) are not interfaces.
///
/// # Panics
/// If `labels.len() != triangles.len()`.
pub fn interface_edges(triangles: &[[u32; 3]], labels: &[u32]) -> Vec<InterfaceEdge> {
    assert_eq!(triangles.len(), labels.len(), "one label per triangle");
    let mut sides: HashMap<[u32; 2], (u32, Option<u32>)> = HashMap::new();
    for (t, &l) in triangles.iter().zip(labels) {
        for e in tri_edges(t) {
            sides
                .entry(e)
                .and_modify(|s| s.1 = Some(l))
                .or_insert((l, None));
        }
    }
    let mut out: Vec<InterfaceEdge> = sides
        .into_iter()
        .filter_map(|(e, (a, b))| match b {
            Some(b) if a != b => Some(InterfaceEdge {
                vertices: e,
                phases: [a.min(b), a.max(b)],
            }),
            _ => None,
        })
        .collect();
    out.sort_by_key(|e| e.vertices);
    out
}

/// The three edges of a triangle, each with the smaller index first.
fn tri_edges(t: &[u32; 3]) -> [[u32; 2]; 3] {
    let e = |a: u32, b: u32| [a.min(b), a.max(b)];
    [e(t[0], t[1]), e(t[1], t[2]), e(t[2], t[0])]
}

/// A figure of a labelled triangle mesh over a grayscale image; see the
/// module documentation for what is drawn.
#[derive(Clone, Copy, Debug)]
pub struct Overlay<'a> {
    /// The background image, drawn in gray (values clamped to `[0,1]`).
    pub image: &'a Image2,
    /// Mesh vertices in image pixel units.
    pub points: &'a [[f64; 2]],
    /// Mesh triangles as indices into `points`.
    pub triangles: &'a [[u32; 3]],
    /// Phase label of each triangle.
    pub labels: &'a [u32],
    /// Output pixels per image pixel (the default makes the figure at least
    /// 768 px wide, using an integer factor so pixels stay square blocks).
    pub scale: f32,
    /// Whether to draw all mesh edges as thin light lines.
    pub draw_mesh: bool,
    /// Width of interface lines in output pixels (default 3).
    pub line_width: f32,
    /// Width of mesh lines in output pixels (default: 15% of
    /// [`Overlay::line_width`], at least 0.6).
    pub mesh_width: Option<f32>,
    /// Opacity of the (white) mesh lines (default 0.35).
    pub mesh_alpha: f32,
    /// Opacity of the phase colour filling each triangle (default 0: none).
    pub fill_alpha: f32,
    /// Whether each interface is drawn as two strokes side by side, each
    /// in the colour of the phase on its side (default: one stroke in the
    /// higher phase's colour).
    pub two_sided: bool,
    /// Whether to draw a legend (a swatch and the number of each phase)
    /// in the top-left corner.
    pub legend: bool,
}

impl<'a> Overlay<'a> {
    /// An overlay with the default scale, mesh drawing on and 3 px
    /// interface lines.
    pub fn new(
        image: &'a Image2,
        points: &'a [[f64; 2]],
        triangles: &'a [[u32; 3]],
        labels: &'a [u32],
    ) -> Self {
        let w = image.width().max(1) as f32;
        let longest = image.width().max(image.height()).max(1) as f32;
        Overlay {
            image,
            points,
            triangles,
            labels,
            scale: (TARGET_WIDTH / w).ceil().max(1.0).min(MAX_SIDE / longest),
            draw_mesh: true,
            line_width: 3.0,
            mesh_width: None,
            mesh_alpha: 0.35,
            fill_alpha: 0.0,
            two_sided: false,
            legend: false,
        }
    }

    /// The style of the command line's `overlay.png`: translucent phase
    /// fills under the interfaces, each interface in both of its phases'
    /// colours, a legend, and a thinner mesh.
    pub fn readable(mut self) -> Self {
        self.fill_alpha = 0.35;
        self.two_sided = true;
        self.legend = true;
        self.line_width = 4.0;
        self.mesh_alpha = 0.2;
        self
    }

    /// Sets [`Overlay::scale`].
    pub fn with_scale(mut self, scale: f32) -> Self {
        self.scale = scale;
        self
    }

    /// Sets [`Overlay::draw_mesh`].
    pub fn with_mesh(mut self, draw_mesh: bool) -> Self {
        self.draw_mesh = draw_mesh;
        self
    }

    /// Output size in pixels, `(round(W·scale), round(H·scale))`, at least 1.
    pub fn output_size(&self) -> (u32, u32) {
        let s = |n: usize| ((n as f32 * self.scale).round() as u32).max(1);
        (s(self.image.width()), s(self.image.height()))
    }

    /// Checks the inputs; the message says what is inconsistent.
    fn check(&self) -> std::result::Result<(), String> {
        if self.labels.len() != self.triangles.len() {
            return Err(format!(
                "{} labels for {} triangles",
                self.labels.len(),
                self.triangles.len()
            ));
        }
        let n = self.points.len();
        if let Some((i, _)) = self
            .triangles
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&v| v as usize >= n))
        {
            return Err(format!("triangle {i} uses a point index >= {n}"));
        }
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(format!("scale {} must be positive", self.scale));
        }
        let (w, h) = self.output_size();
        if u64::from(w) * u64::from(h) > 1 << 28 {
            return Err(format!("output {w}x{h} is too large"));
        }
        Ok(())
    }

    /// Renders the figure to an RGBA image (e.g. a GIF frame).
    ///
    /// # Panics
    /// If the inputs are inconsistent (labels vs. triangles, point indices
    /// out of range, non-positive scale); [`Overlay::to_png`] and
    /// [`Overlay::to_svg`] report these as errors instead.
    pub fn to_rgba_image(&self) -> RgbaImage {
        if let Err(e) = self.check() {
            panic!("Overlay: {e}");
        }
        let (w, h) = self.output_size();
        let mut pixmap = Pixmap::new(w, h).expect("non-zero size checked");
        // Background: nearest-neighbour upscaled gray image (opaque, so the
        // premultiplied and straight RGBA values coincide).
        let (iw, ih) = self.image.dims();
        let data = self.image.data();
        let cols: Vec<usize> = (0..w)
            .map(|x| (((x as f32 + 0.5) / self.scale) as usize).min(iw - 1))
            .collect();
        for (y, row) in pixmap
            .data_mut()
            .chunks_exact_mut(4 * w as usize)
            .enumerate()
        {
            let iy = (((y as f32 + 0.5) / self.scale) as usize).min(ih - 1);
            for (px, &ix) in row.chunks_exact_mut(4).zip(&cols) {
                let g = unit_to_u8(data[iy * iw + ix]);
                px.copy_from_slice(&[g, g, g, 255]);
            }
        }
        let t = Transform::from_scale(self.scale, self.scale);
        self.fill_phases(&mut pixmap, t);
        for layer in self.layers() {
            let mut pb = PathBuilder::new();
            for [a, b] in &layer.segments {
                pb.move_to(a[0] as f32, a[1] as f32);
                pb.line_to(b[0] as f32, b[1] as f32);
            }
            let Some(path) = pb.finish() else { continue };
            let mut paint = Paint::default();
            let [r, g, b] = layer.rgb;
            paint.set_color_rgba8(r, g, b, (layer.alpha * 255.0).round() as u8);
            paint.anti_alias = true;
            let stroke = Stroke {
                // Stroke widths are given in output pixels; the transform
                // scales them, so divide here.
                width: layer.width / self.scale,
                line_cap: LineCap::Round,
                line_join: LineJoin::Round,
                ..Stroke::default()
            };
            pixmap.stroke_path(&path, &paint, &stroke, t, None);
        }
        if self.legend {
            self.draw_legend(&mut pixmap);
        }
        let mut out = RgbaImage::new(w, h);
        for (dst, src) in out.pixels_mut().zip(pixmap.pixels()) {
            let c = src.demultiply();
            dst.0 = [c.red(), c.green(), c.blue(), c.alpha()];
        }
        out
    }

    /// Renders the figure and saves it as a PNG, atomically.
    pub fn to_png(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        self.check().map_err(|e| IoError::invalid(path, e))?;
        let img = self.to_rgba_image();
        encode_png_atomic(
            path,
            img.width() as usize,
            img.height() as usize,
            img.as_raw(),
            image::ExtendedColorType::Rgba8,
        )
    }

    /// Saves the figure as SVG, atomically: the image embedded as a
    /// base64 PNG at its native resolution (asked to be shown pixelated;
    /// browsers honour this, some converters smooth it), the mesh and
    /// interfaces as vector paths in image pixel units (`viewBox` is
    /// `0 0 W H`, the displayed size that of [`Overlay::output_size`]).
    pub fn to_svg(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        self.check().map_err(|e| IoError::invalid(path, e))?;
        let (iw, ih) = self.image.dims();
        let (w, h) = self.output_size();
        let gray: Vec<u8> = self.image.data().iter().map(|&v| unit_to_u8(v)).collect();
        let mut png = Vec::new();
        {
            use image::ImageEncoder;
            image::codecs::png::PngEncoder::new(&mut png)
                .write_image(&gray, iw as u32, ih as u32, image::ExtendedColorType::L8)
                .map_err(|e| IoError::write(path, std::io::Error::other(e)))?;
        }
        let mut svg = String::new();
        // Writing to a String cannot fail.
        let _ = write!(
            svg,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
             <svg xmlns=\"http://www.w3.org/2000/svg\" \
             xmlns:xlink=\"http://www.w3.org/1999/xlink\" width=\"{w}\" height=\"{h}\" \
             viewBox=\"0 0 {iw} {ih}\">\n\
             <image x=\"0\" y=\"0\" width=\"{iw}\" height=\"{ih}\" \
             preserveAspectRatio=\"none\" image-rendering=\"optimizeSpeed\" \
             style=\"image-rendering:pixelated\" \
             xlink:href=\"data:image/png;base64,{}\"/>\n",
            base64(&png)
        );
        if self.fill_alpha > 0.0 {
            for phase in self.phases() {
                let [r, g, b] = phase_color(phase);
                let _ = write!(
                    svg,
                    "<path stroke=\"none\" fill=\"#{r:02x}{g:02x}{b:02x}\" fill-opacity=\"{}\" d=\"",
                    self.fill_alpha
                );
                for (tri, _) in self
                    .triangles
                    .iter()
                    .zip(self.labels)
                    .filter(|(_, &l)| l == phase)
                {
                    let [a, b, c] = tri.map(|i| self.points[i as usize]);
                    let _ = write!(
                        svg,
                        "M{:.3} {:.3}L{:.3} {:.3}L{:.3} {:.3}Z",
                        a[0], a[1], b[0], b[1], c[0], c[1]
                    );
                }
                svg.push_str("\"/>\n");
            }
        }
        for layer in self.layers() {
            let [r, g, b] = layer.rgb;
            let _ = write!(
                svg,
                "<path fill=\"none\" stroke=\"#{r:02x}{g:02x}{b:02x}\" stroke-opacity=\"{}\" \
                 stroke-width=\"{}\" stroke-linecap=\"round\" stroke-linejoin=\"round\" d=\"",
                layer.alpha,
                layer.width / self.scale
            );
            for [a, b] in &layer.segments {
                let _ = write!(svg, "M{:.3} {:.3}L{:.3} {:.3}", a[0], a[1], b[0], b[1]);
            }
            svg.push_str("\"/>\n");
        }
        if self.legend {
            self.svg_legend(&mut svg);
        }
        svg.push_str("</svg>\n");
        write_bytes_atomic(path, svg.as_bytes())
    }

    /// The stroked layers, bottom to top: mesh, interface halo, one layer
    /// per interface colour. Each edge appears once per layer so that
    /// semi-transparent lines are not darkened where triangles share edges.
    fn layers(&self) -> Vec<Layer> {
        let p = |i: u32| self.points[i as usize];
        let mut layers = Vec::new();
        if self.draw_mesh {
            let mut edges: Vec<[u32; 2]> = self.triangles.iter().flat_map(tri_edges).collect();
            edges.sort_unstable();
            edges.dedup();
            layers.push(Layer {
                rgb: [255, 255, 255],
                alpha: self.mesh_alpha,
                width: self.mesh_width.unwrap_or((0.15 * self.line_width).max(0.6)),
                segments: edges.iter().map(|&[a, b]| [p(a), p(b)]).collect(),
            });
        }
        let iface = interface_edges(self.triangles, self.labels);
        if iface.is_empty() {
            return layers;
        }
        // A dark outline under every interface, whichever way it is coloured.
        layers.push(Layer {
            rgb: [0, 0, 0],
            alpha: 0.55,
            width: self.line_width + 2.0,
            segments: iface
                .iter()
                .map(|e| [p(e.vertices[0]), p(e.vertices[1])])
                .collect(),
        });
        if self.two_sided {
            layers.extend(self.sided_layers());
            return layers;
        }
        let mut by_phase: Vec<(u32, Vec<[[f64; 2]; 2]>)> = Vec::new();
        for e in &iface {
            let ph = e.phases[1];
            let seg = [p(e.vertices[0]), p(e.vertices[1])];
            match by_phase.iter_mut().find(|(q, _)| *q == ph) {
                Some((_, v)) => v.push(seg),
                None => by_phase.push((ph, vec![seg])),
            }
        }
        by_phase.sort_by_key(|(ph, _)| *ph);
        for (ph, segments) in by_phase {
            layers.push(Layer {
                rgb: phase_color(ph),
                alpha: 1.0,
                width: self.line_width,
                segments,
            });
        }
        layers
    }
}

impl Overlay<'_> {
    /// The phases present, in increasing order.
    fn phases(&self) -> Vec<u32> {
        let mut phases = self.labels.to_vec();
        phases.sort_unstable();
        phases.dedup();
        phases
    }

    /// Fills every triangle with its phase's colour at [`Overlay::fill_alpha`]:
    /// one path per phase, so shared edges inside a phase leave no seam.
    fn fill_phases(&self, pixmap: &mut Pixmap, t: Transform) {
        if self.fill_alpha <= 0.0 {
            return;
        }
        for phase in self.phases() {
            let mut pb = PathBuilder::new();
            for (tri, _) in self
                .triangles
                .iter()
                .zip(self.labels)
                .filter(|(_, &l)| l == phase)
            {
                let [a, b, c] = tri.map(|i| self.points[i as usize]);
                pb.move_to(a[0] as f32, a[1] as f32);
                pb.line_to(b[0] as f32, b[1] as f32);
                pb.line_to(c[0] as f32, c[1] as f32);
                pb.close();
            }
            let Some(path) = pb.finish() else { continue };
            let mut paint = Paint::default();
            let [r, g, b] = phase_color(phase);
            paint.set_color_rgba8(r, g, b, (self.fill_alpha * 255.0).round() as u8);
            // Not anti-aliased: the interface strokes drawn over it cover
            // every edge of a phase's fill. Anti-aliasing the fills took a
            // third of a 512² overlay's rendering and changed 0.4 % of its
            // pixels by at most 9 of 765 levels.
            paint.anti_alias = false;
            pixmap.fill_path(&path, &paint, tiny_skia::FillRule::Winding, t, None);
        }
    }

    /// One layer per phase: each interface edge shifted a quarter of the
    /// line width into each of its two triangles, in that triangle's colour.
    fn sided_layers(&self) -> Vec<Layer> {
        let shift = f64::from(self.line_width) / 4.0 / f64::from(self.scale);
        let mut sides: HashMap<[u32; 2], (u32, Option<u32>)> = HashMap::new();
        for (t, &l) in self.triangles.iter().zip(self.labels) {
            for e in tri_edges(t) {
                sides
                    .entry(e)
                    .and_modify(|s| s.1 = Some(l))
                    .or_insert((l, None));
            }
        }
        let mut by_phase: Vec<(u32, Vec<[[f64; 2]; 2]>)> = Vec::new();
        for (t, &l) in self.triangles.iter().zip(self.labels) {
            for (k, e) in tri_edges(t).into_iter().enumerate() {
                match sides.get(&e) {
                    Some(&(a, Some(b))) if a != b => {}
                    _ => continue,
                }
                let [a, b] = e.map(|i| self.points[i as usize]);
                // The corner opposite edge k of `tri_edges` is t[(k + 2) % 3].
                let c = self.points[t[(k + 2) % 3] as usize];
                let Some(seg) = shifted_towards(a, b, c, shift) else {
                    continue;
                };
                match by_phase.iter_mut().find(|(q, _)| *q == l) {
                    Some((_, v)) => v.push(seg),
                    None => by_phase.push((l, vec![seg])),
                }
            }
        }
        by_phase.sort_by_key(|(ph, _)| *ph);
        by_phase
            .into_iter()
            .map(|(ph, segments)| Layer {
                rgb: phase_color(ph),
                alpha: 1.0,
                width: self.line_width / 2.0,
                segments,
            })
            .collect()
    }

    /// The legend's boxes in output pixels: per phase present, its swatch
    /// `(phase, x, y, side)`, on a panel `(x, y, w, h)`.
    fn legend_layout(&self) -> (Vec<Swatch>, [f32; 4]) {
        let phases = self.phases();
        let (side, gap, pad) = (18.0f32, 6.0f32, 6.0f32);
        let digits = phases
            .iter()
            .map(|p| p.to_string().len())
            .max()
            .unwrap_or(1) as f32;
        let width = pad * 2.0 + side + gap + digits * (side * 0.6 + 3.0);
        let height = pad * 2.0 + phases.len() as f32 * (side + gap) - gap;
        let boxes = phases
            .iter()
            .enumerate()
            .map(|(i, &p)| (p, pad + pad, pad + pad + i as f32 * (side + gap), side))
            .collect();
        (boxes, [pad, pad, width, height])
    }

    /// Draws the legend: a light panel, a swatch per phase and its number
    /// (seven-segment strokes, no font needed).
    fn draw_legend(&self, pixmap: &mut Pixmap) {
        let (boxes, [px, py, pw, ph]) = self.legend_layout();
        let fill = |pixmap: &mut Pixmap, rect: [f32; 4], rgba: [u8; 4]| {
            if let Some(r) = tiny_skia::Rect::from_xywh(rect[0], rect[1], rect[2], rect[3]) {
                let mut paint = Paint::default();
                paint.set_color_rgba8(rgba[0], rgba[1], rgba[2], rgba[3]);
                pixmap.fill_rect(r, &paint, Transform::identity(), None);
            }
        };
        fill(pixmap, [px, py, pw, ph], [255, 255, 255, 220]);
        for (phase, x, y, side) in boxes {
            let [r, g, b] = phase_color(phase);
            fill(
                pixmap,
                [x - 1.0, y - 1.0, side + 2.0, side + 2.0],
                [0, 0, 0, 255],
            );
            fill(pixmap, [x, y, side, side], [r, g, b, 255]);
            let mut pb = PathBuilder::new();
            let mut dx = x + side + 6.0;
            for ch in phase.to_string().chars() {
                seven_segment(&mut pb, ch, dx, y + 2.0, side * 0.5, side - 4.0);
                dx += side * 0.6 + 3.0;
            }
            if let Some(path) = pb.finish() {
                let mut paint = Paint::default();
                paint.set_color_rgba8(0, 0, 0, 255);
                paint.anti_alias = true;
                let stroke = Stroke {
                    width: 2.0,
                    line_cap: LineCap::Round,
                    ..Stroke::default()
                };
                pixmap.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
            }
        }
    }
}

impl Overlay<'_> {
    /// The legend as SVG rectangles and text, in image units.
    fn svg_legend(&self, svg: &mut String) {
        let s = self.scale;
        let (boxes, [px, py, pw, ph]) = self.legend_layout();
        let _ = writeln!(
            svg,
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"#ffffff\" fill-opacity=\"0.86\"/>",
            px / s,
            py / s,
            pw / s,
            ph / s
        );
        for (phase, x, y, side) in boxes {
            let [r, g, b] = phase_color(phase);
            let _ = writeln!(
                svg,
                "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"#{r:02x}{g:02x}{b:02x}\" \
                 stroke=\"#000000\" stroke-width=\"{}\"/>\n<text x=\"{}\" y=\"{}\" \
                 font-family=\"sans-serif\" font-size=\"{}\">{phase}</text>",
                x / s,
                y / s,
                side / s,
                side / s,
                1.0 / s,
                (x + side + 6.0) / s,
                (y + side - 2.0) / s,
                side / s
            );
        }
    }
}

/// The segment `a`–`b` moved by `shift` perpendicular to itself, towards
/// `c`; `None` for a degenerate segment.
fn shifted_towards(a: [f64; 2], b: [f64; 2], c: [f64; 2], shift: f64) -> Option<[[f64; 2]; 2]> {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len = (dx * dx + dy * dy).sqrt();
    if len == 0.0 {
        return None;
    }
    let mut n = [-dy / len, dx / len];
    if n[0] * (c[0] - a[0]) + n[1] * (c[1] - a[1]) < 0.0 {
        n = [-n[0], -n[1]];
    }
    Some([
        [a[0] + n[0] * shift, a[1] + n[1] * shift],
        [b[0] + n[0] * shift, b[1] + n[1] * shift],
    ])
}

/// Adds the strokes of digit `ch` as a seven-segment figure of size `w × h`
/// with its top-left corner at `(x, y)`.
fn seven_segment(pb: &mut PathBuilder, ch: char, x: f32, y: f32, w: f32, h: f32) {
    // Segments a..g: top, top right, bottom right, bottom, bottom left, top left, middle.
    const ON: [u8; 10] = [
        0b0111111, 0b0000110, 0b1011011, 0b1001111, 0b1100110, 0b1101101, 0b1111101, 0b0000111,
        0b1111111, 0b1101111,
    ];
    let Some(d) = ch.to_digit(10) else { return };
    let m = h / 2.0;
    let ends = [
        ((0.0, 0.0), (w, 0.0)),
        ((w, 0.0), (w, m)),
        ((w, m), (w, h)),
        ((0.0, h), (w, h)),
        ((0.0, m), (0.0, h)),
        ((0.0, 0.0), (0.0, m)),
        ((0.0, m), (w, m)),
    ];
    for (bit, ((x0, y0), (x1, y1))) in ends.iter().enumerate() {
        if ON[d as usize] >> bit & 1 == 1 {
            pb.move_to(x + x0, y + y0);
            pb.line_to(x + x1, y + y1);
        }
    }
}

/// A legend swatch: phase, top-left corner and side, in output pixels.
type Swatch = (u32, f32, f32, f32);

/// A set of line segments stroked with one style.
struct Layer {
    rgb: [u8; 3],
    alpha: f32,
    /// Width in output pixels.
    width: f32,
    segments: Vec<[[f64; 2]; 2]>,
}

/// Standard base64 (RFC 4648, with padding); small enough not to justify a
/// dependency for embedding one PNG in an SVG.
fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for i in 0..4 {
            if i <= c.len() {
                out.push(A[(n >> (18 - 6 * i)) as usize & 63] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Saves `frames` as an endlessly looping animated GIF with `delay_ms`
/// between frames, atomically. All frames must have the same size (e.g.
/// [`Overlay::to_rgba_image`] of successive iterations).
pub fn save_gif(path: impl AsRef<Path>, frames: &[RgbaImage], delay_ms: u32) -> Result<()> {
    use image::codecs::gif::{GifEncoder, Repeat};
    let path = path.as_ref();
    let Some(first) = frames.first() else {
        return Err(IoError::invalid(path, "no frames"));
    };
    if let Some(i) = frames
        .iter()
        .position(|f| f.dimensions() != first.dimensions())
    {
        return Err(IoError::invalid(
            path,
            format!(
                "frame {i} is {:?}, frame 0 is {:?}",
                frames[i].dimensions(),
                first.dimensions()
            ),
        ));
    }
    write_atomic(path, |w| {
        // Speed 10 (of 1..=30) keeps colour quantisation quick with good quality.
        let mut enc = GifEncoder::new_with_speed(w, 10);
        enc.set_repeat(Repeat::Infinite)
            .map_err(std::io::Error::other)?;
        let delay = Delay::from_numer_denom_ms(delay_ms, 1);
        enc.encode_frames(
            frames
                .iter()
                .map(|f| Frame::from_parts(f.clone(), 0, 0, delay)),
        )
        .map_err(std::io::Error::other)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    type Points = Vec<[f64; 2]>;

    /// A 40 × 40 gray image and a 3 × 3-vertex mesh: phase 0 left of
    /// x = 20, phase 1 right of it.
    fn halves() -> (Image2, Points, Vec<[u32; 3]>, Vec<u32>) {
        let image = Image2::from_fn(40, 40, |_, _| 0.5);
        let points: Vec<[f64; 2]> = (0..9)
            .map(|i| [20.0 * (i % 3) as f64, 20.0 * (i / 3) as f64])
            .collect();
        let mut tris = Vec::new();
        let mut labels = Vec::new();
        for (cx, cy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let v = |dx: u32, dy: u32| (cy + dy) * 3 + cx + dx;
            tris.push([v(0, 0), v(1, 0), v(1, 1)]);
            tris.push([v(0, 0), v(1, 1), v(0, 1)]);
            labels.extend([cx, cx]);
        }
        (image, points, tris, labels)
    }

    #[test]
    fn readable_overlay_has_fills_two_coloured_interfaces_and_a_legend() {
        let (image, points, tris, labels) = halves();
        let img = Overlay::new(&image, &points, &tris, &labels)
            .readable()
            .with_mesh(false)
            .with_scale(8.0)
            .to_rgba_image();
        let px = |x: u32, y: u32| img.get_pixel(x, y).0;
        let blend = |c: [u8; 3]| c.map(|v| (0.65 * 128.0 + 0.35 * f64::from(v)).round() as i32);
        let near = |p: [u8; 4], q: [i32; 3]| (0..3).all(|k| (i32::from(p[k]) - q[k]).abs() <= 2);
        // Fills: each half is its phase's colour over the gray, translucent.
        assert!(
            near(px(80, 240), blend(phase_color(0))),
            "{:?}",
            px(80, 240)
        );
        assert!(
            near(px(240, 240), blend(phase_color(1))),
            "{:?}",
            px(240, 240)
        );
        // The interface x = 20 (output 160): phase 0's colour on its left,
        // phase 1's on its right.
        let c = |p: u32| phase_color(p);
        assert_eq!(&px(159, 200)[..3], &c(0)[..]);
        assert_eq!(&px(160, 200)[..3], &c(1)[..]);
        // The legend: a swatch per phase in the top-left corner.
        assert_eq!(&px(20, 20)[..3], &c(0)[..]);
        assert_eq!(&px(20, 44)[..3], &c(1)[..]);
    }

    #[test]
    fn a_long_thin_image_gives_a_capped_overlay() {
        let image = Image2::from_fn(50, 2000, |_, _| 0.5);
        let ov = Overlay::new(&image, &[], &[], &[]);
        let (w, h) = ov.output_size();
        assert!(w.max(h) <= 2048, "{w}x{h}");
        assert_eq!(h, 2048);
    }

    /// A 64×64 test scene: a two-disk image with a faint texture, an 8×8 grid of squares
    /// split into triangles, labelled 1/2 inside the disks and 0 outside.
    type Scene = (Image2, Vec<[f64; 2]>, Vec<[u32; 3]>, Vec<u32>);

    fn scene() -> Scene {
        let disk = |x: f64, y: f64| -> u32 {
            if (x - 26.0).hypot(y - 30.0) < 16.0 {
                1
            } else if (x - 48.0).hypot(y - 46.0) < 10.0 {
                2
            } else {
                0
            }
        };
        let image = Image2::from_fn(64, 64, |x, y| {
            [0.2, 0.55, 0.85][disk(x as f64 + 0.5, y as f64 + 0.5) as usize]
                + 0.05 * (((x * 7 + y * 13) % 5) as f32 / 5.0)
        });
        let n = 16; // cells per side
        let h = 64.0 / n as f64;
        let mut points = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                points.push([i as f64 * h, j as f64 * h]);
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let (mut tris, mut labels) = (Vec::new(), Vec::new());
        for j in 0..n {
            for i in 0..n {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                for t in [[a, b, c], [a, c, d]] {
                    let cx = t.iter().map(|&v| points[v as usize][0]).sum::<f64>() / 3.0;
                    let cy = t.iter().map(|&v| points[v as usize][1]).sum::<f64>() / 3.0;
                    tris.push(t);
                    labels.push(disk(cx, cy));
                }
            }
        }
        (image, points, tris, labels)
    }

    #[test]
    fn base64_matches_rfc4648() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
    }

    #[test]
    fn interfaces_between_different_labels_only() {
        // Two triangles sharing edge (1,2), plus a third sharing (2,3) with the same label.
        let tris = [[0, 1, 2], [1, 3, 2], [2, 3, 4]];
        let e = interface_edges(&tris, &[0, 1, 1]);
        assert_eq!(
            e,
            vec![InterfaceEdge {
                vertices: [1, 2],
                phases: [0, 1]
            }]
        );
        assert!(interface_edges(&tris, &[3, 3, 3]).is_empty());
    }

    #[test]
    fn overlay_png_svg_gif() {
        let (image, points, tris, labels) = scene();
        let ov = Overlay::new(&image, &points, &tris, &labels);
        assert_eq!(ov.output_size(), (768, 768));
        let rgba = ov.to_rgba_image();
        // Far from any line: the plain gray background pixel.
        let bg = rgba.get_pixel(3, 3).0;
        assert_eq!(bg[0], bg[1]);
        assert_eq!(bg[3], 255);
        // The vertical interface of disk 1 at x = 12 (grid line) must be
        // somewhere in phase 1's colour along row y = 30 (output 360).
        let c1 = phase_color(1);
        let hit = (0..768).any(|x| {
            let p = rgba.get_pixel(x, 30 * 12 + 6).0;
            p[..3] == c1
        });
        assert!(hit, "no interface pixel in phase 1's colour");

        let keep = std::env::var_os("DSC_SEG_RENDER_OUT").map(std::path::PathBuf::from);
        let tmp = tempfile::tempdir().unwrap();
        let dir = keep.as_deref().unwrap_or(tmp.path());
        let png = dir.join("overlay.png");
        ov.to_png(&png).unwrap();
        let back = image::open(&png).unwrap().to_rgba8();
        assert_eq!(back, rgba);
        let svg = dir.join("overlay.svg");
        ov.to_svg(&svg).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.contains("data:image/png;base64,iVBORw0KGgo"));
        assert!(text.contains("stroke=\"#d55e00\""));
        let frames = [
            ov.with_mesh(false).to_rgba_image(),
            ov.with_scale(12.0).to_rgba_image(),
        ];
        let gif = dir.join("anim.gif");
        save_gif(&gif, &frames, 200).unwrap();
        use image::AnimationDecoder;
        let dec = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(
            std::fs::File::open(&gif).unwrap(),
        ))
        .unwrap();
        let decoded = dec.into_frames().collect_frames().unwrap();
        assert_eq!(decoded.len(), 2);
        assert_eq!(decoded[0].buffer().dimensions(), (768, 768));
        assert_eq!(decoded[1].delay().numer_denom_ms(), (200, 1));
    }

    #[test]
    fn invalid_overlays_are_errors() {
        let (image, points, tris, labels) = scene();
        let dir = tempfile::tempdir().unwrap();
        let short = &labels[1..];
        let e = Overlay::new(&image, &points, &tris, short)
            .to_png(dir.path().join("x.png"))
            .unwrap_err();
        assert!(e.to_string().contains("x.png"));
        assert!(save_gif(dir.path().join("a.gif"), &[], 10).is_err());
        let frames = [RgbaImage::new(2, 2), RgbaImage::new(3, 2)];
        assert!(save_gif(dir.path().join("a.gif"), &frames, 10).is_err());
    }
}
