//! The band of ink along a drawn line (`rigctl trace --paths`): a plotter that draws a line
//! several times leaves passes side by side, crossing each other, each broken where the tracker
//! lost it. Rather than pairing passes, the line is followed through the cloud of every written
//! point (paths and strays) with its direction: from a seed, step along the line and put each
//! centre at the median offset across it of the points in a window ([`BAND_HALF_MM`] either
//! side, [`HALF_ALONG_MM`] along) whose own direction runs within [`BAND_DEG`] of the line's
//! (so a line crossing it is not followed). Where the window is empty the walk looks ahead in
//! a narrow cone for points running the same way: within `--max-gap-mm` the gap is bridged,
//! farther (up to [`reach_mm`], to a path only) it is missing; nothing ahead ends the line.
//! The points in every window are the line's: the paths they belong to are its passes.

use super::plane::{dist, sub, unit, Grid};
use super::stages::link::Gap;

/// A line's band reaches this far either side of its centre, mm.
pub const BAND_HALF_MM: f64 = 3.0;
/// Points running within this angle of the line belong to it, degrees.
pub const BAND_DEG: f64 = 40.0;
/// A centre is placed among the points running within this angle of the line, degrees.
const CENTRE_DEG: f64 = 25.0;
/// ... moving at most this across the line from one centre to the next, mm.
const MAX_SHIFT_MM: f64 = 0.15;
/// Distance between centres, mm.
const STEP_MM: f64 = 0.5;
/// The window reaches this far along the line either side of a centre, mm.
const HALF_ALONG_MM: f64 = 1.5;
/// The line's direction: the chord back over this arc, mm.
const DIR_BACK_MM: f64 = 4.0;
/// A walk coming back within this of its own start (after [`CLOSE_AFTER_MM`]) closes, mm.
const CLOSE_MM: f64 = 1.5;
const CLOSE_AFTER_MM: f64 = 20.0;
/// A walk turning by more than these angles (degrees) over these arcs (mm) ends there (a
/// corner).
const TURNS: [(f64, f64); 2] = [(45.0, 8.0), (60.0, 16.0)];
/// A gap longer than `--max-gap-mm` leads only to a path running the line's way (within
/// [`CENTRE_DEG`]) with this many points within [`FAR_MARK_MM`] of each other along it.
const FAR_MIN_DOTS: usize = 12;
const FAR_MARK_MM: f64 = 5.0;
/// ... and only from a line drawn straight for this long before the gap, mm.
const SETTLED_MM: f64 = 10.0;
/// A point of a gap within this of a written point is inked, mm.
const INK_NEAR_MM: f64 = 1.0;
/// Grid cell of the cloud, mm.
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
}

impl Cloud {
    pub fn new(dots: Vec<Dot>) -> Self {
        let mut grid = Grid::new(CELL_MM);
        for (i, d) in dots.iter().enumerate() {
            grid.insert(d.p, i as u32);
        }
        Self { dots, grid }
    }

    /// The dots within `r` (mm) of `c`, and maybe a few more, in no particular order.
    pub fn around(&self, c: [f64; 2], r: f64) -> impl Iterator<Item = usize> + '_ {
        self.grid.around(c, r).map(|(_, i)| *i as usize)
    }

    /// The longest stretch of the segment `a`-`b` with no written point (of any direction:
    /// where the segment crosses another line, its ink is there) within [`INK_NEAR_MM`], mm.
    pub fn inkless_mm(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        let len = dist(a, b);
        let n = (len / 0.25).ceil().max(1.0) as usize;
        let (mut run, mut best) = (0.0f64, 0.0f64);
        for k in 0..=n {
            let f = k as f64 / n as f64;
            let p = [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])];
            let inked = self
                .around(p, INK_NEAR_MM)
                .any(|i| dist(self.dots[i].p, p) <= INK_NEAR_MM);
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
        (d[0] * t[0] + d[1] * t[1]).abs() >= BAND_DEG.to_radians().cos()
    }

    /// The dots in the window at `c` (direction `t`, normal `n`) with their offsets across.
    fn window(&self, c: [f64; 2], t: [f64; 2], n: [f64; 2]) -> Vec<(usize, f64)> {
        self.around(c, BAND_HALF_MM + HALF_ALONG_MM)
            .filter_map(|i| {
                let v = sub(self.dots[i].p, c);
                let along = v[0] * t[0] + v[1] * t[1];
                let across = v[0] * n[0] + v[1] * n[1];
                (along.abs() <= HALF_ALONG_MM
                    && across.abs() <= BAND_HALF_MM
                    && self.runs_along(i, t))
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
    let back_steps = (DIR_BACK_MM / STEP_MM).round() as usize;
    let max_steps = cloud.dots.len() * 4 + 1000;
    for _ in 0..max_steps {
        let c = *h.centres.last().unwrap_or(&seed);
        let n = [-t[1], t[0]];
        let pred = [c[0] + STEP_MM * t[0], c[1] + STEP_MM * t[1]];
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
        let advance = (STEP_MM + ahead_mm).min(STEP_MM);
        if advance < 0.05 {
            win.clear();
        }
        let (next, gap) = if win.is_empty() {
            match look_ahead(cloud, c, t, n, max_gap_mm, settled(&h.centres[since..], t)) {
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
            // MAX_SHIFT_MM a step across (a pass leaving the line cannot pull it along).
            let cos_centre = CENTRE_DEG.to_radians().cos();
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
            let m = median(&mut across).clamp(-MAX_SHIFT_MM, MAX_SHIFT_MM);
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
            && s >= CLOSE_AFTER_MM
            && dist(next, seed) <= CLOSE_MM.max(gap.as_ref().map_or(0.0, |g| g.length_mm + STEP_MM))
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
        if overlaps(&h.centres, &arc, s, next) || overlaps_other(other_way, next, s) {
            break;
        }
        let gap_here = gap.is_some();
        if let Some(g) = gap {
            h.gaps.push(g);
        }
        h.centres.push(next);
        arc.push(s);
        // The direction from the chord back over DIR_BACK_MM, not across a jump (which may
        // land beside the line's last centre): kept until 2 mm past it.
        let k = h.centres.len() - 1;
        if gap_here {
            since = k;
        }
        let b = h.centres[k.saturating_sub(back_steps).max(since)];
        if let Some(u) = unit(sub(next, b)) {
            if dist(next, b) >= 0.5 * DIR_BACK_MM {
                t = u;
            }
        }
        heads.push(t);
        // Turned a corner: the line ends where the turn began.
        let turned = TURNS.iter().find(|(deg, over)| {
            let k = (over / STEP_MM).round() as usize;
            let old = heads[heads.len().saturating_sub(k + 1)];
            heads.len() > k && old[0] * t[0] + old[1] * t[1] < deg.to_radians().cos()
        });
        if let Some((_, over)) = turned {
            let cut = (over / STEP_MM / 2.0).round() as usize;
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
fn overlaps(centres: &[[f64; 2]], arc: &[f64], s: f64, p: [f64; 2]) -> bool {
    centres
        .iter()
        .zip(arc)
        .step_by(2)
        .any(|(c, &a)| s - a >= 10.0 && dist(*c, p) < 2.0 * STEP_MM)
}

/// Whether `p` (at arc `s` from the seed) comes onto the other way's centres farther than 10
/// mm from the seed.
fn overlaps_other(other: &[[f64; 2]], p: [f64; 2], s: f64) -> bool {
    s >= 5.0
        && other
            .iter()
            .skip((10.0 / STEP_MM) as usize)
            .step_by(2)
            .any(|c| dist(*c, p) < 2.0 * STEP_MM)
}

/// Whether the line's way is settled at the end of `centres` (drawn, since the last jump): the
/// last [`SETTLED_MM`] of them run straight along `t` (within [`CENTRE_DEG`]); only then may a
/// gap longer than `--max-gap-mm` be looked across.
fn settled(centres: &[[f64; 2]], t: [f64; 2]) -> bool {
    let Some(&end) = centres.last() else {
        return false;
    };
    let mut len = 0.0;
    for w in centres.windows(2).rev() {
        len += dist(w[0], w[1]);
        if len >= SETTLED_MM {
            let Some(u) = unit(sub(end, w[0])) else {
                return false;
            };
            return u[0] * t[0] + u[1] * t[1] >= CENTRE_DEG.to_radians().cos();
        }
    }
    false
}

/// Past an empty window at `c`: the nearest dots ahead running along `t`, within
/// [`BAND_HALF_MM`] + 10 % of the distance of the line, up to `max_gap_mm` (any dot) or
/// [`reach_mm`] (a path's dot). Returns the new centre and the dots of its window.
fn look_ahead(
    cloud: &Cloud,
    c: [f64; 2],
    t: [f64; 2],
    n: [f64; 2],
    max_gap_mm: f64,
    settled: bool,
) -> Option<([f64; 2], Vec<usize>)> {
    let reach = reach_mm(max_gap_mm);
    let mid = [c[0] + 0.5 * reach * t[0], c[1] + 0.5 * reach * t[1]];
    let cos_far = CENTRE_DEG.to_radians().cos();
    let mut near: Vec<(usize, f64, f64)> = Vec::new();
    let mut far: Vec<(usize, f64, f64)> = Vec::new();
    for i in cloud.around(mid, 0.5 * reach + BAND_HALF_MM + 0.1 * reach) {
        let v = sub(cloud.dots[i].p, c);
        let along = v[0] * t[0] + v[1] * t[1];
        let across = v[0] * n[0] + v[1] * n[1];
        if along <= STEP_MM || along > reach || !cloud.runs_along(i, t) {
            continue;
        }
        if along <= max_gap_mm && across.abs() <= BAND_HALF_MM + 0.1 * along {
            near.push((i, along, across));
        } else if settled
            && along > max_gap_mm
            && across.abs() <= BAND_HALF_MM + 0.05 * along
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
                .take_while(|a| a.1 <= far[k].1 + FAR_MARK_MM)
                .count()
                >= FAR_MIN_DOTS
        })?;
        let f = far[found].1;
        (far.split_off(found), f)
    };
    let win: Vec<&(usize, f64, f64)> = cands
        .iter()
        .filter(|a| a.1 <= first + 2.0 * HALF_ALONG_MM)
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
