//! Unit tests of `recording.rs`.

use super::*;

fn meta() -> RecordingMeta {
    RecordingMeta {
        protocol_version: 1,
        port: "/dev/ttyACM0".into(),
        start_time_unix_us: 1_700_000_000_000_000,
        pot_rate_hz: 1000,
        tilt_rate_hz: 100,
        hello: Some(HelloMeta {
            protocol_version: 1,
            firmware_version: "0.1.0".into(),
            board_id: "00112233445566778899aabb".into(),
            schema_hash: 0xdead_beef,
            tilt_sensors: 3,
        }),
        rigctl_version: "0.1.0".into(),
    }
}

fn frames() -> Vec<Record> {
    vec![
        Record {
            host_rx_us: 10,
            frame: vec![1, 2, 3],
        },
        Record {
            host_rx_us: 2_000,
            frame: vec![7; 40],
        },
        Record {
            host_rx_us: u64::MAX,
            frame: vec![0xff],
        },
    ]
}

fn write_small(path: &Path) -> Vec<u8> {
    let mut w = RecordingWriter::create(path, &meta(), false).unwrap();
    for r in frames() {
        w.append(r.host_rx_us, &r.frame).unwrap();
    }
    assert_eq!(w.records(), 3);
    w.finish().unwrap();
    std::fs::read(path).unwrap()
}

#[test]
fn round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.rigrec");
    write_small(&path);
    let rec = read_recording(&path).unwrap();
    assert_eq!(rec.meta, meta());
    assert_eq!(rec.records, frames());
    assert_eq!(rec.truncated_tail_bytes, 0);
}

#[test]
fn layout_is_as_documented() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = write_small(&dir.path().join("run.rigrec"));
    assert!(bytes.starts_with(b"RIGREC 1\n{\"protocol_version\":1,"));
    let header_len = header_bytes(&meta()).len();
    // First record: len 3, time 10, frame 1 2 3.
    assert_eq!(
        &bytes[header_len..header_len + 15],
        &[3, 0, 0, 0, 10, 0, 0, 0, 0, 0, 0, 0, 1, 2, 3]
    );
    assert_eq!(bytes.len(), header_len + 3 * 12 + 3 + 40 + 1);
}

#[test]
fn every_truncation_keeps_the_complete_records() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = write_small(&dir.path().join("run.rigrec"));
    let header_len = header_bytes(&meta()).len();
    let ends: Vec<usize> = {
        let mut end = header_len;
        frames()
            .iter()
            .map(|r| {
                end += RECORD_PREFIX_LEN + r.frame.len();
                end
            })
            .collect()
    };
    let path = Path::new("cut.rigrec");
    for cut in 0..=bytes.len() {
        let result = parse_recording(path, &bytes[..cut]);
        if cut < header_len {
            assert!(result.is_err(), "cut {cut} inside the header must fail");
            continue;
        }
        let rec = result.unwrap_or_else(|e| panic!("cut {cut}: {e}"));
        let complete = ends.iter().filter(|&&e| e <= cut).count();
        assert_eq!(rec.records, frames()[..complete], "cut {cut}");
        let last_end = if complete == 0 {
            header_len
        } else {
            ends[complete - 1]
        };
        assert_eq!(rec.truncated_tail_bytes, cut - last_end, "cut {cut}");
    }
}

#[test]
fn garbage_never_panics() {
    let path = Path::new("x");
    let mut header = header_bytes(&meta());
    // Pseudo-random bodies after a valid header and pseudo-random whole files.
    let mut state = 0x1234_5678_9abc_def0u64;
    for n in 0..500 {
        let mut body = Vec::new();
        for _ in 0..(n % 64) {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            body.push((state >> 24) as u8);
        }
        let _ = parse_recording(path, &body);
        header.truncate(header_bytes(&meta()).len());
        header.extend_from_slice(&body);
        let _ = parse_recording(path, &header);
    }
}

#[test]
fn corrupt_length_is_an_error_with_offset() {
    let mut bytes = header_bytes(&meta());
    let header_len = bytes.len();
    bytes.extend_from_slice(&(MAX_FRAME_LEN as u32 + 1).to_le_bytes());
    bytes.extend_from_slice(&[0; 8]);
    match parse_recording(Path::new("x"), &bytes) {
        Err(RecordingError::CorruptRecord { offset, .. }) => assert_eq!(offset, header_len),
        other => panic!("expected CorruptRecord, got {other:?}"),
    }
}

#[test]
fn wrong_magic_and_version_are_refused() {
    let p = Path::new("x");
    assert!(matches!(
        parse_recording(p, b"PNG\n"),
        Err(RecordingError::NotARecording { .. })
    ));
    assert!(matches!(
        parse_recording(p, b"RIGREC 2\n{}\n"),
        Err(RecordingError::UnsupportedVersion { .. })
    ));
}

#[test]
fn existing_file_is_not_overwritten_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.rigrec");
    std::fs::write(&path, b"keep").unwrap();
    assert!(matches!(
        RecordingWriter::create(&path, &meta(), false),
        Err(RecordingError::Exists { .. })
    ));
    assert_eq!(std::fs::read(&path).unwrap(), b"keep");
    RecordingWriter::create(&path, &meta(), true).unwrap();
}
