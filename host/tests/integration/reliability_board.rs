//! Recordings are never lost and never written twice at once; wire values are checked against
//! the board's announced configuration (docs/reliability.md, "Boards and recordings"). Every
//! board here is a scripted fake board on a real pseudo-terminal (`common::fake_board`).

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use rig_protocol::{DeviceMsg, TiltReading};
use rigctl::daq::export::export_csv;
use rigctl::daq::recording::{read_recording, RecordingError};
use rigctl::daq::session::{record, RecordConfig, RecordError, Timing};
use rigctl::daq::tally::Tally;
use rigctl::error::{Classify, ErrorKind};

use crate::common::fake_board::{self, batch, batch_at, frame, good_stream};

fn config(port: &Path, out: &Path, overwrite: bool, duration_ms: Option<u64>) -> RecordConfig {
    RecordConfig {
        port: port.to_path_buf(),
        out: out.to_path_buf(),
        duration: duration_ms.map(Duration::from_millis),
        pot_rate_hz: 1000,
        tilt_rate_hz: 100,
        overwrite,
        timing: Timing {
            hello_timeout: Duration::from_millis(300),
            silence_timeout: Duration::from_millis(400),
            drain_timeout: Duration::from_millis(300),
            ..Timing::default()
        },
    }
}

/// The names in `dir` other than `keep`.
fn others(dir: &Path, keep: &str) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != keep)
        .collect()
}

const OLD: &[u8] = b"RIGREC 1\nthe only recording of Tuesday's run\n";

#[test]
fn overwrite_keeps_the_old_recording_when_start_is_never_acknowledged() {
    let (port, board) = fake_board::spawn(false, good_stream());
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run.rigrec");
    std::fs::write(&out, OLD).unwrap();
    let stop = AtomicBool::new(false);
    let err = record(&config(&port, &out, true, None), &stop, &mut |_, _| {}).unwrap_err();
    board.join().unwrap();
    assert!(matches!(err, RecordError::NoAck { .. }), "{err}");
    assert_eq!(err.kind(), ErrorKind::Failure);
    assert_eq!(
        std::fs::read(&out).unwrap(),
        OLD,
        "the old recording was touched"
    );
    assert!(
        others(dir.path(), "run.rigrec").is_empty(),
        "{:?}",
        others(dir.path(), "run.rigrec")
    );
}

#[test]
fn overwrite_keeps_the_old_recording_when_the_run_brings_no_data() {
    // Ack(Start), then nothing but the Ack(Stop) when asked
    let (port, board) = fake_board::spawn(true, Box::new(|_| Vec::new()));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run.rigrec");
    std::fs::write(&out, OLD).unwrap();
    let mut cfg = config(&port, &out, true, None);
    cfg.timing.silence_timeout = Duration::from_secs(5);
    // Ctrl-C once the run is on
    let stop = AtomicBool::new(false);
    let err = std::thread::scope(|s| {
        let h = s.spawn(|| record(&cfg, &stop, &mut |_, _| {}));
        std::thread::sleep(Duration::from_millis(400));
        stop.store(true, Ordering::SeqCst);
        h.join().unwrap()
    })
    .unwrap_err();
    board.join().unwrap();
    assert!(
        matches!(err, RecordError::NoData { .. } | RecordError::Interrupted),
        "{err}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), OLD);
    assert!(others(dir.path(), "run.rigrec").is_empty());
}

#[test]
fn overwrite_replaces_the_old_recording_once_the_run_holds_data() {
    let (port, board) = fake_board::spawn(true, good_stream());
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run.rigrec");
    std::fs::write(&out, OLD).unwrap();
    let stop = AtomicBool::new(false);
    let tally = record(&config(&port, &out, true, Some(300)), &stop, &mut |_, _| {}).unwrap();
    board.join().unwrap();
    let rec = read_recording(&out).unwrap();
    assert_eq!(rec.records.len() as u64, tally.frames);
    assert!(tally.samples > 0);
    assert!(others(dir.path(), "run.rigrec").is_empty());
}

/// Runs `record` on a good board in a thread until `stop`; `started` gets a message at the
/// first progress call (the run is on and its data is in the file).
fn first_writer(
    out: &Path,
    overwrite: bool,
    stop: &'static AtomicBool,
) -> (
    std::path::PathBuf,
    mpsc::Receiver<()>,
    std::thread::JoinHandle<Result<Tally, RecordError>>,
) {
    let (port, _board) = fake_board::spawn(true, good_stream());
    let (tx, rx) = mpsc::channel();
    let cfg = config(&port, out, overwrite, None);
    let h = std::thread::spawn(move || {
        let mut sent = false;
        record(&cfg, stop, &mut |t, _| {
            if !sent && t.samples > 0 {
                sent = tx.send(()).is_ok();
            }
        })
    });
    (port, rx, h)
}

#[test]
fn two_records_into_one_file_one_is_refused_and_the_file_is_one_stream() {
    for (old, overwrite_a) in [(false, false), (true, true)] {
        static STOP_A: [AtomicBool; 2] = [AtomicBool::new(false), AtomicBool::new(false)];
        let stop = &STOP_A[usize::from(old)];
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("run.rigrec");
        if old {
            std::fs::write(&out, OLD).unwrap();
        }
        let (port_a, started, a) = first_writer(&out, overwrite_a, stop);
        started
            .recv_timeout(Duration::from_secs(10))
            .expect("the first record runs");
        // the second writer, with and without --overwrite, on its own board
        for overwrite_b in [true, false] {
            let (port_b, board_b) = fake_board::spawn(true, good_stream());
            let no_stop = AtomicBool::new(false);
            let err = record(
                &config(&port_b, &out, overwrite_b, Some(300)),
                &no_stop,
                &mut |_, _| {},
            )
            .unwrap_err();
            if overwrite_b {
                // (without --overwrite the port is never opened: that board just times out)
                board_b.join().unwrap();
            }
            let expected = if overwrite_b {
                matches!(err, RecordError::Recording(RecordingError::Busy { .. }))
            } else {
                matches!(err, RecordError::Recording(RecordingError::Exists { .. }))
            };
            assert!(expected, "second writer (overwrite {overwrite_b}): {err}");
            assert_eq!(err.kind(), ErrorKind::BadInput);
        }
        stop.store(true, Ordering::SeqCst);
        let tally = a.join().unwrap().unwrap();
        let rec = read_recording(&out).unwrap();
        assert_eq!(rec.meta.port, port_a.display().to_string());
        assert_eq!(rec.records.len() as u64, tally.frames, "one stream");
        assert!(others(dir.path(), "run.rigrec").is_empty());
    }
}

#[test]
fn a_board_sending_only_garbage_after_start_is_lost_after_the_silence_timeout() {
    // bytes that never make a good frame: a frame-sized run of 0x55 between delimiters
    let (port, board) = fake_board::spawn(
        true,
        Box::new(|_| {
            let mut b = vec![0x55; 40];
            b.push(0);
            b
        }),
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run.rigrec");
    let stop = AtomicBool::new(false);
    let err = record(&config(&port, &out, false, None), &stop, &mut |_, _| {}).unwrap_err();
    board.join().unwrap();
    assert!(matches!(err, RecordError::DeviceLost { .. }), "{err}");
    assert!(err.to_string().contains("no good frame"), "{err}");
    assert_eq!(err.kind(), ErrorKind::Failure);
    assert!(err.tally().unwrap().crc_errors > 0);
}

/// The absurd frames of the issue, each with a valid CRC.
fn absurd(k: u64) -> DeviceMsg {
    let seq = k as u32;
    let t0 = k * 20_000;
    match k % 6 {
        1 => batch_at(seq, t0, 0, &[1; 20]),        // sample period 0
        2 => batch_at(seq, t0, 1, &[1; 20]),        // 1 MHz
        3 => batch_at(seq, t0, 1000, &[65535; 20]), // beyond 12 bits
        4 => DeviceMsg::Tilt(TiltReading {
            sensor: 255, // on a 3-sensor board
            t_us: t0,
            x: 0,
            y: 0,
            z: 6000,
            temp: 5000,
            status: 0,
        }),
        5 => batch_at(seq, u64::MAX - 1000, 1000, &[1; 20]), // times wrap
        _ => batch(seq),
    }
}

#[test]
fn absurd_wire_values_are_counted_not_kept_and_fail_the_run() {
    let (port, board) = fake_board::spawn(
        true,
        Box::new(|k| {
            let mut b = frame(&absurd(k));
            if k % 6 == 5 {
                // and time going backwards after it
                b.extend(frame(&batch_at(k as u32, 0, 1000, &[1; 20])));
            }
            b
        }),
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run.rigrec");
    let stop = AtomicBool::new(false);
    let err = record(
        &config(&port, &out, false, Some(400)),
        &stop,
        &mut |_, _| {},
    )
    .unwrap_err();
    board.join().unwrap();
    let RecordError::OutOfRange { summary, tally, .. } = &err else {
        panic!("{err}");
    };
    assert_eq!(err.kind(), ErrorKind::Failure);
    assert!(
        summary.contains("out of the board's announced range"),
        "{summary}"
    );
    // only the good batches were counted: nothing absurd in the counts
    assert!(tally.samples > 0 && tally.samples % 20 == 0);
    assert!(tally.dropped() < 1_000_000, "dropped {}", tally.dropped());
    // and none of the absurd frames is in the recording: its export is clean and monotone
    let csv = dir.path().join("csv");
    let summary = export_csv(&out, &csv, true).unwrap();
    assert_eq!(summary.out_of_range, None);
    let pot = std::fs::read_to_string(csv.join("pot.csv")).unwrap();
    let times: Vec<u64> = pot
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    assert!(!times.is_empty());
    assert!(
        times.windows(2).all(|w| w[0] < w[1]),
        "pot.csv times not increasing"
    );
    assert!(pot.lines().skip(1).all(|l| l.ends_with(",2048")));
}

/// A recording (written as `record` did before this check) holding the absurd frames:
/// `export` leaves them out, counts them, and its arithmetic never wraps (a debug build of the
/// test would panic on an unchecked `u64` addition).
#[test]
fn export_of_absurd_recorded_frames_never_wraps_and_reports_them() {
    use rigctl::daq::recording::{HelloMeta, RecordingMeta, RecordingWriter};
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("old.rigrec");
    let meta = RecordingMeta {
        protocol_version: rig_protocol::PROTOCOL_VERSION,
        port: "test".into(),
        start_time_unix_us: 0,
        pot_rate_hz: 1000,
        tilt_rate_hz: 100,
        hello: Some(HelloMeta::from(&fake_board::hello())),
        rigctl_version: "0".into(),
    };
    let mut w = RecordingWriter::create(&rec, &meta, false).unwrap();
    let mut tally = Tally::new();
    for k in 0..12u64 {
        let msg = absurd(k);
        tally.on_message(&msg); // saturating: no panic in debug
        w.append(k, &frame(&msg)[..frame(&msg).len() - 1]).unwrap();
    }
    w.finish().unwrap();
    let csv = dir.path().join("csv");
    let summary = export_csv(&rec, &csv, false).unwrap();
    assert_eq!(summary.pot_rows, 40, "the two good batches");
    let why = summary
        .out_of_range
        .expect("the absurd frames are reported");
    assert!(why.starts_with("10 frames out of"), "{why}");
    let pot = std::fs::read_to_string(csv.join("pot.csv")).unwrap();
    assert!(!pot.contains("18446744073709"), "{pot}");
}
