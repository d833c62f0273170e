//! The potentiometer samples of a board recording (`daq::recording`), with their board times.

use std::path::Path;

use rig_protocol::DeviceMsg;

use super::error::FusionError;
use crate::daq::salvage::{read_salvaged, SalvagedRecording};
use crate::daq::wire_check::in_range;

/// One potentiometer sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PotSample {
    /// Board time, microseconds since boot.
    pub t_us: u64,
    /// Raw ADC counts.
    pub raw: u16,
}

/// The potentiometer samples of a recording and what was left out of them.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct PotSamples {
    /// In board-time order.
    pub samples: Vec<PotSample>,
    /// Frames out of the board's announced range, not used
    /// ([`crate::daq::wire_check::WireCheck::summary`]); `None` when there were none.
    pub out_of_range: Option<String>,
}

/// Every potentiometer sample of the recording at `path`, in board-time order (a sample time
/// recorded twice keeps its first value). Damaged records are skipped (see
/// [`crate::daq::salvage`]) and reported through `on_damage`; with `strict` they are an error.
/// Frames out of the board's announced range are left out, as `export` leaves them out
/// ([`crate::daq::wire_check::in_range`]), and counted in [`PotSamples::out_of_range`].
pub fn read_pot_samples(
    path: &Path,
    strict: bool,
    on_damage: &mut dyn FnMut(&SalvagedRecording),
) -> Result<PotSamples, FusionError> {
    let mut rec = read_salvaged(path, strict)?;
    if !rec.damaged.is_empty() {
        on_damage(&rec);
    }
    let (frames, check) = in_range(&rec.meta, std::mem::take(&mut rec.frames));
    let mut out = Vec::new();
    for (_, msg) in &frames {
        if let DeviceMsg::Pot(b) = msg {
            for (i, &raw) in b.samples.iter().enumerate() {
                // checked (a kept batch's last time fits, `WireCheck`); never a wrap
                let Some(t_us) = (i as u64)
                    .checked_mul(u64::from(b.period_us))
                    .and_then(|d| b.t0_us.checked_add(d))
                else {
                    continue;
                };
                out.push(PotSample { t_us, raw });
            }
        }
    }
    out.sort_by_key(|s| s.t_us);
    out.dedup_by_key(|s| s.t_us);
    Ok(PotSamples {
        samples: out,
        out_of_range: check.summary(),
    })
}

/// Potentiometer travel as a time series on the board clock (s), for interpolation.
#[derive(Debug, Clone, PartialEq)]
pub struct TravelSeries {
    /// Board times, s, increasing.
    pub t_s: Vec<f64>,
    /// Pencil travel, mm.
    pub travel_mm: Vec<f64>,
}

impl TravelSeries {
    /// The series of `samples` through the count -> travel map `travel_of_raw`.
    pub fn new(samples: &[PotSample], travel_of_raw: impl Fn(f64) -> f64) -> Self {
        Self {
            t_s: samples.iter().map(|s| s.t_us as f64 * 1e-6).collect(),
            travel_mm: samples
                .iter()
                .map(|s| travel_of_raw(f64::from(s.raw)))
                .collect(),
        }
    }

    /// Linear interpolation at board time `t_s`; `None` outside the series or across a gap of
    /// more than `max_gap_s`.
    pub fn at(&self, t_s: f64, max_gap_s: f64) -> Option<f64> {
        let n = self.t_s.len();
        if n < 2 || !(t_s >= self.t_s[0] && t_s <= self.t_s[n - 1]) {
            return None;
        }
        let i = self.t_s.partition_point(|&x| x < t_s).clamp(1, n - 1);
        let (t0, t1) = (self.t_s[i - 1], self.t_s[i]);
        if t1 - t0 > max_gap_s {
            return None;
        }
        let f = if t1 > t0 { (t_s - t0) / (t1 - t0) } else { 0.0 };
        Some(self.travel_mm[i - 1] + f * (self.travel_mm[i] - self.travel_mm[i - 1]))
    }

    /// The stop reading (pencil fully extended, off the paper): the 99.9th percentile of the
    /// travel, robust against single noisy samples.
    pub fn stop_mm(&self) -> Option<f64> {
        let mut v: Vec<f64> = self
            .travel_mm
            .iter()
            .copied()
            .filter(|x| x.is_finite())
            .collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let k = ((v.len() - 1) as f64 * 0.999).round() as usize;
        Some(v[k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_and_gaps() {
        let s = TravelSeries {
            t_s: vec![1.0, 1.001, 1.002, 1.5],
            travel_mm: vec![0.0, 1.0, 2.0, 3.0],
        };
        assert!((s.at(1.0005, 0.01).unwrap() - 0.5).abs() < 1e-9);
        assert_eq!(s.at(1.002, 0.01), Some(2.0));
        assert_eq!(s.at(1.2, 0.01), None);
        assert_eq!(s.at(0.9, 0.01), None);
        assert_eq!(s.stop_mm(), Some(3.0));
    }
}
