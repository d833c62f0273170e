//! Gross errors: the calibration poses a fit flags (fit-and-flag with the declared fit, the
//! selection on the kept poses, the flags re-checked under the final model), and the held-out
//! poses judged by the calibration's scale and the final model's prediction uncertainty at each
//! (FORMATS.md: extrapolation is not a gross error; a pose a model within the fit's uncertainty
//! predicts is kept).

use super::decide::{DecideConfig, Selection};
use super::declared::{trim_outliers, Declared};
use super::extended::ExtendedFit;
use super::select::forward_selection;
use super::{envelope, probe, simplest, verdict, DiagnoseError};
use crate::calib::outliers::{self, OutlierReport};
use crate::calib::problem::norms_mm;
use crate::calib::MeasuredSet;
use crate::model::Model;

/// The selection on the calibration poses that are not gross errors.
pub(super) struct Selected {
    /// The declared fit on the calibration poses kept (gross errors and spikes left out,
    /// [`trim_outliers`]).
    pub declared: Declared,
    /// The selection of effects.
    pub selection: Selection,
    /// Indices (in the whole calibration set) of the poses flagged as gross errors.
    pub flagged: Vec<usize>,
    /// What the gross-error rule says about itself, when anything.
    pub note: Option<String>,
}

/// The selection on `cal_all` less its gross errors (when `gross`): the declared fit flags
/// them, the selection runs on the kept poses, and the flags are re-checked under its final
/// model. The flagged poses may carry the evidence of a missing effect (a step of the declared
/// tilting law, a backlash): the selection on every pose is also run, and when its effects
/// explain some of the flagged poses they are kept.
pub(super) fn select_without_gross(
    model: &Model,
    cal_all: &MeasuredSet,
    cfg: &DecideConfig,
    gross: bool,
) -> Result<Selected, DiagnoseError> {
    let mut flagged: Vec<usize> = Vec::new();
    let mut note = None;
    // the declared fit of trim's last round (on the poses it keeps), reused by the selection
    let mut last_declared: Option<(Vec<usize>, Declared)> = None;
    if gross {
        let t = outliers::trim(cal_all.len(), 3, cfg.floor_mm, |keep| {
            let declared = Declared::on(model, cal_all.subset(keep), 0, cfg)?;
            let norms = norms_mm(&declared.fit.model.errors(cal_all)?);
            last_declared = Some((keep.to_vec(), declared));
            Ok::<_, DiagnoseError>(norms)
        })?;
        flagged = t.flagged;
        note = t.note;
    }
    // the selection on the poses not in `flagged` (gross errors only on unordered poses, so the
    // spike rule of `trim_outliers` leaves them as they are and trim's declared fit serves)
    let run = |flagged: &[usize]| -> Result<Selected, DiagnoseError> {
        let keep = outliers::kept(cal_all.len(), flagged);
        let reused = last_declared
            .as_ref()
            .filter(|(k, d)| *k == keep && !d.cal.is_serial());
        let declared = match reused {
            Some((_, d)) => d.clone(),
            None => trim_outliers(model, &cal_all.subset(&keep), cfg)?,
        };
        let Declared {
            cal,
            fit,
            requested,
            ..
        } = &declared;
        let greedy = forward_selection(fit.clone(), requested, cal, cfg)?;
        let selection = simplest::prefer_simplest(greedy, fit, requested, cal, cfg)?;
        Ok(Selected {
            declared,
            selection,
            flagged: flagged.to_vec(),
            note: None,
        })
    };
    // the flags under the final model of `selection`, the scale from the poses not in `flagged`
    let flags_under = |selection: &Selection,
                       flagged: &[usize]|
     -> Result<Vec<usize>, DiagnoseError> {
        let all = norms_mm(&selection.last.model.errors(cal_all)?);
        let kept_norms: Vec<f64> = outliers::kept(all.len(), flagged)
            .iter()
            .map(|&k| all[k])
            .collect();
        let thr = outliers::threshold_mm(outliers::robust_sigma_mm(&kept_norms, 3), cfg.floor_mm);
        Ok(outliers::flag_set_against(&all, thr).0)
    };
    let mut result = run(&flagged)?;
    if gross && !flagged.is_empty() {
        let with_all = run(&[])?;
        let flags_all = flags_under(&with_all.selection, &[])?;
        if flags_all.len() < flagged.len() && flags_all.iter().all(|k| flagged.contains(k)) {
            flagged = flags_all;
            result = if flagged.is_empty() {
                with_all
            } else {
                run(&flagged)?
            };
        } else {
            let again = flags_under(&result.selection, &flagged)?;
            if again != flagged {
                flagged = again;
                result = run(&flagged)?;
            }
        }
    }
    result.note = note;
    Ok(result)
}

/// The held-out poses after the gross-error judgement, and the reports of it.
pub(super) struct HeldOut {
    /// The held-out poses kept, when some were listed as gross errors (else all of them serve).
    pub kept: Option<MeasuredSet>,
    /// The gross errors of both sets (calibration first).
    pub outliers: Vec<OutlierReport>,
    /// Held-out poses above the threshold that a model within the fit's uncertainty predicts.
    pub within: Vec<OutlierReport>,
}

/// The calibration poses `flagged` (indices in `cal_all`) reported, and the held-out poses
/// `val_all` judged by the scale of the final fit `last` on the kept calibration poses `cal` and
/// its prediction uncertainty at each (`cal_jac`: the fitted unknowns' Jacobians at `cal`).
pub(super) fn judge_held_out(
    last: &ExtendedFit,
    cal: &MeasuredSet,
    flagged: &[usize],
    (cal_all, val_all): (&MeasuredSet, &MeasuredSet),
    cal_jac: &[nalgebra::DMatrix<f64>],
    cfg: &DecideConfig,
) -> Result<HeldOut, DiagnoseError> {
    let sigma = outliers::robust_sigma_mm(&norms_mm(&last.model.errors(cal)?), 3)
        .max(cfg.floor_mm.unwrap_or(0.0));
    let thr = outliers::threshold_mm(sigma, None);
    let all = norms_mm(&last.model.errors(cal_all)?);
    let mut reports = labelled(outliers::reports("cal", flagged, &all, &all, thr), cal_all);
    let vn = norms_mm(&last.model.errors(val_all)?);
    let val_jac = probe::jacobians(&last.model, val_all, &last.fitted)?;
    let sd = held_out_sd_mm(cal, cal_jac, val_all, &val_jac, sigma);
    let (vflag, thresholds) = outliers::flag_held_out(&vn, &sd, sigma);
    // a pose that a model within the fit's uncertainty predicts is not a gross error
    let (vflag, kept) =
        envelope::within_uncertainty(last, cal, cal_jac, val_all, &vflag, &thresholds, sigma)?;
    let within = labelled(envelope::reports(&kept, &vn, &thresholds), val_all);
    reports.extend(labelled(
        outliers::held_out_reports(&vflag, &vn, &vn, &thresholds, &sd),
        val_all,
    ));
    let kept_val = val_all.subset(&outliers::kept(val_all.len(), &vflag));
    Ok(HeldOut {
        kept: (kept_val.len() < val_all.len()).then_some(kept_val),
        outliers: reports,
        within,
    })
}

/// `reports` with the line and id of each pose of `data`.
fn labelled(mut reports: Vec<OutlierReport>, data: &MeasuredSet) -> Vec<OutlierReport> {
    for r in &mut reports {
        r.pose.label(data);
    }
    reports
}

/// One standard deviation per measured component (mm) of the final model's prediction at
/// every held-out pose: the residual scale `sigma_mm` times the root of the pose's prediction
/// variance per component ([`verdict::prediction_variances`]); infinite where a joint lies
/// outside the calibration poses' range ([`outliers::outside_range`]: the fit never saw it).
fn held_out_sd_mm(
    cal: &MeasuredSet,
    cal_jac: &[nalgebra::DMatrix<f64>],
    val: &MeasuredSet,
    val_jac: &[nalgebra::DMatrix<f64>],
    sigma_mm: f64,
) -> Vec<f64> {
    let var = verdict::prediction_variances(cal, cal_jac, val, val_jac)
        .unwrap_or_else(|| vec![0.0; val.len()]);
    let outside = outliers::outside_range(&cal.poses.q_deg, &val.poses.q_deg);
    var.iter()
        .zip(&outside)
        .enumerate()
        .map(|(k, (v, o))| {
            if o.is_empty() {
                sigma_mm * (v.max(0.0) / val.rows(k).max(1) as f64).sqrt()
            } else {
                f64::INFINITY
            }
        })
        .collect()
}
