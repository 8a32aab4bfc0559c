//! The crate-level error: every way a run can fail, one line each.

use crate::io::IoError;
use crate::segment::SegmentError;
use std::path::PathBuf;
use thiserror::Error;

/// Any failure of a `dsc-seg` job (bad input, bad parameters, I/O).
#[derive(Debug, Error)]
pub enum Error {
    /// Reading or writing a file failed.
    #[error(transparent)]
    Io(#[from] IoError),
    /// The segmentation rejected its input or parameters.
    #[error(transparent)]
    Segment(#[from] SegmentError),
    /// The output directory cannot be created or written.
    #[error("cannot write to output directory {path}: {reason}")]
    OutputDir {
        /// The directory.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// A command-line value that parses but makes no sense.
    #[error("{0}")]
    Usage(String),
    /// The caller cancelled the run ([`crate::cancel`]); nothing was produced.
    #[error("interrupted")]
    Interrupted,
}

/// Shorthand for results with [`enum@Error`].
pub type Result<T> = std::result::Result<T, Error>;
