//! Changes within a session: at pose time `t_s` the tool point (or marker) moves by a 3-D offset
//! in the last link frame, or a payload mass is picked up (put down: a negative mass). A pose at
//! `t >= t_s` is evaluated with the change applied ([`Model::at_time`]): the tool offset adds to
//! `tool_dx/dy/dz`, the mass to `payload_kg`, so the change acts through every law the model
//! already has (the tool point's place in the chain; the payload's moments through the tilting).
//! FORMATS.md effects extended by `tool_change` and `payload_change` (docs/diagnose.md).

use std::borrow::Cow;

use nalgebra::Vector3;

use super::{Model, ModelError};

/// What changes at a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StepKind {
    /// The tool point moves by this offset, mm in the last link frame.
    Tool(Vector3<f64>),
    /// A payload mass picked up (> 0) or put down (< 0), kg at the tool point.
    Payload(f64),
}

/// One change within a session.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// The time of the change, s (poses at `t >= t_s` carry it).
    pub t_s: f64,
    /// What changes.
    pub kind: StepKind,
}

impl Step {
    /// Whether it changes anything (a zero offset or mass does not).
    pub fn is_active(&self) -> bool {
        match self.kind {
            StepKind::Tool(d) => d != Vector3::zeros(),
            StepKind::Payload(m) => m != 0.0,
        }
    }

    /// Whether a pose at `t_s` comes after the change.
    pub fn applies_at(&self, t_s: f64) -> bool {
        t_s >= self.t_s
    }

    /// The indicator of the step at `t_s` (1 after it, 0 before): the factor of its Jacobian
    /// columns.
    pub fn indicator(&self, t_s: f64) -> f64 {
        if self.applies_at(t_s) {
            1.0
        } else {
            0.0
        }
    }
}

/// The parameters a tool change adds to, in the order of its offset's axes.
pub const TOOL_PARAMS: [&str; 3] = ["tool_dx", "tool_dy", "tool_dz"];

impl Model {
    /// The changes within the session this model carries (model file `[[change]]` rows).
    pub fn steps(&self) -> &[Step] {
        &self.time_terms().changes
    }

    /// Whether the model carries a change that moves anything.
    pub fn has_steps(&self) -> bool {
        self.steps().iter().any(Step::is_active)
    }

    /// Checks that the model has the parameters its changes add to (`tool_dx/dy/dz`).
    pub fn check_steps(&self) -> Result<(), ModelError> {
        for s in self.steps() {
            if !s.t_s.is_finite() {
                return Err(ModelError::Invalid(format!(
                    "a change at t_s = {}: not a finite time",
                    s.t_s
                )));
            }
            if let StepKind::Tool(_) = s.kind {
                for name in TOOL_PARAMS {
                    self.require_param(name)?;
                }
            }
        }
        // the mass carried never below zero: a payload is put down only after it is picked up
        let mut steps: Vec<&Step> = self.steps().iter().collect();
        steps.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
        let mut kg = self
            .params()
            .get(self.payload_param())
            .map_or(0.0, |p| p.value);
        for s in steps {
            if let StepKind::Payload(m) = s.kind {
                kg += m;
                if kg < -1e-9 {
                    return Err(ModelError::Invalid(format!(
                        "a payload change of {m} kg at t_s = {} leaves {kg} kg carried: a \
                         payload put down must have been carried",
                        s.t_s
                    )));
                }
            }
        }
        Ok(())
    }

    /// The model as it is at pose time `t_s`: every change at or before `t_s` applied to the
    /// parameters it adds to (the model itself when none applies).
    pub fn at_time(&self, t_s: f64) -> Cow<'_, Model> {
        let due: Vec<Step> = self
            .steps()
            .iter()
            .filter(|s| s.is_active() && s.applies_at(t_s))
            .copied()
            .collect();
        if due.is_empty() {
            return Cow::Borrowed(self);
        }
        let mut m = self.clone();
        for s in due {
            match s.kind {
                StepKind::Tool(d) => {
                    for (a, name) in TOOL_PARAMS.iter().enumerate() {
                        if let Some(i) = m.param_index(name) {
                            let v = m.params()[i].value + d[a];
                            // finite by construction (a finite offset on a finite value)
                            let _ = m.set_param_at(i, v);
                        }
                    }
                }
                StepKind::Payload(kg) => {
                    let i = m.payload_param();
                    let v = m.params().get(i).map_or(0.0, |p| p.value) + kg;
                    let _ = m.set_param_at(i, v);
                }
            }
        }
        Cow::Owned(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{katana450, Tilt};

    #[test]
    fn a_tool_change_moves_the_point_only_after_its_time() {
        let mut m = katana450(200.0).expect("preset");
        let d = Vector3::new(0.1, -0.05, 0.2);
        m.time_terms_mut().changes.push(Step {
            t_s: 100.0,
            kind: StepKind::Tool(d),
        });
        let q = [10.0, 80.0, -60.0, 20.0, 30.0];
        let before = m.at_time(99.0).fk(&q, Tilt::Off).expect("fk");
        let after = m.at_time(100.0).fk(&q, Tilt::Off).expect("fk");
        let plain = m.fk(&q, Tilt::Off).expect("fk");
        assert_eq!(before.position_mm, plain.position_mm);
        // the offset in the last frame, rotated into R
        let moved = after.position_mm - plain.position_mm;
        assert!((moved.norm() - d.norm()).abs() < 1e-9, "{moved:?}");
    }

    #[test]
    fn a_payload_change_adds_its_mass_after_its_time() {
        let mut m = katana450(200.0).expect("preset");
        let base = m.params()[m.payload_param()].value;
        m.time_terms_mut().changes.push(Step {
            t_s: 5.0,
            kind: StepKind::Payload(0.4),
        });
        let at = |t: f64| {
            let mt = m.at_time(t);
            mt.params()[mt.payload_param()].value
        };
        assert_eq!(at(4.9), base);
        assert!((at(5.0) - base - 0.4).abs() < 1e-12);
    }
}
