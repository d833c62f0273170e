//! Assembles a [`Report`] from a [`RunDir`]: what can be read is used, what cannot is noted.

use serde_json::Value;

use super::analysis::{
    demo_trajectory, evaluate, influence_names, moments_and_tilts, most_correlated_joint,
    parameter_influence, path_error, Evaluated,
};
use super::path_errors::path_errors_section;
use super::run_dir::RunDir;
use super::table::{tables_from_calibrate_json, Column, ErrorTable};
use super::{
    DiagnoseSection, EffectRow, Figure, ParamRow, ParamTable, Report, ReportError, ReportOptions,
};
use crate::calib::Poses;
use crate::model::{choose_model, Model, ModelChoice, KATANA_GEOMETRIC_PARAMS};
use crate::plot::{svg_string, Chart, ErrorHistogram, LineChart, PoseErrorBars, Scatter, Series};

fn figure<C: Chart>(caption: String, chart: &C, notes: &mut Vec<String>) -> Option<Figure> {
    match svg_string(chart) {
        Ok(svg) => Some(Figure { caption, svg }),
        Err(e) => {
            notes.push(format!("figure {:?} skipped: {e}", chart.title()));
            None
        }
    }
}

fn norms(e: &[nalgebra::Vector3<f64>]) -> Vec<f64> {
    e.iter().map(|v| v.norm()).collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
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

    // models: declared (nominal), truth, calibrated files
    let robot = opts.robot.clone().or_else(|| {
        run.truth_json
            .as_ref()
            .and_then(|t| t.get("robot"))
            .and_then(Value::as_str)
            .map(String::from)
    });
    let declared = match choose_model(&ModelChoice {
        robot: robot.as_deref(),
        tool_mm: opts.tool_mm,
        ..Default::default()
    }) {
        Ok(m) => Some(m),
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
    let mut models: Vec<(String, Model)> = Vec::new();
    for p in &run.models {
        match Model::from_file(p) {
            Ok(m) => models.push((
                p.file_stem()
                    .map_or_else(String::new, |s| s.to_string_lossy().into_owned()),
                m,
            )),
            Err(e) => notes.push(format!("model skipped: {e}")),
        }
    }
    if let Some(t) = &run.truth_json {
        report.simulation = simulation_facts(t);
    }

    // calibrate JSON documents
    for (name, doc) in &run.calibrate {
        report.tables.extend(tables_from_calibrate_json(name, doc));
        if let Some(p) = param_table(name, doc, declared.as_ref(), truth.as_ref()) {
            report.parameters.push(p);
        }
    }

    // pose files, recomputed
    let mut best_model: Option<usize> = None;
    let mut cal_q: Option<Vec<Vec<f64>>> = None;
    if let Some(decl) = &declared {
        for (path, title) in [
            (&run.cal_csv, "Calibration poses"),
            (&run.val_csv, "Validation poses"),
        ] {
            let Some(path) = path else { continue };
            let poses = match Poses::read(path, decl) {
                Ok(p) if !p.is_empty() => p,
                Ok(_) => {
                    notes.push(format!("{}: no poses", path.display()));
                    continue;
                }
                Err(e) => {
                    notes.push(format!("{title} skipped: {e}"));
                    continue;
                }
            };
            let mut cols: Vec<Evaluated> = Vec::new();
            match evaluate("before (nominal, no tilting)", decl, &poses, Some(false)) {
                Ok(e) => cols.push(e),
                Err(e) => {
                    notes.push(format!("{title}: nominal model failed: {e}"));
                    continue;
                }
            }
            for (name, m) in &models {
                match evaluate(name, m, &poses, None) {
                    Ok(mut e) => {
                        if e.tilt {
                            e.label.push_str(" (tilting)");
                        }
                        cols.push(e);
                    }
                    Err(e) => notes.push(format!("{title}: model {name} skipped: {e}")),
                }
            }
            let columns: Vec<(String, Column)> = cols
                .iter()
                .map(|c| (c.label.clone(), Column::from_errors(&c.errors_mm)))
                .collect();
            report.tables.push(ErrorTable::new(
                &format!("{title} (recomputed)"),
                &path
                    .file_name()
                    .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
                &columns,
            ));
            // the best model on the calibration poses is "after" in every figure
            if best_model.is_none() && cols.len() > 1 {
                best_model = (1..cols.len())
                    .min_by(|&a, &b| {
                        mean(&norms(&cols[a].errors_mm))
                            .total_cmp(&mean(&norms(&cols[b].errors_mm)))
                    })
                    .map(|k| k - 1);
            }
            let before = norms(&cols[0].errors_mm);
            if let Some(b) = best_model.filter(|b| b + 1 < cols.len()) {
                let after_col = &cols[b + 1];
                let after = norms(&after_col.errors_mm);
                let labels = ["before".to_string(), format!("after: {}", after_col.label)];
                let bars = PoseErrorBars {
                    title: format!("{title}: error per pose"),
                    before_mm: before.clone(),
                    after_mm: after.clone(),
                    labels: labels.clone(),
                };
                report.figures.extend(figure(format!("{title}: error of every pose before and after, sorted by the error before."), &bars, &mut notes));
                let hist = ErrorHistogram {
                    title: format!("{title}: error distribution"),
                    before_mm: before.clone(),
                    after_mm: after.clone(),
                    bins: 20,
                    labels: labels.clone(),
                };
                report.figures.extend(figure(
                    format!("{title}: histogram of the pose errors."),
                    &hist,
                    &mut notes,
                ));
                if let Some((j, r)) = most_correlated_joint(&poses.q_deg, &before) {
                    let sc = Scatter {
                        title: format!("{title}: residual against q{}", j + 1),
                        x_label: format!("q{} (deg)", j + 1),
                        y_label: "|dP| (mm)".into(),
                        x: poses.q_deg.iter().map(|q| q[j]).collect(),
                        before,
                        after,
                        labels,
                    };
                    report.figures.extend(figure(format!("{title}: residual against the joint whose reading correlates most with the error before (q{}, r = {r:.2}).", j + 1), &sc, &mut notes));
                }
            } else {
                notes.push(format!("{title}: no calibrated model file (*.toml) in the run directory, so no before/after plots"));
            }
            if cal_q.is_none() {
                cal_q = Some(poses.q_deg.clone());
            }
        }
        // fig. 3.8
        if let Some(q) = &cal_q {
            let preferred: Vec<String> = run
                .calibrate
                .first()
                .and_then(|(_, d)| d.get("parameters"))
                .and_then(Value::as_object)
                .map(|o| o.keys().cloned().collect())
                .unwrap_or_else(|| {
                    KATANA_GEOMETRIC_PARAMS
                        .iter()
                        .map(|s| s.to_string())
                        .collect()
                });
            let names = influence_names(decl, &preferred);
            match parameter_influence(decl, q, &names) {
                Ok(inf) if !inf.is_empty() => {
                    let series = inf
                        .into_iter()
                        .map(|i| {
                            Series::new(
                                format!("{} +{} {}", i.name, i.step, i.unit.label()),
                                i.dp_mm,
                            )
                        })
                        .collect();
                    report.figures.extend(figure(
                        format!("Influence of each parameter per configuration (thesis fig. 3.8): |dP| caused by +{} deg or +{} mm on each parameter of the nominal model, at every pose of the first pose file.", super::analysis::INFLUENCE_STEP_DEG, super::analysis::INFLUENCE_STEP_MM),
                        &LineChart::influence(series),
                        &mut notes,
                    ));
                }
                Ok(_) => notes.push("influence plot: no angle or length parameter".into()),
                Err(e) => notes.push(format!("influence plot skipped: {e}")),
            }
        }
    }
    if let Some((name, doc)) = &run.diagnose {
        report.diagnose = Some(diagnose_section(name, doc));
    }
    if let Some(path) = &run.path_errors {
        let method = run
            .calibrate
            .first()
            .and_then(|(_, d)| d.get("method"))
            .and_then(Value::as_str);
        report.path_errors = path_errors_section(path, method, &mut notes);
    }
    // the demonstration trajectory alone (nominal model only) is not a report of this run
    if report.tables.is_empty()
        && report.parameters.is_empty()
        && report.diagnose.is_none()
        && report.path_errors.is_none()
    {
        return Err(ReportError::NothingUsable {
            path: dir.to_path_buf(),
            notes,
        });
    }
    if let Some(decl) = &declared {
        trajectory_figures(
            decl,
            truth.as_ref(),
            best_model.map(|b| &models[b]),
            &mut report,
            &mut notes,
        );
    }
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
                    format!("Joint moments (RNEA, slender-rod links) and the tilts they cause along the {} (thesis fig. 5.8-5.10), nominal model; magnitudes of the vectors in joint frame i.", demo.name),
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
                let chart = LineChart::path_error(
                    s,
                    b,
                    a,
                    [
                        "planned with the nominal model",
                        "planned with the calibrated model",
                    ],
                );
                report.figures.extend(figure(
                    format!("Position error along the {} (thesis fig. 5.12): the simulated robot (truth.toml, tilting from the dynamic moments) follows joints planned with the rigid IK of the nominal model and of {name}.", demo.name),
                    &chart,
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

fn simulation_facts(t: &Value) -> Vec<(String, String)> {
    [
        "format",
        "seed",
        "robot",
        "noise_mm",
        "tilt",
        "cal_poses",
        "val_poses",
        "effects",
        "time_drift",
    ]
    .iter()
    .filter_map(|k| t.get(*k).map(|v| (k.to_string(), compact(v))))
    .collect()
}

fn compact(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

fn param_table(
    name: &str,
    doc: &Value,
    decl: Option<&Model>,
    truth: Option<&Model>,
) -> Option<ParamTable> {
    let params = doc.get("parameters")?.as_object()?;
    let sigma = doc.get("sigma").and_then(Value::as_object);
    let rows = params
        .iter()
        .filter_map(|(k, v)| {
            Some(ParamRow {
                name: k.clone(),
                value: v.as_f64()?,
                sigma: sigma.and_then(|s| s.get(k)).and_then(Value::as_f64),
                nominal: decl.and_then(|m| m.param(k)),
                truth: truth.and_then(|m| m.param(k)),
            })
        })
        .collect();
    Some(ParamTable {
        source: name.to_string(),
        method: doc
            .get("method")
            .and_then(Value::as_str)
            .unwrap_or("")
            .to_string(),
        rows,
        unidentifiable: doc
            .get("unidentifiable")
            .and_then(Value::as_array)
            .map(|a| a.iter().map(compact).collect())
            .unwrap_or_default(),
        condition_number: doc.get("condition_number").and_then(Value::as_f64),
    })
}

fn diagnose_section(name: &str, doc: &Value) -> DiagnoseSection {
    let mut tables = Vec::new();
    for set in ["calibration", "validation"] {
        let cols: Vec<(String, Column)> =
            [("declared", "declared model"), ("final", "final model")]
                .iter()
                .filter_map(|(k, label)| {
                    doc.get(*k)
                        .and_then(|s| s.get(set))
                        .and_then(Column::from_json)
                        .map(|c| (label.to_string(), c))
                })
                .collect();
        if !cols.is_empty() {
            tables.push(ErrorTable::new(
                &format!("diagnose: {set} poses"),
                name,
                &cols,
            ));
        }
    }
    let effects = doc
        .get("effects")
        .and_then(Value::as_array)
        .map(|a| {
            a.iter()
                .map(|e| EffectRow {
                    id: e.get("id").map(compact).unwrap_or_default(),
                    parameters: e
                        .get("parameters")
                        .and_then(Value::as_object)
                        .map(|o| {
                            o.iter()
                                .map(|(k, v)| {
                                    format!(
                                        "{k} = {}",
                                        v.as_f64()
                                            .map_or_else(|| compact(v), |x| format!("{x:.6}"))
                                    )
                                })
                                .collect::<Vec<_>>()
                                .join(", ")
                        })
                        .unwrap_or_default(),
                    validation_mean_mm_before: e
                        .get("validation_mean_mm_before")
                        .and_then(Value::as_f64),
                    validation_mean_mm_after: e
                        .get("validation_mean_mm_after")
                        .and_then(Value::as_f64),
                    evidence: e.get("evidence").map(compact).unwrap_or_default(),
                })
                .collect()
        })
        .unwrap_or_default();
    let unexplained = doc
        .get("unexplained")
        .map(|u| {
            let structured = u
                .get("structured")
                .and_then(Value::as_bool)
                .unwrap_or(false);
            let note = u.get("note").map(compact).unwrap_or_default();
            format!(
                "{}{note}",
                if structured {
                    "structured residual remains: "
                } else {
                    ""
                }
            )
        })
        .unwrap_or_default();
    DiagnoseSection {
        source: name.to_string(),
        tables,
        effects,
        unexplained,
    }
}
