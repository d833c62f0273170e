//! Potentiometer batcher: turns timestamped raw samples into [`PotBatch`]es.

use crate::messages::{PotBatch, POT_BATCH_MAX};

/// Groups samples taken at a constant period into [`PotBatch`]es.
///
/// A batch closes when it holds [`POT_BATCH_MAX`] samples, when a sample does not arrive on
/// the batch's time grid (more than half a period off `t0_us + k * period_us`: a lost sample, a
/// restarted timer, time going backwards), or when [`PotBatcher::flush_older_than`] /
/// [`PotBatcher::flush`] says so. Every closed batch takes the next `seq`, whether or not the
/// link then manages to send it, so the host sees a gap in `seq` for each lost batch.
#[derive(Debug, Clone)]
pub struct PotBatcher {
    period_us: u32,
    next_seq: u32,
    t0_us: u64,
    samples: heapless::Vec<u16, POT_BATCH_MAX>,
}

impl Default for PotBatcher {
    fn default() -> Self {
        Self::new(1000)
    }
}

impl PotBatcher {
    /// A batcher for samples `period_us` apart (0 is treated as 1); `seq` starts at 0.
    pub const fn new(period_us: u32) -> Self {
        Self {
            period_us: if period_us == 0 { 1 } else { period_us },
            next_seq: 0,
            t0_us: 0,
            samples: heapless::Vec::new(),
        }
    }

    /// The sampling period, microseconds.
    pub fn period_us(&self) -> u32 {
        self.period_us
    }

    /// `seq` the next closed batch will carry.
    pub fn next_seq(&self) -> u32 {
        self.next_seq
    }

    /// Samples waiting in the open batch.
    pub fn pending(&self) -> usize {
        self.samples.len()
    }

    /// Board time of the open batch's first sample, if any.
    pub fn open_since_us(&self) -> Option<u64> {
        (!self.samples.is_empty()).then_some(self.t0_us)
    }

    fn on_grid(&self, t_us: u64) -> bool {
        let expected = self
            .t0_us
            .saturating_add(self.samples.len() as u64 * u64::from(self.period_us));
        t_us.abs_diff(expected) <= u64::from(self.period_us / 2)
    }

    fn close(&mut self) -> Option<PotBatch> {
        if self.samples.is_empty() {
            return None;
        }
        let batch = PotBatch {
            seq: self.next_seq,
            t0_us: self.t0_us,
            period_us: self.period_us,
            samples: core::mem::take(&mut self.samples),
        };
        self.next_seq = self.next_seq.wrapping_add(1);
        Some(batch)
    }

    /// Adds one sample taken at board time `t_us`; returns a batch if one closed.
    ///
    /// At most one batch closes per sample: either the open batch is full after this sample,
    /// or this sample is off the open batch's grid (then the open batch is returned and this
    /// sample starts the next one).
    pub fn push(&mut self, t_us: u64, raw: u16) -> Option<PotBatch> {
        let mut closed = None;
        if !self.samples.is_empty() && !self.on_grid(t_us) {
            closed = self.close();
        }
        if self.samples.is_empty() {
            self.t0_us = t_us;
        }
        // Cannot fail: a full batch is always closed right below.
        let _ = self.samples.push(raw);
        if self.samples.is_full() {
            debug_assert!(closed.is_none() || POT_BATCH_MAX == 1);
            return closed.or_else(|| self.close());
        }
        closed
    }

    /// Closes the open batch if its first sample is at least `max_age_us` older than `now_us`
    /// (bounds the latency at low sample rates).
    pub fn flush_older_than(&mut self, now_us: u64, max_age_us: u64) -> Option<PotBatch> {
        let t0 = self.open_since_us()?;
        if now_us.saturating_sub(t0) >= max_age_us {
            self.close()
        } else {
            None
        }
    }

    /// Closes the open batch, if any (at `Stop`).
    pub fn flush(&mut self) -> Option<PotBatch> {
        self.close()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn feed(b: &mut PotBatcher, t0: u64, period: u64, n: usize) -> heapless::Vec<PotBatch, 16> {
        let mut out = heapless::Vec::new();
        for i in 0..n {
            if let Some(batch) = b.push(t0 + i as u64 * period, i as u16) {
                out.push(batch).unwrap();
            }
        }
        out
    }

    #[test]
    fn full_batches_carry_consecutive_seq_and_exact_t0() {
        let mut b = PotBatcher::new(100);
        let batches = feed(&mut b, 5_000, 100, 3 * POT_BATCH_MAX + 5);
        assert_eq!(batches.len(), 3);
        for (k, batch) in batches.iter().enumerate() {
            assert_eq!(batch.seq, k as u32);
            assert_eq!(batch.period_us, 100);
            assert_eq!(batch.t0_us, 5_000 + (k * POT_BATCH_MAX) as u64 * 100);
            assert_eq!(batch.samples.len(), POT_BATCH_MAX);
            assert_eq!(batch.samples[0], (k * POT_BATCH_MAX) as u16);
        }
        assert_eq!(b.pending(), 5);
        let last = b.flush().unwrap();
        assert_eq!(last.seq, 3);
        assert_eq!(last.samples.len(), 5);
        assert_eq!(b.flush(), None);
    }

    #[test]
    fn jitter_below_half_period_keeps_the_batch() {
        let mut b = PotBatcher::new(100);
        assert_eq!(b.push(1_000, 1), None);
        assert_eq!(b.push(1_150, 2), None); // +50: still sample 1
        assert_eq!(b.push(1_249, 3), None); // -51 would break, -1 does not
        assert_eq!(b.pending(), 3);
    }

    #[test]
    fn a_gap_closes_the_batch_and_starts_a_new_grid() {
        let mut b = PotBatcher::new(100);
        b.push(1_000, 1);
        b.push(1_100, 2);
        let closed = b.push(1_351, 3).unwrap(); // sample at 1_200 and 1_300 lost
        assert_eq!((closed.seq, closed.t0_us), (0, 1_000));
        assert_eq!(&closed.samples[..], &[1, 2]);
        assert_eq!(b.open_since_us(), Some(1_351));
        // Time going backwards also breaks the grid.
        let closed = b.push(900, 4).unwrap();
        assert_eq!(
            (closed.seq, closed.t0_us, closed.samples.len()),
            (1, 1_351, 1)
        );
    }

    #[test]
    fn latency_flush_only_after_max_age() {
        let mut b = PotBatcher::new(10_000);
        b.push(0, 7);
        assert_eq!(b.flush_older_than(99_999, 100_000), None);
        let batch = b.flush_older_than(100_000, 100_000).unwrap();
        assert_eq!(&batch.samples[..], &[7]);
        assert_eq!(b.flush_older_than(1_000_000, 100_000), None);
    }

    #[test]
    fn extreme_timestamps_do_not_panic() {
        let mut b = PotBatcher::new(0);
        b.push(u64::MAX, 1);
        b.push(u64::MAX, 2);
        b.push(0, 3);
        assert!(b.pending() >= 1);
    }
}
