//! The parts of a Levenberg-Marquardt iteration that every linearisation shares: the settings,
//! the termination and errors, the report, the SVD step of the column-scaled Jacobian, the
//! damping (Nielsen 1999), the column scaling (Moré 1978) and the negligible-step rule.

use nalgebra::{DMatrix, DVector};

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
    pub(super) fn new(js: DMatrix<f64>, r: &DVector<f64>) -> Option<Self> {
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

pub(super) fn all_finite<'a>(it: impl IntoIterator<Item = &'a f64>) -> bool {
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
