//! A tree's run in the report: which tree the documents are of (`tree` of a `calibrate*.json`
//! or `diagnose*.json`, or the declared tree model), its statistics counted in points (one per
//! tip of every pose), and its pose files evaluated with the nominal tree and every tree model
//! file of the run: a table over every tip and one per tip, the before / after figures per tip.

use std::path::PathBuf;

use nalgebra::Vector3;
use serde_json::Value;

use super::analysis::Evaluated;
use super::pose_sets::{before_after_figures, best_model, read_pose_files, PoseFile, PoseSets};
use super::run_dir::RunDir;
use super::table::{Column, ErrorTable};
use super::ReportOptions;
use crate::calib::measured::MeasuredSet;
use crate::calib::tree_fit::tree_errors;
use crate::calib::tree_read::read_tree_set;
use crate::model::Tree;

/// The noun of a tree's statistics: every tip's point of every pose.
pub const POINTS: &str = "points";

/// Which tree a run is of.
#[derive(Debug, Clone, PartialEq)]
pub struct TreeFacts {
    /// The tree's name.
    pub name: String,
    /// Its joints.
    pub joints: usize,
    /// Its tips, in the pose files' point order.
    pub tips: Vec<String>,
    /// Where it was read (a document's or the model file's name).
    pub source: String,
}

impl TreeFacts {
    fn of_tree(tree: &Tree, source: String) -> Self {
        Self {
            name: tree.name.clone(),
            joints: tree.n_joints(),
            tips: tree.tips.iter().map(|t| t.name.clone()).collect(),
            source,
        }
    }

    /// The `tree` object of a `calibrate --json` or `diagnose --json` document.
    fn of_doc(doc: &Value, source: &str) -> Option<Self> {
        let t = doc.get("tree")?;
        Some(Self {
            name: t.get("name")?.as_str()?.to_string(),
            joints: t.get("joints")?.as_u64()? as usize,
            tips: t
                .get("tips")?
                .as_array()?
                .iter()
                .map(|v| v.as_str().map(String::from))
                .collect::<Option<_>>()?,
            source: source.to_string(),
        })
    }

    /// The robot line of the first screen.
    pub fn robot_line(&self) -> String {
        format!(
            "Robot: the tree `{}` ({} joints; tips {}; from {}): every figure is over each \
             tip's point of a pose ({} per pose), counted as points.",
            self.name,
            self.joints,
            self.tips.join(", "),
            self.source,
            self.tips.len()
        )
    }
}

/// The tree of the run: the declared tree model, else the first document's `tree`.
pub(crate) fn tree_facts(run: &RunDir, declared: Option<&(PathBuf, Tree)>) -> Option<TreeFacts> {
    if let Some((path, tree)) = declared {
        let name = path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        return Some(TreeFacts::of_tree(tree, name));
    }
    run.calibrate
        .iter()
        .chain(&run.diagnose)
        .find_map(|(name, doc)| TreeFacts::of_doc(doc, name))
}

/// The tip of every measured point of `set`, in the order of its error vectors, with the joint
/// readings of the pose it was measured in.
fn point_tips(set: &MeasuredSet) -> Vec<(usize, &[f64])> {
    (0..set.len())
        .flat_map(|k| set.measured_of(k))
        .map(|m| (set.tip(m.slot), set.poses.q_deg[m.pose].as_slice()))
        .collect()
}

/// The error vectors of tip `t` among `all` (one per measured point, as `point_tips`).
fn of_tip(all: &[Vector3<f64>], tips: &[(usize, &[f64])], t: usize) -> Vec<Vector3<f64>> {
    tips.iter()
        .zip(all)
        .filter(|((tip, _), _)| *tip == t)
        .map(|(_, e)| *e)
        .collect()
}

/// Evaluates `cal.csv` and `val.csv` with the nominal tree `decl` and every tree model file.
pub(crate) fn tree_pose_sets(
    run: &RunDir,
    decl: &Tree,
    models: &[(String, Tree)],
    opts: &ReportOptions,
    notes: &mut Vec<String>,
) -> PoseSets {
    let mut out = PoseSets::default();
    let read = |p: &std::path::Path| read_tree_set(p, decl, opts.pose_units, opts.pose_dialect);
    for PoseFile {
        path,
        title,
        held_out,
        set,
    } in read_pose_files(run, read, notes)
    {
        out.counts.push(set.n_measured_points());
        let mut cols: Vec<Evaluated> = Vec::new();
        for (label, tree) in std::iter::once(("nominal model".to_string(), decl))
            .chain(models.iter().map(|(n, t)| (format!("{n}.toml"), t)))
        {
            match tree_errors(tree, &set) {
                Ok(errors_mm) => cols.push(Evaluated {
                    label,
                    tilt: false,
                    errors_mm,
                }),
                Err(e) => notes.push(format!("{title}: model {label} skipped: {e}")),
            }
        }
        if cols.first().is_none_or(|c| c.label != "nominal model") {
            continue;
        }
        let file = path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        let columns = |pick: &dyn Fn(&Evaluated) -> Vec<Vector3<f64>>| -> Vec<(String, Column)> {
            cols.iter()
                .map(|c| (c.label.clone(), Column::from_errors(&pick(c))))
                .collect()
        };
        // every tip (the calibrate document's statistics), then each tip
        out.tables.push(
            ErrorTable::new(title, &file, &columns(&|c| c.errors_mm.clone())).with_noun(POINTS),
        );
        let point_tip = point_tips(&set);
        for (t, tip) in decl.tips.iter().enumerate() {
            out.tables.push(
                ErrorTable::new(
                    &format!("{title}, tip `{}`", tip.name),
                    &file,
                    &columns(&|c| of_tip(&c.errors_mm, &point_tip, t)),
                )
                .with_noun("poses"),
            );
        }
        // the best model on the calibration poses is "after" in every figure
        if out.best_model.is_none() {
            out.best_model = best_model(&cols);
        }
        let Some(b) = out.best_model.filter(|b| b + 1 < cols.len()) else {
            notes.push(format!(
                "{title}: no calibrated tree model file (*.toml) in the run directory, so no \
                 before/after plots"
            ));
            continue;
        };
        for (t, tip) in decl.tips.iter().enumerate() {
            let at = |k: usize| Evaluated {
                label: cols[k].label.clone(),
                tilt: false,
                errors_mm: of_tip(&cols[k].errors_mm, &point_tip, t),
            };
            let q_deg: Vec<Vec<f64>> = point_tip
                .iter()
                .filter(|(tip, _)| *tip == t)
                .map(|(_, q)| q.to_vec())
                .collect();
            before_after_figures(
                &format!("{title}, tip `{}`", tip.name),
                held_out,
                &q_deg,
                &at(0),
                &at(b + 1),
                &mut out.figures,
                notes,
            );
        }
    }
    out
}
