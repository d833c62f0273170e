//! The recording session (`rigctl::daq::session::record`) against the virtual board served on a
//! real pseudo-terminal in a thread, and against hand-made misbehaving boards.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use rig_protocol::{encode_device, CommandKind, DeviceMsg, Hello, DEVICE_FRAME_MAX};
use rigctl::daq::board_sim::{serve, SimConfig, SimEnd, SimReport};
use rigctl::daq::export::decode_recording;
use rigctl::daq::pty::{MasterEvent, Pty};
use rigctl::daq::recording::read_recording;
use rigctl::daq::session::{record, RecordConfig, RecordError, Timing};
use rigctl::error::{Classify, ErrorKind};

fn config(port: &Path, out: &Path, duration: Option<Duration>) -> RecordConfig {
    RecordConfig {
        port: port.to_path_buf(),
        out: out.to_path_buf(),
        duration,
        pot_rate_hz: 1000,
        tilt_rate_hz: 100,
        overwrite: false,
        timing: Timing::default(),
    }
}

/// Serves a virtual board in a thread; returns the slave path and the thread.
fn spawn_sim(cfg: SimConfig) -> (std::path::PathBuf, JoinHandle<(SimReport, SimEnd)>) {
    let mut pty = Pty::open().unwrap();
    let path = pty.slave_path().to_path_buf();
    let handle = std::thread::spawn(move || {
        let stop = AtomicBool::new(false);
        serve(&mut pty, &cfg, &stop).unwrap()
    });
    (path, handle)
}

#[test]
fn session_records_every_frame_the_board_sent() {
    let (port, sim) = spawn_sim(SimConfig {
        seed: 9,
        speed: 20.0,
        ..SimConfig::default()
    });
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run.rigrec");
    let stop = AtomicBool::new(false);
    let mut calls = 0;
    let tally = record(
        &config(&port, &out, Some(Duration::from_millis(1500))),
        &stop,
        &mut |_, _| calls += 1,
    )
    .unwrap();
    let (report, end) = sim.join().unwrap();
    assert_eq!(end, SimEnd::HostStopped);
    assert!(calls >= 3, "progress called {calls} times");

    assert_eq!(tally.frames, report.frames_sent);
    assert_eq!(tally.samples, report.samples);
    assert_eq!(tally.tilt_readings, report.tilt_readings);
    assert_eq!((tally.dropped(), tally.crc_errors), (0, 0));
    // 1.5 s at 20x: about 30 000 samples.
    assert!(
        (29_000..=32_000).contains(&tally.samples),
        "{}",
        tally.samples
    );

    let recording = read_recording(&out).unwrap();
    assert_eq!(recording.records.len() as u64, tally.frames);
    let hello = recording.meta.hello.as_ref().unwrap();
    assert_eq!(hello.tilt_sensors, 3);
    assert_eq!(hello.schema_hash, rig_protocol::SCHEMA_HASH);
    assert_eq!(recording.meta.port, port.display().to_string());
    let frames = decode_recording(&out, &recording).unwrap();
    assert!(matches!(frames[0].1, DeviceMsg::Hello(_)));
    assert_eq!(frames.last().unwrap().1, DeviceMsg::Ack(CommandKind::Stop));
    assert!(
        frames.windows(2).all(|w| w[0].0 <= w[1].0),
        "receive times ascend"
    );
}

#[test]
fn stop_flag_ends_the_session_cleanly() {
    let (port, sim) = spawn_sim(SimConfig {
        speed: 5.0,
        ..SimConfig::default()
    });
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run.rigrec");
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let stopper = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(700));
        flag.store(true, Ordering::Relaxed);
    });
    let tally = record(&config(&port, &out, None), &stop, &mut |_, _| {}).unwrap();
    stopper.join().unwrap();
    let (report, _) = sim.join().unwrap();
    assert_eq!(tally.frames, report.frames_sent);
    assert!(tally.last_status.is_some(), "the final Status was recorded");
}

#[test]
fn board_ending_the_run_ends_the_session_cleanly() {
    let (port, sim) = spawn_sim(SimConfig {
        speed: 10.0,
        duration: Some(Duration::from_secs(3)),
        ..SimConfig::default()
    });
    let dir = tempfile::tempdir().unwrap();
    let stop = AtomicBool::new(false);
    let tally = record(
        &config(&port, &dir.path().join("r"), None),
        &stop,
        &mut |_, _| {},
    )
    .unwrap();
    let (report, end) = sim.join().unwrap();
    assert_eq!(end, SimEnd::DurationElapsed);
    // Samples at 0, 1, ..., 3000 ms of board time.
    assert_eq!((tally.samples, report.samples), (3001, 3001));
}

/// A board that answers every read with `hello`.
fn spawn_fake_board(hello: Hello) -> (std::path::PathBuf, JoinHandle<()>) {
    let mut pty = Pty::open().unwrap();
    let path = pty.slave_path().to_path_buf();
    let handle = std::thread::spawn(move || {
        let mut buf = [0u8; 256];
        let mut frame = [0u8; DEVICE_FRAME_MAX];
        let bytes = encode_device(&DeviceMsg::Hello(hello), &mut frame).unwrap();
        let mut connected = false;
        for _ in 0..500 {
            match pty.wait(Duration::from_millis(10)).unwrap() {
                MasterEvent::Readable => {
                    if let Some(n) = pty.read(&mut buf).unwrap() {
                        if n > 0 {
                            if !connected {
                                connected = true;
                                pty.release_slave();
                            }
                            pty.write(bytes).unwrap();
                        }
                    }
                }
                MasterEvent::HungUp if connected => return,
                _ => {}
            }
        }
    });
    (path, handle)
}

#[test]
fn a_board_with_another_protocol_is_refused_before_any_file_is_written() {
    for (version, hash, word) in [
        (
            rig_protocol::PROTOCOL_VERSION + 1,
            rig_protocol::SCHEMA_HASH,
            "protocol version",
        ),
        (
            rig_protocol::PROTOCOL_VERSION,
            rig_protocol::SCHEMA_HASH ^ 1,
            "schema hash",
        ),
    ] {
        let (port, board) = spawn_fake_board(Hello {
            protocol_version: version,
            firmware_version: [9, 9, 9],
            board_id: [0; 12],
            schema_hash: hash,
            tilt_sensors: 3,
        });
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("run.rigrec");
        let stop = AtomicBool::new(false);
        let err = record(&config(&port, &out, None), &stop, &mut |_, _| {}).unwrap_err();
        board.join().unwrap();
        assert!(matches!(err, RecordError::Mismatch { .. }), "{err}");
        assert!(err.to_string().contains(word), "{err}");
        assert_eq!(err.kind(), ErrorKind::Failure);
        assert!(!out.exists());
    }
}

#[test]
fn a_silent_port_gives_a_clear_timeout() {
    let pty = Pty::open().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut cfg = config(pty.slave_path(), &dir.path().join("run.rigrec"), None);
    cfg.timing.hello_timeout = Duration::from_millis(100);
    let stop = AtomicBool::new(false);
    let err = record(&cfg, &stop, &mut |_, _| {}).unwrap_err();
    assert!(
        matches!(err, RecordError::NoHello { attempts: 3, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("no Hello"), "{err}");
    assert!(!dir.path().join("run.rigrec").exists());
}

#[test]
fn an_existing_output_is_refused_before_the_port_is_opened() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run.rigrec");
    std::fs::write(&out, b"precious").unwrap();
    let stop = AtomicBool::new(false);
    let err = record(
        &config(Path::new("/nonexistent/port"), &out, None),
        &stop,
        &mut |_, _| {},
    )
    .unwrap_err();
    assert_eq!(err.kind(), ErrorKind::BadInput);
    assert_eq!(std::fs::read(&out).unwrap(), b"precious");
}
