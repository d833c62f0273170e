//! The potentiometer: ADC1 on PA1, one conversion per TIM3 update event (TRGO), DMA2 stream 0
//! into a circular buffer of [`RING_LEN`] samples.
//!
//! The CPU never touches a single conversion. Every [`DRAIN_PERIOD_US`] (and right before the
//! board core handles host bytes) [`PotSampler::drain`] takes the new samples out of the ring
//! and hands each one, with its board time, to the protocol's board core, which batches them
//! and queues the frames without waiting.
//!
//! Timestamps: sample `k` of a run segment was converted at `t_start + (k + 1) * period_us`,
//! where `t_start` is the board time at which TIM3 was enabled (its first update event comes
//! one period later). TIM3 and the embassy-time timer (TIM9) run from the same crystal, so that
//! arithmetic does not drift. A drain that finds fewer samples than timer periods elapsed (the
//! DMA lapped the ring) is an overrun: counted, and the segment restarts with a new `t_start`,
//! so timestamps stay exact (the batcher closes the batch at the gap).

use embassy_stm32::adc::{Adc, AdcChannel, Exten, RingBufferedAdc, SampleTime};
use embassy_stm32::peripherals::{ADC1, TIM3};
use embassy_stm32::time::Hertz;
use embassy_stm32::timer::low_level::{MasterMode, Timer};
use embassy_stm32::triggers::TIM3_TRGO;
use embassy_time::{block_for, Duration, Ticker};
use rig_protocol::device::Board;
use static_cell::ConstStaticCell;

use crate::board::PotPins;
use crate::clock::now_us;
use crate::shared;

/// DMA ring length in samples: 25.6 ms at the highest rate (10 kHz), five drain periods.
const RING_LEN: usize = 256;
/// How often the ring is drained (and the board core polled).
pub const DRAIN_PERIOD_US: u64 = 5_000;
/// TIM3 counter clock.
const TRIGGER_TICK_HZ: u32 = 1_000_000;
/// Longer than one conversion (480 + 12 ADC clocks at 21..24 MHz, about 23 us).
const CONVERSION_SETTLE_US: u64 = 50;

static DMA_BUF: ConstStaticCell<[u16; RING_LEN]> = ConstStaticCell::new([0; RING_LEN]);

/// The timer-paced, DMA-fed ADC and the bookkeeping of the current run segment.
pub struct PotSampler {
    trigger: Timer<'static, TIM3>,
    ring: RingBufferedAdc<'static, ADC1>,
    /// Sampling period of the run, 0 while stopped.
    period_us: u32,
    /// Board time at which TIM3 was enabled for this segment.
    t_start_us: u64,
    /// Samples handed to the board core in this segment.
    taken: u64,
}

impl PotSampler {
    /// Configures TIM3, ADC1 and the DMA ring; nothing is sampled until [`PotSampler::start`].
    pub fn new(pins: PotPins) -> Self {
        let mut trigger = Timer::new(pins.pot_trigger);
        // While TIM3 is being configured, TRGO follows the counter enable, so loading the
        // prescaler with an update event does not start a conversion.
        trigger.set_master_mode(MasterMode::ENABLE);
        // TIM3 counts microseconds (its clock is 84 or 96 MHz, a whole number of MHz on every
        // supported chip), so any period of whole microseconds is exact: ARR = period - 1.
        defmt::debug_assert_eq!(trigger.get_clock_frequency().0 % TRIGGER_TICK_HZ, 0);
        trigger.set_tick_freq(Hertz(TRIGGER_TICK_HZ));
        let adc = Adc::new(pins.pot_adc);
        let ring = adc.into_ring_buffered(
            pins.pot_dma,
            DMA_BUF.take(),
            crate::Irqs,
            [(pins.pot_wiper.degrade_adc(), SampleTime::CYCLES480)].into_iter(),
            TIM3_TRGO,
            Exten::RISING_EDGE,
        );
        Self {
            trigger,
            ring,
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

    /// Stops the trigger timer; conversions already in the ring are dropped.
    pub fn stop(&mut self) {
        self.trigger.stop();
        self.period_us = 0;
    }

    fn start_segment(&mut self) {
        let t = &self.trigger;
        t.stop();
        t.set_master_mode(MasterMode::ENABLE);
        // Run periods are 100..=10_000 us (`rig_protocol::device::POT_RATE_HZ`): they fit.
        t.set_max_compare_value(u16::try_from(self.period_us - 1).unwrap_or(u16::MAX));
        t.reset();
        // Starting the DMA also issues one software-started conversion: let it land, drop it.
        self.ring.start();
        block_for(Duration::from_micros(CONVERSION_SETTLE_US));
        self.ring.clear();
        t.set_master_mode(MasterMode::UPDATE);
        self.t_start_us = cortex_m::interrupt::free(|_| {
            t.start();
            now_us()
        });
        self.taken = 0;
    }

    /// Hands every sample converted so far to `board` (with its board time). Detects a lapped
    /// ring, counts it and restarts the segment.
    pub fn drain(&mut self, board: &mut Board, now_us: u64) {
        if self.period_us == 0 {
            return;
        }
        let period = u64::from(self.period_us);
        let mut samples = [0u16; RING_LEN];
        let n = self.ring.read_latest(&mut samples);
        // Update events so far; the newest conversion may still be in flight.
        let triggers = now_us.saturating_sub(self.t_start_us) / period;
        let after = self.taken + n as u64;
        if triggers > after + 1 {
            defmt::warn!("pot: DMA ring lapped, restarting the segment");
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
