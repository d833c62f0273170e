//! Wire values checked where a recording is read (docs/reliability.md, "Boards and
//! recordings"): `potcal --recording` and `fuse` leave out the frames out of the board's
//! announced range exactly as `export` does (one check, `rigctl::daq::wire_check::in_range`),
//! report their count and exit 1, and what they write is what the same recording without those
//! frames gives. The binary under test is the debug build: an unchecked `u64` addition on the
//! wrapping batch would panic (exit 101).

use std::path::Path;

use rig_protocol::{DeviceMsg, TiltReading};
use rigctl::daq::export::decode_recording;
use rigctl::daq::recording::{read_recording, HelloMeta, RecordingMeta, RecordingWriter};

use crate::common::fake_board::{self, batch_at, frame};
use crate::common::spawn::{output, text};

/// A frame as `record` stores it (no delimiter).
fn stored(msg: &DeviceMsg) -> Vec<u8> {
    let mut f = frame(msg);
    f.pop();
    f
}

/// Writes `frames` (receive time, message) as a recording of a board that announced three
/// inclinometers.
fn write(path: &Path, pot_rate_hz: u32, frames: &[(u64, DeviceMsg)]) {
    let meta = RecordingMeta {
        protocol_version: rig_protocol::PROTOCOL_VERSION,
        port: "test".into(),
        start_time_unix_us: 0,
        pot_rate_hz,
        tilt_rate_hz: 100,
        hello: Some(HelloMeta::from(&fake_board::hello())),
        rigctl_version: "0".into(),
    };
    let mut w = RecordingWriter::create(path, &meta, false).unwrap();
    for (rx, msg) in frames {
        w.append(*rx, &stored(msg)).unwrap();
    }
    w.finish().unwrap();
}

/// `good` with six absurd frames (valid CRC) among its potentiometer batches: raw 65535,
/// period 0 and 1 MHz at the time of the next batch, a batch whose times wrap `u64`, one back
/// at the first batch's time, inclinometer 255 on a three-sensor board.
fn with_absurd(good: &[(u64, DeviceMsg)]) -> Vec<(u64, DeviceMsg)> {
    let pots: Vec<(usize, u64, u32, usize)> = good
        .iter()
        .enumerate()
        .filter_map(|(i, (_, m))| match m {
            DeviceMsg::Pot(b) => Some((i, b.t0_us, b.period_us, b.samples.len())),
            _ => None,
        })
        .collect();
    assert!(pots.len() > 30, "enough batches to spoil");
    let at = |k: usize| pots[k];
    let (_, first_t0, _, _) = at(0);
    let mut inserts: Vec<(usize, DeviceMsg)> = Vec::new();
    for (k, make) in [
        (6, 0u8), // raw beyond 12 bits, before the batch of its time
        (11, 1),  // period 0
        (16, 2),  // 1 MHz
        (21, 3),  // times wrap
        (26, 4),  // backwards
        (28, 5),  // inclinometer 255
    ] {
        let (i, t0, period, n) = at(k);
        let msg = match make {
            0 => batch_at(9000, t0, period, &vec![65535; n]),
            1 => batch_at(9001, t0, 0, &vec![100; n]),
            2 => batch_at(9002, t0, 1, &vec![100; n]),
            3 => batch_at(9003, u64::MAX - 1000, period, &vec![100; n]),
            4 => batch_at(9004, first_t0, period, &vec![100; n]),
            _ => DeviceMsg::Tilt(TiltReading {
                sensor: 255,
                t_us: t0,
                x: 0,
                y: 0,
                z: 6000,
                temp: 5000,
                status: 0,
            }),
        };
        inserts.push((i, msg));
    }
    let mut out = Vec::new();
    for (i, f) in good.iter().enumerate() {
        for (_, m) in inserts.iter().filter(|(at, _)| *at == i) {
            out.push((f.0, m.clone()));
        }
        out.push(f.clone());
    }
    out
}

/// The stderr line of the count: `N frames out of the board's announced range`.
fn out_of_range_count(stderr: &str) -> Option<u64> {
    let line = stderr
        .lines()
        .find(|l| l.contains("out of the board's announced range, not kept"))?;
    line.split(" frame")
        .next()?
        .rsplit(' ')
        .next()?
        .parse()
        .ok()
}

#[test]
fn potcal_leaves_out_absurd_recorded_frames_and_fails() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 1 kHz, 100 batches of 20 samples (2 s), counts rising 10 per batch: a linear pot
    let good: Vec<(u64, DeviceMsg)> = (0..100u32)
        .map(|k| {
            let t0 = u64::from(k) * 20_000;
            (t0, batch_at(k, t0, 1000, &[1000 + 10 * k as u16; 20]))
        })
        .collect();
    let (clean, spoiled) = (d.join("clean.rec"), d.join("spoiled.rec"));
    write(&clean, 1000, &good);
    write(&spoiled, 1000, &with_absurd(&good));
    let jig = d.join("jig.csv");
    std::fs::write(
        &jig,
        "start_s,end_s,travel_mm\n0.1,0.3,0\n0.7,0.9,5\n1.3,1.5,10\n",
    )
    .unwrap();
    let potcal = |rec: &Path, out: &Path| {
        output(&[
            "potcal".as_ref(),
            "--points".as_ref(),
            jig.as_os_str(),
            "--recording".as_ref(),
            rec.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
        ] as &[&std::ffi::OsStr])
    };
    let (a, b) = (d.join("clean.toml"), d.join("spoiled.toml"));
    let o = potcal(&clean, &a);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert_eq!(out_of_range_count(&text(&o.stderr)), None);

    let o = potcal(&spoiled, &b);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(out_of_range_count(&err), Some(6), "{err}");
    assert!(err.contains("left out"), "{err}");
    // the calibration is the one of the frames in range: the clean recording's
    assert_eq!(
        std::fs::read_to_string(&b).unwrap(),
        std::fs::read_to_string(&a).unwrap()
    );
}

#[test]
fn fuse_leaves_out_absurd_recorded_frames_and_fails() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let sim = d.join("s");
    let ok = |args: &[String]| {
        let o = output(args);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", text(&o.stderr));
        o
    };
    ok(&[
        "simulate".into(),
        "--session".into(),
        "line".into(),
        "--out".into(),
        s(&sim),
    ]);
    let trace = d.join("trace.csv");
    ok(&[
        "trace".into(),
        s(&sim.join("scan.png")),
        "--out".into(),
        s(&trace),
    ]);
    let pot = d.join("pot.toml");
    ok(&[
        "potcal".into(),
        "--points".into(),
        s(&sim.join("potjig.csv")),
        "--out".into(),
        s(&pot),
    ]);
    // the simulated recording as frames, written again by a board that announced its sensors
    let rec_path = sim.join("pot.rec");
    let good = decode_recording(&rec_path, &read_recording(&rec_path).unwrap()).unwrap();
    let rate = read_recording(&rec_path).unwrap().meta.pot_rate_hz;
    let (clean, spoiled) = (d.join("clean.rec"), d.join("spoiled.rec"));
    write(&clean, rate, &good);
    write(&spoiled, rate, &with_absurd(&good));
    let fuse = |rec: &Path, out: &Path| {
        output(&[
            "fuse".into(),
            "--joints".into(),
            s(&sim.join("joints.csv")),
            "--recording".into(),
            s(rec),
            "--trace".into(),
            s(&trace),
            "--placement".into(),
            s(&sim.join("placement.toml")),
            "--pot".into(),
            s(&pot),
            "--out".into(),
            s(out),
        ])
    };
    let (a, b) = (d.join("clean.csv"), d.join("spoiled.csv"));
    let clean_run = fuse(&clean, &a);
    assert_eq!(
        clean_run.status.code(),
        Some(0),
        "{}",
        text(&clean_run.stderr)
    );
    let o = fuse(&spoiled, &b);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(out_of_range_count(&err), Some(6), "{err}");
    // fused from the frames in range only: the clean recording's samples and report
    assert_eq!(o.stdout, clean_run.stdout);
    let fused = std::fs::read_to_string(&b).unwrap();
    assert!(fused.lines().count() > 100, "fused samples written");
    assert_eq!(fused, std::fs::read_to_string(&a).unwrap());
}
