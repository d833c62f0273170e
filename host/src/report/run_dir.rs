//! What a run directory holds: the files `rigctl report` understands, and their provenance.

use std::path::{Path, PathBuf};

use serde_json::Value;
use sha2::{Digest, Sha256};

use super::ReportError;

/// File name `rigctl report` reads the per-sample path errors from.
pub const PATH_ERRORS_FILE: &str = "path_errors.csv";

/// Name, size and SHA-256 of one file of the run directory.
#[derive(Debug, Clone, PartialEq)]
pub struct FileInfo {
    /// File name (no directory).
    pub name: String,
    /// Size in bytes.
    pub size_bytes: u64,
    /// SHA-256 of the content, lowercase hex.
    pub sha256: String,
    /// What the report used it as (`"calibration poses"`, `"model"`, ...; empty if unused).
    pub role: String,
}

/// The files found in a run directory, sorted by role.
#[derive(Debug, Clone, Default)]
pub struct RunDir {
    /// The directory.
    pub dir: PathBuf,
    /// Every regular file, sorted by name.
    pub files: Vec<FileInfo>,
    /// `cal.csv`.
    pub cal_csv: Option<PathBuf>,
    /// `val.csv`.
    pub val_csv: Option<PathBuf>,
    /// `truth.json` (from `rigctl simulate`), parsed.
    pub truth_json: Option<Value>,
    /// `truth.toml` (the simulated truth model).
    pub truth_toml: Option<PathBuf>,
    /// Every `calibrate*.json`, parsed: (file name, document).
    pub calibrate: Vec<(String, Value)>,
    /// Every `diagnose*.json`, parsed, sorted by name.
    pub diagnose: Vec<(String, Value)>,
    /// `plan.csv` (from `rigctl plan --out`: `q1..qN,nom_x,nom_y,nom_z`).
    pub plan_csv: Option<PathBuf>,
    /// `plan.json` (from `rigctl plan --json`), parsed.
    pub plan_json: Option<(String, Value)>,
    /// Every `*overlay*.png` (from `rigctl trace --overlay`), sorted by name.
    pub overlays: Vec<PathBuf>,
    /// `path_errors.csv` (per-sample errors of `calibrate --samples --errors-csv`).
    pub path_errors: Option<PathBuf>,
    /// Every other `*.toml` (calibrated models), sorted by name.
    pub models: Vec<PathBuf>,
    /// Recorded command lines (`commands.txt`, `*.cmd`), (file name, text).
    pub commands: Vec<(String, String)>,
    /// Things that could not be used, with the reason.
    pub notes: Vec<String>,
}

/// Lowercase hex SHA-256 of `bytes`.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

fn read_json(path: &Path, name: &str, notes: &mut Vec<String>) -> Option<Value> {
    let text = crate::io::read::read_text_capped(path, crate::io::read::CAP_SMALL_TEXT)
        .map_err(|e| notes.push(format!("{name}: cannot read: {e}")))
        .ok()?;
    serde_json::from_str(&text)
        .map_err(|e| notes.push(format!("{name}: not valid JSON ({e}); skipped")))
        .ok()
}

/// The fields of FORMATS.md "diagnose --json" that the report's conclusions read.
fn diagnose_shape(doc: &Value) -> Result<(), String> {
    let obj = doc
        .as_object()
        .ok_or("not a diagnose --json document (not a JSON object)")?;
    for key in ["declared", "final"] {
        if !obj.get(key).is_some_and(Value::is_object) {
            return Err(format!(
                "not a diagnose --json document: `{key}` missing or not an object"
            ));
        }
    }
    let effects = obj
        .get("effects")
        .and_then(Value::as_array)
        .ok_or("not a diagnose --json document: `effects` missing or not an array")?;
    for (k, e) in effects.iter().enumerate() {
        if !e.get("id").is_some_and(Value::is_string) {
            return Err(format!("`effects[{k}].id` missing or not a string"));
        }
    }
    if let Some(a) = obj.get("aliased") {
        if !a.is_array() {
            return Err("`aliased` is not an array".into());
        }
    }
    Ok(())
}

impl RunDir {
    /// Scans `dir` (not recursively). Unreadable or malformed files become notes; only a
    /// missing or unreadable directory is an error.
    pub fn scan(dir: &Path) -> Result<Self, ReportError> {
        let io = |source| ReportError::Dir {
            path: dir.to_path_buf(),
            source,
        };
        let mut run = RunDir {
            dir: dir.to_path_buf(),
            ..Default::default()
        };
        let mut names: Vec<String> = Vec::new();
        for e in std::fs::read_dir(dir).map_err(io)?.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') {
                continue;
            }
            let link = e.file_type().is_ok_and(|t| t.is_symlink());
            // a symbolic link is read as the file it points to; a dangling one is a note
            match std::fs::metadata(e.path()) {
                Ok(m) if m.is_file() => names.push(name),
                Err(err) if link => run.notes.push(format!(
                    "{}: a symbolic link to nothing readable ({err}): skipped",
                    crate::io::shown::escape(&name)
                )),
                _ => {}
            }
        }
        names.sort();
        for name in names {
            let path = dir.join(&name);
            let bytes = match crate::io::read::read_capped(&path, crate::io::read::CAP_TABLE) {
                Ok(b) => b,
                Err(e) => {
                    run.notes.push(format!("{name}: cannot read: {e}"));
                    continue;
                }
            };
            let lower = name.to_ascii_lowercase();
            let role = if lower == "cal.csv" {
                run.cal_csv = Some(path.clone());
                "calibration poses"
            } else if lower == "val.csv" {
                run.val_csv = Some(path.clone());
                "validation poses"
            } else if lower == "truth.json" {
                run.truth_json = read_json(&path, &name, &mut run.notes);
                "simulation truth"
            } else if lower == "truth.toml" {
                run.truth_toml = Some(path.clone());
                "truth model"
            } else if lower.starts_with("calibrate") && lower.ends_with(".json") {
                match read_json(&path, &name, &mut run.notes) {
                    Some(v) => {
                        run.calibrate.push((name.clone(), v));
                        "calibrate result"
                    }
                    None => "",
                }
            } else if lower.starts_with("diagnose") && lower.ends_with(".json") {
                match read_json(&path, &name, &mut run.notes) {
                    Some(v) => {
                        // a conclusion drawn from a document of another shape would be wrong
                        diagnose_shape(&v).map_err(|reason| ReportError::Shape {
                            path: path.clone(),
                            reason,
                        })?;
                        run.diagnose.push((name.clone(), v));
                        "diagnose result"
                    }
                    None => "",
                }
            } else if lower == PATH_ERRORS_FILE {
                run.path_errors = Some(path.clone());
                "path errors along the drawn path"
            } else if lower == "plan.csv" {
                run.plan_csv = Some(path.clone());
                "planned poses"
            } else if lower == "plan.json" {
                match read_json(&path, &name, &mut run.notes) {
                    Some(v) => {
                        run.plan_json = Some((name.clone(), v));
                        "plan summary"
                    }
                    None => "",
                }
            } else if lower.contains("overlay") && lower.ends_with(".png") {
                run.overlays.push(path.clone());
                "trace overlay"
            } else if lower.ends_with(".toml") {
                run.models.push(path.clone());
                "model"
            } else if lower == "commands.txt" || lower.ends_with(".cmd") {
                run.commands
                    .push((name.clone(), String::from_utf8_lossy(&bytes).into_owned()));
                "command lines"
            } else {
                ""
            };
            run.files.push(FileInfo {
                name,
                size_bytes: bytes.len() as u64,
                sha256: sha256_hex(&bytes),
                role: role.to_string(),
            });
        }
        Ok(run)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sha256_matches_the_fips_180_2_examples() {
        // FIPS 180-2 appendix B.1 and the empty message.
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        assert_eq!(
            sha256_hex(b""),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
        );
    }

    #[test]
    fn malformed_json_is_a_note_not_an_error() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("calibrate.json"), "{not json").unwrap();
        std::fs::write(dir.path().join("m.toml"), "x").unwrap();
        let run = RunDir::scan(dir.path()).unwrap();
        assert!(run.calibrate.is_empty());
        assert_eq!(run.notes.len(), 1, "{:?}", run.notes);
        assert!(run.notes[0].contains("calibrate.json"));
        assert_eq!(run.models.len(), 1);
        assert_eq!(run.files.len(), 2);
    }
}
