//! The records of an MCAP chunk: decompressed (`zstd`: `ruzstd`, `lz4`: `lz4_flex`, or none),
//! its length and CRC checked ([`unchunk`]), then split into records ([`ChunkRecords`]).

use std::io::Read;

use super::MAX_RECORD_BYTES;

/// The records `opcode, u64 length, body` of a decompressed chunk.
pub(super) struct ChunkRecords<'a>(pub(super) &'a [u8]);

impl<'a> Iterator for ChunkRecords<'a> {
    type Item = Result<(u8, &'a [u8]), String>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.0.is_empty() {
            return None;
        }
        let head = match self.0.get(..9) {
            Some(h) => h,
            None => {
                self.0 = &[];
                return Some(Err("a record header cut short inside the chunk".into()));
            }
        };
        let mut len = [0u8; 8];
        len.copy_from_slice(&head[1..9]);
        let len = u64::from_le_bytes(len);
        let body = usize::try_from(len)
            .ok()
            .and_then(|n| self.0.get(9..9usize.checked_add(n)?));
        match body {
            Some(b) => {
                let op = head[0];
                self.0 = &self.0[9 + b.len()..];
                Some(Ok((op, b)))
            }
            None => {
                self.0 = &[];
                Some(Err(format!("a record of {len} bytes overruns the chunk")))
            }
        }
    }
}

/// The records of a chunk: decompressed (`zstd`, `lz4` or none), length and CRC checked.
pub(super) fn unchunk<'d>(
    h: &mcap::records::ChunkHeader,
    data: &'d [u8],
) -> Result<std::borrow::Cow<'d, [u8]>, String> {
    use std::borrow::Cow;
    let size = usize::try_from(h.uncompressed_size)
        .ok()
        .filter(|n| *n <= MAX_RECORD_BYTES)
        .ok_or_else(|| format!("chunk of {} bytes uncompressed", h.uncompressed_size))?;
    let out = match h.compression.as_str() {
        "" => Cow::Borrowed(data),
        "zstd" => {
            let mut out = Vec::with_capacity(size);
            let mut src = data;
            while !src.is_empty() && out.len() <= size {
                let dec = ruzstd::decoding::StreamingDecoder::new(&mut src)
                    .map_err(|e| format!("zstd: {e}"))?;
                dec.take((size - out.len()) as u64 + 1)
                    .read_to_end(&mut out)
                    .map_err(|e| format!("zstd: {e}"))?;
            }
            Cow::Owned(out)
        }
        "lz4" => {
            let mut out = Vec::with_capacity(size);
            lz4_flex::frame::FrameDecoder::new(data)
                .take(size as u64 + 1)
                .read_to_end(&mut out)
                .map_err(|e| format!("lz4: {e}"))?;
            Cow::Owned(out)
        }
        other => {
            return Err(format!(
                "chunk compression `{other}` is not read (zstd, lz4, none)"
            ))
        }
    };
    if out.len() != size {
        return Err(format!(
            "chunk holds {} bytes, its header says {size}",
            out.len()
        ));
    }
    if h.uncompressed_crc != 0 && crc32fast::hash(&out) != h.uncompressed_crc {
        return Err("chunk CRC mismatch".into());
    }
    Ok(out)
}
