//! The virtual board's synthetic sensor signals: pure functions of the seed and the board time,
//! so that a test can predict every sample `rigctl board-sim --seed N` sends.
//!
//! - Potentiometer (pencil travel): a 12-bit ADC reading around mid-scale, the sum of a slow and
//!   a faster sine (the pencil sliding in its sleeve as the arm draws), plus uniform noise of
//!   +-[`POT_NOISE_COUNTS`] counts, clamped to `0..=4095`.
//! - Inclinometers (SCL3300, mode 1, [`SCL3300_COUNTS_PER_G`]): each sensor has a fixed mounting
//!   tilt of up to +-2 deg about x and y plus a slow +-0.3 deg wobble; the raw x, y, z counts are
//!   the gravity vector in the tilted sensor frame, plus +-[`TILT_NOISE_COUNTS`] counts of noise.
//!   Temperature drifts slowly around 25 degC, raw = (T + 273) * 18.9.
//!
//! Phases, mounting tilts and noise come from SplitMix64 of the seed; the noise of a sample
//! depends only on (seed, channel, board time), never on the order in which samples are made.

/// SCL3300 acceleration sensitivity in measurement mode 1, counts per g.
pub const SCL3300_COUNTS_PER_G: f64 = 6000.0;
/// SCL3300 temperature scale: T(degC) = -273 + raw / 18.9.
pub const SCL3300_TEMP_COUNTS_PER_K: f64 = 18.9;
/// Largest ADC count (12 bits).
pub const POT_FULL_SCALE: u16 = 4095;
/// Amplitude of the uniform potentiometer noise, counts.
pub const POT_NOISE_COUNTS: i64 = 2;
/// Amplitude of the uniform inclinometer noise, counts.
pub const TILT_NOISE_COUNTS: i64 = 3;

const POT_MID_COUNTS: f64 = 2048.0;
const POT_SLOW_AMPLITUDE_COUNTS: f64 = 900.0;
const POT_SLOW_HZ: f64 = 0.2;
const POT_FAST_AMPLITUDE_COUNTS: f64 = 150.0;
const POT_FAST_HZ: f64 = 1.7;
const MOUNT_TILT_MAX_DEG: f64 = 2.0;
const WOBBLE_AMPLITUDE_DEG: f64 = 0.3;
const WOBBLE_HZ: f64 = 0.05;
const TEMP_MEAN_DEGC: f64 = 25.0;
const TEMP_SWING_DEGC: f64 = 0.5;
const TEMP_HZ: f64 = 0.01;

/// SplitMix64 finaliser: a well-mixed 64-bit hash of `x`.
fn mix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// A value in `[0, 1)` for (seed, channel, k).
fn unit(seed: u64, channel: u64, k: u64) -> f64 {
    let h = mix(mix(seed ^ mix(channel)) ^ k);
    (h >> 11) as f64 / (1u64 << 53) as f64
}

/// Uniform integer noise in `-amplitude..=amplitude` for (seed, channel, t_us).
fn noise(seed: u64, channel: u64, t_us: u64, amplitude: i64) -> i64 {
    let h = mix(mix(seed ^ mix(channel)) ^ t_us.wrapping_mul(0xD6E8_FEB8_6659_FD93));
    (h % (2 * amplitude as u64 + 1)) as i64 - amplitude
}

fn phase_rad(seed: u64, channel: u64) -> f64 {
    std::f64::consts::TAU * unit(seed, channel, 0)
}

fn seconds(t_us: u64) -> f64 {
    t_us as f64 * 1e-6
}

const CH_POT: u64 = 1;
const CH_POT_FAST: u64 = 2;
const CH_TILT: u64 = 16;

/// The potentiometer's raw ADC count at board time `t_us`.
pub fn pot_raw(seed: u64, t_us: u64) -> u16 {
    let t = seconds(t_us);
    let value = POT_MID_COUNTS
        + POT_SLOW_AMPLITUDE_COUNTS
            * (std::f64::consts::TAU * POT_SLOW_HZ * t + phase_rad(seed, CH_POT)).sin()
        + POT_FAST_AMPLITUDE_COUNTS
            * (std::f64::consts::TAU * POT_FAST_HZ * t + phase_rad(seed, CH_POT_FAST)).sin();
    let counts = value.round() as i64 + noise(seed, CH_POT, t_us, POT_NOISE_COUNTS);
    counts.clamp(0, i64::from(POT_FULL_SCALE)) as u16
}

/// One inclinometer reading in raw counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TiltRaw {
    pub x: i16,
    pub y: i16,
    pub z: i16,
    pub temp: i16,
}

/// The tilt of `sensor` about x and y at time `t_us`, degrees (without noise).
pub fn tilt_deg(seed: u64, sensor: u8, t_us: u64) -> (f64, f64) {
    let t = seconds(t_us);
    let ch = CH_TILT + 8 * u64::from(sensor);
    let mount = |k| MOUNT_TILT_MAX_DEG * (2.0 * unit(seed, ch, k) - 1.0);
    let wobble = |c| {
        WOBBLE_AMPLITUDE_DEG
            * (std::f64::consts::TAU * WOBBLE_HZ * t + phase_rad(seed, ch + c)).sin()
    };
    (mount(1) + wobble(1), mount(2) + wobble(2))
}

/// The raw reading of `sensor` at board time `t_us`.
pub fn tilt_raw(seed: u64, sensor: u8, t_us: u64) -> TiltRaw {
    let ch = CH_TILT + 8 * u64::from(sensor);
    let (ax_deg, ay_deg) = tilt_deg(seed, sensor, t_us);
    let (ax, ay) = (ax_deg.to_radians(), ay_deg.to_radians());
    // Gravity (0, 0, 1 g) seen by a sensor rotated by ax about x, then ay about y.
    let g = [ay.sin() * ax.cos(), -ax.sin(), ax.cos() * ay.cos()];
    let count = |gi: f64, c: u64| {
        let n = (gi * SCL3300_COUNTS_PER_G).round() as i64
            + noise(seed, ch + c, t_us, TILT_NOISE_COUNTS);
        n.clamp(i64::from(i16::MIN), i64::from(i16::MAX)) as i16
    };
    let temp_degc = TEMP_MEAN_DEGC
        + TEMP_SWING_DEGC
            * (std::f64::consts::TAU * TEMP_HZ * seconds(t_us) + phase_rad(seed, ch + 4)).sin();
    let temp = ((temp_degc + 273.0) * SCL3300_TEMP_COUNTS_PER_K).round() as i16;
    TiltRaw {
        x: count(g[0], 5),
        y: count(g[1], 6),
        z: count(g[2], 7),
        temp,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pot_stays_in_range_and_moves_smoothly() {
        for seed in [0, 1, 42, u64::MAX] {
            let mut prev = pot_raw(seed, 0);
            let (mut lo, mut hi) = (u16::MAX, 0);
            for ms in 1..20_000u64 {
                let v = pot_raw(seed, ms * 1000);
                assert!(v <= POT_FULL_SCALE);
                // Largest slope: 2 pi (0.2 * 900 + 1.7 * 150) counts/s = 2.73 counts/ms, + noise.
                assert!(
                    (i32::from(v) - i32::from(prev)).abs() <= 3 + 2 * POT_NOISE_COUNTS as i32,
                    "seed {seed} at {ms} ms: {prev} -> {v}"
                );
                lo = lo.min(v);
                hi = hi.max(v);
                prev = v;
            }
            // Over 20 s (4 slow periods) the pencil travels most of the range.
            assert!(hi - lo > 1500, "seed {seed}: travel {lo}..{hi}");
        }
    }

    #[test]
    fn signals_depend_on_seed_only_through_the_documented_parameters() {
        assert_eq!(pot_raw(7, 123_000), pot_raw(7, 123_000));
        let differ = (0..100u64)
            .filter(|&k| pot_raw(7, k * 1000) != pot_raw(8, k * 1000))
            .count();
        assert!(differ > 90);
    }

    #[test]
    fn tilt_counts_are_a_unit_gravity_vector_at_6000_counts_per_g() {
        for sensor in 0..3 {
            for k in 0..200u64 {
                let t_us = k * 10_000;
                let r = tilt_raw(3, sensor, t_us);
                let norm =
                    (f64::from(r.x).powi(2) + f64::from(r.y).powi(2) + f64::from(r.z).powi(2))
                        .sqrt();
                // |g| = 6000 counts, noise at most 3 counts per axis.
                assert!((norm - 6000.0).abs() < 6.0, "norm {norm}");
                let (ax, ay) = tilt_deg(3, sensor, t_us);
                assert!(ax.abs() <= 2.3 && ay.abs() <= 2.3);
                // y count = -6000 sin(ax) within the noise.
                let y_expected = -6000.0 * ax.to_radians().sin();
                assert!((f64::from(r.y) - y_expected).abs() <= 3.5);
                let temp_degc = -273.0 + f64::from(r.temp) / 18.9;
                assert!((temp_degc - 25.0).abs() < 0.6, "temp {temp_degc}");
            }
        }
    }

    #[test]
    fn noise_is_uniform_over_its_range() {
        let mut hist = [0u32; 5];
        for t in 0..50_000u64 {
            hist[(noise(9, CH_POT, t * 1000, 2) + 2) as usize] += 1;
        }
        for (i, &n) in hist.iter().enumerate() {
            // 10 000 expected per bin; 5 sigma = 450.
            assert!((n as i64 - 10_000).abs() < 450, "bin {i}: {n}");
        }
    }
}
