//! Link masses assumed where a model declares none, so that gravity-driven effects (joint
//! compliance) can be offered: one point mass per joint at the middle of the segment from its
//! joint frame to the next joint frame (the last joint's to the tool point), the masses in
//! proportion to the segments' lengths and summing to a given total. A crude guess: compliance
//! values fitted with it are per kgf.m of the assumed torques (their pattern over the joints is
//! what it tells); declare the CAD masses (`[[mass]]`) for values in real units.

use nalgebra::Vector3;

use super::chain::PointMass;
use super::{Model, ModelError};

/// The heaviest robot mass taken as given, kg (the heaviest industrial arms weigh a few tonnes):
/// more is a mass in grams or another unit.
pub const MAX_ROBOT_MASS_KG: f64 = 10_000.0;

/// A default total mass per metre of the summed segment lengths, kg/m (industrial and service
/// arms of 0.6-1 m reach weigh about 15-25 kg: UR5 18.4 kg at 0.85 m, Panda 18 kg at 0.86 m).
pub const DEFAULT_KG_PER_M: f64 = 20.0;

impl Model {
    /// Whether the model's masses are assumed ([`Model::with_assumed_masses`]).
    pub fn masses_assumed(&self) -> bool {
        self.masses_assumed
    }

    /// A copy of the model with assumed link masses (see the module documentation) totalling
    /// `total_kg`, or [`DEFAULT_KG_PER_M`] per metre of the segments when `None`. Refused when
    /// the model already has masses (they are declared, not assumed) or the total is not a
    /// positive finite number.
    pub fn with_assumed_masses(&self, total_kg: Option<f64>) -> Result<Model, ModelError> {
        if !self.masses.is_empty() {
            return Err(ModelError::Invalid(
                "the model declares link masses: nothing to assume".into(),
            ));
        }
        if let Some(t) = total_kg {
            if !(t.is_finite() && t > 0.0) {
                return Err(ModelError::Invalid(format!(
                    "assumed robot mass {t} kg: must be a finite number > 0"
                )));
            }
            if t > MAX_ROBOT_MASS_KG {
                return Err(ModelError::Invalid(format!(
                    "assumed robot mass {t} kg: more than {MAX_ROBOT_MASS_KG} kg, is it in grams ({} kg)?",
                    t / 1000.0
                )));
            }
        }
        let q: Vec<f64> = self
            .joint_limits()
            .iter()
            .map(|l| 0.0f64.clamp(l[0].min(l[1]), l[0].max(l[1])))
            .collect();
        let f = self.frames(&q, None)?;
        let n = self.joints.len();
        let end = f.pos_mm.last().copied().unwrap_or_else(Vector3::zeros);
        let segments: Vec<Vector3<f64>> = (0..n)
            .map(|j| {
                let e = self.joints[j].elem;
                let next = if j + 1 < n {
                    f.pos_mm[self.joints[j + 1].elem]
                } else {
                    end
                };
                f.rot[e].transpose() * (next - f.pos_mm[e])
            })
            .collect();
        let lengths: Vec<f64> = segments.iter().map(|s| s.norm()).collect();
        let sum_m: f64 = lengths.iter().sum::<f64>() * 1e-3;
        let total = total_kg.unwrap_or(DEFAULT_KG_PER_M * sum_m);
        if !(total.is_finite() && total > 0.0) {
            return Err(ModelError::Invalid(
                "the model's segments have no length: give the robot's mass".into(),
            ));
        }
        let mut out = self.clone();
        out.masses = segments
            .iter()
            .zip(&lengths)
            .enumerate()
            .map(|(j, (s, l))| PointMass {
                joint: j,
                after: 0,
                mass_kg: if sum_m > 0.0 {
                    total * l * 1e-3 / sum_m
                } else {
                    total / n as f64
                },
                com_mm: 0.5 * s,
            })
            .collect();
        out.masses_assumed = true;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn masses_sit_mid_segment_and_sum_to_the_total() {
        // the UR5 preset without its link masses (a model built by hand, a URDF without
        // inertials)
        let mut ur5 = crate::model::ur5().unwrap();
        ur5.masses.clear();
        let m = ur5.with_assumed_masses(Some(18.4)).unwrap();
        assert!(m.masses_assumed() && !ur5.masses_assumed());
        let total: f64 = m.masses().iter().map(|p| p.mass_kg).sum();
        assert!((total - 18.4).abs() < 1e-9, "{total}");
        assert_eq!(m.masses().len(), ur5.n_joints());
        // each centre of mass is half-way to the next joint frame, in the joint's frame
        let q = vec![0.0; ur5.n_joints()];
        let f = m.frames(&q, None).unwrap();
        for (j, p) in m.masses().iter().enumerate() {
            let e = m.joints()[j].elem;
            let world = f.pos_mm[e] + f.rot[e] * p.com_mm;
            let next = if j + 1 < m.n_joints() {
                f.pos_mm[m.joints()[j + 1].elem]
            } else {
                *f.pos_mm.last().unwrap()
            };
            let mid = 0.5 * (f.pos_mm[e] + next);
            assert!(
                (world - mid).norm() < 1e-9,
                "joint {}: {world} vs {mid}",
                j + 1
            );
        }
        // the gravity torques exist now: the default total is by reach
        let d = ur5.with_assumed_masses(None).unwrap();
        let t: f64 = d.masses().iter().map(|p| p.mass_kg).sum();
        assert!(t > 10.0 && t < 40.0, "{t}");
        assert!(
            m.with_assumed_masses(None).is_err(),
            "declared masses are kept"
        );
        assert!(ur5.with_assumed_masses(Some(-1.0)).is_err());
        // a mass in grams is refused, naming it
        let e = ur5
            .with_assumed_masses(Some(18_400.0))
            .unwrap_err()
            .to_string();
        assert!(e.contains("grams (18.4 kg)"), "{e}");
    }
}
