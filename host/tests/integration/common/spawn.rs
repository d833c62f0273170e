//! Spawning the CLI under test with a time bound: the exit code (`None` when killed), stdout
//! and stderr.

use std::io::Read;
use std::process::{Command, Stdio};
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

/// The binary under test (`RIGCTL_UNDER_TEST` runs these tests against another build, e.g. an
/// older one, to see which of them it fails).
pub fn bin() -> std::ffi::OsString {
    std::env::var_os("RIGCTL_UNDER_TEST").unwrap_or_else(|| env!("CARGO_BIN_EXE_rigctl").into())
}

/// Runs `rigctl args` for at most `limit`.
pub fn run_for(args: &[&std::ffi::OsStr], limit: Duration) -> Run {
    let mut child = Command::new(bin())
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
        stdout: String::from_utf8_lossy(&t_out.join().unwrap()).into_owned(),
        stderr: String::from_utf8_lossy(&t_err.join().unwrap()).into_owned(),
        timed_out,
    }
}

pub fn os<S: AsRef<std::ffi::OsStr> + ?Sized>(s: &S) -> &std::ffi::OsStr {
    s.as_ref()
}

/// Runs with arguments given as strings and paths.
macro_rules! rig_ {
    ($limit:expr; $($a:expr),* $(,)?) => {
        $crate::common::spawn::run_for(
            &[$($crate::common::spawn::os(&$a)),*],
            std::time::Duration::from_secs($limit),
        )
    };
}
pub(crate) use rig_ as rig;
