//! `rigctl compensate --path PATH.csv [--robot NAME | --model CALIBRATED.toml] [--set ...]
//! [--no-tilt] [--no-nominal] --out JOINTS.csv`: joints that put the calibrated, tilting arm on a
//! Cartesian path (thesis eq. 5.22; see `rigctl::compensate`), through the model file's
//! transmission terms when it has some.

use std::path::PathBuf;

use rigctl::compensate::{compensate, read_path, write_joints_csv};
use rigctl::model::ik::IkTilt;
use rigctl::model::preset;

use super::model_args::ModelArgs;
use super::out::errln;
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Desired path: columns x,y,z (mm, frame R), optional ax,ay,az (tool axis) and t (s).
    #[arg(long, value_name = "PATH.csv")]
    pub path: PathBuf,
    // The model choice: --robot NAME | --model FILE.toml, --tool-mm L, --set NAME=VALUE.
    #[command(flatten)]
    pub model: ModelArgs,
    /// Solve with static joint tilting (the default; accepted for explicitness).
    #[arg(long, overrides_with = "no_tilt")]
    pub tilt: bool,
    /// Solve on the rigid calibrated chain (no tilting).
    #[arg(long)]
    pub no_tilt: bool,
    /// Leave out the nominal (katana450 preset, the model's d5) joints q<i>_nominal.
    #[arg(long)]
    pub no_nominal: bool,
    /// Output joint file: [t,]q1..qN[,q1_nominal..qN_nominal], deg.
    #[arg(long, value_name = "JOINTS.csv")]
    pub out: PathBuf,
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("--path", Some(&args.path))
        .input("--model", args.model.model.as_deref())
        .output("--out", Some(&args.out))
        .check()?;
    let model = args.model.choose()?;
    let points = read_path(&args.path)?;
    if model.time_terms().is_active() && points.iter().any(|p| p.t_s.is_none()) {
        errln!(
            "note: {}: the model's time terms (thermal growth, drifts) need `t` on every point; \
             points without it are solved at t = 0, the start of the session",
            args.path.display()
        );
    }
    let nominal = if args.no_nominal {
        None
    } else {
        // the uncalibrated controller: the preset with the same tool length
        let mut nom = preset("katana450", None)?;
        if let (Some(d5), Some(_)) = (model.param("d5"), nom.param_index("d5")) {
            nom.set_param("d5", d5)?;
        }
        (nom.n_joints() == model.n_joints()).then_some(nom)
    };
    let tilt = if args.no_tilt {
        IkTilt::Off
    } else {
        IkTilt::Static
    };
    let file = args.path.display().to_string();
    let out = compensate(&model, nominal.as_ref(), &points, tilt, &file)?;
    write_joints_csv(&args.out, model.n_joints(), &out)?;
    let held: Vec<String> = out
        .iter()
        .zip(&points)
        .filter(|(o, _)| !o.held_joints.is_empty())
        .map(|(o, p)| {
            let joints: Vec<String> = o
                .held_joints
                .iter()
                .map(|j| format!("q{}", j + 1))
                .collect();
            format!("line {} ({})", p.line, joints.join(", "))
        })
        .collect();
    if !held.is_empty() {
        errln!(
            "rigctl compensate: warning: {} path point(s) ask a joint with hysteresis to reverse by less than its dead band (2 x hysteresis_deg); the joint is held at its previous command there and misses by less than the dead band: {}",
            held.len(),
            held.join("; ")
        );
    }
    errln!("{} path points -> {}", out.len(), args.out.display());
    Ok(())
}
