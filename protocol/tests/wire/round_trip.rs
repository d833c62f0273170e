//! Encode -> decode round trips, buffer sizing, and the encoder's errors.

use crate::common;

use common::{frame_device, frame_host, max_pot_batch};
use rig_protocol::*;

#[test]
fn every_variant_round_trips() {
    for (name, msg) in common::device_samples() {
        let mut decoder = DeviceDecoder::new();
        let events: Vec<_> = decoder.feed(&frame_device(&msg)).collect();
        assert_eq!(events, vec![Decoded::Frame(msg)], "{name}");
    }
    for (name, msg) in common::host_samples() {
        let mut decoder = HostDecoder::new();
        let events: Vec<_> = decoder.feed(&frame_host(&msg)).collect();
        assert_eq!(events, vec![Decoded::Frame(msg)], "{name}");
    }
}

#[test]
fn max_size_pot_batch_fills_device_frame_max_exactly_and_round_trips() {
    let msg = max_pot_batch();
    let frame = frame_device(&msg);
    assert_eq!(frame.len(), DEVICE_FRAME_MAX);
    assert!(frame.len() <= FRAME_BUDGET);
    assert_eq!(
        frame.iter().filter(|&&b| b == 0).count(),
        1,
        "one delimiter, at the end"
    );
    let mut decoder = DeviceDecoder::new();
    assert_eq!(
        decoder.feed(&frame).collect::<Vec<_>>(),
        vec![Decoded::Frame(msg)]
    );
}

#[test]
fn largest_host_message_fits_host_frame_max() {
    let msg = HostMsg::Start {
        pot_rate_hz: u32::MAX,
        tilt_rate_hz: u32::MAX,
    };
    assert_eq!(frame_host(&msg).len(), HOST_FRAME_MAX);
}

#[test]
fn realistic_full_batch_is_smaller_than_the_bound() {
    // 12-bit samples take 2 varint bytes, not 3.
    let msg = DeviceMsg::Pot(PotBatch {
        seq: 1_000,
        t0_us: 3_600_000_000,
        period_us: 100,
        samples: heapless::Vec::from_slice(&[4095; POT_BATCH_MAX]).unwrap(),
    });
    let len = frame_device(&msg).len();
    // tag 1 + seq 2 + t0 5 + period 1 + len 1 + 64 x 2 = 138; + CRC 4 + COBS 1 + delimiter 1.
    assert_eq!(len, 144);
}

#[test]
fn small_buffer_is_an_error_not_a_panic() {
    let msg = max_pot_batch();
    for capacity in [0, 1, 2, 100, DEVICE_FRAME_MAX - 1] {
        let mut buf = vec![0u8; capacity];
        assert_eq!(
            encode_device(&msg, &mut buf),
            Err(FrameError::BufferTooSmall { capacity }),
            "capacity {capacity}"
        );
    }
    let mut buf = [0u8; 3];
    assert!(encode_host(&HostMsg::Stop, &mut buf).is_err());
    let mut buf = [0u8; 7];
    assert_eq!(
        encode_host(&HostMsg::Stop, &mut buf).map(<[u8]>::len),
        Ok(7)
    );
}

#[test]
fn back_to_back_frames_decode_in_order_from_one_slice() {
    let mut wire = Vec::new();
    let mut expected = Vec::new();
    for (_, msg) in common::device_samples() {
        wire.extend(frame_device(&msg));
        expected.push(Decoded::Frame(msg));
    }
    wire.extend(frame_device(&max_pot_batch()));
    expected.push(Decoded::Frame(max_pot_batch()));
    let mut decoder = DeviceDecoder::new();
    assert_eq!(decoder.feed(&wire).collect::<Vec<_>>(), expected);
    let stats = decoder.stats();
    assert_eq!(stats.frames, expected.len() as u64);
    assert_eq!(stats.corrupt, 0);
    assert_eq!(stats.bytes, wire.len() as u64);
}
