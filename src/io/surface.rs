//! Readers for triangle surfaces in OFF, OBJ and STL (ASCII and binary).
//!
//! All readers return a [`TriangleSurface`]: a list of points and a list of
//! triangles indexing into it (zero-based). Polygonal faces (OFF, OBJ) are
//! fan-triangulated around their first vertex. STL stores every triangle
//! with its own three vertices; the STL reader merges vertices with exactly
//! identical coordinates (`-0.0` and `0.0` are treated as equal), so that the
//! result is an indexed mesh. OFF and OBJ points are taken as they are.
//!
//! The readers only parse: they do not check that the surface is closed,
//! manifold or free of degenerate triangles. Non-finite coordinates and
//! out-of-range indices are rejected.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A triangle surface: points and zero-based triangle indices into them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleSurface {
    /// Vertex coordinates.
    pub points: Vec<[f64; 3]>,
    /// Triangles as indices into [`TriangleSurface::points`].
    pub triangles: Vec<[u32; 3]>,
}

/// The surface file formats understood by [`read_surface`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SurfaceFormat {
    /// Object File Format (`.off`).
    Off,
    /// Wavefront OBJ (`.obj`): only `v` and `f` lines are used.
    Obj,
    /// STL (`.stl`), ASCII or binary (detected from the content).
    Stl,
}

impl SurfaceFormat {
    /// Guesses the format from a file extension (case-insensitive).
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "off" => Some(SurfaceFormat::Off),
            "obj" => Some(SurfaceFormat::Obj),
            "stl" => Some(SurfaceFormat::Stl),
            _ => None,
        }
    }

    /// Short upper-case name used in error messages.
    pub fn name(self) -> &'static str {
        match self {
            SurfaceFormat::Off => "OFF",
            SurfaceFormat::Obj => "OBJ",
            SurfaceFormat::Stl => "STL",
        }
    }
}

/// Errors from reading a surface file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SurfaceError {
    /// The file could not be read.
    #[error("cannot read surface file {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file extension is not one of `.off`, `.obj`, `.stl`.
    #[error("cannot tell the surface format of {path}: expected a .off, .obj or .stl file")]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// A text format file is not valid UTF-8.
    #[error("{format} file is not valid UTF-8 text")]
    NotText {
        /// Format name.
        format: &'static str,
    },
    /// A line of a text file is malformed.
    #[error("{format} line {line}: {message}")]
    Parse {
        /// Format name.
        format: &'static str,
        /// One-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The file is malformed as a whole (e.g. truncated or wrong counts).
    #[error("malformed {format} file: {message}")]
    Malformed {
        /// Format name.
        format: &'static str,
        /// What is wrong.
        message: String,
    },
    /// An error while parsing the named file.
    #[error("{}: {source}", path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// The parse error.
        #[source]
        source: Box<SurfaceError>,
    },
}

/// Reads a surface file, choosing the format from its extension.
///
/// # Errors
///
/// [`SurfaceError::Io`] if the file cannot be read,
/// [`SurfaceError::UnknownFormat`] for an unknown extension, and otherwise a
/// parse error wrapped in [`SurfaceError::InFile`].
pub fn read_surface(path: impl AsRef<Path>) -> Result<TriangleSurface, SurfaceError> {
    let path = path.as_ref();
    let format = SurfaceFormat::from_path(path).ok_or_else(|| SurfaceError::UnknownFormat {
        path: path.to_path_buf(),
    })?;
    let bytes = std::fs::read(path).map_err(|source| SurfaceError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_surface(&bytes, format).map_err(|e| SurfaceError::InFile {
        path: path.to_path_buf(),
        source: Box::new(e),
    })
}

/// Parses surface file contents in the given format.
///
/// # Errors
///
/// A [`SurfaceError`] describing the first problem found.
pub fn parse_surface(bytes: &[u8], format: SurfaceFormat) -> Result<TriangleSurface, SurfaceError> {
    let text = |format: SurfaceFormat| {
        std::str::from_utf8(bytes).map_err(|_| SurfaceError::NotText {
            format: format.name(),
        })
    };
    match format {
        SurfaceFormat::Off => parse_off(text(format)?),
        SurfaceFormat::Obj => parse_obj(text(format)?),
        SurfaceFormat::Stl => parse_stl(bytes),
    }
}

fn parse_error(format: &'static str, line: usize, message: impl Into<String>) -> SurfaceError {
    SurfaceError::Parse {
        format,
        line,
        message: message.into(),
    }
}

/// Parses a finite coordinate.
fn coordinate(format: &'static str, line: usize, token: Option<&str>) -> Result<f64, SurfaceError> {
    let token = token.ok_or_else(|| parse_error(format, line, "expected 3 coordinates"))?;
    let x: f64 = token
        .parse()
        .map_err(|_| parse_error(format, line, format!("invalid coordinate {token:?}")))?;
    if !x.is_finite() {
        return Err(parse_error(
            format,
            line,
            format!("non-finite coordinate {token:?}"),
        ));
    }
    Ok(x)
}

fn point3<'a>(
    format: &'static str,
    line: usize,
    tokens: &mut impl Iterator<Item = &'a str>,
) -> Result<[f64; 3], SurfaceError> {
    Ok([
        coordinate(format, line, tokens.next())?,
        coordinate(format, line, tokens.next())?,
        coordinate(format, line, tokens.next())?,
    ])
}

/// Converts a point count to a `u32` index limit.
fn check_point_count(format: &'static str, n: usize) -> Result<(), SurfaceError> {
    if n > u32::MAX as usize {
        return Err(SurfaceError::Malformed {
            format,
            message: format!("{n} points exceed the u32 index range"),
        });
    }
    Ok(())
}

/// Appends the fan triangulation of a polygon.
fn fan(polygon: &[u32], triangles: &mut Vec<[u32; 3]>) {
    for k in 1..polygon.len() - 1 {
        triangles.push([polygon[0], polygon[k], polygon[k + 1]]);
    }
}

/// Parses an OFF file.
///
/// Accepts the `OFF` header (also `COFF`, `NOFF`, `CNOFF`, `STOFF`, … whose
/// extra per-vertex values are ignored) or no header, the counts on the
/// header line or the next one, `#` comments and blank lines, and faces with
/// three or more zero-based vertex indices (extra values such as colours
/// after the indices are ignored).
///
/// # Errors
///
/// [`SurfaceError::Parse`] or [`SurfaceError::Malformed`] for malformed
/// content.
pub fn parse_off(text: &str) -> Result<TriangleSurface, SurfaceError> {
    const F: &str = "OFF";
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.split('#').next().unwrap_or("").trim()))
        .filter(|(_, l)| !l.is_empty());
    let truncated = |what: &str| SurfaceError::Malformed {
        format: F,
        message: format!("file ends before {what}"),
    };

    let (mut line, first) = lines.next().ok_or_else(|| truncated("the header"))?;
    let mut tokens: Vec<&str> = first.split_whitespace().collect();
    if let Some(header) = tokens.first().filter(|t| t.ends_with("OFF")) {
        let prefix = &header[..header.len() - 3];
        if !prefix.chars().all(|c| matches!(c, 'S' | 'T' | 'C' | 'N')) {
            return Err(parse_error(
                F,
                line,
                format!("unsupported OFF variant {header:?} (only 3-D OFF is supported)"),
            ));
        }
        tokens.remove(0);
        if tokens.is_empty() {
            let (l, next) = lines.next().ok_or_else(|| truncated("the counts line"))?;
            line = l;
            tokens = next.split_whitespace().collect();
        }
    }
    if tokens.len() < 2 {
        return Err(parse_error(
            F,
            line,
            "expected the counts: <vertices> <faces> [<edges>]",
        ));
    }
    let count = |t: &str, what: &str| {
        t.parse::<usize>()
            .map_err(|_| parse_error(F, line, format!("invalid {what} count {t:?}")))
    };
    let num_points = count(tokens[0], "vertex")?;
    let num_faces = count(tokens[1], "face")?;
    check_point_count(F, num_points)?;

    let mut surface = TriangleSurface::default();
    for _ in 0..num_points {
        let (line, l) = lines
            .next()
            .ok_or_else(|| truncated(&format!("all {num_points} vertices were read")))?;
        surface
            .points
            .push(point3(F, line, &mut l.split_whitespace())?);
    }
    let mut polygon = Vec::new();
    for _ in 0..num_faces {
        let (line, l) = lines
            .next()
            .ok_or_else(|| truncated(&format!("all {num_faces} faces were read")))?;
        let mut tokens = l.split_whitespace();
        let n: usize = tokens
            .next()
            .and_then(|t| t.parse().ok())
            .ok_or_else(|| parse_error(F, line, "expected a face: <n> <i1> ... <in>"))?;
        if n < 3 {
            return Err(parse_error(
                F,
                line,
                format!("face has {n} vertices, need at least 3"),
            ));
        }
        polygon.clear();
        for _ in 0..n {
            let t = tokens
                .next()
                .ok_or_else(|| parse_error(F, line, format!("face has fewer than {n} indices")))?;
            let i: usize = t
                .parse()
                .map_err(|_| parse_error(F, line, format!("invalid vertex index {t:?}")))?;
            if i >= num_points {
                return Err(parse_error(
                    F,
                    line,
                    format!("vertex index {i} out of range (there are {num_points} vertices)"),
                ));
            }
            polygon.push(i as u32);
        }
        fan(&polygon, &mut surface.triangles);
    }
    Ok(surface)
}

/// Parses a Wavefront OBJ file.
///
/// Uses `v x y z` lines (extra values such as `w` or colours are ignored) and
/// `f` lines with three or more vertex references, each written `i`, `i/t`,
/// `i//n` or `i/t/n`; indices are one-based, negative ones count back from
/// the most recent vertex. All other statements (`vn`, `vt`, `g`, `usemtl`,
/// …) are ignored.
///
/// # Errors
///
/// [`SurfaceError::Parse`] for malformed `v`/`f` lines or out-of-range
/// indices.
pub fn parse_obj(text: &str) -> Result<TriangleSurface, SurfaceError> {
    const F: &str = "OBJ";
    let mut surface = TriangleSurface::default();
    // Faces with their line numbers; positive indices may refer to vertices
    // defined later, so ranges are checked at the end.
    let mut faces: Vec<(usize, [i64; 3])> = Vec::new();
    let mut polygon: Vec<i64> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let content = raw.split('#').next().unwrap_or("");
        let mut tokens = content.split_whitespace();
        match tokens.next() {
            Some("v") => {
                surface.points.push(point3(F, line, &mut tokens)?);
            }
            Some("f") => {
                polygon.clear();
                for t in tokens {
                    let index = t.split('/').next().unwrap_or("");
                    let k: i64 = index.parse().map_err(|_| {
                        parse_error(F, line, format!("invalid vertex reference {t:?}"))
                    })?;
                    let k = match k {
                        0 => {
                            return Err(parse_error(
                                F,
                                line,
                                "vertex index 0 (OBJ indices start at 1)",
                            ))
                        }
                        k if k > 0 => k - 1,
                        k => {
                            let abs = surface.points.len() as i64 + k;
                            if abs < 0 {
                                return Err(parse_error(
                                    F,
                                    line,
                                    format!(
                                        "relative vertex index {k} points before the first vertex"
                                    ),
                                ));
                            }
                            abs
                        }
                    };
                    polygon.push(k);
                }
                if polygon.len() < 3 {
                    return Err(parse_error(
                        F,
                        line,
                        format!("face has {} vertices, need at least 3", polygon.len()),
                    ));
                }
                for k in 1..polygon.len() - 1 {
                    faces.push((line, [polygon[0], polygon[k], polygon[k + 1]]));
                }
            }
            _ => {}
        }
    }
    let n = surface.points.len();
    check_point_count(F, n)?;
    for (line, face) in faces {
        let mut tri = [0u32; 3];
        for (slot, &k) in tri.iter_mut().zip(&face) {
            if k as usize >= n {
                return Err(parse_error(
                    F,
                    line,
                    format!(
                        "vertex index {} out of range (there are {n} vertices)",
                        k + 1
                    ),
                ));
            }
            *slot = k as u32;
        }
        surface.triangles.push(tri);
    }
    Ok(surface)
}

/// Builds an indexed surface from triangle soup, merging exactly equal
/// vertices.
#[derive(Default)]
struct Merger {
    surface: TriangleSurface,
    index: HashMap<[u64; 3], u32>,
}

impl Merger {
    fn vertex(&mut self, p: [f64; 3]) -> Result<u32, SurfaceError> {
        // `+ 0.0` maps -0.0 to +0.0, so both merge.
        let key = p.map(|x| (x + 0.0).to_bits());
        if let Some(&i) = self.index.get(&key) {
            return Ok(i);
        }
        let i = u32::try_from(self.surface.points.len()).map_err(|_| SurfaceError::Malformed {
            format: "STL",
            message: "too many distinct vertices for u32 indices".into(),
        })?;
        self.surface.points.push(p);
        self.index.insert(key, i);
        Ok(i)
    }
}

/// Parses an STL file, ASCII or binary, merging exactly equal vertices.
///
/// A file whose size is `84 + 50 n`, where `n` is the little-endian triangle
/// count at byte 80, is read as binary (even if its header starts with
/// `solid`, as many binary files do); otherwise a file starting with `solid`
/// is read as ASCII. Normals and attribute bytes are ignored.
///
/// # Errors
///
/// [`SurfaceError::Parse`] for malformed ASCII content,
/// [`SurfaceError::Malformed`] for a truncated binary file or non-finite
/// coordinates.
pub fn parse_stl(bytes: &[u8]) -> Result<TriangleSurface, SurfaceError> {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        if 84 + 50 * n == bytes.len() as u64 {
            return parse_binary_stl(bytes);
        }
    }
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(bytes.len());
    if bytes[start..].starts_with(b"solid") {
        let text =
            std::str::from_utf8(bytes).map_err(|_| SurfaceError::NotText { format: "STL" })?;
        return parse_ascii_stl(text);
    }
    if bytes.len() < 84 {
        return Err(SurfaceError::Malformed {
            format: "STL",
            message: format!(
                "{} bytes is too short for binary STL and the file does not start with \"solid\"",
                bytes.len()
            ),
        });
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
    Err(SurfaceError::Malformed {
        format: "STL",
        message: format!(
            "binary STL declares {n} triangles ({} bytes expected) but the file has {} bytes",
            84 + 50 * n,
            bytes.len()
        ),
    })
}

fn parse_binary_stl(bytes: &[u8]) -> Result<TriangleSurface, SurfaceError> {
    let mut merger = Merger::default();
    for (t, record) in bytes[84..].chunks_exact(50).enumerate() {
        let f = |k: usize| {
            let o = 12 + 4 * k; // skip the normal
            f64::from(f32::from_le_bytes([
                record[o],
                record[o + 1],
                record[o + 2],
                record[o + 3],
            ]))
        };
        let mut tri = [0u32; 3];
        for (v, slot) in tri.iter_mut().enumerate() {
            let p = [f(3 * v), f(3 * v + 1), f(3 * v + 2)];
            if !p.iter().all(|x| x.is_finite()) {
                return Err(SurfaceError::Malformed {
                    format: "STL",
                    message: format!("triangle {t} has a non-finite coordinate"),
                });
            }
            *slot = merger.vertex(p)?;
        }
        merger.surface.triangles.push(tri);
    }
    Ok(merger.surface)
}

fn parse_ascii_stl(text: &str) -> Result<TriangleSurface, SurfaceError> {
    const F: &str = "STL";
    let mut merger = Merger::default();
    let mut polygon: Vec<u32> = Vec::new();
    let mut in_loop = false;
    let mut loop_line = 0;
    let mut last_line = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        last_line = line;
        let mut tokens = raw.split_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        match keyword {
            "solid" | "endsolid" | "facet" => {}
            "endfacet" => {
                if in_loop {
                    return Err(parse_error(F, line, "\"endfacet\" before \"endloop\""));
                }
            }
            "outer" => {
                if tokens.next() != Some("loop") {
                    return Err(parse_error(F, line, "expected \"outer loop\""));
                }
                if in_loop {
                    return Err(parse_error(F, line, "\"outer loop\" inside another loop"));
                }
                in_loop = true;
                loop_line = line;
                polygon.clear();
            }
            "vertex" => {
                if !in_loop {
                    return Err(parse_error(F, line, "\"vertex\" outside \"outer loop\""));
                }
                let p = point3(F, line, &mut tokens)?;
                polygon.push(merger.vertex(p)?);
            }
            "endloop" => {
                if !in_loop {
                    return Err(parse_error(F, line, "\"endloop\" without \"outer loop\""));
                }
                if polygon.len() < 3 {
                    return Err(parse_error(
                        F,
                        line,
                        format!("loop has {} vertices, need at least 3", polygon.len()),
                    ));
                }
                fan(&polygon, &mut merger.surface.triangles);
                in_loop = false;
            }
            other => {
                return Err(parse_error(
                    F,
                    line,
                    format!("unexpected keyword {other:?}"),
                ));
            }
        }
    }
    if in_loop {
        return Err(parse_error(
            F,
            last_line,
            format!("file ends inside the loop opened on line {loop_line}"),
        ));
    }
    Ok(merger.surface)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tetrahedron's 4 points and 4 faces.
    fn tet() -> TriangleSurface {
        TriangleSurface {
            points: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

    #[test]
    fn off_tetrahedron_and_quad() {
        let text = "OFF\n# a comment\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n\
                    3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3 255 0 0\n";
        assert_eq!(parse_off(text).unwrap(), tet());

        // Counts on the header line, a quad face, no trailing newline.
        let text = "OFF 4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3";
        let s = parse_off(text).unwrap();
        assert_eq!(s.triangles, vec![[0, 1, 2], [0, 2, 3]]);

        // No header, COFF colours ignored.
        let s = parse_off("3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
        assert_eq!(s.triangles, vec![[0, 1, 2]]);
        let s = parse_off("COFF\n3 1 0\n0 0 0 1 1 1 1\n1 0 0 1 1 1 1\n0 1 0 1 1 1 1\n3 0 1 2\n")
            .unwrap();
        assert_eq!(s.points[1], [1.0, 0.0, 0.0]);
    }

    #[test]
    fn off_errors() {
        let msg = |t: &str| parse_off(t).unwrap_err().to_string();
        assert!(msg("").contains("file ends before the header"));
        assert!(msg("OFF\n3 1 0\n0 0 0\n1 0 0\n").contains("vertices"));
        assert!(msg("OFF\n3 1 0\n0 0 0\n1 0 x\n0 1 0\n3 0 1 2\n").contains("line 4"));
        assert!(msg("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").contains("out of range"));
        assert!(msg("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n").contains("at least 3"));
        assert!(msg("OFF\n3 1 0\n0 0 0\n1 0 nan\n0 1 0\n3 0 1 2\n").contains("non-finite"));
        assert!(msg("4OFF\n1 0 0\n0 0 0 0\n").contains("unsupported"));
        assert!(msg("OFF\nthree 1 0\n").contains("invalid vertex count"));
    }

    #[test]
    fn obj_with_index_syntax_and_polygons() {
        let text = "# tet\nmtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1 1.0\n\
                    vn 0 0 1\nvt 0 0\ng tet\ns off\n\
                    f 1 3 2\nf 1/1 2/1 4/1\nf 1//1 4//1 3//1\nf -3/1/1 -2/1/1 -1/1/1\n";
        assert_eq!(parse_obj(text).unwrap(), tet());

        let s = parse_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\nf 1 2 3 4 5\n").unwrap();
        assert_eq!(s.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    }

    #[test]
    fn obj_errors() {
        let msg = |t: &str| parse_obj(t).unwrap_err().to_string();
        assert!(msg("v 0 0\n").contains("OBJ line 1: expected 3 coordinates"));
        assert!(msg("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").contains("line 4"));
        assert!(msg("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n").contains("start at 1"));
        assert!(msg("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n").contains("before the first"));
        assert!(msg("v 0 0 0\nv 1 0 0\nf 1 2\n").contains("at least 3"));
        assert!(msg("v 0 0 0\nf a b c\n").contains("invalid vertex reference"));
    }

    const ASCII_STL: &str = "solid tet\n\
        facet normal 0 0 -1\n outer loop\n  vertex 0 0 0\n  vertex 0 1 0\n  vertex 1 0 0\n endloop\nendfacet\n\
        facet normal 0 -1 0\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 0 1\n endloop\nendfacet\n\
        facet normal -1 0 0\n outer loop\n  vertex -0 0 0\n  vertex 0 0 1\n  vertex 0 1 0\n endloop\nendfacet\n\
        facet normal 1 1 1\n outer loop\n  vertex 1 0 0\n  vertex 0 1 0\n  vertex 0 0 1\n endloop\nendfacet\n\
        endsolid tet\n";

    fn binary_stl(surface: &TriangleSurface, header: &[u8]) -> Vec<u8> {
        let mut bytes = vec![0u8; 80];
        bytes[..header.len()].copy_from_slice(header);
        bytes.extend((surface.triangles.len() as u32).to_le_bytes());
        for t in &surface.triangles {
            bytes.extend([0u8; 12]);
            for &i in t {
                for x in surface.points[i as usize] {
                    bytes.extend((x as f32).to_le_bytes());
                }
            }
            bytes.extend([0u8; 2]);
        }
        bytes
    }

    /// Same triangles as coordinates, and no unmerged duplicate points.
    fn assert_same_geometry(a: &TriangleSurface, b: &TriangleSurface) {
        let coords = |s: &TriangleSurface| -> Vec<[[f64; 3]; 3]> {
            s.triangles
                .iter()
                .map(|t| t.map(|i| s.points[i as usize]))
                .collect()
        };
        assert_eq!(coords(a), coords(b));
        assert_eq!(a.points.len(), b.points.len());
    }

    #[test]
    fn ascii_stl_merges_vertices() {
        let s = parse_stl(ASCII_STL.as_bytes()).unwrap();
        assert_same_geometry(&s, &tet());
        assert_eq!(s.points[0], [0.0, 0.0, 0.0]);
        // Surrounding whitespace and several solids are fine.
        let two = format!("  \n{ASCII_STL}{ASCII_STL}");
        let s = parse_stl(two.as_bytes()).unwrap();
        assert_eq!((s.points.len(), s.triangles.len()), (4, 8));
    }

    #[test]
    fn binary_stl_merges_vertices() {
        let bytes = binary_stl(&tet(), b"binary");
        assert_eq!(bytes.len(), 84 + 4 * 50);
        assert_same_geometry(&parse_stl(&bytes).unwrap(), &tet());
        // A binary header starting with "solid" is still read as binary.
        let bytes = binary_stl(&tet(), b"solid but binary");
        assert_same_geometry(&parse_stl(&bytes).unwrap(), &tet());
    }

    #[test]
    fn stl_errors() {
        let msg = |b: &[u8]| parse_stl(b).unwrap_err().to_string();
        let mut truncated = binary_stl(&tet(), b"binary");
        truncated.pop();
        assert!(msg(&truncated).contains("declares 4 triangles"));
        assert!(msg(b"garbage").contains("too short"));
        let bad = ASCII_STL.replace("vertex 0 0 1\n endloop", "vertex 0 0\n endloop");
        assert!(msg(bad.as_bytes()).contains("expected 3 coordinates"));
        let open = ASCII_STL.replace(" endloop\nendfacet\nendsolid", "endfacet\nendsolid");
        assert!(msg(open.as_bytes()).contains("line 28: \"endfacet\" before \"endloop\""));
        let unterminated = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n";
        assert!(msg(unterminated.as_bytes()).contains("file ends inside the loop"));
        let mut nan = binary_stl(&tet(), b"binary");
        nan[84 + 12..84 + 16].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(msg(&nan).contains("non-finite"));
    }

    #[test]
    fn read_surface_from_files() {
        let dir = tempfile::tempdir().unwrap();
        let off = dir.path().join("tet.OFF");
        std::fs::write(
            &off,
            "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
        )
        .unwrap();
        assert_eq!(read_surface(&off).unwrap(), tet());
        let stl = dir.path().join("tet.stl");
        std::fs::write(&stl, binary_stl(&tet(), b"")).unwrap();
        assert_same_geometry(&read_surface(&stl).unwrap(), &tet());

        let err = read_surface(dir.path().join("missing.obj")).unwrap_err();
        assert!(matches!(err, SurfaceError::Io { .. }), "{err}");
        let err = read_surface(dir.path().join("tet.ply")).unwrap_err();
        assert!(matches!(err, SurfaceError::UnknownFormat { .. }), "{err}");
        let bad = dir.path().join("bad.obj");
        std::fs::write(&bad, "v 0 0 0\nf 1 1\n").unwrap();
        let err = read_surface(&bad).unwrap_err().to_string();
        assert!(
            err.contains("bad.obj") && err.contains("OBJ line 2"),
            "{err}"
        );
        let binary = dir.path().join("binary.off");
        std::fs::write(&binary, [0xffu8, 0xfe, 0x00]).unwrap();
        assert!(read_surface(&binary)
            .unwrap_err()
            .to_string()
            .contains("UTF-8"));
    }
}
