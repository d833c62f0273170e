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
//! A read error, a hang-up or [`Timing::silence_timeout`] without a good frame while running is a lost
//! device: the recording keeps every complete frame received so far and the error carries the
//! counts ([`RecordError::tally`]).

use super::link::{open_port, FrameReader, LinkEvent};
use super::rec_file::RecTarget;
use super::recording::{HelloMeta, RecordingError, RecordingMeta, RecordingWriter};
use super::tally::Tally;
use super::wire_check::WireCheck;
use rig_protocol::{
    check_hello, encode_host, CommandKind, DeviceMsg, Hello, HostMsg, NackReason, HOST_FRAME_MAX,
    PROTOCOL_VERSION,
};
use std::io::ErrorKind as IoKind;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

mod config;
pub use config::{RecordConfig, RecordError, Timing};

/// A `Pot` batch with a `seq` below this, after `Start`, acknowledges it implicitly.
const IMPLICIT_ACK_SEQ: u32 = 4;

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
    /// Where the recording goes (with `--overwrite`: a temporary file until the commit).
    target: Option<RecTarget>,
    /// `Start` was acknowledged.
    started: bool,
    tally: Tally,
    /// Frames checked against the `Hello` and `Start` (created with the recording).
    check: Option<WireCheck>,
    /// When the last good, in-range frame arrived (the silence timeout counts these).
    last_good: Instant,
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
        if let Some(check) = &mut self.check {
            if !check.accept(&frame.msg) {
                return Ok(()); // counted there; not stored, not counted as a frame
            }
        }
        self.last_good = Instant::now();
        if let Some(writer) = &mut self.writer {
            writer.append(frame.rx_us, &frame.raw)?;
            self.tally.on_message(&frame.msg);
            // the run has started and holds data: now the new recording may replace the old
            let data = matches!(frame.msg, DeviceMsg::Pot(_) | DeviceMsg::Tilt(_));
            if self.started && data {
                if let Some(target) = self.target.as_mut().filter(|t| !t.committed()) {
                    target.commit()?;
                }
            }
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
        let target = self.target.take();
        let committed = target.as_ref().is_some_and(RecTarget::committed);
        let recorded = writer.is_some() && committed;
        if let Some(writer) = writer {
            // The records are already with the OS; a failed sync changes nothing for them.
            let _ = writer.finish();
        }
        if let Some(t) = target.filter(|t| !t.committed()) {
            t.discard(); // the old recording stays
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
        self.check = Some(WireCheck::new(
            Some(self.cfg.pot_rate_hz),
            Some(hello.tilt_sensors),
        ));
        let (file, target) = super::rec_file::open(&self.cfg.out, self.cfg.overwrite)?;
        match RecordingWriter::with_file(file, target.write_path(), &meta) {
            Ok(w) => {
                self.writer = Some(w);
                self.target = Some(target);
                Ok(())
            }
            Err(e) => {
                target.discard();
                Err(e.into())
            }
        }
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
                            if let Some(c) = &mut self.check {
                                c.restart();
                            }
                            started = true;
                        }
                        // The Ack was lost but our run's first batches arrive (`seq` restarts
                        // at 0 on `Start`; a run left over from before has larger ones).
                        DeviceMsg::Pot(ref batch) if batch.seq < IMPLICIT_ACK_SEQ && !started => {
                            self.tally.start_run();
                            if let Some(c) = &mut self.check {
                                c.restart();
                            }
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
        self.last_good = run_start;
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
            if self.last_good.elapsed() >= t.silence_timeout {
                let silent = self.last_good.elapsed().as_secs_f64();
                return Err(self.lost(format!("no good frame for {silent:.1} s")));
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
        target: None,
        started: false,
        tally: Tally::new(),
        check: None,
        last_good: origin,
    };
    s.handshake(stop)?;
    if let Err(e) = s.start(stop) {
        s.writer = None;
        if let Some(t) = s.target.take() {
            // Nothing was recorded but the Hello: leave no new file behind a refused start,
            // and an old recording (`--overwrite`) as it was.
            t.discard();
        }
        return Err(e);
    }
    s.started = true;
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
    if let Some(t) = s.target.take() {
        if !t.committed() {
            // `--overwrite`: no frame of data came; the old recording stays
            t.discard();
            return Err(RecordError::NoData {
                port: cfg.port.clone(),
                out: cfg.out.clone(),
            });
        }
    }
    if let Some(summary) = s.check.as_ref().and_then(WireCheck::summary) {
        return Err(RecordError::OutOfRange {
            port: cfg.port.clone(),
            out: cfg.out.clone(),
            summary,
            tally: Box::new(s.tally),
        });
    }
    Ok(s.tally)
}
