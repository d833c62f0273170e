//! Encode cost of the two hot frames: a full potentiometer batch and a tilt reading.

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use rig_protocol::{
    encode_device, DeviceMsg, PotBatch, TiltReading, DEVICE_FRAME_MAX, POT_BATCH_MAX,
};

fn full_batch() -> DeviceMsg {
    DeviceMsg::Pot(PotBatch {
        seq: 123_456,
        t0_us: 3_600_000_000,
        period_us: 100,
        samples: (0..POT_BATCH_MAX)
            .map(|i| (2048 + 17 * i) as u16 % 4096)
            .collect(),
    })
}

fn tilt() -> DeviceMsg {
    DeviceMsg::Tilt(TiltReading {
        sensor: 1,
        t_us: 3_600_000_123,
        x: -120,
        y: 35,
        z: 5999,
        temp: 5580,
        status: 0,
    })
}

fn encode(c: &mut Criterion) {
    let mut group = c.benchmark_group("encode");
    for (name, msg) in [("pot_batch_full", full_batch()), ("tilt_reading", tilt())] {
        let mut buf = [0u8; DEVICE_FRAME_MAX];
        let len = encode_device(&msg, &mut buf).expect("fits").len();
        group.throughput(Throughput::Bytes(len as u64));
        group.bench_function(name, |b| {
            b.iter(|| {
                let frame = encode_device(black_box(&msg), &mut buf).expect("fits");
                black_box(frame.len())
            })
        });
    }
    group.finish();
}

criterion_group!(benches, encode);
criterion_main!(benches);
