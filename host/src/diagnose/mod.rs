//! `rigctl diagnose`: fit the declared model, study the residual, add the missing effects the
//! data establish, and report the error before and after each addition (FORMATS.md).
//!
//! | module | holds |
//! |---|---|
//! | [`declared`] | the declared fit every diagnosis starts from; spikes along a traced path left out |
//! | [`spikes`] | the spike rule of a residual along a traced path (running median, robust sigmas) |
//! | [`gross`] | gross errors of the calibration and held-out poses (kept where a model within the fit's uncertainty predicts them) |
//! | [`effect_reports`] | one report per accepted effect and the data of its plot |
//! | [`final_residual`] | the final fit's noise, floor verdict, aliased pairs, probe and structure |
//! | [`extended`] | the model plus non-parameter effects (time drift, compliance); the extended fit |
//! | [`candidates`] | the effect library (FORMATS.md effect ids) and effect-unit parameters |
//! | [`compress`] | the stacked Jacobian of many poses reduced to its triangular factor (bounded memory) |
//! | [`residual`] | regressors, linearised screening, structure tests |
//! | [`decide`] | the decision rule: F-test + BIC + k-fold cross-validation, its settings and tests |
//! | [`select`] | the greedy forward selection in named steps (shortlist, refit, near ties, tests) |
//! | [`simplest`] | a smaller set of effects (single, pair) that does as well as the greedy selection is preferred |
//! | [`parallel`] | deterministic use of both cores for independent fits |
//! | [`polish`] | derivative-free polish of a refit across the sign steps of the tilting law |
//! | [`stat`] | F distribution, BIC, noise statistics |
//! | [`envelope`] | held-out poses a model within the fit's uncertainty predicts (a sign step): kept, not gross errors |
//! | [`floor`] | the independent floor (`--instrument-mm`, repeatability) and its tests |
//! | [`bounds`] | physical bounds on fitted values (a compliance, a mass cannot be negative): held at the bound and refitted |
//! | [`alias`] | pairs of effects/parameters these poses cannot tell apart |
//! | [`ordered`] | a map that keeps its insertion order in JSON |
//! | [`report`] | the `diagnose --json` document and the text table |
//! | [`plots`] | SVG plots of the residual against the regressor that traced each effect |
//! | [`probe`] | a smooth function of the joint angles (and the time) fitted to the final residual under cross-validation: where the unexplained error lives |
//! | [`verdict`] | one verdict from the calibration, cross-validated and held-out residuals: floor, missing effect, overfitting, change between the sets |
//!
//! The measurements are a [`crate::calib::MeasuredSet`] (full positions, fused samples, or both).
//!
//! The starting point is the declared model (MODEL.md) fitted exactly as `calibrate --method
//! tilting`: [`crate::calib::position_fit::fit_parameters`] on [`crate::calib::default_selection`] (the
//! thesis's 12 for the Katana; offsets, twists, lengths and tool point for other models) with
//! the declared tilting when the model has tilting data.
//!
//! **Noise floor.** The measurement noise is estimated from the final fit as
//! `sigma = sqrt(RSS / (m - p))` per coordinate; the mean error that noise alone gives is
//! `sigma sqrt(8/pi)`. **Unexplained**: the final residual is regressed on every regressor
//! group; it is `structured` when the strongest one explains at least
//! [`final_residual::STRUCTURE_MIN_R2`] of it with a Bonferroni-corrected p-value below
//! [`final_residual::STRUCTURE_ALPHA`] — then something systematic remains that no candidate explained.

pub mod alias;
pub mod bounds;
pub mod candidates;
pub mod changes;
pub mod compress;
pub mod decide;
pub mod declared;
pub mod effect_reports;
pub mod envelope;
pub mod extended;
pub mod final_residual;
pub mod floor;
mod gross;
pub mod ordered;
pub mod parallel;
pub mod plots;
pub mod polish;
pub mod probe;
pub mod report;
pub mod residual;
pub mod select;
pub mod simplest;
pub mod spikes;
pub mod stat;
pub mod tree;
pub mod verdict;

use crate::calib::{CalibError, MeasuredSet, Stats};
use crate::error::{Classify, ErrorKind};
use crate::model::{Model, ModelError};
use decide::{DecideConfig, Selection};
pub use declared::{declared_fit, trim_outliers, Declared};
pub use effect_reports::EffectTrace;
use extended::ExtModel;
use final_residual::{aliased_pairs, judge_floor, probe_residual, unexplained};
pub use final_residual::{STRUCTURE_ALPHA, STRUCTURE_MIN_R2};
use report::{DiagnoseReport, SetStats, TrialReport};
use residual::{explain, regressors};
pub use spikes::{OUTLIER_HALF_WINDOW, OUTLIER_SIGMAS};

/// Everything that can stop a diagnosis.
#[derive(Debug, thiserror::Error)]
pub enum DiagnoseError {
    /// The identification failed.
    #[error(transparent)]
    Calib(#[from] CalibError),
    /// The model could not be evaluated.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// Not enough poses to fit and cross-validate.
    #[error("{what}: {n} poses; the diagnosis needs at least {min}")]
    TooFewPoses {
        what: &'static str,
        n: usize,
        min: usize,
    },
}

impl Classify for DiagnoseError {
    fn kind(&self) -> ErrorKind {
        match self {
            DiagnoseError::Calib(e) => e.kind(),
            DiagnoseError::Model(e) => e.kind(),
            DiagnoseError::TooFewPoses { .. } => ErrorKind::BadInput,
        }
    }
}

/// Settings of [`diagnose`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DiagnoseOptions {
    /// Selection rule settings.
    pub decide: DecideConfig,
    /// One-sigma accuracy per coordinate of the measuring instrument (mm), when known
    /// (`--instrument-mm`).
    pub instrument_mm: Option<f64>,
    /// Settings of the probe of the final residual (its folds and seed are the selection's).
    pub probe: probe::ProbeConfig,
    /// Keep every pose: no gross-error rule ([`crate::calib::outliers`]).
    pub keep_outliers: bool,
}

/// Result of [`diagnose`].
#[derive(Debug, Clone)]
pub struct Diagnosis {
    /// The JSON document.
    pub report: DiagnoseReport,
    /// The final extended model.
    pub model: ExtModel,
    /// The selection details.
    pub selection: Selection,
    /// Regressors of the calibration poses.
    pub regressors: Vec<residual::Regressor>,
    /// Per accepted effect, the data of its plot.
    pub traces: Vec<EffectTrace>,
    /// The probe of the final calibration residual.
    pub probe: probe::ProbeResult,
}

/// Said first in `unexplained.note` when the final fit stopped on its iteration budget.
pub const NOT_CONVERGED_NOTE: &str =
    "the final fit did not converge (iteration budget spent while still improving): its values and the verdict are not those of the optimum";

/// Diagnoses `model` on the calibration poses `cal`, reporting held-out numbers on `val`.
pub fn diagnose(
    model: &Model,
    cal: &MeasuredSet,
    val: &MeasuredSet,
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    let cfg = &opts.decide;
    check_sizes(cal, val, cfg)?;
    crate::calib::plausible::check_set(model, cal, "calibration poses")?;
    crate::calib::plausible::check_set(model, val, "held-out poses")?;
    // repeats anywhere (calibration and held-out files) are pooled
    let repeat = floor::repeatability_of_files(&[cal, val]);
    let known_floor = floor::choose_floor(opts.instrument_mm, repeat).1;
    let cfg_owned = DecideConfig {
        floor_mm: known_floor,
        ..cfg.clone()
    };
    let cfg = &cfg_owned;
    let cal_all = cal.clone().with_approach();
    let val_all = val.clone().with_approach();
    let gross = !opts.keep_outliers
        && !cal_all.is_serial()
        && cal_all.len() >= crate::calib::calibrate::MIN_POSES_FOR_OUTLIERS;
    let gross::Selected {
        declared:
            declared::Declared {
                cal,
                spikes_left_out: outliers,
                fit: declared,
                requested,
            },
        mut selection,
        flagged,
        note: outlier_note,
    } = gross::select_without_gross(model, &cal_all, cfg, gross)?;
    let cal = &cal;
    let bound_reports = bounds::enforce(&mut selection, model, cal, cfg);
    // the fitted unknowns' Jacobians at the calibration poses (the held-out judgement and the
    // probe of the final residual)
    let cal_jac = probe::jacobians(&selection.last.model, cal, &selection.last.fitted)?;
    let held = if gross {
        Some(gross::judge_held_out(
            &selection.last,
            cal,
            &flagged,
            (&cal_all, &val_all),
            &cal_jac,
            cfg,
        )?)
    } else {
        None
    };
    let val = held
        .as_ref()
        .and_then(|h| h.kept.as_ref())
        .unwrap_or(&val_all);
    let listed_val = val.len() < val_all.len();
    let declared_cal = declared.model.errors(cal)?;
    let declared_val = declared.model.errors(val)?;
    // every held-out pose, the listed ones included (FORMATS.md)
    let validation_all = |m: &ExtModel| -> Result<Stats, ModelError> {
        Ok(Stats::from_errors(&m.errors(if listed_val {
            &val_all
        } else {
            val
        })?))
    };
    let regs = regressors(&selection.last.model, cal)?;

    let (mut effects, traces) = effect_reports::of_selection(&selection, &regs, cal, val, cfg)?;

    let last = &selection.last;
    let final_cal = last.model.errors(cal)?;
    let final_val = last.model.errors(val)?;
    let (noise, tau, floor) = judge_floor(last, cal, val, &final_val, opts.instrument_mm, repeat)?;
    let mut unexplained = unexplained(
        &final_cal,
        &final_val,
        &regs,
        &noise,
        &selection,
        (cal.measured_dims(), tau),
    );
    let aliased = aliased_pairs(&selection, &requested, cal, &mut effects)?;
    let (probe, probe_cfg) = probe_residual(model, last, cal, &final_cal, &cal_jac, &floor, opts)?;
    let verdict = final_residual::judge_verdict(
        last,
        (cal, val),
        &cal_jac,
        &final_val,
        (&floor, &probe),
        tau,
    )?;
    unexplained.note = format!("{}; {}", verdict.note, unexplained.note);
    if !bound_reports.is_empty() {
        unexplained.note = format!("{}; {}", bounds::sentence(&bound_reports), unexplained.note);
        effect_reports::tell_bounds(&mut effects, &bound_reports);
    }
    if !last.converged {
        unexplained.note = format!("{NOT_CONVERGED_NOTE}; {}", unexplained.note);
    }
    // the calibration residual above the floor (the held-out one alone is a change between
    // the sets or overfitting, not a structure of this residual)
    unexplained.structured |= verdict.kind == "missing_effect";
    unexplained.add_probe(&probe);
    // a step in time the accepted effects leave in the residual
    let change_point = changes::residual_change_point(last, cal, cfg.alpha)?;
    if let Some(cp) = &change_point {
        unexplained.structured = true;
        unexplained.note.push_str("; ");
        unexplained.note.push_str(&cp.sentence());
    }
    if verdict.kind == "missing_effect" {
        let explained: Vec<(String, f64)> = regs
            .iter()
            .map(|r| {
                let e = explain(&final_cal, r);
                (e.regressor, e.r2)
            })
            .collect();
        unexplained.add_where_to_look(&explained);
    }
    let report = DiagnoseReport {
        declared: SetStats {
            calibration: Stats::from_errors(&declared_cal),
            validation: Stats::from_errors(&declared_val),
            validation_all: validation_all(&declared.model)?,
        },
        effects,
        final_: SetStats {
            calibration: Stats::from_errors(&final_cal),
            validation: Stats::from_errors(&final_val),
            validation_all: validation_all(&last.model)?,
        },
        unexplained,
        floor,
        aliased,
        noise,
        robot: model.name().to_string(),
        tilting: last.model.tilt,
        declared_unidentifiable: declared.unidentifiable.clone(),
        rejected: selection
            .last_trials
            .iter()
            .map(TrialReport::from_trial)
            .collect(),
        rule: report::rule_text(cfg),
        measurements: if cal.is_serial() {
            "partial"
        } else {
            "positions"
        }
        .to_string(),
        outliers_left_out: outliers,
        outliers: held
            .as_ref()
            .map(|h| h.outliers.clone())
            .unwrap_or_default(),
        within_uncertainty: held.map(|h| h.within).unwrap_or_default(),
        outlier_note,
        converged: last.converged && declared.converged,
        probe: probe::ProbeReport {
            change_point,
            ..probe.report(&probe_cfg)
        },
        residual_model: None,
        assumed_masses: None,
        simplest: selection.simpler.as_ref().map(report::SimplestReport::from),
        verdict,
        bounds: bound_reports,
    };
    Ok(Diagnosis {
        report,
        model: selection.last.model.clone(),
        selection,
        regressors: regs,
        traces,
        probe,
    })
}

/// The calibration set needs two poses per fold, the held-out set at least one.
fn check_sizes(
    cal: &MeasuredSet,
    val: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<(), DiagnoseError> {
    let min = 2 * cfg.folds.max(2);
    if cal.len() < min {
        return Err(DiagnoseError::TooFewPoses {
            what: "calibration set",
            n: cal.len(),
            min,
        });
    }
    if val.is_empty() {
        return Err(DiagnoseError::TooFewPoses {
            what: "validation set",
            n: 0,
            min: 1,
        });
    }
    Ok(())
}
