//! Host decoder throughput over a realistic recording stream: 10 kHz potentiometer in full
//! batches, three inclinometers at 100 Hz (two readings per batch), and a status.

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use rig_protocol::{
    encode_device, Decoded, DeviceDecoder, DeviceMsg, PotBatch, Status, TiltReading,
    DEVICE_FRAME_MAX, POT_BATCH_MAX,
};

/// One second of board output, plus the number of frames in it.
fn one_second_stream() -> (Vec<u8>, u64) {
    let mut wire = Vec::new();
    let mut frames = 0u64;
    let mut buf = [0u8; DEVICE_FRAME_MAX];
    let mut push = |msg: &DeviceMsg, wire: &mut Vec<u8>| {
        wire.extend_from_slice(encode_device(msg, &mut buf).expect("fits"));
    };
    let batches = 10_000 / POT_BATCH_MAX as u64;
    for seq in 0..batches {
        let t0_us = seq * POT_BATCH_MAX as u64 * 100;
        let batch = DeviceMsg::Pot(PotBatch {
            seq: seq as u32,
            t0_us,
            period_us: 100,
            samples: (0..POT_BATCH_MAX)
                .map(|i| (2000 + ((seq as usize * 7 + i * 13) % 97)) as u16)
                .collect(),
        });
        push(&batch, &mut wire);
        frames += 1;
        // ~2 tilt readings per batch (300/s vs 156 batches/s).
        for k in 0..2u64 {
            let tilt = DeviceMsg::Tilt(TiltReading {
                sensor: ((seq * 2 + k) % 3) as u8,
                t_us: t0_us + k * 3333,
                x: -120 + (seq % 11) as i16,
                y: 35,
                z: 5999,
                temp: 5580,
                status: 0,
            });
            push(&tilt, &mut wire);
            frames += 1;
        }
    }
    push(&DeviceMsg::Status(Status::default()), &mut wire);
    frames += 1;
    (wire, frames)
}

fn decode(c: &mut Criterion) {
    let (wire, frames) = one_second_stream();
    let mut group = c.benchmark_group("decode");
    group.throughput(Throughput::Bytes(wire.len() as u64));
    group.bench_function(format!("one_second_stream_{frames}_frames"), |b| {
        b.iter(|| {
            let mut decoder = DeviceDecoder::new();
            let mut good = 0u64;
            for event in decoder.feed(black_box(&wire)) {
                if let Decoded::Frame(msg) = event {
                    black_box(&msg);
                    good += 1;
                }
            }
            assert_eq!(good, frames);
            good
        })
    });
    // The same stream read in 64-byte chunks, as from a serial port.
    group.bench_function("one_second_stream_64_byte_reads", |b| {
        b.iter(|| {
            let mut decoder = DeviceDecoder::new();
            for chunk in wire.chunks(64) {
                for event in decoder.feed(black_box(chunk)) {
                    black_box(&event);
                }
            }
            decoder.stats().frames
        })
    });
    group.finish();
}

criterion_group!(benches, decode);
criterion_main!(benches);
