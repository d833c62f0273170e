//! `rigctl diagnose --poses CAL.csv --validate VAL.csv [--json OUT.json] [--out MODEL.toml]
//! [--plots DIR] [--robot NAME | --model FILE.toml] [--tool-mm L] [--set NAME=VALUE ...]`:
//! fits the declared model, adds the missing effects the data establish (see
//! `rigctl::diagnose`), prints a table, and writes the JSON report, the extended model and plots.

use std::fmt::Write as _;
use std::path::PathBuf;

use rigctl::diagnose::data::Dataset;
use rigctl::diagnose::plots::write_plots;
use rigctl::diagnose::{diagnose, DiagnoseOptions};
use rigctl::io::atomic::write_bytes_atomic;
use rigctl::model::{choose_model, ModelChoice};

use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Calibration poses (q1..qN, x, y, z [, t]).
    #[arg(long, value_name = "CAL.csv")]
    pub poses: PathBuf,
    /// Validation poses (held out; reported before/after every effect).
    #[arg(long, value_name = "VAL.csv")]
    pub validate: PathBuf,
    /// Write the JSON report (FORMATS.md "diagnose --json").
    #[arg(long, value_name = "OUT.json")]
    pub json: Option<PathBuf>,
    /// Write the extended model (loadable by fk / calibrate --model).
    #[arg(long, value_name = "MODEL.toml")]
    pub out: Option<PathBuf>,
    /// Write SVG plots of the residual against the regressor of every added effect.
    #[arg(long, value_name = "DIR")]
    pub plots: Option<PathBuf>,
    /// Built-in robot: katana450 (default) or ur5.
    #[arg(long, value_name = "NAME", conflicts_with = "model")]
    pub robot: Option<String>,
    /// Model file (TOML).
    #[arg(long, value_name = "FILE.toml")]
    pub model: Option<PathBuf>,
    /// Katana tool length d5 in mm.
    #[arg(long, value_name = "L")]
    pub tool_mm: Option<f64>,
    /// Override a model parameter before the diagnosis, e.g. tool_dz=31; repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub sets: Vec<String>,
    /// Seed of the cross-validation folds.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

pub fn run(args: Args) -> Result<(), CliError> {
    let model = choose_model(&ModelChoice {
        robot: args.robot.as_deref(),
        model_file: args.model.as_deref(),
        tool_mm: args.tool_mm,
        sets: &args.sets,
    })?;
    let cal = Dataset::read(&args.poses, &model)?;
    let val = Dataset::read(&args.validate, &model)?;
    let mut opts = DiagnoseOptions::default();
    opts.decide.seed = args.seed;
    let diag = diagnose(&model, &cal, &val, &opts)?;
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&diag.report)
            .map_err(|e| CliError::failure(format!("serialising the report: {e}")))?;
        write_bytes_atomic(path, (text + "\n").as_bytes())?;
    }
    if let Some(path) = &args.out {
        let mut text = String::new();
        let ext = &diag.model;
        let extras: Vec<String> = ext
            .joint_drift_deg_per_h
            .iter()
            .enumerate()
            .filter(|(_, v)| **v != 0.0)
            .map(|(j, v)| format!("joint {} offset drift {v:.6} deg/h", j + 1))
            .chain(
                ext.compliance_deg_per_kgfm
                    .iter()
                    .enumerate()
                    .filter(|(_, v)| **v != 0.0)
                    .map(|(j, v)| format!("joint {} compliance {v:.6} deg per kgf.m", j + 1)),
            )
            .chain((ext.drift_mm_per_h.norm() > 0.0).then(|| {
                let d = ext.drift_mm_per_h;
                format!(
                    "position drift ({:.6}, {:.6}, {:.6}) mm/h in R",
                    d.x, d.y, d.z
                )
            }))
            .collect();
        let _ = writeln!(
            text,
            "# Written by rigctl diagnose; evaluate with{} tilting.",
            if ext.tilt { "" } else { "out" }
        );
        for e in &extras {
            let _ = writeln!(
                text,
                "# Not expressible in a model file (applied by diagnose only): {e}"
            );
        }
        text.push_str(&ext.model.to_toml_string());
        write_bytes_atomic(path, text.as_bytes())?;
    }
    if let Some(dir) = &args.plots {
        write_plots(dir, &diag)?;
    }
    print!("{}", diag.report.table());
    Ok(())
}
