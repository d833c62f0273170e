//! Schema hash: a fingerprint of the message definitions, sent by the board in
//! [`Hello::schema_hash`] so that the host refuses to talk to firmware built from different
//! message types even when [`PROTOCOL_VERSION`] was not bumped.
//!
//! The fingerprint is derived from the types themselves: every wire type derives
//! [`postcard_schema::Schema`], whose const FNV-1a-64 key of a type covers its name, every field
//! and variant name and every field type, recursively. [`SCHEMA_HASH`] folds the keys of the two
//! top-level messages ([`DeviceMsg`], [`HostMsg`]) and [`POT_BATCH_MAX`] (a capacity, which the
//! derived schema does not see) into 32 bits with FNV-1a. Nothing is written by hand, so the
//! hash cannot drift from the types; the frozen byte vectors in `tests/wire/frozen_vectors.rs` and the
//! frozen hash in `tests/schema.rs` break on purpose when a message changes.

use postcard_schema::key::hash::fnv1a64::hash_ty_path;

use crate::messages::{DeviceMsg, Hello, HostMsg, POT_BATCH_MAX, PROTOCOL_VERSION};

/// Name of the schema the keys are computed under (part of the hash).
pub const SCHEMA_NAME: &str = "rig-protocol/1";

/// 32-bit FNV-1a (offset basis 0x811C9DC5, prime 0x01000193), continuing from `hash`.
pub const fn fnv1a32_update(mut hash: u32, bytes: &[u8]) -> u32 {
    let mut i = 0;
    while i < bytes.len() {
        hash ^= bytes[i] as u32;
        hash = hash.wrapping_mul(0x0100_0193);
        i += 1;
    }
    hash
}

/// 32-bit FNV-1a of `bytes`.
pub const fn fnv1a32(bytes: &[u8]) -> u32 {
    fnv1a32_update(0x811C_9DC5, bytes)
}

/// The schema hash for a given potentiometer batch capacity: FNV-1a-32 over the derived
/// FNV-1a-64 keys of `DeviceMsg` and `HostMsg` (under [`SCHEMA_NAME`]) and `pot_batch_max` as
/// little-endian u32.
pub const fn schema_hash(pot_batch_max: u32) -> u32 {
    let device = hash_ty_path::<DeviceMsg>(SCHEMA_NAME);
    let host = hash_ty_path::<HostMsg>(SCHEMA_NAME);
    let h = fnv1a32_update(0x811C_9DC5, &device);
    let h = fnv1a32_update(h, &host);
    fnv1a32_update(h, &pot_batch_max.to_le_bytes())
}

/// [`schema_hash`] of this crate's types: the value the board puts in [`Hello::schema_hash`].
pub const SCHEMA_HASH: u32 = schema_hash(POT_BATCH_MAX as u32);

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
