//! The rule that every test runs the CLI through its crate's one spawn helper (so that
//! `RIGCTL_UNDER_TEST` reaches every test): the integration tests' `common::spawn` and the
//! end-to-end tests' `rig_tests::rigctl` check their folders with [`offences`].

use std::path::{Path, PathBuf};

/// The `.rs` files under `dir`.
fn sources(dir: &Path, found: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("the test folder reads") {
        let path = entry.expect("a folder entry").path();
        if path.is_dir() {
            sources(&path, found);
        } else if path.extension().is_some_and(|e| e == "rs") {
            found.push(path);
        }
    }
}

/// What in `src` runs the CLI without the helper: the binary's cargo path (`CARGO_BIN_EXE`),
/// `RIGCTL_UNDER_TEST`, or a `Command::new(..)` whose argument names `bin(`, `CARGO_BIN_EXE` or
/// `rigctl`.
pub fn own_spawns(src: &str) -> Vec<String> {
    let flat: String = src.chars().filter(|c| !c.is_whitespace()).collect();
    let mut found: Vec<String> = ["CARGO_BIN_EXE", "RIGCTL_UNDER_TEST"]
        .into_iter()
        .filter(|n| flat.contains(n))
        .map(String::from)
        .collect();
    for (at, call) in flat.match_indices("Command::new(") {
        let rest = &flat[at + call.len()..];
        let mut depth = 1;
        let end = rest
            .char_indices()
            .find(|&(_, c)| {
                depth += match c {
                    '(' => 1,
                    ')' => -1,
                    _ => 0,
                };
                depth == 0
            })
            .map_or(rest.len(), |(i, _)| i);
        let arg = &rest[..end];
        let lower = arg.to_ascii_lowercase();
        if ["bin(", "cargo_bin_exe", "rigctl"]
            .iter()
            .any(|n| lower.contains(n))
        {
            found.push(format!("{call}{arg})"));
        }
    }
    found
}

/// `file: what` for every [`own_spawns`] of the `.rs` files under `root` but the `exempt` ones
/// (the helper), in file order; panics when `root` holds no source at all.
pub fn offences(root: &Path, exempt: &[PathBuf]) -> Vec<String> {
    let mut files = Vec::new();
    sources(root, &mut files);
    files.sort();
    assert!(
        !files.is_empty(),
        "no test sources under {}",
        root.display()
    );
    files
        .iter()
        .filter(|f| !exempt.contains(f))
        .flat_map(|f| {
            let src = std::fs::read_to_string(f).expect("the test source reads");
            let name = f.strip_prefix(root).unwrap_or(f).display().to_string();
            own_spawns(&src)
                .into_iter()
                .map(move |what| format!("{name}: {what}"))
        })
        .collect()
}
