//! The deformable simplicial complex: the deform loop and its parameters.
//!
//! `deform` moves vertices as far as they can go without inverting a cell,
//! improves the mesh, and repeats; topology changes fall out of the removal of
//! the degenerate cells that approaching interfaces squeeze.

mod deform;
mod improve;
mod params;
mod refusals;
mod resize;
mod sizing;
mod splits_made;
mod workspace;

pub use deform::{DeformReport, Destinations};
pub use improve::{Connectivity, Region};
pub use params::{DscParams, ParamError};
pub use sizing::SizingField;
pub use workspace::DscWorkspace;
