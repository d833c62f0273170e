//! The messages. Counters in [`Status`] count since the last `Start` (see
//! [`crate::device::Board`]). Changing any of these changes the wire format: bump [`PROTOCOL_VERSION`] and
//! update the frozen byte vectors in the tests on purpose.

use postcard::experimental::max_size::MaxSize;
use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

/// Version of the wire format; the board sends it in [`Hello`] and the host refuses a mismatch.
pub const PROTOCOL_VERSION: u16 = 1;

/// Most potentiometer samples in one [`PotBatch`].
pub const POT_BATCH_MAX: usize = 64;

/// Board -> host.
#[derive(Serialize, Deserialize, Schema, MaxSize, Debug, Clone, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DeviceMsg {
    /// Sent at power-up and in answer to [`HostMsg::GetInfo`].
    Hello(Hello),
    /// Potentiometer samples.
    Pot(PotBatch),
    /// One inclinometer reading.
    Tilt(TiltReading),
    /// Health counters.
    Status(Status),
    /// Answer to [`HostMsg::Ping`].
    Pong {
        /// The ping's nonce, echoed.
        nonce: u32,
    },
    /// Acknowledges a command (echoes its kind).
    Ack(CommandKind),
    /// A command was refused (for example a rate out of range).
    Nack {
        /// The refused command.
        command: CommandKind,
        /// Why.
        reason: NackReason,
    },
}

/// Host -> board.
#[derive(Serialize, Deserialize, Schema, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HostMsg {
    /// Start sampling: potentiometer at `pot_rate_hz` (100..=10000), each inclinometer at
    /// `tilt_rate_hz` (1..=1000).
    Start {
        /// Potentiometer sample rate, Hz.
        pot_rate_hz: u32,
        /// Read rate of each inclinometer, Hz.
        tilt_rate_hz: u32,
    },
    /// Stop sampling; the board flushes its data, sends a `Status`, then `Ack(Stop)`.
    Stop,
    /// Liveness check; answered by `Pong` with the same nonce.
    Ping {
        /// Any value, echoed.
        nonce: u32,
    },
    /// Ask for the board's `Hello`.
    GetInfo,
}

#[derive(Serialize, Deserialize, Schema, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
/// Which command an `Ack`/`Nack` answers.
pub enum CommandKind {
    /// [`HostMsg::Start`].
    Start,
    /// [`HostMsg::Stop`].
    Stop,
    /// [`HostMsg::Ping`].
    Ping,
    /// [`HostMsg::GetInfo`].
    GetInfo,
}

#[derive(Serialize, Deserialize, Schema, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
/// Why a command was refused.
pub enum NackReason {
    /// A rate outside pot 100..=10000 Hz or tilt 1..=1000 Hz.
    RateOutOfRange,
    /// `Start` while already running (send `Stop` first).
    AlreadyRunning,
    /// `Stop` while not running.
    NotRunning,
}

/// First message after power-up and the answer to `GetInfo`.
#[derive(Serialize, Deserialize, Schema, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Hello {
    /// The board's [`PROTOCOL_VERSION`].
    pub protocol_version: u16,
    /// major, minor, patch
    pub firmware_version: [u8; 3],
    /// The MCU's unique id (96 bits on STM32).
    pub board_id: [u8; 12],
    /// Hash of the message schema: [`crate::SCHEMA_HASH`].
    pub schema_hash: u32,
    /// Number of inclinometers detected.
    pub tilt_sensors: u8,
}

/// A run of potentiometer samples taken at a constant period.
#[derive(Serialize, Deserialize, Schema, Debug, Clone, PartialEq)]
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
#[derive(Serialize, Deserialize, Schema, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TiltReading {
    /// 0-based chip-select index.
    pub sensor: u8,
    /// Board time of the reading, microseconds since boot.
    pub t_us: u64,
    /// Raw acceleration counts, x axis (SCL3300 mode 1: 6000 counts per g).
    pub x: i16,
    /// Raw acceleration counts, y axis.
    pub y: i16,
    /// Raw acceleration counts, z axis.
    pub z: i16,
    /// Raw temperature counts (SCL3300: `T_degC = -273 + raw / 18.9`).
    pub temp: i16,
    /// Sensor status: the return-status bits of the last SPI frame (0 = normal).
    pub status: u8,
}

/// Health counters, sent periodically while running and after `Stop`.
#[derive(Serialize, Deserialize, Schema, MaxSize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// Board time when the status was made, microseconds since boot.
    pub uptime_us: u64,
    /// Potentiometer samples lost because their batch could not be sent.
    pub dropped_samples: u32,
    /// Whole frames dropped because the link was busy.
    pub dropped_frames: u32,
    /// Sampler overruns: ADC/DMA overruns reported by the firmware, plus inclinometer read
    /// slots skipped because the board polled its schedule late.
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
