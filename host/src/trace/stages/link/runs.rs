//! Two drawn runs on one sheet: where a left-out chain that could be part of the path (a line of
//! its own, or one ahead of a free end) crosses the path, the two are two drawn paths crossing,
//! and the run says so by where they cross ([`crossings`]) rather than calling the other run a
//! gap or a mark that may continue the path.

use super::params::LinkParams;
use super::{Crossing, LeftOut, LeftOutKind};
use crate::trace::chain::Stroke;
use crate::trace::plane::{dist, Grid};

/// Where the left-out chains cross or meet `path` (`left_out`: each mark with its chain's
/// stroke, in the order of [`super::Linking::left_out`]): a mark that could be part of the
/// path crossing or meeting it, or a mark of `LinkParams::min_mark_mm` or more meeting it at two places
/// `LinkParams::run_apart_mm` apart, is a second drawn path (its kind raised to
/// [`LeftOutKind::Separate`]). Meeting: the polylines intersect, a centre of the mark lies
/// within `LinkParams::run_touch_mm` of the path, or an end of it within `LinkParams::run_meet_mm`. Each mark's places once (two parts of one run may meet the
/// path at the same place); sorted along x.
pub(super) fn crossings(
    path: &Stroke,
    left_out: &mut [(&Stroke, LeftOut)],
    lk: &LinkParams,
) -> Vec<Crossing> {
    let pts = &path.points_mm;
    let n = pts.len();
    if n < 2 {
        return Vec::new();
    }
    let segs = if path.closed { n } else { n - 1 };
    let mut grid: Grid<usize> = Grid::new(lk.run_meet_mm);
    for i in 0..segs {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        grid.insert([0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])], i);
    }
    let seg = |i: usize| (pts[i], pts[(i + 1) % n]);
    let mut out: Vec<Crossing> = Vec::new();
    for (k, (s, o)) in left_out.iter_mut().enumerate() {
        if o.length_mm < lk.min_mark_mm {
            continue;
        }
        let mut meets: Vec<[f64; 2]> = Vec::new();
        let mut add = |at: [f64; 2]| {
            if meets.iter().all(|c| dist(*c, at) > lk.run_same_mm) {
                meets.push(at);
            }
        };
        let q = &s.points_mm;
        let m = q.len();
        if m < 2 {
            continue;
        }
        let qsegs = if s.closed { m } else { m - 1 };
        for j in 0..qsegs {
            let (c, d) = (q[j], q[(j + 1) % m]);
            let mid = [0.5 * (c[0] + d[0]), 0.5 * (c[1] + d[1])];
            let reach = dist(c, d) + 1.0;
            let mut nearest: Option<[f64; 2]> = None;
            for (_, i) in grid.around(mid, reach) {
                let (a, b) = seg(*i);
                if let Some(x) = intersect(a, b, c, d) {
                    add(x);
                }
                let f = foot(c, a, b);
                if nearest.is_none_or(|n| dist(c, f) < dist(c, n)) {
                    nearest = Some(f);
                }
            }
            // Touching without crossing: where the tracker joined a half of each run at their
            // crossing, the rest of the two runs touches the path there.
            if let Some(f) = nearest.filter(|f| dist(c, *f) <= lk.run_touch_mm) {
                add(f);
            }
        }
        if !s.closed {
            for e in [q[0], q[m - 1]] {
                let near = grid
                    .around(e, lk.run_meet_mm + 1.0)
                    .map(|(_, i)| {
                        let (a, b) = seg(*i);
                        foot(e, a, b)
                    })
                    .min_by(|x, y| dist(e, *x).total_cmp(&dist(e, *y)));
                if let Some(f) = near.filter(|f| dist(e, *f) <= lk.run_meet_mm) {
                    add(f);
                }
            }
        }
        let apart = meets
            .iter()
            .any(|a| meets.iter().any(|b| dist(*a, *b) >= lk.run_apart_mm));
        if meets.is_empty() || !(o.could_be_path() || apart) {
            continue;
        }
        if !o.could_be_path() {
            o.kind = LeftOutKind::Separate;
        }
        out.extend(meets.into_iter().map(|at| Crossing {
            at_mm: at,
            other: k,
        }));
    }
    out.sort_by(|a, b| a.at_mm[0].total_cmp(&b.at_mm[0]));
    out
}

/// The point where segments `a`-`b` and `c`-`d` cross, if they do.
fn intersect(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> Option<[f64; 2]> {
    let r = [b[0] - a[0], b[1] - a[1]];
    let s = [d[0] - c[0], d[1] - c[1]];
    let den = r[0] * s[1] - r[1] * s[0];
    if den.abs() < 1e-12 {
        return None;
    }
    let w = [c[0] - a[0], c[1] - a[1]];
    let t = (w[0] * s[1] - w[1] * s[0]) / den;
    let u = (w[0] * r[1] - w[1] * r[0]) / den;
    ((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u))
        .then(|| [a[0] + t * r[0], a[1] + t * r[1]])
}

/// The point of segment `a`-`b` nearest `p`.
fn foot(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    let d = [b[0] - a[0], b[1] - a[1]];
    let l2 = d[0] * d[0] + d[1] * d[1];
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    [a[0] + t * d[0], a[1] + t * d[1]]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stroke(points_mm: Vec<[f64; 2]>, closed: bool) -> Stroke {
        Stroke {
            points_mm,
            closed,
            bridged_mm: 0.0,
        }
    }

    #[test]
    fn a_second_run_across_the_path_crosses_it_where_it_does() {
        let lk = &LinkParams::default();
        let path = stroke((0..=100).map(|i| [i as f64, 0.0]).collect(), false);
        let other = stroke((0..=40).map(|i| [30.0, i as f64 - 20.5]).collect(), false);
        let o = LeftOut {
            from_mm: [30.0, -20.5],
            to_mm: [30.0, 19.5],
            length_mm: 40.0,
            kind: LeftOutKind::Separate,
        };
        let x = crossings(&path, &mut [(&other, o.clone())], lk);
        assert_eq!(x.len(), 1, "{x:?}");
        assert!(dist(x[0].at_mm, [30.0, 0.0]) < 1e-9, "{x:?}");
        // A mark across the path once (a pencil stroke across it) is not a second run.
        let mark = LeftOut {
            kind: LeftOutKind::Mark,
            ..o.clone()
        };
        let mut marks = [(&other, mark.clone())];
        assert!(crossings(&path, &mut marks, lk).is_empty());
        assert_eq!(marks[0].1.kind, LeftOutKind::Mark);
        // An arc from one place on the path to another, stopped by the tracker 1 mm short of
        // it at both ends: a second run, met at both places.
        let arc = stroke(
            (0..=60)
                .map(|i| {
                    let a = std::f64::consts::PI * i as f64 / 60.0;
                    [50.0 - 20.0 * a.cos(), 1.0 + 20.0 * a.sin()]
                })
                .collect(),
            false,
        );
        let mut arcs = [(&arc, mark)];
        let x = crossings(&path, &mut arcs, lk);
        assert_eq!(x.len(), 2, "{x:?}");
        assert!(dist(x[0].at_mm, [30.0, 0.0]) < 1e-9, "{x:?}");
        assert!(dist(x[1].at_mm, [70.0, 0.0]) < 1e-9, "{x:?}");
        assert_eq!(arcs[0].1.kind, LeftOutKind::Separate);
    }
}
