//! All integration tests in one binary (one link, shared helpers).

mod cli;
mod common;
mod dsc2d;
mod generic;
mod prop2d;
mod segment2d;
