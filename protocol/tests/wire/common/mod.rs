//! Shared fixtures of the protocol's integration tests.
#![allow(dead_code)]

use rig_protocol::*;

/// One message of every `DeviceMsg` variant (and every `CommandKind` / `NackReason`), with
/// field values chosen to exercise multi-byte varints, zeros (COBS) and negative numbers.
pub fn device_samples() -> Vec<(&'static str, DeviceMsg)> {
    vec![
        (
            "hello",
            DeviceMsg::Hello(Hello {
                protocol_version: PROTOCOL_VERSION,
                firmware_version: [0, 3, 12],
                board_id: [
                    0x10, 0x20, 0x30, 0x40, 0x50, 0x60, 0x70, 0x80, 0x90, 0xA0, 0xB0, 0x00,
                ],
                schema_hash: 0xDEAD_BEEF,
                tilt_sensors: 3,
            }),
        ),
        (
            "pot",
            DeviceMsg::Pot(PotBatch {
                seq: 300,
                t0_us: 1_234_567_890,
                period_us: 1000,
                samples: heapless::Vec::from_slice(&[0, 1, 127, 128, 2048, 4095]).unwrap(),
            }),
        ),
        (
            "pot_empty",
            DeviceMsg::Pot(PotBatch {
                seq: 0,
                t0_us: 0,
                period_us: 100,
                samples: heapless::Vec::new(),
            }),
        ),
        (
            "tilt",
            DeviceMsg::Tilt(TiltReading {
                sensor: 2,
                t_us: 987_654,
                x: -120,
                y: 35,
                z: 5999,
                temp: 5580,
                status: 1,
            }),
        ),
        (
            "status",
            DeviceMsg::Status(Status {
                uptime_us: 60_000_000,
                dropped_samples: 64,
                dropped_frames: 1,
                overruns: 0,
                sensor_errors: 2,
                rx_errors: 3,
            }),
        ),
        ("pong", DeviceMsg::Pong { nonce: 0x0102_0304 }),
        ("ack_start", DeviceMsg::Ack(CommandKind::Start)),
        ("ack_stop", DeviceMsg::Ack(CommandKind::Stop)),
        ("ack_ping", DeviceMsg::Ack(CommandKind::Ping)),
        ("ack_getinfo", DeviceMsg::Ack(CommandKind::GetInfo)),
        (
            "nack_rate",
            DeviceMsg::Nack {
                command: CommandKind::Start,
                reason: NackReason::RateOutOfRange,
            },
        ),
        (
            "nack_running",
            DeviceMsg::Nack {
                command: CommandKind::Start,
                reason: NackReason::AlreadyRunning,
            },
        ),
        (
            "nack_not_running",
            DeviceMsg::Nack {
                command: CommandKind::Stop,
                reason: NackReason::NotRunning,
            },
        ),
    ]
}

/// One message of every `HostMsg` variant.
pub fn host_samples() -> Vec<(&'static str, HostMsg)> {
    vec![
        (
            "start",
            HostMsg::Start {
                pot_rate_hz: 1000,
                tilt_rate_hz: 100,
            },
        ),
        ("stop", HostMsg::Stop),
        ("ping", HostMsg::Ping { nonce: 42 }),
        ("getinfo", HostMsg::GetInfo),
    ]
}

/// The largest `DeviceMsg`: a full batch with every field at its maximum.
pub fn max_pot_batch() -> DeviceMsg {
    DeviceMsg::Pot(PotBatch {
        seq: u32::MAX,
        t0_us: u64::MAX,
        period_us: u32::MAX,
        samples: heapless::Vec::from_slice(&[u16::MAX; POT_BATCH_MAX]).unwrap(),
    })
}

/// Encodes a board message into a fresh `Vec`.
pub fn frame_device(msg: &DeviceMsg) -> Vec<u8> {
    let mut buf = [0u8; DEVICE_FRAME_MAX];
    encode_device(msg, &mut buf).expect("fits").to_vec()
}

/// Encodes a host message into a fresh `Vec`.
pub fn frame_host(msg: &HostMsg) -> Vec<u8> {
    let mut buf = [0u8; HOST_FRAME_MAX];
    encode_host(msg, &mut buf).expect("fits").to_vec()
}

/// Lower-case hex without separators.
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// xorshift64* -- a tiny deterministic generator for property-style tests.
pub struct XorShift(u64);

impl XorShift {
    /// Seeded generator (a zero seed is replaced, xorshift needs a non-zero state).
    pub fn new(seed: u64) -> Self {
        Self(if seed == 0 {
            0x9E37_79B9_7F4A_7C15
        } else {
            seed
        })
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform-ish in `0..n` (n > 0).
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n
    }

    /// A random byte.
    pub fn byte(&mut self) -> u8 {
        (self.next_u64() >> 56) as u8
    }
}
