//! The one mechanism by which `rigctl` writes its output files (FORMATS.md: nothing
//! half-written under the final name).
//!
//! - A **new path or a regular file** is written under a temporary name in the same directory
//!   (`.NAME.tmp-PID`), flushed, synced and renamed over the target only when complete.
//! - A **symbolic link** is resolved (chains included, relative to the link's directory) and the
//!   file it points to is written as above: the link stays a link.
//! - A **character/block device, FIFO or socket** (`/dev/stdout`, `/dev/null`, a named pipe) is
//!   opened and written directly: it is never replaced by a regular file, and its reader gets the
//!   data.
//!
//! Live temporary files are kept in a registry that [`crate::io::interrupt`] empties on SIGINT /
//! SIGTERM; temporary files left by a process that no longer exists (kill -9, power cut) are
//! removed the next time `rigctl` writes into the same directory ([`clean_stale_temps`]).
//! Commands with several outputs call [`check_output`] on each before the work, so that an
//! unwritable last output cannot leave the first ones written.

use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use crate::io::interrupt;
use crate::io::shown::shown;

#[derive(Debug, thiserror::Error)]
pub enum AtomicWriteError {
    #[error("cannot write {}: {source}", shown(path))]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot write {}: {reason}", shown(path))]
    Unusable { path: PathBuf, reason: String },
    #[error("{}: {source}", shown(path))]
    NonFinite {
        path: PathBuf,
        #[source]
        source: super::finite::NonFinite,
    },
}

impl crate::error::Classify for AtomicWriteError {
    /// An unusable path (a directory, a missing parent) is bad input; the system refusing the
    /// write (no space, permission denied) is a failure of the run.
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::Io { .. } | Self::NonFinite { .. } => crate::error::ErrorKind::Failure,
            Self::Unusable { .. } => crate::error::ErrorKind::BadInput,
        }
    }
}

/// An exclusive lock on an output directory, held while a command writes its set of files into
/// it, so that concurrent runs into the same directory leave the files of one run, never a mix
/// (`simulate --out DIR` run several times at once). Released when dropped.
pub struct DirLock {
    _lock: nix::fcntl::Flock<File>,
}

/// Creates `dir` if missing and locks it exclusively (waits for another holder).
pub fn lock_dir(dir: &Path) -> Result<DirLock, AtomicWriteError> {
    let io = |source| AtomicWriteError::Io {
        path: dir.to_path_buf(),
        source,
    };
    std::fs::create_dir_all(dir).map_err(io)?;
    let file = File::open(dir).map_err(io)?;
    let lock = nix::fcntl::Flock::lock(file, nix::fcntl::FlockArg::LockExclusive)
        .map_err(|(_, e)| io(std::io::Error::from(e)))?;
    Ok(DirLock { _lock: lock })
}

/// Most symbolic links followed before giving up (as the kernel's ELOOP limit).
const MAX_LINK_HOPS: usize = 40;

/// What is at an output path once links are resolved.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OutputTarget {
    /// A regular file or nothing yet: temp + rename at this (resolved) path.
    Replace(PathBuf),
    /// A device, FIFO or socket: written in place.
    Direct(PathBuf),
}

impl OutputTarget {
    pub fn path(&self) -> &Path {
        match self {
            Self::Replace(p) | Self::Direct(p) => p,
        }
    }
}

/// Follows symbolic links from `path` to the file that would be written.
pub fn resolve_output(path: &Path) -> Result<OutputTarget, AtomicWriteError> {
    let unusable = |reason: String| AtomicWriteError::Unusable {
        path: path.to_path_buf(),
        reason,
    };
    let mut current = path.to_path_buf();
    for _ in 0..MAX_LINK_HOPS {
        let meta = match std::fs::symlink_metadata(&current) {
            Ok(m) => m,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Ok(OutputTarget::Replace(current))
            }
            Err(source) => {
                return Err(AtomicWriteError::Io {
                    path: path.to_path_buf(),
                    source,
                })
            }
        };
        let ft = meta.file_type();
        if ft.is_symlink() {
            let link = std::fs::read_link(&current).map_err(|source| AtomicWriteError::Io {
                path: path.to_path_buf(),
                source,
            })?;
            current = match current.parent() {
                Some(dir) if link.is_relative() => dir.join(link),
                _ => link,
            };
        } else if ft.is_dir() {
            return Err(unusable(format!("{} is a directory", current.display())));
        } else if ft.is_file() {
            return Ok(OutputTarget::Replace(current));
        } else {
            return Ok(OutputTarget::Direct(current));
        }
    }
    Err(unusable("too many levels of symbolic links".into()))
}

/// Output folders (`simulate --out`, `diagnose --plots`, `export --csv`, `trace --paths`): a
/// file written into one replaces whatever entry has its name, and a symbolic link there is
/// replaced, never followed (a link planted in an output folder cannot send a write to another
/// file).
static OUTPUT_DIRS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Declares `dir` an output folder of this process (see [`OUTPUT_DIRS`]); it need not exist yet.
pub fn declare_output_dir(dir: &Path) {
    if let Ok(mut dirs) = OUTPUT_DIRS.lock() {
        dirs.push(dir.to_path_buf());
    }
}

/// Whether `path` names an entry of a declared output folder.
fn in_output_dir(path: &Path) -> bool {
    let Ok(dirs) = OUTPUT_DIRS.lock() else {
        return false;
    };
    if dirs.is_empty() {
        return false;
    }
    let Ok(parent) = std::fs::canonicalize(parent_dir(path)) else {
        return false;
    };
    dirs.iter()
        .any(|d| std::fs::canonicalize(d).is_ok_and(|d| d == parent))
}

/// The target of a write into an output folder: the entry itself, whatever it is (a link is
/// replaced by the new file), unless it is a directory.
fn replace_in_place(path: &Path) -> Result<OutputTarget, AtomicWriteError> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => Err(AtomicWriteError::Unusable {
            path: path.to_path_buf(),
            reason: "is a directory".into(),
        }),
        _ => Ok(OutputTarget::Replace(path.to_path_buf())),
    }
}

/// The directory a new file at `path` goes into (`.` for a bare file name).
fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The temporary name `.NAME.tmp-PID` beside `path`, which [`clean_stale_temps`] removes once
/// its process is gone.
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

/// The PID in a temporary name `.NAME.tmp-PID`, if `name` is one.
fn temp_owner(name: &str) -> Option<u32> {
    if !name.starts_with('.') {
        return None;
    }
    let (_, pid) = name.rsplit_once(".tmp-")?;
    pid.parse().ok()
}

fn process_alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    Path::new("/proc").join(pid.to_string()).exists()
}

/// Removes the temporary files (`.NAME.tmp-PID`) in `dir` whose process is gone; returns how
/// many were removed. Errors (unreadable directory, a file already gone) are ignored: this is
/// housekeeping.
pub fn clean_stale_temps(dir: &Path) -> usize {
    if !Path::new("/proc/self").exists() {
        return 0; // no way to tell live processes from dead ones
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = temp_owner(&name.to_string_lossy()) else {
            continue;
        };
        let is_file = entry.file_type().map(|t| t.is_file()).unwrap_or(false);
        if is_file && !process_alive(pid) && std::fs::remove_file(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// Checks, before any work, that `path` can be written: its directory exists and is writable
/// (a probe file is created and removed), it is not a directory, a device or FIFO is writable.
pub fn check_output(path: &Path) -> Result<(), AtomicWriteError> {
    match resolve_output(path)? {
        OutputTarget::Direct(target) => {
            let access = nix::unistd::access(&target, nix::unistd::AccessFlags::W_OK);
            access.map_err(|e| AtomicWriteError::Io {
                path: path.to_path_buf(),
                source: std::io::Error::from(e),
            })
        }
        OutputTarget::Replace(target) => {
            let dir = parent_dir(&target);
            if !dir.is_dir() {
                return Err(AtomicWriteError::Unusable {
                    path: path.to_path_buf(),
                    reason: format!("directory {} does not exist", dir.display()),
                });
            }
            let probe = temp_path(&target);
            // registered before it exists: a signal at any point leaves no probe behind
            interrupt::register_temp(&probe);
            let created = OpenOptions::new().write(true).create_new(true).open(&probe);
            if created.is_ok() {
                let _ = std::fs::remove_file(&probe);
            }
            interrupt::unregister_temp(&probe);
            created.map(drop).map_err(|source| AtomicWriteError::Io {
                path: path.to_path_buf(),
                source,
            })
        }
    }
}

/// [`check_output`] on every path given.
pub fn check_outputs<'a>(
    paths: impl IntoIterator<Item = &'a Path>,
) -> Result<(), AtomicWriteError> {
    paths.into_iter().try_for_each(check_output)
}

/// Writes `path`: `fill` writes into a buffered writer; see the module documentation for what
/// happens with regular files, links, devices and FIFOs. On any error with a regular file the
/// temporary file is removed and `path` is untouched.
pub fn write_atomic<E>(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> Result<(), E>,
) -> Result<(), E>
where
    E: From<AtomicWriteError>,
{
    let io_err = |source| AtomicWriteError::Io {
        path: path.to_path_buf(),
        source,
    };
    let target = if in_output_dir(path) {
        replace_in_place(path)?
    } else {
        resolve_output(path)?
    };
    match target {
        OutputTarget::Direct(target) => {
            let file = OpenOptions::new()
                .write(true)
                .open(&target)
                .map_err(io_err)?;
            let mut w = BufWriter::new(file);
            fill(&mut w)?;
            w.flush().map_err(io_err)?;
            Ok(())
        }
        OutputTarget::Replace(target) => {
            clean_stale_temps(&parent_dir(&target));
            let tmp = temp_path(&target);
            // registered before it exists: no gap in which a signal would leave it behind
            interrupt::register_temp(&tmp);
            let file = match File::create(&tmp) {
                Ok(f) => f,
                Err(e) => {
                    interrupt::unregister_temp(&tmp);
                    return Err(io_err(e).into());
                }
            };
            let mut w = BufWriter::new(file);
            let result = fill(&mut w).and_then(|()| {
                let file = w.into_inner().map_err(|e| io_err(e.into_error()))?;
                file.sync_all().map_err(io_err)?;
                Ok(())
            });
            if result.is_err() {
                let _ = std::fs::remove_file(&tmp);
                interrupt::unregister_temp(&tmp);
                return result;
            }
            // a set of files open for the folder renames it with the others at its commit
            if super::file_set::stage(&tmp, &target) {
                return result;
            }
            let renamed = std::fs::rename(&tmp, &target).map_err(io_err);
            if renamed.is_err() {
                let _ = std::fs::remove_file(&tmp);
            }
            interrupt::unregister_temp(&tmp);
            renamed?;
            result
        }
    }
}

/// Writes `text` to `path` as [`write_bytes_atomic`] does, after checking that every number
/// in it is finite (read as `format`, [`super::finite::check_text`]); a non-finite one leaves
/// `path` untouched (a failure of the run: exit 1).
pub fn write_text_atomic(
    path: &Path,
    format: super::finite::TextFormat,
    text: &str,
) -> Result<(), AtomicWriteError> {
    check_text_for(path, format, text)?;
    write_bytes_atomic(path, text.as_bytes())
}

/// [`super::finite::check_text`] with the error naming `path`: for a command that checks a set
/// of texts before writing any of them.
pub fn check_text_for(
    path: &Path,
    format: super::finite::TextFormat,
    text: &str,
) -> Result<(), AtomicWriteError> {
    super::finite::check_text(format, text).map_err(|source| AtomicWriteError::NonFinite {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes `value` as pretty JSON (and a final newline) atomically, after
/// [`super::finite_json::check_json`]: a non-finite number is an error naming `path` and the
/// key, and nothing is written (`serde_json` would write it as `null`, "not available").
pub fn write_json_atomic<T: serde::Serialize + ?Sized>(
    path: &Path,
    value: &T,
) -> Result<(), AtomicWriteError> {
    super::finite_json::check_json(value).map_err(|source| AtomicWriteError::NonFinite {
        path: path.to_path_buf(),
        source,
    })?;
    let text = serde_json::to_string_pretty(value).map_err(|e| AtomicWriteError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(e),
    })?;
    write_bytes_atomic(path, format!("{text}\n").as_bytes())
}

/// Convenience: write a whole byte string atomically.
pub fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> Result<(), AtomicWriteError> {
    write_atomic(path, |w| {
        w.write_all(bytes).map_err(|source| AtomicWriteError::Io {
            path: path.to_path_buf(),
            source,
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_fill_leaves_no_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.csv");
        let r: Result<(), AtomicWriteError> = write_atomic(&path, |w| {
            w.write_all(b"half").unwrap();
            Err(AtomicWriteError::Io {
                path: path.clone(),
                source: std::io::Error::other("boom"),
            })
        });
        assert!(r.is_err());
        assert!(!path.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn complete_fill_is_renamed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.csv");
        write_bytes_atomic(&path, b"x,y\n1,2\n").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"x,y\n1,2\n");
    }

    #[test]
    fn temp_names_carry_their_pid() {
        assert_eq!(temp_owner(".cal.csv.tmp-1234"), Some(1234));
        assert_eq!(temp_owner("cal.csv.tmp-1234"), None);
        assert_eq!(temp_owner(".cal.csv"), None);
    }
}
