//! Segmentation.

pub mod voxel3d;
