//! `rigctl init --urdf ROBOT.urdf --tip LINK [--base-link LINK] | --robot NAME | --model FILE
//! [--out rigctl.toml] [--force]`: writes a commented project file (docs/project.md); from a
//! URDF also the chain as a model file beside it (`<urdf stem>.model.toml`, as `urdf2model`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use rigctl::io::atomic::write_text_atomic;
use rigctl::io::finite::TextFormat;
use rigctl::model::Model;
use rigctl::plan::collision::{Collider, GeometrySource};
use rigctl::plan::workspace::DEFAULT_CLEARANCE_MM;
use rigctl::urdf::{import_chain_with_masses, ImportOptions, Urdf};

use super::out::errln;
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The robot's URDF: its chain --base-link .. --tip is the model (written beside the
    /// project file), its collision geometry is checked by `plan`.
    #[arg(long, value_name = "FILE.urdf", requires = "tip", conflicts_with_all = ["robot", "model"])]
    pub urdf: Option<PathBuf>,
    /// Last link of the chain in --urdf (the tool flange or the tool).
    #[arg(long, value_name = "LINK", requires = "urdf")]
    pub tip: Option<String>,
    /// First link of the chain in --urdf (default: the root link).
    #[arg(long, value_name = "LINK", requires = "urdf")]
    pub base_link: Option<String>,
    /// A built-in robot instead: katana450 or ur5.
    #[arg(long, value_name = "NAME", conflicts_with = "model")]
    pub robot: Option<String>,
    /// A model file (TOML) instead.
    #[arg(long, value_name = "FILE.toml")]
    pub model: Option<PathBuf>,
    /// The project file to write.
    #[arg(long, value_name = "FILE", default_value = super::project::DEFAULT_FILE)]
    pub out: PathBuf,
    /// Overwrite an existing project file (and model file).
    #[arg(long)]
    pub force: bool,
}

/// A path as written in the project file (relative to its folder `dir`): as given when `dir` is
/// the working directory or the path is absolute, else from `dir` through `..`.
fn shown(path: &Path, dir: &Path) -> String {
    if dir == Path::new(".") || path.is_absolute() {
        return path.display().to_string();
    }
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let (p, d) = (abs(path), abs(dir));
    let pc: Vec<_> = p.components().collect();
    let dc: Vec<_> = d.components().collect();
    let common = pc.iter().zip(&dc).take_while(|(a, b)| a == b).count();
    let mut out = PathBuf::new();
    for _ in common..dc.len() {
        out.push("..");
    }
    for c in &pc[common..] {
        out.push(c);
    }
    out.display().to_string()
}

fn refuse_existing(path: &Path, force: bool) -> Result<(), CliError> {
    if path.exists() && !force {
        return Err(CliError::bad_input(format!(
            "{} exists: not overwritten (--force to replace it)",
            path.display()
        )));
    }
    Ok(())
}

/// A TOML string.
fn quoted(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// The model file `init` writes for the URDF `urdf`: `<stem>.model.toml` in `dir`.
fn model_path_for(urdf: &Path, dir: &Path) -> PathBuf {
    let stem = urdf
        .file_stem()
        .map_or_else(|| "robot".into(), |s| s.to_string_lossy().into_owned());
    let name = format!("{stem}.model.toml");
    if dir == Path::new(".") {
        PathBuf::from(name)
    } else {
        dir.join(name)
    }
}

pub fn run(args: Args) -> Result<(), CliError> {
    let dir = args
        .out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf();
    let model_out = args.urdf.as_deref().map(|u| model_path_for(u, &dir));
    super::files()
        .input("--urdf", args.urdf.as_deref())
        .input("--model", args.model.as_deref())
        .output("--out", Some(&args.out))
        .output("the model file", model_out.as_deref())
        .check()?;
    refuse_existing(&args.out, args.force)?;
    if let Some(m) = &model_out {
        refuse_existing(m, args.force)?;
    }
    let mut robot = String::new();
    let model: Model;
    let mut joint_names = Vec::new();
    let mut model_written = None;
    let mut collision = None;
    if let (Some(urdf_path), Some(tip)) = (&args.urdf, &args.tip) {
        let urdf = Urdf::from_file(urdf_path)?;
        let imported = import_chain_with_masses(
            &urdf,
            &ImportOptions {
                base_link: args.base_link.as_deref(),
                tip_link: tip,
                tool_mm: [0.0; 3],
            },
        )?;
        let model_path = model_path_for(urdf_path, &dir);
        let _ = writeln!(
            robot,
            "# The chain {}..{tip} of the URDF as a model file (joints in deg, mm for prismatic\n\
             # ones), written by `rigctl init` as `rigctl urdf2model` would.\nmodel = {}",
            args.base_link.as_deref().unwrap_or("(root link)"),
            quoted(&shown(&model_path, &dir))
        );
        let _ = writeln!(
            robot,
            "# The robot's URDF: plan checks its collision geometry, model2urdf writes the \
             calibrated robot into it.\nurdf = {}\n# Last link of the chain (the tool flange).\n\
             tip_link = {}",
            quoted(&shown(urdf_path, &dir)),
            quoted(tip)
        );
        match &args.base_link {
            Some(b) => {
                let _ = writeln!(robot, "# First link of the chain.\nbase_link = {}", quoted(b));
            }
            None => robot.push_str("# First link of the chain (default: the URDF's root link).\n# base_link = \"base_link\"\n"),
        }
        collision = collision_note(urdf_path, args.base_link.as_deref(), tip, &imported.model);
        model_written = Some((model_path, imported.model.clone()));
        model = imported.model;
        joint_names = imported.joint_names;
    } else if let Some(path) = &args.model {
        model = Model::from_file(path)?;
        let _ = writeln!(
            robot,
            "# The model file (TOML: docs/model-files.md).\nmodel = {}",
            quoted(&shown(path, &dir))
        );
    } else {
        let name = args.robot.as_deref().unwrap_or("katana450");
        model = rigctl::model::choose_model(&rigctl::model::ModelChoice {
            robot: Some(name),
            ..Default::default()
        })?;
        let _ = writeln!(
            robot,
            "# A built-in robot: katana450 or ur5.\npreset = {}",
            quoted(name)
        );
    }
    let mut text = project_text(&robot, &model, &joint_names);
    if let Some(reason) = &collision {
        let _ = writeln!(
            text,
            "# No collision check: the URDF's collision geometry cannot be read here ({reason}).\n\
             # Give package_path in [robot] and remove this key to check it.\ncollision = false"
        );
    } else {
        text.push_str("# false: plan checks no collision geometry (none of the URDF's meshes at hand).\n# collision = false\n");
    }
    // the written file loads back
    toml::from_str::<super::project::Project>(&text)
        .map_err(|e| CliError::failure(format!("init wrote an unreadable project file: {e}")))?;
    if let Some((path, m)) = &model_written {
        m.write_file(path)?;
        errln!("init: the chain as a model file -> {}", path.display());
    }
    write_text_atomic(&args.out, TextFormat::Toml, &text)?;
    errln!(
        "init: project file -> {} ({} joints); edit it, then e.g. `rigctl plan --n 60 --out plan.csv`",
        args.out.display(),
        model.n_joints()
    );
    Ok(())
}

/// Why `plan` could not check the URDF's collision geometry (missing meshes), if it cannot.
fn collision_note(
    urdf: &Path,
    base_link: Option<&str>,
    tip: &str,
    model: &Model,
) -> Option<String> {
    let mut package_paths = Vec::new();
    if let Some(p) = std::env::var_os("ROS_PACKAGE_PATH") {
        package_paths.extend(std::env::split_paths(&p));
    }
    let src = GeometrySource {
        urdf: urdf.to_path_buf(),
        base_link: base_link.map(String::from),
        tip_link: tip.to_string(),
        package_paths,
        srdf: None,
    };
    Collider::from_urdf(&src, model, DEFAULT_CLEARANCE_MM, Some(0.0))
        .err()
        .map(|e| {
            let e = e.to_string();
            match e.split_once(" (tried") {
                Some((head, _)) => head.to_string(),
                None => e,
            }
        })
}

/// The joints and their limits, as comment lines.
fn joint_lines(model: &Model, names: &[String]) -> String {
    let mut s = String::from(
        "# The joints (q1..qN in pose files, or their URDF names) and their limits:\n",
    );
    for (k, (j, lim)) in model.joints().iter().zip(model.joint_limits()).enumerate() {
        let unit = if j.prismatic { "mm" } else { "deg" };
        let name = names.get(k).map_or_else(String::new, |n| format!(" {n}"));
        let _ = writeln!(
            s,
            "#   q{}{name}: {} {:.3} .. {:.3} {unit}",
            k + 1,
            if j.prismatic { "prismatic" } else { "revolute" },
            lim[0],
            lim[1]
        );
    }
    s
}

pub(super) fn project_text(robot: &str, model: &Model, names: &[String]) -> String {
    format!(
        "# rigctl project file (docs/project.md). Every rigctl command run in this folder (or given\n\
         # --project FILE) reads it; a flag on the command line wins over its value here.\n\
         # Relative paths are relative to this file's folder.\n\
         \n\
         [robot]\n\
         {robot}\
         {joints}\
         # Folders searched for package:// meshes of the URDF.\n\
         # package_path = [\"meshes\"]\n\
         # Overrides of model parameters (deg for angles, mm for lengths; keys of the model file,\n\
         # e.g. the tool point), as a table after the [robot] keys:\n\
         # [robot.set]\n\
         # tool_dz = 31.0\n\
         \n\
         [units]\n\
         # Joint readings in the pose files and joint logs: deg or rad (prismatic joints: mm or m\n\
         # with the points).\n\
         joints = \"deg\"\n\
         # Measured points: mm or m.\n\
         points = \"mm\"\n\
         # CSV field separator: \",\", \";\" (a German or French spreadsheet) or \"\\t\".\n\
         sep = \",\"\n\
         # CSV decimal mark: \".\" or \",\" (with sep = \";\").\n\
         decimal = \".\"\n\
         \n\
         [instrument]\n\
         # One-sigma accuracy per coordinate of the measuring instrument, mm (a laser tracker\n\
         # ~0.01, motion capture ~0.2): diagnose's floor, plan's measurement noise.\n\
         # sigma_mm = 0.05\n\
         \n\
         [frames]\n\
         # The instrument's frame is not the robot's: fit the base frame (calibrate --base).\n\
         base = true\n\
         # With several measured points per pose (x1,y1,z1,..): the points used, 1-based.\n\
         # markers = [1]\n\
         \n\
         [data]\n\
         # Calibration poses (pose CSV: q1..qN, x, y, z [, t, id]).\n\
         poses = \"run/cal.csv\"\n\
         # Held-out poses, only evaluated (the error to expect).\n\
         validate = \"run/val.csv\"\n\
         # The robot's joint log (CSV or ROS 2 bag) and the instrument's log, for `rigctl poses`.\n\
         # joint_log = \"session_bag\"\n\
         # instrument_log = \"tracker.csv\"\n\
         \n\
         [plan]\n\
         # Height of the table plane, mm in the robot's base frame (0: the base plane).\n\
         table_z_mm = 0.0\n\
         # No table at all (a robot on a wall or a pedestal).\n\
         # no_table = true\n\
         # Keep-out boxes, mm: [x0, y0, z0, x1, y1, z1] each.\n\
         # keep_out = [[300.0, -200.0, 0.0, 600.0, 200.0, 150.0]]\n\
         # Every joint this far inside its limits, deg (mm for prismatic joints).\n\
         limit_margin_deg = 2.0\n\
         # Smallest distance between collision shapes, mm.\n\
         # clearance_mm = 10.0\n\
         # An SRDF whose disable_collisions pairs are not checked.\n\
         # srdf = \"robot.srdf\"\n",
        joints = joint_lines(model, names),
    )
}
