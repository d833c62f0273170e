//! The schema hash is frozen like the wire vectors: it is derived from the message types
//! (`postcard_schema::Schema`), so changing a message changes what the board announces, and old
//! hosts refuse new boards. Update the frozen value only together with the frozen vectors and
//! `PROTOCOL_VERSION`, on purpose.

use postcard_schema::schema::owned::OwnedNamedType;
use postcard_schema::Schema;
use rig_protocol::{schema_hash, DeviceMsg, HostMsg, POT_BATCH_MAX, SCHEMA_HASH};

#[test]
fn schema_hash_is_frozen() {
    assert_eq!(SCHEMA_HASH, FROZEN_SCHEMA_HASH, "got {SCHEMA_HASH:#010x}");
}

const FROZEN_SCHEMA_HASH: u32 = 0xde26_4da3;

#[test]
fn schema_hash_follows_the_batch_size() {
    // POT_BATCH_MAX bounds `samples` (part of the wire contract) but is not in the derived schema:
    // it is folded into the hash explicitly.
    let n = POT_BATCH_MAX as u32;
    assert_eq!(schema_hash(n), SCHEMA_HASH);
    assert_ne!(schema_hash(n + 1), SCHEMA_HASH);
}

/// The derived schema, as pseudo-code: what the hash covers. Frozen text, so a reviewer sees in
/// the diff exactly which wire change moved the hash.
fn described() -> String {
    let mut lines: Vec<String> = [DeviceMsg::SCHEMA, HostMsg::SCHEMA]
        .into_iter()
        .flat_map(|nt| OwnedNamedType::from(nt).all_used_types())
        .map(|t| t.to_pseudocode())
        .collect();
    lines.sort();
    lines.dedup();
    lines.join("\n")
}

#[test]
fn the_hash_covers_every_message_type_and_field() {
    let text = described();
    for name in [
        "DeviceMsg",
        "HostMsg",
        "CommandKind",
        "NackReason",
        "Hello",
        "PotBatch",
        "TiltReading",
        "Status",
        "schema_hash",
        "pot_rate_hz",
        "samples",
        "sensor_errors",
        "RateOutOfRange",
    ] {
        assert!(text.contains(name), "derived schema lacks {name}:\n{text}");
    }
}
