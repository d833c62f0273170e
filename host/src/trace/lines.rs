//! Drawn lines of a drawing (`rigctl trace --paths DIR`): a plotter may draw a line several
//! times, each pass beside the last and crossing it, and the tracker breaks each pass where it
//! loses it. A drawn line is followed through the band of ink all its passes leave
//! ([`super::band`]): from the longest path not yet in a line, through every written point
//! running its way, bridging gaps up to `--max-gap-mm` (a longer one, up to
//! [`band::reach_mm`], is missing). The paths with [`PASS_MM`] (or half their length) in its
//! band are its passes; its centreline is the band's (written as a file of its own). A path
//! that is the only pass of every line it is in is one line (a box drawn round in one go,
//! turning its corners).
//!
//! A line is **whole** when no gap is missing and nothing may continue it: a path running its
//! way within `max(2 x --max-gap-mm, 15 mm)` ahead of one of its ends (within 45 degrees of
//! its direction), or a mark that may continue one of its passes at one of the line's ends
//! (or a gap too long to bridge to it), unless that mark is a pass of the same line, lies off
//! the line's axis, or runs across it (more than [`ACROSS_DEG`] to it) within `--max-gap-mm`
//! of the pass's end: a line ending on another one.

use super::band::{self, Cloud, Dot, Source, Walk, BAND_DEG, BAND_HALF_MM};
use super::chain::resample;
use super::link::{Gap, LeftOut, LeftOutKind, MIN_MARK_MM};
use super::paths::DrawnPath;
use super::plane::{self, dist, sub};
use std::collections::HashSet;

mod overrun;

/// Passes of one line lie within this of its centre, mm.
pub const ALONGSIDE_MM: f64 = BAND_HALF_MM;
/// A path is a pass of a line with this much of it in the line's band (or half of it), mm.
pub const PASS_MM: f64 = 5.0;
/// Direction of a path at a point: the chord over this arc length either side of it, mm.
const DIR_HALF_MM: f64 = 4.0;
/// A mark meeting a pass's end at more than this to it runs across the line, degrees.
pub const ACROSS_DEG: f64 = 45.0;
/// Direction of a line's end (to carry it on past the end, and to tell whether another line
/// continues it): the chord over this length, mm (a zigzag pass turns often within a few mm).
const END_CHORD_MM: f64 = 12.0;
/// A walk whose centres lie within this of another line's (running its way) for half its
/// length is that line, mm.
const DUPLICATE_MM: f64 = 1.5 * BAND_HALF_MM;
/// A walk starts the way its seed path runs over this either side of the seed, mm.
const SEED_HALF_MM: f64 = 8.0;
/// A walk whose end lies within this of another's centres may be continued by it, mm (the
/// band's width: passes drawn apart).
const JOIN_MM: f64 = 2.0 * BAND_HALF_MM;
/// Walks continue each other only where their directions (over [`END_CHORD_MM`]) agree within
/// this, degrees.
const JOIN_DEG: f64 = 40.0;
/// A line ends on a line across it whose centreline lies within this ahead of its end, mm.
const MEET_MM: f64 = BAND_HALF_MM + 1.5;
/// ... or within this, where the stretch beyond the other's band is drawn (no stretch longer
/// than [`INKLESS_OK_MM`] without a written point within 1 mm) or else a skip (bridged), mm.
const MEET_INKED_MM: f64 = 2.0 * BAND_HALF_MM;
const INKLESS_OK_MM: f64 = 1.0;
/// ... within this of the end's direction, mm.
const STEP_OFF_MM: f64 = 1.0;
/// Marks shorter than this are not followed (dust), mm.
const MIN_DOT_MARK_MM: f64 = 1.0;
/// Spacing of a line's centreline, mm.
const LINE_SPACING_MM: f64 = 0.25;

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

/// Unit directions along `pts` (an open polyline): the chord over [`DIR_HALF_MM`] either side.
fn directions(pts: &[[f64; 2]], s: &[f64]) -> Vec<[f64; 2]> {
    let n = pts.len();
    (0..n)
        .map(|i| {
            let a = s[..i].partition_point(|&v| v < s[i] - DIR_HALF_MM);
            let b = (i + s[i..].partition_point(|&v| v <= s[i] + DIR_HALF_MM)).min(n - 1);
            unit(sub(pts[b], pts[a.min(n - 1)]))
        })
        .collect()
}

/// A path turning by more than this between the chords of [`DIR_HALF_MM`] before and after a
/// point turns a corner there, degrees.
const CORNER_DEG: f64 = 50.0;
/// Direction of a path's point for following a band: the chord over this either side, mm.
const BAND_DIR_HALF_MM: f64 = 4.0;

/// Directions along `pts` for following a band: the chord over [`BAND_DIR_HALF_MM`] either
/// side (over a zigzag pass's teeth), none (zero) where the path turns a corner (by more than
/// [`CORNER_DEG`] between the chords before and after a point): a band is not followed round
/// a pass's corner into the line it turns into.
fn band_directions(pts: &[[f64; 2]], s: &[f64]) -> Vec<[f64; 2]> {
    let n = pts.len();
    let cos_corner = CORNER_DEG.to_radians().cos();
    let h = BAND_DIR_HALF_MM;
    (0..n)
        .map(|i| {
            let a = s[..i].partition_point(|&v| v < s[i] - h).min(n - 1);
            let b = (i + s[i..].partition_point(|&v| v <= s[i] + h)).min(n - 1);
            let (back, ahead) = (sub(pts[i], pts[a]), sub(pts[b], pts[i]));
            let (lb, la) = (back[0].hypot(back[1]), ahead[0].hypot(ahead[1]));
            if lb > 0.5 * h
                && la > 0.5 * h
                && (back[0] * ahead[0] + back[1] * ahead[1]) / (lb * la) < cos_corner
            {
                [0.0, 0.0]
            } else {
                unit(sub(pts[b], pts[a]))
            }
        })
        .collect()
}

/// The written points of the paths and of the strays (`strays`: their points, mm), with
/// their directions; `first[i]..first[i + 1]` are path `i`'s.
fn cloud(paths: &[DrawnPath], strays: &[Vec<[f64; 2]>]) -> (Cloud, Vec<usize>) {
    let mut dots = Vec::new();
    let mut first = Vec::with_capacity(paths.len() + 1);
    let add = |pts: &[[f64; 2]], src: Source, dots: &mut Vec<Dot>| {
        if pts.len() < 2 {
            return;
        }
        let s = arc(pts);
        for (p, dir) in pts.iter().zip(band_directions(pts, &s)) {
            dots.push(Dot { p: *p, dir, src });
        }
    };
    for (i, p) in paths.iter().enumerate() {
        first.push(dots.len());
        add(&p.stroke.points_mm, Source::Path(i), &mut dots);
    }
    first.push(dots.len());
    for s in strays {
        if arc(s).last().copied().unwrap_or(0.0) >= MIN_DOT_MARK_MM {
            add(s, Source::Stray, &mut dots);
        }
    }
    (Cloud::new(dots), first)
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

/// The walk among `walks` that `w` runs along for half its length or more (its centres within
/// [`BAND_HALF_MM`] of that walk's).
fn duplicate_of(w: &Walk, walks: &[Walk]) -> Option<usize> {
    let probe: Vec<[f64; 2]> = w.centres.iter().step_by(4).copied().collect();
    if probe.is_empty() {
        return None;
    }
    let dirs = |c: &[[f64; 2]]| directions(c, &arc(c));
    let wd: Vec<[f64; 2]> = dirs(&w.centres).into_iter().step_by(4).collect();
    let cos_along = BAND_DEG.to_radians().cos();
    walks.iter().position(|o| {
        let od = dirs(&o.centres);
        let near = probe
            .iter()
            .zip(&wd)
            .filter(|(p, d)| {
                o.centres
                    .iter()
                    .zip(&od)
                    .any(|(c, e)| dist(*c, **p) <= DUPLICATE_MM && abs_cos(*e, **d) >= cos_along)
            })
            .count();
        2 * near >= probe.len()
    })
}

/// Joins walks that continue each other: an end of one lies within [`JOIN_MM`] of the
/// other's centres (running its way) and the other goes on past it (a line whose band was
/// walked from two seeds that met where it splits or thins).
fn join_continuing(
    mut walks: Vec<Walk>,
    mut taken: Vec<HashSet<usize>>,
) -> (Vec<Walk>, Vec<HashSet<usize>>) {
    'again: loop {
        for i in 0..walks.len() {
            for j in 0..walks.len() {
                if i == j || walks[i].closed || walks[j].closed {
                    continue;
                }
                let Some(joined) = continued(&walks[i], &walks[j]) else {
                    continue;
                };
                let tj = std::mem::take(&mut taken[j]);
                taken[i].extend(tj);
                walks[i] = joined;
                walks.remove(j);
                taken.remove(j);
                continue 'again;
            }
        }
        break;
    }
    (walks, taken)
}

/// `a` carried on by `b` past its tail (or head), when that end of `a` lies on `b`.
fn continued(a: &Walk, b: &Walk) -> Option<Walk> {
    let (ac, bc) = (&a.centres, &b.centres);
    if ac.len() < 2 || bc.len() < 2 {
        return None;
    }
    let cos_join = JOIN_DEG.to_radians().cos();
    for tail in [true, false] {
        let (ei, e) = if tail {
            (ac.len() - 1, ac[ac.len() - 1])
        } else {
            (0, ac[0])
        };
        let ta = chord_dir(ac, ei, END_CHORD_MM);
        let Some((l, _)) = bc
            .iter()
            .enumerate()
            .filter(|(_, c)| dist(**c, e) <= JOIN_MM)
            .min_by(|x, y| dist(*x.1, e).total_cmp(&dist(*y.1, e)))
        else {
            continue;
        };
        let tb = chord_dir(bc, l, END_CHORD_MM);
        if abs_cos(ta, tb) < cos_join {
            continue;
        }
        // b oriented the way a runs at its end; the part of b past a's end.
        let same = tb[0] * ta[0] + tb[1] * ta[1] > 0.0;
        let past: Vec<[f64; 2]> = match (tail, same) {
            (true, true) => bc[l + 1..].to_vec(),
            (true, false) => bc[..l].iter().rev().copied().collect(),
            (false, true) => bc[..l].to_vec(),
            (false, false) => bc[l + 1..].iter().rev().copied().collect(),
        };
        let past_len: f64 = past.windows(2).map(|w| dist(w[0], w[1])).sum();
        if past_len < 2.0 {
            continue;
        }
        // ... and goes on a's way (not round a corner).
        let on = if tail {
            past.clone()
        } else {
            past.iter().rev().copied().collect()
        };
        let k = arc(&on)
            .partition_point(|&v| v < END_CHORD_MM)
            .min(on.len() - 1);
        let way = unit(sub(on[k], e));
        if (way[0] * ta[0] + way[1] * ta[1]) * if tail { 1.0 } else { -1.0 } < cos_join {
            continue;
        }
        let on_past = |g: &Gap| {
            past.iter()
                .any(|c| dist(*c, g.from_mm) < 1e-9 || dist(*c, g.to_mm) < 1e-9)
        };
        let mut centres;
        let mut gaps: Vec<Gap>;
        if tail {
            centres = ac.clone();
            centres.extend(past.iter().copied());
            gaps = a.gaps.clone();
            gaps.extend(b.gaps.iter().filter(|g| on_past(g)).cloned());
        } else {
            centres = past.clone();
            centres.extend(ac.iter().copied());
            gaps = b.gaps.iter().filter(|g| on_past(g)).cloned().collect();
            gaps.extend(a.gaps.iter().cloned());
        }
        let mut taken = a.taken.clone();
        taken.extend(b.taken.iter().copied());
        return Some(Walk {
            centres,
            gaps,
            closed: false,
            taken,
        });
    }
    None
}

/// A line ending within [`MEET_MM`] of the centreline of a line across it (more than
/// [`ACROSS_DEG`] to it), ahead of its end (or within [`MEET_INKED_MM`] with ink all the way),
/// ends on that line: the passes of a line stop at the
/// edge of the other's band (where the tracker met the other's ink), so the line is carried on
/// straight through that band to the other's centreline.
fn meet_lines_across(walks: &mut [Walk], cloud: &Cloud) {
    let cos_across = ACROSS_DEG.to_radians().cos();
    let arcs: Vec<Vec<f64>> = walks.iter().map(|w| arc(&w.centres)).collect();
    let mut ext: Vec<(usize, bool, [f64; 2], bool)> = Vec::new();
    for (i, w) in walks.iter().enumerate() {
        let c = &w.centres;
        if w.closed || c.len() < 2 {
            continue;
        }
        for tail in [false, true] {
            let ei = if tail { c.len() - 1 } else { 0 };
            let e = c[ei];
            let t = chord_dir(c, ei, END_CHORD_MM);
            let t = if tail { t } else { [-t[0], -t[1]] };
            let mut best: Option<(f64, [f64; 2], bool)> = None;
            for (j, o) in walks.iter().enumerate() {
                if j == i || o.centres.len() < 2 {
                    continue;
                }
                for (k, q) in o.centres.iter().enumerate() {
                    let v = sub(*q, e);
                    let along = v[0] * t[0] + v[1] * t[1];
                    let off = (v[0] * t[1] - v[1] * t[0]).abs();
                    if along <= 0.0 || along > MEET_INKED_MM || off > STEP_OFF_MM {
                        continue;
                    }
                    let foot = [e[0] + along * t[0], e[1] + along * t[1]];
                    // Beyond the line's band with no ink: a skip, bridged.
                    let skip = along > MEET_MM && cloud.inkless_mm(e, foot) > INKLESS_OK_MM;
                    if abs_cos(chord_dir_on(&o.centres, &arcs[j], k, DIR_HALF_MM), t) >= cos_across
                    {
                        continue;
                    }
                    if best.is_none_or(|b| along < b.0) {
                        best = Some((along, foot, skip));
                    }
                }
            }
            if let Some((_, foot, skip)) = best {
                ext.push((i, tail, foot, skip));
            }
        }
    }
    // Two lines ending at a corner (their ends' rays meeting within MEET_MM ahead of both,
    // across each other): both carried on to where they meet.
    let has = |ext: &[(usize, bool, [f64; 2], bool)], i: usize, tail: bool| {
        ext.iter().any(|e| e.0 == i && e.1 == tail)
    };
    let ends: Vec<(usize, bool, [f64; 2], [f64; 2])> = walks
        .iter()
        .enumerate()
        .filter(|(_, w)| !w.closed && w.centres.len() >= 2)
        .flat_map(|(i, w)| {
            let c = &w.centres;
            let (h, t) = (
                chord_dir(c, 0, END_CHORD_MM),
                chord_dir(c, c.len() - 1, END_CHORD_MM),
            );
            [
                (i, false, c[0], [-h[0], -h[1]]),
                (i, true, c[c.len() - 1], t),
            ]
        })
        .collect();
    let mut corners = Vec::new();
    for (x, &(i, ti, ei, di)) in ends.iter().enumerate() {
        for &(j, tj, ej, dj) in &ends[x + 1..] {
            if i == j
                || has(&ext, i, ti)
                || has(&ext, j, tj)
                || has(&corners, i, ti)
                || has(&corners, j, tj)
                || abs_cos(di, dj) >= cos_across
            {
                continue;
            }
            // ei + a di = ej + b dj
            let den = di[0] * dj[1] - di[1] * dj[0];
            let r = sub(ej, ei);
            let a = (r[0] * dj[1] - r[1] * dj[0]) / den;
            let bb = (r[0] * di[1] - r[1] * di[0]) / den;
            let x = [ei[0] + a * di[0], ei[1] + a * di[1]];
            let reach = |v: f64| (-0.5..=MEET_INKED_MM).contains(&v);
            let skip = |v: f64, e: [f64; 2]| v > MEET_MM && cloud.inkless_mm(e, x) > INKLESS_OK_MM;
            if reach(a) && reach(bb) {
                if a > 0.05 {
                    corners.push((i, ti, x, skip(a, ei)));
                }
                if bb > 0.05 {
                    corners.push((j, tj, x, skip(bb, ej)));
                }
            }
        }
    }
    ext.extend(corners);
    for (i, tail, foot, skip) in ext {
        let w = &mut walks[i];
        let e = if tail {
            w.centres[w.centres.len() - 1]
        } else {
            w.centres[0]
        };
        if skip {
            let (from_mm, to_mm) = if tail { (e, foot) } else { (foot, e) };
            let g = Gap {
                from_mm,
                to_mm,
                length_mm: dist(e, foot),
                bridged: true,
            };
            if tail {
                w.gaps.push(g);
            } else {
                w.gaps.insert(0, g);
            }
        }
        extend_to(w, tail, foot);
    }
}

/// `w` carried straight on from its tail (or head) to `foot`, in steps of [`LINE_SPACING_MM`].
fn extend_to(w: &mut Walk, tail: bool, foot: [f64; 2]) {
    let c = &mut w.centres;
    let Some(&e) = (if tail { c.last() } else { c.first() }) else {
        return;
    };
    let n = (dist(e, foot) / LINE_SPACING_MM).ceil() as usize;
    let pts: Vec<[f64; 2]> = (1..=n)
        .map(|k| {
            let f = k as f64 / n as f64;
            [e[0] + f * (foot[0] - e[0]), e[1] + f * (foot[1] - e[1])]
        })
        .collect();
    if tail {
        c.extend(pts);
    } else {
        let mut v: Vec<[f64; 2]> = pts.into_iter().rev().collect();
        v.extend(c.iter().copied());
        *c = v;
    }
}

/// The drawn lines of `paths` (with the points of the strays, and the marks beyond each
/// path's free ends, `loose[i]` for path `i`), longest first.
pub(crate) fn lines(
    paths: &[DrawnPath],
    strays: &[Vec<[f64; 2]>],
    loose: &[Vec<Loose>],
    max_gap_mm: f64,
) -> Vec<DrawnLine> {
    let (cloud, first) = cloud(paths, strays);
    // Walk from the middle of the longest stretch of each path not yet in a line, longest
    // path first.
    let mut free = vec![true; cloud.dots.len()];
    let mut walks: Vec<Walk> = Vec::new();
    for (pi, p) in paths.iter().enumerate() {
        let (a, b) = (first[pi], first[pi + 1]);
        while let Some((r0, r1, len)) = longest_free_run(&free[a..b], &p.stroke.points_mm) {
            if len < PASS_MM {
                break;
            }
            let mid = a + (r0 + r1) / 2;
            if cloud.dots[mid].dir == [0.0, 0.0] {
                free[mid] = false;
                continue;
            }
            let seed_dir = chord_dir(&p.stroke.points_mm, mid - a, SEED_HALF_MM);
            let w = band::walk(&cloud, cloud.dots[mid].p, seed_dir, max_gap_mm);
            if w.length_mm() < MIN_MARK_MM || !w.taken.contains(&mid) {
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
        match duplicate_of(&w, &kept) {
            Some(d) => taken[d].extend(w.taken.iter().copied()),
            None => {
                taken.push(w.taken.iter().copied().collect());
                kept.push(w);
            }
        }
    }
    let (mut walks, taken) = join_continuing(kept, taken);
    overrun::cut_overruns(&mut walks);
    meet_lines_across(&mut walks, &cloud);
    // The passes of each line: the paths with PASS_MM (or half their length) in its band.
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
                    count[p] > 0 && len >= PASS_MM.min(0.5 * paths[p].stroke.length_mm())
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
        out.push(path_line(paths, p, loose, max_gap_mm));
    }
    for (l, w) in walks.iter().enumerate() {
        if passes[l].is_empty() || (passes[l].len() == 1 && alone(passes[l][0])) {
            continue;
        }
        let mut line = band_line(w, passes[l].clone());
        // A pass of another line running across this one there is that line's.
        let across_here = |p: usize, q: [f64; 2], t: [f64; 2]| {
            lines_of_path[p].iter().any(|&o| {
                o != l && {
                    let c = &walks[o].centres;
                    c.iter()
                        .enumerate()
                        .filter(|(_, x)| dist(**x, q) <= BAND_HALF_MM)
                        .min_by(|x, y| dist(*x.1, q).total_cmp(&dist(*y.1, q)))
                        .is_some_and(|(k, _)| {
                            abs_cos(chord_dir_on(c, &arcs[o], k, DIR_HALF_MM), t)
                                < ACROSS_DEG.to_radians().cos()
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
        );
        out.push(line);
    }
    out.sort_by(|a, b| b.length_mm.total_cmp(&a.length_mm));
    out
}

/// The line that is path `p`, judged by what lies beyond its free ends.
fn path_line(paths: &[DrawnPath], p: usize, loose: &[Vec<Loose>], max_gap_mm: f64) -> DrawnLine {
    let path = &paths[p];
    let pts = &path.stroke.points_mm;
    let len = path.stroke.length_mm();
    let s = arc(pts);
    let head = point_at(pts, &s, END_CHORD_MM.min(len));
    let tail = point_at(pts, &s, (len - END_CHORD_MM).max(0.0));
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
        if !counts(l, &line.passes, None, max_gap_mm) {
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

/// The line of walk `w` (passes `passes`): its centreline smoothed over [`DIR_HALF_MM`].
fn band_line(w: &Walk, passes: Vec<usize>) -> DrawnLine {
    let pts = resample(&smoothed(&w.centres), w.closed, LINE_SPACING_MM);
    let pts = if pts.len() >= 2 {
        pts
    } else {
        w.centres.clone()
    };
    let s = arc(&pts);
    let total = s.last().copied().unwrap_or(0.0);
    let head = point_at(&pts, &s, END_CHORD_MM.min(total));
    let tail = point_at(&pts, &s, (total - END_CHORD_MM).max(0.0));
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

/// What may continue an open band line at its ends: a path (its points not in the line's band,
/// nor where it is a pass of a line running across, `across_here(path, point, direction)`)
/// running its way ahead of an end, within `max(2 x max_gap_mm, 15 mm)` and [`ACROSS_DEG`] of the
/// end's direction (anything running its way nearer, within `--max-gap-mm` and the band, the
/// walk has taken; farther, to a path, it is a missing gap).
fn judge_ends(
    line: &mut DrawnLine,
    taken: &HashSet<usize>,
    cloud: &Cloud,
    paths: &[DrawnPath],
    max_gap_mm: f64,
    across_here: &dyn Fn(usize, [f64; 2], [f64; 2]) -> bool,
) {
    if line.closed {
        return;
    }
    let reach = (2.0 * max_gap_mm).max(15.0);
    let cos_along = BAND_DEG.to_radians().cos();
    let cos_cone = ACROSS_DEG.to_radians().cos();
    let ends = [
        (line.from_mm, line.out_dir[0]),
        (line.to_mm, line.out_dir[1]),
    ];
    let mut ahead: Vec<usize> = Vec::new();
    for (e, t) in ends {
        // In the order of the dots, so the paths found come in a fixed order.
        let mut near: Vec<usize> = cloud.around(e, reach).collect();
        near.sort_unstable();
        for k in near {
            let d = &cloud.dots[k];
            let Source::Path(p) = d.src else {
                continue;
            };
            if taken.contains(&k) || ahead.contains(&p) {
                continue;
            }
            let v = sub(d.p, e);
            let r = v[0].hypot(v[1]);
            if r > reach || r < 1e-9 {
                continue;
            }
            let along = (v[0] * t[0] + v[1] * t[1]) / r;
            if along >= cos_cone && abs_cos(d.dir, t) >= cos_along && !across_here(p, d.p, t) {
                ahead.push(p);
            }
        }
    }
    for p in ahead {
        let pts = &paths[p].stroke.points_mm;
        let m = LeftOut {
            from_mm: pts[0],
            to_mm: pts[pts.len() - 1],
            length_mm: paths[p].stroke.length_mm(),
            kind: LeftOutKind::Continues,
        };
        if !line.continued_by.contains(&m) {
            line.continued_by.push(m);
        }
    }
}

/// Whether a mark beyond a free end of one of a line's `passes` counts against the line
/// (`axis`: the line's direction, `None` for a line of one path: the end's own): a mark that
/// is not a path (or the path's own other end) always; a pass of the line never; another path
/// only when it lies ahead on the line's axis (off it by at most [`ALONGSIDE_MM`] + 10 % of
/// the distance), and not when it runs across the line within `max_gap_mm` of the end (the
/// line ends on another line).
fn counts(l: &Loose, passes: &[usize], axis: Option<[f64; 2]>, max_gap_mm: f64) -> bool {
    if l.path.is_some_and(|p| passes.contains(&p)) {
        return false;
    }
    if l.mark.is_empty() {
        return true;
    }
    let (k, d) = l
        .mark
        .iter()
        .enumerate()
        .map(|(k, q)| (k, dist(*q, l.end_mm)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((0, f64::INFINITY));
    let u = axis.unwrap_or(l.dir);
    let v = sub(l.mark[k], l.end_mm);
    let off_axis = (v[0] * u[1] - v[1] * u[0]).abs();
    if off_axis > ALONGSIDE_MM + 0.1 * d {
        return false;
    }
    if l.path.is_none() || l.mark.len() < 2 {
        return true;
    }
    let dirs = directions(&l.mark, &arc(&l.mark));
    let across = abs_cos(dirs[k], u) < ACROSS_DEG.to_radians().cos();
    !(across && d <= max_gap_mm.max(ALONGSIDE_MM))
}

/// `pts` with each point the mean of those within [`DIR_HALF_MM`] of arc length either side
/// (the window shrunk near the ends, which stay in place).
fn smoothed(pts: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let s = arc(pts);
    let total = s.last().copied().unwrap_or(0.0);
    (0..pts.len())
        .map(|i| {
            let half = DIR_HALF_MM.min(s[i]).min(total - s[i]);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// An open path along `corners`, a point every 0.25 mm, with a zigzag of `zig` mm across.
    fn pass(corners: &[[f64; 2]], zig: f64) -> DrawnPath {
        let mut pts = Vec::new();
        for w in corners.windows(2) {
            let d = sub(w[1], w[0]);
            let len = d[0].hypot(d[1]);
            let n = (len / 0.25).ceil() as usize;
            let (t, nrm) = (unit(d), [-d[1] / len, d[0] / len]);
            for k in 0..n {
                let s = k as f64 * len / n as f64;
                let off = zig * ((s / 1.5).fract() - 0.5).abs();
                pts.push([
                    w[0][0] + s * t[0] + off * nrm[0],
                    w[0][1] + s * t[1] + off * nrm[1],
                ]);
            }
        }
        pts.extend(corners.last());
        crate::trace::paths::open_path(pts)
    }

    fn lines_of(paths: &[DrawnPath]) -> Vec<DrawnLine> {
        let loose = vec![Vec::new(); paths.len()];
        lines(paths, &[], &loose, 10.0)
    }

    #[test]
    fn passes_side_by_side_are_one_line_and_a_line_across_another() {
        // Three zigzag passes of one line, 1 mm apart, of different extents; a line across
        // them; one pass turning the corner into the line across.
        let paths = vec![
            pass(&[[0.0, 0.0], [100.0, 0.0]], 0.6),
            pass(&[[-2.0, 1.0], [60.0, 1.0]], 0.8),
            pass(&[[40.0, -1.0], [101.0, -1.0]], 0.5),
            pass(&[[50.0, -40.0], [50.0, 40.0]], 0.6),
            pass(&[[30.0, 40.5], [49.0, 40.5], [49.0, -30.0]], 0.6),
        ];
        let l = lines_of(&paths);
        let along = l
            .iter()
            .find(|x| x.passes.len() == 3)
            .expect("the line of three");
        assert_eq!(along.passes, vec![0, 1, 2]);
        assert!((along.length_mm - 103.0).abs() < 1.5, "{}", along.length_mm);
        assert!(along.is_whole() && along.gaps.is_empty(), "{along:#?}");
        // Its centreline runs in the middle of the band.
        assert!(along.points_mm.iter().all(|p| p[1].abs() < 1.5));
        assert!(along
            .points_mm
            .iter()
            .filter(|p| p[0] > 5.0 && p[0] < 95.0)
            .all(|p| p[1].abs() < 0.8));
        // The line across: the straight pass and the one round the corner (longest first).
        let across = l
            .iter()
            .find(|x| x.passes.contains(&3))
            .expect("the line across");
        assert_eq!(across.passes, vec![4, 3]);
        assert!(across.is_whole(), "{across:#?}");
        assert!(
            (across.length_mm - 80.5).abs() < 1.5,
            "{}",
            across.length_mm
        );
        // The stretch before the corner is a line of its own, ending on the line across.
        let top = l
            .iter()
            .find(|x| x.passes == [4] && x.points_mm.iter().all(|p| (p[1] - 40.5).abs() < 1.0))
            .expect("the stretch before the corner");
        assert!(top.is_whole());
        let right = top.from_mm[0].max(top.to_mm[0]);
        assert!((right - 49.5).abs() < 1.0, "{top:#?}");
        assert_eq!(l.len(), 3, "{l:#?}");
    }

    #[test]
    fn a_stretch_no_pass_covers_is_a_gap_of_the_line() {
        // Two passes of one line, both broken at the same place: 6 mm (bridged), then 25 mm
        // (missing).
        let short = vec![
            pass(&[[0.0, 0.0], [40.0, 0.0]], 0.5),
            pass(&[[0.0, 1.0], [38.0, 1.0]], 0.5),
            pass(&[[46.0, 0.5], [90.0, 0.5]], 0.5),
            pass(&[[47.0, -0.5], [89.0, -0.5]], 0.5),
        ];
        let l = lines_of(&short);
        assert_eq!(l.len(), 1, "{l:#?}");
        assert_eq!(l[0].passes.len(), 4);
        assert!(l[0].is_whole());
        assert_eq!(l[0].gaps.len(), 1);
        assert!(
            (l[0].gaps[0].length_mm - 6.0).abs() < 0.6,
            "{:?}",
            l[0].gaps
        );
        let far = vec![
            pass(&[[0.0, 0.0], [40.0, 0.0]], 0.5),
            pass(&[[0.0, 1.0], [38.0, 1.0]], 0.5),
            pass(&[[65.0, 0.5], [110.0, 0.5]], 0.5),
            pass(&[[66.0, -0.5], [109.0, -0.5]], 0.5),
        ];
        let l = lines_of(&far);
        // Farther apart than --max-gap-mm: one line with the stretch between missing.
        assert_eq!(l.len(), 1, "{l:#?}");
        assert!(!l[0].is_whole());
        let missing: Vec<&Gap> = l[0].gaps.iter().filter(|g| !g.bridged).collect();
        assert_eq!(missing.len(), 1, "{:?}", l[0].gaps);
        assert!((missing[0].length_mm - 25.0).abs() < 1.5, "{missing:?}");
    }

    #[test]
    fn a_box_drawn_round_in_one_go_is_one_line() {
        let boxed = vec![pass(
            &[
                [0.0, 0.0],
                [40.0, 0.0],
                [40.0, 30.0],
                [0.0, 30.0],
                [0.0, 2.0],
            ],
            0.0,
        )];
        let l = lines_of(&boxed);
        assert_eq!(l.len(), 1, "{l:#?}");
        assert_eq!(l[0].passes, vec![0]);
        assert!((l[0].length_mm - 138.0).abs() < 0.5, "{}", l[0].length_mm);
    }
}
