//! Inclinometer scheduler: which sensor to read when.

/// Round-robin schedule reading each of `sensors` inclinometers at `rate_hz`, the reads spread
/// evenly in time: read slot `k` (0, 1, 2, ...) is for sensor `k % sensors` at
/// `start + ceil(k * 1e6 / (rate_hz * sensors))` microseconds. The slot times are exact over
/// any run length (no accumulated rounding), using only `u64` arithmetic.
///
/// If the caller polls late and several slots have passed, only the most recent one is
/// returned and the others are counted in [`TiltScheduler::skipped`]: the schedule never
/// builds a backlog.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TiltScheduler {
    start_us: u64,
    /// Slots per second: `rate_hz * sensors` (0 = stopped).
    slots_per_s: u64,
    sensors: u8,
    /// Next slot: whole seconds since start, and slot index within that second.
    next_second: u64,
    next_in_second: u64,
    skipped: u64,
}

const US_PER_S: u64 = 1_000_000;

impl Default for TiltScheduler {
    fn default() -> Self {
        Self::stopped()
    }
}

impl TiltScheduler {
    /// A scheduler that never asks for a read.
    pub const fn stopped() -> Self {
        Self {
            start_us: 0,
            slots_per_s: 0,
            sensors: 0,
            next_second: 0,
            next_in_second: 0,
            skipped: 0,
        }
    }

    /// Starts a schedule at `now_us` (the first read, sensor 0, is due at once). `rate_hz == 0`
    /// or `sensors == 0` gives a stopped scheduler.
    pub fn start(now_us: u64, rate_hz: u32, sensors: u8) -> Self {
        let slots_per_s = u64::from(rate_hz) * u64::from(sensors);
        if slots_per_s == 0 {
            return Self::stopped();
        }
        Self {
            start_us: now_us,
            slots_per_s,
            sensors,
            ..Self::stopped()
        }
    }

    /// True while reads are scheduled.
    pub fn is_running(&self) -> bool {
        self.slots_per_s != 0
    }

    /// Slots missed because polls came late.
    pub fn skipped(&self) -> u64 {
        self.skipped
    }

    fn slot_time_us(&self, second: u64, in_second: u64) -> u64 {
        let offset = (in_second * US_PER_S).div_ceil(self.slots_per_s);
        self.start_us
            .saturating_add(second.saturating_mul(US_PER_S))
            .saturating_add(offset)
    }

    /// Board time at which the next read is due, or `None` when stopped.
    pub fn next_due_us(&self) -> Option<u64> {
        self.is_running()
            .then(|| self.slot_time_us(self.next_second, self.next_in_second))
    }

    /// The sensor to read now, if a read is due at `now_us`.
    pub fn poll(&mut self, now_us: u64) -> Option<u8> {
        let due = self.next_due_us()?;
        if now_us < due {
            return None;
        }
        // Latest slot whose time is <= now: within second s = d / 1e6, the largest j with
        // ceil(j * 1e6 / n) <= rem, i.e. j = floor(rem * n / 1e6).
        let elapsed = now_us - self.start_us;
        let second = elapsed / US_PER_S;
        let in_second = (elapsed % US_PER_S) * self.slots_per_s / US_PER_S;
        let latest = second
            .saturating_mul(self.slots_per_s)
            .saturating_add(in_second);
        let next = self
            .next_second
            .saturating_mul(self.slots_per_s)
            .saturating_add(self.next_in_second);
        self.skipped = self.skipped.saturating_add(latest.saturating_sub(next));
        self.next_second = second;
        self.next_in_second = in_second + 1;
        if self.next_in_second == self.slots_per_s {
            self.next_second = self.next_second.saturating_add(1);
            self.next_in_second = 0;
        }
        Some(((latest) % u64::from(self.sensors)) as u8)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Polls every microsecond from `from` to `to` (exclusive), collecting (time, sensor).
    fn run(s: &mut TiltScheduler, from: u64, to: u64) -> heapless::Vec<(u64, u8), 64> {
        let mut reads = heapless::Vec::new();
        for t in from..to {
            if let Some(sensor) = s.poll(t) {
                reads.push((t, sensor)).unwrap();
            }
        }
        reads
    }

    #[test]
    fn three_sensors_at_100_hz_interleave_evenly() {
        let mut s = TiltScheduler::start(1_000, 100, 3);
        // 300 reads/s: slots at 0, 3333.3 -> 3334, 6666.7 -> 6667, 10000, ...
        let reads = run(&mut s, 1_000, 1_000 + 20_001);
        let expected: [(u64, u8); 7] = [
            (1_000, 0),
            (4_334, 1),
            (7_667, 2),
            (11_000, 0),
            (14_334, 1),
            (17_667, 2),
            (21_000, 0),
        ];
        assert_eq!(&reads[..], &expected[..]);
        assert_eq!(s.skipped(), 0);
    }

    #[test]
    fn long_run_has_exact_count_and_no_drift() {
        // 7 Hz x 3 sensors does not divide a second evenly.
        let mut s = TiltScheduler::start(0, 7, 3);
        let mut count = [0u32; 3];
        let mut t = 0;
        while t < 10 * US_PER_S {
            if let Some(sensor) = s.poll(t) {
                count[sensor as usize] += 1;
            }
            t += 50; // polls much faster than the 47.6 ms slot interval
        }
        assert_eq!(count, [70, 70, 70]);
        assert_eq!(s.next_due_us(), Some(10 * US_PER_S));
        assert_eq!(s.skipped(), 0);
    }

    #[test]
    fn late_poll_skips_missed_slots_without_backlog() {
        let mut s = TiltScheduler::start(0, 1000, 2); // a slot every 500 us
        assert_eq!(s.poll(0), Some(0));
        // Next poll 2.2 ms later: slots 1..=4 have passed, slot 4 (sensor 0) is the latest.
        assert_eq!(s.poll(2_200), Some(0));
        assert_eq!(s.skipped(), 3);
        assert_eq!(s.poll(2_200), None);
        assert_eq!(s.next_due_us(), Some(2_500));
        assert_eq!(s.poll(2_500), Some(1));
    }

    #[test]
    fn stopped_never_due() {
        let mut s = TiltScheduler::start(0, 100, 0);
        assert_eq!(s.next_due_us(), None);
        assert_eq!(s.poll(u64::MAX), None);
        let mut s = TiltScheduler::start(0, 0, 3);
        assert_eq!(s.poll(5), None);
    }

    #[test]
    fn huge_times_do_not_panic() {
        let mut s = TiltScheduler::start(u64::MAX - 10, 1000, 255);
        let _ = s.poll(u64::MAX);
        let _ = s.next_due_us();
        let mut s = TiltScheduler::start(0, 1000, 255);
        let _ = s.poll(u64::MAX);
        let _ = s.poll(u64::MAX);
    }
}
