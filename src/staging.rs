//! Staged output directories: every output of a run is written into a hidden
//! staging directory inside the output directory and renamed into place only
//! once all of them exist, so a failed run leaves the directory as it was.
//!
//! Every live staging directory is also listed process-wide, so that an
//! interrupted process (Ctrl-C) can remove them before it exits:
//! [`remove_all_and_hold`] waits for a rename into place that is under way,
//! removes every staging directory and keeps any other from starting.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// The staging directories alive in this process. Publishing holds the lock
/// for its renames, so an interruption never sees half a publication.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn live() -> MutexGuard<'static, Vec<PathBuf>> {
    // A panicking holder cannot leave the list inconsistent: keep using it.
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// The prefix of staging directories' names.
pub const STAGING_PREFIX: &str = ".dsc-seg-staging-";

/// A staging directory inside an output directory, removed when dropped
/// unless published.
#[derive(Debug)]
pub struct Staging {
    dir: tempfile::TempDir,
}

impl Staging {
    /// Checks that `dir` can hold our outputs: creates it, then a staging
    /// directory in it.
    pub fn new(dir: &Path) -> Result<Self> {
        let err = |reason: String| Error::OutputDir {
            path: dir.to_path_buf(),
            reason,
        };
        if dir.exists() && !dir.is_dir() {
            return Err(err("it exists and is not a directory".into()));
        }
        std::fs::create_dir_all(dir).map_err(|e| err(e.to_string()))?;
        let mut list = live();
        let stage = tempfile::Builder::new()
            .prefix(STAGING_PREFIX)
            .tempdir_in(dir)
            // The error text would name the random staging path; its kind says it all.
            .map_err(|e| err(std::io::Error::from(e.kind()).to_string()))?;
        list.push(stage.path().to_path_buf());
        Ok(Staging { dir: stage })
    }

    /// The staging directory, where the outputs are written.
    pub fn path(&self) -> &Path {
        self.dir.path()
    }

    /// Moves the files `names` of the staging directory into `dir`, then
    /// removes the staging directory.
    pub fn publish(self, dir: &Path, names: &[&str]) -> Result<()> {
        let mut list = live();
        for name in names {
            std::fs::rename(self.path().join(name), dir.join(name)).map_err(|e| {
                Error::OutputDir {
                    path: dir.to_path_buf(),
                    reason: format!("{name}: {e}"),
                }
            })?;
        }
        // Gone from the disk and the list before an interruption can look.
        let _ = std::fs::remove_dir_all(self.path());
        list.retain(|p| p != self.path());
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        let path = self.dir.path();
        live().retain(|p| p != path);
        // The TempDir removes the directory itself.
    }
}

/// For an interrupted process: waits for any publication under way, removes
/// every live staging directory and returns the lock, which the caller keeps
/// until it exits so that no new output is published.
pub fn remove_all_and_hold() -> MutexGuard<'static, Vec<PathBuf>> {
    let mut list = live();
    for dir in list.drain(..) {
        let _ = std::fs::remove_dir_all(dir);
    }
    list
}

/// Runs `f` while no interruption can remove staging directories or exit
/// (for writes outside a staging directory, such as a summary file).
pub fn uninterrupted<T>(f: impl FnOnce() -> T) -> T {
    let _list = live();
    f()
}
