//! The inclinometers of the emulated board: three sensors that answer every read with the row
//! of `rig_protocol::device::known_signal`'s table for their index and the read's board time.

use rig_protocol::device::known_signal;
use rig_protocol::TiltReading;

/// Inclinometers on the emulated board (as many chip selects as the STM32 board has).
const SENSORS: u8 = 3;

/// Stands for the inclinometer bus the STM32 probes at boot.
pub struct TiltBus;

/// A failed read; the emulated sensors never fail, but the scheduler may name a slot that
/// does not exist.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TiltReadError;

/// The emulated sensors.
pub struct TiltSensors {
    count: u8,
}

impl TiltSensors {
    /// Number of sensors.
    pub fn count(&self) -> u8 {
        self.count
    }

    /// Reads the `slot`-th sensor at board time `t_us`.
    pub fn read(&mut self, slot: u8, t_us: u64) -> Result<TiltReading, TiltReadError> {
        if slot >= self.count {
            return Err(TiltReadError);
        }
        Ok(known_signal::tilt_reading(slot, t_us))
    }
}

/// "Probes" the bus: every sensor is present.
pub fn probe(_bus: TiltBus) -> TiltSensors {
    TiltSensors { count: SENSORS }
}
