//! Minimal bindings and a small safe wrapper for the system TetGen 1.5 library.
//!
//! # Licence warning
//!
//! The code in this crate is MIT OR Apache-2.0, but it links against TetGen
//! (`libtet`), which is licensed under the **AGPL-3.0**. Any binary that
//! enables this crate is therefore subject to the AGPL. In `dsc-seg` it is only
//! pulled in by the opt-in `tetgen` cargo feature, which is off by default.
//!
//! # System requirements
//!
//! Debian/Ubuntu: `apt-get install libtet1.5-dev`, which provides
//! `/usr/include/tetgen.h` and `/usr/lib/<triple>/libtet.so`. The build script
//! honours `TETGEN_INCLUDE_DIR` and `TETGEN_LIB_DIR` for other locations.
//!
//! # Usage
//!
//! Describe a closed, non-self-intersecting triangle surface as a [`Plc`] and
//! call [`tetrahedralize`]:
//!
//! ```no_run
//! use tetgen_sys::{tetrahedralize, Plc, Switches};
//! # fn cube() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) { unimplemented!() }
//! let (points, triangles) = cube();
//! let plc = Plc { points, triangles, regions: Vec::new() };
//! let switches = Switches { quality: Some(1.5), ..Switches::default() };
//! let mesh = tetrahedralize(&plc, &switches)?;
//! println!("{} tets", mesh.tets.len());
//! # Ok::<(), tetgen_sys::TetgenError>(())
//! ```
//!
//! # Safety of the wrapper
//!
//! TetGen signals errors by throwing C++ `int`s, which the C++ shim catches and
//! turns into [`TetgenError::Tetgen`]. However, Debian's TetGen 1.5.0 can also
//! crash (segfault) or loop on bad input such as self-intersecting surfaces,
//! so [`tetrahedralize`] first validates the input (see [`validate_plc`]) and
//! refuses to call TetGen on anything that is not a clean closed 2-manifold
//! surface.
//!
//! # Orientation convention
//!
//! Every tetrahedron `[a, b, c, d]` of a returned [`TetMesh`] is *positively
//! oriented* in the right-handed sense: the signed volume
//! `(b - a) · ((c - a) × (d - a)) / 6` is strictly positive, i.e. `d` lies on
//! the side of the plane `abc` from which `a, b, c` appear counter-clockwise.
//! Note that this is the **opposite** sign of Shewchuk's `orient3d` (and of the
//! `robust` crate's [`robust::orient3d`]), which is positive when `d` lies
//! *below* `abc`: for every returned tet, `robust::orient3d(a, b, c, d) < 0`.
//! Debian's TetGen 1.5.0 already emits tetrahedra in this right-handed
//! orientation; the wrapper nevertheless checks every tet with the exact
//! predicate and swaps two corners of any tet with the opposite orientation,
//! so the guarantee does not depend on TetGen's convention.
#![warn(missing_docs)]

mod ffi;
mod validate;

use std::fmt::Write as _;

pub use validate::validate_plc;

/// A region (subdomain) seed: marks the connected component of the domain
/// containing `seed` with `attribute` and, optionally, a volume bound.
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    /// A point strictly inside the region (not on the surface).
    pub seed: [f64; 3],
    /// Attribute assigned to every tetrahedron of the region (needs
    /// [`Switches::region_attributes`] to be reported).
    pub attribute: i32,
    /// Maximum tetrahedron volume inside this region. Enables TetGen's
    /// regional volume constraint (`-a` without a number, which also needs
    /// `-A`; the wrapper adds both and drops the attributes again unless
    /// [`Switches::region_attributes`] is set).
    pub max_volume: Option<f64>,
}

/// A piecewise linear complex given as a closed triangle surface.
///
/// The surface may have several components (e.g. nested shells bounding
/// different regions), but as a whole it must be a closed, edge-manifold,
/// non-self-intersecting triangle surface without unused or duplicate points;
/// see [`validate_plc`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Plc {
    /// Vertex coordinates.
    pub points: Vec<[f64; 3]>,
    /// Triangles as zero-based indices into [`Plc::points`]. Their orientation
    /// does not matter.
    pub triangles: Vec<[u32; 3]>,
    /// Region seeds.
    pub regions: Vec<Region>,
}

/// TetGen command-line switches, built into a switch string by
/// [`Switches::to_switch_string`]. `-p` (tetrahedralise a PLC) and `-z`
/// (zero-based indices) are always set.
#[derive(Clone, Debug, PartialEq)]
pub struct Switches {
    /// Quality mesh with this maximum radius-edge ratio (`-q`). Must be at
    /// least 1.0; TetGen's default is 2.0, and values close to 1.0 may make it
    /// run for a very long time.
    pub quality: Option<f64>,
    /// Minimum dihedral angle in degrees for the quality mesh (`-q<r>/<a>`);
    /// only used together with [`Switches::quality`]. Must be in `[0, 70)`.
    pub min_dihedral_angle: Option<f64>,
    /// Global maximum tetrahedron volume (`-a<v>`).
    pub max_volume: Option<f64>,
    /// Report the region attributes of the tetrahedra (`-A`). Subdomains
    /// without a [`Region`] seed get attributes numbered by TetGen: `1, 2, …`
    /// without any seeds; with seeds, an unseeded subdomain was observed to
    /// get one more than the largest given attribute.
    pub region_attributes: bool,
    /// Do not insert Steiner points on the boundary surface (`-Y`), so the
    /// boundary triangles of the mesh are exactly the input triangles.
    pub preserve_surface: bool,
    /// Upper bound on the number of Steiner points TetGen may add (`-S`).
    pub max_steiner_points: Option<u32>,
    /// Suppress TetGen's console output (`-Q`). On by default.
    pub quiet: bool,
}

impl Default for Switches {
    /// No quality or volume constraints, no attributes, quiet.
    fn default() -> Self {
        Switches {
            quality: None,
            min_dihedral_angle: None,
            max_volume: None,
            region_attributes: false,
            preserve_surface: false,
            max_steiner_points: None,
            quiet: true,
        }
    }
}

impl Switches {
    /// Builds the TetGen switch string (without a leading `-`).
    ///
    /// `regional_volumes` adds a bare `a` and forces `A`, enabling the
    /// per-region [`Region::max_volume`] constraints (TetGen 1.5 ignores the
    /// region list without `A`). Numbers are written in plain decimal
    /// notation, as TetGen's parser does not accept exponents.
    ///
    /// # Errors
    ///
    /// [`TetgenError::InvalidSwitch`] if a parameter is out of range.
    pub fn to_switch_string(&self, regional_volumes: bool) -> Result<String, TetgenError> {
        let mut s = String::from("pz");
        if let Some(q) = self.quality {
            if !(q.is_finite() && q >= 1.0) {
                return Err(TetgenError::InvalidSwitch(format!(
                    "radius-edge ratio must be a finite number >= 1.0, got {q}"
                )));
            }
            write!(s, "q{}", decimal(q)).expect("writing to a String");
            if let Some(angle) = self.min_dihedral_angle {
                if !(angle.is_finite() && (0.0..70.0).contains(&angle)) {
                    return Err(TetgenError::InvalidSwitch(format!(
                        "minimum dihedral angle must be in [0, 70) degrees, got {angle}"
                    )));
                }
                write!(s, "/{}", decimal(angle)).expect("writing to a String");
            }
        } else if self.min_dihedral_angle.is_some() {
            return Err(TetgenError::InvalidSwitch(
                "a minimum dihedral angle needs a radius-edge ratio (quality)".into(),
            ));
        }
        if regional_volumes {
            s.push('a');
        }
        if let Some(v) = self.max_volume {
            check_volume(v).map_err(TetgenError::InvalidSwitch)?;
            write!(s, "a{}", decimal(v)).expect("writing to a String");
        }
        if self.region_attributes || regional_volumes {
            s.push('A');
        }
        if self.preserve_surface {
            s.push('Y');
        }
        if let Some(n) = self.max_steiner_points {
            write!(s, "S{n}").expect("writing to a String");
        }
        if self.quiet {
            s.push('Q');
        }
        Ok(s)
    }
}

/// Formats a finite, non-negative float in plain decimal notation
/// (Rust's `Display` for `f64` never uses an exponent).
fn decimal(x: f64) -> String {
    format!("{x}")
}

/// Accepts volume bounds that TetGen can parse and that make sense.
fn check_volume(v: f64) -> Result<(), String> {
    if v.is_finite() && v > 0.0 && (1e-100..=1e100).contains(&v) {
        Ok(())
    } else {
        Err(format!(
            "maximum volume must be a positive number in [1e-100, 1e100], got {v}"
        ))
    }
}

/// A tetrahedral mesh produced by TetGen.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TetMesh {
    /// Vertex coordinates. The input points come first, in input order,
    /// followed by any Steiner points TetGen added.
    pub points: Vec<[f64; 3]>,
    /// Tetrahedra as indices into [`TetMesh::points`], each positively
    /// oriented in the right-handed sense (see the crate docs).
    pub tets: Vec<[u32; 4]>,
    /// One region attribute per tetrahedron when
    /// [`Switches::region_attributes`] was set, otherwise empty.
    pub tet_attributes: Vec<i32>,
}

impl TetMesh {
    /// Signed volume of tetrahedron `t`, `(b - a) · ((c - a) × (d - a)) / 6`
    /// (positive for every tetrahedron of a mesh returned by
    /// [`tetrahedralize`]).
    pub fn tet_volume(&self, t: usize) -> f64 {
        let [a, b, c, d] = self.tets[t].map(|i| self.points[i as usize]);
        signed_volume(a, b, c, d)
    }
}

/// Right-handed signed volume of the tetrahedron `abcd` (floating point).
pub fn signed_volume(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> f64 {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let w = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
    let cross = [
        v[1] * w[2] - v[2] * w[1],
        v[2] * w[0] - v[0] * w[2],
        v[0] * w[1] - v[1] * w[0],
    ];
    (u[0] * cross[0] + u[1] * cross[1] + u[2] * cross[2]) / 6.0
}

/// Errors from validating the input or running TetGen.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TetgenError {
    /// The surface has no points or no triangles.
    #[error("empty input: the surface needs points and triangles")]
    EmptyInput,
    /// More points or triangles than TetGen's `int` indices can address.
    #[error("input too large for TetGen: {0}")]
    TooLarge(String),
    /// A coordinate is NaN, infinite or too large for exact predicates.
    #[error("point {point} has a non-finite or out-of-range coordinate (|x| must be <= 1e100)")]
    InvalidCoordinate {
        /// Index of the offending point.
        point: usize,
    },
    /// Two points have identical coordinates.
    #[error("points {first} and {second} have identical coordinates")]
    DuplicatePoint {
        /// Lower index.
        first: usize,
        /// Higher index.
        second: usize,
    },
    /// A point is used by no triangle.
    #[error("point {point} is not used by any triangle")]
    UnusedPoint {
        /// Index of the unused point.
        point: usize,
    },
    /// A triangle refers to a point that does not exist.
    #[error("triangle {triangle} refers to point {index}, but there are only {num_points} points")]
    IndexOutOfRange {
        /// Index of the triangle.
        triangle: usize,
        /// The offending point index.
        index: u32,
        /// Number of points.
        num_points: usize,
    },
    /// A triangle repeats a vertex or has collinear vertices (zero area).
    #[error("triangle {triangle} is degenerate (repeated or collinear vertices)")]
    DegenerateTriangle {
        /// Index of the triangle.
        triangle: usize,
    },
    /// Two triangles have the same three vertices.
    #[error("triangles {first} and {second} are duplicates")]
    DuplicateTriangle {
        /// Lower index.
        first: usize,
        /// Higher index.
        second: usize,
    },
    /// An edge is not shared by exactly two triangles, so the surface is open
    /// (count 1) or non-manifold (count > 2).
    #[error("edge {edge:?} is shared by {count} triangle(s); a closed 2-manifold surface needs exactly 2")]
    NonManifoldEdge {
        /// The edge's point indices, smaller first.
        edge: [u32; 2],
        /// Number of triangles containing the edge.
        count: usize,
    },
    /// Two triangles intersect other than in their shared vertex or edge.
    #[error("triangles {first} and {second} intersect (self-intersecting surface)")]
    SelfIntersection {
        /// Lower index.
        first: usize,
        /// Higher index.
        second: usize,
    },
    /// A region seed or volume is invalid.
    #[error("region {region}: {reason}")]
    InvalidRegion {
        /// Index of the region.
        region: usize,
        /// What is wrong.
        reason: String,
    },
    /// A switch parameter is out of range.
    #[error("invalid switch: {0}")]
    InvalidSwitch(String),
    /// TetGen (or the C++ shim) reported an error.
    #[error("TetGen failed with code {code}: {message}")]
    Tetgen {
        /// TetGen's exit code (1–10) or a negative shim code.
        code: i32,
        /// Human-readable description of the code.
        message: &'static str,
    },
    /// TetGen returned something the wrapper cannot represent.
    #[error("unexpected TetGen output: {0}")]
    InvalidOutput(String),
}

/// Describes an error code returned by the shim.
fn describe_code(code: i32) -> &'static str {
    match code {
        1 => "out of memory",
        2 => "internal error",
        3 => "a self-intersection was detected",
        4 => "a very small input feature size was detected",
        5 => "two very close input facets were detected",
        10 => "an input error was detected",
        ffi::TG_ERR_ARGS => "invalid arguments to the shim",
        ffi::TG_ERR_ALLOC => "C++ allocation failure",
        ffi::TG_ERR_STD => "C++ standard exception",
        _ => "unknown error",
    }
}

/// Tetrahedralises the domain bounded by a closed triangle surface.
///
/// The input is validated first ([`validate_plc`]); TetGen is only called on
/// valid input. The resulting tetrahedra are all positively oriented (see the
/// crate docs). Tetrahedra outside the surface are removed; with several
/// nested shells every enclosed component is meshed (no holes). Region seeds
/// must lie inside the surface; for the attributes of unseeded subdomains see
/// [`Switches::region_attributes`].
///
/// # Errors
///
/// Any validation error, [`TetgenError::InvalidSwitch`] or
/// [`TetgenError::InvalidRegion`] for bad parameters, and
/// [`TetgenError::Tetgen`] if TetGen itself fails.
pub fn tetrahedralize(input: &Plc, switches: &Switches) -> Result<TetMesh, TetgenError> {
    validate_plc(input)?;
    let regional_volumes = input.regions.iter().any(|r| r.max_volume.is_some());
    let switch_string = switches.to_switch_string(regional_volumes)?;

    let points: Vec<f64> = input.points.iter().flatten().copied().collect();
    let triangles: Vec<i32> = input
        .triangles
        .iter()
        .flatten()
        .map(|&i| i as i32) // in range: validated against the point count
        .collect();
    // TetGen treats a negative regional volume as "no constraint".
    let regions: Vec<f64> = input
        .regions
        .iter()
        .flat_map(|r| {
            [
                r.seed[0],
                r.seed[1],
                r.seed[2],
                f64::from(r.attribute),
                r.max_volume.unwrap_or(-1.0),
            ]
        })
        .collect();

    let raw = ffi::run(&switch_string, &points, &triangles, &regions).map_err(|code| {
        TetgenError::Tetgen {
            code,
            message: describe_code(code),
        }
    })?;
    finish(raw, switches.region_attributes)
}

/// Converts TetGen's raw output into a [`TetMesh`], fixing orientation.
fn finish(raw: ffi::RawOutput, want_attributes: bool) -> Result<TetMesh, TetgenError> {
    if raw.num_corners != 4 {
        return Err(TetgenError::InvalidOutput(format!(
            "expected 4 corners per tetrahedron, got {}",
            raw.num_corners
        )));
    }
    let points: Vec<[f64; 3]> = raw
        .points
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let n = points.len();
    let first = i64::from(raw.first_number);
    let mut tets = Vec::with_capacity(raw.tets.len() / 4);
    for (t, c) in raw.tets.chunks_exact(4).enumerate() {
        let mut tet = [0u32; 4];
        for (k, &v) in c.iter().enumerate() {
            let i = i64::from(v) - first;
            if i < 0 || i >= n as i64 {
                return Err(TetgenError::InvalidOutput(format!(
                    "tetrahedron {t} refers to point {v}, but there are {n} points"
                )));
            }
            tet[k] = i as u32;
        }
        let o = validate::orient3d(
            points[tet[0] as usize],
            points[tet[1] as usize],
            points[tet[2] as usize],
            points[tet[3] as usize],
        );
        // Shewchuk's orient3d > 0 means left-handed; swap to right-handed.
        if o > 0.0 {
            tet.swap(2, 3);
        } else if o == 0.0 {
            return Err(TetgenError::InvalidOutput(format!(
                "tetrahedron {t} is flat (zero volume)"
            )));
        }
        tets.push(tet);
    }

    let mut tet_attributes = Vec::new();
    if want_attributes && raw.num_tet_attributes > 0 {
        let stride = raw.num_tet_attributes as usize;
        tet_attributes.reserve(tets.len());
        for (t, chunk) in raw.tet_attributes.chunks_exact(stride).enumerate() {
            let a = chunk[0];
            if !(a.is_finite()
                && a.fract() == 0.0
                && a >= f64::from(i32::MIN)
                && a <= f64::from(i32::MAX))
            {
                return Err(TetgenError::InvalidOutput(format!(
                    "tetrahedron {t} has non-integer attribute {a}"
                )));
            }
            tet_attributes.push(a as i32);
        }
    }
    Ok(TetMesh {
        points,
        tets,
        tet_attributes,
    })
}
