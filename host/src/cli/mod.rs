//! One file per subcommand; each has an `Args` (clap) and a `run`.

use rigctl::error::{Classify, ErrorKind};

mod board_sim;
mod calibrate;
mod calibrate_text;
mod calibrate_tree;
mod compensate;
mod diagnose;
mod diagnose_tree;
mod export;
mod fk;
mod fuse;
mod init;
mod joint_log;
mod joints;
mod model2urdf;
mod model_args;
pub mod out;
mod plan;
mod plan_safety;
mod plan_tree;
mod ports;
mod pose_args;
mod poses;
mod potcal;
pub mod project;
mod record;
mod report;
mod sheet;
mod simulate;
mod trace;
mod trace_paths;
mod urdf2model;

#[derive(clap::Parser, Debug)]
#[command(
    name = "rigctl",
    version,
    about = "Low-cost robot calibration rig: record, model, simulate, calibrate"
)]
pub struct Cli {
    /// Project file (TOML: robot, units, instrument, data files, plan environment;
    /// docs/project.md); default: rigctl.toml in the working directory when present. Flags on
    /// the command line win over its values.
    #[arg(long, global = true, value_name = "FILE")]
    pub project: Option<std::path::PathBuf>,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// Forward kinematics of every row of a joint file (CSV x,y,z,phi,theta,psi).
    Fk(fk::Args),
    /// A virtual rig with known truth: writes pose files and the truth.
    Simulate(simulate::Args),
    /// Identify the model's parameters from measured poses.
    Calibrate(calibrate::Args),
    /// Fit the declared model, find the effects it lacks, report before/after each.
    Diagnose(diagnose::Args),
    /// One self-contained HTML page (tables, plots, provenance) from a run directory.
    Report(report::Args),
    /// List serial ports.
    Ports(ports::Args),
    /// Record the DAQ board's frames to a file.
    Record(record::Args),
    /// Export a recording to CSV.
    Export(export::Args),
    /// A virtual DAQ board on a pseudo-terminal.
    BoardSim(board_sim::Args),
    /// Write the printable trace sheet (SVG, A4).
    Sheet(sheet::Args),
    /// Extract the pencil centreline from a scanned sheet (CSV x,y in mm).
    Trace(trace::Args),
    /// Calibrate the pencil's potentiometer (counts -> mm) from a gauge-block jig.
    Potcal(potcal::Args),
    /// Fuse joint readings, the pot recording and the pencil trace into partial error samples.
    Fuse(fuse::Args),
    /// Write a URDF serial chain (base link .. tip link) as a model file.
    Urdf2model(urdf2model::Args),
    /// Write the model as a URDF (world .. tool0), or into the URDF it was imported from.
    Model2urdf(model2urdf::Args),
    /// Joint clearance, backlash and stiffness from inclinometer readings, into a model file.
    Joints(joints::Args),
    /// Joints that put the calibrated, tilting arm on a Cartesian path (eq. 5.22).
    Compensate(compensate::Args),
    /// Choose the calibration poses that identify the model best (A-optimal by default; G, I or
    /// D with --criterion), or that separate the effects a diagnosis found aliased.
    Plan(Box<plan::Args>),
    /// Measured poses from a continuous joint log (CSV or ROS 2 bag) and an instrument log:
    /// standstills, clock offset, averaged points and their spread.
    Poses(poses::Args),
    /// Write a commented project file (rigctl.toml) for a URDF's chain, a preset or a model file.
    Init(init::Args),
}

pub fn run(cli: Cli) -> Result<(), CliError> {
    match cli.command {
        Command::Fk(a) => fk::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Calibrate(a) => calibrate::run(a),
        Command::Diagnose(a) => diagnose::run(a),
        Command::Report(a) => report::run(a),
        Command::Ports(a) => ports::run(a),
        Command::Record(a) => record::run(a),
        Command::Export(a) => export::run(a),
        Command::BoardSim(a) => board_sim::run(a),
        Command::Sheet(a) => sheet::run(a),
        Command::Trace(a) => trace::run(a),
        Command::Potcal(a) => potcal::run(a),
        Command::Fuse(a) => fuse::run(a),
        Command::Urdf2model(a) => urdf2model::run(a),
        Command::Model2urdf(a) => model2urdf::run(a),
        Command::Joints(a) => joints::run(a),
        Command::Compensate(a) => compensate::run(a),
        Command::Plan(a) => plan::run(*a),
        Command::Poses(a) => poses::run(a),
        Command::Init(a) => init::run(a),
    }
}

/// A command's files, declared with [`rigctl::io::files::RunFiles`] and checked before its work:
/// every output usable, none of them an input or written twice (exit 2 otherwise), so that an
/// unwritable output cannot leave the others written and no output destroys an input.
pub fn files() -> rigctl::io::files::RunFiles {
    rigctl::io::files::RunFiles::new()
}

/// Reports on stderr what a damaged recording lost (it was skipped, the run goes on).
pub fn note_damage(rec: &rigctl::daq::salvage::SalvagedRecording) {
    for d in &rec.damaged {
        out::errln!("rigctl: recording: skipped {d}");
    }
}

/// Reports on stderr the frames of a recording left out as out of the board's announced range
/// (`rigctl::fusion::pot::PotSamples::out_of_range`); the run goes on without them and ends with
/// [`out_of_range_failure`].
pub fn note_out_of_range(rec: &std::path::Path, out_of_range: Option<&str>) {
    if let Some(why) = out_of_range {
        out::errln!("rigctl: {}: {why}", rigctl::io::shown::shown(rec));
    }
}

/// Exit 1 after an output was written from a recording's in-range frames only (as `export`).
pub fn out_of_range_failure(rec: &std::path::Path, out: &std::path::Path) -> CliError {
    CliError::failure(format!(
        "{}: frames out of the board's announced range were left out (above); {} is from the others",
        rigctl::io::shown::shown(rec),
        rigctl::io::shown::shown(out)
    ))
}

/// An error on its way to the exit code: the message and its class.
#[derive(Debug)]
pub struct CliError {
    pub kind: ErrorKind,
    pub message: String,
    /// Set for an ending that prints nothing (stdout's reader gone): this exit status.
    pub quiet_exit: Option<u8>,
}

impl CliError {
    pub fn exit_code(&self) -> u8 {
        if let Some(code) = self.quiet_exit {
            return code;
        }
        match self.kind {
            ErrorKind::BadInput => 2,
            ErrorKind::Failure => 1,
        }
    }

    pub fn bad_input(message: impl Into<String>) -> Self {
        Self {
            kind: ErrorKind::BadInput,
            message: message.into(),
            quiet_exit: None,
        }
    }

    pub fn failure(message: impl Into<String>) -> Self {
        Self {
            kind: ErrorKind::Failure,
            message: message.into(),
            quiet_exit: None,
        }
    }

    /// The same error with its message prefixed by the file it is about.
    pub fn in_file(self, path: &std::path::Path) -> Self {
        Self {
            message: format!("{}: {}", path.display(), self.message),
            ..self
        }
    }

    /// The same error with the pose (1-based row of the joint file) it is about.
    pub fn with_row(self, row: usize) -> Self {
        Self {
            message: format!("pose {row}: {}", self.message),
            ..self
        }
    }

    /// An ending without a message, with exit status `code`.
    pub fn quiet(code: u8) -> Self {
        Self {
            kind: ErrorKind::Failure,
            message: String::new(),
            quiet_exit: Some(code),
        }
    }
}

impl std::fmt::Display for CliError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl<E: Classify + std::fmt::Display> From<E> for CliError {
    fn from(e: E) -> Self {
        Self {
            kind: e.kind(),
            message: e.to_string(),
            quiet_exit: None,
        }
    }
}

#[cfg(test)]
mod tests {
    /// Clap's own consistency checks (ids, `conflicts_with`/`requires` targets, flattened args).
    #[test]
    fn cli_definition_is_consistent() {
        <super::Cli as clap::CommandFactory>::command().debug_assert();
    }
}
