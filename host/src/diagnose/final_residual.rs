//! What the final fit leaves: its noise level and the verdict against the floor, the pairs the
//! poses cannot separate, the probe of the residual for what no candidate describes, and whether
//! the residual is structured.

use super::decide::{self, Selection};
use super::effect_reports::mean_norm;
use super::extended::{ExtModel, Unknown, Values};
use super::report::{EffectReport, NoiseReport, Unexplained};
use super::residual::{self, explain_with};
use super::{alias, candidates, floor, probe, stat, verdict, DiagnoseError, DiagnoseOptions};
use crate::calib::fit::Fit;
use crate::calib::MeasuredSet;
use crate::model::Model;
use nalgebra::Vector3;

/// Smallest share of the final residual a regressor must explain to call it structured.
pub const STRUCTURE_MIN_R2: f64 = 0.05;
/// Significance (after Bonferroni correction over the regressors) of residual structure.
pub const STRUCTURE_ALPHA: f64 = 1e-3;

/// The residual's noise level, its serial correlation and the verdict against the floor.
pub(super) fn judge_floor(
    last: &Fit<ExtModel, Unknown>,
    cal: &MeasuredSet,
    val: &MeasuredSet,
    final_val: &[Vector3<f64>],
    instrument_mm: Option<f64>,
    repeat: Option<(f64, usize)>,
) -> Result<(NoiseReport, f64, floor::FloorReport), DiagnoseError> {
    let dof = last.n_residuals.saturating_sub(last.fitted.len()).max(1);
    let sigma = (last.rss_mm2 / dof as f64).sqrt();
    let noise = NoiseReport {
        sigma_mm: sigma,
        expected_mean_mm: stat::expected_mean_norm_dims(sigma, cal.measured_dims()),
    };
    let tau = decide::serial_tau(&last.model, cal)?;
    let val_dims: usize = (0..val.len()).map(|k| val.rows(k)).sum();
    let floor = floor::judge(
        &floor::FinalResidual {
            rss_mm2: last.rss_mm2,
            n_residuals: last.n_residuals,
            n_params: last.fitted.len(),
            tau,
            n_poses: cal.len(),
            val_ss_mm2: final_val.iter().map(|e| e.norm_squared()).sum(),
            val_residuals: val_dims,
        },
        instrument_mm,
        repeat,
    );
    Ok((noise, tau, floor))
}

/// The pairs the poses cannot separate, ranked, with the accepted effects' evidence told which
/// candidates they may stand in for.
pub(super) fn aliased_pairs(
    selection: &decide::Selection,
    requested: &[Unknown],
    cal: &MeasuredSet,
    effects: &mut [EffectReport],
) -> Result<Vec<alias::AliasReport>, DiagnoseError> {
    let last = &selection.last;
    let accepted: Vec<candidates::Candidate> = selection
        .steps
        .iter()
        .map(|s| s.trial.candidate.clone())
        .collect();
    let others = candidates::library(&last.model, &selection.requested, cal);
    let mut aliased = alias::aliased(last, requested, &accepted, &others, cal)?;
    let tested: Vec<String> = selection
        .last_trials
        .iter()
        .map(|t| t.candidate.id.clone())
        .chain(
            selection
                .steps
                .iter()
                .flat_map(|s| s.equivalent.iter().cloned()),
        )
        .collect();
    alias::rank_pairs(&mut aliased, &tested);
    for e in effects.iter_mut() {
        let stand_in: Vec<&str> = aliased
            .iter()
            .filter(|a| a.a == e.id && a.kind != "declared")
            .map(|a| a.b.as_str())
            .collect();
        if !stand_in.is_empty() {
            e.evidence.push_str(&format!(
                "; not separable on these poses from {}: its value may be a stand-in",
                stand_in.join(", ")
            ));
        }
    }
    Ok(aliased)
}

/// The probe of the final residual for what no candidate describes, with the physical
/// cross-validation and the number of parameters the poses support.
pub(super) fn probe_residual(
    model: &Model,
    last: &Fit<ExtModel, Unknown>,
    cal: &MeasuredSet,
    final_cal: &[Vector3<f64>],
    jac: &[nalgebra::DMatrix<f64>],
    floor: &floor::FloorReport,
    opts: &DiagnoseOptions,
) -> Result<(probe::ProbeResult, probe::ProbeConfig), DiagnoseError> {
    let cfg = &opts.decide;
    // an independent floor (instrument, repeatability) also sets the smallest term worth naming
    let known_floor_mm = match floor.used.as_str() {
        "instrument" => floor.instrument_mm,
        "repeatability" => floor.repeatability_mm,
        _ => None,
    };
    let probe_cfg = probe::ProbeConfig {
        folds: cfg.folds,
        seed: cfg.seed,
        floor_mm: opts.probe.floor_mm.or(known_floor_mm),
        ..opts.probe.clone()
    };
    let start = ExtModel::new(model.clone());
    let departure: Vec<f64> = last
        .fitted
        .iter()
        .map(|&u| last.model.value(u) - start.value(u))
        .collect();
    let probe = probe::probe_dataset_with(cal, final_cal, jac, &departure, &probe_cfg);
    Ok((probe, probe_cfg))
}

/// The final residual regressed on every regressor group: structured when the strongest explains
/// at least [`STRUCTURE_MIN_R2`] of it with a Bonferroni-corrected p-value below
/// [`STRUCTURE_ALPHA`].
pub(super) fn unexplained(
    cal: &[Vector3<f64>],
    val: &[Vector3<f64>],
    regs: &[residual::Regressor],
    noise: &NoiseReport,
    sel: &Selection,
    (dims, tau): (usize, f64),
) -> Unexplained {
    let n_tests = regs.len().max(1) as f64;
    let best = regs
        .iter()
        .map(|r| explain_with(cal, r, dims, tau))
        .max_by(|a, b| a.r2.total_cmp(&b.r2));
    let val_mean = mean_norm(val);
    let ratio = if noise.expected_mean_mm > 0.0 {
        val_mean / noise.expected_mean_mm
    } else {
        f64::NAN
    };
    let mut note = format!(
        "noise estimated from the final calibration residual: {:.4} mm per coordinate (mean error from noise alone {:.4} mm); \
         validation mean {:.4} mm = {:.2} x that",
        noise.sigma_mm, noise.expected_mean_mm, val_mean, ratio
    );
    let structured = match &best {
        Some(b) if b.r2 >= STRUCTURE_MIN_R2 && b.p_value * n_tests < STRUCTURE_ALPHA => {
            note.push_str(&format!(
                "; the remaining residual is structured: {} explains {:.0} % of it (Bonferroni p = {:.1e}) but no candidate effect passed the tests",
                b.regressor,
                100.0 * b.r2,
                (b.p_value * n_tests).min(1.0)
            ));
            if let Some(t) = sel.last_trials.first() {
                note.push_str(&format!(
                    " (best refitted: {}: {})",
                    t.candidate.id, t.reason
                ));
            }
            true
        }
        Some(b) => {
            note.push_str(&format!(
                "; no regressor explains a significant share of the remaining residual (strongest: {}, {:.1} %)",
                b.regressor,
                100.0 * b.r2
            ));
            false
        }
        None => false,
    };
    Unexplained {
        structured,
        note,
        depends_on: Vec::new(),
        explainable_share: 0.0,
        depends_on_shares: Vec::new(),
    }
}

/// The verdict on the final fit `last` (calibration and held-out residuals against the floor and
/// the probe): `cal_jac` are the fitted unknowns' Jacobians at the calibration poses.
pub(super) fn judge_verdict(
    last: &Fit<ExtModel, Unknown>,
    (cal, val): (&MeasuredSet, &MeasuredSet),
    cal_jac: &[nalgebra::DMatrix<f64>],
    final_val: &[Vector3<f64>],
    (floor, probe): (&floor::FloorReport, &probe::ProbeResult),
    tau: f64,
) -> Result<verdict::Verdict, DiagnoseError> {
    // the held-out Jacobians of the fitted unknowns are the first columns of those of the
    // unknowns a change between the sets may move (`change_unknowns` starts with them)
    let change = verdict::change_unknowns(&last.model.model, &last.fitted);
    let val_jac_change = probe::jacobians(&last.model, val, &change)?;
    let val_jac: Vec<nalgebra::DMatrix<f64>> = val_jac_change
        .iter()
        .map(|j| j.columns(0, last.fitted.len()).into_owned())
        .collect();
    Ok(verdict::judge(
        floor,
        probe,
        verdict::Counts {
            n_residuals: last.n_residuals,
            n_params: last.fitted.len(),
            tau,
            val_residuals: (0..val.len()).map(|k| val.rows(k)).sum(),
            val_inflation: verdict::prediction_inflation(cal, cal_jac, val, &val_jac),
            val_after_change: verdict::after_parameter_change(val, final_val, &val_jac_change),
        },
    ))
}
