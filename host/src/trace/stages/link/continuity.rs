//! Which ends continue each other across a gap, and at what cost: each end's arc carried over the
//! gap lands on the other end and the directions agree ([`continuity`]), or, where those arcs
//! miss on a tight crest, the path bends one way through the gap and each end with it
//! ([`bends_through`]); the candidate links within reach ([`candidates`]).

use super::end::{arc_point, k_noise, reads_own_bend, rot, with_curvature, End};
use super::params::LinkParams;
use crate::trace::plane::dist;

/// A candidate link between end `a` and end `b` (end index = 2 * piece + side; side 0 head,
/// 1 tail).
#[derive(Debug, Clone, Copy)]
pub(super) struct Cand {
    pub(super) a: usize,
    pub(super) b: usize,
    pub(super) gap: f64,
    pub(super) cost: f64,
}

/// Continuity of `a` into `b` across their gap: `None` when not admissible, else the cost.
/// `reach` bounds the gap.
pub(super) fn continuity(a: &End, b: &End, reach: f64, lk: &LinkParams) -> Option<f64> {
    let g = dist(a.p, b.p);
    if g > reach {
        return None;
    }
    // An end too short to read its curvature bends as the other end does: across a short gap
    // the curve turns the same way on both sides (a wiggle's crest with a skip on it).
    let (bent_a, bent_b);
    let (a, b) = match (a.k_read(lk), b.k_read(lk)) {
        (false, true) => {
            bent_a = with_curvature(a, -b.k, lk);
            (&bent_a, b)
        }
        (true, false) => {
            bent_b = with_curvature(b, -a.k, lk);
            (a, &bent_b)
        }
        // Both short: they bend alike by what those that read their own bend read (a crest
        // between skips), else not at all.
        (false, false) => {
            let own: Vec<f64> = [
                reads_own_bend(a, lk).then_some(a.k_raw),
                reads_own_bend(b, lk).then_some(-b.k_raw),
            ]
            .into_iter()
            .flatten()
            .collect();
            let k = if own.is_empty() {
                0.0
            } else {
                (own.iter().sum::<f64>() / own.len() as f64)
                    .clamp(-lk.max_k_per_mm, lk.max_k_per_mm)
            };
            bent_a = with_curvature(a, k, lk);
            bent_b = with_curvature(b, -k, lk);
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
        return bends_through(a, b, chord, g, lk)
            .map(|odd| g + 2.0 * lat + 10.0 * turn_ab + 10.0 * odd);
    }
    Some(g + 2.0 * lat + 10.0 * turn_ab)
}

/// Two ends whose arcs miss each other across a gap of `g` mm (unit `chord` from `a` to `b`)
/// continue each other when the path can bend one way through it, as at a crest: the chord
/// splits the turn from `a`'s direction into `b`'s, each side taking at least `LinkParams::joint_share` of
/// it in the same sense, the turn is at most `LinkParams::max_joint_k_per_mm` times the length from the middle of
/// one end's span to the other's, and each end bends with it. A stroke crossing the path meets
/// it with the turn on one side only. `None` when not; else how far the chord's split is from
/// even, rad.
pub(super) fn bends_through(
    a: &End,
    b: &End,
    chord: [f64; 2],
    g: f64,
    lk: &LinkParams,
) -> Option<f64> {
    let into_b = [-b.t[0], -b.t[1]];
    let angle =
        |u: [f64; 2], v: [f64; 2]| (u[0] * v[1] - u[1] * v[0]).atan2(u[0] * v[0] + u[1] * v[1]);
    let (alpha, beta) = (angle(a.t, chord), angle(chord, into_b));
    let turn = alpha + beta;
    let len = a.mid_span() + g + b.mid_span();
    // Each side's share is read through its own end's tangent.
    let share = lk.joint_share * turn.abs();
    let ok = turn.abs() <= lk.max_joint_k_per_mm * len
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
        let reads = if e.k_read(lk) {
            let need = k_out.abs().min(lk.max_k_per_mm);
            [
                (e.k, e.span, need),
                (
                    e.k_near.clamp(-lk.max_k_per_mm, lk.max_k_per_mm),
                    lk.k_span_mm,
                    need,
                ),
            ]
        } else {
            [(e.k_raw, e.span, k_out.abs()); 2]
        };
        // The span must be long enough to tell a bend of half the mean from a straight one.
        reads.iter().any(|&(own, span, need)| {
            let noise = k_noise(span, lk);
            noise <= 0.5 * need && own * k_out.signum() >= 0.5 * need - noise
        })
    };
    let k_mean = turn / len;
    (ok && bends_too(a, k_mean) && bends_too(b, -k_mean)).then_some((alpha - beta).abs())
}

/// Candidate links between ends of different pieces or the two ends of one piece, with the
/// gap within `reach`; `admit` gives the cost or refuses.
pub(super) fn candidates(
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
