//! Effects the declared model lacks, applied to the simulated truth (`--effect ID=VALUE`).
//!
//! The ids, the values each takes and the change each makes are the effect table's
//! ([`crate::model::effect`]: [`EffectId`] parses the id, [`EffectId::change`] turns the values
//! into a [`Change`]); this module reads the argument and applies the change. Deltas (not
//! absolute values) are used throughout so that an effect's VALUE is its size: a parameter
//! delta is **added** to the declared value (a stiffness must stay > 0). The joint terms and
//! the time terms are carried by the truth model itself
//! ([`crate::model::transmission::JointTerms`], [`crate::model::time_terms::TimeTerms`]), so
//! `truth.toml` evaluates to the simulated measurements without noise.

pub use crate::model::effect::{Change, JointTerm};
use crate::model::effect::{EffectId, UnknownEffectId};
use crate::model::{Model, ModelError};

/// A bad `--effect` argument.
#[derive(Debug, thiserror::Error)]
pub enum EffectError {
    /// No `=` in the argument.
    #[error("effect `{0}`: expected ID=VALUE")]
    Syntax(String),
    /// An effect id the effect table does not know.
    #[error(transparent)]
    UnknownId(#[from] UnknownEffectId),
    /// A value that is not a finite number, or the wrong number of values.
    #[error("effect `{id}`: value `{value}`: {reason}")]
    BadValue {
        id: String,
        value: String,
        reason: String,
    },
    /// The model rejected the changed parameter (e.g. a joint it does not have, stiffness <= 0).
    #[error("effect `{id}`: {source}")]
    Model {
        id: String,
        #[source]
        source: ModelError,
    },
}

impl crate::error::Classify for EffectError {
    fn kind(&self) -> crate::error::ErrorKind {
        crate::error::ErrorKind::BadInput
    }
}

/// One parsed `--effect`.
#[derive(Debug, Clone, PartialEq)]
pub struct Effect {
    /// The effect id as given (e.g. `encoder_harmonic:j2:h1`).
    pub id: String,
    /// The values as given.
    pub values: Vec<f64>,
    /// What it does to the truth.
    pub change: Change,
}

/// Parses `ID=VALUE` (see the module documentation).
pub fn parse_effect(arg: &str) -> Result<Effect, EffectError> {
    let (id, raw) = arg
        .split_once('=')
        .ok_or_else(|| EffectError::Syntax(arg.to_string()))?;
    let (id, raw) = (id.trim(), raw.trim());
    let effect: EffectId = id.parse()?;
    let values: Vec<f64> = raw
        .split(',')
        .map(|s| {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| EffectError::BadValue {
                    id: id.into(),
                    value: raw.into(),
                    reason: format!("`{}` is not a finite number", s.trim()),
                })
        })
        .collect::<Result<_, _>>()?;
    let change = effect.change(&values).map_err(|e| EffectError::BadValue {
        id: id.into(),
        value: raw.into(),
        reason: e.0,
    })?;
    Ok(Effect {
        id: id.to_string(),
        values,
        change,
    })
}

impl Effect {
    /// Adds this effect to `model`: parameter deltas, joint terms, time terms. Checks that the
    /// joints it names exist.
    pub fn apply(&self, model: &mut Model) -> Result<(), EffectError> {
        let err = |source| EffectError::Model {
            id: self.id.clone(),
            source,
        };
        match &self.change {
            Change::Params(list) => {
                for (name, delta) in list {
                    let v = model.param(name).ok_or_else(|| {
                        err(ModelError::UnknownParam {
                            name: name.clone(),
                            valid: model.param_names().collect::<Vec<_>>().join(", "),
                        })
                    })?;
                    model.set_param(name, v + delta).map_err(err)?;
                }
                Ok(())
            }
            Change::PositionDrift(v) => {
                model.time_terms_mut().drift_mm_per_h += v;
                Ok(())
            }
            Change::Thermal { ppm, tau_min } => {
                let t = model.time_terms_mut();
                t.thermal_ppm = *ppm;
                t.thermal_tau_min = *tau_min;
                Ok(())
            }
            Change::Joint(term) => {
                for j in term.joints() {
                    if j >= model.n_joints() {
                        return Err(err(ModelError::JointIndex {
                            index: j,
                            count: model.n_joints(),
                        }));
                    }
                }
                if matches!(term, JointTerm::Compliance(..))
                    && crate::model::gravity::GravityModel::for_model(model).is_none()
                {
                    return Err(EffectError::BadValue {
                        id: self.id.clone(),
                        value: format!("{:?}", self.values),
                        reason: "the model has no link masses ([[mass]] rows) for gravity torques"
                            .into(),
                    });
                }
                let n = model.n_joints();
                let mut terms = model.transmission().sized(n);
                match *term {
                    JointTerm::Scale(j, v) => terms.scale[j] += v,
                    JointTerm::Coupling(i, k, v) => terms.coupling[i][k] += v,
                    JointTerm::Hysteresis(j, v) => terms.hysteresis_deg[j] += v,
                    JointTerm::Compliance(j, v) => terms.compliance_deg_per_kgfm[j] += v,
                }
                model.set_transmission(terms);
                Ok(())
            }
            Change::LateralCompliance(j, v) => {
                if crate::model::gravity::GravityModel::for_model(model).is_none() {
                    return Err(EffectError::BadValue {
                        id: self.id.clone(),
                        value: format!("{:?}", self.values),
                        reason: "the model has no link masses ([[mass]] rows) for gravity moments"
                            .into(),
                    });
                }
                let c = model.lateral_compliance_at(*j) + v;
                model.set_lateral_compliance(*j, c).map_err(err)
            }
            Change::Step(step) => {
                let mut m = model.clone();
                m.time_terms_mut().changes.push(*step);
                m.check_steps().map_err(err)?;
                let changes = &mut model.time_terms_mut().changes;
                changes.push(*step);
                changes.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
                Ok(())
            }
            Change::JointDrift(j, rate) => {
                let n = model.n_joints();
                if *j >= n {
                    return Err(err(ModelError::JointIndex {
                        index: *j,
                        count: n,
                    }));
                }
                let rates = &mut model.time_terms_mut().joint_drift_deg_per_h;
                rates.resize(n, 0.0);
                rates[*j] += rate;
                Ok(())
            }
        }
    }
}
