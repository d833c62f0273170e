//! Calibration from **partial** measurements: each measurement is the projection `d . P` of the
//! tool point on a known unit direction `d` (the low-cost rig of thesis 5.5.2 measures the
//! out-of-plane component with the pencil's potentiometer and the in-plane component across the
//! path with the trace, never the component along the path; see [`crate::fusion`]).
//!
//! Residual of one measurement: `r = d . p_model(q) - value`, with the model's parameter
//! Jacobian projected onto `d` (`d^T J`). The calibration rejects outliers (residuals beyond
//! five robust sigmas, refitted) and inflates the parameter sigmas for the serial correlation of
//! the residuals along the path ([`fit_projected_robust`], [`autocorrelation_time`]). Identifiability is decided on this stacked projected
//! Jacobian by [`super::identifiability::analyse`]: a planar path seen through two components
//! constrains fewer parameter combinations than full 3-D positions, and the unidentifiable ones
//! are reported and kept nominal.
//!
//! # Error statistics with partial measurements
//! The error of a sample is the **measured part** of the error vector,
//! `e = sum_d (value_d - d . p_model) d` (for a fused sample `dev_u u + dev_n n`), so in the
//! `calibrate --json` stats `|dP|` is `sqrt(dev_u^2 + dev_n^2)` (the along-path error is not in
//! it), and `mean_abs_x/y/z` are the R components of `e`.

use nalgebra::{DMatrix, Vector3};

use super::calibrate::{fit_report, resolve_selection, CalibrateOptions};
use super::error::CalibError;
use super::fit::{fit_problem, Fit};
use super::lm::LmConfig;
use super::measured::MeasuredSet;
use super::problem::{param_problem, ModelProblem, Rows, Unknowns};
use super::report::CalibrateReport;
use super::samples::FusedSample;
use super::stats;
use crate::model::{Model, ModelError, Tilt};

/// How the model is evaluated at the samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SampleTilt {
    /// Rigid chain.
    #[default]
    Off,
    /// Declared tilting from the static (gravity) moments.
    Static,
    /// Declared tilting from the moments in motion: the static moments of the model evaluated
    /// plus the set's inertial moments ([`MeasuredSet::with_inertial_moments`]; static only
    /// where the set has none).
    Dynamic,
}

impl SampleTilt {
    /// The tilt of pose `k` of `data`.
    pub fn at(self, data: &MeasuredSet, k: usize) -> Tilt<'_> {
        match self {
            SampleTilt::Off => Tilt::Off,
            SampleTilt::Static => Tilt::Static,
            SampleTilt::Dynamic => data.moments(k).map_or(Tilt::Static, Tilt::StaticPlus),
        }
    }
}

/// `f(k, p)` at every pose `k` with the model's tool point `p` (mm) there.
fn at_poses<T>(
    model: &Model,
    data: &MeasuredSet,
    mode: SampleTilt,
    f: impl Fn(usize, &Vector3<f64>) -> T,
) -> Result<Vec<T>, ModelError> {
    data.poses
        .q_deg
        .iter()
        .enumerate()
        .map(|(k, q)| Ok(f(k, &model.position_mm(q, mode.at(data, k))?)))
        .collect()
}

/// The measured part of the error, `sum_d (d . (measured - p_model)) d`, of every pose (mm).
pub fn measured_errors(
    model: &Model,
    data: &MeasuredSet,
    tilt: SampleTilt,
) -> Result<Vec<Vector3<f64>>, ModelError> {
    at_poses(model, data, tilt, |k, p| data.error_mm(k, p))
}

/// The stacked projected Jacobian (one row per measured component, [`MeasuredSet::jacobian_rows`])
/// wrt `cols`.
pub fn projected_jacobian(
    model: &Model,
    data: &MeasuredSet,
    cols: &[usize],
    tilt: SampleTilt,
) -> Result<DMatrix<f64>, ModelError> {
    let mut jac = DMatrix::zeros(data.n_residuals(), cols.len());
    let mut row = 0;
    for (k, q) in data.poses.q_deg.iter().enumerate() {
        let (_, j) = model.param_jacobian(q, tilt.at(data, k), cols)?;
        let j = DMatrix::from_column_slice(3, cols.len(), j.as_slice());
        row = data.put_jacobian_rows(k, &j, row, &mut jac);
    }
    Ok(jac)
}

/// The identification on projected measurements as a least-squares problem
/// ([`param_problem`]): residuals `d . (p_model - measured)` (mm, [`MeasuredSet::residual`]).
pub fn projected_problem<'a>(
    model: &Model,
    data: &'a MeasuredSet,
    cols: Vec<usize>,
    tilt: SampleTilt,
) -> ModelProblem<Unknowns, impl Rows<Unknowns> + 'a> {
    param_problem(model, cols, data.n_residuals(), move |m, cols, r, jac| {
        for (ri, v) in r.iter_mut().zip(residuals(m, data, tilt)?) {
            *ri = v;
        }
        if let Some(jac) = jac {
            jac.copy_from(&projected_jacobian(m, data, cols, tilt)?);
        }
        Ok(())
    })
}

/// Identifies the parameters `selection` of `start` from projected measurements
/// ([`super::fit::fit_problem`] on [`projected_problem`]: identifiability at the start, LM on
/// the identifiable parameters, sigmas and condition number at the solution).
pub fn fit_projected(
    start: &Model,
    data: &MeasuredSet,
    selection: &[usize],
    tilt: SampleTilt,
    lm: &LmConfig,
    rtol: f64,
) -> Result<Fit, CalibError> {
    if data.is_empty() {
        return Err(CalibError::NoPoses);
    }
    let jac0 = projected_jacobian(start, data, selection, tilt)?;
    fit_problem(
        start,
        selection,
        &jac0,
        |cols| projected_problem(start, data, cols, tilt),
        lm,
        rtol,
        None,
    )
}

/// Residuals `d . (p_model - measured)` of every measured component (mm), pose by pose.
pub fn residuals(
    model: &Model,
    data: &MeasuredSet,
    tilt: SampleTilt,
) -> Result<Vec<f64>, ModelError> {
    Ok(at_poses(model, data, tilt, |k, p| data.residual(k, p))?
        .into_iter()
        .flatten()
        .collect())
}

/// Integrated autocorrelation time ([`stats::autocorrelation_time`]) of the residuals, each
/// measurement slot (the first, second, ... projection of a sample: across the path, out of
/// plane) taken as a series in sample order. The largest over the slots; at least 1. Residuals of a traced
/// path are serially correlated (the tracer's error and unmodelled effects vary slowly along
/// the path), so `sqrt` of this inflates the white-noise parameter sigmas.
pub fn autocorrelation_time(data: &MeasuredSet, r: &[f64]) -> f64 {
    let slot_of: Vec<usize> = (0..data.len()).flat_map(|k| 0..data.rows(k)).collect();
    let slots = slot_of.iter().copied().max().map_or(0, |m| m + 1);
    (0..slots)
        .map(|slot| {
            let series: Vec<f64> = r
                .iter()
                .zip(&slot_of)
                .filter(|(_, &s)| s == slot)
                .map(|(v, _)| *v)
                .collect();
            stats::autocorrelation_time(&series)
        })
        .fold(1.0, f64::max)
}

/// Default outlier threshold of [`fit_projected_robust`], in robust standard deviations: the
/// gross-error rule's.
pub use super::outliers::OUTLIER_SIGMAS;

/// A fit with outlier rejection: after a fit (`fit_on`, e.g. [`fit_projected`] from a start
/// model), measurements of `data` whose residual (evaluated with `tilt`) exceeds `k` robust
/// standard deviations (`1.4826 * median |r|`) are left out and the fit is repeated from the
/// start, until no further measurement is rejected (at most 3 passes) or fewer than `min_kept`
/// would be left (the number of selected unknowns). Such outliers are expected with the declared
/// tilting law: where a joint torque is near zero its sign, hence the backlash side, can differ
/// between the arm and the model for a sample or two. The sigmas of the returned fit are inflated
/// by `sqrt` of the residuals' [`autocorrelation_time`]. Returns the fit and the number of
/// measurements left out.
pub fn fit_projected_robust(
    data: &MeasuredSet,
    tilt: SampleTilt,
    k: f64,
    min_kept: usize,
    fit_on: impl Fn(&MeasuredSet) -> Result<Fit, CalibError>,
) -> Result<(Fit, usize), CalibError> {
    let mut kept = data.clone();
    let mut n_kept = data.n_residuals();
    let mut fit = fit_on(&kept)?;
    for _ in 0..3 {
        let r = residuals(&fit.model, data, tilt)?;
        let sigma = stats::robust_sigma(r.iter().copied());
        let keep: Vec<bool> = r.iter().map(|ri| ri.abs() <= k * sigma).collect();
        let n = keep.iter().filter(|&&x| x).count();
        if n == n_kept || n < min_kept {
            break;
        }
        kept = data.keep_components(&keep);
        n_kept = n;
        fit = fit_on(&kept)?;
    }
    let tau = autocorrelation_time(&kept, &residuals(&fit.model, &kept, tilt)?);
    for s in &mut fit.sigma {
        *s *= tau.sqrt();
    }
    Ok((fit, data.n_residuals() - n_kept))
}

/// Extra passes of [`calibrate_projected`] with `SampleTilt::Dynamic`, each recomputing the
/// moments in motion on the model fitted last.
pub const DYNAMIC_PASSES: usize = 2;

/// Result of [`calibrate_projected`].
#[derive(Debug, Clone)]
pub(super) struct ProjectedOutcome {
    /// The calibrated model.
    pub model: Model,
    /// How the calibrated model is evaluated.
    pub tilt: SampleTilt,
    /// The `calibrate --json` document (stats over the measured components).
    pub report: CalibrateReport,
    /// Measured error vectors per sample: nominal (rigid), standard fit (rigid), chosen method.
    pub errors: [Vec<Vector3<f64>>; 3],
    /// Measurements left out of the chosen fit as outliers ([`fit_projected_robust`]).
    pub rejected: usize,
}

/// `rigctl calibrate --samples`: the standard (rigid) identification, and the chosen one with
/// `tilt` (`Static` or `Dynamic` for the method `tilting`; `Off` repeats the standard one), both
/// with outlier rejection ([`fit_projected_robust`]; the statistics cover every sample). With
/// `Dynamic` the moments in motion are recomputed on the fitted model and the fit repeated
/// ([`DYNAMIC_PASSES`]); `data`'s own moments (e.g. of the nominal model) start it.
/// `opts.method` names the method in the report; the influence method needs full positions and
/// is treated as `standard`.
pub(super) fn calibrate_projected(
    nominal: &Model,
    data: &MeasuredSet,
    tilt: SampleTilt,
    opts: &CalibrateOptions,
) -> Result<ProjectedOutcome, CalibError> {
    let selection = resolve_selection(nominal, opts)?;
    let robust = |d: &MeasuredSet, t: SampleTilt| {
        let fit_on =
            |kept: &MeasuredSet| fit_projected(nominal, kept, &selection, t, &opts.lm, opts.rtol);
        fit_projected_robust(d, t, OUTLIER_SIGMAS, selection.len(), fit_on)
    };
    let standard = robust(data, SampleTilt::Off)?;
    let tilt = if nominal.has_tilt() {
        tilt
    } else {
        SampleTilt::Off
    };
    let mut moved = data.clone();
    let (chosen, rejected) = match tilt {
        SampleTilt::Off => standard.clone(),
        SampleTilt::Static => robust(data, tilt)?,
        SampleTilt::Dynamic => {
            // the moments depend on the chain: recompute them on the fitted model and refit
            // (the arm's moments are those of its true chain, not of the nominal one)
            let mut fit = robust(data, tilt)?;
            for _ in 0..DYNAMIC_PASSES {
                moved = moved.with_inertial_moments(&fit.0.model)?;
                fit = robust(&moved, tilt)?;
            }
            fit
        }
    };
    let standard = standard.0;
    let errors = [
        measured_errors(nominal, data, SampleTilt::Off)?,
        measured_errors(&standard.model, data, SampleTilt::Off)?,
        measured_errors(&chosen.model, &moved, tilt)?,
    ];
    let report = fit_report(
        &chosen,
        &selection,
        if tilt == SampleTilt::Off {
            "standard"
        } else {
            "tilting"
        },
        &errors,
        None,
        tilt != SampleTilt::Off,
    );
    Ok(ProjectedOutcome {
        model: chosen.model,
        tilt,
        report,
        errors,
        rejected,
    })
}

/// Per-sample measured errors before calibration, after the standard one and after the chosen
/// method, as CSV (for plots, thesis fig. 5.12 style):
/// `t,q1..qN,dev_u_before,dev_n_before,dp_before,dev_u_after,dev_n_after,dp_after,dev_u_standard,dev_n_standard,dp_standard`
/// (mm; `dev_*` = measured minus model along `u` / `n`, `dp` = `sqrt(dev_u^2 + dev_n^2)`;
/// `errors` is [`ProjectedOutcome::errors`]: nominal, standard, chosen).
pub fn errors_csv(samples: &[FusedSample], errors: &[Vec<Vector3<f64>>; 3]) -> String {
    use std::fmt::Write as _;
    let nj = samples.first().map_or(0, |s| s.q_deg.len());
    let mut out = String::from("t");
    for j in 1..=nj {
        let _ = write!(out, ",q{j}");
    }
    out.push_str(",dev_u_before,dev_n_before,dp_before,dev_u_after,dev_n_after,dp_after");
    out.push_str(",dev_u_standard,dev_n_standard,dp_standard\n");
    for (k, s) in samples.iter().enumerate() {
        let _ = write!(out, "{}", s.t_s);
        for q in &s.q_deg {
            let _ = write!(out, ",{q}");
        }
        for set in [0, 2, 1] {
            let e = errors[set].get(k).copied().unwrap_or_else(Vector3::zeros);
            let (u, n) = (s.u.dot(&e), s.n.dot(&e));
            let _ = write!(out, ",{u:.6},{n:.6},{:.6}", u.hypot(n));
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::katana450;

    /// Projections of a truth model's points on two fixed directions recover a parameter that
    /// moves the points across them, and the projected Jacobian matches finite differences.
    #[test]
    fn projected_fit_recovers_an_offset() {
        let nominal = katana450(330.0).unwrap();
        let mut truth = nominal.clone();
        truth.set_param("dth2", 0.05).unwrap();
        truth.set_param("dth3", -0.03).unwrap();
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let (u, n) = (Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, h, h));
        let mut data = MeasuredSet::default();
        let mut t_s = Vec::new();
        let mut directions = Vec::new();
        for k in 0..30 {
            let q = vec![-90.0 + k as f64, 60.0 + 0.5 * k as f64, -60.0, 10.0, 90.0];
            data.poses
                .xyz_mm
                .push(truth.position_mm(&q, Tilt::Off).unwrap());
            data.poses.q_deg.push(q);
            t_s.push(k as f64);
            directions.push(vec![u, n]);
        }
        data.t_s = Some(t_s);
        data.directions = Some(directions);
        let cols = vec![
            nominal.param_index("dth2").unwrap(),
            nominal.param_index("dth3").unwrap(),
        ];
        let jac = projected_jacobian(&nominal, &data, &cols, SampleTilt::Off).unwrap();
        let eps = 1e-6;
        for (c, &col) in cols.iter().enumerate() {
            let mut m = nominal.clone();
            m.set_param_at(col, eps).unwrap();
            for i in (0..data.n_residuals()).step_by(7) {
                let (k, d) = (i / 2, [u, n][i % 2]);
                let q = &data.poses.q_deg[k];
                let fd = d.dot(
                    &(m.position_mm(q, Tilt::Off).unwrap()
                        - nominal.position_mm(q, Tilt::Off).unwrap()),
                ) / eps;
                assert!(
                    (fd - jac[(i, c)]).abs() < 1e-4 * (1.0 + fd.abs()),
                    "{fd} {}",
                    jac[(i, c)]
                );
            }
        }
        let fit = fit_projected(
            &nominal,
            &data,
            &cols,
            SampleTilt::Off,
            &LmConfig::default(),
            1e-4,
        )
        .unwrap();
        assert!((fit.model.param("dth2").unwrap() - 0.05).abs() < 1e-8);
        assert!((fit.model.param("dth3").unwrap() + 0.03).abs() < 1e-8);
        let e = measured_errors(&fit.model, &data, SampleTilt::Off).unwrap();
        assert!(e.iter().all(|v| v.norm() < 1e-8));
    }
}
