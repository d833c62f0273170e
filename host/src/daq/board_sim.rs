//! The virtual DAQ board (`rigctl board-sim`): the firmware's portable logic
//! ([`rig_protocol::device::Board`]) driven by a virtual clock and fed with the synthetic signals
//! of [`super::signals`], serving the wire protocol on a pseudo-terminal ([`super::pty`]).
//!
//! # Time
//!
//! Board time starts at 0 when the simulator starts and runs at `speed` times the host's wall
//! clock (1 = real time). Every event happens at its exact board time, whatever the pacing:
//! potentiometer sample `k` of a run at `start_us + k * period_us`, inclinometer reads when the
//! board's schedule says, housekeeping at the board's deadlines. The loop wakes at least every
//! [`TICK`] of wall time, runs every event up to "now" and writes what the board queued.
//!
//! # Rates
//!
//! The host's `Start` sets the rates, as with the real firmware. `pot_hz_max` / `tilt_hz_max`
//! (the `--pot-hz` / `--tilt-hz` flags) are the virtual hardware's limits: a `Start` asking for
//! more is answered `Nack(RateOutOfRange)`.
//!
//! # Link
//!
//! Nothing is written before the host's first bytes arrive (a USB CDC board's data goes nowhere
//! until the port is open); the `Hello` queued at boot goes out then. `corrupt_ppm` replaces that
//! many bytes per million on the way out with another non-zero value (seeded); delimiters are
//! never touched and no byte becomes a delimiter, so each corrupted frame is exactly one frame
//! lost and one `crc_errors` at the host, which [`SimReport`] lets a test check.
//!
//! # End
//!
//! The run ends on the host's `Stop`, or after `duration` of board time from `Start` (then the
//! simulator stops itself as if the host had sent `Stop`: the last batch, a `Status` and an
//! unsolicited `Ack(Stop)` go out). After the end the simulator waits up to [`LINGER`] for the
//! host to close the port, so that the host reads every last frame, and returns. It also returns
//! when the host closes the port, or when `stop` is set (Ctrl-C).

use super::pty::{MasterEvent, Pty, PtyError};
use super::signals;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rig_protocol::device::{Action, Board, BoardInfo};
use rig_protocol::{Decoded, HostDecoder, HostMsg, TiltReading, DELIMITER, HOST_FRAME_MAX};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Longest wall-clock sleep between two passes of the loop.
pub const TICK: Duration = Duration::from_millis(2);
/// Largest step of board time between two writes to the link, microseconds.
pub const CATCH_UP_STEP_US: u64 = 5_000;
/// How long the simulator waits, after the run ended, for the host to close the port.
pub const LINGER: Duration = Duration::from_secs(3);

/// How the virtual board behaves.
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// Highest potentiometer rate the virtual hardware accepts, Hz.
    pub pot_hz_max: u32,
    /// Highest inclinometer rate the virtual hardware accepts, Hz.
    pub tilt_hz_max: u32,
    /// Inclinometers on the board (reported in `Hello`).
    pub sensors: u8,
    /// Bytes per million replaced on the way out.
    pub corrupt_ppm: u32,
    /// Seed of the signals and of the corruption.
    pub seed: u64,
    /// Board time from `Start` after which the board stops itself; `None`: run until `Stop`.
    pub duration: Option<Duration>,
    /// Board time per wall time (1 = real time).
    pub speed: f64,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            pot_hz_max: 1000,
            tilt_hz_max: 100,
            sensors: 3,
            corrupt_ppm: 0,
            seed: 0,
            duration: None,
            speed: 1.0,
        }
    }
}

/// Why the simulator returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimEnd {
    /// The host sent `Stop`.
    HostStopped,
    /// `duration` elapsed.
    DurationElapsed,
    /// The host closed the port while the board was running (or before any run).
    HostClosed,
    /// `stop` was set (Ctrl-C).
    Interrupted,
}

/// What the simulator did: a test's ground truth.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SimReport {
    /// Frames written to the link (each ends with its delimiter).
    pub frames_sent: u64,
    /// Of those, frames with at least one replaced byte.
    pub frames_corrupted: u64,
    /// Bytes written.
    pub bytes_sent: u64,
    /// Bytes replaced.
    pub bytes_corrupted: u64,
    /// Potentiometer samples taken while running.
    pub samples: u64,
    /// Inclinometer readings taken while running.
    pub tilt_readings: u64,
    /// Frames the board's queue dropped (its `Status.dropped_frames` at the end).
    pub board_dropped_frames: u32,
    /// Potentiometer samples in them (`Status.dropped_samples`).
    pub board_dropped_samples: u32,
}

impl std::fmt::Display for SimReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "sent frames {}, corrupted frames {}, samples {}, tilt readings {}, board dropped frames {}, board dropped samples {}",
            self.frames_sent,
            self.frames_corrupted,
            self.samples,
            self.tilt_readings,
            self.board_dropped_frames,
            self.board_dropped_samples
        )
    }
}

/// The board and its virtual sensors, without any link: advance it in board time, feed it the
/// host's bytes, take what it queued.
#[derive(Debug)]
pub struct VirtualBoard {
    board: Board,
    cfg: SimConfig,
    /// Board time of the next potentiometer sample and the period, while running.
    pot: Option<(u64, u64)>,
    /// Board time at which the current run ends by itself.
    end_us: Option<u64>,
    samples: u64,
    tilt_readings: u64,
    ended: Option<SimEnd>,
    now_us: u64,
    /// The host's frames, decoded here too so that a `Start` beyond the limits is refused.
    rx: HostDecoder,
    rx_raw: Vec<u8>,
}

impl VirtualBoard {
    /// A powered-up board at board time 0 (its `Hello` is queued).
    pub fn new(cfg: SimConfig) -> Self {
        let mut board_id = [0u8; 12];
        for (i, chunk) in board_id.chunks_mut(8).enumerate() {
            let bytes = (cfg.seed ^ 0xB0A2_D1D0_0000_0000)
                .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                .rotate_left(17 * i as u32)
                .to_le_bytes();
            chunk.copy_from_slice(&bytes[..chunk.len()]);
        }
        let mut board = Board::new(BoardInfo {
            firmware_version: [0, 1, 0],
            board_id,
            tilt_sensors: cfg.sensors,
        });
        board.boot(0);
        Self {
            board,
            cfg,
            pot: None,
            end_us: None,
            samples: 0,
            tilt_readings: 0,
            ended: None,
            now_us: 0,
            rx: HostDecoder::new(),
            rx_raw: Vec::with_capacity(HOST_FRAME_MAX),
        }
    }

    /// Board time reached so far.
    pub fn now_us(&self) -> u64 {
        self.now_us
    }

    /// `Some` once a run has ended (by `Stop` or by the duration).
    pub fn ended(&self) -> Option<SimEnd> {
        self.ended
    }

    /// True while sampling.
    pub fn is_running(&self) -> bool {
        self.board.is_running()
    }

    /// Runs every event up to board time `now_us` (a run whose duration elapses stops there).
    pub fn advance_to(&mut self, now_us: u64) {
        let target = match self.end_us {
            Some(end) if self.board.is_running() => now_us.min(end),
            _ => now_us,
        };
        // A deadline the board does not move past would loop forever; skip it for this call.
        let mut stuck: Option<u64> = None;
        while let Some((t_pot, period_us)) = self.pot {
            let deadline = self
                .board
                .next_deadline_us()
                .filter(|&d| Some(d) != stuck)
                .unwrap_or(u64::MAX);
            let t = t_pot.min(deadline);
            if t > target {
                break;
            }
            if t_pot <= deadline {
                self.board
                    .on_pot_sample(t_pot, signals::pot_raw(self.cfg.seed, t_pot));
                self.samples += 1;
                self.pot = Some((t_pot + period_us, period_us));
            } else {
                if let Some(sensor) = self.board.tilt_due(t) {
                    let raw = signals::tilt_raw(self.cfg.seed, sensor, t);
                    self.board.on_tilt_reading(TiltReading {
                        sensor,
                        t_us: t,
                        x: raw.x,
                        y: raw.y,
                        z: raw.z,
                        temp: raw.temp,
                        status: 0,
                    });
                    self.tilt_readings += 1;
                }
                self.board.poll(t);
                if self.board.next_deadline_us() == Some(t) {
                    stuck = Some(t);
                }
            }
        }
        self.now_us = self.now_us.max(target);
        if let Some(end) = self.end_us {
            if self.board.is_running() && now_us >= end {
                self.board.handle_command(end, HostMsg::Stop);
                self.pot = None;
                self.ended = Some(SimEnd::DurationElapsed);
            }
        }
        if !self.board.is_running() {
            // Idle (or just stopped): the clock runs on without events.
            self.now_us = self.now_us.max(now_us);
        }
    }

    /// Feeds bytes from the host at the current board time.
    pub fn receive(&mut self, bytes: &[u8]) {
        for &byte in bytes {
            if byte != DELIMITER {
                if self.rx_raw.len() < 4 * HOST_FRAME_MAX {
                    self.rx_raw.push(byte);
                }
                // An overlong frame is condemned here, and again by the board at its delimiter.
                let _ = self.rx.push(byte);
                continue;
            }
            let event = self.rx.push(byte);
            self.rx_raw.push(DELIMITER);
            let refused = matches!(
                event,
                Some(Decoded::Frame(HostMsg::Start { pot_rate_hz, tilt_rate_hz }))
                    if pot_rate_hz > self.cfg.pot_hz_max || tilt_rate_hz > self.cfg.tilt_hz_max
            );
            let action = if refused {
                // Refused through the board's own validation (a rate it cannot run either).
                let zero = HostMsg::Start {
                    pot_rate_hz: 0,
                    tilt_rate_hz: 0,
                };
                self.board.handle_command(self.now_us, zero)
            } else {
                // The board decodes the frame itself (and counts it in `rx_errors` if corrupt).
                self.board.receive(self.now_us, &self.rx_raw)
            };
            self.rx_raw.clear();
            self.on_action(action);
        }
    }

    fn on_action(&mut self, action: Action) {
        let now = self.now_us;
        match action {
            Action::StartSampling(cfg) => {
                self.pot = Some((now, u64::from(cfg.pot_period_us)));
                self.end_us = self
                    .cfg
                    .duration
                    .map(|d| now.saturating_add(d.as_micros() as u64));
                self.ended = None;
            }
            Action::StopSampling => {
                self.pot = None;
                self.ended = Some(SimEnd::HostStopped);
            }
            Action::None => {}
        }
    }

    /// The board's outbound bytes waiting to be written.
    pub fn tx_peek(&self) -> &[u8] {
        self.board.tx_peek()
    }

    /// Forgets `n` written bytes.
    pub fn tx_consume(&mut self, n: usize) {
        self.board.tx_consume(n);
    }

    /// Bytes waiting.
    pub fn tx_len(&self) -> usize {
        self.board.tx_len()
    }

    /// Samples and readings taken so far and the board's drop counters.
    pub fn counts(&self) -> (u64, u64, rig_protocol::Status) {
        (
            self.samples,
            self.tilt_readings,
            self.board.status(self.now_us),
        )
    }
}

/// Replaces bytes on their way out and counts frames.
#[derive(Debug)]
pub struct Corruptor {
    rng: ChaCha8Rng,
    ppm: u32,
    frame_hit: bool,
    report: SimReport,
    scratch: Vec<u8>,
}

impl Corruptor {
    /// `ppm` bytes per million replaced, reproducibly for a given `seed`.
    pub fn new(ppm: u32, seed: u64) -> Self {
        Self {
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0xC0AA_0F7E_5EED_0001),
            ppm: ppm.min(1_000_000),
            frame_hit: false,
            report: SimReport::default(),
            scratch: Vec::new(),
        }
    }

    /// Writes as much of `bytes` as `write` takes (it returns how many it took), corrupting
    /// on the way; returns the count taken.
    pub fn write<E>(
        &mut self,
        bytes: &[u8],
        write: impl FnOnce(&[u8]) -> Result<usize, E>,
    ) -> Result<usize, E> {
        self.scratch.clear();
        self.scratch.extend_from_slice(bytes);
        if self.ppm > 0 {
            for b in self.scratch.iter_mut() {
                if *b != DELIMITER && self.rng.gen_range(0..1_000_000u32) < self.ppm {
                    // Uniform over the 254 non-zero values other than `b`.
                    let r: u8 = self.rng.gen_range(1..=254);
                    *b = if r >= *b { r + 1 } else { r };
                }
            }
        }
        let n = write(&self.scratch)?.min(bytes.len());
        for (sent, orig) in self.scratch[..n].iter().zip(&bytes[..n]) {
            if sent != orig {
                self.report.bytes_corrupted += 1;
                self.frame_hit = true;
            }
            if *orig == DELIMITER {
                self.report.frames_sent += 1;
                if self.frame_hit {
                    self.report.frames_corrupted += 1;
                }
                self.frame_hit = false;
            }
        }
        self.report.bytes_sent += n as u64;
        Ok(n)
    }

    /// Counts so far (link part of the report).
    pub fn report(&self) -> SimReport {
        self.report
    }
}

/// Writes what the board queued, as far as the link takes it.
fn flush_tx(
    board: &mut VirtualBoard,
    corruptor: &mut Corruptor,
    pty: &mut Pty,
) -> Result<(), PtyError> {
    while board.tx_len() > 0 {
        let chunk = board.tx_peek();
        let len = chunk.len();
        let n = corruptor.write(chunk, |b| pty.write(b))?;
        board.tx_consume(n);
        if n < len {
            break;
        }
    }
    Ok(())
}

/// Serves the virtual board on `pty` until the run ends, the host closes the port or `stop` is
/// set. See the module documentation.
pub fn serve(
    pty: &mut Pty,
    cfg: &SimConfig,
    stop: &AtomicBool,
) -> Result<(SimReport, SimEnd), PtyError> {
    let speed = if cfg.speed.is_finite() && cfg.speed > 0.0 {
        cfg.speed
    } else {
        1.0
    };
    let mut board = VirtualBoard::new(cfg.clone());
    let mut corruptor = Corruptor::new(cfg.corrupt_ppm, cfg.seed);
    let origin = Instant::now();
    let mut connected = false;
    let mut ended_at: Option<Instant> = None;
    let mut buf = [0u8; 1024];
    let board_now = |origin: Instant| (origin.elapsed().as_secs_f64() * 1e6 * speed) as u64;
    let end = loop {
        if stop.load(Ordering::Relaxed) {
            break SimEnd::Interrupted;
        }
        // Catch up with the clock in small steps, writing between them, so that a late wake-up
        // (a busy host machine) does not overflow the board's small outbound queue.
        let now_us = board_now(origin);
        while board.now_us() < now_us {
            board.advance_to(now_us.min(board.now_us() + CATCH_UP_STEP_US));
            if connected {
                flush_tx(&mut board, &mut corruptor, pty)?;
            }
        }

        match pty.wait(if connected && board.tx_len() > 0 {
            Duration::ZERO
        } else {
            TICK
        })? {
            MasterEvent::HungUp if connected => {
                break board.ended().unwrap_or(SimEnd::HostClosed);
            }
            MasterEvent::HungUp | MasterEvent::Idle => {}
            MasterEvent::Readable => match pty.read(&mut buf)? {
                None if connected => break board.ended().unwrap_or(SimEnd::HostClosed),
                None | Some(0) => {}
                Some(n) => {
                    if !connected {
                        connected = true;
                        pty.release_slave();
                    }
                    board.advance_to(board_now(origin));
                    board.receive(&buf[..n]);
                }
            },
        }
        if connected {
            flush_tx(&mut board, &mut corruptor, pty)?;
        }

        if board.ended().is_some() && board.tx_len() == 0 {
            let since = *ended_at.get_or_insert_with(Instant::now);
            if since.elapsed() >= LINGER {
                break board.ended().unwrap_or(SimEnd::HostStopped);
            }
        } else {
            ended_at = None;
        }
        if connected && board.tx_len() > 0 {
            // The host is not reading fast enough; do not spin.
            std::thread::sleep(Duration::from_micros(200));
        }
    };
    let (samples, tilt_readings, status) = board.counts();
    let mut report = corruptor.report();
    report.samples = samples;
    report.tilt_readings = tilt_readings;
    report.board_dropped_frames = status.dropped_frames;
    report.board_dropped_samples = status.dropped_samples;
    Ok((report, end))
}

#[cfg(test)]
mod tests;
