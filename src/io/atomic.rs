//! Atomic file output: write to a temporary file in the target directory,
//! then rename it over the destination.
//!
//! A rename within one filesystem is atomic, so an interrupted or failed run
//! leaves either the previous file or the complete new one, never a truncated
//! output. The temporary file is removed automatically on failure.

use std::io::{self, BufWriter, Write};
use std::path::Path;

use super::error::{IoError, Result};

/// Writes `path` atomically: `write` fills a buffered temporary file in the
/// same directory, which is flushed, synced and then renamed onto `path`.
///
/// Any error from `write` (or from flushing/renaming) is reported as
/// [`IoError::Write`] and leaves `path` untouched.
pub fn write_atomic<F>(path: impl AsRef<Path>, write: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let path = path.as_ref();
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let err = |e| IoError::write(path, e);
    let mut builder = tempfile::Builder::new();
    builder.prefix(".dsc-seg-tmp-");
    // Temporary files are created 0600; outputs should get ordinary
    // permissions (0644 before the umask), like a plain `File::create`.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o644));
    }
    let tmp = builder.tempfile_in(dir).map_err(err)?;
    let mut w = BufWriter::new(tmp);
    write(&mut w).map_err(err)?;
    let tmp = w.into_inner().map_err(|e| err(e.into_error()))?;
    tmp.as_file().sync_all().map_err(err)?;
    tmp.persist(path).map_err(|e| err(e.error))?;
    Ok(())
}

/// Writes `bytes` to `path` atomically (see [`write_atomic`]).
pub fn write_bytes_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| w.write_all(bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_and_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.txt");
        write_bytes_atomic(&p, b"first").unwrap();
        write_bytes_atomic(&p, b"second").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"second");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn failure_keeps_old_file_and_leaves_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.txt");
        write_bytes_atomic(&p, b"old").unwrap();
        let r = write_atomic(&p, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("interrupted"))
        });
        let e = r.unwrap_err();
        assert!(matches!(e, IoError::Write { .. }));
        assert!(e.to_string().contains("out.txt"));
        assert_eq!(std::fs::read(&p).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn missing_directory_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("no/such/dir/out.txt");
        assert!(write_bytes_atomic(&p, b"x").is_err());
    }
}
