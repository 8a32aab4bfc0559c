//! All integration tests in one binary (one link, shared helpers).

mod common;
mod dsc2d;
mod dsc3d;
mod figures;
mod generic;
mod prop2d;
mod seg3d;
