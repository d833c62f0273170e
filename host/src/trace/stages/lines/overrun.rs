//! A line's end followed round into a line across it: where the passes of a line meet a line
//! drawn across (a T or a corner), their ink merges with that line's, and the walk along the
//! band may carry on a few mm along the other line before it stops. That stretch is the other
//! line's: it is cut off, and the end is then carried to the other line's centreline like any
//! end that stops at a line across ([`super::meet::meet_lines_across`]).

use super::meet::extend_to;
use super::params::LinesParams;
use super::{abs_cos, arc, chord_dir_on};
use crate::trace::band::{arc_of, Walk};
use crate::trace::plane::{dist, sub, unit, Grid};

/// What is kept of a walk: centres `first..last`, carried on at its head and tail to `feet`.
struct Kept {
    walk: usize,
    first: usize,
    last: usize,
    feet: [Option<[f64; 2]>; 2],
}

/// Cuts from every open walk's ends the stretch that has turned off the line's own direction
/// (the chord over `LinesParams::own_dir_mm` before the last `LinesParams::overrun_max_mm`) by more than
/// `LinesParams::turned_deg` inside the band of another walk running across the line (more than
/// `LinesParams::across_deg` to its own direction), when it ran at least `LinesParams::along_other_mm` along that
/// walk inside its band (a curve that merely begins on a line does not), and carries the end
/// straight on to that walk's centreline (an end with no centreline ahead is kept). Walks
/// shorter than twice `LinesParams::overrun_max_mm` plus `LinesParams::own_dir_mm` are left as they are.
pub(super) fn cut_overruns(walks: &mut [Walk], lp: &LinesParams) {
    let arcs: Vec<Vec<f64>> = walks.iter().map(|w| arc(&w.centres)).collect();
    let dirs: Vec<Vec<[f64; 2]>> = walks
        .iter()
        .zip(&arcs)
        .map(|(w, s)| {
            (0..w.centres.len())
                .map(|k| chord_dir_on(&w.centres, s, k, lp.dir_half_mm))
                .collect()
        })
        .collect();
    let mut centres: Grid<(usize, usize)> = Grid::new(lp.band_half_mm);
    for (j, w) in walks.iter().enumerate() {
        for (m, c) in w.centres.iter().enumerate() {
            centres.insert(*c, (j, m));
        }
    }
    let cos_across = lp.across_deg.to_radians().cos();
    let cos_turned = lp.turned_deg.to_radians().cos();
    let mut keep: Vec<Kept> = Vec::new();
    for (i, w) in walks.iter().enumerate() {
        let (c, s) = (&w.centres, &arcs[i]);
        let n = c.len();
        let total = s.last().copied().unwrap_or(0.0);
        if w.closed || n < 2 || total < 2.0 * lp.overrun_max_mm + lp.own_dir_mm {
            continue;
        }
        let (mut first, mut last) = (0, n);
        let mut feet: [Option<[f64; 2]>; 2] = [None, None];
        for tail in [true, false] {
            // Index `k` counted from the end being judged.
            let idx = |k: usize| if tail { n - 1 - k } else { k };
            let from_end = |k: usize| if tail { total - s[idx(k)] } else { s[idx(k)] };
            let at = |d: f64| (0..n).find(|&k| from_end(k) >= d).unwrap_or(n - 1);
            let (a, b) = (at(lp.overrun_max_mm), at(lp.overrun_max_mm + lp.own_dir_mm));
            let Some(own) = unit(sub(c[idx(a)], c[idx(b)])) else {
                continue;
            };
            // A centre of another walk, running across this one.
            let across = |x: &&([f64; 2], (usize, usize))| {
                let (j, m) = x.1;
                j != i && abs_cos(dirs[j][m], own) < cos_across
            };
            let on_across = |k: usize| {
                let (p, t) = (c[idx(k)], dirs[i][idx(k)]);
                abs_cos(t, own) < cos_turned
                    && centres.within(p, lp.band_half_mm).any(|x| across(&x))
            };
            let mut k = 0;
            while k < a && on_across(k) {
                k += 1;
            }
            // How far it ran along the line across, inside its band.
            let end = c[idx(0)];
            let other = centres
                .within(end, lp.band_half_mm)
                .filter(across)
                .min_by(|x, y| dist(x.0, end).total_cmp(&dist(y.0, end)))
                .map(|(_, (j, m))| dirs[*j][*m]);
            let ran = match (k, other) {
                (0, _) | (_, None) => 0.0,
                (_, Some(d)) => {
                    let v = sub(end, c[idx(k - 1)]);
                    (v[0] * d[0] + v[1] * d[1]).abs()
                }
            };
            if ran < lp.along_other_mm {
                continue;
            }
            // ... and back from there as long as it is still turned off the line (the line
            // bent towards the other one on its way in).
            if k > 0 {
                while k < a && abs_cos(dirs[i][idx(k)], own) < cos_turned {
                    k += 1;
                }
            }
            if k == 0 || from_end(k) < lp.overrun_min_mm {
                continue;
            }
            // Carried straight on to the centreline of the line across ahead (none: kept).
            let e = c[idx(k)];
            let foot = centres
                .within(e, lp.overrun_max_mm + lp.band_half_mm)
                .filter(across)
                .filter_map(|(q, _)| {
                    let v = sub(*q, e);
                    let along = v[0] * own[0] + v[1] * own[1];
                    let off = (v[0] * own[1] - v[1] * own[0]).abs();
                    (along > 0.0 && off <= lp.step_off_mm).then_some(along)
                })
                .min_by(f64::total_cmp)
                .map(|along| [e[0] + along * own[0], e[1] + along * own[1]]);
            let Some(foot) = foot else { continue };
            if tail {
                last = n - k;
                feet[1] = Some(foot);
            } else {
                first = k;
                feet[0] = Some(foot);
            }
        }
        if first > 0 || last < n {
            keep.push(Kept {
                walk: i,
                first,
                last,
                feet,
            });
        }
    }
    for Kept {
        walk,
        first,
        last,
        feet,
    } in keep
    {
        let w = &mut walks[walk];
        w.centres = w.centres[first..last].to_vec();
        let kept = &w.centres;
        w.gaps
            .retain(|g| arc_of(kept, g.from_mm) && arc_of(kept, g.to_mm));
        for (tail, foot) in [(false, feet[0]), (true, feet[1])] {
            if let Some(foot) = foot {
                extend_to(w, tail, foot, lp);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn walk(centres: Vec<[f64; 2]>) -> Walk {
        Walk {
            centres,
            ..Walk::default()
        }
    }

    /// Points from `a` to `b` every 0.5 mm (without `b`).
    fn run(a: [f64; 2], b: [f64; 2]) -> Vec<[f64; 2]> {
        let n = (dist(a, b) / 0.5).round() as usize;
        (0..n)
            .map(|k| {
                let f = k as f64 / n as f64;
                [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]
            })
            .collect()
    }

    /// A vertical line at x = 45 and a horizontal one ending on it at y = 0.
    fn across() -> Walk {
        walk(run([45.0, 40.0], [45.0, -40.0]))
    }

    #[test]
    fn an_end_followed_round_into_a_line_across_is_cut_and_carried_to_it() {
        let lp = &LinesParams::default();
        // Along y = 0, bending down from x = 38 and then running down the other line.
        let mut c = run([-60.0, 0.0], [38.0, 0.0]);
        c.extend(run([38.0, 0.0], [43.0, -3.0]));
        c.extend(run([43.0, -3.0], [45.0, -12.0]));
        c.push([45.0, -12.0]);
        let mut walks = vec![walk(c), across()];
        cut_overruns(&mut walks, lp);
        let c = &walks[0].centres;
        let end = c[c.len() - 1];
        assert!(dist(end, [45.0, 0.0]) < 0.6, "end {end:?}");
        assert!(c.iter().all(|p| p[1] > -0.6), "a centre left the line");
        assert_eq!(
            walks[1].centres,
            across().centres,
            "the line across is kept"
        );
    }

    #[test]
    fn a_line_crossing_another_or_curving_freely_is_kept() {
        let lp = &LinesParams::default();
        let straight = run([-60.0, 0.0], [80.0, 0.0]);
        let arc: Vec<[f64; 2]> = (0..=300)
            .map(|k| {
                let a = k as f64 * 0.01;
                [40.0 * a.cos() - 100.0, 40.0 * a.sin()]
            })
            .collect();
        let mut walks = vec![walk(straight.clone()), walk(arc.clone()), across()];
        cut_overruns(&mut walks, lp);
        assert_eq!(walks[0].centres, straight);
        assert_eq!(walks[1].centres, arc);
    }
}
