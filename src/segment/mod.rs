//! Segmentation.

pub mod region3d;
pub mod voxel3d;
