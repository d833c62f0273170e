//! What an effect of a given size changes in a model (`simulate --effect ID=VALUE`): deltas of
//! named parameters, a term of the joint map, a time term. The values are the row's
//! `sim_values` ([`super::Row`]); deltas, not absolute values, so that a VALUE is the effect's
//! size.

use nalgebra::Vector3;

use super::EffectId;
use crate::io::ranges::{show, MAX_ANGLE_DEG, MAX_POSITION_MM};
use crate::model::changes::{Step, StepKind};
use crate::model::ranges as r;

/// What an effect changes.
#[derive(Debug, Clone, PartialEq)]
pub enum Change {
    /// Deltas added to named model parameters.
    Params(Vec<(String, f64)>),
    /// Measured position drift, mm per hour in frame R.
    PositionDrift(Vector3<f64>),
    /// Joint offset drift of joint index (0-based), deg per hour.
    JointDrift(usize, f64),
    /// A term on the joint angles before the chain (transmission, hysteresis, compliance).
    Joint(JointTerm),
    /// Lateral compliance of joint index (0-based), deg per kgf.m, added to the model's.
    LateralCompliance(usize, f64),
    /// Warm-up growth: ppm at saturation, time constant in min.
    Thermal { ppm: f64, tau_min: f64 },
    /// A change within the session at a time.
    Step(Step),
}

/// A joint-angle term, 0-based joint indices.
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
    /// The joints it names (0-based; twice the same for a one-joint term).
    pub fn joints(&self) -> [usize; 2] {
        match *self {
            JointTerm::Scale(j, _) | JointTerm::Hysteresis(j, _) | JointTerm::Compliance(j, _) => {
                [j, j]
            }
            JointTerm::Coupling(i, k, _) => [i, k],
        }
    }
}

/// Values that do not fit an effect: the wrong count, or out of physical range.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ChangeError(pub String);

impl EffectId {
    /// The change this effect makes with `values` (its row's `sim_values`), checked against
    /// the physical ranges of [`crate::model::ranges`] (parameter deltas are checked on the
    /// model they produce).
    pub fn change(&self, values: &[f64]) -> Result<Change, ChangeError> {
        let row = self.row();
        let (counts, what) = row.sim_values;
        if !counts.contains(&values.len()) {
            let counts: Vec<String> = counts.iter().map(|n| n.to_string()).collect();
            return Err(ChangeError(format!(
                "expected {} comma-separated value(s) ({what})",
                counts.join(" or ")
            )));
        }
        let v0 = values[0];
        let params = |names: &[String]| {
            Change::Params(names.iter().cloned().zip(values.iter().copied()).collect())
        };
        let named =
            |names: &[&str]| params(&names.iter().map(|n| n.to_string()).collect::<Vec<_>>());
        let change = match self {
            EffectId::LinkLength(name) => params(std::slice::from_ref(name)),
            EffectId::EncoderHarmonic { joint, order } => {
                let phi = values.get(1).copied().unwrap_or(0.0).to_radians();
                let (i, n) = (joint + 1, order);
                Change::Params(vec![
                    (format!("enc_j{i}_h{n}_sin"), v0 * phi.cos()),
                    (format!("enc_j{i}_h{n}_cos"), v0 * phi.sin()),
                ])
            }
            EffectId::ToolOffset => named(&["tool_dx", "tool_dy", "tool_dz"]),
            EffectId::ToolLength => named(&["tool_dz"]),
            EffectId::BaseOffset => named(&["base_x", "base_y", "base_z"]),
            EffectId::BaseTilt => named(&["base_rx", "base_ry"]),
            EffectId::Payload => named(&["payload_kg"]),
            EffectId::Scale => named(&["scale_ppm"]),
            EffectId::Stiffness(j) | EffectId::Backlash(j) | EffectId::Clearance(j) => {
                params(&[format!("{}_j{}", self.kind().family(), j + 1)])
            }
            EffectId::TimeDrift => Change::PositionDrift(match values {
                [v] => Vector3::new(0.0, 0.0, *v),
                _ => Vector3::new(values[0], values[1], values[2]),
            }),
            EffectId::JointDrift(j) => Change::JointDrift(*j, v0),
            EffectId::JointScale(j) => Change::Joint(JointTerm::Scale(*j, v0)),
            EffectId::JointCoupling(i, k) => Change::Joint(JointTerm::Coupling(*i, *k, v0)),
            EffectId::Hysteresis(j) => Change::Joint(JointTerm::Hysteresis(*j, v0)),
            EffectId::Compliance(j) => Change::Joint(JointTerm::Compliance(*j, v0)),
            EffectId::LateralCompliance(j) => Change::LateralCompliance(*j, v0),
            EffectId::Thermal => {
                let tau_min = values[1];
                if tau_min.is_nan() || tau_min <= 0.0 {
                    return Err(ChangeError(
                        "the time constant (second value, min) must be > 0".into(),
                    ));
                }
                Change::Thermal { ppm: v0, tau_min }
            }
            EffectId::ToolChange => Change::Step(Step {
                t_s: values[3],
                kind: StepKind::Tool(Vector3::new(values[0], values[1], values[2])),
            }),
            EffectId::PayloadChange => Change::Step(Step {
                t_s: values[1],
                kind: StepKind::Payload(v0),
            }),
        };
        change.check_range()?;
        Ok(change)
    }
}

impl Change {
    /// Every value within its physical range.
    fn check_range(&self) -> Result<(), ChangeError> {
        let (values, limit): (Vec<f64>, f64) = match self {
            Change::Params(list) => (list.iter().map(|(_, v)| *v).collect(), MAX_POSITION_MM),
            Change::PositionDrift(v) => (v.iter().copied().collect(), MAX_POSITION_MM),
            Change::JointDrift(_, v) => (vec![*v], MAX_ANGLE_DEG),
            Change::Joint(JointTerm::Scale(_, v)) => (vec![*v], r::MAX_JOINT_SCALE),
            Change::Joint(JointTerm::Coupling(_, _, v)) => (vec![*v], r::MAX_COUPLING),
            Change::Joint(JointTerm::Hysteresis(_, v)) => (vec![*v], r::MAX_HYSTERESIS_DEG),
            Change::Joint(JointTerm::Compliance(_, v)) | Change::LateralCompliance(_, v) => {
                (vec![*v], r::MAX_COMPLIANCE)
            }
            Change::Thermal { ppm, tau_min } => {
                if *tau_min > r::MAX_THERMAL_TAU_MIN {
                    return Err(ChangeError(format!(
                        "tau {tau_min} min is beyond {} min",
                        r::MAX_THERMAL_TAU_MIN
                    )));
                }
                (vec![*ppm], r::MAX_THERMAL_PPM)
            }
            Change::Step(step) => {
                if !(step.t_s.is_finite() && step.t_s >= 0.0) {
                    return Err(ChangeError(format!(
                        "the change time t_s (last value, s) must be >= 0, not {}",
                        show(step.t_s)
                    )));
                }
                match step.kind {
                    StepKind::Tool(d) => (d.iter().copied().collect(), MAX_POSITION_MM),
                    StepKind::Payload(kg) => (vec![kg], r::MAX_MASS_KG),
                }
            }
        };
        match values.iter().find(|v| !(v.is_finite() && v.abs() <= limit)) {
            Some(v) => Err(ChangeError(format!(
                "{} is out of physical range (|value| <= {limit})",
                show(*v)
            ))),
            None => Ok(()),
        }
    }
}
