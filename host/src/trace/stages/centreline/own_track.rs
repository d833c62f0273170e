//! A walk stepping onto its own earlier track: across it (its own loop, or another run crossing
//! it and round back: it stops there) or along it (a line drawn in several passes, or turned back
//! on at its end: it goes on). Told apart by the angle between the walk's heading and the heading
//! it had where it marked the track, and, where that angle is in between, by what follows: a
//! retrace comes into line with the track, a crossing leaves the track again at its angle.

use super::params::CentrelineParams;
use super::{dist, Tracker};

/// What the walk does at its next step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Verdict {
    /// Goes on.
    Go,
    /// Stops before the step, its points cut back to the first `keep` (where it first stepped
    /// onto the track it then crossed); the marks made after mark `since` (on
    /// [`Tracker::clock`]) undone where it cut back.
    StopAt { keep: usize, since: Option<u32> },
}

/// The state of one walk with respect to its own track.
#[derive(Debug)]
pub(super) struct Retrace {
    /// The number of points the walk had, and the mark clock, when it stepped onto its track at
    /// an angle in between (not yet told whether crossing or retracing).
    pending: Option<(usize, u32)>,
    /// Steps in a row off the track since it stepped onto it at that angle.
    off: usize,
    /// Steps off the track that tell a crossing (a retrace turning back onto its track at the
    /// end of a line may touch it and come off it for a few steps first).
    patience: usize,
    /// Steps in a row along its own track, once told a retrace.
    along: usize,
    /// [`CentrelineParams::cross_cos`], [`CentrelineParams::aligned_cos`].
    cross_cos: f64,
    aligned_cos: f64,
}

impl Retrace {
    pub(super) fn new(patience: usize, params: &CentrelineParams) -> Self {
        Retrace {
            pending: None,
            off: 0,
            patience,
            along: 0,
            cross_cos: params.cross_cos,
            aligned_cos: params.aligned_cos,
        }
    }

    /// The verdict on the next step: `cos` is |cos| of the angle between the heading and the
    /// track's where the step lands on the walk's own earlier track (`None` where it does not),
    /// `walked` the walk's points so far, `marks` the marks the piece made so far (a retrace
    /// never runs longer than the piece: round a closed stroke drawn twice it would go on to
    /// the step limit).
    pub(super) fn step(
        &mut self,
        cos: Option<f64>,
        walked: usize,
        marks: usize,
        clock: u32,
    ) -> Verdict {
        let stop_here = Verdict::StopAt {
            keep: walked,
            since: None,
        };
        let cut_back = |(keep, since): (usize, u32)| Verdict::StopAt {
            keep,
            since: Some(since),
        };
        match cos {
            None => {
                self.along = 0;
                let Some(at) = self.pending else {
                    return Verdict::Go;
                };
                self.off += 1;
                if self.off > self.patience {
                    // Off the track again without coming into line: it crossed.
                    cut_back(at)
                } else {
                    Verdict::Go
                }
            }
            Some(c) if c >= self.aligned_cos || (self.along > 0 && c >= self.cross_cos) => {
                self.pending = None;
                self.along += 1;
                if self.along > marks {
                    stop_here
                } else {
                    Verdict::Go
                }
            }
            Some(c) if c < self.cross_cos => self.pending.map_or(stop_here, cut_back),
            Some(_) => {
                self.off = 0;
                self.pending.get_or_insert((walked, clock));
                Verdict::Go
            }
        }
    }
}

impl Tracker<'_> {
    /// Where `p` lies on what piece `id` walked earlier, not in its last steps nor around its
    /// start (`start`, where a closed stroke comes back): |cos| of the angle between the
    /// heading `t` and the walk's heading where it marked that block.
    pub(super) fn own_track_cos(
        &self,
        p: [f64; 2],
        t: [f64; 2],
        id: u32,
        start: [f64; 2],
        half_w: f64,
    ) -> Option<f64> {
        let k = self.map.k as f64;
        let step = self.p.step_px;
        if dist(p, start) < half_w + 3.0 * k + 2.0 * step || p[0] < 0.0 || p[1] < 0.0 {
            return None;
        }
        let (bx, by) = ((p[0] / k) as usize, (p[1] / k) as usize);
        if bx >= self.map.w || by >= self.map.h {
            return None;
        }
        let b = by * self.map.w + bx;
        // The blocks the last steps marked reach this far ahead and behind.
        let recent = (2.0 * (half_w + 2.0 * k) / step).ceil() as u32 + 4;
        if self.visited[b] != id || self.marked_at[b].saturating_add(recent) >= self.clock {
            return None;
        }
        let d = self.marked_dir[b];
        Some((t[0] * f64::from(d[0]) + t[1] * f64::from(d[1])).abs())
    }

    /// Undoes the marks piece `id` made after mark `since` (a walk cut back to where it met
    /// its track, past which it crossed it onto another run).
    pub(super) fn unmark_since(&mut self, id: u32, since: u32) {
        for (v, at) in self.visited.iter_mut().zip(&self.marked_at) {
            if *v == id && *at > since {
                *v = 0;
            }
        }
    }

    /// The steps a walk may go off its track after meeting it at an angle in between before
    /// it is told to have crossed it: the stretch the last steps' marks reach.
    pub(super) fn retrace_patience(&self, half_w: f64) -> usize {
        let k = self.map.k as f64;
        2 * ((2.0 * (half_w + 2.0 * k) / self.p.step_px).ceil() as usize + 4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cut(keep: usize, since: u32) -> Verdict {
        Verdict::StopAt {
            keep,
            since: Some(since),
        }
    }

    #[test]
    fn a_crossing_stops_where_it_met_the_track() {
        let mut r = Retrace::new(2, &CentrelineParams::default());
        assert_eq!(r.step(None, 10, 10, 110), Verdict::Go);
        // Onto the track at 35 deg: not yet told.
        assert_eq!(r.step(Some(0.82), 11, 11, 111), Verdict::Go);
        assert_eq!(r.step(Some(0.84), 12, 12, 112), Verdict::Go);
        // Off it again at that angle for longer than the patience: crossed, cut back to where
        // it met the track.
        assert_eq!(r.step(None, 13, 13, 113), Verdict::Go);
        assert_eq!(r.step(None, 14, 14, 114), Verdict::Go);
        assert_eq!(r.step(None, 15, 15, 115), cut(11, 111));
        // At 60 deg: at once.
        let mut r = Retrace::new(2, &CentrelineParams::default());
        let here = Verdict::StopAt {
            keep: 20,
            since: None,
        };
        assert_eq!(r.step(Some(0.5), 20, 20, 120), here);
    }

    #[test]
    fn a_retrace_goes_on_and_not_past_the_piece() {
        let mut r = Retrace::new(2, &CentrelineParams::default());
        assert_eq!(r.step(Some(0.83), 40, 40, 40), Verdict::Go);
        // Touches the track and comes off it for a step, then in line with it.
        assert_eq!(r.step(None, 41, 41, 41), Verdict::Go);
        assert_eq!(r.step(Some(0.99), 42, 42, 42), Verdict::Go);
        // In line: a wobble to 40 deg on the track is still the same line.
        assert_eq!(r.step(Some(0.77), 43, 43, 43), Verdict::Go);
        for i in 44..50 {
            assert_eq!(r.step(None, i, i, i as u32), Verdict::Go);
        }
        // Along the track for longer than the piece: round a closed stroke again.
        let mut r = Retrace::new(2, &CentrelineParams::default());
        for i in 0..30 {
            assert_eq!(r.step(Some(1.0), 20 + i, 20 + i, 0), Verdict::Go);
        }
        let mut r = Retrace::new(2, &CentrelineParams::default());
        for _ in 0..5 {
            assert_eq!(r.step(Some(1.0), 5, 5, 0), Verdict::Go);
        }
        let here = Verdict::StopAt {
            keep: 5,
            since: None,
        };
        assert_eq!(r.step(Some(1.0), 5, 5, 0), here);
    }
}
