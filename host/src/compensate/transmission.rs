//! The commands behind the joint angles (`rigctl compensate` with a model file's transmission
//! terms, README "Transmission terms"): the inverse kinematics gives the angles the joints must
//! really take; the commands are the readings that the model's [`JointTerms`] map to them,
//!
//! ```text
//! q_eff_i = q_i + s_i q_i + sum_k c_ik q_k + b_i d_i + g_i tau_i(q)   solved for q (Newton)
//! ```
//!
//! with `d_i` the direction in which joint i's *command* last moved, in the pose order that
//! `fk` and `calibrate` use ([`approach_directions`]: by `t` when every point has one, else file
//! order; the first point has no history). The direction is guessed from the desired motion,
//! checked on the commands and corrected once. A joint with hysteresis that has to reverse by
//! less than its dead band `2 b_i` cannot reach the angle on that point (any reversal moves its
//! angle by more than `2 b_i`): its command is held at the previous one (the closest angle the
//! joint can take, off by less than `2 b_i`) and the point is listed in [`Commands::held`].

use nalgebra::{DMatrix, DVector};

use crate::model::transmission::{JointTerms, APPROACH_MIN_MOVE};
use crate::model::{Model, ModelError};

/// Newton tolerance on the joint angles (deg, mm for a prismatic joint).
const TOLERANCE_DEG: f64 = 1e-10;
/// Newton iterations at most (the map is the identity plus small terms: a few suffice).
const MAX_ITERATIONS: usize = 50;

/// Why no command gives an angle.
#[derive(Debug, thiserror::Error)]
pub enum InvertError {
    /// The model failed at a path point (pose index).
    #[error("path point {} (1-based): {source}", .index + 1)]
    Model {
        index: usize,
        #[source]
        source: ModelError,
    },
    /// The transmission map is singular or the iteration did not converge (pose index).
    #[error(
        "path point {} (1-based): the transmission terms cannot be inverted: {problem}",
        .index + 1
    )]
    NotInvertible { index: usize, problem: String },
}

/// The commands for a sequence of joint angles.
#[derive(Debug, Clone, PartialEq)]
pub struct Commands {
    /// One command vector per point, in the input order (deg; mm for a prismatic joint).
    pub q_deg: Vec<Vec<f64>>,
    /// `(point index, joint index)` (0-based) of the joints held in a hysteresis dead band.
    pub held: Vec<(usize, usize)>,
}

/// The commands whose angles through `model`'s transmission terms are `q_eff` (one vector per
/// point, in file order; `t_s` the points' times when every point has one). Without terms,
/// the angles themselves.
pub fn commands_for(
    model: &Model,
    q_eff: &[Vec<f64>],
    t_s: Option<&[f64]>,
) -> Result<Commands, InvertError> {
    let terms = model.transmission();
    if !terms.is_active() {
        return Ok(Commands {
            q_deg: q_eff.to_vec(),
            held: Vec::new(),
        });
    }
    let n = q_eff.len();
    let mut order: Vec<usize> = (0..n).collect();
    if let Some(t) = t_s.filter(|t| t.len() == n) {
        order.sort_by(|&a, &b| t[a].total_cmp(&t[b]));
    }
    let mut out = Commands {
        q_deg: q_eff.to_vec(),
        held: Vec::new(),
    };
    // State along the pose order: the previous command, its angles and each joint's direction.
    let mut prev: Option<(Vec<f64>, Vec<f64>)> = None;
    let mut dir: Vec<f64> = Vec::new();
    for &k in &order {
        let target = &q_eff[k];
        let nj = target.len();
        dir.resize(nj, 0.0);
        let s = match &prev {
            None => Step {
                q: solve(model, terms, target, &dir, target, &[], k)?,
                d: dir.clone(),
                held: Vec::new(),
            },
            Some((q_prev, eff_prev)) => step(model, terms, target, q_prev, eff_prev, &dir, k)?,
        };
        out.held.extend(s.held.iter().map(|&j| (k, j)));
        dir = s.d;
        prev = Some((s.q.clone(), target.clone()));
        out.q_deg[k] = s.q;
    }
    out.held.sort_unstable();
    Ok(out)
}

/// The command of one point, the directions of approach after it and the held joints.
struct Step {
    q: Vec<f64>,
    d: Vec<f64>,
    held: Vec<usize>,
}

/// One point after the first.
fn step(
    model: &Model,
    terms: &JointTerms,
    target: &[f64],
    q_prev: &[f64],
    eff_prev: &[f64],
    dir_prev: &[f64],
    index: usize,
) -> Result<Step, InvertError> {
    let moved = |a: f64, b: f64, old: f64| match a - b {
        delta if delta.abs() > APPROACH_MIN_MOVE => delta.signum(),
        _ => old,
    };
    let hysteretic = |j: usize| terms.hysteresis_deg.get(j).is_some_and(|b| *b != 0.0);
    // Guess: each joint moves as its angle should.
    let mut d: Vec<f64> = (0..target.len())
        .map(|j| moved(target[j], eff_prev[j], dir_prev[j]))
        .collect();
    let mut q = solve(model, terms, target, &d, q_prev, &[], index)?;
    for round in 0..2 {
        let actual: Vec<f64> = (0..q.len())
            .map(|j| moved(q[j], q_prev[j], dir_prev[j]))
            .collect();
        let wrong: Vec<usize> = (0..q.len())
            .filter(|&j| hysteretic(j) && actual[j] != d[j])
            .collect();
        if wrong.is_empty() {
            return Ok(Step {
                q,
                d,
                held: Vec::new(),
            });
        }
        if round == 0 {
            // Coupled joints may move against their angle: take the commands' directions.
            d = actual;
            q = solve(model, terms, target, &d, &q, &[], index)?;
            continue;
        }
        // Dead band: hold those joints where they were (their direction stays).
        for &j in &wrong {
            d[j] = dir_prev[j];
        }
        let held: Vec<(usize, f64)> = wrong.iter().map(|&j| (j, q_prev[j])).collect();
        q = solve(model, terms, target, &d, &q, &held, index)?;
        return Ok(Step { q, d, held: wrong });
    }
    Ok(Step {
        q,
        d,
        held: Vec::new(),
    })
}

/// Newton on the transmission map with the directions `d` fixed, from `start`; the joints in
/// `held` keep their value and their equations are dropped.
fn solve(
    model: &Model,
    terms: &JointTerms,
    target: &[f64],
    d: &[f64],
    start: &[f64],
    held: &[(usize, f64)],
    index: usize,
) -> Result<Vec<f64>, InvertError> {
    let mut q = start.to_vec();
    for &(j, v) in held {
        if let Some(x) = q.get_mut(j) {
            *x = v;
        }
    }
    let free: Vec<usize> = (0..q.len())
        .filter(|j| !held.iter().any(|(h, _)| h == j))
        .collect();
    let fail = |problem: String| InvertError::NotInvertible { index, problem };
    let model_err = |source| InvertError::Model { index, source };
    for _ in 0..MAX_ITERATIONS {
        let eff = terms.effective_joints(model, &q, d).map_err(model_err)?;
        let r = DVector::from_iterator(free.len(), free.iter().map(|&j| eff[j] - target[j]));
        if r.amax() < TOLERANCE_DEG {
            return Ok(q);
        }
        let jac = terms.joint_map_jacobian(model, &q).map_err(model_err)?;
        let sub = DMatrix::from_fn(free.len(), free.len(), |a, b| jac[(free[a], free[b])]);
        let dx = sub
            .lu()
            .solve(&r)
            .ok_or_else(|| fail("the map from commands to angles is singular".into()))?;
        for (a, &j) in free.iter().enumerate() {
            q[j] -= dx[a];
        }
        if q.iter().any(|v| !v.is_finite()) {
            return Err(fail("the iteration diverged".into()));
        }
    }
    Err(fail(format!(
        "no convergence to {TOLERANCE_DEG:e} deg in {MAX_ITERATIONS} iterations"
    )))
}
