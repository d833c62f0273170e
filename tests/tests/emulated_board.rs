//! End to end on the emulated board: the firmware's tasks built for the MPS2 AN386
//! (`firmware`, feature `mps2-an386`) run in QEMU (`firmware/emulated/run.sh`), `rigctl record`
//! records them over QEMU's pseudo-terminal, `rigctl export` turns the recording into CSV, and
//! every exported value is checked against the emulated sensors' known signal
//! (`rig_protocol::device::known_signal`).
//!
//! One QEMU session serves two recordings with different rates (the board obeys `Start`'s
//! rates, and `Stop`: it is silent but alive between the runs); a second session is forced to
//! panic, which must be reported on QEMU's output and end it with a failure status.
//!
//! Timing: QEMU's clock follows the host's (no `-icount`), so board time is real time but the
//! guest runs only when QEMU's thread gets the CPU. Potentiometer timestamps are computed from
//! the trigger period and must be exact; inclinometer timestamps are taken when the read
//! starts and may be late by the guest's scheduling latency: [`TILT_JITTER_US`].
//!
//! Without `qemu-system-arm` the test is skipped with a message, except with `CI=true`, where
//! it fails (`.ci/run` installs QEMU).

use std::collections::BTreeMap;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Output, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use rig_protocol::device::known_signal::{pot_raw, tilt_reading};
use rig_protocol::{encode_host, DeviceMsg, HostMsg, HOST_FRAME_MAX};
use rig_tests::rigctl;
use rigctl::daq::link::{open_port, FrameReader, LinkEvent};

/// Seconds of the long recording (1 kHz pot, 3 x 100 Hz tilt).
const LONG_RUN_S: u64 = 25;
/// Seconds of the second recording, at other rates.
const SHORT_RUN_S: u64 = 5;
/// Largest delay of an inclinometer read after its slot, microseconds. The board reads when
/// its executor gets to it; in QEMU that is when QEMU's thread runs. Measured on an idle
/// 2-core machine: well under 1 ms; the margin is for a loaded one.
const TILT_JITTER_US: i64 = 20_000;
/// Board clock against the host clock (Status uptime vs host receive time), relative.
const CLOCK_RATE_TOLERANCE: f64 = 0.02;
/// Samples against the host's recording duration, relative (the host's duration runs from its
/// `Start` to its `Stop`; the board's from the `Start` it received to the `Stop`).
const SAMPLE_COUNT_TOLERANCE: f64 = 0.03;

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ is inside the repository")
        .to_path_buf()
}

/// True if QEMU can run; without it the test is skipped locally and fails in CI.
fn qemu_or_skip() -> bool {
    let found = Command::new("qemu-system-arm")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !found {
        let msg = "emulated_board: qemu-system-arm is not installed (apt-get install qemu-system-arm)";
        assert!(!rigctl::in_ci(), "{msg}; with CI=true it is required");
        eprintln!("SKIPPED {msg}");
    }
    found
}

/// `run.sh` running, with its stdout (the firmware's semihosting console) collected.
struct Emulator {
    child: Child,
    link: PathBuf,
    console: Arc<Mutex<String>>,
    reader: Option<std::thread::JoinHandle<()>>,
}

impl Emulator {
    /// Starts `run.sh DURATION LINK SWITCHES` and waits for the link (the first run also builds
    /// the firmware).
    fn start(dir: &Path, name: &str, duration_s: u64, switches: &[&str]) -> Self {
        let link = dir.join(name);
        let mut child = Command::new("bash")
            .arg(repo_root().join("firmware/emulated/run.sh"))
            .arg(duration_s.to_string())
            .arg(&link)
            .args(switches)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("spawn run.sh");
        let mut stdout = child.stdout.take().expect("piped stdout");
        let console = Arc::new(Mutex::new(String::new()));
        let sink = Arc::clone(&console);
        let reader = std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = stdout.read(&mut buf) {
                if n == 0 {
                    break;
                }
                let text = String::from_utf8_lossy(&buf[..n]);
                eprint!("{text}");
                sink.lock().unwrap_or_else(|e| e.into_inner()).push_str(&text);
            }
        });
        let deadline = Instant::now() + Duration::from_secs(600);
        while std::fs::symlink_metadata(&link).is_err() {
            if let Some(status) = child.try_wait().expect("poll run.sh") {
                panic!("run.sh ended before linking {}: {status}", link.display());
            }
            assert!(Instant::now() < deadline, "run.sh did not link {}", link.display());
            std::thread::sleep(Duration::from_millis(50));
        }
        Self {
            child,
            link,
            console,
            reader: Some(reader),
        }
    }

    /// The console output so far.
    fn console(&self) -> String {
        self.console.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    /// Waits (at most `limit`) for run.sh to end; returns its status and the whole console.
    fn wait(mut self, limit: Duration) -> (ExitStatus, String) {
        let deadline = Instant::now() + limit;
        let status = loop {
            if let Some(status) = self.child.try_wait().expect("poll run.sh") {
                break status;
            }
            if Instant::now() > deadline {
                let _ = self.child.kill();
                panic!("run.sh did not end within {limit:?}");
            }
            std::thread::sleep(Duration::from_millis(50));
        };
        if let Some(reader) = self.reader.take() {
            let _ = reader.join();
        }
        (status, self.console())
    }

    /// Ends run.sh (and with it QEMU) with SIGTERM.
    fn stop(self) -> String {
        let _ = Command::new("kill")
            .arg("-TERM")
            .arg(self.child.id().to_string())
            .status();
        self.wait(Duration::from_secs(20)).1
    }
}

fn record(link: &Path, out: &Path, duration_s: u64, pot_hz: u32, tilt_hz: u32) -> Output {
    rigctl()
        .args(["record", "--port"])
        .arg(link)
        .arg("--out")
        .arg(out)
        .args([
            "--duration",
            &duration_s.to_string(),
            "--pot-hz",
            &pot_hz.to_string(),
            "--tilt-hz",
            &tilt_hz.to_string(),
        ])
        .output()
        .expect("run rigctl record")
}

/// `frames, samples, dropped, crc_errors` from record's summary line.
fn summary(stdout: &[u8]) -> [u64; 4] {
    let text = String::from_utf8_lossy(stdout);
    let line = text.lines().last().expect("record printed nothing");
    let names = ["frames", "samples", "dropped", "crc_errors"];
    let mut values = [0u64; 4];
    for (value, name) in values.iter_mut().zip(names) {
        *value = line
            .split(", ")
            .find_map(|part| part.strip_prefix(name)?.strip_prefix(' ')?.parse().ok())
            .unwrap_or_else(|| panic!("no `{name} N` in {line:?}"));
    }
    values
}

fn csv_rows(path: &Path, header: &str) -> Vec<Vec<i64>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(header), "{}", path.display());
    lines
        .map(|l| {
            l.split(',')
                .map(|f| f.parse().unwrap_or_else(|e| panic!("{l:?}: {e}")))
                .collect()
        })
        .collect()
}

/// What one recording showed.
struct RunCheck {
    frames: u64,
    pot_samples: usize,
    tilt_readings: usize,
    /// Largest distance of a tilt read from its slot, microseconds.
    tilt_late_max_us: i64,
    /// Board clock rate against the host clock.
    clock_rate: f64,
}

/// Records `duration_s` at the given rates and checks everything the recording can show.
fn record_and_check(
    link: &Path,
    dir: &Path,
    name: &str,
    duration_s: u64,
    pot_hz: u32,
    tilt_hz: u32,
) -> RunCheck {
    let rec = dir.join(format!("{name}.rigrec"));
    let out = record(link, &rec, duration_s, pot_hz, tilt_hz);
    assert!(
        out.status.success(),
        "record {name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let [frames, samples, dropped, crc_errors] = summary(&out.stdout);
    assert_eq!((dropped, crc_errors), (0, 0), "record {name}: lost frames");

    // The recording itself: the emulated board's Hello, the run's acknowledgements.
    let recording = rigctl::daq::recording::read_recording(&rec).expect("read the recording");
    assert_eq!(recording.truncated_tail_bytes, 0);
    let msgs: Vec<DeviceMsg> = recording
        .records
        .iter()
        .map(|r| rigctl::daq::link::decode_stored(&r.frame).expect("stored frame decodes"))
        .collect();
    assert_eq!(msgs.len() as u64, frames);
    let hello = msgs
        .iter()
        .find_map(|m| match m {
            DeviceMsg::Hello(h) => Some(*h),
            _ => None,
        })
        .expect("a Hello");
    assert_eq!(&hello.board_id, b"QEMU-AN386\0\0");
    assert_eq!(hello.tilt_sensors, 3);
    assert!(
        msgs.contains(&DeviceMsg::Ack(rig_protocol::CommandKind::Start)),
        "Start acknowledged"
    );
    assert_eq!(
        msgs.last(),
        Some(&DeviceMsg::Ack(rig_protocol::CommandKind::Stop)),
        "the run ends with Ack(Stop)"
    );
    let mut seqs = msgs.iter().filter_map(|m| match m {
        DeviceMsg::Pot(b) => Some((b.seq, b.period_us)),
        _ => None,
    });
    let period_us = 1_000_000 / pot_hz;
    for (expected, (seq, period)) in (0u32..).zip(seqs.by_ref()) {
        assert_eq!(seq, expected, "{name}: pot batches in sequence from 0");
        assert_eq!(period, period_us, "{name}: the commanded pot period");
    }

    let csv = dir.join(format!("{name}-csv"));
    let export = rigctl()
        .arg("export")
        .arg(&rec)
        .arg("--csv")
        .arg(&csv)
        .output()
        .expect("run rigctl export");
    assert!(
        export.status.success(),
        "export {name}: {}",
        String::from_utf8_lossy(&export.stderr)
    );

    // Every potentiometer sample: on the commanded grid without a gap, equal to the ramp.
    let pot = csv_rows(&csv.join("pot.csv"), "seq,t_us,raw");
    assert_eq!(pot.len() as u64, samples);
    for pair in pot.windows(2) {
        assert_eq!(
            pair[1][1] - pair[0][1],
            i64::from(period_us),
            "{name}: pot samples {:?} -> {:?}",
            pair[0],
            pair[1]
        );
    }
    for row in &pot {
        assert_eq!(
            row[2],
            i64::from(pot_raw(row[1] as u64)),
            "{name}: pot sample at {} us",
            row[1]
        );
    }
    let expected_samples = (duration_s * u64::from(pot_hz)) as f64;
    let ratio = pot.len() as f64 / expected_samples;
    assert!(
        (ratio - 1.0).abs() <= SAMPLE_COUNT_TOLERANCE,
        "{name}: {} pot samples in {duration_s} s at {pot_hz} Hz",
        pot.len()
    );

    // Every inclinometer reading: the table's row for its sensor and time; each sensor read
    // at the commanded rate, none skipped.
    let tilt = csv_rows(&csv.join("tilt.csv"), "sensor,t_us,x,y,z,temp");
    let mut by_sensor: BTreeMap<i64, Vec<i64>> = BTreeMap::new();
    for row in &tilt {
        let r = tilt_reading(row[0] as u8, row[1] as u64);
        assert_eq!(
            &row[2..],
            &[r.x, r.y, r.z, r.temp].map(i64::from),
            "{name}: sensor {} at {} us",
            row[0],
            row[1]
        );
        by_sensor.entry(row[0]).or_default().push(row[1]);
    }
    assert_eq!(
        by_sensor.keys().copied().collect::<Vec<_>>(),
        [0, 1, 2],
        "{name}: all three sensors read"
    );
    // The board's schedule (`rig_protocol::device::TiltScheduler`): read slot `k` is for
    // sensor `k % 3` at `start + ceil(k * 1e6 / (rate * 3))`; the first read (sensor 0) is due
    // at `Start`, so its time stands for `start`. A read is late by the guest's latency, never
    // early (but `start` itself may be taken late).
    let sensors = by_sensor.len() as i64;
    let slots_per_s = i64::from(tilt_hz) * sensors;
    let start = by_sensor[&0][0];
    let mut late_max = 0i64;
    for (&sensor, times) in &by_sensor {
        for (j, &t) in times.iter().enumerate() {
            let k = j as i64 * sensors + sensor;
            let slot = start + (k * 1_000_000 + slots_per_s - 1) / slots_per_s;
            let late = t - slot;
            assert!(
                (-TILT_JITTER_US..=TILT_JITTER_US).contains(&late),
                "{name}: sensor {sensor} reading {j} at {t} us is {late} us off its slot"
            );
            late_max = late_max.max(late.abs());
        }
        let expected = (duration_s * u64::from(tilt_hz)) as f64;
        let ratio = times.len() as f64 / expected;
        assert!(
            (ratio - 1.0).abs() <= SAMPLE_COUNT_TOLERANCE,
            "{name}: sensor {sensor}: {} readings in {duration_s} s at {tilt_hz} Hz",
            times.len()
        );
    }

    // Health: the board's own counters; its clock against the host's.
    let status = csv_rows(
        &csv.join("status.csv"),
        "host_rx_us,uptime_us,dropped_samples,dropped_frames,overruns,sensor_errors,rx_errors",
    );
    assert!(status.len() as u64 >= duration_s, "{name}: a Status a second");
    for row in &status {
        assert_eq!(&row[2..], &[0, 0, 0, 0, 0], "{name}: status {row:?}");
    }
    let (first, last) = (&status[0], &status[status.len() - 1]);
    let clock_rate = (last[1] - first[1]) as f64 / (last[0] - first[0]) as f64;
    assert!(
        (clock_rate - 1.0).abs() <= CLOCK_RATE_TOLERANCE,
        "{name}: board clock runs at {clock_rate:.4} of the host's"
    );

    RunCheck {
        frames,
        pot_samples: pot.len(),
        tilt_readings: tilt.len(),
        tilt_late_max_us: late_max,
        clock_rate,
    }
}

/// Between runs the board sends no data (it obeyed `Stop`) but answers a `Ping`.
fn idle_but_alive(link: &Path) {
    let mut port = open_port(link, Duration::from_millis(50)).expect("open the board's link");
    let mut frame = [0u8; HOST_FRAME_MAX];
    let ping = encode_host(&HostMsg::Ping { nonce: 0x5EED }, &mut frame).expect("encode Ping");
    let mut reader = FrameReader::new();
    let mut buf = [0u8; 1024];
    let mut pong = false;
    let mut data_frames = 0u32;
    // QEMU notices a reopened pty within about a second; ping until it answers.
    let deadline = Instant::now() + Duration::from_secs(5);
    let mut next_ping = Instant::now();
    let quiet_until = Instant::now() + Duration::from_millis(1500);
    while Instant::now() < deadline && !(pong && Instant::now() >= quiet_until) {
        if !pong && Instant::now() >= next_ping {
            port.write_all(ping).expect("write Ping");
            next_ping = Instant::now() + Duration::from_millis(300);
        }
        let n = match port.read(&mut buf) {
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::TimedOut
                        | std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::Interrupted
                ) =>
            {
                0
            }
            Err(e) => panic!("read from the board: {e}"),
        };
        reader.push_slice(&buf[..n], |event| match event {
            LinkEvent::Frame {
                msg: DeviceMsg::Pong { nonce: 0x5EED },
                ..
            } => pong = true,
            LinkEvent::Frame {
                msg: DeviceMsg::Pot(_) | DeviceMsg::Tilt(_) | DeviceMsg::Status(_),
                ..
            } => data_frames += 1,
            _ => {}
        });
    }
    assert!(pong, "the stopped board answers Ping");
    assert_eq!(data_frames, 0, "the stopped board sends no data");
}

/// The high-water marks the board logged (`stack high-water mark: USED of SIZE bytes`).
fn stack_marks(console: &str) -> Vec<(u64, u64)> {
    console
        .lines()
        .filter_map(|line| {
            let rest = line.split("stack high-water mark: ").nth(1)?;
            let mut words = rest.split_whitespace();
            let used = words.next()?.parse().ok()?;
            let size = words.nth(1)?.parse().ok()?;
            Some((used, size))
        })
        .collect()
}

#[test]
fn emulated_board_records_known_signals_and_reports_panics() {
    if !qemu_or_skip() {
        return;
    }
    let started = Instant::now();
    let dir = tempfile::tempdir().expect("temp dir");
    // run.sh builds the firmware first; the QEMU session covers both recordings.
    let emulator = Emulator::start(dir.path(), "board", LONG_RUN_S + SHORT_RUN_S + 60, &[]);

    let long = record_and_check(&emulator.link, dir.path(), "long", LONG_RUN_S, 1000, 100);
    idle_but_alive(&emulator.link);
    let short = record_and_check(&emulator.link, dir.path(), "short", SHORT_RUN_S, 500, 50);
    let console = emulator.stop();

    assert!(console.contains("INFO rig firmware"), "boot log: {console}");
    assert!(
        console.contains("start: RunConfig { pot_rate_hz: 1000")
            && console.contains("start: RunConfig { pot_rate_hz: 500"),
        "the board logged both starts: {console}"
    );
    let marks = stack_marks(&console);
    assert_eq!(marks.len(), 2, "a stack report at each Stop: {console}");
    for &(used, size) in &marks {
        assert!(used > 0 && used < size, "stack {used} of {size} bytes");
    }
    let (used, size) = marks[marks.len() - 1];

    // A panic on the board is reported on the console and ends QEMU with a failure.
    let panicking = Emulator::start(dir.path(), "panicking", 60, &["panic-after-ms=1500"]);
    let (status, panic_console) = panicking.wait(Duration::from_secs(60));
    assert!(!status.success(), "run.sh exits non-zero after a panic");
    assert!(
        panic_console.contains("PANIC panicked at")
            && panic_console.contains("forced panic after 1500 ms"),
        "panic message on the console: {panic_console}"
    );

    for (name, run) in [("1 kHz / 100 Hz", &long), ("500 Hz / 50 Hz", &short)] {
        println!(
            "emulated board, {name}: frames {}, lost 0, pot samples {}, tilt readings {}, \
             tilt read late by at most {} us (tolerance {TILT_JITTER_US} us), board clock {:.4} x host",
            run.frames, run.pot_samples, run.tilt_readings, run.tilt_late_max_us, run.clock_rate
        );
    }
    println!("emulated board: stack high-water mark {used} of {size} bytes (painted stack)");
    println!(
        "emulated board: test took {:.1} s",
        started.elapsed().as_secs_f64()
    );
}
