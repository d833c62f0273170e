//! Sets of files written as one commit: the files a command writes into its output folder
//! (`simulate --out`, `diagnose --plots`, `export --csv`, `trace --paths`) are all written
//! under temporary names first and renamed together at [`FileSet::commit`].
//!
//! While a set is open for a folder, every [`crate::io::atomic::write_atomic`] into that folder
//! writes, syncs and *keeps* its temporary file (registered for the signal cleanup) instead of
//! renaming it. The commit renames them all while holding the interruption lock
//! ([`crate::io::interrupt::commit_guard`]): SIGINT/SIGTERM before the commit removes the
//! temporary files and leaves the old set; during it, the handler waits for the last rename.
//! Either way the folder holds the old set or the new one, never a mix (a kill -9 or a power cut
//! in the microseconds of the renames can still mix them; their temporary files are removed
//! the next time `rigctl` writes there). At the commit, files of an earlier run that the new
//! set does not hold (`stale`) are removed. A set dropped without a commit (an error) removes
//! its temporary files: the old set stays.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

use crate::io::atomic::AtomicWriteError;
use crate::io::interrupt;

struct Open {
    id: u64,
    dir: PathBuf,
    staged: Vec<(PathBuf, PathBuf)>,
}

static OPEN: Mutex<Vec<Open>> = Mutex::new(Vec::new());
static NEXT_ID: AtomicU64 = AtomicU64::new(0);

/// An open set of files for one folder; see the module documentation.
pub struct FileSet {
    id: u64,
    dir: PathBuf,
    stale: fn(&str) -> bool,
}

/// Opens a set for `dir` (which must exist); `stale` names the files of an earlier run that
/// are removed at the commit when the new set does not write them.
pub fn begin(dir: &Path, stale: fn(&str) -> bool) -> Result<FileSet, AtomicWriteError> {
    let canon = std::fs::canonicalize(dir).map_err(|source| AtomicWriteError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let id = NEXT_ID.fetch_add(1, Ordering::SeqCst);
    if let Ok(mut open) = OPEN.lock() {
        open.push(Open {
            id,
            dir: canon.clone(),
            staged: Vec::new(),
        });
    }
    Ok(FileSet {
        id,
        dir: canon,
        stale,
    })
}

/// Called by the atomic writer with a complete temporary file: when `target` is in a folder
/// with an open set, the file is kept for the commit and `true` is returned.
pub(crate) fn stage(tmp: &Path, target: &Path) -> bool {
    let Ok(mut open) = OPEN.lock() else {
        return false;
    };
    if open.is_empty() {
        return false;
    }
    let parent = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let Ok(parent) = std::fs::canonicalize(parent) else {
        return false;
    };
    match open.iter_mut().rev().find(|o| o.dir == parent) {
        Some(o) => {
            // a second write of the same file in one set replaces the first
            if let Some(i) = o.staged.iter().position(|(_, t)| t == target) {
                let (old_tmp, _) = o.staged.remove(i);
                if old_tmp != tmp {
                    let _ = std::fs::remove_file(&old_tmp);
                    interrupt::unregister_temp(&old_tmp);
                }
            }
            o.staged.push((tmp.to_path_buf(), target.to_path_buf()));
            true
        }
        None => false,
    }
}

impl FileSet {
    fn take(&self) -> Vec<(PathBuf, PathBuf)> {
        let Ok(mut open) = OPEN.lock() else {
            return Vec::new();
        };
        match open.iter().position(|o| o.id == self.id) {
            Some(i) => open.remove(i).staged,
            None => Vec::new(),
        }
    }

    /// Renames every staged file into place and removes the stale ones, as one step with
    /// respect to SIGINT/SIGTERM; returns the files written.
    pub fn commit(self) -> Result<Vec<PathBuf>, AtomicWriteError> {
        let staged = self.take();
        let _guard = interrupt::commit_guard();
        let mut written = Vec::with_capacity(staged.len());
        let mut failure = None;
        for (tmp, target) in &staged {
            if failure.is_none() {
                match std::fs::rename(tmp, target) {
                    Ok(()) => written.push(target.clone()),
                    Err(source) => {
                        failure = Some(AtomicWriteError::Io {
                            path: target.clone(),
                            source,
                        })
                    }
                }
            }
            if failure.is_some() {
                let _ = std::fs::remove_file(tmp);
            }
            interrupt::unregister_temp(tmp);
        }
        if let Some(e) = failure {
            return Err(e);
        }
        let fresh: Vec<&std::ffi::OsStr> = written.iter().filter_map(|p| p.file_name()).collect();
        if let Ok(entries) = std::fs::read_dir(&self.dir) {
            for e in entries.flatten() {
                let name = e.file_name();
                if (self.stale)(&name.to_string_lossy()) && !fresh.contains(&name.as_os_str()) {
                    let _ = std::fs::remove_file(self.dir.join(&name));
                }
            }
        }
        Ok(written)
    }
}

impl Drop for FileSet {
    /// Not committed (an error on the way): the temporary files go, the old set stays.
    fn drop(&mut self) {
        for (tmp, _) in self.take() {
            let _ = std::fs::remove_file(&tmp);
            interrupt::unregister_temp(&tmp);
        }
    }
}

/// No file of an earlier run is removed.
pub fn keep_all(_: &str) -> bool {
    false
}
