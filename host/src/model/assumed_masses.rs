//! Link masses assumed where a model declares none, so that gravity-driven effects (joint
//! compliance) can be offered: one point mass per joint at the middle of the segment from its
//! joint frame to the next joint frame (the last joint's to the tool point), the masses in
//! proportion to the segments' lengths and summing to a given total. A crude guess: compliance
//! values fitted with it are per kgf.m of the assumed torques (their pattern over the joints is
//! what it tells); declare the CAD masses (`[[mass]]`) for values in real units.
//!
//! On a tree ([`Tree::with_assumed_masses`]) the same rule per segment: a joint carries one
//! point mass at the middle of the segment to each of its child joints' frames and to each of
//! its tips' tool points (one segment for a joint of a chain, the chain's rule), all masses in
//! proportion to the segments' lengths and summing to the total.

use nalgebra::Vector3;

use super::chain::PointMass;
use super::tree::{Tree, TreeMass};
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
        check_total(total_kg)?;
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

/// Refuses a total that is not a positive finite mass or is heavier than any robot.
fn check_total(total_kg: Option<f64>) -> Result<(), ModelError> {
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
    Ok(())
}

impl Tree {
    /// A copy of the tree with assumed link masses (see the module documentation) totalling
    /// `total_kg`, or [`DEFAULT_KG_PER_M`] per metre of the segments when `None`; the joints at
    /// 0 (or the nearest limit). Refused when the tree already has masses or the total is not a
    /// positive finite number.
    pub fn with_assumed_masses(&self, total_kg: Option<f64>) -> Result<Tree, ModelError> {
        if self.has_masses() {
            return Err(ModelError::Invalid(
                "the tree declares link masses: nothing to assume".into(),
            ));
        }
        check_total(total_kg)?;
        let q: Vec<f64> = self
            .joint_limits()
            .iter()
            .map(|l| 0.0f64.clamp(l[0].min(l[1]), l[0].max(l[1])))
            .collect();
        // every joint's frame and every tip's tool point at q, from the tips' chains
        let n = self.n_joints();
        let mut frames: Vec<Option<(nalgebra::Matrix3<f64>, Vector3<f64>)>> = vec![None; n];
        let mut tools = Vec::with_capacity(self.tips.len());
        for (t, chain) in self.chains()?.iter().enumerate() {
            let path = self.path(t);
            let qc: Vec<f64> = path.iter().map(|&j| q[j]).collect();
            let f = chain.frames(&qc, None)?;
            for (k, &j) in path.iter().enumerate() {
                let e = chain.joints()[k].elem;
                frames[j].get_or_insert((f.rot[e], f.pos_mm[e]));
            }
            tools.push(f.pos_mm.last().copied().unwrap_or_else(Vector3::zeros));
        }
        // per joint, the segments (in its frame) to its children and its tips
        let mut segments: Vec<(usize, Vector3<f64>)> = Vec::new();
        for (j, frame) in frames.iter().enumerate() {
            let Some((rot, origin)) = frame else { continue };
            let ends = (0..n)
                .filter(|&c| self.joints[c].parent == Some(j))
                .filter_map(|c| frames[c].map(|f| f.1))
                .chain(
                    self.tips
                        .iter()
                        .zip(&tools)
                        .filter(|(t, _)| t.joint == j)
                        .map(|(_, p)| *p),
                );
            segments.extend(ends.map(|end| (j, rot.transpose() * (end - origin))));
        }
        let sum_m: f64 = segments.iter().map(|(_, s)| s.norm()).sum::<f64>() * 1e-3;
        let total = total_kg.unwrap_or(DEFAULT_KG_PER_M * sum_m);
        if !(total.is_finite() && total > 0.0) || sum_m <= 0.0 {
            return Err(ModelError::Invalid(
                "the tree's segments have no length: give the robot's mass".into(),
            ));
        }
        let mut out = self.clone();
        for (j, s) in &segments {
            out.joints[*j].masses.push(TreeMass {
                mass_kg: total * s.norm() * 1e-3 / sum_m,
                com_mm: (0.5 * s).into(),
            });
        }
        out.masses_assumed = true;
        Ok(out)
    }

    /// The assumed masses said in words and per joint: `(total kg, kg per tree joint)`.
    pub fn mass_per_joint_kg(&self) -> (f64, Vec<f64>) {
        let per: Vec<f64> = self
            .joints
            .iter()
            .map(|j| j.masses.iter().map(|m| m.mass_kg).sum())
            .collect();
        (per.iter().sum(), per)
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

    /// A tree of one chain gets the chain's assumed masses (the same moments at every joint);
    /// a tree with branches shares the total over every segment, each joint's moment carried by
    /// its subtree.
    #[test]
    fn a_tree_assumes_the_chains_masses_per_segment() {
        let mut ur5 = crate::model::ur5().unwrap();
        ur5.masses.clear();
        let tree =
            crate::model::Tree::from_chains("ur5", &[("tool".to_string(), ur5.clone())]).unwrap();
        let t = tree.with_assumed_masses(Some(18.4)).unwrap();
        let m = ur5.with_assumed_masses(Some(18.4)).unwrap();
        assert!(t.masses_assumed && !tree.masses_assumed);
        let (total, per) = t.mass_per_joint_kg();
        assert!((total - 18.4).abs() < 1e-9, "{total}");
        for (a, b) in per.iter().zip(m.masses()) {
            assert!((a - b.mass_kg).abs() < 1e-9, "{a} vs {}", b.mass_kg);
        }
        for k in 0..4 {
            let q: Vec<f64> = (0..6).map(|j| 40.0 * ((j + 3 * k) as f64).sin()).collect();
            let (a, b) = (t.moments_kgfm(&q).unwrap(), m.moments_kgfm(&q).unwrap());
            for (a, b) in a.iter().zip(&b) {
                assert!((a - b).norm() < 1e-9, "tree {a:?} chain {b:?}");
            }
        }
        assert!(t.with_assumed_masses(None).is_err(), "declared: kept");
        assert!(tree.with_assumed_masses(Some(0.0)).is_err());
        let d = tree.with_assumed_masses(None).unwrap();
        let by_reach: f64 = ur5
            .with_assumed_masses(None)
            .unwrap()
            .masses()
            .iter()
            .map(|p| p.mass_kg)
            .sum();
        assert!((d.mass_per_joint_kg().0 - by_reach).abs() < 1e-9);
    }
}
