//! `rigctl simulate`: a virtual rig with known truth (see `rigctl::sim::simulate`); with
//! `--session circle|line` a simulated low-cost rig session (`rigctl::sim::session`).

use std::path::PathBuf;

use rigctl::model::KATANA_PENCIL_TOOL_MM;
use rigctl::sim::effects::parse_effect;
use rigctl::sim::output::write_outputs;
use rigctl::sim::session::{simulate_session, write_session, SessionConfig, SessionPath};
use rigctl::sim::simulate::{simulate, SimConfig};

use super::model_args::ModelArgs;
use super::out::outln;
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
    /// (deg/h), `thermal=150,20` (ppm at saturation, time constant in min).
    #[arg(long = "effect", value_name = "ID=VALUE")]
    pub effects: Vec<String>,
    /// Measurement noise, standard deviation per coordinate (mm).
    #[arg(long, default_value_t = 0.01, allow_negative_numbers = true)]
    pub noise_mm: f64,
    /// Standard deviation of the random geometric errors (deg) on the 12 geometric parameters.
    #[arg(long, default_value_t = 0.05, allow_negative_numbers = true)]
    pub geometric_sigma_deg: f64,
    // The model choice: --robot NAME | --model FILE.toml, --tool-mm L, --set NAME=VALUE.
    #[command(flatten)]
    pub model: ModelArgs,
    /// Number of validation poses.
    #[arg(long = "val", value_name = "N", default_value_t = 60)]
    pub n_val: usize,
    /// Time between two measured poses, s (pose k at `t = k x interval`, calibration poses
    /// first, then the validation poses).
    #[arg(long, value_name = "S", default_value_t = 10.0)]
    pub pose_interval_s: f64,
    /// Instead of poses: a low-cost rig session (thesis 5.5.2) drawing this path on a sheet on
    /// the 45-degree plane; writes joints.csv, pot.rec, potjig.csv, scan.png, placement.toml and
    /// the truth (truth.toml, truth_path.csv, session.json; see rigctl::sim::session). The same
    /// --seed gives the same robot for both paths. Without --model the Katana's tool length
    /// defaults to 330 mm (the pencil holder). `--effect`s with model parameters apply to the
    /// session's truth robot (time drifts are refused: a session lasts seconds).
    #[arg(long, value_name = "circle|line", value_enum)]
    pub session: Option<SessionPath>,
    /// With --session: the board clock's reading at robot time 0, s.
    #[arg(long, value_name = "S", requires = "session")]
    pub clock_offset_s: Option<f64>,
}

/// `simulate --session`.
fn run_session(args: &Args, path: SessionPath) -> Result<(), CliError> {
    let declared = args
        .model
        .choose_with_default_tool(Some(KATANA_PENCIL_TOOL_MM))?;
    let effects = args
        .effects
        .iter()
        .map(|e| parse_effect(e))
        .collect::<Result<Vec<_>, _>>()?;
    let mut cfg = SessionConfig {
        path,
        seed: args.seed,
        geometric_sigma_deg: args.geometric_sigma_deg,
        effects,
        ..SessionConfig::default()
    };
    if let Some(off) = args.clock_offset_s {
        cfg.clock_offset_s = off;
    }
    let session = simulate_session(&declared, &cfg)?;
    write_session(&args.out, &session, &cfg)?;
    outln!(
        "simulate: {} session, {} joint samples, {} potentiometer frames, scan at {} dpi written to {}",
        path.as_str(),
        session.t_s.len(),
        session.frames.len(),
        cfg.dpi,
        args.out.display()
    )?;
    Ok(())
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("--model", args.model.model.as_deref())
        .output_dir("--out", Some(&args.out), rigctl::sim::output::sim_file)
        .check()?;
    if let Some(path) = args.session {
        return run_session(&args, path);
    }
    let effects = args
        .effects
        .iter()
        .map(|e| parse_effect(e))
        .collect::<Result<Vec<_>, _>>()?;
    let declared = args.model.choose()?;
    let cfg = SimConfig {
        seed: args.seed,
        noise_mm: args.noise_mm,
        geometric_sigma_deg: args.geometric_sigma_deg,
        effects,
        n_val: args.n_val,
        pose_interval_s: args.pose_interval_s,
    };
    let out = simulate(&declared, &cfg)?;
    write_outputs(&args.out, &out, &cfg)?;
    outln!(
        "simulate: {} calibration and {} validation poses written to {}",
        out.cal.len(),
        out.val.len(),
        args.out.display()
    )?;
    Ok(())
}
