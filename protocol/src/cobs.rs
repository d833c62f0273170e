//! Consistent Overhead Byte Stuffing, written incrementally so that neither side needs a second
//! buffer: the encoder writes straight into the output frame, the decoder un-stuffs each byte as
//! it arrives.
//!
//! A COBS block is a code byte `c` (1..=255) followed by `c - 1` non-zero data bytes; a block
//! with `c < 255` stands for its data followed by one zero, except the frame's last block. The
//! encoder below closes a block after 254 data bytes, so `n` input bytes cost at most
//! `n + 1 + n / 254` output bytes ([`max_encoded_len`]), before the 0x00 delimiter.

/// Largest COBS encoding of `raw_len` bytes, delimiter excluded.
pub const fn max_encoded_len(raw_len: usize) -> usize {
    raw_len + 1 + raw_len / 254
}

/// Writes the COBS encoding of a byte stream into a caller's slice.
#[derive(Debug)]
pub(crate) struct Encoder<'a> {
    out: &'a mut [u8],
    /// Where the code byte of the open block goes.
    code_at: usize,
    /// Next free position.
    pos: usize,
    /// Code of the open block: 1 + its data bytes so far.
    code: u8,
}

/// The output slice was too small.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Full;

impl<'a> Encoder<'a> {
    pub(crate) fn new(out: &'a mut [u8]) -> Result<Self, Full> {
        if out.is_empty() {
            return Err(Full);
        }
        Ok(Self {
            out,
            code_at: 0,
            pos: 1,
            code: 1,
        })
    }

    fn close_block(&mut self) -> Result<(), Full> {
        self.out[self.code_at] = self.code;
        self.code_at = self.pos;
        *self.out.get_mut(self.pos).ok_or(Full)? = 0; // reserve the next code byte
        self.pos += 1;
        self.code = 1;
        Ok(())
    }

    pub(crate) fn push(&mut self, byte: u8) -> Result<(), Full> {
        if byte == 0 {
            return self.close_block();
        }
        *self.out.get_mut(self.pos).ok_or(Full)? = byte;
        self.pos += 1;
        self.code += 1;
        if self.code == 0xFF {
            self.close_block()?;
        }
        Ok(())
    }

    /// Closes the last block, appends the 0x00 delimiter and returns the frame.
    pub(crate) fn finish(self) -> Result<&'a [u8], Full> {
        let Self {
            out,
            code_at,
            pos,
            code,
        } = self;
        out[code_at] = code;
        *out.get_mut(pos).ok_or(Full)? = 0;
        Ok(&out[..=pos])
    }
}

/// What the decoder made of one non-zero wire byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Step {
    /// Nothing to store (a code byte opening a block without an implied zero before it).
    None,
    /// Store this decoded byte.
    Byte(u8),
    /// Store a zero: the wire byte was a code byte, and the block it closes implied a zero.
    Zero,
}

/// Un-stuffs a frame byte by byte. Feed every non-zero wire byte to [`Decoder::step`]; at the
/// 0x00 delimiter ask [`Decoder::complete`] whether the frame ended on a block boundary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Decoder {
    /// Data bytes still expected in the open block; 0 means the next byte is a code byte.
    remaining: u8,
    /// Code of the previous block (0 before the first).
    last_code: u8,
}

impl Decoder {
    pub(crate) const fn new() -> Self {
        Self {
            remaining: 0,
            last_code: 0,
        }
    }

    /// Handles one non-zero wire byte.
    #[inline]
    pub(crate) fn step(&mut self, byte: u8) -> Step {
        debug_assert!(byte != 0);
        if self.remaining == 0 {
            let implied_zero = self.last_code != 0 && self.last_code != 0xFF;
            self.last_code = byte;
            self.remaining = byte - 1;
            if implied_zero {
                Step::Zero
            } else {
                Step::None
            }
        } else {
            self.remaining -= 1;
            Step::Byte(byte)
        }
    }

    /// True when the bytes seen so far form a whole COBS frame (the delimiter may come now).
    pub(crate) fn complete(&self) -> bool {
        self.remaining == 0 && self.last_code != 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn encode(raw: &[u8]) -> ([u8; 600], usize) {
        let mut out = [0u8; 600];
        let mut enc = Encoder::new(&mut out).unwrap();
        for &b in raw {
            enc.push(b).unwrap();
        }
        let len = enc.finish().unwrap().len();
        (out, len)
    }

    fn decode(wire: &[u8]) -> Option<([u8; 600], usize)> {
        let mut out = [0u8; 600];
        let mut len = 0;
        let mut dec = Decoder::new();
        for &b in wire {
            if b == 0 {
                return dec.complete().then_some((out, len));
            }
            match dec.step(b) {
                Step::None => {}
                Step::Zero => {
                    out[len] = 0;
                    len += 1;
                }
                Step::Byte(x) => {
                    out[len] = x;
                    len += 1;
                }
            }
        }
        None
    }

    // Examples from the COBS paper (Cheshire & Baker 1999) / the Wikipedia table.
    #[test]
    fn known_encodings() {
        let cases: &[(&[u8], &[u8])] = &[
            (&[0x00], &[0x01, 0x01, 0x00]),
            (&[0x00, 0x00], &[0x01, 0x01, 0x01, 0x00]),
            (&[0x00, 0x11, 0x00], &[0x01, 0x02, 0x11, 0x01, 0x00]),
            (
                &[0x11, 0x22, 0x00, 0x33],
                &[0x03, 0x11, 0x22, 0x02, 0x33, 0x00],
            ),
            (
                &[0x11, 0x22, 0x33, 0x44],
                &[0x05, 0x11, 0x22, 0x33, 0x44, 0x00],
            ),
            (
                &[0x11, 0x00, 0x00, 0x00],
                &[0x02, 0x11, 0x01, 0x01, 0x01, 0x00],
            ),
        ];
        for (raw, wire) in cases {
            let (out, len) = encode(raw);
            assert_eq!(&out[..len], *wire, "encode {raw:02x?}");
            let (dec, dlen) = decode(wire).unwrap();
            assert_eq!(&dec[..dlen], *raw, "decode {wire:02x?}");
        }
    }

    #[test]
    fn long_runs_round_trip_within_bound() {
        for n in [253usize, 254, 255, 508, 509, 580] {
            let raw: heapless::Vec<u8, 600> = (0..n).map(|i| (i % 255 + 1) as u8).collect();
            let (out, len) = encode(&raw);
            assert!(len <= max_encoded_len(n) + 1, "n={n} len={len}");
            assert!(out[..len - 1].iter().all(|&b| b != 0));
            let (dec, dlen) = decode(&out[..len]).unwrap();
            assert_eq!(&dec[..dlen], &raw[..]);
        }
    }

    #[test]
    fn truncated_block_is_incomplete() {
        assert!(decode(&[0x05, 0x11, 0x22, 0x00]).is_none());
        assert!(decode(&[0x00]).is_none());
    }

    #[test]
    fn encoder_reports_full() {
        let mut out = [0u8; 3];
        let mut enc = Encoder::new(&mut out).unwrap();
        enc.push(1).unwrap();
        enc.push(2).unwrap();
        assert_eq!(enc.finish(), Err(Full)); // no room for the delimiter

        let mut out = [0u8; 3];
        let mut enc = Encoder::new(&mut out).unwrap();
        enc.push(1).unwrap();
        enc.push(2).unwrap();
        assert_eq!(enc.push(3), Err(Full));
    }
}
