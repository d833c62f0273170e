//! The recording file written by `rigctl record` and read by `rigctl export`.
//!
//! # Layout (format version 1)
//!
//! ```text
//! RIGREC 1\n                      magic and format version, ASCII
//! {"protocol_version":1,...}\n    one line of JSON: [`RecordingMeta`]
//! record*                         append-only, until the end of the file
//! ```
//!
//! Each record is one complete frame exactly as it arrived on the link (the COBS-encoded bytes
//! between two `0x00` delimiters, delimiters excluded), prefixed by its length and the host's
//! receive time:
//!
//! | bytes | type | meaning |
//! |---|---|---|
//! | 4 | `u32` little-endian | `len`: number of frame bytes, 1 ..= [`MAX_FRAME_LEN`] |
//! | 8 | `u64` little-endian | `host_rx_us`: host monotonic time of reception, microseconds since [`RecordingMeta::start_time_unix_us`] |
//! | `len` | bytes | the frame |
//!
//! Only frames that decoded (CRC correct) are recorded; the frame's own CRC stays inside the
//! stored bytes, so a reader can check every record again.
//!
//! # Crash safety
//!
//! The recording is deliberately *not* written under a temporary name (unlike every other output
//! of `rigctl`): it is a log whose prefix is valuable. Each record is handed to the operating
//! system with one `write` as soon as its frame is decoded, and the file is `fsync`ed about once
//! per second and at the end. A crash of `rigctl`, an unplugged board or a killed process
//! therefore loses no complete frame that had reached the host; a power cut loses at most the last
//! second. A record cut short by such an event is the only damage possible, and the reader
//! tolerates it: [`parse_recording`] returns every complete record and reports the length of the
//! incomplete tail in [`Recording::truncated_tail_bytes`].
//!
//! Damage inside the file (a flipped byte on disk) is handled by [`super::salvage`]: the damaged
//! record is recognised by its frame's CRC, skipped and reported, and reading resynchronises on
//! the next record; `export`, `fuse` and `potcal` read recordings that way.

use serde::{Deserialize, Serialize};
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// First bytes of every recording, up to the version number.
pub const MAGIC: &[u8] = b"RIGREC ";
/// The format version this module writes (and the only one it reads).
pub const FORMAT_VERSION: u32 = 1;
/// Largest frame a record may hold; a larger length prefix means the file is corrupt.
pub const MAX_FRAME_LEN: usize = 4096;
/// Longest accepted metadata line, bytes.
const MAX_HEADER_LEN: usize = 64 * 1024;
/// Bytes before a record's frame: length + receive time.
pub const RECORD_PREFIX_LEN: usize = 4 + 8;
/// How often the writer asks the OS to put the file on disk.
const SYNC_INTERVAL: Duration = Duration::from_secs(1);

/// The metadata line of a recording. Unknown keys are ignored when reading, so later versions of
/// `rigctl` may add keys without bumping [`FORMAT_VERSION`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordingMeta {
    /// Wire protocol version the host spoke (`rig_protocol::PROTOCOL_VERSION`).
    pub protocol_version: u16,
    /// Serial port (or pseudo-terminal) the frames came from.
    pub port: String,
    /// Host wall-clock time at `host_rx_us == 0`, microseconds since the Unix epoch.
    pub start_time_unix_us: u64,
    /// Potentiometer sample rate requested in `Start`, Hz.
    pub pot_rate_hz: u32,
    /// Inclinometer reading rate requested in `Start` (per sensor), Hz.
    pub tilt_rate_hz: u32,
    /// The board's `Hello`, when one was received before recording started.
    pub hello: Option<HelloMeta>,
    /// Version of the `rigctl` that wrote the file.
    pub rigctl_version: String,
}

/// The board's `Hello` in a readable form.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct HelloMeta {
    pub protocol_version: u16,
    /// `"major.minor.patch"`.
    pub firmware_version: String,
    /// The MCU's unique id, lowercase hex.
    pub board_id: String,
    pub schema_hash: u32,
    pub tilt_sensors: u8,
}

impl From<&rig_protocol::Hello> for HelloMeta {
    fn from(h: &rig_protocol::Hello) -> Self {
        let [major, minor, patch] = h.firmware_version;
        Self {
            protocol_version: h.protocol_version,
            firmware_version: format!("{major}.{minor}.{patch}"),
            board_id: h.board_id.iter().map(|b| format!("{b:02x}")).collect(),
            schema_hash: h.schema_hash,
            tilt_sensors: h.tilt_sensors,
        }
    }
}

/// One stored frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Record {
    /// Host receive time, microseconds since [`RecordingMeta::start_time_unix_us`].
    pub host_rx_us: u64,
    /// The frame as received (COBS-encoded, no delimiter).
    pub frame: Vec<u8>,
}

/// A whole recording in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    pub meta: RecordingMeta,
    pub records: Vec<Record>,
    /// Bytes at the end of the file that do not form a complete record (a run cut short); 0 for a
    /// cleanly closed file.
    pub truncated_tail_bytes: usize,
}

/// What can go wrong with a recording file.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    #[error("cannot open recording {path}: {source}")]
    Open {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path} already exists (pass --overwrite to replace it)")]
    Exists { path: PathBuf },
    #[error("{path} is being written by another process (another `rigctl record`?): refusing a second writer")]
    Busy { path: PathBuf },
    #[error("cannot write recording {path}: {source}")]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: not a rigctl recording (no `RIGREC` magic)")]
    NotARecording { path: PathBuf },
    #[error("{path}: recording format version {version} is not supported (this rigctl reads {FORMAT_VERSION})")]
    UnsupportedVersion { path: PathBuf, version: String },
    #[error("{path}: bad header: {reason}")]
    BadHeader { path: PathBuf, reason: String },
    #[error(
        "{path}: corrupt record at byte {offset}: frame length {len} outside 1..={MAX_FRAME_LEN}"
    )]
    CorruptRecord {
        path: PathBuf,
        offset: usize,
        len: u64,
    },
    #[error("{path}: damaged record at byte {offset} (frame does not decode; without --strict it is skipped and reported)")]
    Damaged { path: PathBuf, offset: usize },
}

impl crate::error::Classify for RecordingError {
    fn kind(&self) -> crate::error::ErrorKind {
        use crate::error::ErrorKind;
        match self {
            Self::Write { .. } => ErrorKind::Failure,
            Self::Open { .. }
            | Self::Exists { .. }
            | Self::Busy { .. }
            | Self::NotARecording { .. }
            | Self::UnsupportedVersion { .. }
            | Self::BadHeader { .. }
            | Self::CorruptRecord { .. }
            | Self::Damaged { .. } => ErrorKind::BadInput,
        }
    }
}

/// Appends records to a new recording file; see the module documentation for the guarantees.
#[derive(Debug)]
pub struct RecordingWriter {
    file: File,
    path: PathBuf,
    last_sync: Instant,
    buf: Vec<u8>,
    records: u64,
}

impl RecordingWriter {
    /// Creates `path` and writes the header. Refuses an existing file unless `overwrite`.
    pub fn create(
        path: &Path,
        meta: &RecordingMeta,
        overwrite: bool,
    ) -> Result<Self, RecordingError> {
        let mut opts = OpenOptions::new();
        opts.write(true);
        if overwrite {
            opts.create(true).truncate(true);
        } else {
            opts.create_new(true);
        }
        let file = opts.open(path).map_err(|source| {
            if source.kind() == std::io::ErrorKind::AlreadyExists {
                RecordingError::Exists {
                    path: path.to_path_buf(),
                }
            } else {
                RecordingError::Open {
                    path: path.to_path_buf(),
                    source,
                }
            }
        })?;
        Self::with_file(file, path, meta)
    }

    /// Writes the header into `file` (already opened, for example locked by
    /// [`super::rec_file::open`]) and returns the writer; `path` names it in messages.
    pub fn with_file(
        file: File,
        path: &Path,
        meta: &RecordingMeta,
    ) -> Result<Self, RecordingError> {
        let mut writer = Self {
            file,
            path: path.to_path_buf(),
            last_sync: Instant::now(),
            buf: Vec::with_capacity(MAX_FRAME_LEN + RECORD_PREFIX_LEN),
            records: 0,
        };
        writer.buf.extend_from_slice(&header_bytes(meta));
        writer.write_buf()?;
        writer.sync()?;
        Ok(writer)
    }

    /// Appends one frame with one `write` call (so it is in the OS's hands when this returns);
    /// syncs to disk when the last sync is more than a second old.
    pub fn append(&mut self, host_rx_us: u64, frame: &[u8]) -> Result<(), RecordingError> {
        if frame.is_empty() || frame.len() > MAX_FRAME_LEN {
            return Err(RecordingError::Write {
                path: self.path.clone(),
                source: std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    format!("frame of {} bytes cannot be recorded", frame.len()),
                ),
            });
        }
        self.buf.clear();
        // `frame.len() <= MAX_FRAME_LEN` fits in a u32.
        self.buf
            .extend_from_slice(&(frame.len() as u32).to_le_bytes());
        self.buf.extend_from_slice(&host_rx_us.to_le_bytes());
        self.buf.extend_from_slice(frame);
        self.write_buf()?;
        self.records += 1;
        if self.last_sync.elapsed() >= SYNC_INTERVAL {
            self.sync()?;
        }
        Ok(())
    }

    /// Records appended so far.
    pub fn records(&self) -> u64 {
        self.records
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Syncs the file to disk and closes it.
    pub fn finish(mut self) -> Result<(), RecordingError> {
        self.sync()
    }

    fn write_buf(&mut self) -> Result<(), RecordingError> {
        self.file
            .write_all(&self.buf)
            .map_err(|source| RecordingError::Write {
                path: self.path.clone(),
                source,
            })
    }

    fn sync(&mut self) -> Result<(), RecordingError> {
        self.last_sync = Instant::now();
        self.file
            .sync_data()
            .map_err(|source| RecordingError::Write {
                path: self.path.clone(),
                source,
            })
    }
}

/// The header: magic, version, metadata line.
pub fn header_bytes(meta: &RecordingMeta) -> Vec<u8> {
    let mut out = Vec::with_capacity(256);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(format!("{FORMAT_VERSION}\n").as_bytes());
    // Serializing a struct of strings and integers to JSON cannot fail.
    out.extend_from_slice(serde_json::to_string(meta).unwrap_or_default().as_bytes());
    out.push(b'\n');
    out
}

/// Reads a whole recording file.
pub fn read_recording(path: &Path) -> Result<Recording, RecordingError> {
    let bytes = crate::io::read::read_capped_magic(path, crate::io::read::CAP_RECORDING, MAGIC)
        .map_err(|source| RecordingError::Open {
            path: path.to_path_buf(),
            source,
        })?;
    parse_recording(path, &bytes)
}

/// Parses the bytes of a recording (`path` only names the file in errors). Never panics: a
/// truncated last record is reported in [`Recording::truncated_tail_bytes`]; a truncated header is
/// an error.
pub fn parse_recording(path: &Path, bytes: &[u8]) -> Result<Recording, RecordingError> {
    let (meta, header_len) = parse_header(path, bytes)?;
    let body = &bytes[header_len..];
    let mut records = Vec::new();
    let mut pos = 0usize;
    while body.len() - pos >= RECORD_PREFIX_LEN {
        let len_bytes: [u8; 4] = read_array(body, pos);
        let len = u32::from_le_bytes(len_bytes) as usize;
        if len == 0 || len > MAX_FRAME_LEN {
            return Err(RecordingError::CorruptRecord {
                path: path.to_path_buf(),
                offset: header_len + pos,
                len: len as u64,
            });
        }
        let frame_start = pos + RECORD_PREFIX_LEN;
        if body.len() - frame_start < len {
            break;
        }
        let host_rx_us = u64::from_le_bytes(read_array(body, pos + 4));
        records.push(Record {
            host_rx_us,
            frame: body[frame_start..frame_start + len].to_vec(),
        });
        pos = frame_start + len;
    }
    Ok(Recording {
        meta,
        records,
        truncated_tail_bytes: body.len() - pos,
    })
}

/// Parses the magic, version and metadata lines; returns the metadata and the header's length.
/// Lines may end in CRLF (a file that went through a text-mode transfer).
pub fn parse_header(path: &Path, bytes: &[u8]) -> Result<(RecordingMeta, usize), RecordingError> {
    let bad_header = |reason: String| RecordingError::BadHeader {
        path: path.to_path_buf(),
        reason,
    };
    if !bytes.starts_with(MAGIC) {
        return Err(RecordingError::NotARecording {
            path: path.to_path_buf(),
        });
    }
    let (version_line, rest) = split_line(&bytes[MAGIC.len()..], 16)
        .ok_or_else(|| bad_header("the version line is incomplete".into()))?;
    let version = String::from_utf8_lossy(version_line).into_owned();
    if version != FORMAT_VERSION.to_string() {
        return Err(RecordingError::UnsupportedVersion {
            path: path.to_path_buf(),
            version: version.escape_debug().to_string(),
        });
    }
    let (meta_line, body) = split_line(rest, MAX_HEADER_LEN)
        .ok_or_else(|| bad_header("the metadata line is incomplete".into()))?;
    let meta: RecordingMeta =
        serde_json::from_slice(meta_line).map_err(|e| bad_header(format!("metadata JSON: {e}")))?;
    Ok((meta, bytes.len() - body.len()))
}

/// Splits off the first `\n`-terminated line (without the `\n`) if it ends within `max` bytes.
fn split_line(bytes: &[u8], max: usize) -> Option<(&[u8], &[u8])> {
    let end = bytes.iter().take(max).position(|&b| b == b'\n')?;
    let line = &bytes[..end];
    let line = line.strip_suffix(b"\r").unwrap_or(line);
    Some((line, &bytes[end + 1..]))
}

/// `N` bytes at `pos`; the caller has checked that they exist.
pub(crate) fn read_array<const N: usize>(bytes: &[u8], pos: usize) -> [u8; N] {
    let mut out = [0u8; N];
    out.copy_from_slice(&bytes[pos..pos + N]);
    out
}

#[cfg(test)]
mod tests;
