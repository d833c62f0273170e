//! The potentiometer's ADC source on the STM32: ADC1 on PA1, one conversion per TIM3 update
//! event (TRGO), DMA2 stream 0 into a circular buffer of [`POT_RING_LEN`] samples. The CPU never
//! touches a single conversion; `crate::pot` does the bookkeeping.

use embassy_stm32::adc::{Adc, AdcChannel, Exten, RingBufferedAdc, SampleTime};
use embassy_stm32::peripherals::{ADC1, TIM3};
use embassy_stm32::time::Hertz;
use embassy_stm32::timer::low_level::{MasterMode, Timer};
use embassy_stm32::triggers::TIM3_TRGO;
use embassy_time::{block_for, Duration};
use static_cell::ConstStaticCell;

use super::pins::PotPins;
use super::Irqs;
use crate::shared::now_us;

/// DMA ring length in samples: 25.6 ms at the highest rate (10 kHz), five drain periods.
pub const POT_RING_LEN: usize = 256;
/// TIM3 counter clock.
const TRIGGER_TICK_HZ: u32 = 1_000_000;
/// Longer than one conversion (480 + 12 ADC clocks at 21..24 MHz, about 23 us).
const CONVERSION_SETTLE_US: u64 = 50;

static DMA_BUF: ConstStaticCell<[u16; POT_RING_LEN]> = ConstStaticCell::new([0; POT_RING_LEN]);

/// The timer-paced, DMA-fed ADC.
pub struct PotAdc {
    trigger: Timer<'static, TIM3>,
    ring: RingBufferedAdc<'static, ADC1>,
}

impl PotAdc {
    /// Configures TIM3, ADC1 and the DMA ring; nothing is sampled until [`PotAdc::start`].
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
            Irqs,
            [(pins.pot_wiper.degrade_adc(), SampleTime::CYCLES480)].into_iter(),
            TIM3_TRGO,
            Exten::RISING_EDGE,
        );
        Self { trigger, ring }
    }

    /// Converts every `period_us` from now on into an empty ring; returns the board time at
    /// which TIM3 was enabled (the first conversion comes one period later).
    pub fn start(&mut self, period_us: u32) -> u64 {
        let t = &self.trigger;
        t.stop();
        t.set_master_mode(MasterMode::ENABLE);
        // Run periods are 100..=10_000 us (`rig_protocol::device::POT_RATE_HZ`): they fit.
        t.set_max_compare_value(u16::try_from(period_us - 1).unwrap_or(u16::MAX));
        t.reset();
        // Starting the DMA also issues one software-started conversion: let it land, drop it.
        self.ring.start();
        block_for(Duration::from_micros(CONVERSION_SETTLE_US));
        self.ring.clear();
        t.set_master_mode(MasterMode::UPDATE);
        cortex_m::interrupt::free(|_| {
            t.start();
            now_us()
        })
    }

    /// Stops the trigger timer.
    pub fn stop(&mut self) {
        self.trigger.stop();
    }

    /// Moves the conversions not read yet into `out`, oldest first; returns how many.
    pub fn read_latest(&mut self, _now_us: u64, out: &mut [u16; POT_RING_LEN]) -> usize {
        self.ring.read_latest(out)
    }
}
