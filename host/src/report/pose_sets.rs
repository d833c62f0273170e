//! The pose files of a run directory (`cal.csv`, `val.csv`) evaluated with the nominal model and
//! every model file (with its transmission terms, in the file's pose order, as `fk` and
//! `calibrate` apply them): a table per set, and the before / after figures with the best model.

use serde_json::Value;

use super::analysis::{
    evaluate, evaluate_in_order, influence_names, most_correlated_joint, parameter_influence,
    Evaluated,
};
use super::captions::{histogram_words, pose_bars_words, scatter_words};
use super::markup::{figure, figure_with};
use super::run_dir::RunDir;
use super::table::{Column, ErrorTable};
use super::Figure;
use super::ReportOptions;
use crate::calib::MeasuredSet;
use crate::io::pose_csv::{PoseCsvError, PoseSpec};
use crate::model::{Model, KATANA_GEOMETRIC_PARAMS};
use crate::plot::{ErrorHistogram, LineChart, PoseErrorBars, Scatter, Series};

/// What the pose files gave.
#[derive(Debug, Default)]
pub(crate) struct PoseSets {
    /// One table per pose file.
    pub tables: Vec<ErrorTable>,
    /// Before / after figures and the influence figure.
    pub figures: Vec<Figure>,
    /// Index in `models` of the best model on the first pose file.
    pub best_model: Option<usize>,
    /// Number of poses of each file read.
    pub counts: Vec<usize>,
}

fn norms(e: &[nalgebra::Vector3<f64>]) -> Vec<f64> {
    e.iter().map(|v| v.norm()).collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// The measured set of a pose file read for `model` (its times when every pose has one: the
/// pose order of the hysteresis terms, FORMATS.md "Pose order").
fn read_set(
    path: &std::path::Path,
    model: &Model,
    opts: &ReportOptions,
) -> Result<MeasuredSet, PoseCsvError> {
    let spec = PoseSpec {
        units: opts.pose_units,
        dialect: opts.pose_dialect,
        ..PoseSpec::for_model(model, true)
    };
    MeasuredSet::read_with(path, &spec)
}

/// A pose file of the run read as a measured set.
pub(super) struct PoseFile<'a> {
    pub path: &'a std::path::Path,
    /// "Calibration poses" or "Held-out poses".
    pub title: &'static str,
    pub held_out: bool,
    pub set: MeasuredSet,
}

/// `cal.csv` and `val.csv` read by `read`; a file with no poses or that cannot be read is a note.
pub(super) fn read_pose_files<'a, E: std::fmt::Display>(
    run: &'a RunDir,
    read: impl Fn(&std::path::Path) -> Result<MeasuredSet, E>,
    notes: &mut Vec<String>,
) -> Vec<PoseFile<'a>> {
    let mut out = Vec::new();
    for (path, title, held_out) in [
        (&run.cal_csv, "Calibration poses", false),
        (&run.val_csv, "Held-out poses", true),
    ] {
        let Some(path) = path else { continue };
        match read(path) {
            Ok(set) if !set.is_empty() => out.push(PoseFile {
                path,
                title,
                held_out,
                set,
            }),
            Ok(_) => notes.push(format!("{}: no poses", path.display())),
            Err(e) => notes.push(format!("{title} skipped: {e}")),
        }
    }
    out
}

/// Index among the model files (after the nominal column `cols[0]`) of the one with the lowest
/// mean error; `None` without model files.
pub(super) fn best_model(cols: &[Evaluated]) -> Option<usize> {
    (1..cols.len())
        .min_by(|&a, &b| {
            mean(&norms(&cols[a].errors_mm)).total_cmp(&mean(&norms(&cols[b].errors_mm)))
        })
        .map(|k| k - 1)
}

/// Evaluates `cal.csv` and `val.csv` with `decl` (nominal, no tilting) and every model.
pub(crate) fn pose_sets(
    run: &RunDir,
    decl: &Model,
    models: &[(String, Model)],
    opts: &ReportOptions,
    notes: &mut Vec<String>,
) -> PoseSets {
    let mut out = PoseSets::default();
    let mut cal_q: Option<Vec<Vec<f64>>> = None;
    for PoseFile {
        path,
        title,
        held_out,
        set,
    } in read_pose_files(run, |p| read_set(p, decl, opts), notes)
    {
        out.counts.push(set.len());
        let mut cols: Vec<Evaluated> = Vec::new();
        match evaluate("nominal model", decl, &set, Some(false)) {
            Ok(e) => cols.push(e),
            Err(e) => {
                notes.push(format!("{title}: nominal model failed: {e}"));
                continue;
            }
        }
        for (name, m) in models {
            match evaluate_in_order(name, m, &set, None) {
                Ok(mut e) => {
                    e.label = format!("{name}.toml{}", if e.tilt { " (tilting)" } else { "" });
                    cols.push(e);
                }
                Err(e) => notes.push(format!("{title}: model {name} skipped: {e}")),
            }
        }
        let columns: Vec<(String, Column)> = cols
            .iter()
            .map(|c| (c.label.clone(), Column::from_errors(&c.errors_mm)))
            .collect();
        let file = path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        out.tables.push(ErrorTable::new(title, &file, &columns));
        // the best model on the calibration poses is "after" in every figure
        if out.best_model.is_none() {
            out.best_model = best_model(&cols);
        }
        match out.best_model.filter(|b| b + 1 < cols.len()) {
            Some(b) => before_after_figures(title, held_out, &set.poses.q_deg, &cols[0], &cols[b + 1], &mut out.figures, notes),
            None => notes.push(format!(
                "{title}: no calibrated model file (*.toml) in the run directory, so no before/after plots"
            )),
        }
        if cal_q.is_none() {
            cal_q = Some(set.poses.q_deg.clone());
        }
    }
    if let Some(q) = &cal_q {
        influence_figure(run, decl, q, &mut out.figures, notes);
    }
    out
}

pub(super) fn before_after_figures(
    title: &str,
    held_out: bool,
    q_deg: &[Vec<f64>],
    before_col: &Evaluated,
    after_col: &Evaluated,
    figures: &mut Vec<Figure>,
    notes: &mut Vec<String>,
) {
    let before = norms(&before_col.errors_mm);
    let after = norms(&after_col.errors_mm);
    let labels = ["nominal model".to_string(), after_col.label.clone()];
    let look = if held_out {
        "these poses were not used in the fit, so this is the error to expect"
    } else {
        "these poses were fitted; compare with the held-out poses"
    };
    let bars = PoseErrorBars {
        title: format!("{title}: error per pose"),
        before_mm: before.clone(),
        after_mm: after.clone(),
        labels: labels.clone(),
    };
    let pair = || {
        vec![
            ("before".to_string(), before.clone()),
            ("after".to_string(), after.clone()),
        ]
    };
    figures.extend(figure_with(
        format!(
            "{title}, every pose sorted by its error with the nominal model: {}; {look}.",
            pose_bars_words(&before, &after)
        ),
        &bars,
        pair(),
        notes,
    ));
    let hist = ErrorHistogram {
        title: format!("{title}: error distribution"),
        before_mm: before.clone(),
        after_mm: after.clone(),
        bins: 20,
        labels: labels.clone(),
    };
    figures.extend(figure_with(
        format!(
            "{title}, histogram of the errors: {}.",
            histogram_words(&before, &after)
        ),
        &hist,
        pair(),
        notes,
    ));
    if let Some((j, r)) = most_correlated_joint(q_deg, &before) {
        let x: Vec<f64> = q_deg.iter().map(|q| q[j]).collect();
        let x_cols: Vec<Vec<f64>> = x.iter().map(|v| vec![*v]).collect();
        let r_after = most_correlated_joint(&x_cols, &after).map(|(_, r)| r);
        let mut series = pair();
        series.push(("x".to_string(), x.clone()));
        let sc = Scatter {
            title: format!("{title}: residual against q{}", j + 1),
            x_label: format!("q{} (deg)", j + 1),
            y_label: "|dP| (mm)".into(),
            x,
            before,
            after,
            labels,
        };
        figures.extend(figure_with(
            format!(
                "{title}, error against q{} (the joint that correlates most with the error before, r = {r:.2}): {}.",
                j + 1,
                scatter_words(j + 1, r_after)
            ),
            &sc,
            series,
            notes,
        ));
    }
}

/// Thesis fig. 3.8 at the poses `q` of the first pose file.
fn influence_figure(
    run: &RunDir,
    decl: &Model,
    q: &[Vec<f64>],
    figures: &mut Vec<Figure>,
    notes: &mut Vec<String>,
) {
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
            figures.extend(figure(
                format!("Influence of each parameter at every pose of the first pose file (thesis fig. 3.8), |dP| for +{} deg or +{} mm: a parameter whose curve stays near zero is poorly identified by these poses.", super::analysis::INFLUENCE_STEP_DEG, super::analysis::INFLUENCE_STEP_MM),
                &LineChart::influence(series),
                notes,
            ));
        }
        Ok(_) => notes.push("influence plot: no angle or length parameter".into()),
        Err(e) => notes.push(format!("influence plot skipped: {e}")),
    }
}
