//! `rigctl calibrate` as a library call: choose the parameters, run the standard and the chosen
//! identification, and summarise the errors before and after (thesis table 4.5).

use std::str::FromStr;

use nalgebra::Vector3;

use super::accumulator::{error_norms_mm, position_errors};
use super::error::CalibError;
use super::fit::Fit;
use super::identifiability::DEFAULT_RTOL;
use super::influence::{fit_influence, InfluenceConfig};
use super::lm::LmConfig;
use super::measured::{MeasuredSet, PosePoints};
use super::outliers;
use super::position_fit::fit_parameters;
use super::predict::prediction_sd_mm;
use super::prior::{PriorMode, PriorScales};
use super::problem::norms_mm;
use super::regularise::choose_prior;
pub(super) use super::report::fit_report;
use super::report::CalibrateReport;
use crate::model::{Model, ParamKind, KATANA_GEOMETRIC_PARAMS};

/// Identification method (FORMATS.md `--method`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Method {
    /// Conventional least squares on the geometric parameters, no tilting (thesis 3.6).
    Standard,
    /// Influence-based identification (thesis 3.6, eq. 3.7-3.8), no tilting.
    Influence,
    /// Tilting compensated first (declared tilt model on), then geometric identification
    /// (thesis fig. 4.9). Falls back to `Standard` behaviour for a model without tilting data.
    #[default]
    Tilting,
}

impl Method {
    /// The name used on the command line and in the JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            Method::Standard => "standard",
            Method::Influence => "influence",
            Method::Tilting => "tilting",
        }
    }
}

impl FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        // the names are clap's (`ValueEnum`, the variants' names in kebab case)
        <Self as clap::ValueEnum>::from_str(s, false)
            .map_err(|_| format!("unknown method `{s}` (standard, influence, tilting)"))
    }
}

/// Settings of [`calibrate`].
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrateOptions {
    /// The method.
    pub method: Method,
    /// Parameters to identify by name; `None` = [`default_selection`].
    pub params: Option<Vec<String>>,
    /// Also identify the base frame (`base_*`) with the default selection.
    pub base: bool,
    /// Solver settings.
    pub lm: LmConfig,
    /// Identifiability threshold (relative singular value).
    pub rtol: f64,
    /// Settings of the influence-based method.
    pub influence: InfluenceConfig,
    /// Keep every pose (no gross-error rule, [`super::outliers`]).
    pub keep_outliers: bool,
    /// The prior of ill-posed sets ([`super::prior`]).
    pub prior: PriorMode,
    /// Its scales per kind of parameter.
    pub prior_scales: PriorScales,
}

impl Default for CalibrateOptions {
    fn default() -> Self {
        Self {
            method: Method::default(),
            params: None,
            base: false,
            lm: LmConfig::default(),
            rtol: DEFAULT_RTOL,
            influence: InfluenceConfig::default(),
            keep_outliers: false,
            prior: PriorMode::default(),
            prior_scales: PriorScales::default(),
        }
    }
}

/// The parameters identified by default, in preference order (earlier ones are kept when a
/// combination is unidentifiable):
/// * a model with the Katana's 12 geometric parameters (MODEL.md): those 12
///   (`dth1..dth5, al2..al5, be3..be5`);
/// * any other model (e.g. `ur5`): joint offsets, the tool point, the base frame (with `base`),
///   then every constant twist and length of the chain (so that in a redundant pair the chain
///   constant is the one kept nominal);
/// * with `base`: the base frame `base_*` is added.
pub fn default_selection(model: &Model, base: bool) -> Vec<usize> {
    let mut sel: Vec<usize> = if KATANA_GEOMETRIC_PARAMS
        .iter()
        .all(|n| model.param_index(n).is_some())
    {
        KATANA_GEOMETRIC_PARAMS
            .iter()
            .filter_map(|n| model.param_index(n))
            .collect()
    } else {
        // in preference order among confounded parameters: what the robot's software does not
        // see (the instrument frame, the measured point) before its own joint offsets, so that
        // an offset is fitted only where the data determine it (the UR5's SMR, 0.07 mm off joint
        // 6's axis, is a tool point, not a turn of joint 6)
        let mut s = Vec::new();
        if base {
            s.extend(model.params_of_kind(ParamKind::Base));
        }
        s.extend(model.params_of_kind(ParamKind::Tool));
        s.extend(model.params_of_kind(ParamKind::JointOffset));
        let chain: Vec<usize> = (0..model.params().len())
            .filter(|&i| matches!(model.params()[i].kind, ParamKind::Twist | ParamKind::Length))
            .collect();
        s.extend(chain);
        return s;
    };
    if base {
        sel.extend(model.params_of_kind(ParamKind::Base));
    }
    sel
}

/// The parameters of a group named in `--params` as `@group` (README "Parameter groups"):
/// `@base` (base frame: `base_*`, with `base_rz` when the model has it), `@tool` (`tool_d*`),
/// `@offsets` (joint offsets), `@chain` (the chain's constant lengths and twists, `base_rz`
/// excepted), in model order.
pub fn param_group(model: &Model, group: &str) -> Result<Vec<usize>, CalibError> {
    let rz = model.param_index("base_rz");
    Ok(match group {
        "base" => {
            let mut v = model.params_of_kind(ParamKind::Base);
            v.extend(rz);
            v
        }
        "tool" => model.params_of_kind(ParamKind::Tool),
        "offsets" => model.params_of_kind(ParamKind::JointOffset),
        "chain" => (0..model.params().len())
            .filter(|&i| {
                Some(i) != rz
                    && matches!(model.params()[i].kind, ParamKind::Twist | ParamKind::Length)
            })
            .collect(),
        _ => {
            return Err(CalibError::Unsupported(format!(
                "--params: unknown group `@{group}` (@base, @tool, @offsets, @chain)"
            )))
        }
    })
}

/// Resolves a selection by names and `@group`s ([`param_group`]), or the default one.
pub fn resolve_selection(model: &Model, opts: &CalibrateOptions) -> Result<Vec<usize>, CalibError> {
    match &opts.params {
        None => Ok(default_selection(model, opts.base)),
        Some(names) => {
            let mut sel = Vec::new();
            for n in names.iter().map(|n| n.trim()).filter(|n| !n.is_empty()) {
                let group = match n.strip_prefix('@') {
                    Some(g) => param_group(model, g)?,
                    None => vec![model.require_param(n)?],
                };
                for i in group {
                    if !sel.contains(&i) {
                        sel.push(i);
                    }
                }
            }
            if sel.is_empty() {
                return Err(CalibError::EmptySelection);
            }
            Ok(sel)
        }
    }
}

/// Result of [`calibrate`].
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The calibrated model (write with `to_toml_string`).
    pub model: Model,
    /// Whether the calibrated model is meant to be evaluated with tilting.
    pub tilt: bool,
    /// The JSON document.
    pub report: CalibrateReport,
    /// Error vectors (measured - model) of the calibration poses: before, standard, chosen.
    pub calibration_errors: [Vec<Vector3<f64>>; 3],
    /// Same for the validation poses (empty without them).
    pub validation_errors: [Vec<Vector3<f64>>; 3],
}

/// Fewest calibration poses on which the gross-error rule is applied.
pub const MIN_POSES_FOR_OUTLIERS: usize = 10;

/// Calibrates `nominal` on `cal` (and evaluates on `val`): the standard identification always
/// (for the comparison), then the chosen method. "before" is the nominal model without tilting.
/// Poses with gross errors ([`super::outliers`]) are left out of the fits and of the statistics
/// and listed in the report (`outliers`), unless [`CalibrateOptions::keep_outliers`].
///
/// Every measured point is a full position here, one pose per point
/// ([`MeasuredSet::as_poses`]); partial measurements, point offsets and the model's terms are
/// [`super::calibrate_general::calibrate_poses`]'s, which calls this for one point per pose.
pub fn calibrate(
    nominal: &Model,
    cal: &MeasuredSet,
    val: Option<&MeasuredSet>,
    opts: &CalibrateOptions,
) -> Result<Outcome, CalibError> {
    let cal = &cal.as_poses();
    let val = val.map(MeasuredSet::as_poses);
    let val = val.as_ref();
    let selection = resolve_selection(nominal, opts)?;
    let tilt = opts.method == Method::Tilting && nominal.has_tilt();
    // Gross errors: fit-and-flag with the declared model (with its tilting when it has one, even
    // for the standard method, whose residual carries the tilting's steps); the last fit on the
    // kept poses is reused when it is the chosen method's.
    let judge_tilt = nominal.has_tilt();
    // the prior of an ill-posed set, chosen once on every pose, used by every fit below
    let prior = choose_prior(
        nominal,
        cal,
        &selection,
        judge_tilt,
        &opts.lm,
        opts.rtol,
        opts.prior,
        &opts.prior_scales,
    )?;
    let at = prior.at(&opts.prior_scales, nominal);
    let fit = |poses: &PosePoints, tilt: bool| {
        fit_parameters(nominal, poses, &selection, tilt, &opts.lm, opts.rtol, at)
    };
    let mut last: Option<(Vec<usize>, Fit)> = None;
    let trimmed = if opts.keep_outliers || cal.len() < MIN_POSES_FOR_OUTLIERS {
        None
    } else {
        Some(outliers::trim(cal.len(), 3, None, |keep| {
            let f = fit(&cal.subset(keep), judge_tilt)?;
            let errors = error_norms_mm(&f.model, cal, judge_tilt)?;
            last = Some((keep.to_vec(), f));
            Ok::<_, CalibError>(errors)
        })?)
    };
    let flagged: Vec<usize> = trimmed
        .as_ref()
        .map_or_else(Vec::new, |t| t.flagged.clone());
    let keep = outliers::kept(cal.len(), &flagged);
    let cal_all = cal;
    let cal_kept;
    let cal: &PosePoints = if flagged.is_empty() {
        cal_all
    } else {
        cal_kept = cal_all.subset(&keep);
        &cal_kept
    };
    // the declared model's fit on the kept poses judges the held-out poses
    let judge: Option<Fit> = last
        .as_ref()
        .filter(|(k, _)| *k == keep)
        .map(|(_, f)| f.clone());
    let reused = last
        .filter(|(k, _)| *k == keep && judge_tilt == tilt)
        .map(|(_, f)| f);
    let standard = match (&reused, tilt) {
        (Some(f), false) => f.clone(),
        _ => fit(cal, false)?,
    };
    let chosen: Fit = match opts.method {
        Method::Standard => standard.clone(),
        Method::Tilting if !tilt => standard.clone(),
        Method::Tilting => match reused {
            Some(f) => f,
            None => fit(cal, true)?,
        },
        Method::Influence => {
            // Same identifiable set as the standard fit; the influence iteration on it.
            let inf = fit_influence(nominal, cal, &standard.fitted, &opts.influence)?;
            let rss_mm2 = position_errors(&inf.model, cal, tilt)?
                .iter()
                .map(|e| e.norm_squared())
                .sum();
            Fit {
                rss_mm2,
                model: inf.model,
                iterations: inf.iterations,
                converged: inf.poses_converged == cal.len(),
                ..standard.clone()
            }
        }
    };
    // "standard" and "chosen" are often the same fit: its errors are computed once.
    let same = matches!(opts.method, Method::Standard) || !tilt && opts.method == Method::Tilting;
    let errs = |p: &PosePoints| -> Result<[Vec<Vector3<f64>>; 3], CalibError> {
        let before = position_errors(nominal, p, false)?;
        let standard_errs = position_errors(&standard.model, p, false)?;
        let chosen_errs = if same {
            standard_errs.clone()
        } else {
            position_errors(&chosen.model, p, tilt)?
        };
        Ok([before, standard_errs, chosen_errs])
    };
    let cal_errors = errs(cal)?;
    // The flagged poses' errors under the final model, and the held-out poses judged by the
    // calibration's scale and the model's prediction uncertainty at each.
    let chosen_errors = |p: &PosePoints| -> Result<Vec<f64>, CalibError> {
        Ok(error_norms_mm(&chosen.model, p, tilt)?)
    };
    // the errors of every held-out pose once; the statistics leave the listed ones out, and
    // `validation_all` keeps them (FORMATS.md)
    let val_all_errors = match val {
        Some(v) => errs(v)?,
        None => [Vec::new(), Vec::new(), Vec::new()],
    };
    let mut outlier_reports = Vec::new();
    let mut extrapolated = Vec::new();
    let mut val_flagged: Vec<usize> = Vec::new();
    if let Some(t) = trimmed.as_ref() {
        let judge_model = judge.as_ref().map_or(&chosen.model, |f| &f.model);
        let judged = |p: &PosePoints| -> Result<Vec<f64>, CalibError> {
            Ok(error_norms_mm(judge_model, p, judge_tilt)?)
        };
        if !flagged.is_empty() {
            let all = chosen_errors(cal_all)?;
            let judged_all = judged(cal_all)?;
            outlier_reports.extend(outliers::reports(
                "cal",
                &flagged,
                &all,
                &judged_all,
                t.threshold_mm,
            ));
        }
        if let Some(v) = val {
            let norms = judged(v)?;
            let judge_fit = judge.as_ref().unwrap_or(&chosen);
            let prior_rows = at.map(|a| a.on(&judge_fit.fitted));
            let sd = prediction_sd_mm(
                judge_fit,
                cal,
                v,
                judge_tilt,
                t.sigma_mm,
                prior_rows.as_ref(),
            )?;
            // outside the calibration's joint ranges the covariance knows nothing: never a
            // gross error there
            let outside = outliers::outside_range(&cal.q_deg, &v.q_deg);
            let judged_sd: Vec<f64> = sd
                .iter()
                .zip(&outside)
                .map(|(s, o)| if o.is_empty() { *s } else { f64::INFINITY })
                .collect();
            let (vflag, thresholds) = outliers::flag_held_out(&norms, &judged_sd, t.sigma_mm);
            let final_norms = norms_mm(&val_all_errors[2]);
            // listed: the poses the calibration's scale alone would call gross errors, that
            // the prediction uncertainty or the joint ranges explain
            let (plain, _) = outliers::flag_held_out(&norms, &vec![0.0; v.len()], t.sigma_mm);
            extrapolated = plain
                .iter()
                .copied()
                .filter(|k| vflag.binary_search(k).is_err())
                .map(|k| outliers::Extrapolated {
                    pose: outliers::PoseError::new("val", k, final_norms[k]),
                    prediction_sd_mm: sd[k],
                    outside_joints: outside[k].clone(),
                })
                .collect();
            if !vflag.is_empty() {
                outlier_reports.extend(outliers::held_out_reports(
                    &vflag,
                    &final_norms,
                    &norms,
                    &thresholds,
                    &sd,
                ));
                val_flagged = vflag;
            }
        }
    }
    let validation_all = val.map(|_| super::report::BeforeAfter {
        before: super::stats::Stats::from_errors(&val_all_errors[0]),
        after: super::stats::Stats::from_errors(&val_all_errors[2]),
    });
    let keep = outliers::kept(val.map_or(0, PosePoints::len), &val_flagged);
    let val_errors = val_all_errors.map(|e| keep.iter().map(|&k| e[k]).collect::<Vec<_>>());
    let mut report = fit_report(
        &chosen,
        &selection,
        opts.method.as_str(),
        &cal_errors,
        val.map(|_| &val_errors),
        tilt,
    );
    report.outliers = outlier_reports;
    report.outlier_note = trimmed.and_then(|t| t.note);
    report.validation_all = validation_all;
    report.extrapolated = extrapolated;
    report.prior = Some(prior).filter(|p| p.chosen_by != "well_posed");
    Ok(Outcome {
        model: chosen.model,
        tilt,
        report,
        calibration_errors: cal_errors,
        validation_errors: val_errors,
    })
}
