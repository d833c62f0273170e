//! Streaming decoder: resynchronisation, split feeds, corruption of every kind, counters.

use crate::common;

use common::{frame_device, frame_host, max_pot_batch};
use rig_protocol::*;

fn decode_all(decoder: &mut DeviceDecoder, bytes: &[u8]) -> Vec<Decoded<DeviceMsg>> {
    decoder.feed(bytes).collect()
}

fn corrupt(reason: CorruptReason) -> Decoded<DeviceMsg> {
    Decoded::CorruptFrame { reason }
}

fn pong(nonce: u32) -> DeviceMsg {
    DeviceMsg::Pong { nonce }
}

#[test]
fn garbage_without_delimiter_yields_nothing_until_the_next_zero() {
    let mut decoder = DeviceDecoder::new();
    assert_eq!(decode_all(&mut decoder, &[0x13, 0x37, 0xAB]), vec![]);
    assert!(decoder.in_frame());
    // The 0x00 condemns the garbage; the following frame is clean.
    let mut wire = vec![0x00];
    wire.extend(frame_device(&pong(5)));
    let events = decode_all(&mut decoder, &wire);
    assert_eq!(events.len(), 2);
    assert!(matches!(events[0], Decoded::CorruptFrame { .. }));
    assert_eq!(events[1], Decoded::Frame(pong(5)));
    assert_eq!((decoder.stats().frames, decoder.stats().corrupt), (1, 1));
}

#[test]
fn resyncs_after_garbage_and_a_truncated_frame() {
    let good = frame_device(&max_pot_batch());
    let mut wire = Vec::new();
    wire.extend_from_slice(&good[good.len() / 2..good.len() - 1]); // listening mid-frame
    wire.extend_from_slice(&[0xFF; 40]);
    wire.push(0x00);
    wire.extend_from_slice(&good);
    wire.extend_from_slice(&good[..good.len() - 30]); // cut short by a reset of the board
    wire.push(0x00);
    wire.extend_from_slice(&frame_device(&pong(9)));
    let mut decoder = DeviceDecoder::new();
    let events = decode_all(&mut decoder, &wire);
    let frames: Vec<_> = events
        .iter()
        .filter_map(|e| match e {
            Decoded::Frame(m) => Some(m.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(frames, vec![max_pot_batch(), pong(9)]);
    let stats = decoder.stats();
    assert_eq!(stats.frames, 2);
    assert_eq!(stats.corrupt, 2);
    // The cut frame ends inside a COBS block (the batch has no zero byte: a single 219-byte block).
    assert_eq!(events[2], corrupt(CorruptReason::Cobs));
}

#[test]
fn byte_by_byte_and_every_split_point_give_the_same_events() {
    let mut wire = Vec::new();
    for (_, msg) in common::device_samples() {
        wire.extend(frame_device(&msg));
    }
    let mut whole = DeviceDecoder::new();
    let expected = decode_all(&mut whole, &wire);
    assert_eq!(expected.len(), common::device_samples().len());

    let mut bytewise = DeviceDecoder::new();
    let events: Vec<_> = wire.iter().filter_map(|&b| bytewise.push(b)).collect();
    assert_eq!(events, expected);

    for split in 0..wire.len() {
        let mut decoder = DeviceDecoder::new();
        let mut events = decode_all(&mut decoder, &wire[..split]);
        events.extend(decode_all(&mut decoder, &wire[split..]));
        assert_eq!(events, expected, "split at {split}");
    }
}

#[test]
fn push_slice_matches_feed() {
    let wire = [
        frame_device(&pong(1)),
        vec![1, 2, 0],
        frame_device(&pong(2)),
    ]
    .concat();
    let mut a = DeviceDecoder::new();
    let mut b = DeviceDecoder::new();
    let mut events = Vec::new();
    a.push_slice(&wire, |e| events.push(e));
    assert_eq!(events, decode_all(&mut b, &wire));
    assert_eq!(a.stats(), b.stats());
}

#[test]
fn every_single_bit_flip_is_detected() {
    // CRC-32 detects all 1-bit errors; COBS may turn a flip into a split or a shift, which
    // must still never produce a wrong message.
    let msg = common::device_samples()[3].1.clone(); // tilt
    let good = frame_device(&msg);
    for byte in 0..good.len() {
        for bit in 0..8 {
            let mut bad = good.clone();
            bad[byte] ^= 1 << bit;
            bad.push(0x00); // a flipped delimiter must not glue onto the next test's frame
            let mut decoder = DeviceDecoder::new();
            let events = decode_all(&mut decoder, &bad);
            assert!(
                events.iter().all(|e| !matches!(e, Decoded::Frame(_))),
                "flip of bit {bit} of byte {byte} went unnoticed: {events:?}"
            );
            assert!(decoder.stats().corrupt >= 1);
        }
    }
}

#[test]
fn crc_error_is_reported_as_crc() {
    let mut frame = frame_device(&pong(0x0102_0304));
    frame[3] ^= 0x10; // a data byte, not a COBS code byte
    let mut decoder = DeviceDecoder::new();
    assert_eq!(
        decode_all(&mut decoder, &frame),
        vec![corrupt(CorruptReason::Crc)]
    );
    assert_eq!(decoder.stats().crc_errors, 1);
}

#[test]
fn frame_too_short_for_a_crc_is_a_crc_error() {
    let mut decoder = DeviceDecoder::new();
    // COBS-valid frames of 1..=3 decoded bytes.
    for wire in [
        &[0x02, 0x05, 0x00][..],
        &[0x03, 0x05, 0x06, 0x00],
        &[0x01, 0x01, 0x00],
    ] {
        assert_eq!(
            decode_all(&mut decoder, wire),
            vec![corrupt(CorruptReason::Crc)]
        );
    }
}

#[test]
fn valid_crc_but_not_a_message_is_a_postcard_error() {
    let mut buf = [0u8; 64];
    let mut decoder = DeviceDecoder::new();
    // Unknown enum tag.
    let frame = encode(&99u8, &mut buf).unwrap().to_vec();
    assert_eq!(
        decode_all(&mut decoder, &frame),
        vec![corrupt(CorruptReason::Postcard)]
    );
    // A real message followed by trailing bytes.
    let frame = encode(&(pong(1), 5u8), &mut buf).unwrap().to_vec();
    assert_eq!(
        decode_all(&mut decoder, &frame),
        vec![corrupt(CorruptReason::Postcard)]
    );
    // More samples than POT_BATCH_MAX: tag 1, seq, t0, period, len = 65.
    let mut body = vec![1u8, 0, 0, 100, (POT_BATCH_MAX + 1) as u8];
    body.extend(std::iter::repeat_n(7u8, POT_BATCH_MAX + 1));
    let mut big = [0u8; 256];
    let frame = encode(&Raw(&body), &mut big).unwrap().to_vec();
    assert_eq!(
        decode_all(&mut decoder, &frame),
        vec![corrupt(CorruptReason::Postcard)]
    );
    assert_eq!(decoder.stats().postcard_errors, 3);
}

/// Serializes as the given bytes verbatim (postcard tuples have no framing of their own).
struct Raw<'a>(&'a [u8]);

impl serde::Serialize for Raw<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeTuple;
        let mut t = s.serialize_tuple(self.0.len())?;
        for b in self.0 {
            t.serialize_element(b)?;
        }
        t.end()
    }
}

#[test]
fn host_frames_are_not_accepted_as_device_frames_by_accident() {
    // Tags overlap (HostMsg::Start and DeviceMsg::Hello are both tag 0) but the bodies do not
    // parse: the decoder reports Postcard, never a wrong message.
    let mut decoder = DeviceDecoder::new();
    let events = decode_all(
        &mut decoder,
        &frame_host(&HostMsg::Start {
            pot_rate_hz: 1000,
            tilt_rate_hz: 100,
        }),
    );
    assert_eq!(events, vec![corrupt(CorruptReason::Postcard)]);
}

#[test]
fn overlong_frame_is_reported_once_and_skipped_to_the_next_zero() {
    let mut decoder = DeviceDecoder::new();
    let mut wire = vec![0x42u8; 3 * DEVICE_FRAME_MAX];
    wire.push(0x00);
    wire.extend(frame_device(&pong(3)));
    let events = decode_all(&mut decoder, &wire);
    assert_eq!(
        events,
        vec![corrupt(CorruptReason::Overlong), Decoded::Frame(pong(3))]
    );
    let stats = decoder.stats();
    assert_eq!((stats.overlong, stats.corrupt, stats.frames), (1, 1, 1));
}

#[test]
fn empty_frames_are_ignored() {
    let mut decoder = DeviceDecoder::new();
    let wire = [vec![0, 0, 0], frame_device(&pong(1)), vec![0, 0]].concat();
    assert_eq!(
        decode_all(&mut decoder, &wire),
        vec![Decoded::Frame(pong(1))]
    );
    assert_eq!(decoder.stats().corrupt, 0);
}

#[test]
fn clear_drops_a_partial_frame_and_stats_can_be_reset() {
    let frame = frame_device(&pong(8));
    let mut decoder = DeviceDecoder::new();
    assert_eq!(decode_all(&mut decoder, &frame[..4]), vec![]);
    decoder.clear();
    assert!(!decoder.in_frame());
    assert_eq!(
        decode_all(&mut decoder, &frame),
        vec![Decoded::Frame(pong(8))]
    );
    assert_eq!(decoder.stats().bytes, 4 + frame.len() as u64);
    decoder.reset_stats();
    assert_eq!(decoder.stats(), DecoderStats::default());
}

#[test]
fn host_decoder_on_the_board_side() {
    let mut decoder = HostDecoder::new();
    let wire = [
        frame_host(&HostMsg::Stop),
        vec![0x55; 300],
        vec![0],
        frame_host(&HostMsg::GetInfo),
    ]
    .concat();
    let events: Vec<_> = decoder.feed(&wire).collect();
    assert_eq!(
        events,
        vec![
            Decoded::Frame(HostMsg::Stop),
            Decoded::CorruptFrame {
                reason: CorruptReason::Overlong
            },
            Decoded::Frame(HostMsg::GetInfo)
        ]
    );
}
