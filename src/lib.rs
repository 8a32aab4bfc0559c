//! dsc-seg: multiphase image segmentation with the deformable simplicial complex.
#![forbid(unsafe_code)]
#![warn(missing_docs)]
#![deny(rustdoc::broken_intra_doc_links)]

pub mod complex;
pub mod dim;
pub mod dsc;
pub mod error;
pub mod figures;
pub mod io;
pub mod ops;
pub mod phantom;
pub mod pipeline;
pub mod pipeline3d;
pub mod segment;

pub use error::{Error, Result};
