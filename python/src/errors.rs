//! The library's errors as Python exceptions, with the command line's messages.

use dsc_seg::Error;
use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyValueError};
use pyo3::PyErr;

/// File problems become `OSError`; bad arguments and inputs `ValueError`;
/// a cancelled run `KeyboardInterrupt`.
pub fn to_py(e: Error) -> PyErr {
    let msg = e.to_string().replace('\n', " ");
    match e {
        Error::Io(_) | Error::OutputDir { .. } => PyOSError::new_err(msg),
        Error::Segment(_) | Error::Input { .. } | Error::Usage(_) => PyValueError::new_err(msg),
        Error::Interrupted => PyKeyboardInterrupt::new_err(msg),
    }
}

/// An option that does not parse, as `ValueError`; an unknown option is
/// named as the keyword it came from.
pub fn parse_error(e: &clap::Error) -> PyErr {
    if e.kind() == clap::error::ErrorKind::UnknownArgument {
        if let Some(clap::error::ContextValue::String(arg)) =
            e.get(clap::error::ContextKind::InvalidArg)
        {
            let keyword = arg.trim_start_matches('-').replace('-', "_");
            return PyValueError::new_err(format!(
                "segment() got an unexpected keyword argument '{keyword}'"
            ));
        }
    }
    PyValueError::new_err(dsc_seg::options::one_line(e))
}
