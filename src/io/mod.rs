//! File input and output: images, volumes, VTK, figures.
//!
//! Everything here works on plain slices and arrays (points, triangles,
//! labels) so that the mesh code can call it without this module depending on
//! the mesh types.

pub mod atomic;
pub mod error;
pub mod frame;
pub mod hyperstack;
pub mod image2;
pub mod intensity;
pub mod ome;
pub mod render;
pub mod resolution;
pub mod selection;
pub mod surface;
pub mod volume;
pub mod vti;
pub mod vtk;

pub use atomic::{write_atomic, write_bytes_atomic};
pub use error::IoError;
pub use frame::{Frame, FrameSource};
pub use image2::{
    save_gray8_png, save_gray8_png_with_pixel_size, save_image_png, wide_samples_as_f32, Colour,
    Image2, SampleType, Transparency,
};
pub use render::{phase_color, save_gif, Overlay};
pub use selection::Selection;
pub use volume::{
    min_max_normalise, save_labels_nifti, save_labels_tiff, save_nifti, NonFiniteSamples, Volume,
};
pub use vti::{write_pvd, write_vti, write_vtm};
pub use vtk::{write_vtp, write_vtp_lines, write_vtu, CellArray, Cells};
