//! `rigctl diagnose`: fit the declared model, study the residual, add the missing effects the
//! data establish, and report the error before and after each addition (FORMATS.md).
//!
//! | module | holds |
//! |---|---|
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
//! [`STRUCTURE_MIN_R2`] of it with a Bonferroni-corrected p-value below
//! [`STRUCTURE_ALPHA`] — then something systematic remains that no candidate explained.

pub mod alias;
pub mod bounds;
pub mod candidates;
pub mod changes;
pub mod compress;
pub mod decide;
pub mod envelope;
pub mod extended;
pub mod floor;
pub mod ordered;
pub mod parallel;
pub mod plots;
pub mod polish;
pub mod probe;
pub mod report;
pub mod residual;
pub mod select;
pub mod simplest;
pub mod stat;
pub mod verdict;

use crate::calib::fit::{Fit, Split};
use crate::calib::outliers::{self, OutlierReport};
use crate::calib::problem::norms_mm;
use nalgebra::Vector3;

use crate::calib::position_fit::fit_parameters;
use crate::calib::MeasuredSet;
use crate::calib::{default_selection, CalibError, Stats};
use crate::error::{Classify, ErrorKind};
use crate::model::{Model, ModelError};
use candidates::effect_values;
use decide::{contribution, DecideConfig, Selection};
use extended::{ExtModel, ExtendedFit, Unknown, Values};
use report::{DiagnoseReport, EffectReport, NoiseReport, SetStats, TrialReport, Unexplained};
use residual::{best_regressor, explain, explain_with, regressors};
use select::forward_selection;

/// Smallest share of the final residual a regressor must explain to call it structured.
pub const STRUCTURE_MIN_R2: f64 = 0.05;
/// Significance (after Bonferroni correction over the regressors) of residual structure.
pub const STRUCTURE_ALPHA: f64 = 1e-3;

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

/// One accepted effect with what the plots need.
#[derive(Debug, Clone)]
pub struct EffectTrace {
    /// Effect id.
    pub id: String,
    /// Index of the regressor that traced it in [`Diagnosis::regressors`].
    pub regressor: usize,
    /// Calibration errors before and after the effect (mm, per pose).
    pub errors_before: Vec<Vector3<f64>>,
    /// Calibration errors after.
    pub errors_after: Vec<Vector3<f64>>,
    /// Its contribution per pose (mm).
    pub contribution: Vec<Vector3<f64>>,
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

/// The declared fit (as `calibrate --method tilting`) as an extended fit, and the requested
/// unknowns.
pub fn declared_fit(
    model: &Model,
    cal: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<(Fit<ExtModel, Unknown>, Vec<Unknown>), DiagnoseError> {
    let selection = default_selection(model, false);
    let tilt = model.has_tilt();
    let requested: Vec<Unknown> = selection.iter().copied().map(Unknown::Param).collect();
    if cal.directions.is_some() || cal.moments_kgfm.is_some() {
        // partial measurements (or moments in motion): the same identification on the extended
        // problem, which projects on the measured directions
        let fit = extended::fit(
            &ExtModel::new(model.clone()),
            cal,
            &requested,
            &cfg.lm,
            cfg.rtol,
            false,
        )?;
        return Ok((fit, requested));
    }
    let f = fit_parameters(model, &cal.poses, &selection, tilt, &cfg.lm, cfg.rtol, None)?;
    let mut ext = ExtModel::new(f.model.clone());
    ext.tilt = tilt;
    // the residual of the extended model (its own evaluation of every pose)
    let rss_mm2 = ext.errors(cal)?.iter().map(|e| e.norm_squared()).sum();
    // never worse than the model as given: the geometric fit does not see every term of a model
    // file (its compliance, say), so it can end above where the input already is; the input is
    // then the declared fit, unchanged
    let mut start = ExtModel::new(model.clone());
    start.tilt = tilt;
    let start_rss: f64 = start.errors(cal)?.iter().map(|e| e.norm_squared()).sum();
    if start_rss < rss_mm2 {
        let split = Split {
            fitted: Vec::new(),
            fixed: requested.clone(),
            unidentifiable: f.unidentifiable.clone(),
            rank: f.rank,
        };
        return Ok((
            Fit::unfitted(start, split, start_rss, cal.n_residuals()),
            requested,
        ));
    }
    let fit = Fit {
        rss_mm2,
        n_residuals: cal.n_residuals(),
        ..f.map(|_| ext, Unknown::Param)
    };
    Ok((fit, requested))
}

/// `reports` with the line and id of each pose of `data`.
fn labelled(mut reports: Vec<OutlierReport>, data: &MeasuredSet) -> Vec<OutlierReport> {
    for r in &mut reports {
        r.line = data.lines.as_ref().and_then(|l| l.get(r.index).copied());
        r.id = data.ids.as_ref().and_then(|i| i.get(r.index).cloned());
    }
    reports
}

/// Said first in `unexplained.note` when the final fit stopped on its iteration budget.
pub const NOT_CONVERGED_NOTE: &str =
    "the final fit did not converge (iteration budget spent while still improving): its values and the verdict are not those of the optimum";

/// Outlier threshold of [`trim_outliers`], in robust standard deviations.
pub const OUTLIER_SIGMAS: f64 = 5.0;
/// Half width (samples) of the running median of [`trim_outliers`].
pub const OUTLIER_HALF_WINDOW: usize = 5;

/// The declared fit ([`declared_fit`]) of the calibration set, after leaving out the samples
/// along a traced path whose declared-fit residual is a **spike** (at most 3 passes, each
/// refitting): in some measured component the residual departs from its running median over
/// the neighbouring samples (+- [`OUTLIER_HALF_WINDOW`]) by more than [`OUTLIER_SIGMAS`] robust
/// standard deviations (`1.4826 median |departure|`). Such spikes are expected with the
/// declared tilting law: where a joint moment is near zero its sign, hence the side of the
/// clearance, can differ between the arm and the model for a sample or two. A missing effect
/// changes the residual smoothly along the path and is kept. Full positions (independent poses)
/// are never left out, nor is the validation set. Returns the kept set, the number left out,
/// and the declared fit on the kept set with its requested unknowns.
pub fn trim_outliers(
    model: &Model,
    cal: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<(MeasuredSet, usize, ExtendedFit, Vec<Unknown>), DiagnoseError> {
    if !cal.is_serial() {
        let (fit, requested) = declared_fit(model, cal, cfg)?;
        return Ok((cal.clone(), 0, fit, requested));
    }
    let mut kept: Vec<usize> = (0..cal.len()).collect();
    let mut sub = cal.clone();
    let (mut fit, mut requested) = declared_fit(model, &sub, cfg)?;
    for _ in 0..3 {
        let mut spikes = vec![false; kept.len()];
        let comps: Vec<Vec<f64>> = (0..sub.len())
            .map(|k| {
                let p = fit.model.predict_pose(&sub, k)?;
                Ok(sub.components(k, &(sub.poses.xyz_mm[k] - p)))
            })
            .collect::<Result<_, ModelError>>()?;
        let slots = comps.iter().map(Vec::len).max().unwrap_or(0);
        for slot in 0..slots {
            let series: Vec<(usize, f64)> = comps
                .iter()
                .enumerate()
                .filter_map(|(k, c)| c.get(slot).map(|v| (k, *v)))
                .collect();
            for (k, bad) in running_median_spikes(&series) {
                if bad {
                    spikes[k] = true;
                }
            }
        }
        let next: Vec<usize> = kept
            .iter()
            .zip(&spikes)
            .filter(|(_, s)| !**s)
            .map(|(k, _)| *k)
            .collect();
        if next.len() == kept.len() || next.len() < 2 * cfg.folds.max(2) {
            break;
        }
        kept = next;
        sub = cal.subset(&kept);
        (fit, requested) = declared_fit(model, &sub, cfg)?;
    }
    Ok((sub, cal.len() - kept.len(), fit, requested))
}

/// For each `(index, value)` of a series: whether it departs from the running median of its
/// neighbours by more than [`OUTLIER_SIGMAS`] robust standard deviations of the departures.
fn running_median_spikes(series: &[(usize, f64)]) -> Vec<(usize, bool)> {
    let n = series.len();
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(0.0)
    };
    let dep: Vec<f64> = (0..n)
        .map(|i| {
            let lo = i.saturating_sub(OUTLIER_HALF_WINDOW);
            let hi = (i + OUTLIER_HALF_WINDOW + 1).min(n);
            let mut w: Vec<f64> = series[lo..hi].iter().map(|x| x.1).collect();
            series[i].1 - median(&mut w)
        })
        .collect();
    let sigma = 1.4826 * median(&mut dep.iter().map(|d| d.abs()).collect());
    series
        .iter()
        .zip(&dep)
        .map(|((k, _), d)| (*k, sigma > 0.0 && d.abs() > OUTLIER_SIGMAS * sigma))
        .collect()
}

/// One report (and plot trace) per accepted effect: its final values and sigmas, its values at
/// entry, the before/after statistics and the evidence in words.
fn effect_reports(
    selection: &Selection,
    regs: &[residual::Regressor],
    cal: &MeasuredSet,
    val: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<(Vec<EffectReport>, Vec<EffectTrace>), DiagnoseError> {
    let mut effects = Vec::new();
    let mut traces = Vec::new();
    for step in &selection.steps {
        let t = &step.trial;
        let vb = step.before.model.errors(val)?;
        let va = step.after.model.errors(val)?;
        let cb = step.before.model.errors(cal)?;
        let ca = step.after.model.errors(cal)?;
        let contrib = contribution(&step.before, &step.after, cal)?;
        let (ri, ex) = best_regressor(&contrib, regs).unwrap_or((0, explain(&contrib, &regs[0])));
        let values = effect_values(&t.candidate, &step.before.model, &step.after);
        let final_values = effect_values(&t.candidate, &step.before.model, &selection.last);
        let share = if t.rss_before_mm2 > 0.0 {
            1.0 - t.rss_after_mm2 / t.rss_before_mm2
        } else {
            0.0
        };
        let new_combos: Vec<String> = step
            .after
            .unidentifiable
            .iter()
            .filter(|c| !step.before.unidentifiable.contains(c))
            .cloned()
            .collect();
        let mut evidence = format!(
            "removes {:.0} % of the calibration residual sum of squares with {} new parameter(s) \
             (F = {:.1}, p = {:.1e}, BIC {:+.1}); {}-fold cross-validated mean error {:.4} -> {:.4} mm (paired t = {:.1}); \
             the part it explains follows {} (R^2 = {:.2})",
            100.0 * share,
            t.added,
            t.f,
            t.p_value,
            t.delta_bic,
            cfg.folds,
            t.cv_mean_mm[0],
            t.cv_mean_mm[1],
            t.cv_t,
            ex.regressor,
            ex.r2
        );
        if !new_combos.is_empty() {
            evidence.push_str(&format!(
                "; not separable from fitted parameters (held fixed): {}",
                new_combos.join(", ")
            ));
        }
        if !step.equivalent.is_empty() {
            evidence.push_str(&format!(
                "; equivalent on these poses (explain the same residual within noise): {}",
                step.equivalent.join(", ")
            ));
        }
        let opt = |v: &[(String, f64)]| -> report::Ordered<Option<f64>> {
            v.iter()
                .map(|(n, s)| (n.clone(), if s.is_finite() { Some(*s) } else { None }))
                .collect()
        };
        effects.push(EffectReport {
            id: t.candidate.id.clone(),
            parameters: final_values.values.iter().cloned().collect(),
            sigma: opt(&final_values.sigma),
            parameters_at_entry: values.values.iter().cloned().collect(),
            validation_mean_mm_before: mean_norm(&vb),
            validation_mean_mm_after: mean_norm(&va),
            evidence,
            equivalent: step.equivalent.clone(),
            uncertainty: final_values
                .sigma
                .iter()
                .map(|(n, s)| (n.clone(), if s.is_finite() { Some(*s) } else { None }))
                .collect(),
            calibration_mean_mm_before: mean_norm(&cb),
            calibration_mean_mm_after: mean_norm(&ca),
            cv_mean_mm_before: t.cv_mean_mm[0],
            cv_mean_mm_after: t.cv_mean_mm[1],
            p_value: t.p_value,
            f_statistic: t.f,
            delta_bic: t.delta_bic,
            added_parameters: t.added,
            regressor: ex.regressor.clone(),
            unidentifiable: new_combos,
            model_parameters: t
                .candidate
                .unknowns
                .iter()
                .map(|u| (u.name(&step.after.model.model), step.after.model.value(*u)))
                .collect(),
        });
        traces.push(EffectTrace {
            id: t.candidate.id.clone(),
            regressor: ri,
            errors_before: cb,
            errors_after: ca,
            contribution: contrib,
        });
    }

    Ok((effects, traces))
}

fn mean_norm(e: &[Vector3<f64>]) -> f64 {
    Stats::from_errors(e).mean_mm
}

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
    // Gross errors: fit-and-flag with the declared fit, the selection on the kept poses, then
    // the flags re-checked under the final model (once more from there when they changed).
    let mut flagged: Vec<usize> = Vec::new();
    let mut outlier_note = None;
    // the declared fit of trim's last round (on the poses it keeps), reused by the selection
    let mut last_declared: Option<(Vec<usize>, ExtendedFit, Vec<Unknown>)> = None;
    if gross {
        let t = outliers::trim(cal_all.len(), 3, cfg.floor_mm, |keep| {
            let (fit, requested) = declared_fit(model, &cal_all.subset(keep), cfg)?;
            let norms = norms_mm(&fit.model.errors(&cal_all)?);
            last_declared = Some((keep.to_vec(), fit, requested));
            Ok::<_, DiagnoseError>(norms)
        })?;
        flagged = t.flagged;
        outlier_note = t.note;
    }
    // the selection on the poses not in `flagged` (gross errors only on unordered poses, so the
    // spike rule of `trim_outliers` leaves them as they are and trim's declared fit serves)
    let run = |flagged: &[usize]| -> Result<
        (MeasuredSet, usize, ExtendedFit, Vec<Unknown>, Selection),
        DiagnoseError,
    > {
        let keep = outliers::kept(cal_all.len(), flagged);
        let kept_cal = cal_all.subset(&keep);
        let reused = last_declared
            .as_ref()
            .filter(|(k, _, _)| *k == keep && !kept_cal.is_serial());
        let (cal, left_out, declared, requested) = match reused {
            Some((_, fit, requested)) => (kept_cal, 0, fit.clone(), requested.clone()),
            None => trim_outliers(model, &kept_cal, cfg)?,
        };
        let greedy = forward_selection(declared.clone(), &requested, &cal, cfg)?;
        let selection = simplest::prefer_simplest(greedy, &declared, &requested, &cal, cfg)?;
        Ok((cal, left_out, declared, requested, selection))
    };
    // the flags under the final model of `selection`, the scale from the poses not in `flagged`
    let flags_under = |selection: &Selection,
                       flagged: &[usize]|
     -> Result<Vec<usize>, DiagnoseError> {
        let all = norms_mm(&selection.last.model.errors(&cal_all)?);
        let kept_norms: Vec<f64> = outliers::kept(all.len(), flagged)
            .iter()
            .map(|&k| all[k])
            .collect();
        let thr = outliers::threshold_mm(outliers::robust_sigma_mm(&kept_norms, 3), cfg.floor_mm);
        Ok(outliers::flag_set_against(&all, thr).0)
    };
    let mut result = run(&flagged)?;
    if gross && !flagged.is_empty() {
        // The flagged poses may carry the evidence of a missing effect (a step of the declared
        // tilting law, a backlash): the selection on every pose, and the flags under its final
        // model; when its effects explain some of the flagged poses, they are kept.
        let with_all = run(&[])?;
        let flags_all = flags_under(&with_all.4, &[])?;
        if flags_all.len() < flagged.len() && flags_all.iter().all(|k| flagged.contains(k)) {
            flagged = flags_all;
            result = if flagged.is_empty() {
                with_all
            } else {
                run(&flagged)?
            };
        } else {
            let again = flags_under(&result.4, &flagged)?;
            if again != flagged {
                flagged = again;
                result = run(&flagged)?;
            }
        }
    }
    let (cal, outliers, declared, requested, mut selection) = result;
    let cal = &cal;
    let bound_reports = bounds::enforce(&mut selection, cal, cfg);
    // the fitted unknowns' Jacobians at the calibration poses (the held-out judgement and the
    // probe of the final residual)
    let cal_jac = probe::jacobians(&selection.last.model, cal, &selection.last.fitted)?;
    // held-out poses judged by the calibration's scale and the final model's prediction
    // uncertainty at each (FORMATS.md: extrapolation is not a gross error)
    let mut outlier_reports = Vec::new();
    let mut within_reports = Vec::new();
    let val_kept;
    let val = if gross {
        let sigma = outliers::robust_sigma_mm(&norms_mm(&selection.last.model.errors(cal)?), 3)
            .max(cfg.floor_mm.unwrap_or(0.0));
        let thr = outliers::threshold_mm(sigma, None);
        let all = norms_mm(&selection.last.model.errors(&cal_all)?);
        outlier_reports.extend(labelled(
            outliers::reports("cal", &flagged, &all, &all, thr),
            &cal_all,
        ));
        let vn = norms_mm(&selection.last.model.errors(&val_all)?);
        let val_jac = probe::jacobians(&selection.last.model, &val_all, &selection.last.fitted)?;
        let sd = held_out_sd_mm(cal, &cal_jac, &val_all, &val_jac, sigma);
        let (vflag, thresholds) = outliers::flag_held_out(&vn, &sd, sigma);
        // a pose that a model within the fit's uncertainty predicts is not a gross error
        let (vflag, kept) = envelope::within_uncertainty(
            &selection.last,
            cal,
            &cal_jac,
            &val_all,
            &vflag,
            &thresholds,
            sigma,
        )?;
        within_reports = labelled(envelope::reports(&kept, &vn, &thresholds), &val_all);
        outlier_reports.extend(labelled(
            outliers::held_out_reports(&vflag, &vn, &vn, &thresholds, &sd),
            &val_all,
        ));
        val_kept = val_all.subset(&outliers::kept(val_all.len(), &vflag));
        &val_kept
    } else {
        &val_all
    };
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

    let (mut effects, traces) = effect_reports(&selection, &regs, cal, val, cfg)?;

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
    // the held-out Jacobians of the fitted unknowns are the first columns of those of the
    // unknowns a change between the sets may move (`change_unknowns` starts with them)
    let change = verdict::change_unknowns(&last.model.model, &last.fitted);
    let val_jac_change = probe::jacobians(&last.model, val, &change)?;
    let val_jac: Vec<nalgebra::DMatrix<f64>> = val_jac_change
        .iter()
        .map(|j| j.columns(0, last.fitted.len()).into_owned())
        .collect();
    let verdict = verdict::judge(
        &floor,
        &probe,
        verdict::Counts {
            n_residuals: last.n_residuals,
            n_params: last.fitted.len(),
            tau,
            val_residuals: (0..val.len()).map(|k| val.rows(k)).sum(),
            val_inflation: verdict::prediction_inflation(cal, &cal_jac, val, &val_jac),
            val_after_change: verdict::after_parameter_change(val, &final_val, &val_jac_change),
        },
    );
    unexplained.note = format!("{}; {}", verdict.note, unexplained.note);
    if !bound_reports.is_empty() {
        unexplained.note = format!("{}; {}", bounds::sentence(&bound_reports), unexplained.note);
        for e in &mut effects {
            let hit: Vec<&bounds::BoundReport> = bound_reports
                .iter()
                .filter(|b| e.model_parameters.get(&b.parameter).is_some())
                .collect();
            for b in hit {
                e.evidence.push_str(&format!(
                    "; {} fitted {:.4}, below its physical bound {}: held at {} and the others refitted",
                    b.parameter, b.fitted_value, b.bound, b.held_value
                ));
            }
        }
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
        outliers: outlier_reports,
        within_uncertainty: within_reports,
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

/// The residual's noise level, its serial correlation and the verdict against the floor.
fn judge_floor(
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
fn aliased_pairs(
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
fn probe_residual(
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

fn unexplained(
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
