//! The potentiometer's ADC source on the emulated board: a ring of [`POT_RING_LEN`]
//! conversions, "converted" at `t_start + (k + 1) * period` like the STM32's timer-paced
//! ADC and DMA, whose values are the known ramp `rig_protocol::device::known_signal::pot_raw`
//! of each conversion's board time. As on the STM32, conversions the CPU did not collect within
//! one ring length are overwritten (`crate::pot` counts the overrun).

use rig_protocol::device::known_signal;

use crate::shared::now_us;

/// Ring length in samples (as on the STM32).
pub const POT_RING_LEN: usize = 256;

/// The emulated ADC ring.
pub struct PotAdc {
    /// Sampling period, 0 while stopped.
    period_us: u64,
    /// Board time at which the trigger started.
    t_start_us: u64,
    /// Conversions moved out of the ring so far.
    read: u64,
}

impl PotAdc {
    /// An idle source.
    pub fn new() -> Self {
        Self {
            period_us: 0,
            t_start_us: 0,
            read: 0,
        }
    }

    /// Converts every `period_us` from now on into an empty ring; returns the board time at
    /// which the trigger started (the first conversion comes one period later).
    pub fn start(&mut self, period_us: u32) -> u64 {
        self.period_us = u64::from(period_us.max(1));
        self.t_start_us = now_us();
        self.read = 0;
        self.t_start_us
    }

    /// Stops converting.
    pub fn stop(&mut self) {
        self.period_us = 0;
    }

    /// Moves the conversions up to `now_us` not read yet into `out`, oldest first (only the
    /// newest [`POT_RING_LEN`] if the ring was lapped); returns how many.
    pub fn read_latest(&mut self, now_us: u64, out: &mut [u16; POT_RING_LEN]) -> usize {
        if self.period_us == 0 {
            return 0;
        }
        let converted = now_us.saturating_sub(self.t_start_us) / self.period_us;
        let first = self.read.max(converted.saturating_sub(POT_RING_LEN as u64));
        let mut n = 0;
        for (k, slot) in (first..converted).zip(out.iter_mut()) {
            *slot = known_signal::pot_raw(self.t_start_us + (k + 1) * self.period_us);
            n += 1;
        }
        self.read = converted;
        n
    }
}
