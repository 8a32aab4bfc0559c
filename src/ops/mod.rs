//! Local mesh operations, each generic over dimension unless its name says otherwise.
//!
//! Every operation either succeeds, leaving a valid complex, or returns a
//! [`Rejection`](crate::complex::Rejection) and changes nothing.

mod cell_qualities;
mod cell_stamps;
mod collapse;
mod flip2d;
mod flip3d;
mod memo;
mod relocate;
mod smooth;
mod split;
mod star_cache;

pub(crate) use cell_qualities::{CellQualities, JudgedTet};
pub(crate) use cell_stamps::CellStamps;
pub use collapse::CollapseMode;
pub(crate) use collapse::FlatEnds;
pub use flip3d::{Flip3, MAX_RING};
pub(crate) use memo::edge_settled;
pub use memo::ImproveMemo;
pub use relocate::MoveOutcome;
pub use smooth::SmoothScratch;
pub(crate) use star_cache::StarCache;
