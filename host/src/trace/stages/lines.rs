//! Drawn lines of a drawing (`rigctl trace --paths DIR`): a plotter may draw a line several
//! times, each pass beside the last and crossing it, and the tracker breaks each pass where it
//! loses it. A drawn line is followed through the band of ink all its passes leave
//! ([`crate::trace::band`]): from the longest path not yet in a line, through every written point
//! running its way, bridging gaps up to `--max-gap-mm` (a longer one, up to
//! [`band::reach_mm`], is missing). The paths with `LinesParams::pass_mm` (or half their length) in its
//! band are its passes; its centreline is the band's (written as a file of its own). A path
//! that is the only pass of every line it is in is one line (a box drawn round in one go,
//! turning its corners).
//!
//! A line is **whole** when no gap is missing and nothing may continue it: a path running its
//! way within `max(2 x --max-gap-mm, 15 mm)` ahead of one of its ends (within 45 degrees of
//! its direction), or a mark that may continue one of its passes at one of the line's ends
//! (or a gap too long to bridge to it), unless that mark is a pass of the same line, lies off
//! the line's axis, or runs across it (more than `LinesParams::across_deg` to it) within `--max-gap-mm`
//! of the pass's end: a line ending on another one.
//!
//! Files: `cloud.rs` (the written points and their directions), `walks.rs` (walks that are one
//! line joined), `overrun.rs` (an end followed round into a line across, cut back), `meet.rs`
//! (ends carried on to a line across or a corner), `ends.rs` (what may continue a line); here
//! the lines put together from them ([`lines`]).

use super::link::{Gap, LeftOut};
use crate::trace::band::{self, Source, Walk};
use crate::trace::chain::resample;
use crate::trace::paths::DrawnPath;
use crate::trace::plane::{self, dist, sub};
use cloud::cloud;
use ends::{counts, judge_ends};
use meet::meet_lines_across;
pub use params::LinesParams;
use std::collections::HashSet;
use walks::{duplicate_of, join_continuing};

mod cloud;
mod ends;
mod meet;
mod overrun;
mod params;
#[cfg(test)]
mod tests;
mod walks;

/// Why a path may not be the whole of its drawn line: a mark beyond one of its free ends.
#[derive(Debug, Clone)]
pub(crate) struct Loose {
    /// The path the mark is part of (index into the drawing's paths; `None`: not a path, or
    /// the path's own other end).
    pub path: Option<usize>,
    /// The mark's points (to tell whether it runs across), sheet mm.
    pub mark: Vec<[f64; 2]>,
    /// The free end and its outward direction.
    pub end_mm: [f64; 2],
    pub dir: [f64; 2],
    /// A missing gap (index into the path's gaps) or a mark that may continue it (index into
    /// `continued_by`).
    pub what: LooseWhat,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LooseWhat {
    Gap(usize),
    Mark(usize),
}

/// One drawn line: the passes along it, its centreline, what no pass covers.
#[derive(Debug, Clone)]
pub struct DrawnLine {
    /// The paths running along it (indices into the drawing's paths, longest first).
    pub passes: Vec<usize>,
    /// Its centreline (of its band; a line of one path: that path), sheet mm.
    pub points_mm: Vec<[f64; 2]>,
    pub closed: bool,
    /// Its ends (an open line), sheet mm, and its length along it, mm.
    pub from_mm: [f64; 2],
    pub to_mm: [f64; 2],
    pub length_mm: f64,
    /// Length covered by a pass (drawn or bridged within a pass), mm.
    pub covered_mm: f64,
    /// Stretches no pass covers (bridged: at most `--max-gap-mm`), in order along it; a line of
    /// one path: that path's gaps, with the missing ones that count.
    pub gaps: Vec<Gap>,
    /// Marks that may continue it.
    pub continued_by: Vec<LeftOut>,
    /// The outward unit direction of each end (`from`, `to`).
    pub(crate) out_dir: [[f64; 2]; 2],
}

impl DrawnLine {
    /// Whether the line is drawn end to end: no gap missing, nothing that may continue it.
    pub fn is_whole(&self) -> bool {
        self.gaps.iter().all(|g| g.bridged) && self.continued_by.is_empty()
    }
}

/// `d` scaled to unit length; x for a zero vector.
fn unit(d: [f64; 2]) -> [f64; 2] {
    plane::unit(d).unwrap_or([1.0, 0.0])
}

/// |cos| of the angle between two unit directions (1: parallel either way).
fn abs_cos(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] * b[0] + a[1] * b[1]).abs()
}

/// Cumulative arc length of an open polyline.
fn arc(pts: &[[f64; 2]]) -> Vec<f64> {
    let mut s = vec![0.0; pts.len()];
    for i in 1..pts.len() {
        s[i] = s[i - 1] + dist(pts[i - 1], pts[i]);
    }
    s
}

/// Unit directions along `pts` (an open polyline): the chord over `LinesParams::dir_half_mm` either side.
fn directions(pts: &[[f64; 2]], s: &[f64], lp: &LinesParams) -> Vec<[f64; 2]> {
    let n = pts.len();
    (0..n)
        .map(|i| {
            let a = s[..i].partition_point(|&v| v < s[i] - lp.dir_half_mm);
            let b = (i + s[i..].partition_point(|&v| v <= s[i] + lp.dir_half_mm)).min(n - 1);
            unit(sub(pts[b], pts[a.min(n - 1)]))
        })
        .collect()
}

/// The unit chord of `pts` from `half` mm of arc before point `i` to `half` after it (as far
/// as the polyline goes).
fn chord_dir(pts: &[[f64; 2]], i: usize, half: f64) -> [f64; 2] {
    chord_dir_on(pts, &arc(pts), i, half)
}

/// [`chord_dir`] with the polyline's cumulative arc length `s` ([`arc`]) given.
fn chord_dir_on(pts: &[[f64; 2]], s: &[f64], i: usize, half: f64) -> [f64; 2] {
    let n = pts.len();
    if n < 2 {
        return [1.0, 0.0];
    }
    let i = i.min(n - 1);
    let a = s.partition_point(|&v| v < s[i] - half).min(n - 1);
    let b = s.partition_point(|&v| v <= s[i] + half).clamp(1, n) - 1;
    if a == b {
        return unit(sub(pts[n - 1], pts[0]));
    }
    unit(sub(pts[b], pts[a]))
}

/// The longest run `(a, b)` (`a..b`) of `free` dots of a path; its length, mm.
fn longest_free_run(free: &[bool], pts: &[[f64; 2]]) -> Option<(usize, usize, f64)> {
    let mut best: Option<(usize, usize, f64)> = None;
    let mut i = 0;
    while i < free.len() {
        if !free[i] {
            i += 1;
            continue;
        }
        let mut j = i;
        let mut len = 0.0;
        while j + 1 < free.len() && free[j + 1] {
            len += dist(pts[j], pts[j + 1]);
            j += 1;
        }
        if best.is_none_or(|b| len > b.2) {
            best = Some((i, j + 1, len));
        }
        i = j + 1;
    }
    best
}

/// The drawn lines of `paths` (with the points of the strays, and the marks beyond each
/// path's free ends, `loose[i]` for path `i`), longest first. Walks shorter than `min_mark_mm`
/// (the link stage's speck length) are no line.
pub(crate) fn lines(
    paths: &[DrawnPath],
    strays: &[Vec<[f64; 2]>],
    loose: &[Vec<Loose>],
    max_gap_mm: f64,
    min_mark_mm: f64,
    lp: &LinesParams,
) -> Vec<DrawnLine> {
    let (cloud, first) = cloud(paths, strays, lp);
    // Walk from the middle of the longest stretch of each path not yet in a line, longest
    // path first.
    let mut free = vec![true; cloud.dots.len()];
    let mut walks: Vec<Walk> = Vec::new();
    for (pi, p) in paths.iter().enumerate() {
        let (a, b) = (first[pi], first[pi + 1]);
        while let Some((r0, r1, len)) = longest_free_run(&free[a..b], &p.stroke.points_mm) {
            if len < lp.pass_mm {
                break;
            }
            let mid = a + (r0 + r1) / 2;
            if cloud.dots[mid].dir == [0.0, 0.0] {
                free[mid] = false;
                continue;
            }
            let seed_dir = chord_dir(&p.stroke.points_mm, mid - a, lp.seed_half_mm);
            let w = band::walk(&cloud, cloud.dots[mid].p, seed_dir, max_gap_mm);
            if w.length_mm() < min_mark_mm || !w.taken.contains(&mid) {
                // Not a line: its dots are not seeds again.
                free[a + r0..a + r1].iter_mut().for_each(|f| *f = false);
                continue;
            }
            for &k in &w.taken {
                free[k] = false;
            }
            walks.push(w);
        }
    }
    // A walk along a longer one for half its length is part of it (its dots the longer's).
    walks.sort_by(|x, y| y.length_mm().total_cmp(&x.length_mm()));
    let mut kept: Vec<Walk> = Vec::new();
    let mut taken: Vec<HashSet<usize>> = Vec::new();
    for w in walks {
        match duplicate_of(&w, &kept, lp) {
            Some(d) => taken[d].extend(w.taken.iter().copied()),
            None => {
                taken.push(w.taken.iter().copied().collect());
                kept.push(w);
            }
        }
    }
    let (mut walks, taken) = join_continuing(kept, taken, lp);
    overrun::cut_overruns(&mut walks, lp);
    meet_lines_across(&mut walks, &cloud, lp);
    // The passes of each line: the paths with LinesParams::pass_mm (or half their length) in its band.
    let spacing =
        |p: &DrawnPath| p.stroke.length_mm() / (p.stroke.points_mm.len().max(2) - 1) as f64;
    let passes: Vec<Vec<usize>> = taken
        .iter()
        .map(|set| {
            let mut count = vec![0usize; paths.len()];
            for &k in set {
                if let Source::Path(p) = cloud.dots[k].src {
                    count[p] += 1;
                }
            }
            let mut v: Vec<usize> = (0..paths.len())
                .filter(|&p| {
                    let len = count[p] as f64 * spacing(&paths[p]);
                    count[p] > 0 && len >= lp.pass_mm.min(0.5 * paths[p].stroke.length_mm())
                })
                .collect();
            v.sort_by(|&x, &y| {
                paths[y]
                    .stroke
                    .length_mm()
                    .total_cmp(&paths[x].stroke.length_mm())
            });
            v
        })
        .collect();
    // A path that is the only pass of every line it is in: one line, the path.
    let mut lines_of_path: Vec<Vec<usize>> = vec![Vec::new(); paths.len()];
    for (l, ps) in passes.iter().enumerate() {
        for &p in ps {
            lines_of_path[p].push(l);
        }
    }
    let alone = |p: usize| {
        !lines_of_path[p].is_empty() && lines_of_path[p].iter().all(|&l| passes[l] == [p])
    };
    let arcs: Vec<Vec<f64>> = walks.iter().map(|w| arc(&w.centres)).collect();
    let mut out: Vec<DrawnLine> = Vec::new();
    for p in (0..paths.len()).filter(|&p| alone(p)) {
        out.push(path_line(paths, p, loose, max_gap_mm, lp));
    }
    for (l, w) in walks.iter().enumerate() {
        if passes[l].is_empty() || (passes[l].len() == 1 && alone(passes[l][0])) {
            continue;
        }
        let mut line = band_line(w, passes[l].clone(), lp);
        // A pass of another line running across this one there is that line's.
        let across_here = |p: usize, q: [f64; 2], t: [f64; 2]| {
            lines_of_path[p].iter().any(|&o| {
                o != l && {
                    let c = &walks[o].centres;
                    c.iter()
                        .enumerate()
                        .filter(|(_, x)| dist(**x, q) <= lp.band_half_mm)
                        .min_by(|x, y| dist(*x.1, q).total_cmp(&dist(*y.1, q)))
                        .is_some_and(|(k, _)| {
                            abs_cos(chord_dir_on(c, &arcs[o], k, lp.dir_half_mm), t)
                                < lp.across_deg.to_radians().cos()
                        })
                }
            })
        };
        judge_ends(
            &mut line,
            &taken[l],
            &cloud,
            paths,
            max_gap_mm,
            &across_here,
            lp,
        );
        out.push(line);
    }
    out.sort_by(|a, b| b.length_mm.total_cmp(&a.length_mm));
    out
}

/// The line that is path `p`, judged by what lies beyond its free ends.
fn path_line(
    paths: &[DrawnPath],
    p: usize,
    loose: &[Vec<Loose>],
    max_gap_mm: f64,
    lp: &LinesParams,
) -> DrawnLine {
    let path = &paths[p];
    let pts = &path.stroke.points_mm;
    let len = path.stroke.length_mm();
    let s = arc(pts);
    let head = point_at(pts, &s, lp.end_chord_mm.min(len));
    let tail = point_at(pts, &s, (len - lp.end_chord_mm).max(0.0));
    let mut line = DrawnLine {
        out_dir: [unit(sub(pts[0], head)), unit(sub(pts[pts.len() - 1], tail))],
        passes: vec![p],
        points_mm: pts.clone(),
        closed: path.stroke.closed,
        from_mm: pts[0],
        to_mm: pts[pts.len() - 1],
        length_mm: len,
        covered_mm: len,
        gaps: path.gaps.iter().filter(|g| g.bridged).cloned().collect(),
        continued_by: Vec::new(),
    };
    for l in &loose[p] {
        if !counts(l, &line.passes, None, max_gap_mm, lp) {
            continue;
        }
        match l.what {
            LooseWhat::Gap(k) => line.gaps.extend(path.gaps.get(k).cloned()),
            LooseWhat::Mark(k) => {
                if let Some(m) = path.continued_by.get(k) {
                    if !line.continued_by.contains(m) {
                        line.continued_by.push(m.clone());
                    }
                }
            }
        }
    }
    line
}

/// The line of walk `w` (passes `passes`): its centreline smoothed over `LinesParams::dir_half_mm`.
fn band_line(w: &Walk, passes: Vec<usize>, lp: &LinesParams) -> DrawnLine {
    let pts = resample(&smoothed(&w.centres, lp), w.closed, lp.line_spacing_mm);
    let pts = if pts.len() >= 2 {
        pts
    } else {
        w.centres.clone()
    };
    let s = arc(&pts);
    let total = s.last().copied().unwrap_or(0.0);
    let head = point_at(&pts, &s, lp.end_chord_mm.min(total));
    let tail = point_at(&pts, &s, (total - lp.end_chord_mm).max(0.0));
    let length_mm = w.length_mm();
    let gaps_mm: f64 = w.gaps.iter().map(|g| g.length_mm).sum();
    DrawnLine {
        out_dir: [unit(sub(pts[0], head)), unit(sub(pts[pts.len() - 1], tail))],
        passes,
        closed: w.closed,
        from_mm: pts[0],
        to_mm: if w.closed { pts[0] } else { pts[pts.len() - 1] },
        length_mm,
        covered_mm: (length_mm - gaps_mm).max(0.0),
        gaps: w.gaps.clone(),
        continued_by: Vec::new(),
        points_mm: pts,
    }
}

/// `pts` with each point the mean of those within `LinesParams::dir_half_mm` of arc length either side
/// (the window shrunk near the ends, which stay in place).
fn smoothed(pts: &[[f64; 2]], lp: &LinesParams) -> Vec<[f64; 2]> {
    let s = arc(pts);
    let total = s.last().copied().unwrap_or(0.0);
    (0..pts.len())
        .map(|i| {
            let half = lp.dir_half_mm.min(s[i]).min(total - s[i]);
            let a = s.partition_point(|&v| v < s[i] - half);
            let b = s.partition_point(|&v| v <= s[i] + half);
            let n = (b - a).max(1) as f64;
            let (sx, sy) = pts[a..b.max(a + 1).min(pts.len())]
                .iter()
                .fold((0.0, 0.0), |acc, p| (acc.0 + p[0], acc.1 + p[1]));
            [sx / n, sy / n]
        })
        .collect()
}

/// The point at arc length `v` along `pts` (cumulative arc `s`).
fn point_at(pts: &[[f64; 2]], s: &[f64], v: f64) -> [f64; 2] {
    let n = pts.len();
    if n == 1 {
        return pts[0];
    }
    let k = s.partition_point(|&x| x < v).clamp(1, n - 1);
    let f = ((v - s[k - 1]) / (s[k] - s[k - 1]).max(1e-12)).clamp(0.0, 1.0);
    [
        pts[k - 1][0] + f * (pts[k][0] - pts[k - 1][0]),
        pts[k - 1][1] + f * (pts[k][1] - pts[k - 1][1]),
    ]
}
