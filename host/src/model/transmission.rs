//! Transmission effects on the joint angles (FORMATS.md `joint_scale`, `joint_coupling`,
//! `hysteresis`): what the joint really turns by, given the commanded angles and the direction
//! from which each joint approached the pose (pose order). Used by `simulate` (the truth) and
//! `diagnose` (the candidates), and carried by a [`Model`] ([`JointTerms`], model files) so
//! that `fk` and `calibrate` apply them.

use super::gravity::GravityModel;
use super::time_terms::TimeTerms;
use super::{Model, ModelError};
use nalgebra::Vector3;

/// Joint-motion threshold (deg, or mm for a prismatic joint) below which a joint did not move
/// between two poses.
pub const APPROACH_MIN_MOVE: f64 = 1e-9;

/// Direction in which each joint last moved before each pose (FORMATS.md pose order): the
/// poses are visited in the order of `t_s` when given (ties in file order), else in file order;
/// for joint i at pose k the sign of the last non-zero change of `q_i` up to k (+1 up, -1
/// down), 0 for the first pose and while the joint has not moved yet.
pub fn approach_directions(q_deg: &[Vec<f64>], t_s: Option<&[f64]>) -> Vec<Vec<f64>> {
    let n = q_deg.len();
    let mut order: Vec<usize> = (0..n).collect();
    if let Some(t) = t_s.filter(|t| t.len() == n) {
        order.sort_by(|&a, &b| t[a].total_cmp(&t[b]));
    }
    let nj = q_deg.first().map_or(0, Vec::len);
    let mut out = vec![vec![0.0; nj]; n];
    let mut dir = vec![0.0; nj];
    let mut prev: Option<&Vec<f64>> = None;
    for &k in &order {
        if let Some(p) = prev {
            for (j, d) in dir.iter_mut().enumerate() {
                let delta =
                    q_deg[k].get(j).copied().unwrap_or(0.0) - p.get(j).copied().unwrap_or(0.0);
                if delta.abs() > APPROACH_MIN_MOVE {
                    *d = delta.signum();
                }
            }
        }
        out[k] = dir.clone();
        prev = Some(&q_deg[k]);
    }
    out
}

/// The transmission terms of joint angles (FORMATS.md `joint_scale`, `joint_coupling`,
/// `hysteresis`): `q_eff_i = q_i + s_i q_i + sum_k c_ik q_k + b_i d_i`, with `d_i` the
/// direction of approach of joint i (+1, -1, 0). `scale`, `coupling` (rows i, columns k) and
/// `hysteresis_deg` may be empty (no term); returns the increments per joint.
pub fn transmission_increments(
    q_deg: &[f64],
    approach: &[f64],
    scale: &[f64],
    coupling: &[Vec<f64>],
    hysteresis_deg: &[f64],
) -> Vec<f64> {
    (0..q_deg.len())
        .map(|i| {
            let s = scale.get(i).copied().unwrap_or(0.0) * q_deg[i];
            let c: f64 = coupling
                .get(i)
                .map(|row| row.iter().zip(q_deg).map(|(c, q)| c * q).sum())
                .unwrap_or(0.0);
            let h = hysteresis_deg.get(i).copied().unwrap_or(0.0)
                * approach.get(i).copied().unwrap_or(0.0);
            s + c + h
        })
        .collect()
}

/// The compliance law (FORMATS.md effect `compliance:j<i>`): joint j deflects by `c_j tau_j`,
/// `c_j` deg per kgf.m (mm per kgf.m for a prismatic joint) and `tau_j` the static gravity
/// torque about its axis (kgf.m, [`GravityModel::axis_torques_kgfm`]). Missing coefficients or
/// torques count as 0. The one home of the law: the model files ([`JointTerms`]), the general
/// identification (`calib::general`) and `diagnose` (`diagnose::extended`) call it.
pub fn compliance_deflection_deg(
    compliance_deg_per_kgfm: &[f64],
    tau_kgfm: &[f64],
    j: usize,
) -> f64 {
    compliance_deg_per_kgfm.get(j).copied().unwrap_or(0.0) * compliance_regressor(tau_kgfm, j)
}

/// The derivative of [`compliance_deflection_deg`] of joint j with respect to its coefficient
/// `c_j`: the torque `tau_j` (kgf.m), 0 when missing.
pub fn compliance_regressor(tau_kgfm: &[f64], j: usize) -> f64 {
    tau_kgfm.get(j).copied().unwrap_or(0.0)
}

/// The joint readings deflected by compliance: joint j reads
/// `q_j + `[`compliance_deflection_deg`]`(c, tau, j)`.
pub fn compliance_deflected(q_deg: &[f64], compliance: &[f64], tau_kgfm: &[f64]) -> Vec<f64> {
    q_deg
        .iter()
        .enumerate()
        .map(|(j, q)| q + compliance_deflection_deg(compliance, tau_kgfm, j))
        .collect()
}

/// The transmission terms a model carries (model file `[[joint]]` keys `joint_scale`,
/// `joint_coupling`, `hysteresis_deg`, `compliance_deg_per_kgfm`; FORMATS.md effects
/// `joint_scale:j<i>`, `joint_coupling:j<i>:j<k>`, `hysteresis:j<i>`, `compliance:j<i>`):
/// the map from the joint readings to the angles the joints really take,
///
/// ```text
/// q_eff_i = q_i + s_i q_i + sum_k c_ik q_k + b_i d_i + g_i tau_i(q)
/// ```
///
/// with `d_i` the direction of approach (pose order, [`approach_directions`]) and `tau_i` the
/// static gravity torque about joint axis i at the readings (kgf.m, the model's link masses,
/// [`super::gravity::GravityModel`]). Applied once per pose before the model's evaluation
/// ([`Model::effective_joints`]); [`Model::fk`] itself evaluates the angles it is given.
/// Empty vectors mean no term.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct JointTerms {
    /// Transmission-ratio error per joint (dimensionless).
    pub scale: Vec<f64>,
    /// Coupling, row i (the joint moved) column k (the command it follows), deg/deg.
    pub coupling: Vec<Vec<f64>>,
    /// Hysteresis per joint, deg (times the direction of approach).
    pub hysteresis_deg: Vec<f64>,
    /// Compliance per joint, deg per kgf.m of gravity torque about the joint axis.
    pub compliance_deg_per_kgfm: Vec<f64>,
}

impl JointTerms {
    /// No term, sized for `n_joints` joints.
    pub fn zeros(n_joints: usize) -> Self {
        Self {
            scale: vec![0.0; n_joints],
            coupling: vec![vec![0.0; n_joints]; n_joints],
            hysteresis_deg: vec![0.0; n_joints],
            compliance_deg_per_kgfm: vec![0.0; n_joints],
        }
    }

    /// Whether any term is non-zero.
    pub fn is_active(&self) -> bool {
        self.scale
            .iter()
            .chain(self.coupling.iter().flatten())
            .chain(&self.hysteresis_deg)
            .chain(&self.compliance_deg_per_kgfm)
            .any(|v| *v != 0.0)
    }

    /// Whether some hysteresis term is non-zero (the pose order matters).
    pub fn uses_pose_order(&self) -> bool {
        self.hysteresis_deg.iter().any(|v| *v != 0.0)
    }

    /// Whether some compliance term is non-zero (gravity torques needed).
    pub fn has_compliance(&self) -> bool {
        self.compliance_deg_per_kgfm.iter().any(|v| *v != 0.0)
    }

    /// Joint i's coupling to joint k's command (deg/deg), 0 when absent.
    pub fn coupling_at(&self, i: usize, k: usize) -> f64 {
        self.coupling
            .get(i)
            .and_then(|r| r.get(k))
            .copied()
            .unwrap_or(0.0)
    }

    /// The terms of joint `i` in model-file form, 0 when absent: (scale, hysteresis_deg,
    /// compliance_deg_per_kgfm).
    pub fn joint_values(&self, i: usize) -> (f64, f64, f64) {
        let at = |v: &[f64]| v.get(i).copied().unwrap_or(0.0);
        (
            at(&self.scale),
            at(&self.hysteresis_deg),
            at(&self.compliance_deg_per_kgfm),
        )
    }

    /// `d q_eff / d q` at the readings `q_deg` for the linear terms (identity + scale +
    /// coupling; hysteresis is piecewise constant). The compliance term's derivative is taken
    /// by central differences of the gravity torques (step 1e-4 deg) when compliance is
    /// present. Row i, column k.
    pub fn joint_map_jacobian(
        &self,
        model: &Model,
        q_deg: &[f64],
    ) -> Result<nalgebra::DMatrix<f64>, ModelError> {
        let n = q_deg.len();
        let mut jac = nalgebra::DMatrix::<f64>::identity(n, n);
        for i in 0..n {
            jac[(i, i)] += self.scale.get(i).copied().unwrap_or(0.0);
            for k in 0..n {
                jac[(i, k)] += self.coupling_at(i, k);
            }
        }
        if self.has_compliance() {
            if let Some(g) = GravityModel::for_model(model) {
                const STEP_DEG: f64 = 1e-4;
                let mut q = q_deg.to_vec();
                for k in 0..n {
                    q[k] = q_deg[k] + STEP_DEG;
                    let up = g.axis_torques_kgfm(model, &q)?;
                    q[k] = q_deg[k] - STEP_DEG;
                    let down = g.axis_torques_kgfm(model, &q)?;
                    q[k] = q_deg[k];
                    for i in 0..n {
                        let c = self.compliance_deg_per_kgfm.get(i).copied().unwrap_or(0.0);
                        let (u, d) = (
                            up.get(i).copied().unwrap_or(0.0),
                            down.get(i).copied().unwrap_or(0.0),
                        );
                        jac[(i, k)] += c * (u - d) / (2.0 * STEP_DEG);
                    }
                }
            }
        }
        Ok(jac)
    }

    /// The angles the joints really take for the readings `q_deg`, with the directions of
    /// approach `approach` (+1, -1, 0 per joint; empty = none known). Compliance torques come
    /// from `model`'s masses (none: no compliance).
    pub fn effective_joints(
        &self,
        model: &Model,
        q_deg: &[f64],
        approach: &[f64],
    ) -> Result<Vec<f64>, ModelError> {
        Ok(self.apply(
            q_deg,
            approach,
            &self.compliance_torques_kgfm(model, q_deg)?,
        ))
    }

    /// The gravity torques about the axes (kgf.m) that the compliance terms need at `q_deg`,
    /// from `model`'s masses; empty when there is no compliance term or no mass.
    pub fn compliance_torques_kgfm(
        &self,
        model: &Model,
        q_deg: &[f64],
    ) -> Result<Vec<f64>, ModelError> {
        match self
            .has_compliance()
            .then(|| GravityModel::for_model(model))
            .flatten()
        {
            Some(g) => g.axis_torques_kgfm(model, q_deg),
            None => Ok(Vec::new()),
        }
    }

    /// These terms sized for `n_joints` joints: the values present kept, the others 0.
    pub fn sized(&self, n_joints: usize) -> JointTerms {
        let at = |v: &[f64], j: usize| v.get(j).copied().unwrap_or(0.0);
        let mut z = JointTerms::zeros(n_joints);
        for j in 0..n_joints {
            z.scale[j] = at(&self.scale, j);
            z.hysteresis_deg[j] = at(&self.hysteresis_deg, j);
            z.compliance_deg_per_kgfm[j] = at(&self.compliance_deg_per_kgfm, j);
            for k in 0..n_joints {
                z.coupling[j][k] = self.coupling_at(j, k);
            }
        }
        z
    }

    /// The joint map with the gravity torques about the axes given (`tau_kgfm`, kgf.m; empty:
    /// no compliance term): `q_eff_i = q_i + s_i q_i + sum_k c_ik q_k + b_i d_i + g_i tau_i`.
    pub fn apply(&self, q_deg: &[f64], approach: &[f64], tau_kgfm: &[f64]) -> Vec<f64> {
        let trans = transmission_increments(
            q_deg,
            approach,
            &self.scale,
            &self.coupling,
            &self.hysteresis_deg,
        );
        q_deg
            .iter()
            .enumerate()
            .map(|(j, q)| {
                q + trans[j] + compliance_deflection_deg(&self.compliance_deg_per_kgfm, tau_kgfm, j)
            })
            .collect()
    }
}

impl Model {
    /// The transmission terms this model carries (model file `[[joint]]` keys).
    pub fn transmission(&self) -> &JointTerms {
        &self.transmission
    }

    /// The transmission terms, to change them in place.
    pub fn transmission_mut(&mut self) -> &mut JointTerms {
        &mut self.transmission
    }

    /// Replaces the transmission terms.
    pub fn set_transmission(&mut self, terms: JointTerms) {
        self.transmission = terms;
    }

    /// The terms that depend on the pose time (model file `[time]`).
    pub fn time_terms(&self) -> &TimeTerms {
        &self.time_terms
    }

    /// The time terms, to change them in place.
    pub fn time_terms_mut(&mut self) -> &mut TimeTerms {
        &mut self.time_terms
    }

    /// Replaces the time terms.
    pub fn set_time_terms(&mut self, terms: TimeTerms) {
        self.time_terms = terms;
    }

    /// Whether the readings are mapped before the chain (transmission terms or joint drifts).
    pub fn maps_joints(&self) -> bool {
        self.transmission.is_active()
            || self
                .time_terms
                .joint_drift_deg_per_h
                .iter()
                .any(|r| *r != 0.0)
    }

    /// The one joint map of the model: the angles the joints take for the readings `q_deg` at
    /// pose time `t_s`, with the directions of approach `approach` and the gravity torques
    /// `tau_kgfm` (empty: no compliance term), i.e. [`JointTerms::apply`] plus the joint-offset
    /// drifts of [`TimeTerms`].
    pub fn joint_map(
        &self,
        q_deg: &[f64],
        t_s: f64,
        approach: &[f64],
        tau_kgfm: &[f64],
    ) -> Vec<f64> {
        let mut q = self.transmission.apply(q_deg, approach, tau_kgfm);
        for (j, v) in q.iter_mut().enumerate() {
            *v += self.time_terms.joint_drift_deg(j, t_s);
        }
        q
    }

    /// [`Model::joint_map`] of one pose, with the gravity torques of the model's masses when it
    /// has compliance terms.
    pub fn effective_joints_at(
        &self,
        q_deg: &[f64],
        t_s: f64,
        approach: &[f64],
    ) -> Result<Vec<f64>, ModelError> {
        let tau = self.transmission.compliance_torques_kgfm(self, q_deg)?;
        Ok(self.joint_map(q_deg, t_s, approach, &tau))
    }

    /// The angles fed to the chain for a sequence of joint readings (one vector per pose, in
    /// file order; `t_s` the pose times when the file has them): the readings mapped through
    /// [`Model::joint_map`], the direction of approach taken from the pose order (FORMATS.md
    /// "Pose order"; the first pose has no history). Without terms, the readings themselves.
    pub fn effective_pose_joints(
        &self,
        q_deg: &[Vec<f64>],
        t_s: Option<&[f64]>,
    ) -> Result<Vec<Vec<f64>>, ModelError> {
        if !self.maps_joints() {
            return Ok(q_deg.to_vec());
        }
        let approach = if self.transmission.uses_pose_order() {
            approach_directions(q_deg, t_s)
        } else {
            Vec::new()
        };
        q_deg
            .iter()
            .enumerate()
            .map(|(k, q)| {
                let a = approach.get(k).map_or(&[][..], Vec::as_slice);
                let t = t_s.and_then(|t| t.get(k)).copied().unwrap_or(0.0);
                self.effective_joints_at(q, t, a)
            })
            .collect()
    }

    /// The chain's position whose measurement at `t_s` is `measured_mm` (the inverse of
    /// [`Model::measured_mm`]).
    pub fn chain_mm_for(&self, measured_mm: &Vector3<f64>, t_s: f64) -> Vector3<f64> {
        if self.time_terms.is_active() {
            let t = &self.time_terms;
            (measured_mm - t.drift_mm(t_s)) / t.growth_factor(t_s)
        } else {
            *measured_mm
        }
    }

    /// The position a measurement gives of the chain's position `chain_mm` at pose time `t_s`
    /// ([`TimeTerms::measured_mm`]; the chain's own position without time terms).
    pub fn measured_mm(&self, chain_mm: &Vector3<f64>, t_s: f64) -> Vector3<f64> {
        if self.time_terms.is_active() {
            self.time_terms.measured_mm(chain_mm, t_s)
        } else {
            *chain_mm
        }
    }
}
