//! The `diagnose --json` document (FORMATS.md keys, plus extra keys) and the text table.
//!
//! Documented keys: `declared{calibration, validation}`, `effects[{id, parameters,
//! validation_mean_mm_before, validation_mean_mm_after, evidence}]`, `final{calibration,
//! validation}`, `unexplained{structured, note}`. Extra keys: per effect `uncertainty` (one sigma
//! per parameter, null when held fixed), `calibration_mean_mm_before/after`,
//! `cv_mean_mm_before/after`, `p_value`, `f_statistic`, `delta_bic`, `added_parameters`,
//! `regressor`, `unidentifiable`, `model_parameters` (fitted model values); at the top `noise`,
//! `robot`, `tilting`, `declared_unidentifiable`, `rejected` (candidates refitted at the last
//! step and why they failed), `rule`. Also FORMATS.md: per effect `sigma` and
//! `parameters_at_entry` (`parameters` are the final values), `unexplained{depends_on,
//! explainable_share}`, `floor` ([`super::floor`]), `aliased` ([`super::alias`]); extra per
//! effect `equivalent` (near ties); at the top `probe` (the probe's terms and cross-validated
//! RMS, [`super::probe`]) and, with `--residual-model`, `residual_model` (the hybrid correction
//! and its held-out statistics).

use serde::Serialize;

use super::decide::{DecideConfig, Trial};
pub use super::ordered::Ordered;
use crate::calib::Stats;

/// Statistics of the calibration and validation poses.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SetStats {
    pub calibration: Stats,
    /// The held-out poses not listed as gross errors.
    pub validation: Stats,
    /// Every held-out pose, the listed ones included (FORMATS.md "Gross errors").
    pub validation_all: Stats,
}

/// One added effect.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EffectReport {
    pub id: String,
    /// Values in the final fit (with every accepted effect).
    pub parameters: Ordered<f64>,
    /// One sigma of each, final fit (null when held fixed).
    pub sigma: Ordered<Option<f64>>,
    /// Values when the effect was added.
    pub parameters_at_entry: Ordered<f64>,
    pub validation_mean_mm_before: f64,
    pub validation_mean_mm_after: f64,
    pub evidence: String,
    /// Candidates that explained the same residual within noise when it was added
    /// (statistically equivalent on these poses).
    pub equivalent: Vec<String>,
    pub uncertainty: Ordered<Option<f64>>,
    pub calibration_mean_mm_before: f64,
    pub calibration_mean_mm_after: f64,
    pub cv_mean_mm_before: f64,
    pub cv_mean_mm_after: f64,
    pub p_value: f64,
    pub f_statistic: f64,
    pub delta_bic: f64,
    pub added_parameters: usize,
    pub regressor: String,
    pub unidentifiable: Vec<String>,
    pub model_parameters: Ordered<f64>,
}

/// What remains unexplained.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Unexplained {
    pub structured: bool,
    pub note: String,
    /// Joints (`q2`) and joint pairs (`q1:q3`) the probe's smooth function depends on.
    pub depends_on: Vec<String>,
    /// Share of the residual variance the probe explains out of sample.
    pub explainable_share: f64,
    /// With a `missing_effect` verdict and no term of the probe accepted: the variables the
    /// regressor scan ranks highest on the final residual, with the share of it each explains
    /// in sample (where to look; `depends_on` then names them). Absent otherwise.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub depends_on_shares: Vec<(String, f64)>,
}

impl Unexplained {
    /// Adds the probe's finding ([`super::probe`]): `depends_on`, `explainable_share`, the
    /// sentence, and `structured` when it found out-of-sample structure.
    pub fn add_probe(&mut self, probe: &super::probe::ProbeResult) {
        self.depends_on = probe.depends_on.clone();
        self.explainable_share = probe.explainable_share;
        self.structured |= probe.structured;
        self.note.push_str("; probe: ");
        self.note.push_str(&probe.sentence());
    }

    /// Where to look when the model lacks something and the probe accepted no term: the
    /// variables of the regressors (`explained`: name and in-sample share of the final
    /// residual) ranked highest, at most [`WHERE_TO_LOOK`] of them with a share of at least
    /// [`WHERE_TO_LOOK_MIN_SHARE`], into `depends_on` with their shares.
    pub fn add_where_to_look(&mut self, explained: &[(String, f64)]) {
        if !self.depends_on.is_empty() {
            return;
        }
        let mut ranked: Vec<(String, f64)> = explained
            .iter()
            .filter_map(|(name, share)| variable_of(name).map(|v| (v, *share)))
            .filter(|(_, s)| s.is_finite() && *s >= WHERE_TO_LOOK_MIN_SHARE)
            .collect();
        ranked.sort_by(|a, b| b.1.total_cmp(&a.1));
        let mut seen: Vec<(String, f64)> = Vec::new();
        for (v, s) in ranked {
            if seen.len() < WHERE_TO_LOOK && !seen.iter().any(|(w, _)| *w == v) {
                seen.push((v, s));
            }
        }
        if seen.is_empty() {
            return;
        }
        self.note.push_str(&format!(
            "; where to look: {}",
            seen.iter()
                .map(|(v, s)| format!("{v} ({:.0} % of the residual in sample)", 100.0 * s))
                .collect::<Vec<_>>()
                .join(", ")
        ));
        self.depends_on = seen.iter().map(|(v, _)| v.clone()).collect();
        self.depends_on_shares = seen;
    }
}

/// Most variables named by [`Unexplained::add_where_to_look`].
pub const WHERE_TO_LOOK: usize = 3;
/// Smallest in-sample share of the residual a variable must explain to be named.
pub const WHERE_TO_LOOK_MIN_SHARE: f64 = 0.02;

/// The variable of a regressor's name: `q6` of `sin/cos(2 q6)`, `t` of `t`, `None` for a
/// regressor of no single variable (a torque, the position).
fn variable_of(name: &str) -> Option<String> {
    let tokens: Vec<&str> = name
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|t| !t.is_empty())
        .collect();
    let vars: Vec<&str> = tokens
        .iter()
        .copied()
        .filter(|t| *t == "t" || (t.starts_with('q') && t[1..].parse::<usize>().is_ok()))
        .collect();
    match vars.as_slice() {
        [] => None,
        [v] => Some((*v).to_string()),
        [a, b, ..] => Some(format!("{a}:{b}")),
    }
}

/// The noise estimated from the final calibration residual.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct NoiseReport {
    /// Standard deviation per coordinate, mm.
    pub sigma_mm: f64,
    /// Mean Euclidean error of that noise alone, mm.
    pub expected_mean_mm: f64,
}

/// A candidate tested at the last step and not accepted.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrialReport {
    pub id: String,
    pub added_parameters: usize,
    pub p_value: f64,
    pub delta_bic: f64,
    pub cv_mean_mm_before: Option<f64>,
    pub cv_mean_mm_after: Option<f64>,
    pub reason: String,
}

impl TrialReport {
    /// From a trial.
    pub fn from_trial(t: &Trial) -> Self {
        let fin = |v: f64| v.is_finite().then_some(v);
        Self {
            id: t.candidate.id.clone(),
            added_parameters: t.added,
            p_value: t.p_value,
            delta_bic: t.delta_bic,
            cv_mean_mm_before: fin(t.cv_mean_mm[0]),
            cv_mean_mm_after: fin(t.cv_mean_mm[1]),
            reason: t.reason.clone(),
        }
    }
}

/// The whole document.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DiagnoseReport {
    pub declared: SetStats,
    pub effects: Vec<EffectReport>,
    #[serde(rename = "final")]
    pub final_: SetStats,
    pub unexplained: Unexplained,
    pub floor: super::floor::FloorReport,
    pub aliased: Vec<super::alias::AliasReport>,
    pub noise: NoiseReport,
    pub robot: String,
    pub tilting: bool,
    pub declared_unidentifiable: Vec<String>,
    pub rejected: Vec<TrialReport>,
    pub rule: String,
    /// What the calibration set measures: `"positions"` (full 3-D positions) or `"partial"`
    /// (traced samples: across the path and out of the sheet; stats over those components).
    pub measurements: String,
    /// Calibration samples left out as outliers of the declared tilting law
    /// ([`super::trim_outliers`]; always 0 for full positions).
    pub outliers_left_out: usize,
    /// Poses left out as gross errors (FORMATS.md); the statistics are over the other poses.
    pub outliers: Vec<crate::calib::outliers::OutlierReport>,
    /// Held-out poses the gross-error rule flagged that a model within the fit's uncertainty
    /// predicts (a sign step of a law, [`super::envelope`]): kept in the statistics (extra key).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub within_uncertainty: Vec<crate::calib::outliers::OutlierReport>,
    /// Set when the gross-error rule was not applied as such (heavy tails) or did not settle.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outlier_note: Option<String>,
    /// Whether the declared and the final fits converged (false: an iteration budget was spent
    /// while the solver still made progress; `diagnose` then exits 1).
    pub converged: bool,
    /// The probe of the final residual: its terms and cross-validated RMS.
    pub probe: super::probe::ProbeReport,
    /// With `--residual-model`: the probe's function as a correction (a hybrid model, never in
    /// `effects`) and its held-out statistics.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual_model: Option<super::probe::HybridReport>,
    /// One verdict from the calibration, cross-validated and held-out residuals (extra key,
    /// [`super::verdict`]).
    pub verdict: super::verdict::Verdict,
    /// Fitted values that fell outside their physical range and what was done (extra key,
    /// [`super::bounds`]).
    pub bounds: Vec<super::bounds::BoundReport>,
    /// The link masses the model was given because it declared none (`diagnose
    /// --assume-masses`): `{total_kg, per_joint_kg, rule}` (extra key).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub assumed_masses: Option<serde_json::Value>,
    /// The greedy selection a smaller set replaced because it did as well ([`super::simplest`];
    /// extra key, absent when the greedy selection stood).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub simplest: Option<SimplestReport>,
}

/// A smaller set of effects taken instead of the greedy selection (extra key `simplest`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SimplestReport {
    /// The effects the greedy selection had accepted, in order.
    pub greedy: Vec<String>,
    /// The effects taken instead (as in `effects`).
    pub taken: Vec<String>,
    /// Cross-validated mean error of the greedy set (mm).
    pub cv_mean_mm_greedy: f64,
    /// Cross-validated mean error of the set taken (mm).
    pub cv_mean_mm_taken: f64,
    /// BIC of the set taken minus the greedy set's.
    pub delta_bic: f64,
    /// Other sets, no more than one effect larger than the one taken, that did as well.
    pub close: Vec<String>,
}

impl From<&super::decide::Simpler> for SimplestReport {
    fn from(s: &super::decide::Simpler) -> Self {
        Self {
            greedy: s.greedy.clone(),
            taken: s.taken.clone(),
            cv_mean_mm_greedy: s.cv_mean_mm[0],
            cv_mean_mm_taken: s.cv_mean_mm[1],
            delta_bic: s.delta_bic,
            close: s.close.clone(),
        }
    }
}

/// One-line statement of the decision rule in force.
pub fn rule_text(cfg: &DecideConfig) -> String {
    format!(
        "greedy forward selection; accept when the F-test p < {:.0e} with a BIC decrease and {}-fold cross-validation \
         (seed {}) lowers the held-out mean error by >= {:.0} % with paired t >= {:.2}",
        cfg.alpha,
        cfg.folds,
        cfg.seed,
        100.0 * cfg.cv_min_gain,
        cfg.cv_t_min
    )
}

/// The line said when no effect was added, consistent with the verdict `kind`.
pub fn no_effect_line(kind: &str) -> &'static str {
    match kind {
        "floor" => "no effect added: the declared model explains the data down to the noise",
        "missing_effect" => {
            "no effect added: no candidate passed the tests, yet the model still lacks something (verdict below)"
        }
        "overfitting" => {
            "no effect added: the declared model fits the calibration poses to the floor but does not predict the poses left out (verdict below)"
        }
        "change_between_sets" => {
            "no effect added: the declared model explains the calibration poses down to the noise; the held-out set differs (verdict below)"
        }
        "instrument" => {
            "no effect added: what is left has no structure, and is consistent with a worse instrument than the one stated (verdict below)"
        }
        _ => "no effect added (no independent floor: verdict below)",
    }
}

mod text;
