//! `rigctl plan --from-diagnose D.json [--poses CAL.csv]`: extra poses that separate what a
//! diagnosis could not tell apart.
//!
//! Read from the diagnose JSON (FORMATS.md): `aliased[{a, b, correlation, note}]` (effect ids
//! or declared parameter names) and `effects[{id, parameters, sigma | uncertainty}]`. The
//! unknowns are the declared ones, then those of every accepted effect, then those of every
//! aliased effect (the diagnose candidate library maps an effect id to its unknowns). The
//! columns of interest are the aliased effects' unknowns and those of accepted effects whose
//! sigma is large (more than [`LOOSE_RELATIVE_SIGMA`] of the value); the design is Ds-optimal
//! for them, added to the poses already measured (`--poses`).
//!
//! An effect that depends on the path to a pose or on time, not on the pose (`hysteresis:j<i>`,
//! `time_drift`, `time_drift:j<i>`, `thermal`), is not separated by a choice of poses: its
//! unknowns stay out of the design, and the report gives the measuring order that separates it
//! ([`path_protocol`]) instead of correlations.

use std::path::Path;

use nalgebra::DMatrix;
use serde_json::Value;

use super::candidates::CandidatePose;
use super::robust::{self, DEFAULT_EFFECT_RMS_MM};
use super::setup::Setup;
use super::PlanError;
use crate::calib::default_selection;
use crate::diagnose::candidates::library_for;
use crate::diagnose::extended::{ExtModel, Unknown, Values};
use crate::model::effect::{self, EffectId};
use crate::model::Model;

/// An accepted effect is pinned down by the plan too when a parameter's sigma exceeds this
/// fraction of its value.
pub const LOOSE_RELATIVE_SIGMA: f64 = 0.1;

/// One aliased pair of the diagnosis.
#[derive(Debug, Clone, PartialEq)]
pub struct AliasedPair {
    /// Effect id or parameter name.
    pub a: String,
    /// Effect id or parameter name.
    pub b: String,
    /// Correlation the diagnosis reported (NaN when absent).
    pub correlation: f64,
}

/// What `--from-diagnose` read, with the poses already measured.
#[derive(Debug, Clone, PartialEq)]
pub struct FromDiagnose {
    /// The JSON file (for messages).
    pub path: String,
    /// Aliased pairs.
    pub pairs: Vec<AliasedPair>,
    /// Accepted effect ids.
    pub effects: Vec<String>,
    /// Accepted effects with a large sigma.
    pub loose: Vec<String>,
    /// The declared fit's calibration RMS error (`declared.calibration.rms_mm`), the size of
    /// an effect the declared model lacks ([`super::robust`]); `None` when absent.
    pub declared_rms_mm: Option<f64>,
    /// Fitted model values of the accepted effects' unknowns (`effects[].model_parameters`).
    pub fitted: Vec<(String, f64)>,
}

/// A pair after planning.
#[derive(Debug, Clone, PartialEq)]
pub struct PairReport {
    pub a: String,
    pub b: String,
    /// As reported by the diagnosis.
    pub correlation_diagnose: f64,
    /// Largest |correlation| between the two effects' estimates on the poses already measured
    /// (NaN without them).
    pub correlation_before: f64,
    /// The same with the planned poses added (NaN when a side is path-dependent).
    pub correlation_after: f64,
    /// For a pair with a path-dependent side: how the measurements separate it
    /// ([`path_protocol`]).
    pub protocol: Option<String>,
}

/// The `from_diagnose` object of `plan.json`.
#[derive(Debug, Clone, PartialEq)]
pub struct FromDiagnoseReport {
    pub file: String,
    pub pairs: Vec<PairReport>,
    pub effects: Vec<String>,
    /// Names of the unknowns the design separates.
    pub interest: Vec<String>,
    pub existing_poses: usize,
    /// The plausible magnitude of each unknown of interest the linearity test used
    /// ([`super::robust`]), by name.
    pub magnitudes: Vec<(String, f64)>,
    /// Candidates that passed the linearity test.
    pub admissible_candidates: usize,
    /// The largest nonlinearity admitted ([`robust::LINEARITY_RTOL`] unless raised).
    pub nonlinearity_threshold: f64,
    /// The path-dependent effects of the diagnosis (accepted or aliased) with the measuring
    /// order that separates each ([`path_protocol`]).
    pub path_dependent: Vec<(String, String)>,
}

/// For an effect that depends on the path to a pose or on time rather than on the pose
/// (`hysteresis:j<i>`, `time_drift`, `time_drift:j<i>`, `thermal`): the measuring order that
/// separates it from every effect of the pose alone. `None` for any other id.
pub fn path_protocol(id: &str) -> Option<String> {
    let parsed: EffectId = id.parse().ok()?;
    match parsed.row().path {
        effect::Path::Pose => None,
        effect::Path::Approach => {
            let i = parsed.joint()? + 1;
            Some(format!(
                "{id} depends on the direction joint {i} last moved, not on the pose: measure every \
                 planned pose twice, reached once with joint {i} moving up and once moving down \
                 (diagnose reads the direction from the order of the rows); the difference of the \
                 two readings separates it from every effect of the pose alone"
            ))
        }
        effect::Path::Time => Some(format!(
            "{id} grows with the time of a reading, not with the pose: give the pose file a time \
             column `t`, spread the planned poses over the session and measure the first of them \
             again at its end; the repeated readings separate it from every effect of the pose alone"
        )),
    }
}

fn field_err(path: &str, message: String) -> PlanError {
    PlanError::Diagnose {
        path: path.to_string(),
        message,
    }
}

fn is_loose(effect: &Value) -> bool {
    let values = effect.get("parameters").and_then(Value::as_object);
    let sigmas = effect
        .get("sigma")
        .or_else(|| effect.get("uncertainty"))
        .and_then(Value::as_object);
    let (Some(values), Some(sigmas)) = (values, sigmas) else {
        return false;
    };
    values.iter().any(|(k, v)| {
        let (Some(v), Some(s)) = (v.as_f64(), sigmas.get(k).and_then(Value::as_f64)) else {
            return false;
        };
        s > LOOSE_RELATIVE_SIGMA * v.abs()
    })
}

impl FromDiagnose {
    /// Parses the diagnose JSON text `text` (named `path` in messages).
    pub fn parse(path: &str, text: &str) -> Result<Self, PlanError> {
        let doc: Value = serde_json::from_str(text).map_err(|e| {
            field_err(
                path,
                format!("line {}, column {}: {e}", e.line(), e.column()),
            )
        })?;
        let mut pairs = Vec::new();
        if let Some(list) = doc.get("aliased") {
            let list = list
                .as_array()
                .ok_or_else(|| field_err(path, "field `aliased`: not an array".into()))?;
            for (k, item) in list.iter().enumerate() {
                let name = |f: &str| {
                    item.get(f)
                        .and_then(Value::as_str)
                        .map(str::to_string)
                        .ok_or_else(|| {
                            field_err(
                                path,
                                format!("field `aliased[{k}].{f}`: missing or not a string"),
                            )
                        })
                };
                let (a, b) = (name("a")?, name("b")?);
                if a == b {
                    return Err(field_err(
                        path,
                        format!("field `aliased[{k}]`: `a` and `b` are the same (`{a}`)"),
                    ));
                }
                pairs.push(AliasedPair {
                    a,
                    b,
                    correlation: item
                        .get("correlation")
                        .and_then(Value::as_f64)
                        .unwrap_or(f64::NAN),
                });
            }
        }
        let mut effects = Vec::new();
        let mut loose = Vec::new();
        let mut fitted = Vec::new();
        let effects_list = match doc.get("effects") {
            None | Some(Value::Null) => None,
            Some(v) => Some(
                v.as_array()
                    .ok_or_else(|| field_err(path, "field `effects`: not an array".into()))?,
            ),
        };
        if let Some(list) = effects_list {
            for (k, e) in list.iter().enumerate() {
                if let Some(mp) = e.get("model_parameters").and_then(Value::as_object) {
                    fitted.extend(
                        mp.iter()
                            .filter_map(|(n, v)| v.as_f64().map(|v| (n.clone(), v))),
                    );
                }
                let id = e.get("id").and_then(Value::as_str).ok_or_else(|| {
                    field_err(
                        path,
                        format!("field `effects[{k}].id`: missing or not a string"),
                    )
                })?;
                effects.push(id.to_string());
                if is_loose(e) {
                    loose.push(id.to_string());
                }
            }
        }
        if pairs.is_empty() && loose.is_empty() {
            return Err(field_err(
                path,
                "no `aliased` pair and no effect with a large sigma: nothing to separate (plan without --from-diagnose)".into(),
            ));
        }
        let declared_rms_mm = doc
            .pointer("/declared/calibration/rms_mm")
            .and_then(Value::as_f64)
            .filter(|v| v.is_finite() && *v > 0.0);
        Ok(Self {
            path: path.to_string(),
            pairs,
            effects,
            loose,
            declared_rms_mm,
            fitted,
        })
    }

    /// Reads the diagnose JSON `path`.
    pub fn read(path: &Path) -> Result<Self, PlanError> {
        let shown = path.display().to_string();
        let text = crate::io::read::read_text_capped(path, crate::io::read::CAP_SMALL_TEXT)
            .map_err(|e| field_err(&shown, format!("cannot read: {e}")))?;
        Self::parse(&shown, &text)
    }

    /// The unknowns of an effect id or a parameter name.
    fn unknowns_of(
        &self,
        ext: &ExtModel,
        id: &str,
        field: &str,
    ) -> Result<Vec<Unknown>, PlanError> {
        if let Some(c) = library_for(ext, &[], true, true)
            .into_iter()
            .find(|c| c.id == id)
        {
            return Ok(c.unknowns);
        }
        match ext.model.param_index(id) {
            Some(i) => Ok(vec![Unknown::Param(i)]),
            None => Err(field_err(
                &self.path,
                format!("field `{field}`: `{id}` is neither an effect id of this model nor one of its parameters"),
            )),
        }
    }

    /// The design problem (see the module docs).
    pub fn setup(
        &self,
        model: &Model,
        cands: &[CandidatePose],
        existing_q: &[Vec<f64>],
    ) -> Result<Setup, PlanError> {
        let ext = ExtModel::new(model.clone());
        let mut requested: Vec<Unknown> = default_selection(model, false)
            .into_iter()
            .map(Unknown::Param)
            .collect();
        let push = |us: Vec<Unknown>, requested: &mut Vec<Unknown>| {
            for u in us {
                if !requested.contains(&u) {
                    requested.push(u);
                }
            }
        };
        let mut interest = Vec::new();
        for (k, id) in self.effects.iter().enumerate() {
            if path_protocol(id).is_some() {
                continue;
            }
            let us = self.unknowns_of(&ext, id, &format!("effects[{k}].id"))?;
            if self.loose.contains(id) {
                interest.extend(us.iter().copied());
            }
            push(us, &mut requested);
        }
        for (k, p) in self.pairs.iter().enumerate() {
            for (f, id) in [("a", &p.a), ("b", &p.b)] {
                if path_protocol(id).is_some() {
                    continue;
                }
                let us = self.unknowns_of(&ext, id, &format!("aliased[{k}].{f}"))?;
                interest.extend(us.iter().copied());
                push(us, &mut requested);
            }
        }
        let mut setup = Setup::build(ext, cands, &requested, &interest, existing_q)?;
        let target_mm = self.declared_rms_mm.unwrap_or(DEFAULT_EFFECT_RMS_MM);
        let sizing = robust::sizing_poses(cands);
        let (mut unknowns, mut magnitudes) = (Vec::new(), Vec::new());
        for &c in &setup.interest {
            let u = setup.unknowns[c];
            let name = u.name(&setup.ext.model);
            let change = self
                .fitted
                .iter()
                .find(|(n, _)| *n == name)
                .map(|(_, v)| (v - setup.ext.value(u)).abs())
                .filter(|d| *d > 0.0 && d.is_finite());
            // the linear guess: the column's RMS over the candidates is `scale` (mm per unit)
            let linear = target_mm / setup.scale[c];
            if let Some(m) = change
                .or_else(|| robust::effect_magnitude(&setup.ext, u, &sizing, target_mm, linear))
            {
                unknowns.push(u);
                magnitudes.push(m);
            }
        }
        let mut linearity = robust::Linearity::new(&setup.ext, unknowns, magnitudes);
        setup.admissible = linearity.admissible(cands)?;
        setup.linearity = Some(linearity);
        Ok(setup)
    }

    /// The report after planning `chosen` (candidate indices of `setup`).
    pub fn report(&self, setup: &Setup, chosen: &[usize]) -> FromDiagnoseReport {
        let ext = &setup.ext;
        let cols_of = |id: &str| -> Vec<usize> {
            self.unknowns_of(ext, id, "")
                .unwrap_or_default()
                .iter()
                .filter_map(|u| setup.unknowns.iter().position(|v| v == u))
                .collect()
        };
        let after_rows = super::metrics::stack_rows(
            &setup.b,
            super::criteria::POSE_ROWS,
            &vec![1.0; setup.b.ncols()],
            &setup.prior_rows,
            chosen,
        );
        let pairs = self
            .pairs
            .iter()
            .map(|p| {
                let (ca, cb) = (cols_of(&p.a), cols_of(&p.b));
                let protocol = path_protocol(&p.a).or_else(|| path_protocol(&p.b));
                if protocol.is_some() {
                    return PairReport {
                        a: p.a.clone(),
                        b: p.b.clone(),
                        correlation_diagnose: p.correlation,
                        correlation_before: f64::NAN,
                        correlation_after: f64::NAN,
                        protocol,
                    };
                }
                PairReport {
                    a: p.a.clone(),
                    b: p.b.clone(),
                    correlation_diagnose: p.correlation,
                    correlation_before: if setup.prior_rows.nrows() == 0 {
                        f64::NAN
                    } else {
                        max_correlation(&setup.prior_rows, &ca, &cb)
                    },
                    correlation_after: max_correlation(&after_rows, &ca, &cb),
                    protocol: None,
                }
            })
            .collect();
        FromDiagnoseReport {
            file: self.path.clone(),
            pairs,
            effects: self.effects.clone(),
            interest: setup
                .interest
                .iter()
                .map(|&c| setup.names[c].clone())
                .collect(),
            existing_poses: setup.prior_rows.nrows() / 3,
            magnitudes: setup
                .linearity
                .as_ref()
                .map(|l| {
                    l.unknowns
                        .iter()
                        .zip(&l.magnitudes)
                        .map(|(u, m)| (u.name(&ext.model), *m))
                        .collect()
                })
                .unwrap_or_default(),
            admissible_candidates: setup.admissible.iter().filter(|a| **a).count(),
            path_dependent: {
                let mut ids: Vec<&String> = self.effects.iter().collect();
                ids.extend(self.pairs.iter().flat_map(|p| [&p.a, &p.b]));
                let mut out: Vec<(String, String)> = Vec::new();
                for id in ids {
                    if let Some(p) = path_protocol(id).filter(|_| !out.iter().any(|(i, _)| i == id))
                    {
                        out.push((id.clone(), p));
                    }
                }
                out
            },
            nonlinearity_threshold: setup
                .linearity
                .as_ref()
                .map_or(f64::INFINITY, |l| l.threshold),
        }
    }
}

/// Largest |correlation| between the estimates of any column of `a` and any of `b` from the
/// rows `jac` (covariance `(J^T J + ridge)^-1`, the ridge making an exact alias read 1).
pub fn max_correlation(jac: &DMatrix<f64>, a: &[usize], b: &[usize]) -> f64 {
    let p = jac.ncols();
    let m = jac.transpose() * jac;
    let ridge = 1e-10 * (m.trace() / p.max(1) as f64).max(f64::MIN_POSITIVE);
    let Some(cov) = (m + DMatrix::identity(p, p) * ridge)
        .cholesky()
        .map(|c| c.inverse())
    else {
        return f64::NAN;
    };
    let mut worst: f64 = 0.0;
    for &i in a {
        for &j in b {
            if i == j {
                return 1.0;
            }
            let r = cov[(i, j)] / (cov[(i, i)] * cov[(j, j)]).sqrt();
            worst = worst.max(r.abs());
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sizes the linearity test needs come from the diagnose JSON when it has them.
    #[test]
    fn parse_reads_the_declared_residual_and_the_fitted_values() {
        let json = r#"{"declared": {"calibration": {"rms_mm": 0.25}},
            "effects": [{"id": "link_length:a3", "parameters": {"delta_mm": 0.29},
                         "sigma": {"delta_mm": 0.016}, "model_parameters": {"a3": 139.29}}],
            "aliased": [{"a": "link_length:a3", "b": "payload", "correlation": 0.9}]}"#;
        let f = FromDiagnose::parse("d.json", json).unwrap();
        assert_eq!(f.declared_rms_mm, Some(0.25));
        assert_eq!(f.fitted, vec![("a3".to_string(), 139.29)]);
        assert!(f.loose.is_empty());
        let bare = r#"{"aliased": [{"a": "payload", "b": "link_length:a3"}]}"#;
        let f = FromDiagnose::parse("d.json", bare).unwrap();
        assert_eq!(f.declared_rms_mm, None);
        assert!(f.fitted.is_empty());
    }
}
