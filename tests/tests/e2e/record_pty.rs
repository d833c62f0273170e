//! End to end over a real pseudo-terminal: `rigctl board-sim` serves the virtual board,
//! `rigctl record` records it, `rigctl export` turns the recording into CSV, and every exported
//! value is checked against the board-sim's seeded signals (`rigctl::daq::signals`).
//!
//! The acceptance test (`sixty_seconds_real_time_lose_nothing`) runs 60 s in real time; the
//! others run the virtual board ten times faster than real time (`--speed 10`).

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Output, Stdio};
use std::time::{Duration, Instant};

use rig_tests::rigctl;

use rigctl::daq::signals::{pot_raw, tilt_raw};

/// Starts `rigctl board-sim --link DIR/board ARGS` and waits for the link.
fn board_sim(dir: &Path, args: &[&str]) -> (Child, PathBuf) {
    let link = dir.join("board");
    let child = rigctl()
        .arg("board-sim")
        .arg("--link")
        .arg(&link)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn rigctl board-sim");
    let deadline = Instant::now() + Duration::from_secs(20);
    while std::fs::symlink_metadata(&link).is_err() {
        assert!(
            Instant::now() < deadline,
            "board-sim did not create {}",
            link.display()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    (child, link)
}

fn record(link: &Path, out: &Path, duration_s: &str) -> Output {
    rigctl()
        .args(["record", "--port"])
        .arg(link)
        .arg("--out")
        .arg(out)
        .args([
            "--duration",
            duration_s,
            "--pot-hz",
            "1000",
            "--tilt-hz",
            "100",
        ])
        .output()
        .expect("run rigctl record")
}

/// Waits for the board-sim to end (it does once the host closed the port) and returns its
/// stdout.
fn finish(mut child: Child) -> String {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        if let Some(status) = child.try_wait().expect("wait board-sim") {
            let mut out = String::new();
            let mut err = String::new();
            child
                .stdout
                .take()
                .unwrap()
                .read_to_string(&mut out)
                .unwrap();
            child
                .stderr
                .take()
                .unwrap()
                .read_to_string(&mut err)
                .unwrap();
            assert!(status.success(), "board-sim failed: {status}\n{err}");
            return out;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("board-sim did not end after the host closed the port");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The numbers after `names` in a line like `frames 1, samples 2, ...`.
fn numbers(line: &str, names: &[&str]) -> Vec<u64> {
    names
        .iter()
        .map(|name| {
            line.split(", ")
                .find_map(|part| part.strip_prefix(name)?.strip_prefix(' ')?.parse().ok())
                .unwrap_or_else(|| panic!("no `{name} N` in {line:?}"))
        })
        .collect()
}

/// `frames, samples, dropped, crc_errors` from record's last stdout line (exact format).
fn summary(stdout: &[u8]) -> [u64; 4] {
    let text = String::from_utf8_lossy(stdout);
    let line = text.lines().last().expect("record printed nothing");
    let v = numbers(line, &["frames", "samples", "dropped", "crc_errors"]);
    assert_eq!(
        line,
        format!(
            "frames {}, samples {}, dropped {}, crc_errors {}",
            v[0], v[1], v[2], v[3]
        )
    );
    [v[0], v[1], v[2], v[3]]
}

/// What the board-sim says it sent.
struct Sent {
    frames: u64,
    corrupted: u64,
    samples: u64,
    tilt_readings: u64,
    board_dropped: u64,
}

fn sent(stdout: &str) -> Sent {
    let line = stdout.lines().last().expect("board-sim printed nothing");
    let v = numbers(
        line,
        &[
            "sent frames",
            "corrupted frames",
            "samples",
            "tilt readings",
            "board dropped frames",
        ],
    );
    Sent {
        frames: v[0],
        corrupted: v[1],
        samples: v[2],
        tilt_readings: v[3],
        board_dropped: v[4],
    }
}

fn csv_rows(path: &Path, header: &str) -> Vec<Vec<i64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(header), "{}", path.display());
    lines
        .map(|l| l.split(',').map(|f| f.parse().unwrap()).collect())
        .collect()
}

/// Exports `rec` and checks every value against the seeded signals. Returns (pot rows, tilt
/// rows, pot samples missing from the grid inside the recording).
fn export_and_check(rec: &Path, dir: &Path, seed: u64) -> (usize, usize, u64) {
    let csv = dir.join("csv");
    let out = rigctl()
        .arg("export")
        .arg(rec)
        .arg("--csv")
        .arg(&csv)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let pot = csv_rows(&csv.join("pot.csv"), "seq,t_us,raw");
    let mut missing = 0u64;
    for pair in pot.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        assert!(b[0] >= a[0], "seq goes back: {a:?} -> {b:?}");
        let step = b[1] - a[1];
        assert!(
            step >= 1000 && step % 1000 == 0,
            "off the 1 ms grid: {a:?} -> {b:?}"
        );
        missing += (step / 1000 - 1) as u64;
    }
    for row in &pot {
        let expected = pot_raw(seed, row[1] as u64);
        assert_eq!(row[2], i64::from(expected), "pot sample at {} us", row[1]);
    }

    let tilt = csv_rows(&csv.join("tilt.csv"), "sensor,t_us,x,y,z,temp");
    for row in &tilt {
        let r = tilt_raw(seed, row[0] as u8, row[1] as u64);
        assert_eq!(
            &row[2..],
            &[r.x, r.y, r.z, r.temp].map(i64::from),
            "sensor {} at {} us",
            row[0],
            row[1]
        );
    }
    let status = std::fs::read_to_string(csv.join("status.csv")).unwrap();
    assert!(status.starts_with(
        "host_rx_us,uptime_us,dropped_samples,dropped_frames,overruns,sensor_errors,rx_errors\n"
    ));
    (pot.len(), tilt.len(), missing)
}

/// Inclinometer readings missing between consecutive readings of each sensor on a grid of
/// `period_us`.
fn tilt_grid_missing(tilt_csv: &Path, period_us: i64) -> u64 {
    let mut last = std::collections::BTreeMap::new();
    let mut missing = 0u64;
    for row in csv_rows(tilt_csv, "sensor,t_us,x,y,z,temp") {
        if let Some(prev) = last.insert(row[0], row[1]) {
            let slots = (row[1] - prev + period_us / 2) / period_us;
            missing += (slots - 1).max(0) as u64;
        }
    }
    missing
}

#[test]
fn sixty_seconds_real_time_lose_nothing() {
    let _serial = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    let seed = 20_240_601;
    // The board's own limit is a safety net if record never stops it.
    let (sim, link) = board_sim(
        dir.path(),
        &[
            "--seed",
            &seed.to_string(),
            "--duration-s",
            "120",
            "--sensors",
            "3",
        ],
    );
    let rec = dir.path().join("run.rigrec");
    let out = record(&link, &rec, "60");
    let sim_out = finish(sim);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let [frames, samples, dropped, crc_errors] = summary(&out.stdout);
    let sent = sent(&sim_out);

    assert_eq!((dropped, crc_errors), (0, 0));
    assert_eq!(frames, sent.frames, "every frame sent was recorded");
    assert_eq!(samples, sent.samples);
    assert_eq!(sent.board_dropped, 0);
    // 60 s from the host's Start to its Stop, at 1 kHz; the ends differ by the link latency.
    assert!((59_900..=60_500).contains(&samples), "samples {samples}");
    // 3 sensors x 100 Hz x 60 s.
    assert!(
        (17_900..=18_200).contains(&sent.tilt_readings),
        "tilt {}",
        sent.tilt_readings
    );

    let (pot_rows, tilt_rows, missing) = export_and_check(&rec, dir.path(), seed);
    assert_eq!(pot_rows as u64, samples);
    assert_eq!(tilt_rows as u64, sent.tilt_readings);
    assert_eq!(missing, 0);
    assert!(
        std::fs::symlink_metadata(&link).is_err(),
        "board-sim removes its link"
    );
}

#[test]
fn corrupted_link_loses_exactly_the_corrupted_frames() {
    let _serial = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    let seed = 77;
    let (sim, link) = board_sim(
        dir.path(),
        &[
            "--seed",
            "77",
            "--speed",
            "10",
            "--corrupt-ppm",
            "400",
            "--duration-s",
            "300",
        ],
    );
    let rec = dir.path().join("run.rigrec");
    let out = record(&link, &rec, "3");
    let sim_out = finish(sim);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let [frames, samples, dropped, crc_errors] = summary(&out.stdout);
    let sent = sent(&sim_out);

    // ~30 s of board time, ~9500 frames of ~25-150 bytes at 400 ppm: dozens corrupted.
    assert!(sent.corrupted >= 10, "corrupted {}", sent.corrupted);
    assert_eq!(crc_errors, sent.corrupted);
    assert_eq!(frames + crc_errors, sent.frames);
    assert_eq!(sent.board_dropped, 0);

    let (pot_rows, _, missing) = export_and_check(&rec, dir.path(), seed);
    assert_eq!(pot_rows as u64, samples);
    // Issue 15, defect 7: tilt readings lost to corruption are in `dropped` too (each sensor
    // reads on a 10 ms grid at 100 Hz).
    let tilt_missing = tilt_grid_missing(&dir.path().join("csv/tilt.csv"), 10_000);
    assert!(tilt_missing > 0, "no tilt reading lost at 400 ppm?");
    let dropped = dropped - tilt_missing;
    // Samples lost in the middle are on the grid; a lost first or last batch is estimated.
    assert!(dropped >= missing);
    assert!(
        samples + dropped <= sent.samples + 64 && samples + dropped + 64 >= sent.samples,
        "received {samples} + dropped {dropped} vs taken {}",
        sent.samples
    );
    if dropped == missing {
        // No loss at the edges: the count is exact.
        assert_eq!(samples + dropped, sent.samples);
    }
}

#[test]
fn killed_board_leaves_a_readable_file_and_exit_1() {
    let _serial = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    let seed = 5;
    let (mut sim, link) = board_sim(dir.path(), &["--seed", "5", "--speed", "10"]);
    let rec = dir.path().join("run.rigrec");
    let recorder = rigctl()
        .args(["record", "--port"])
        .arg(&link)
        .arg("--out")
        .arg(&rec)
        .args(["--duration", "30"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Let it record for a while, then pull the plug.
    let deadline = Instant::now() + Duration::from_secs(20);
    while std::fs::metadata(&rec).map_or(0, |m| m.len()) < 100_000 {
        assert!(Instant::now() < deadline, "recording does not grow");
        std::thread::sleep(Duration::from_millis(20));
    }
    sim.kill().unwrap();
    let _ = sim.wait();
    let out = recorder.wait_with_output().unwrap();

    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("lost"), "{stderr}");
    let [frames, samples, _, crc_errors] = summary(&out.stdout);
    assert_eq!(crc_errors, 0);

    let recording = rigctl::daq::recording::read_recording(&rec).unwrap();
    assert_eq!(recording.records.len() as u64, frames);
    assert_eq!(recording.truncated_tail_bytes, 0);
    for record in &recording.records {
        rigctl::daq::link::decode_stored(&record.frame).unwrap();
    }
    let (pot_rows, _, missing) = export_and_check(&rec, dir.path(), seed);
    assert_eq!(pot_rows as u64, samples);
    assert_eq!(missing, 0);
}

#[test]
fn record_refuses_a_start_the_board_cannot_run() {
    let _serial = crate::one_at_a_time();
    let dir = tempfile::tempdir().unwrap();
    let (sim, link) = board_sim(dir.path(), &["--pot-hz", "500"]);
    let rec = dir.path().join("run.rigrec");
    let out = record(&link, &rec, "1");
    let _ = finish(sim);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("RateOutOfRange"));
    assert!(!rec.exists(), "no recording is left behind a refused start");
}

#[test]
fn record_without_a_board_fails_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let out = record(
        &dir.path().join("no-such-port"),
        &dir.path().join("run.rigrec"),
        "1",
    );
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!dir.path().join("run.rigrec").exists());
}
