//! `rigctl export`: a recording to CSV files (FORMATS.md).
//!
//! | file | columns | one row per |
//! |---|---|---|
//! | `pot.csv` | `seq,t_us,raw` | potentiometer sample; `t_us = t0_us + i * period_us` (board time, us), `raw` ADC counts |
//! | `tilt.csv` | `sensor,t_us,x,y,z,temp` | inclinometer reading, raw counts (SCL3300 mode 1: 6000 counts/g; T(degC) = -273 + temp / 18.9) |
//! | `status.csv` | `host_rx_us,uptime_us,dropped_samples,dropped_frames,overruns,sensor_errors,rx_errors` | board `Status` frame; `host_rx_us` = host receive time (us since the recording's start), the rest as in `rig_protocol::Status` |
//!
//! Frames with values out of the board's announced range (`super::wire_check`) are left out
//! and counted ([`ExportSummary::out_of_range`], [`super::wire_check::in_range`]; `rigctl
//! export` exits 1 then).
//! Rows are in the order the frames arrived. Each file is written under a temporary name and
//! renamed when complete. Every stored frame is decoded (and its CRC checked) again; a frame
//! that fails means the file was damaged after recording, which is bad input.

use super::link::decode_stored;
use super::recording::{Recording, RecordingError};
use super::salvage::{read_salvaged, DamagedRegion};
use super::tally::Tally;
use super::wire_check::in_range;
use crate::io::atomic::{write_atomic, AtomicWriteError};
use rig_protocol::{CorruptReason, DeviceMsg};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Header of `pot.csv`.
pub const POT_HEADER: &str = "seq,t_us,raw";
/// Header of `tilt.csv`.
pub const TILT_HEADER: &str = "sensor,t_us,x,y,z,temp";
/// Header of `status.csv`.
pub const STATUS_HEADER: &str =
    "host_rx_us,uptime_us,dropped_samples,dropped_frames,overruns,sensor_errors,rx_errors";

/// What can go wrong exporting.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error(transparent)]
    Recording(#[from] RecordingError),
    #[error("{path}: record {index} (received at {host_rx_us} us) does not decode ({reason:?}): the file was damaged")]
    BadFrame {
        path: PathBuf,
        index: usize,
        host_rx_us: u64,
        reason: CorruptReason,
    },
    #[error("cannot create directory {path}: {source}")]
    Dir {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Write(#[from] AtomicWriteError),
}

impl crate::error::Classify for ExportError {
    fn kind(&self) -> crate::error::ErrorKind {
        use crate::error::ErrorKind;
        match self {
            Self::Recording(e) => e.kind(),
            Self::BadFrame { .. } => ErrorKind::BadInput,
            Self::Dir { .. } => ErrorKind::Failure,
            Self::Write(e) => e.kind(),
        }
    }
}

/// Rows written per file, and the recording's counts.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportSummary {
    pub pot_rows: u64,
    pub tilt_rows: u64,
    pub status_rows: u64,
    /// The counts of the recorded frames (`crc_errors` is 0: only good frames are recorded).
    pub tally: Tally,
    /// Bytes of an incomplete last record that were ignored.
    pub truncated_tail_bytes: usize,
    /// Damaged stretches skipped (empty for an intact file).
    pub damaged: Vec<DamagedRegion>,
    /// Frames out of the board's announced range, not exported
    /// ([`super::wire_check::WireCheck::summary`]); `None` when there were none.
    pub out_of_range: Option<String>,
}

/// The decoded frames of a recording, with their receive times.
pub fn decode_recording(
    path: &Path,
    recording: &Recording,
) -> Result<Vec<(u64, DeviceMsg)>, ExportError> {
    recording
        .records
        .iter()
        .enumerate()
        .map(|(index, record)| {
            decode_stored(&record.frame)
                .map(|msg| (record.host_rx_us, msg))
                .map_err(|reason| ExportError::BadFrame {
                    path: path.to_path_buf(),
                    index,
                    host_rx_us: record.host_rx_us,
                    reason,
                })
        })
        .collect()
}

/// Exports the recording at `path` into `dir` (created if missing). Damaged records are
/// skipped and reported in [`ExportSummary::damaged`]; with `strict` they are an error.
pub fn export_csv(path: &Path, dir: &Path, strict: bool) -> Result<ExportSummary, ExportError> {
    let salvaged = read_salvaged(path, strict)?;
    // frames out of the board's announced range are not exported (counted in the summary)
    let (kept, check) = in_range(&salvaged.meta, salvaged.frames);
    let frames = &kept;
    // the three files of one run, never a mix of concurrent exports into the same directory
    let _lock = crate::io::atomic::lock_dir(dir)?;
    // the three files as one commit (crate::io::file_set)
    let set = crate::io::file_set::begin(dir, crate::io::file_set::keep_all)?;
    let mut tally = Tally::new();
    for (_, msg) in frames {
        tally.on_message(msg);
    }

    let pot_path = dir.join("pot.csv");
    let pot_rows = write_csv(&pot_path, POT_HEADER, |w| {
        let mut rows = 0u64;
        for (_, msg) in frames {
            if let DeviceMsg::Pot(b) = msg {
                for (i, raw) in b.samples.iter().enumerate() {
                    // checked (the batch's last time fits, `WireCheck`); never a wrap
                    let Some(t_us) = (i as u64)
                        .checked_mul(u64::from(b.period_us))
                        .and_then(|d| b.t0_us.checked_add(d))
                    else {
                        continue;
                    };
                    writeln!(w, "{},{t_us},{raw}", b.seq)?;
                    rows += 1;
                }
            }
        }
        Ok(rows)
    })?;
    let tilt_path = dir.join("tilt.csv");
    let tilt_rows = write_csv(&tilt_path, TILT_HEADER, |w| {
        let mut rows = 0u64;
        for (_, msg) in frames {
            if let DeviceMsg::Tilt(r) = msg {
                writeln!(
                    w,
                    "{},{},{},{},{},{}",
                    r.sensor, r.t_us, r.x, r.y, r.z, r.temp
                )?;
                rows += 1;
            }
        }
        Ok(rows)
    })?;
    let status_path = dir.join("status.csv");
    let status_rows = write_csv(&status_path, STATUS_HEADER, |w| {
        let mut rows = 0u64;
        for (host_rx_us, msg) in frames {
            if let DeviceMsg::Status(s) = msg {
                writeln!(
                    w,
                    "{host_rx_us},{},{},{},{},{},{}",
                    s.uptime_us,
                    s.dropped_samples,
                    s.dropped_frames,
                    s.overruns,
                    s.sensor_errors,
                    s.rx_errors
                )?;
                rows += 1;
            }
        }
        Ok(rows)
    })?;
    set.commit()?;
    Ok(ExportSummary {
        pot_rows,
        tilt_rows,
        status_rows,
        tally,
        truncated_tail_bytes: salvaged.truncated_tail_bytes,
        damaged: salvaged.damaged,
        out_of_range: check.summary(),
    })
}

/// Writes `header` and the rows `fill` writes, atomically; returns the row count.
fn write_csv(
    path: &Path,
    header: &str,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<u64>,
) -> Result<u64, ExportError> {
    let mut rows = 0;
    write_atomic(path, |w| {
        let io = |source| AtomicWriteError::Io {
            path: path.to_path_buf(),
            source,
        };
        writeln!(w, "{header}").map_err(io)?;
        rows = fill(w).map_err(io)?;
        Ok::<(), ExportError>(())
    })?;
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::daq::recording::{RecordingMeta, RecordingWriter};
    use rig_protocol::{encode_device, PotBatch, Status, TiltReading, DEVICE_FRAME_MAX};

    fn stored(msg: &DeviceMsg) -> Vec<u8> {
        let mut buf = [0u8; DEVICE_FRAME_MAX];
        let frame = encode_device(msg, &mut buf).unwrap();
        frame[..frame.len() - 1].to_vec()
    }

    fn meta() -> RecordingMeta {
        RecordingMeta {
            protocol_version: 1,
            port: "test".into(),
            start_time_unix_us: 0,
            // the batches below are 250 us apart
            pot_rate_hz: 4000,
            tilt_rate_hz: 100,
            hello: None,
            rigctl_version: "test".into(),
        }
    }

    fn write_recording(path: &Path, msgs: &[DeviceMsg]) {
        let mut w = RecordingWriter::create(path, &meta(), false).unwrap();
        for (i, m) in msgs.iter().enumerate() {
            w.append(1000 * i as u64, &stored(m)).unwrap();
        }
        w.finish().unwrap();
    }

    fn batch(seq: u32, t0_us: u64, samples: &[u16]) -> DeviceMsg {
        DeviceMsg::Pot(PotBatch {
            seq,
            t0_us,
            period_us: 250,
            samples: heapless::Vec::from_slice(samples).unwrap(),
        })
    }

    #[test]
    fn rows_follow_the_documented_columns() {
        let dir = tempfile::tempdir().unwrap();
        let rec = dir.path().join("run.rigrec");
        write_recording(
            &rec,
            &[
                batch(0, 1_000, &[10, 11, 12]),
                DeviceMsg::Tilt(TiltReading {
                    sensor: 2,
                    t_us: 1_300,
                    x: -5,
                    y: 6000,
                    z: 7,
                    temp: 5632,
                    status: 0,
                }),
                batch(2, 2_000, &[4095]),
                DeviceMsg::Status(Status {
                    uptime_us: 9,
                    dropped_samples: 1,
                    dropped_frames: 2,
                    overruns: 3,
                    sensor_errors: 4,
                    rx_errors: 5,
                }),
            ],
        );
        let out = dir.path().join("csv");
        let summary = export_csv(&rec, &out, false).unwrap();
        assert_eq!(
            std::fs::read_to_string(out.join("pot.csv")).unwrap(),
            "seq,t_us,raw\n0,1000,10\n0,1250,11\n0,1500,12\n2,2000,4095\n"
        );
        assert_eq!(
            std::fs::read_to_string(out.join("tilt.csv")).unwrap(),
            "sensor,t_us,x,y,z,temp\n2,1300,-5,6000,7,5632\n"
        );
        assert_eq!(
            std::fs::read_to_string(out.join("status.csv")).unwrap(),
            format!("{STATUS_HEADER}\n3000,9,1,2,3,4,5\n")
        );
        assert_eq!(
            (summary.pot_rows, summary.tilt_rows, summary.status_rows),
            (4, 1, 1)
        );
        // 1000 + 3 * 250 = 1750 expected next, 2000 came: one sample missing.
        assert_eq!(summary.tally.gap_samples, 1);
    }

    #[test]
    fn damaged_frame_is_refused_with_strict_and_skipped_without() {
        let dir = tempfile::tempdir().unwrap();
        let rec = dir.path().join("run.rigrec");
        write_recording(&rec, &[batch(0, 0, &[1, 2]), batch(1, 500, &[3])]);
        let mut bytes = std::fs::read(&rec).unwrap();
        let last = bytes.len() - 2;
        bytes[last] ^= 0x40;
        std::fs::write(&rec, &bytes).unwrap();
        let out = dir.path().join("csv");
        match export_csv(&rec, &out, true) {
            Err(ExportError::Recording(RecordingError::Damaged { .. })) => {}
            other => panic!("expected Damaged, got {other:?}"),
        }
        assert!(!out.join("pot.csv").exists());
        let summary = export_csv(&rec, &out, false).unwrap();
        assert_eq!(summary.pot_rows, 2);
        assert_eq!(summary.damaged.len(), 1);
        assert_eq!(
            std::fs::read_to_string(out.join("pot.csv")).unwrap(),
            "seq,t_us,raw\n0,0,1\n0,250,2\n"
        );
    }
}
