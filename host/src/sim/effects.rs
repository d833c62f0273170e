//! Effects the declared model lacks (FORMATS.md effect ids), applied to the simulated truth.
//!
//! `--effect ID=VALUE`: VALUE is one number or a comma-separated list:
//!
//! | id | VALUE | applied as |
//! |---|---|---|
//! | `link_length:a2` `:a3` `:d4` `:d5` | delta mm | added to that length parameter |
//! | `encoder_harmonic:j<i>:h<n>` | `A,phi` (deg, deg; `A` alone means phi = 0) | joint error `A sin(n q_i + phi)`: `enc_j<i>_h<n>_sin += A cos phi`, `enc_j<i>_h<n>_cos += A sin phi` |
//! | `tool_offset` | `dx,dy,dz` mm | `tool_dx/dy/dz` (last link frame) |
//! | `base_offset` | `dx,dy,dz` mm | `base_x/y/z` (frame R) |
//! | `base_tilt` | `rx,ry` deg | `base_rx/ry`: the chain rotates about x, y of R while gravity stays along -z of R, so gravity changes direction in robot coordinates |
//! | `payload` | kg | `payload_kg` (a point mass at the tool point: moments, so tilting) |
//! | `scale` | ppm | `scale_ppm` (instrument scale about the origin of R) |
//! | `stiffness:j<i>` | delta kgf.m/deg | **added** to the declared `stiffness_j<i>` (the result must stay > 0) |
//! | `backlash:j<i>` `clearance:j<i>` | delta deg | **added** to the declared `backlash_j<i>` / `clearance_j<i>` |
//! | `time_drift` | `vx,vy,vz` mm per hour (one value `v` means `0,0,v`) | measured position += v t / 3600 (a thermal drift of the instrument or base, linear in the pose time `t`) |
//! | `time_drift:j<i>` | deg per hour | joint i's angle grows by rate x t / 3600 (thermal drift of the encoder zero) |
//! | `thermal` | `s,tau` (ppm, min) | warm-up: every length from the origin of R to the tool point x `1 + s 1e-6 (1 - exp(-t / tau))` |
//! | `joint_scale:j<i>` | `s` (dimensionless) | transmission-ratio error: joint i turns `(1 + s) q_i` |
//! | `joint_coupling:j<i>:j<k>` | `c` deg/deg | joint i's angle += `c q_k` |
//! | `hysteresis:j<i>` | `b` deg | joint i's angle += `b` when it last moved up before the pose, `- b` when down, 0 before its first move (pose order of each file, FORMATS.md) |
//! | `compliance:j<i>` | deg per kgf.m | joint i's angle += value x the gravity torque about its axis (link masses of the model, [`crate::model::gravity`]) |
//!
//! Deltas (not absolute values) are used throughout so that an effect's VALUE is its size. The
//! joint terms and the time terms are carried by the truth model itself
//! ([`crate::model::transmission::JointTerms`], [`crate::model::time_terms::TimeTerms`]), so
//! `truth.toml` evaluates to the simulated measurements without noise.

use nalgebra::Vector3;

use crate::model::{Model, ModelError};

/// A bad `--effect` argument.
#[derive(Debug, thiserror::Error)]
pub enum EffectError {
    /// No `=` in the argument.
    #[error("effect `{0}`: expected ID=VALUE")]
    Syntax(String),
    /// An effect id this simulator does not know.
    #[error("unknown effect id `{id}`; known: link_length:a2|a3|d4|d5, encoder_harmonic:j<i>:h<n>, tool_offset, base_offset, base_tilt, payload, scale, stiffness:j<i>, backlash:j<i>, clearance:j<i>, time_drift, time_drift:j<i>, thermal, joint_scale:j<i>, joint_coupling:j<i>:j<k>, hysteresis:j<i>, compliance:j<i>")]
    UnknownId { id: String },
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

/// What an effect changes.
#[derive(Debug, Clone, PartialEq)]
pub enum EffectKind {
    /// Deltas added to named model parameters.
    Params(Vec<(String, f64)>),
    /// Measured position drift, mm per hour in frame R.
    PositionDrift(Vector3<f64>),
    /// Joint offset drift of joint index (0-based), deg per hour.
    JointDrift(usize, f64),
    /// A term on the joint angles before the chain (transmission, hysteresis, compliance).
    Joint(JointTerm),
    /// Warm-up growth: ppm at saturation, time constant in min.
    Thermal { ppm: f64, tau_min: f64 },
}

/// A joint-angle term of the truth, 0-based joint indices.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JointTerm {
    /// `q_i += s q_i`.
    Scale(usize, f64),
    /// `q_i += c q_k` as `(i, k, c)`.
    Coupling(usize, usize, f64),
    /// `q_i += b d_i` (direction of approach).
    Hysteresis(usize, f64),
    /// `q_i += c tau_i` (gravity torque about the axis, kgf.m).
    Compliance(usize, f64),
}

impl JointTerm {
    fn joints(&self) -> [usize; 2] {
        match *self {
            JointTerm::Scale(j, _) | JointTerm::Hysteresis(j, _) | JointTerm::Compliance(j, _) => {
                [j, j]
            }
            JointTerm::Coupling(i, k, _) => [i, k],
        }
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
    pub kind: EffectKind,
}

fn joint_index(id: &str, s: &str) -> Result<usize, EffectError> {
    s.strip_prefix('j')
        .and_then(|n| n.parse::<usize>().ok())
        .filter(|&n| n >= 1)
        .ok_or_else(|| EffectError::UnknownId { id: id.to_string() })
}

fn expect_count(id: &str, raw: &str, values: &[f64], allowed: &[usize]) -> Result<(), EffectError> {
    if allowed.contains(&values.len()) {
        Ok(())
    } else {
        Err(EffectError::BadValue {
            id: id.into(),
            value: raw.into(),
            reason: format!(
                "expected {} comma-separated value(s)",
                allowed
                    .iter()
                    .map(|n| n.to_string())
                    .collect::<Vec<_>>()
                    .join(" or ")
            ),
        })
    }
}

/// Parses `ID=VALUE` (see the module documentation).
pub fn parse_effect(arg: &str) -> Result<Effect, EffectError> {
    let (id, raw) = arg
        .split_once('=')
        .ok_or_else(|| EffectError::Syntax(arg.to_string()))?;
    let (id, raw) = (id.trim(), raw.trim());
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
    let parts: Vec<&str> = id.split(':').collect();
    let one = |name: String| -> Result<EffectKind, EffectError> {
        expect_count(id, raw, &values, &[1])?;
        Ok(EffectKind::Params(vec![(name, values[0])]))
    };
    let names3 = |names: [&str; 3]| -> Result<EffectKind, EffectError> {
        expect_count(id, raw, &values, &[3])?;
        Ok(EffectKind::Params(
            names
                .iter()
                .zip(&values)
                .map(|(n, v)| (n.to_string(), *v))
                .collect(),
        ))
    };
    let kind = match parts.as_slice() {
        ["link_length", l @ ("a2" | "a3" | "d4" | "d5")] => one(l.to_string())?,
        ["encoder_harmonic", j, h] => {
            let ji = joint_index(id, j)?;
            let n = h
                .strip_prefix('h')
                .and_then(|n| n.parse::<u32>().ok())
                .filter(|n| (1..=3).contains(n))
                .ok_or_else(|| EffectError::UnknownId { id: id.to_string() })?;
            expect_count(id, raw, &values, &[1, 2])?;
            let amp = values[0];
            let phi = values.get(1).copied().unwrap_or(0.0).to_radians();
            EffectKind::Params(vec![
                (format!("enc_j{ji}_h{n}_sin"), amp * phi.cos()),
                (format!("enc_j{ji}_h{n}_cos"), amp * phi.sin()),
            ])
        }
        ["tool_offset"] => names3(["tool_dx", "tool_dy", "tool_dz"])?,
        ["base_offset"] => names3(["base_x", "base_y", "base_z"])?,
        ["base_tilt"] => {
            expect_count(id, raw, &values, &[2])?;
            EffectKind::Params(vec![
                ("base_rx".into(), values[0]),
                ("base_ry".into(), values[1]),
            ])
        }
        ["payload"] => one("payload_kg".into())?,
        ["scale"] => one("scale_ppm".into())?,
        [what @ ("stiffness" | "backlash" | "clearance"), j] => {
            let ji = joint_index(id, j)?;
            one(format!("{what}_j{ji}"))?
        }
        ["time_drift"] => {
            expect_count(id, raw, &values, &[1, 3])?;
            let v = if values.len() == 1 {
                Vector3::new(0.0, 0.0, values[0])
            } else {
                Vector3::new(values[0], values[1], values[2])
            };
            EffectKind::PositionDrift(v)
        }
        ["joint_scale", j] => {
            expect_count(id, raw, &values, &[1])?;
            EffectKind::Joint(JointTerm::Scale(joint_index(id, j)? - 1, values[0]))
        }
        ["joint_coupling", i, k] => {
            expect_count(id, raw, &values, &[1])?;
            let (i, k) = (joint_index(id, i)? - 1, joint_index(id, k)? - 1);
            if i == k {
                return Err(EffectError::UnknownId { id: id.to_string() });
            }
            EffectKind::Joint(JointTerm::Coupling(i, k, values[0]))
        }
        ["hysteresis", j] => {
            expect_count(id, raw, &values, &[1])?;
            EffectKind::Joint(JointTerm::Hysteresis(joint_index(id, j)? - 1, values[0]))
        }
        ["compliance", j] => {
            expect_count(id, raw, &values, &[1])?;
            EffectKind::Joint(JointTerm::Compliance(joint_index(id, j)? - 1, values[0]))
        }
        ["thermal"] => {
            expect_count(id, raw, &values, &[2])?;
            if values[1].is_nan() || values[1] <= 0.0 {
                return Err(EffectError::BadValue {
                    id: id.into(),
                    value: raw.into(),
                    reason: "the time constant (second value, min) must be > 0".into(),
                });
            }
            EffectKind::Thermal {
                ppm: values[0],
                tau_min: values[1],
            }
        }
        ["time_drift", j] => {
            let ji = joint_index(id, j)?;
            expect_count(id, raw, &values, &[1])?;
            EffectKind::JointDrift(ji - 1, values[0])
        }
        _ => return Err(EffectError::UnknownId { id: id.to_string() }),
    };
    effect_in_range(id, raw, &kind)?;
    Ok(Effect {
        id: id.to_string(),
        values,
        kind,
    })
}

/// The physical range of an effect's value ([`crate::model::ranges`]; parameter deltas are
/// checked on the truth model they produce, see [`crate::sim::simulate::truth_model`]).
fn effect_in_range(id: &str, raw: &str, kind: &EffectKind) -> Result<(), EffectError> {
    use crate::io::ranges::{MAX_ANGLE_DEG, MAX_POSITION_MM};
    use crate::model::ranges as r;
    let (values, limit): (Vec<f64>, f64) = match kind {
        EffectKind::Params(list) => (list.iter().map(|(_, v)| *v).collect(), MAX_POSITION_MM),
        EffectKind::PositionDrift(v) => (v.iter().copied().collect(), MAX_POSITION_MM),
        EffectKind::JointDrift(_, v) => (vec![*v], MAX_ANGLE_DEG),
        EffectKind::Joint(JointTerm::Scale(_, v)) => (vec![*v], r::MAX_JOINT_SCALE),
        EffectKind::Joint(JointTerm::Coupling(_, _, v)) => (vec![*v], r::MAX_COUPLING),
        EffectKind::Joint(JointTerm::Hysteresis(_, v)) => (vec![*v], r::MAX_HYSTERESIS_DEG),
        EffectKind::Joint(JointTerm::Compliance(_, v)) => (vec![*v], r::MAX_COMPLIANCE),
        EffectKind::Thermal { ppm, tau_min } => {
            if *tau_min > r::MAX_THERMAL_TAU_MIN {
                return Err(EffectError::BadValue {
                    id: id.into(),
                    value: raw.into(),
                    reason: format!("tau {tau_min} min is beyond {} min", r::MAX_THERMAL_TAU_MIN),
                });
            }
            (vec![*ppm], r::MAX_THERMAL_PPM)
        }
    };
    match values.iter().find(|v| !(v.is_finite() && v.abs() <= limit)) {
        Some(v) => Err(EffectError::BadValue {
            id: id.into(),
            value: raw.into(),
            reason: format!(
                "{} is out of physical range (|value| <= {limit})",
                crate::io::ranges::show(*v)
            ),
        }),
        None => Ok(()),
    }
}

impl Effect {
    /// Adds this effect to `model`: parameter deltas, joint terms, time terms. Checks that the
    /// joints it names exist.
    pub fn apply(&self, model: &mut Model) -> Result<(), EffectError> {
        let err = |source| EffectError::Model {
            id: self.id.clone(),
            source,
        };
        match &self.kind {
            EffectKind::Params(list) => {
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
            EffectKind::PositionDrift(v) => {
                model.time_terms_mut().drift_mm_per_h += v;
                Ok(())
            }
            EffectKind::Thermal { ppm, tau_min } => {
                let t = model.time_terms_mut();
                t.thermal_ppm = *ppm;
                t.thermal_tau_min = *tau_min;
                Ok(())
            }
            EffectKind::Joint(term) => {
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
            EffectKind::JointDrift(j, rate) => {
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
