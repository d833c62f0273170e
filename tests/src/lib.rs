//! Helpers for the end-to-end tests in `tests/tests/e2e/`.

use std::path::PathBuf;
use std::process::Command;

/// `rigctl`, the binary under test ([`rigctl_path`]), as a `Command`: every end-to-end test runs
/// the CLI through this (`every_spawn_of_the_cli_goes_through_the_helper` keeps it so).
pub fn rigctl() -> Command {
    Command::new(rigctl_path())
}

/// The binary under test: `RIGCTL_UNDER_TEST` when set (the tests run against another build,
/// e.g. an older one, to see which of them it fails), else the `rigctl` this workspace builds
/// (cargo builds it before running the tests of the workspace; if it is missing it is built
/// here).
pub fn rigctl_path() -> PathBuf {
    if let Some(under_test) = std::env::var_os("RIGCTL_UNDER_TEST") {
        return PathBuf::from(under_test);
    }
    let exe = std::env::current_exe().expect("test executable path");
    // target/<profile>/deps/<test> -> target/<profile>/rigctl
    let profile_dir = exe.parent().and_then(|d| d.parent()).expect("target dir");
    let bin = profile_dir.join(format!("rigctl{}", std::env::consts::EXE_SUFFIX));
    if !bin.exists() {
        let status = Command::new(env!("CARGO"))
            .args(["build", "-p", "rigctl", "--bin", "rigctl"])
            .status()
            .expect("run cargo build");
        assert!(status.success(), "cargo build -p rigctl failed");
    }
    bin
}

/// `../shared` beside the checkout, or `None` with a message saying the test is skipped. With
/// `CI=true` its absence fails the test instead: CI runs with `../shared` beside the clone, so a
/// missing shared directory there is a broken setup, never a reason to pass.
pub fn shared_or_skip(test: &str) -> Option<PathBuf> {
    let dir = rigctl::shared_dir();
    if dir.is_none() {
        let msg = format!("{test}: ../shared (or $RIG_SHARED_DIR) is absent");
        assert!(
            !rigctl::in_ci(),
            "{msg}; with CI=true the shared data is required"
        );
        eprintln!("SKIPPED {msg}");
    }
    dir
}
