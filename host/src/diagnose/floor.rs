//! The floor the final residual is judged against (FORMATS.md `diagnose --instrument-mm`):
//! an independent one when known, the residual itself only as the last resort.
//!
//! * **instrument**: the one-sigma accuracy per coordinate of the measuring instrument, given by
//!   the user (`--instrument-mm`); known exactly.
//! * **repeatability**: the pooled per-coordinate standard deviation of the poses measured more
//!   than once (the same `id`, or the same joint readings within [`SAME_JOINTS_TOL`]):
//!   `sqrt(sum_groups sum_poses |p - mean_group|^2 / (dims (sum_groups (n_g - 1))))`, estimated
//!   with `dims (sum (n_g - 1))` degrees of freedom.
//! * **residual**: `sqrt(RSS / (m - p))` of the final fit, when neither is known; then the test
//!   cannot tell a missing effect from noise, and the output says so.
//!
//! The repeatability pools every pose measured more than once, in the calibration and the
//! held-out files together, and serves as a floor only with at least [`MIN_REPEAT_DOF`] degrees
//! of freedom ([`choose_floor`]; the ISO 9283 sequence repeats one pose: 3). The floor used is
//! the larger known one; the fallback is instrument > repeatability > residual, and
//! `floor.note` says which floors were known and why one was used. The final calibration residual is tested against it:
//! `RSS / sigma_floor^2` is chi-square with `(m - p) / tau` degrees of freedom (`tau` the
//! serial-correlation time along a traced path, 1 for independent poses) when the instrument
//! sets the floor, an F ratio with the repeatability's own degrees of freedom when the
//! repeatability does. The held-out residual is tested the same way
//! (`sum |e|^2 / (sigma_floor^2 (1 + p / n))` over `dims n_val` degrees of freedom, the factor
//! for the uncertainty of the fitted parameters).

use serde::Serialize;

use super::stat::f_test_p_value;
use crate::calib::MeasuredSet;

/// Joint readings that agree within this (deg, mm) are the same pose.
pub const SAME_JOINTS_TOL: f64 = 1e-6;
/// Significance level of the floor tests.
pub const FLOOR_ALPHA: f64 = 1e-3;
/// Fewest degrees of freedom of the pooled repeatability for it to serve as the floor: below
/// this its sigma is uncertain by more than about 20 % (relative standard error
/// `1 / sqrt(2 dof)`), e.g. the ISO 9283 sequence's single repeated pose gives 3.
pub const MIN_REPEAT_DOF: usize = 12;

/// The `floor` object of the diagnose JSON (FORMATS.md).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FloorReport {
    /// `--instrument-mm`, if given.
    pub instrument_mm: Option<f64>,
    /// Repeatability from repeated poses, if any.
    pub repeatability_mm: Option<f64>,
    /// One sigma per coordinate of the final calibration residual (mm).
    pub residual_mm: f64,
    /// `"instrument"`, `"repeatability"` or `"residual"`.
    pub used: String,
    /// `residual_mm` over the floor used.
    pub final_over_floor: f64,
    /// p-value of the calibration residual against the floor (extra key; null for the
    /// residual floor).
    pub p_value: Option<f64>,
    /// Held-out residual per coordinate (mm, extra key) and its ratio to the floor.
    pub validation_rms_mm: f64,
    /// `validation_rms_mm` over the floor used (extra key).
    pub validation_over_floor: f64,
    /// p-value of the held-out residual against the floor (extra key; null for the residual
    /// floor).
    pub validation_p_value: Option<f64>,
    /// Whether the residual is significantly above a known floor (extra key).
    pub above: bool,
    /// Degrees of freedom of the pooled repeatability (extra key; null without repeats).
    pub repeatability_dof: Option<usize>,
    /// Why this floor was used (extra key): which floors were known, the repeatability's degrees
    /// of freedom, and the fallback taken (instrument > repeatability > residual).
    pub note: String,
}

/// The floor to use and why: the instrument's and the repeatability's (when it has at least
/// [`MIN_REPEAT_DOF`] degrees of freedom), the larger when both are known; the residual only
/// without either. Returns `(used, sigma_mm, dof of an estimated floor, note)`;
/// `sigma_mm` is `None` for the residual.
pub fn choose_floor(
    instrument_mm: Option<f64>,
    repeat: Option<(f64, usize)>,
) -> (&'static str, Option<f64>, Option<usize>, String) {
    let instrument = instrument_mm.filter(|s| *s > 0.0 && s.is_finite());
    let rep = repeat.filter(|(s, _)| *s > 0.0 && s.is_finite());
    let rep_text = |(r, d): (f64, usize)| {
        format!("repeatability {r:.4} mm per coordinate from {d} degrees of freedom (poses measured more than once, pooled)")
    };
    let usable = rep.filter(|(_, d)| *d >= MIN_REPEAT_DOF);
    let too_few = rep.filter(|(_, d)| *d < MIN_REPEAT_DOF).map(|x| {
        format!(
            "{} is too uncertain to be a floor (needs >= {MIN_REPEAT_DOF} degrees of freedom: measure more poses more than once)",
            rep_text(x)
        )
    });
    match (instrument, usable) {
        (Some(i), Some((r, d))) if r > i => (
            "repeatability",
            Some(r),
            Some(d),
            format!(
                "{} is above the instrument's {i:.4} mm: the robot's own repeatability is the floor",
                rep_text((r, d))
            ),
        ),
        (Some(i), _) => {
            let other = match (usable, &too_few) {
                (Some(x), _) => format!("; {} is below it", rep_text(x)),
                (None, Some(t)) => format!("; {t}"),
                (None, None) => "; no pose measured more than once".to_string(),
            };
            ("instrument", Some(i), None, format!("the instrument's {i:.4} mm (--instrument-mm){other}"))
        }
        (None, Some((r, d))) => (
            "repeatability",
            Some(r),
            Some(d),
            format!("{} (no --instrument-mm)", rep_text((r, d))),
        ),
        (None, None) => (
            "residual",
            None,
            None,
            match too_few {
                Some(t) => format!("no --instrument-mm, and the {t}: the floor falls back to the residual itself"),
                None => "no --instrument-mm and no pose measured more than once: the floor falls back to the residual itself".to_string(),
            },
        ),
    }
}

/// Pooled repeatability (mm per coordinate) and its degrees of freedom, from the poses of
/// `data` measured more than once; `None` without repeated poses.
pub fn repeatability_mm(data: &MeasuredSet) -> Option<(f64, usize)> {
    let groups = repeat_groups(data);
    let dims = data.measured_dims();
    let (mut ss, mut dof) = (0.0, 0usize);
    for idx in &groups {
        let mean = idx
            .iter()
            .map(|&k| data.poses.xyz_mm[k])
            .sum::<nalgebra::Vector3<f64>>()
            / idx.len() as f64;
        for &k in idx {
            let d = data.measured_part(k, &(data.poses.xyz_mm[k] - mean));
            ss += d.norm_squared();
        }
        dof += dims * (idx.len() - 1);
    }
    (dof > 0).then(|| ((ss / dof as f64).sqrt(), dof))
}

/// The poses measured more than once, each group in file order: a pose that is no member yet
/// opens a group, which takes every later pose that is no member yet and has its `id` (not
/// empty) or its joint readings within [`SAME_JOINTS_TOL`] ([`same_pose`]).
///
/// In `O(n log n)` for distinct poses: the candidates for the same joint readings are found in
/// the poses sorted by a weighted sum of their readings (two poses within the tolerance on every
/// joint are within the tolerance times the sum of the weights there), the same ids by a map.
fn repeat_groups(data: &MeasuredSet) -> Vec<Vec<usize>> {
    let n = data.len();
    let q = &data.poses.q_deg;
    // weights in [1, 2), unequal, so that distinct poses rarely share a key
    let weight = |j: usize| 1.0 + (j as f64 * 0.618_033_988_749_895).fract();
    let key = |k: usize| -> f64 { q[k].iter().enumerate().map(|(j, x)| weight(j) * x).sum() };
    let keys: Vec<f64> = (0..n).map(key).collect();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| keys[a].total_cmp(&keys[b]));
    let sorted: Vec<f64> = order.iter().map(|&k| keys[k]).collect();
    let mut by_id: std::collections::HashMap<&str, Vec<usize>> = std::collections::HashMap::new();
    if let Some(ids) = &data.ids {
        for (k, id) in ids.iter().enumerate().take(n) {
            if !id.is_empty() {
                by_id.entry(id.as_str()).or_default().push(k);
            }
        }
    }
    let mut member = vec![false; n];
    // `taken[k] == i + 1`: pose k is already among the members of the group pose i opens
    let mut taken = vec![0usize; n];
    let mut groups = Vec::new();
    for i in 0..n {
        if member[i] {
            continue;
        }
        let mut members = vec![i];
        taken[i] = i + 1;
        let id = data
            .ids
            .as_ref()
            .and_then(|ids| ids.get(i))
            .filter(|id| !id.is_empty());
        if let Some(same) = id.and_then(|id| by_id.get(id.as_str())) {
            for &k in same.iter().filter(|&&k| k > i && !member[k]) {
                taken[k] = i + 1;
                members.push(k);
            }
        }
        // the tolerance through the key, plus the rounding of both sums
        let magnitude: f64 = q[i]
            .iter()
            .enumerate()
            .map(|(j, x)| weight(j) * x.abs())
            .sum();
        let reach = SAME_JOINTS_TOL * (0..q[i].len()).map(weight).sum::<f64>();
        let span = reach * (1.0 + 1e-9) + 16.0 * f64::EPSILON * (magnitude + reach);
        let lo = sorted.partition_point(|&v| v < keys[i] - span);
        for &k in order[lo..]
            .iter()
            .take_while(|&&k| keys[k] <= keys[i] + span)
        {
            if k > i && !member[k] && taken[k] != i + 1 && same_pose(data, i, k) {
                taken[k] = i + 1;
                members.push(k);
            }
        }
        if members.len() > 1 {
            members.sort_unstable();
            for &m in &members {
                member[m] = true;
            }
            groups.push(members);
        }
    }
    groups
}

/// [`repeatability_mm`] pooled over several files (calibration and held out): a pose id names
/// the same pose only within its own file; across files, the same joint readings do.
pub fn repeatability_of_files(sets: &[&MeasuredSet]) -> Option<(f64, usize)> {
    let mut merged: Option<MeasuredSet> = None;
    for (f, d) in sets.iter().enumerate() {
        let mut d = (*d).clone();
        let ids: Vec<String> = (0..d.len())
            .map(|k| {
                d.ids
                    .as_ref()
                    .and_then(|ids| ids.get(k))
                    .filter(|id| !id.is_empty())
                    .map_or_else(String::new, |id| format!("{f}:{id}"))
            })
            .collect();
        d.ids = Some(ids);
        merged = Some(match merged {
            Some(m) => m.concat(d),
            None => d,
        });
    }
    repeatability_mm(&merged?)
}

fn same_pose(data: &MeasuredSet, a: usize, b: usize) -> bool {
    if let Some(ids) = &data.ids {
        if let (Some(x), Some(y)) = (ids.get(a), ids.get(b)) {
            if !x.is_empty() && x == y {
                return true;
            }
        }
    }
    let (qa, qb) = (&data.poses.q_deg[a], &data.poses.q_deg[b]);
    qa.len() == qb.len()
        && qa
            .iter()
            .zip(qb)
            .all(|(x, y)| (x - y).abs() <= SAME_JOINTS_TOL)
}

/// Upper tail `P(X > x)` of a chi-square variable with `dof` degrees of freedom
/// (Wilson-Hilferty cube-root normal approximation; accurate to a few 1e-3 in p for dof >= 10,
/// which is all the floor tests use).
pub fn chi2_upper_p(x: f64, dof: f64) -> f64 {
    if dof.is_nan() || dof <= 0.0 || !x.is_finite() {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 1.0;
    }
    let v = 2.0 / (9.0 * dof);
    let z = ((x / dof).cbrt() - (1.0 - v)) / v.sqrt();
    0.5 * erfc(z / std::f64::consts::SQRT_2)
}

/// Complementary error function (Numerical Recipes' Chebyshev fit, relative error < 1.2e-7).
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.26551223
            + t * (1.00002368
                + t * (0.37409196
                    + t * (0.09678418
                        + t * (-0.18628806
                            + t * (0.27886807
                                + t * (-1.13520398
                                    + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// What [`judge`] needs of the final fit.
#[derive(Debug, Clone, Copy)]
pub struct FinalResidual {
    /// Calibration residual sum of squares (mm^2).
    pub rss_mm2: f64,
    /// Number of calibration residuals.
    pub n_residuals: usize,
    /// Number of fitted unknowns.
    pub n_params: usize,
    /// Serial-correlation time (1 for independent poses).
    pub tau: f64,
    /// Number of calibration poses.
    pub n_poses: usize,
    /// Held-out sum of squared errors (mm^2) and number of held-out residuals.
    pub val_ss_mm2: f64,
    /// Number of held-out residuals.
    pub val_residuals: usize,
}

/// The floor report of a final fit `r`, with the instrument sigma and repeatability when known.
pub fn judge(
    r: &FinalResidual,
    instrument_mm: Option<f64>,
    repeat: Option<(f64, usize)>,
) -> FloorReport {
    let dof = r.n_residuals.saturating_sub(r.n_params).max(1) as f64;
    let residual_mm = (r.rss_mm2 / dof).sqrt();
    let tau = r.tau.max(1.0);
    let inflation = 1.0 + r.n_params as f64 / r.n_residuals.max(1) as f64;
    let val_dof = r.val_residuals.max(1) as f64;
    let validation_rms_mm = (r.val_ss_mm2 / val_dof).sqrt();
    let instrument = instrument_mm.filter(|s| *s > 0.0 && s.is_finite());
    let rep = repeat.filter(|(s, _)| *s > 0.0);
    let (used, floor, floor_dof, note) = choose_floor(instrument, rep);
    let floor = floor.unwrap_or(residual_mm);
    let floor_dof = floor_dof.map(|d| d as f64);
    let test = |ss: f64, d: f64| -> f64 {
        let stat = ss / (floor * floor);
        match floor_dof {
            // the floor is itself an estimate: F ratio of the two variances
            Some(d2) => f_test_p_value(stat / d, d, d2),
            None => chi2_upper_p(stat, d),
        }
    };
    let (p, vp) = if used == "residual" {
        (None, None)
    } else {
        (
            Some(test(r.rss_mm2 / tau, dof / tau)),
            Some(test(r.val_ss_mm2 / inflation, val_dof)),
        )
    };
    let above = p.is_some_and(|p| p < FLOOR_ALPHA) || vp.is_some_and(|p| p < FLOOR_ALPHA);
    FloorReport {
        instrument_mm: instrument,
        repeatability_mm: rep.map(|r| r.0),
        residual_mm,
        used: used.to_string(),
        final_over_floor: residual_mm / floor,
        p_value: p,
        validation_rms_mm,
        validation_over_floor: validation_rms_mm / floor,
        validation_p_value: vp,
        above,
        repeatability_dof: rep.map(|r| r.1),
        note,
    }
}

#[cfg(test)]
mod tests;
