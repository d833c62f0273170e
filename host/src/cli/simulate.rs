//! `rigctl simulate`: a virtual rig with known truth (see `rigctl::sim::simulate`).

use std::path::PathBuf;

use rigctl::model::{choose_model, ModelChoice};
use rigctl::sim::effects::parse_effect;
use rigctl::sim::output::write_outputs;
use rigctl::sim::simulate::{simulate, SimConfig};

use super::CliError;

/// Writes cal.csv (118 ISO 9283 poses), val.csv, truth.toml and truth.json into DIR.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Seed of every random draw; the same seed gives byte-identical files.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// An effect the declared model lacks, ID=VALUE (repeatable), e.g. `link_length:a3=0.2`,
    /// `tool_offset=0.1,0,-0.2`, `encoder_harmonic:j2:h1=0.05,30`, `stiffness:j2=-10`
    /// (deltas added to the declared values), `time_drift=0,0,0.5` (mm/h), `time_drift:j2=0.01`
    /// (deg/h).
    #[arg(long = "effect", value_name = "ID=VALUE")]
    pub effects: Vec<String>,
    /// Measurement noise, standard deviation per coordinate (mm).
    #[arg(long, default_value_t = 0.01, allow_negative_numbers = true)]
    pub noise_mm: f64,
    /// Standard deviation of the random geometric errors (deg) on the 12 geometric parameters.
    #[arg(long, default_value_t = 0.05, allow_negative_numbers = true)]
    pub geometric_sigma_deg: f64,
    /// Built-in robot (declared model): katana450 (default) or ur5.
    #[arg(long, value_name = "NAME", conflicts_with = "model")]
    pub robot: Option<String>,
    /// Declared model from a model file instead of a preset.
    #[arg(long, value_name = "FILE.toml")]
    pub model: Option<PathBuf>,
    /// Tool length d5 of the katana450 preset (mm; 330 with the pencil holder).
    #[arg(long, value_name = "L")]
    pub tool_mm: Option<f64>,
    /// Override a parameter of the declared model, NAME=VALUE (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub sets: Vec<String>,
    /// Number of validation poses.
    #[arg(long = "val", value_name = "N", default_value_t = 60)]
    pub n_val: usize,
}

pub fn run(args: Args) -> Result<(), CliError> {
    let effects = args
        .effects
        .iter()
        .map(|e| parse_effect(e))
        .collect::<Result<Vec<_>, _>>()?;
    let declared = choose_model(&ModelChoice {
        robot: args.robot.as_deref(),
        model_file: args.model.as_deref(),
        tool_mm: args.tool_mm,
        sets: &args.sets,
    })?;
    let cfg = SimConfig {
        seed: args.seed,
        noise_mm: args.noise_mm,
        geometric_sigma_deg: args.geometric_sigma_deg,
        effects,
        n_val: args.n_val,
        ..SimConfig::default()
    };
    let out = simulate(&declared, &cfg)?;
    write_outputs(&args.out, &out, &cfg)?;
    println!(
        "simulate: {} calibration and {} validation poses written to {}",
        out.cal.len(),
        out.val.len(),
        args.out.display()
    );
    Ok(())
}
