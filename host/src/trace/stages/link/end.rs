//! The ends of open pieces: where each leaves off, its outward tangent and curvature read from
//! the circle through three points of its last `LinkParams::end_span_mm` (on a crest the tangent again from
//! its last `LinkParams::tangent_span_mm`; a short end's own tangent where its last millimetre holds no
//! hook), and the point an end's osculating arc reaches when carried over a gap.

use super::params::LinkParams;
use super::strokes::Strokes;
use crate::trace::chain::{polyline_length, PieceMm};
use crate::trace::plane::{dist, norm, sub};

/// The end of an open piece: position, outward unit tangent, signed curvature (1/mm, positive
/// turning left when moving outward).
#[derive(Debug, Clone, Copy)]
pub(super) struct End {
    pub(super) p: [f64; 2],
    pub(super) t: [f64; 2],
    pub(super) k: f64,
    /// The anchor of a bridge, `skip` mm back from the end (the last millimetre may be pulled
    /// aside), and the tangent there.
    pub(super) anchor: [f64; 2],
    pub(super) ta: [f64; 2],
    pub(super) skip: f64,
    /// Uncertainty of the tangent, rad (short pieces give poor directions).
    pub(super) sigma: f64,
    /// The span the tangent was read over, mm (the curvature too when [`End::k_read`]).
    pub(super) span: f64,
    /// The curvature through the span's ends and middle however short the span, 1/mm.
    pub(super) k_raw: f64,
    /// The curvature over the span's last `LinkParams::k_span_mm` (the whole span when shorter),
    /// unclamped, 1/mm: where the path bends harder towards the end than over the span.
    pub(super) k_near: f64,
    /// A short span's own tangent at the end, from the circle through its three points, where
    /// its last millimetre follows that circle (no hook): see [`own_tangent`].
    pub(super) t_own: Option<[f64; 2]>,
}

impl End {
    pub(super) fn k_read(&self, lk: &LinkParams) -> bool {
        self.span >= lk.k_span_mm
    }

    /// How far back from the end the middle of its span lies, mm.
    pub(super) fn mid_span(&self) -> f64 {
        0.5 * (self.skip + self.span)
    }
}

pub(super) fn rot(t: [f64; 2], a: f64) -> [f64; 2] {
    let (s, c) = a.sin_cos();
    [c * t[0] - s * t[1], s * t[0] + c * t[1]]
}

/// The point at arc length `l` along `p`'s osculating circle (tangent `t`, curvature `k`).
pub(super) fn arc_point(e: &End, l: f64) -> [f64; 2] {
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
pub(super) fn point_back(pts: &[[f64; 2]], l: f64) -> [f64; 2] {
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

/// The curvature the centres' scatter (`LinkParams::sag_noise_mm`, twice over) reads through three
/// points spanning `span` mm, 1/mm: a span's sag is `k span^2 / 8`.
pub(super) fn k_noise(span: f64, lk: &LinkParams) -> f64 {
    2.0 * 8.0 * lk.sag_noise_mm / (span * span)
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
/// `skip` mm, halfway and `LinkParams::end_span_mm` back, carried to the end point; the bridge anchor
/// `skip` mm back (0: the last point). On the rig's one path, where that curvature is over
/// `LinkParams::max_k_per_mm` (a crest within the span), the tangent is read again from the circle through the
/// last `LinkParams::tangent_span_mm` before the anchor, unclamped: the span's chord, turned by the
/// clamped curvature, would point the end tens of degrees off across the crest. (A plotter's
/// passes, [`Strokes::PASSES`], saw at their ends: the last millimetres would turn it.)
pub(super) fn end_with(
    pts: &[[f64; 2]],
    skip: f64,
    strokes: Strokes,
    lk: &LinkParams,
) -> Option<End> {
    let len = polyline_length(pts, false);
    if len <= 0.0 {
        return None;
    }
    let span = lk.end_span_mm.min(0.7 * len);
    let skip = skip.min(0.2 * span);
    let p0 = pts[pts.len() - 1];
    let q1 = point_back(pts, skip);
    let (chord, n, k_raw) = three_point(pts, skip, span)?;
    let k_near =
        three_point(pts, skip, skip + lk.k_span_mm.min(span - skip)).map_or(k_raw, |v| v.2);
    // Curvature only from a span long enough to tell it from the centreline's noise.
    let k = if span >= lk.k_span_mm {
        k_raw.clamp(-lk.max_k_per_mm, lk.max_k_per_mm)
    } else {
        0.0
    };
    // The chord's direction is the tangent at its middle; turn it on to the anchor and the end.
    let near = (strokes.crest_tangent && span >= lk.k_span_mm && k_raw.abs() > lk.max_k_per_mm)
        .then(|| three_point(pts, skip, skip + lk.tangent_span_mm))
        .flatten();
    let ta = match near {
        Some((c, m, k_near)) => rot(c, k_near * 0.5 * m),
        None => rot(chord, k * 0.5 * n),
    };
    let t = rot(ta, k * dist(q1, p0));
    let t_own = (strokes.own_short_tangent && span < lk.k_span_mm)
        .then(|| own_tangent(pts, skip, span, ta, k_raw, lk))
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
/// where the last `LinkParams::hook_chord_mm` follow that circle within `LinkParams::hook_deg`; `None` otherwise
/// (a hook: the chord then stands for the tangent). Whether it is taken is
/// [`with_curvature`]'s choice.
fn own_tangent(
    pts: &[[f64; 2]],
    skip: f64,
    span: f64,
    ta: [f64; 2],
    k_raw: f64,
    lk: &LinkParams,
) -> Option<[f64; 2]> {
    if span < 2.0 * lk.hook_chord_mm {
        return None;
    }
    let mid = 0.5 * (skip + span);
    let last = sub(
        point_back(pts, skip),
        point_back(pts, skip + lk.hook_chord_mm),
    );
    let n = norm(last);
    if n <= 1e-9 {
        return None;
    }
    let along = rot(ta, k_raw * (mid - skip - 0.5 * lk.hook_chord_mm));
    let c = (last[0] * along[0] + last[1] * along[1]) / n;
    (c >= lk.hook_deg.to_radians().cos()).then(|| rot(ta, k_raw * (mid - skip)))
}

/// Whether a short end's own three points bend beyond twice the scatter's curvature, with no
/// hook at its end: it shows its own bend.
pub(super) fn reads_own_bend(e: &End, lk: &LinkParams) -> bool {
    e.t_own.is_some() && e.k_raw.abs() > 2.0 * k_noise(e.span, lk)
}

/// `e` bent by the curvature `k` it could not read itself (a short piece), `k` read by the other
/// end (so within `LinkParams::max_k_per_mm`): the chord's direction is the tangent at its middle, turned on to
/// the end. Where its own points tell a bend ([`reads_own_bend`]), or tell that it does not
/// bend as much as `k` (they differ from `k` by more than twice the scatter's curvature: a
/// nearly straight piece past a crest the other end reads), it takes its own tangent
/// ([`own_tangent`]) instead.
pub(super) fn with_curvature(e: &End, k: f64, lk: &LinkParams) -> End {
    let own = e
        .t_own
        .filter(|_| reads_own_bend(e, lk) || (e.k_raw - k).abs() > 2.0 * k_noise(e.span, lk));
    End {
        t: own.unwrap_or_else(|| rot(e.ta, k * e.mid_span())),
        k,
        ..*e
    }
}

/// Piece ends, read as `strokes` are (from [`Strokes::end_skip_mm`] back); `None`
/// for closed pieces.
pub(super) fn ends(piece: &PieceMm, strokes: Strokes, lk: &LinkParams) -> Option<[End; 2]> {
    if piece.closed || piece.pts.len() < 2 {
        return None;
    }
    let skip = strokes.end_skip_mm(lk);
    let tail = end_with(&piece.pts, skip, strokes, lk)?;
    let rev: Vec<[f64; 2]> = piece.pts.iter().rev().copied().collect();
    let head = end_with(&rev, skip, strokes, lk)?;
    Some([head, tail])
}
