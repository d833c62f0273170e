//! The files of one command run, declared in one place and checked before any work:
//!
//! - every output is usable: its directory exists, it is not a directory, it can be written
//!   (bad input, exit 2, when the path itself is wrong; a failure, exit 1, when the system
//!   refuses, e.g. permission denied);
//! - no output is, or resolves to (through symbolic links or hard links), one of the inputs or
//!   another output: writing it would destroy the input (exit 2);
//! - an output directory (`simulate --out DIR`, `diagnose --plots DIR`, `export --csv DIR`) is a
//!   directory or a new path under an existing one, and none of the inputs is a file the command
//!   writes into it.
//!
//! Identity is the file's device and inode when it exists (after following links), otherwise the
//! canonical parent directory joined with the file name.

use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use crate::io::atomic::{check_output, declare_output_dir, resolve_output, AtomicWriteError};
use crate::io::shown::shown;

#[derive(Debug, thiserror::Error)]
pub enum FilesError {
    #[error(
        "{flag} {}: is also the input {input_flag} {}: refusing to overwrite an input",
        shown(path),
        shown(input)
    )]
    OutputIsInput {
        flag: String,
        path: PathBuf,
        input_flag: String,
        input: PathBuf,
    },
    #[error(
        "{flag} {} and {other_flag} {}: the same file written twice",
        shown(path),
        shown(other)
    )]
    OutputTwice {
        flag: String,
        path: PathBuf,
        other_flag: String,
        other: PathBuf,
    },
    #[error(
        "{flag} {} is also {other_flag}: the held-out data must be other data",
        shown(path)
    )]
    SameData {
        flag: String,
        path: PathBuf,
        other_flag: String,
    },
    #[error("{flag} {}: {reason}", shown(path))]
    BadDir {
        flag: String,
        path: PathBuf,
        reason: String,
    },
    #[error(
        "{flag} {}: already exists in the run directory {dir_flag} {} that the command reads: refusing to overwrite a file of the run (give a new name)",
        shown(path),
        shown(dir)
    )]
    InRunDir {
        flag: String,
        path: PathBuf,
        dir_flag: String,
        dir: PathBuf,
    },
    #[error(transparent)]
    Output(#[from] AtomicWriteError),
}

impl crate::error::Classify for FilesError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::Output(e) => e.kind(),
            _ => crate::error::ErrorKind::BadInput,
        }
    }
}

/// What a file is, for comparing two paths.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Identity {
    Inode(u64, u64),
    Path(PathBuf),
}

fn identity(path: &Path) -> Option<Identity> {
    if let Ok(m) = std::fs::metadata(path) {
        return Some(Identity::Inode(m.dev(), m.ino()));
    }
    // not there yet: its directory's canonical form and its name
    let name = path.file_name()?;
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let dir = std::fs::canonicalize(parent).ok()?;
    Some(Identity::Path(dir.join(name)))
}

/// The identity of what writing `path` would replace (links followed, dangling ones included).
fn output_identity(path: &Path) -> Option<Identity> {
    match resolve_output(path) {
        Ok(t) => identity(t.path()),
        Err(_) => identity(path),
    }
}

struct OutDir {
    flag: String,
    path: PathBuf,
    writes: fn(&str) -> bool,
}

/// A directory read by the command: its flag, its path, and which existing files in it an
/// output may replace.
type RunDir = (String, PathBuf, fn(&Path) -> bool);

/// The declared files of one run; [`RunFiles::check`] before the work.
#[derive(Default)]
pub struct RunFiles {
    inputs: Vec<(String, PathBuf)>,
    outputs: Vec<(String, PathBuf)>,
    dirs: Vec<OutDir>,
    run_dirs: Vec<RunDir>,
    apart: Vec<(String, String)>,
}

impl RunFiles {
    pub fn new() -> Self {
        Self::default()
    }

    /// An input file (read by the command), if given.
    pub fn input(mut self, flag: &str, path: Option<&Path>) -> Self {
        if let Some(p) = path {
            self.inputs.push((flag.to_string(), p.to_path_buf()));
        }
        self
    }

    /// Several input files of one flag.
    pub fn inputs(mut self, flag: &str, paths: &[PathBuf]) -> Self {
        for p in paths {
            self.inputs.push((flag.to_string(), p.clone()));
        }
        self
    }

    /// A directory the command reads (`report RUN_DIR`): every file in it is an input (links
    /// followed), and an output inside it must be a new name (no entry of that name at all) or
    /// a file `replaceable` accepts (an earlier output of the same command, e.g. a report page).
    pub fn input_dir(mut self, flag: &str, path: &Path, replaceable: fn(&Path) -> bool) -> Self {
        if let Ok(entries) = std::fs::read_dir(path) {
            for e in entries.flatten() {
                let p = path.join(e.file_name());
                if !replaceable(&p) {
                    self.inputs.push((format!("{flag} file"), p));
                }
            }
        }
        self.run_dirs
            .push((flag.to_string(), path.to_path_buf(), replaceable));
        self
    }

    /// An output file, if given.
    pub fn output(mut self, flag: &str, path: Option<&Path>) -> Self {
        if let Some(p) = path {
            self.outputs.push((flag.to_string(), p.to_path_buf()));
        }
        self
    }

    /// An output directory (created if missing) into which the command writes the files whose
    /// names `writes` accepts.
    pub fn output_dir(mut self, flag: &str, path: Option<&Path>, writes: fn(&str) -> bool) -> Self {
        if let Some(p) = path {
            self.dirs.push(OutDir {
                flag: flag.to_string(),
                path: p.to_path_buf(),
                writes,
            });
        }
        self
    }

    /// The inputs of flags `a` and `b` must be different files (calibration and held-out data).
    pub fn apart(mut self, a: &str, b: &str) -> Self {
        self.apart.push((a.to_string(), b.to_string()));
        self
    }

    /// Checks every declared file; see the module documentation.
    pub fn check(&self) -> Result<(), FilesError> {
        let inputs: Vec<(&str, &Path, Identity)> = self
            .inputs
            .iter()
            .filter_map(|(f, p)| identity(p).map(|id| (f.as_str(), p.as_path(), id)))
            .collect();
        for (a, b) in &self.apart {
            for (fa, pa, ia) in inputs.iter().filter(|(f, _, _)| f == a) {
                if inputs.iter().any(|(fb, _, ib)| fb == b && ib == ia) {
                    return Err(FilesError::SameData {
                        flag: fa.to_string(),
                        path: pa.to_path_buf(),
                        other_flag: b.clone(),
                    });
                }
            }
        }
        let mut seen: Vec<(&str, &Path, Identity)> = Vec::new();
        for (flag, path) in &self.outputs {
            self.check_not_in_run_dir(flag, path)?;
            check_output(path)?;
            let Some(id) = output_identity(path) else {
                continue;
            };
            if let Some((f, p, _)) = inputs.iter().find(|(_, _, i)| *i == id) {
                return Err(FilesError::OutputIsInput {
                    flag: flag.clone(),
                    path: path.clone(),
                    input_flag: f.to_string(),
                    input: p.to_path_buf(),
                });
            }
            if let Some((f, p, _)) = seen.iter().find(|(_, _, i)| *i == id) {
                return Err(FilesError::OutputTwice {
                    flag: flag.clone(),
                    path: path.clone(),
                    other_flag: f.to_string(),
                    other: p.to_path_buf(),
                });
            }
            seen.push((flag, path, id));
        }
        for d in &self.dirs {
            self.check_dir(d, &inputs, &seen)?;
        }
        Ok(())
    }

    /// An output inside a run directory the command reads must be a new name.
    fn check_not_in_run_dir(&self, flag: &str, path: &Path) -> Result<(), FilesError> {
        let parent = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let Ok(parent) = std::fs::canonicalize(parent) else {
            return Ok(());
        };
        for (rflag, dir, replaceable) in &self.run_dirs {
            let same = std::fs::canonicalize(dir).is_ok_and(|d| d == parent);
            if same && std::fs::symlink_metadata(path).is_ok() && !replaceable(path) {
                return Err(FilesError::InRunDir {
                    flag: flag.to_string(),
                    path: path.to_path_buf(),
                    dir_flag: rflag.clone(),
                    dir: dir.clone(),
                });
            }
        }
        Ok(())
    }

    fn check_dir(
        &self,
        d: &OutDir,
        inputs: &[(&str, &Path, Identity)],
        outputs: &[(&str, &Path, Identity)],
    ) -> Result<(), FilesError> {
        let bad = |reason: String| FilesError::BadDir {
            flag: d.flag.clone(),
            path: d.path.clone(),
            reason,
        };
        match std::fs::metadata(&d.path) {
            Ok(m) if !m.is_dir() => return Err(bad("exists and is not a directory".into())),
            Ok(_) => {
                let canon = std::fs::canonicalize(&d.path)
                    .map_err(|e| bad(format!("cannot resolve: {e}")))?;
                let inside = |p: &Path| {
                    let name = p.file_name().map(|n| n.to_string_lossy().into_owned());
                    let dir = p
                        .parent()
                        .map(|q| {
                            if q.as_os_str().is_empty() {
                                Path::new(".")
                            } else {
                                q
                            }
                        })
                        .and_then(|q| std::fs::canonicalize(q).ok());
                    // the file itself, resolved through a link, or its name in the directory
                    let target = std::fs::canonicalize(p).ok();
                    let hit = |dir: Option<PathBuf>, name: Option<String>| {
                        dir.as_deref() == Some(canon.as_path())
                            && name.as_deref().is_some_and(d.writes)
                    };
                    hit(dir, name)
                        || target.as_ref().is_some_and(|t| {
                            hit(
                                t.parent().map(Path::to_path_buf),
                                t.file_name().map(|n| n.to_string_lossy().into_owned()),
                            )
                        })
                };
                if let Some((f, p, _)) = inputs.iter().find(|(_, p, _)| inside(p)) {
                    return Err(bad(format!(
                        "would overwrite the input {f} {}: refusing",
                        shown(p)
                    )));
                }
                if let Some((f, p, _)) = outputs.iter().find(|(_, p, _)| inside(p)) {
                    return Err(bad(format!("would be written over by {f} {}", shown(p))));
                }
                self.check_dir_entries(d, inputs, outputs)?;
                let probe = d
                    .path
                    .join(format!(".rigctl-probe.tmp-{}", std::process::id()));
                // registered before it exists: a signal at any point leaves no probe behind
                crate::io::interrupt::register_temp(&probe);
                let created = std::fs::File::create(&probe);
                if created.is_ok() {
                    let _ = std::fs::remove_file(&probe);
                }
                crate::io::interrupt::unregister_temp(&probe);
                created.map_err(|source| AtomicWriteError::Io {
                    path: d.path.clone(),
                    source,
                })?;
            }
            Err(_) => {
                if std::fs::symlink_metadata(&d.path).is_ok() {
                    return Err(bad("is a dangling symbolic link".into()));
                }
                let parent = match d.path.parent() {
                    Some(p) if !p.as_os_str().is_empty() => p,
                    _ => Path::new("."),
                };
                if !parent.is_dir() {
                    return Err(bad(format!(
                        "its directory {} does not exist",
                        shown(parent)
                    )));
                }
            }
        }
        // whatever the command writes into the folder replaces the entry there (a link is
        // replaced, never followed)
        declare_output_dir(&d.path);
        Ok(())
    }

    /// The entries already in an output folder under the names the command writes: none may
    /// be, resolve to (a symbolic link) or share its inode with (a hard link) an input or
    /// another output.
    fn check_dir_entries(
        &self,
        d: &OutDir,
        inputs: &[(&str, &Path, Identity)],
        outputs: &[(&str, &Path, Identity)],
    ) -> Result<(), FilesError> {
        let Ok(entries) = std::fs::read_dir(&d.path) else {
            return Ok(());
        };
        for e in entries.flatten() {
            let name = e.file_name();
            if !(d.writes)(&name.to_string_lossy()) {
                continue;
            }
            let entry = d.path.join(&name);
            let Some(id) = identity(&entry) else {
                continue;
            };
            let clash = inputs
                .iter()
                .map(|(f, p, i)| (f, p, i, "input "))
                .chain(outputs.iter().map(|(f, p, i)| (f, p, i, "output ")))
                .find(|(_, _, i, _)| **i == id);
            if let Some((f, p, _, role)) = clash {
                let how = if e.file_type().is_ok_and(|t| t.is_symlink()) {
                    "a link to"
                } else {
                    "the same file as (hard link)"
                };
                return Err(FilesError::BadDir {
                    flag: d.flag.clone(),
                    path: d.path.clone(),
                    reason: format!(
                        "{} is {how} the {role}{f} {}: refusing to write it",
                        shown(&entry),
                        shown(p)
                    ),
                });
            }
        }
        Ok(())
    }
}

/// Every file name: for directories the command fills with names it chooses.
pub fn any_name(_: &str) -> bool {
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_equal_to_input_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.csv");
        std::fs::write(&a, "x").unwrap();
        let e = RunFiles::new()
            .input("--poses", Some(&a))
            .output("--out", Some(&a))
            .check()
            .unwrap_err();
        assert!(matches!(e, FilesError::OutputIsInput { .. }), "{e}");
        // through a symbolic link and a relative spelling
        let link = dir.path().join("l.csv");
        std::os::unix::fs::symlink("a.csv", &link).unwrap();
        let e = RunFiles::new()
            .input("--poses", Some(&a))
            .output("--out", Some(&link))
            .check()
            .unwrap_err();
        assert!(matches!(e, FilesError::OutputIsInput { .. }), "{e}");
        assert!(RunFiles::new()
            .input("--poses", Some(&a))
            .output("--out", Some(&dir.path().join("b.csv")))
            .check()
            .is_ok());
    }

    #[test]
    fn same_new_output_twice_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let b = dir.path().join("b.json");
        let e = RunFiles::new()
            .output("--json", Some(&b))
            .output("--out", Some(&dir.path().join(".").join("b.json")))
            .check()
            .unwrap_err();
        assert!(matches!(e, FilesError::OutputTwice { .. }), "{e}");
    }

    #[test]
    fn output_dir_that_is_a_file_or_holds_an_input() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("keep.json");
        std::fs::write(&f, "{}").unwrap();
        let e = RunFiles::new()
            .output_dir("--plots", Some(&f), any_name)
            .check()
            .unwrap_err();
        assert!(matches!(e, FilesError::BadDir { .. }), "{e}");
        let e = RunFiles::new()
            .input("--poses", Some(&f))
            .output_dir("--out", Some(dir.path()), |n| n == "keep.json")
            .check()
            .unwrap_err();
        assert!(matches!(e, FilesError::BadDir { .. }), "{e}");
        assert!(RunFiles::new()
            .input("--poses", Some(&f))
            .output_dir("--out", Some(dir.path()), |n| n == "cal.csv")
            .check()
            .is_ok());
    }
}
