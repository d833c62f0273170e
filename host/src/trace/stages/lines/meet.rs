//! Lines that end on a line across them, or meet another at a corner, carried on to its
//! centreline or to the corner ([`meet_lines_across`]).

use super::super::link::Gap;
use super::params::LinesParams;
use super::{abs_cos, arc, chord_dir, chord_dir_on};
use crate::trace::band::{Cloud, Walk};
use crate::trace::plane::{dist, sub};

/// A line ending within `LinesParams::meet_mm` of the centreline of a line across it (more than
/// `LinesParams::across_deg` to it), ahead of its end (or within `LinesParams::meet_inked_mm` with ink all the way),
/// ends on that line: the passes of a line stop at the
/// edge of the other's band (where the tracker met the other's ink), so the line is carried on
/// straight through that band to the other's centreline.
pub(super) fn meet_lines_across(walks: &mut [Walk], cloud: &Cloud, lp: &LinesParams) {
    let cos_across = lp.across_deg.to_radians().cos();
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
            let t = chord_dir(c, ei, lp.end_chord_mm);
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
                    if along <= 0.0 || along > lp.meet_inked_mm || off > lp.step_off_mm {
                        continue;
                    }
                    let foot = [e[0] + along * t[0], e[1] + along * t[1]];
                    // Beyond the line's band with no ink: a skip, bridged.
                    let skip = along > lp.meet_mm && cloud.inkless_mm(e, foot) > lp.inkless_ok_mm;
                    if abs_cos(chord_dir_on(&o.centres, &arcs[j], k, lp.dir_half_mm), t)
                        >= cos_across
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
    // Two lines ending at a corner (their ends' rays meeting within LinesParams::meet_mm ahead of both,
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
                chord_dir(c, 0, lp.end_chord_mm),
                chord_dir(c, c.len() - 1, lp.end_chord_mm),
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
            let reach = |v: f64| (-0.5..=lp.meet_inked_mm).contains(&v);
            let skip =
                |v: f64, e: [f64; 2]| v > lp.meet_mm && cloud.inkless_mm(e, x) > lp.inkless_ok_mm;
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
        extend_to(w, tail, foot, lp);
    }
}

/// `w` carried straight on from its tail (or head) to `foot`, in steps of `LinesParams::line_spacing_mm`.
pub(super) fn extend_to(w: &mut Walk, tail: bool, foot: [f64; 2], lp: &LinesParams) {
    let c = &mut w.centres;
    let Some(&e) = (if tail { c.last() } else { c.first() }) else {
        return;
    };
    let n = (dist(e, foot) / lp.line_spacing_mm).ceil() as usize;
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
