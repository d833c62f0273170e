//! Levenberg-Marquardt (and plain Gauss-Newton) for small dense nonlinear least-squares problems.
//!
//! Minimises `0.5 |r(x)|^2`. Each iteration factors the column-scaled Jacobian `J D^-1` once
//! (Householder QR, then an SVD of the small `n x n` triangular factor), so trial steps for
//! several damping values cost only `O(n^2)`. The step solves
//! `(Js^T Js + lambda I) y = -Js^T r`, `dx = D^-1 y` with the SVD (singular values below
//! `rank_rtol * s_max` are dropped, so a rank-deficient problem still takes finite steps).
//! Column scaling `D` is the running maximum of the Jacobian column norms (Moré 1978), which
//! makes the method invariant to the units of the parameters (degrees vs millimetres).
//! Damping follows Nielsen (1999): `lambda *= max(1/3, 1 - (2 rho - 1)^3)` on success,
//! `lambda *= nu, nu *= 2` on failure.

use nalgebra::{DMatrix, DVector};

use super::iterate::{iterate, Linearisation};

/// A least-squares problem: residuals `r(x)` (length [`Self::n_residuals`]) and their Jacobian
/// `dr/dx` (`n_residuals x n_params`).
pub trait Problem {
    /// The problem's own error type (e.g. a model evaluation error).
    type Error;
    /// Number of unknowns.
    fn n_params(&self) -> usize;
    /// Number of residuals.
    fn n_residuals(&self) -> usize;
    /// Writes `r(x)` into `r`, and `dr/dx` into `jac` when it is given.
    fn evaluate(
        &mut self,
        x: &DVector<f64>,
        r: &mut DVector<f64>,
        jac: Option<&mut DMatrix<f64>>,
    ) -> Result<(), Self::Error>;
}

/// Settings of the solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmConfig {
    /// Iteration budget (Jacobian evaluations). A solve that still makes progress at the budget
    /// goes on ([`Budget`]): while the last `max_iterations / 10` iterations (at least 5) lowered
    /// the cost by more than `progress_rtol` of itself, up to `max_iterations_hard`.
    pub max_iterations: usize,
    /// Hard cap on the iterations, whatever the progress.
    pub max_iterations_hard: usize,
    /// Relative decrease of the cost over the last window that counts as progress past the
    /// budget.
    pub progress_rtol: f64,
    /// Stop when the relative decrease of the cost in a successful step is below this.
    pub ftol: f64,
    /// Stop when the scaled step is below `xtol * (|D x| + xtol)`.
    pub xtol: f64,
    /// Stop when the infinity norm of the scaled gradient `Js^T r / |r|` is below this.
    pub gtol: f64,
    /// Initial damping relative to the largest squared scaled singular value; 0 gives
    /// Gauss-Newton steps (with step halving when a step increases the cost).
    pub initial_damping: f64,
    /// Singular values of the scaled Jacobian below `rank_rtol * s_max` are treated as zero.
    pub rank_rtol: f64,
    /// End a converged solve with one Gauss-Newton correction ([`ScaledSvd::final_correction`]:
    /// one more evaluation; the fit is then the optimum to round-off along weakly seen
    /// directions too). Off for approximate refits (cross-validation folds).
    pub final_correction: bool,
}

impl Default for LmConfig {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            max_iterations_hard: 2000,
            progress_rtol: 1e-9,
            ftol: 1e-12,
            xtol: 1e-10,
            gtol: 1e-10,
            initial_damping: 1e-4,
            rank_rtol: 1e-12,
            final_correction: true,
        }
    }
}

impl LmConfig {
    /// Gauss-Newton: no damping (steps are halved when they increase the cost).
    pub fn gauss_newton() -> Self {
        Self {
            initial_damping: 0.0,
            ..Self::default()
        }
    }
}

/// Why the solver stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// The cost no longer decreases (relative decrease below `ftol`).
    CostConverged,
    /// The step became negligible (`xtol`).
    StepConverged,
    /// The gradient vanished (`gtol`), or the residual is exactly zero.
    GradientConverged,
    /// No damping value produced a decrease: the current point is a minimum to working precision.
    NoFurtherDecrease,
    /// The iteration budget was spent while the solve still made progress (or the hard cap was
    /// reached); the best point found is returned.
    MaxIterations,
}

impl Termination {
    /// Whether the stop is a convergence criterion (not the iteration cap).
    pub fn converged(self) -> bool {
        self != Termination::MaxIterations
    }
}

/// Failure of the solver.
#[derive(Debug, thiserror::Error)]
pub enum LmError<E> {
    /// The problem's evaluation failed.
    #[error("{0}")]
    Problem(E),
    /// Residuals or Jacobian are NaN or infinite at the start point.
    #[error("residuals or Jacobian not finite at the start point")]
    NonFiniteStart,
    /// Start vector or problem dimensions inconsistent.
    #[error("dimension mismatch: {0}")]
    Dimensions(String),
    /// Fewer residuals than unknowns.
    #[error("{residuals} residuals cannot determine {params} unknowns")]
    Underdetermined { residuals: usize, params: usize },
}

impl<E: crate::error::Classify> crate::error::Classify for LmError<E> {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            LmError::Problem(e) => e.kind(),
            LmError::Underdetermined { .. } => crate::error::ErrorKind::BadInput,
            _ => crate::error::ErrorKind::Failure,
        }
    }
}

/// Result of a solve.
#[derive(Debug, Clone)]
pub struct LmReport {
    /// The solution.
    pub x: DVector<f64>,
    /// Residuals at `x`.
    pub residuals: DVector<f64>,
    /// Jacobian at `x` (evaluated after the last accepted step).
    pub jacobian: DMatrix<f64>,
    /// `0.5 |r|^2` at `x`.
    pub cost: f64,
    /// `0.5 |r|^2` at the start.
    pub initial_cost: f64,
    /// Number of Jacobian evaluations (iterations).
    pub iterations: usize,
    /// Number of residual evaluations.
    pub evaluations: usize,
    /// Why it stopped.
    pub termination: Termination,
}

/// The SVD of the column-scaled Jacobian, kept as `V`, `s` and `U^T r`.
pub(super) struct ScaledSvd {
    v: DMatrix<f64>,
    s: DVector<f64>,
    ut_r: DVector<f64>,
}

impl ScaledSvd {
    /// From `V`, the singular values and `U^T r` directly.
    pub(super) fn from_parts(v: DMatrix<f64>, s: DVector<f64>, ut_r: DVector<f64>) -> Self {
        Self { v, s, ut_r }
    }

    /// QR of `js` (m x n, m >= n), then SVD of `R`; `U^T r = U_R^T (Q^T r)`.
    fn new(js: DMatrix<f64>, r: &DVector<f64>) -> Option<Self> {
        let n = js.ncols();
        let qr = js.qr();
        let mut qtr = r.clone();
        qr.q_tr_mul(&mut qtr);
        let rr = qr.r();
        let svd = rr.svd(true, true);
        let u = svd.u?;
        let v_t = svd.v_t?;
        let qtr_n = qtr.rows(0, n).into_owned();
        Some(Self {
            v: v_t.transpose(),
            s: svd.singular_values,
            ut_r: u.transpose() * qtr_n,
        })
    }

    pub(super) fn max_sv(&self) -> f64 {
        self.s.iter().copied().fold(0.0, f64::max)
    }

    /// Scaled step `y = -V diag(s / (s^2 + lambda)) U^T r` (dropping tiny singular values).
    pub(super) fn step(&self, lambda: f64, rank_rtol: f64) -> DVector<f64> {
        let cut = rank_rtol * self.max_sv();
        let coef = DVector::from_iterator(
            self.s.len(),
            self.s.iter().zip(self.ut_r.iter()).map(|(&s, &u)| {
                if s > cut {
                    -s * u / (s * s + lambda)
                } else {
                    0.0
                }
            }),
        );
        &self.v * coef
    }

    /// The final Gauss-Newton correction at a converged point (see [`solve`]): the undamped
    /// scaled step `y` of this linearisation, when the decrease it predicts is below `ftol` of
    /// `cost` (so the linear model is exact there to far below the stopping tolerances).
    /// The cost-based stopping rules cannot see a remaining step along a weakly scaled direction
    /// (e.g. a joint offset seen through a tool point 0.2 mm off its axis: 1e-7 deg there moves
    /// the cost by 1e-17 of itself); this step removes it without another evaluation.
    pub(super) fn final_correction(&self, cost: f64, cfg: &LmConfig) -> Option<DVector<f64>> {
        let y = self.step(0.0, cfg.rank_rtol);
        let jy: DVector<f64> = (self.v.transpose() * &y).component_mul(&self.s);
        let predicted = -(jy.dot(&self.ut_r)) - 0.5 * jy.norm_squared();
        (y.iter().all(|v| v.is_finite()) && predicted >= 0.0 && predicted <= cfg.ftol * cost)
            .then_some(y)
    }

    /// Whether a solve that stopped with `termination` at `cost` takes the final correction.
    pub(super) fn wants_final_correction(
        cfg: &LmConfig,
        termination: Termination,
        cost: f64,
    ) -> bool {
        cfg.final_correction && termination.converged() && cost > 0.0
    }

    /// Whether the evaluated final correction (cost `cost_try`) is kept: unless the cost grew
    /// beyond round-off (the decrease it predicts is below `ftol` of the cost, i.e. round-off).
    pub(super) fn keeps_correction(cost: f64, cost_try: f64) -> bool {
        cost_try.is_finite() && cost_try <= cost * (1.0 + 1e-12)
    }

    /// Gain ratio: the actual decrease of the cost over the decrease `-(Js y).r - |Js y|^2 / 2`
    /// the linear model predicts for the scaled step `y` (1 when it predicts none).
    pub(super) fn gain_ratio(&self, y: &DVector<f64>, actual_decrease: f64) -> f64 {
        let jy = {
            let lin: DVector<f64> = self.v.transpose() * y;
            lin.component_mul(&self.s)
        };
        let predicted = -(jy.dot(&self.ut_r)) - 0.5 * jy.norm_squared();
        if predicted > 0.0 {
            actual_decrease / predicted
        } else {
            1.0
        }
    }
}

/// Damping `lambda` and its growth factor `nu` (Nielsen 1999); `lambda = 0` is Gauss-Newton.
pub(super) struct Damping {
    pub(super) lambda: f64,
    pub(super) nu: f64,
}

impl Damping {
    /// After a step that decreased the cost with gain ratio `rho`.
    pub(super) fn accepted(&mut self, rho: f64) {
        if self.lambda > 0.0 {
            self.lambda *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
        }
        self.nu = 2.0;
    }

    /// After a step that did not decrease the cost: more damping, or (Gauss-Newton) half the
    /// step length `gn_scale`.
    pub(super) fn rejected(&mut self, gn_scale: &mut f64) {
        if self.lambda > 0.0 {
            self.lambda *= self.nu;
            self.nu *= 2.0;
        } else {
            *gn_scale *= 0.5;
        }
    }
}

fn all_finite<'a>(it: impl IntoIterator<Item = &'a f64>) -> bool {
    it.into_iter().all(|v| v.is_finite())
}

/// Whether a scaled step of norm `step_norm` is negligible at a point of scaled norm `xs_norm`.
pub(super) fn negligible(step_norm: f64, xs_norm: f64, xtol: f64) -> bool {
    step_norm <= xtol * (xs_norm + xtol)
}

/// Raises the column scaling `diag` to the column norms `norm(j)` (running max, 1 for a column
/// that has always been zero): the scaling of both linearisations.
pub(super) fn raise_scaling(diag: &mut DVector<f64>, norm: impl Fn(usize) -> f64) {
    for (j, d) in diag.iter_mut().enumerate() {
        *d = d.max(norm(j));
        if *d == 0.0 {
            *d = 1.0;
        }
    }
}

/// Checks the start vector's length (`x0_len`) against a problem of `n` unknowns and `m`
/// residuals.
pub(super) fn check_dimensions<E>(n: usize, m: usize, x0_len: usize) -> Result<(), LmError<E>> {
    if x0_len != n {
        return Err(LmError::Dimensions(format!(
            "start vector has {x0_len} entries, problem has {n} unknowns"
        )));
    }
    if m < n {
        return Err(LmError::Underdetermined {
            residuals: m,
            params: n,
        });
    }
    Ok(())
}

/// Updates the column scaling `diag` ([`raise_scaling`]) with `jac`, and returns the scaled
/// Jacobian `J D^-1`.
fn scale_columns(jac: &DMatrix<f64>, diag: &mut DVector<f64>) -> DMatrix<f64> {
    raise_scaling(diag, |j| jac.column(j).norm());
    let mut js = jac.clone();
    for (j, d) in diag.iter().enumerate() {
        js.column_mut(j).unscale_mut(*d);
    }
    js
}

/// The tall linearisation: residuals and Jacobian at the current point, the trial's residuals
/// (and Jacobian, for the final correction) beside them.
struct Tall<'p, P> {
    problem: &'p mut P,
    r: DVector<f64>,
    jac: DMatrix<f64>,
    r_try: DVector<f64>,
    jac_try: Option<DMatrix<f64>>,
    /// The scaled Jacobian of the last [`Linearisation::rescale`].
    js: Option<DMatrix<f64>>,
}

impl<P: Problem> Linearisation for Tall<'_, P> {
    type Error = P::Error;

    fn cost(&self) -> f64 {
        0.5 * self.r.norm_squared()
    }

    fn rescale(&mut self, diag: &mut DVector<f64>) -> f64 {
        let js = scale_columns(&self.jac, diag);
        let grad_inf = (js.transpose() * &self.r).amax() / self.r.norm();
        self.js = Some(js);
        grad_inf
    }

    fn scaled_svd(&mut self, _diag: &DVector<f64>) -> Option<ScaledSvd> {
        ScaledSvd::new(self.js.take()?, &self.r)
    }

    fn trial(&mut self, x: &DVector<f64>, jacobian: bool) -> Result<f64, P::Error> {
        if jacobian {
            let mut jac = DMatrix::zeros(self.jac.nrows(), self.jac.ncols());
            self.problem.evaluate(x, &mut self.r_try, Some(&mut jac))?;
            self.jac_try = Some(jac);
        } else {
            self.jac_try = None;
            self.problem.evaluate(x, &mut self.r_try, None)?;
        }
        Ok(0.5 * self.r_try.norm_squared())
    }

    fn accept(&mut self, x: &DVector<f64>) -> Result<bool, P::Error> {
        std::mem::swap(&mut self.r, &mut self.r_try);
        if let Some(jac) = self.jac_try.take() {
            self.jac = jac;
            return Ok(false);
        }
        self.problem.evaluate(x, &mut self.r, Some(&mut self.jac))?;
        Ok(true)
    }
}

/// Solves `problem` from `x0` with Levenberg-Marquardt (or Gauss-Newton, see
/// [`LmConfig::gauss_newton`]).
pub fn solve<P: Problem>(
    problem: &mut P,
    x0: DVector<f64>,
    cfg: &LmConfig,
) -> Result<LmReport, LmError<P::Error>> {
    let (n, m) = (problem.n_params(), problem.n_residuals());
    check_dimensions(n, m, x0.len())?;
    let mut r = DVector::zeros(m);
    let mut jac = DMatrix::zeros(m, n);
    problem
        .evaluate(&x0, &mut r, Some(&mut jac))
        .map_err(LmError::Problem)?;
    if !all_finite(r.iter()) || !all_finite(jac.iter()) {
        return Err(LmError::NonFiniteStart);
    }
    let mut lin = Tall {
        problem,
        r,
        jac,
        r_try: DVector::zeros(m),
        jac_try: None,
        js: None,
    };
    let it = iterate(&mut lin, x0, cfg, 1, false)?;
    Ok(LmReport {
        x: it.x,
        residuals: lin.r,
        jacobian: lin.jac,
        cost: it.cost,
        initial_cost: it.initial_cost,
        iterations: it.iterations,
        evaluations: it.evaluations,
        termination: it.termination,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A test problem of `n` unknowns and `m` residuals whose closure writes `r` and, when asked,
    /// the Jacobian.
    struct Fns<F> {
        n: usize,
        m: usize,
        f: F,
    }

    impl<F> Problem for Fns<F>
    where
        F: FnMut(&DVector<f64>, &mut DVector<f64>, Option<&mut DMatrix<f64>>),
    {
        type Error = std::convert::Infallible;
        fn n_params(&self) -> usize {
            self.n
        }
        fn n_residuals(&self) -> usize {
            self.m
        }
        fn evaluate(
            &mut self,
            x: &DVector<f64>,
            r: &mut DVector<f64>,
            jac: Option<&mut DMatrix<f64>>,
        ) -> Result<(), Self::Error> {
            (self.f)(x, r, jac);
            Ok(())
        }
    }

    fn problem<F>(n: usize, m: usize, f: F) -> Fns<F>
    where
        F: FnMut(&DVector<f64>, &mut DVector<f64>, Option<&mut DMatrix<f64>>),
    {
        Fns { n, m, f }
    }

    /// Rosenbrock as least squares: r = (10 (x2 - x1^2), 1 - x1); minimum (1, 1).
    #[test]
    fn rosenbrock_reaches_the_minimum() {
        let mut rosenbrock = problem(2, 2, |x, r, jac| {
            r[0] = 10.0 * (x[1] - x[0] * x[0]);
            r[1] = 1.0 - x[0];
            if let Some(j) = jac {
                j[(0, 0)] = -20.0 * x[0];
                j[(0, 1)] = 10.0;
                j[(1, 0)] = -1.0;
                j[(1, 1)] = 0.0;
            }
        });
        let rep = solve(
            &mut rosenbrock,
            DVector::from_vec(vec![-1.2, 1.0]),
            &LmConfig::default(),
        )
        .unwrap();
        assert!(
            (rep.x[0] - 1.0).abs() < 1e-8 && (rep.x[1] - 1.0).abs() < 1e-8,
            "{:?}",
            rep.x
        );
        assert!(rep.termination.converged());
    }

    /// Exponential fit y = a exp(b t) on exact data with badly scaled unknowns
    /// (a ~ 1e3, b ~ 1e-3): column scaling must make it converge from far away.
    #[test]
    fn badly_scaled_exponential_fit() {
        let t: Vec<f64> = (0..50).map(|i| f64::from(i) * 20.0).collect();
        let y: Vec<f64> = t.iter().map(|t| 2500.0 * (1.5e-3 * t).exp()).collect();
        let mut p = problem(2, t.len(), |x, r, mut jac| {
            for (i, (&t, &y)) in t.iter().zip(&y).enumerate() {
                let e = (x[1] * t).exp();
                r[i] = x[0] * e - y;
                if let Some(j) = jac.as_deref_mut() {
                    j[(i, 0)] = e;
                    j[(i, 1)] = x[0] * t * e;
                }
            }
        });
        for cfg in [LmConfig::default(), LmConfig::gauss_newton()] {
            let rep = solve(&mut p, DVector::from_vec(vec![1000.0, 1e-4]), &cfg).unwrap();
            assert!(
                (rep.x[0] / 2500.0 - 1.0).abs() < 1e-9,
                "{cfg:?} {:?}",
                rep.x
            );
            assert!(
                (rep.x[1] / 1.5e-3 - 1.0).abs() < 1e-9,
                "{cfg:?} {:?}",
                rep.x
            );
        }
    }

    /// A linear problem with two identical columns: the rank-deficient step must stay finite and
    /// reach the least-squares residual (the minimum-norm split between the twins).
    #[test]
    fn rank_deficient_problem_stays_finite() {
        let a = DMatrix::from_row_slice(
            4,
            3,
            &[1.0, 1.0, 0.0, 2.0, 2.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 3.0],
        );
        let b = DVector::from_vec(vec![2.0, 5.0, 1.0, 5.0]);
        let mut twins = problem(3, 4, |x, r, jac| {
            r.copy_from(&(&a * x - &b));
            if let Some(j) = jac {
                j.copy_from(&a);
            }
        });
        let rep = solve(&mut twins, DVector::zeros(3), &LmConfig::default()).unwrap();
        assert!(rep.x.iter().all(|v| v.is_finite()));
        // Exact solution exists: x0 + x1 = 2, x2 = 1.
        assert!((rep.x[0] + rep.x[1] - 2.0).abs() < 1e-8, "{:?}", rep.x);
        assert!((rep.x[2] - 1.0).abs() < 1e-8);
        assert!(
            (rep.x[0] - rep.x[1]).abs() < 1e-6,
            "minimum-norm split expected: {:?}",
            rep.x
        );
        assert!(rep.cost < 1e-16);
    }

    #[test]
    fn underdetermined_is_an_error() {
        let mut one = problem(2, 1, |_, _, _| {});
        assert!(matches!(
            solve(&mut one, DVector::zeros(2), &LmConfig::default()),
            Err(LmError::Underdetermined {
                residuals: 1,
                params: 2
            })
        ));
    }
}
