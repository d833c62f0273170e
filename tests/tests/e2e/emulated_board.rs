//! End to end on the emulated board: the firmware's tasks built for the MPS2 AN386
//! (`firmware`, feature `mps2-an386`) run in QEMU (`firmware/emulated/run.sh`), `rigctl record`
//! records them over QEMU's pseudo-terminal, `rigctl export` turns the recording into CSV, and
//! every exported value is checked against the emulated sensors' known signal
//! (`rig_protocol::device::known_signal`).
//!
//! One QEMU session serves two recordings with different rates (the board obeys `Start`'s
//! rates, and `Stop`: it is silent but alive between the runs); a second session is forced to
//! panic, which must be reported on QEMU's output and end it with a failure status, and a
//! third to overflow its stack (unbounded recursion), which must lock the core up with the
//! stack pointer below RAM (flip-link's layout) and be reported by `run.sh` (exit 1).
//!
//! Timing: QEMU's clock follows the host's (no `-icount`), so board time is real time but the
//! guest runs only when the host schedules QEMU. Potentiometer timestamps are computed from
//! the trigger period and must be exact. Inclinometer timestamps are taken when the read
//! starts: late by the wake-up latency of the emulated board (measured: median about 0.1 ms,
//! 99th percentile about 2 ms on a loaded 2-core machine). The board's scheduler reads the most
//! recent slot that has passed, so every reading is within one slot interval (1 / (rate x 3))
//! after its slot, and a wake-up later than that skips a slot, which the board counts in
//! `Status.overruns`. The test allows [`TILT_SKIPPED_MAX`] of the slots to be skipped and
//! requires each skipped slot to be counted by the board; none may be lost on the link. It
//! runs apart from the binary's other real-time and CPU-heavy tests (`one_at_a_time`).
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
/// Fraction of inclinometer slots that may be skipped because QEMU woke late (each one
/// counted in `Status.overruns`).
const TILT_SKIPPED_MAX: f64 = 0.01;
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
        let msg =
            "emulated_board: qemu-system-arm is not installed (apt-get install qemu-system-arm)";
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
                sink.lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .push_str(&text);
            }
        });
        let deadline = Instant::now() + Duration::from_secs(600);
        while std::fs::symlink_metadata(&link).is_err() {
            if let Some(status) = child.try_wait().expect("poll run.sh") {
                panic!("run.sh ended before linking {}: {status}", link.display());
            }
            assert!(
                Instant::now() < deadline,
                "run.sh did not link {}",
                link.display()
            );
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
        self.console
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
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
        self.terminate();
        self.wait(Duration::from_secs(20)).1
    }

    /// SIGTERM to run.sh, which stops QEMU and removes the link.
    fn terminate(&self) {
        let _ = Command::new("kill")
            .arg("-TERM")
            .arg(self.child.id().to_string())
            .status();
    }
}

impl Drop for Emulator {
    /// A failed assertion leaves no QEMU behind.
    fn drop(&mut self) {
        if matches!(self.child.try_wait(), Ok(None)) {
            self.terminate();
            let _ = self.child.wait();
        }
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
    /// Tilt read lateness after its slot (relative to the earliest), microseconds: median,
    /// 99th percentile, largest.
    tilt_late_us: [i64; 3],
    /// Tilt slots skipped (and counted by the board as overruns).
    tilt_skipped: u64,
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
    assert_eq!(crc_errors, 0, "record {name}: corrupt frames");

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
    // at `Start`, so its time stands for `start`. Each reading belongs to the nearest slot of
    // its sensor; it is at most one slot interval after it (`start` itself may be late).
    let sensors = by_sensor.len() as i64;
    let slots_per_s = i64::from(tilt_hz) * sensors;
    let slot_us = |k: i64| (k * 1_000_000 + slots_per_s - 1) / slots_per_s;
    let start = by_sensor[&0][0];
    let mut lateness = Vec::with_capacity(tilt.len());
    let mut skipped = 0u64;
    for (&sensor, times) in &by_sensor {
        let mut last_k: Option<i64> = None;
        let mut sensor_skipped = 0u64;
        for &t in times {
            let approx = ((t - start) * slots_per_s) as f64 / 1e6;
            let k = ((approx - sensor as f64) / sensors as f64).round() as i64 * sensors + sensor;
            let late = t - start - slot_us(k);
            assert!(
                late * slots_per_s <= 1_000_000,
                "{name}: sensor {sensor} read at {t} us, {late} us after its slot {k}"
            );
            lateness.push(late);
            if let Some(prev) = last_k {
                assert!(k > prev, "{name}: sensor {sensor} read twice in slot {k}");
                sensor_skipped += ((k - prev) / sensors - 1) as u64;
            } else {
                assert_eq!(
                    k, sensor,
                    "{name}: sensor {sensor}'s first read is in its first slot"
                );
            }
            last_k = Some(k);
        }
        skipped += sensor_skipped;
        // Its slots (read or skipped) at the commanded rate over the run.
        let expected = (duration_s * u64::from(tilt_hz)) as f64;
        let ratio = (times.len() as u64 + sensor_skipped) as f64 / expected;
        assert!(
            (ratio - 1.0).abs() <= SAMPLE_COUNT_TOLERANCE,
            "{name}: sensor {sensor}: {} readings and {sensor_skipped} skipped slots in \
             {duration_s} s at {tilt_hz} Hz",
            times.len()
        );
    }
    let earliest = lateness.iter().copied().min().unwrap_or(0);
    let mut lateness: Vec<i64> = lateness.iter().map(|l| l - earliest).collect();
    lateness.sort_unstable();
    let pick = |q: f64| lateness[((lateness.len() - 1) as f64 * q) as usize];
    let tilt_late_us = [pick(0.5), pick(0.99), pick(1.0)];
    let slots = tilt.len() as u64 + skipped;
    assert!(
        skipped as f64 <= TILT_SKIPPED_MAX * slots as f64,
        "{name}: {skipped} of {slots} tilt slots skipped (QEMU woke late; lateness p50/p99/max \
         {tilt_late_us:?} us)"
    );
    // Record's `dropped` is its estimate of the missing pot samples (none: checked above and
    // here) plus the tilt readings missing from each sensor's grid, which it takes as the
    // smallest interval seen: read jitter makes that grid finer than the slots, so it may
    // count a skipped slot twice, never miss one.
    let mut tally = rigctl::daq::tally::Tally::new();
    for msg in &msgs {
        tally.on_message(msg);
    }
    assert_eq!(tally.dropped(), dropped, "{name}: the recording's tally");
    assert_eq!(
        (tally.gap_samples, tally.gap_batches, tally.first_seq),
        (0, 0, Some(0)),
        "{name}: pot samples missing"
    );
    assert!(
        tally.tilt_gap_readings >= skipped && dropped == tally.tilt_gap_readings,
        "{name}: record's dropped {dropped} vs {skipped} skipped tilt slots"
    );

    // Health: the board's own counters; its clock against the host's.
    let status = csv_rows(
        &csv.join("status.csv"),
        "host_rx_us,uptime_us,dropped_samples,dropped_frames,overruns,sensor_errors,rx_errors",
    );
    assert!(
        status.len() as u64 >= duration_s,
        "{name}: a Status a second"
    );
    // dropped samples, dropped frames, sensor errors, rx errors: none; overruns: exactly the
    // skipped tilt slots (the last Status is the one sent at Stop).
    for row in &status {
        assert_eq!(
            [row[2], row[3], row[5], row[6]],
            [0, 0, 0, 0],
            "{name}: status {row:?}"
        );
    }
    assert_eq!(
        status[status.len() - 1][4] as u64,
        skipped,
        "{name}: the board counted every skipped tilt slot as an overrun"
    );
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
        tilt_late_us,
        tilt_skipped: skipped,
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
fn emulated_board_records_known_signals_and_reports_panics_and_overflows() {
    if !qemu_or_skip() {
        return;
    }
    // Real time: nothing else real-time or CPU-heavy in this binary runs beside it.
    let _alone = crate::one_at_a_time();
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

    // A stack overflow (unbounded recursion) runs off the bottom of RAM, where flip-link put
    // the stack: the core cannot even stack the HardFault's frame, locks up, and run.sh says
    // so, naming the stack pointer below RAM, and fails.
    let overflowing = Emulator::start(dir.path(), "overflowing", 60, &["overflow-after-ms=1500"]);
    let (status, overflow_console) = overflowing.wait(Duration::from_secs(60));
    assert_eq!(
        status.code(),
        Some(1),
        "run.sh exits 1 after a stack overflow"
    );
    assert!(
        overflow_console.contains("forced stack overflow after 1500 ms"),
        "the overflow was started: {overflow_console}"
    );
    let report = overflow_console
        .lines()
        .find(|l| l.starts_with("run.sh: FAULT stack overflow"))
        .unwrap_or_else(|| panic!("stack overflow reported: {overflow_console}"));
    let sp = report
        .split("stack pointer at 0x")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .and_then(|h| u32::from_str_radix(h, 16).ok())
        .unwrap_or_else(|| panic!("stack pointer in the report: {report}"));
    assert!(
        sp < 0x2000_0000,
        "stack pointer {sp:#x} below RAM: {report}"
    );
    assert!(
        !overflow_console.contains("PANIC"),
        "no panic, a fault: {overflow_console}"
    );

    for (name, run) in [("1 kHz / 100 Hz", &long), ("500 Hz / 50 Hz", &short)] {
        println!(
            "emulated board, {name}: frames {}, lost 0, pot samples {}, tilt readings {}, \
             tilt slots skipped {} (allowed {:.0} %), tilt read lateness p50/p99/max {:?} us, \
             board clock {:.4} x host",
            run.frames,
            run.pot_samples,
            run.tilt_readings,
            run.tilt_skipped,
            TILT_SKIPPED_MAX * 100.0,
            run.tilt_late_us,
            run.clock_rate
        );
    }
    println!("emulated board: stack high-water mark {used} of {size} bytes (painted stack)");
    println!(
        "emulated board: test took {:.1} s",
        started.elapsed().as_secs_f64()
    );
}
