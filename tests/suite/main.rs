//! All integration tests in one binary (one link, shared helpers).

mod adaptive;
mod batch;
mod cli;
mod cli3d;
mod common;
mod determinism;
mod dsc2d;
mod dsc3d;
mod figures;
mod forces;
mod generic;
mod inputs;
mod intensity;
mod measures;
mod messages;
mod missed;
mod ome_tiff;
mod physical;
mod prop2d;
mod report_units;
mod reseed;
mod seg3d;
mod segment2d;
mod shading;
mod sizing;
mod stopping3d;
