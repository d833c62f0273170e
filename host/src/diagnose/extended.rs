//! The extended fit of `diagnose`: the state ([`ExtModel`], [`crate::calib::state`]) fitted
//! on the tall Jacobian (QR) or, on many poses, on normal equations accumulated pose by pose.

use nalgebra::DVector;

use crate::calib::fit::{fit_at_normal, solve_split, solve_values, Fit, Split};
use crate::calib::identifiability::{analyse, Identifiability};
use crate::calib::lm::LmConfig;
use crate::calib::normal::{
    solve_normal, solve_normal_from, use_normal_equations, Normal, NormalProblem,
};
use crate::calib::problem::SetUnknowns;
pub use crate::calib::state::ExtModel;
use crate::calib::unknown::Freed;
pub use crate::calib::unknown::{Unknown, Values};
use crate::calib::CalibError;
use crate::calib::MeasuredSet;
use crate::model::ModelError;

/// Fewest residuals from which [`super::compress::stacked_or_compressed`] compresses (and
/// from which [`uses_normal`] may take the normal equations).
pub const COMPRESS_MIN_RESIDUALS: usize = 6000;

/// Whether the fits on `data` go through normal equations: from
/// [`COMPRESS_MIN_RESIDUALS`] residuals on (below, the tall Jacobian is small
/// and its QR keeps the full precision), when the identifiability threshold allows them
/// ([`use_normal_equations`]).
pub fn uses_normal(data: &MeasuredSet, rtol: f64) -> bool {
    use_normal_equations(rtol) && data.n_residuals() >= COMPRESS_MIN_RESIDUALS
}

/// The extended fit on normal equations (residual `predicted - measured`).
struct ExtNormal<'a> {
    freed: Freed<ExtModel>,
    data: &'a MeasuredSet,
}

impl NormalProblem for ExtNormal<'_> {
    type Error = ModelError;

    fn n_params(&self) -> usize {
        self.freed.n_unknowns()
    }

    fn n_residuals(&self) -> usize {
        self.data.n_residuals()
    }

    fn sum_sq(&mut self, x: &DVector<f64>) -> Result<f64, ModelError> {
        self.freed.set(x)?;
        self.freed.state.sum_sq(self.data)
    }

    fn normal(&mut self, x: &DVector<f64>, eq: &mut Normal) -> Result<(), ModelError> {
        self.freed.set(x)?;
        let f = &self.freed;
        f.state.normal_into(self.data, &f.unknowns, eq)
    }
}

/// The one identification result ([`Fit`]) on the extended model: what [`fit`] returns.
pub type ExtendedFit = Fit<ExtModel, Unknown>;

/// Fits `unknowns` of `start` to `data`: identifiability analysis of the Jacobian at the start
/// (unknowns listed first are preferred; see [`analyse`]), then Levenberg-Marquardt on the
/// identifiable ones. `skip_analysis` fits all of them as given (for cross-validation refits that
/// reuse an earlier analysis; the solver still drops numerically null directions).
///
/// On many poses ([`uses_normal`]) the analysis, the solver and the sigmas work on normal
/// equations accumulated pose by pose ([`ExtModel::normal`]; the analysis and the sigmas on the
/// square root of `J^T J`, which has the tall Jacobian's column norms and singular values):
/// memory `O(p^2)`. Otherwise on the tall Jacobian (QR).
pub fn fit(
    start: &ExtModel,
    data: &MeasuredSet,
    unknowns: &[Unknown],
    lm: &LmConfig,
    rtol: f64,
    skip_analysis: bool,
) -> Result<Fit<ExtModel, Unknown>, CalibError> {
    if data.is_empty() {
        return Err(CalibError::NoPoses);
    }
    let normal = uses_normal(data, rtol);
    // the normal equations of the fitted unknowns at the start, when the analysis built them
    let mut eq0 = None;
    let split = if skip_analysis {
        Split {
            fitted: unknowns.to_vec(),
            fixed: Vec::new(),
            unidentifiable: Vec::new(),
            rank: unknowns.len(),
        }
    } else if normal {
        let full = start.normal(data, unknowns)?;
        let id = analyse(&full.jacobian_root(), rtol);
        eq0 = Some(full.select(&id.kept));
        split_of(start, unknowns, &id)
    } else {
        let (jac0, _) = start.stacked(data, unknowns)?;
        split_of(start, unknowns, &analyse(&jac0, rtol))
    };
    if split.fitted.is_empty() {
        let rss = start.errors(data)?.iter().map(|e| e.norm_squared()).sum();
        return Ok(Fit::unfitted(start.clone(), split, rss, data.n_residuals()));
    }
    let freed = Freed::new(start.clone(), split.fitted.clone());
    let x0 = freed.values();
    let fit = if normal {
        let mut problem = ExtNormal { freed, data };
        let rep = match eq0 {
            Some(eq) => solve_normal_from(&mut problem, x0, eq, lm),
            None => solve_normal(&mut problem, x0, lm),
        }
        .map_err(CalibError::from_lm)?;
        fit_at_normal(split, problem.freed, &rep, rtol)?
    } else {
        solve_split(split, ExtModel::problem(freed, data), x0, lm, rtol)?
    };
    Ok(fit.map_model(|f| f.state))
}

/// The state [`fit`] with `skip_analysis` reaches, without the sigmas and condition number of
/// the result (the same solver from the same start, so the same values): for the refits of a
/// cross-validation, which use only the fitted model.
pub fn fit_values(
    start: &ExtModel,
    data: &MeasuredSet,
    unknowns: &[Unknown],
    lm: &LmConfig,
    rtol: f64,
) -> Result<ExtModel, CalibError> {
    if data.is_empty() || unknowns.is_empty() {
        return fit(start, data, unknowns, lm, rtol, true).map(|f| f.model);
    }
    let freed = Freed::new(start.clone(), unknowns.to_vec());
    let x0 = freed.values();
    if uses_normal(data, rtol) {
        let mut problem = ExtNormal { freed, data };
        let rep = solve_normal(&mut problem, x0, lm).map_err(CalibError::from_lm)?;
        problem.freed.set(&rep.x)?;
        return Ok(problem.freed.state);
    }
    Ok(solve_values(ExtModel::problem(freed, data), x0, lm)?.state)
}

/// `unknowns` split by the analysis `id` of their columns.
fn split_of(start: &ExtModel, unknowns: &[Unknown], id: &Identifiability) -> Split<Unknown> {
    let names: Vec<String> = unknowns.iter().map(|u| u.name(&start.model)).collect();
    let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
    Split::of(unknowns, &name_refs, id)
}
