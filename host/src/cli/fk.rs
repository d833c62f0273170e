//! `rigctl fk --joints FILE.csv [--tilt] [--tool-mm L] [--set NAME=VALUE ...]
//! [--robot NAME | --model FILE.toml] [--units m,rad]`: forward kinematics of every row, CSV
//! `x,y,z,phi,theta,psi` (mm in frame R, ZXZ Euler angles in deg, whatever `--units` says of
//! the input) on stdout. A model file's transmission terms are applied to the readings first,
//! hysteresis in the pose order of the file (by `t` when every row has one).

use std::fmt::Write as _;
use std::path::PathBuf;

use rigctl::io::pose_csv::read_poses;
use rigctl::model::{ModelError, Tilt};

use super::model_args::ModelArgs;
use super::pose_args::PoseArgs;
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Pose file with columns q1..qN (deg), or the model's joint names; other columns are
    /// ignored.
    #[arg(long, value_name = "FILE.csv")]
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
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("--joints", Some(&args.joints))
        .input("--model", args.model.model.as_deref())
        .check()?;
    let model = args.model.choose()?;
    if args.tilt && !model.has_tilt() {
        return Err(ModelError::NoTiltData {
            model: model.name().to_string(),
        }
        .into());
    }
    let poses = read_poses(&args.joints, &args.pose.spec(&model, false, 0))?;
    let tilt = if args.tilt { Tilt::Static } else { Tilt::Off };
    // The model's transmission terms map the readings to the joints' angles, with the
    // directions of approach from the file's pose order (FORMATS.md "Pose order").
    let q_eff = model.effective_pose_joints(&poses.joints(), pose_times(&poses).as_deref())?;
    let mut out = String::from("x,y,z,phi,theta,psi\n");
    for (k, q) in q_eff.iter().enumerate() {
        let fk = model.fk(q, tilt)?;
        let p = fk.position_mm;
        let [phi, theta, psi] = fk.zxz_deg();
        if ![p.x, p.y, p.z, phi, theta, psi]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err(CliError::failure(format!(
                "{}: pose {} (row {}): the pose is not a finite number (model and joints out of any physical range)",
                args.joints.display(),
                k + 1,
                k + 1
            )));
        }
        let _ = writeln!(
            out,
            "{:.9},{:.9},{:.9},{phi:.9},{theta:.9},{psi:.9}",
            p.x, p.y, p.z
        );
    }
    super::out::stdout_bytes(out.as_bytes())
}

/// The pose times when every pose has one (the pose order is then by `t`), else `None`.
pub(crate) fn pose_times(file: &rigctl::io::pose_csv::PoseFile) -> Option<Vec<f64>> {
    file.poses.iter().map(|p| p.t_s).collect()
}
