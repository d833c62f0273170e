//! Issue 15, defects 3, 5 (the .rec header) and 7 (tilt losses counted): damaged recordings.

use std::path::Path;

use rig_protocol::{encode_device, DeviceMsg, PotBatch, TiltReading, DEVICE_FRAME_MAX};
use rigctl::daq::recording::{header_bytes, RecordingMeta, RecordingWriter};
use rigctl::daq::salvage::salvage;
use rigctl::daq::tally::Tally;

use super::common::record::record;
use super::common::spawn::rigctl;

fn meta() -> RecordingMeta {
    RecordingMeta {
        protocol_version: 1,
        port: "test".into(),
        start_time_unix_us: 0,
        pot_rate_hz: 1000,
        tilt_rate_hz: 100,
        hello: None,
        rigctl_version: "test".into(),
    }
}

fn pot(seq: u32) -> DeviceMsg {
    let samples: Vec<u16> = (0..32)
        .map(|i| 1000 + (seq * 32 + i) as u16 % 3000)
        .collect();
    DeviceMsg::Pot(PotBatch {
        seq,
        t0_us: u64::from(seq) * 32_000,
        period_us: 1000,
        samples: heapless::Vec::from_slice(&samples).unwrap(),
    })
}

fn tilt(k: u64) -> DeviceMsg {
    DeviceMsg::Tilt(TiltReading {
        sensor: 0,
        t_us: k * 10_000,
        x: 1,
        y: 2,
        z: 6000,
        temp: 5632,
        status: 0,
    })
}

/// 100 pot batches (1 ms grid, 32 samples each) and a tilt reading every 10 ms, as recorded.
fn write_rec(path: &Path) -> Vec<usize> {
    let mut w = RecordingWriter::create(path, &meta(), false).unwrap();
    let mut offsets = Vec::new();
    let mut end = header_bytes(&meta()).len();
    for seq in 0..100u32 {
        for msg in [pot(seq), tilt(u64::from(seq) * 32 / 10)] {
            let mut buf = [0u8; DEVICE_FRAME_MAX];
            let frame = encode_device(&msg, &mut buf).unwrap();
            let stored = &frame[..frame.len() - 1];
            offsets.push(end);
            end += 12 + stored.len();
            w.append(u64::from(seq) * 32_000, stored).unwrap();
        }
    }
    w.finish().unwrap();
    offsets
}

#[test]
fn defect3_one_flipped_byte_costs_one_record_and_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("run.rec");
    let offsets = write_rec(&rec);
    let clean = std::fs::read(&rec).unwrap();
    // Every byte of record 80 (a pot batch) in its length prefix and its frame. (The host
    // receive time, bytes 4..12 of a record, is outside the frame's CRC: a flip there changes
    // only that time, the record is still read.)
    let (start, end) = (offsets[80], offsets[81]);
    for at in (start..start + 4).chain(start + 12..end) {
        let mut bytes = clean.clone();
        bytes[at] ^= 0x5a;
        let s = salvage(&rec, &bytes, false).unwrap_or_else(|e| panic!("byte {at}: {e}"));
        assert_eq!(s.frames.len(), 199, "byte {at}");
        assert_eq!(s.damaged.len(), 1, "byte {at}");
        assert_eq!(s.damaged[0].offset, start, "byte {at}");
        assert_eq!(s.damaged[0].bytes, end - start, "byte {at}");
        assert_eq!(s.damaged[0].pot_samples_lost, 32, "byte {at}");
        assert!(salvage(&rec, &bytes, true).is_err(), "strict, byte {at}");
        if at == start {
            record("records_written", offsets.len());
            record("records_read", s.frames.len());
            record("pot_samples_lost", s.damaged[0].pot_samples_lost);
        }
    }

    // The CLI: export/potcal go on, report on stderr; --strict refuses with exit 2.
    let mut bytes = clean.clone();
    bytes[(start + end) / 2] ^= 0xff;
    std::fs::write(&rec, &bytes).unwrap();
    let csv = dir.path().join("csv");
    let o = rigctl()
        .arg("export")
        .arg(&rec)
        .arg("--csv")
        .arg(&csv)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("skipped") && err.contains("32 potentiometer samples lost"),
        "{err}"
    );
    assert!(
        err.contains("(32 samples dropped)") || err.contains("dropped"),
        "{err}"
    );
    let pot_rows = std::fs::read_to_string(csv.join("pot.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    assert_eq!(pot_rows, 99 * 32);
    let csv2 = dir.path().join("csv2");
    let o = rigctl()
        .arg("export")
        .arg(&rec)
        .arg("--csv")
        .arg(&csv2)
        .arg("--strict")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(!csv2.join("pot.csv").exists());

    // potcal --recording with jig windows: works on the damaged file.
    let jig = dir.path().join("jig.csv");
    std::fs::write(
        &jig,
        "start_s,end_s,travel_mm\n0,0.5,0\n1.0,1.5,5\n2.0,2.5,10\n",
    )
    .unwrap();
    let o = rigctl()
        .args(["potcal", "--points"])
        .arg(&jig)
        .arg("--recording")
        .arg(&rec)
        .arg("--out")
        .arg(dir.path().join("pot.toml"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.code() != Some(101), "{err}");
    assert!(
        !err.contains("does not decode"),
        "potcal refused the damaged recording: {err}"
    );
}

#[test]
fn defect5_crlf_recording_header_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("run.rec");
    write_rec(&rec);
    let bytes = std::fs::read(&rec).unwrap();
    let header_len = header_bytes(&meta()).len();
    let text = String::from_utf8(bytes[..header_len].to_vec()).unwrap();
    let mut crlf = text.replace('\n', "\r\n").into_bytes();
    crlf.extend_from_slice(&bytes[header_len..]);
    let s = salvage(&rec, &crlf, true).unwrap();
    assert_eq!(s.frames.len(), 200);
}

#[test]
fn defect7_tilt_readings_lost_count_in_dropped() {
    let mut t = Tally::new();
    for k in 0..50u64 {
        if k == 20 || k == 21 {
            continue; // two readings lost to corrupt frames
        }
        t.on_message(&tilt(k));
    }
    assert_eq!(t.tilt_gap_readings, 2);
    assert_eq!(t.dropped(), 2);
}
