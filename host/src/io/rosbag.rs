//! Joint logs from ROS 2 bags (rosbag2, MCAP storage): the `sensor_msgs/msg/JointState`
//! messages of one topic, joints taken by name (FORMATS.md "The robot's own ecosystem").
//!
//! * A path is an `.mcap` file, or a rosbag2 directory whose `metadata.yaml` lists its `.mcap`
//!   files (`relative_file_paths`, read in order); the metadata's message count of the topic is
//!   used to say how many messages a damaged file lost.
//! * The file is streamed (the `mcap` crate's sans-I/O [`LinearReader`] fed from the file in
//!   blocks): memory holds one record (a chunk) at a time, whatever the length of the bag; each
//!   wanted joint vector is handed to the caller's function and nothing else is kept.
//! * Chunks are decompressed here (`zstd`: `ruzstd`, `lz4`: `lz4_flex`, pure Rust) and their
//!   CRC checked (when the writer stored one) before any message of the chunk is used; a chunk
//!   that fails is skipped and counted, and reading goes on with the next one. A file cut short
//!   (or whose record structure breaks) is read up to the last intact record; what follows is
//!   reported in [`BagDamage`] (bytes lost, messages lost when the metadata knows the count),
//!   as `daq::salvage` does for recordings.
//! * Each message: `t` = header stamp minus the topic's first message's stamp (s); positions rad
//!   -> deg (m -> mm for prismatic joints); joints the caller does not ask for are ignored; a
//!   message that lacks one of them (or holds a non-finite value for it) is skipped and
//!   counted. Messages on other topics are not decoded.

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use mcap::records::Record;
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};

use crate::error::{Classify, ErrorKind};

mod chunk;
mod messages;
mod metadata;

use chunk::{unchunk, ChunkRecords};
use messages::{Channels, State};
use metadata::bag_files;
pub use metadata::parse_metadata;

/// The ROS 2 type of a joint log message.
pub const JOINT_STATE_TYPE: &str = "sensor_msgs/msg/JointState";

/// Default topic of a joint log.
pub const DEFAULT_JOINT_TOPIC: &str = "/joint_states";

/// The largest record (a chunk, decompressed) read into memory: bounds memory on hostile input.
const MAX_RECORD_BYTES: usize = 256 << 20;

/// Bytes read from the file per request at most.
const READ_BLOCK: usize = 1 << 20;

/// Whether `path` is to be read as a ROS 2 bag (an `.mcap` file, or a directory with a
/// `metadata.yaml`) rather than as a CSV table.
pub fn is_bag(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
        || (path.is_dir() && path.join("metadata.yaml").is_file())
}

/// What to take from a bag.
#[derive(Debug, Clone, Copy)]
pub struct JointLogSpec<'a> {
    /// The topic of the `JointState` messages.
    pub topic: &'a str,
    /// The joints wanted, in the order of the returned vectors.
    pub names: &'a [String],
    /// Per wanted joint: prismatic (position in m, returned in mm) or revolute (rad -> deg).
    pub prismatic: &'a [bool],
}

/// One used message.
#[derive(Debug, Clone, PartialEq)]
pub struct JointReading {
    /// 1-based number of the message among the topic's messages (for messages).
    pub message: u64,
    /// Header stamp minus the stamp of the topic's first (decodable) message, s.
    pub t_s: f64,
    /// The wanted joints' positions, deg (mm for prismatic joints).
    pub q: Vec<f64>,
}

/// The part of a bag that could not be read.
#[derive(Debug, Clone, PartialEq)]
pub struct BagDamage {
    /// The `.mcap` file.
    pub file: PathBuf,
    /// What stopped the reading (the MCAP reader's words).
    pub reason: String,
    /// End of the last intact record (bytes from the start of the file): what follows is lost.
    pub intact_bytes: u64,
    /// Size of the file.
    pub file_bytes: u64,
    /// Messages on the topic that the bag's `metadata.yaml` counts, when known.
    pub expected_messages: Option<u64>,
    /// Messages on the topic read before the damage (all files).
    pub messages_read: u64,
}

impl BagDamage {
    /// Messages on the topic lost, when the metadata says how many there were.
    pub fn messages_lost(&self) -> Option<u64> {
        self.expected_messages
            .map(|n| n.saturating_sub(self.messages_read))
    }
}

impl std::fmt::Display for BagDamage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}: damaged or cut short ({}); intact up to byte {} of {}, the {} bytes after it \
             are lost; ",
            self.file.display(),
            self.reason,
            self.intact_bytes,
            self.file_bytes,
            self.file_bytes.saturating_sub(self.intact_bytes)
        )?;
        match self.messages_lost() {
            Some(lost) => write!(
                f,
                "{lost} of the {} messages the metadata counts lost",
                self.expected_messages.unwrap_or(0)
            ),
            None => write!(
                f,
                "{} messages read, how many followed is unknown (no metadata.yaml)",
                self.messages_read
            ),
        }
    }
}

/// What a bag held and what was used.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BagSummary {
    /// The `.mcap` files read, in order.
    pub files: Vec<PathBuf>,
    /// `JointState` messages on the topic.
    pub topic_messages: u64,
    /// Messages handed to the caller.
    pub used: u64,
    /// Messages skipped because they lack a wanted joint (or its position is not finite).
    pub skipped_missing: u64,
    /// The first such message: (message number, joint name).
    pub first_missing: Option<(u64, String)>,
    /// Messages on the topic that do not decode as `JointState` (skipped).
    pub undecodable: u64,
    /// The first such message and why.
    pub first_undecodable: Option<(u64, String)>,
    /// Messages on other topics (ignored).
    pub other_messages: u64,
    /// Chunks skipped as damaged (CRC mismatch, undecodable compression, broken records);
    /// reading goes on after them.
    pub skipped_chunks: u64,
    /// Their bytes (compressed).
    pub skipped_chunk_bytes: u64,
    /// Where the first one was and why.
    pub first_skipped_chunk: Option<String>,
    /// Where the reading stopped early, if it did.
    pub damage: Option<BagDamage>,
    /// Messages on the topic that the bag's `metadata.yaml` counts, when known.
    pub expected_messages: Option<u64>,
}

impl BagSummary {
    /// Lines for stderr about skipped messages and damage (empty for a clean bag whose every
    /// message was used).
    pub fn notes(&self, path: &Path) -> Vec<String> {
        let mut out = Vec::new();
        if self.skipped_missing > 0 {
            let (m, j) = self.first_missing.clone().unwrap_or_default();
            out.push(format!(
                "{}: skipped {} of {} messages that lack a needed joint (first: message {m}, \
                 joint `{j}`)",
                path.display(),
                self.skipped_missing,
                self.topic_messages
            ));
        }
        out.extend(self.damage_notes(path));
        out
    }

    /// The lines about damage only (undecodable messages, skipped chunks, a file cut short):
    /// empty for an intact bag.
    pub fn damage_notes(&self, path: &Path) -> Vec<String> {
        let mut out = Vec::new();
        if self.undecodable > 0 {
            let (m, why) = self.first_undecodable.clone().unwrap_or_default();
            out.push(format!(
                "{}: skipped {} messages that do not decode (first: message {m}: {why})",
                path.display(),
                self.undecodable
            ));
        }
        if self.skipped_chunks > 0 {
            out.push(format!(
                "{}: skipped {} damaged chunk(s), {} bytes (first {})",
                path.display(),
                self.skipped_chunks,
                self.skipped_chunk_bytes,
                self.first_skipped_chunk.clone().unwrap_or_default()
            ));
            if self.damage.is_none() {
                out.push(match self.expected_messages {
                    Some(n) => format!(
                        "{}: {} of the {n} messages the metadata counts lost",
                        path.display(),
                        n.saturating_sub(self.topic_messages)
                    ),
                    None => format!(
                        "{}: how many messages the damaged chunks held is unknown (no \
                         metadata.yaml)",
                        path.display()
                    ),
                });
            }
        }
        if let Some(d) = &self.damage {
            out.push(d.to_string());
        }
        out
    }
}

/// Why a bag cannot be read (all bad input, exit 2).
#[derive(Debug, thiserror::Error)]
pub enum BagError {
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: not an MCAP file ({reason})")]
    NotMcap { path: PathBuf, reason: String },
    #[error("{path}:{line}: {problem}")]
    Metadata {
        path: PathBuf,
        line: usize,
        problem: String,
    },
    #[error("{path}: topic `{topic}` carries `{found}` (encoding `{encoding}`), not {JOINT_STATE_TYPE} in cdr")]
    TopicType {
        path: PathBuf,
        topic: String,
        found: String,
        encoding: String,
    },
    #[error("{path}: no {JOINT_STATE_TYPE} message on topic `{topic}` (topics: {topics}); choose one with --joint-topic")]
    NoMessages {
        path: PathBuf,
        topic: String,
        topics: String,
    },
    #[error("{path}: no message on `{topic}` has all the needed joints ({names}); {skipped} lacked one (first: message {message}, joint `{joint}`); name them with --joint-names")]
    NoneComplete {
        path: PathBuf,
        topic: String,
        names: String,
        skipped: u64,
        message: u64,
        joint: String,
    },
    #[error("{path}: none of the {count} messages on `{topic}` decodes as {JOINT_STATE_TYPE} (first: message {message}: {why})")]
    Undecodable {
        path: PathBuf,
        topic: String,
        count: u64,
        message: u64,
        why: String,
    },
    #[error("{damage}; no usable {JOINT_STATE_TYPE} message on `{topic}` before it")]
    NothingReadable {
        topic: String,
        damage: Box<BagDamage>,
    },
    #[error("{} (--strict refuses a damaged bag)", .0.join("; "))]
    Damaged(Vec<String>),
}

impl Classify for BagError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::BadInput
    }
}

/// Reads the joint log of `path` (see the module doc), handing every used message to `each` in
/// file order; returns what the bag held. An error of `each` stops the reading and is returned.
pub fn read_joint_log<E: From<BagError>>(
    path: &Path,
    spec: &JointLogSpec,
    mut each: impl FnMut(JointReading) -> Result<(), E>,
) -> Result<BagSummary, E> {
    let (files, expected) = bag_files(path, spec.topic)?;
    let mut summary = BagSummary {
        files: files.clone(),
        expected_messages: expected,
        ..Default::default()
    };
    let mut state = State {
        spec,
        first_stamp_ns: None,
        topics: Vec::new(),
    };
    for file in &files {
        if !read_file(file, &mut state, &mut summary, &mut each)? {
            if let Some(d) = &mut summary.damage {
                d.expected_messages = expected;
                d.messages_read = summary.topic_messages;
            }
            break;
        }
    }
    if summary.used == 0 {
        if let Some(damage) = summary.damage {
            return Err(BagError::NothingReadable {
                topic: spec.topic.to_string(),
                damage: Box::new(damage),
            }
            .into());
        }
    }
    if summary.topic_messages == 0 {
        return Err(BagError::NoMessages {
            path: path.to_path_buf(),
            topic: spec.topic.to_string(),
            topics: if state.topics.is_empty() {
                "none".into()
            } else {
                state.topics.join(", ")
            },
        }
        .into());
    }
    if summary.used == 0 && summary.skipped_missing > 0 {
        let (message, joint) = summary.first_missing.clone().unwrap_or_default();
        return Err(BagError::NoneComplete {
            path: path.to_path_buf(),
            topic: spec.topic.to_string(),
            names: spec.names.join(", "),
            skipped: summary.skipped_missing,
            message,
            joint,
        }
        .into());
    }
    if summary.used == 0 {
        let (message, why) = summary.first_undecodable.clone().unwrap_or_default();
        return Err(BagError::Undecodable {
            path: path.to_path_buf(),
            topic: spec.topic.to_string(),
            count: summary.undecodable,
            message,
            why,
        }
        .into());
    }
    Ok(summary)
}

/// Reads one `.mcap` file; `Ok(false)` when it stopped at damage (recorded in `summary`).
fn read_file<E: From<BagError>>(
    file: &Path,
    state: &mut State,
    summary: &mut BagSummary,
    each: &mut impl FnMut(JointReading) -> Result<(), E>,
) -> Result<bool, E> {
    let io_err = |source| BagError::Io {
        path: file.to_path_buf(),
        source,
    };
    let mut f = File::open(file).map_err(io_err)?;
    let file_bytes = f.metadata().map_err(io_err)?.len();
    // Whole chunks come out (decompressed and checked here, one at a time).
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_emit_chunks(true)
            .with_record_length_limit(MAX_RECORD_BYTES),
    );
    // Bytes given to the reader; at a record it has asked for no byte past that record.
    let mut bytes_read = 0u64;
    let mut intact_bytes = 0u64;
    let mut records = 0u64;
    let mut channels = Channels::default();
    let damage = |reason: String, intact_bytes: u64| BagDamage {
        file: file.to_path_buf(),
        reason,
        intact_bytes,
        file_bytes,
        expected_messages: None,
        messages_read: 0,
    };
    while let Some(event) = reader.next_event() {
        let event = match event {
            Ok(e) => e,
            Err(e) => {
                if records == 0 {
                    return Err(BagError::NotMcap {
                        path: file.to_path_buf(),
                        reason: e.to_string(),
                    }
                    .into());
                }
                summary.damage = Some(damage(e.to_string(), intact_bytes));
                return Ok(false);
            }
        };
        match event {
            LinearReadEvent::ReadRequest(need) => {
                let buf = reader.insert(need.clamp(1, READ_BLOCK));
                let n = f.read(buf).map_err(io_err)?;
                reader.notify_read(n);
                bytes_read += n as u64;
            }
            LinearReadEvent::Record { opcode, data } => {
                records += 1;
                let record_start = intact_bytes;
                intact_bytes = bytes_read;
                let record = match mcap::parse_record(opcode, data) {
                    Ok(r) => r,
                    Err(e) => {
                        summary.damage = Some(damage(e.to_string(), record_start));
                        return Ok(false);
                    }
                };
                if let Record::Chunk { header, data } = record {
                    match unchunk(&header, &data) {
                        Ok(inner) => {
                            for r in ChunkRecords(&inner) {
                                match r {
                                    Ok((op, body)) => match mcap::parse_record(op, body) {
                                        Ok(r) => channels.record(r, file, state, summary, each)?,
                                        Err(e) => {
                                            summary.skip_chunk(record_start, &data, e.to_string());
                                            break;
                                        }
                                    },
                                    Err(why) => {
                                        summary.skip_chunk(record_start, &data, why);
                                        break;
                                    }
                                }
                            }
                        }
                        Err(why) => summary.skip_chunk(record_start, &data, why),
                    }
                } else {
                    channels.record(record, file, state, summary, each)?;
                }
            }
        }
    }
    Ok(true)
}

impl BagSummary {
    fn skip_chunk(&mut self, offset: u64, data: &[u8], why: String) {
        self.skipped_chunks += 1;
        self.skipped_chunk_bytes += data.len() as u64;
        if self.first_skipped_chunk.is_none() {
            self.first_skipped_chunk = Some(format!("at byte {offset}: {why}"));
        }
    }
}

#[cfg(test)]
mod tests;
