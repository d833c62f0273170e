//! Joint trajectories along paths (IK at every sample, quintic time profile) and tool positions
//! in motion; the moments in motion come from [`crate::model::dynamics`].

use nalgebra::Vector3;

use super::paths::{quintic_profile, Path};
use crate::model::dynamics::{moments_kgfm, Inertia};
use crate::model::ik::{solve, IkError, IkTilt};
use crate::model::{Model, ModelError, Tilt};

/// A sampled joint trajectory: uniform time steps.
#[derive(Debug, Clone, PartialEq)]
pub struct JointTrajectory {
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// Joint readings, deg.
    pub q_deg: Vec<Vec<f64>>,
    /// Joint rates, deg/s.
    pub qd_deg_s: Vec<Vec<f64>>,
    /// Joint accelerations, deg/s^2.
    pub qdd_deg_s2: Vec<Vec<f64>>,
}

/// Step of the path parameter for the numerical path derivatives `dq/ds`, `d2q/ds2`.
const PATH_STEP: f64 = 1e-3;

/// Samples `path` over `duration_s` with the quintic rest-to-rest profile at `samples` instants
/// (>= 2), solving the IK of `model` (rigid, as the controller would) at each, seeded by the
/// previous solution (the first by `seed_deg`). Rates by the chain rule with the analytic
/// profile: `qd = q'(s) s'`, `qdd = q''(s) s'^2 + q'(s) s''`, where `q'` and `q''` are central
/// differences of the IK in the path parameter (step 1e-3; the path is evaluated slightly
/// beyond 0..1 at the ends). So the rates are exactly zero at both ends (the arm at rest).
pub fn joint_trajectory(
    model: &Model,
    path: &dyn Path,
    duration_s: f64,
    samples: usize,
    seed_deg: &[f64],
) -> Result<JointTrajectory, IkError> {
    let n = samples.max(2);
    let dt = duration_s / (n - 1) as f64;
    let mut seed = seed_deg.to_vec();
    let mut traj = JointTrajectory {
        t_s: Vec::new(),
        q_deg: Vec::new(),
        qd_deg_s: Vec::new(),
        qdd_deg_s2: Vec::new(),
    };
    for k in 0..n {
        let t = k as f64 * dt;
        let (s, ds, dds) = quintic_profile(t, duration_s);
        let q = solve(model, &path.at(s), &seed, IkTilt::Off)?;
        let qm = solve(model, &path.at(s - PATH_STEP), &q, IkTilt::Off)?;
        let qp = solve(model, &path.at(s + PATH_STEP), &q, IkTilt::Off)?;
        let h = PATH_STEP;
        let (mut qd, mut qdd) = (Vec::with_capacity(q.len()), Vec::with_capacity(q.len()));
        for j in 0..q.len() {
            let d1 = (qp[j] - qm[j]) / (2.0 * h);
            let d2 = (qp[j] - 2.0 * q[j] + qm[j]) / (h * h);
            qd.push(d1 * ds);
            qdd.push(d2 * ds * ds + d1 * dds);
        }
        seed = q.clone();
        traj.t_s.push(t);
        traj.q_deg.push(q);
        traj.qd_deg_s.push(qd);
        traj.qdd_deg_s2.push(qdd);
    }
    Ok(traj)
}

/// Tool positions (mm, R) of `model` along `traj` with joint tilting from the dynamic moments
/// (RNEA, `inertia`), i.e. the thesis's "robot in motion" (section 5.4).
pub fn positions_in_motion(
    model: &Model,
    traj: &JointTrajectory,
    inertia: Inertia,
) -> Result<Vec<Vector3<f64>>, ModelError> {
    (0..traj.t_s.len())
        .map(|k| {
            let m = moments_kgfm(
                model,
                &traj.q_deg[k],
                &traj.qd_deg_s[k],
                &traj.qdd_deg_s2[k],
                inertia,
            )?;
            model.position_mm(&traj.q_deg[k], Tilt::Moments(&m))
        })
        .collect()
}
