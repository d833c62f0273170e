//! The drawn path from the graphite itself: tracked pieces are linked end to end by continuity
//! (position, direction and curvature carried across each gap), one curve per drawn line, open
//! or closed, any shape; the printed reference is never a mask, only a hint between chains of
//! similar length.
//!
//! Open pieces are first cut where they turn sharply (a corner, or the tracker turning onto a
//! stroke that crosses the path). Every end of an open piece gets its outward tangent and
//! curvature from its last 8 mm (on a plotter's passes, [`Strokes::Passes`], from the 6.5 mm
//! before its last 1.5 mm); on the rig's one path, where a crest within them bends it harder
//! than the curvature is clamped to, its tangent from its last 3 mm. A link
//! between two ends is admissible when each end's arc, extrapolated over the gap, lands on the
//! other end and the directions agree, turned by the mean of the two ends' curvatures over the
//! gap (tolerances grow with the gap); ends that nearly touch
//! (< 1 mm) need only not double back (a corner). A link those arcs miss (a short end reads no
//! curvature, a long one its span's mean, clamped) is admissible when the path bends one way
//! through the gap and each end bends along itself with it ([`bends_through`]: a tight crest,
//! not a corner).
//! Links are taken cheapest first, each end once, a cycle only as
//! the closing link of a chain, so a second pencil stroke crossing the path is passed over: its
//! ends meet the path's ends at the wrong angle, and where the crossing cut the path in two the
//! two halves continue each other across it. On the rig's one path a second round reads the
//! free ends of the chains again through the chains themselves ([`relink`]: a short stroke
//! between two skips gets the bend of the stroke it is linked to) and links what it then
//! admits. Gaps up to `max_gap_mm` are bridged: a cubic
//! Hermite curve through both ends' positions and tangents as a first guess, then refitted
//! from the written points on both sides ([`bridge_fit`]).
//!
//! The longest chain is the drawn path. What is left out is listed: specks (shorter than
//! [`MIN_MARK_MM`]), marks, and marks that could be part of the path: a link from one of the
//! path's free ends that would be admissible but longer than `max_gap_mm` (a gap not bridged,
//! including an open path whose ends continue into each other), or a mark of at least
//! [`MIN_MARK_MM`] ahead of a free end within reach, or a separate line nearly as long as the
//! path. Those make the trace incomplete.

use super::chain::{polyline_length, PieceMm, Stroke};
use super::plane::{dist, norm, sub, Grid};
use super::{bridge_fit, smooth};
use crate::sheet::ReferencePath;

/// Marks shorter than this are specks (dust, grain), mm.
pub const MIN_MARK_MM: f64 = 5.0;
/// A left-out line at least this share of the path's length is a drawn line of its own.
const SEPARATE_SHARE: f64 = 0.3;
/// Length of an end used for its tangent and curvature, mm.
const END_SPAN_MM: f64 = 8.0;
/// The part of an end left out of its reading and bridged over where it may be pulled aside:
/// next to a crossing the path is cut at, and on a plotter's passes ([`Strokes::Passes`]), mm.
const END_SKIP_MM: f64 = 1.5;
/// An end's curvature is read only from a span of at least this (shorter ones cannot tell it
/// from the centreline's noise), mm, and is at most this, 1/mm.
const K_SPAN_MM: f64 = 5.0;
const MAX_K: f64 = 0.1;
/// Length of an end a crest's tangent is read over, mm: short against a crest of 3 mm radius,
/// long enough that the centres' scatter turns it by a few degrees at most.
const TANGENT_SPAN_MM: f64 = 3.0;
/// A short end's last chord, mm, and how far it may turn off its span's circle, deg, for the
/// span's own tangent to hold (a hook turns it).
const HOOK_CHORD_MM: f64 = 1.0;
const HOOK_DEG: f64 = 8.0;
/// Where the ends' arcs miss each other, the mean curvature a link may bend by from the middle
/// of one end's span to the other's (a pencil crest of 3 mm radius), 1/mm, and the least share
/// of the turn each end takes from the chord between them ([`bends_through`]).
const MAX_JOINT_K: f64 = 0.35;
const JOINT_SHARE: f64 = 0.25;
/// Scatter of a centre about the stroke's true centreline, mm, read into a short span's sag.
const SAG_NOISE_MM: f64 = 0.03;
/// A piece turning by more than this between its chords of [`KINK_CHORD_MM`] is cut there.
const KINK_DEG: f64 = 25.0;
const KINK_CHORD_MM: f64 = 1.0;
/// A mark ending this close to the path touches it; the path is bridged over this radius
/// around the place, mm.
const CROSS_TOUCH_MM: f64 = 1.5;
const CROSS_CUT_MM: f64 = 3.0;
const CROSS_MAX_MM: f64 = 15.0;
/// Spacing of bridge points, mm.
const BRIDGE_STEP_MM: f64 = 0.2;

/// A gap between two linked pieces of the drawn path.
#[derive(Debug, Clone, PartialEq)]
pub struct Gap {
    /// Where the written trace stops and starts again, sheet mm.
    pub from_mm: [f64; 2],
    pub to_mm: [f64; 2],
    /// Length of the bridge curve across it, mm.
    pub length_mm: f64,
    /// Bridged (at most `max_gap_mm`); otherwise missing.
    pub bridged: bool,
}

/// Why a mark was not written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LeftOutKind {
    /// Shorter than [`MIN_MARK_MM`]: dust, a fibre, a flick.
    Speck,
    /// A mark apart from the path (a stroke across it, a stray line).
    Mark,
    /// Long enough and ahead of a free end of the path, within reach: it may continue the path.
    Continues,
    /// A drawn line of its own, comparable in length to the path.
    Separate,
}

/// A mark (chain of pieces) not in the written path.
#[derive(Debug, Clone, PartialEq)]
pub struct LeftOut {
    pub from_mm: [f64; 2],
    pub to_mm: [f64; 2],
    pub length_mm: f64,
    pub kind: LeftOutKind,
}

impl LeftOut {
    /// Whether leaving it out means the written trace may not be the whole drawn path.
    pub fn could_be_path(&self) -> bool {
        matches!(self.kind, LeftOutKind::Continues | LeftOutKind::Separate)
    }
}

/// The linked path and what was left out.
#[derive(Debug, Clone)]
pub struct Linking {
    /// The drawn path (bridges included), ordered along it.
    pub path: Stroke,
    /// The other chains, longest first (not resampled).
    pub others: Vec<Stroke>,
    /// Gaps of the path: bridged ones in order along it, then the missing ones.
    pub gaps: Vec<Gap>,
    pub left_out: Vec<LeftOut>,
    /// Number of tracked pieces linked into the path.
    pub pieces: usize,
    /// The printed path used as a hint, and the mean distance of the path from it, mm.
    pub hint: Option<(ReferencePath, f64)>,
}

impl Linking {
    /// The gaps too long to bridge.
    pub fn missing(&self) -> impl Iterator<Item = &Gap> {
        self.gaps.iter().filter(|g| !g.bridged)
    }

    /// Whether the written path is the whole drawn path: nothing missing, nothing left out that
    /// could be part of it.
    pub fn is_whole(&self) -> bool {
        self.missing().next().is_none() && !self.left_out.iter().any(LeftOut::could_be_path)
    }
}

/// The end of an open piece: position, outward unit tangent, signed curvature (1/mm, positive
/// turning left when moving outward).
#[derive(Debug, Clone, Copy)]
struct End {
    p: [f64; 2],
    t: [f64; 2],
    k: f64,
    /// The anchor of a bridge, `skip` mm back from the end (the last millimetre may be pulled
    /// aside), and the tangent there.
    anchor: [f64; 2],
    ta: [f64; 2],
    skip: f64,
    /// Uncertainty of the tangent, rad (short pieces give poor directions).
    sigma: f64,
    /// The span the tangent was read over, mm (the curvature too when [`End::k_read`]).
    span: f64,
    /// The curvature through the span's ends and middle however short the span, 1/mm.
    k_raw: f64,
    /// The curvature over the span's last [`K_SPAN_MM`] (the whole span when shorter),
    /// unclamped, 1/mm: where the path bends harder towards the end than over the span.
    k_near: f64,
    /// A short span's own tangent at the end, from the circle through its three points, where
    /// its last millimetre follows that circle (no hook): see [`own_tangent`].
    t_own: Option<[f64; 2]>,
}

impl End {
    fn k_read(&self) -> bool {
        self.span >= K_SPAN_MM
    }

    /// How far back from the end the middle of its span lies, mm.
    fn mid_span(&self) -> f64 {
        0.5 * (self.skip + self.span)
    }
}

/// A candidate link between end `a` and end `b` (end index = 2 * piece + side; side 0 head,
/// 1 tail).
#[derive(Debug, Clone, Copy)]
struct Cand {
    a: usize,
    b: usize,
    gap: f64,
    cost: f64,
}

fn rot(t: [f64; 2], a: f64) -> [f64; 2] {
    let (s, c) = a.sin_cos();
    [c * t[0] - s * t[1], s * t[0] + c * t[1]]
}

/// The point at arc length `l` along `p`'s osculating circle (tangent `t`, curvature `k`).
fn arc_point(e: &End, l: f64) -> [f64; 2] {
    let phi = e.k * l;
    let (along, across) = if phi.abs() < 1e-6 {
        (l, 0.5 * e.k * l * l)
    } else {
        (phi.sin() / e.k, (1.0 - phi.cos()) / e.k)
    };
    let n = [-e.t[1], e.t[0]];
    [
        e.p[0] + along * e.t[0] + across * n[0],
        e.p[1] + along * e.t[1] + across * n[1],
    ]
}

/// The point `l` mm back from the end of `pts` (walking from the last point), or the first.
fn point_back(pts: &[[f64; 2]], l: f64) -> [f64; 2] {
    let mut acc = 0.0;
    for w in pts.windows(2).rev() {
        let d = dist(w[0], w[1]);
        if acc + d >= l && d > 0.0 {
            let f = (l - acc) / d;
            return [
                w[1][0] + f * (w[0][0] - w[1][0]),
                w[1][1] + f * (w[0][1] - w[1][1]),
            ];
        }
        acc += d;
    }
    pts[0]
}

/// The curvature the centres' scatter ([`SAG_NOISE_MM`], twice over) reads through three
/// points spanning `span` mm, 1/mm: a span's sag is `k span^2 / 8`.
fn k_noise(span: f64) -> f64 {
    2.0 * 8.0 * SAG_NOISE_MM / (span * span)
}

/// The circle through the points `from`, halfway and `to` mm back from the end of `pts`: the
/// chord between the first and last (unit direction, length) and the signed curvature.
fn three_point(pts: &[[f64; 2]], from: f64, to: f64) -> Option<([f64; 2], f64, f64)> {
    let q1 = point_back(pts, from);
    let q2 = point_back(pts, 0.5 * (from + to));
    let q3 = point_back(pts, to);
    let d = sub(q1, q3);
    let n = norm(d);
    if n <= 1e-9 {
        return None;
    }
    let (a, b) = (sub(q2, q3), sub(q1, q2));
    let cross = a[0] * b[1] - a[1] * b[0];
    let k = 2.0 * cross / (norm(a) * norm(b) * n).max(1e-12);
    Some(([d[0] / n, d[1] / n], n, k))
}

/// The end at the last point of `pts`: tangent and curvature from the circle through the points
/// `skip` mm, halfway and [`END_SPAN_MM`] back, carried to the end point; the bridge anchor
/// `skip` mm back (0: the last point). On the rig's one path, where that curvature is over
/// [`MAX_K`] (a crest within the span), the tangent is read again from the circle through the
/// last [`TANGENT_SPAN_MM`] before the anchor, unclamped: the span's chord, turned by the
/// clamped curvature, would point the end tens of degrees off across the crest. (A plotter's
/// passes, [`Strokes::Passes`], saw at their ends: the last millimetres would turn it.)
fn end_with(pts: &[[f64; 2]], skip: f64, strokes: Strokes) -> Option<End> {
    let len = polyline_length(pts, false);
    if len <= 0.0 {
        return None;
    }
    let span = END_SPAN_MM.min(0.7 * len);
    let skip = skip.min(0.2 * span);
    let p0 = pts[pts.len() - 1];
    let q1 = point_back(pts, skip);
    let (chord, n, k_raw) = three_point(pts, skip, span)?;
    let k_near = three_point(pts, skip, skip + K_SPAN_MM.min(span - skip)).map_or(k_raw, |v| v.2);
    // Curvature only from a span long enough to tell it from the centreline's noise.
    let k = if span >= K_SPAN_MM {
        k_raw.clamp(-MAX_K, MAX_K)
    } else {
        0.0
    };
    // The chord's direction is the tangent at its middle; turn it on to the anchor and the end.
    let near = (strokes == Strokes::OnePath && span >= K_SPAN_MM && k_raw.abs() > MAX_K)
        .then(|| three_point(pts, skip, skip + TANGENT_SPAN_MM))
        .flatten();
    let ta = match near {
        Some((c, m, k_near)) => rot(c, k_near * 0.5 * m),
        None => rot(chord, k * 0.5 * n),
    };
    let t = rot(ta, k * dist(q1, p0));
    let t_own = (strokes == Strokes::OnePath && span < K_SPAN_MM)
        .then(|| own_tangent(pts, skip, span, ta, k_raw))
        .flatten();
    Some(End {
        p: p0,
        t,
        k,
        anchor: q1,
        ta,
        skip,
        sigma: 0.15 / span.max(0.5),
        span,
        k_raw,
        k_near,
        t_own,
    })
}

/// The tangent at the end of a span too short to read a curvature to carry across a gap,
/// from its own circle (`ta`, the chord's direction at the span's middle, turned by `k_raw`),
/// where the last [`HOOK_CHORD_MM`] follow that circle within [`HOOK_DEG`]; `None` otherwise
/// (a hook: the chord then stands for the tangent). Whether it is taken is
/// [`with_curvature`]'s choice.
fn own_tangent(
    pts: &[[f64; 2]],
    skip: f64,
    span: f64,
    ta: [f64; 2],
    k_raw: f64,
) -> Option<[f64; 2]> {
    if span < 2.0 * HOOK_CHORD_MM {
        return None;
    }
    let mid = 0.5 * (skip + span);
    let last = sub(point_back(pts, skip), point_back(pts, skip + HOOK_CHORD_MM));
    let n = norm(last);
    if n <= 1e-9 {
        return None;
    }
    let along = rot(ta, k_raw * (mid - skip - 0.5 * HOOK_CHORD_MM));
    let c = (last[0] * along[0] + last[1] * along[1]) / n;
    (c >= HOOK_DEG.to_radians().cos()).then(|| rot(ta, k_raw * (mid - skip)))
}

/// Whether a short end's own three points bend beyond twice the scatter's curvature, with no
/// hook at its end: it shows its own bend.
fn reads_own_bend(e: &End) -> bool {
    e.t_own.is_some() && e.k_raw.abs() > 2.0 * k_noise(e.span)
}

/// `e` bent by the curvature `k` it could not read itself (a short piece), `k` read by the other
/// end (so within [`MAX_K`]): the chord's direction is the tangent at its middle, turned on to
/// the end. Where its own points tell a bend ([`reads_own_bend`]), or tell that it does not
/// bend as much as `k` (they differ from `k` by more than twice the scatter's curvature: a
/// nearly straight piece past a crest the other end reads), it takes its own tangent
/// ([`own_tangent`]) instead.
fn with_curvature(e: &End, k: f64) -> End {
    let own = e
        .t_own
        .filter(|_| reads_own_bend(e) || (e.k_raw - k).abs() > 2.0 * k_noise(e.span));
    End {
        t: own.unwrap_or_else(|| rot(e.ta, k * e.mid_span())),
        k,
        ..*e
    }
}

/// Piece ends, read as `strokes` are (on a plotter's passes from [`END_SKIP_MM`] back); `None`
/// for closed pieces.
fn ends(piece: &PieceMm, strokes: Strokes) -> Option<[End; 2]> {
    if piece.closed || piece.pts.len() < 2 {
        return None;
    }
    let skip = match strokes {
        Strokes::OnePath => 0.0,
        Strokes::Passes => END_SKIP_MM,
    };
    let tail = end_with(&piece.pts, skip, strokes)?;
    let rev: Vec<[f64; 2]> = piece.pts.iter().rev().copied().collect();
    let head = end_with(&rev, skip, strokes)?;
    Some([head, tail])
}

/// Open pieces cut where they turn by more than [`KINK_DEG`] between the chords of the
/// [`KINK_CHORD_MM`] before and after a point (a corner, or the tracker turning onto a stroke
/// that crosses the path): the linker decides which way the path goes on.
fn split_kinks(pieces: &[PieceMm]) -> Vec<PieceMm> {
    let mut out = Vec::with_capacity(pieces.len());
    for p in pieces {
        let n = p.pts.len();
        if p.closed || n < 5 {
            out.push(p.clone());
            continue;
        }
        // Chord ends by arc length: for each point the indices ~KINK_CHORD_MM back and ahead.
        let mut s = vec![0.0; n];
        for i in 1..n {
            s[i] = s[i - 1] + dist(p.pts[i - 1], p.pts[i]);
        }
        let turn_at = |i: usize| -> f64 {
            let back = s[..i].partition_point(|&v| v < s[i] - KINK_CHORD_MM);
            let ahead = i + s[i..].partition_point(|&v| v < s[i] + KINK_CHORD_MM);
            if back >= i || ahead >= n || s[i] - s[back] < 0.8 * KINK_CHORD_MM {
                return 0.0;
            }
            let (u, v) = (sub(p.pts[i], p.pts[back]), sub(p.pts[ahead], p.pts[i]));
            let (nu, nv) = (norm(u), norm(v));
            if nu < 1e-9 || nv < 1e-9 {
                return 0.0;
            }
            ((u[0] * v[0] + u[1] * v[1]) / (nu * nv))
                .clamp(-1.0, 1.0)
                .acos()
        };
        let turns: Vec<f64> = (0..n).map(turn_at).collect();
        let limit = KINK_DEG.to_radians();
        let mut cuts = Vec::new();
        let mut i = 0;
        while i < n {
            if turns[i] > limit {
                let mut j = i;
                while j + 1 < n && turns[j + 1] > limit {
                    j += 1;
                }
                let best = (i..=j)
                    .max_by(|&a, &b| turns[a].total_cmp(&turns[b]))
                    .unwrap_or(i);
                cuts.push(best);
                i = j + 1;
            } else {
                i += 1;
            }
        }
        let mut from = 0;
        for c in cuts.into_iter().chain(std::iter::once(n - 1)) {
            if c > from {
                out.push(PieceMm {
                    pts: p.pts[from..=c].to_vec(),
                    closed: false,
                });
            }
            from = c;
        }
    }
    out
}

/// Continuity of `a` into `b` across their gap: `None` when not admissible, else the cost.
/// `reach` bounds the gap.
fn continuity(a: &End, b: &End, reach: f64) -> Option<f64> {
    let g = dist(a.p, b.p);
    if g > reach {
        return None;
    }
    // An end too short to read its curvature bends as the other end does: across a short gap
    // the curve turns the same way on both sides (a wiggle's crest with a skip on it).
    let (bent_a, bent_b);
    let (a, b) = match (a.k_read(), b.k_read()) {
        (false, true) => {
            bent_a = with_curvature(a, -b.k);
            (&bent_a, b)
        }
        (true, false) => {
            bent_b = with_curvature(b, -a.k);
            (a, &bent_b)
        }
        // Both short: they bend alike by what those that read their own bend read (a crest
        // between skips), else not at all.
        (false, false) => {
            let own: Vec<f64> = [
                reads_own_bend(a).then_some(a.k_raw),
                reads_own_bend(b).then_some(-b.k_raw),
            ]
            .into_iter()
            .flatten()
            .collect();
            let k = if own.is_empty() {
                0.0
            } else {
                (own.iter().sum::<f64>() / own.len() as f64).clamp(-MAX_K, MAX_K)
            };
            bent_a = with_curvature(a, k);
            bent_b = with_curvature(b, -k);
            (&bent_a, &bent_b)
        }
        _ => (a, b),
    };
    // The turn across the gap is the mean of the two ends' curvatures times the gap (the
    // curvature may change along it, as on the flank of a crest: one end nearly straight, the
    // other bending hard); `b`'s curvature is read outwards, so it counts with its sign turned.
    // Ends that nearly touch continue each other unless they double back (a corner the
    // tracker did not turn); straighter is cheaper.
    let turn_ab = {
        let expect = rot(a.t, 0.5 * (a.k - b.k) * g);
        let into_b = [-b.t[0], -b.t[1]];
        (expect[0] * into_b[0] + expect[1] * into_b[1])
            .clamp(-1.0, 1.0)
            .acos()
    };
    if g < 1.0 {
        return (turn_ab <= 120f64.to_radians()).then_some(g + 10.0 * turn_ab);
    }
    // Each end's arc, carried over the gap, lands on the other end.
    let lat = 0.5 * (dist(arc_point(a, g), b.p) + dist(arc_point(b, g), a.p));
    let sigma = a.sigma + b.sigma;
    let lat_tol = 0.3 + 0.12 * g + 2.0 * sigma * g;
    let ang_tol = (25.0 + 15.0 * (g / 20.0).min(1.0)).to_radians() + 2.0 * sigma;
    // The chord must leave each end forwards.
    let chord = [(b.p[0] - a.p[0]) / g, (b.p[1] - a.p[1]) / g];
    let fwd_a = chord[0] * a.t[0] + chord[1] * a.t[1];
    let fwd_b = -(chord[0] * b.t[0] + chord[1] * b.t[1]);
    if fwd_a < 0.5 || fwd_b < 0.5 {
        return None;
    }
    if lat > lat_tol || turn_ab > ang_tol {
        // The arcs miss where the path bends harder in the gap than its ends read (a crest: a
        // short end reads no curvature, a long one its span's mean, clamped); the ends continue
        // each other when the path can bend one way through the gap.
        return bends_through(a, b, chord, g)
            .map(|odd| g + 2.0 * lat + 10.0 * turn_ab + 10.0 * odd);
    }
    Some(g + 2.0 * lat + 10.0 * turn_ab)
}

/// Two ends whose arcs miss each other across a gap of `g` mm (unit `chord` from `a` to `b`)
/// continue each other when the path can bend one way through it, as at a crest: the chord
/// splits the turn from `a`'s direction into `b`'s, each side taking at least [`JOINT_SHARE`] of
/// it in the same sense, the turn is at most [`MAX_JOINT_K`] times the length from the middle of
/// one end's span to the other's, and each end bends with it. A stroke crossing the path meets
/// it with the turn on one side only. `None` when not; else how far the chord's split is from
/// even, rad.
fn bends_through(a: &End, b: &End, chord: [f64; 2], g: f64) -> Option<f64> {
    let into_b = [-b.t[0], -b.t[1]];
    let angle =
        |u: [f64; 2], v: [f64; 2]| (u[0] * v[1] - u[1] * v[0]).atan2(u[0] * v[0] + u[1] * v[1]);
    let (alpha, beta) = (angle(a.t, chord), angle(chord, into_b));
    let turn = alpha + beta;
    let len = a.mid_span() + g + b.mid_span();
    // Each side's share is read through its own end's tangent.
    let share = JOINT_SHARE * turn.abs();
    let ok = turn.abs() <= MAX_JOINT_K * len
        && alpha * turn > 0.0
        && beta * turn > 0.0
        && alpha.abs() >= share - a.sigma
        && beta.abs() >= share - b.sigma;
    // Each end bends with the crest: its own curvature (a short end's read from its three
    // points, a long end's within the clamp) takes at least half the mean, on a span long
    // enough to tell that from straight. A corner between straight strokes,
    // or a plotter's sawtooth, turns across the gap but not along its ends.
    let bends_too = |e: &End, k_out: f64| {
        // (curvature, span it was read over, what it must reach)
        let reads = if e.k_read() {
            let need = k_out.abs().min(MAX_K);
            [
                (e.k, e.span, need),
                (e.k_near.clamp(-MAX_K, MAX_K), K_SPAN_MM, need),
            ]
        } else {
            [(e.k_raw, e.span, k_out.abs()); 2]
        };
        // The span must be long enough to tell a bend of half the mean from a straight one.
        reads.iter().any(|&(own, span, need)| {
            let noise = k_noise(span);
            noise <= 0.5 * need && own * k_out.signum() >= 0.5 * need - noise
        })
    };
    let k_mean = turn / len;
    (ok && bends_too(a, k_mean) && bends_too(b, -k_mean)).then_some((alpha - beta).abs())
}

/// Cubic Hermite bridge from end `a` to end `b` (inner points only), and its length.
fn bridge(a: &End, b: &End) -> (Vec<[f64; 2]>, f64) {
    hermite(a.p, a.t, b.p, [-b.t[0], -b.t[1]])
}

/// Cubic Hermite curve from `pa` (tangent `ta`) to `pb` (arriving along `tb`): its inner points
/// every [`BRIDGE_STEP_MM`] and its length.
fn hermite(pa: [f64; 2], ta: [f64; 2], pb: [f64; 2], tb: [f64; 2]) -> (Vec<[f64; 2]>, f64) {
    let a = End {
        p: pa,
        t: ta,
        k: 0.0,
        anchor: pa,
        ta,
        skip: 0.0,
        sigma: 0.0,
        span: 0.0,
        k_raw: 0.0,
        k_near: 0.0,
        t_own: None,
    };
    let b = End { p: pb, ..a };
    // Tangent length: exact for a circular arc turning by theta (4 R tan(theta / 4) =
    // chord / cos^2(theta / 4)); the chord for a straight bridge.
    let theta = (ta[0] * tb[0] + ta[1] * tb[1]).clamp(-1.0, 1.0).acos();
    let m = dist(a.p, b.p) / (0.25 * theta).cos().powi(2);
    let at = |u: f64| {
        let (u2, u3) = (u * u, u * u * u);
        let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
        let h10 = u3 - 2.0 * u2 + u;
        let h01 = -2.0 * u3 + 3.0 * u2;
        let h11 = u3 - u2;
        [
            h00 * a.p[0] + h10 * m * ta[0] + h01 * b.p[0] + h11 * m * tb[0],
            h00 * a.p[1] + h10 * m * ta[1] + h01 * b.p[1] + h11 * m * tb[1],
        ]
    };
    let fine: Vec<[f64; 2]> = (0..=64).map(|i| at(i as f64 / 64.0)).collect();
    let len = polyline_length(&fine, false);
    let n = (len / BRIDGE_STEP_MM).ceil().max(1.0) as usize;
    let inner = (1..n).map(|i| at(i as f64 / n as f64)).collect();
    (inner, len)
}

/// A chain of pieces: piece indices in order, each reversed or not, and whether it closes.
#[derive(Debug, Clone)]
struct Chain {
    order: Vec<(usize, bool)>,
    closed: bool,
}

/// Tracked pieces linked into chains (one per drawn line), each built with its bridges.
pub(super) struct Network {
    pieces: Vec<PieceMm>,
    piece_ends: Vec<Option<[End; 2]>>,
    chains: Vec<Chain>,
    /// Each chain's polyline, gaps and bridge mask ([`build`]).
    built: Vec<(Stroke, Vec<Gap>, Vec<bool>)>,
    /// Each chain's length, mm.
    pub(super) lengths: Vec<f64>,
    /// Every point of every chain of two points or more: (chain, index).
    points: Grid<(usize, usize)>,
    max_gap_mm: f64,
    strokes: Strokes,
}

/// What drew the strokes a [`Network`] links.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Strokes {
    /// The rig's pencil, one path: an end is read to its last point and a bridge starts there
    /// (the bridge refit gets the graphite next to the skip); the written centres are smoothed.
    OnePath,
    /// A plotter's passes (`--paths`): backlash saws and passes cross near the ends, so the last
    /// [`END_SKIP_MM`] of an end are left out of its reading and bridged over; centres as
    /// tracked.
    Passes,
}

/// One chain judged as a drawn line: its refined polyline, its gaps (bridged in order along
/// it, then the missing ones), its free ends, and which other chains may continue it.
pub(super) struct Judged {
    pub(super) path: Stroke,
    pub(super) gaps: Vec<Gap>,
    free: Vec<End>,
    continues: Vec<bool>,
    /// For each missing gap in `gaps` (in order), the chain it leads to (`None`: the path's
    /// own other end).
    pub(super) missing_to: Vec<Option<usize>>,
}

impl Judged {
    /// The free ends of the path: position and outward unit tangent.
    pub(super) fn free_ends(&self) -> Vec<([f64; 2], [f64; 2])> {
        self.free.iter().map(|e| (e.p, e.t)).collect()
    }
}

impl Network {
    /// Links `pieces` end to end by continuity. `None` without pieces.
    pub(super) fn build(pieces: &[PieceMm], max_gap_mm: f64, strokes: Strokes) -> Option<Self> {
        let pieces: Vec<PieceMm> = split_kinks(pieces)
            .into_iter()
            .filter(|p| p.pts.len() >= 2)
            .collect();
        if pieces.is_empty() {
            return None;
        }
        let piece_ends: Vec<Option<[End; 2]>> = pieces.iter().map(|p| ends(p, strokes)).collect();
        let n_ends = 2 * pieces.len();
        // Candidate links within the bridging reach, over a coarse grid of end positions.
        let reach = max_gap_mm.max(1.0);
        let piece_len: Vec<f64> = pieces
            .iter()
            .map(|p| polyline_length(&p.pts, p.closed))
            .collect();
        let mut cands = candidates(&piece_ends, reach, |ea, eb, a, b| {
            let g = dist(a.p, b.p);
            // A piece closes on itself only across a gap short against its length.
            if ea / 2 == eb / 2 && piece_len[ea / 2] < 3.0 * g + 10.0 {
                return None;
            }
            continuity(a, b, reach).filter(|_| g <= max_gap_mm || g < 1.0)
        });
        cands.sort_by(|x, y| x.cost.total_cmp(&y.cost));
        // Greedy: cheapest first, each end once. Every chain has exactly two free ends, so a
        // link between two ends of one chain closes it.
        let mut partner: Vec<Option<usize>> = vec![None; n_ends];
        for c in &cands {
            if partner[c.a].is_some() || partner[c.b].is_some() {
                continue;
            }
            partner[c.a] = Some(c.b);
            partner[c.b] = Some(c.a);
        }
        let first = walk_chains(&pieces, &piece_ends, &partner);
        // The rig's one path only: a plotter's lines meet at corners and crossings, where a
        // chain's end read through its bridges would turn onto the crossing line.
        if strokes == Strokes::OnePath {
            relink::relink(&first, &pieces, &piece_ends, &mut partner, max_gap_mm);
        }
        let chains = walk_chains(&pieces, &piece_ends, &partner);
        let built: Vec<(Stroke, Vec<Gap>, Vec<bool>)> = chains
            .iter()
            .map(|c| build(c, &pieces, &piece_ends, strokes))
            .collect();
        let lengths: Vec<f64> = built.iter().map(|(s, ..)| s.length_mm()).collect();
        let mut points = Grid::new(CROSS_TOUCH_MM);
        for (ci, (s, ..)) in built.iter().enumerate() {
            if s.points_mm.len() >= 2 {
                for (k, p) in s.points_mm.iter().enumerate() {
                    points.insert(*p, (ci, k));
                }
            }
        }
        Some(Self {
            pieces,
            piece_ends,
            chains,
            built,
            lengths,
            points,
            max_gap_mm,
            strokes,
        })
    }

    fn end(&self, e: usize) -> Option<End> {
        self.piece_ends[e / 2].map(|pe| pe[e % 2])
    }

    /// The drawn path: the longest chain; among chains within 80 % of it, the one nearest the
    /// printed path.
    fn choose_main(&self, hint: Option<ReferencePath>) -> Option<usize> {
        let longest = self.lengths.iter().copied().fold(0.0, f64::max);
        (0..self.built.len())
            .filter(|&i| self.lengths[i] >= 0.8 * longest)
            .min_by(|&i, &j| {
                let near =
                    |k: usize| hint.map_or(0.0, |h| mean_from(&self.built[k].0.points_mm, h));
                near(i)
                    .total_cmp(&near(j))
                    .then(self.lengths[j].total_cmp(&self.lengths[i]))
            })
    }

    /// Chain `main` as a drawn line: bridged across the marks that touch it, its bridges
    /// refitted, its written centres smoothed along it on one path ([`Strokes::OnePath`]; the
    /// lines of `--paths` are smoothed across the band of their passes instead), its free ends
    /// and the gaps beyond them that are too long to bridge.
    pub(super) fn judge(&self, main: usize) -> Judged {
        let max_gap_mm = self.max_gap_mm;
        let (path, mut gaps, mask) = self.built[main].clone();
        // The points of other chains that touch this one (the rest cannot cut it).
        let mut touching: Vec<(usize, usize)> = path
            .points_mm
            .iter()
            .flat_map(|p| self.points.within(*p, CROSS_TOUCH_MM))
            .map(|(_, ck)| *ck)
            .filter(|(ci, _)| *ci != main)
            .collect();
        touching.sort_unstable();
        touching.dedup();
        let touching: Vec<[f64; 2]> = touching
            .into_iter()
            .map(|(ci, k)| self.built[ci].0.points_mm[k])
            .collect();
        let (path, mask) =
            cut_crossings(path, mask, &[touching.as_slice()], &mut gaps, self.strokes);
        let (points_mm, mask, bridged_mm) = bridge_fit::refine(&path.points_mm, &mask, path.closed);
        let points_mm = if matches!(self.strokes, Strokes::OnePath) {
            smooth::smooth_written(&points_mm, &mask, path.closed)
        } else {
            points_mm
        };
        let path = Stroke {
            points_mm,
            bridged_mm,
            ..path
        };
        let main_chain = &self.chains[main];
        // Free ends of the path and what lies beyond them.
        let mut free: Vec<End> = Vec::new();
        if !main_chain.closed {
            let (first, last) = (
                main_chain.order[0],
                main_chain.order[main_chain.order.len() - 1],
            );
            let first_entry = 2 * first.0 + usize::from(first.1);
            let last_exit = (2 * last.0 + usize::from(last.1)) ^ 1;
            for e in [first_entry, last_exit] {
                if let Some(x) = self.end(e) {
                    free.push(x);
                }
            }
        }
        let far = (5.0 * max_gap_mm).max(50.0);
        let mut continues: Vec<bool> = vec![false; self.chains.len()];
        let mut missing_to: Vec<Option<usize>> = Vec::new();
        if free.len() == 2 {
            // The path's ends continuing into each other across a gap too long to bridge.
            if dist(free[0].p, free[1].p) > max_gap_mm {
                if let Some(_c) = continuity(&free[0], &free[1], far)
                    .filter(|_| path.length_mm() > 2.0 * dist(free[0].p, free[1].p))
                {
                    let (_, len) = bridge(&free[0], &free[1]);
                    gaps.push(Gap {
                        from_mm: free[1].p,
                        to_mm: free[0].p,
                        length_mm: len,
                        bridged: false,
                    });
                    missing_to.push(None);
                }
            }
        }
        let mut main_pieces = vec![false; self.pieces.len()];
        for (p, _) in &main_chain.order {
            main_pieces[*p] = true;
        }
        for f in &free {
            let mut best: Option<(f64, usize, End)> = None;
            for (ci, ch) in self.chains.iter().enumerate() {
                if ci == main || self.lengths[ci] < 2.0 || ch.closed {
                    continue;
                }
                let (first, last) = (ch.order[0], ch.order[ch.order.len() - 1]);
                for e in [
                    2 * first.0 + usize::from(first.1),
                    (2 * last.0 + usize::from(last.1)) ^ 1,
                ] {
                    if main_pieces[e / 2] {
                        continue;
                    }
                    let Some(x) = self.end(e) else { continue };
                    if dist(f.p, x.p) <= max_gap_mm {
                        continue; // was admissible and not taken: not a continuation
                    }
                    if let Some(c) = continuity(f, &x, far) {
                        if best.is_none_or(|(bc, ..)| c < bc) {
                            best = Some((c, ci, x));
                        }
                    }
                }
            }
            if let Some((_, ci, x)) = best {
                let (_, len) = bridge(f, &x);
                gaps.push(Gap {
                    from_mm: f.p,
                    to_mm: x.p,
                    length_mm: len,
                    bridged: false,
                });
                missing_to.push(Some(ci));
                continues[ci] = true;
            }
        }
        Judged {
            path: orient(path),
            gaps,
            free,
            continues,
            missing_to,
        }
    }

    /// What the judged chain `main` leaves out: every other chain, longest first, with why.
    pub(super) fn left_out(&self, main: usize, judged: &Judged) -> Vec<LeftOut> {
        self.left_out_indexed(main, judged)
            .into_iter()
            .map(|(_, o)| o)
            .collect()
    }

    /// [`Self::left_out`] with each mark's chain index.
    pub(super) fn left_out_indexed(&self, main: usize, judged: &Judged) -> Vec<(usize, LeftOut)> {
        let reach_ahead = (2.0 * self.max_gap_mm).max(15.0);
        let main_len = self.lengths[main];
        let mut left_out: Vec<(usize, LeftOut)> = Vec::new();
        for (ci, (s, ..)) in self.built.iter().enumerate() {
            if ci == main {
                continue;
            }
            let len = self.lengths[ci];
            let pts = &s.points_mm;
            let ahead = len >= MIN_MARK_MM
                && judged.free.iter().any(|f| {
                    pts.iter().any(|q| {
                        let d = sub(*q, f.p);
                        let dn = norm(d);
                        dn <= reach_ahead
                            && (dn < 1e-9 || (d[0] * f.t[0] + d[1] * f.t[1]) / dn >= 0.7)
                    })
                });
            let kind = if judged.continues[ci] || ahead {
                LeftOutKind::Continues
            } else if len >= MIN_MARK_MM.max(SEPARATE_SHARE * main_len) {
                LeftOutKind::Separate
            } else if len < MIN_MARK_MM {
                LeftOutKind::Speck
            } else {
                LeftOutKind::Mark
            };
            left_out.push((
                ci,
                LeftOut {
                    from_mm: pts[0],
                    to_mm: pts[pts.len() - 1],
                    length_mm: len,
                    kind,
                },
            ));
        }
        left_out.sort_by(|a, b| b.1.length_mm.total_cmp(&a.1.length_mm));
        left_out
    }

    /// The chain of index `ci` as built (bridges as first guesses, not refitted).
    pub(super) fn chain_stroke(&self, ci: usize) -> &Stroke {
        &self.built[ci].0
    }
}

/// Links `pieces` into chains; returns the drawn path and what was left out. `hint`: the printed
/// path, to choose between chains of similar length. `None` without pieces.
pub(crate) fn link(
    pieces: &[PieceMm],
    max_gap_mm: f64,
    hint: Option<ReferencePath>,
) -> Option<Linking> {
    let net = Network::build(pieces, max_gap_mm, Strokes::OnePath)?;
    let main = net.choose_main(hint)?;
    let judged = net.judge(main);
    let left_out = net.left_out(main, &judged);
    let mut others: Vec<Stroke> = (0..net.built.len())
        .filter(|&ci| ci != main)
        .map(|ci| net.chain_stroke(ci).clone())
        .collect();
    others.sort_by(|a, b| b.length_mm().total_cmp(&a.length_mm()));
    let path = judged.path;
    let hint = hint.map(|h| (h, mean_from(&path.points_mm, h)));
    Some(Linking {
        path,
        others,
        gaps: judged.gaps,
        left_out,
        pieces: net.chains[main].order.len(),
        hint,
    })
}

/// The chains of linked pieces: each from a free end (or around a cycle).
fn walk_chains(
    pieces: &[PieceMm],
    piece_ends: &[Option<[End; 2]>],
    partner: &[Option<usize>],
) -> Vec<Chain> {
    let mut seen = vec![false; pieces.len()];
    let mut chains = Vec::new();
    for start in 0..pieces.len() {
        if seen[start] {
            continue;
        }
        seen[start] = true;
        if piece_ends[start].is_none() {
            chains.push(Chain {
                order: vec![(start, false)],
                closed: pieces[start].closed,
            });
            continue;
        }
        // Backwards from the head of `start` to a free end, or around a cycle.
        let mut e = 2 * start;
        let mut cycle = false;
        for _ in 0..=pieces.len() {
            match partner[e] {
                Some(q) if q / 2 == start => {
                    cycle = true;
                    break;
                }
                Some(q) => e = q ^ 1,
                None => break,
            }
        }
        let mut entry = if cycle { 2 * start } else { e };
        let mut order = Vec::new();
        loop {
            let p = entry / 2;
            order.push((p, entry % 2 == 1));
            seen[p] = true;
            match partner[entry ^ 1] {
                Some(q) if q / 2 != order[0].0 && !order.iter().any(|(o, _)| *o == q / 2) => {
                    entry = q;
                }
                _ => break,
            }
        }
        chains.push(Chain {
            order,
            closed: cycle,
        });
    }
    chains
}

/// Where another mark touches the path (a stroke crossing it, whether the tracker cut it or the
/// path there), the path's centroids were pulled towards it: the path within [`CROSS_CUT_MM`]
/// of every place where another mark comes within [`CROSS_TOUCH_MM`] is replaced by a bridge
/// between the undisturbed sides (a stretch longer than [`CROSS_MAX_MM`], a mark running along
/// the path, is kept).
fn cut_crossings(
    path: Stroke,
    mask: Vec<bool>,
    marks: &[&[[f64; 2]]],
    gaps: &mut Vec<Gap>,
    strokes: Strokes,
) -> (Stroke, Vec<bool>) {
    let pts = &path.points_mm;
    let n = pts.len();
    if n < 8 {
        return (path, mask);
    }
    let cell = CROSS_CUT_MM;
    let key = |p: [f64; 2]| ((p[0] / cell).floor() as i64, (p[1] / cell).floor() as i64);
    let mut grid: std::collections::HashMap<(i64, i64), Vec<usize>> = Default::default();
    for (i, p) in pts.iter().enumerate() {
        grid.entry(key(*p)).or_default().push(i);
    }
    let mut cut = vec![false; n];
    for m in marks {
        for q in m.iter() {
            let (kx, ky) = key(*q);
            let mut best: Option<(usize, f64)> = None;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for &i in grid.get(&(kx + dx, ky + dy)).into_iter().flatten() {
                        let d = dist(pts[i], *q);
                        if d <= CROSS_TOUCH_MM && best.is_none_or(|(_, bd)| d < bd) {
                            best = Some((i, d));
                        }
                    }
                }
            }
            let Some((i, _)) = best else { continue };
            let c = pts[i];
            let (kx, ky) = key(c);
            for dx in -2..=2 {
                for dy in -2..=2 {
                    for &k in grid.get(&(kx + dx, ky + dy)).into_iter().flatten() {
                        if dist(pts[k], c) <= CROSS_CUT_MM {
                            cut[k] = true;
                        }
                    }
                }
            }
        }
    }
    // Long runs are kept.
    let mut i = 0;
    while i < n {
        if !cut[i] {
            i += 1;
            continue;
        }
        let mut j = i;
        while j + 1 < n && cut[j + 1] {
            j += 1;
        }
        if polyline_length(&pts[i..=j], false) > CROSS_MAX_MM {
            cut[i..=j].iter_mut().for_each(|c| *c = false);
        }
        i = j + 1;
    }
    if !cut.iter().any(|c| *c) || cut.iter().all(|c| *c) {
        return (path, mask);
    }
    // Start a closed path at a kept point, so no cut run wraps around.
    let (pts, cut, mask): (Vec<[f64; 2]>, Vec<bool>, Vec<bool>) = if path.closed {
        let start = cut.iter().position(|c| !c).unwrap_or(0);
        let mut p = pts.clone();
        let mut c = cut.clone();
        let mut m = mask;
        p.rotate_left(start);
        c.rotate_left(start);
        let k = start.min(m.len());
        m.rotate_left(k);
        (p, c, m)
    } else {
        (pts.clone(), cut, mask)
    };
    let mut out_mask: Vec<bool> = Vec::with_capacity(n);
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(n);
    let mut bridged = path.bridged_mm;
    let mut i = 0;
    while i < n {
        if !cut[i] {
            out.push(pts[i]);
            out_mask.push(mask.get(i).copied().unwrap_or(false));
            i += 1;
            continue;
        }
        let mut j = i;
        while j + 1 < n && cut[j + 1] {
            j += 1;
        }
        let after = if path.closed && j + 1 == n {
            // Up to the (kept) start of the closed path.
            let mut v: Vec<[f64; 2]> = out.clone();
            v.reverse();
            v
        } else {
            pts[j + 1..].iter().rev().copied().collect()
        };
        if let (Some(a), Some(b), false) = (
            end_with(&out, END_SKIP_MM, strokes),
            end_with(&after, END_SKIP_MM, strokes),
            after.is_empty(),
        ) {
            let (inner, len) = bridge(&a, &b);
            gaps.push(Gap {
                from_mm: a.p,
                to_mm: b.p,
                length_mm: len,
                bridged: true,
            });
            bridged += len;
            out_mask.extend(std::iter::repeat_n(true, inner.len()));
            out.extend(inner);
        }
        i = j + 1;
    }
    (
        Stroke {
            points_mm: out,
            closed: path.closed,
            bridged_mm: bridged,
        },
        out_mask,
    )
}

/// Total length of piece segments within `band_mm` of the printed `path` (to pick the hint).
pub(crate) fn length_near(pieces: &[PieceMm], path: ReferencePath, band_mm: f64) -> f64 {
    pieces
        .iter()
        .flat_map(|p| p.pts.windows(2))
        .filter(|w| path.distance_mm(w[0]) <= band_mm && path.distance_mm(w[1]) <= band_mm)
        .map(|w| dist(w[0], w[1]))
        .sum()
}

/// Mean distance of `pts` from the printed path.
fn mean_from(pts: &[[f64; 2]], h: ReferencePath) -> f64 {
    if pts.is_empty() {
        return f64::INFINITY;
    }
    pts.iter().map(|p| h.distance_mm(*p)).sum::<f64>() / pts.len() as f64
}

/// Candidate links between ends of different pieces or the two ends of one piece, with the
/// gap within `reach`; `admit` gives the cost or refuses.
fn candidates(
    piece_ends: &[Option<[End; 2]>],
    reach: f64,
    admit: impl Fn(usize, usize, &End, &End) -> Option<f64>,
) -> Vec<Cand> {
    let mut grid: std::collections::HashMap<(i64, i64), Vec<usize>> = Default::default();
    let cell = reach.max(1.0);
    let key = |p: [f64; 2]| ((p[0] / cell).floor() as i64, (p[1] / cell).floor() as i64);
    for (i, pe) in piece_ends.iter().enumerate() {
        if let Some(pe) = pe {
            for (side, e) in pe.iter().enumerate() {
                grid.entry(key(e.p)).or_default().push(2 * i + side);
            }
        }
    }
    let mut out = Vec::new();
    for (i, pe) in piece_ends.iter().enumerate() {
        let Some(pe) = pe else { continue };
        for (side, a) in pe.iter().enumerate() {
            let ea = 2 * i + side;
            let (kx, ky) = key(a.p);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for &eb in grid.get(&(kx + dx, ky + dy)).into_iter().flatten() {
                        if eb <= ea {
                            continue;
                        }
                        let Some(b) = piece_ends[eb / 2].map(|p| p[eb % 2]) else {
                            continue;
                        };
                        if let Some(cost) = admit(ea, eb, a, &b) {
                            out.push(Cand {
                                a: ea,
                                b: eb,
                                gap: dist(a.p, b.p),
                                cost,
                            });
                        }
                    }
                }
            }
        }
    }
    out.retain(|c| c.gap <= reach || c.gap < 1.0);
    out
}

/// The polyline of a chain with its bridges (a first guess, see [`bridge_fit`]), which of its
/// points are bridge points, and its gaps.
fn build(
    chain: &Chain,
    pieces: &[PieceMm],
    piece_ends: &[Option<[End; 2]>],
    strokes: Strokes,
) -> (Stroke, Vec<Gap>, Vec<bool>) {
    let mut pts: Vec<[f64; 2]> = Vec::new();
    let mut mask: Vec<bool> = Vec::new();
    let mut gaps = Vec::new();
    let mut bridged = 0.0;
    let n = chain.order.len();
    let linked_cycle = chain.closed && piece_ends[chain.order[0].0].is_some();
    // A piece in its direction along the chain, cut back to the anchors of its linked ends.
    let oriented = |i: usize| -> Vec<[f64; 2]> {
        let (p, rev) = chain.order[i];
        let mut v = pieces[p].pts.clone();
        if rev {
            v.reverse();
        }
        let Some(e) = piece_ends[p] else {
            return v;
        };
        let (entry, exit) = if rev { (e[1], e[0]) } else { (e[0], e[1]) };
        if i + 1 < n || linked_cycle {
            trim_back(&mut v, exit.skip);
        }
        if i > 0 || linked_cycle {
            v.reverse();
            trim_back(&mut v, entry.skip);
            v.reverse();
        }
        v
    };
    // The end by which the chain leaves piece (p, rev), and the end by which it enters.
    let exit_end = |&(p, rev): &(usize, bool)| piece_ends[p].map(|e| if rev { e[0] } else { e[1] });
    let entry_end =
        |&(p, rev): &(usize, bool)| piece_ends[p].map(|e| if rev { e[1] } else { e[0] });
    // Bridges run between the anchors: the pencil's own gap and the millimetre before each end.
    // The side already written gives its direction from the chain so far (a short piece alone
    // gives a poor one).
    let mut link = |a: End, b: End, pts: &mut Vec<[f64; 2]>, mask: &mut Vec<bool>| {
        let (from, ta) = match end_with(pts, 0.0, strokes) {
            Some(e) if pts.len() >= 2 => (e.p, e.t),
            _ => (a.anchor, a.ta),
        };
        let (inner, len) = hermite(from, ta, b.anchor, [-b.ta[0], -b.ta[1]]);
        let gap = dist(a.p, b.p);
        if gap > 1e-9 {
            gaps.push(Gap {
                from_mm: a.p,
                to_mm: b.p,
                length_mm: (len - a.skip - b.skip).max(gap),
                bridged: true,
            });
            bridged += len;
        }
        mask.extend(std::iter::repeat_n(true, inner.len()));
        pts.extend(inner);
    };
    for (i, item) in chain.order.iter().enumerate() {
        if i > 0 {
            if let (Some(a), Some(b)) = (exit_end(&chain.order[i - 1]), entry_end(item)) {
                link(a, b, &mut pts, &mut mask);
            }
        }
        let v = oriented(i);
        mask.extend(std::iter::repeat_n(false, v.len()));
        pts.extend(v);
    }
    if linked_cycle {
        if let (Some(a), Some(b)) = (exit_end(&chain.order[n - 1]), entry_end(&chain.order[0])) {
            link(a, b, &mut pts, &mut mask);
        }
    }
    let (pts, mask) = dedup_masked(pts, mask);
    (
        Stroke {
            points_mm: pts,
            closed: chain.closed,
            bridged_mm: bridged,
        },
        gaps,
        mask,
    )
}

/// Removes consecutive repeated points (and their mask entries).
fn dedup_masked(pts: Vec<[f64; 2]>, mask: Vec<bool>) -> (Vec<[f64; 2]>, Vec<bool>) {
    let mut p: Vec<[f64; 2]> = Vec::with_capacity(pts.len());
    let mut m: Vec<bool> = Vec::with_capacity(mask.len());
    for (q, b) in pts.into_iter().zip(mask) {
        if p.last() != Some(&q) {
            p.push(q);
            m.push(b);
        }
    }
    (p, m)
}

/// Shortens the polyline `v` by `len` mm at its end (never below one point).
fn trim_back(v: &mut Vec<[f64; 2]>, len: f64) {
    if len <= 0.0 || v.len() < 2 {
        return;
    }
    let cut = point_back(v, len);
    let mut acc = 0.0;
    while v.len() >= 2 {
        let d = dist(v[v.len() - 2], v[v.len() - 1]);
        if acc + d >= len {
            break;
        }
        acc += d;
        v.pop();
    }
    if let Some(last) = v.last_mut() {
        *last = cut;
    }
}

/// A fixed order: a closed path counter-clockwise from its point at the smallest polar angle
/// about its centroid; an open path from its end with the smaller x (then y).
pub(super) fn orient(mut s: Stroke) -> Stroke {
    let pts = &mut s.points_mm;
    if pts.len() < 2 {
        return s;
    }
    if s.closed {
        let area: f64 = (0..pts.len())
            .map(|i| {
                let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
                a[0] * b[1] - a[1] * b[0]
            })
            .sum();
        if area < 0.0 {
            pts.reverse();
        }
        let n = pts.len() as f64;
        let c = [
            pts.iter().map(|p| p[0]).sum::<f64>() / n,
            pts.iter().map(|p| p[1]).sum::<f64>() / n,
        ];
        let start = (0..pts.len())
            .min_by(|&i, &j| {
                let a = |k: usize| {
                    (pts[k][1] - c[1])
                        .atan2(pts[k][0] - c[0])
                        .rem_euclid(std::f64::consts::TAU)
                };
                a(i).total_cmp(&a(j))
            })
            .unwrap_or(0);
        pts.rotate_left(start);
    } else {
        let (a, b) = (pts[0], pts[pts.len() - 1]);
        if (b[0], b[1]) < (a[0], a[1]) {
            pts.reverse();
        }
    }
    s
}

mod relink;
#[cfg(test)]
mod tests;
