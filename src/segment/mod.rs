//! The paper's segmentation (sections III.B and III.C) on the DSC engine.
//!
//! One concept per file, all generic over the dimension except [`raster`]:
//!
//! - [`image`]: the input as a borrowed scalar grid;
//! - [`raster`]: the dimension-specific part ([`Raster`]: cell over pixels,
//!   samples along a facet, interpolation), implemented for [`D2`](crate::dim::D2);
//! - [`integrate`]: per-cell sums (exactly once per pixel, in parallel) and
//!   per-phase means;
//! - [`init`]: range/interval, disk and label-image initialisations;
//! - [`forces`]: region forces (eqs. 5–7) and rigidity (eq. 2);
//! - [`flips`]: label flips (mean rule, pixel-dominant rule);
//! - [`driver`]: the iteration, the Mumford–Shah energy and the stopping rule;
//! - [`params`] and [`error`];
//! - `tetgen_init` (feature `tetgen`): initial 3D complexes conforming to a
//!   closed surface, built with TetGen.

pub mod driver;
pub mod error;
pub mod flips;
pub mod forces;
pub mod image;
pub mod init;
pub mod integrate;
pub mod output3d;
pub mod params;
pub mod raster;
#[cfg(feature = "tetgen")]
pub mod tetgen_init;
pub mod voxel3d;

pub use driver::{IterationRecord, SegmentReport, Segmentation, StageTimes, StopReason};
pub use error::SegmentError;
pub use image::ImageView;
pub use params::{
    default_edge_length, ForceModel, Init, InitBall, InitDisk, SegmentParams, MAX_PHASES,
};
pub use raster::Raster;
