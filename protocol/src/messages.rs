//! The messages. Changing any of these changes the wire format: bump [`PROTOCOL_VERSION`] and
//! update the frozen byte vectors in the tests on purpose.

use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

/// Version of the wire format; the board sends it in [`Hello`] and the host refuses a mismatch.
pub const PROTOCOL_VERSION: u16 = 1;

/// Most potentiometer samples in one [`PotBatch`].
pub const POT_BATCH_MAX: usize = 64;

/// Board -> host.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DeviceMsg {
    Hello(Hello),
    Pot(PotBatch),
    Tilt(TiltReading),
    Status(Status),
    Pong { nonce: u32 },
    /// Acknowledges a command (echoes its kind).
    Ack(CommandKind),
    /// A command was refused (for example a rate out of range).
    Nack { command: CommandKind, reason: NackReason },
}

/// Host -> board.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HostMsg {
    Start { pot_rate_hz: u32, tilt_rate_hz: u32 },
    Stop,
    Ping { nonce: u32 },
    GetInfo,
}

#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CommandKind {
    Start,
    Stop,
    Ping,
    GetInfo,
}

#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NackReason {
    RateOutOfRange,
    AlreadyRunning,
    NotRunning,
}

/// First message after power-up and the answer to `GetInfo`.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Hello {
    pub protocol_version: u16,
    /// major, minor, patch
    pub firmware_version: [u8; 3],
    /// The MCU's unique id (96 bits on STM32).
    pub board_id: [u8; 12],
    /// Hash of the message schema; see `schema_hash()`.
    pub schema_hash: u32,
    /// Number of inclinometers detected.
    pub tilt_sensors: u8,
}

/// A run of potentiometer samples taken at a constant period.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PotBatch {
    /// Counts batches since `Start`; a gap means batches were dropped.
    pub seq: u32,
    /// Board time of the first sample, microseconds since boot.
    pub t0_us: u64,
    /// Time between samples, microseconds.
    pub period_us: u32,
    /// Raw 12-bit ADC counts.
    pub samples: heapless::Vec<u16, POT_BATCH_MAX>,
}

/// One reading of one inclinometer.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TiltReading {
    /// 0-based chip-select index.
    pub sensor: u8,
    /// Board time of the reading, microseconds since boot.
    pub t_us: u64,
    /// Raw acceleration counts (SCL3300 mode 1: 6000 counts per g).
    pub x: i16,
    pub y: i16,
    pub z: i16,
    /// Raw temperature counts (SCL3300: T[degC] = -273 + raw / 18.9).
    pub temp: i16,
    /// Sensor status: the return-status bits of the last SPI frame (0 = normal).
    pub status: u8,
}

/// Health counters, sent periodically while running and after `Stop`.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    pub uptime_us: u64,
    /// Potentiometer samples lost because their batch could not be sent.
    pub dropped_samples: u32,
    /// Whole frames dropped because the link was busy.
    pub dropped_frames: u32,
    /// ADC/DMA overruns (the sampler fell behind).
    pub overruns: u32,
    /// Inclinometer read failures (CRC or status errors).
    pub sensor_errors: u32,
    /// Host frames that failed to decode.
    pub rx_errors: u32,
}

// `heapless` 0.9 has no `MaxSize`; the bound is written out: each field's varint worst case.
impl MaxSize for PotBatch {
    const POSTCARD_MAX_SIZE: usize = u32::POSTCARD_MAX_SIZE
        + u64::POSTCARD_MAX_SIZE
        + u32::POSTCARD_MAX_SIZE
        + varint_len(POT_BATCH_MAX)
        + POT_BATCH_MAX * u16::POSTCARD_MAX_SIZE;
}

/// Bytes of the varint encoding of `n`.
const fn varint_len(mut n: usize) -> usize {
    let mut len = 1;
    while n >= 0x80 {
        n >>= 7;
        len += 1;
    }
    len
}
