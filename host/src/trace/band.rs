//! The band of ink along a drawn line (`rigctl trace --paths`): a plotter that draws a line
//! several times leaves passes side by side, crossing each other, each broken where the tracker
//! lost it. Rather than pairing passes, the line is followed through the cloud of every written
//! point (paths and strays) with its direction: from a seed, step along the line and put each
//! centre at the median offset across it of the points in a window (`band_half_mm` either
//! side, `band_half_along_mm` along) whose own direction runs within `band_deg` of the line's
//! (so a line crossing it is not followed). Where the window is empty the walk looks ahead in
//! a narrow cone for points running the same way: within `--max-gap-mm` the gap is bridged,
//! farther (up to [`reach_mm`], to a path only) it is missing; nothing ahead ends the line.
//! The points in every window are the line's: the paths they belong to are its passes. The
//! tuned numbers are [`LinesParams`]' `band_*`, carried by the [`Cloud`].

use super::plane::{dist, sub, unit, Grid};
use super::stages::link::Gap;
use super::stages::LinesParams;

/// Grid cell of the cloud, mm: how the points are bucketed for neighbour queries (what a query
/// finds does not depend on it, only the order and the speed), not a tuned number.
const CELL_MM: f64 = 4.0;

/// Where a point of the cloud comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Source {
    /// Path `i` of the drawing.
    Path(usize),
    /// A mark shorter than a path.
    Stray,
}

/// One written point and the direction of its path there (either way).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Dot {
    pub p: [f64; 2],
    pub dir: [f64; 2],
    pub src: Source,
}

/// Every written point, on a grid.
pub(crate) struct Cloud {
    pub dots: Vec<Dot>,
    grid: Grid<u32>,
    /// The numbers the band is followed with (`band_*`).
    lp: LinesParams,
}

impl Cloud {
    pub fn new(dots: Vec<Dot>, lp: &LinesParams) -> Self {
        let mut grid = Grid::new(CELL_MM);
        for (i, d) in dots.iter().enumerate() {
            grid.insert(d.p, i as u32);
        }
        Self {
            dots,
            grid,
            lp: *lp,
        }
    }

    /// The dots within `r` (mm) of `c`, and maybe a few more, in no particular order.
    pub fn around(&self, c: [f64; 2], r: f64) -> impl Iterator<Item = usize> + '_ {
        self.grid.around(c, r).map(|(_, i)| *i as usize)
    }

    /// The longest stretch of the segment `a`-`b` with no written point (of any direction:
    /// where the segment crosses another line, its ink is there) within `LinesParams::band_ink_near_mm`, mm.
    pub fn inkless_mm(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        let len = dist(a, b);
        let n = (len / 0.25).ceil().max(1.0) as usize;
        let (mut run, mut best) = (0.0f64, 0.0f64);
        for k in 0..=n {
            let f = k as f64 / n as f64;
            let p = [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])];
            let near = self.lp.band_ink_near_mm;
            let inked = self
                .around(p, near)
                .any(|i| dist(self.dots[i].p, p) <= near);
            if inked {
                run = 0.0;
            } else {
                run += len / n as f64;
                best = best.max(run);
            }
        }
        best
    }

    /// Whether dot `i` runs along `t`.
    fn runs_along(&self, i: usize, t: [f64; 2]) -> bool {
        let d = self.dots[i].dir;
        (d[0] * t[0] + d[1] * t[1]).abs() >= self.lp.band_deg.to_radians().cos()
    }

    /// The dots in the window at `c` (direction `t`, normal `n`) with their offsets across.
    fn window(&self, c: [f64; 2], t: [f64; 2], n: [f64; 2]) -> Vec<(usize, f64)> {
        let (half, half_along) = (self.lp.band_half_mm, self.lp.band_half_along_mm);
        self.around(c, half + half_along)
            .filter_map(|i| {
                let v = sub(self.dots[i].p, c);
                let along = v[0] * t[0] + v[1] * t[1];
                let across = v[0] * n[0] + v[1] * n[1];
                (along.abs() <= half_along && across.abs() <= half && self.runs_along(i, t))
                    .then_some((i, across))
            })
            .collect()
    }
}

/// How far ahead a line's end looks for more of it, mm: a gap longer than `--max-gap-mm` up
/// to this is missing.
pub fn reach_mm(max_gap_mm: f64) -> f64 {
    (5.0 * max_gap_mm).max(50.0)
}

/// A line followed through the cloud.
#[derive(Debug, Clone, Default)]
pub(crate) struct Walk {
    /// Centres in order along the line, mm.
    pub centres: Vec<[f64; 2]>,
    /// Stretches with nothing written, in order along the line.
    pub gaps: Vec<Gap>,
    pub closed: bool,
    /// The dots of the line's windows (a dot may appear more than once).
    pub taken: Vec<usize>,
}

impl Walk {
    pub fn length_mm(&self) -> f64 {
        let mut s: f64 = self.centres.windows(2).map(|w| dist(w[0], w[1])).sum();
        if self.closed {
            if let (Some(a), Some(b)) = (self.centres.first(), self.centres.last()) {
                s += dist(*a, *b);
            }
        }
        s
    }
}

/// One way of a walk.
struct Half {
    centres: Vec<[f64; 2]>,
    gaps: Vec<Gap>,
    closed: bool,
    taken: Vec<usize>,
}

/// Follows the line through `seed` (direction `t0`) both ways.
pub(crate) fn walk(cloud: &Cloud, seed: [f64; 2], t0: [f64; 2], max_gap_mm: f64) -> Walk {
    let fwd = walk_half(cloud, seed, t0, max_gap_mm, &[]);
    if fwd.closed {
        return Walk {
            centres: fwd.centres,
            gaps: fwd.gaps,
            closed: true,
            taken: fwd.taken,
        };
    }
    let back = walk_half(cloud, seed, [-t0[0], -t0[1]], max_gap_mm, &fwd.centres);
    // Backwards part reversed, then the forward part (the seed once).
    let mut centres: Vec<[f64; 2]> = back.centres.iter().rev().copied().collect();
    centres.pop();
    centres.extend(fwd.centres);
    let mut gaps: Vec<Gap> = back
        .gaps
        .into_iter()
        .rev()
        .map(|g| Gap {
            from_mm: g.to_mm,
            to_mm: g.from_mm,
            ..g
        })
        .collect();
    gaps.extend(fwd.gaps);
    let mut taken = back.taken;
    taken.extend(fwd.taken);
    Walk {
        centres,
        gaps,
        closed: false,
        taken,
    }
}

/// The median of `v` (not empty).
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

fn walk_half(
    cloud: &Cloud,
    seed: [f64; 2],
    t0: [f64; 2],
    max_gap_mm: f64,
    other_way: &[[f64; 2]],
) -> Half {
    let lp = &cloud.lp;
    let step_mm = lp.band_step_mm;
    let mut h = Half {
        centres: vec![seed],
        gaps: Vec::new(),
        closed: false,
        taken: Vec::new(),
    };
    let mut t = t0;
    let mut arc = vec![0.0f64];
    let mut heads: Vec<[f64; 2]> = vec![t0];
    let mut since = 0usize;
    let back_steps = (lp.band_dir_back_mm / step_mm).round() as usize;
    let max_steps = cloud.dots.len() * 4 + 1000;
    for _ in 0..max_steps {
        let c = *h.centres.last().unwrap_or(&seed);
        let n = [-t[1], t[0]];
        let pred = [c[0] + step_mm * t[0], c[1] + step_mm * t[1]];
        let mut win = cloud.window(pred, t, n);
        // Past the last of the line's points: step only as far as the farthest of them (the
        // end), then look ahead.
        let ahead_mm = win
            .iter()
            .map(|w| {
                let v = sub(cloud.dots[w.0].p, pred);
                v[0] * t[0] + v[1] * t[1]
            })
            .fold(f64::NEG_INFINITY, f64::max);
        let advance = (step_mm + ahead_mm).min(step_mm);
        if advance < 0.05 {
            win.clear();
        }
        let (next, gap) = if win.is_empty() {
            match look_ahead(
                cloud,
                c,
                t,
                n,
                max_gap_mm,
                settled(&h.centres[since..], t, lp),
            ) {
                Some((q, w)) => {
                    let len = dist(c, q);
                    h.taken.extend(w);
                    (
                        q,
                        Some(Gap {
                            from_mm: c,
                            to_mm: q,
                            length_mm: len,
                            bridged: cloud.inkless_mm(c, q) <= max_gap_mm,
                        }),
                    )
                }
                None => break,
            }
        } else {
            // Centred on the dots running closest to the line's way, at most
            // `band_max_shift_mm` a step across (a pass leaving the line cannot pull it along).
            let cos_centre = lp.band_centre_deg.to_radians().cos();
            let mut across: Vec<f64> = win
                .iter()
                .filter(|w| {
                    let d = cloud.dots[w.0].dir;
                    (d[0] * t[0] + d[1] * t[1]).abs() >= cos_centre
                })
                .map(|w| w.1)
                .collect();
            if across.is_empty() {
                across = win.iter().map(|w| w.1).collect();
            }
            let m = median(&mut across).clamp(-lp.band_max_shift_mm, lp.band_max_shift_mm);
            h.taken.extend(win.iter().map(|w| w.0));
            (
                [
                    c[0] + advance * t[0] + m * n[0],
                    c[1] + advance * t[1] + m * n[1],
                ],
                None,
            )
        };
        let s = arc[arc.len() - 1] + dist(c, next);
        // Back at its start: closed (with the gap, if it jumped there).
        if other_way.is_empty()
            && s >= lp.band_close_after_mm
            && dist(next, seed)
                <= lp
                    .band_close_mm
                    .max(gap.as_ref().map_or(0.0, |g| g.length_mm + step_mm))
        {
            if let Some(mut g) = gap {
                g.to_mm = seed;
                g.length_mm = dist(c, seed);
                g.bridged = cloud.inkless_mm(c, seed) <= max_gap_mm;
                h.gaps.push(g);
            }
            h.closed = true;
            break;
        }
        // Onto itself (or onto the other way's centres): the line ends here.
        if overlaps(&h.centres, &arc, s, next, step_mm)
            || overlaps_other(other_way, next, s, step_mm)
        {
            break;
        }
        let gap_here = gap.is_some();
        if let Some(g) = gap {
            h.gaps.push(g);
        }
        h.centres.push(next);
        arc.push(s);
        // The direction from the chord back over `band_dir_back_mm`, not across a jump (which may
        // land beside the line's last centre): kept until 2 mm past it.
        let k = h.centres.len() - 1;
        if gap_here {
            since = k;
        }
        let b = h.centres[k.saturating_sub(back_steps).max(since)];
        if let Some(u) = unit(sub(next, b)) {
            if dist(next, b) >= 0.5 * lp.band_dir_back_mm {
                t = u;
            }
        }
        heads.push(t);
        // Turned a corner: the line ends where the turn began.
        let mut turns = lp.band_turn_deg.iter().zip(&lp.band_turn_over_mm);
        let turned = turns.find(|&(deg, over)| {
            let k = (over / step_mm).round() as usize;
            let old = heads[heads.len().saturating_sub(k + 1)];
            heads.len() > k && old[0] * t[0] + old[1] * t[1] < deg.to_radians().cos()
        });
        if let Some((_, over)) = turned {
            let cut = (over / step_mm / 2.0).round() as usize;
            let keep = h.centres.len().saturating_sub(cut).max(1);
            h.centres.truncate(keep);
            arc.truncate(keep);
            h.gaps.retain(|g| arc_of(&h.centres, g.to_mm));
            break;
        }
    }
    h
}

/// Whether `q` is one of `centres`.
pub(crate) fn arc_of(centres: &[[f64; 2]], q: [f64; 2]) -> bool {
    centres.iter().any(|c| dist(*c, q) < 1e-9)
}

/// Whether `p` (at arc `s`) comes within a step of a centre at least 10 mm of arc back.
fn overlaps(centres: &[[f64; 2]], arc: &[f64], s: f64, p: [f64; 2], step_mm: f64) -> bool {
    centres
        .iter()
        .zip(arc)
        .step_by(2)
        .any(|(c, &a)| s - a >= 10.0 && dist(*c, p) < 2.0 * step_mm)
}

/// Whether `p` (at arc `s` from the seed) comes onto the other way's centres farther than 10
/// mm from the seed.
fn overlaps_other(other: &[[f64; 2]], p: [f64; 2], s: f64, step_mm: f64) -> bool {
    s >= 5.0
        && other
            .iter()
            .skip((10.0 / step_mm) as usize)
            .step_by(2)
            .any(|c| dist(*c, p) < 2.0 * step_mm)
}

/// Whether the line's way is settled at the end of `centres` (drawn, since the last jump): the
/// last `band_settled_mm` of them run straight along `t` (within `band_centre_deg`); only then may a
/// gap longer than `--max-gap-mm` be looked across.
fn settled(centres: &[[f64; 2]], t: [f64; 2], lp: &LinesParams) -> bool {
    let Some(&end) = centres.last() else {
        return false;
    };
    let mut len = 0.0;
    for w in centres.windows(2).rev() {
        len += dist(w[0], w[1]);
        if len >= lp.band_settled_mm {
            let Some(u) = unit(sub(end, w[0])) else {
                return false;
            };
            return u[0] * t[0] + u[1] * t[1] >= lp.band_centre_deg.to_radians().cos();
        }
    }
    false
}

/// Past an empty window at `c`: the nearest dots ahead running along `t`, within
/// `band_half_mm` + 10 % of the distance of the line, up to `max_gap_mm` (any dot) or
/// [`reach_mm`] (a path's dot). Returns the new centre and the dots of its window.
fn look_ahead(
    cloud: &Cloud,
    c: [f64; 2],
    t: [f64; 2],
    n: [f64; 2],
    max_gap_mm: f64,
    settled: bool,
) -> Option<([f64; 2], Vec<usize>)> {
    let lp = &cloud.lp;
    let (half, step_mm) = (lp.band_half_mm, lp.band_step_mm);
    let reach = reach_mm(max_gap_mm);
    let mid = [c[0] + 0.5 * reach * t[0], c[1] + 0.5 * reach * t[1]];
    let cos_far = lp.band_centre_deg.to_radians().cos();
    let mut near: Vec<(usize, f64, f64)> = Vec::new();
    let mut far: Vec<(usize, f64, f64)> = Vec::new();
    for i in cloud.around(mid, 0.5 * reach + half + 0.1 * reach) {
        let v = sub(cloud.dots[i].p, c);
        let along = v[0] * t[0] + v[1] * t[1];
        let across = v[0] * n[0] + v[1] * n[1];
        if along <= step_mm || along > reach || !cloud.runs_along(i, t) {
            continue;
        }
        if along <= max_gap_mm && across.abs() <= half + 0.1 * along {
            near.push((i, along, across));
        } else if settled
            && along > max_gap_mm
            && across.abs() <= half + 0.05 * along
            && matches!(cloud.dots[i].src, Source::Path(_))
        {
            let d = cloud.dots[i].dir;
            if (d[0] * t[0] + d[1] * t[1]).abs() >= cos_far {
                far.push((i, along, across));
            }
        }
    }
    let first_of = |v: &[(usize, f64, f64)]| v.iter().map(|a| a.1).fold(f64::INFINITY, f64::min);
    let (cands, first) = if !near.is_empty() {
        let f = first_of(&near);
        (near, f)
    } else {
        // Farther than --max-gap-mm only to a stretch of a path running the line's way.
        far.sort_by(|x, y| x.1.total_cmp(&y.1));
        let found = (0..far.len()).find(|&k| {
            far[k..]
                .iter()
                .take_while(|a| a.1 <= far[k].1 + lp.band_far_mark_mm)
                .count()
                >= lp.band_far_min_dots
        })?;
        let f = far[found].1;
        (far.split_off(found), f)
    };
    let win: Vec<&(usize, f64, f64)> = cands
        .iter()
        .filter(|a| a.1 <= first + 2.0 * lp.band_half_along_mm)
        .collect();
    let mut across: Vec<f64> = win.iter().map(|a| a.2).collect();
    let m = median(&mut across);
    let a = first;
    Some((
        [c[0] + a * t[0] + m * n[0], c[1] + a * t[1] + m * n[1]],
        win.iter().map(|a| a.0).collect(),
    ))
}

#[cfg(test)]
mod tests;
