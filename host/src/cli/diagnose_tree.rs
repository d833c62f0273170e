//! `rigctl diagnose --model TREE.toml --poses CAL.csv --validate VAL.csv [--instrument-mm S]
//! [--json OUT.json] [--out MODEL.toml] [--assume-masses | --robot-mass-kg KG]`: the diagnosis of
//! a tree model (`rigctl::diagnose::tree`): its geometric calibration over every tip is the
//! declared fit, the axial and lateral compliances of its joints under the whole tree's gravity
//! the candidates. Pose files as `calibrate` on a tree reads them (one point per tip).

use std::fmt::Write as _;

use rigctl::calib::CalibrateOptions;
use rigctl::diagnose::tree::{diagnose_tree, TreeDiagnoseOptions, TreeDiagnosis};
use rigctl::model::Tree;

use super::calibrate_tree::{assumed_masses_json, assumed_masses_line, read, tree_masses};
use super::diagnose::Args;
use super::out::{errln, out};
use super::CliError;

pub fn run(args: &Args, tree: Tree) -> Result<(), CliError> {
    if !args.samples.is_empty() || args.residual_model || args.plots.is_some() || args.marker != 1 {
        return Err(CliError::bad_input(
            "a tree model's diagnosis reads pose files with one point per tip: --samples, \
             --residual-model, --plots and --marker are for a single chain",
        ));
    }
    if args.model.robot.is_some() || !args.model.sets.is_empty() || args.model.tool_mm.is_some() {
        return Err(CliError::bad_input(
            "--robot, --set and --tool-mm are for a single chain (a tree model file declares \
             every tip's tool point)",
        ));
    }
    let Some(poses_path) = args.poses.as_deref() else {
        return Err(CliError::bad_input("--poses is required"));
    };
    let tree = tree_masses(tree, args.assume_masses, args.robot_mass_kg, false)?;
    let cal = read(&args.pose, &tree, poses_path)?;
    let mut val: Option<rigctl::calib::MeasuredSet> = None;
    for path in &args.validate {
        let set = read(&args.pose, &tree, path)?;
        super::pose_args::check_apart(&cal, &set, poses_path, path)?;
        val = Some(match val {
            Some(v) => v.concat(set),
            None => set,
        });
    }
    let val = val.ok_or_else(|| CliError::bad_input("--validate is required"))?;
    let opts = TreeDiagnoseOptions {
        calibrate: CalibrateOptions {
            keep_outliers: args.keep_outliers,
            ..Default::default()
        },
        instrument_mm: super::diagnose::instrument_mm(args)?,
        ..Default::default()
    };
    let spinner = super::diagnose::spinner(format!(
        "diagnose: tree `{}`: declared fit, elastic candidates, cross-validation on {} + {} poses",
        tree.name,
        cal.len(),
        val.len()
    ));
    let diag = diagnose_tree(&tree, &cal, &val, &opts);
    spinner.finish_and_clear();
    let diag = diag?;
    if let Some(path) = &args.json {
        let mut doc = serde_json::to_value(&diag)
            .map_err(|e| CliError::failure(format!("diagnose --json: {e}")))?;
        if let (Some(m), Some(obj)) = (assumed_masses_json(&tree), doc.as_object_mut()) {
            obj.insert("assumed_masses".into(), m);
        }
        rigctl::io::atomic::write_json_atomic(path, &doc)?;
    }
    if let Some(path) = &args.out {
        diag.model.write_file(path)?;
        errln!("tree with the accepted effects -> {}", path.display());
    }
    out!("{}{}", assumed_masses_line(&tree), text(&diag))?;
    if !diag.large_changes.is_empty() {
        let names: Vec<&str> = diag
            .large_changes
            .iter()
            .map(|c| c.parameter.as_str())
            .collect();
        return Err(CliError::failure(format!(
            "the diagnosis moved {} beyond a real arm's errors: check the model, the units and \
             the robot the poses came from (outputs written, JSON `large_changes`)",
            names.join(", ")
        )));
    }
    if !diag.converged {
        return Err(CliError::failure(
            "the final fit did not meet its stopping rule; outputs written with \"converged\": false",
        ));
    }
    Ok(())
}

/// The diagnosis in words: the table of the added effects and the verdict.
fn text(d: &TreeDiagnosis) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "tree `{}`: {} candidates ({}){}",
        d.tree["name"].as_str().unwrap_or(""),
        d.candidates.len(),
        if d.candidates.is_empty() {
            d.candidates_note.as_str()
        } else {
            "axial and lateral compliance of every revolute joint"
        },
        {
            let listed = |file: &str| d.outliers.iter().filter(|o| o.pose.file == file).count();
            match (listed("cal"), listed("val")) {
                (0, 0) => String::new(),
                (c, v) => format!(
                    "; gross errors listed: {c} calibration poses left out, {v} held-out poses \
                     out of the held-out figures (all held out: mean {:.4} mm)",
                    d.final_.validation_all.mean_mm
                ),
            }
        }
    );
    let _ = writeln!(
        s,
        "{:<28} {:>12} {:>12} {:>12}",
        "step", "cal mean mm", "cv mean mm", "held-out mm"
    );
    let _ = writeln!(
        s,
        "{:<28} {:>12.4} {:>12} {:>12.4}",
        "declared (geometric)",
        d.declared.calibration.mean_mm,
        d.effects
            .first()
            .map_or("-".to_string(), |e| format!("{:.4}", e.cv_mean_mm_before)),
        d.declared.validation.mean_mm
    );
    for e in &d.effects {
        let _ = writeln!(
            s,
            "{:<28} {:>12.4} {:>12.4} {:>12.4}",
            format!("+ {}", e.id),
            e.calibration_mean_mm_after,
            e.cv_mean_mm_after,
            e.validation_mean_mm_after
        );
    }
    for e in &d.effects {
        let vals: Vec<String> = e
            .parameters
            .0
            .iter()
            .zip(&e.sigma.0)
            .map(|((n, v), (_, sg))| match sg {
                Some(sg) => format!("{n} = {v:.4} +- {sg:.4}"),
                None => format!("{n} = {v:.4}"),
            })
            .collect();
        let _ = writeln!(s, "{}: {}; {}", e.id, vals.join(", "), e.evidence);
    }
    let _ = writeln!(
        s,
        "final: calibration rms {:.4} mm, held out rms {:.4} mm over {} points",
        d.final_.calibration.rms_mm, d.final_.validation.rms_mm, d.final_.validation.n
    );
    let _ = writeln!(s, "verdict: {}: {}", d.verdict, d.unexplained.note);
    s
}
