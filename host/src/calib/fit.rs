//! Least-squares identification of a parameter subset: identifiability analysis at the start
//! point ([`Split`]), Levenberg-Marquardt on the identifiable parameters ([`solve_split`], or
//! [`fit_at_normal`] on normal equations), covariance at the solution; the one result
//! [`Fit`] of every identification. The fit of model parameters on full positions is
//! [`super::position_fit`].

use nalgebra::{DMatrix, DVector};

use super::error::CalibError;
use super::identifiability::{analyse, analyse_svd, scaled_svd, Identifiability, ScaledSvd};
use super::lm::{solve, LmConfig, Problem};
use super::normal::NormalReport;
use super::prior::{Prior, PriorScales, WithPrior};
use super::problem::{param_vector, ModelProblem, Rows, SetUnknowns, Unknowns};
use crate::model::Model;

/// Result of every identification: [`super::position_fit::fit_parameters`] and [`fit_problem`] (a [`Model`] and its
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
    if jac.ncols() == 0 {
        return Vec::new();
    }
    sigmas_of_svd(&scaled_svd(jac), m, residual_norm_sq, rtol)
}

/// [`parameter_sigmas_m`] given the Jacobian's [`scaled_svd`] `svd` (computed once by a caller
/// that also analyses it, [`analyse_svd`]).
fn sigmas_of_svd(svd: &ScaledSvd, m: usize, residual_norm_sq: f64, rtol: f64) -> Vec<f64> {
    let (norms, s, v) = svd;
    let n = v.nrows();
    if n == 0 {
        return Vec::new();
    }
    let dof = m.saturating_sub(n).max(1) as f64;
    let s2 = residual_norm_sq / dof;
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
pub(super) fn split_selection(
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
    let (sigma, condition_number) = sigmas_and_condition(&rep.jacobian, m, rss_mm2, rtol);
    Ok(Fit {
        model: state,
        fitted: split.fitted,
        fixed: split.fixed,
        unidentifiable: split.unidentifiable,
        sigma,
        condition_number,
        rank: split.rank,
        iterations: rep.iterations,
        converged: rep.termination.converged(),
        rss_mm2,
        n_residuals: m,
    })
}

/// The state at the solution of `problem` from `x0` alone: [`solve_split`]'s solve without its
/// sigmas and condition number (for refits whose values are all that is used, e.g. the folds
/// of a cross-validation).
pub fn solve_values<S: SetUnknowns, F: Rows<S>>(
    mut problem: ModelProblem<S, F>,
    x0: DVector<f64>,
    lm: &LmConfig,
) -> Result<S, CalibError> {
    let rep = solve(&mut problem, x0, lm).map_err(CalibError::from_lm)?;
    let mut state = problem.into_state();
    state.set(&rep.x)?;
    Ok(state)
}

/// The sigmas ([`parameter_sigmas_m`]) of the solver's Jacobian `jac` (its first `m` rows the
/// measurements', any further rows a prior's) and the condition number of the measurements'
/// rows ([`analyse`]); one decomposition serves both when there is no prior.
fn sigmas_and_condition(jac: &DMatrix<f64>, m: usize, rss_mm2: f64, rtol: f64) -> (Vec<f64>, f64) {
    if jac.nrows() != m || jac.ncols() == 0 {
        let data_jac = jac.rows(0, m.min(jac.nrows())).into_owned();
        return (
            parameter_sigmas_m(jac, m, rss_mm2, rtol),
            analyse(&data_jac, rtol).condition_number,
        );
    }
    let svd = scaled_svd(jac);
    let sigma = sigmas_of_svd(&svd, m, rss_mm2, rtol);
    (sigma, analyse_svd(jac, rtol, svd).condition_number)
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
