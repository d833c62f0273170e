//! Bounded reads: every file `rigctl` reads goes through [`read_capped`] or [`read_text_capped`]
//! with a size cap for its kind, so that `/dev/zero`, a FIFO that never ends or a file of the
//! wrong kind cannot grow the process without bound. A text reader also refuses a NUL byte at
//! once (no text format of rigctl holds one): `--model /dev/zero` is refused after the first
//! block.
//!
//! | input | cap |
//! |---|---|
//! | model file, placement, pot TOML, `diagnose --json` for `plan --from-diagnose` / `report` | [`CAP_SMALL_TEXT`] 64 MiB |
//! | URDF | [`CAP_URDF`] 256 MiB |
//! | CSV tables (pose files, fused samples, joint readings, jig, paths) | [`CAP_TABLE`] 2 GiB |
//! | recordings | [`CAP_RECORDING`] 8 GiB |

use std::io::Read;
use std::path::Path;

/// Model files, rig TOML files and JSON reports.
pub const CAP_SMALL_TEXT: u64 = 64 << 20;
/// URDF files (meshes are separate files; a 10 000-joint chain is about 5 MB).
pub const CAP_URDF: u64 = 256 << 20;
/// CSV tables: a pose file of 10 million poses is about 1 GB.
pub const CAP_TABLE: u64 = 2 << 30;
/// Board recordings: days of 1 kHz potentiometer frames.
pub const CAP_RECORDING: u64 = 8 << 30;

const CHUNK: usize = 1 << 16;

fn too_large(cap: u64) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::FileTooLarge,
        format!("larger than the {} MiB this input may be", cap >> 20),
    )
}

/// Whether an I/O error is one of this module's refusals (bad input, not a failure of the run).
pub fn is_refusal(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        std::io::ErrorKind::FileTooLarge | std::io::ErrorKind::InvalidData
    )
}

fn read_inner(path: &Path, cap: u64, text: bool, prefix: &[u8]) -> std::io::Result<Vec<u8>> {
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if meta.is_dir() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::IsADirectory,
            "is a directory",
        ));
    }
    if meta.is_file() && meta.len() > cap {
        return Err(too_large(cap));
    }
    let hint = if meta.is_file() {
        meta.len() as usize
    } else {
        0
    };
    let mut out = Vec::with_capacity(hint.min(cap as usize));
    let mut limited = file.take(cap + 1);
    let mut buf = vec![0u8; CHUNK];
    loop {
        let n = match limited.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        let chunk = &buf[..n];
        // UTF-16 text (a byte-order mark first) holds NUL bytes: decoded by the caller
        let utf16 = utf16_bom(if out.is_empty() { chunk } else { &out });
        if text && utf16.is_none() {
            if let Some(at) = chunk.iter().position(|&b| b == 0) {
                let what = if looks_utf16(chunk) && out.is_empty() {
                    "UTF-16 text without a byte-order mark? save it as UTF-8; "
                } else {
                    ""
                };
                return Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!(
                        "not a text file ({what}a NUL byte at offset {})",
                        out.len() + at
                    ),
                ));
            }
        }
        out.extend_from_slice(chunk);
        let k = out.len().min(prefix.len());
        if out[..k] != prefix[..k] {
            // not this kind of file: the caller's check of the start reports it
            return Ok(out);
        }
        if out.len() as u64 > cap {
            return Err(too_large(cap));
        }
    }
    Ok(out)
}

/// The bytes of `path`, at most `cap` of them (more is an error of kind `FileTooLarge`).
pub fn read_capped(path: &Path, cap: u64) -> std::io::Result<Vec<u8>> {
    read_inner(path, cap, false, &[])
}

/// [`read_capped`] for a binary format that starts with `magic`: reading stops as soon as the
/// start differs (the bytes read so far are returned, for the caller's header check).
pub fn read_capped_magic(path: &Path, cap: u64, magic: &[u8]) -> std::io::Result<Vec<u8>> {
    read_inner(path, cap, false, magic)
}

/// Whether `bytes` start with a UTF-16 byte-order mark: `Some(true)` little-endian.
fn utf16_bom(bytes: &[u8]) -> Option<bool> {
    match bytes {
        [0xFF, 0xFE, ..] => Some(true),
        [0xFE, 0xFF, ..] => Some(false),
        _ => None,
    }
}

/// Whether a first block looks like UTF-16 without a mark: ASCII with a NUL every other byte.
fn looks_utf16(chunk: &[u8]) -> bool {
    let n = chunk.len().min(64) & !1;
    n >= 4
        && (chunk[..n].iter().skip(1).step_by(2).all(|&b| b == 0)
            || chunk[..n].iter().step_by(2).all(|&b| b == 0))
}

/// UTF-16 text (after its byte-order mark) as a `String`.
fn decode_utf16(bytes: &[u8], little: bool) -> std::io::Result<String> {
    let bad = |what: String| std::io::Error::new(std::io::ErrorKind::InvalidData, what);
    let body = &bytes[2..];
    if !body.len().is_multiple_of(2) {
        return Err(bad(format!(
            "UTF-16 text (byte-order mark {}) of an odd number of bytes",
            if little { "LE" } else { "BE" }
        )));
    }
    let units = body.chunks_exact(2).map(|p| {
        if little {
            u16::from_le_bytes([p[0], p[1]])
        } else {
            u16::from_be_bytes([p[0], p[1]])
        }
    });
    let text: String = char::decode_utf16(units)
        .collect::<Result<_, _>>()
        .map_err(|e| bad(format!("UTF-16 text with an invalid code unit: {e}")))?;
    if let Some(at) = text.find('\0') {
        return Err(bad(format!(
            "not a text file (UTF-16 with a NUL character at character {at})"
        )));
    }
    Ok(text)
}

/// The text of `path`, at most `cap` bytes: UTF-8, or UTF-16 with a byte-order mark (a
/// spreadsheet's "Unicode text" export; decoded), without NUL characters (errors of kind
/// `FileTooLarge` / `InvalidData`).
pub fn read_text_capped(path: &Path, cap: u64) -> std::io::Result<String> {
    let bytes = read_inner(path, cap, true, &[])?;
    if let Some(little) = utf16_bom(&bytes) {
        return decode_utf16(&bytes, little);
    }
    String::from_utf8(bytes).map_err(|e| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "not UTF-8 text (invalid byte at offset {})",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dev_zero_is_refused_at_once() {
        if Path::new("/dev/zero").exists() {
            let e = read_text_capped(Path::new("/dev/zero"), CAP_TABLE).unwrap_err();
            assert!(is_refusal(&e), "{e}");
            let e = read_capped(Path::new("/dev/zero"), 1 << 20).unwrap_err();
            assert_eq!(e.kind(), std::io::ErrorKind::FileTooLarge);
        }
    }

    #[test]
    fn utf16_with_a_mark_is_decoded_and_without_one_named() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f");
        let mut le = vec![0xFF, 0xFE];
        le.extend("t,x\n1,2\n".encode_utf16().flat_map(u16::to_le_bytes));
        std::fs::write(&p, &le).unwrap();
        assert_eq!(read_text_capped(&p, 1 << 20).unwrap(), "t,x\n1,2\n");
        let mut be = vec![0xFE, 0xFF];
        be.extend("a\u{e4}".encode_utf16().flat_map(u16::to_be_bytes));
        std::fs::write(&p, &be).unwrap();
        assert_eq!(read_text_capped(&p, 1 << 20).unwrap(), "a\u{e4}");
        std::fs::write(&p, &le[2..]).unwrap();
        let e = read_text_capped(&p, 1 << 20).unwrap_err().to_string();
        assert!(e.contains("UTF-16"), "{e}");
    }

    #[test]
    fn a_file_over_its_cap_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f");
        std::fs::write(&p, "abcdef").unwrap();
        assert_eq!(read_text_capped(&p, 6).unwrap(), "abcdef");
        assert!(is_refusal(&read_text_capped(&p, 5).unwrap_err()));
    }
}
