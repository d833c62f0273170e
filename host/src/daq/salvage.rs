//! Reading a recording that may be damaged (a flipped byte on disk, a bad sector, a copy cut
//! short): every stored frame carries its own CRC-32, so a damaged record is recognised, skipped,
//! and the reader resynchronises on the next record whose length prefix is plausible and whose
//! frame decodes with a valid CRC. What was skipped is reported (file offset, bytes, records
//! seen on either side, potentiometer samples lost on the time grid), so `export`, `fuse` and
//! `potcal --recording` go on with the intact part; with `strict` the first damage is an error.

use std::path::Path;

use rig_protocol::DeviceMsg;

use super::link::decode_stored;
use super::recording::{
    parse_header, read_array, RecordingError, RecordingMeta, MAX_FRAME_LEN, RECORD_PREFIX_LEN,
};

/// One stretch of bytes that held no decodable record.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DamagedRegion {
    /// File offset of the first skipped byte.
    pub offset: usize,
    /// Bytes skipped.
    pub bytes: usize,
    /// Good records before the damage.
    pub after_record: usize,
    /// Potentiometer samples missing on the time grid across the damage (0 when no pot batch
    /// is on both sides).
    pub pot_samples_lost: u64,
}

impl std::fmt::Display for DamagedRegion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} damaged bytes at offset {} (after record {}), {} potentiometer samples lost",
            self.bytes, self.offset, self.after_record, self.pot_samples_lost
        )
    }
}

/// The decodable content of a recording and what could not be read.
#[derive(Debug, Clone, PartialEq)]
pub struct SalvagedRecording {
    pub meta: RecordingMeta,
    /// Decoded frames with their host receive times, in file order.
    pub frames: Vec<(u64, DeviceMsg)>,
    /// Damaged stretches that were skipped, in file order.
    pub damaged: Vec<DamagedRegion>,
    /// Bytes of an incomplete last record (a run cut short), ignored.
    pub truncated_tail_bytes: usize,
}

impl SalvagedRecording {
    /// Total bytes skipped as damaged.
    pub fn damaged_bytes(&self) -> usize {
        self.damaged.iter().map(|d| d.bytes).sum()
    }

    /// Total potentiometer samples lost in damaged stretches.
    pub fn pot_samples_lost(&self) -> u64 {
        self.damaged.iter().map(|d| d.pot_samples_lost).sum()
    }

    /// One line for stderr, `None` for an undamaged file.
    pub fn damage_note(&self, path: &Path) -> Option<String> {
        if self.damaged.is_empty() {
            return None;
        }
        let first = &self.damaged[0];
        Some(format!(
            "{}: skipped {} damaged region(s), {} bytes, {} potentiometer samples lost; first: {first}",
            path.display(),
            self.damaged.len(),
            self.damaged_bytes(),
            self.pot_samples_lost()
        ))
    }
}

/// Reads and salvages the recording at `path`.
pub fn read_salvaged(path: &Path, strict: bool) -> Result<SalvagedRecording, RecordingError> {
    let bytes = crate::io::read::read_capped_magic(
        path,
        crate::io::read::CAP_RECORDING,
        crate::daq::recording::MAGIC,
    )
    .map_err(|source| RecordingError::Open {
        path: path.to_path_buf(),
        source,
    })?;
    salvage(path, &bytes, strict)
}

/// The record at `pos` of `body` if it is complete and its frame decodes: (receive time,
/// message, end).
fn record_at(body: &[u8], pos: usize) -> Option<(u64, DeviceMsg, usize)> {
    if body.len() - pos < RECORD_PREFIX_LEN {
        return None;
    }
    let len = u32::from_le_bytes(read_array(body, pos)) as usize;
    let start = pos + RECORD_PREFIX_LEN;
    if len == 0 || len > MAX_FRAME_LEN || body.len() - start < len {
        return None;
    }
    let msg = decode_stored(&body[start..start + len]).ok()?;
    Some((
        u64::from_le_bytes(read_array(body, pos + 4)),
        msg,
        start + len,
    ))
}

/// Whether the bytes at `pos` look like the start of a record cut short by the end of the file.
fn truncated_at(body: &[u8], pos: usize) -> bool {
    let rest = body.len() - pos;
    if rest < RECORD_PREFIX_LEN {
        return true;
    }
    let len = u32::from_le_bytes(read_array(body, pos)) as usize;
    (1..=MAX_FRAME_LEN).contains(&len) && rest < RECORD_PREFIX_LEN + len
}

/// Where the next pot sample is due after the last pot batch among `frames`, and its period.
fn pot_grid_end(frames: &[(u64, DeviceMsg)]) -> Option<(u64, u64)> {
    frames.iter().rev().find_map(|(_, m)| match m {
        DeviceMsg::Pot(b) => {
            let period = u64::from(b.period_us.max(1));
            Some((b.t0_us + b.samples.len() as u64 * period, period))
        }
        _ => None,
    })
}

/// Parses `bytes` (see the module documentation); `path` names the file in messages.
pub fn salvage(
    path: &Path,
    bytes: &[u8],
    strict: bool,
) -> Result<SalvagedRecording, RecordingError> {
    let (meta, header_len) = parse_header(path, bytes)?;
    let body = &bytes[header_len..];
    let mut frames = Vec::new();
    let mut damaged = Vec::new();
    let mut pending: Option<(usize, Option<(u64, u64)>)> = None; // damage start, pot grid end
    let mut open_loss: Option<(usize, (u64, u64))> = None; // region index, pot grid end
    let mut pos = 0;
    let mut truncated_tail_bytes = 0;
    while pos < body.len() {
        if let Some((rx, msg, end)) = record_at(body, pos) {
            if let Some((start, grid)) = pending.take() {
                damaged.push(DamagedRegion {
                    offset: header_len + start,
                    bytes: pos - start,
                    after_record: frames.len(),
                    pot_samples_lost: 0,
                });
                // The loss is known at the next pot batch (other records may come first).
                open_loss = grid.map(|g| (damaged.len() - 1, g));
            }
            if let (DeviceMsg::Pot(b), Some((i, (next_t_us, period)))) = (&msg, open_loss) {
                if b.t0_us > next_t_us {
                    damaged[i].pot_samples_lost = (b.t0_us - next_t_us + period / 2) / period;
                }
                open_loss = None;
            }
            frames.push((rx, msg));
            pos = end;
            continue;
        }
        if pending.is_none() {
            if truncated_at(body, pos)
                && (pos + 1..body.len()).all(|p| record_at(body, p).is_none())
            {
                truncated_tail_bytes = body.len() - pos;
                break;
            }
            if strict {
                return Err(RecordingError::Damaged {
                    path: path.to_path_buf(),
                    offset: header_len + pos,
                });
            }
            pending = Some((pos, pot_grid_end(&frames)));
        }
        pos += 1;
    }
    if let Some((start, _)) = pending {
        damaged.push(DamagedRegion {
            offset: header_len + start,
            bytes: body.len() - start,
            after_record: frames.len(),
            pot_samples_lost: 0,
        });
    }
    Ok(SalvagedRecording {
        meta,
        frames,
        damaged,
        truncated_tail_bytes,
    })
}
