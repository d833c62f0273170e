//! The one [`Values`] impl of the state ([`ExtModel`]): every [`Unknown`] read from and written
//! into the model's chain parameters, joint map, time terms, changes within a session and the
//! point offsets.

use super::{offsets_elsewhere, ExtModel};
use super::{Unknown, Values};
use crate::model::changes::StepKind;
use crate::model::ModelError;

impl Values for ExtModel {
    fn value(&self, u: Unknown) -> f64 {
        let (t, time) = (self.model.transmission(), self.model.time_terms());
        let at = |v: &[f64], j: usize| v.get(j).copied().unwrap_or(0.0);
        match u {
            // a parameter the model lacks is no value (NaN, refused by `set_value`)
            Unknown::Param(i) => self.model.params().get(i).map_or(f64::NAN, |p| p.value),
            Unknown::PositionDrift(a) => time.drift_mm_per_h[a.min(2)],
            Unknown::JointDrift(j) => at(&time.joint_drift_deg_per_h, j),
            Unknown::Compliance(j) => at(&t.compliance_deg_per_kgfm, j),
            Unknown::LateralCompliance(j) => self.model.lateral_compliance_at(j),
            Unknown::JointScale(j) => at(&t.scale, j),
            Unknown::Coupling(i, k) => t.coupling_at(i, k),
            Unknown::Hysteresis(j) => at(&t.hysteresis_deg, j),
            Unknown::ThermalPpm => time.thermal_ppm,
            Unknown::ThermalTauMin => time.thermal_tau_min,
            Unknown::Offset { slot, axis } => self
                .offsets_mm
                .get(slot)
                .map_or(f64::NAN, |o| o[axis.min(2)]),
            Unknown::ToolStep { slot, axis } => match time.changes.get(slot).map(|s| s.kind) {
                Some(StepKind::Tool(d)) => d[axis.min(2)],
                _ => 0.0,
            },
            Unknown::PayloadStep(slot) => match time.changes.get(slot).map(|s| s.kind) {
                Some(StepKind::Payload(kg)) => kg,
                _ => 0.0,
            },
        }
    }

    fn set_value(&mut self, u: Unknown, v: f64) -> Result<(), ModelError> {
        if !v.is_finite() {
            return Err(ModelError::NonFinite {
                name: u.name(&self.model),
                value: v,
            });
        }
        let set = |slot: Option<&mut f64>| {
            if let Some(x) = slot {
                *x = v;
            }
        };
        match u {
            Unknown::Param(i) => self.model.set_param_at(i, v)?,
            Unknown::PositionDrift(a) => self.model.time_terms_mut().drift_mm_per_h[a.min(2)] = v,
            Unknown::JointDrift(j) => {
                set(self.model.time_terms_mut().joint_drift_deg_per_h.get_mut(j));
            }
            Unknown::Compliance(j) => {
                set(self
                    .model
                    .transmission_mut()
                    .compliance_deg_per_kgfm
                    .get_mut(j));
            }
            // a joint beyond the chain is no value (as a missing term above)
            Unknown::LateralCompliance(j) => {
                if j < self.model.n_joints() {
                    self.model.set_lateral_compliance(j, v)?;
                }
            }
            Unknown::JointScale(j) => set(self.model.transmission_mut().scale.get_mut(j)),
            Unknown::Coupling(i, k) => set(self
                .model
                .transmission_mut()
                .coupling
                .get_mut(i)
                .and_then(|r| r.get_mut(k))),
            Unknown::Hysteresis(j) => {
                set(self.model.transmission_mut().hysteresis_deg.get_mut(j));
            }
            Unknown::ThermalPpm => self.model.time_terms_mut().thermal_ppm = v,
            Unknown::ThermalTauMin => {
                // a time constant is positive: the fit's step is kept within the bound
                let v = crate::model::effect::bound(u, &self.model).map_or(v, |b| b.clamp(v));
                self.model.time_terms_mut().thermal_tau_min = v;
            }
            Unknown::Offset { slot, axis } => match self.offsets_mm.get_mut(slot) {
                Some(o) => o[axis.min(2)] = v,
                None => return Err(offsets_elsewhere(u, &self.model)),
            },
            Unknown::ToolStep { slot, axis } => {
                if let Some(StepKind::Tool(d)) = self.step_kind(slot) {
                    d[axis.min(2)] = v;
                }
            }
            Unknown::PayloadStep(slot) => {
                if let Some(StepKind::Payload(kg)) = self.step_kind(slot) {
                    *kg = v;
                }
            }
        }
        Ok(())
    }
}

impl ExtModel {
    /// The kind (and size) of the change in slot `slot` of the model's time terms, `None` for
    /// a slot the model does not have.
    fn step_kind(&mut self, slot: usize) -> Option<&mut StepKind> {
        self.model
            .time_terms_mut()
            .changes
            .get_mut(slot)
            .map(|s| &mut s.kind)
    }
}
