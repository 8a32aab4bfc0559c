//! Segmentation.

pub mod output3d;
pub mod region3d;
pub mod voxel3d;
