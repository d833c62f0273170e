//! Polish of a candidate's refit across the sign steps of the joint-tilting law.
//!
//! The declared tilting (MODEL.md eq. 5.16-5.19) has terms `sign(eta) C` and `sign(eta_z) b`:
//! the prediction jumps where a pose's static joint moment changes sign. A candidate that moves
//! the moments (a base tilt gives joint 1 a gravity torque about its axis, switching its backlash
//! on with pose-dependent signs) makes the least-squares objective piecewise smooth. The
//! Levenberg-Marquardt solver treats the steps as flat (its Jacobian has no term for them) and
//! stops at a step edge, short of the minimum.
//!
//! Detection: the sign pattern of the moments ([`ExtModel::moment_signs`]) differs between the
//! fit before the candidate and its refit, so the refit crossed steps ([`crossed_steps`]).
//!
//! Polish ([`polish`]): a derivative-free Nelder-Mead search over the candidate's fitted
//! unknowns, each trial point scored by its profile residual sum of squares (every other fitted
//! unknown re-fitted by Levenberg-Marquardt, warm-started from the best fit so far), then one
//! Levenberg-Marquardt pass on all unknowns from the best point, which only lowers the RSS and
//! gives the parameter uncertainties. Nelder-Mead uses only comparisons of RSS values, so the
//! steps do not stop it; it ends when the simplex has shrunk below a tenth of the initial step
//! and the RSS values of its vertices agree to [`RSS_RTOL`], or after
//! [`super::decide::DecideConfig::polish_max_evals`] trial points.

use super::compress::stacked_or_compressed;
use super::decide::DecideConfig;
use super::extended::{fit, ExtModel, Unknown, Values};
use crate::calib::fit::{Fit, Split};
use crate::calib::CalibError;
use crate::calib::MeasuredSet;
use crate::model::ModelError;

/// Relative agreement of the simplex RSS values at which the search stops.
pub const RSS_RTOL: f64 = 1e-6;
/// Initial simplex step per unknown: this share of the candidate's change from its start value,
/// and at least [`STEP_MIN_SIGMAS`] of its standard deviation.
pub const STEP_SHARE: f64 = 0.1;
/// Smallest initial simplex step, in standard deviations of the unknown.
pub const STEP_MIN_SIGMAS: f64 = 3.0;

/// Smallest predicted decrease (noise variances) that marks a refit as stopped short.
pub const STALL_MIN_DECREASE: f64 = 1.0;

/// Number of sign entries (pose x joint x moment component) that differ between `before` and
/// `after` on `data`; 0 without tilting.
pub fn crossed_steps(
    before: &ExtModel,
    after: &ExtModel,
    data: &MeasuredSet,
) -> Result<usize, ModelError> {
    let a = before.moment_signs(data)?;
    let b = after.moment_signs(data)?;
    Ok(a.iter().zip(&b).filter(|(x, y)| x != y).count())
}

/// The decrease of the RSS that one Gauss-Newton step of `f`'s fitted unknowns predicts from
/// `f`'s solution, in units of the noise variance `RSS / (m - p)`: about 0 where the solver
/// converged to a minimum, large where it stopped at a step edge with the smooth part of the
/// objective still sloping (a change of 1 moves one parameter's confidence region by one
/// standard deviation).
pub fn predicted_decrease(
    f: &Fit<ExtModel, Unknown>,
    data: &MeasuredSet,
    rank_rtol: f64,
) -> Result<f64, ModelError> {
    let m = data.n_residuals();
    let dof = m.saturating_sub(f.fitted.len());
    if f.fitted.is_empty() || dof == 0 || f.rss_mm2 <= 0.0 {
        return Ok(0.0);
    }
    let (mut jac, err) = stacked_or_compressed(&f.model, data, &f.fitted)?;
    for mut c in jac.column_iter_mut() {
        let n = c.norm();
        if n > 0.0 {
            c.unscale_mut(n);
        }
    }
    let svd = jac.svd(true, false);
    let top = svd.singular_values.iter().copied().fold(0.0, f64::max);
    let Some(u) = svd.u else {
        return Ok(0.0);
    };
    let decrease: f64 = svd
        .singular_values
        .iter()
        .enumerate()
        .filter(|(_, s)| **s > rank_rtol * top)
        .map(|(k, _)| u.column(k).dot(&err).powi(2))
        .sum();
    Ok(decrease / (f.rss_mm2 / dof as f64))
}

/// Whether the refit `after` of a candidate (from `before`) stopped at a step edge: it crossed
/// sign steps ([`crossed_steps`]) and the Gauss-Newton step at its solution still predicts a
/// decrease of more than [`STALL_MIN_DECREASE`] noise variances ([`predicted_decrease`]).
pub fn needs_polish(
    before: &ExtModel,
    after: &Fit<ExtModel, Unknown>,
    data: &MeasuredSet,
    rank_rtol: f64,
) -> Result<bool, ModelError> {
    Ok(crossed_steps(before, &after.model, data)? > 0
        && predicted_decrease(after, data, rank_rtol)? > STALL_MIN_DECREASE)
}

/// Profile objective: the candidate unknowns at trial values, the others re-fitted.
struct Profile<'a> {
    data: &'a MeasuredSet,
    cfg: &'a DecideConfig,
    over: Vec<Unknown>,
    others: Vec<Unknown>,
    best: Fit<ExtModel, Unknown>,
}

impl Profile<'_> {
    /// RSS of the profile fit at `x` (infinite when the point cannot be evaluated).
    fn rss(&mut self, x: &[f64]) -> f64 {
        let mut start = self.best.model.clone();
        for (u, v) in self.over.iter().zip(x) {
            if start.set_value(*u, *v).is_err() {
                return f64::INFINITY;
            }
        }
        let f = if self.others.is_empty() {
            start.errors(self.data).ok().map(|e| {
                let rss = e.iter().map(|v| v.norm_squared()).sum();
                let n = self.data.n_residuals();
                Fit::unfitted(start, Split::none(), rss, n)
            })
        } else {
            fit(
                &start,
                self.data,
                &self.others,
                &self.cfg.lm_cv,
                self.cfg.rtol,
                true,
            )
            .ok()
        };
        match f {
            Some(f) if f.rss_mm2.is_finite() => {
                let rss = f.rss_mm2;
                if rss < self.best.rss_mm2 {
                    self.best = f;
                }
                rss
            }
            _ => f64::INFINITY,
        }
    }
}

/// Nelder-Mead minimisation of `f` from `x0` with initial steps `step` (standard coefficients:
/// reflection 1, expansion 2, contraction 1/2, shrink 1/2). Stops after `max_evals` evaluations
/// or when the simplex is smaller than `size_tol` steps and its values agree to `f_rtol`;
/// returns the number of evaluations.
fn nelder_mead(
    f: &mut dyn FnMut(&[f64]) -> f64,
    x0: &[f64],
    step: &[f64],
    max_evals: usize,
    size_tol: f64,
    f_rtol: f64,
) -> usize {
    let n = x0.len();
    let mut evals = 0usize;
    let mut eval = |x: &[f64], evals: &mut usize| {
        *evals += 1;
        f(x)
    };
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(n + 1);
    simplex.push((x0.to_vec(), eval(x0, &mut evals)));
    for k in 0..n {
        let mut x = x0.to_vec();
        x[k] += step[k];
        let fx = eval(&x, &mut evals);
        simplex.push((x, fx));
    }
    let lerp = |a: &[f64], b: &[f64], t: f64| -> Vec<f64> {
        a.iter().zip(b).map(|(p, q)| p + t * (q - p)).collect()
    };
    while evals < max_evals {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (f_lo, f_hi) = (simplex[0].1, simplex[n].1);
        let size = simplex[1..]
            .iter()
            .map(|(x, _)| {
                x.iter()
                    .zip(&simplex[0].0)
                    .zip(step)
                    .map(|((a, b), s)| ((a - b) / s).abs())
                    .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max);
        if size < size_tol && (f_hi - f_lo) <= f_rtol * f_lo.abs() {
            break;
        }
        let centroid: Vec<f64> = (0..n)
            .map(|k| simplex[..n].iter().map(|(x, _)| x[k]).sum::<f64>() / n as f64)
            .collect();
        let worst = simplex[n].0.clone();
        let xr = lerp(&centroid, &worst, -1.0);
        let fr = eval(&xr, &mut evals);
        if fr < f_lo {
            let xe = lerp(&centroid, &worst, -2.0);
            let fe = eval(&xe, &mut evals);
            simplex[n] = if fe < fr { (xe, fe) } else { (xr, fr) };
            continue;
        }
        if fr < simplex[n - 1].1 {
            simplex[n] = (xr, fr);
            continue;
        }
        // Outside contraction when the reflection beat the worst vertex, inside otherwise.
        let xc = if fr < f_hi {
            lerp(&centroid, &xr, 0.5)
        } else {
            lerp(&centroid, &worst, 0.5)
        };
        let fc = eval(&xc, &mut evals);
        if fc < fr.min(f_hi) {
            simplex[n] = (xc, fc);
            continue;
        }
        let best = simplex[0].0.clone();
        for v in simplex.iter_mut().skip(1) {
            let x = lerp(&best, &v.0, 0.5);
            let fx = eval(&x, &mut evals);
            *v = (x, fx);
        }
    }
    evals
}

/// Polishes `refit` (the refit of a candidate whose unknowns are `over`, started from `start`)
/// across the sign steps of the tilting law; see the module documentation. Returns the refit
/// unchanged when none of `over` was fitted; never a fit with a higher RSS.
pub fn polish(
    refit: Fit<ExtModel, Unknown>,
    start: &ExtModel,
    over: &[Unknown],
    data: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<Fit<ExtModel, Unknown>, CalibError> {
    let over: Vec<Unknown> = over
        .iter()
        .copied()
        .filter(|u| refit.fitted.contains(u))
        .collect();
    if over.is_empty() || cfg.polish_max_evals == 0 {
        return Ok(refit);
    }
    let others: Vec<Unknown> = refit
        .fitted
        .iter()
        .copied()
        .filter(|u| !over.contains(u))
        .collect();
    let x0: Vec<f64> = over.iter().map(|u| refit.model.value(*u)).collect();
    let step: Vec<f64> = over
        .iter()
        .zip(&x0)
        .map(|(u, x)| {
            let s = (STEP_SHARE * (x - start.value(*u)).abs())
                .max(STEP_MIN_SIGMAS * refit.sigma_of(*u));
            if s.is_finite() && s > 0.0 {
                s
            } else {
                STEP_SHARE * x.abs().max(1e-6)
            }
        })
        .collect();
    let mut profile = Profile {
        data,
        cfg,
        over: over.clone(),
        others,
        best: refit.clone(),
    };
    nelder_mead(
        &mut |x| profile.rss(x),
        &x0,
        &step,
        cfg.polish_max_evals,
        0.1,
        RSS_RTOL,
    );
    if profile.best.rss_mm2 >= refit.rss_mm2 {
        return Ok(refit);
    }
    let last = fit(
        &profile.best.model,
        data,
        &refit.fitted,
        &cfg.lm,
        cfg.rtol,
        true,
    )?;
    if last.rss_mm2 > refit.rss_mm2 {
        return Ok(refit);
    }
    Ok(Fit {
        fixed: refit.fixed,
        unidentifiable: refit.unidentifiable,
        ..last
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::measured::PosePoints;
    use crate::model::katana450;
    use crate::sim::simulate::{simulate, SimConfig};

    /// At a converged fit the Gauss-Newton step predicts no decrease; moved off it by 0.01 deg
    /// on a joint offset (about 0.1 mm at the tool, ten times the noise), it predicts many noise
    /// variances.
    #[test]
    fn predicted_decrease_marks_a_fit_stopped_short() {
        let declared = katana450(200.0).expect("preset");
        let out = simulate(&declared, &SimConfig::default()).expect("simulate");
        let data = MeasuredSet {
            poses: PosePoints {
                q_deg: out.cal.iter().map(|p| p.q_deg.clone()).collect(),
                xyz_mm: out.cal.iter().map(|p| p.measured_mm).collect(),
            },
            ..MeasuredSet::default()
        };
        let cfg = DecideConfig::default();
        let (f, _) = crate::diagnose::declared_fit(&declared, &data, &cfg).expect("fit");
        let at_min = predicted_decrease(&f, &data, cfg.rtol).expect("decrease");
        assert!(at_min < 1e-6, "{at_min}");
        let mut off = f.clone();
        let u = f.fitted[0];
        off.model
            .set_value(u, f.model.value(u) + 0.01)
            .expect("finite");
        off.rss_mm2 = off
            .model
            .errors(&data)
            .expect("errors")
            .iter()
            .map(|e| e.norm_squared())
            .sum();
        let moved = predicted_decrease(&off, &data, cfg.rtol).expect("decrease");
        assert!(moved > 10.0, "{moved}");
        assert_eq!(crossed_steps(&f.model, &f.model, &data).expect("signs"), 0);
    }

    /// A function with steps (a staircase on a bowl): Nelder-Mead still reaches the bowl's
    /// bottom cell, which a gradient method started at a tread would not leave.
    #[test]
    fn nelder_mead_crosses_steps() {
        let mut best = (f64::INFINITY, vec![0.0; 2]);
        let mut f = |x: &[f64]| {
            let smooth = (x[0] - 3.0).powi(2) + 2.0 * (x[1] + 1.0).powi(2);
            let steps = (x[0] - 3.0).abs().floor() + (x[1] + 1.0).abs().floor();
            let v = smooth + steps;
            if v < best.0 {
                best = (v, x.to_vec());
            }
            v
        };
        let evals = nelder_mead(&mut f, &[0.0, 0.0], &[0.5, 0.5], 400, 1e-4, 1e-12);
        assert!(evals <= 400, "{evals}");
        assert!(
            (best.1[0] - 3.0).abs() < 1e-2 && (best.1[1] + 1.0).abs() < 1e-2,
            "{best:?}"
        );
    }
}
