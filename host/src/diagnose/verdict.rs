//! One verdict from the three residuals a diagnosis has: the final calibration residual, its
//! k-fold cross-validation, and the held-out set (JSON key `verdict`, the text's `floor:` line,
//! the report's first screen).
//!
//! Each is tested against the floor ([`super::floor`]): the calibration residual as there
//! (`RSS / sigma^2`, `(m - p) / tau` degrees of freedom), the cross-validated one (the physical
//! parameters refitted without each fold, [`super::probe::design::Design::physical_cv_residuals`])
//! as `SS_cv / (sigma^2 c)` over `m / tau` degrees of freedom, `c = (m + sum_g tr(N_g
//! N_{-g}^+)) / m` the exact inflation of a right model's held-out residuals by the uncertainty
//! of the parameters fitted without each fold ([`super::probe::design::Design::physical_cv_inflation`]),
//! the held-out one as in the floor report. A residual is **above** when its p-value is below
//! [`super::floor::FLOOR_ALPHA`]. Then:
//!
//! | calibration | cross-validation | held out | verdict |
//! |---|---|---|---|
//! | at | at | at | `floor` |
//! | above | any | any | `missing_effect`: the model lacks something the calibration poses already show |
//! | at | above | any | `overfitting`: the parameters follow these poses' noise and errors; the number of parameter combinations the poses support is given |
//! | at | at | above | `change_between_sets`: drift, another day, another tool mounting or base |
//!
//! Without an independent floor the calibration residual is the floor by definition: the
//! cross-validated and held-out residuals are tested against it (an F ratio with its degrees of
//! freedom), and when both agree with it the verdict is `no_floor` (a missing effect cannot be
//! told from noise).

use serde::Serialize;

use super::floor::{chi2_upper_p, FloorReport, FLOOR_ALPHA};
use super::probe::ProbeResult;
use super::stat::f_test_p_value;

/// The `verdict` object of `diagnose --json` (extra key).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verdict {
    /// `floor`, `missing_effect`, `overfitting`, `change_between_sets` or `no_floor`.
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
    let val_p = if residual_floor {
        // held out against the residual itself: the F ratio of the two variances
        let d = c.val_residuals.max(1) as f64;
        let inflation = 1.0 + c.n_params as f64 / c.n_residuals.max(1) as f64;
        Some(test(floor.validation_rms_mm.powi(2) * d / inflation, d))
    } else {
        floor.validation_p_value
    };
    let above = |p: Option<f64>| p.is_some_and(|p| p < FLOOR_ALPHA);
    let cal_above = !residual_floor && above(floor.p_value);
    let cv_above = above(cv.map(|x| x.1));
    let val_above = above(val_p);
    let kind = if cal_above {
        "missing_effect"
    } else if cv_above {
        "overfitting"
    } else if val_above {
        "change_between_sets"
    } else if residual_floor {
        "no_floor"
    } else {
        "floor"
    };
    let mut v = Verdict {
        kind: kind.to_string(),
        calibration_over_floor: floor.final_over_floor,
        cv_over_floor: cv.map(|x| x.0),
        validation_over_floor: floor.validation_over_floor,
        calibration_p_value: floor.p_value,
        cv_p_value: cv.map(|x| x.1),
        validation_p_value: val_p,
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
        "missing_effect" => format!(
            "a missing effect: the model still lacks something the calibration poses already show: {numbers}"
        ),
        "overfitting" => format!(
            "overfitting: the calibration residual is at the floor but the cross-validated one is not: {} fitted parameters follow these poses' noise and errors{}; measure more poses or fit fewer parameters: {numbers}",
            v.fitted_parameters,
            v.supported_parameters
                .map(|s| format!(" (the poses support about {s} parameter combinations)"))
                .unwrap_or_default()
        ),
        "change_between_sets" => format!(
            "a change between the sets: the calibration and its cross-validation are at the floor, the held-out set is not (drift, another day, another tool mounting or base): {numbers}"
        ),
        _ => format!(
            "no independent floor: the calibration residual is its own floor, so a missing effect cannot be told from noise; the cross-validated and held-out residuals agree with it: {numbers}"
        ),
    }
}
