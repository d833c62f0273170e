//! The rosbag2 `metadata.yaml` of a bag directory: its `.mcap` files (`relative_file_paths`, in
//! order) and the message count of a topic (`topics_with_message_count`), read from the subset
//! of YAML these files use (block mappings and sequences, plain or quoted scalars).

use std::path::{Path, PathBuf};

use super::BagError;

/// The `.mcap` files of `path` and, for a rosbag2 directory, the message count of `topic` in
/// its metadata.
pub(super) fn bag_files(path: &Path, topic: &str) -> Result<(Vec<PathBuf>, Option<u64>), BagError> {
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
            i = file_paths(&lines, i, &mut files);
        } else if t == "topics_with_message_count:" {
            let (next, found) = topic_message_count(&lines, i, topic)?;
            i = next;
            if found.is_some() {
                count = found;
            }
        } else {
            i += 1;
        }
    }
    checked_files(storage, files).map(|files| (files, count))
}

/// The indentation of a line, list dashes included.
fn indent(l: &str) -> usize {
    l.len() - l.trim_start_matches([' ', '-']).len()
}

/// A plain or quoted scalar.
fn scalar(v: &str) -> String {
    let v = v.trim();
    let unq = v
        .strip_prefix('"')
        .and_then(|s| s.strip_suffix('"'))
        .or_else(|| v.strip_prefix('\'').and_then(|s| s.strip_suffix('\'')));
    unq.unwrap_or(v).to_string()
}

/// The list under the key `relative_file_paths:` at line index `start`, appended to `files` as
/// (1-based line, path); returns the index of the first line after it.
fn file_paths(lines: &[&str], start: usize, files: &mut Vec<(usize, String)>) -> usize {
    let base = indent(lines[start]);
    let mut i = start + 1;
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
    i
}

/// The `message_count` of `topic` in the list under the key `topics_with_message_count:` at line
/// index `start` (`None` when the topic is not listed); returns the index of the first line
/// after the list too.
fn topic_message_count(
    lines: &[&str],
    start: usize,
    topic: &str,
) -> Result<(usize, Option<u64>), (usize, String)> {
    let base = indent(lines[start]);
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
    let mut i = start + 1;
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
    let count = match found {
        Some((line, v)) => Some(
            v.parse::<u64>()
                .map_err(|_| (line, format!("message_count `{v}` is not a count")))?,
        ),
        None => None,
    };
    Ok((i, count))
}

/// The files, when the storage is MCAP (or not said), there is at least one and each is an
/// `.mcap` file.
fn checked_files(
    storage: Option<(usize, String)>,
    files: Vec<(usize, String)>,
) -> Result<Vec<String>, (usize, String)> {
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
    Ok(files.into_iter().map(|(_, f)| f).collect())
}
