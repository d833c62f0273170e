//! One verdict from the three residuals a diagnosis has: the final calibration residual, its
//! k-fold cross-validation, and the held-out set (JSON key `verdict`, the text's `floor:` line,
//! the report's first screen).
//!
//! Each is tested against the floor ([`super::floor`]): the calibration residual as there
//! (`RSS / sigma^2`, `(m - p) / tau` degrees of freedom); the cross-validated one (the physical
//! parameters refitted without each fold, [`super::probe::design::Design::physical_cv`])
//! as `SS_cv / (sigma^2 c)` over `m / tau` degrees of freedom, `c = (m + sum_g tr(N_g
//! N_{-g}^+)) / m` the exact inflation of a right model's held-out residuals by the
//! uncertainty of the parameters fitted without each fold
//! ([`super::probe::design::Design::physical_cv`]; leave-one-out up to
//! [`super::probe::design::LOO_MAX_POSES`] poses); the held-out one both as
//! `SS_val / sigma^2` and as `SS_val / (sigma^2 c_val)` over its `m_val` residuals, `c_val`
//! the same inflation at the held-out poses ([`prediction_inflation`]). A residual is
//! **above** when its p-value is below [`super::floor::FLOOR_ALPHA`]. Then, in this order:
//!
//! | calibration | cross-validation | held out | verdict |
//! |---|---|---|---|
//! | above | any | any | `missing_effect`: the model lacks something the calibration poses already show |
//! | at | above | any | `overfitting`: the parameters absorb errors of these poses that do not carry over |
//! | at | at | above, even with the parameters' uncertainty, which is small; at the floor once the fitted parameters may change on the held-out poses | `change_between_sets`: drift, another day, another tool mounting or base |
//! | at | at | above, even with the parameters' uncertainty, which is small; still above with the parameters changed | `missing_effect`: an error the calibration poses barely show and the held-out poses do, which no parameter change explains |
//! | at | at | above, the parameters' uncertainty alone lifting it by [`UNCERTAIN_PREDICTION_RATIO`] or more | `overfitting` |
//! | at | at | above the floor, not above it with the parameters' uncertainty | `overfitting`: too many parameters for the poses (the held-out error is their uncertainty) |
//! | at | at | at | `floor` |
//!
//! A change between the sets moves the parameters (a tool remounted, a base moved, a drift of
//! the joint offsets), so the held-out residual left after the best change of the fitted
//! parameters and of the base and tool placement ([`change_unknowns`]), fitted on the held-out
//! poses alone ([`after_parameter_change`]), is at the floor; a missing effect is
//! not a parameter change and leaves it above. Without more held-out residuals than fitted
//! parameters, without an independent floor, or along a traced path (serially correlated
//! residuals, [`SERIAL_TAU_MAX`]), a held-out set measured with more noise cannot be told from a
//! missing effect: the verdict stays `change_between_sets`, saying so.
//!
//! With `overfitting` the number of parameter combinations the poses support is given
//! ([`super::probe::design::Design::supported_parameters`]). Without an independent floor the
//! calibration residual is the floor by definition: the cross-validated and held-out residuals
//! are tested against it (an F ratio with its degrees of freedom), and when both agree with it
//! the verdict is `no_floor` (a missing effect cannot be told from noise).

use nalgebra::{DMatrix, DVector, Vector3};
use serde::Serialize;

use super::floor::{chi2_upper_p, FloorReport, FLOOR_ALPHA};
use super::probe::ProbeResult;
use super::stat::f_test_p_value;
use crate::calib::unknown::Unknown;
use crate::calib::MeasuredSet;
use crate::model::Model;

/// When the fitted parameters' uncertainty alone lifts the expected held-out RMS by this factor
/// or more over the floor, the poses are too few for the parameters: a held-out excess is
/// called `overfitting`, not a change between the sets (it cannot be told from the parameters'
/// errors).
pub const UNCERTAIN_PREDICTION_RATIO: f64 = 1.2;

/// Largest serial-correlation time (in poses) for which the held-out residual is tested against
/// a change of the parameters ([`after_parameter_change`]): beyond it the residuals are a traced
/// path's, whose held-out excess may be another session's noise.
pub const SERIAL_TAU_MAX: f64 = 1.5;

/// Largest ratio of the final residual to a stated instrument at which a residual without
/// structure is said to be the instrument's ([`judge`]: verdict `instrument`), not a missing
/// effect.
pub const INSTRUMENT_CHECK_MAX_RATIO: f64 = 2.0;

/// The `verdict` object of `diagnose --json` (extra key).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verdict {
    /// `floor`, `missing_effect`, `overfitting`, `change_between_sets`, `no_floor` or
    /// `instrument` (above the stated instrument by at most [`INSTRUMENT_CHECK_MAX_RATIO`], with
    /// no structure found: the instrument figure is likely optimistic).
    pub kind: String,
    /// Final calibration residual per coordinate over the floor.
    pub calibration_over_floor: f64,
    /// Cross-validated residual per coordinate over the floor (null when not computed).
    pub cv_over_floor: Option<f64>,
    /// Held-out residual per coordinate over the floor.
    pub validation_over_floor: f64,
    /// p-values of the three against the floor (null when not tested).
    pub calibration_p_value: Option<f64>,
    pub cv_p_value: Option<f64>,
    pub validation_p_value: Option<f64>,
    /// Held-out RMS a right model would reach, over the floor: the square root of the
    /// inflation of the held-out sum of squares by the uncertainty of the fitted parameters at
    /// the held-out poses ([`prediction_inflation`]).
    pub validation_expected_ratio: f64,
    /// p-value of the held-out residual against the floor with that uncertainty (a change
    /// between the sets when it is below the level and the cross-validation is at the floor).
    pub validation_p_value_with_parameters: Option<f64>,
    /// p-value of the held-out residual left after the best change of the fitted parameters
    /// on the held-out poses alone (null when the held-out set has no more residuals than
    /// parameters, or when not needed): at the floor for a change between the sets.
    pub validation_p_value_after_parameter_change: Option<f64>,
    /// Physical parameters fitted.
    pub fitted_parameters: usize,
    /// Parameter combinations the calibration poses support (truncated-SVD fit chosen by
    /// cross-validation; null when not estimated).
    pub supported_parameters: Option<usize>,
    /// The verdict in words.
    pub note: String,
}

/// What [`judge`] needs besides the floor report and the probe.
#[derive(Debug, Clone, Copy)]
pub struct Counts {
    /// Number of calibration residuals of the final fit.
    pub n_residuals: usize,
    /// Fitted parameters.
    pub n_params: usize,
    /// Serial-correlation time (1 for independent poses).
    pub tau: f64,
    /// Number of held-out residuals.
    pub val_residuals: usize,
    /// Expected held-out sum of squares of a right model over the floor's (>= 1,
    /// [`prediction_inflation`]).
    pub val_inflation: f64,
    /// The held-out residual after the best parameter change on the held-out poses,
    /// `(sum of squares mm^2, degrees of freedom)` ([`after_parameter_change`]).
    pub val_after_change: Option<(f64, f64)>,
}

/// Expected held-out sum of squares of a right model over its value without parameter errors:
/// `(m_val + sum_k tr(L_k N^+ L_k^T)) / m_val`, `N = sum L^T L` over the calibration poses and
/// `L_k` the measured Jacobian of the fitted parameters at held-out pose `k` (the exact
/// prediction variance at every held-out pose, which grows where the held-out poses leave the
/// calibration poses' span, [`prediction_variances`]). 1 without Jacobians.
pub fn prediction_inflation(
    cal: &MeasuredSet,
    cal_jac: &[DMatrix<f64>],
    val: &MeasuredSet,
    val_jac: &[DMatrix<f64>],
) -> f64 {
    let m_val: usize = (0..val.len()).map(|k| val.rows(k)).sum();
    let Some(v) = prediction_variances(cal, cal_jac, val, val_jac) else {
        return 1.0;
    };
    if m_val == 0 {
        return 1.0;
    }
    let m = m_val as f64;
    ((m + v.iter().sum::<f64>().max(0.0)) / m).max(1.0)
}

/// The normal matrix `N = sum L_k^T L_k` of the calibration poses' measured rows
/// ([`MeasuredSet::jacobian_rows`] of `cal_jac`, 3 x `p` each; others skipped).
pub fn calibration_normal(cal: &MeasuredSet, cal_jac: &[DMatrix<f64>], p: usize) -> DMatrix<f64> {
    let mut n = DMatrix::zeros(p, p);
    for (k, j) in cal_jac.iter().enumerate() {
        if j.ncols() == p {
            let l = cal.jacobian_rows(k, j);
            n += l.transpose() * l;
        }
    }
    n
}

/// The prediction variance of every held-out pose `k` in units of the residual variance:
/// `tr(L_k N^+ L_k^T)` over its measured components (see [`prediction_inflation`]); `None`
/// without Jacobians.
pub fn prediction_variances(
    cal: &MeasuredSet,
    cal_jac: &[DMatrix<f64>],
    val: &MeasuredSet,
    val_jac: &[DMatrix<f64>],
) -> Option<Vec<f64>> {
    let p = cal_jac.first().map_or(0, DMatrix::ncols);
    if p == 0 || val.is_empty() || val_jac.len() != val.len() {
        return None;
    }
    let n = calibration_normal(cal, cal_jac, p);
    let scale = n.diagonal().amax().max(f64::MIN_POSITIVE);
    let ninv = n.pseudo_inverse(1e-10 * scale).ok()?;
    Some(
        val_jac
            .iter()
            .enumerate()
            .map(|(k, j)| {
                if j.ncols() != p {
                    return 0.0;
                }
                let l = val.jacobian_rows(k, j);
                (&l * &ninv * l.transpose()).trace()
            })
            .collect(),
    )
}

/// What may change between two sets of the same arm: the fitted parameters, and the base and
/// tool placement (`base_x/y/z`, `base_rx/ry/rz`, `tool_dx/dy/dz` where the model has them, even
/// when the calibration does not fit them: a remounted tool or a moved base).
pub fn change_unknowns(model: &Model, fitted: &[Unknown]) -> Vec<Unknown> {
    let mut out = fitted.to_vec();
    for name in [
        "base_x", "base_y", "base_z", "base_rx", "base_ry", "base_rz", "tool_dx", "tool_dy",
        "tool_dz",
    ] {
        if let Some(u) = model.param_index(name).map(Unknown::Param) {
            if !out.contains(&u) {
                out.push(u);
            }
        }
    }
    out
}

/// The held-out residual left after the least-squares change of the fitted parameters on the
/// held-out poses alone: `(|r - L x|^2, m_val - rank L)`, `r` the measured held-out errors and
/// `L` their measured Jacobians (columns scaled to unit norm, directions below `1e-10` of the
/// largest singular value dropped). `None` without Jacobians or when no degree of freedom is
/// left.
pub fn after_parameter_change(
    val: &MeasuredSet,
    val_err_mm: &[Vector3<f64>],
    val_jac: &[DMatrix<f64>],
) -> Option<(f64, f64)> {
    let p = val_jac.first().map_or(0, DMatrix::ncols);
    if p == 0 || val_jac.len() != val.len() || val_err_mm.len() != val.len() {
        return None;
    }
    let m_val: usize = (0..val.len()).map(|k| val.rows(k)).sum();
    let mut n = DMatrix::zeros(p, p);
    let mut b = DVector::zeros(p);
    let mut rtr = 0.0;
    for (k, (j, e)) in val_jac.iter().zip(val_err_mm).enumerate() {
        if j.ncols() != p || j.nrows() != 3 {
            return None;
        }
        let l = val.jacobian_rows(k, j);
        n += l.transpose() * &l;
        let r = DVector::from_vec(val.components(k, e));
        b += l.transpose() * &r;
        rtr += r.norm_squared();
    }
    let scale: DVector<f64> = n
        .diagonal()
        .map(|d| if d > 0.0 { 1.0 / d.sqrt() } else { 0.0 });
    let ns = DMatrix::from_fn(p, p, |r, c| n[(r, c)] * scale[r] * scale[c]);
    let bs = b.component_mul(&scale);
    let eig = ns.symmetric_eigen();
    let top = eig.eigenvalues.amax();
    if !(top.is_finite() && top > 0.0) {
        return None;
    }
    // singular values below 1e-10 of the largest: eigenvalues below 1e-20 of the largest
    let mut explained = 0.0;
    let mut rank = 0usize;
    for (i, &ev) in eig.eigenvalues.iter().enumerate() {
        if ev > 1e-20 * top {
            let proj = eig.eigenvectors.column(i).dot(&bs);
            explained += proj * proj / ev;
            rank += 1;
        }
    }
    let dof = m_val.checked_sub(rank).filter(|&d| d > 0)? as f64;
    Some(((rtr - explained).max(0.0), dof))
}

/// The verdict of a diagnosis whose floor report is `floor` and whose probe (with its physical
/// cross-validation) is `probe`.
pub fn judge(floor: &FloorReport, probe: &ProbeResult, c: Counts) -> Verdict {
    let sigma = match floor.used.as_str() {
        "instrument" => floor.instrument_mm,
        "repeatability" => floor.repeatability_mm,
        _ => None,
    }
    .unwrap_or(floor.residual_mm);
    let tau = c.tau.max(1.0);
    let dof_cal = c.n_residuals.saturating_sub(c.n_params).max(1) as f64;
    // the floor's own degrees of freedom when it is an estimate
    let floor_dof = match floor.used.as_str() {
        "repeatability" => floor.repeatability_dof.map(|d| d as f64),
        "instrument" => None,
        _ => Some(dof_cal / tau),
    };
    let test = |ss: f64, dof: f64| -> f64 {
        let stat = ss / (sigma * sigma);
        match floor_dof {
            Some(d2) => f_test_p_value(stat / dof, dof, d2),
            None => chi2_upper_p(stat, dof),
        }
    };
    let m = probe.n_components;
    let cv = (m > 0 && probe.physical_cv_rms_mm.is_finite() && sigma > 0.0).then(|| {
        let inflation = probe.physical_cv_inflation.max(1.0);
        let ss = probe.physical_cv_rms_mm.powi(2) * m as f64;
        let dof = (m as f64 / tau).max(1.0);
        (
            probe.physical_cv_rms_mm / sigma,
            test(ss / inflation / tau, dof),
        )
    });
    let residual_floor = floor.used == "residual";
    // the held-out residual against the floor alone, and against the floor with the exact
    // uncertainty of the fitted parameters at the held-out poses
    let val_ss = floor.validation_rms_mm.powi(2) * c.val_residuals.max(1) as f64;
    let val_dof = c.val_residuals.max(1) as f64;
    let val_raw_p = test(val_ss, val_dof);
    let val_p = test(val_ss / c.val_inflation.max(1.0), val_dof);
    let above = |p: Option<f64>| p.is_some_and(|p| p < FLOOR_ALPHA);
    let cal_above = !residual_floor && above(floor.p_value);
    let cv_above = above(cv.map(|x| x.1));
    let val_above = above(Some(val_p));
    let val_raw_above = above(Some(val_raw_p));
    let expected_ratio = c.val_inflation.max(1.0).sqrt();
    // only against an independent floor and on independent poses: with the residual as its
    // own floor, or along a traced path, a held-out set measured with more noise (another
    // session, another sheet) cannot be told from an error no parameter change explains
    let after_change_p = c
        .val_after_change
        .filter(|_| !residual_floor && tau <= SERIAL_TAU_MAX)
        .map(|(ss, dof)| test(ss, dof));
    let kind = if cal_above {
        "missing_effect"
    } else if cv_above || (val_above && expected_ratio >= UNCERTAIN_PREDICTION_RATIO) {
        "overfitting"
    } else if val_above && above(after_change_p) {
        // no change of the parameters explains the held-out excess
        "missing_effect"
    } else if val_above {
        "change_between_sets"
    } else if val_raw_above {
        // above the floor only by the uncertainty of the fitted parameters
        "overfitting"
    } else if residual_floor {
        "no_floor"
    } else {
        "floor"
    };
    // the instrument figure checked: above a stated instrument by a modest factor, with no
    // structure that a smooth function of the variables finds, the data say the instrument is
    // worse than stated rather than that the model lacks something
    let kind = if kind == "missing_effect"
        && floor.used == "instrument"
        && !probe.structured
        && floor.final_over_floor <= INSTRUMENT_CHECK_MAX_RATIO
    {
        "instrument"
    } else {
        kind
    };
    let mut v = Verdict {
        kind: kind.to_string(),
        calibration_over_floor: floor.final_over_floor,
        cv_over_floor: cv.map(|x| x.0),
        validation_over_floor: floor.validation_over_floor,
        calibration_p_value: floor.p_value,
        cv_p_value: cv.map(|x| x.1),
        validation_p_value: Some(val_raw_p),
        validation_expected_ratio: expected_ratio,
        validation_p_value_with_parameters: Some(val_p),
        validation_p_value_after_parameter_change: after_change_p,
        fitted_parameters: c.n_params,
        supported_parameters: probe.supported_parameters,
        note: String::new(),
    };
    v.note = sentence(&v, floor);
    v
}

/// The verdict in words: never "at the floor" and "lacks something" at once.
pub fn sentence(v: &Verdict, floor: &FloorReport) -> String {
    let fmt_p = |p: Option<f64>| p.map_or("-".to_string(), |p| format!("{p:.1e}"));
    let cv = match (v.cv_over_floor, v.cv_p_value) {
        (Some(r), p) => format!(", cross-validated {r:.2} x (p = {})", fmt_p(p)),
        _ => String::new(),
    };
    let which = if floor.used == "residual" {
        "floor estimated from the final residual itself".to_string()
    } else {
        format!("{} floor", floor.used)
    };
    let numbers = format!(
        "calibration residual {:.4} mm per coordinate = {:.2} x the {which} (p = {}){cv}, held out {:.4} mm = {:.2} x (p = {})",
        floor.residual_mm,
        v.calibration_over_floor,
        fmt_p(v.calibration_p_value),
        floor.validation_rms_mm,
        v.validation_over_floor,
        fmt_p(v.validation_p_value)
    );
    match v.kind.as_str() {
        "floor" => format!("at the floor: {numbers}"),
        "instrument" => format!(
            "consistent with an instrument of about {:.4} mm per coordinate (the stated one is {} \
             mm): the residual is {:.2} x the stated figure, but no smooth function of the joint \
             angles or the time explains any of it, so the instrument figure is more likely \
             optimistic than the model short of an effect; check it with repeated poses (measure \
             some poses twice): {numbers}",
            floor.residual_mm,
            floor.instrument_mm.map_or("-".into(), |x| format!("{x}")),
            v.calibration_over_floor
        ),
        "missing_effect" if v.calibration_p_value.is_some_and(|p| p < FLOOR_ALPHA) => format!(
            "a missing effect: the model still lacks something the calibration poses already show: {numbers}"
        ),
        "missing_effect" => format!(
            "a missing effect: the model still lacks something the held-out poses show and the calibration poses barely do; no change of the fitted parameters explains it (p = {}), so it is not a change between the sets; measure more poses where the held-out ones are: {numbers}",
            fmt_p(v.validation_p_value_after_parameter_change)
        ),
        "overfitting" => format!(
            "overfitting: the calibration residual is at the floor but the poses left out are not: {} fitted parameters follow these poses' noise and errors (with their uncertainty alone a right model would reach {:.2} x the floor on the held-out poses){}; measure more poses or fit fewer parameters: {numbers}",
            v.fitted_parameters,
            v.validation_expected_ratio,
            v.supported_parameters
                .map(|s| format!("; the poses support about {s} parameter combinations"))
                .unwrap_or_default()
        ),
        "change_between_sets" => format!(
            "a change between the sets: the calibration and its cross-validation are at the floor, the held-out set is not (drift, another day, another tool mounting or base){}: {numbers}",
            match v.validation_p_value_after_parameter_change {
                Some(p) => format!("; a change of the fitted parameters on the held-out poses brings them to the floor (p = {p:.1e})"),
                None => "; whether a parameter change explains it is not tested here (no more held-out residuals than unknowns, no independent floor, or a traced path)".to_string(),
            }
        ),
        _ => format!(
            "no independent floor: the calibration residual is its own floor, so a missing effect cannot be told from noise; the cross-validated and held-out residuals agree with it: {numbers}"
        ),
    }
}
