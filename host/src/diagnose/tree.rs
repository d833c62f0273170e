//! `diagnose` on a tree model: the geometric calibration of the whole tree is the declared fit,
//! and the elastic effects of the tree's joints are the candidates - `compliance:j<i>` (about
//! the axis, under the whole tree's gravity torque) and `lateral_compliance:j<i>` (across it,
//! under the whole tree's perpendicular moments), `j<i>` the tree joint (1-based, tree order).
//! Forward selection as on a chain, then swaps ([`select`]): every candidate refitted with
//! everything accepted so far (the tree's one identification, compliances bounded at 0), the
//! one that lowers the residual most accepted when the nested F-test (`p <`
//! [`TreeDiagnoseOptions::alpha`]), the BIC and a cross-validation over folds of the calibration
//! poses all say so; then each accepted effect is tried against every candidate left and
//! replaced where that lowers the residual. The held-out set is only reported. Candidates whose
//! swap for an accepted effect leaves the residual within noise are listed as its `equivalent`
//! (an axial and a lateral compliance the poses cannot tell apart, or two joints that share an
//! origin). The report replays the accepted effects in order, one step each.
//!
//! Without link masses (declared or assumed) no elastic candidate exists; the report says so.

use nalgebra::Vector3;
use serde::Serialize;

use super::floor::{self, FinalResidual, FloorReport};
use super::ordered::Ordered;
use super::report::{EffectReport, SetStats, Unexplained};
use super::stat::{delta_bic, nested_f_test};
use crate::calib::large_changes::LargeChange;
use crate::calib::outliers::OutlierReport;
use crate::calib::tree_calibrate::{calibrate_tree, tree_large_changes, tree_selection};
use crate::calib::tree_fit::tree_errors;
use crate::calib::{CalibError, CalibrateOptions, MeasuredSet, Stats};
use crate::model::effect::EffectId;
use crate::model::tree_params::{compliance_joint, lateral_joint};
use crate::model::Tree;

pub mod select;
pub mod where_to_look;

use select::{replay_order, select, Candidate, Fits, Trial};

/// What a tree diagnosis is asked.
#[derive(Debug, Clone)]
pub struct TreeDiagnoseOptions {
    /// The calibration's options (the declared selection: `params`, `base`; the solver).
    pub calibrate: CalibrateOptions,
    /// One-sigma accuracy per coordinate of the instrument (mm): the floor.
    pub instrument_mm: Option<f64>,
    /// Significance level of the F-test.
    pub alpha: f64,
}

impl Default for TreeDiagnoseOptions {
    fn default() -> Self {
        Self {
            calibrate: CalibrateOptions::default(),
            instrument_mm: None,
            alpha: 1e-3,
        }
    }
}

/// The tree diagnosis (FORMATS.md "diagnose --json", with `tree` and the candidates tried).
#[derive(Debug, Clone, Serialize)]
pub struct TreeDiagnosis {
    /// The tree with the accepted effects fitted (for `--out`).
    #[serde(skip)]
    pub model: Tree,
    pub declared: SetStats,
    pub effects: Vec<EffectReport>,
    #[serde(rename = "final")]
    pub final_: SetStats,
    pub unexplained: Unexplained,
    pub floor: FloorReport,
    pub aliased: Vec<serde_json::Value>,
    /// The tree: its name and tips.
    pub tree: serde_json::Value,
    /// The elastic candidates offered (empty without link masses), and why not when empty.
    pub candidates: Vec<String>,
    pub candidates_note: String,
    /// Poses listed as gross errors by the declared fit (FORMATS.md "Gross errors": calibration
    /// poses left out of every fit, held-out poses out of the held-out statistics but in
    /// `validation_all`).
    pub outliers: Vec<OutlierReport>,
    /// Final residual statistics are judged `floor` or `missing_effect`.
    pub verdict: String,
    /// Whether the final fit's solver met its stopping rule.
    pub converged: bool,
    /// Parameters the final fit moved beyond a real arm's errors (a chain's rule on every tip's
    /// chain): the model, the units or the robot the poses came from are to be checked.
    pub large_changes: Vec<LargeChange>,
}

/// The elastic candidates of `tree`: the axial then the lateral compliance of every revolute
/// joint (none without link masses).
fn candidates(tree: &Tree) -> Vec<Candidate> {
    if !tree.has_masses() {
        return Vec::new();
    }
    let axial = tree.compliance_names().into_iter().filter_map(|p| {
        let j = compliance_joint(&p)?;
        Some(Candidate {
            id: EffectId::Compliance(j).to_string(),
            param: p,
            joint: j,
        })
    });
    let lateral = tree.lateral_names().into_iter().filter_map(|p| {
        let j = lateral_joint(&p)?;
        Some(Candidate {
            id: EffectId::LateralCompliance(j).to_string(),
            param: p,
            joint: j,
        })
    });
    axial.chain(lateral).collect()
}

/// Mean error norm (mm) of a set of error vectors.
fn mean_mm(e: &[Vector3<f64>]) -> f64 {
    Stats::from_errors(e).mean_mm
}

/// What a candidate's effect follows: the moment it acts under.
fn regressor(c: &Candidate) -> String {
    if lateral_joint(&c.param).is_some() {
        format!(
            "perpendicular gravity moment at tree joint {} (whole tree)",
            c.joint + 1
        )
    } else {
        format!(
            "gravity torque about tree joint {} (whole tree)",
            c.joint + 1
        )
    }
}

/// The values (and sigmas) of the tree parameters `params` in a trial's fit.
fn values(t: &Trial, params: &[String]) -> (Ordered<f64>, Ordered<Option<f64>>) {
    let fit = &t.outcome.fit;
    let v = params
        .iter()
        .map(|p| (p.clone(), fit.model.param(p).unwrap_or(0.0)))
        .collect();
    let s = params
        .iter()
        .map(|p| {
            let s = fit
                .fitted
                .iter()
                .position(|u| u == p)
                .map(|i| fit.sigma[i])
                .filter(|s| s.is_finite());
            (p.clone(), s)
        })
        .collect();
    (v, s)
}

/// Diagnoses `nominal` on `cal`, held out `val` (see the module doc).
pub fn diagnose_tree(
    nominal: &Tree,
    cal: &MeasuredSet,
    val: &MeasuredSet,
    opts: &TreeDiagnoseOptions,
) -> Result<TreeDiagnosis, CalibError> {
    let declared_sel = tree_selection(nominal, &opts.calibrate, false)?;
    // the declared fit, with the gross-error rule of a tree's calibration
    let first = calibrate_tree(nominal, cal, Some(val), &opts.calibrate, false)?;
    let outliers = first.report.outliers.clone();
    let cal_flagged: Vec<usize> = outliers
        .iter()
        .filter(|o| o.pose.file == "cal")
        .map(|o| o.pose.index)
        .collect();
    let kept: Vec<usize> = (0..cal.len())
        .filter(|k| !cal_flagged.contains(k))
        .collect();
    let cal = cal.subset(&kept);
    // the held-out poses listed as gross errors by the declared fit are left out of every
    // held-out statistic after it, and kept in `validation_all`
    let val_all = val;
    let val = &val.subset(&crate::calib::outliers::kept(
        val.len(),
        &first.validation_flagged,
    ));
    let stats = |t: &Trial| -> Result<SetStats, CalibError> {
        Ok(SetStats {
            calibration: Stats::from_errors(&t.outcome.calibration_errors[2]),
            validation: Stats::from_errors(&t.outcome.validation_errors[2]),
            validation_all: Stats::from_errors(&tree_errors(&t.outcome.fit.model, val_all)?),
        })
    };
    let fits = Fits::new(nominal, &cal, &opts.calibrate, &declared_sel);
    // the declared fit is the calibration's own (refitted on the kept poses after the gross
    // errors, as every trial is): the selection starts from it
    let declared_fit = Trial::from(first);
    let declared = stats(&declared_fit)?;
    let all = candidates(nominal);
    let candidates_note = if all.is_empty() {
        "no elastic candidate: the tree model has no link masses, so no gravity moments \
         (declare [[mass]] rows, or give --assume-masses / --robot-mass-kg)"
            .to_string()
    } else {
        String::new()
    };
    let chosen = select(&fits, &all, declared_fit.clone(), opts.alpha)?;
    // the report: one step per accepted effect, in order
    let mut current = declared_fit;
    let mut cv_current = fits.cv_mean_mm(&[])?;
    let mut effects: Vec<EffectReport> = Vec::new();
    let mut extra: Vec<String> = Vec::new();
    let order = replay_order(&fits, &chosen.accepted, &current)?;
    for c in &order {
        let equivalent = chosen
            .accepted
            .iter()
            .position(|a| a == c)
            .and_then(|i| chosen.equivalent.get(i))
            .cloned()
            .unwrap_or_default();
        extra.push(c.param.clone());
        let t = fits.fit(&current.outcome.fit.model, None, Some(val), &extra)?;
        let added = t.n_fitted.saturating_sub(current.n_fitted);
        let dof = t.m.saturating_sub(t.n_fitted);
        let (f, p) = nested_f_test(current.rss_mm2, t.rss_mm2, added, dof);
        let dbic = delta_bic(t.m, current.rss_mm2, t.rss_mm2, added);
        let cv_after = fits.cv_mean_mm(&extra)?;
        let swapped: Vec<&str> = chosen
            .swaps
            .iter()
            .filter(|(_, b)| *b == c.id)
            .map(|(a, _)| a.as_str())
            .collect();
        let evidence =
            format!(
            "F = {f:.1} (p = {p:.1e}), BIC {dbic:+.1}, cross-validated mean {cv_current:.4} -> \
             {cv_after:.4} mm{}{}",
            if swapped.is_empty() {
                String::new()
            } else {
                format!("; in place of {} (a lower residual with the others)", swapped.join(", "))
            },
            if equivalent.is_empty() {
                String::new()
            } else {
                format!("; equivalent on these poses: {}", equivalent.join(", "))
            }
        );
        let (at_entry, sigma_at_entry) = values(&t, std::slice::from_ref(&c.param));
        effects.push(EffectReport {
            id: c.id.clone(),
            parameters: at_entry.clone(),
            sigma: sigma_at_entry.clone(),
            parameters_at_entry: at_entry,
            validation_mean_mm_before: mean_mm(&current.outcome.validation_errors[2]),
            validation_mean_mm_after: mean_mm(&t.outcome.validation_errors[2]),
            evidence,
            equivalent: equivalent.clone(),
            uncertainty: sigma_at_entry,
            calibration_mean_mm_before: mean_mm(&current.outcome.calibration_errors[2]),
            calibration_mean_mm_after: mean_mm(&t.outcome.calibration_errors[2]),
            cv_mean_mm_before: cv_current,
            cv_mean_mm_after: cv_after,
            p_value: p,
            f_statistic: f,
            delta_bic: dbic,
            added_parameters: added,
            regressor: regressor(c),
            unidentifiable: Vec::new(),
            model_parameters: values(&t, &extra).0,
        });
        current = t;
        cv_current = cv_after;
    }
    let accepted = order;
    // every effect's values in the final fit
    for (e, c) in effects.iter_mut().zip(&accepted) {
        let (v, s) = values(&current, std::slice::from_ref(&c.param));
        e.parameters = v;
        e.sigma = s.clone();
        e.uncertainty = s;
    }
    let final_ = stats(&current)?;
    let val_errors = &current.outcome.validation_errors[2];
    let floor = floor::judge(
        &FinalResidual {
            rss_mm2: current.rss_mm2,
            n_residuals: current.m,
            n_params: current.n_fitted,
            tau: 1.0,
            n_poses: cal.len(),
            val_ss_mm2: val_errors.iter().map(|e| e.norm_squared()).sum(),
            val_residuals: 3 * val_errors.len(),
        },
        opts.instrument_mm,
        floor::repeatability_of_files(&[&cal, val]),
    );
    let verdict = if floor.used == "residual" {
        "no_floor"
    } else if floor.above {
        "missing_effect"
    } else {
        "floor"
    };
    let note = match verdict {
        "floor" => format!(
            "the final residual ({:.4} mm per coordinate, held out {:.4}) is at the {} floor \
             ({:.2} x)",
            floor.residual_mm, floor.validation_rms_mm, floor.used, floor.final_over_floor
        ),
        "missing_effect" => format!(
            "the final residual ({:.4} mm per coordinate, held out {:.4}) is {:.2} x the {} \
             floor: the tree model lacks something its elastic candidates do not describe (a \
             tree has no residual probe yet: the regressor scan of every tip's residual says \
             where to look)",
            floor.residual_mm,
            floor.validation_rms_mm,
            floor.final_over_floor.max(floor.validation_over_floor),
            floor.used
        ),
        _ => "no instrument figure and no repeated poses: the final residual is its own floor, \
              so a missing effect cannot be told from noise (give --instrument-mm)"
            .to_string(),
    };
    let mut unexplained = Unexplained {
        structured: floor.above,
        note,
        depends_on: Vec::new(),
        explainable_share: 0.0,
        depends_on_shares: Vec::new(),
    };
    if verdict == "missing_effect" {
        let shares = where_to_look::tree_regressor_shares(
            &current.outcome.fit.model,
            &cal,
            &current.outcome.calibration_errors[2],
        );
        unexplained.add_where_to_look(&shares);
    }
    Ok(TreeDiagnosis {
        model: current.outcome.fit.model.clone(),
        declared,
        effects,
        final_,
        unexplained,
        floor,
        aliased: Vec::new(),
        tree: crate::calib::tree_calibrate::tree_json(nominal),
        candidates: all.iter().map(|c| c.id.clone()).collect(),
        candidates_note,
        outliers,
        verdict: verdict.to_string(),
        converged: current.outcome.fit.converged,
        large_changes: tree_large_changes(nominal, &current.outcome.fit.model)?,
    })
}
