//! Issue 15, defects 1, 2 and 6: output files, stdout/stderr and litter, tried as a hostile user
//! would. Each test names its defect.

use std::io::Read;
use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use super::common::spawn::{rigctl, text};

/// A simulated run directory (cal.csv, val.csv, truth.*), made once per test.
fn simulated(dir: &Path) -> PathBuf {
    let out = dir.join("sim");
    let o = rigctl()
        .args(["simulate", "--seed", "3", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    out
}

fn is_char_device(p: &str) -> bool {
    std::fs::metadata(p)
        .map(|m| m.file_type().is_char_device())
        .unwrap_or(false)
}

#[test]
fn defect1_outputs_write_through_devices_links_and_fifos() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(dir.path());
    let cal = sim.join("cal.csv");

    // A full device: exit 1 with a message, and the device stays a device.
    if is_char_device("/dev/full") {
        let o = rigctl()
            .args(["calibrate", "--poses"])
            .arg(&cal)
            .args(["--json", "/dev/full"])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
        assert!(text(&o.stderr).contains("/dev/full"));
        assert!(is_char_device("/dev/full"), "/dev/full was replaced");
    }
    if is_char_device("/dev/null") {
        let o = rigctl()
            .args(["calibrate", "--poses"])
            .arg(&cal)
            .args(["--json", "/dev/null"])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
        assert!(is_char_device("/dev/null"), "/dev/null was replaced");
    }

    // A symbolic link (relative, to a file not yet there) is written through and stays a link.
    let link = dir.path().join("link.json");
    std::os::unix::fs::symlink("target.json", &link).unwrap();
    let o = rigctl()
        .args(["calibrate", "--poses"])
        .arg(&cal)
        .arg("--json")
        .arg(&link)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    let written = std::fs::read_to_string(dir.path().join("target.json")).unwrap();
    assert!(written.contains("\"parameters\""));

    // A FIFO: its reader gets the JSON, and it stays a FIFO.
    let fifo = dir.path().join("fifo");
    let made = Command::new("mkfifo").arg(&fifo).status();
    if made.map(|s| s.success()).unwrap_or(false) {
        let reader_path = fifo.clone();
        let reader = std::thread::spawn(move || {
            let mut s = String::new();
            std::fs::File::open(&reader_path)
                .unwrap()
                .read_to_string(&mut s)
                .unwrap();
            s
        });
        let o = rigctl()
            .args(["calibrate", "--poses"])
            .arg(&cal)
            .arg("--json")
            .arg(&fifo)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", text(&o.stderr));
        let got = reader.join().unwrap();
        assert!(got.contains("\"parameters\""), "FIFO reader got {got:?}");
        assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    }
}

/// Runs `args` with stdout a pipe whose read end is already closed.
fn with_closed_stdout(args: &[&std::ffi::OsStr]) -> Output {
    let mut child = rigctl()
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    child.wait_with_output().unwrap()
}

fn with_full_stdout(args: &[&std::ffi::OsStr]) -> Option<Output> {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .ok()?;
    Some(rigctl().args(args).stdout(full).output().unwrap())
}

#[test]
fn defect2_closed_or_full_stdout_never_exits_101() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(dir.path());
    let jig = dir.path().join("jig.csv");
    std::fs::write(&jig, "raw,travel_mm\n1000,0\n2000,5\n3000,10.01\n").unwrap();
    let p = |s: &str| sim.join(s).into_os_string();
    let o = |s: &str| std::ffi::OsString::from(s);
    let d = |s: &str| dir.path().join(s).into_os_string();
    let commands: Vec<(&str, Vec<std::ffi::OsString>)> = vec![
        ("fk", vec![o("fk"), o("--joints"), p("cal.csv")]),
        ("simulate", vec![o("simulate"), o("--out"), d("sim2")]),
        (
            "calibrate",
            vec![o("calibrate"), o("--poses"), p("cal.csv")],
        ),
        (
            "diagnose",
            vec![
                o("diagnose"),
                o("--poses"),
                p("cal.csv"),
                o("--validate"),
                p("val.csv"),
            ],
        ),
        (
            "report",
            vec![
                o("report"),
                sim.clone().into_os_string(),
                o("--html"),
                d("r.html"),
            ],
        ),
        (
            "potcal",
            vec![
                o("potcal"),
                o("--points"),
                jig.clone().into_os_string(),
                o("--out"),
                d("pot.toml"),
            ],
        ),
        ("ports", vec![o("ports")]),
    ];
    for (name, args) in &commands {
        let args: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
        let out = with_closed_stdout(&args);
        let code = out.status.code();
        assert!(
            matches!(code, Some(0) | Some(141)),
            "{name} | closed pipe: {code:?} {}",
            text(&out.stderr)
        );
        assert!(!text(&out.stderr).contains("panicked"), "{name}");
        if let Some(out) = with_full_stdout(&args) {
            let printed_something = !matches!(*name, "ports");
            let code = out.status.code();
            assert_ne!(code, Some(101), "{name} > /dev/full: {}", text(&out.stderr));
            if printed_something {
                assert_eq!(code, Some(1), "{name} > /dev/full: {}", text(&out.stderr));
                assert!(text(&out.stderr).contains("No space left"), "{name}");
            }
        }
    }
    // stderr on a full device: the exit code of the error still comes through.
    if let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") {
        let out = rigctl()
            .args(["calibrate", "--poses", "/nonexistent.csv"])
            .stderr(full)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2));
    }
}

#[test]
fn defect6_no_litter_and_all_or_none_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let sim = simulated(dir.path());

    // An unwritable second output: the first one keeps its old content.
    let ok = dir.path().join("ok.json");
    std::fs::write(&ok, "old").unwrap();
    let o = rigctl()
        .args(["calibrate", "--poses"])
        .arg(sim.join("cal.csv"))
        .arg("--json")
        .arg(&ok)
        .args(["--out", "/nonexistent-dir/m.toml"])
        .output()
        .unwrap();
    // a missing directory is bad input (exit 2), found before the work
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("/nonexistent-dir"));
    assert_eq!(std::fs::read_to_string(&ok).unwrap(), "old");

    // A temporary file of a killed run (its process is gone) is removed at the next run.
    let dead = {
        let mut c = Command::new("true").spawn().unwrap();
        let pid = c.id();
        c.wait().unwrap();
        pid
    };
    let stale = sim.join(format!(".cal.csv.tmp-{dead}"));
    std::fs::write(&stale, vec![b'x'; 1000]).unwrap();
    let o = rigctl()
        .args(["simulate", "--seed", "3", "--out"])
        .arg(&sim)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(!stale.exists(), "stale temp file left");
    let litter: Vec<_> = std::fs::read_dir(&sim)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp-"))
        .collect();
    assert!(litter.is_empty(), "{litter:?}");
}

#[test]
fn defect6_sigterm_during_a_run_leaves_no_temp_file() {
    // A long simulate --session writes several files; SIGTERM it at various points: never a
    // temporary file left behind, and the exit is 130 (or 0 if it had already finished).
    let dir = tempfile::tempdir().unwrap();
    for delay_ms in [300u64, 900, 1500] {
        let out = dir.path().join(format!("s{delay_ms}"));
        let child = rigctl()
            .args(["simulate", "--session", "circle", "--out"])
            .arg(&out)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        let _ = Command::new("kill")
            .args(["-TERM", &child.id().to_string()])
            .status();
        let status = child.wait_with_output().unwrap().status;
        assert!(
            matches!(status.code(), Some(130) | Some(0)),
            "{delay_ms} ms: {status:?}"
        );
        if let Ok(entries) = std::fs::read_dir(&out) {
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().into_owned();
                assert!(!name.contains(".tmp-"), "{delay_ms} ms: {name} left");
            }
        }
    }
}
