//! Shared by the integration tests: the files of `../shared`, which CI requires.
#![allow(dead_code)]

use std::path::PathBuf;

/// `rel` (a file or folder) under the shared directory (`rigctl::shared_dir()`: `$RIG_SHARED_DIR`
/// or `../shared`), or `None` after a `SKIPPED` message when it is absent. With `CI=true` its
/// absence fails the test instead: CI runs with `../shared` beside the clone, so a missing file
/// there is a broken setup, never a reason to pass.
pub fn shared_file(test: &str, rel: &str) -> Option<PathBuf> {
    let path = rigctl::shared_dir().map(|d| d.join(rel));
    if let Some(p) = path.filter(|p| p.exists()) {
        return Some(p);
    }
    let msg = format!("{test}: ../shared/{rel} is absent (or set RIG_SHARED_DIR)");
    if rigctl::in_ci() {
        panic!("{msg}; with CI=true the shared data is required");
    }
    eprintln!("SKIPPED {msg}");
    None
}
