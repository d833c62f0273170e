//! The frame decoders on arbitrary bytes. The first byte chooses one check per input (so each
//! execution passes the bytes through one or two decoders, not every decoder every time) and,
//! with its upper six bits, where a stream is split:
//!
//! - 0 / 1: the bytes as a wire stream into the device / host decoder, fed in two parts split
//!   at that point, compared in lockstep with a second decoder fed the whole: the same events,
//!   counters that add up, and every decoded message re-encodes to a frame that decodes to it;
//! - 2 / 3: the bytes as a frame *payload*: the harness appends the CRC-32 and COBS-stuffs it
//!   (its own encoder, independent of the crate's), so postcard decoding is fuzzed behind a
//!   valid CRC; the decoder must yield exactly one event, never a COBS or CRC error: a message
//!   (which re-encodes to itself), a postcard error, or "overlong" for a body past the buffer.
//!
//! No allocation, no logging: the whole check is a few passes over at most `-max_len` bytes
//! (README: 512, a couple of frames).
#![no_main]

use core::fmt::Debug;

use libfuzzer_sys::fuzz_target;
use postcard::experimental::max_size::MaxSize;
use rig_protocol::frame::{encode, CorruptReason, Decoder};
use rig_protocol::{Decoded, DeviceMsg, HostMsg, DEVICE_RAW_MAX, FRAME_BUDGET, HOST_RAW_MAX};
use serde::{de::DeserializeOwned, Serialize};

trait Msg: DeserializeOwned + MaxSize + Serialize + PartialEq + Debug {}
impl<M: DeserializeOwned + MaxSize + Serialize + PartialEq + Debug> Msg for M {}

/// A decoded message must re-encode to a frame that decodes to the same event.
fn check_reencodes<M: Msg, const RAW: usize>(event: &Decoded<M>) {
    if let Decoded::Frame(msg) = event {
        let mut buf = [0u8; FRAME_BUDGET];
        let frame = encode(msg, &mut buf).expect("decoded message re-encodes");
        let mut again = Decoder::<M, RAW>::new();
        assert_eq!(again.feed(frame).next().as_ref(), Some(event));
    }
}

fn stream<M: Msg, const RAW: usize>(data: &[u8], split: usize) {
    let mut parts = Decoder::<M, RAW>::new();
    let mut whole = Decoder::<M, RAW>::new();
    {
        let mut whole_events = whole.feed(data);
        for part in [&data[..split], &data[split..]] {
            for event in parts.feed(part) {
                assert_eq!(whole_events.next().as_ref(), Some(&event));
                check_reencodes::<M, RAW>(&event);
            }
        }
        assert!(whole_events.next().is_none());
    }
    let s = parts.stats();
    assert_eq!(s, whole.stats());
    assert_eq!(s.bytes, data.len() as u64);
    assert_eq!(
        s.corrupt,
        s.cobs_errors + s.crc_errors + s.postcard_errors + s.overlong
    );
}

/// COBS of `raw` (plain textbook encoder) plus the delimiter into `out`; the frame's length.
fn cobs_frame(raw: &[u8], out: &mut [u8]) -> usize {
    let mut code_at = 0;
    let mut pos = 1;
    let mut code = 1u8;
    for &b in raw {
        if b != 0 {
            out[pos] = b;
            pos += 1;
            code += 1;
        }
        if b == 0 || code == 0xFF {
            out[code_at] = code;
            code_at = pos;
            pos += 1;
            code = 1;
        }
    }
    out[code_at] = code;
    out[pos] = 0;
    pos + 1
}

fn payload<M: Msg, const RAW: usize>(payload: &[u8]) {
    // Longer bodies cannot be framed in the buffers below; they are the overlong case, which
    // mode 0/1 covers with arbitrary bytes.
    const MAX_BODY: usize = 600;
    let body_len = payload.len() + 4;
    if body_len > MAX_BODY {
        return;
    }
    let mut body = [0u8; MAX_BODY];
    body[..payload.len()].copy_from_slice(payload);
    body[payload.len()..body_len].copy_from_slice(&rig_protocol::crc::crc32(payload).to_le_bytes());
    let mut wire = [0u8; MAX_BODY + MAX_BODY / 254 + 2];
    let n = cobs_frame(&body[..body_len], &mut wire);

    let mut decoder = Decoder::<M, RAW>::new();
    let mut events = decoder.feed(&wire[..n]);
    let event = events.next().expect("a delimited frame yields an event");
    if body_len > RAW {
        assert_eq!(
            event,
            Decoded::CorruptFrame {
                reason: CorruptReason::Overlong
            }
        );
        return;
    }
    assert!(events.next().is_none(), "one frame, one event");
    match &event {
        Decoded::Frame(_) => check_reencodes::<M, RAW>(&event),
        Decoded::CorruptFrame { reason } => assert_eq!(*reason, CorruptReason::Postcard),
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&control, rest)) = data.split_first() else {
        return;
    };
    let split = (control >> 2) as usize * rest.len() / 64;
    match control & 3 {
        0 => stream::<DeviceMsg, DEVICE_RAW_MAX>(rest, split),
        1 => stream::<HostMsg, HOST_RAW_MAX>(rest, split),
        2 => payload::<DeviceMsg, DEVICE_RAW_MAX>(rest),
        _ => payload::<HostMsg, HOST_RAW_MAX>(rest),
    }
});
