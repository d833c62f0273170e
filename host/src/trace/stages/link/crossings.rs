//! Where another mark touches the path, the path's centres were pulled towards it: that stretch
//! is replaced by a bridge between the undisturbed sides ([`cut_crossings`]).

use super::bridge::bridge;
use super::end::end_with;
use super::params::LinkParams;
use super::strokes::Strokes;
use super::Gap;
use crate::trace::chain::{polyline_length, Stroke};
use crate::trace::plane::dist;

/// Where another mark touches the path (a stroke crossing it, whether the tracker cut it or the
/// path there), the path's centroids were pulled towards it: the path within `LinkParams::cross_cut_mm`
/// of every place where another mark comes within `LinkParams::cross_touch_mm` is replaced by a bridge
/// between the undisturbed sides (a stretch longer than `LinkParams::cross_max_mm`, a mark running along
/// the path, is kept).
pub(super) fn cut_crossings(
    path: Stroke,
    mask: Vec<bool>,
    marks: &[&[[f64; 2]]],
    gaps: &mut Vec<Gap>,
    strokes: Strokes,
    lk: &LinkParams,
) -> (Stroke, Vec<bool>) {
    let pts = &path.points_mm;
    let n = pts.len();
    if n < 8 {
        return (path, mask);
    }
    let cell = lk.cross_cut_mm;
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
                        if d <= lk.cross_touch_mm && best.is_none_or(|(_, bd)| d < bd) {
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
                        if dist(pts[k], c) <= lk.cross_cut_mm {
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
        if polyline_length(&pts[i..=j], false) > lk.cross_max_mm {
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
            end_with(&out, lk.pulled_end_mm, strokes, lk),
            end_with(&after, lk.pulled_end_mm, strokes, lk),
            after.is_empty(),
        ) {
            let (inner, len) = bridge(&a, &b, lk);
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
