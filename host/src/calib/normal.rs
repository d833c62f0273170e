//! Levenberg-Marquardt on the normal equations, for problems with many residuals: the problem
//! accumulates `J^T J` (n x n), `J^T r` and `r^T r` per measurement instead of building the tall
//! `m x n` Jacobian, so memory stays bounded whatever the number of poses.
//!
//! The iteration is the one of [`super::lm::solve`] (same column scaling, damping, stopping
//! rules); only the linear algebra differs: the SVD of the column-scaled Jacobian `Js = J D^-1`
//! is obtained from the symmetric eigen-decomposition of `Js^T Js = D^-1 J^T J D^-1`
//! (`s_i = sqrt(eig_i)`, `U^T r = S^-1 V^T Js^T r`). Squaring the Jacobian squares its condition
//! number, so singular values below [`NORMAL_EIG_FLOOR`]`^(1/2)` of the largest are round-off
//! and are dropped like the ones below `rank_rtol`; [`super::position_fit::fit_parameters`] uses this path
//! only when the identifiability threshold keeps the condition number far from that floor and
//! falls back to the tall QR path otherwise (never silently: see [`use_normal_equations`]).

use nalgebra::{DMatrix, DVector};

use super::identifiability::ZERO_COLUMN_RTOL;
use super::iterate::{iterate, Linearisation};
use super::lm_parts::{check_dimensions, raise_scaling, LmConfig, LmError, ScaledSvd, Termination};

/// Eigenvalues of the scaled normal matrix below this fraction of the largest are round-off
/// (about 100 machine epsilons); their directions are not stepped along.
pub const NORMAL_EIG_FLOOR: f64 = 1e-14;

/// Largest identifiability threshold (`rtol`, relative singular value) below which the normal
/// equations are not accurate enough: with `rtol >= 1e-6` every kept direction has a scaled
/// eigenvalue above 1e-12 of the largest, 100 times the round-off floor.
pub const NORMAL_MIN_RTOL: f64 = 1e-6;

/// Whether an identification with threshold `rtol` may use the normal equations.
pub fn use_normal_equations(rtol: f64) -> bool {
    rtol >= NORMAL_MIN_RTOL
}

/// Normal equations of a linearisation: `J^T J`, `J^T r`, `r^T r` and the number of residuals.
#[derive(Debug, Clone, PartialEq)]
pub struct Normal {
    /// `J^T J` (n x n, symmetric, both triangles filled by [`Normal::symmetrise`]).
    pub jtj: DMatrix<f64>,
    /// `J^T r`.
    pub jtr: DVector<f64>,
    /// `r^T r`.
    pub rtr: f64,
    /// Number of residuals accumulated.
    pub m: usize,
}

impl Normal {
    /// Zero equations for `n` unknowns.
    pub fn zeros(n: usize) -> Self {
        Self {
            jtj: DMatrix::zeros(n, n),
            jtr: DVector::zeros(n),
            rtr: 0.0,
            m: 0,
        }
    }

    /// Resets to zero (no allocation).
    pub fn clear(&mut self) {
        self.jtj.fill(0.0);
        self.jtr.fill(0.0);
        self.rtr = 0.0;
        self.m = 0;
    }

    /// Becomes a copy of `other` (without allocating when the sizes agree).
    pub fn assign(&mut self, other: &Normal) {
        if self.jtj.shape() == other.jtj.shape() && self.jtr.len() == other.jtr.len() {
            self.jtj.copy_from(&other.jtj);
            self.jtr.copy_from(&other.jtr);
        } else {
            self.jtj = other.jtj.clone();
            self.jtr = other.jtr.clone();
        }
        self.rtr = other.rtr;
        self.m = other.m;
    }

    /// Adds `other` (same size).
    pub fn add(&mut self, other: &Normal) {
        self.jtj += &other.jtj;
        self.jtr += &other.jtr;
        self.rtr += other.rtr;
        self.m += other.m;
    }

    /// The equations of the unknowns `idx` only (indices into these unknowns, in that order).
    pub fn select(&self, idx: &[usize]) -> Normal {
        Normal {
            jtj: self.jtj.select_rows(idx).select_columns(idx),
            jtr: self.jtr.select_rows(idx),
            rtr: self.rtr,
            m: self.m,
        }
    }

    /// Copies the upper triangle into the lower one (accumulators fill the upper one only).
    pub fn symmetrise(&mut self) {
        let n = self.jtj.nrows();
        for a in 0..n {
            for b in 0..a {
                self.jtj[(a, b)] = self.jtj[(b, a)];
            }
        }
    }

    /// A square matrix `M` with `M^T M = J^T J`, whose column norms, singular values and right
    /// singular vectors are those of `J` (to round-off): what the identifiability analysis and the
    /// sigmas need, without the tall Jacobian. Built as `sqrt(D^-1 J^T J D^-1) D` with `D` the
    /// exact column norms `sqrt((J^T J)_jj)`, so a column that is round-off in `J` (below
    /// [`ZERO_COLUMN_RTOL`] of the largest) stays one here instead of taking the size of the
    /// eigen-solver's round-off.
    pub fn jacobian_root(&self) -> DMatrix<f64> {
        let n = self.jtj.nrows();
        if n == 0 {
            return DMatrix::zeros(0, 0);
        }
        let norms: Vec<f64> = (0..n).map(|j| self.jtj[(j, j)].max(0.0).sqrt()).collect();
        let top = norms.iter().copied().fold(0.0, f64::max);
        let live: Vec<bool> = norms
            .iter()
            .map(|&c| c > ZERO_COLUMN_RTOL * top && c > 0.0)
            .collect();
        let ns = DMatrix::from_fn(n, n, |a, b| {
            if live[a] && live[b] {
                self.jtj[(a, b)] / (norms[a] * norms[b])
            } else {
                0.0
            }
        });
        let eig = ns.symmetric_eigen();
        let mut root = DMatrix::zeros(n, n);
        for k in 0..n {
            let s = eig.eigenvalues[k].max(0.0).sqrt();
            let v = eig.eigenvectors.column(k);
            root.ger(s, &v, &v, 1.0);
        }
        for (j, &c) in norms.iter().enumerate() {
            let scale = if live[j] { c } else { 0.0 };
            root.column_mut(j).scale_mut(scale);
        }
        root
    }
}

/// A least-squares problem that gives its normal equations (see the module doc).
pub trait NormalProblem {
    /// The problem's own error type.
    type Error;
    /// Number of unknowns.
    fn n_params(&self) -> usize;
    /// Number of residuals.
    fn n_residuals(&self) -> usize;
    /// `r(x)^T r(x)` (the residuals alone, cheaper than [`NormalProblem::normal`]).
    fn sum_sq(&mut self, x: &DVector<f64>) -> Result<f64, Self::Error>;
    /// The normal equations at `x` into `eq` (upper triangle of `jtj` at least).
    fn normal(&mut self, x: &DVector<f64>, eq: &mut Normal) -> Result<(), Self::Error>;
}

/// Result of [`solve_normal`].
#[derive(Debug, Clone)]
pub struct NormalReport {
    /// The solution.
    pub x: DVector<f64>,
    /// Normal equations at `x` (evaluated after the last accepted step; symmetric).
    pub normal: Normal,
    /// `0.5 |r|^2` at `x`.
    pub cost: f64,
    /// `0.5 |r|^2` at the start.
    pub initial_cost: f64,
    /// Number of linearisations (iterations).
    pub iterations: usize,
    /// Number of evaluations (linearisations and residual sums).
    pub evaluations: usize,
    /// Why it stopped.
    pub termination: Termination,
}

impl ScaledSvd {
    /// The SVD of `Js = J D^-1` from the normal equations (see the module doc).
    fn from_normal(eq: &Normal, diag: &DVector<f64>) -> Option<Self> {
        let n = diag.len();
        let ns = DMatrix::from_fn(n, n, |a, b| eq.jtj[(a, b)] / (diag[a] * diag[b]));
        let gs = eq.jtr.component_div(diag);
        let eig = ns.try_symmetric_eigen(f64::EPSILON, 0)?;
        let top = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
        let s = eig.eigenvalues.map(|e| {
            if e > NORMAL_EIG_FLOOR * top {
                e.sqrt()
            } else {
                0.0
            }
        });
        let vtg = eig.eigenvectors.transpose() * gs;
        let ut_r = DVector::from_fn(n, |i, _| if s[i] > 0.0 { vtg[i] / s[i] } else { 0.0 });
        Some(ScaledSvd::from_parts(eig.eigenvectors, s, ut_r))
    }
}

/// The linearisation by normal equations: those at the current point and at the last trial
/// (each trial evaluates them at once: near a solution nearly every trial is accepted, and its
/// linearisation is then the next iteration's).
struct Equations<'p, P> {
    problem: &'p mut P,
    eq: Normal,
    eq_try: Normal,
}

impl<P: NormalProblem> Linearisation for Equations<'_, P> {
    type Error = P::Error;

    fn cost(&self) -> f64 {
        0.5 * self.eq.rtr
    }

    fn rescale(&mut self, diag: &mut DVector<f64>) -> f64 {
        // the column norms are `sqrt((J^T J)_jj)`
        raise_scaling(diag, |j| self.eq.jtj[(j, j)].max(0.0).sqrt());
        self.eq.jtr.component_div(diag).amax() / self.eq.rtr.sqrt()
    }

    fn scaled_svd(&mut self, diag: &DVector<f64>) -> Option<ScaledSvd> {
        ScaledSvd::from_normal(&self.eq, diag)
    }

    fn trial(&mut self, x: &DVector<f64>, _jacobian: bool) -> Result<f64, P::Error> {
        self.problem.normal(x, &mut self.eq_try)?;
        Ok(0.5 * self.eq_try.rtr)
    }

    fn accept(&mut self, _x: &DVector<f64>) -> Result<bool, P::Error> {
        std::mem::swap(&mut self.eq, &mut self.eq_try);
        self.eq.symmetrise();
        Ok(false)
    }
}

/// Solves `problem` from `x0` with Levenberg-Marquardt on its normal equations (the iteration
/// of [`super::lm::solve`]).
pub fn solve_normal<P: NormalProblem>(
    problem: &mut P,
    x0: DVector<f64>,
    cfg: &LmConfig,
) -> Result<NormalReport, LmError<P::Error>> {
    let n = problem.n_params();
    check_sizes(problem, &x0)?;
    let mut eq = Normal::zeros(n);
    problem.normal(&x0, &mut eq).map_err(LmError::Problem)?;
    eq.symmetrise();
    solve_normal_from(problem, x0, eq, cfg)
}

fn check_sizes<P: NormalProblem>(problem: &P, x0: &DVector<f64>) -> Result<(), LmError<P::Error>> {
    check_dimensions(problem.n_params(), problem.n_residuals(), x0.len())
}

/// [`solve_normal`] given the problem's normal equations at `x0` (symmetric, e.g. selected from
/// an identifiability analysis done at the same point): saves their evaluation.
pub fn solve_normal_from<P: NormalProblem>(
    problem: &mut P,
    x0: DVector<f64>,
    eq0: Normal,
    cfg: &LmConfig,
) -> Result<NormalReport, LmError<P::Error>> {
    let n = problem.n_params();
    check_sizes(problem, &x0)?;
    if eq0.jtr.len() != n || eq0.jtj.nrows() != n || eq0.jtj.ncols() != n {
        return Err(LmError::Dimensions(format!(
            "start normal equations are for {} unknowns, problem has {n}",
            eq0.jtr.len()
        )));
    }
    if !eq0.rtr.is_finite() || !eq0.jtj.iter().all(|v| v.is_finite()) {
        return Err(LmError::NonFiniteStart);
    }
    let mut lin = Equations {
        problem,
        eq: eq0,
        eq_try: Normal::zeros(n),
    };
    let it = iterate(&mut lin, x0, cfg, 1, true)?;
    Ok(NormalReport {
        x: it.x,
        normal: lin.eq,
        cost: it.cost,
        initial_cost: it.initial_cost,
        iterations: it.iterations,
        evaluations: it.evaluations,
        termination: it.termination,
    })
}
