//! The one state every identification writes its unknowns into ([`ExtModel`], `calibrate`'s
//! and `diagnose`'s): the declared model extended with the effects that are not parameters of a
//! [`Model`]'s chain but terms it carries: the joint map ([`crate::model::transmission::JointTerms`]:
//! transmission-ratio errors, coupling, hysteresis, compliance) and the time terms
//! ([`crate::model::time_terms::TimeTerms`]: thermal growth, position and joint-offset drifts).
//! One [`Unknown`] names any value the fit can free; the values live in the model.
//!
//! Prediction of pose k (joint readings `q`, time `t` s, directions of approach `d`):
//!
//! ```text
//! q_eff = Model::joint_map(q, t, d, tau(q))             tau: gravity torques about the axes
//! p     = Model::measured_mm(fk(q_eff, declared tilt), t)
//! ```
//!
//! `tau_j(q)` is the static gravity torque about joint axis j (kgf.m) of the untilted chain at the
//! readings, from [`GravityModel`], of the state's own chain (its current parameters: what the
//! model applies when its compliance is used, [`crate::model::transmission`]). Several measured
//! points per pose, each with its offset in the tool frame, are predicted by [`super::general`]. A file without a `t` column has `t = 0` for every pose, so
//! the time terms have no effect (and are never candidates).

use nalgebra::{DMatrix, DVector, Vector3};

use super::measured::MeasuredSet;
use super::normal::Normal;
use super::problem::{ModelProblem, Rows};
use super::unknown::Freed;
pub use super::unknown::{Unknown, Values};
use crate::model::changes::TOOL_PARAMS;
use crate::model::gravity::GravityModel;
use crate::model::time_terms::TimeTerms;
use crate::model::transmission::{compliance_regressor, JointTerms};
use crate::model::{sign_1e9, Model, ModelError, Tilt, Wrt};

/// Point offsets are evaluated by the prediction of several points per pose
/// ([`super::general`]), not by the one of one point per pose.
fn offsets_elsewhere(u: Unknown, model: &Model) -> ModelError {
    ModelError::Invalid(format!(
        "{}: point offsets are identified by calibrate with several points per pose",
        u.name(model)
    ))
}

/// The one state of every identification: a model with its joint map and time terms sized for
/// its joints, the offsets of further measured points, and what the fit needs to evaluate them
/// (tilting on or off, the link masses for the compliance torques).
#[derive(Debug, Clone)]
pub struct ExtModel {
    /// The robot model: parameters, joint map, time terms.
    pub model: Model,
    /// Whether the declared static tilting is applied.
    pub tilt: bool,
    /// Link masses for the compliance torques (None: no compliance possible).
    pub gravity: Option<GravityModel>,
    /// Offset of every measured point slot in the tool frame (mm) for several points per pose
    /// ([`super::general`]); slot 0 mirrors the tool point. Empty for one point per pose.
    pub offsets_mm: Vec<Vector3<f64>>,
}

impl ExtModel {
    /// `model` with its own terms as the starting values; tilting when the model has tilting
    /// data.
    pub fn new(mut model: Model) -> Self {
        let n = model.n_joints();
        let tilt = model.has_tilt();
        let gravity = GravityModel::for_model(&model);
        let terms = model.transmission().sized(n);
        model.set_transmission(terms);
        if model.time_terms().joint_drift_deg_per_h.len() != n {
            let rates = &mut model.time_terms_mut().joint_drift_deg_per_h;
            rates.resize(n, 0.0);
        }
        Self {
            model,
            tilt,
            gravity,
            offsets_mm: Vec::new(),
        }
    }

    /// The model with this fit's terms, for `diagnose --out`: terms that are all zero are left
    /// out (so a model without terms reads back identical), and compliance only with masses.
    pub fn to_model(&self) -> Model {
        let mut m = self.model.clone();
        if self.gravity.is_none() {
            m.transmission_mut().compliance_deg_per_kgfm.clear();
        }
        m.clear_zero_lateral_compliance();
        if !m.transmission().is_active() {
            m.set_transmission(JointTerms::default());
        }
        if !m.time_terms().is_active() {
            let tau = m.time_terms().thermal_tau_min;
            m.set_time_terms(TimeTerms {
                thermal_tau_min: tau,
                ..TimeTerms::default()
            });
        }
        m
    }

    /// The tilting applied at pose `k` of `data`: none, or the static moments plus the dataset's
    /// inertial ones when it carries them.
    fn tilt_at<'d>(&self, data: &'d MeasuredSet, k: usize) -> Tilt<'d> {
        match (self.tilt, data.moments(k)) {
            (false, _) => Tilt::Off,
            (true, Some(m)) => Tilt::StaticPlus(m),
            (true, None) => Tilt::Static,
        }
    }

    /// Gravity torques about the joint axes (kgf.m), zeros without a gravity model.
    pub fn torques_kgfm(&self, q_deg: &[f64]) -> Result<Vec<f64>, ModelError> {
        match &self.gravity {
            Some(g) => g.axis_torques_kgfm(&self.model, q_deg),
            None => Ok(vec![0.0; self.model.n_joints()]),
        }
    }

    /// Whether the prediction wrt `unknowns` needs the gravity torques (compliance in the model
    /// or among the unknowns).
    pub(super) fn needs_torques(&self, unknowns: &[Unknown]) -> bool {
        self.model.transmission().has_compliance()
            || unknowns.iter().any(|u| matches!(u, Unknown::Compliance(_)))
    }

    /// Effective joint values fed to the model and the torques used (empty if not needed).
    fn effective_joints(
        &self,
        q_deg: &[f64],
        t_s: f64,
        approach: &[f64],
        with_torques: bool,
    ) -> Result<(Vec<f64>, Vec<f64>), ModelError> {
        let tau = if with_torques {
            self.torques_kgfm(q_deg)?
        } else {
            Vec::new()
        };
        Ok((self.model.joint_map(q_deg, t_s, approach, &tau), tau))
    }

    /// The direction of approach of every joint before pose `k` of `data` (empty: no history).
    pub(super) fn approach_of(data: &MeasuredSet, k: usize) -> &[f64] {
        data.approach
            .as_ref()
            .and_then(|a| a.get(k))
            .map_or(&[], Vec::as_slice)
    }

    /// Predicted measured position (mm, R) of pose `k` of `data` (with its moments, if any).
    pub fn predict_pose(&self, data: &MeasuredSet, k: usize) -> Result<Vector3<f64>, ModelError> {
        let approach = Self::approach_of(data, k);
        self.predict_with(
            &data.poses.q_deg[k],
            data.t(k),
            approach,
            self.tilt_at(data, k),
        )
    }

    fn predict_with(
        &self,
        q_deg: &[f64],
        t_s: f64,
        approach: &[f64],
        tilt: Tilt<'_>,
    ) -> Result<Vector3<f64>, ModelError> {
        let with_tau = self.model.transmission().has_compliance();
        let (q_eff, _) = self.effective_joints(q_deg, t_s, approach, with_tau)?;
        // the model as it is at t: the changes within the session before it applied
        let at_t = self.model.at_time(t_s);
        Ok(self
            .model
            .measured_mm(&at_t.position_mm(&q_eff, tilt)?, t_s))
    }

    /// Predicted position of pose `k` of `data` and its Jacobian (3 x unknowns, mm per unit).
    pub fn predict_with_jacobian(
        &self,
        data: &MeasuredSet,
        k: usize,
        unknowns: &[Unknown],
    ) -> Result<(Vector3<f64>, DMatrix<f64>), ModelError> {
        let t_s = data.t(k);
        let with_tau = self.needs_torques(unknowns);
        let approach = Self::approach_of(data, k);
        let q = &data.poses.q_deg[k];
        let (q_eff, tau) = self.effective_joints(q, t_s, approach, with_tau)?;
        let at_t = self.model.at_time(t_s);
        let steps = self.model.steps();
        // a change's columns: those of the parameter it adds to, after its time
        let step_param = |slot: usize, name: Option<&str>| -> Option<Wrt> {
            steps.get(slot).filter(|s| s.applies_at(t_s))?;
            match name {
                Some(n) => at_t.param_index(n).map(Wrt::Param),
                None => Some(Wrt::Param(at_t.payload_param())),
            }
        };
        let mut wrt: Vec<Wrt> = Vec::with_capacity(unknowns.len());
        let mut slot = Vec::with_capacity(unknowns.len());
        for u in unknowns {
            let w = match *u {
                Unknown::Param(i) => Some(Wrt::Param(i)),
                Unknown::ToolStep { slot, axis } => {
                    step_param(slot, Some(TOOL_PARAMS[axis.min(2)]))
                }
                Unknown::PayloadStep(slot) => step_param(slot, None),
                Unknown::LateralCompliance(j) => Some(Wrt::Lateral(j)),
                Unknown::JointDrift(j)
                | Unknown::Compliance(j)
                | Unknown::JointScale(j)
                | Unknown::Coupling(j, _)
                | Unknown::Hysteresis(j) => Some(Wrt::Joint(j)),
                Unknown::PositionDrift(_) | Unknown::ThermalPpm | Unknown::ThermalTauMin => None,
                Unknown::Offset { .. } => return Err(offsets_elsewhere(*u, &self.model)),
            };
            slot.push(w.map(|w| {
                wrt.push(w);
                wrt.len() - 1
            }));
        }
        // the chain's position and columns read in the evaluation workspace (no copies)
        let columns = |position_mm: &Vector3<f64>, jm: &[Vector3<f64>]| {
            // the time terms scale the chain's position (and so its derivatives)
            let thermal = self
                .model
                .time_terms()
                .thermal_derivatives(position_mm, t_s);
            let mut jac = DMatrix::zeros(3, unknowns.len());
            for (c, u) in unknowns.iter().enumerate() {
                let col: Vector3<f64> = match (*u, slot[c]) {
                    (Unknown::PositionDrift(a), _) => TimeTerms::drift_column(a, t_s),
                    (Unknown::ThermalPpm, _) => thermal.d_ppm,
                    (Unknown::ThermalTauMin, _) => thermal.d_tau_min,
                    (Unknown::JointDrift(_), Some(s)) => {
                        jm[s] * TimeTerms::joint_drift_regressor(t_s) * thermal.factor
                    }
                    (Unknown::Compliance(j), Some(s)) => {
                        jm[s] * compliance_regressor(&tau, j) * thermal.factor
                    }
                    (Unknown::JointScale(j), Some(s)) => {
                        jm[s] * q.get(j).copied().unwrap_or(0.0) * thermal.factor
                    }
                    (Unknown::Coupling(_, k), Some(s)) => {
                        jm[s] * q.get(k).copied().unwrap_or(0.0) * thermal.factor
                    }
                    (Unknown::Hysteresis(j), Some(s)) => {
                        jm[s] * approach.get(j).copied().unwrap_or(0.0) * thermal.factor
                    }
                    (_, Some(s)) => jm[s] * thermal.factor,
                    (_, None) => Vector3::zeros(),
                };
                jac.view_mut((0, c), (3, 1)).copy_from(&col);
            }
            (self.model.measured_mm(position_mm, t_s), jac)
        };
        at_t.with_position_jacobian(&q_eff, self.tilt_at(data, k), &wrt, columns)
    }

    /// The sign pattern of the tilting law (MODEL.md eq. 5.19, `sign(x)` = 0 for `|x| < 1e-9`):
    /// per pose, per joint, the signs of the three components of the static joint moment, in
    /// that order. The prediction is smooth in the unknowns only while this pattern stays the
    /// same; empty without tilting.
    pub fn moment_signs(&self, data: &MeasuredSet) -> Result<Vec<i8>, ModelError> {
        if !self.tilt {
            return Ok(Vec::new());
        }
        let with_tau = self.model.transmission().has_compliance();
        let mut out = Vec::with_capacity(3 * data.len() * self.model.n_joints());
        for k in 0..data.len() {
            let approach = Self::approach_of(data, k);
            let (q_eff, _) =
                self.effective_joints(&data.poses.q_deg[k], data.t(k), approach, with_tau)?;
            let mut moments = self.model.at_time(data.t(k)).moments_kgfm(&q_eff)?;
            if let Some(extra) = data.moments(k) {
                for (m, e) in moments.iter_mut().zip(extra) {
                    *m += e;
                }
            }
            for eta in moments {
                out.extend(eta.iter().map(|x| sign_1e9(*x) as i8));
            }
        }
        Ok(out)
    }

    /// Errors `measured - predicted` of every pose (mm): the measured part for partial
    /// measurements ([`MeasuredSet::error_mm`]).
    pub fn errors(&self, data: &MeasuredSet) -> Result<Vec<Vector3<f64>>, ModelError> {
        (0..data.len())
            .map(|k| Ok(data.error_mm(k, &self.predict_pose(data, k)?)))
            .collect()
    }

    /// Stacked Jacobian (one row per measured component: 3 per full position, one per measured
    /// direction of a partial one) wrt `unknowns`, and the stacked errors `measured - predicted`.
    pub fn stacked(
        &self,
        data: &MeasuredSet,
        unknowns: &[Unknown],
    ) -> Result<(DMatrix<f64>, DVector<f64>), ModelError> {
        let mut jac = DMatrix::zeros(data.n_residuals(), unknowns.len());
        let mut err = DVector::zeros(data.n_residuals());
        self.stacked_into(data, unknowns, &mut jac, &mut err)?;
        Ok((jac, err))
    }

    /// [`ExtModel::stacked`] into `jac` and `err`, sized for `data` and `unknowns` (every entry
    /// written).
    fn stacked_into(
        &self,
        data: &MeasuredSet,
        unknowns: &[Unknown],
        jac: &mut DMatrix<f64>,
        err: &mut DVector<f64>,
    ) -> Result<(), ModelError> {
        let mut row = 0;
        for k in 0..data.len() {
            let (p, j) = self.predict_with_jacobian(data, k, unknowns)?;
            let e = data.components(k, &(data.poses.xyz_mm[k] - p));
            err.rows_mut(row, e.len()).copy_from_slice(&e);
            row = data.put_jacobian_rows(k, &j, row, jac);
        }
        Ok(())
    }

    /// Number of rows of [`ExtModel::rows`] over `data`.
    pub fn n_rows(&self, data: &MeasuredSet) -> usize {
        match self.offsets_mm.is_empty() {
            true => data.n_residuals(),
            false => 3 * data.n_points(),
        }
    }

    /// The residual of every identification on this state: `predicted - measured` into `r`
    /// and, with `jac`, its Jacobian wrt `unknowns`. One row per measured component of every
    /// pose ([`ExtModel::stacked`]); with point slots (`offsets_mm`, [`super::general`]) 3 rows
    /// per measured point.
    pub fn rows(
        &self,
        data: &MeasuredSet,
        unknowns: &[Unknown],
        r: &mut DVector<f64>,
        jac: Option<&mut DMatrix<f64>>,
    ) -> Result<(), ModelError> {
        match (self.offsets_mm.is_empty(), jac) {
            (false, Some(jac)) => self.point_jacobian(data, unknowns, r, jac)?,
            (false, None) => self.point_residuals(data, unknowns, r)?,
            (true, Some(jac)) => {
                self.stacked_into(data, unknowns, jac, r)?;
                r.neg_mut();
            }
            (true, None) => {
                let mut row = 0;
                for k in 0..data.len() {
                    let e = data.residual(k, &self.predict_pose(data, k)?);
                    r.rows_mut(row, e.len()).copy_from_slice(&e);
                    row += e.len();
                }
            }
        }
        Ok(())
    }

    /// The least-squares problem of [`ExtModel::rows`] over `data` on the unknowns `freed`.
    pub fn problem<'a>(
        freed: Freed<ExtModel>,
        data: &'a MeasuredSet,
    ) -> ModelProblem<Freed<ExtModel>, impl Rows<Freed<ExtModel>> + 'a> {
        let m = freed.state.n_rows(data);
        let rows = |f: &Freed<ExtModel>, r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>| {
            f.state.rows(data, &f.unknowns, r, jac)
        };
        ModelProblem::new(freed, m, rows)
    }

    /// Normal equations of the residual `predicted - measured` over `data` wrt `unknowns`
    /// (both triangles of `J^T J`), accumulated pose by pose: memory `O(p^2)` whatever the
    /// number of poses, the same rows as [`ExtModel::stacked`].
    pub fn normal(&self, data: &MeasuredSet, unknowns: &[Unknown]) -> Result<Normal, ModelError> {
        let mut eq = Normal::zeros(unknowns.len());
        self.normal_into(data, unknowns, &mut eq)?;
        Ok(eq)
    }

    /// [`ExtModel::normal`] into `eq` (sized for `unknowns`).
    pub fn normal_into(
        &self,
        data: &MeasuredSet,
        unknowns: &[Unknown],
        eq: &mut Normal,
    ) -> Result<(), ModelError> {
        eq.clear();
        let n = unknowns.len();
        for k in 0..data.len() {
            let (p, j) = self.predict_with_jacobian(data, k, unknowns)?;
            let r = data.residual(k, &p);
            let partial;
            let rows = if !data.has_directions(k) {
                &j
            } else {
                partial = data.jacobian_rows(k, &j);
                &partial
            };
            for (i, ri) in r.iter().enumerate() {
                for a in 0..n {
                    let ja = rows[(i, a)];
                    if ja == 0.0 {
                        continue;
                    }
                    eq.jtr[a] += ja * ri;
                    for b in a..n {
                        eq.jtj[(a, b)] += ja * rows[(i, b)];
                    }
                }
                eq.rtr += ri * ri;
            }
            eq.m += r.len();
        }
        eq.symmetrise();
        Ok(())
    }

    /// Sum of the squared residuals (measured components) over `data`.
    pub fn sum_sq(&self, data: &MeasuredSet) -> Result<f64, ModelError> {
        let mut s = 0.0;
        for k in 0..data.len() {
            let p = self.predict_pose(data, k)?;
            s += data.residual(k, &p).iter().map(|c| c * c).sum::<f64>();
        }
        Ok(s)
    }
}

mod values;

#[cfg(test)]
mod transmission_tests {
    use super::*;
    use crate::calib::measured::PosePoints;
    use crate::model::katana450;

    /// The analytic columns of the transmission unknowns match central differences.
    #[test]
    fn transmission_jacobian_matches_finite_differences() {
        let mut ext = ExtModel::new(katana450(200.0).expect("preset"));
        let q = vec![
            vec![10.0, 80.0, -60.0, 20.0, 30.0],
            vec![-20.0, 95.0, -80.0, -10.0, 60.0],
            vec![35.0, 70.0, -40.0, 40.0, -30.0],
        ];
        let data = MeasuredSet::from_poses(PosePoints {
            xyz_mm: vec![Vector3::zeros(); q.len()],
            q_deg: q,
        })
        .with_approach();
        let unknowns = [
            Unknown::JointScale(1),
            Unknown::Coupling(2, 1),
            Unknown::Hysteresis(3),
        ];
        for (u, v) in unknowns.iter().zip([1e-3, 2e-3, 0.05]) {
            ext.set_value(*u, v).expect("set");
        }
        for k in 0..data.len() {
            let (_, jac) = ext
                .predict_with_jacobian(&data, k, &unknowns)
                .expect("jacobian");
            for (c, u) in unknowns.iter().enumerate() {
                let h = 1e-6;
                let mut plus = ext.clone();
                plus.set_value(*u, ext.value(*u) + h).expect("set");
                let mut minus = ext.clone();
                minus.set_value(*u, ext.value(*u) - h).expect("set");
                let fd = (plus.predict_pose(&data, k).expect("p")
                    - minus.predict_pose(&data, k).expect("p"))
                    / (2.0 * h);
                let an = Vector3::new(jac[(0, c)], jac[(1, c)], jac[(2, c)]);
                let scale = fd.norm().max(an.norm()).max(1e-9);
                assert!(
                    (fd - an).norm() <= 1e-5 * scale,
                    "pose {k} {u:?}: fd {fd:?} analytic {an:?}"
                );
            }
        }
    }
}
