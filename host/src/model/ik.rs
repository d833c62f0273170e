//! Inverse kinematics of the 5-DOF Katana: tool point + tool-axis direction -> joint readings.
//!
//! # Which targets are attainable
//! The Katana's 200 mm tool stands at right angles to the wrist-roll axis (MODEL.md erratum 5):
//! `tool axis t = sin(q5) e_phi - cos(q5) e_n`, where `e_n` is the horizontal normal of the arm's
//! vertical plane (azimuth q1) and `e_phi` the in-plane direction at pitch `q2+q3+q4`. Position
//! (3) + axis direction (2) are 5 conditions for 5 joints, so *any* tool-axis direction is
//! attainable at a point, as long as
//! - the wrist point `W = p - d5 t` is not on the joint-1 axis (there q1 is free),
//! - the joint-4 point `W - d4 r` (r: roll axis, in the arm plane and normal to t) is within
//!   `|a2 - a3| .. a2 + a3` of the shoulder,
//! - the joint values are within the limits.
//!
//! The rotation of the tool about its own axis is not free (it follows from q1..q5). When `t` is
//! normal to the arm plane (`t = -+e_n`, as at q = 0) the roll axis may point anywhere in the
//! plane and the arm has a one-parameter self-motion; the reachable wrist pitch nearest the
//! seed's is used there.
//!
//! # Method
//! A closed-form solution on the model's geometry at q = 0 (lengths a2, a3, d4, d5 and the
//! shoulder position, read off the model's frames, so it is exact for the nominal Katana)
//! gives up to 8 candidates (q1 or q1 + 180, the sign of sin q5, elbow up/down). They are tried
//! nearest-to-seed first; each is refined by Gauss-Newton on the model's own FK (analytic joint
//! Jacobian from the joint frames: `z_i x (p - o_i)` and `z_i x t`), which makes the result
//! exact for any calibrated (non-nominal) model and, with tilting, for the tilted model. The
//! first candidate that converges within the joint limits is returned.

use nalgebra::{DMatrix, DVector, Vector3};

use super::lateral::lateral_tilt_deg;
use super::{Model, ModelError, Tilt};

/// Joints the Katana's IK starts its search from (arm forward over the ISO cube, tool down-ish).
pub const KATANA_SEED_DEG: [f64; 5] = [-90.0, 60.0, -60.0, 0.0, 90.0];

/// A Cartesian target: a tool-point position (mm, frame R) and the tool-axis direction (unit).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolTarget {
    /// Tool point, mm in frame R.
    pub position_mm: Vector3<f64>,
    /// Unit vector along the tool (from the wrist towards the tool point).
    pub axis: Vector3<f64>,
}

/// Weight of the tool-axis residual relative to the position residual (mm per unit vector).
const AXIS_WEIGHT_MM: f64 = 100.0;
/// Newton iterations per candidate.
const MAX_ITER: usize = 60;
/// Convergence: position residual, mm.
const TOL_MM: f64 = 1e-10;
/// Convergence: tool-axis residual (unit vector).
const TOL_AXIS: f64 = 1e-12;
/// Closed-form candidates this far outside the limits are still refined (a calibrated model's
/// solution may lie inside while the nominal one does not), deg.
const CANDIDATE_MARGIN_DEG: f64 = 10.0;
/// Largest Newton step (deg, infinity norm).
const MAX_STEP_DEG: f64 = 10.0;
/// Joint limits are enforced with this slack (deg).
const LIMIT_SLACK_DEG: f64 = 1e-9;

/// Why a target could not be reached.
#[derive(Debug, thiserror::Error)]
pub enum IkError {
    /// No candidate converged within the joint limits.
    #[error("target {position_mm:?} mm with tool axis {axis:?} is not reachable within the joint limits (best residual {residual_mm:.3e} mm)")]
    Unreachable {
        position_mm: [f64; 3],
        axis: [f64; 3],
        residual_mm: f64,
    },
    /// The seed has the wrong number of joints, or the model failed.
    #[error(transparent)]
    Model(#[from] ModelError),
}

impl crate::error::Classify for IkError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            IkError::Unreachable { .. } => crate::error::ErrorKind::Failure,
            IkError::Model(e) => e.kind(),
        }
    }
}

/// Whether the IK solves against the rigid chain or the chain with static joint tilting.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum IkTilt {
    /// Rigid chain (what a controller with this model would command).
    #[default]
    Off,
    /// Chain with the declared static tilting (the pose the arm really reaches).
    Static,
}

/// Lengths of the Katana-type chain, read off the model's frames at q = 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmGeometry {
    /// Origin of joint frames 1/2 (the shoulder), mm in R.
    pub shoulder_mm: Vector3<f64>,
    /// Upper arm (joint 2 -> joint 3), mm.
    pub a2_mm: f64,
    /// Forearm (joint 3 -> joint 4), mm.
    pub a3_mm: f64,
    /// Joint 4 -> wrist point (joint 5 origin), mm.
    pub d4_mm: f64,
    /// Wrist point -> tool point, mm.
    pub d5_mm: f64,
}

impl ArmGeometry {
    /// Reads the geometry of a 5-joint model from its frames at q = 0.
    pub fn of(model: &Model) -> Result<Self, ModelError> {
        let n = model.n_joints();
        if n != 5 {
            return Err(ModelError::Invalid(format!(
                "the closed-form IK needs a 5-joint Katana-type chain, model `{}` has {n} joints",
                model.name()
            )));
        }
        let fr = model.frames(&[0.0; 5], None)?;
        let o: Vec<Vector3<f64>> = model.joints().iter().map(|j| fr.pos_mm[j.elem]).collect();
        Ok(Self {
            shoulder_mm: o[1],
            a2_mm: (o[2] - o[1]).norm(),
            a3_mm: (o[3] - o[2]).norm(),
            d4_mm: (o[4] - o[3]).norm(),
            d5_mm: (fr.tool_mm() - o[4]).norm(),
        })
    }
}

fn wrap_rad(a: f64) -> f64 {
    let w = a.rem_euclid(std::f64::consts::TAU);
    if w > std::f64::consts::PI {
        w - std::f64::consts::TAU
    } else {
        w
    }
}

/// Closed-form candidates (rad, unwrapped later) for the nominal Katana geometry.
/// `phi_seed` is the wrist pitch `q2+q3+q4` wanted when the roll axis is free (the reachable
/// pitch nearest to it is used).
pub fn closed_form_candidates(
    geo: &ArmGeometry,
    target: &ToolTarget,
    phi_seed: f64,
    q1_seed: f64,
) -> Vec<[f64; 5]> {
    let t = target.axis.normalize();
    let w = target.position_mm - geo.shoulder_mm - t * geo.d5_mm;
    let rho_w = w.x.hypot(w.y);
    let az = if rho_w > 1e-9 {
        w.y.atan2(w.x)
    } else {
        q1_seed
    };
    let up = Vector3::z();
    let mut out = Vec::new();
    for q1 in [az, az + std::f64::consts::PI] {
        let e_rho = Vector3::new(q1.cos(), q1.sin(), 0.0);
        let e_n = Vector3::new(-q1.sin(), q1.cos(), 0.0);
        let c5 = -t.dot(&e_n);
        let t_p = t - e_n * t.dot(&e_n);
        let s_abs = t_p.norm();
        // elbow position of the planar 2-link problem for wrist pitch `phi`, if reachable
        let planar = |phi: f64| {
            let r = -e_rho * phi.sin() + up * phi.cos();
            let p4 = w - r * geo.d4_mm;
            let (rho, h) = (p4.dot(&e_rho), p4.z);
            let (a2, a3) = (geo.a2_mm, geo.a3_mm);
            let d = (rho * rho + h * h - a2 * a2 - a3 * a3) / (2.0 * a2 * a3);
            (-1.0 - 1e-12..=1.0 + 1e-12)
                .contains(&d)
                .then_some((rho, h, d.clamp(-1.0, 1.0)))
        };
        for sgn in [1.0, -1.0] {
            let (phi, q5) = if s_abs < 1e-12 {
                // singular: the roll axis may point anywhere in the arm plane; take the
                // reachable pitch nearest the seed's (1-degree search)
                let Some(phi) = (0..=180)
                    .flat_map(|k| [k, -k])
                    .map(|k| phi_seed + f64::from(k).to_radians())
                    .find(|phi| planar(*phi).is_some())
                else {
                    break;
                };
                (phi, 0f64.atan2(c5))
            } else {
                let e_phi = t_p * (sgn / s_abs);
                (
                    e_phi.dot(&up).atan2(e_phi.dot(&e_rho)),
                    (sgn * s_abs).atan2(c5),
                )
            };
            if let Some((rho, h, d)) = planar(phi) {
                let (a2, a3) = (geo.a2_mm, geo.a3_mm);
                for elbow in [1.0, -1.0] {
                    let q3 = elbow * d.acos();
                    let q2 = h.atan2(rho) - (a3 * q3.sin()).atan2(a2 + a3 * q3.cos());
                    let q4 = phi - q2 - q3;
                    out.push([q1, q2, q3, q4, q5].map(wrap_rad));
                }
            }
            if s_abs < 1e-12 {
                break;
            }
        }
    }
    out
}

/// Chooses, for each joint, the representation `a + 2 pi k` nearest to the seed inside the
/// limits widened by `margin_deg` (deg), clamped into the limits. `None` if some joint has no
/// such representation.
fn fit_to_limits(
    q_rad: &[f64],
    seed_deg: &[f64],
    limits: &[[f64; 2]],
    margin_deg: f64,
) -> Option<Vec<f64>> {
    let mut out = Vec::with_capacity(q_rad.len());
    for (i, l) in limits.iter().enumerate() {
        let base = wrap_rad(q_rad[i]).to_degrees();
        let best = [-360.0, 0.0, 360.0]
            .iter()
            .map(|k| base + k)
            .filter(|v| *v >= l[0] - margin_deg && *v <= l[1] + margin_deg)
            .min_by(|a, b| (a - seed_deg[i]).abs().total_cmp(&(b - seed_deg[i]).abs()))?;
        out.push(best.clamp(l[0], l[1]));
    }
    Some(out)
}

/// The tilts the chain takes at `q_deg`: the declared tilting (with [`IkTilt::Static`]) plus
/// the lateral compliance's bend, which is part of the chain whatever the tilting mode (as in
/// [`Model::fk`]); `None` when nothing tilts.
fn tilt_mode(
    model: &Model,
    q_deg: &[f64],
    tilt: IkTilt,
) -> Result<Option<Vec<Vector3<f64>>>, ModelError> {
    let lateral = model.has_lateral_compliance();
    if matches!(tilt, IkTilt::Off) && !lateral {
        return Ok(None);
    }
    let m = model.moments_kgfm(q_deg)?;
    let mut tilts = match tilt {
        IkTilt::Static => model.tilts_deg(&m)?,
        IkTilt::Off => vec![Vector3::zeros(); m.len()],
    };
    if lateral {
        for (j, (t, eta)) in tilts.iter_mut().zip(&m).enumerate() {
            *t += lateral_tilt_deg(model.lateral_compliance_at(j), eta);
        }
    }
    Ok(Some(tilts))
}

/// Tool point (mm, R, scale included) and tool axis of `model` at `q_deg`.
pub fn tool_target(model: &Model, q_deg: &[f64], tilt: IkTilt) -> Result<ToolTarget, ModelError> {
    let fk = match tilt {
        IkTilt::Off => model.fk(q_deg, Tilt::Off)?,
        IkTilt::Static => model.fk(q_deg, Tilt::Static)?,
    };
    Ok(ToolTarget {
        position_mm: fk.position_mm,
        axis: fk.rotation.column(2).into_owned(),
    })
}

/// Residual (target - current; the axis rows weighted by [`AXIS_WEIGHT_MM`]) and joint
/// Jacobian (per degree, or per mm for a prismatic joint) at `q_deg`.
fn residual_and_jacobian(
    model: &Model,
    q_deg: &[f64],
    target: &ToolTarget,
    tilt: IkTilt,
) -> Result<(DVector<f64>, DMatrix<f64>, f64, f64), ModelError> {
    let tilts = tilt_mode(model, q_deg, tilt)?;
    let fr = model.frames(q_deg, tilts.as_deref())?;
    let scale = model.scale_factor();
    let p = fr.tool_mm() * scale;
    let t = fr.tool_rot().column(2).into_owned();
    let n = q_deg.len();
    let mut e = DVector::zeros(6);
    let dp = target.position_mm - p;
    let dt = target.axis.normalize() - t;
    for k in 0..3 {
        e[k] = dp[k];
        e[3 + k] = dt[k] * AXIS_WEIGHT_MM;
    }
    let mut jac = DMatrix::zeros(6, n);
    for (j, joint) in model.joints().iter().enumerate() {
        let o = fr.pos_mm[joint.elem];
        let z = fr.joint_rot_untilted[j].column(2).into_owned();
        // d(effective joint value)/d(reading): 1 + the encoder harmonics' slope
        let dv = model.joint_value(j, q_deg[j]).1;
        let (col_p, col_t) = if joint.prismatic {
            (z * (dv * scale), Vector3::zeros())
        } else {
            let per_deg = dv.to_radians();
            (z.cross(&(p - o * scale)) * per_deg, z.cross(&t) * per_deg)
        };
        for k in 0..3 {
            jac[(k, j)] = col_p[k];
            jac[(3 + k, j)] = col_t[k] * AXIS_WEIGHT_MM;
        }
    }
    Ok((e, jac, dp.norm(), dt.norm()))
}

/// Gauss-Newton refinement of `q_start_deg` on the model's FK (SVD least squares on the 6 x n
/// system of position and weighted tool-axis residuals, steps capped at 10 deg, stopping when
/// converged, after 60 iterations, or when a step makes the residual grow more than 4-fold).
/// With tilting the Jacobian leaves out the tilt's slope, so convergence is linear (the tilt
/// changes slowly with the joints). Returns the joints (deg) and the final position residual
/// (mm) and axis residual (unit vector).
pub fn refine(
    model: &Model,
    target: &ToolTarget,
    q_start_deg: &[f64],
    tilt: IkTilt,
) -> Result<(Vec<f64>, f64, f64), ModelError> {
    let mut q = q_start_deg.to_vec();
    let (mut e, mut jac, mut rp, mut rt) = residual_and_jacobian(model, &q, target, tilt)?;
    for _ in 0..MAX_ITER {
        if rp < TOL_MM && rt < TOL_AXIS {
            break;
        }
        let svd = jac.clone().svd(true, true);
        let Ok(step) = svd.solve(&e, 1e-12) else {
            break;
        };
        let biggest = step.amax();
        let shrink = if biggest > MAX_STEP_DEG {
            MAX_STEP_DEG / biggest
        } else {
            1.0
        };
        let mut trial = q.clone();
        for (qi, s) in trial.iter_mut().zip(step.iter()) {
            *qi += s * shrink;
        }
        let (e2, j2, rp2, rt2) = residual_and_jacobian(model, &trial, target, tilt)?;
        let before = rp + rt * AXIS_WEIGHT_MM;
        let after = rp2 + rt2 * AXIS_WEIGHT_MM;
        if !after.is_finite() || after > before * 4.0 + 1e-9 {
            break;
        }
        q = trial;
        (e, jac, rp, rt) = (e2, j2, rp2, rt2);
    }
    Ok((q, rp, rt))
}

/// Joints (deg) that put the tool point at `target.position_mm` with the tool axis along
/// `target.axis`, within the joint limits, nearest to `seed_deg` among the closed-form branches.
pub fn solve(
    model: &Model,
    target: &ToolTarget,
    seed_deg: &[f64],
    tilt: IkTilt,
) -> Result<Vec<f64>, IkError> {
    model.check_joints(seed_deg)?;
    let axis_norm = target.axis.norm();
    let finite = target
        .position_mm
        .iter()
        .chain(target.axis.iter())
        .all(|v| v.is_finite());
    if !finite || axis_norm < 1e-9 {
        return Err(IkError::Unreachable {
            position_mm: target.position_mm.into(),
            axis: target.axis.into(),
            residual_mm: f64::INFINITY,
        });
    }
    let geo = ArmGeometry::of(model)?;
    let limits = model.joint_limits();
    let phi_seed = (seed_deg[1] + seed_deg[2] + seed_deg[3]).to_radians();
    let mut cands: Vec<Vec<f64>> =
        closed_form_candidates(&geo, target, phi_seed, seed_deg[0].to_radians())
            .iter()
            .filter_map(|c| fit_to_limits(c, seed_deg, &limits, CANDIDATE_MARGIN_DEG))
            .collect();
    let dist = |q: &[f64]| {
        q.iter()
            .zip(seed_deg)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
    };
    cands.sort_by(|a, b| dist(a).total_cmp(&dist(b)));
    // the seed itself is a last resort (a calibrated model far from the nominal geometry)
    cands.push(seed_deg.to_vec());
    let mut best = f64::INFINITY;
    for c in cands {
        let (q, rp, rt) = refine(model, target, &c, tilt)?;
        best = best.min(rp);
        let converged = rp < TOL_MM * 10.0 && rt < TOL_AXIS * 1e3;
        if !converged {
            continue;
        }
        // the same pose with every angle in its representation nearest the seed, if inside
        let q_rad: Vec<f64> = q.iter().map(|v| v.to_radians()).collect();
        if let Some(fitted) = fit_to_limits(&q_rad, seed_deg, &limits, LIMIT_SLACK_DEG) {
            return Ok(fitted);
        }
    }
    Err(IkError::Unreachable {
        position_mm: target.position_mm.into(),
        axis: target.axis.into(),
        residual_mm: best,
    })
}
