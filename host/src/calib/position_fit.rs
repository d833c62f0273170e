//! The identification of model parameters on full positions ([`fit_parameters`]): the
//! analysis at the start, the solve on the tall Jacobian or on normal equations accumulated per
//! pose, the rank analysed again at the solution, and what the fit does not determine kept at
//! its input. That loop ([`refine`]) is written once for every [`Identification`]: the fit on
//! full positions ([`PositionFit`]) and the fit over a tree ([`super::tree_fit`]).

use super::accumulate::{normal_equations_with, JointTrig, PositionNormalProblem};
use super::error::CalibError;
use super::fit::{fit_at_normal, fit_problem, split_selection, Fit, PriorAt};
use super::identifiability::analyse;
use super::lm::LmConfig;
use super::measured::PosePoints;
use super::normal::{solve_normal, solve_normal_from, use_normal_equations};
use super::problem::{param_vector, position_problem, stacked_jacobian, Unknowns};
use crate::model::Model;

/// Most refits of [`fit_parameters`] when the rank grows at the solution.
const MAX_RANK_REFITS: usize = 3;

/// Identifies the parameters `selection` (model indices; put the ones you would rather fit
/// first) of `start` from `poses`, with or without the declared tilting: [`refine`] on a
/// [`PositionFit`] (the rank analysed again at the solution).
///
/// With `prior`, a prior toward the values of `prior.center` ([`super::prior`]); `None`, or a
/// weight of 0, is the plain fit.
pub fn fit_parameters(
    start: &Model,
    poses: &PosePoints,
    selection: &[usize],
    tilt: bool,
    lm: &LmConfig,
    rtol: f64,
    prior: Option<PriorAt<'_>>,
) -> Result<Fit, CalibError> {
    let on = PositionFit {
        poses,
        selection,
        tilt,
        lm,
        rtol,
        prior: prior.filter(|p| p.weight > 0.0),
    };
    if poses.is_empty() {
        return Err(CalibError::NoPoses);
    }
    refine(&on, start)
}

/// An identification that [`refine`] runs: one analysis-and-solve from any start on any part
/// of its selection, the rank of its whole selection anywhere, and the values of its unknowns
/// (indices, in the selection's preference order). The fit of a model's parameters on full
/// positions ([`PositionFit`]) and the fit over a tree ([`super::tree_fit`]) are two.
pub trait Identification {
    /// The state whose values the unknowns are.
    type State: Clone;
    /// The selected unknowns, in preference order.
    fn selection(&self) -> &[usize];
    /// One identification of `selection` (part of [`Self::selection`], same order) from
    /// `start`: the identifiability analysis there ([`super::fit::Split`]), then the solve.
    fn once(
        &self,
        start: &Self::State,
        selection: &[usize],
    ) -> Result<Fit<Self::State, usize>, CalibError>;
    /// The rank of the whole selection's Jacobian at `state`.
    fn rank_at(&self, state: &Self::State) -> Result<usize, CalibError>;
    /// The value of unknown `u` in `state` (NaN when it has none).
    fn value(&self, state: &Self::State, u: usize) -> f64;
    /// Sets unknown `u` of `state` to `v`.
    fn set_value(&self, state: &mut Self::State, u: usize, v: f64) -> Result<(), CalibError>;
}

/// The identification `on` from `start`, its rank analysed again at the solution.
///
/// The identifiability analysis is that of the Jacobian at the start; a nominal model with
/// exact right angles can hide directions that the fitted model shows (the rank at the solution
/// is larger). The analysis is then repeated at the solution and the fit goes on from there with
/// the larger set (at most [`MAX_RANK_REFITS`] times), so that a second run from the result
/// cannot improve on it; the iterations add up. What the fit does not determine is then kept at
/// its input ([`keep_what_is_not_determined`]).
pub fn refine<I: Identification>(
    on: &I,
    start: &I::State,
) -> Result<Fit<I::State, usize>, CalibError> {
    let mut fit = on.once(start, on.selection())?;
    for _ in 0..MAX_RANK_REFITS {
        if on.rank_at(&fit.model)? <= fit.rank {
            break;
        }
        let next = on.once(&fit.model, on.selection())?;
        fit = Fit {
            iterations: fit.iterations + next.iterations,
            converged: fit.converged && next.converged,
            ..next
        };
    }
    keep_what_is_not_determined(start, fit, on)
}

/// What a fit does not determine keeps its input value: an unknown fixed by a later analysis
/// than the one that first moved it is put back to its value in `start`, and where a fitted
/// unknown's sigma is infinite at the solution (a direction the start did not show as null)
/// the analysis there fixes the ones that direction needs (the later in preference order);
/// the others are refitted from there, until nothing moves.
fn keep_what_is_not_determined<I: Identification>(
    start: &I::State,
    mut fit: Fit<I::State, usize>,
    on: &I,
) -> Result<Fit<I::State, usize>, CalibError> {
    for _ in 0..MAX_RANK_REFITS {
        let undetermined = fit.sigma.iter().any(|s| !s.is_finite());
        let moved: Vec<usize> = fit
            .fixed
            .iter()
            .copied()
            .filter(|&p| on.value(&fit.model, p) != on.value(start, p))
            .collect();
        if !undetermined && moved.is_empty() {
            break;
        }
        let mut from = fit.model.clone();
        for &p in &moved {
            on.set_value(&mut from, p, on.value(start, p))?;
        }
        // the fitted ones in preference order, analysed again where the fit stands
        let keep: Vec<usize> = on
            .selection()
            .iter()
            .copied()
            .filter(|p| fit.fitted.contains(p))
            .collect();
        let next = match on.once(&from, &keep) {
            Ok(next) => next,
            Err(CalibError::NothingToFit) => break,
            Err(e) => return Err(e),
        };
        let mut fixed: Vec<usize> = fit.fixed.clone();
        fixed.extend(&next.fixed);
        fixed.sort_by_key(|p| on.selection().iter().position(|s| s == p));
        fixed.dedup();
        let mut unidentifiable = fit.unidentifiable.clone();
        unidentifiable.extend(next.unidentifiable.iter().cloned());
        fit = Fit {
            fixed,
            unidentifiable,
            iterations: fit.iterations + next.iterations,
            converged: fit.converged && next.converged,
            ..next
        };
    }
    Ok(fit)
}

/// An identification of model parameters on full positions: the poses, the selected parameters
/// (model indices, preference order), the declared tilting on or off, the solver's settings and
/// the identifiability threshold `rtol` (which also picks the normal equations,
/// [`use_normal_equations`]).
#[derive(Debug, Clone, Copy)]
pub struct PositionFit<'a> {
    pub poses: &'a PosePoints,
    pub selection: &'a [usize],
    pub tilt: bool,
    pub lm: &'a LmConfig,
    pub rtol: f64,
    /// A prior on the fitted parameters (solved on the tall Jacobian: ill-posed sets are small).
    pub prior: Option<PriorAt<'a>>,
}

impl Identification for PositionFit<'_> {
    type State = Model;

    fn selection(&self) -> &[usize] {
        self.selection
    }

    fn once(&self, start: &Model, selection: &[usize]) -> Result<Fit, CalibError> {
        let on = PositionFit { selection, ..*self };
        if use_normal_equations(on.rtol) && on.prior.is_none() {
            return fit_parameters_normal(start, &on);
        }
        let (poses, tilt) = (on.poses, on.tilt);
        let jac0 = stacked_jacobian(start, poses, on.selection, tilt)?;
        let make = |cols| position_problem(start, poses, cols, tilt);
        fit_problem(
            start,
            on.selection,
            &jac0,
            make,
            on.lm,
            on.rtol,
            on.prior.as_ref(),
        )
    }

    fn rank_at(&self, model: &Model) -> Result<usize, CalibError> {
        let (poses, selection, tilt, rtol) = (self.poses, self.selection, self.tilt, self.rtol);
        Ok(if use_normal_equations(rtol) {
            let eq = normal_equations_with(model, poses, None, selection, tilt)?;
            analyse(&eq.jacobian_root(), rtol).rank
        } else {
            analyse(&stacked_jacobian(model, poses, selection, tilt)?, rtol).rank
        })
    }

    fn value(&self, model: &Model, p: usize) -> f64 {
        model.params().get(p).map_or(f64::NAN, |x| x.value)
    }

    fn set_value(&self, model: &mut Model, p: usize, v: f64) -> Result<(), CalibError> {
        Ok(model.set_param_at(p, v)?)
    }
}

/// [`fit_parameters`] on normal equations accumulated per pose (bounded memory, see
/// [`super::normal`]), whatever `on.rtol`: the identifiability analysis and the sigmas work on
/// the square root of `J^T J`, which has the tall Jacobian's column norms and singular values.
pub fn fit_parameters_normal(start: &Model, on: &PositionFit<'_>) -> Result<Fit, CalibError> {
    let (poses, selection, tilt, lm, rtol) = (on.poses, on.selection, on.tilt, on.lm, on.rtol);
    if poses.is_empty() {
        return Err(CalibError::NoPoses);
    }
    let trig = JointTrig::new(poses);
    let full = normal_equations_with(start, poses, Some(&trig), selection, tilt)?;
    let split = split_selection(start, selection, &full.jacobian_root(), rtol)?;
    let x0 = param_vector(start, &split.fitted);
    // The fitted unknowns' equations at the start are part of the ones just analysed.
    let kept: Vec<usize> = split
        .fitted
        .iter()
        .filter_map(|c| selection.iter().position(|s| s == c))
        .collect();
    let mut problem =
        PositionNormalProblem::with_trig(start, poses, trig, split.fitted.clone(), tilt);
    let rep = if kept.len() == split.fitted.len() {
        solve_normal_from(&mut problem, x0, full.select(&kept), lm)
    } else {
        solve_normal(&mut problem, x0, lm)
    }
    .map_err(CalibError::from_lm)?;
    Ok(fit_at_normal(split, problem.into_unknowns(), &rep, rtol)?.map_model(Unknowns::into_model))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    /// Exact poses of a model with two joint-offset errors: the fit recovers them, and a start
    /// Jacobian that does not match the selection is an error, not a panic.
    #[test]
    fn position_fit_recovers_offsets() {
        let nominal = crate::model::katana450(200.0).unwrap();
        let mut truth = nominal.clone();
        truth.set_param("dth2", 0.04).unwrap();
        truth.set_param("dth4", -0.02).unwrap();
        let mut poses = PosePoints::default();
        for k in 0..12 {
            let k = f64::from(k);
            let q = vec![
                -60.0 + 10.0 * k,
                40.0 + 5.0 * k,
                -70.0 + 3.0 * k,
                20.0 - 4.0 * k,
                90.0,
            ];
            poses
                .xyz_mm
                .push(truth.position_mm(&q, crate::model::Tilt::Off).unwrap());
            poses.q_deg.push(q);
        }
        let cols = ["dth2", "dth4"].map(|n| nominal.param_index(n).unwrap());
        let lm = LmConfig::default();
        let fit = fit_parameters(&nominal, &poses, &cols, false, &lm, 1e-4, None).unwrap();
        assert_eq!(fit.fitted, cols);
        assert!((fit.model.param("dth2").unwrap() - 0.04).abs() < 1e-9);
        assert!((fit.model.param("dth4").unwrap() + 0.02).abs() < 1e-9);
        assert!(fit.converged && fit.rank == 2);
        let wrong = DMatrix::zeros(3 * poses.len(), 1);
        let make = |c| position_problem(&nominal, &poses, c, false);
        let res = fit_problem(&nominal, &cols, &wrong, make, &lm, 1e-4, None);
        assert!(matches!(res, Err(CalibError::Solver(_))), "{res:?}");
    }
}
