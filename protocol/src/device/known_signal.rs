//! The known signals of the emulated board (`firmware`, feature `mps2-an386`): what its
//! potentiometer and inclinometer sources return, as pure functions of board time, so that a
//! host test can check every value of a recording.
//!
//! - Potentiometer: a ramp over the 10 kHz sample grid. The sample converted at board time
//!   `t_us` reads `(t_us / 100) * POT_RAMP_STEP mod 4096` (12-bit counts).
//! - Inclinometers: row `(t_us / 1000 + TILT_SENSOR_OFFSET * sensor) mod N` of [`TILT_TABLE`]
//!   (raw x, y, z, temperature counts of an SCL3300 in mode 1: 6000 counts per g, temperature
//!   `-273 + raw / 18.9` degC).

use crate::messages::TiltReading;

/// Counts added per 100 us step of the potentiometer ramp (odd: every 12-bit value is visited).
pub const POT_RAMP_STEP: u64 = 37;

/// Rows a sensor's readings are shifted by per sensor index.
pub const TILT_SENSOR_OFFSET: u64 = 4;

/// Raw SCL3300 readings `[x, y, z, temp]`: tilts of a few degrees around level (z about 1 g)
/// at 23..27 degC. 11 rows (prime), so consecutive readings at any whole-millisecond period
/// walk through the table.
pub const TILT_TABLE: [[i16; 4]; 11] = [
    [0, 0, 6000, 5678],
    [105, -52, 5999, 5680],
    [314, -157, 5991, 5683],
    [-209, 366, 5985, 5685],
    [523, 0, 5977, 5687],
    [-628, -261, 5961, 5690],
    [1040, 732, 5864, 5692],
    [-1250, -105, 5867, 5695],
    [2052, -1545, 5426, 5697],
    [3000, 3000, 4243, 5700],
    [-5196, 0, 3000, 5703],
];

/// The potentiometer's raw counts for the sample converted at board time `t_us`.
pub fn pot_raw(t_us: u64) -> u16 {
    ((t_us / 100).wrapping_mul(POT_RAMP_STEP) % 4096) as u16
}

/// The reading inclinometer `sensor` returns when read at board time `t_us`.
pub fn tilt_reading(sensor: u8, t_us: u64) -> TiltReading {
    let row = (t_us / 1000 + TILT_SENSOR_OFFSET * u64::from(sensor)) % TILT_TABLE.len() as u64;
    let [x, y, z, temp] = TILT_TABLE[row as usize];
    TiltReading {
        sensor,
        t_us,
        x,
        y,
        z,
        temp,
        status: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pot_ramp_is_12_bit_and_steps_on_the_10_khz_grid() {
        assert_eq!(pot_raw(0), 0);
        assert_eq!(pot_raw(99), 0);
        assert_eq!(pot_raw(100), 37);
        assert_eq!(pot_raw(1_000), 370);
        assert!((0..1_000_000u64).step_by(7).all(|t| pot_raw(t) < 4096));
    }

    #[test]
    fn tilt_rows_differ_per_sensor() {
        let t = 123_456;
        let rows: [TiltReading; 3] = [0, 1, 2].map(|s| tilt_reading(s, t));
        assert_ne!(rows[0].x, rows[1].x);
        assert_ne!(rows[1].x, rows[2].x);
        assert!(rows.iter().all(|r| r.t_us == t && r.status == 0));
        // Each row is a plausible acceleration: |a| within 1 % of 1 g (6000 counts).
        for [x, y, z, _] in TILT_TABLE {
            let g2 = [x, y, z].map(|v| i64::from(v).pow(2)).iter().sum::<i64>();
            assert!((5940 * 5940..=6060 * 6060).contains(&g2), "{x} {y} {z}");
        }
    }
}
