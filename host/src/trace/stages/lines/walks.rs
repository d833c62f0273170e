//! Walks that are one line: a walk running along a longer one is part of it
//! ([`duplicate_of`]); walks that continue each other, walked from two seeds that met, are
//! joined ([`join_continuing`]).

use super::super::link::Gap;
use super::params::LinesParams;
use super::{abs_cos, arc, chord_dir, directions, unit};
use crate::trace::band::Walk;
use crate::trace::plane::{dist, sub};
use std::collections::HashSet;

/// The walk among `walks` that `w` runs along for half its length or more (its centres within
/// `LinesParams::band_half_mm` of that walk's).
pub(super) fn duplicate_of(w: &Walk, walks: &[Walk], lp: &LinesParams) -> Option<usize> {
    let probe: Vec<[f64; 2]> = w.centres.iter().step_by(4).copied().collect();
    if probe.is_empty() {
        return None;
    }
    let dirs = |c: &[[f64; 2]]| directions(c, &arc(c), lp);
    let wd: Vec<[f64; 2]> = dirs(&w.centres).into_iter().step_by(4).collect();
    let cos_along = lp.band_deg.to_radians().cos();
    walks.iter().position(|o| {
        let od = dirs(&o.centres);
        let near = probe
            .iter()
            .zip(&wd)
            .filter(|(p, d)| {
                o.centres
                    .iter()
                    .zip(&od)
                    .any(|(c, e)| dist(*c, **p) <= lp.duplicate_mm && abs_cos(*e, **d) >= cos_along)
            })
            .count();
        2 * near >= probe.len()
    })
}

/// Joins walks that continue each other: an end of one lies within `LinesParams::join_mm` of the
/// other's centres (running its way) and the other goes on past it (a line whose band was
/// walked from two seeds that met where it splits or thins).
pub(super) fn join_continuing(
    mut walks: Vec<Walk>,
    mut taken: Vec<HashSet<usize>>,
    lp: &LinesParams,
) -> (Vec<Walk>, Vec<HashSet<usize>>) {
    'again: loop {
        for i in 0..walks.len() {
            for j in 0..walks.len() {
                if i == j || walks[i].closed || walks[j].closed {
                    continue;
                }
                let Some(joined) = continued(&walks[i], &walks[j], lp) else {
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
fn continued(a: &Walk, b: &Walk, lp: &LinesParams) -> Option<Walk> {
    let (ac, bc) = (&a.centres, &b.centres);
    if ac.len() < 2 || bc.len() < 2 {
        return None;
    }
    let cos_join = lp.join_deg.to_radians().cos();
    for tail in [true, false] {
        let (ei, e) = if tail {
            (ac.len() - 1, ac[ac.len() - 1])
        } else {
            (0, ac[0])
        };
        let ta = chord_dir(ac, ei, lp.end_chord_mm);
        let Some((l, _)) = bc
            .iter()
            .enumerate()
            .filter(|(_, c)| dist(**c, e) <= lp.join_mm)
            .min_by(|x, y| dist(*x.1, e).total_cmp(&dist(*y.1, e)))
        else {
            continue;
        };
        let tb = chord_dir(bc, l, lp.end_chord_mm);
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
            .partition_point(|&v| v < lp.end_chord_mm)
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
