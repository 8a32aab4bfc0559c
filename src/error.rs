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
    /// The segmentation rejected the input read from `path` (a constant
    /// image, one too small to mesh, fewer distinct values than phases):
    /// the message names the file, as every input error does.
    #[error("{}: {source}", path.display())]
    Input {
        /// The input file or folder.
        path: PathBuf,
        /// What the segmentation found wrong with it.
        source: SegmentError,
    },
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

impl Error {
    /// `self` naming the input `path` when it is the segmentation's refusal
    /// of the input itself; a parameter out of its range, or any other
    /// error (which names its own file), is returned as it is.
    pub fn naming_input(self, path: &std::path::Path) -> Self {
        match self {
            Error::Segment(source) if !source.is_parameter() => Error::Input {
                path: path.to_path_buf(),
                source,
            },
            other => other,
        }
    }
}

/// Shorthand for results with [`enum@Error`].
pub type Result<T> = std::result::Result<T, Error>;
