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

/// The output directories this process created, in order: an interrupted
/// run removes those it leaves empty, so that it leaves no trace where
/// there was nothing. Locked only while [`LIVE`] is held.
static CREATED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

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
        let mut list = live();
        if !dir.exists() {
            std::fs::create_dir_all(dir).map_err(|e| err(e.to_string()))?;
            created().push(dir.to_path_buf());
        }
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
        remove_while_written(&dir);
    }
    // Newest first: a batch's per-input folders before the batch's own.
    for dir in created().drain(..).rev() {
        // Fails, leaving it, unless empty: finished outputs stay.
        let _ = std::fs::remove_dir(&dir);
    }
    list
}

fn created() -> MutexGuard<'static, Vec<PathBuf>> {
    CREATED.lock().unwrap_or_else(|e| e.into_inner())
}

/// Removes `dir` although another thread may still be writing an output into
/// it. `dir` is first renamed to a sibling: from then on no writer can create
/// a file under the old path (it no longer exists), whereas a writer creating
/// files faster than `remove_dir_all` lists and deletes them could keep the
/// directory alive for ever (every `rmdir` failing on a newer file). The
/// renamed directory is then removed; the bound on the tries only keeps a
/// directory that cannot be removed (permissions) from holding the exit
/// forever.
fn remove_while_written(dir: &Path) {
    let target = match (dir.parent(), dir.file_name()) {
        (Some(parent), Some(name)) => {
            let removing = parent.join(format!(".removing{}", name.to_string_lossy()));
            match std::fs::rename(dir, &removing) {
                Ok(()) => removing,
                Err(_) => dir.to_path_buf(),
            }
        }
        _ => dir.to_path_buf(),
    };
    for _ in 0..100 {
        match std::fs::remove_dir_all(&target) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound && target.exists() => {
                std::thread::sleep(std::time::Duration::from_millis(5))
            }
            _ => return,
        }
    }
}

/// Runs `f` while no interruption can remove staging directories or exit
/// (for writes outside a staging directory, such as a summary file).
pub fn uninterrupted<T>(f: impl FnOnce() -> T) -> T {
    let _list = live();
    f()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    /// A writer creating files as fast as it can while the directory is
    /// removed (as the main thread writing outputs while Ctrl-C is handled):
    /// the directory must be gone afterwards, whatever the interleaving, and
    /// nothing left beside it.
    #[test]
    fn a_directory_being_written_is_removed() {
        let parent = tempfile::tempdir().unwrap();
        for round in 0..10 {
            let dir = parent.path().join(format!("stage{round}"));
            std::fs::create_dir(&dir).unwrap();
            let (started, stop) = (
                Arc::new(AtomicBool::new(false)),
                Arc::new(AtomicBool::new(false)),
            );
            let writer = {
                let (dir, started, stop) = (dir.clone(), started.clone(), stop.clone());
                std::thread::spawn(move || {
                    for i in 0.. {
                        let written = std::fs::write(dir.join(format!("out{i}")), [0u8; 64]);
                        if written.is_err() || stop.load(Ordering::Acquire) {
                            return;
                        }
                        started.store(true, Ordering::Release);
                    }
                })
            };
            while !started.load(Ordering::Acquire) {
                std::thread::yield_now();
            }
            remove_while_written(&dir);
            // A directory left behind would keep the writer going for ever.
            stop.store(true, Ordering::Release);
            writer.join().unwrap();
            assert!(!dir.exists(), "round {round}: the directory survived");
            let left: Vec<_> = std::fs::read_dir(parent.path()).unwrap().collect();
            assert!(left.is_empty(), "round {round}: {left:?} left behind");
        }
    }
}
