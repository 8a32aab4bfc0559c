//! File input and output: images, volumes, VTK, figures.
//!
//! Everything here works on plain slices and arrays (points, triangles,
//! labels) so that the mesh code can call it without this module depending on
//! the mesh types.

pub mod atomic;
pub mod error;
pub mod image2;
pub mod render;
pub mod volume;
pub mod vtk;

pub use atomic::{write_atomic, write_bytes_atomic};
pub use error::IoError;
pub use image2::Image2;
pub use volume::Volume;
