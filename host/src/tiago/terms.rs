//! Non-geometric joint terms for the TIAGo data: a joint deflection added to the reading of
//! joint `i`, proportional to the gravity torque about its axis (`compliance_j<i>`, deg per
//! kgf.m) or to its sign (`backlash_j<i>`, deg: half the play, the side taken by the load).
//! `i` is the 1-based model joint, as in `enc_j<i>_*`: for TIAGo j1 = `torso_lift_joint`,
//! j2..j8 = `arm_1_joint`..`arm_7_joint`.
//! Torques come from the URDF link masses ([`crate::urdf::import_chain_with_masses`]) on the
//! nominal chain, gravity along `-z` of `base_footprint`.
//!
//! [`fit_terms`] identifies model parameters and term coefficients together (LM);
//! [`select_terms`] chooses them on the training postures alone, by forward selection on the
//! leave-one-posture-out PRESS of the linearised problem ([`super::select`]).

use nalgebra::{DMatrix, DVector, Vector3};

use super::select::forward_select;
use crate::calib::lm::{solve, LmConfig, Problem};
use crate::calib::problem::stacked_jacobian;
use crate::calib::{CalibError, Poses};
use crate::model::gravity::GravityModel;
use crate::model::{Model, ModelError, ParamKind, Tilt};

/// What a joint term is proportional to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TermKind {
    /// The gravity torque about the joint axis (coefficient deg per kgf.m).
    Compliance,
    /// The sign of that torque (coefficient deg).
    Backlash,
}

/// One deflection term of joint `joint` (0-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct JointTerm {
    pub joint: usize,
    pub kind: TermKind,
}

impl JointTerm {
    /// `compliance_j<i>` / `backlash_j<i>` (1-based joint number).
    pub fn name(&self) -> String {
        match self.kind {
            TermKind::Compliance => format!("compliance_j{}", self.joint + 1),
            TermKind::Backlash => format!("backlash_j{}", self.joint + 1),
        }
    }

    /// The term's regressor for the axis torques `torques_kgfm`.
    pub fn regressor(&self, torques_kgfm: &[f64]) -> f64 {
        let t = torques_kgfm.get(self.joint).copied().unwrap_or(0.0);
        match self.kind {
            TermKind::Compliance => t,
            TermKind::Backlash => {
                if t == 0.0 {
                    0.0
                } else {
                    t.signum()
                }
            }
        }
    }
}

/// Gravity axis torques of a chain with link masses (the nominal posture of the base).
#[derive(Debug, Clone)]
pub struct Torques {
    model: Model,
    gravity: GravityModel,
}

impl Torques {
    /// Torques of `mass_model` (a model with masses); `None` if it has none.
    pub fn new(mass_model: &Model) -> Option<Self> {
        Some(Self {
            gravity: GravityModel::for_model(mass_model)?,
            model: mass_model.clone(),
        })
    }

    /// Axis torque of every joint (kgf.m) at `q_deg`.
    pub fn at(&self, q_deg: &[f64]) -> Result<Vec<f64>, ModelError> {
        self.gravity.axis_torques_kgfm(&self.model, q_deg)
    }
}

/// A model plus joint terms: joint `i` reads `q_i + sum coef_k regressor_k(q)`.
#[derive(Debug, Clone)]
pub struct TermModel {
    pub model: Model,
    pub terms: Vec<JointTerm>,
    /// One coefficient per term (deg per kgf.m, or deg).
    pub coef: Vec<f64>,
    /// Fitted model parameters (model indices).
    pub fitted: Vec<usize>,
    torques: Torques,
}

fn corrected(q: &[f64], terms: &[JointTerm], coef: &[f64], tau: &[f64]) -> Vec<f64> {
    let mut q = q.to_vec();
    for (t, c) in terms.iter().zip(coef) {
        if let Some(v) = q.get_mut(t.joint) {
            *v += c * t.regressor(tau);
        }
    }
    q
}

impl TermModel {
    /// Position errors (model - measured, mm) on `poses`.
    pub fn errors(&self, poses: &Poses) -> Result<Vec<Vector3<f64>>, ModelError> {
        poses
            .q_deg
            .iter()
            .zip(&poses.xyz_mm)
            .map(|(q, xyz)| {
                let tau = self.torques.at(q)?;
                let qc = corrected(q, &self.terms, &self.coef, &tau);
                Ok(self.model.position_mm(&qc, Tilt::Off)? - xyz)
            })
            .collect()
    }
}

struct TermProblem<'a> {
    model: Model,
    poses: &'a Poses,
    tau: Vec<Vec<f64>>,
    cols: Vec<usize>,
    terms: Vec<JointTerm>,
}

impl TermProblem<'_> {
    fn set(&mut self, x: &DVector<f64>) -> Result<Vec<f64>, ModelError> {
        for (&c, &v) in self.cols.iter().zip(x.iter()) {
            self.model.set_param_at(c, v)?;
        }
        Ok(x.iter().skip(self.cols.len()).copied().collect())
    }
}

impl Problem for TermProblem<'_> {
    type Error = ModelError;

    fn n_params(&self) -> usize {
        self.cols.len() + self.terms.len()
    }

    fn n_residuals(&self) -> usize {
        3 * self.poses.len()
    }

    fn evaluate(
        &mut self,
        x: &DVector<f64>,
        r: &mut DVector<f64>,
        mut jac: Option<&mut DMatrix<f64>>,
    ) -> Result<(), ModelError> {
        let coef = self.set(x)?;
        let n = self.cols.len();
        for (i, (q, xyz)) in self.poses.q_deg.iter().zip(&self.poses.xyz_mm).enumerate() {
            let qc = corrected(q, &self.terms, &coef, &self.tau[i]);
            match jac.as_deref_mut() {
                Some(jac) => {
                    let (fk, jp) = self.model.param_jacobian(&qc, Tilt::Off, &self.cols)?;
                    let (_, jq) = self.model.joint_jacobian(&qc, Tilt::Off)?;
                    r.fixed_rows_mut::<3>(3 * i)
                        .copy_from(&(fk.position_mm - xyz));
                    jac.view_mut((3 * i, 0), (3, n)).copy_from(&jp);
                    for (k, t) in self.terms.iter().enumerate() {
                        let col = jq.column(t.joint) * t.regressor(&self.tau[i]);
                        jac.view_mut((3 * i, n + k), (3, 1)).copy_from(&col);
                    }
                }
                None => {
                    let p = self.model.position_mm(&qc, Tilt::Off)?;
                    r.fixed_rows_mut::<3>(3 * i).copy_from(&(p - xyz));
                }
            }
        }
        Ok(())
    }
}

/// Fits the parameters `cols` of `start` and the coefficients of `terms` (from 0) on `poses`.
pub fn fit_terms(
    start: &Model,
    poses: &Poses,
    cols: &[usize],
    terms: &[JointTerm],
    torques: &Torques,
    lm: &LmConfig,
) -> Result<TermModel, CalibError> {
    if poses.is_empty() {
        return Err(CalibError::NoPoses);
    }
    let tau = poses
        .q_deg
        .iter()
        .map(|q| torques.at(q))
        .collect::<Result<Vec<_>, _>>()?;
    let mut problem = TermProblem {
        model: start.clone(),
        poses,
        tau,
        cols: cols.to_vec(),
        terms: terms.to_vec(),
    };
    let v = start.param_values();
    let mut x0: Vec<f64> = cols.iter().map(|&c| v[c]).collect();
    x0.extend(std::iter::repeat_n(0.0, terms.len()));
    let rep = solve(&mut problem, DVector::from_vec(x0), lm).map_err(CalibError::from_lm)?;
    let coef = problem.set(&rep.x)?;
    Ok(TermModel {
        model: problem.model,
        terms: terms.to_vec(),
        coef,
        fitted: cols.to_vec(),
        torques: torques.clone(),
    })
}

/// Candidate pools of [`select_terms`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Pools {
    /// Chain constants (lengths, twists: URDF joint origins and tip transform).
    pub geometric: bool,
    /// Encoder harmonics `enc_j<i>_h<n>_sin/_cos` of the revolute joints.
    pub encoder: bool,
    /// `compliance_j<i>` of the revolute joints.
    pub compliance: bool,
    /// `backlash_j<i>` of the revolute joints.
    pub backlash: bool,
}

/// Result of [`select_terms`]: model parameters and joint terms to fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    /// Model parameters (always-fitted first, then the added ones in order).
    pub cols: Vec<usize>,
    /// Added joint terms, in order.
    pub terms: Vec<JointTerm>,
    /// Names of everything added, in the order chosen.
    pub added: Vec<String>,
}

/// Forward selection (block PRESS, leave one posture out, linearised at `start`) of chain
/// constants / encoder harmonics / joint terms (`pools`) added to the always-fitted model
/// parameters `always`, on `poses` alone.
pub fn select_terms(
    start: &Model,
    poses: &Poses,
    always: &[usize],
    pools: Pools,
    torques: &Torques,
) -> Result<Selection, CalibError> {
    let mut params: Vec<usize> = always.to_vec();
    let mut kinds = Vec::new();
    if pools.geometric {
        kinds.extend([ParamKind::Length, ParamKind::Twist]);
    }
    if pools.encoder {
        kinds.push(ParamKind::EncoderHarmonic);
    }
    for k in kinds {
        for c in start.params_of_kind(k) {
            if !params.contains(&c) {
                params.push(c);
            }
        }
    }
    let mut terms = Vec::new();
    for (j, joint) in start.joints().iter().enumerate() {
        if joint.prismatic {
            continue;
        }
        if pools.compliance {
            terms.push(JointTerm {
                joint: j,
                kind: TermKind::Compliance,
            });
        }
        if pools.backlash {
            terms.push(JointTerm {
                joint: j,
                kind: TermKind::Backlash,
            });
        }
    }
    let jp = stacked_jacobian(start, poses, &params, false)?;
    let np = params.len();
    let mut jac = DMatrix::zeros(jp.nrows(), np + terms.len());
    jac.columns_mut(0, np).copy_from(&jp);
    let mut r = DVector::zeros(3 * poses.len());
    for (i, (q, xyz)) in poses.q_deg.iter().zip(&poses.xyz_mm).enumerate() {
        let tau = torques.at(q)?;
        let (fk, jq) = start.joint_jacobian(q, Tilt::Off)?;
        // Residuals measured - model: the sign of the identification problem.
        r.fixed_rows_mut::<3>(3 * i)
            .copy_from(&(xyz - fk.position_mm));
        for (k, t) in terms.iter().enumerate() {
            let col = jq.column(t.joint) * t.regressor(&tau);
            jac.view_mut((3 * i, np + k), (3, 1)).copy_from(&col);
        }
    }
    let fixed: Vec<usize> = (0..always.len()).collect();
    let candidates: Vec<usize> = (always.len()..np + terms.len()).collect();
    let names: Vec<&str> = start.param_names().collect();
    let mut out = Selection {
        cols: always.to_vec(),
        terms: Vec::new(),
        added: Vec::new(),
    };
    for k in forward_select(&jac, &r, 3, &fixed, &candidates) {
        if k < np {
            out.cols.push(params[k]);
            out.added.push(names[params[k]].to_string());
        } else {
            let t = terms[k - np];
            out.terms.push(t);
            out.added.push(t.name());
        }
    }
    Ok(out)
}

/// Leave-one-posture-out cross-validation of the whole procedure (selection with `pools`, then
/// fit) on `poses`: every posture is predicted by a model selected and fitted without it.
/// Returns the RMS of the held-out error lengths (mm). Uses the training postures only.
pub fn cross_validated_rms(
    start: &Model,
    poses: &Poses,
    always: &[usize],
    pools: Pools,
    torques: &Torques,
    lm: &LmConfig,
) -> Result<f64, CalibError> {
    let mut sum_sq = 0.0;
    for out in 0..poses.len() {
        let keep = |v: &Vec<Vec<f64>>| -> Vec<Vec<f64>> {
            v.iter()
                .enumerate()
                .filter(|(i, _)| *i != out)
                .map(|(_, x)| x.clone())
                .collect()
        };
        let fold = Poses {
            q_deg: keep(&poses.q_deg),
            xyz_mm: poses
                .xyz_mm
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != out)
                .map(|(_, x)| *x)
                .collect(),
        };
        let held = Poses {
            q_deg: vec![poses.q_deg[out].clone()],
            xyz_mm: vec![poses.xyz_mm[out]],
        };
        let sel = select_terms(start, &fold, always, pools, torques)?;
        let fit = fit_terms(start, &fold, &sel.cols, &sel.terms, torques, lm)?;
        sum_sq += fit.errors(&held)?[0].norm_squared();
    }
    Ok((sum_sq / poses.len().max(1) as f64).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::urdf::{import_chain_with_masses, ImportOptions, Urdf};

    /// Two joints about horizontal axes (y), a 2 kg link 0.4 m long and a 1 kg link: the
    /// gravity torques vary with the posture.
    const XML: &str = r#"<robot name="m">
      <link name="base"/>
      <link name="l1"><inertial><mass value="2"/><origin xyz="0.4 0 0"/></inertial></link>
      <link name="l2"><inertial><mass value="1"/><origin xyz="0.3 0 0"/></inertial></link>
      <link name="tip"/>
      <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
        <origin xyz="0 0 0.5"/><axis xyz="0 1 0"/><limit lower="-3" upper="3"/></joint>
      <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
        <origin xyz="0.8 0 0"/><axis xyz="0 1 0"/><limit lower="-3" upper="3"/></joint>
      <joint name="t" type="fixed"><parent link="l2"/><child link="tip"/>
        <origin xyz="0.6 0 0"/></joint>
    </robot>"#;

    #[test]
    fn synthetic_compliance_is_selected_and_recovered() {
        let urdf = Urdf::parse(XML, "m.urdf").unwrap();
        let opts = ImportOptions {
            base_link: None,
            tip_link: "tip",
            tool_mm: [0.0; 3],
        };
        let model = import_chain_with_masses(&urdf, &opts).unwrap().model;
        let torques = Torques::new(&model).unwrap();
        // At q = 0 both links are horizontal: |torque j1| = 2*0.4 + 1*1.1 = 1.9 kgf.m.
        let t0 = torques.at(&[0.0, 0.0]).unwrap();
        assert!((t0[0].abs() - 1.9).abs() < 1e-12, "{t0:?}");
        assert!((t0[1].abs() - 0.3).abs() < 1e-12, "{t0:?}");
        let truth = [
            JointTerm {
                joint: 0,
                kind: TermKind::Compliance,
            },
            JointTerm {
                joint: 1,
                kind: TermKind::Compliance,
            },
        ];
        let coef = [0.05, -0.2];
        let mut poses = Poses {
            q_deg: Vec::new(),
            xyz_mm: Vec::new(),
        };
        for a in [-60.0, -25.0, 0.0, 30.0, 70.0] {
            for b in [-80.0, -20.0, 15.0, 50.0, 100.0] {
                let q = vec![a, b];
                let tau = torques.at(&q).unwrap();
                let qc = corrected(&q, &truth, &coef, &tau);
                poses
                    .xyz_mm
                    .push(model.position_mm(&qc, Tilt::Off).unwrap());
                poses.q_deg.push(q);
            }
        }
        let pools = Pools {
            compliance: true,
            backlash: true,
            ..Pools::default()
        };
        let sel = select_terms(&model, &poses, &[], pools, &torques).unwrap();
        for t in &truth {
            assert!(sel.terms.contains(t), "{:?}", sel.added);
        }
        let fit = fit_terms(&model, &poses, &[], &truth, &torques, &LmConfig::default()).unwrap();
        for (f, c) in fit.coef.iter().zip(coef) {
            assert!((f - c).abs() < 1e-6, "{f} vs {c}");
        }
        let max_mm = fit
            .errors(&poses)
            .unwrap()
            .iter()
            .map(|e| e.norm())
            .fold(0.0, f64::max);
        assert!(max_mm < 1e-6, "{max_mm}");
    }
}
