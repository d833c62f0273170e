//! Wire values checked against the board's own announced configuration.
//!
//! A frame whose CRC is right may still carry values no board in that configuration can send
//! (a firmware bug, a board of another build, a hostile device): a sample period other than
//! the one `Start` asked for, a raw count beyond the 12-bit ADC, an inclinometer index beyond
//! the `Hello`'s `tilt_sensors`, board time going backwards (per stream: the potentiometer
//! batches, each inclinometer), or a batch whose sample times do not fit in a `u64`. Such a
//! frame is not stored, not counted in the [`super::tally::Tally`] and not exported; it is
//! counted here, and `record` reports the count and the first one and exits 1. The period and
//! the monotone times are checked from the acknowledged `Start` on ([`WireCheck::restart`]); the
//! frames before it may be the end of an earlier run.
//!
//! Every reader of a stored recording (`export`, `fuse`, `potcal --recording`) keeps only the
//! frames [`in_range`] passes (the same check, against the configuration the recording's header
//! stores), reports the rest and exits 1.

use rig_protocol::device::RunConfig;
use rig_protocol::{CommandKind, DeviceMsg};

use super::recording::RecordingMeta;

/// Largest raw count of the board's 12-bit ADC.
pub const ADC_MAX: u16 = 4095;

/// Why a frame is out of range.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OutOfRange {
    Period {
        got_us: u32,
        expected_us: u32,
    },
    Raw {
        value: u16,
    },
    Sensor {
        sensor: u8,
        sensors: u8,
    },
    Backwards {
        stream: String,
        t_us: u64,
        after_us: u64,
    },
    TimeOverflow {
        t0_us: u64,
    },
}

impl std::fmt::Display for OutOfRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Period {
                got_us,
                expected_us,
            } => write!(
                f,
                "sample period {got_us} us where Start asked for {expected_us} us"
            ),
            Self::Raw { value } => write!(f, "raw count {value} beyond the 12-bit ADC's {ADC_MAX}"),
            Self::Sensor { sensor, sensors } => write!(
                f,
                "inclinometer {sensor} on a board that announced {sensors}"
            ),
            Self::Backwards {
                stream,
                t_us,
                after_us,
            } => write!(f, "{stream} time {t_us} us before {after_us} us"),
            Self::TimeOverflow { t0_us } => {
                write!(f, "batch at {t0_us} us whose sample times overflow")
            }
        }
    }
}

/// The checker of one run (see the module documentation).
#[derive(Debug, Clone, Default)]
pub struct WireCheck {
    /// `period_us` every batch must carry, when known.
    pot_period_us: Option<u32>,
    /// Inclinometers announced in `Hello`, when known.
    tilt_sensors: Option<u8>,
    /// Board time where the next potentiometer sample is due.
    pot_next_us: Option<u64>,
    /// Last reading time of each inclinometer.
    tilt_last_us: Vec<Option<u64>>,
    /// `Start` acknowledged: the period and the monotone times are checked from here (frames
    /// before it may be the end of a run left over from an earlier session).
    armed: bool,
    /// Frames out of range.
    pub count: u64,
    /// The first of them.
    pub first: Option<OutOfRange>,
}

impl WireCheck {
    /// A checker for a run started at `pot_rate_hz` on a board with `tilt_sensors`
    /// inclinometers (each `None` when unknown: that check is skipped).
    pub fn new(pot_rate_hz: Option<u32>, tilt_sensors: Option<u8>) -> Self {
        let pot_period_us = pot_rate_hz
            .and_then(|hz| RunConfig::new(hz, 1).ok())
            .map(|c| c.pot_period_us);
        Self {
            pot_period_us,
            tilt_sensors,
            ..Self::default()
        }
    }

    /// A new `Start` (acknowledged): board time and counters may restart, and from here every
    /// check applies.
    pub fn restart(&mut self) {
        self.pot_next_us = None;
        self.tilt_last_us.clear();
        self.armed = true;
    }

    /// Checks one frame; `false` (and counted) when it is out of range.
    pub fn accept(&mut self, msg: &DeviceMsg) -> bool {
        match self.verdict(msg) {
            Ok(()) => true,
            Err(why) => {
                self.count = self.count.saturating_add(1);
                self.first.get_or_insert(why);
                false
            }
        }
    }

    fn verdict(&mut self, msg: &DeviceMsg) -> Result<(), OutOfRange> {
        match msg {
            DeviceMsg::Pot(b) => {
                if let Some(expected_us) = self.pot_period_us.filter(|_| self.armed) {
                    if b.period_us != expected_us {
                        return Err(OutOfRange::Period {
                            got_us: b.period_us,
                            expected_us,
                        });
                    }
                }
                if b.period_us == 0 {
                    return Err(OutOfRange::Period {
                        got_us: 0,
                        expected_us: self.pot_period_us.unwrap_or(1),
                    });
                }
                if let Some(&value) = b.samples.iter().find(|&&v| v > ADC_MAX) {
                    return Err(OutOfRange::Raw { value });
                }
                let next = (b.samples.len() as u64)
                    .checked_mul(u64::from(b.period_us))
                    .and_then(|d| b.t0_us.checked_add(d))
                    .ok_or(OutOfRange::TimeOverflow { t0_us: b.t0_us })?;
                if let Some(after_us) = self.pot_next_us.filter(|&n| self.armed && b.t0_us < n) {
                    return Err(OutOfRange::Backwards {
                        stream: "potentiometer".into(),
                        t_us: b.t0_us,
                        after_us,
                    });
                }
                self.pot_next_us = Some(next);
            }
            DeviceMsg::Tilt(r) => {
                if let Some(sensors) = self.tilt_sensors.filter(|&n| r.sensor >= n) {
                    return Err(OutOfRange::Sensor {
                        sensor: r.sensor,
                        sensors,
                    });
                }
                let s = usize::from(r.sensor);
                if self.tilt_last_us.len() <= s {
                    self.tilt_last_us.resize(s + 1, None);
                }
                if let Some(after_us) = self.tilt_last_us[s].filter(|&l| self.armed && r.t_us <= l)
                {
                    return Err(OutOfRange::Backwards {
                        stream: format!("inclinometer {}", r.sensor),
                        t_us: r.t_us,
                        after_us,
                    });
                }
                self.tilt_last_us[s] = Some(r.t_us);
            }
            _ => {}
        }
        Ok(())
    }

    /// `N frames out of range (first: ...)`, or `None` when every frame was in range.
    pub fn summary(&self) -> Option<String> {
        let first = self.first.as_ref()?;
        Some(format!(
            "{} frame{} out of the board's announced range, not kept (first: {first})",
            self.count,
            if self.count == 1 { "" } else { "s" }
        ))
    }
}

/// The frames of a stored recording that are within the configuration its header records
/// (`pot_rate_hz`, the `Hello`'s `tilt_sensors`), in file order, and the check that counted the
/// others. Each `Start` acknowledged in the file restarts the period and time checks; a file
/// without one (a simulated session) is checked as one run from its first frame.
pub fn in_range(
    meta: &RecordingMeta,
    frames: Vec<(u64, DeviceMsg)>,
) -> (Vec<(u64, DeviceMsg)>, WireCheck) {
    let mut check = WireCheck::new(
        Some(meta.pot_rate_hz),
        meta.hello.as_ref().map(|h| h.tilt_sensors),
    );
    let start = |m: &DeviceMsg| matches!(m, DeviceMsg::Ack(CommandKind::Start));
    if !frames.iter().any(|(_, m)| start(m)) {
        check.restart();
    }
    let kept = frames
        .into_iter()
        .filter(|(_, msg)| {
            if start(msg) {
                check.restart();
            }
            check.accept(msg)
        })
        .collect();
    (kept, check)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rig_protocol::{PotBatch, TiltReading};

    fn pot(t0_us: u64, period_us: u32, samples: &[u16]) -> DeviceMsg {
        DeviceMsg::Pot(PotBatch {
            seq: 0,
            t0_us,
            period_us,
            samples: heapless::Vec::from_slice(samples).unwrap(),
        })
    }

    fn tilt(sensor: u8, t_us: u64) -> DeviceMsg {
        DeviceMsg::Tilt(TiltReading {
            sensor,
            t_us,
            x: 0,
            y: 0,
            z: 6000,
            temp: 0,
            status: 0,
        })
    }

    #[test]
    fn absurd_values_are_refused_and_good_ones_kept() {
        let mut c = WireCheck::new(Some(1000), Some(3));
        // before Start: a left-over run at another rate passes, a 16-bit count does not
        assert!(c.accept(&pot(500, 250, &[1])));
        assert!(!c.accept(&pot(600, 250, &[65535])));
        c.restart();
        c.count = 0;
        c.first = None;
        assert!(c.accept(&pot(0, 1000, &[0, 4095])));
        assert!(!c.accept(&pot(2000, 0, &[1])));
        assert!(!c.accept(&pot(2000, 1, &[1])));
        assert!(!c.accept(&pot(2000, 1000, &[65535])));
        assert!(!c.accept(&pot(1000, 1000, &[1]))); // backwards
        assert!(!c.accept(&pot(u64::MAX - 10, 1000, &[1, 2])));
        assert!(c.accept(&pot(2000, 1000, &[5])));
        assert!(c.accept(&tilt(2, 10)));
        assert!(!c.accept(&tilt(255, 20)));
        assert!(!c.accept(&tilt(2, 10)));
        assert_eq!(c.count, 7);
        assert!(matches!(
            c.first,
            Some(OutOfRange::Period { got_us: 0, .. })
        ));
        assert!(c.summary().unwrap().starts_with("7 frames out of"));
        c.restart();
        assert!(c.accept(&pot(0, 1000, &[1])));
    }
}
