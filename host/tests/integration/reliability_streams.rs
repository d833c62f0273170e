//! Issue 15, defect 2 for every subcommand: no command can be made to exit 101 (a panic) by
//! its standard streams. Each subcommand of `rigctl --help` (and `--help`, `--version`) runs
//! once normally, then with
//!
//! - stdout a pipe whose reader has gone (`| true`): exit 0 or 141, quietly;
//! - stdout `/dev/full` (`> /dev/full`): exit 1 with "No space left" when the command prints
//!   on stdout, else its normal exit;
//! - stderr a closed pipe (`2>&-` of a pipeline) and stderr `/dev/full` (`2> /dev/full`): its
//!   normal exit code (stderr errors are ignored, never a panic).
//!
//! `record` and `board-sim` run against each other, one of them with the hostile stream. The
//! inputs and command lines of every subcommand are in `commands`.

mod commands;

use std::ffi::OsString;
use std::fs::OpenOptions;
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use super::common::record::record;
use super::common::spawn::{rigctl, text};
use commands::commands;

/// The hostile streams tried on every command.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Hostile {
    ClosedStdout,
    FullStdout,
    ClosedStderr,
    FullStderr,
}

const HOSTILE: [Hostile; 4] = [
    Hostile::ClosedStdout,
    Hostile::FullStdout,
    Hostile::ClosedStderr,
    Hostile::FullStderr,
];

fn dev_full() -> Option<std::fs::File> {
    OpenOptions::new().write(true).open("/dev/full").ok()
}

/// Spawns `cmd` with `how` applied (the other stream piped), returns the child.
fn spawn_hostile(mut cmd: Command, how: Hostile) -> Option<Child> {
    cmd.stdin(Stdio::null());
    match how {
        Hostile::ClosedStdout | Hostile::ClosedStderr => {
            cmd.stdout(Stdio::piped()).stderr(Stdio::piped());
        }
        Hostile::FullStdout => {
            cmd.stdout(dev_full()?).stderr(Stdio::piped());
        }
        Hostile::FullStderr => {
            cmd.stdout(Stdio::piped()).stderr(dev_full()?);
        }
    }
    let mut child = cmd.spawn().expect("spawn rigctl");
    match how {
        Hostile::ClosedStdout => drop(child.stdout.take()),
        Hostile::ClosedStderr => drop(child.stderr.take()),
        _ => {}
    }
    Some(child)
}

/// Checks one hostile run of `name` against its normal run.
fn judge(name: &str, how: Hostile, normal: &Output, got: &Output) {
    let code = got.status.code();
    let err = text(&got.stderr);
    let what = format!("{name} with {how:?}: {code:?}, stderr {err:?}");
    assert_ne!(code, Some(101), "{what}");
    assert!(!err.contains("panicked"), "{what}");
    let normal_code = normal.status.code();
    match how {
        Hostile::ClosedStdout => {
            assert!(matches!(code, Some(0) | Some(141)), "{what}");
            assert!(
                !err.contains("stdout") && !err.contains("Broken pipe"),
                "a closed pipe ends quietly: {what}"
            );
        }
        Hostile::FullStdout if !normal.stdout.is_empty() => {
            assert_eq!(code, Some(1), "{what}");
            assert!(err.contains("No space left"), "{what}");
        }
        Hostile::FullStdout | Hostile::ClosedStderr | Hostile::FullStderr => {
            assert_eq!(code, normal_code, "{what}");
        }
    }
}

fn run_normal(name: &str, args: &[OsString]) -> Output {
    let o = rigctl()
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("run rigctl");
    assert_eq!(o.status.code(), Some(0), "{name}: {}", text(&o.stderr));
    o
}

#[test]
fn defect2_no_subcommand_exits_101_on_closed_or_full_streams() {
    let dir = tempfile::tempdir().unwrap();
    let cases = commands(dir.path());
    let help = run_normal("--help", &[OsString::from("--help")]);
    // Every subcommand listed by --help is in the table (or is `help`, or record/board-sim,
    // tried below against each other).
    let listed = text(&help.stdout);
    let names: Vec<&str> = listed
        .split("Commands:")
        .nth(1)
        .and_then(|s| s.split("Options:").next())
        .unwrap_or_default()
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert!(names.len() > 10, "{listed}");
    for n in &names {
        assert!(
            matches!(*n, "help" | "record" | "board-sim") || cases.iter().any(|(c, _)| c == n),
            "subcommand {n} is not tried"
        );
    }
    record(
        "subcommands",
        names.iter().filter(|n| **n != "help").count(),
    );
    record("runs", cases.len());
    let mut printing = 0;
    for (name, args) in &cases {
        let normal = run_normal(name, args);
        printing += usize::from(!normal.stdout.is_empty());
        for how in HOSTILE {
            let mut cmd = rigctl();
            cmd.args(args);
            let Some(child) = spawn_hostile(cmd, how) else {
                continue;
            };
            let got = child.wait_with_output().unwrap();
            judge(name, how, &normal, &got);
        }
        assert_no_temp_files(dir.path());
    }
    record("runs_printing_on_stdout", printing);
}

fn assert_no_temp_files(dir: &Path) {
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            assert!(!name.contains(".tmp-"), "{name} left in {}", d.display());
            if e.file_type().map(|t| t.is_dir()).unwrap_or(false) {
                stack.push(e.path());
            }
        }
    }
}

/// `rigctl board-sim --link DIR/board` at ten times real time for `duration_s` of board time.
fn board_sim_cmd(link: &Path) -> Command {
    let mut cmd = rigctl();
    cmd.arg("board-sim")
        .arg("--link")
        .arg(link)
        .args(["--speed", "10", "--duration-s", "3"]);
    cmd
}

fn record_cmd(link: &Path, rec: &Path) -> Command {
    let mut cmd = rigctl();
    cmd.args(["record", "--overwrite", "--duration", "0.3", "--port"])
        .arg(link)
        .arg("--out")
        .arg(rec);
    cmd
}

fn wait_for_link(link: &Path) {
    let deadline = Instant::now() + Duration::from_secs(30);
    while std::fs::symlink_metadata(link).is_err() {
        assert!(Instant::now() < deadline, "board-sim made no link");
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Waits at most 60 s for `child`.
fn finish(mut child: Child) -> Output {
    let deadline = Instant::now() + Duration::from_secs(60);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("process did not end");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

fn quiet(mut cmd: Command) -> Child {
    cmd.stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// One record run against one board-sim; `hostile` applies to `which` of the two.
fn acquisition(dir: &Path, which: &str, how: Option<Hostile>) -> Option<Output> {
    let link = dir.join(format!("board-{which}"));
    let rec = dir.join("run.rec");
    let sim = match (which, how) {
        ("board-sim", Some(h)) => spawn_hostile(board_sim_cmd(&link), h)?,
        _ => quiet(board_sim_cmd(&link)),
    };
    wait_for_link(&link);
    let record = match (which, how) {
        ("record", Some(h)) => spawn_hostile(record_cmd(&link, &rec), h)?,
        _ => quiet(record_cmd(&link, &rec)),
    };
    let record = finish(record);
    let sim = finish(sim);
    assert!(
        std::fs::symlink_metadata(&link).is_err(),
        "board-sim left its link"
    );
    Some(if which == "record" { record } else { sim })
}

#[test]
fn defect2_record_and_board_sim_never_exit_101_on_closed_or_full_streams() {
    let dir = tempfile::tempdir().unwrap();
    for which in ["record", "board-sim"] {
        let normal = acquisition(dir.path(), which, None).unwrap();
        assert_eq!(
            normal.status.code(),
            Some(0),
            "{which}: {}",
            text(&normal.stderr)
        );
        assert!(!normal.stdout.is_empty(), "{which} prints a summary");
        for how in HOSTILE {
            if let Some(got) = acquisition(dir.path(), which, Some(how)) {
                judge(which, how, &normal, &got);
            }
        }
    }
    assert_no_temp_files(dir.path());
}
