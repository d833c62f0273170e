//! `rigctl calibrate --model TREE.toml --poses CAL.csv [--validate VAL.csv] [--params a,b,@group]
//! [--base] [--rtol R] [--method standard|tilting] [--json OUT.json] [--out FITTED.toml]`: one
//! geometric fit over a tree model (`rigctl::calib::tree_calibrate`, the chain's identification
//! on the tree's unknowns). The pose files hold the joints of the whole tree (`q1..qN` in tree
//! order, or the joint names) and one measured point per tip: `x1,y1,z1` on the first `[[tip]]`,
//! `x2,y2,z2` on the second, .. A parameter shared by several tips is one unknown (`NAME@TIP`
//! for a tip's own). The selection, `--json` keys, sigmas, `fixed` / `unidentifiable`, exit codes
//! and the summary are a chain's; the statistics are over every measured tip point.

use std::path::Path;

use std::fmt::Write as _;

use rigctl::calib::calibrate_general::Select;
use rigctl::calib::measured::MeasuredSet;
use rigctl::calib::prior::PriorMode;
use rigctl::calib::tree_calibrate::{calibrate_tree, tree_registration_only};
use rigctl::calib::tree_read::read_tree_set;
use rigctl::calib::CalibrateOptions;
use rigctl::model::Tree;

use super::calibrate::{
    no_redundancy, not_converged, plausible_changes, registers, writes_model, Args,
};
use super::calibrate_text::{report_tail, table};
use super::model_args::ModelArgs;
use super::out::{errln, out};
use super::pose_args::PoseArgs;
use super::CliError;

/// The tree model `--model` names, `None` for a chain (or a preset).
pub fn tree_model(model: &ModelArgs) -> Result<Option<Tree>, CliError> {
    let Some(path) = &model.model else {
        return Ok(None);
    };
    Ok(Tree::from_file_if_tree(path)?)
}

/// The poses of a tree's pose file as the tree's measured set (point k on the k-th tip, the
/// file's lines), checked for units and motion on every tip.
pub(super) fn read(pose: &PoseArgs, tree: &Tree, path: &Path) -> Result<MeasuredSet, CliError> {
    Ok(read_tree_set(path, tree, pose.units, pose.dialect())?)
}

pub fn run(args: &Args, tree: Tree) -> Result<(), CliError> {
    if args.markers.is_some() || args.select != Select::All {
        return Err(CliError::bad_input(
            "a tree model's calibration measures one point per tip (x1,y1,z1 on the first \
             [[tip]] ..): --markers and --select press are for a single chain",
        ));
    }
    if args.hysteresis {
        return Err(CliError::bad_input(
            "--hysteresis: a tree model's calibration has no joint hysteresis yet (it is for a \
             single chain)",
        ));
    }
    if args.prior != PriorMode::default() {
        return Err(CliError::bad_input(
            "--prior: a tree model's calibration has no prior yet (leave --prior at auto)",
        ));
    }
    let Some(poses_path) = args.poses.as_deref() else {
        return Err(CliError::bad_input("--poses is required"));
    };
    let tree = assumed_masses(tree, args)?;
    let poses = read(&args.pose, &tree, poses_path)?;
    let val = args
        .validate
        .as_deref()
        .map(|v| read(&args.pose, &tree, v))
        .transpose()?;
    let opts = CalibrateOptions {
        method: args.method,
        params: args.params.clone(),
        base: args.base,
        rtol: args.rtol,
        keep_outliers: args.keep_outliers,
        ..Default::default()
    };
    let mut o = calibrate_tree(&tree, &poses, val.as_ref(), &opts, args.compliance)?;
    if let Some(with_tool) = registers(args) {
        // as on a chain: a registration that fails leaves the key out
        o.report.registered = tree_registration_only(&tree, &poses, val.as_ref(), with_tool).ok();
    }
    o.report.assumed_masses = assumed_masses_json(&tree);
    let n_points = o.calibration_errors[0].len();
    no_redundancy(poses_path, 3 * n_points, o.report.rank)?;
    let write_model = writes_model(&o.report, args);
    if let Some(path) = &args.json {
        rigctl::io::atomic::write_json_atomic(path, &o.report)?;
    }
    if let (Some(out), true) = (&args.out, write_model) {
        o.fit.model.write_file(out)?;
        errln!("fitted tree -> {}", out.display());
    }
    let mut s = assumed_masses_line(&tree);
    let _ = writeln!(
        s,
        "tree `{}`: {} joints, {} tips; {} poses, {} coordinates; {} unknowns",
        tree.name,
        tree.n_joints(),
        tree.tips.len(),
        poses.len(),
        3 * n_points,
        o.report.parameters.0.len()
    );
    s.push_str(&table(
        "Calibration points (every tip)",
        "points",
        &o.calibration_errors,
        &o.report.method,
    ));
    if val.is_some() {
        s.push('\n');
        s.push_str(&table(
            "Validation points (every tip)",
            "points",
            &o.validation_errors,
            &o.report.method,
        ));
    }
    s.push_str(&report_tail(&o.report));
    let _ = writeln!(
        s,
        "calibration rms {:.4} mm -> {:.4} mm",
        rms_mm(&o.calibration_errors[0]),
        rms_mm(&o.calibration_errors[2])
    );
    if val.is_some() {
        let _ = writeln!(
            s,
            "validation rms {:.4} mm -> {:.4} mm",
            rms_mm(&o.validation_errors[0]),
            rms_mm(&o.validation_errors[2])
        );
    }
    out!("{s}")?;
    plausible_changes(&o.report, args)?;
    not_converged(&o.report)
}

/// RMS (mm) of the coordinates of error vectors.
fn rms_mm(errors: &[nalgebra::Vector3<f64>]) -> f64 {
    let ss: f64 = errors.iter().map(|e| e.norm_squared()).sum();
    (ss / (3 * errors.len()).max(1) as f64).sqrt()
}

/// Whether the selection asks for compliance (`--compliance`, or `@compliance` in `--params`).
fn asks_compliance(args: &Args) -> bool {
    args.compliance
        || args
            .params
            .iter()
            .flatten()
            .any(|p| p.trim() == "@compliance")
}

/// `tree` with assumed link masses when asked (`--assume-masses`, `--robot-mass-kg`); a tree
/// without masses asked for compliance is refused, naming the flags.
fn assumed_masses(tree: Tree, args: &Args) -> Result<Tree, CliError> {
    tree_masses(
        tree,
        args.assume_masses,
        args.robot_mass_kg,
        asks_compliance(args),
    )
}

/// `tree` with assumed link masses when asked (`assume`, or `robot_mass_kg`); refused when the
/// tree declares its own, or when it has none and `needs_masses` (compliance asked) without the
/// flags.
pub(super) fn tree_masses(
    tree: Tree,
    assume: bool,
    robot_mass_kg: Option<f64>,
    needs_masses: bool,
) -> Result<Tree, CliError> {
    let asked = assume || robot_mass_kg.is_some();
    if tree.has_masses() {
        if asked {
            return Err(CliError::bad_input(
                "--assume-masses / --robot-mass-kg: the tree model declares its link masses \
                 (remove the flag, or its [[mass]] rows)",
            ));
        }
        return Ok(tree);
    }
    if !asked {
        if needs_masses {
            return Err(CliError::bad_input(
                "the tree model has no link masses, so no gravity moments for the joint \
                 compliances: give --assume-masses (or --robot-mass-kg KG) to fit them with \
                 assumed masses, or [[mass]] rows with the robot's own",
            ));
        }
        return Ok(tree);
    }
    tree.with_assumed_masses(robot_mass_kg)
        .map_err(|e| CliError::bad_input(format!("--robot-mass-kg: {e}")))
}

/// The line that says the masses are assumed (empty when they are not).
pub(super) fn assumed_masses_line(tree: &Tree) -> String {
    if !tree.masses_assumed {
        return String::new();
    }
    let (total, per) = tree.mass_per_joint_kg();
    let per: Vec<String> = per.iter().map(|kg| format!("{kg:.2}")).collect();
    format!(
        "link masses ASSUMED (none declared): {total:.2} kg in total, {} kg on tree joints \
         1..{}, mid-segment; compliance values are per kgf.m of these assumed moments\n",
        per.join(", "),
        per.len()
    )
}

/// The JSON `assumed_masses` of a tree whose masses are assumed (`diagnose`'s keys).
pub(super) fn assumed_masses_json(tree: &Tree) -> Option<serde_json::Value> {
    tree.masses_assumed.then(|| {
        let (total, per) = tree.mass_per_joint_kg();
        serde_json::json!({
            "total_kg": total,
            "per_joint_kg": per,
            "rule": "one point mass per segment from a joint to each child joint or tip, \
                     mid-segment, in proportion to the segment lengths",
        })
    })
}
