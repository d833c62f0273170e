//! Property-style tests over many seeded random byte streams: the decoder never panics, its
//! counters stay consistent, and it never yields a message that was not sent.

use crate::common;

use common::{frame_device, XorShift};
use rig_protocol::*;

/// Pure noise, with a bias towards zeros so that many short "frames" occur.
#[test]
fn random_noise_never_panics_and_counters_add_up() {
    for seed in 1..=200u64 {
        let mut rng = XorShift::new(seed);
        let len = rng.below(4096) as usize;
        let zero_every = 1 + rng.below(300);
        let bytes: Vec<u8> = (0..len)
            .map(|_| {
                if rng.below(zero_every) == 0 {
                    0
                } else {
                    rng.byte()
                }
            })
            .collect();
        let mut decoder = DeviceDecoder::new();
        let mut frames = 0u64;
        let mut corrupt = 0u64;
        // Feed in random-sized chunks.
        let mut rest = &bytes[..];
        while !rest.is_empty() {
            let n = 1 + rng.below(rest.len() as u64) as usize;
            for event in decoder.feed(&rest[..n]) {
                match event {
                    Decoded::Frame(_) => frames += 1,
                    Decoded::CorruptFrame { .. } => corrupt += 1,
                }
            }
            rest = &rest[n..];
        }
        let s = decoder.stats();
        assert_eq!(s.bytes, len as u64, "seed {seed}");
        assert_eq!((s.frames, s.corrupt), (frames, corrupt), "seed {seed}");
        assert_eq!(
            s.corrupt,
            s.cobs_errors + s.crc_errors + s.postcard_errors + s.overlong,
            "seed {seed}"
        );
    }
}

fn random_msg(rng: &mut XorShift) -> DeviceMsg {
    match rng.below(4) {
        0 => DeviceMsg::Pot(PotBatch {
            seq: rng.next_u64() as u32,
            t0_us: rng.next_u64() >> rng.below(64),
            period_us: 100 + rng.below(10_000) as u32,
            samples: (0..rng.below(POT_BATCH_MAX as u64 + 1))
                .map(|_| rng.below(4096) as u16)
                .collect(),
        }),
        1 => DeviceMsg::Tilt(TiltReading {
            sensor: rng.byte(),
            t_us: rng.next_u64() >> 20,
            x: rng.next_u64() as i16,
            y: rng.next_u64() as i16,
            z: rng.next_u64() as i16,
            temp: rng.next_u64() as i16,
            status: rng.byte() & 3,
        }),
        2 => DeviceMsg::Pong {
            nonce: rng.next_u64() as u32,
        },
        _ => common::device_samples()[rng.below(13) as usize].1.clone(),
    }
}

/// A realistic stream with corruption injected inside frames (byte flips, drops, inserted
/// garbage; delimiters left alone): exactly the intact frames come out, in order, and every
/// damaged frame is reported corrupt.
#[test]
fn corrupted_streams_lose_exactly_the_damaged_frames() {
    for seed in 1..=100u64 {
        let mut rng = XorShift::new(seed * 7919);
        let mut wire = Vec::new();
        let mut intact = Vec::new();
        let mut damaged = 0u64;
        for _ in 0..200 {
            let msg = random_msg(&mut rng);
            let mut frame = frame_device(&msg);
            // Positions before the delimiter.
            let body = frame.len() as u64 - 1;
            match rng.below(10) {
                0 => {
                    let i = rng.below(body) as usize;
                    frame[i] ^= 1 + rng.below(255) as u8;
                }
                1 => {
                    frame.remove(rng.below(body) as usize);
                }
                2 => {
                    let i = rng.below(body) as usize;
                    let junk: Vec<u8> = (0..1 + rng.below(20)).map(|_| rng.byte()).collect();
                    frame.splice(i..i, junk);
                }
                _ => {
                    intact.push(msg);
                    wire.extend(frame);
                    continue;
                }
            }
            damaged += 1;
            wire.extend(frame);
        }
        let mut decoder = DeviceDecoder::new();
        let decoded: Vec<DeviceMsg> = decoder
            .feed(&wire)
            .filter_map(|e| match e {
                Decoded::Frame(m) => Some(m),
                Decoded::CorruptFrame { .. } => None,
            })
            .collect();
        assert_eq!(decoded, intact, "seed {seed}");
        // A damaged frame may split in several corrupt pieces (a flip to 0x00, junk with
        // zeros), never fewer than one.
        assert!(decoder.stats().corrupt >= damaged, "seed {seed}");
    }
}
