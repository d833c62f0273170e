//! FROZEN wire vectors: the exact bytes of one frame of every message variant.
//!
//! These hex strings were produced once by the encoder (messages from `common::device_samples`
//! / `common::host_samples`) and independently checked: COBS un-stuffed by hand, CRC compared
//! with zlib's crc32, postcard bytes read field by field. They are checked byte-exactly.
//!
//! DO NOT regenerate them to make a failing test pass. A failure here means the wire format
//! changed: if that is intended, bump `PROTOCOL_VERSION`, update the frozen schema hash
//! (tests/schema.rs, derived from the types), then replace these vectors on purpose, in the
//! same commit.

use crate::common;

use common::{frame_device, frame_host, hex};
use rig_protocol::{Decoded, DeviceDecoder, HostDecoder};

const DEVICE_VECTORS: &[(&str, &str)] = &[
    (
        "hello",
        "0102010e030c102030405060708090a0b00beffdb6f50d036e86a66800",
    ),
    (
        "pot",
        "0c01ac02d285d8cc04e807060d017f80018010ff1fa3b19d6600",
    ),
    ("pot_empty", "0201010264050e70d3fa00"),
    ("tilt", "12020286a43cef0146de5d985701e5da282f00"),
    ("status", "0803808ece1c4001070203f06e1f8b00"),
    ("pong", "0a0484868808f28da04900"),
    ("ack_start", "020505bae6ae3c00"),
    ("ack_stop", "0705012cd6a94b00"),
    ("ack_ping", "0705029687a0d200"),
    ("ack_getinfo", "03050304b7a7a500"),
    ("nack_rate", "02060105a0a5ccfb00"),
    ("nack_running", "020606013695cb8c00"),
    ("nack_not_running", "08060102cdf5d90c00"),
];

const HOST_VECTORS: &[(&str, &str)] = &[
    ("start", "0108e80764826d2b8300"),
    ("stop", "06011bdf05a500"),
    ("ping", "07022aabb954a800"),
    ("getinfo", "060337be0b4b00"),
];

fn unhex(s: &str) -> Vec<u8> {
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).expect("hex literal"))
        .collect()
}

#[test]
fn every_device_variant_encodes_to_its_frozen_bytes() {
    let samples = common::device_samples();
    assert_eq!(
        samples.len(),
        DEVICE_VECTORS.len(),
        "a variant lacks a vector"
    );
    for ((name, msg), (vname, vector)) in samples.iter().zip(DEVICE_VECTORS) {
        assert_eq!(name, vname);
        assert_eq!(
            hex(&frame_device(msg)),
            *vector,
            "wire format of `{name}` changed"
        );
    }
}

#[test]
fn every_host_variant_encodes_to_its_frozen_bytes() {
    let samples = common::host_samples();
    assert_eq!(
        samples.len(),
        HOST_VECTORS.len(),
        "a variant lacks a vector"
    );
    for ((name, msg), (vname, vector)) in samples.iter().zip(HOST_VECTORS) {
        assert_eq!(name, vname);
        assert_eq!(
            hex(&frame_host(msg)),
            *vector,
            "wire format of `{name}` changed"
        );
    }
}

#[test]
fn frozen_bytes_decode_to_the_messages() {
    for ((name, msg), (_, vector)) in common::device_samples().iter().zip(DEVICE_VECTORS) {
        let mut decoder = DeviceDecoder::new();
        let events: Vec<_> = decoder.feed(&unhex(vector)).collect();
        assert_eq!(events, vec![Decoded::Frame(msg.clone())], "{name}");
    }
    for ((name, msg), (_, vector)) in common::host_samples().iter().zip(HOST_VECTORS) {
        let mut decoder = HostDecoder::new();
        let events: Vec<_> = decoder.feed(&unhex(vector)).collect();
        assert_eq!(events, vec![Decoded::Frame(*msg)], "{name}");
    }
}
