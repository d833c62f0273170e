//! `rigctl calibrate` on a tree model as a library call: the selection (the chain's rules on
//! every tip's chain, each shared parameter once), the one fit over the tree
//! ([`super::tree_fit::fit_tree`]) and the same `calibrate --json` document as a chain's
//! ([`super::report::unknowns_report`]), over every measured tip point.

use nalgebra::Vector3;

use super::calibrate::{
    default_selection, param_group, CalibrateOptions, Method, MIN_POSES_FOR_OUTLIERS,
};
use super::error::CalibError;
use super::fit::Fit;
use super::large_changes::{large_changes, LargeChange};
use super::measured::MeasuredSet;
use super::outliers;
use super::registered::{registered_summary, registration_options};
use super::report::{unknowns_report, CalibrateReport, StandardSummary};
use super::tree_fit::{check_poses, fit_tree, tree_errors};
use super::tree_held_out::{flag_tree_held_out, pose_norms_mm, TreeHeldOut};
use crate::model::tree_gravity::tree_moments_kgfm;
use crate::model::tree_params::{compliance_joint, lateral_joint};
use crate::model::{Model, ParamKind, Tree};

/// The unknowns of a tree's calibration by tree name, in preference order: `opts.params`
/// (names, or `@group`s taken on every tip's chain as [`param_group`] takes them on a chain), or
/// by default every tip chain's [`default_selection`], each shared parameter once, ordered by
/// kind as a chain's (the base frame with `opts.base`, the tool points, the joint offsets, then
/// the constants). With `compliance`, the compliance of every revolute tree joint follows
/// ([`Tree::compliance_names`]), then its lateral compliance ([`Tree::lateral_names`]; last:
/// kept at 0 where the poses do not identify them); the group `@compliance` in `opts.params`
/// names the same.
pub fn tree_selection(
    tree: &Tree,
    opts: &CalibrateOptions,
    compliance: bool,
) -> Result<Vec<String>, CalibError> {
    if compliance && !tree.has_masses() {
        return Err(CalibError::Unsupported(
            "joint compliance on a tree needs link masses ([[mass]] rows in the tree model \
             file, or --assume-masses / --robot-mass-kg KG): the gravity moments come from them"
                .into(),
        ));
    }
    let chains = tree.chains()?;
    let mut out: Vec<String> = Vec::new();
    let mut add = |name: String| {
        if !out.contains(&name) {
            out.push(name);
        }
    };
    let on_chains = |pick: &dyn Fn(&Model) -> Result<Vec<usize>, CalibError>| {
        let mut named: Vec<(String, usize)> = Vec::new();
        for (t, chain) in chains.iter().enumerate() {
            for i in pick(chain)? {
                let p = &chain.params()[i];
                named.push((tree.tree_param_name(t, &p.name), kind_rank(p.kind)));
            }
        }
        Ok::<_, CalibError>(named)
    };
    match &opts.params {
        None => {
            let mut named = on_chains(&|c| Ok(default_selection(c, opts.base)))?;
            named.sort_by_key(|(_, rank)| *rank);
            named.into_iter().for_each(|(n, _)| add(n));
        }
        Some(names) => {
            for n in names.iter().map(|n| n.trim()).filter(|n| !n.is_empty()) {
                match n.strip_prefix('@') {
                    Some("compliance") => tree
                        .compliance_names()
                        .into_iter()
                        .chain(tree.lateral_names())
                        .for_each(&mut add),
                    Some(g) => on_chains(&|c| param_group(c, g))?
                        .into_iter()
                        .for_each(|(n, _)| add(n)),
                    None => add(n.to_string()),
                }
            }
        }
    }
    if compliance {
        tree.compliance_names()
            .into_iter()
            .chain(tree.lateral_names())
            .for_each(&mut add);
    }
    if out.is_empty() {
        return Err(CalibError::EmptySelection);
    }
    Ok(out)
}

/// The preference of a parameter kind in a default selection (a chain's order).
fn kind_rank(kind: ParamKind) -> usize {
    match kind {
        ParamKind::Base => 0,
        ParamKind::Tool => 1,
        ParamKind::JointOffset => 2,
        _ => 3,
    }
}

/// Result of [`calibrate_tree`].
#[derive(Debug, Clone)]
pub struct TreeOutcome {
    /// The fit: the calibrated tree, the unknowns by tree name, sigmas, identifiability.
    pub fit: Fit<Tree, String>,
    /// The `calibrate --json` document.
    pub report: CalibrateReport,
    /// Error vectors (measured - model, mm) of every measured tip point of the calibration
    /// poses: before, standard, chosen (the standard fit is the chosen one: a tree has no
    /// tilting).
    pub calibration_errors: [Vec<Vector3<f64>>; 3],
    /// Same for the validation poses not listed as gross errors (empty without them).
    pub validation_errors: [Vec<Vector3<f64>>; 3],
    /// The held-out poses listed as gross errors (indices into the validation set, ascending).
    pub validation_flagged: Vec<usize>,
}

/// Calibrates `nominal` on `cal` (and evaluates on `val`) with the options of a chain's
/// calibration: the selection ([`tree_selection`], with the joint compliances when
/// `compliance`), `rtol`, the solver's settings. `tilting`
/// is `standard` here (a tree declares no tilting), as on a chain without tilting data;
/// `influence` is refused. Every measured tip point is a full position; the statistics are
/// over all of them.
pub fn calibrate_tree(
    nominal: &Tree,
    cal: &MeasuredSet,
    val: Option<&MeasuredSet>,
    opts: &CalibrateOptions,
    compliance: bool,
) -> Result<TreeOutcome, CalibError> {
    if opts.method == Method::Influence {
        return Err(CalibError::Unsupported(
            "--method influence is not available on a tree model (standard or tilting, which \
             is standard on a tree)"
                .into(),
        ));
    }
    let mut selection = tree_selection(nominal, opts, compliance)?;
    drop_unloaded(nominal, cal, &mut selection)?;
    // gross errors: the chain's fit-and-flag rule, on the error norm of every pose over its tips
    let trimmed = if opts.keep_outliers || cal.len() < MIN_POSES_FOR_OUTLIERS {
        None
    } else {
        let dims = 3 * nominal.tips.len().max(1);
        Some(outliers::trim(cal.len(), dims, None, |keep| {
            let f = fit_tree(nominal, &cal.subset(keep), &selection, &opts.lm, opts.rtol)?;
            pose_norms_mm(&f.model, cal)
        })?)
    };
    let flagged: Vec<usize> = trimmed
        .as_ref()
        .map_or_else(Vec::new, |t| t.flagged.clone());
    let cal_all = cal;
    let kept_cal = cal.subset(&outliers::kept(cal.len(), &flagged));
    let cal = &kept_cal;
    let (fit, held) = fit_bounded(nominal, cal, &mut selection, opts)?;
    let errors = |poses: &MeasuredSet| -> Result<[Vec<Vector3<f64>>; 3], CalibError> {
        let after = tree_errors(&fit.model, poses)?;
        Ok([tree_errors(nominal, poses)?, after.clone(), after])
    };
    let calibration_errors = errors(cal)?;
    // held-out gross errors, by a chain's rule, when the calibration's were looked for
    let held_out = match (&trimmed, val) {
        (Some(t), Some(v)) => flag_tree_held_out(&fit, cal, v, t.sigma_mm)?,
        _ => TreeHeldOut::default(),
    };
    let validation_all_errors = match val {
        Some(v) => errors(v)?,
        None => [Vec::new(), Vec::new(), Vec::new()],
    };
    // the held-out statistics leave the listed poses out; `validation_all` keeps them
    let validation_errors = match val {
        Some(v) if !held_out.flagged.is_empty() => {
            let kept = outliers::kept(v.len(), &held_out.flagged);
            errors(&v.subset(&kept))?
        }
        _ => validation_all_errors.clone(),
    };
    let entry = |t: &Tree, n: &String| t.param(n).map(|v| (n.clone(), v));
    let mut report = unknowns_report(
        &fit,
        &selection,
        entry,
        opts.method.as_str(),
        &calibration_errors,
        val.map(|_| &validation_errors),
        false,
    );
    report.large_changes = tree_large_changes(nominal, &fit.model)?;
    report.tree = Some(tree_json(nominal));
    report.unphysical.extend(held);
    if let Some(t) = &trimmed {
        let all = pose_norms_mm(&fit.model, cal_all)?;
        report.outliers = outliers::reports("cal", &flagged, &all, &all, t.threshold_mm);
        report.outlier_note = t.note.clone();
    }
    report.validation_all = val.map(|_| super::report::BeforeAfter {
        before: super::stats::Stats::from_errors(&validation_all_errors[0]),
        after: super::stats::Stats::from_errors(&validation_all_errors[2]),
    });
    report.outliers.extend(held_out.reports);
    report.extrapolated = held_out.extrapolated;
    // every pose named by its line and id in its own file
    for r in &mut report.outliers {
        match (r.pose.file.as_str(), val) {
            ("val", Some(v)) => r.pose.label(v),
            _ => r.pose.label(cal_all),
        }
    }
    if let Some(v) = val {
        report.extrapolated.iter_mut().for_each(|e| e.pose.label(v));
    }
    Ok(TreeOutcome {
        fit,
        report,
        calibration_errors,
        validation_errors,
        validation_flagged: held_out.flagged,
    })
}

/// The `tree` object of a tree's `calibrate --json` and `diagnose --json`: its name, tips (in the
/// pose files' point order) and number of joints.
pub fn tree_json(tree: &Tree) -> serde_json::Value {
    serde_json::json!({
        "name": tree.name,
        "tips": tree.tips.iter().map(|t| t.name.clone()).collect::<Vec<_>>(),
        "joints": tree.n_joints(),
    })
}

/// Gravity torques (kgf.m) under which, in every calibration pose, a joint's compliance has
/// nothing to act on (a vertical axis on a level base carries none): not an unknown. The same
/// bound on the perpendicular moment for a lateral compliance.
const MIN_TORQUE_KGFM: f64 = 1e-6;

/// Whether `name` is an axial or lateral compliance (bounded at 0).
fn is_compliance(name: &str) -> bool {
    compliance_joint(name).is_some() || lateral_joint(name).is_some()
}

/// Takes out of `selection` the compliances of joints without gravity torque in any pose of
/// `cal`, and the lateral compliances of joints without perpendicular moment in any (their
/// columns are rounding noise, not a term the poses can tell).
fn drop_unloaded(
    nominal: &Tree,
    cal: &MeasuredSet,
    selection: &mut Vec<String>,
) -> Result<(), CalibError> {
    if !selection.iter().any(|n| is_compliance(n)) {
        return Ok(());
    }
    check_poses(nominal, cal)?;
    let chains = nominal.chains()?;
    let mut loaded = vec![false; nominal.n_joints()];
    let mut bent = vec![false; nominal.n_joints()];
    for q in &cal.poses.q_deg {
        for (j, m) in tree_moments_kgfm(nominal, &chains, q)?.iter().enumerate() {
            loaded[j] |= m.z.abs() >= MIN_TORQUE_KGFM;
            bent[j] |= m.xy().norm() >= MIN_TORQUE_KGFM;
        }
    }
    selection.retain(|n| {
        compliance_joint(n).is_none_or(|j| loaded.get(j) == Some(&true))
            && lateral_joint(n).is_none_or(|j| bent.get(j) == Some(&true))
    });
    if selection.is_empty() {
        return Err(CalibError::EmptySelection);
    }
    Ok(())
}

/// The fit of `selection` with the compliances bounded at 0, as on a chain: a compliance fitted
/// negative (no joint has one) is held at 0 and left out of the selection, and the rest refitted;
/// the held ones are described for the report's `unphysical`.
fn fit_bounded(
    nominal: &Tree,
    cal: &MeasuredSet,
    selection: &mut Vec<String>,
    opts: &CalibrateOptions,
) -> Result<(Fit<Tree, String>, Vec<String>), CalibError> {
    let mut start = nominal.clone();
    let mut held = Vec::new();
    loop {
        let fit = fit_tree(&start, cal, selection, &opts.lm, opts.rtol)?;
        let negative: Vec<(String, f64, f64)> = fit
            .fitted
            .iter()
            .zip(&fit.sigma)
            .filter(|(n, _)| is_compliance(n))
            .filter_map(|(n, s)| {
                let v = fit.model.param(n)?;
                (v < 0.0).then(|| (n.clone(), v, *s))
            })
            .collect();
        // each pass leaves at least one unknown out: it ends
        if negative.is_empty() {
            return Ok((fit, held));
        }
        for (n, v, s) in negative {
            held.push(format!(
                "{n} = {v:.4} +- {s:.4} fitted below its physical bound: held at 0 and left out \
                 of the fit (the term stood in for something the model lacks, e.g. a length or \
                 the link masses)"
            ));
            start.set_param(&n, 0.0)?;
            selection.retain(|u| *u != n);
        }
        if selection.is_empty() {
            return Err(CalibError::EmptySelection);
        }
    }
}

/// The robot's geometry moved beyond a real arm's errors ([`large_changes`]) on any tip's
/// chain, each tree parameter once.
pub fn tree_large_changes(nominal: &Tree, fitted: &Tree) -> Result<Vec<LargeChange>, CalibError> {
    let mut out: Vec<LargeChange> = Vec::new();
    for (t, (a, b)) in nominal.chains()?.iter().zip(fitted.chains()?).enumerate() {
        for mut c in large_changes(a, &b) {
            c.parameter = nominal.tree_param_name(t, &c.parameter);
            if !out.iter().any(|o| o.parameter == c.parameter) {
                out.push(c);
            }
        }
    }
    Ok(out)
}

/// The tree with only the instrument's frame fitted (and, with `with_tool`, every tip's tool
/// point): a chain's [`super::registered::registration_only`] on a tree, the report's
/// `registered`.
pub fn tree_registration_only(
    nominal: &Tree,
    cal: &MeasuredSet,
    val: Option<&MeasuredSet>,
    with_tool: bool,
) -> Result<StandardSummary, CalibError> {
    let opts = registration_options(with_tool);
    Ok(registered_summary(
        &calibrate_tree(nominal, cal, val, &opts, false)?.report,
    ))
}
