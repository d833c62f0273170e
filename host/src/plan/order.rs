//! The planned poses in an order that keeps the joint travel short, with every segment between
//! consecutive poses checked: nearest neighbour from the pose closest to the home
//! configuration, then 2-opt on the open path, on the weighted joint distance
//! `sum_j w_j |q_j - q'_j|` (deg; mm for prismatic joints). Each segment is the straight line in
//! joint space, checked at configurations at most `step_deg` apart in every joint
//! ([`Workspace::violation`]); a segment that is not safe is barred and the order searched
//! again, or taken through a via configuration (home, else mid-range, when safe) when both
//! halves are safe; a pose whose every ordering keeps an unsafe segment is dropped.

use std::collections::HashMap;

use rand::seq::SliceRandom;
use rand::SeedableRng;

use super::candidates::CandidatePose;
use super::collision::home_configuration;
use super::workspace::Workspace;
use super::PlanError;
use crate::model::{Model, Tilt};

/// Default largest joint step between the checked configurations of a segment, deg (mm).
pub const DEFAULT_STEP_DEG: f64 = 1.0;

/// Between two checked configurations of a segment the links may always move this far, mm
/// (with a clearance below it, a move within it is not checked in between).
const MIN_MOVE_MM: f64 = 1.0;

/// Cost of a barred segment (it is only taken when nothing else is left).
const BARRED: f64 = 1e12;

/// Searches of the order before poses are dropped.
const MAX_SEARCHES: usize = 300;

/// An ordered plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Ordered {
    /// The poses kept, as indices into the given poses, in the order to visit.
    pub order: Vec<usize>,
    /// Weighted joint travel along that order, deg.
    pub travel_deg: f64,
    /// The mean travel of 100 random orders of the same poses, deg.
    pub random_travel_deg: f64,
    /// Segments checked and configurations checked along them.
    pub segments_checked: usize,
    pub configurations_checked: usize,
    /// Of the segments checked, those found unsafe (barred from the order).
    pub segments_unsafe: usize,
    /// The joint step of the check, deg (mm).
    pub step_deg: f64,
    /// Poses dropped (index) because every order left an unsafe segment to them, and why.
    pub dropped: Vec<(usize, String)>,
    /// Per position in `order`: the way to it goes through [`Ordered::via_q`] (its straight
    /// segment is not safe).
    pub via_before: Vec<bool>,
    /// The via configuration (deg), when a segment uses it.
    pub via_q: Option<Vec<f64>>,
    /// Without collision geometry (the joint frames' origins stand in for the links, which is
    /// not exact): the moves of the order that leave the safe space on the straight way and have
    /// no safe way through the via configuration, as `(from, to, why)` positions in `order`.
    /// They are kept and said, not dropped: the plan's moves are then not verified. Empty
    /// with collision geometry (such a pose is dropped instead).
    pub unsafe_left: Vec<(usize, usize, String)>,
}

/// Weighted joint distance.
pub fn joint_distance(a: &[f64], b: &[f64], w: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .zip(w)
        .map(|((x, y), w)| w * (x - y).abs())
        .sum()
}

/// Travel along `order` of `q`.
pub fn travel(q: &[Vec<f64>], order: &[usize], w: &[f64]) -> f64 {
    order
        .windows(2)
        .map(|p| joint_distance(&q[p[0]], &q[p[1]], w))
        .sum()
}

/// Why the straight joint-space segment `a -> b` is not safe, checked at configurations at
/// most `step` apart in every joint (the ends excluded: they are checked as poses), and, with
/// collision geometry, between any two checked configurations no link moving farther than the
/// distance it keeps, at least
/// [`MIN_MOVE_MM`] (the interval halved until so); and how many configurations were checked.
pub fn segment_violation(
    model: &Model,
    ws: &Workspace,
    a: &[f64],
    b: &[f64],
    step: f64,
) -> Result<(Option<String>, usize), PlanError> {
    let span = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    let k = (span / step).ceil().max(1.0) as usize;
    let at = |t: f64| -> Vec<f64> { a.iter().zip(b).map(|(x, y)| x + (y - x) * t).collect() };
    let mut checked = 0;
    let mut check = |t: f64| -> Result<Option<String>, PlanError> {
        checked += 1;
        let q = at(t);
        let p = model.position_mm(&q, Tilt::Off)?;
        Ok(ws
            .path_violation(model, &q, &p)?
            .map(|why| format!("at {:.0} % of the way: {why}", 100.0 * t)))
    };
    for s in 1..k {
        if let Some(why) = check(s as f64 / k as f64)? {
            return Ok((Some(why), checked));
        }
    }
    // the intervals between checked configurations, halved while a link may move farther
    // than the distance it keeps (so that no contact hides between two checks)
    let mut ts: Vec<f64> = (0..=k).map(|s| s as f64 / k as f64).collect();
    let mut i = 0;
    while i + 1 < ts.len() {
        let (t0, t1) = (ts[i], ts[i + 1]);
        let too_far = ws
            .path_motion_mm(&at(t0), &at(t1))
            .is_some_and(|(kept, moved)| moved > kept.max(MIN_MOVE_MM) && t1 - t0 > 1e-9);
        if too_far {
            let m = 0.5 * (t0 + t1);
            if let Some(why) = check(m)? {
                return Ok((Some(why), checked));
            }
            ts.insert(i + 1, m);
        } else {
            i += 1;
        }
    }
    Ok((None, checked))
}

/// Nearest neighbour from `start`, then 2-opt, on `cost` over the poses `alive`.
fn search(alive: &[usize], start: usize, cost: &dyn Fn(usize, usize) -> f64) -> Vec<usize> {
    let mut left: Vec<usize> = alive.iter().copied().filter(|&i| i != start).collect();
    let mut path = vec![start];
    while !left.is_empty() {
        let last = path[path.len() - 1];
        let (k, _) = left
            .iter()
            .enumerate()
            .map(|(k, &i)| (k, cost(last, i)))
            .fold((0, f64::INFINITY), |b, c| if c.1 < b.1 { c } else { b });
        path.push(left.swap_remove(k));
    }
    // 2-opt on the open path: reverse path[i..=j]
    let n = path.len();
    let mut improved = true;
    let mut passes = 0;
    while improved && passes < 200 {
        improved = false;
        passes += 1;
        for i in 1..n {
            for j in i + 1..n {
                let before = cost(path[i - 1], path[i])
                    + if j + 1 < n {
                        cost(path[j], path[j + 1])
                    } else {
                        0.0
                    };
                let after = cost(path[i - 1], path[j])
                    + if j + 1 < n {
                        cost(path[i], path[j + 1])
                    } else {
                        0.0
                    };
                if after < before - 1e-9 {
                    path[i..=j].reverse();
                    improved = true;
                }
            }
        }
    }
    path
}

/// A checked segment between two poses.
#[derive(Debug, Clone, PartialEq)]
enum Edge {
    /// The straight segment is safe.
    Direct,
    /// Not straight, but through the via configuration (both halves safe).
    Via,
    /// Neither: why the straight one is not.
    Barred(String),
}

/// The via configuration: home ([`home_configuration`]), else mid-range, when it is safe.
fn via_configuration(model: &Model, ws: &Workspace) -> Result<Option<Vec<f64>>, PlanError> {
    let mid: Vec<f64> = model
        .joint_limits()
        .iter()
        .map(|l| {
            let (lo, hi) = ws.usable_range(l);
            0.5 * (lo + hi)
        })
        .collect();
    for q in [home_configuration(model), mid] {
        let p = model.position_mm(&q, Tilt::Off)?;
        let inside = q.iter().zip(model.joint_limits()).all(|(v, l)| {
            let (lo, hi) = ws.usable_range(&l);
            *v >= lo && *v <= hi
        });
        if inside && ws.path_violation(model, &q, &p)?.is_none() {
            return Ok(Some(q));
        }
    }
    Ok(None)
}

/// Orders `poses` (see the module docs) with joint weights `w`, checking every segment at
/// `step_deg`; a pair whose straight segment is unsafe may go through the via configuration
/// (home, else mid-range, when safe) when both halves are safe.
pub fn order_poses(
    model: &Model,
    ws: &Workspace,
    poses: &[CandidatePose],
    w: &[f64],
    step_deg: f64,
) -> Result<Ordered, PlanError> {
    if !(step_deg.is_finite() && step_deg > 0.0) {
        return Err(PlanError::Config(format!(
            "--segment-step-deg {step_deg}: a positive number"
        )));
    }
    // with collision geometry an unsafe way drops the pose; without it, it is said
    let strict = ws.collision.is_some();
    let q: Vec<Vec<f64>> = poses.iter().map(|p| p.q_deg.clone()).collect();
    let n = q.len();
    let home = home_configuration(model);
    let via = via_configuration(model, ws)?;
    let mut to_via: HashMap<usize, bool> = HashMap::new();
    let mut checked: HashMap<(usize, usize), Edge> = HashMap::new();
    let (mut segments, mut configs, mut unsafe_segments) = (0, 0, 0);
    let mut alive: Vec<usize> = (0..n).collect();
    let mut dropped = Vec::new();
    let mut order = Vec::new();
    let via_cost = |a: usize, b: usize| match &via {
        Some(v) => joint_distance(&q[a], v, w) + joint_distance(v, &q[b], w),
        None => f64::INFINITY,
    };
    while !alive.is_empty() {
        let start = *alive
            .iter()
            .min_by(|&&a, &&b| {
                joint_distance(&q[a], &home, w).total_cmp(&joint_distance(&q[b], &home, w))
            })
            .unwrap_or(&0);
        let mut bad: Option<(usize, String)> = None;
        for _ in 0..MAX_SEARCHES {
            let cost = |a: usize, b: usize| {
                let d = joint_distance(&q[a], &q[b], w);
                match checked.get(&(a.min(b), a.max(b))) {
                    None | Some(Edge::Direct) => d,
                    Some(Edge::Via) => via_cost(a, b),
                    Some(Edge::Barred(_)) => d + BARRED,
                }
            };
            order = search(&alive, start, &cost);
            bad = None;
            for p in order.windows(2) {
                let key = (p[0].min(p[1]), p[0].max(p[1]));
                if let std::collections::hash_map::Entry::Vacant(slot) = checked.entry(key) {
                    let (why, c) = segment_violation(model, ws, &q[p[0]], &q[p[1]], step_deg)?;
                    segments += 1;
                    configs += c;
                    let edge = match why {
                        None => Edge::Direct,
                        Some(why) => {
                            unsafe_segments += 1;
                            let mut both = via.is_some();
                            for k in [p[0], p[1]] {
                                if !both {
                                    break;
                                }
                                if let (Some(v), None) = (&via, to_via.get(&k)) {
                                    let (w2, c2) =
                                        segment_violation(model, ws, &q[k], v, step_deg)?;
                                    segments += 1;
                                    configs += c2;
                                    to_via.insert(k, w2.is_none());
                                }
                                both = to_via.get(&k).copied().unwrap_or(false);
                            }
                            if both {
                                Edge::Via
                            } else {
                                Edge::Barred(why)
                            }
                        }
                    };
                    slot.insert(edge);
                }
                if let Some(Edge::Barred(why)) = checked.get(&key) {
                    bad = bad.or(Some((p[1], why.clone())));
                }
            }
            if bad.is_none() || !strict {
                break;
            }
        }
        if !strict {
            bad = None;
        }
        match bad {
            None => break,
            Some((k, why)) => {
                alive.retain(|&i| i != k);
                dropped.push((k, why));
                order.clear();
            }
        }
    }
    let via_before: Vec<bool> = (0..order.len())
        .map(|k| {
            k > 0
                && checked.get(&(order[k - 1].min(order[k]), order[k - 1].max(order[k])))
                    == Some(&Edge::Via)
        })
        .collect();
    let travel_deg = order
        .windows(2)
        .zip(via_before.iter().skip(1))
        .map(|(p, v)| {
            if *v {
                via_cost(p[0], p[1])
            } else {
                joint_distance(&q[p[0]], &q[p[1]], w)
            }
        })
        .sum();
    let unsafe_left: Vec<(usize, usize, String)> = order
        .windows(2)
        .enumerate()
        .filter_map(
            |(k, p)| match checked.get(&(p[0].min(p[1]), p[0].max(p[1]))) {
                Some(Edge::Barred(why)) => Some((k, k + 1, why.clone())),
                _ => None,
            },
        )
        .collect();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut shuffled = order.clone();
    let random_travel_deg = (0..100)
        .map(|_| {
            shuffled.shuffle(&mut rng);
            travel(&q, &shuffled, w)
        })
        .sum::<f64>()
        / 100.0;
    Ok(Ordered {
        travel_deg,
        random_travel_deg,
        order,
        segments_checked: segments,
        segments_unsafe: unsafe_segments,
        configurations_checked: configs,
        step_deg,
        dropped,
        via_q: via.filter(|_| via_before.iter().any(|v| *v)),
        via_before,
        unsafe_left,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_opt_untangles_a_line() {
        // points on a line visited in a scrambled order: the search finds the monotone path
        let q: Vec<Vec<f64>> = [0.0, 5.0, 1.0, 4.0, 2.0, 3.0]
            .iter()
            .map(|v| vec![*v])
            .collect();
        let w = [1.0];
        let cost = |a: usize, b: usize| joint_distance(&q[a], &q[b], &w);
        let p = search(&[0, 1, 2, 3, 4, 5], 0, &cost);
        assert_eq!(travel(&q, &p, &w), 5.0);
        // a barred edge is avoided when another order exists
        let barred = |a: usize, b: usize| {
            let base = joint_distance(&q[a], &q[b], &w);
            if (a.min(b), a.max(b)) == (2, 4) {
                base + BARRED
            } else {
                base
            }
        };
        let p = search(&[0, 1, 2, 3, 4, 5], 0, &barred);
        assert!(p
            .windows(2)
            .all(|e| (e[0].min(e[1]), e[0].max(e[1])) != (2, 4)));
    }
}
