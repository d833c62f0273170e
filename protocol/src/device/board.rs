//! The board core: command state machine, counters, and the outbound queue.

use crate::device::command::RunConfig;
use crate::device::pot::PotBatcher;
use crate::device::queue::FrameQueue;
use crate::device::tilt::TiltScheduler;
use crate::frame::{encode_device, Decoded, HostDecoder, DEVICE_FRAME_MAX, FRAME_BUDGET};
use crate::messages::{
    CommandKind, DeviceMsg, Hello, HostMsg, NackReason, Status, TiltReading, PROTOCOL_VERSION,
};
use crate::schema::SCHEMA_HASH;

/// A `Status` goes out this often while running (plus one at `Stop`).
pub const STATUS_PERIOD_US: u64 = 1_000_000;
/// An open potentiometer batch is sent at the latest this long after its first sample, so that
/// low rates still stream (100 Hz: 10-sample batches instead of 64).
pub const POT_MAX_LATENCY_US: u64 = 100_000;
/// Outbound queue size: 8 frame budgets (2 KiB), about 14 ms of the heaviest stream
/// (10 kHz pot, 3 x 1 kHz tilt ~ 150 kB/s) -- more than a USB frame or a busy UART DMA.
pub const TX_QUEUE_BYTES: usize = 8 * FRAME_BUDGET;
/// Queue bytes that data frames (pot, tilt, periodic status) may not use, kept for replies
/// (`Hello`, `Pong`, `Ack`, `Nack`, the final `Status`) so that a saturated link still answers.
pub const CONTROL_RESERVE: usize = FRAME_BUDGET;

const _: () = assert!(TX_QUEUE_BYTES >= CONTROL_RESERVE + 2 * DEVICE_FRAME_MAX);

/// Fixed facts about the board, reported in [`Hello`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BoardInfo {
    /// major, minor, patch.
    pub firmware_version: [u8; 3],
    /// The MCU's unique id.
    pub board_id: [u8; 12],
    /// Inclinometers detected at boot.
    pub tilt_sensors: u8,
}

/// What the firmware must do with its sampling hardware after a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Action {
    /// Nothing changes.
    None,
    /// Start (or restart with new rates) the ADC timer at `pot_period_us` and the tilt reads.
    StartSampling(RunConfig),
    /// Stop the ADC timer and the tilt reads.
    StopSampling,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Priority {
    /// Sent only if the control reserve stays free.
    Data,
    /// May use the whole queue.
    Control,
}

/// The board's logic, without hardware. See the [module documentation](crate::device).
///
/// Counters in [`Status`] count since the last accepted `Start` (they are zeroed by it);
/// `rx_errors` also counts host frames that failed to decode while idle.
#[derive(Debug)]
pub struct Board {
    info: BoardInfo,
    run: Option<RunConfig>,
    pot: PotBatcher,
    tilt: TiltScheduler,
    tilt_skipped_seen: u64,
    counters: Status,
    next_status_us: u64,
    rx: HostDecoder,
    tx: FrameQueue<TX_QUEUE_BYTES>,
}

impl Board {
    /// A board that is idle and has sent nothing yet.
    pub fn new(info: BoardInfo) -> Self {
        Self {
            info,
            run: None,
            pot: PotBatcher::default(),
            tilt: TiltScheduler::stopped(),
            tilt_skipped_seen: 0,
            counters: Status::default(),
            next_status_us: 0,
            rx: HostDecoder::new(),
            tx: FrameQueue::new(),
        }
    }

    /// The `Hello` this board sends.
    pub fn hello(&self) -> Hello {
        Hello {
            protocol_version: PROTOCOL_VERSION,
            firmware_version: self.info.firmware_version,
            board_id: self.info.board_id,
            schema_hash: SCHEMA_HASH,
            tilt_sensors: self.info.tilt_sensors,
        }
    }

    /// Call once at power-up: queues the `Hello`.
    pub fn boot(&mut self, _now_us: u64) {
        let hello = self.hello();
        self.send(&DeviceMsg::Hello(hello), Priority::Control);
    }

    /// The running configuration, `None` when idle.
    pub fn run_config(&self) -> Option<RunConfig> {
        self.run
    }

    /// True between an accepted `Start` and `Stop`.
    pub fn is_running(&self) -> bool {
        self.run.is_some()
    }

    /// Counters as they would be sent now.
    pub fn status(&self, now_us: u64) -> Status {
        Status {
            uptime_us: now_us,
            ..self.counters
        }
    }

    /// Feeds bytes received from the host; decodes and handles every complete command. Corrupt
    /// frames count in `rx_errors`. Returns the net change of the sampling state over all the
    /// commands in `bytes` (`None` if it ends where it began).
    pub fn receive(&mut self, now_us: u64, bytes: &[u8]) -> Action {
        let before = self.run;
        for &byte in bytes {
            match self.rx.push(byte) {
                None => {}
                Some(Decoded::Frame(cmd)) => {
                    self.handle_command(now_us, cmd);
                }
                Some(Decoded::CorruptFrame { .. }) => {
                    self.counters.rx_errors = self.counters.rx_errors.saturating_add(1);
                }
            }
        }
        match (before, self.run) {
            (Some(a), Some(b)) if a == b => Action::None,
            (None, None) => Action::None,
            (_, Some(cfg)) => Action::StartSampling(cfg),
            (Some(_), None) => Action::StopSampling,
        }
    }

    /// Handles one decoded command: queues its answer and says what the hardware must do.
    ///
    /// - `Start` (idle, rates valid): zeroes counters and `seq`, starts the tilt schedule at
    ///   `now_us`, answers `Ack(Start)`. Running: `Nack(AlreadyRunning)`. Bad rates:
    ///   `Nack(RateOutOfRange)`.
    /// - `Stop` (running): sends the open pot batch, a `Status`, then `Ack(Stop)`, so the
    ///   `Ack` is the run's last frame. Idle: `Nack(NotRunning)`.
    /// - `Ping { nonce }`: `Pong { nonce }`. `GetInfo`: `Hello`.
    pub fn handle_command(&mut self, now_us: u64, cmd: HostMsg) -> Action {
        match cmd {
            HostMsg::Start {
                pot_rate_hz,
                tilt_rate_hz,
            } => {
                if self.run.is_some() {
                    self.nack(CommandKind::Start, NackReason::AlreadyRunning);
                    return Action::None;
                }
                match RunConfig::new(pot_rate_hz, tilt_rate_hz) {
                    Ok(cfg) => {
                        self.start(now_us, cfg);
                        self.send(&DeviceMsg::Ack(CommandKind::Start), Priority::Control);
                        Action::StartSampling(cfg)
                    }
                    Err(reason) => {
                        self.nack(CommandKind::Start, reason);
                        Action::None
                    }
                }
            }
            HostMsg::Stop => {
                if self.run.is_none() {
                    self.nack(CommandKind::Stop, NackReason::NotRunning);
                    return Action::None;
                }
                if let Some(batch) = self.pot.flush() {
                    self.send(&DeviceMsg::Pot(batch), Priority::Control);
                }
                self.run = None;
                self.tilt = TiltScheduler::stopped();
                self.send(&DeviceMsg::Status(self.status(now_us)), Priority::Control);
                self.send(&DeviceMsg::Ack(CommandKind::Stop), Priority::Control);
                Action::StopSampling
            }
            HostMsg::Ping { nonce } => {
                self.send(&DeviceMsg::Pong { nonce }, Priority::Control);
                Action::None
            }
            HostMsg::GetInfo => {
                let hello = self.hello();
                self.send(&DeviceMsg::Hello(hello), Priority::Control);
                Action::None
            }
        }
    }

    fn start(&mut self, now_us: u64, cfg: RunConfig) {
        self.run = Some(cfg);
        self.counters = Status::default();
        self.pot = PotBatcher::new(cfg.pot_period_us);
        self.tilt = TiltScheduler::start(now_us, cfg.tilt_rate_hz, self.info.tilt_sensors);
        self.tilt_skipped_seen = 0;
        self.next_status_us = now_us.saturating_add(STATUS_PERIOD_US);
    }

    fn nack(&mut self, command: CommandKind, reason: NackReason) {
        self.send(&DeviceMsg::Nack { command, reason }, Priority::Control);
    }

    /// Encodes and queues `msg`; on a full queue drops it whole and counts it.
    fn send(&mut self, msg: &DeviceMsg, priority: Priority) -> bool {
        let mut buf = [0u8; DEVICE_FRAME_MAX];
        let queued = match encode_device(msg, &mut buf) {
            Ok(frame) => {
                let reserve = match priority {
                    Priority::Data => CONTROL_RESERVE,
                    Priority::Control => 0,
                };
                self.tx.push_frame(frame, reserve)
            }
            // Cannot happen (the buffer holds the largest message); counted as a drop anyway.
            Err(_) => false,
        };
        if !queued {
            let c = &mut self.counters;
            c.dropped_frames = c.dropped_frames.saturating_add(1);
            if let DeviceMsg::Pot(batch) = msg {
                c.dropped_samples = c.dropped_samples.saturating_add(batch.samples.len() as u32);
            }
        }
        queued
    }

    /// One potentiometer sample taken at board time `t_us` (ignored while idle). Queues a
    /// `Pot` frame when a batch closes; never blocks.
    pub fn on_pot_sample(&mut self, t_us: u64, raw: u16) {
        if self.run.is_none() {
            return;
        }
        if let Some(batch) = self.pot.push(t_us, raw) {
            self.send(&DeviceMsg::Pot(batch), Priority::Data);
        }
    }

    /// The inclinometer to read now, if one is due (`None` while idle). Read slots missed
    /// because this was called late count as `overruns`.
    pub fn tilt_due(&mut self, now_us: u64) -> Option<u8> {
        let sensor = self.tilt.poll(now_us);
        let skipped = self.tilt.skipped();
        let new = skipped.saturating_sub(self.tilt_skipped_seen);
        if new > 0 {
            self.tilt_skipped_seen = skipped;
            let c = &mut self.counters;
            c.overruns = c
                .overruns
                .saturating_add(u32::try_from(new).unwrap_or(u32::MAX));
        }
        sensor
    }

    /// A successful inclinometer reading (ignored while idle).
    pub fn on_tilt_reading(&mut self, reading: TiltReading) {
        if self.run.is_some() {
            self.send(&DeviceMsg::Tilt(reading), Priority::Data);
        }
    }

    /// An inclinometer read failed (SPI CRC or status error).
    pub fn on_sensor_error(&mut self) {
        self.counters.sensor_errors = self.counters.sensor_errors.saturating_add(1);
    }

    /// The ADC/DMA sampler fell behind and lost samples.
    pub fn on_overrun(&mut self) {
        self.counters.overruns = self.counters.overruns.saturating_add(1);
    }

    /// Periodic housekeeping: sends a pot batch that has waited [`POT_MAX_LATENCY_US`] and the
    /// periodic `Status`. Call at least every few milliseconds, or at [`Self::next_deadline_us`].
    pub fn poll(&mut self, now_us: u64) {
        if self.run.is_none() {
            return;
        }
        if let Some(batch) = self.pot.flush_older_than(now_us, POT_MAX_LATENCY_US) {
            self.send(&DeviceMsg::Pot(batch), Priority::Data);
        }
        if now_us >= self.next_status_us {
            self.send(&DeviceMsg::Status(self.status(now_us)), Priority::Data);
            // Skip whole periods if polled very late; never a burst of statuses.
            while self.next_status_us <= now_us {
                self.next_status_us = self.next_status_us.saturating_add(STATUS_PERIOD_US);
                if self.next_status_us == u64::MAX {
                    break;
                }
            }
        }
    }

    /// Earliest board time at which [`Self::poll`] or [`Self::tilt_due`] has something to do;
    /// `None` while idle.
    pub fn next_deadline_us(&self) -> Option<u64> {
        self.run?;
        let mut deadline = self.next_status_us;
        if let Some(t0) = self.pot.open_since_us() {
            deadline = deadline.min(t0.saturating_add(POT_MAX_LATENCY_US));
        }
        if let Some(due) = self.tilt.next_due_us() {
            deadline = deadline.min(due);
        }
        Some(deadline)
    }

    /// Bytes waiting to be sent.
    pub fn tx_len(&self) -> usize {
        self.tx.len()
    }

    /// The oldest waiting bytes that are contiguous (write them, then [`Self::tx_consume`]).
    pub fn tx_peek(&self) -> &[u8] {
        self.tx.peek()
    }

    /// Forgets `n` bytes that were sent.
    pub fn tx_consume(&mut self, n: usize) {
        self.tx.consume(n);
    }

    /// Moves waiting bytes into `out`; returns how many.
    pub fn tx_pop_into(&mut self, out: &mut [u8]) -> usize {
        self.tx.pop_into(out)
    }
}
