//! `rigctl calibrate --model TREE.toml --poses CAL.csv [--validate VAL.csv] [--params a,b,..]
//! [--out FITTED.toml]`: one geometric fit over a tree model (`rigctl::calib::tree_fit`). The
//! pose files hold the joints of the whole tree (`q1..qN` in tree order, or the joint names) and
//! one measured point per tip: `x1,y1,z1` on the first `[[tip]]`, `x2,y2,z2` on the second, ..
//! A parameter shared by several tips is one unknown. Without `--params` the unknowns are the
//! identifiable ones of every constant, joint offset and tip tool point (`NAME@TIP`).

use std::path::Path;

use rigctl::calib::tree_fit::{fit_tree, identifiable, tree_candidates, tree_rms_mm, TreePose};
use rigctl::io::pose_csv::{read_poses, PoseSpec};
use rigctl::model::tree_file::is_tree_text;
use rigctl::model::{ModelError, Tree};

use super::calibrate::Args;
use super::model_args::ModelArgs;
use super::out::{errln, outln};
use super::CliError;

/// The tree model `--model` names, `None` for a chain (or a preset).
pub fn tree_model(model: &ModelArgs) -> Result<Option<Tree>, CliError> {
    let Some(path) = &model.model else {
        return Ok(None);
    };
    let text = rigctl::io::read::read_text_capped(path, rigctl::io::read::CAP_SMALL_TEXT).map_err(
        |source| ModelError::Read {
            path: path.clone(),
            source,
        },
    )?;
    if !is_tree_text(&text) {
        return Ok(None);
    }
    Ok(Some(Tree::from_toml_str(
        &text,
        &path.display().to_string(),
    )?))
}

fn read(args: &Args, tree: &Tree, path: &Path) -> Result<Vec<TreePose>, CliError> {
    let spec = PoseSpec {
        n_joints: tree.n_joints(),
        limits: tree.joint_limits(),
        require_xyz: true,
        joint_names: tree.joint_names(),
        prismatic: tree.prismatic(),
        units: args.pose.units,
        marker: 0,
        dialect: args.pose.dialect(),
    };
    let file = read_poses(path, &spec)?;
    if file.n_markers() != tree.tips.len() {
        return Err(CliError::bad_input(format!(
            "{}: {} measured point(s) per pose for a tree of {} tips: give x1,y1,z1 .. x{n},y{n},z{n} \
             (point k on the k-th [[tip]])",
            path.display(),
            file.n_markers(),
            tree.tips.len(),
            n = tree.tips.len()
        )));
    }
    Ok(file
        .poses
        .iter()
        .map(|p| TreePose {
            q: p.q.clone(),
            points_mm: p.markers_mm.iter().map(|m| Some(*m)).collect(),
        })
        .collect())
}

pub fn run(args: &Args, tree: Tree) -> Result<(), CliError> {
    if args.json.is_some() || args.markers.is_some() || args.base || args.compliance {
        return Err(CliError::bad_input(
            "a tree model's calibration takes --poses, --validate, --params, --out and --units \
             (not --json, --markers, --base, --compliance yet)",
        ));
    }
    let Some(poses_path) = args.poses.as_deref() else {
        return Err(CliError::bad_input("--poses is required"));
    };
    let poses = read(args, &tree, poses_path)?;
    let unknowns = match &args.params {
        Some(p) => p.clone(),
        None => identifiable(&tree, &poses, &tree_candidates(&tree))?,
    };
    let fit = fit_tree(&tree, &poses, &unknowns)?;
    outln!(
        "tree `{}`: {} joints, {} tips; {} poses, {} coordinates; {} unknowns",
        tree.name,
        tree.n_joints(),
        tree.tips.len(),
        poses.len(),
        fit.n_residuals,
        fit.names.len()
    )?;
    outln!("parameter,value,sigma,change")?;
    for ((name, v), s) in fit.names.iter().zip(&fit.values).zip(&fit.sigmas) {
        let before = tree.param(name).unwrap_or(0.0);
        outln!("{name},{v:.6},{s:.6},{:+.6}", v - before)?;
    }
    outln!(
        "calibration rms {:.4} mm -> {:.4} mm",
        fit.rms_before_mm,
        fit.rms_after_mm
    )?;
    if let Some(v) = &args.validate {
        let val = read(args, &tree, v)?;
        outln!(
            "validation rms {:.4} mm -> {:.4} mm",
            tree_rms_mm(&tree, &val)?,
            tree_rms_mm(&fit.tree, &val)?
        )?;
    }
    if let Some(out) = &args.out {
        fit.tree.write_file(out)?;
        errln!("fitted tree -> {}", out.display());
    }
    Ok(())
}
