//! `rigctl report RUN_DIR --html OUT.html [--robot NAME | --model FILE] [--tool-mm L] [--set N=V]`: one self-contained HTML
//! page from a run directory (see `rigctl::report`).

use std::path::PathBuf;

use rigctl::report::{write_report, ReportOptions};

use super::out::{errln, outln};
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Directory holding any of cal.csv, val.csv, truth.json, truth.toml, calibrate*.json,
    /// diagnose*.json, model files (*.toml), commands.txt.
    #[arg(value_name = "RUN_DIR")]
    pub run_dir: PathBuf,
    /// The page to write.
    #[arg(long, value_name = "OUT.html")]
    pub html: PathBuf,
    /// Declared (nominal) robot preset (default: truth.json's robot, else katana450).
    #[arg(long, value_name = "NAME", conflicts_with = "model")]
    pub robot: Option<String>,
    /// Declared model as a model file (TOML) instead of a preset.
    #[arg(long, value_name = "FILE.toml")]
    pub model: Option<PathBuf>,
    /// Override a parameter of the declared model (deg, mm), e.g. tool_dz=31; repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub sets: Vec<String>,
    // --units, --sep, --decimal of the run's pose files.
    #[command(flatten)]
    pub pose: super::pose_args::PoseArgs,
    /// Katana tool length d5 of the declared model (mm).
    #[arg(long, value_name = "L")]
    pub tool_mm: Option<f64>,
}

/// The model flags of the suggested commands when the project file supplied the model: none
/// (or `--project FILE` when it was given so).
fn project_model_flags() -> Option<String> {
    let p = super::project::in_effect()?;
    if !p.supplied.iter().any(|f| *f == "model" || *f == "robot") {
        return None;
    }
    Some(if p.explicit {
        format!(" --project {}", p.file.display())
    } else {
        String::new()
    })
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        // every file of the run is an input; an --html inside it only under a new name or
        // over the page of an earlier report (a plain file beginning as every report page)
        .input_dir(
            "RUN_DIR",
            &args.run_dir,
            rigctl::report::html::is_report_page,
        )
        .output("--html", Some(&args.html))
        .input("--model", args.model.as_deref())
        .check()?;
    let opts = ReportOptions {
        robot: args.robot,
        tool_mm: args.tool_mm,
        model_file: args.model,
        sets: args.sets,
        command_model: project_model_flags(),
        pose_units: args.pose.units,
        pose_dialect: args.pose.dialect(),
    };
    let report = write_report(&args.run_dir, &args.html, &opts)?;
    outln!(
        "report: {} tables, {} figures, {} notes written to {}",
        report.tables.len(),
        report.figure_count(),
        report.notes.len(),
        args.html.display()
    )?;
    for n in &report.notes {
        errln!("note: {n}");
    }
    Ok(())
}
