//! The potentiometer: the board's ADC source converts at the commanded period into a ring of
//! [`POT_RING_LEN`] samples without the CPU (STM32: TIM3 TRGO paces ADC1, DMA2 stream 0 fills
//! the ring; emulated board: a known signal computed from board time).
//!
//! Every [`DRAIN_PERIOD_US`] (and right before the board core handles host bytes)
//! [`PotSampler::drain`] takes the new samples out of the ring and hands each one, with its
//! board time, to the protocol's board core, which batches them and queues the frames without
//! waiting.
//!
//! Timestamps: sample `k` of a run segment was converted at `t_start + (k + 1) * period_us`,
//! where `t_start` is the board time at which the source's trigger was enabled (its first
//! conversion comes one period later). The trigger and embassy-time run from the same clock,
//! so that arithmetic does not drift. A drain that finds fewer samples than trigger periods
//! elapsed (the ring was lapped) is an overrun: counted, and the segment restarts with a new
//! `t_start`, so timestamps stay exact (the batcher closes the batch at the gap).

use embassy_time::{Duration, Ticker};
use rig_protocol::device::Board;

use crate::board::{PotAdc, POT_RING_LEN};
use crate::log::warning;
use crate::shared::{self, now_us};

/// How often the ring is drained (and the board core polled).
pub const DRAIN_PERIOD_US: u64 = 5_000;

/// The board's ADC source and the bookkeeping of the current run segment.
pub struct PotSampler {
    adc: PotAdc,
    /// Sampling period of the run, 0 while stopped.
    period_us: u32,
    /// Board time at which the trigger was enabled for this segment.
    t_start_us: u64,
    /// Samples handed to the board core in this segment.
    taken: u64,
}

impl PotSampler {
    /// Wraps the board's configured (idle) ADC source.
    pub fn new(adc: PotAdc) -> Self {
        Self {
            adc,
            period_us: 0,
            t_start_us: 0,
            taken: 0,
        }
    }

    /// Starts (or restarts) sampling every `period_us` microseconds.
    pub fn start(&mut self, period_us: u32) {
        self.period_us = period_us.max(1);
        self.start_segment();
    }

    /// Stops the trigger; conversions already in the ring are dropped.
    pub fn stop(&mut self) {
        self.adc.stop();
        self.period_us = 0;
    }

    fn start_segment(&mut self) {
        self.t_start_us = self.adc.start(self.period_us);
        self.taken = 0;
    }

    /// Hands every sample converted so far to `board` (with its board time). Detects a lapped
    /// ring, counts it and restarts the segment.
    pub fn drain(&mut self, board: &mut Board, now_us: u64) {
        if self.period_us == 0 {
            return;
        }
        let period = u64::from(self.period_us);
        let mut samples = [0u16; POT_RING_LEN];
        let n = self.adc.read_latest(now_us, &mut samples);
        // Trigger events so far; the newest conversion may still be in flight.
        let triggers = now_us.saturating_sub(self.t_start_us) / period;
        let after = self.taken + n as u64;
        if triggers > after + 1 {
            warning!("pot: ring lapped, restarting the segment");
            board.on_overrun();
            self.start_segment();
            return;
        }
        for (k, &raw) in (self.taken..).zip(&samples[..n]) {
            board.on_pot_sample(self.t_start_us + (k + 1) * period, raw);
        }
        self.taken = after;
    }
}

/// Drains the ring and lets the board core do its periodic work (latency flush of pot
/// batches, periodic `Status`) every [`DRAIN_PERIOD_US`].
#[embassy_executor::task]
pub async fn adc_task() -> ! {
    let mut ticker = Ticker::every(Duration::from_micros(DRAIN_PERIOD_US));
    loop {
        ticker.next().await;
        shared::with(|s| {
            let now = now_us();
            s.pot.drain(&mut s.board, now);
            s.board.poll(now);
        });
        shared::tx_ready();
    }
}
