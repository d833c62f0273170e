//! Drawn lines of a drawing (`rigctl trace --paths DIR`): the paths that run alongside each
//! other are the passes of one drawn line (a plotter drawing a line several times, each pass
//! beside the last and crossing it). A path is first cut where it turns a corner (so a pass
//! that goes round from one line into the next counts for both); its stretches are grouped by
//! running alongside each other (within [`ALONGSIDE_MM`], in directions within
//! [`ALONGSIDE_DEG`], for [`SHARED_MM`] or half the shorter; the longest shared runs first, and
//! two groups only while their mean directions agree within [`ALONGSIDE_DEG`]); a path whose
//! stretches all stay in groups of their own is one line (a box drawn round in one go).
//!
//! A line of several passes is measured along its longest stretch (smoothed over
//! [`DIR_HALF_MM`] either side, carried on straight past its ends): its extent is the union of its passes there, a stretch no pass covers is a gap
//! (bridged when at most `--max-gap-mm`, else missing). A line of one path is that path. A line
//! is **whole** when no gap is missing and nothing may continue it: a mark that may continue
//! one of its passes at one of the line's ends (or a gap too long to bridge to it) counts
//! unless the mark is a pass of the same line, lies off the line's axis, or runs across it
//! (more than [`ACROSS_DEG`] to it) within `--max-gap-mm` of the pass's end: a line ending on
//! another one.

use super::chain::Stroke;
use super::link::{Gap, LeftOut};
use super::paths::DrawnPath;

/// Passes of one line lie within this of each other, mm.
pub const ALONGSIDE_MM: f64 = 3.0;
/// ... running within this angle of each other, degrees.
pub const ALONGSIDE_DEG: f64 = 30.0;
/// ... for this long, or half the shorter stretch, mm.
pub const SHARED_MM: f64 = 10.0;
/// Direction of a path at a point: the chord over this arc length either side of it, mm.
const DIR_HALF_MM: f64 = 4.0;
/// A path turning by more than this between the chords of [`CORNER_CHORD_MM`] before and
/// after a point turns a corner there, degrees.
const CORNER_DEG: f64 = 50.0;
const CORNER_CHORD_MM: f64 = 4.0;
/// A mark meeting a pass's end at more than this to it runs across the line, degrees.
pub const ACROSS_DEG: f64 = 45.0;
/// Direction of a line's end (to carry it on past the end, and to tell whether another line
/// continues it): the chord over this length, mm (a zigzag pass turns often within a few mm).
const END_CHORD_MM: f64 = 12.0;

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

/// One drawn line: the passes along it, its extent, what no pass covers.
#[derive(Debug, Clone)]
pub struct DrawnLine {
    /// The paths running along it (indices into the drawing's paths, longest first).
    pub passes: Vec<usize>,
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

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn unit(d: [f64; 2]) -> [f64; 2] {
    let n = d[0].hypot(d[1]);
    if n > 1e-12 {
        [d[0] / n, d[1] / n]
    } else {
        [1.0, 0.0]
    }
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

/// A stretch of a path between its corners: its points and their directions.
struct Stretch {
    path: usize,
    pts: Vec<[f64; 2]>,
    dirs: Vec<[f64; 2]>,
    len: f64,
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

/// The path's points as stretches between the corners it turns.
fn stretches(pi: usize, stroke: &Stroke) -> Vec<Stretch> {
    let mut pts = stroke.points_mm.clone();
    let closed = stroke.closed;
    if closed {
        if let Some(&p0) = pts.first() {
            pts.push(p0);
        }
    }
    let n = pts.len();
    let make = |v: Vec<[f64; 2]>| {
        let s = arc(&v);
        let dirs = directions(&v, &s);
        Stretch {
            path: pi,
            len: s.last().copied().unwrap_or(0.0),
            pts: v,
            dirs,
        }
    };
    if n < 4 {
        return vec![make(pts)];
    }
    // The turn at each point between the chords before and after it (around a closed path).
    let s = arc(&pts);
    let total = s[n - 1];
    let at = |v: f64| -> [f64; 2] {
        let v = if closed {
            v.rem_euclid(total)
        } else {
            v.clamp(0.0, total)
        };
        let k = s.partition_point(|&x| x < v).clamp(1, n - 1);
        let f = ((v - s[k - 1]) / (s[k] - s[k - 1]).max(1e-12)).clamp(0.0, 1.0);
        [
            pts[k - 1][0] + f * (pts[k][0] - pts[k - 1][0]),
            pts[k - 1][1] + f * (pts[k][1] - pts[k - 1][1]),
        ]
    };
    let turn: Vec<f64> = (0..n)
        .map(|i| {
            if !closed && (s[i] < CORNER_CHORD_MM || s[i] > total - CORNER_CHORD_MM) {
                return 0.0;
            }
            let (u, v) = (
                unit(sub(pts[i], at(s[i] - CORNER_CHORD_MM))),
                unit(sub(at(s[i] + CORNER_CHORD_MM), pts[i])),
            );
            (u[0] * v[0] + u[1] * v[1]).clamp(-1.0, 1.0).acos()
        })
        .collect();
    let limit = CORNER_DEG.to_radians();
    let mut cuts = Vec::new();
    let mut i = 0;
    while i < n {
        if turn[i] > limit {
            let mut j = i;
            while j + 1 < n && turn[j + 1] > limit {
                j += 1;
            }
            cuts.push(
                (i..=j)
                    .max_by(|&a, &b| turn[a].total_cmp(&turn[b]))
                    .unwrap_or(i),
            );
            i = j + 1;
        } else {
            i += 1;
        }
    }
    if cuts.is_empty() {
        return vec![make(stroke.points_mm.clone())];
    }
    let mut out = Vec::new();
    if closed {
        // From corner to corner around the loop (the last point repeats the first).
        let ring = &pts[..n - 1];
        let m = ring.len();
        for (k, &c) in cuts.iter().enumerate() {
            let next = cuts[(k + 1) % cuts.len()];
            let mut v = Vec::new();
            let mut j = c % m;
            loop {
                v.push(ring[j]);
                if j == next % m && v.len() > 1 {
                    break;
                }
                j = (j + 1) % m;
                if v.len() > m {
                    break;
                }
            }
            out.push(make(v));
        }
    } else {
        let mut from = 0;
        for c in cuts.into_iter().chain(std::iter::once(n - 1)) {
            if c > from {
                out.push(make(pts[from..=c].to_vec()));
            }
            from = c;
        }
    }
    out
}

/// Points of all stretches on a grid of [`ALONGSIDE_MM`] cells.
struct Grid {
    cells: std::collections::HashMap<(i64, i64), Vec<(u32, u32)>>,
}

impl Grid {
    fn key(p: [f64; 2]) -> (i64, i64) {
        (
            (p[0] / ALONGSIDE_MM).floor() as i64,
            (p[1] / ALONGSIDE_MM).floor() as i64,
        )
    }

    fn new(st: &[Stretch]) -> Self {
        let mut cells: std::collections::HashMap<(i64, i64), Vec<(u32, u32)>> = Default::default();
        for (k, s) in st.iter().enumerate() {
            for (i, p) in s.pts.iter().enumerate() {
                cells
                    .entry(Self::key(*p))
                    .or_default()
                    .push((k as u32, i as u32));
            }
        }
        Self { cells }
    }

    fn near(&self, p: [f64; 2]) -> impl Iterator<Item = (usize, usize)> + '_ {
        let (kx, ky) = Self::key(p);
        (-1..=1)
            .flat_map(move |dx| (-1..=1).map(move |dy| (kx + dx, ky + dy)))
            .filter_map(|c| self.cells.get(&c))
            .flatten()
            .map(|&(k, i)| (k as usize, i as usize))
    }
}

fn find(parent: &mut [usize], mut a: usize) -> usize {
    while parent[a] != a {
        parent[a] = parent[parent[a]];
        a = parent[a];
    }
    a
}

fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb)] = ra.min(rb);
    }
}

/// The drawn lines of `paths` (with the marks beyond each path's free ends, `loose[i]` for
/// path `i`), longest first.
pub(crate) fn lines(paths: &[DrawnPath], loose: &[Vec<Loose>], max_gap_mm: f64) -> Vec<DrawnLine> {
    let st: Vec<Stretch> = paths
        .iter()
        .enumerate()
        .flat_map(|(i, p)| stretches(i, &p.stroke))
        .filter(|s| s.pts.len() >= 2)
        .collect();
    let grid = Grid::new(&st);
    let cos_along = ALONGSIDE_DEG.to_radians().cos();
    let mut parent: Vec<usize> = (0..st.len()).collect();
    // How long each stretch runs alongside each other one (of another path).
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for (a, sa) in st.iter().enumerate() {
        let mut shared: std::collections::HashMap<usize, usize> = Default::default();
        let mut hit: Vec<usize> = Vec::new();
        for (i, p) in sa.pts.iter().enumerate() {
            hit.clear();
            for (b, j) in grid.near(*p) {
                if st[b].path == sa.path || hit.contains(&b) {
                    continue;
                }
                if dist(*p, st[b].pts[j]) <= ALONGSIDE_MM
                    && abs_cos(sa.dirs[i], st[b].dirs[j]) >= cos_along
                {
                    hit.push(b);
                }
            }
            for &b in &hit {
                *shared.entry(b).or_default() += 1;
            }
        }
        let step = if sa.pts.len() > 1 {
            sa.len / (sa.pts.len() - 1) as f64
        } else {
            0.0
        };
        for (b, count) in shared {
            let along = count as f64 * step;
            if along >= SHARED_MM.min(0.5 * sa.len.min(st[b].len)) {
                pairs.push((along, a, b));
            }
        }
    }
    // The longest shared runs first; two groups join only while their directions (length
    // weighted, as doubled angles) agree within ALONGSIDE_DEG, so a stretch that turns from one
    // line into another cannot join the two.
    pairs.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
    let mut heading: Vec<[f64; 2]> = st
        .iter()
        .map(|x| {
            let d = sub(x.pts[x.pts.len() - 1], x.pts[0]);
            let a = 2.0 * d[1].atan2(d[0]);
            [x.len * a.cos(), x.len * a.sin()]
        })
        .collect();
    for (_, a, b) in pairs {
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra == rb {
            continue;
        }
        let (va, vb) = (heading[ra], heading[rb]);
        let turn = 0.5 * (va[1].atan2(va[0]) - vb[1].atan2(vb[0]));
        if turn.cos().abs() < cos_along {
            continue;
        }
        union(&mut parent, ra, rb);
        let r = find(&mut parent, ra);
        heading[r] = [va[0] + vb[0], va[1] + vb[1]];
    }
    // A path's stretches on either side of a corner: one line when one of the two groups has
    // no other path's stretch (drawn round the corner in one go).
    let groups_of = |parent: &mut Vec<usize>| -> Vec<usize> {
        (0..st.len()).map(|k| find(parent, k)).collect()
    };
    let g = groups_of(&mut parent);
    let alone = |grp: usize, path: usize| {
        st.iter()
            .zip(&g)
            .all(|(s, &gg)| gg != grp || s.path == path)
    };
    let mut joins = Vec::new();
    for k in 1..st.len() {
        if st[k].path == st[k - 1].path && g[k] != g[k - 1] {
            let p = st[k].path;
            if alone(g[k], p) || alone(g[k - 1], p) {
                joins.push((k - 1, k));
            }
        }
    }
    // Around a closed path: its last stretch meets its first.
    for k in 0..st.len() {
        let first = (0..st.len()).find(|&j| st[j].path == st[k].path);
        let last = (0..st.len()).rev().find(|&j| st[j].path == st[k].path);
        if let (Some(f), Some(l)) = (first, last) {
            if k == f && l != f && paths[st[k].path].stroke.closed && g[f] != g[l] {
                let p = st[k].path;
                if alone(g[f], p) || alone(g[l], p) {
                    joins.push((f, l));
                }
            }
        }
    }
    for (a, b) in joins {
        union(&mut parent, a, b);
    }
    // Lines that continue each other end to end (one drawn line where, over a stretch, no
    // pass runs alongside another): joined, the stretch between them a gap of the line.
    let mut out: Vec<DrawnLine>;
    let mut members_of: Vec<Vec<usize>>;
    loop {
        let g = groups_of(&mut parent);
        let mut roots: Vec<usize> = g.clone();
        roots.sort_unstable();
        roots.dedup();
        members_of = roots
            .iter()
            .map(|&r| (0..st.len()).filter(|&k| g[k] == r).collect())
            .collect();
        out = members_of
            .iter()
            .map(|members| line_of(&st, members, paths, max_gap_mm))
            .collect();
        let mut joined = false;
        for i in 0..out.len() {
            for j in i + 1..out.len() {
                if continue_each_other(&out[i], &out[j], max_gap_mm)
                    && find(&mut parent, roots[i]) != find(&mut parent, roots[j])
                {
                    union(&mut parent, roots[i], roots[j]);
                    joined = true;
                }
            }
        }
        if !joined {
            break;
        }
    }
    // Each path's first and last stretch (where its free ends are).
    let end_stretches: Vec<[usize; 2]> = (0..paths.len())
        .map(|p| {
            let first = st.iter().position(|x| x.path == p).unwrap_or(usize::MAX);
            let last = st.iter().rposition(|x| x.path == p).unwrap_or(usize::MAX);
            [first, last]
        })
        .collect();
    // What lies beyond the passes' free ends, judged per line: the ends of the stretches of the
    // line (a pass that turns into another line has its other end there).
    for (line, members) in out.iter_mut().zip(&members_of) {
        let passes = line.passes.clone();
        let axis = (passes.len() > 1 && !line.closed).then(|| unit(sub(line.to_mm, line.from_mm)));
        // A pass's end inside a line of several passes (farther than --max-gap-mm from the
        // line's ends) is continued by the other passes: what lies beyond it is the line's own
        // coverage (its gaps judged above) or a line across it.
        let at_line_end = |end: [f64; 2]| {
            passes.len() == 1
                || dist(end, line.from_mm).min(dist(end, line.to_mm))
                    <= max_gap_mm.max(ALONGSIDE_MM)
        };
        let own_end = |p: usize, end: [f64; 2]| {
            let pts = &paths[p].stroke.points_mm;
            let (Some(a), Some(b)) = (pts.first(), pts.last()) else {
                return false;
            };
            let k = end_stretches[p][usize::from(dist(end, *b) < dist(end, *a))];
            members.contains(&k)
        };
        let mut counted: Vec<LeftOut> = Vec::new();
        let mut missing: Vec<Gap> = Vec::new();
        for &p in &passes {
            for l in &loose[p] {
                if !own_end(p, l.end_mm)
                    || !at_line_end(l.end_mm)
                    || !counts(l, &passes, axis, max_gap_mm)
                {
                    continue;
                }
                match l.what {
                    LooseWhat::Gap(k) => {
                        if let Some(gap) = paths[p].gaps.get(k) {
                            missing.push(gap.clone());
                        }
                    }
                    LooseWhat::Mark(k) => {
                        if let Some(m) = paths[p].continued_by.get(k) {
                            if !counted.contains(m) {
                                counted.push(m.clone());
                            }
                        }
                    }
                }
            }
        }
        line.gaps.extend(missing);
        line.continued_by = counted;
    }
    out.sort_by(|a, b| b.length_mm.total_cmp(&a.length_mm));
    out
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
    if l.path.is_none() || l.mark.len() < 2 {
        return true;
    }
    let s = arc(&l.mark);
    let dirs = directions(&l.mark, &s);
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
    let across = abs_cos(dirs[k], u) < ACROSS_DEG.to_radians().cos();
    !(across && d <= max_gap_mm.max(ALONGSIDE_MM))
}

/// The line of the stretches `members`.
fn line_of(st: &[Stretch], members: &[usize], paths: &[DrawnPath], max_gap_mm: f64) -> DrawnLine {
    let mut passes: Vec<usize> = members.iter().map(|&k| st[k].path).collect();
    passes.sort_unstable();
    passes.dedup();
    passes.sort_by(|&a, &b| {
        paths[b]
            .stroke
            .length_mm()
            .total_cmp(&paths[a].stroke.length_mm())
    });
    if passes.len() == 1 {
        // One path: the line is that path.
        let p = &paths[passes[0]];
        let pts = &p.stroke.points_mm;
        let len = p.stroke.length_mm();
        let s = arc(pts);
        let head = point_at(pts, &s, END_CHORD_MM.min(len));
        let tail = point_at(pts, &s, (len - END_CHORD_MM).max(0.0));
        return DrawnLine {
            out_dir: [unit(sub(pts[0], head)), unit(sub(pts[pts.len() - 1], tail))],
            passes,
            closed: p.stroke.closed,
            from_mm: pts[0],
            to_mm: pts[pts.len() - 1],
            length_mm: len,
            covered_mm: len,
            gaps: p.gaps.iter().filter(|g| g.bridged).cloned().collect(),
            continued_by: Vec::new(),
        };
    }
    // Along the longest stretch, carried on straight past its ends.
    let r = *members
        .iter()
        .max_by(|&&a, &&b| st[a].len.total_cmp(&st[b].len))
        .unwrap_or(&members[0]);
    // Smoothed over DIR_HALF_MM either side (a zigzag pass is longer than its line).
    let rp = &smoothed(&st[r].pts);
    let rs = arc(rp);
    let total = rs[rs.len() - 1];
    let head_t = unit(sub(point_at(rp, &rs, END_CHORD_MM.min(total)), rp[0]));
    let tail_t = unit(sub(
        rp[rp.len() - 1],
        point_at(rp, &rs, (total - END_CHORD_MM).max(0.0)),
    ));
    let project = |q: [f64; 2]| -> f64 {
        let (j, _) = rp
            .iter()
            .enumerate()
            .map(|(j, p)| (j, dist(*p, q)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((0, 0.0));
        let d0 = sub(q, rp[0]);
        let d1 = sub(q, rp[rp.len() - 1]);
        let along0 = d0[0] * head_t[0] + d0[1] * head_t[1];
        let along1 = d1[0] * tail_t[0] + d1[1] * tail_t[1];
        if j == 0 && along0 < 0.0 {
            along0
        } else if j == rp.len() - 1 && along1 > 0.0 {
            total + along1
        } else {
            rs[j]
        }
    };
    let place = |s: f64| -> [f64; 2] {
        if s < 0.0 {
            [rp[0][0] + s * head_t[0], rp[0][1] + s * head_t[1]]
        } else if s > total {
            let e = rp[rp.len() - 1];
            [
                e[0] + (s - total) * tail_t[0],
                e[1] + (s - total) * tail_t[1],
            ]
        } else {
            point_at(rp, &rs, s)
        }
    };
    // Each stretch covers the span of its projections.
    let mut spans: Vec<[f64; 2]> = members
        .iter()
        .map(|&k| {
            let step = (st[k].pts.len() / 100).max(1);
            let v: Vec<f64> = st[k]
                .pts
                .iter()
                .step_by(step)
                .chain(st[k].pts.last())
                .map(|q| project(*q))
                .collect();
            [
                v.iter().copied().fold(f64::INFINITY, f64::min),
                v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            ]
        })
        .collect();
    spans.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let mut gaps = Vec::new();
    let (lo, mut reach) = (spans[0][0], spans[0][1]);
    let mut covered = 0.0;
    let mut start = lo;
    for sp in &spans[1..] {
        if sp[0] > reach {
            covered += reach - start;
            let (a, b) = (place(reach), place(sp[0]));
            gaps.push(Gap {
                from_mm: a,
                to_mm: b,
                length_mm: sp[0] - reach,
                bridged: sp[0] - reach <= max_gap_mm,
            });
            start = sp[0];
        }
        reach = reach.max(sp[1]);
    }
    covered += reach - start;
    DrawnLine {
        out_dir: [[-head_t[0], -head_t[1]], tail_t],
        passes,
        closed: false,
        from_mm: place(lo),
        to_mm: place(reach),
        length_mm: reach - lo,
        covered_mm: covered,
        gaps,
        continued_by: Vec::new(),
    }
}

/// A line turning by at most this where it continues another, degrees.
const CONTINUE_DEG: f64 = 20.0;

/// Whether open lines `a` and `b` continue each other: an end of one lies ahead of an end of
/// the other within `max_gap_mm`, off its direction by at most [`ALONGSIDE_MM`] + 10 % of the
/// gap, and the two ends face each other within [`CONTINUE_DEG`].
fn continue_each_other(a: &DrawnLine, b: &DrawnLine, max_gap_mm: f64) -> bool {
    if a.closed || b.closed {
        return false;
    }
    let cos_turn = CONTINUE_DEG.to_radians().cos();
    for (pa, ta) in [(a.from_mm, a.out_dir[0]), (a.to_mm, a.out_dir[1])] {
        for (pb, tb) in [(b.from_mm, b.out_dir[0]), (b.to_mm, b.out_dir[1])] {
            if -(ta[0] * tb[0] + ta[1] * tb[1]) < cos_turn {
                continue;
            }
            let d = sub(pb, pa);
            let gap = d[0].hypot(d[1]);
            let along = d[0] * ta[0] + d[1] * ta[1];
            let across = (d[0] * ta[1] - d[1] * ta[0]).abs();
            if gap <= max_gap_mm && along >= -ALONGSIDE_MM && across <= ALONGSIDE_MM + 0.1 * gap {
                return true;
            }
        }
    }
    false
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
        lines(paths, &loose, 10.0)
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
        assert_eq!(l.len(), 2, "{l:#?}");
        let (along, across) = if l[0].passes.len() == 3 {
            (&l[0], &l[1])
        } else {
            (&l[1], &l[0])
        };
        assert_eq!(along.passes.len(), 3, "{along:#?}");
        assert!((along.length_mm - 103.0).abs() < 1.5, "{}", along.length_mm);
        assert!(along.is_whole() && along.gaps.is_empty());
        // Longest first: the pass round the corner (89.5 mm), then the straight one.
        assert_eq!(across.passes, vec![4, 3]);
        assert!(across.is_whole());
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
        // Farther apart than --max-gap-mm: two lines (each whole on its own: nothing marks
        // them as continuing each other here, that is the paths' own judgement).
        assert_eq!(l.len(), 2, "{l:#?}");
    }
}
