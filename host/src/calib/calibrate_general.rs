//! `rigctl calibrate` beyond one point and the chain parameters, as a library call: several
//! measured points per pose, joint compliance (`--compliance`) and parameter selection by
//! leave-one-pose-out PRESS on the calibration poses (`--select press`, [`super::press`]).
//!
//! The unknowns:
//! * always: the selected model parameters ([`super::calibrate::resolve_selection`]; with
//!   `--select press` and no `--params`, the default selection without the chain constants),
//!   and the offsets of every point slot after the first;
//! * with `--select press`, candidates added by forward selection at the fit of the always-set:
//!   the chain constants (`@chain`: lengths, twists) not already selected and, with
//!   `--compliance`, the axial and the lateral compliance of every revolute joint, with
//!   `--hysteresis` the hysteresis of every joint (an offset by the direction of approach in
//!   the pose order: a backlash whose side the path sets); without `--select press`,
//!   `--compliance` fits every axial compliance (no lateral ones) and `--hysteresis` every
//!   joint's hysteresis.

use std::str::FromStr;

use nalgebra::Vector3;

use super::calibrate::{
    calibrate, fit_report, resolve_selection, CalibrateOptions, Method, Outcome,
};
use super::error::CalibError;
use super::fit::Fit;
use super::general::{fit_general, stacked, ExtModel, GeneralFit, Unknown, Values};
use super::measured::MeasuredSet;
use super::press::forward_select;
use super::projected::{calibrate_projected, SampleTilt};
use crate::model::gravity::GravityModel;
use crate::model::{Model, ParamKind};

/// How the identified set is chosen (`--select`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Select {
    /// Every selected unknown.
    #[default]
    All,
    /// Forward selection by block PRESS on the calibration poses.
    Press,
}

impl FromStr for Select {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        // the names are clap's (`ValueEnum`)
        <Self as clap::ValueEnum>::from_str(s, false)
            .map_err(|_| format!("unknown selection `{s}` (all, press)"))
    }
}

/// Settings beyond [`CalibrateOptions`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GeneralOptions {
    pub select: Select,
    /// Identify joint compliances (needs link masses).
    pub compliance: bool,
    /// Identify joint hysteresis (`hysteresis:j<i>`, the pose order's directions of approach).
    pub hysteresis: bool,
}

/// Result of [`calibrate_poses`].
#[derive(Debug, Clone)]
pub struct GeneralOutcome {
    /// The calibrated model, report (with `terms`) and error vectors (one per measurement).
    pub outcome: Outcome,
    /// The chosen identification (offsets and compliances included); `None` for the
    /// identification on one point per pose ([`calibrate`]).
    pub fit: Option<GeneralFit>,
    /// Names of the unknowns added by `--select press`, in order.
    pub added: Vec<String>,
    /// Validation RMS (mm) of every point slot (empty without validation data).
    pub validation_rms_by_point_mm: Vec<f64>,
    /// Measured components left out of the fit as outliers (partial measurements,
    /// [`super::projected::fit_projected_robust`]; 0 otherwise).
    pub rejected: usize,
}

fn chain_constant(model: &Model, i: usize) -> bool {
    matches!(
        model.params().get(i).map(|p| p.kind),
        Some(ParamKind::Length | ParamKind::Twist)
    ) && model.param_index("base_rz") != Some(i)
}

/// The always-fitted unknowns and the PRESS candidates (empty with [`Select::All`]).
fn unknown_sets(
    nominal: &Model,
    data: &MeasuredSet,
    opts: &CalibrateOptions,
    gen: &GeneralOptions,
) -> Result<(Vec<Unknown>, Vec<Unknown>), CalibError> {
    let selection = resolve_selection(nominal, opts)?;
    let press = gen.select == Select::Press;
    // in preference order among confounded unknowns: the further points' offsets (what the
    // robot's software does not see) first, then the selection
    let mut always: Vec<Unknown> = Vec::new();
    for slot in 1..data.n_slots() {
        always.extend((0..3).map(|axis| Unknown::Offset { slot, axis }));
    }
    always.extend(
        selection
            .iter()
            .filter(|&&i| !(press && opts.params.is_none() && chain_constant(nominal, i)))
            .map(|&i| Unknown::Param(i)),
    );
    let compliance: Vec<Unknown> = match gen.compliance {
        true => (0..nominal.n_joints())
            .filter(|&j| !nominal.joints()[j].prismatic)
            .map(Unknown::Compliance)
            .collect(),
        false => Vec::new(),
    };
    let hysteresis: Vec<Unknown> = match gen.hysteresis {
        true => (0..nominal.n_joints()).map(Unknown::Hysteresis).collect(),
        false => Vec::new(),
    };
    if !press {
        always.extend(compliance);
        always.extend(hysteresis);
        return Ok((always, Vec::new()));
    }
    let chain = super::calibrate::param_group(nominal, "chain")?;
    let mut candidates: Vec<Unknown> = chain
        .into_iter()
        .map(Unknown::Param)
        .filter(|u| !always.contains(u))
        .collect();
    candidates.extend(compliance);
    if gen.compliance {
        candidates.extend(
            (0..nominal.n_joints())
                .filter(|&j| !nominal.joints()[j].prismatic)
                .map(Unknown::LateralCompliance),
        );
    }
    candidates.extend(hysteresis);
    Ok((always, candidates))
}

/// Fits `always`, then (with candidates) adds the ones chosen by block PRESS at that fit and
/// fits them all.
fn identify(
    start: &ExtModel,
    data: &MeasuredSet,
    sets: &(Vec<Unknown>, Vec<Unknown>),
    opts: &CalibrateOptions,
) -> Result<(GeneralFit, Vec<Unknown>), CalibError> {
    let (always, candidates) = sets;
    let first = fit_general(start, data, always, &opts.lm, opts.rtol)?;
    if candidates.is_empty() {
        return Ok((first, Vec::new()));
    }
    let mut cols = first.fitted.clone();
    cols.extend(candidates.iter().filter(|c| !first.fitted.contains(c)));
    let (jac, r) = stacked(&first.model, data, &cols)?;
    let fixed: Vec<usize> = (0..first.fitted.len()).collect();
    let cand: Vec<usize> = (first.fitted.len()..cols.len()).collect();
    let added: Vec<Unknown> = forward_select(&jac, &r, &data.row_blocks(), &fixed, &cand)
        .into_iter()
        .map(|k| cols[k])
        .collect();
    if added.is_empty() {
        return Ok((first, added));
    }
    let mut sel = first.fitted.clone();
    sel.extend(&added);
    let fit = fit_general(&first.model, data, &sel, &opts.lm, opts.rtol)?;
    Ok((fit, added))
}

/// `--compliance` needs link masses (the gravity torques).
fn masses_for(nominal: &Model, compliance: bool) -> Result<(), CalibError> {
    match compliance && GravityModel::for_model(nominal).is_none() {
        true => Err(CalibError::NoMasses),
        false => Ok(()),
    }
}

/// The model-parameter part of a general fit, for the report.
fn model_fit(f: &GeneralFit) -> Fit {
    let params = |v: &[Unknown]| -> Vec<usize> {
        v.iter()
            .filter_map(|u| match u {
                Unknown::Param(i) => Some(*i),
                _ => None,
            })
            .collect()
    };
    Fit {
        model: f.model.model.clone(),
        fitted: params(&f.fitted),
        fixed: params(&f.fixed),
        unidentifiable: f.unidentifiable.clone(),
        sigma: f
            .fitted
            .iter()
            .zip(&f.sigma)
            .filter(|(u, _)| matches!(u, Unknown::Param(_)))
            .map(|(_, s)| *s)
            .collect(),
        condition_number: f.condition_number,
        rank: f.rank,
        iterations: f.iterations,
        converged: f.converged,
        rss_mm2: f.rss_mm2,
        n_residuals: f.n_residuals,
    }
}

/// The library's `calibrate` on a measured set, whatever the variant: `nominal`'s own terms (its
/// joint map and time terms, from a model file) applied to the readings and the measured points
/// ([`MeasuredSet::through_terms`]) and kept in the calibrated model, then the identification
/// on partial measurements ([`super::projected`], `calibrate --samples`: the declared tilting
/// with the set's inertial moments when it has them), on one point per pose ([`calibrate`]:
/// standard, tilting, influence) or, with several points per pose, `--select press` or
/// `--compliance`, [`calibrate_general`].
pub fn calibrate_poses(
    nominal: &Model,
    cal: &MeasuredSet,
    val: Option<&MeasuredSet>,
    opts: &CalibrateOptions,
    gen: &GeneralOptions,
) -> Result<GeneralOutcome, CalibError> {
    if gen.compliance && nominal.transmission().has_compliance() {
        return Err(CalibError::Unsupported(
            "the model already has compliance terms (compliance_deg_per_kgfm), which --compliance \
             would fit again from zero: remove them from the model file or leave out --compliance"
                .into(),
        ));
    }
    super::plausible::check_set(nominal, cal, "calibration poses")?;
    if let Some(v) = val {
        super::plausible::check_set(nominal, v, "held-out poses")?;
    }
    let run = Run {
        nominal,
        cal: cal.through_terms(nominal)?,
        val: val.map(|v| v.through_terms(nominal)).transpose()?,
        opts,
        gen,
    };
    if run.cal.is_serial() {
        return run.partial();
    }
    if run.cal.n_slots() == 1 && *gen == GeneralOptions::default() {
        let outcome = calibrate(nominal, &run.cal, run.val.as_ref(), opts)?;
        return Ok(GeneralOutcome {
            outcome,
            fit: None,
            added: Vec::new(),
            validation_rms_by_point_mm: Vec::new(),
            rejected: 0,
        });
    }
    run.general()
}

/// One `calibrate`: the model, its settings, and the calibration and validation sets as the
/// model's chain sees them ([`MeasuredSet::through_terms`]).
struct Run<'a> {
    nominal: &'a Model,
    cal: MeasuredSet,
    val: Option<MeasuredSet>,
    opts: &'a CalibrateOptions,
    gen: &'a GeneralOptions,
}

impl Run<'_> {
    /// Calibrates `nominal` on `cal` (several points per pose, compliance, PRESS selection) and
    /// evaluates on `val`. "before" is the nominal model without tilting, its further points at
    /// their identified offsets (they have no nominal value).
    fn general(&self) -> Result<GeneralOutcome, CalibError> {
        let Run {
            nominal,
            cal,
            val,
            opts,
            gen,
        } = self;
        let (nominal, opts, gen, val) = (*nominal, *opts, *gen, val.as_ref());
        if opts.method == Method::Influence {
            return Err(CalibError::Unsupported(
                "--method influence works on one point per pose without --select/--compliance"
                    .into(),
            ));
        }
        if let Some(v) = val.filter(|v| v.n_slots() != cal.n_slots()) {
            return Err(CalibError::Unsupported(format!(
                "the validation poses have {} measured point(s) per pose, the calibration poses {}",
                v.n_slots(),
                cal.n_slots()
            )));
        }
        let sets = unknown_sets(nominal, cal, opts, gen)?;
        masses_for(nominal, gen.compliance)?;
        let tilt = opts.method == Method::Tilting && nominal.has_tilt();
        let run = |tilt: bool| {
            let start = ExtModel::with_points(nominal.clone(), cal.n_slots(), tilt)?;
            identify(&start, cal, &sets, opts)
        };
        let (chosen, added) = run(tilt)?;
        let (chosen, held) = settle(nominal, cal, chosen, opts, gen.compliance)?;
        let standard = if tilt { run(false)?.0 } else { chosen.clone() };
        let mut before = ExtModel::with_points(nominal.clone(), cal.n_slots(), false)?;
        for (b, c) in before
            .offsets_mm
            .iter_mut()
            .zip(&chosen.model.offsets_mm)
            .skip(1)
        {
            *b = *c;
        }
        // every model's errors with the torques of its own chain (what `fk` on the written
        // model computes)
        let errs = |m: &ExtModel, d: &MeasuredSet| m.point_errors(d);
        let cal_errors = [
            errs(&before, cal)?,
            errs(&standard.model, cal)?,
            errs(&chosen.model, cal)?,
        ];
        let val_errors = match val {
            Some(v) => [
                errs(&before, v)?,
                errs(&standard.model, v)?,
                errs(&chosen.model, v)?,
            ],
            None => [Vec::new(), Vec::new(), Vec::new()],
        };
        let validation_rms_by_point_mm = match val {
            Some(v) => rms_by_slot(v, &val_errors[2]),
            None => Vec::new(),
        };
        let mut selection: Vec<usize> = resolve_selection(nominal, opts)?;
        for u in &added {
            if let Unknown::Param(i) = u {
                selection.push(*i);
            }
        }
        let mut report = fit_report(
            &model_fit(&chosen),
            &selection,
            opts.method.as_str(),
            &cal_errors,
            val.map(|_| &val_errors),
            tilt,
        );
        report.unphysical.extend(held);
        for (u, s) in chosen.fitted.iter().zip(&chosen.sigma) {
            if !matches!(u, Unknown::Param(_)) {
                let name = chosen.model.name_in(*u, cal);
                let value = chosen.model.value(*u);
                if matches!(u, Unknown::Compliance(_)) && value < 0.0 {
                    report.unphysical.push(format!(
                    "{name} = {value:.4} +- {s:.4}: a negative compliance, which no joint has (the term \
                     stands in for something the model lacks, e.g. a length or the link masses){}",
                    if value + 2.0 * s >= 0.0 {
                        "; within 2 sigma of 0"
                    } else {
                        ""
                    }
                ));
                }
                report.terms.0.push((name.clone(), value));
                report.sigma.0.push((name, *s));
            }
        }
        Ok(GeneralOutcome {
            added: added
                .iter()
                .map(|&u| chosen.model.name_in(u, cal))
                .collect(),
            outcome: Outcome {
                model: with_own_hysteresis(&chosen.model.model, nominal),
                tilt,
                report,
                calibration_errors: cal_errors,
                validation_errors: val_errors,
            },
            fit: Some(chosen),
            validation_rms_by_point_mm,
            rejected: 0,
        })
    }

    /// The identification on partial measurements ([`super::projected::calibrate_projected`]):
    /// one point per pose, no validation set, no PRESS selection or compliance.
    fn partial(&self) -> Result<GeneralOutcome, CalibError> {
        let (nominal, cal, opts) = (self.nominal, &self.cal, self.opts);
        if self.val.is_some() || *self.gen != GeneralOptions::default() || cal.n_slots() != 1 {
            return Err(CalibError::Unsupported(
            "partial measurements (fused samples) are calibrated on one point per pose, without \
             validation poses, --select or --compliance"
                .into(),
        ));
        }
        let tilt = match (opts.method, cal.moments_kgfm.is_some()) {
            (Method::Tilting, true) => SampleTilt::Dynamic,
            (Method::Tilting, false) => SampleTilt::Static,
            _ => SampleTilt::Off,
        };
        let p = calibrate_projected(nominal, cal, tilt, opts)?;
        Ok(GeneralOutcome {
            outcome: Outcome {
                model: p.model,
                tilt: p.tilt != SampleTilt::Off,
                report: p.report,
                calibration_errors: p.errors,
                validation_errors: [Vec::new(), Vec::new(), Vec::new()],
            },
            fit: None,
            added: Vec::new(),
            validation_rms_by_point_mm: Vec::new(),
            rejected: p.rejected,
        })
    }
}

/// The calibrated `model` as written: the hysteresis fitted on the readings through
/// `nominal`'s own terms ([`MeasuredSet::through_terms`]) plus `nominal`'s own (a hysteresis
/// adds to the angle, so the two add), so that `fk` on the written model reproduces the
/// reported errors.
fn with_own_hysteresis(model: &Model, nominal: &Model) -> Model {
    let own = &nominal.transmission().hysteresis_deg;
    if own.iter().all(|b| *b == 0.0) {
        return model.clone();
    }
    let mut out = model.clone();
    let n = out.n_joints();
    let fitted = &mut out.transmission_mut().hysteresis_deg;
    fitted.resize(n, 0.0);
    for (f, b) in fitted.iter_mut().zip(own) {
        *f += b;
    }
    out
}

/// Most refits of [`settle`].
const MAX_SETTLE_REFITS: usize = 4;

/// With compliance: the fit made consistent with its own chain and with the physical bounds
/// ([`crate::model::effect::bound`], one table for `calibrate` and `diagnose`). The gravity
/// torques are always those of the state's chain (as `fk` on the written model computes them),
/// and a compliance fitted below its bound (negative) is held at the bound and
/// left out of the fitted set; the others are refitted, until nothing changes. Without
/// compliance only a value outside its bound (a payload heavier than the robot's links and
/// than the one `nominal` declares) is held so. Returns the fit and a line for every value held.
fn settle(
    nominal: &Model,
    cal: &MeasuredSet,
    mut fit: GeneralFit,
    opts: &CalibrateOptions,
    compliance: bool,
) -> Result<(GeneralFit, Vec<String>), CalibError> {
    use crate::model::effect::bound_declared;
    let mut held = Vec::new();
    for _ in 0..MAX_SETTLE_REFITS {
        let below: Vec<(Unknown, f64, f64)> = fit
            .fitted
            .iter()
            .zip(&fit.sigma)
            .filter_map(|(&u, &s)| {
                let b = bound_declared(u, &fit.model.model, nominal)?;
                b.outside(fit.model.value(u)).map(|hold| (u, hold, s))
            })
            .collect();
        // without compliance nothing else needs settling (a payload above the robot's links does)
        if !compliance && below.is_empty() {
            break;
        }
        let mut start = fit.model.clone();
        for &(u, hold, sigma) in &below {
            let value = start.value(u);
            held.push(format!(
                "{} = {value:.4} +- {sigma:.4} fitted {} its physical bound: held at {hold} and \
                 left out of the fit (the term stood in for something the model lacks, e.g. a \
                 length or the link masses)",
                start.name_in(u, cal),
                if value > hold { "above" } else { "below" },
            ));
            start.set_value(u, hold)?;
        }
        let selection: Vec<Unknown> = fit
            .fitted
            .iter()
            .copied()
            .filter(|u| !below.iter().any(|b| b.0 == *u))
            .collect();
        let next = fit_general(&start, cal, &selection, &opts.lm, opts.rtol)?;
        let moved = (next.rss_mm2 - fit.rss_mm2).abs() > 1e-9 * fit.rss_mm2.max(f64::MIN_POSITIVE);
        let mut fixed = fit.fixed.clone();
        fixed.extend(below.iter().map(|b| b.0));
        fixed.extend(next.fixed.iter().copied());
        fixed.dedup();
        let iterations = fit.iterations + next.iterations;
        fit = GeneralFit {
            fixed,
            iterations,
            converged: fit.converged && next.converged,
            ..next
        };
        if below.is_empty() && !moved {
            break;
        }
    }
    Ok((fit, held))
}

/// RMS of the error lengths of every slot (mm).
fn rms_by_slot(data: &MeasuredSet, errors: &[Vector3<f64>]) -> Vec<f64> {
    (0..data.n_slots())
        .map(|slot| {
            let e: Vec<f64> = data
                .points()
                .zip(errors)
                .filter(|(m, _)| m.slot == slot)
                .map(|(_, e)| e.norm_squared())
                .collect();
            (e.iter().sum::<f64>() / e.len().max(1) as f64).sqrt()
        })
        .collect()
}
