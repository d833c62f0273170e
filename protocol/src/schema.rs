//! Schema hash: a fingerprint of the message definitions, sent by the board in
//! [`Hello::schema_hash`] so that the host refuses to talk to firmware built from different
//! message types even when [`PROTOCOL_VERSION`] was not bumped.
//!
//! The fingerprint is the 32-bit FNV-1a hash of [`SCHEMA`], a hand-written description of every
//! type in postcard order. Whoever changes `messages.rs` must change `SCHEMA` alongside; the
//! frozen byte vectors in `tests/frozen_vectors.rs` and the frozen hash in `tests/schema.rs`
//! break on purpose to remind them.

use crate::messages::{Hello, PROTOCOL_VERSION};

/// Description of the wire types, field by field, in serialization order.
pub const SCHEMA: &str = "\
rig-protocol/1;\
DeviceMsg=enum{Hello(Hello),Pot(PotBatch),Tilt(TiltReading),Status(Status),\
Pong{nonce:u32},Ack(CommandKind),Nack{command:CommandKind,reason:NackReason}};\
HostMsg=enum{Start{pot_rate_hz:u32,tilt_rate_hz:u32},Stop,Ping{nonce:u32},GetInfo};\
CommandKind=enum{Start,Stop,Ping,GetInfo};\
NackReason=enum{RateOutOfRange,AlreadyRunning,NotRunning};\
Hello=struct{protocol_version:u16,firmware_version:[u8;3],board_id:[u8;12],\
schema_hash:u32,tilt_sensors:u8};\
PotBatch=struct{seq:u32,t0_us:u64,period_us:u32,samples:seq<u16;64>};\
TiltReading=struct{sensor:u8,t_us:u64,x:i16,y:i16,z:i16,temp:i16,status:u8};\
Status=struct{uptime_us:u64,dropped_samples:u32,dropped_frames:u32,overruns:u32,\
sensor_errors:u32,rx_errors:u32};";

/// 32-bit FNV-1a (offset basis 0x811C9DC5, prime 0x01000193).
pub const fn fnv1a32(bytes: &[u8]) -> u32 {
    let mut hash: u32 = 0x811C_9DC5;
    let mut i = 0;
    while i < bytes.len() {
        hash ^= bytes[i] as u32;
        hash = hash.wrapping_mul(0x0100_0193);
        i += 1;
    }
    hash
}

/// [`fnv1a32`] of [`SCHEMA`]: the value the board puts in [`Hello::schema_hash`].
pub const SCHEMA_HASH: u32 = fnv1a32(SCHEMA.as_bytes());

/// Why the host refuses a board.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HelloMismatch {
    /// The board speaks another protocol version.
    ProtocolVersion {
        /// Version in the board's `Hello`.
        board: u16,
        /// This crate's [`PROTOCOL_VERSION`].
        host: u16,
    },
    /// Same version number, different message definitions.
    SchemaHash {
        /// Hash in the board's `Hello`.
        board: u32,
        /// This crate's [`SCHEMA_HASH`].
        host: u32,
    },
}

impl core::fmt::Display for HelloMismatch {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::ProtocolVersion { board, host } => write!(
                f,
                "board speaks protocol version {board}, this host speaks {host}"
            ),
            Self::SchemaHash { board, host } => write!(
                f,
                "board schema hash {board:#010x} differs from this host's {host:#010x} \
                 (firmware built from other message definitions)"
            ),
        }
    }
}

impl core::error::Error for HelloMismatch {}

/// Accepts a board's [`Hello`] only if it speaks exactly this crate's protocol.
pub fn check_hello(hello: &Hello) -> Result<(), HelloMismatch> {
    if hello.protocol_version != PROTOCOL_VERSION {
        return Err(HelloMismatch::ProtocolVersion {
            board: hello.protocol_version,
            host: PROTOCOL_VERSION,
        });
    }
    if hello.schema_hash != SCHEMA_HASH {
        return Err(HelloMismatch::SchemaHash {
            board: hello.schema_hash,
            host: SCHEMA_HASH,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    // Reference values of FNV-1a 32 from the FNV test suite (isthe.com/chongo/tech/comp/fnv).
    #[test]
    fn fnv_reference_values() {
        assert_eq!(fnv1a32(b""), 0x811C_9DC5);
        assert_eq!(fnv1a32(b"a"), 0xE40C_292C);
        assert_eq!(fnv1a32(b"foobar"), 0xBF9C_F968);
    }

    fn hello(version: u16, hash: u32) -> Hello {
        Hello {
            protocol_version: version,
            firmware_version: [0, 1, 0],
            board_id: [0; 12],
            schema_hash: hash,
            tilt_sensors: 3,
        }
    }

    #[test]
    fn check_hello_accepts_only_exact_match() {
        assert_eq!(check_hello(&hello(PROTOCOL_VERSION, SCHEMA_HASH)), Ok(()));
        assert_eq!(
            check_hello(&hello(PROTOCOL_VERSION + 1, SCHEMA_HASH)),
            Err(HelloMismatch::ProtocolVersion {
                board: PROTOCOL_VERSION + 1,
                host: PROTOCOL_VERSION
            })
        );
        assert!(matches!(
            check_hello(&hello(PROTOCOL_VERSION, SCHEMA_HASH ^ 1)),
            Err(HelloMismatch::SchemaHash { .. })
        ));
    }
}
