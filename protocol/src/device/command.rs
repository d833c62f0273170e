//! Command validation: the rate limits of `Start`.

use core::ops::RangeInclusive;

use crate::messages::NackReason;

/// Accepted potentiometer sample rates, Hz.
pub const POT_RATE_HZ: RangeInclusive<u32> = 100..=10_000;
/// Accepted read rates of each inclinometer, Hz.
pub const TILT_RATE_HZ: RangeInclusive<u32> = 1..=1_000;

/// A validated sampling configuration, what the firmware programs its timers with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RunConfig {
    /// Requested potentiometer rate, Hz.
    pub pot_rate_hz: u32,
    /// Potentiometer sample period actually used, microseconds: `1e6 / pot_rate_hz` rounded
    /// to the nearest microsecond. The ADC timer must run at exactly this period; it is the
    /// `period_us` of every [`crate::PotBatch`].
    pub pot_period_us: u32,
    /// Read rate of each inclinometer, Hz.
    pub tilt_rate_hz: u32,
}

impl RunConfig {
    /// Validates `Start`'s rates.
    pub fn new(pot_rate_hz: u32, tilt_rate_hz: u32) -> Result<Self, NackReason> {
        if !POT_RATE_HZ.contains(&pot_rate_hz) || !TILT_RATE_HZ.contains(&tilt_rate_hz) {
            return Err(NackReason::RateOutOfRange);
        }
        Ok(Self {
            pot_rate_hz,
            pot_period_us: (1_000_000 + pot_rate_hz / 2) / pot_rate_hz,
            tilt_rate_hz,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rate_limits_are_inclusive() {
        assert!(RunConfig::new(100, 1).is_ok());
        assert!(RunConfig::new(10_000, 1_000).is_ok());
        for (pot, tilt) in [
            (99, 10),
            (10_001, 10),
            (1000, 0),
            (1000, 1001),
            (0, 0),
            (u32::MAX, u32::MAX),
        ] {
            assert_eq!(
                RunConfig::new(pot, tilt),
                Err(NackReason::RateOutOfRange),
                "{pot} {tilt}"
            );
        }
    }

    #[test]
    fn period_is_rounded_to_the_nearest_microsecond() {
        assert_eq!(RunConfig::new(1000, 10).unwrap().pot_period_us, 1000);
        assert_eq!(RunConfig::new(3000, 10).unwrap().pot_period_us, 333); // 333.33
        assert_eq!(RunConfig::new(6000, 10).unwrap().pot_period_us, 167); // 166.67
        assert_eq!(RunConfig::new(100, 10).unwrap().pot_period_us, 10_000);
        assert_eq!(RunConfig::new(10_000, 10).unwrap().pot_period_us, 100);
    }
}
