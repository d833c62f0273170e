//! Bridges refitted from the graphite on both sides of each gap: one smooth curve (x and y
//! polynomials of the arc length) fitted to the written points before and after the gap, robust
//! to dust and pulled centroids (Tukey biweight), its window and degree chosen by the data
//! (leave-one-out residuals), then sampled across the gap. The bridge lies in the interior of
//! the fitted stretch, so its shape comes from both ends at once, not from two tangents
//! extrapolated over the gap. The least squares themselves are in `bridge_fit/least_squares.rs`;
//! the tuned numbers are [`LinkParams`]' `bridge_*`.

use super::plane::dist;
use super::stages::LinkParams;
use least_squares::weighted_fit;

mod least_squares;

/// Tukey biweight constant, in residual scales: the textbook value (95 % efficiency under
/// normal errors), not a tuned number.
const TUKEY_C: f64 = 4.685;

/// A point of the unrolled path: position, arc length, whether it is a bridge point.
#[derive(Clone, Copy)]
struct Node {
    p: [f64; 2],
    s: f64,
    bridge: bool,
}

/// A weighted polynomial fit of x(t) and y(t), t the arc length scaled to about [-1, 1].
struct Fit {
    cx: Vec<f64>,
    cy: Vec<f64>,
    s0: f64,
    half: f64,
    /// Mean squared leave-one-out residual (weighted), mm^2.
    press: f64,
}

impl Fit {
    fn at(&self, s: f64) -> [f64; 2] {
        let t = (s - self.s0) / self.half;
        [horner(&self.cx, t), horner(&self.cy, t)]
    }
}

fn horner(c: &[f64], t: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, v| acc * t + v)
}

/// Refits every run of bridge points of `pts` (`bridge[i]` marks them) from the written points
/// around it; returns the new polyline, its mask and the total bridge length, mm. A run with
/// too few written points around it keeps its points.
pub(crate) fn refine(
    pts: &[[f64; 2]],
    bridge: &[bool],
    closed: bool,
    lk: &LinkParams,
) -> (Vec<[f64; 2]>, Vec<bool>, f64) {
    let n = pts.len();
    let unchanged = || {
        let len = bridge_length(pts, bridge, closed);
        (pts.to_vec(), bridge.to_vec(), len)
    };
    if n < 4 || bridge.len() != n || !bridge.iter().any(|b| *b) || bridge.iter().all(|b| *b) {
        return unchanged();
    }
    // A closed path starts at a written point, so no run wraps around.
    let start = if closed {
        bridge.iter().position(|b| !b).unwrap_or(0)
    } else {
        0
    };
    let mut nodes: Vec<Node> = Vec::with_capacity(n);
    let mut s = 0.0;
    for k in 0..n {
        let i = (start + k) % n;
        if k > 0 {
            s += dist(nodes[k - 1].p, pts[i]);
        }
        nodes.push(Node {
            p: pts[i],
            s,
            bridge: bridge[i],
        });
    }
    let total = if closed {
        s + dist(nodes[n - 1].p, nodes[0].p)
    } else {
        s
    };
    // The node at unrolled index k (a closed path repeats around).
    let at = |k: isize| -> Option<Node> {
        if closed {
            let m = k.rem_euclid(n as isize) as usize;
            let turns = k.div_euclid(n as isize) as f64;
            let v = nodes[m];
            Some(Node {
                s: v.s + turns * total,
                ..v
            })
        } else if k >= 0 && (k as usize) < n {
            Some(nodes[k as usize])
        } else {
            None
        }
    };
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(n);
    let mut mask: Vec<bool> = Vec::with_capacity(n);
    let mut bridged = 0.0;
    let mut i = 0;
    while i < n {
        if !nodes[i].bridge {
            out.push(nodes[i].p);
            mask.push(false);
            i += 1;
            continue;
        }
        let mut j = i;
        while j + 1 < n && nodes[j + 1].bridge {
            j += 1;
        }
        let refit = run_fit(&at, (i as isize, j as isize), n, total, closed, lk);
        match refit {
            Some(points) => {
                let (a, b) = (at(i as isize - 1), at(j as isize + 1));
                let mut prev = a.map_or(points[0], |v| v.p);
                for p in &points {
                    bridged += dist(prev, *p);
                    prev = *p;
                }
                if let Some(b) = b {
                    bridged += dist(prev, b.p);
                }
                mask.extend(std::iter::repeat_n(true, points.len()));
                out.extend(points);
            }
            None => {
                out.extend(nodes[i..=j].iter().map(|v| v.p));
                mask.extend(std::iter::repeat_n(true, j + 1 - i));
                bridged += run_length(&at, i as isize, j as isize);
            }
        }
        i = j + 1;
    }
    (out, mask, bridged)
}

/// Length of the bridge run `i..=j` with its links to the written points on both sides.
fn run_length(at: &dyn Fn(isize) -> Option<Node>, i: isize, j: isize) -> f64 {
    let mut len = 0.0;
    for k in i - 1..=j {
        if let (Some(a), Some(b)) = (at(k), at(k + 1)) {
            len += dist(a.p, b.p);
        }
    }
    len
}

fn bridge_length(pts: &[[f64; 2]], bridge: &[bool], closed: bool) -> f64 {
    let n = pts.len();
    let segs = if closed { n } else { n.saturating_sub(1) };
    (0..segs)
        .filter(|&k| bridge.get(k) == Some(&true) || bridge.get((k + 1) % n) == Some(&true))
        .map(|k| dist(pts[k], pts[(k + 1) % n]))
        .sum()
}

/// The written points on one side of the run, walking outwards from unrolled index `from` by
/// `dir` (+1 / -1), until `side_mm` of written path is collected.
fn side_points(
    at: &dyn Fn(isize) -> Option<Node>,
    from: isize,
    dir: isize,
    side_mm: f64,
    limit: usize,
    walk_extra_mm: f64,
) -> Vec<Node> {
    let mut got = Vec::new();
    let Some(first) = at(from) else {
        return got;
    };
    let mut written = 0.0;
    let mut prev = first;
    let mut k = from;
    for _ in 0..limit {
        let Some(v) = at(k) else { break };
        if (v.s - first.s).abs() > side_mm + walk_extra_mm {
            break;
        }
        if !v.bridge {
            if !prev.bridge {
                written += (v.s - prev.s).abs();
            }
            got.push(v);
            if written >= side_mm {
                break;
            }
        }
        prev = v;
        k += dir;
    }
    got
}

/// The refitted points of the bridge run `i..=j` (unrolled indices), or `None` when the data
/// around it do not support a fit.
fn run_fit(
    at: &dyn Fn(isize) -> Option<Node>,
    (i, j): (isize, isize),
    n: usize,
    total: f64,
    closed: bool,
    lk: &LinkParams,
) -> Option<Vec<[f64; 2]>> {
    let (a, b) = (at(i - 1)?, at(j + 1)?);
    if a.bridge || b.bridge {
        return None;
    }
    // A closed path's two sides must not overlap.
    let limit = if closed { n / 2 } else { n };
    let mut best: Option<(Fit, f64)> = None;
    let mut first_press = None;
    if b.s - a.s > lk.bridge_max_refit_mm {
        return None;
    }
    let extra_mm = lk.bridge_walk_extra_mm;
    for side_mm in lk.bridge_side_mm {
        if closed && 2.0 * (side_mm + extra_mm) + (b.s - a.s) > total {
            break;
        }
        let before = side_points(at, i - 1, -1, side_mm, limit, extra_mm);
        let after = side_points(at, j + 1, 1, side_mm, limit, extra_mm);
        if before.len() < 6 || after.len() < 6 {
            continue;
        }
        let data: Vec<Node> = before.iter().rev().chain(after.iter()).copied().collect();
        let Some(fit) = best_degree(&data, lk) else {
            continue;
        };
        let base = *first_press.get_or_insert(fit.press);
        if fit.press > lk.bridge_wider_ok * lk.bridge_wider_ok * base {
            break;
        }
        best = Some((fit, side_mm));
    }
    let (fit, _) = best.filter(|(f, _)| f.press.sqrt() <= lk.bridge_max_residual_mm)?;
    let (s_a, s_b) = (a.s, b.s);
    let len = curve_length(&fit, s_a, s_b);
    let m = (len / lk.bridge_step_mm).ceil().max(1.0) as usize;
    let pts: Vec<[f64; 2]> = (1..m)
        .map(|k| fit.at(s_a + (s_b - s_a) * k as f64 / m as f64))
        .collect();
    let finite = pts.iter().all(|p| p[0].is_finite() && p[1].is_finite());
    (finite && !pts.is_empty()).then_some(pts)
}

fn curve_length(fit: &Fit, s_a: f64, s_b: f64) -> f64 {
    let m = 64;
    let mut prev = fit.at(s_a);
    let mut len = 0.0;
    for k in 1..=m {
        let p = fit.at(s_a + (s_b - s_a) * k as f64 / m as f64);
        len += dist(prev, p);
        prev = p;
    }
    len
}

/// The robust fit of the degree (1..=`bridge_max_degree`) with the smallest leave-one-out
/// residual.
fn best_degree(data: &[Node], lk: &LinkParams) -> Option<Fit> {
    let mut best: Option<Fit> = None;
    for deg in 1..=lk.bridge_max_degree {
        if data.len() < 3 * (deg + 1) {
            break;
        }
        if let Some(f) = robust_fit(data, deg, lk.bridge_min_scale_mm) {
            if best.as_ref().is_none_or(|b| f.press < b.press) {
                best = Some(f);
            }
        }
    }
    best
}

/// Iteratively reweighted least squares with Tukey's biweight on the 2-D residual.
fn robust_fit(data: &[Node], deg: usize, min_scale_mm: f64) -> Option<Fit> {
    let (lo, hi) = (data.first()?.s, data.last()?.s);
    let half = 0.5 * (hi - lo);
    if half <= 1e-9 {
        return None;
    }
    let s0 = 0.5 * (lo + hi);
    let ts: Vec<f64> = data.iter().map(|v| (v.s - s0) / half).collect();
    let mut w = vec![1.0; data.len()];
    let mut fit = None;
    for _ in 0..5 {
        let (cx, cy, press) = weighted_fit(data, &ts, &w, deg)?;
        let r: Vec<f64> = data
            .iter()
            .zip(&ts)
            .map(|(v, t)| (v.p[0] - horner(&cx, *t)).hypot(v.p[1] - horner(&cy, *t)))
            .collect();
        let mut sorted = r.clone();
        let mid = sorted.len() / 2;
        let (_, median, _) = sorted.select_nth_unstable_by(mid, f64::total_cmp);
        let scale = (1.4826 * *median).max(min_scale_mm);
        for (wi, ri) in w.iter_mut().zip(&r) {
            let u = ri / (TUKEY_C * scale);
            *wi = if u < 1.0 { (1.0 - u * u).powi(2) } else { 0.0 };
        }
        fit = Some(Fit {
            cx,
            cy,
            s0,
            half,
            press,
        });
    }
    fit
}

#[cfg(test)]
mod tests;
