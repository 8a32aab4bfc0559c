//! The paper's segmentation (sections III.B and III.C) on the DSC engine.
//!
//! One concept per file, all generic over the dimension except [`raster`]:
//!
//! - [`image`]: the input as a borrowed scalar grid;
//! - [`raster`]: the dimension-specific part ([`Raster`]: cell over pixels,
//!   samples along a facet, interpolation), `raster/d2.rs` for triangles over
//!   pixels, `raster/d3.rs` for tetrahedra over voxels;
//! - [`integrate`]: per-cell sums (exactly once per pixel, in parallel) and
//!   per-phase means;
//! - [`intensity`]: the input's intensity scale (robust range, noise,
//!   histogram), which makes the energy invariant to `a·I + b`;
//! - [`contrast`]: the phase contrast Δ of the length weight `ν = w·Δ²/2`;
//! - [`thresholds`]: least-variance histogram splits (multi-Otsu, k-means++);
//! - [`init`]: histogram, range/interval, disk and label-image initialisations;
//! - [`forces`]: region forces (eqs. 5–7) and rigidity (eq. 2);
//! - [`smoothing`]: the image the region force samples (in 2D under noise,
//!   smoothed by a Gaussian that follows the noise);
//! - `force_stage`: an iteration's force terms summed, its step and the
//!   destinations of the deformation;
//! - [`auto`]: the number of phases chosen from the data (`--phases auto`);
//! - [`flips`]: label flips (mean rule, pixel-dominant rule);
//! - [`cluster_flips`]: connected groups of small cells that fit another
//!   phase, relabelled together (adaptive resolution);
//! - [`band_flips`]: layers of an intermediate phase as thin as a blurred
//!   edge's band, given back to the phases on their sides (3D), with
//!   [`phase_distance`] (each cell's depth in its phase towards every other)
//!   and [`edge_blur`] (the edges' blur estimated along the interfaces);
//! - [`relaxed_length`]: the length a staircase border of small cells
//!   relaxes to;
//! - [`reseed`]: phases that empty or duplicate another, found and re-seeded;
//! - [`shading`]: a smooth trend of intensity inside the phases (uneven
//!   illumination, a bias field), fitted after a run and reported;
//! - [`model`]: the extension points ([`ForceTerm`], [`LabelRule`],
//!   [`Initialiser`], [`Models`]) through which a user supplies the evolution;
//! - [`models`]: the paper's terms and rules written against them, and
//!   examples from the deformable-model literature (balloon, edge attraction,
//!   volcano);
//! - [`adaptive`]: the sizing field of adaptive resolution (refinement
//!   where the data is not explained, coarsening where nothing happens);
//! - [`coarse_pass`]: a first run on the image at half resolution whose
//!   mesh starts the run at full resolution;
//! - [`measurements`]: a finished segmentation's per-phase and per-interface
//!   figures; [`partial_volume`]: areas/volumes from the band's intensities;
//!   [`censored`]: the model of intensities clipped where the data saturate;
//! - [`driver`]: the segmentation loop, the Mumford–Shah energy and the stopping rule;
//! - [`params`] and [`error`].

pub mod absorbed;
pub mod adaptive;
pub mod auto;
pub mod band_flips;
pub mod band_phase;
pub mod censored;
pub mod check_image;
pub mod cluster_flips;
pub mod coarse_pass;
pub mod contrast;
pub mod driver;
pub mod edge_blur;
pub mod error;
pub mod flips;
mod force_stage;
pub mod forces;
mod graded_start;
pub mod image;
pub mod init;
pub mod integrate;
pub mod intensity;
pub mod measurements;
pub mod missed_objects;
pub mod model;
pub mod models;
pub mod noise_correlation;
mod normal_motion;
pub mod outliers;
pub mod params;
pub mod partial_volume;
pub mod phase_distance;
mod rank_select;
pub mod raster;
pub mod relaxed_length;
pub mod reseed;
pub mod reseed_trial;
pub mod shading;
pub mod smoothing;
mod step_gain;
pub mod thresholds;

pub use driver::{IterationRecord, SegmentReport, Segmentation, StageTimes, StopReason};
pub use error::SegmentError;
pub use image::ImageView;
pub use integrate::{CellStats, PhaseStats};
pub use model::{
    phase_normals, Flow, ForceTerm, Initialiser, IterationState, LabelRule, Models, TermKind,
};
pub use params::{
    default_edge_length, ForceModel, Init, InitBall, InitDisk, JunctionForce, SegmentParams,
    MAX_PHASES,
};
pub use raster::Raster;

/// The 2D segmentation (triangles over pixels).
pub type Segmentation2<'a> = Segmentation<'a, crate::dim::D2>;
/// The 2D models of the evolution.
pub type Models2 = Models<crate::dim::D2>;
/// The 3D segmentation (tetrahedra over voxels).
pub type Segmentation3<'a> = Segmentation<'a, crate::dim::D3>;
/// The 3D models of the evolution.
pub type Models3 = Models<crate::dim::D3>;
