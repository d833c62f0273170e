//! Least-squares identification of a parameter subset: identifiability analysis at the start
//! point, Levenberg-Marquardt on the identifiable parameters, covariance at the solution.

use nalgebra::{DMatrix, DVector};

use super::accumulate::{normal_equations_with, JointTrig, PositionNormalProblem};
use super::error::CalibError;
use super::identifiability::{analyse, scaled_svd, Identifiability};
use super::lm::{solve, LmConfig, Problem};
use super::normal::{solve_normal, solve_normal_from, use_normal_equations, NormalReport};
use super::prior::{Prior, PriorScales, WithPrior};
use super::problem::{
    param_vector, position_problem, stacked_jacobian, ModelProblem, Poses, Rows, SetUnknowns,
    Unknowns,
};
use crate::model::Model;

/// Result of every identification: [`fit_parameters`] and [`fit_problem`] (a [`Model`] and its
/// parameters by model index), [`super::general::fit_general`] (the state with point offsets and
/// [`super::unknown::Unknown`]s), `diagnose`'s extended fit
/// ([`crate::diagnose::extended::fit`]: the one state [`super::state::ExtModel`] and its `Unknown`s).
#[derive(Debug, Clone)]
pub struct Fit<M = Model, U = usize> {
    /// The model with the fitted values.
    pub model: M,
    /// Fitted unknowns.
    pub fitted: Vec<U>,
    /// Selected unknowns kept at their start value because they are not identifiable.
    pub fixed: Vec<U>,
    /// Names of the unidentifiable unknowns or combinations (`"be5"`, `"dth5+be4"`).
    pub unidentifiable: Vec<String>,
    /// One standard deviation of each fitted unknown (its unit), same order as `fitted`:
    /// `sqrt(diag(s^2 (J^T J)^-1))`, `s^2 = |r|^2 / (m - n)`.
    pub sigma: Vec<f64>,
    /// Condition number of the column-scaled Jacobian of the fitted unknowns at the solution.
    pub condition_number: f64,
    /// Rank of the Jacobian over all selected unknowns.
    pub rank: usize,
    /// Solver iterations.
    pub iterations: usize,
    /// Whether the solver converged (not stopped by the iteration cap).
    pub converged: bool,
    /// Residual sum of squares at the solution, over every measured component (mm^2).
    pub rss_mm2: f64,
    /// Number of residuals (measured components: 3 per full position).
    pub n_residuals: usize,
}

impl<M, U: PartialEq> Fit<M, U> {
    /// One standard deviation of `u` (infinite when it was not fitted).
    pub fn sigma_of(&self, u: U) -> f64 {
        self.fitted
            .iter()
            .position(|f| *f == u)
            .map_or(f64::INFINITY, |i| self.sigma[i])
    }
}

impl<M, U> Fit<M, U> {
    /// A fit that frees nothing: `model` as it is, with the residual sum of squares `rss_mm2`
    /// of its `n_residuals` residuals; the split's unknowns all kept.
    pub fn unfitted(model: M, split: Split<U>, rss_mm2: f64, n_residuals: usize) -> Self {
        Fit {
            model,
            fitted: split.fitted,
            fixed: split.fixed,
            unidentifiable: split.unidentifiable,
            sigma: Vec::new(),
            condition_number: 1.0,
            rank: split.rank,
            iterations: 0,
            converged: true,
            rss_mm2,
            n_residuals,
        }
    }

    /// The same fit with the model `f(model)`.
    pub fn map_model<N>(self, f: impl FnOnce(M) -> N) -> Fit<N, U> {
        self.map(f, |u| u)
    }

    /// The same fit with every unknown `f(u)`.
    pub fn map_unknowns<V>(self, f: impl Fn(U) -> V) -> Fit<M, V> {
        self.map(|m| m, f)
    }

    /// The same fit with the model `model(m)` and every unknown `unknown(u)`.
    pub fn map<N, V>(self, model: impl FnOnce(M) -> N, unknown: impl Fn(U) -> V) -> Fit<N, V> {
        Fit {
            model: model(self.model),
            fitted: self.fitted.into_iter().map(&unknown).collect(),
            fixed: self.fixed.into_iter().map(&unknown).collect(),
            unidentifiable: self.unidentifiable,
            sigma: self.sigma,
            condition_number: self.condition_number,
            rank: self.rank,
            iterations: self.iterations,
            converged: self.converged,
            rss_mm2: self.rss_mm2,
            n_residuals: self.n_residuals,
        }
    }
}

/// Standard deviations `sqrt(diag(s^2 (J^T J)^-1))` with `s^2 = |r|^2 / (m - n)`, through the
/// SVD of the column-scaled Jacobian (directions below `rtol * s_max` count as infinite).
pub fn parameter_sigmas(jac: &DMatrix<f64>, residual_norm_sq: f64, rtol: f64) -> Vec<f64> {
    parameter_sigmas_m(jac, jac.nrows(), residual_norm_sq, rtol)
}

/// [`parameter_sigmas`] for a Jacobian given by any matrix with the same `J^T J` (e.g. the
/// square root of the normal matrix, [`super::normal::Normal::jacobian_root`]) and `m`
/// residuals.
pub fn parameter_sigmas_m(
    jac: &DMatrix<f64>,
    m: usize,
    residual_norm_sq: f64,
    rtol: f64,
) -> Vec<f64> {
    let n = jac.ncols();
    if n == 0 {
        return Vec::new();
    }
    let dof = m.saturating_sub(n).max(1) as f64;
    let s2 = residual_norm_sq / dof;
    let (norms, s, v) = scaled_svd(jac);
    let cut = rtol * s.first().copied().unwrap_or(0.0);
    (0..n)
        .map(|i| {
            let mut var = 0.0;
            for (k, &sk) in s.iter().enumerate() {
                let vik = v[(i, k)];
                if sk > cut && sk > 0.0 {
                    var += (vik / sk).powi(2);
                } else if vik.abs() > 1e-9 {
                    return f64::INFINITY;
                }
            }
            (s2 * var).sqrt() / norms[i]
        })
        .collect()
}

/// Most refits of [`fit_parameters`] when the rank grows at the solution.
const MAX_RANK_REFITS: usize = 3;

/// Identifies the parameters `selection` (model indices; put the ones you would rather fit
/// first) of `start` from `poses`, with or without the declared tilting.
///
/// The identifiability analysis is that of the Jacobian at the start; a nominal model with
/// exact right angles can hide directions that the fitted model shows (the rank at the solution
/// is larger). The analysis is then repeated at the solution and the fit goes on from there with
/// the larger set (at most [`MAX_RANK_REFITS`] times), so that a second run from the result
/// cannot improve on it; the iterations add up.
pub fn fit_parameters(
    start: &Model,
    poses: &Poses,
    selection: &[usize],
    tilt: bool,
    lm: &LmConfig,
    rtol: f64,
) -> Result<Fit, CalibError> {
    fit_parameters_with(start, poses, selection, tilt, lm, rtol, None)
}

/// [`fit_parameters`] with a prior toward the values of `prior.center` ([`super::prior`]);
/// `None`, or a weight of 0, is the plain fit.
pub fn fit_parameters_with(
    start: &Model,
    poses: &Poses,
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
    let mut fit = on.once(start)?;
    for _ in 0..MAX_RANK_REFITS {
        if on.rank_at(&fit.model)? <= fit.rank {
            break;
        }
        let next = on.once(&fit.model)?;
        fit = Fit {
            iterations: fit.iterations + next.iterations,
            converged: fit.converged && next.converged,
            ..next
        };
    }
    keep_what_is_not_determined(start, fit, &on)
}

/// What a fit does not determine keeps its input value: a parameter fixed by a later analysis
/// than the one that first moved it is put back to its value in `start`, and where a fitted
/// parameter's sigma is infinite at the solution (a direction the start did not show as null)
/// the analysis there fixes the ones that direction needs (the later in preference order);
/// the others are refitted from there, until nothing moves.
fn keep_what_is_not_determined(
    start: &Model,
    mut fit: Fit,
    on: &PositionFit<'_>,
) -> Result<Fit, CalibError> {
    for _ in 0..MAX_RANK_REFITS {
        let undetermined = fit.sigma.iter().any(|s| !s.is_finite());
        let moved: Vec<usize> = fit
            .fixed
            .iter()
            .copied()
            .filter(|&p| fit.model.params()[p].value != start.params()[p].value)
            .collect();
        if !undetermined && moved.is_empty() {
            break;
        }
        let mut from = fit.model.clone();
        for &p in &moved {
            from.set_param_at(p, start.params()[p].value)?;
        }
        // the fitted ones in preference order, analysed again where the fit stands
        let keep: Vec<usize> = on
            .selection
            .iter()
            .copied()
            .filter(|p| fit.fitted.contains(p))
            .collect();
        let next = match (PositionFit {
            selection: &keep,
            ..*on
        })
        .once(&from)
        {
            Ok(next) => next,
            Err(CalibError::NothingToFit) => break,
            Err(e) => return Err(e),
        };
        let mut fixed: Vec<usize> = fit.fixed.clone();
        fixed.extend(&next.fixed);
        fixed.sort_by_key(|p| on.selection.iter().position(|s| s == p));
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
    pub poses: &'a Poses,
    pub selection: &'a [usize],
    pub tilt: bool,
    pub lm: &'a LmConfig,
    pub rtol: f64,
    /// A prior on the fitted parameters (solved on the tall Jacobian: ill-posed sets are small).
    pub prior: Option<PriorAt<'a>>,
}

/// A prior of an identification: its weight, the scales per kind, and the model whose values
/// are the prior's centre (the input model, whatever point a refit starts from).
#[derive(Debug, Clone, Copy)]
pub struct PriorAt<'a> {
    pub weight: f64,
    pub scales: &'a PriorScales,
    pub center: &'a Model,
}

impl PriorAt<'_> {
    /// The prior on the fitted parameters `fitted` (model indices).
    pub fn on(&self, fitted: &[usize]) -> Prior {
        Prior {
            weight: self.weight,
            x0: param_vector(self.center, fitted),
            scales: fitted
                .iter()
                .map(|&i| self.scales.of(self.center, i))
                .collect(),
        }
    }
}

impl PositionFit<'_> {
    /// One identification from `start`: the analysis there, then the solve.
    fn once(&self, start: &Model) -> Result<Fit, CalibError> {
        if use_normal_equations(self.rtol) && self.prior.is_none() {
            return fit_parameters_normal(start, self);
        }
        let (poses, tilt) = (self.poses, self.tilt);
        let jac0 = stacked_jacobian(start, poses, self.selection, tilt)?;
        let make = |cols| position_problem(start, poses, cols, tilt);
        fit_problem(
            start,
            self.selection,
            &jac0,
            make,
            self.lm,
            self.rtol,
            self.prior.as_ref(),
        )
    }

    /// The rank of the selection's Jacobian at `model`.
    fn rank_at(&self, model: &Model) -> Result<usize, CalibError> {
        let (poses, selection, tilt, rtol) = (self.poses, self.selection, self.tilt, self.rtol);
        Ok(if use_normal_equations(rtol) {
            let eq = normal_equations_with(model, poses, None, selection, tilt)?;
            analyse(&eq.jacobian_root(), rtol).rank
        } else {
            analyse(&stacked_jacobian(model, poses, selection, tilt)?, rtol).rank
        })
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

/// The fit at the solution `rep` of normal equations: `state` set to it, the sigmas and the
/// condition number from the square root of `J^T J` there (the tall Jacobian's column norms and
/// singular values).
pub fn fit_at_normal<U, S: SetUnknowns>(
    split: Split<U>,
    mut state: S,
    rep: &NormalReport,
    rtol: f64,
) -> Result<Fit<S, U>, CalibError> {
    state.set(&rep.x)?;
    let root = rep.normal.jacobian_root();
    Ok(Fit {
        model: state,
        fitted: split.fitted,
        fixed: split.fixed,
        unidentifiable: split.unidentifiable,
        sigma: parameter_sigmas_m(&root, rep.normal.m, rep.normal.rtr, rtol),
        condition_number: analyse(&root, rtol).condition_number,
        rank: split.rank,
        iterations: rep.iterations,
        converged: rep.termination.converged(),
        rss_mm2: rep.normal.rtr,
        n_residuals: rep.normal.m,
    })
}

/// A selection split by the identifiability analysis of its start Jacobian.
#[derive(Debug, Clone)]
pub struct Split<U> {
    /// The unknowns to fit, in selection order.
    pub fitted: Vec<U>,
    /// The unknowns kept at their start value.
    pub fixed: Vec<U>,
    /// Names of the unidentifiable unknowns or combinations.
    pub unidentifiable: Vec<String>,
    /// Rank of the start Jacobian.
    pub rank: usize,
}

impl<U> Split<U> {
    /// No unknown.
    pub fn none() -> Self {
        Self {
            fitted: Vec::new(),
            fixed: Vec::new(),
            unidentifiable: Vec::new(),
            rank: 0,
        }
    }
}

impl<U: Copy> Split<U> {
    /// `selection` split by the analysis `id` of its columns (`names`: one per selected unknown).
    pub fn of(selection: &[U], names: &[&str], id: &Identifiability) -> Self {
        Self {
            fitted: id.kept.iter().map(|&k| selection[k]).collect(),
            fixed: id.fixed.iter().map(|&k| selection[k]).collect(),
            unidentifiable: id.combinations.iter().map(|c| c.name(names)).collect(),
            rank: id.rank,
        }
    }

    /// The split, or [`CalibError::NothingToFit`] when nothing is left to fit.
    pub fn nonempty(self) -> Result<Self, CalibError> {
        if self.fitted.is_empty() {
            return Err(CalibError::NothingToFit);
        }
        Ok(self)
    }
}

/// Splits `selection` into fitted and fixed parameters by the identifiability analysis of
/// `jac0` (one column per selected parameter); [`CalibError::NothingToFit`] when none is left.
fn split_selection(
    start: &Model,
    selection: &[usize],
    jac0: &DMatrix<f64>,
    rtol: f64,
) -> Result<Split<usize>, CalibError> {
    if jac0.ncols() != selection.len() {
        return Err(CalibError::Solver(format!(
            "start Jacobian has {} columns for {} selected parameters",
            jac0.ncols(),
            selection.len()
        )));
    }
    let names: Vec<&str> = start.param_names().collect();
    let sel_names: Vec<&str> = selection
        .iter()
        .map(|&c| names.get(c).copied().unwrap_or("?"))
        .collect();
    Split::of(selection, &sel_names, &analyse(jac0, rtol)).nonempty()
}

/// The solve of an identification split by [`Split`]: Levenberg-Marquardt on `problem` from the
/// fitted unknowns' start values `x0`; the state at the solution, with the sigmas and the
/// condition number of the Jacobian there.
pub fn solve_split<U, S: SetUnknowns, F: Rows<S>>(
    split: Split<U>,
    problem: ModelProblem<S, F>,
    x0: DVector<f64>,
    lm: &LmConfig,
    rtol: f64,
) -> Result<Fit<S, U>, CalibError> {
    solve_split_with(split, problem, x0, lm, rtol, None)
}

/// [`solve_split`] with a prior's rows after the measurements' ([`super::prior`]): the residual
/// sum of squares and the condition number are those of the measurements; the sigmas are the
/// posterior ones (`(J^T J + P)^-1`, measurement degrees of freedom).
pub fn solve_split_with<U, S: SetUnknowns, F: Rows<S>>(
    split: Split<U>,
    mut problem: ModelProblem<S, F>,
    x0: DVector<f64>,
    lm: &LmConfig,
    rtol: f64,
    prior: Option<&Prior>,
) -> Result<Fit<S, U>, CalibError> {
    let m = problem.n_residuals();
    let rep = match prior {
        Some(p) => solve(&mut WithPrior::new(&mut problem, p), x0, lm),
        None => solve(&mut problem, x0, lm),
    }
    .map_err(CalibError::from_lm)?;
    let mut state = problem.into_state();
    state.set(&rep.x)?;
    let rss_mm2 = rep.residuals.rows(0, m).norm_squared();
    let data_jac = rep.jacobian.rows(0, m).into_owned();
    Ok(Fit {
        model: state,
        fitted: split.fitted,
        fixed: split.fixed,
        unidentifiable: split.unidentifiable,
        sigma: parameter_sigmas_m(&rep.jacobian, m, rss_mm2, rtol),
        condition_number: analyse(&data_jac, rtol).condition_number,
        rank: split.rank,
        iterations: rep.iterations,
        converged: rep.termination.converged(),
        rss_mm2,
        n_residuals: m,
    })
}

/// The identification common to every kind of measurement: the identifiability analysis of
/// `jac0` (the Jacobian of the residuals wrt `selection` at `start`, one column per selected
/// parameter) splits the selection into fitted and fixed parameters; `make_problem` builds the
/// least-squares problem on a copy of `start` with the fitted ones (model indices) as unknowns,
/// which Levenberg-Marquardt solves from their values in `start` ([`solve_split_with`], with the
/// prior `prior` on the fitted ones when given).
pub fn fit_problem<F: Rows<Unknowns>>(
    start: &Model,
    selection: &[usize],
    jac0: &DMatrix<f64>,
    make_problem: impl FnOnce(Vec<usize>) -> ModelProblem<Unknowns, F>,
    lm: &LmConfig,
    rtol: f64,
    prior: Option<&PriorAt<'_>>,
) -> Result<Fit, CalibError> {
    let split = split_selection(start, selection, jac0, rtol)?;
    let x0 = param_vector(start, &split.fitted);
    let prior = prior.map(|p| p.on(&split.fitted));
    let problem = make_problem(split.fitted.clone());
    Ok(
        solve_split_with(split, problem, x0, lm, rtol, prior.as_ref())?
            .map_model(Unknowns::into_model),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact poses of a model with two joint-offset errors: the fit recovers them, and a start
    /// Jacobian that does not match the selection is an error, not a panic.
    #[test]
    fn position_fit_recovers_offsets() {
        let nominal = crate::model::katana450(200.0).unwrap();
        let mut truth = nominal.clone();
        truth.set_param("dth2", 0.04).unwrap();
        truth.set_param("dth4", -0.02).unwrap();
        let mut poses = Poses::default();
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
        let fit = fit_parameters(&nominal, &poses, &cols, false, &lm, 1e-4).unwrap();
        assert_eq!(fit.fitted, cols);
        assert!((fit.model.param("dth2").unwrap() - 0.04).abs() < 1e-9);
        assert!((fit.model.param("dth4").unwrap() + 0.02).abs() < 1e-9);
        assert!(fit.converged && fit.rank == 2);
        let wrong = DMatrix::zeros(3 * poses.len(), 1);
        let make = |c| position_problem(&nominal, &poses, c, false);
        let res = fit_problem(&nominal, &cols, &wrong, make, &lm, 1e-4, None);
        assert!(matches!(res, Err(CalibError::Solver(_))), "{res:?}");
    }

    #[test]
    fn sigmas_of_a_straight_line_fit() {
        // y = a + b t with residuals r: var(b) = s^2 / sum (t - tbar)^2 for centred t.
        let t = [-2.0, -1.0, 0.0, 1.0, 2.0];
        let jac = DMatrix::from_fn(5, 2, |r, c| if c == 0 { 1.0 } else { t[r] });
        let res_sq = 0.3;
        let s = parameter_sigmas(&jac, res_sq, 1e-12);
        let s2 = res_sq / 3.0;
        assert!((s[0] - (s2 / 5.0).sqrt()).abs() < 1e-12);
        assert!((s[1] - (s2 / 10.0).sqrt()).abs() < 1e-12);
    }
}
