//! A recording session (`rigctl record`): handshake, run, stop, drain.
//!
//! 1. Open the port (discarding stale input), send `GetInfo` and wait for the board's `Hello`
//!    ([`Timing::hello_timeout`], [`Timing::attempts`] tries). A board speaking another protocol
//!    version or built from other message definitions is refused ([`rig_protocol::check_hello`]).
//! 2. Create the recording (header with the `Hello`), store the `Hello` frame, send `Start` and
//!    wait for `Ack(Start)` (one of the run's first `Pot` batches counts as an implicit
//!    acknowledgement, in case the `Ack` was corrupted). A board
//!    still running from an earlier session (`Nack(AlreadyRunning)`) is stopped and started
//!    again; `Nack(RateOutOfRange)` is bad input.
//! 3. Store every good frame as it arrives until the duration is over or `stop` is set (Ctrl-C),
//!    or the board ends the run itself (an unsolicited `Ack(Stop)`).
//! 4. Send `Stop` and store frames until `Ack(Stop)` (the board sends the last batch and a final
//!    `Status` before it) or [`Timing::drain_timeout`].
//!
//! A read error, a hang-up or [`Timing::silence_timeout`] without a byte while running is a lost
//! device: the recording keeps every complete frame received so far and the error carries the
//! counts ([`RecordError::tally`]).

use super::link::{open_port, FrameReader, LinkError, LinkEvent};
use super::recording::{HelloMeta, RecordingError, RecordingMeta, RecordingWriter};
use super::tally::Tally;
use rig_protocol::{
    check_hello, encode_host, CommandKind, DeviceMsg, Hello, HelloMismatch, HostMsg, NackReason,
    HOST_FRAME_MAX, PROTOCOL_VERSION,
};
use std::io::ErrorKind as IoKind;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// A `Pot` batch with a `seq` below this, after `Start`, acknowledges it implicitly.
const IMPLICIT_ACK_SEQ: u32 = 4;

/// Time limits of a session.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timing {
    /// Longest single read from the port (how often the loop checks `stop` and the clock).
    pub read_timeout: Duration,
    /// Wait for `Hello` after each `GetInfo`, and for `Ack(Start)` after each `Start`.
    pub hello_timeout: Duration,
    /// Tries of `GetInfo` and of `Start`.
    pub attempts: u32,
    /// A running board silent this long is lost.
    pub silence_timeout: Duration,
    /// Wait for `Ack(Stop)` after `Stop`.
    pub drain_timeout: Duration,
    /// Interval between progress callbacks.
    pub progress_interval: Duration,
}

impl Default for Timing {
    fn default() -> Self {
        Self {
            read_timeout: Duration::from_millis(20),
            hello_timeout: Duration::from_secs(1),
            attempts: 3,
            silence_timeout: Duration::from_secs(3),
            drain_timeout: Duration::from_secs(2),
            progress_interval: Duration::from_millis(200),
        }
    }
}

/// What to record.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordConfig {
    /// Serial port or pseudo-terminal.
    pub port: PathBuf,
    /// Recording file to create.
    pub out: PathBuf,
    /// Stop after this long (from `Start`); `None`: until `stop` is set.
    pub duration: Option<Duration>,
    /// Potentiometer rate asked for in `Start`, Hz.
    pub pot_rate_hz: u32,
    /// Inclinometer rate asked for in `Start`, Hz.
    pub tilt_rate_hz: u32,
    /// Replace an existing `out`.
    pub overwrite: bool,
    pub timing: Timing,
}

/// How a session failed.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    #[error(transparent)]
    Link(#[from] LinkError),
    #[error(transparent)]
    Recording(#[from] RecordingError),
    #[error("no Hello from {port} after {attempts} GetInfo requests ({timeout_ms} ms each): is the board connected and running the rig firmware?")]
    NoHello {
        port: PathBuf,
        attempts: u32,
        timeout_ms: u128,
    },
    #[error("refusing the board on {port}: {mismatch}")]
    Mismatch {
        port: PathBuf,
        mismatch: HelloMismatch,
    },
    #[error("the board on {port} refused Start (pot {pot_rate_hz} Hz, tilt {tilt_rate_hz} Hz): {reason:?}")]
    Refused {
        port: PathBuf,
        pot_rate_hz: u32,
        tilt_rate_hz: u32,
        reason: NackReason,
    },
    #[error("the board on {port} did not acknowledge Start after {attempts} tries")]
    NoAck { port: PathBuf, attempts: u32 },
    #[error("interrupted before the recording started")]
    Interrupted,
    #[error("device on {port} lost ({reason}); {}", kept(out, *recorded, tally.frames))]
    DeviceLost {
        port: PathBuf,
        out: PathBuf,
        reason: String,
        /// Whether the recording had been created.
        recorded: bool,
        tally: Box<Tally>,
    },
}

fn kept(out: &std::path::Path, recorded: bool, frames: u64) -> String {
    if recorded {
        format!(
            "{} keeps the {frames} complete frames received",
            out.display()
        )
    } else {
        "nothing was recorded".into()
    }
}

impl RecordError {
    /// The counts of a session that failed after recording started.
    pub fn tally(&self) -> Option<&Tally> {
        match self {
            Self::DeviceLost { tally, .. } => Some(tally),
            _ => None,
        }
    }
}

impl crate::error::Classify for RecordError {
    fn kind(&self) -> crate::error::ErrorKind {
        use crate::error::ErrorKind;
        match self {
            Self::Link(e) => e.kind(),
            Self::Recording(e) => e.kind(),
            Self::Refused {
                reason: NackReason::RateOutOfRange,
                ..
            } => ErrorKind::BadInput,
            _ => ErrorKind::Failure,
        }
    }
}

/// A good frame as it came off the link.
struct Received {
    msg: DeviceMsg,
    raw: Vec<u8>,
    rx_us: u64,
}

/// The port, the decoder, the recording and the counts.
struct Session<'a> {
    cfg: &'a RecordConfig,
    port: Box<dyn serialport::SerialPort>,
    reader: FrameReader,
    origin: Instant,
    start_time_unix_us: u64,
    buf: Vec<u8>,
    writer: Option<RecordingWriter>,
    tally: Tally,
    last_byte: Instant,
}

impl Session<'_> {
    /// One read (at most `read_timeout`): the good frames it completed. `Err` = device lost.
    fn pump(&mut self) -> Result<Vec<Received>, String> {
        let n = match self.port.read(&mut self.buf) {
            Ok(0) => return Err("the port reached end of file (hang-up)".into()),
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    IoKind::TimedOut | IoKind::WouldBlock | IoKind::Interrupted
                ) =>
            {
                return Ok(Vec::new())
            }
            Err(e) if e.kind() == IoKind::BrokenPipe => {
                return Err(format!(
                    "the port hung up: unplugged, or the board-sim ended ({e})"
                ))
            }
            Err(e) => return Err(format!("read failed: {e}")),
        };
        self.last_byte = Instant::now();
        let rx_us = self.origin.elapsed().as_micros() as u64;
        let mut frames = Vec::new();
        self.reader.push_slice(&self.buf[..n], |event| {
            if let LinkEvent::Frame { msg, raw } = event {
                frames.push(Received {
                    msg,
                    raw: raw.to_vec(),
                    rx_us,
                });
            }
        });
        self.tally.crc_errors = self.reader.stats().corrupt;
        Ok(frames)
    }

    /// Stores and counts a frame (once the recording exists).
    fn keep(&mut self, frame: &Received) -> Result<(), RecordError> {
        if let Some(writer) = &mut self.writer {
            writer.append(frame.rx_us, &frame.raw)?;
            self.tally.on_message(&frame.msg);
        }
        Ok(())
    }

    fn send(&mut self, msg: HostMsg) -> Result<(), String> {
        let mut buf = [0u8; HOST_FRAME_MAX];
        let frame = encode_host(&msg, &mut buf).map_err(|e| e.to_string())?;
        self.port
            .write_all(frame)
            .map_err(|e| format!("write of {msg:?} failed: {e}"))
    }

    fn lost(&mut self, reason: String) -> RecordError {
        let writer = self.writer.take();
        let recorded = writer.is_some();
        if let Some(writer) = writer {
            // The records are already with the OS; a failed sync changes nothing for them.
            let _ = writer.finish();
        }
        RecordError::DeviceLost {
            port: self.cfg.port.clone(),
            out: self.cfg.out.clone(),
            reason,
            recorded,
            tally: Box::new(self.tally.clone()),
        }
    }

    /// Step 1 and the start of step 2: `GetInfo` until a `Hello`; creates the recording.
    fn handshake(&mut self, stop: &AtomicBool) -> Result<(), RecordError> {
        let t = self.cfg.timing;
        for _ in 0..t.attempts {
            self.send(HostMsg::GetInfo).map_err(|r| self.lost(r))?;
            let deadline = Instant::now() + t.hello_timeout;
            while Instant::now() < deadline {
                if stop.load(Ordering::Relaxed) {
                    return Err(RecordError::Interrupted);
                }
                let frames = self.pump().map_err(|r| self.lost(r))?;
                let mut frames = frames.into_iter();
                while let Some(frame) = frames.next() {
                    if let DeviceMsg::Hello(hello) = frame.msg {
                        self.accept(&hello)?;
                        self.keep(&frame)?;
                        for rest in frames {
                            self.keep(&rest)?;
                        }
                        return Ok(());
                    }
                }
            }
        }
        Err(RecordError::NoHello {
            port: self.cfg.port.clone(),
            attempts: t.attempts,
            timeout_ms: t.hello_timeout.as_millis(),
        })
    }

    fn accept(&mut self, hello: &Hello) -> Result<(), RecordError> {
        check_hello(hello).map_err(|mismatch| RecordError::Mismatch {
            port: self.cfg.port.clone(),
            mismatch,
        })?;
        let meta = RecordingMeta {
            protocol_version: PROTOCOL_VERSION,
            port: self.cfg.port.display().to_string(),
            start_time_unix_us: self.start_time_unix_us,
            pot_rate_hz: self.cfg.pot_rate_hz,
            tilt_rate_hz: self.cfg.tilt_rate_hz,
            hello: Some(HelloMeta::from(hello)),
            rigctl_version: env!("CARGO_PKG_VERSION").to_string(),
        };
        self.writer = Some(RecordingWriter::create(
            &self.cfg.out,
            &meta,
            self.cfg.overwrite,
        )?);
        Ok(())
    }

    /// Step 2: `Start` until acknowledged.
    fn start(&mut self, stop: &AtomicBool) -> Result<(), RecordError> {
        let t = self.cfg.timing;
        let start = HostMsg::Start {
            pot_rate_hz: self.cfg.pot_rate_hz,
            tilt_rate_hz: self.cfg.tilt_rate_hz,
        };
        for _ in 0..t.attempts {
            self.send(start).map_err(|r| self.lost(r))?;
            let deadline = Instant::now() + t.hello_timeout;
            while Instant::now() < deadline {
                if stop.load(Ordering::Relaxed) {
                    return Err(RecordError::Interrupted);
                }
                let mut started = false;
                let mut already_running = false;
                for frame in self.pump().map_err(|r| self.lost(r))? {
                    match frame.msg {
                        DeviceMsg::Ack(CommandKind::Start) => {
                            self.tally.start_run();
                            started = true;
                        }
                        // The Ack was lost but our run's first batches arrive (`seq` restarts
                        // at 0 on `Start`; a run left over from before has larger ones).
                        DeviceMsg::Pot(ref batch) if batch.seq < IMPLICIT_ACK_SEQ && !started => {
                            self.tally.start_run();
                            started = true;
                        }
                        DeviceMsg::Nack {
                            command: CommandKind::Start,
                            reason: NackReason::AlreadyRunning,
                        } => already_running = true,
                        DeviceMsg::Nack {
                            command: CommandKind::Start,
                            reason,
                        } => {
                            return Err(RecordError::Refused {
                                port: self.cfg.port.clone(),
                                pot_rate_hz: self.cfg.pot_rate_hz,
                                tilt_rate_hz: self.cfg.tilt_rate_hz,
                                reason,
                            })
                        }
                        _ => {}
                    }
                    self.keep(&frame)?;
                }
                if already_running && !started {
                    // A run left over from an earlier session: stop it, then start ours.
                    self.send(HostMsg::Stop).map_err(|r| self.lost(r))?;
                    self.drain(t.drain_timeout)?;
                    break;
                }
                if started {
                    return Ok(());
                }
            }
        }
        Err(RecordError::NoAck {
            port: self.cfg.port.clone(),
            attempts: t.attempts,
        })
    }

    /// Stores frames until `Ack(Stop)` or `timeout`; returns whether the `Ack` came.
    fn drain(&mut self, timeout: Duration) -> Result<bool, RecordError> {
        let deadline = Instant::now() + timeout;
        while Instant::now() < deadline {
            for frame in self.pump().map_err(|r| self.lost(r))? {
                self.keep(&frame)?;
                if frame.msg == DeviceMsg::Ack(CommandKind::Stop) {
                    return Ok(true);
                }
            }
        }
        Ok(false)
    }

    /// Step 3. Returns whether the board ended the run itself.
    fn run(
        &mut self,
        stop: &AtomicBool,
        progress: &mut dyn FnMut(&Tally, Duration),
    ) -> Result<bool, RecordError> {
        let t = self.cfg.timing;
        let run_start = Instant::now();
        let mut last_progress = run_start;
        self.last_byte = run_start;
        loop {
            let elapsed = run_start.elapsed();
            if stop.load(Ordering::Relaxed) || self.cfg.duration.is_some_and(|d| elapsed >= d) {
                return Ok(false);
            }
            for frame in self.pump().map_err(|r| self.lost(r))? {
                self.keep(&frame)?;
                if frame.msg == DeviceMsg::Ack(CommandKind::Stop) {
                    return Ok(true);
                }
            }
            if self.last_byte.elapsed() >= t.silence_timeout {
                let silent = self.last_byte.elapsed().as_secs_f64();
                return Err(self.lost(format!("no byte for {silent:.1} s")));
            }
            if last_progress.elapsed() >= t.progress_interval {
                last_progress = Instant::now();
                progress(&self.tally, elapsed);
            }
        }
    }
}

/// Runs a whole session (see the module documentation); returns the final counts.
/// `progress` is called about every [`Timing::progress_interval`] while running, with the counts
/// and the time since `Start`.
pub fn record(
    cfg: &RecordConfig,
    stop: &AtomicBool,
    progress: &mut dyn FnMut(&Tally, Duration),
) -> Result<Tally, RecordError> {
    if !cfg.overwrite && std::fs::symlink_metadata(&cfg.out).is_ok() {
        return Err(RecordingError::Exists {
            path: cfg.out.clone(),
        }
        .into());
    }
    let port = open_port(&cfg.port, cfg.timing.read_timeout)?;
    let origin = Instant::now();
    let start_time_unix_us = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_micros() as u64);
    let mut s = Session {
        cfg,
        port,
        reader: FrameReader::new(),
        origin,
        start_time_unix_us,
        buf: vec![0u8; 4096],
        writer: None,
        tally: Tally::new(),
        last_byte: origin,
    };
    s.handshake(stop)?;
    if let Err(e) = s.start(stop) {
        if s.writer.take().is_some() && e.tally().is_none() {
            // Nothing was recorded but the Hello: leave no file behind a refused start.
            let _ = std::fs::remove_file(&cfg.out);
        }
        return Err(e);
    }
    let board_ended = s.run(stop, progress)?;
    if !board_ended {
        s.send(HostMsg::Stop).map_err(|r| s.lost(r))?;
        if !s.drain(cfg.timing.drain_timeout / 2)? {
            // The Stop may have been lost; ask again (an idle board answers Nack).
            s.send(HostMsg::Stop).map_err(|r| s.lost(r))?;
            s.drain(cfg.timing.drain_timeout / 2)?;
        }
    }
    if let Some(writer) = s.writer.take() {
        writer.finish()?;
    }
    Ok(s.tally)
}
