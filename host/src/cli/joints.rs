//! `rigctl joints --readings JOINTS_TILT.csv [--robot NAME | --model FILE.toml] [--set ...]
//! --out MODEL.toml [--json OUT.json]`: joint clearance, backlash and stiffness from
//! inclinometer readings (see `rigctl::joints`), written into the model file.

use std::path::PathBuf;

use rigctl::joints::{identify, read_readings, report_json, JointsError};

use super::model_args::ModelArgs;
use super::out::errln;
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Inclinometer readings: joint,config,q1..qN,payload_kg,incl_x_deg,incl_y_deg,incl_z_deg.
    #[arg(long, value_name = "FILE.csv")]
    pub readings: PathBuf,
    // The model choice: --robot NAME | --model FILE.toml, --tool-mm L, --set NAME=VALUE.
    #[command(flatten)]
    pub model: ModelArgs,
    /// The model file to write, with clearance_j<i>, backlash_j<i>, stiffness_j<i> identified.
    #[arg(long, value_name = "MODEL.toml")]
    pub out: PathBuf,
    /// Also write the per-joint estimates, sigmas and residuals as JSON.
    #[arg(long, value_name = "OUT.json")]
    pub json: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("--readings", Some(&args.readings))
        .input("--model", args.model.model.as_deref())
        .output("--out", Some(&args.out))
        .output("--json", args.json.as_deref())
        .check()?;
    let model = args.model.choose()?;
    let readings = read_readings(&args.readings, &model)?;
    let result = identify(&model, &readings)?;
    for f in &result.fits {
        let show = |e: Option<rigctl::joints::Estimate>| match e {
            Some(e) => format!("{:.6} +- {:.6}", e.value, e.sigma),
            None => "kept".to_string(),
        };
        errln!(
            "joint {}: {} readings, C = {} deg, b = {} deg, k = {} kgf.m/deg",
            f.joint,
            f.rows,
            show(f.clearance_deg),
            show(f.backlash_deg),
            show(f.stiffness_kgfm_per_deg)
        );
        for n in &f.notes {
            errln!("  joint {}: {n}", f.joint);
        }
    }
    result.model.write_file(&args.out)?;
    if let Some(path) = &args.json {
        // the fits are checked as they are (the JSON value would already hold a NaN as null)
        rigctl::io::finite_json::check_json(&result.fits).map_err(|source| {
            JointsError::from(rigctl::io::atomic::AtomicWriteError::NonFinite {
                path: path.clone(),
                source,
            })
        })?;
        rigctl::io::atomic::write_json_atomic(path, &report_json(&result.fits))
            .map_err(JointsError::from)?;
    }
    Ok(())
}
