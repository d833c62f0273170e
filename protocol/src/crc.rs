//! CRC-32/ISO-HDLC (the zlib / Ethernet CRC), table driven, usable in `const` context.
//!
//! Parameters (Rocksoft model): width 32, poly 0x04C11DB7 (reflected 0xEDB88320), init
//! 0xFFFFFFFF, refin/refout true, xorout 0xFFFFFFFF, check("123456789") = 0xCBF43926.
//!
//! Why CRC-32 rather than CRC-16/CCITT: frames are at most a few hundred bytes, where both have
//! Hamming distance >= 4, but a random corruption (a noisy link, a `--corrupt-ppm` simulation,
//! garbage that happens to be COBS-valid) slips through a 16-bit CRC once in 65 536 corrupt
//! frames, and at ~200 frames/s of corrupt traffic that is one silent error every few minutes.
//! The 2 extra bytes per frame are cheap. The table is 1 KiB of flash.

/// The CRC is appended to the postcard bytes in this many bytes, little-endian.
pub const CRC_LEN: usize = 4;

const POLY_REFLECTED: u32 = 0xEDB8_8320;

const TABLE: [u32; 256] = make_table();

const fn make_table() -> [u32; 256] {
    let mut table = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut crc = i as u32;
        let mut bit = 0;
        while bit < 8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ POLY_REFLECTED
            } else {
                crc >> 1
            };
            bit += 1;
        }
        table[i] = crc;
        i += 1;
    }
    table
}

/// Incremental CRC-32 state; feed bytes with [`Crc32::update`], read with [`Crc32::finish`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Crc32 {
    state: u32,
}

impl Default for Crc32 {
    fn default() -> Self {
        Self::new()
    }
}

impl Crc32 {
    /// A fresh CRC (no bytes seen).
    pub const fn new() -> Self {
        Self { state: 0xFFFF_FFFF }
    }

    /// Adds one byte.
    #[inline]
    pub const fn update_byte(self, byte: u8) -> Self {
        let index = ((self.state ^ byte as u32) & 0xFF) as usize;
        Self {
            state: (self.state >> 8) ^ TABLE[index],
        }
    }

    /// Adds a run of bytes.
    pub const fn update(mut self, bytes: &[u8]) -> Self {
        let mut i = 0;
        while i < bytes.len() {
            self = self.update_byte(bytes[i]);
            i += 1;
        }
        self
    }

    /// The CRC of every byte added so far.
    pub const fn finish(self) -> u32 {
        self.state ^ 0xFFFF_FFFF
    }
}

/// CRC-32/ISO-HDLC of `bytes`.
pub const fn crc32(bytes: &[u8]) -> u32 {
    Crc32::new().update(bytes).finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    // Check values from the CRC catalogue (reveng) and RFC 1952 implementations, not from this code.
    #[test]
    fn catalogue_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn empty_and_known_strings() {
        assert_eq!(crc32(b""), 0);
        // zlib.crc32(b"The quick brown fox jumps over the lazy dog")
        assert_eq!(
            crc32(b"The quick brown fox jumps over the lazy dog"),
            0x414F_A339
        );
    }

    #[test]
    fn incremental_equals_one_shot() {
        let data = b"calibration rig";
        let split = Crc32::new().update(&data[..5]).update(&data[5..]).finish();
        assert_eq!(split, crc32(data));
    }
}
