//! The `calibrate --json` document (FORMATS.md): exact keys, parameter values in file units
//! (degrees for angles, millimetres for lengths).
//!
//! Contract keys: `method`, `calibration {before, after}`, `validation {before, after}` (only with
//! validation poses), `parameters {name: value}`, `unidentifiable [names or combinations]`,
//! `condition_number`. Added keys (FORMATS.md allows additions): `standard` (the conventional
//! result used for the table-4.5 comparison), `sigma` (one standard deviation of each fitted
//! parameter), `fixed` (parameters kept at their nominal value), `rank`, `iterations`,
//! `converged`, `tilting_applied`, `terms` (non-parameter values: point offsets, compliance).

use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use nalgebra::Vector3;

use super::fit::Fit;
use super::stats::Stats;
use crate::model::Model;

/// Error statistics before (nominal model without tilting) and after calibration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BeforeAfter {
    /// Nominal model, no tilting.
    pub before: Stats,
    /// The calibrated model.
    pub after: Stats,
}

/// `{name: value}` in a fixed (model) order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct NamedValues(pub Vec<(String, f64)>);

impl Serialize for NamedValues {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// `{name: value}` with a value that is not a finite number written `null`.
fn finite_or_null<S: Serializer>(v: &NamedValues, s: S) -> Result<S::Ok, S::Error> {
    let mut m = s.serialize_map(Some(v.0.len()))?;
    for (k, x) in &v.0 {
        m.serialize_entry(k, &x.is_finite().then_some(*x))?;
    }
    m.end()
}

impl NamedValues {
    /// The names of the values that are not finite numbers.
    pub fn not_finite(&self) -> Vec<String> {
        self.0
            .iter()
            .filter(|(_, v)| !v.is_finite())
            .map(|(k, _)| k.clone())
            .collect()
    }

    /// Whether there is no value.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The value called `name`.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.0.iter().find(|(k, _)| k == name).map(|(_, v)| *v)
    }
}

/// The conventional (no tilting) calibration run alongside the chosen method.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StandardSummary {
    /// Calibration poses after the standard calibration.
    pub calibration: Stats,
    /// Validation poses after the standard calibration (with validation poses only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub validation: Option<Stats>,
}

/// The whole `calibrate --json` document.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CalibrateReport {
    /// `standard`, `influence` or `tilting`.
    pub method: String,
    /// Statistics over the calibration poses.
    pub calibration: BeforeAfter,
    /// Statistics over the validation poses (with `--validate` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub validation: Option<BeforeAfter>,
    /// Identified parameter values (file units), fitted and fixed ones, in model order.
    pub parameters: NamedValues,
    /// Unidentifiable parameters or combinations (`"be5"`, `"dth5+be4"`).
    pub unidentifiable: Vec<String>,
    /// Condition number of the column-scaled identification Jacobian of the fitted parameters.
    pub condition_number: f64,
    /// Standard calibration for comparison (table 4.5 "conventional calibration").
    pub standard: StandardSummary,
    /// One standard deviation of each fitted parameter (file units), `sigma^2 (J^T J)^-1`;
    /// `null` for one the poses do not determine (an infinite sigma).
    #[serde(serialize_with = "finite_or_null")]
    pub sigma: NamedValues,
    /// Parameters kept at their nominal value because they are not identifiable.
    pub fixed: Vec<String>,
    /// Numerical rank of the identification Jacobian over the selected parameters.
    pub rank: usize,
    /// Solver iterations of the chosen method.
    pub iterations: usize,
    /// Whether the solver met a convergence criterion (not the iteration cap).
    pub converged: bool,
    /// Whether the calibrated model includes the declared joint tilting (method `tilting` on a
    /// model with tilting data).
    pub tilting_applied: bool,
    /// Identified values that are not model parameters (README "calibrate: several points,
    /// compliance, PRESS selection"): `marker<k>_x_mm` (point offsets in the tool frame) and
    /// `compliance_j<i>_deg_per_kgfm`; their sigmas are in `sigma`. Absent when empty.
    #[serde(skip_serializing_if = "NamedValues::is_empty")]
    pub terms: NamedValues,
    /// Identified values outside their physical range (a negative compliance): reported, not
    /// silently kept; each entry names the value and why. Absent when empty.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub unphysical: Vec<String>,
    /// Poses left out as gross errors (FORMATS.md "Gross errors in measured poses"); the
    /// statistics above are over the other poses.
    pub outliers: Vec<super::outliers::OutlierReport>,
    /// Set when the gross-error rule was not applied as such (heavy tails) or did not settle.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outlier_note: Option<String>,
    /// Parameters of the robot's geometry moved further than a real arm's errors
    /// ([`super::large_changes::large_changes`]); `calibrate` exits 1 and writes no model unless
    /// `--allow-large-changes`. Absent when empty.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub large_changes: Vec<super::large_changes::LargeChange>,
    /// Statistics over every held-out pose, the listed gross errors included (FORMATS.md "Gross
    /// errors in measured poses"; with validation poses only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub validation_all: Option<BeforeAfter>,
    /// Held-out poses whose error the calibration residual alone would call a gross error, but
    /// which the model extrapolates to (a large prediction uncertainty at the pose, or joints
    /// outside the calibration poses' ranges): reported, kept in the statistics.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub extrapolated: Vec<super::outliers::Extrapolated>,
    /// The prior of an ill-posed identification ([`super::regularise`]); absent when none was
    /// considered.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prior: Option<super::regularise::PriorChoice>,
    /// The input model with only the base (instrument) frame fitted, every other parameter at
    /// its input value ([`super::registered`]); with `--base` only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub registered: Option<StandardSummary>,
    /// The link masses assumed where the model declared none (a tree's `calibrate
    /// --assume-masses`): `{total_kg, per_joint_kg, rule}`, as `diagnose`'s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub assumed_masses: Option<serde_json::Value>,
    /// The tree a tree model's calibration is of: `{name, tips, joints}`, as `diagnose`'s; its
    /// statistics are over every tip's point of a pose.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tree: Option<serde_json::Value>,
}

/// The `calibrate --json` document of the chosen `fit` of a model's parameters (model
/// indices): [`unknowns_report`] with the parameters' names and values.
pub fn fit_report(
    fit: &Fit,
    selection: &[usize],
    method: &str,
    cal: &[Vec<Vector3<f64>>; 3],
    val: Option<&[Vec<Vector3<f64>>; 3]>,
    tilting_applied: bool,
) -> CalibrateReport {
    let entry = |m: &Model, c: &usize| m.params().get(*c).map(|p| (p.name.clone(), p.value));
    unknowns_report(fit, selection, entry, method, cal, val, tilting_applied)
}

/// The `calibrate --json` document of the chosen `fit`: its unknowns (fitted and fixed, in
/// `selection` order) by `entry` (an unknown's name and value in the fitted state), their
/// sigmas and identifiability, with the error statistics of the error vectors `[before,
/// standard, chosen]` of the calibration measurements `cal` and, with validation measurements,
/// of those ([`error_summary`]).
pub fn unknowns_report<M, U: Clone + PartialEq>(
    fit: &Fit<M, U>,
    selection: &[U],
    entry: impl Fn(&M, &U) -> Option<(String, f64)>,
    method: &str,
    cal: &[Vec<Vector3<f64>>; 3],
    val: Option<&[Vec<Vector3<f64>>; 3]>,
    tilting_applied: bool,
) -> CalibrateReport {
    let (calibration, validation, standard) = error_summary(cal, val);
    let name = |c: &U| entry(&fit.model, c).map_or_else(String::new, |(n, _)| n);
    let mut reported: Vec<U> = fit.fitted.iter().chain(&fit.fixed).cloned().collect();
    reported.sort_unstable_by_key(|c| selection.iter().position(|s| s == c));
    CalibrateReport {
        method: method.to_string(),
        calibration,
        validation,
        parameters: NamedValues(
            reported
                .iter()
                .filter_map(|c| entry(&fit.model, c))
                .collect(),
        ),
        unidentifiable: fit.unidentifiable.clone(),
        condition_number: fit.condition_number,
        standard,
        // the kept parameters' sigma is `null` (FORMATS.md): NaN here
        sigma: NamedValues(
            reported
                .iter()
                .map(|c| (name(c), fit.sigma_of(c.clone())))
                .map(|(n, s)| (n, if s.is_finite() { s } else { f64::NAN }))
                .collect(),
        ),
        fixed: fit.fixed.iter().map(name).collect(),
        rank: fit.rank,
        iterations: fit.iterations,
        converged: fit.converged,
        tilting_applied,
        terms: NamedValues::default(),
        unphysical: Vec::new(),
        outliers: Vec::new(),
        outlier_note: None,
        large_changes: Vec::new(),
        validation_all: None,
        extrapolated: Vec::new(),
        prior: None,
        registered: None,
        assumed_masses: None,
        tree: None,
    }
}

impl CalibrateReport {
    /// The calibration's result judged (`large_changes`, `unphysical`): the geometry's
    /// [`super::large_changes::large_changes`] and the payload's
    /// [`super::large_changes::payload_plausibility`].
    pub fn judge(&mut self, nominal: &Model, calibrated: &Model) {
        use super::large_changes::{large_changes, payload_plausibility};
        self.large_changes = large_changes(nominal, calibrated);
        let sigma = self.sigma.get(crate::model::PAYLOAD_PARAM);
        let (change, line) = payload_plausibility(nominal, calibrated, sigma);
        self.large_changes.extend(change);
        self.unphysical.extend(line);
    }
}

/// The error statistics of `calibrate --json` from the error vectors `[before, standard,
/// chosen]` of the calibration poses and, with validation poses, of those.
fn error_summary(
    cal: &[Vec<Vector3<f64>>; 3],
    val: Option<&[Vec<Vector3<f64>>; 3]>,
) -> (BeforeAfter, Option<BeforeAfter>, StandardSummary) {
    let before_after = |e: &[Vec<Vector3<f64>>; 3]| BeforeAfter {
        before: Stats::from_errors(&e[0]),
        after: Stats::from_errors(&e[2]),
    };
    (
        before_after(cal),
        val.map(before_after),
        StandardSummary {
            calibration: Stats::from_errors(&cal[1]),
            validation: val.map(|e| Stats::from_errors(&e[1])),
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contract_keys_and_order() {
        let e = vec![Vector3::new(0.1, 0.0, 0.0)];
        let errors = [e.clone(), e.clone(), e];
        // a state of named values; unknowns 0 and 1 fitted, 2 and 3 fixed
        let state = vec![
            ("dth2".to_string(), 0.03),
            ("al2".to_string(), 90.01),
            ("be4".to_string(), 0.0),
            ("be5".to_string(), 0.0),
        ];
        let fit = Fit {
            model: state,
            fitted: vec![0usize, 1],
            fixed: vec![2, 3],
            unidentifiable: vec!["be5".into(), "dth5+be4".into()],
            sigma: vec![0.001, 0.002],
            condition_number: 12.5,
            rank: 10,
            iterations: 4,
            converged: true,
            rss_mm2: 0.01,
            n_residuals: 3,
        };
        let entry = |s: &Vec<(String, f64)>, c: &usize| s.get(*c).cloned();
        let r = unknowns_report(&fit, &[0, 1, 2, 3], entry, "tilting", &errors, None, true);
        let text = serde_json::to_string(&r).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        for key in [
            "method",
            "calibration",
            "parameters",
            "unidentifiable",
            "condition_number",
        ] {
            assert!(v.get(key).is_some(), "missing {key}");
        }
        assert!(
            v.get("validation").is_none(),
            "validation only with --validate"
        );
        assert!(v["calibration"]["before"]["mean_mm"].is_number());
        assert!(v["calibration"]["after"]["n"].is_number());
        // Model order is kept.
        assert!(text.find("\"dth2\"").unwrap() < text.find("\"al2\"").unwrap());
        assert_eq!(v["parameters"]["al2"], 90.01);
        assert_eq!(v["fixed"], serde_json::json!(["be4", "be5"]));
        // the fixed ones' sigma is null
        assert_eq!(r.sigma.not_finite(), ["be4", "be5"]);
        // a sigma the poses do not determine is null, and the document is still written
        let mut r = r;
        r.sigma.0[1].1 = f64::INFINITY;
        assert_eq!(r.sigma.not_finite(), ["al2", "be4", "be5"]);
        let v: serde_json::Value = serde_json::to_value(&r).unwrap();
        assert!(v["sigma"]["al2"].is_null() && v["sigma"]["dth2"] == 0.001);
        crate::io::finite_json::check_json(&r).unwrap();
    }
}
