//! The schema hash is frozen like the wire vectors: changing `SCHEMA` changes what the board
//! announces, and old hosts will refuse new boards. Update this value only together with the
//! frozen vectors and `PROTOCOL_VERSION`, on purpose.

use rig_protocol::{POT_BATCH_MAX, SCHEMA, SCHEMA_HASH};

#[test]
fn schema_hash_is_frozen() {
    assert_eq!(SCHEMA_HASH, 0x78c2_1c5c);
}

#[test]
fn schema_text_follows_the_batch_size() {
    // POT_BATCH_MAX is part of the wire contract (it bounds `samples`); the schema text must
    // change with it, which changes the hash.
    let needle = format!("samples:seq<u16;{POT_BATCH_MAX}>");
    assert!(SCHEMA.contains(&needle), "SCHEMA lacks {needle}");
}

#[test]
fn schema_describes_every_message_type() {
    for name in [
        "DeviceMsg=",
        "HostMsg=",
        "CommandKind=",
        "NackReason=",
        "Hello=",
        "PotBatch=",
        "TiltReading=",
        "Status=",
    ] {
        assert!(SCHEMA.contains(name), "SCHEMA lacks {name}");
    }
}
