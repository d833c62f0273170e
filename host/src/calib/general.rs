//! The identification beyond one tool point and the chain parameters: several measured points
//! per pose ([`MeasuredSet`], each point with its own offset in the tool frame) and joint
//! compliance (a joint deflection proportional to the gravity torque about its axis, the
//! `compliance:j<i>` law of [`crate::model::transmission::compliance_deflection_deg`]) and
//! lateral compliance (the joint bent across its axis by the gravity moments, applied by the
//! chain itself, `lateral_compliance:j<i>`) and joint hysteresis (an angle offset by the
//! direction from which the joint approached the pose, `hysteresis:j<i>`: a backlash whose
//! side the path to the pose sets), on the one state [`ExtModel`] (its `offsets_mm`).
//!
//! Prediction of measurement (pose i, slot k):
//!
//! ```text
//! q_eff = q_i + c . tau(q_i) + b . d_i      c deg per kgf.m, tau from the link masses;
//!                                           b deg, d_i the directions of approach (+1, -1, 0)
//! p     = fk(q_eff) with the tool point = slot k's offset (slot 0: tool_dx..dz)
//! ```
//!
//! The torques are those of the state's chain at the readings ([`ExtModel::torques_kgfm`], as
//! the written model applies them); the Jacobian takes them as fixed regressors (the
//! compliance is a small correction of a stiff joint).

use nalgebra::{DMatrix, DVector, Vector3};

use super::error::CalibError;
use super::fit::{solve_split, Fit, Split};
use super::identifiability::analyse;
use super::lm::LmConfig;
use super::measured::MeasuredSet;
use super::problem::{put_position_rows, tilt_mode};
pub use super::state::ExtModel;
use super::unknown::Freed;
pub use super::unknown::{Unknown, Values};
use crate::model::gravity::GravityModel;
use crate::model::transmission::{compliance_deflected, compliance_regressor};
use crate::model::{Model, ModelError, Wrt};

/// An unknown this identification does not evaluate.
fn not_here(u: Unknown, model: &Model) -> ModelError {
    ModelError::Invalid(format!(
        "{} is not an unknown of the identification with point offsets and compliance",
        u.name(model)
    ))
}

fn tool_of(model: &Model) -> Result<[usize; 3], ModelError> {
    Ok([
        model.require_param("tool_dx")?,
        model.require_param("tool_dy")?,
        model.require_param("tool_dz")?,
    ])
}

impl ExtModel {
    /// `model` with `slots` point slots, all starting at its tool point, and no compliance or
    /// hysteresis (its other terms as they are: the measured set has been through them,
    /// [`MeasuredSet::through_terms`]; so are a model file's own hysteresis terms, which the
    /// caller adds back to the written model).
    pub fn with_points(model: Model, slots: usize, tilt: bool) -> Result<Self, ModelError> {
        let t = tool_of(&model)?;
        let v = model.param_values();
        let tool = Vector3::new(v[t[0]], v[t[1]], v[t[2]]);
        let mut model = model;
        let n = model.n_joints();
        model.transmission_mut().compliance_deg_per_kgfm = vec![0.0; n];
        model.transmission_mut().hysteresis_deg = vec![0.0; n];
        Ok(Self {
            gravity: GravityModel::for_model(&model),
            offsets_mm: vec![tool; slots.max(1)],
            model,
            tilt,
        })
    }

    /// Compliance per joint, deg per kgf.m (the model's joint terms).
    pub fn compliance_deg_per_kgfm(&self) -> &[f64] {
        &self.model.transmission().compliance_deg_per_kgfm
    }

    /// The name of an unknown: the parameter's, `marker<k>_x_mm`, `compliance_j<i>_deg_per_kgfm`.
    pub fn name_in(&self, u: Unknown, data: &MeasuredSet) -> String {
        match u {
            Unknown::Param(i) => self
                .model
                .params()
                .get(i)
                .map_or_else(|| format!("param{i}"), |p| p.name.clone()),
            Unknown::Offset { slot, axis } => data.offset_name(slot, axis),
            other => other.name(&self.model),
        }
    }

    /// The model of every slot: the tool point moved to the slot's offset (slot 0: as is).
    fn slot_models(&self) -> Result<Vec<Model>, ModelError> {
        let t = tool_of(&self.model)?;
        let mut out = vec![self.model.clone()];
        for o in self.offsets_mm.iter().skip(1) {
            let mut m = self.model.clone();
            for (&i, &v) in t.iter().zip(o.iter()) {
                m.set_param_at(i, v)?;
            }
            out.push(m);
        }
        Ok(out)
    }

    /// The joint values the chain turns by at pose `pose` of `data` with torques `tau`: the
    /// readings deflected by the compliance and offset by the hysteresis in the direction of
    /// approach.
    fn pose_joints(&self, data: &MeasuredSet, pose: usize, tau: &[f64]) -> Vec<f64> {
        let mut q =
            compliance_deflected(&data.poses.q_deg[pose], self.compliance_deg_per_kgfm(), tau);
        let approach = ExtModel::approach_of(data, pose);
        for ((qj, b), d) in q
            .iter_mut()
            .zip(&self.model.transmission().hysteresis_deg)
            .zip(approach)
        {
            *qj += b * d;
        }
        q
    }

    /// The gravity torques of every pose of `data` (kgf.m; empty ones when not `needed`).
    fn pose_torques(&self, data: &MeasuredSet, needed: bool) -> Result<Vec<Vec<f64>>, ModelError> {
        data.poses
            .q_deg
            .iter()
            .map(|q| match needed {
                true => self.torques_kgfm(q),
                false => Ok(Vec::new()),
            })
            .collect()
    }

    /// Errors `measured - predicted` of every measured point (mm).
    pub fn point_errors(&self, data: &MeasuredSet) -> Result<Vec<Vector3<f64>>, ModelError> {
        let models = self.slot_models()?;
        let tilt = tilt_mode(self.tilt);
        let tau = self.pose_torques(data, self.needs_torques(&[]))?;
        data.points()
            .map(|m| {
                let q = self.pose_joints(data, m.pose, &tau[m.pose]);
                let model = models.get(m.slot).unwrap_or(&self.model);
                Ok(m.xyz_mm - model.position_mm(&q, tilt)?)
            })
            .collect()
    }

    /// The unknowns of `unknowns` as what the chain differentiates: a point offset moves the
    /// tool point (`tool_of`).
    fn point_wrt(&self, unknowns: &[Unknown]) -> Result<Vec<Wrt>, ModelError> {
        let t = tool_of(&self.model)?;
        unknowns
            .iter()
            .map(|u| match *u {
                Unknown::Param(i) => Ok(Wrt::Param(i)),
                Unknown::Offset { axis, .. } => Ok(Wrt::Param(t[axis.min(2)])),
                Unknown::Compliance(j) => Ok(Wrt::Joint(j)),
                Unknown::LateralCompliance(j) => Ok(Wrt::Lateral(j)),
                Unknown::Hysteresis(j) => Ok(Wrt::Joint(j)),
                other => Err(not_here(other, &self.model)),
            })
            .collect()
    }

    /// The residuals `predicted - measured` of every measured point (3 rows each) into `r`:
    /// [`ExtModel::rows`] with point slots, without the Jacobian.
    pub(super) fn point_residuals(
        &self,
        data: &MeasuredSet,
        unknowns: &[Unknown],
        r: &mut DVector<f64>,
    ) -> Result<(), ModelError> {
        // an unknown this prediction does not evaluate is refused with or without the Jacobian
        self.point_wrt(unknowns)?;
        let models = self.slot_models()?;
        let tilt = tilt_mode(self.tilt);
        let tau = self.pose_torques(data, self.needs_torques(unknowns))?;
        for (i, m) in data.points().enumerate() {
            let q = self.pose_joints(data, m.pose, &tau[m.pose]);
            let model = models.get(m.slot).unwrap_or(&self.model);
            let p = model.position_mm(&q, tilt)?;
            put_position_rows(3 * i, &p, &m.xyz_mm, r, None);
        }
        Ok(())
    }

    /// [`ExtModel::point_residuals`] and their Jacobian wrt `unknowns` into `jac`:
    /// [`ExtModel::rows`] with point slots.
    pub(super) fn point_jacobian(
        &self,
        data: &MeasuredSet,
        unknowns: &[Unknown],
        r: &mut DVector<f64>,
        jac: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        let wrt = self.point_wrt(unknowns)?;
        let models = self.slot_models()?;
        let tilt = tilt_mode(self.tilt);
        let t = tool_of(&self.model)?;
        let tau = self.pose_torques(data, self.needs_torques(unknowns))?;
        for (i, m) in data.points().enumerate() {
            let tau_i = &tau[m.pose];
            let approach = ExtModel::approach_of(data, m.pose);
            let q = self.pose_joints(data, m.pose, tau_i);
            let model = models.get(m.slot).unwrap_or(&self.model);
            let (fk, j) = model.position_jacobian(&q, tilt, &wrt)?;
            let mut columns = unknowns.iter().enumerate().map(|(c, u)| {
                let scale = match *u {
                    // The tool point of slot 0 is not the point of the other slots.
                    Unknown::Param(p) if m.slot != 0 && t.contains(&p) => 0.0,
                    Unknown::Offset { slot, .. } if slot != m.slot || slot == 0 => 0.0,
                    Unknown::Compliance(jt) => compliance_regressor(tau_i, jt),
                    Unknown::Hysteresis(jt) => approach.get(jt).copied().unwrap_or(0.0),
                    _ => 1.0,
                };
                j.fixed_view::<3, 1>(0, c) * scale
            });
            let jac = Some((
                &mut *jac,
                &mut columns as &mut dyn Iterator<Item = Vector3<f64>>,
            ));
            put_position_rows(3 * i, &fk.position_mm, &m.xyz_mm, r, jac);
        }
        Ok(())
    }
}

/// Result of [`fit_general`]: the fitted model, offsets and compliances, and the fitted and
/// fixed unknowns.
pub type GeneralFit = Fit<ExtModel, Unknown>;

/// Stacked Jacobian (rows `predicted - measured`) and residuals of `state`'s measured points wrt
/// `unknowns`.
pub fn stacked(
    state: &ExtModel,
    data: &MeasuredSet,
    unknowns: &[Unknown],
) -> Result<(DMatrix<f64>, DVector<f64>), ModelError> {
    let mut r = DVector::zeros(state.n_rows(data));
    let mut jac = DMatrix::zeros(state.n_rows(data), unknowns.len());
    state.rows(data, unknowns, &mut r, Some(&mut jac))?;
    Ok((jac, r))
}

/// Identifies `selection` (in preference order: later ones are fixed first when a combination
/// is unidentifiable, threshold `rtol`) from `start` on `data`'s measured points.
pub fn fit_general(
    start: &ExtModel,
    data: &MeasuredSet,
    selection: &[Unknown],
    lm: &LmConfig,
    rtol: f64,
) -> Result<GeneralFit, CalibError> {
    if data.is_empty() {
        return Err(CalibError::NoPoses);
    }
    let (jac0, _) = stacked(start, data, selection)?;
    let names: Vec<String> = selection.iter().map(|&u| start.name_in(u, data)).collect();
    let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let split = Split::of(selection, &name_refs, &analyse(&jac0, rtol)).nonempty()?;
    let freed = Freed::new(start.clone(), split.fitted.clone());
    let x0 = freed.values();
    let problem = ExtModel::problem(freed, data);
    let mut fit = solve_split(split, problem, x0, lm, rtol)?.map_model(|f| f.state);
    // Slot 0's offset mirrors the tool point.
    let v = fit.model.model.param_values();
    let t = tool_of(&fit.model.model)?;
    if let Some(o) = fit.model.offsets_mm.first_mut() {
        *o = Vector3::new(v[t[0]], v[t[1]], v[t[2]]);
    }
    Ok(fit)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::measured::PosePoints;
    use crate::model::Tilt;
    use crate::urdf::{import_chain_with_masses, ImportOptions, Urdf};

    /// The analytic Jacobian of [`stacked`] at `at` against central differences of its
    /// residuals, column by column; returns the Jacobian.
    fn columns_match_central_differences(
        at: &ExtModel,
        data: &MeasuredSet,
        sel: &[Unknown],
    ) -> DMatrix<f64> {
        let (jac, r0) = stacked(at, data, sel).unwrap();
        for (c, &u) in sel.iter().enumerate() {
            let h = 1e-6;
            let (mut p, mut m) = (at.clone(), at.clone());
            p.set_value(u, at.value(u) + h).unwrap();
            m.set_value(u, at.value(u) - h).unwrap();
            let (_, rp) = stacked(&p, data, sel).unwrap();
            let (_, rm) = stacked(&m, data, sel).unwrap();
            let fd = (rp - rm) / (2.0 * h);
            assert!(
                (fd - jac.column(c)).amax() < 1e-5 * (1.0 + r0.amax()),
                "column {c}"
            );
        }
        jac
    }

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

    /// The two-link arm of [`XML`], with the URDF's masses.
    fn xml_model() -> Model {
        let urdf = Urdf::parse(XML, "m.urdf").unwrap();
        let opts = ImportOptions {
            base_link: None,
            tip_link: "tip",
            tool_mm: [0.0; 3],
        };
        import_chain_with_masses(&urdf, &opts).unwrap().model
    }

    /// Exact data of a compliant arm: the torques are the URDF's (|tau_1| = 2*0.4 + 1*1.1 kgf.m
    /// at q = 0), the compliances are recovered, the residual vanishes, and the Jacobian
    /// matches finite differences.
    #[test]
    fn compliance_is_recovered_with_the_gravity_torques() {
        let model = xml_model();
        let g = GravityModel::for_model(&model).unwrap();
        let t0 = g.axis_torques_kgfm(&model, &[0.0, 0.0]).unwrap();
        assert!((t0[0].abs() - 1.9).abs() < 1e-12, "{t0:?}");
        let coef = [0.05, -0.2];
        let mut poses = PosePoints::default();
        for a in [-60.0, -25.0, 0.0, 30.0, 70.0] {
            for b in [-80.0, -20.0, 15.0, 50.0, 100.0] {
                let q = vec![a, b];
                let tau = g.axis_torques_kgfm(&model, &q).unwrap();
                let qc = compliance_deflected(&q, &coef, &tau);
                poses
                    .xyz_mm
                    .push(model.position_mm(&qc, Tilt::Off).unwrap());
                poses.q_deg.push(q);
            }
        }
        let data = MeasuredSet::from_poses(poses);
        let start = ExtModel::with_points(model.clone(), 1, false).unwrap();
        let sel = [Unknown::Compliance(0), Unknown::Compliance(1)];
        // Jacobian against central differences at a point off the solution.
        let mut at = start.clone();
        at.model.transmission_mut().compliance_deg_per_kgfm = vec![0.02, 0.1];
        columns_match_central_differences(&at, &data, &sel);
        let fit = fit_general(&start, &data, &sel, &LmConfig::default(), 1e-6).unwrap();
        for (f, c) in fit.model.compliance_deg_per_kgfm().iter().zip(coef) {
            assert!((f - c).abs() < 1e-6, "{f} vs {c}");
        }
        let worst = fit
            .model
            .point_errors(&data)
            .unwrap()
            .iter()
            .map(|e| e.norm())
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "{worst}");
    }

    /// A third joint about the vertical axis under the two: gravity bends it across its axis
    /// (its lateral compliance), which the planar joints above cannot express exactly. The
    /// lateral column matches finite differences at a point off the solution, and the fit
    /// recovers the lateral and axial compliances of exact data.
    #[test]
    fn lateral_compliance_in_the_general_identification() {
        let xml = XML
            .replace(
                r#"<link name="base"/>"#,
                r#"<link name="base"/><link name="l0"><inertial><mass value="3"/><origin xyz="0 0 0.2"/></inertial></link>
      <joint name="j0" type="revolute"><parent link="base"/><child link="l0"/>
        <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit lower="-3" upper="3"/></joint>"#,
            )
            .replace(r#"<parent link="base"/><child link="l1"/>"#, r#"<parent link="l0"/><child link="l1"/>"#);
        let urdf = Urdf::parse(&xml, "m.urdf").unwrap();
        let opts = ImportOptions {
            base_link: None,
            tip_link: "tip",
            tool_mm: [0.0; 3],
        };
        let model = import_chain_with_masses(&urdf, &opts).unwrap().model;
        assert_eq!(model.n_joints(), 3);
        let sel = [Unknown::LateralCompliance(0), Unknown::Compliance(1)];
        let mut truth = ExtModel::with_points(model.clone(), 1, false).unwrap();
        truth.set_value(sel[0], 0.3).unwrap();
        truth.set_value(sel[1], 0.05).unwrap();
        let mut poses = PosePoints::default();
        for z in [-120.0, -40.0, 30.0, 110.0] {
            for a in [-60.0, -25.0, 10.0, 45.0] {
                for b in [-80.0, 15.0, 90.0] {
                    poses.q_deg.push(vec![z, a, b]);
                    poses.xyz_mm.push(Vector3::zeros());
                }
            }
        }
        let blank = MeasuredSet::from_poses(poses.clone());
        for (k, e) in truth.point_errors(&blank).unwrap().iter().enumerate() {
            poses.xyz_mm[k] = -e; // measured = 0 - error = predicted
        }
        let data = MeasuredSet::from_poses(poses);
        let start = ExtModel::with_points(model, 1, false).unwrap();
        let mut at = start.clone();
        at.set_value(sel[0], 0.1).unwrap();
        at.set_value(sel[1], 0.02).unwrap();
        let jac = columns_match_central_differences(&at, &data, &sel);
        assert!(jac.column(0).amax() > 1e-3, "the bend is seen");
        let fit = fit_general(&start, &data, &sel, &LmConfig::default(), 1e-6).unwrap();
        for (u, want) in sel.iter().zip([0.3, 0.05]) {
            let got = fit.model.value(*u);
            assert!((got - want).abs() < 1e-6, "{u:?}: {got} vs {want}");
        }
    }
    /// Hysteresis: each joint offset by `b` in the direction from which it approached the pose
    /// (the pose order). The column is the joint's column times that direction (0 at the first
    /// pose), it matches finite differences off the solution, and the fit recovers `b` of
    /// exact data together with a length.
    #[test]
    fn hysteresis_in_the_general_identification() {
        let model = xml_model();
        let length = Unknown::Param(model.param_index("j2_x").unwrap());
        let sel = [Unknown::Hysteresis(0), Unknown::Hysteresis(1), length];
        let mut truth = ExtModel::with_points(model.clone(), 1, false).unwrap();
        truth.set_value(sel[0], 0.3).unwrap();
        truth.set_value(sel[1], -0.5).unwrap();
        truth.set_value(length, 801.5).unwrap();
        // up and down in both joints, not together
        let path = [
            [-60.0, -80.0],
            [-20.0, 40.0],
            [30.0, 10.0],
            [10.0, 90.0],
            [-40.0, -30.0],
            [50.0, -60.0],
            [20.0, 70.0],
            [70.0, 20.0],
            [-10.0, 100.0],
            [0.0, -10.0],
        ];
        let mut poses = PosePoints::default();
        for q in path {
            poses.q_deg.push(q.to_vec());
            poses.xyz_mm.push(Vector3::zeros());
        }
        let blank = MeasuredSet::from_poses(poses.clone()).with_approach();
        for (k, e) in truth.point_errors(&blank).unwrap().iter().enumerate() {
            poses.xyz_mm[k] = -e; // measured = 0 - error = predicted
        }
        let data = MeasuredSet::from_poses(poses).with_approach();
        let start = ExtModel::with_points(model, 1, false).unwrap();
        let mut at = start.clone();
        at.set_value(sel[0], 0.1).unwrap();
        at.set_value(sel[1], -0.1).unwrap();
        let jac = columns_match_central_differences(&at, &data, &sel);
        // the first pose has no history: no hysteresis there
        assert_eq!(jac.fixed_view::<3, 2>(0, 0).amax(), 0.0);
        assert!(jac.column(1).amax() > 1.0, "the offset is seen");
        let fit = fit_general(&start, &data, &sel, &LmConfig::default(), 1e-6).unwrap();
        for (u, want) in sel.iter().zip([0.3, -0.5, 801.5]) {
            let got = fit.model.value(*u);
            assert!((got - want).abs() < 1e-6, "{u:?}: {got} vs {want}");
        }
    }
}
