//! Wire protocol of the calibration rig's DAQ board.
//!
//! Every type that crosses the link between the board (`firmware/`) and the host (`rigctl`) lives
//! here and only here. `no_std` by default (no allocation anywhere); `use-std` is what the host
//! enables; `defmt` derives `defmt::Format` on every public type for the firmware's logs.
//!
//! - [`messages`]: the messages themselves (board -> host [`DeviceMsg`], host -> board
//!   [`HostMsg`]).
//! - [`frame`]: framing and the streaming decoder.
//! - [`schema`]: the schema hash carried in [`Hello`] and the host's check of it.
//! - [`crc`]: CRC-32/ISO-HDLC used by the framing.
//! - [`device`]: the board's portable logic (batching, tilt scheduling, commands, counters,
//!   outbound queue), shared by the firmware and the host-side virtual board.
//!
//! # Framing (stable API)
//!
//! `frame = COBS(postcard(msg) ++ crc32_le) ++ 0x00` (details and size arithmetic in
//! [`frame`]).
//!
//! | item | use |
//! | --- | --- |
//! | [`encode_device`]`(&DeviceMsg, &mut [u8]) -> Result<&[u8], FrameError>` | board: one frame into a `[u8; DEVICE_FRAME_MAX]` |
//! | [`encode_host`]`(&HostMsg, &mut [u8]) -> Result<&[u8], FrameError>` | host: one frame into a `[u8; HOST_FRAME_MAX]` |
//! | [`DEVICE_FRAME_MAX`], [`HOST_FRAME_MAX`] | largest frame, delimiter included (220 and small) |
//! | [`DeviceDecoder`] / [`HostDecoder`] | streaming decoders (host side / board side) |
//! | [`Decoder::push`]`(u8) -> Option<Decoded<M>>` | `None` = need more bytes |
//! | [`Decoder::feed`]`(&[u8]) -> impl Iterator<Item = Decoded<M>>` | slice at a time |
//! | [`Decoded::Frame`]`(M)`, [`Decoded::CorruptFrame`]` { reason }` | events; reasons `Cobs`, `Crc`, `Postcard`, `Overlong` |
//! | [`Decoder::stats`]`() -> DecoderStats` | `bytes`, `frames`, `corrupt`, and per-reason counters (`crc_errors`, ...) |
//! | [`SCHEMA_HASH`], [`check_hello`]`(&Hello) -> Result<(), HelloMismatch>` | host refuses a board built from other messages |
//!
//! ```
//! use rig_protocol::{encode_device, DeviceDecoder, Decoded, DeviceMsg, DEVICE_FRAME_MAX};
//!
//! let mut buf = [0u8; DEVICE_FRAME_MAX];
//! let frame = encode_device(&DeviceMsg::Pong { nonce: 7 }, &mut buf).unwrap();
//! assert_eq!(frame.last(), Some(&0x00));
//!
//! let mut decoder = DeviceDecoder::new();
//! let mut events = decoder.feed(frame);
//! assert_eq!(events.next(), Some(Decoded::Frame(DeviceMsg::Pong { nonce: 7 })));
//! assert_eq!(events.next(), None); // need more bytes
//! assert_eq!(decoder.stats().frames, 1);
//! ```
#![cfg_attr(not(feature = "use-std"), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod cobs;
pub mod crc;
pub mod device;
pub mod frame;
pub mod messages;
pub mod schema;

pub use frame::{
    encode, encode_device, encode_host, CorruptReason, Decoded, Decoder, DecoderStats,
    DeviceDecoder, FrameError, HostDecoder, DELIMITER, DEVICE_FRAME_MAX, DEVICE_RAW_MAX,
    FRAME_BUDGET, HOST_FRAME_MAX, HOST_RAW_MAX,
};
pub use messages::*;
pub use schema::{check_hello, schema_hash, HelloMismatch, SCHEMA_HASH, SCHEMA_NAME};
