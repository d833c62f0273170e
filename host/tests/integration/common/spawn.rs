//! Spawning the CLI under test. Every test of this binary that runs `rigctl` does it through
//! this module, so that `RIGCTL_UNDER_TEST` runs all of them against another build (e.g. an
//! older one, to see which of them it fails); the test
//! `every_spawn_of_the_cli_goes_through_here` keeps it so.
//!
//! - [`output`]: run `rigctl ARGS` to its end (stdin closed), stdout and stderr captured.
//! - [`rigctl`]: the `Command` for anything more (a working directory, stdin, environment,
//!   redirected streams, or [`Command::spawn`] for a child to signal); [`bin`] is its program.
//! - [`text`]: a captured stream as text.
//! - [`rig!`] and [`run_for`]: a run with a time bound, as a [`Run`].
//! - [`bin_dir`]: a folder whose `rigctl` is the binary under test, for shells that call it by
//!   name on `PATH`.

use std::ffi::{OsStr, OsString};
use std::io::Read;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The outcome of one run: exit code (`None` when killed at the time bound), stdout, stderr.
pub struct Run {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
    pub timed_out: bool,
}

impl Run {
    pub fn show(&self) -> String {
        format!(
            "exit {:?}{}; stderr: {}",
            self.code,
            if self.timed_out { " (killed)" } else { "" },
            self.stderr.chars().take(600).collect::<String>()
        )
    }
}

/// The binary under test: `RIGCTL_UNDER_TEST` when set, else the `rigctl` cargo built.
pub fn bin() -> OsString {
    std::env::var_os("RIGCTL_UNDER_TEST").unwrap_or_else(|| env!("CARGO_BIN_EXE_rigctl").into())
}

/// `rigctl` (the binary under test) as a `Command`, for the caller to add its arguments and
/// whatever else the run needs.
pub fn rigctl() -> Command {
    Command::new(bin())
}

/// Runs `rigctl args` to its end: stdin closed, the exit status, stdout and stderr.
pub fn output<S: AsRef<OsStr>>(args: &[S]) -> Output {
    rigctl().args(args).output().expect("rigctl runs")
}

/// A captured stream as text (invalid UTF-8 replaced).
/// [`output`] of a run that must succeed: panics naming the arguments, stdout and stderr
/// otherwise.
pub fn output_ok(args: &[&str]) -> Output {
    let out = output(args);
    assert!(
        out.status.success(),
        "rigctl {}: {}\n{}",
        args.join(" "),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// A path as an argument (test paths are UTF-8).
pub fn path_arg(p: &std::path::Path) -> &str {
    p.to_str().expect("utf-8 path")
}

pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A folder holding `rigctl`, the binary under test: the folder cargo built it in, or with
/// `RIGCTL_UNDER_TEST` a folder (in the temporary directory) with a link by that name to it.
#[cfg(unix)]
pub fn bin_dir() -> PathBuf {
    let Some(under_test) = std::env::var_os("RIGCTL_UNDER_TEST") else {
        return PathBuf::from(env!("CARGO_BIN_EXE_rigctl"))
            .parent()
            .expect("the binary's folder")
            .to_path_buf();
    };
    let target = std::fs::canonicalize(&under_test).unwrap_or_else(|e| {
        panic!(
            "RIGCTL_UNDER_TEST={}: {e}",
            PathBuf::from(&under_test).display()
        )
    });
    let dir = std::env::temp_dir().join(format!("rigctl_under_test_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a folder for the link");
    let link = dir.join("rigctl");
    if std::fs::read_link(&link).ok().as_ref() != Some(&target) {
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink(&target, &link).expect("link to RIGCTL_UNDER_TEST");
    }
    dir
}

/// Runs `rigctl args` for at most `limit`.
pub fn run_for(args: &[&OsStr], limit: Duration) -> Run {
    let mut child = rigctl()
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("rigctl runs");
    let mut out = child.stdout.take().unwrap();
    let mut err = child.stderr.take().unwrap();
    let t_out = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = out.read_to_end(&mut s);
        s
    });
    let t_err = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = err.read_to_end(&mut s);
        s
    });
    let start = Instant::now();
    let mut timed_out = false;
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            timed_out = true;
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Run {
        code: status.and_then(|s| s.code()),
        stdout: text(&t_out.join().unwrap()),
        stderr: text(&t_err.join().unwrap()),
        timed_out,
    }
}

/// An argument of [`rig!`] (a string or a path) as an `OsStr`.
pub fn os<S: AsRef<OsStr> + ?Sized>(s: &S) -> &OsStr {
    s.as_ref()
}

/// `rig!(LIMIT_S; ARG, ...)`: [`run_for`] with arguments given as strings and paths and a time
/// bound in seconds.
macro_rules! rig_ {
    ($limit:expr; $($a:expr),* $(,)?) => {
        $crate::common::spawn::run_for(
            &[$($crate::common::spawn::os(&$a)),*],
            std::time::Duration::from_secs($limit),
        )
    };
}
pub(crate) use rig_ as rig;

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use crate::common::spawn_rule::{offences, own_spawns};

    /// Every test of this binary runs the CLI through this module (so `RIGCTL_UNDER_TEST`
    /// reaches all of them): no other file under `tests/integration` names the binary's cargo
    /// path or makes its own `Command` of it.
    #[test]
    fn every_spawn_of_the_cli_goes_through_here() {
        let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/integration");
        let exempt = ["common/spawn.rs", "common/spawn_rule.rs"].map(|f| root.join(f));
        let found = offences(&root, &exempt);
        assert!(
            found.is_empty(),
            "run the CLI through common::spawn (output, rigctl, rig!):\n{}",
            found.join("\n")
        );
        // the rule sees what it is for
        let own = "let o = Command::new(\n    env!(\"CARGO_BIN_EXE_rigctl\"))";
        assert_eq!(own_spawns(own).len(), 2);
        assert_eq!(own_spawns("Command::new(bin()).arg(x)").len(), 1);
        assert!(own_spawns("Command::new(\"python3\").args([\"-c\", p])").is_empty());
    }
}
