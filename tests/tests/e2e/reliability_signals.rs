//! Issue 15, defect 7: acquisition on SIGTERM. `record` stops as on Ctrl-C (summary, exit 0,
//! a readable recording); `board-sim` removes its link.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use rig_tests::rigctl;

fn board_sim(dir: &Path) -> (Child, PathBuf) {
    let link = dir.join("board");
    let child = rigctl()
        .arg("board-sim")
        .arg("--link")
        .arg(&link)
        .args(["--speed", "10", "--duration-s", "300"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn rigctl board-sim");
    let deadline = Instant::now() + Duration::from_secs(20);
    while std::fs::symlink_metadata(&link).is_err() {
        assert!(
            Instant::now() < deadline,
            "board-sim did not create its link"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    (child, link)
}

fn sigterm(child: &Child) {
    let status = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("run kill");
    assert!(status.success());
}

/// Waits for `child` to end (at most 20 s) and returns its output.
fn wait(mut child: Child) -> std::process::Output {
    let deadline = Instant::now() + Duration::from_secs(20);
    while child.try_wait().expect("wait").is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("process did not end after SIGTERM");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    child.wait_with_output().expect("output")
}

#[test]
fn defect7_board_sim_on_sigterm_removes_its_link() {
    let dir = tempfile::tempdir().unwrap();
    let (sim, link) = board_sim(dir.path());
    sigterm(&sim);
    let out = wait(sim);
    assert!(
        out.status.success(),
        "{:?} {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        std::fs::symlink_metadata(&link).is_err(),
        "link left behind"
    );
}

#[test]
fn defect7_record_on_sigterm_prints_its_summary_and_exits_0() {
    let dir = tempfile::tempdir().unwrap();
    let (sim, link) = board_sim(dir.path());
    let rec = dir.path().join("run.rec");
    let record = rigctl()
        .args(["record", "--port"])
        .arg(&link)
        .arg("--out")
        .arg(&rec)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn record");
    // Let it record a little.
    let deadline = Instant::now() + Duration::from_secs(20);
    while std::fs::metadata(&rec).map(|m| m.len()).unwrap_or(0) < 10_000 {
        assert!(Instant::now() < deadline, "record wrote nothing");
        std::thread::sleep(Duration::from_millis(50));
    }
    sigterm(&record);
    let out = wait(record);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{:?} {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let last = stdout.lines().last().unwrap_or_default();
    assert!(
        last.starts_with("frames ") && last.contains("crc_errors"),
        "{stdout}"
    );
    let _ = wait(sim);
    let csv = dir.path().join("csv");
    let o = rigctl()
        .arg("export")
        .arg(&rec)
        .arg("--strict")
        .arg("--csv")
        .arg(&csv)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
