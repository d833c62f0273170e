//! Counting a run: frames, samples, lost samples and corrupt frames, as `rigctl record` reports
//! them in its last line `frames N, samples N, dropped N, crc_errors N`.
//!
//! # Definitions
//!
//! - `frames`: frames that passed every check (COBS, CRC-32, postcard), of any message kind.
//! - `samples`: potentiometer samples in the received [`PotBatch`]es.
//! - `crc_errors`: frames the host threw away, whatever check failed first (COBS structure,
//!   CRC, postcard, overlong; `rig_protocol::DecoderStats::corrupt`). A corrupted byte inside a
//!   frame costs exactly that frame and one count here.
//! - `dropped`: potentiometer samples the board took (or should have taken) that the host does
//!   not have, the larger of two counts:
//!   1. *missing from the stream*. Samples lie on a grid: sample `i` of a batch is at
//!      `t0_us + i * period_us`. Between two consecutive received batches `A`, `B` the samples
//!      missing are `round((B.t0_us - (A.t0_us + A.len * period_us)) / period_us)`. This counts
//!      batches lost on the link (corrupt frames), batches the board dropped because its queue
//!      was full (the board's batcher gives every closed batch a `seq`, sent or not, so both
//!      show as a `seq` gap) and samples the ADC never took (an overrun breaks the grid without
//!      a `seq` gap). Batches lost before the first received one (its `seq` > 0) are estimated
//!      at the mean received batch length each. Batches lost after the last received one are
//!      not visible in the stream.
//!   2. *reported by the board*: `dropped_samples` of the last [`Status`] (queue drops since
//!      `Start`), which also covers queue drops after the last received batch.
//!
//!   Both counts see a queue drop in the middle of the run, so they are not added.
//!
//!   To these are added the *inclinometer readings missing from the stream*: each sensor's
//!   readings lie on its own grid (the smallest interval seen between two of its readings);
//!   between two consecutive received readings of a sensor `round(dt / period) - 1` are
//!   missing (readings lost to a corrupt frame, not only counted in `crc_errors`).

use rig_protocol::{DeviceMsg, PotBatch, Status};

/// The running counts of one recording session (or of a recording read back).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Tally {
    /// Good frames, all kinds.
    pub frames: u64,
    /// Potentiometer samples received.
    pub samples: u64,
    /// Potentiometer batches received.
    pub pot_batches: u64,
    /// Inclinometer readings received.
    pub tilt_readings: u64,
    /// Frames thrown away by the decoder (see the module documentation).
    pub crc_errors: u64,
    /// Samples missing between received batches (time-grid gaps).
    pub gap_samples: u64,
    /// Batches missing between received batches (`seq` gaps).
    pub gap_batches: u64,
    /// `seq` of the first received batch (batches before it were lost).
    pub first_seq: Option<u32>,
    /// The last `Status` received.
    pub last_status: Option<Status>,
    /// Inclinometer readings missing between received readings of the same sensor.
    pub tilt_gap_readings: u64,
    last_pot: Option<PotEnd>,
    /// Per sensor: last reading time and the smallest interval seen, us.
    tilt_grid: Vec<(u64, Option<u64>)>,
    /// Readings of each sensor since its last gap count (counted once the period is known).
    tilt_unresolved: Vec<Vec<u64>>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct PotEnd {
    seq: u32,
    /// Board time where the next sample is due.
    next_t_us: u64,
}

impl Tally {
    /// An empty tally.
    pub fn new() -> Self {
        Self::default()
    }

    /// Counts one good frame.
    pub fn on_message(&mut self, msg: &DeviceMsg) {
        self.frames = self.frames.saturating_add(1);
        match msg {
            DeviceMsg::Pot(batch) => self.on_pot(batch),
            DeviceMsg::Tilt(r) => self.on_tilt(r.sensor, r.t_us),
            DeviceMsg::Status(status) => self.last_status = Some(*status),
            DeviceMsg::Hello(_)
            | DeviceMsg::Pong { .. }
            | DeviceMsg::Ack(_)
            | DeviceMsg::Nack { .. } => {}
        }
    }

    fn on_pot(&mut self, batch: &PotBatch) {
        let len = batch.samples.len() as u64;
        let period_us = u64::from(batch.period_us.max(1));
        match self.last_pot {
            Some(prev) if batch.seq > prev.seq => {
                self.gap_batches = self
                    .gap_batches
                    .saturating_add(u64::from(batch.seq - prev.seq - 1));
                if batch.t0_us > prev.next_t_us {
                    let gap_us = batch.t0_us - prev.next_t_us;
                    let gap = gap_us / period_us
                        + u64::from(gap_us % period_us >= period_us - period_us / 2);
                    self.gap_samples = self.gap_samples.saturating_add(gap);
                }
            }
            // A repeated or older seq: the board restarted its run; start counting afresh.
            Some(_) => {}
            None => self.first_seq = Some(batch.seq),
        }
        self.samples = self.samples.saturating_add(len);
        self.pot_batches = self.pot_batches.saturating_add(1);
        self.last_pot = Some(PotEnd {
            seq: batch.seq,
            next_t_us: batch.t0_us.saturating_add(len.saturating_mul(period_us)),
        });
    }

    fn on_tilt(&mut self, sensor: u8, t_us: u64) {
        self.tilt_readings = self.tilt_readings.saturating_add(1);
        let s = usize::from(sensor);
        if self.tilt_grid.len() <= s {
            self.tilt_grid.resize(s + 1, (0, None));
            self.tilt_unresolved.resize(s + 1, Vec::new());
        }
        let (last, period) = &mut self.tilt_grid[s];
        if *last > 0 && t_us > *last {
            let dt = t_us - *last;
            let pending = &mut self.tilt_unresolved[s];
            let count =
                |dt: u64, p: u64| (dt / p + u64::from(dt % p >= p - p / 2)).saturating_sub(1);
            match *period {
                // The first two intervals wait: their smaller one is the grid.
                None if pending.is_empty() => pending.push(dt),
                None => {
                    pending.push(dt);
                    let p = pending.iter().copied().min().unwrap_or(dt).max(1);
                    *period = Some(p);
                    for dt in pending.drain(..) {
                        self.tilt_gap_readings =
                            self.tilt_gap_readings.saturating_add(count(dt, p));
                    }
                }
                Some(p) => {
                    let p = p.min(dt);
                    *period = Some(p);
                    self.tilt_gap_readings = self.tilt_gap_readings.saturating_add(count(dt, p));
                }
            }
        }
        *last = t_us;
    }

    /// The board acknowledged a new `Start`: its `seq` and counters restart, so batches from
    /// before (a previous run still streaming) do not make a gap.
    pub fn start_run(&mut self) {
        self.last_pot = None;
        self.first_seq = None;
        self.last_status = None;
        self.tilt_grid.clear();
        self.tilt_unresolved.clear();
    }

    /// Samples estimated lost before the first received batch.
    pub fn leading_samples(&self) -> u64 {
        match self.first_seq {
            Some(seq) if seq > 0 && self.pot_batches > 0 => {
                let mean = self.samples as f64 / self.pot_batches as f64;
                (f64::from(seq) * mean).round() as u64
            }
            _ => 0,
        }
    }

    /// Lost potentiometer samples (module documentation: the larger of the stream's and the
    /// board's count).
    pub fn dropped(&self) -> u64 {
        let stream = self.gap_samples.saturating_add(self.leading_samples());
        let board = self.last_status.map_or(0, |s| u64::from(s.dropped_samples));
        stream.max(board).saturating_add(self.tilt_gap_readings)
    }

    /// The summary line: `frames N, samples N, dropped N, crc_errors N`.
    pub fn summary_line(&self) -> String {
        format!(
            "frames {}, samples {}, dropped {}, crc_errors {}",
            self.frames,
            self.samples,
            self.dropped(),
            self.crc_errors
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn batch(seq: u32, t0_us: u64, len: usize) -> DeviceMsg {
        let mut samples = heapless::Vec::new();
        for i in 0..len {
            samples.push(i as u16).unwrap();
        }
        DeviceMsg::Pot(PotBatch {
            seq,
            t0_us,
            period_us: 1000,
            samples,
        })
    }

    #[test]
    fn contiguous_batches_drop_nothing() {
        let mut t = Tally::new();
        for k in 0..10u32 {
            t.on_message(&batch(k, 5_000 + u64::from(k) * 20_000, 20));
        }
        assert_eq!((t.frames, t.samples, t.dropped()), (10, 200, 0));
        assert_eq!(
            t.summary_line(),
            "frames 10, samples 200, dropped 0, crc_errors 0"
        );
    }

    #[test]
    fn a_lost_batch_counts_its_samples_from_the_time_grid() {
        let mut t = Tally::new();
        t.on_message(&batch(0, 0, 20));
        // seq 1 (20 samples at 20..40 ms) lost, seq 2 is short (a flush), seq 3 lost (7), seq 4.
        t.on_message(&batch(2, 40_000, 5));
        t.on_message(&batch(4, 52_000, 10));
        assert_eq!(t.gap_batches, 2);
        assert_eq!(t.gap_samples, 27);
        assert_eq!(t.dropped(), 27);
        assert_eq!(t.samples, 35);
    }

    #[test]
    fn an_overrun_is_a_time_gap_without_seq_gap() {
        let mut t = Tally::new();
        t.on_message(&batch(0, 0, 10));
        // Samples at 10 and 11 ms never taken; the batcher closed seq 0 and seq 1 starts at 12.
        t.on_message(&batch(1, 12_000, 10));
        assert_eq!((t.gap_batches, t.dropped()), (0, 2));
    }

    #[test]
    fn leading_loss_is_estimated_and_board_count_is_a_floor() {
        let mut t = Tally::new();
        t.on_message(&batch(2, 40_000, 20));
        t.on_message(&batch(3, 60_000, 20));
        assert_eq!(t.leading_samples(), 40);
        assert_eq!(t.dropped(), 40);
        t.on_message(&DeviceMsg::Status(Status {
            dropped_samples: 100,
            ..Status::default()
        }));
        assert_eq!(t.dropped(), 100);
        assert_eq!(t.frames, 3);
    }

    #[test]
    fn restart_does_not_count_a_gap() {
        let mut t = Tally::new();
        t.on_message(&batch(5, 100_000, 20));
        t.on_message(&batch(0, 900_000, 20));
        t.on_message(&batch(1, 920_000, 20));
        assert_eq!(t.gap_samples, 0);
    }
}
