//! `rigctl fk --joints FILE.csv [--tilt] [--tool-mm L] [--set NAME=VALUE ...]
//! [--robot NAME | --model FILE.toml] [--units m,rad]`: forward kinematics of every row, CSV
//! `x,y,z,phi,theta,psi` (mm in frame R, ZXZ Euler angles in deg, whatever `--units` says of
//! the input) on stdout. A model file's transmission terms are applied to the readings first,
//! hysteresis in the pose order of the file (by `t` when every row has one); its time terms
//! (`[time]`: thermal growth, drifts; `[[change]]`: changes within the session) at each row's `t` (s from the start of the session; 0
//! when the file has no `t`, with a note; a bag's session starts at its first message). A ROS 2 bag as
//! `--joints` (`.mcap` or rosbag2 directory; `--joint-topic`, `--joint-names`) is streamed:
//! each message's row is written as it is read (all rows are gathered first only when the
//! model's hysteresis needs the pose order).
//!
//! A tree model file (`[[tip]]` tables, docs/model-files.md "Tree models"): the pose file holds
//! the joints of the whole tree, and each row gives `x<k>,y<k>,z<k>,phi<k>,theta<k>,psi<k>` for
//! every tip k = 1.. in the file's tip order (the columns a tree's pose file measures the tips
//! in).

use std::fmt::Write as _;
use std::path::PathBuf;

use rigctl::io::pose_csv::read_poses;
use rigctl::model::tree_bend::{bend, tree_at};
use rigctl::model::tree_file::is_tree_text;
use rigctl::model::{parse_set, ModelError, Tilt, Tree};

use super::joint_log::JointLogArgs;
use super::model_args::ModelArgs;
use super::pose_args::PoseArgs;
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Pose file with columns q1..qN (deg), or the model's joint names; other columns are
    /// ignored. Or a ROS 2 bag: an .mcap file or a rosbag2 directory (JointState, rad and m).
    #[arg(long, value_name = "FILE.csv|BAG")]
    pub joints: PathBuf,
    /// Add joint tilting with the declared values (MODEL.md).
    #[arg(long)]
    pub tilt: bool,
    // The model choice: --robot NAME | --model FILE.toml, --tool-mm L, --set NAME=VALUE.
    #[command(flatten)]
    pub model: ModelArgs,
    // --units LENGTH,ANGLE of the joint readings.
    #[command(flatten)]
    pub pose: PoseArgs,
    // --joint-topic, --joint-names of a bag.
    #[command(flatten)]
    pub joint_log: JointLogArgs,
}

fn fk_row(
    out: &mut String,
    model: &rigctl::model::Model,
    q: &[f64],
    t_s: f64,
    tilt: Tilt,
) -> Result<(), CliError> {
    // the model as it is at t: its changes within the session before t applied
    let fk = model.at_time(t_s).fk(q, tilt)?;
    let p = model.measured_mm(&fk.position_mm, t_s);
    let [phi, theta, psi] = fk.zxz_deg();
    if ![p.x, p.y, p.z, phi, theta, psi]
        .iter()
        .all(|v| v.is_finite())
    {
        return Err(CliError::failure(
            "the pose is not a finite number (model and joints out of any physical range)",
        ));
    }
    let _ = writeln!(
        out,
        "{:.9},{:.9},{:.9},{phi:.9},{theta:.9},{psi:.9}",
        p.x, p.y, p.z
    );
    Ok(())
}

/// `fk` of a bag: rows written as the messages are read.
fn run_bag(args: &Args, model: &rigctl::model::Model, tilt: Tilt) -> Result<(), CliError> {
    use std::io::Write as _;
    if args.pose.units != Default::default() {
        return Err(CliError::bad_input(format!(
            "{}: --units applies to CSV files; a bag's JointState positions are in rad and m",
            args.joints.display()
        )));
    }
    let stdout = std::io::stdout();
    let mut w = std::io::BufWriter::with_capacity(1 << 16, stdout.lock());
    w.write_all(b"x,y,z,phi,theta,psi\n")
        .map_err(super::out::stdout_error)?;
    let mut line = String::new();
    if model.transmission().uses_pose_order() {
        let (mut q, mut t) = (Vec::new(), Vec::new());
        args.joint_log.read_bag(&args.joints, model, |r| {
            q.push(r.q);
            t.push(r.t_s);
            Ok(())
        })?;
        for (qe, t_s) in model.effective_pose_joints(&q, Some(&t))?.iter().zip(&t) {
            line.clear();
            fk_row(&mut line, model, qe, *t_s, tilt)?;
            w.write_all(line.as_bytes())
                .map_err(super::out::stdout_error)?;
        }
    } else {
        args.joint_log.read_bag(&args.joints, model, |r| {
            // a bag's times count from its first message: the session's start
            let qe = model.effective_pose_joints(std::slice::from_ref(&r.q), Some(&[r.t_s]))?;
            line.clear();
            fk_row(&mut line, model, &qe[0], r.t_s, tilt)?;
            w.write_all(line.as_bytes())
                .map_err(super::out::stdout_error)
        })?;
    }
    w.flush().map_err(super::out::stdout_error)
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("--joints", Some(&args.joints))
        .input("--model", args.model.model.as_deref())
        .check()?;
    if let Some(path) = &args.model.model {
        let text = rigctl::io::read::read_text_capped(path, rigctl::io::read::CAP_SMALL_TEXT)
            .map_err(|source| ModelError::Read {
                path: path.clone(),
                source,
            })?;
        if is_tree_text(&text) {
            let tree = Tree::from_toml_str(&text, &path.display().to_string())?;
            return run_tree(&args, &tree);
        }
    }
    let model = args.model.choose()?;
    if args.tilt && !model.has_tilt() {
        return Err(ModelError::NoTiltData {
            model: model.name().to_string(),
        }
        .into());
    }
    let tilt = if args.tilt { Tilt::Static } else { Tilt::Off };
    if args.joint_log.check_for(&args.joints)? {
        return run_bag(&args, &model, tilt);
    }
    let poses = read_poses(&args.joints, &args.pose.spec(&model, false, 0))?;
    // The model's transmission terms map the readings to the joints' angles, with the
    // directions of approach from the file's pose order (FORMATS.md "Pose order").
    let times = pose_times(&poses);
    if model.time_terms().is_active() && times.is_none() {
        super::out::errln!(
            "note: {}: no time `t` on every row; the model's time terms (thermal growth, \
             drifts) are evaluated at t = 0, the start of the session",
            args.joints.display()
        );
    }
    let q_eff = model.effective_pose_joints(&poses.joints(), times.as_deref())?;
    let mut out = String::from("x,y,z,phi,theta,psi\n");
    for (k, q) in q_eff.iter().enumerate() {
        let t_s = times
            .as_ref()
            .and_then(|t| t.get(k))
            .copied()
            .unwrap_or(0.0);
        fk_row(&mut out, &model, q, t_s, tilt)
            .map_err(|e| e.in_file(&args.joints).with_row(k + 1))?;
    }
    super::out::stdout_bytes(out.as_bytes())
}

/// The pose times when every pose has one (the pose order is then by `t`), else `None`.
pub(crate) fn pose_times(file: &rigctl::io::pose_csv::PoseFile) -> Option<Vec<f64>> {
    file.poses.iter().map(|p| p.t_s).collect()
}

/// `fk` of a tree model: every tip's pose per row (see the module doc).
fn run_tree(args: &Args, tree: &Tree) -> Result<(), CliError> {
    if args.tilt || args.model.tool_mm.is_some() {
        return Err(CliError::bad_input(
            "a tree model has no tilting data and no --tool-mm (its tips' tool points are in \
             its [[tip]] tables)",
        ));
    }
    if args.joint_log.check_for(&args.joints)? {
        return Err(CliError::bad_input(format!(
            "{}: a tree model's fk reads pose files (CSV), not bags",
            args.joints.display()
        )));
    }
    let mut chains = tree.bent_chains()?;
    for set in &args.model.sets {
        let (name, value) = parse_set(set)?;
        let mut found = false;
        for m in chains.iter_mut().filter(|m| m.param_index(name).is_some()) {
            m.set_param(name, value)?;
            found = true;
        }
        if !found {
            return Err(CliError::bad_input(format!(
                "--set {set}: no tip's chain has a parameter `{name}`"
            )));
        }
    }
    let paths: Vec<Vec<usize>> = (0..tree.tips.len()).map(|t| tree.path(t)).collect();
    let spec = rigctl::io::pose_csv::PoseSpec {
        n_joints: tree.n_joints(),
        limits: tree.joint_limits(),
        require_xyz: false,
        joint_names: tree.joint_names(),
        prismatic: tree.prismatic(),
        units: args.pose.units,
        marker: 0,
        dialect: args.pose.dialect(),
    };
    let poses = read_poses(&args.joints, &spec)?;
    let mut out = String::new();
    let header: Vec<String> = (1..=tree.tips.len())
        .map(|k| format!("x{k},y{k},z{k},phi{k},theta{k},psi{k}"))
        .collect();
    let _ = writeln!(out, "{}", header.join(","));
    for (row, q) in poses.joints().iter().enumerate() {
        // compliant joints bend under the whole tree's gravity (docs/model-files.md)
        let at = tree_at(tree, &chains, q, false, false)
            .map_err(|e| CliError::from(e).in_file(&args.joints).with_row(row + 1))?;
        for (k, (model, path)) in chains.iter().zip(&paths).enumerate() {
            let qc = at.chain_joints(path);
            let moments = at.chain_moments(path);
            let mut cell = String::new();
            fk_row(&mut cell, model, &qc, 0.0, bend(&moments))
                .map_err(|e| e.in_file(&args.joints).with_row(row + 1))?;
            if k > 0 {
                out.push(',');
            }
            out.push_str(cell.trim_end());
        }
        out.push('\n');
    }
    super::out::stdout_bytes(out.as_bytes())
}
