//! Wire protocol of the calibration rig's DAQ board.
//!
//! Every type that crosses the link between the board (`firmware/`) and the host (`rigctl`) lives
//! here and only here. `no_std` by default; the `use-std` feature adds what the host needs.
//!
//! - [`messages`]: the messages themselves (device -> host and host -> device).
//! - [`frame`]: postcard + CRC + COBS framing and the streaming decoder.
//! - [`device`]: the board's portable logic (batching, scheduling, counters), shared by the
//!   firmware and the host-side virtual board.
#![cfg_attr(not(feature = "use-std"), no_std)]
#![forbid(unsafe_code)]

pub mod messages;

pub use messages::*;
