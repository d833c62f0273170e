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
use super::lm_parts::{all_finite, check_dimensions, raise_scaling, ScaledSvd};
pub use super::lm_parts::{LmConfig, LmError, LmReport, Termination};

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

    use crate::calib::problem::{ModelProblem, Rows};

    /// A problem of `n` unknowns (a plain vector, the state) and `m` residuals whose closure
    /// writes `r` and, when asked, the Jacobian.
    fn problem<F>(
        n: usize,
        m: usize,
        mut f: F,
    ) -> ModelProblem<DVector<f64>, impl Rows<DVector<f64>>>
    where
        F: FnMut(&DVector<f64>, &mut DVector<f64>, Option<&mut DMatrix<f64>>),
    {
        let rows = move |x: &DVector<f64>, r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>| {
            f(x, r, jac);
            Ok(())
        };
        ModelProblem::new(DVector::zeros(n), m, rows)
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
