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

use super::cdr::decode_joint_state;
use crate::error::{Classify, ErrorKind};

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

/// The `.mcap` files of `path` and, for a rosbag2 directory, the message count of `topic` in
/// its metadata.
fn bag_files(path: &Path, topic: &str) -> Result<(Vec<PathBuf>, Option<u64>), BagError> {
    if !path.is_dir() {
        return Ok((vec![path.to_path_buf()], None));
    }
    let meta = path.join("metadata.yaml");
    let text = std::fs::read_to_string(&meta).map_err(|source| BagError::Io {
        path: meta.clone(),
        source,
    })?;
    let (files, count) =
        parse_metadata(&text, topic).map_err(|(line, problem)| BagError::Metadata {
            path: meta.clone(),
            line,
            problem,
        })?;
    Ok((files.into_iter().map(|f| path.join(f)).collect(), count))
}

/// The `relative_file_paths` of a rosbag2 `metadata.yaml` and the `message_count` of `topic`
/// in `topics_with_message_count` (the subset of YAML these files use: block mappings and
/// sequences, plain or quoted scalars). Errors are (1-based line, problem).
pub fn parse_metadata(
    text: &str,
    topic: &str,
) -> Result<(Vec<String>, Option<u64>), (usize, String)> {
    fn indent(l: &str) -> usize {
        l.len() - l.trim_start_matches([' ', '-']).len()
    }
    fn scalar(v: &str) -> String {
        let v = v.trim();
        let unq = v
            .strip_prefix('"')
            .and_then(|s| s.strip_suffix('"'))
            .or_else(|| v.strip_prefix('\'').and_then(|s| s.strip_suffix('\'')));
        unq.unwrap_or(v).to_string()
    }
    let lines: Vec<&str> = text.lines().collect();
    let mut files = Vec::new();
    let mut storage: Option<(usize, String)> = None;
    let mut count = None;
    let mut i = 0;
    while i < lines.len() {
        let l = lines[i];
        let t = l.trim();
        if let Some(v) = t.strip_prefix("storage_identifier:") {
            storage = Some((i + 1, scalar(v)));
        }
        if t == "relative_file_paths:" {
            let base = indent(l);
            i += 1;
            while i < lines.len() {
                let item = lines[i].trim();
                if item.is_empty() {
                    i += 1;
                    continue;
                }
                if indent(lines[i]) <= base && !item.starts_with('-') {
                    break;
                }
                match item.strip_prefix('-') {
                    Some(f) => files.push((i + 1, scalar(f))),
                    None => break,
                }
                i += 1;
            }
            continue;
        }
        if t == "topics_with_message_count:" {
            let base = indent(l);
            // One list item per topic; its keys (`message_count`, `topic_metadata.name`) come
            // in any order.
            let mut item_indent = None;
            let mut item: (Option<String>, Option<(usize, String)>) = (None, None);
            let close = |item: &mut (Option<String>, Option<(usize, String)>)| {
                if let (Some(name), Some((line, v))) = (item.0.take(), item.1.take()) {
                    if name == topic {
                        return Some((line, v));
                    }
                }
                None
            };
            let mut found = None;
            i += 1;
            while i < lines.len() {
                let raw = lines[i];
                let item_text = raw.trim();
                if item_text.is_empty() {
                    i += 1;
                    continue;
                }
                if indent(raw) <= base && !item_text.starts_with('-') {
                    break;
                }
                let lead = raw.len() - raw.trim_start_matches(' ').len();
                if item_text.starts_with('-') && *item_indent.get_or_insert(lead) == lead {
                    if let Some(f) = close(&mut item) {
                        found = Some(f);
                    }
                }
                let key = item_text.trim_start_matches(['-', ' ']);
                if let Some(v) = key.strip_prefix("name:") {
                    item.0 = Some(scalar(v));
                } else if let Some(v) = key.strip_prefix("message_count:") {
                    item.1 = Some((i + 1, scalar(v)));
                }
                i += 1;
            }
            if let Some(f) = close(&mut item) {
                found = Some(f);
            }
            if let Some((line, v)) = found {
                count = Some(
                    v.parse::<u64>()
                        .map_err(|_| (line, format!("message_count `{v}` is not a count")))?,
                );
            }
            continue;
        }
        i += 1;
    }
    if let Some((line, s)) = storage {
        if s != "mcap" {
            return Err((
                line,
                format!("storage `{s}`: only MCAP bags are read (ros2 bag convert writes one)"),
            ));
        }
    }
    if files.is_empty() {
        return Err((
            1,
            "no relative_file_paths: which file holds the bag?".into(),
        ));
    }
    for (line, f) in &files {
        if !f.to_ascii_lowercase().ends_with(".mcap") {
            return Err((
                *line,
                format!("`{f}` is not an .mcap file (only MCAP bags are read)"),
            ));
        }
    }
    Ok((files.into_iter().map(|(_, f)| f).collect(), count))
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

struct State<'s, 'a> {
    spec: &'s JointLogSpec<'a>,
    /// Stamp of the topic's first decodable message, ns.
    first_stamp_ns: Option<i64>,
    /// Every topic seen, for messages.
    topics: Vec<String>,
}

/// The schemas and channels of one file.
#[derive(Default)]
struct Channels {
    /// Per channel id: whether it is the wanted JointState topic.
    wanted: std::collections::HashMap<u16, bool>,
    schemas: std::collections::HashMap<u16, String>,
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

/// The records `opcode, u64 length, body` of a decompressed chunk.
struct ChunkRecords<'a>(&'a [u8]);

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
fn unchunk<'d>(
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

impl BagSummary {
    fn skip_chunk(&mut self, offset: u64, data: &[u8], why: String) {
        self.skipped_chunks += 1;
        self.skipped_chunk_bytes += data.len() as u64;
        if self.first_skipped_chunk.is_none() {
            self.first_skipped_chunk = Some(format!("at byte {offset}: {why}"));
        }
    }
}

impl Channels {
    /// A schema, channel or message record (of the file or of a chunk).
    fn record<E: From<BagError>>(
        &mut self,
        record: Record,
        file: &Path,
        state: &mut State,
        summary: &mut BagSummary,
        each: &mut impl FnMut(JointReading) -> Result<(), E>,
    ) -> Result<(), E> {
        match record {
            Record::Schema { header, .. } => {
                self.schemas.insert(header.id, header.name);
            }
            Record::Channel(c) => {
                if !state.topics.contains(&c.topic) {
                    state.topics.push(c.topic.clone());
                }
                let wanted = c.topic == state.spec.topic;
                if wanted {
                    let found = self.schemas.get(&c.schema_id).cloned().unwrap_or_default();
                    if found != JOINT_STATE_TYPE || c.message_encoding != "cdr" {
                        return Err(BagError::TopicType {
                            path: file.to_path_buf(),
                            topic: c.topic,
                            found,
                            encoding: c.message_encoding,
                        }
                        .into());
                    }
                }
                self.wanted.insert(c.id, wanted);
            }
            Record::Message { header, data } => {
                if self.wanted.get(&header.channel_id) == Some(&true) {
                    summary.topic_messages += 1;
                    message(&data, state, summary, each)?;
                } else {
                    summary.other_messages += 1;
                }
            }
            _ => {}
        }
        Ok(())
    }
}

/// One message of the wanted topic.
fn message<E: From<BagError>>(
    data: &[u8],
    state: &mut State,
    summary: &mut BagSummary,
    each: &mut impl FnMut(JointReading) -> Result<(), E>,
) -> Result<(), E> {
    let n = summary.topic_messages;
    let msg = match decode_joint_state(data) {
        Ok(m) => m,
        Err(e) => {
            summary.undecodable += 1;
            if summary.first_undecodable.is_none() {
                summary.first_undecodable = Some((n, e.to_string()));
            }
            return Ok(());
        }
    };
    // t counts from the first message on the topic (FORMATS.md), used or not.
    let stamp = msg.stamp_ns();
    let first = *state.first_stamp_ns.get_or_insert(stamp);
    let spec = state.spec;
    let mut q = Vec::with_capacity(spec.names.len());
    for (k, name) in spec.names.iter().enumerate() {
        let v = msg
            .names
            .iter()
            .position(|m| m == name)
            .and_then(|i| msg.position.get(i))
            .copied()
            .filter(|v| v.is_finite());
        match v {
            Some(v) => q.push(if spec.prismatic.get(k).copied().unwrap_or(false) {
                v * 1e3
            } else {
                v.to_degrees()
            }),
            None => {
                summary.skipped_missing += 1;
                if summary.first_missing.is_none() {
                    summary.first_missing = Some((n, name.clone()));
                }
                return Ok(());
            }
        }
    }
    summary.used += 1;
    each(JointReading {
        message: n,
        t_s: (stamp - first) as f64 / 1e9,
        q,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const METADATA: &str = "rosbag2_bagfile_information:
  version: 8
  storage_identifier: mcap
  message_count: 12
  topics_with_message_count:
    - topic_metadata:
        name: /other
        type: std_msgs/msg/String
        serialization_format: cdr
        offered_qos_profiles: ''
      message_count: 2
    - topic_metadata:
        name: /joint_states
        type: sensor_msgs/msg/JointState
        serialization_format: cdr
        offered_qos_profiles: \"\"
      message_count: 10
  compression_format: ''
  relative_file_paths:
    - session_0.mcap
    - 'session_1.mcap'
  files:
    - path: session_0.mcap
      message_count: 12
";

    #[test]
    fn metadata_files_and_topic_count() {
        let (files, n) = parse_metadata(METADATA, "/joint_states").unwrap();
        assert_eq!(files, ["session_0.mcap", "session_1.mcap"]);
        assert_eq!(n, Some(10));
        let (_, n) = parse_metadata(METADATA, "/other").unwrap();
        assert_eq!(n, Some(2));
        let (_, n) = parse_metadata(METADATA, "/absent").unwrap();
        assert_eq!(n, None);
    }

    /// rosbags writes the keys sorted: an item's count before its topic's name.
    #[test]
    fn metadata_count_before_name() {
        let text = "rosbag2_bagfile_information:
  files:
  - message_count: 99
    path: b.mcap
  relative_file_paths:
  - b.mcap
  storage_identifier: mcap
  topics_with_message_count:
  - message_count: 7
    topic_metadata:
      name: /other
      type: std_msgs/msg/String
  - message_count: 1348
    topic_metadata:
      name: /joint_states
      type_description_hash: 
        RIHS01_a13e
      type: sensor_msgs/msg/JointState
  version: 8
";
        let (files, n) = parse_metadata(text, "/joint_states").unwrap();
        assert_eq!(files, ["b.mcap"]);
        assert_eq!(n, Some(1348));
        assert_eq!(parse_metadata(text, "/other").unwrap().1, Some(7));
    }

    #[test]
    fn metadata_refuses_sqlite_and_no_files() {
        let sqlite = METADATA.replace("storage_identifier: mcap", "storage_identifier: sqlite3");
        assert_eq!(parse_metadata(&sqlite, "/x").unwrap_err().0, 3);
        let none = "rosbag2_bagfile_information:\n  version: 8\n";
        assert!(parse_metadata(none, "/x").is_err());
        let db3 = METADATA.replace("session_0.mcap\n    - 'session_1.mcap'", "bag.db3");
        let err = parse_metadata(&db3, "/x").unwrap_err();
        assert!(err.1.contains("bag.db3"), "{err:?}");
    }

    /// An MCAP file of `n` JointState messages (joints `a`, `b`; `a` = 0.001 k rad) in
    /// uncompressed chunks of about 2 kB with CRCs, written by the `mcap` crate.
    fn bag_bytes(n: u32) -> Vec<u8> {
        let mut buf = std::io::Cursor::new(Vec::new());
        let mut w = mcap::WriteOptions::new()
            .compression(None)
            .chunk_size(Some(2000))
            .create(&mut buf)
            .unwrap();
        let schema = w.add_schema(JOINT_STATE_TYPE, "ros2msg", b"").unwrap();
        let ch = w
            .add_channel(schema, "/joint_states", "cdr", &Default::default())
            .unwrap();
        for k in 0..n {
            let m = crate::io::cdr::JointState {
                sec: 10,
                nanosec: k * 1000,
                frame_id: String::new(),
                names: vec!["b".into(), "a".into()],
                position: vec![-0.2, 0.001 * f64::from(k)],
            };
            let header = mcap::records::MessageHeader {
                channel_id: ch,
                sequence: k,
                log_time: u64::from(k),
                publish_time: u64::from(k),
            };
            w.write_to_known_channel(&header, &crate::io::cdr::encode_joint_state(&m))
                .unwrap();
        }
        w.finish().unwrap();
        drop(w);
        buf.into_inner()
    }

    fn read(bytes: &[u8]) -> Result<(BagSummary, Vec<JointReading>), BagError> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("b.mcap");
        std::fs::write(&path, bytes).unwrap();
        let names = ["a".to_string()];
        let spec = JointLogSpec {
            topic: DEFAULT_JOINT_TOPIC,
            names: &names,
            prismatic: &[false],
        };
        let mut got = Vec::new();
        let summary = read_joint_log(&path, &spec, |r| {
            got.push(r);
            Ok::<(), BagError>(())
        })?;
        Ok((summary, got))
    }

    #[test]
    fn reads_every_message_by_name() {
        let (summary, got) = read(&bag_bytes(100)).unwrap();
        assert_eq!(summary.used, 100);
        assert!(summary.notes(Path::new("b")).is_empty());
        for (k, r) in got.iter().enumerate() {
            assert_eq!(r.message, k as u64 + 1);
            assert!((r.t_s - k as f64 * 1e-6).abs() < 1e-15);
            assert!((r.q[0] - (0.001 * k as f64).to_degrees()).abs() < 1e-12);
        }
    }

    #[test]
    fn a_chunk_with_a_bad_crc_is_skipped_and_reading_goes_on() {
        let mut bytes = bag_bytes(100);
        // Flip a byte of message 50's position `a` (0.05 rad): its chunk's CRC no longer holds.
        let needle = 0.05f64.to_le_bytes();
        let at = bytes
            .windows(8)
            .position(|w| w == needle)
            .expect("message 50 is in the file");
        bytes[at] ^= 0x01;
        let (summary, got) = read(&bytes).unwrap();
        assert_eq!(summary.skipped_chunks, 1);
        assert!(summary.damage.is_none());
        assert!(got.len() < 100 && got.len() > 50, "{}", got.len());
        assert!(got
            .iter()
            .all(|r| (r.q[0] - 0.05f64.to_degrees()).abs() > 1e-9));
        // Messages after the skipped chunk are read.
        assert!((got.last().unwrap().q[0] - 0.099f64.to_degrees()).abs() < 1e-12);
        let notes = summary.notes(Path::new("b")).join("\n");
        assert!(notes.contains("skipped 1 damaged chunk(s)"), "{notes}");
        assert!(notes.contains("CRC"), "{notes}");
    }

    #[test]
    fn every_cut_reads_a_prefix_or_refuses() {
        let bytes = bag_bytes(60);
        let (_, all) = read(&bytes).unwrap();
        for cut in (0..bytes.len()).step_by(37) {
            match read(&bytes[..cut]) {
                Ok((summary, got)) => {
                    assert!(summary.damage.is_some(), "cut at {cut}");
                    assert_eq!(got[..], all[..got.len()], "cut at {cut}");
                }
                Err(e) => assert!(
                    matches!(
                        e,
                        BagError::NotMcap { .. } | BagError::NothingReadable { .. }
                    ),
                    "cut at {cut}: {e}"
                ),
            }
        }
    }

    #[test]
    fn bag_paths() {
        assert!(is_bag(Path::new("a/b.mcap")));
        assert!(is_bag(Path::new("a/b.MCAP")));
        assert!(!is_bag(Path::new("a/b.csv")));
    }
}
