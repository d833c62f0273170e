//! Framing: `frame = COBS(postcard(msg) ++ crc32_le(postcard(msg))) ++ 0x00`.
//!
//! - postcard: the message's compact serde encoding (varints, enum tags as varints).
//! - CRC: CRC-32/ISO-HDLC of the postcard bytes, appended little-endian ([`crate::crc`]).
//! - COBS: removes every 0x00 from the frame so that 0x00 can delimit frames; a receiver that
//!   starts mid-stream or loses bytes resynchronises at the next 0x00.
//!
//! # Sizes, derived at compile time
//!
//! `RAW = M::POSTCARD_MAX_SIZE + CRC_LEN`, `FRAME = RAW + 1 + RAW / 254 + 1` (COBS code bytes,
//! delimiter). For [`DeviceMsg`] the largest message is a full [`crate::PotBatch`]:
//!
//! ```text
//! enum tag 1 + seq u32 5 + t0_us u64 10 + period_us u32 5 + len varint 1 + 64 x u16 3 = 214
//! RAW = 214 + 4 = 218;  FRAME = 218 + 1 + 0 + 1 = 220 <= FRAME_BUDGET = 256
//! ```
//!
//! (worst-case varints; real 12-bit samples take 2 bytes, so a real full batch is ~155 bytes.)
//! [`FRAME_BUDGET`] is the board's transmit unit: 256 bytes = four full-speed USB packets, and
//! the unit the outbound queue is sized in. The `const` assertions below fail the build if a
//! message change breaks the budget. A larger `POT_BATCH_MAX` than 64 would fit (75), but 64
//! keeps a batch's latency at 6.4 ms at the 10 kHz ceiling and gives a round number per batch.

use core::fmt;
use core::marker::PhantomData;

use postcard::experimental::max_size::MaxSize;
use postcard::ser_flavors::Flavor;
use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::cobs;
use crate::crc::{Crc32, CRC_LEN};
use crate::messages::{DeviceMsg, HostMsg};

/// Byte that ends every frame (and never occurs inside one).
pub const DELIMITER: u8 = 0x00;

/// Upper bound the board's transmit path is designed for; every frame fits it (checked at
/// compile time).
pub const FRAME_BUDGET: usize = 256;

/// Largest un-stuffed frame body of a [`DeviceMsg`]: postcard bytes + CRC.
pub const DEVICE_RAW_MAX: usize = DeviceMsg::POSTCARD_MAX_SIZE + CRC_LEN;
/// Largest wire frame of a [`DeviceMsg`], delimiter included. Size encode buffers with it.
pub const DEVICE_FRAME_MAX: usize = cobs::max_encoded_len(DEVICE_RAW_MAX) + 1;
/// Largest un-stuffed frame body of a [`HostMsg`]: postcard bytes + CRC.
pub const HOST_RAW_MAX: usize = HostMsg::POSTCARD_MAX_SIZE + CRC_LEN;
/// Largest wire frame of a [`HostMsg`], delimiter included. Size encode buffers with it.
pub const HOST_FRAME_MAX: usize = cobs::max_encoded_len(HOST_RAW_MAX) + 1;

const _: () = assert!(DEVICE_FRAME_MAX <= FRAME_BUDGET);
const _: () = assert!(HOST_FRAME_MAX <= FRAME_BUDGET);
// The arithmetic in the module documentation, checked.
const _: () = assert!(DEVICE_RAW_MAX == 218 && DEVICE_FRAME_MAX == 220);

/// Why a message could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrameError {
    /// The output buffer is shorter than the frame; size it with `DEVICE_FRAME_MAX` /
    /// `HOST_FRAME_MAX`.
    BufferTooSmall {
        /// Length of the buffer that was given.
        capacity: usize,
    },
    /// postcard refused the value (cannot happen for this crate's message types).
    Serialize,
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BufferTooSmall { capacity } => {
                write!(f, "frame does not fit the {capacity}-byte buffer")
            }
            Self::Serialize => f.write_str("message could not be serialized"),
        }
    }
}

impl core::error::Error for FrameError {}

/// postcard output flavor: CRC over the serialized bytes, COBS-stuffed straight into the frame.
struct CrcCobs<'a> {
    crc: Crc32,
    cobs: cobs::Encoder<'a>,
}

impl<'a> Flavor for CrcCobs<'a> {
    type Output = &'a [u8];

    #[inline]
    fn try_push(&mut self, byte: u8) -> postcard::Result<()> {
        self.crc = self.crc.update_byte(byte);
        self.cobs
            .push(byte)
            .map_err(|_| postcard::Error::SerializeBufferFull)
    }

    fn finalize(mut self) -> postcard::Result<&'a [u8]> {
        for byte in self.crc.finish().to_le_bytes() {
            self.cobs
                .push(byte)
                .map_err(|_| postcard::Error::SerializeBufferFull)?;
        }
        self.cobs
            .finish()
            .map_err(|_| postcard::Error::SerializeBufferFull)
    }
}

/// Encodes any serializable message as one frame into `buf`; returns the frame (delimiter
/// included), a prefix of `buf`.
pub fn encode<'b, M: Serialize + ?Sized>(
    msg: &M,
    buf: &'b mut [u8],
) -> Result<&'b [u8], FrameError> {
    let capacity = buf.len();
    let cobs = cobs::Encoder::new(buf).map_err(|_| FrameError::BufferTooSmall { capacity })?;
    let flavor = CrcCobs {
        crc: Crc32::new(),
        cobs,
    };
    postcard::serialize_with_flavor(msg, flavor).map_err(|e| match e {
        postcard::Error::SerializeBufferFull => FrameError::BufferTooSmall { capacity },
        _ => FrameError::Serialize,
    })
}

/// Encodes a board -> host message. A `[u8; DEVICE_FRAME_MAX]` buffer always suffices.
pub fn encode_device<'b>(msg: &DeviceMsg, buf: &'b mut [u8]) -> Result<&'b [u8], FrameError> {
    encode(msg, buf)
}

/// Encodes a host -> board message. A `[u8; HOST_FRAME_MAX]` buffer always suffices.
pub fn encode_host<'b>(msg: &HostMsg, buf: &'b mut [u8]) -> Result<&'b [u8], FrameError> {
    encode(msg, buf)
}

/// Why a delimited frame was thrown away.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CorruptReason {
    /// The COBS structure was cut short by a 0x00 (bytes lost, or the receiver started
    /// mid-frame).
    Cobs,
    /// The CRC did not match, or the frame was too short to hold one.
    Crc,
    /// CRC fine but the bytes are not a message of this direction (unknown tag, bad varint,
    /// too many samples, trailing bytes): usually a schema mismatch.
    Postcard,
    /// More bytes than the largest message before any 0x00; reported as soon as the limit is
    /// passed, and the rest up to the next 0x00 is skipped silently.
    Overlong,
}

/// One event out of the [`Decoder`].
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Decoded<M> {
    /// A frame that passed COBS, CRC and postcard.
    Frame(M),
    /// A frame that failed; the decoder has already resynchronised.
    CorruptFrame {
        /// The first check that failed.
        reason: CorruptReason,
    },
}

/// Counters kept by a [`Decoder`] since it was made (or [`Decoder::reset_stats`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DecoderStats {
    /// Every byte pushed, delimiters included.
    pub bytes: u64,
    /// Frames decoded successfully.
    pub frames: u64,
    /// Frames thrown away, all reasons (= the sum of the four counters below).
    pub corrupt: u64,
    /// ... because of [`CorruptReason::Cobs`].
    pub cobs_errors: u64,
    /// ... because of [`CorruptReason::Crc`].
    pub crc_errors: u64,
    /// ... because of [`CorruptReason::Postcard`].
    pub postcard_errors: u64,
    /// ... because of [`CorruptReason::Overlong`].
    pub overlong: u64,
}

impl DecoderStats {
    fn count(&mut self, reason: CorruptReason) {
        self.corrupt += 1;
        let counter = match reason {
            CorruptReason::Cobs => &mut self.cobs_errors,
            CorruptReason::Crc => &mut self.crc_errors,
            CorruptReason::Postcard => &mut self.postcard_errors,
            CorruptReason::Overlong => &mut self.overlong,
        };
        *counter += 1;
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum RxState {
    /// Between frames (just after a 0x00, or at start).
    Idle,
    /// Inside a frame.
    InFrame,
    /// Discarding an overlong frame up to the next 0x00.
    Skipping,
}

/// Streaming frame decoder with a fixed buffer (`RAW` bytes; use the aliases
/// [`DeviceDecoder`] on the host and [`HostDecoder`] on the board).
///
/// Push bytes in any split ([`Decoder::push`], [`Decoder::feed`]); `None` / an exhausted
/// iterator means "need more bytes". Every 0x00 ends a frame: empty frames (`00 00`) are
/// ignored (a sender may send a lone 0x00 to flush a receiver), anything else yields either
/// [`Decoded::Frame`] or [`Decoded::CorruptFrame`]. Never panics, never allocates.
///
/// A receiver that starts listening mid-stream sees one corrupt frame (the tail of the frame in
/// flight) before the first good one; that is expected.
pub struct Decoder<M, const RAW: usize> {
    buf: [u8; RAW],
    len: usize,
    cobs: cobs::Decoder,
    state: RxState,
    stats: DecoderStats,
    _msg: PhantomData<fn() -> M>,
}

/// Host side: decodes board -> host frames.
pub type DeviceDecoder = Decoder<DeviceMsg, DEVICE_RAW_MAX>;
/// Board side: decodes host -> board frames.
pub type HostDecoder = Decoder<HostMsg, HOST_RAW_MAX>;

impl<M, const RAW: usize> fmt::Debug for Decoder<M, RAW> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Decoder")
            .field("buffered", &self.len)
            .field("state", &self.state)
            .field("stats", &self.stats)
            .finish()
    }
}

impl<M: DeserializeOwned + MaxSize, const RAW: usize> Default for Decoder<M, RAW> {
    fn default() -> Self {
        Self::new()
    }
}

impl<M: DeserializeOwned + MaxSize, const RAW: usize> Decoder<M, RAW> {
    const BUFFER_HOLDS_LARGEST_MESSAGE: () = assert!(RAW >= M::POSTCARD_MAX_SIZE + CRC_LEN);

    /// An empty decoder, waiting for a frame.
    pub const fn new() -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::BUFFER_HOLDS_LARGEST_MESSAGE;
        Self {
            buf: [0; RAW],
            len: 0,
            cobs: cobs::Decoder::new(),
            state: RxState::Idle,
            stats: DecoderStats {
                bytes: 0,
                frames: 0,
                corrupt: 0,
                cobs_errors: 0,
                crc_errors: 0,
                postcard_errors: 0,
                overlong: 0,
            },
            _msg: PhantomData,
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> DecoderStats {
        self.stats
    }

    /// Zeroes the counters (the partial frame, if any, is kept).
    pub fn reset_stats(&mut self) {
        self.stats = DecoderStats::default();
    }

    /// Drops a partial frame (for example after reopening the port); counters are kept.
    pub fn clear(&mut self) {
        self.start_frame(RxState::Idle);
    }

    /// True when bytes of an unfinished frame are buffered.
    pub fn in_frame(&self) -> bool {
        self.state != RxState::Idle
    }

    fn start_frame(&mut self, state: RxState) {
        self.len = 0;
        self.cobs = cobs::Decoder::new();
        self.state = state;
    }

    fn corrupt(&mut self, reason: CorruptReason) -> Decoded<M> {
        self.stats.count(reason);
        Decoded::CorruptFrame { reason }
    }

    /// Pushes one byte; `Some` when it completed (or condemned) a frame.
    #[inline]
    pub fn push(&mut self, byte: u8) -> Option<Decoded<M>> {
        self.stats.bytes += 1;
        if byte == DELIMITER {
            let state = self.state;
            let result = match state {
                RxState::Idle | RxState::Skipping => None,
                RxState::InFrame => Some(self.finish_frame()),
            };
            self.start_frame(RxState::Idle);
            return result;
        }
        match self.state {
            RxState::Skipping => None,
            RxState::Idle | RxState::InFrame => {
                self.state = RxState::InFrame;
                let decoded = match self.cobs.step(byte) {
                    cobs::Step::None => return None,
                    cobs::Step::Zero => 0,
                    cobs::Step::Byte(b) => b,
                };
                match self.buf.get_mut(self.len) {
                    Some(slot) => {
                        *slot = decoded;
                        self.len += 1;
                        None
                    }
                    None => {
                        self.start_frame(RxState::Skipping);
                        Some(self.corrupt(CorruptReason::Overlong))
                    }
                }
            }
        }
    }

    /// Checks the buffered frame at its delimiter.
    fn finish_frame(&mut self) -> Decoded<M> {
        if !self.cobs.complete() {
            return self.corrupt(CorruptReason::Cobs);
        }
        let body = &self.buf[..self.len];
        let Some(payload_len) = body.len().checked_sub(CRC_LEN) else {
            return self.corrupt(CorruptReason::Crc);
        };
        let (payload, crc_bytes) = body.split_at(payload_len);
        let mut sent = [0u8; CRC_LEN];
        sent.copy_from_slice(crc_bytes);
        if u32::from_le_bytes(sent) != crate::crc::crc32(payload) {
            return self.corrupt(CorruptReason::Crc);
        }
        match postcard::take_from_bytes::<M>(payload) {
            Ok((msg, [])) => {
                self.stats.frames += 1;
                Decoded::Frame(msg)
            }
            Ok(_) | Err(_) => self.corrupt(CorruptReason::Postcard),
        }
    }

    /// Pushes a slice; the iterator yields each completed frame in order and ends when the
    /// slice is used up (bytes not yet pulled stay unconsumed if the iterator is dropped early).
    pub fn feed<'d, 'b>(&'d mut self, bytes: &'b [u8]) -> Feed<'d, 'b, M, RAW> {
        Feed {
            decoder: self,
            bytes: bytes.iter(),
        }
    }

    /// Pushes a whole slice, calling `on_event` for each completed frame.
    pub fn push_slice(&mut self, bytes: &[u8], mut on_event: impl FnMut(Decoded<M>)) {
        for &byte in bytes {
            if let Some(event) = self.push(byte) {
                on_event(event);
            }
        }
    }
}

/// Iterator returned by [`Decoder::feed`].
pub struct Feed<'d, 'b, M, const RAW: usize> {
    decoder: &'d mut Decoder<M, RAW>,
    bytes: core::slice::Iter<'b, u8>,
}

impl<M: DeserializeOwned + MaxSize, const RAW: usize> Iterator for Feed<'_, '_, M, RAW> {
    type Item = Decoded<M>;

    fn next(&mut self) -> Option<Decoded<M>> {
        for &byte in self.bytes.by_ref() {
            if let Some(event) = self.decoder.push(byte) {
                return Some(event);
            }
        }
        None
    }
}
