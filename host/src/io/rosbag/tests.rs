//! Unit tests of `rosbag.rs`.

use super::*;

const METADATA: &str = "rosbag2_bagfile_information:
  version: 8
  storage_identifier: mcap
  message_count: 12
  topics_with_message_count:
    - topic_metadata:
        name: /other
        type: std_msgs/msg/String
        serialization_format: cdr
        offered_qos_profiles: ''
      message_count: 2
    - topic_metadata:
        name: /joint_states
        type: sensor_msgs/msg/JointState
        serialization_format: cdr
        offered_qos_profiles: \"\"
      message_count: 10
  compression_format: ''
  relative_file_paths:
    - session_0.mcap
    - 'session_1.mcap'
  files:
    - path: session_0.mcap
      message_count: 12
";

#[test]
fn metadata_files_and_topic_count() {
    let (files, n) = parse_metadata(METADATA, "/joint_states").unwrap();
    assert_eq!(files, ["session_0.mcap", "session_1.mcap"]);
    assert_eq!(n, Some(10));
    let (_, n) = parse_metadata(METADATA, "/other").unwrap();
    assert_eq!(n, Some(2));
    let (_, n) = parse_metadata(METADATA, "/absent").unwrap();
    assert_eq!(n, None);
}

/// rosbags writes the keys sorted: an item's count before its topic's name.
#[test]
fn metadata_count_before_name() {
    let text = "rosbag2_bagfile_information:
  files:
  - message_count: 99
    path: b.mcap
  relative_file_paths:
  - b.mcap
  storage_identifier: mcap
  topics_with_message_count:
  - message_count: 7
    topic_metadata:
      name: /other
      type: std_msgs/msg/String
  - message_count: 1348
    topic_metadata:
      name: /joint_states
      type_description_hash: 
        RIHS01_a13e
      type: sensor_msgs/msg/JointState
  version: 8
";
    let (files, n) = parse_metadata(text, "/joint_states").unwrap();
    assert_eq!(files, ["b.mcap"]);
    assert_eq!(n, Some(1348));
    assert_eq!(parse_metadata(text, "/other").unwrap().1, Some(7));
}

#[test]
fn metadata_refuses_sqlite_and_no_files() {
    let sqlite = METADATA.replace("storage_identifier: mcap", "storage_identifier: sqlite3");
    assert_eq!(parse_metadata(&sqlite, "/x").unwrap_err().0, 3);
    let none = "rosbag2_bagfile_information:\n  version: 8\n";
    assert!(parse_metadata(none, "/x").is_err());
    let db3 = METADATA.replace("session_0.mcap\n    - 'session_1.mcap'", "bag.db3");
    let err = parse_metadata(&db3, "/x").unwrap_err();
    assert!(err.1.contains("bag.db3"), "{err:?}");
}

/// An MCAP file of `n` JointState messages (joints `a`, `b`; `a` = 0.001 k rad) in
/// uncompressed chunks of about 2 kB with CRCs, written by the `mcap` crate.
fn bag_bytes(n: u32) -> Vec<u8> {
    let mut buf = std::io::Cursor::new(Vec::new());
    let mut w = mcap::WriteOptions::new()
        .compression(None)
        .chunk_size(Some(2000))
        .create(&mut buf)
        .unwrap();
    let schema = w.add_schema(JOINT_STATE_TYPE, "ros2msg", b"").unwrap();
    let ch = w
        .add_channel(schema, "/joint_states", "cdr", &Default::default())
        .unwrap();
    for k in 0..n {
        let m = crate::io::cdr::JointState {
            sec: 10,
            nanosec: k * 1000,
            frame_id: String::new(),
            names: vec!["b".into(), "a".into()],
            position: vec![-0.2, 0.001 * f64::from(k)],
        };
        let header = mcap::records::MessageHeader {
            channel_id: ch,
            sequence: k,
            log_time: u64::from(k),
            publish_time: u64::from(k),
        };
        w.write_to_known_channel(&header, &crate::io::cdr::encode_joint_state(&m))
            .unwrap();
    }
    w.finish().unwrap();
    drop(w);
    buf.into_inner()
}

fn read(bytes: &[u8]) -> Result<(BagSummary, Vec<JointReading>), BagError> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("b.mcap");
    std::fs::write(&path, bytes).unwrap();
    let names = ["a".to_string()];
    let spec = JointLogSpec {
        topic: DEFAULT_JOINT_TOPIC,
        names: &names,
        prismatic: &[false],
    };
    let mut got = Vec::new();
    let summary = read_joint_log(&path, &spec, |r| {
        got.push(r);
        Ok::<(), BagError>(())
    })?;
    Ok((summary, got))
}

#[test]
fn reads_every_message_by_name() {
    let (summary, got) = read(&bag_bytes(100)).unwrap();
    assert_eq!(summary.used, 100);
    assert!(summary.notes(Path::new("b")).is_empty());
    for (k, r) in got.iter().enumerate() {
        assert_eq!(r.message, k as u64 + 1);
        assert!((r.t_s - k as f64 * 1e-6).abs() < 1e-15);
        assert!((r.q[0] - (0.001 * k as f64).to_degrees()).abs() < 1e-12);
    }
}

#[test]
fn a_chunk_with_a_bad_crc_is_skipped_and_reading_goes_on() {
    let mut bytes = bag_bytes(100);
    // Flip a byte of message 50's position `a` (0.05 rad): its chunk's CRC no longer holds.
    let needle = 0.05f64.to_le_bytes();
    let at = bytes
        .windows(8)
        .position(|w| w == needle)
        .expect("message 50 is in the file");
    bytes[at] ^= 0x01;
    let (summary, got) = read(&bytes).unwrap();
    assert_eq!(summary.skipped_chunks, 1);
    assert!(summary.damage.is_none());
    assert!(got.len() < 100 && got.len() > 50, "{}", got.len());
    assert!(got
        .iter()
        .all(|r| (r.q[0] - 0.05f64.to_degrees()).abs() > 1e-9));
    // Messages after the skipped chunk are read.
    assert!((got.last().unwrap().q[0] - 0.099f64.to_degrees()).abs() < 1e-12);
    let notes = summary.notes(Path::new("b")).join("\n");
    assert!(notes.contains("skipped 1 damaged chunk(s)"), "{notes}");
    assert!(notes.contains("CRC"), "{notes}");
}

#[test]
fn every_cut_reads_a_prefix_or_refuses() {
    let bytes = bag_bytes(60);
    let (_, all) = read(&bytes).unwrap();
    for cut in (0..bytes.len()).step_by(37) {
        match read(&bytes[..cut]) {
            Ok((summary, got)) => {
                assert!(summary.damage.is_some(), "cut at {cut}");
                assert_eq!(got[..], all[..got.len()], "cut at {cut}");
            }
            Err(e) => assert!(
                matches!(
                    e,
                    BagError::NotMcap { .. } | BagError::NothingReadable { .. }
                ),
                "cut at {cut}: {e}"
            ),
        }
    }
}

#[test]
fn bag_paths() {
    assert!(is_bag(Path::new("a/b.mcap")));
    assert!(is_bag(Path::new("a/b.MCAP")));
    assert!(!is_bag(Path::new("a/b.csv")));
}
