//! File input and output.

pub mod surface;
