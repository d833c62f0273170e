//! The Levenberg-Marquardt iteration, written once for every linearisation: the tall Jacobian
//! with Householder QR ([`super::lm`]) and the normal equations accumulated per measurement
//! ([`super::normal`]) differ only in how they linearise the problem and obtain the SVD of the
//! column-scaled Jacobian ([`Linearisation`]); the column scaling, the damping, the stopping
//! rules, the iteration budget by progress ([`Budget`]) and the final Gauss-Newton correction are
//! this file's.

use nalgebra::DVector;

use super::lm_parts::{negligible, Damping, LmConfig, LmError, ScaledSvd, Termination};

/// A problem linearised at a current point, able to evaluate trial points.
pub(super) trait Linearisation {
    /// The problem's own error type.
    type Error;
    /// `0.5 |r|^2` at the current point.
    fn cost(&self) -> f64;
    /// Updates the column scaling `diag` (running maximum of the Jacobian's column norms, 1 for a
    /// zero column) with the current linearisation, and returns the infinity norm of the scaled
    /// gradient over the residual norm, `|Js^T r|_inf / |r|`.
    fn rescale(&mut self, diag: &mut DVector<f64>) -> f64;
    /// The SVD of the current column-scaled Jacobian `J D^-1` (after [`Self::rescale`]); `None`
    /// when it cannot be computed.
    fn scaled_svd(&mut self, diag: &DVector<f64>) -> Option<ScaledSvd>;
    /// Evaluates the trial point `x` and returns its cost; with `jacobian` the trial's
    /// linearisation is evaluated too (so that [`Self::accept`] needs no evaluation).
    fn trial(&mut self, x: &DVector<f64>, jacobian: bool) -> Result<f64, Self::Error>;
    /// Makes the last trial (at `x`) the current point, linearised there; returns whether that
    /// took another evaluation.
    fn accept(&mut self, x: &DVector<f64>) -> Result<bool, Self::Error>;
}

/// The outcome of [`iterate`]; the linearisation at `x` stays in the [`Linearisation`].
pub(super) struct Iterated {
    pub x: DVector<f64>,
    pub cost: f64,
    pub initial_cost: f64,
    pub iterations: usize,
    pub evaluations: usize,
    pub termination: Termination,
}

/// The iteration budget by progress (see [`LmConfig::max_iterations`]): the costs after each
/// iteration, so that a solve past its budget goes on only while it still makes progress.
struct Budget {
    costs: Vec<f64>,
}

impl Budget {
    fn new(initial_cost: f64) -> Self {
        Self {
            costs: vec![initial_cost],
        }
    }

    /// Records the cost after an iteration; true when the solve must stop (budget spent with no
    /// progress over the window, or the hard cap reached).
    fn exhausted(&mut self, cfg: &LmConfig, iterations: usize, cost: f64) -> bool {
        self.costs.push(cost);
        if iterations < cfg.max_iterations {
            return false;
        }
        if iterations >= cfg.max_iterations_hard.max(cfg.max_iterations) {
            return true;
        }
        let window = (cfg.max_iterations / 10).max(5);
        let Some(before) = self
            .costs
            .len()
            .checked_sub(window + 1)
            .map(|i| self.costs[i])
        else {
            return false;
        };
        !(before > 0.0 && (before - cost) > cfg.progress_rtol * before)
    }
}

/// A trial step that decreased the cost (its linearisation state is the [`Linearisation`]'s).
struct Accepted {
    x: DVector<f64>,
    cost: f64,
    /// Norm of the scaled step.
    step_norm: f64,
}

/// Inner loop of an iteration: tries steps from `x` (cost `cost`), adapting the damping, until
/// one decreases the cost. `None` when the step became negligible or 40 trials gave no
/// decrease.
#[allow(clippy::too_many_arguments)]
fn find_decrease<L: Linearisation>(
    lin: &mut L,
    evaluations: &mut usize,
    svd: &ScaledSvd,
    damping: &mut Damping,
    x: &DVector<f64>,
    diag: &DVector<f64>,
    cost: f64,
    cfg: &LmConfig,
    jacobian: bool,
) -> Result<Option<Accepted>, LmError<L::Error>> {
    let xs_norm = x.component_mul(diag).norm();
    let mut gn_scale = 1.0;
    for _ in 0..40 {
        let y = svd.step(damping.lambda, cfg.rank_rtol) * gn_scale;
        if negligible(y.norm(), xs_norm, cfg.xtol) {
            return Ok(None);
        }
        let x_try = x + y.component_div(diag);
        *evaluations += 1;
        let cost_try = lin.trial(&x_try, jacobian).map_err(LmError::Problem)?;
        if cost_try.is_finite() && cost_try < cost {
            damping.accepted(svd.gain_ratio(&y, cost - cost_try));
            return Ok(Some(Accepted {
                x: x_try,
                cost: cost_try,
                step_norm: y.norm(),
            }));
        }
        damping.rejected(&mut gn_scale);
    }
    Ok(None)
}

/// Levenberg-Marquardt (or Gauss-Newton, see [`LmConfig::gauss_newton`]) from `x0`, whose
/// linearisation `lin` holds (counted as `evaluations` so far). `trial_jacobian`: whether a
/// trial evaluates its linearisation at once (cheap when the trial's residuals give it anyway).
pub(super) fn iterate<L: Linearisation>(
    lin: &mut L,
    x0: DVector<f64>,
    cfg: &LmConfig,
    mut evaluations: usize,
    trial_jacobian: bool,
) -> Result<Iterated, LmError<L::Error>> {
    let n = x0.len();
    let mut x = x0;
    let mut cost = lin.cost();
    let initial_cost = cost;
    let mut diag: DVector<f64> = DVector::from_element(n, 0.0);
    let mut damping: Option<Damping> = None;
    let mut iterations = 1;
    let mut budget = Budget::new(cost);
    let termination = loop {
        if cost == 0.0 {
            break Termination::GradientConverged;
        }
        if lin.rescale(&mut diag) < cfg.gtol {
            break Termination::GradientConverged;
        }
        let Some(svd) = lin.scaled_svd(&diag) else {
            break Termination::NoFurtherDecrease;
        };
        let damping = damping.get_or_insert_with(|| Damping {
            lambda: cfg.initial_damping * svd.max_sv().powi(2),
            nu: 2.0,
        });
        let found = find_decrease(
            lin,
            &mut evaluations,
            &svd,
            damping,
            &x,
            &diag,
            cost,
            cfg,
            trial_jacobian,
        )?;
        let Some(step) = found else {
            break if iterations == 1 && cost == initial_cost {
                Termination::NoFurtherDecrease
            } else {
                Termination::StepConverged
            };
        };
        let rel_decrease = (cost - step.cost) / cost;
        x = step.x;
        cost = step.cost;
        if lin.accept(&x).map_err(LmError::Problem)? {
            evaluations += 1;
        }
        if rel_decrease < cfg.ftol {
            break Termination::CostConverged;
        }
        if negligible(step.step_norm, x.component_mul(&diag).norm(), cfg.xtol) {
            break Termination::StepConverged;
        }
        if budget.exhausted(cfg, iterations, cost) {
            break Termination::MaxIterations;
        }
        iterations += 1;
    };
    if ScaledSvd::wants_final_correction(cfg, termination, cost) {
        // The final Gauss-Newton correction ([`ScaledSvd::final_correction`]) from the last
        // linearisation, evaluated so that the linearisation and the cost are those of the
        // returned point.
        lin.rescale(&mut diag);
        if let Some(y) = lin
            .scaled_svd(&diag)
            .and_then(|svd| svd.final_correction(cost, cfg))
        {
            let x_try = &x + y.component_div(&diag);
            evaluations += 1;
            let cost_try = lin.trial(&x_try, true).map_err(LmError::Problem)?;
            if ScaledSvd::keeps_correction(cost, cost_try) {
                if lin.accept(&x_try).map_err(LmError::Problem)? {
                    evaluations += 1;
                }
                x = x_try;
                cost = cost_try;
            }
        }
    }
    Ok(Iterated {
        x,
        cost,
        initial_cost,
        iterations,
        evaluations,
        termination,
    })
}
