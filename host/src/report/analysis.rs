//! Numbers the report recomputes from pose files and models: per-pose errors, the influence of
//! each parameter (thesis fig. 3.8), joint moments and tilts along a trajectory (fig. 5.8-5.10)
//! and the error along a path (fig. 5.12).

use nalgebra::Vector3;

use crate::calib::{position_errors, MeasuredSet};
use crate::model::dynamics::{moments_kgfm, Inertia};
use crate::model::{Model, ModelError, ParamKind, Tilt, Unit};
use crate::sim::paths::{quintic_profile, Circle, Line, Path};
use crate::sim::trajectory::{joint_trajectory, positions_in_motion, JointTrajectory};

/// Parameter step of thesis fig. 3.8 for angles (deg).
pub const INFLUENCE_STEP_DEG: f64 = 0.05;
/// Parameter step of thesis fig. 3.8 for lengths (mm).
pub const INFLUENCE_STEP_MM: f64 = 0.1;

/// A model evaluated on a pose set, with the tilt mode that fits it best.
#[derive(Debug, Clone)]
pub struct Evaluated {
    /// Column heading.
    pub label: String,
    /// Whether static tilting was applied.
    pub tilt: bool,
    /// Error vectors (measured - model), mm.
    pub errors_mm: Vec<Vector3<f64>>,
}

/// Evaluates `model` on `poses`; with `tilt = None` both without and (if the model has tilting
/// data) with static tilting are tried and the one with the lower mean error is kept, since a
/// model file does not record which mode it was identified in.
pub fn evaluate(
    label: &str,
    model: &Model,
    set: &MeasuredSet,
    tilt: Option<bool>,
) -> Result<Evaluated, ModelError> {
    let modes: Vec<bool> = match tilt {
        Some(t) => vec![t],
        None if model.has_tilt() => vec![false, true],
        None => vec![false],
    };
    let mut best: Option<(f64, bool, Vec<Vector3<f64>>)> = None;
    for t in modes {
        let e = position_errors(model, &set.poses, t)?;
        let mean = e.iter().map(|v| v.norm()).sum::<f64>() / e.len().max(1) as f64;
        if best.as_ref().is_none_or(|(m, _, _)| mean < *m) {
            best = Some((mean, t, e));
        }
    }
    let (_, tilt, errors_mm) = best.unwrap_or((0.0, false, Vec::new()));
    Ok(Evaluated {
        label: label.to_string(),
        tilt,
        errors_mm,
    })
}

/// [`evaluate`] with `model`'s transmission terms (model file `[[joint]]` keys) applied to the
/// readings first, as `fk` and `calibrate` do: the directions of approach of the hysteresis
/// terms from the pose order (`t_s` when every pose has a time, else file order).
pub fn evaluate_in_order(
    label: &str,
    model: &Model,
    set: &MeasuredSet,
    tilt: Option<bool>,
) -> Result<Evaluated, ModelError> {
    if !model.transmission().is_active() {
        return evaluate(label, model, set, tilt);
    }
    let mut mapped = set.clone();
    mapped.poses.q_deg = model.effective_pose_joints(&set.poses.q_deg, set.t_s.as_deref())?;
    evaluate(label, model, &mapped, tilt)
}

/// How much one parameter's small step moves the tool point at each pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Influence {
    /// Parameter name.
    pub name: String,
    /// Step applied (deg or mm, see `unit`).
    pub step: f64,
    /// Unit of the step.
    pub unit: Unit,
    /// `|dP|` at every pose (mm).
    pub dp_mm: Vec<f64>,
}

/// Thesis fig. 3.8: `|dP| = |J_p * step|` at every pose `q_deg` for each parameter named in
/// `names` that the model has, with step [`INFLUENCE_STEP_DEG`] for angles and
/// [`INFLUENCE_STEP_MM`] for lengths (other units are skipped), from the analytic parameter
/// Jacobian of the rigid model (no tilting).
pub fn parameter_influence(
    model: &Model,
    q_deg: &[Vec<f64>],
    names: &[&str],
) -> Result<Vec<Influence>, ModelError> {
    let cols: Vec<(usize, f64, Unit)> = names
        .iter()
        .filter_map(|n| model.param_index(n))
        .filter_map(|i| match model.params()[i].unit {
            Unit::Deg => Some((i, INFLUENCE_STEP_DEG, Unit::Deg)),
            Unit::Mm => Some((i, INFLUENCE_STEP_MM, Unit::Mm)),
            _ => None,
        })
        .collect();
    let idx: Vec<usize> = cols.iter().map(|c| c.0).collect();
    let mut out: Vec<Influence> = cols
        .iter()
        .map(|&(i, step, unit)| Influence {
            name: model.params()[i].name.clone(),
            step,
            unit,
            dp_mm: Vec::with_capacity(q_deg.len()),
        })
        .collect();
    for q in q_deg {
        let (_, jac) = model.param_jacobian(q, Tilt::Off, &idx)?;
        for (k, inf) in out.iter_mut().enumerate() {
            inf.dp_mm.push((jac.column(k) * inf.step).norm());
        }
    }
    Ok(out)
}

/// The parameters whose influence the report plots: `preferred` (e.g. the identified ones)
/// when the model has any of them, else the model's joint offsets, twists and lengths.
pub fn influence_names<'a>(model: &'a Model, preferred: &'a [String]) -> Vec<&'a str> {
    let have: Vec<&str> = preferred
        .iter()
        .map(String::as_str)
        .filter(|n| model.param_index(n).is_some())
        .collect();
    if !have.is_empty() {
        return have;
    }
    [ParamKind::JointOffset, ParamKind::Twist, ParamKind::Length]
        .iter()
        .flat_map(|k| model.params_of_kind(*k))
        .map(|i| model.params()[i].name.as_str())
        .collect()
}

/// A demonstration trajectory: the thesis's circle (section 5.5.1) if the model reaches it,
/// else a 160 mm straight line in front of the robot; quintic rest-to-rest timing.
#[derive(Debug, Clone)]
pub struct DemoPath {
    /// Name of the path.
    pub name: &'static str,
    /// Duration (s).
    pub duration_s: f64,
    /// Number of samples.
    pub samples: usize,
}

const CIRCLE: DemoPath = DemoPath {
    name: "thesis circle (r = 100 mm, 45-degree plane), 6 s",
    duration_s: 6.0,
    samples: 121,
};
const LINE: DemoPath = DemoPath {
    name: "straight line x = -80..80 mm at y = -300, z = 139.3 mm, 4 s",
    duration_s: 4.0,
    samples: 81,
};
const IK_SEED_DEG: [f64; 5] = [-90.0, 60.0, -60.0, 0.0, 90.0];

fn path_of(p: &DemoPath) -> Box<dyn Path> {
    if p.name == CIRCLE.name {
        Box::new(Circle::thesis(Vector3::zeros()))
    } else {
        Box::new(Line {
            start_mm: Vector3::new(-80.0, -300.0, 139.29),
            end_mm: Vector3::new(80.0, -300.0, 139.29),
            tool_axis: -Vector3::z(),
        })
    }
}

/// Plans the demonstration trajectory with `model`'s rigid IK (as a controller would): the
/// circle, else the line; `None` when the model is not a 5-joint arm or neither is reachable.
pub fn demo_trajectory(model: &Model) -> Option<(DemoPath, JointTrajectory)> {
    if model.n_joints() != IK_SEED_DEG.len() {
        return None;
    }
    [CIRCLE, LINE].into_iter().find_map(|p| {
        let path = path_of(&p);
        joint_trajectory(model, path.as_ref(), p.duration_s, p.samples, &IK_SEED_DEG)
            .ok()
            .map(|t| (p, t))
    })
}

/// Joint moments (RNEA, slender-rod links) and the tilts they cause, per sample: `(moments,
/// tilts)`, each `[sample][joint]` (kgf.m, deg; joint frame i).
pub type MomentsTilts = (Vec<Vec<Vector3<f64>>>, Vec<Vec<Vector3<f64>>>);

/// Moments and tilts of `model` along `traj` (thesis fig. 5.8-5.10).
pub fn moments_and_tilts(
    model: &Model,
    traj: &JointTrajectory,
) -> Result<MomentsTilts, ModelError> {
    let mut moments = Vec::with_capacity(traj.t_s.len());
    let mut tilts = Vec::with_capacity(traj.t_s.len());
    for k in 0..traj.t_s.len() {
        let m = moments_kgfm(
            model,
            &traj.q_deg[k],
            &traj.qd_deg_s[k],
            &traj.qdd_deg_s2[k],
            Inertia::SlenderRod,
        )?;
        tilts.push(model.tilts_deg(&m)?);
        moments.push(m);
    }
    Ok((moments, tilts))
}

/// Thesis fig. 5.12: the controller plans `path` with `planner`'s rigid IK; the robot (`truth`,
/// tilting from the dynamic moments) follows; returns `(s, |actual - target|)` per sample (mm).
pub fn path_error(planner: &Model, truth: &Model, demo: &DemoPath) -> Option<(Vec<f64>, Vec<f64>)> {
    let path = path_of(demo);
    let traj = joint_trajectory(
        planner,
        path.as_ref(),
        demo.duration_s,
        demo.samples,
        &IK_SEED_DEG,
    )
    .ok()?;
    let actual = positions_in_motion(truth, &traj, Inertia::SlenderRod).ok()?;
    let s: Vec<f64> = traj
        .t_s
        .iter()
        .map(|&t| quintic_profile(t, demo.duration_s).0)
        .collect();
    let err = s
        .iter()
        .zip(&actual)
        .map(|(&s, a)| (a - path.at(s).position_mm).norm())
        .collect();
    Some((s, err))
}

/// Index of the joint whose reading correlates most (absolute Pearson) with `values` over the
/// poses, and that correlation; `None` for fewer than 3 poses or constant data.
pub fn most_correlated_joint(q_deg: &[Vec<f64>], values: &[f64]) -> Option<(usize, f64)> {
    let n = values.len();
    if n < 3 || q_deg.len() != n {
        return None;
    }
    let nj = q_deg[0].len();
    let corr = |x: &dyn Fn(usize) -> f64| {
        let mx = (0..n).map(x).sum::<f64>() / n as f64;
        let my = values.iter().sum::<f64>() / n as f64;
        let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
        for (k, y) in values.iter().enumerate() {
            let (dx, dy) = (x(k) - mx, y - my);
            sxy += dx * dy;
            sxx += dx * dx;
            syy += dy * dy;
        }
        (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
    };
    (0..nj)
        .filter_map(|j| corr(&|k| q_deg[k].get(j).copied().unwrap_or(0.0)).map(|c| (j, c)))
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::katana450;

    #[test]
    fn influence_matches_finite_differences_of_the_fk() {
        let model = katana450(200.0).unwrap();
        let q = vec![
            vec![-90.0, 60.0, -60.0, 10.0, 90.0],
            vec![0.0, 100.0, -80.0, 30.0, 0.0],
        ];
        let inf = parameter_influence(&model, &q, &["dth2", "a3", "payload_kg"]).unwrap();
        assert_eq!(inf.len(), 2, "payload (kg) has no fig. 3.8 step");
        for i in &inf {
            for (k, qk) in q.iter().enumerate() {
                let mut m = model.clone();
                let v = m.param(&i.name).unwrap();
                m.set_param(&i.name, v + i.step).unwrap();
                let d = (m.position_mm(qk, Tilt::Off).unwrap()
                    - model.position_mm(qk, Tilt::Off).unwrap())
                .norm();
                assert!(
                    (d - i.dp_mm[k]).abs() < 1e-3 * d.max(1e-3),
                    "{} pose {k}: {d} vs {}",
                    i.name,
                    i.dp_mm[k]
                );
            }
        }
        // a3 is a length: a 0.1 mm step moves the tool by at most 0.1 mm
        assert!(inf[1].dp_mm.iter().all(|d| *d <= 0.1 + 1e-9));
    }

    #[test]
    fn correlation_finds_the_driving_joint() {
        let q: Vec<Vec<f64>> = (0..10)
            .map(|k| vec![(k * 7 % 5) as f64, k as f64])
            .collect();
        let v: Vec<f64> = (0..10).map(|k| 2.0 * k as f64 + 1.0).collect();
        let (j, c) = most_correlated_joint(&q, &v).unwrap();
        assert_eq!(j, 1);
        assert!((c - 1.0).abs() < 1e-12);
    }
}
