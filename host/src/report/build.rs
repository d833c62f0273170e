//! Assembles a [`Report`] from a [`RunDir`] in named steps (models, documents, pose files,
//! diagnosis, path errors, plan and overlays, trajectories, then the first screen): what can be
//! read is used, what cannot is noted.

use serde_json::Value;

use super::analysis::{demo_trajectory, moments_and_tilts, path_error};
use super::captions::{near_zero, path_error_words};
use super::docs::{diagnose_section, param_table, simulation_facts};
use super::extras::{overlay_figures, plan_section};
use super::first_screen::build_summary;
use super::markup::{figure, figure_with};
use super::path_errors::path_errors_section;
use super::pose_sets::pose_sets;
use super::run_dir::RunDir;
use super::suggest::Suggest;
use super::table::{merge_tables, tables_from_calibrate_json};
use super::tree::{tree_facts, tree_pose_sets, POINTS};
use super::{Report, ReportError, ReportOptions};
use crate::model::{choose_model, Model, ModelChoice, Tree};
use crate::plot::{LineChart, Series};

/// The declared robot: the option, else `truth.json`'s, else a diagnose document's.
fn robot_name(run: &RunDir, opts: &ReportOptions) -> Option<String> {
    let from = |v: &Value| v.get("robot").and_then(Value::as_str).map(String::from);
    opts.robot
        .clone()
        .or_else(|| run.truth_json.as_ref().and_then(from))
        .or_else(|| run.diagnose.iter().find_map(|(_, d)| from(d)))
}

struct Models {
    declared: Option<Model>,
    truth: Option<Model>,
    files: Vec<(String, Model)>,
    /// The declared model when `--model` names a tree model file.
    declared_tree: Option<(std::path::PathBuf, Tree)>,
    /// The tree model files of the run.
    tree_files: Vec<(String, Tree)>,
}

fn stem(p: &std::path::Path) -> String {
    p.file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned())
}

fn load_models(
    run: &RunDir,
    robot: Option<&str>,
    opts: &ReportOptions,
    notes: &mut Vec<String>,
) -> Models {
    let declared_tree = match opts.model_file.as_deref().map(Tree::from_file_if_tree) {
        Some(Ok(Some(t))) => opts.model_file.clone().map(|p| (p, t)),
        Some(Err(e)) => {
            notes.push(format!("declared model: {e}; pose files not evaluated"));
            None
        }
        _ => None,
    };
    let declared = match choose_model(&ModelChoice {
        robot: robot.filter(|_| opts.model_file.is_none()),
        model_file: opts.model_file.as_deref(),
        tool_mm: opts.tool_mm,
        sets: &opts.sets,
    }) {
        Ok(m) => Some(m),
        Err(_) if declared_tree.is_some() => None,
        Err(e) => {
            notes.push(format!("declared model: {e}; pose files not evaluated"));
            None
        }
    };
    let truth = run.truth_toml.as_deref().and_then(|p| {
        Model::from_file(p)
            .map_err(|e| notes.push(format!("truth model skipped: {e}")))
            .ok()
    });
    let mut files = Vec::new();
    let mut tree_files = Vec::new();
    // the declared model file is the nominal column already, not a calibrated model of its own
    let declared_file = opts
        .model_file
        .as_deref()
        .and_then(|d| d.canonicalize().ok());
    for p in run
        .models
        .iter()
        .filter(|p| declared_file.is_none() || p.canonicalize().ok() != declared_file)
    {
        match Tree::from_file_if_tree(p) {
            Ok(Some(t)) => tree_files.push((stem(p), t)),
            Ok(None) => match Model::from_file(p) {
                Ok(m) => files.push((stem(p), m)),
                Err(e) => notes.push(format!("model skipped: {e}")),
            },
            Err(e) => notes.push(format!("model skipped: {e}")),
        }
    }
    Models {
        declared,
        truth,
        files,
        declared_tree,
        tree_files,
    }
}

/// Builds the report of `dir`. Fails only when the directory cannot be read or holds nothing
/// usable ([`ReportError::NothingUsable`]).
pub fn build_report(dir: &std::path::Path, opts: &ReportOptions) -> Result<Report, ReportError> {
    let run = RunDir::scan(dir)?;
    let mut notes = run.notes.clone();
    let mut report = Report {
        run_dir: dir.display().to_string(),
        rigctl_version: env!("CARGO_PKG_VERSION"),
        files: run.files.clone(),
        commands: run.commands.clone(),
        ..Default::default()
    };
    let robot = robot_name(&run, opts);
    let models = load_models(&run, robot.as_deref(), opts, &mut notes);
    if let Some(t) = &run.truth_json {
        report.simulation = simulation_facts(t);
    }

    // pose files recomputed first, so that their columns (with per-axis extremes) win the merge
    let mut tables = Vec::new();
    let mut best_model = None;
    let mut pose_counts = Vec::new();
    let tree = tree_facts(&run, models.declared_tree.as_ref());
    let sets = match (&models.declared_tree, &tree, &models.declared) {
        (Some((_, decl)), _, _) => Some(tree_pose_sets(
            &run,
            decl,
            &models.tree_files,
            opts,
            &mut notes,
        )),
        (None, Some(t), _) => {
            if run.cal_csv.is_some() || run.val_csv.is_some() {
                notes.push(format!(
                    "pose files not evaluated: the run is of the tree `{}` ({}); give its tree \
                     model file with --model",
                    t.name, t.source
                ));
            }
            None
        }
        (None, None, Some(decl)) => Some(pose_sets(&run, decl, &models.files, opts, &mut notes)),
        (None, None, None) => None,
    };
    if let Some(sets) = sets {
        tables.extend(sets.tables);
        report.figures.extend(sets.figures);
        best_model = sets.best_model;
        pose_counts = sets.counts;
    }
    let path_errors = run.path_errors.as_ref().and_then(|path| {
        let method = run
            .calibrate
            .first()
            .and_then(|(_, d)| d.get("method"))
            .and_then(Value::as_str);
        path_errors_section(path, method, &mut notes)
    });
    let n_samples = path_errors.as_ref().map(|p| p.summary.n_samples);
    let no_pose_file = run.cal_csv.is_none() && run.val_csv.is_none();
    let noun_of = |n: usize| -> &'static str {
        if tree.is_some() {
            POINTS
        } else if pose_counts.contains(&n) {
            "poses"
        } else if n_samples == Some(n) || (no_pose_file && n_samples.is_some()) {
            "samples"
        } else {
            "poses"
        }
    };
    for (name, doc) in &run.calibrate {
        for t in tables_from_calibrate_json(name, doc) {
            let noun = noun_of(t.n);
            let title = t.title.replace("poses", noun);
            tables.push(super::table::ErrorTable { title, ..t }.with_noun(noun));
        }
        if let Some(p) = param_table(name, doc, models.declared.as_ref(), models.truth.as_ref()) {
            report.parameters.push(p);
        }
    }
    report.tables = merge_tables(tables);
    report.diagnose = run
        .diagnose
        .iter()
        .map(|(name, doc)| diagnose_section(name, doc))
        .collect();
    report.path_errors = path_errors;
    report.plan = plan_section(&run, &mut notes);
    report.overlays = overlay_figures(&run, &mut notes);
    // the demonstration trajectory alone (nominal model only) is not a report of this run
    if report.tables.is_empty()
        && report.parameters.is_empty()
        && report.diagnose.is_empty()
        && report.path_errors.is_none()
        && report.plan.is_none()
    {
        return Err(ReportError::NothingUsable {
            path: dir.to_path_buf(),
            notes,
        });
    }
    // the demonstration trajectory and its plots are a chain's
    if let (Some(decl), None) = (&models.declared, &tree) {
        trajectory_figures(
            decl,
            models.truth.as_ref(),
            best_model.map(|b| &models.files[b]),
            &mut report,
            &mut notes,
        );
    }
    let suggest = Suggest::new(dir, &run, robot.as_deref(), opts);
    report.summary = build_summary(
        &run,
        robot.as_deref(),
        tree.as_ref(),
        &suggest,
        &report,
        &noun_of,
        &mut notes,
    );
    report.notes = notes;
    Ok(report)
}

fn trajectory_figures(
    decl: &Model,
    truth: Option<&Model>,
    best: Option<&(String, Model)>,
    report: &mut Report,
    notes: &mut Vec<String>,
) {
    let Some((demo, traj)) = demo_trajectory(decl) else {
        notes.push(
            "trajectory plots skipped: no demonstration path is reachable with this model".into(),
        );
        return;
    };
    if decl.has_tilt() {
        match moments_and_tilts(decl, &traj) {
            Ok((m, t)) => {
                let nj = decl.n_joints();
                let per_joint = |v: &[Vec<nalgebra::Vector3<f64>>], what: &str| -> Vec<Series> {
                    (0..nj)
                        .map(|j| {
                            Series::new(
                                format!("{what} j{}", j + 1),
                                v.iter().map(|s| s[j].norm()).collect(),
                            )
                        })
                        .filter(|s| s.values.iter().any(|x| *x > 1e-12))
                        .collect()
                };
                let chart = LineChart::moments_tilts(
                    traj.t_s.clone(),
                    per_joint(&m, "|eta|"),
                    per_joint(&t, "|tilt|"),
                );
                report.figures.extend(figure(
                    format!("Joint moments (RNEA, slender-rod links) and the tilts they cause along the {} (thesis fig. 5.8-5.10), nominal model.", demo.name),
                    &chart,
                    notes,
                ));
            }
            Err(e) => notes.push(format!("moments/tilts plot skipped: {e}")),
        }
    }
    match (truth, best) {
        (Some(truth), Some((name, model))) => {
            let before = path_error(decl, truth, &demo);
            let after = path_error(model, truth, &demo);
            if let (Some((s, b)), Some((_, a))) = (before, after) {
                let mut words = path_error_words(&b, &a);
                if truth.has_tilt() && !near_zero(&b, &a) {
                    words.push_str("; the joints are planned with rigid IK, so the robot's tilting under its own weight is not compensated by either plan");
                }
                let series = vec![
                    ("before".to_string(), b.clone()),
                    ("after".to_string(), a.clone()),
                ];
                report.figures.extend(figure_with(
                    format!("Position error along the {} (thesis fig. 5.12), the simulated robot (truth.toml) following joints planned with the nominal model and with {name}: {words}.", demo.name),
                    &LineChart::path_error(
                        s,
                        b,
                        a,
                        [
                            "planned with the nominal model",
                            "planned with the calibrated model",
                        ],
                    ),
                    series,
                    notes,
                ));
            } else {
                notes.push(
                    "path error plot skipped: the path is not reachable with both models".into(),
                );
            }
        }
        _ => notes.push("path error plot needs truth.toml and a calibrated model file".into()),
    }
}
