//! What may continue a drawn line past its ends: paths running its way ahead of an end of a
//! band line ([`judge_ends`]), and whether a mark beyond a pass's free end counts against the
//! line ([`counts`]).

use super::super::link::{LeftOut, LeftOutKind};
use super::params::LinesParams;
use super::{abs_cos, arc, directions, DrawnLine, Loose};
use crate::trace::band::{Cloud, Source};
use crate::trace::paths::DrawnPath;
use crate::trace::plane::{dist, sub};
use std::collections::HashSet;

/// What may continue an open band line at its ends: a path (its points not in the line's band,
/// nor where it is a pass of a line running across, `across_here(path, point, direction)`)
/// running its way ahead of an end, within `max(2 x max_gap_mm, 15 mm)` and `LinesParams::across_deg` of the
/// end's direction (anything running its way nearer, within `--max-gap-mm` and the band, the
/// walk has taken; farther, to a path, it is a missing gap).
pub(super) fn judge_ends(
    line: &mut DrawnLine,
    taken: &HashSet<usize>,
    cloud: &Cloud,
    paths: &[DrawnPath],
    max_gap_mm: f64,
    across_here: &dyn Fn(usize, [f64; 2], [f64; 2]) -> bool,
    lp: &LinesParams,
) {
    if line.closed {
        return;
    }
    let reach = (2.0 * max_gap_mm).max(15.0);
    let cos_along = lp.band_deg.to_radians().cos();
    let cos_cone = lp.across_deg.to_radians().cos();
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
/// only when it lies ahead on the line's axis (off it by at most `LinesParams::alongside_mm` + 10 % of
/// the distance), and not when it runs across the line within `max_gap_mm` of the end (the
/// line ends on another line).
pub(super) fn counts(
    l: &Loose,
    passes: &[usize],
    axis: Option<[f64; 2]>,
    max_gap_mm: f64,
    lp: &LinesParams,
) -> bool {
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
    if off_axis > lp.alongside_mm + 0.1 * d {
        return false;
    }
    if l.path.is_none() || l.mark.len() < 2 {
        return true;
    }
    let dirs = directions(&l.mark, &arc(&l.mark), lp);
    let across = abs_cos(dirs[k], u) < lp.across_deg.to_radians().cos();
    !(across && d <= max_gap_mm.max(lp.alongside_mm))
}
