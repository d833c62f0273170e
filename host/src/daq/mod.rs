//! The acquisition path: the DAQ board's frames from the serial port to a recording file
//! (`rigctl record`), from the recording to CSV (`rigctl export`), and a virtual board that
//! serves the same protocol on a pseudo-terminal (`rigctl board-sim`).
//!
//! ```text
//!  board (firmware) or board-sim          host
//!  rig_protocol::device::Board  --USB/pty-->  link::FrameReader --> session (record)
//!        ^ signals (board-sim)                        |                 |
//!                                                     v                 v
//!                                             tally (counts)     recording (file) --> export (CSV)
//! ```
//!
//! | module | holds |
//! |---|---|
//! | [`recording`] | the recording file format (header + length-prefixed raw frames), writer and tolerant reader |
//! | [`rec_file`] | where `record` writes: an exclusive lock, `--overwrite` through a temporary file renamed over the old recording once the run holds frames |
//! | [`salvage`] | reading a damaged recording: skip damaged records (CRC), resynchronise, report what was lost |
//! | [`link`] | opening/listing serial ports; cutting the byte stream into frames, keeping each frame's raw bytes |
//! | [`session`] | a `record` session: handshake (`GetInfo`/`Hello`, version check), `Start`, run, `Stop`, drain; what it is asked and how it fails in `session/config.rs` |
//! | [`tally`] | the counts `frames`, `samples`, `dropped`, `crc_errors` and their exact definitions |
//! | [`wire_check`] | frames checked against the board's announced configuration (period, 12-bit raw, sensor count, monotone time) |
//! | [`export`] | recording -> `pot.csv`, `tilt.csv`, `status.csv` |
//! | [`board_sim`] | the virtual board: `rig_protocol::device::Board` on a virtual clock, corruption, serving loop |
//! | [`signals`] | the virtual board's seeded synthetic potentiometer and inclinometer signals |
//! | [`pty`] | pseudo-terminal plumbing (raw mode, hang-up detection, the symlink) |

pub mod board_sim;
pub mod export;
pub mod link;
pub mod pty;
pub mod rec_file;
pub mod recording;
pub mod salvage;
pub mod session;
pub mod signals;
pub mod tally;
pub mod wire_check;
