//! Bridges over the gaps of a chain: a cubic Hermite curve through both ends' positions and
//! tangents ([`hermite`]; refitted later from the written points, `bridge_fit.rs`), and a
//! chain's polyline built from its pieces (cut back to their bridge anchors) and those bridges
//! ([`build`]).

use super::end::{end_with, point_back, End};
use super::network::Chain;
use super::params::LinkParams;
use super::strokes::Strokes;
use super::Gap;
use crate::trace::chain::{polyline_length, PieceMm, Stroke};
use crate::trace::plane::dist;

/// Cubic Hermite bridge from end `a` to end `b` (inner points only), and its length.
pub(super) fn bridge(a: &End, b: &End, lk: &LinkParams) -> (Vec<[f64; 2]>, f64) {
    hermite(a.p, a.t, b.p, [-b.t[0], -b.t[1]], lk)
}

/// Cubic Hermite curve from `pa` (tangent `ta`) to `pb` (arriving along `tb`): its inner points
/// every `LinkParams::bridge_step_mm` and its length.
fn hermite(
    pa: [f64; 2],
    ta: [f64; 2],
    pb: [f64; 2],
    tb: [f64; 2],
    lk: &LinkParams,
) -> (Vec<[f64; 2]>, f64) {
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
    let n = (len / lk.bridge_step_mm).ceil().max(1.0) as usize;
    let inner = (1..n).map(|i| at(i as f64 / n as f64)).collect();
    (inner, len)
}

/// The polyline of a chain with its bridges (a first guess, see [`bridge_fit`]), which of its
/// points are bridge points, and its gaps.
pub(super) fn build(
    chain: &Chain,
    pieces: &[PieceMm],
    piece_ends: &[Option<[End; 2]>],
    strokes: Strokes,
    lk: &LinkParams,
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
        let (from, ta) = match end_with(pts, 0.0, strokes, lk) {
            Some(e) if pts.len() >= 2 => (e.p, e.t),
            _ => (a.anchor, a.ta),
        };
        let (inner, len) = hermite(from, ta, b.anchor, [-b.ta[0], -b.ta[1]], lk);
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
