//! What a recording session is asked to do ([`RecordConfig`], its time limits [`Timing`]) and
//! how it fails ([`RecordError`]).

use crate::daq::link::LinkError;
use crate::daq::recording::RecordingError;
use crate::daq::tally::Tally;
use rig_protocol::{HelloMismatch, NackReason};
use std::path::PathBuf;
use std::time::Duration;

/// Time limits of a session.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timing {
    /// Longest single read from the port (how often the loop checks `stop` and the clock).
    pub read_timeout: Duration,
    /// Wait for `Hello` after each `GetInfo`, and for `Ack(Start)` after each `Start`.
    pub hello_timeout: Duration,
    /// Tries of `GetInfo` and of `Start`.
    pub attempts: u32,
    /// A running board silent this long is lost.
    pub silence_timeout: Duration,
    /// Wait for `Ack(Stop)` after `Stop`.
    pub drain_timeout: Duration,
    /// Interval between progress callbacks.
    pub progress_interval: Duration,
}

impl Default for Timing {
    fn default() -> Self {
        Self {
            read_timeout: Duration::from_millis(20),
            hello_timeout: Duration::from_secs(1),
            attempts: 3,
            silence_timeout: Duration::from_secs(3),
            drain_timeout: Duration::from_secs(2),
            progress_interval: Duration::from_millis(200),
        }
    }
}

/// What to record.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordConfig {
    /// Serial port or pseudo-terminal.
    pub port: PathBuf,
    /// Recording file to create.
    pub out: PathBuf,
    /// Stop after this long (from `Start`); `None`: until `stop` is set.
    pub duration: Option<Duration>,
    /// Potentiometer rate asked for in `Start`, Hz.
    pub pot_rate_hz: u32,
    /// Inclinometer rate asked for in `Start`, Hz.
    pub tilt_rate_hz: u32,
    /// Replace an existing `out`.
    pub overwrite: bool,
    pub timing: Timing,
}

/// How a session failed.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    #[error(transparent)]
    Link(#[from] LinkError),
    #[error(transparent)]
    Recording(#[from] RecordingError),
    #[error("no Hello from {port} after {attempts} GetInfo requests ({timeout_ms} ms each): is the board connected and running the rig firmware?")]
    NoHello {
        port: PathBuf,
        attempts: u32,
        timeout_ms: u128,
    },
    #[error("refusing the board on {port}: {mismatch}")]
    Mismatch {
        port: PathBuf,
        mismatch: HelloMismatch,
    },
    #[error("the board on {port} refused Start (pot {pot_rate_hz} Hz, tilt {tilt_rate_hz} Hz): {reason:?}")]
    Refused {
        port: PathBuf,
        pot_rate_hz: u32,
        tilt_rate_hz: u32,
        reason: NackReason,
    },
    #[error("the board on {port} did not acknowledge Start after {attempts} tries")]
    NoAck { port: PathBuf, attempts: u32 },
    #[error("interrupted before the recording started")]
    Interrupted,
    #[error("{}: {summary}; {} keeps the {} good frames", .port.display(), .out.display(), .tally.frames)]
    OutOfRange {
        port: PathBuf,
        out: PathBuf,
        summary: String,
        tally: Box<Tally>,
    },
    #[error("the run on {port} ended before the board sent a frame of data; {} is as it was before", .out.display())]
    NoData { port: PathBuf, out: PathBuf },
    #[error("device on {port} lost ({reason}); {}", kept(out, *recorded, tally.frames))]
    DeviceLost {
        port: PathBuf,
        out: PathBuf,
        reason: String,
        /// Whether the recording had been created.
        recorded: bool,
        tally: Box<Tally>,
    },
}

fn kept(out: &std::path::Path, recorded: bool, frames: u64) -> String {
    if recorded {
        format!(
            "{} keeps the {frames} complete frames received",
            out.display()
        )
    } else {
        format!(
            "nothing was recorded; {} is as it was before",
            out.display()
        )
    }
}

impl RecordError {
    /// The counts of a session that failed after recording started.
    pub fn tally(&self) -> Option<&Tally> {
        match self {
            Self::DeviceLost { tally, .. } | Self::OutOfRange { tally, .. } => Some(tally),
            _ => None,
        }
    }
}

impl crate::error::Classify for RecordError {
    fn kind(&self) -> crate::error::ErrorKind {
        use crate::error::ErrorKind;
        match self {
            Self::Link(e) => e.kind(),
            Self::Recording(e) => e.kind(),
            Self::Refused {
                reason: NackReason::RateOutOfRange,
                ..
            } => ErrorKind::BadInput,
            _ => ErrorKind::Failure,
        }
    }
}
