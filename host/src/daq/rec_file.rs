//! Where `rigctl record` writes: the recording is never lost and never has two writers.
//!
//! - **A new file** is created exclusively (`O_EXCL`) at its name and locked (`flock`, exclusive)
//!   for the whole session: a second `record` to the same name finds it and is refused
//!   ([`RecordingError::Exists`] without `--overwrite`, [`RecordingError::Busy`] with it).
//! - **`--overwrite` of an existing recording** locks the old file (a recording another
//!   process holds is refused: [`RecordingError::Busy`]), writes the new one under a temporary
//!   name beside it (`.NAME.tmp-PID`, locked too) and renames it over the old one only at
//!   [`RecTarget::commit`], once the board has started and its first good frames are stored. A
//!   session that ends before (no `Hello`, no `Ack(Start)`, a lost device, a signal) removes the
//!   temporary file and leaves the old recording as it was.
//! - A symbolic link at the name is followed (the file it points to is the recording, as for
//!   every output of `rigctl`); a device or FIFO is written directly.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::ErrorKind as IoKind;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use super::recording::RecordingError;
use crate::io::atomic::{resolve_output, temp_path, OutputTarget};
use crate::io::interrupt;

/// Tries to take the lock of an old recording whose name was replaced meanwhile.
const ATTEMPTS: usize = 4;

/// The recording being written: its final name and, with `--overwrite`, the temporary file and
/// the lock on the old recording until [`RecTarget::commit`].
#[derive(Debug)]
pub struct RecTarget {
    /// The recording's name (links resolved).
    path: PathBuf,
    /// The temporary file being written, until the commit.
    tmp: Option<PathBuf>,
    /// The old recording, locked until the commit.
    old: Option<File>,
    /// Whether the file at `path` was created by this session.
    created: bool,
}

impl RecTarget {
    /// Whether the new recording is under its final name.
    pub fn committed(&self) -> bool {
        self.tmp.is_none()
    }

    /// The file being written (the temporary file before the commit).
    pub fn write_path(&self) -> &Path {
        self.tmp.as_deref().unwrap_or(&self.path)
    }

    /// Renames the new recording over the old one (with `--overwrite`); nothing to do otherwise.
    pub fn commit(&mut self) -> Result<(), RecordingError> {
        if let Some(tmp) = self.tmp.take() {
            let renamed = std::fs::rename(&tmp, &self.path);
            interrupt::unregister_temp(&tmp);
            if let Err(source) = renamed {
                let _ = std::fs::remove_file(&tmp);
                return Err(RecordingError::Write {
                    path: self.path.clone(),
                    source,
                });
            }
            self.old = None; // the old recording is gone: its lock with it
        }
        Ok(())
    }

    /// The session ended without a recording worth keeping: removes the temporary file (the old
    /// recording stays) or the file this session created.
    pub fn discard(mut self) {
        if self.tmp.is_none() && self.created {
            let _ = std::fs::remove_file(&self.path);
        }
        self.drop_tmp();
    }

    fn drop_tmp(&mut self) {
        if let Some(tmp) = self.tmp.take() {
            let _ = std::fs::remove_file(&tmp);
            interrupt::unregister_temp(&tmp);
        }
    }
}

impl Drop for RecTarget {
    /// Never a temporary file left behind, whatever path the session took.
    fn drop(&mut self) {
        self.drop_tmp();
    }
}

fn open_err(path: &Path) -> impl Fn(std::io::Error) -> RecordingError + '_ {
    move |source| RecordingError::Open {
        path: path.to_path_buf(),
        source,
    }
}

/// Takes the exclusive lock of `file` at once, or refuses a second writer.
fn lock(file: &File, path: &Path) -> Result<(), RecordingError> {
    match file.try_lock() {
        Ok(()) => Ok(()),
        Err(TryLockError::WouldBlock) => Err(RecordingError::Busy {
            path: path.to_path_buf(),
        }),
        Err(TryLockError::Error(e)) => Err(open_err(path)(e)),
    }
}

/// Opens the file a session writes its recording to (module documentation).
pub fn open(path: &Path, overwrite: bool) -> Result<(File, RecTarget), RecordingError> {
    let resolved = resolve_output(path).map_err(|e| open_err(path)(std::io::Error::other(e)))?;
    let target = match resolved {
        OutputTarget::Replace(p) => p,
        OutputTarget::Direct(p) => {
            // a device or FIFO: written directly, nothing to replace or keep
            let file = OpenOptions::new()
                .write(true)
                .open(&p)
                .map_err(open_err(path))?;
            let t = RecTarget {
                path: p,
                tmp: None,
                old: None,
                created: false,
            };
            return Ok((file, t));
        }
    };
    for _ in 0..ATTEMPTS {
        match OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&target)
        {
            Ok(file) => {
                let t = RecTarget {
                    path: target.clone(),
                    tmp: None,
                    old: None,
                    created: true,
                };
                lock(&file, path)?;
                return Ok((file, t));
            }
            Err(e) if e.kind() == IoKind::AlreadyExists && !overwrite => {
                return Err(RecordingError::Exists {
                    path: path.to_path_buf(),
                })
            }
            Err(e) if e.kind() == IoKind::AlreadyExists => {}
            Err(e) => return Err(open_err(path)(e)),
        }
        let old = match File::open(&target) {
            Ok(f) => f,
            Err(e) if e.kind() == IoKind::NotFound => continue, // removed meanwhile: create it
            Err(e) => return Err(open_err(path)(e)),
        };
        lock(&old, path)?;
        // the name may have been replaced between the open and the lock: lock what it is now
        let same =
            |a: &std::fs::Metadata, b: &std::fs::Metadata| a.dev() == b.dev() && a.ino() == b.ino();
        let now = std::fs::metadata(&target);
        let held = old.metadata().map_err(open_err(path))?;
        if !now.is_ok_and(|m| same(&m, &held)) {
            continue;
        }
        let tmp = temp_path(&target);
        interrupt::register_temp(&tmp);
        let t = RecTarget {
            path: target.clone(),
            tmp: Some(tmp.clone()),
            old: Some(old),
            created: false,
        };
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
            .map_err(open_err(&tmp))?;
        lock(&file, &tmp)?;
        return Ok((file, t));
    }
    Err(RecordingError::Busy {
        path: path.to_path_buf(),
    })
}
