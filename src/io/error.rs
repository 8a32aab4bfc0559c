//! The error type shared by all file input/output in [`crate::io`].

use std::path::{Path, PathBuf};

/// An input/output failure, always naming the file involved so that a
/// command-line user can see at once which file is at fault.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The file or directory could not be opened or read at all.
    #[error("cannot read {path}: {source}")]
    Unreadable {
        /// The offending path.
        path: PathBuf,
        /// The underlying operating-system error.
        #[source]
        source: std::io::Error,
    },
    /// The file exists but is not an image in a format we can decode
    /// (unknown format, corrupt header, truncated data, ...).
    #[error("{path} is not a readable image: {reason}")]
    NotAnImage {
        /// The offending path.
        path: PathBuf,
        /// What the decoder complained about.
        reason: String,
    },
    /// The image decodes but its pixel type is not supported.
    #[error("{path}: unsupported image format: {reason}")]
    Unsupported {
        /// The offending path.
        path: PathBuf,
        /// The unsupported feature.
        reason: String,
    },
    /// A multi-page TIFF whose pages are not one volume's slices: an ImageJ
    /// or OME-TIFF time series or hyperstack of channels, slices and time
    /// points, or an OME-TIFF whose pages are not those its OME-XML declares.
    #[error("{path} is {reason}")]
    NotOneVolume {
        /// The offending path.
        path: PathBuf,
        /// What the pages are and what to do instead.
        reason: String,
    },
    /// A channel or time point of a TIFF's pages (`--channel`,
    /// `--time-point`) that the file does not have, or none chosen along an
    /// axis of several once one is chosen.
    #[error("{path}: {reason}")]
    NotInFile {
        /// The offending path.
        path: PathBuf,
        /// What was chosen, what the file holds.
        reason: String,
    },
    /// A channel was asked for that the image does not have.
    #[error("{path} has no channel {channel}: it has {channels} (0 to {last})", last = channels - 1)]
    NoChannel {
        /// The offending path.
        path: PathBuf,
        /// The channel asked for.
        channel: usize,
        /// How many the image has.
        channels: usize,
    },
    /// The image or volume has a zero width, height or depth.
    #[error("{path}: empty image ({dims})")]
    Empty {
        /// The offending path.
        path: PathBuf,
        /// The dimensions found, e.g. `0x12x3`.
        dims: String,
    },
    /// Sizes that must agree do not (slices of a stack, data vs. dimensions).
    #[error("{path}: dimension mismatch: {reason}")]
    DimensionMismatch {
        /// The offending path.
        path: PathBuf,
        /// Which sizes disagree.
        reason: String,
    },
    /// A NIfTI-1 file whose header or data is inconsistent or truncated.
    #[error("{path}: malformed NIfTI file: {reason}")]
    MalformedNifti {
        /// The offending path.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// A TIFF file that the decoder rejects or that is not a grayscale stack.
    #[error("{path}: malformed TIFF file: {reason}")]
    MalformedTiff {
        /// The offending path.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// A folder read as a volume's slices holds no image file.
    #[error("{path}: the folder holds no slices (no file ending in {extensions})")]
    NoSlices {
        /// The folder.
        path: PathBuf,
        /// The extensions read as slices.
        extensions: String,
    },
    /// An image with NaN or infinite samples: no intensity is known there.
    #[error("{path}: {samples}")]
    NonFinite {
        /// The offending path.
        path: PathBuf,
        /// How many samples are not finite, of how many.
        samples: super::volume::NonFiniteSamples,
    },
    /// A file or directory whose kind we cannot guess (e.g. an unknown extension
    /// for a volume).
    #[error("{path}: unknown file type: {reason}")]
    UnknownType {
        /// The offending path.
        path: PathBuf,
        /// Why the type could not be determined.
        reason: String,
    },
    /// Input data handed to a writer is inconsistent (e.g. an index out of range).
    #[error("cannot write {path}: invalid data: {reason}")]
    InvalidData {
        /// The output path.
        path: PathBuf,
        /// What is inconsistent.
        reason: String,
    },
    /// Writing the output failed; no partial file was left behind.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The output path.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

impl IoError {
    /// Builds [`IoError::Unreadable`] for `path`.
    pub(crate) fn unreadable(path: &Path, source: std::io::Error) -> Self {
        IoError::Unreadable {
            path: path.to_path_buf(),
            source,
        }
    }

    /// Builds [`IoError::Write`] for `path`.
    pub(crate) fn write(path: &Path, source: std::io::Error) -> Self {
        IoError::Write {
            path: path.to_path_buf(),
            source,
        }
    }

    /// Builds [`IoError::InvalidData`] for `path`.
    pub(crate) fn invalid(path: &Path, reason: impl Into<String>) -> Self {
        IoError::InvalidData {
            path: path.to_path_buf(),
            reason: reason.into(),
        }
    }

    /// Builds [`IoError::Empty`] for `path` with the dimensions found.
    pub(crate) fn empty(path: &Path, dims: &[usize]) -> Self {
        let dims = dims
            .iter()
            .map(|d| d.to_string())
            .collect::<Vec<_>>()
            .join("x");
        IoError::Empty {
            path: path.to_path_buf(),
            dims,
        }
    }
}

/// A decoder's I/O error as a reason for the user: running out of bytes
/// ("failed to fill whole buffer") means the file is truncated.
pub(crate) fn io_reason(e: &std::io::Error) -> String {
    if e.kind() == std::io::ErrorKind::UnexpectedEof {
        "the file ends early (truncated?)".into()
    } else {
        e.to_string()
    }
}

/// Result alias for [`IoError`].
pub type Result<T> = std::result::Result<T, IoError>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_path() {
        let e = IoError::empty(Path::new("a/b.png"), &[0, 5]);
        assert_eq!(e.to_string(), "a/b.png: empty image (0x5)");
        let e = IoError::unreadable(
            Path::new("x.tif"),
            std::io::Error::new(std::io::ErrorKind::NotFound, "gone"),
        );
        assert!(e.to_string().starts_with("cannot read x.tif"));
    }
}
