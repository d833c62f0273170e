//! `rigctl calibrate --poses CAL.csv [--validate VAL.csv] [--method standard|influence|tilting]
//! [--json OUT.json] [--out MODEL.toml] [--robot NAME | --model FILE] [--tool-mm L]
//! [--set NAME=VALUE ...] [--params a,b,@group] [--base] [--units m,rad] [--markers 1,2]
//! [--select press] [--compliance] [--hysteresis]`: identifies the model's parameters (and, with several
//! measured points per pose or `--compliance`, the points' offsets and the joint compliances:
//! `rigctl::calib::calibrate_general::calibrate_poses`) and prints a thesis-table-4.5 style summary.
//!
//! `rigctl calibrate --samples FUSED.csv [--method standard|tilting] [--errors-csv FILE]
//! [--plot FILE.svg] ...`:
//! the same from the partial measurements of the low-cost rig (`rigctl fuse` output,
//! `rigctl::calib::projected`); with `tilting` the declared tilting is driven by the moments in
//! motion along the logged joint trajectory.

use std::fmt::Write as _;
use std::path::PathBuf;

use rigctl::calib::calibrate_general::{calibrate_poses, GeneralOptions, Select};
use rigctl::calib::large_changes::large_changes_line;
use rigctl::calib::MeasuredSet;
use rigctl::calib::{CalibrateOptions, Method};
use rigctl::io::atomic::write_text_atomic;
use rigctl::io::finite::TextFormat;
use rigctl::io::pose_csv::read_poses;
use rigctl::model::KATANA_PENCIL_TOOL_MM;

use super::calibrate_text::{
    fitted_not_finite, general_notes, held_out_lines, outlier_lines, report_tail, summary, table,
    PoseLabels,
};
use super::model_args::ModelArgs;
use super::out::{errln, out};
use super::pose_args::PoseArgs;
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Calibration poses: q1..qN (deg) and measured x,y,z (mm, frame R).
    #[arg(long, value_name = "CAL.csv", required_unless_present = "samples")]
    pub poses: Option<PathBuf>,
    /// Partial measurements instead of poses: fused samples (`rigctl fuse` output); the stats
    /// are then over the measured components (|dP| = sqrt(dev_u^2 + dev_n^2)). Without --model
    /// the Katana's tool length defaults to 330 mm (the pencil holder).
    #[arg(long, value_name = "FUSED.csv", conflicts_with_all = ["poses", "validate"])]
    pub samples: Option<PathBuf>,
    /// With --samples: write the per-sample measured errors before/after (CSV).
    #[arg(long, value_name = "ERRORS.csv", requires = "samples")]
    pub errors_csv: Option<PathBuf>,
    /// With --samples: plot the path error along the drawn path before calibration, after the
    /// standard one and after the chosen method (thesis fig. 5.12 style, SVG).
    #[arg(long, value_name = "FILE.svg", requires = "samples")]
    pub plot: Option<PathBuf>,
    /// Held-out poses, only evaluated.
    #[arg(long, value_name = "VAL.csv")]
    pub validate: Option<PathBuf>,
    /// standard (no tilting), influence (thesis eq. 3.7-3.8) or tilting (tilting first, fig. 4.9).
    #[arg(long, value_enum, default_value = "tilting")]
    pub method: Method,
    /// Write the result as JSON (FORMATS.md "calibrate --json").
    #[arg(long, value_name = "OUT.json")]
    pub json: Option<PathBuf>,
    /// Write the calibrated model (TOML, loadable with --model).
    #[arg(long, value_name = "MODEL.toml")]
    pub out: Option<PathBuf>,
    // The model choice: --robot NAME | --model FILE.toml, --tool-mm L, --set NAME=VALUE.
    #[command(flatten)]
    pub model: ModelArgs,
    /// Parameters to identify, comma separated (default: the Katana's 12 geometric ones, or for
    /// other robots all joint offsets, twists, lengths and the tool point). Groups: @base (base
    /// frame, base_rz included), @tool, @offsets (joint offsets), @chain (lengths and twists).
    #[arg(long, value_name = "a,b,c", value_delimiter = ',')]
    pub params: Option<Vec<String>>,
    /// Also identify the base frame (base_x, base_y, base_z, base_rx, base_ry).
    #[arg(long)]
    pub base: bool,
    /// Identifiability threshold: directions whose scaled singular value is below RTOL times the
    /// largest are reported unidentifiable and kept nominal.
    #[arg(long, value_name = "RTOL", default_value_t = rigctl::calib::identifiability::DEFAULT_RTOL, value_parser = parse_rtol)]
    pub rtol: f64,
    // --units LENGTH,ANGLE of the pose files.
    #[command(flatten)]
    pub pose: PoseArgs,
    /// With several measured points per pose (x1,y1,z1,..): the points to use, 1-based, comma
    /// separated (default: all). The first is the tool point; each further one gets its own
    /// offset in the tool frame (marker<k>_x_mm ..).
    #[arg(
        long,
        value_name = "1,2,..",
        value_delimiter = ',',
        conflicts_with = "samples"
    )]
    pub markers: Option<Vec<usize>>,
    /// all (fit every selected parameter) or press: fit the selection without the chain
    /// constants, then add the chain constants (and with --compliance the joint compliances)
    /// that lower the leave-one-pose-out prediction error (block PRESS) on the calibration poses.
    #[arg(long, value_enum, default_value = "all", conflicts_with = "samples")]
    pub select: Select,
    /// Identify a compliance of every revolute joint (deg per kgf.m of gravity torque about its
    /// axis, from the model's link masses); with --select press, only those chosen, and the
    /// joints' lateral compliances (bending across the axis) are candidates too.
    #[arg(long, conflicts_with = "samples")]
    pub compliance: bool,
    /// Identify a hysteresis of every joint (deg: the angle offset by +b when the joint last
    /// moved up before the pose, -b when down, in the pose order: a backlash whose side the
    /// path to the pose sets); with --select press, only those chosen.
    #[arg(long, conflicts_with = "samples")]
    pub hysteresis: bool,
    /// A tree model without link masses: assume them (per segment, mid-segment, in proportion
    /// to the segment lengths, 20 kg per metre in total) so that --compliance has gravity
    /// moments; said in the output (JSON `assumed_masses`). Tree models only (on a chain:
    /// `diagnose --assume-masses`).
    #[arg(long, conflicts_with = "samples")]
    pub assume_masses: bool,
    /// The robot's mass for `--assume-masses` (kg; implies it).
    #[arg(long, value_name = "KG", conflicts_with = "samples")]
    pub robot_mass_kg: Option<f64>,
    /// Keep every pose: no gross-error rule (poses whose error is inconsistent with the others
    /// are otherwise left out of the fit and listed as `outliers`).
    #[arg(long, conflicts_with = "samples")]
    pub keep_outliers: bool,
    /// Write the calibrated model even when a joint offset or twist moved by more than 10 deg or
    /// a link length by more than 20 mm and 5 % (otherwise: exit 1, the JSON lists them, no
    /// --out); the output says they were allowed.
    #[arg(long)]
    pub allow_large_changes: bool,
    /// The prior of ill-posed sets (fewer than 10 measured coordinates per parameter): `auto`
    /// (the robot's lengths and angles drawn toward their input values with a weight chosen by
    /// leave-one-pose-out cross-validation; none on well-posed sets), `off`, or a weight.
    #[arg(
        long,
        value_name = "auto|off|WEIGHT",
        default_value = "auto",
        conflicts_with = "samples"
    )]
    pub prior: rigctl::calib::prior::PriorMode,
    /// The prior's scales: `length=MM,angle=DEG` (default 1 mm, 0.1 deg).
    #[arg(
        long,
        value_name = "length=MM,angle=DEG",
        default_value = "length=1,angle=0.1"
    )]
    pub prior_scale: rigctl::calib::prior::PriorScales,
}

/// A relative threshold strictly between 0 and 1 (NaN and infinities refused).
fn parse_rtol(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v < 1.0 => Ok(v),
        _ => Err(format!("`{s}` is not a relative tolerance in (0, 1)")),
    }
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("--poses", args.poses.as_deref())
        .input("--samples", args.samples.as_deref())
        .input("--validate", args.validate.as_deref())
        .input("--model", args.model.model.as_deref())
        .output("--json", args.json.as_deref())
        .output("--out", args.out.as_deref())
        .output("--errors-csv", args.errors_csv.as_deref())
        .output("--plot", args.plot.as_deref())
        .apart("--poses", "--validate")
        .check()?;
    if let Some(samples) = &args.samples {
        return run_samples(&args, samples);
    }
    if let Some(tree) = super::calibrate_tree::tree_model(&args.model)? {
        return super::calibrate_tree::run(&args, tree);
    }
    if args.assume_masses || args.robot_mass_kg.is_some() {
        return Err(CliError::bad_input(
            "--assume-masses / --robot-mass-kg: calibrate assumes masses on a tree model; on a \
             chain, `diagnose --assume-masses` offers the compliance with assumed masses",
        ));
    }
    let poses = args
        .poses
        .as_deref()
        .ok_or_else(|| CliError::bad_input("--poses or --samples is required"))?;
    let model = args.model.choose()?;
    let markers: Option<Vec<usize>> = match &args.markers {
        Some(m) if m.is_empty() || m.contains(&0) => {
            return Err(CliError::bad_input(
                "--markers: 1-based point numbers, e.g. 1,2,3",
            ))
        }
        Some(m) => Some(m.iter().map(|k| k - 1).collect()),
        None => None,
    };
    // The model's own terms (joint map, time terms) are applied by the library's calibrate,
    // which keeps them fixed and writes them back with `--out`.
    let read = |p: &std::path::Path| -> Result<(MeasuredSet, PoseLabels), CliError> {
        let file = read_poses(p, &args.pose.spec(&model, true, 0))?;
        let m = MeasuredSet::from_pose_points(&file, markers.as_deref())?;
        super::pose_args::check_plausible(&model, &m, p)?;
        Ok((m, PoseLabels::of(&file)))
    };
    let (cal, cal_labels) = read(poses)?;
    let (val, val_labels) = match args.validate.as_deref().map(read).transpose()? {
        Some((v, l)) => (Some(v), Some(l)),
        None => (None, None),
    };
    if let (Some(v), Some(vp)) = (&val, args.validate.as_deref()) {
        super::pose_args::check_apart(&cal, v, poses, vp)?;
    }
    let opts = CalibrateOptions {
        method: args.method,
        params: args.params.clone(),
        base: args.base,
        rtol: args.rtol,
        keep_outliers: args.keep_outliers,
        prior: args.prior,
        prior_scales: args.prior_scale,
        ..Default::default()
    };
    let gen = GeneralOptions {
        select: args.select,
        compliance: args.compliance,
        hysteresis: args.hysteresis,
    };
    let g = calibrate_poses(&model, &cal, val.as_ref(), &opts, &gen)?;
    let mut notes = general_notes(&g, &cal);
    let outcome = g.outcome;
    no_redundancy(poses, 3 * cal.n_points(), outcome.report.rank)?;
    let mut outcome = outcome;
    for o in &mut outcome.report.outliers {
        let labels = if o.pose.file == "val" {
            val_labels.as_ref()
        } else {
            Some(&cal_labels)
        };
        if let Some(l) = labels {
            l.fill(&mut o.pose);
        }
    }
    for e in &mut outcome.report.extrapolated {
        if let Some(l) = val_labels.as_ref() {
            l.fill(&mut e.pose);
        }
    }
    // judged before the notes, which list what is unphysical
    outcome.report.judge(&model, &outcome.model);
    notes.push_str(&held_out_lines(&outcome.report));
    notes.push_str(&outlier_lines(
        &outcome.report,
        poses,
        args.validate.as_deref(),
    ));
    if let Some(with_tool) = registers(&args) {
        // the report's "before": the input model with only the instrument frame (and the tool
        // point when the run frees @tool) fitted; a registration that fails leaves the key out
        // (the run's own fit stands)
        outcome.report.registered =
            rigctl::calib::registered::registration_only(&model, &cal, val.as_ref(), with_tool)
                .ok();
    }
    let write_model = writes_model(&outcome.report, &args);
    if let Some(path) = &args.json {
        rigctl::io::atomic::write_json_atomic(path, &outcome.report)?;
    }
    if let (Some(path), true) = (&args.out, write_model) {
        outcome.model.write_file(path)?;
    }
    out!("{}{notes}", summary(&outcome, val.is_some()))?;
    plausible_changes(&outcome.report, &args)?;
    not_converged(&outcome.report)
}

/// Whether the report's `registered` is computed (`--base` or `@base`), and then whether with
/// the tool point (`@tool` freed too).
pub(super) fn registers(args: &Args) -> Option<bool> {
    let group = |g: &str| {
        args.params
            .as_ref()
            .is_some_and(|p| p.iter().any(|x| x == g))
    };
    (args.base || group("@base")).then(|| group("@tool"))
}

/// Exit 1 when the fit stopped on its iteration budget: the outputs are written (with
/// `"converged": false`), but they are not the optimum.
pub(super) fn not_converged(r: &rigctl::calib::report::CalibrateReport) -> Result<(), CliError> {
    if r.converged {
        return Ok(());
    }
    Err(CliError::failure(format!(
        "the fit did not converge: {} iterations spent while it still improved, so the parameters are \
         not at the optimum; outputs written with \"converged\": false (re-run from --out to go on)",
        r.iterations
    )))
}

/// `calibrate --samples`: identification from partial (projected) measurements.
fn run_samples(args: &Args, samples: &std::path::Path) -> Result<(), CliError> {
    use rigctl::calib::projected::errors_csv;
    let model = args
        .model
        .choose_with_default_tool(Some(KATANA_PENCIL_TOOL_MM))?;
    if model.transmission().is_active() {
        return Err(CliError::bad_input(
            "the model file has transmission terms (joint_scale, joint_coupling, hysteresis_deg, compliance_deg_per_kgfm); --samples does not apply them yet: use --poses",
        ));
    }
    let fused = rigctl::fusion::read_fused(samples, model.n_joints())?;
    let data = MeasuredSet::from_fused(&fused)?;
    let data = match args.method {
        Method::Standard => data,
        Method::Tilting => data.with_inertial_moments(&model)?,
        Method::Influence => {
            return Err(CliError::bad_input(
                "--method influence needs full positions (--poses); use standard or tilting with --samples",
            ))
        }
    };
    let opts = CalibrateOptions {
        method: args.method,
        params: args.params.clone(),
        base: args.base,
        rtol: args.rtol,
        ..Default::default()
    };
    let g = calibrate_poses(&model, &data, None, &opts, &GeneralOptions::default())?;
    let (mut outcome, rejected) = (g.outcome, g.rejected);
    no_redundancy(samples, data.n_residuals(), outcome.report.rank)?;
    outcome.report.judge(&model, &outcome.model);
    let write_model = writes_model(&outcome.report, args);
    if let Some(path) = &args.json {
        rigctl::io::atomic::write_json_atomic(path, &outcome.report)?;
    }
    if let (Some(path), true) = (&args.out, write_model) {
        outcome.model.write_file(path)?;
    }
    let csv = errors_csv(&fused, &outcome.calibration_errors);
    if let Some(path) = &args.errors_csv {
        write_text_atomic(path, TextFormat::Csv, &csv)?;
    }
    if let Some(path) = &args.plot {
        let errors = rigctl::plot::path_errors::parse_path_errors(&csv, "calibrate --samples")?;
        let svg = rigctl::plot::path_errors::path_errors_svg(&errors)?;
        write_text_atomic(path, TextFormat::Xml, &svg)?;
    }
    let mut s = table(
        "Fused samples, measured components only in frame R (|dP| = sqrt(dev_u^2 + dev_n^2); along the path not measured)",
        "samples",
        &outcome.calibration_errors,
        &outcome.report.method,
    );
    s.push_str(&report_tail(&outcome.report));
    let _ = writeln!(
        s,
        "outliers left out of the fit: {} of {} measured components (> {} robust sigmas)",
        rejected,
        data.n_residuals(),
        rigctl::calib::projected::OUTLIER_SIGMAS
    );
    out!("{s}")?;
    plausible_changes(&outcome.report, args)?;
    not_converged(&outcome.report)
}

/// Whether `--out` is written: not when a fitted parameter is not determined (an infinite
/// sigma), nor when the robot's geometry moved beyond a real arm's errors without
/// `--allow-large-changes`.
pub(super) fn writes_model(r: &rigctl::calib::report::CalibrateReport, args: &Args) -> bool {
    fitted_not_finite(r).is_empty() && (r.large_changes.is_empty() || args.allow_large_changes)
}

/// Exit 1 when a fitted parameter is not determined (its sigma infinite: the JSON has `null`),
/// or when the calibration moved the robot's geometry further than a real arm's errors, unless
/// `--allow-large-changes` (then said on stderr); in both cases no model was written.
pub(super) fn plausible_changes(
    r: &rigctl::calib::report::CalibrateReport,
    args: &Args,
) -> Result<(), CliError> {
    let undetermined = fitted_not_finite(r);
    if !undetermined.is_empty() {
        return Err(CliError::failure(format!(
            "fitted but not determined by these poses (infinite sigma, `null` in the JSON): {}; \
             no model was written: leave them out of --params or add poses that move them",
            undetermined.join(", ")
        )));
    }
    if r.large_changes.is_empty() {
        return Ok(());
    }
    let line = large_changes_line(&r.large_changes);
    if args.allow_large_changes {
        errln!("large changes allowed by --allow-large-changes, the model is written: {line}");
        return Ok(());
    }
    let payload = r
        .large_changes
        .iter()
        .any(|c| c.parameter == rigctl::model::PAYLOAD_PARAM);
    Err(CliError::failure(format!(
        "the calibration moved the robot's geometry further than a real arm's errors go{}: \
         {line}; check the model, the units and the robot the poses came from (the JSON lists \
         them; no model was written: --allow-large-changes writes it)",
        if payload {
            ", or fitted a payload the robot's link masses do not carry (it stands in for \
             something the model lacks: a joint's stiffness, the link masses themselves)"
        } else {
            ""
        }
    )))
}

/// Refuses a fit with no measured coordinate left over its rank: the residual is then zero
/// whatever the errors, and the sigmas (0) would claim a perfect calibration.
pub(super) fn no_redundancy(
    file: &std::path::Path,
    measured: usize,
    rank: usize,
) -> Result<(), CliError> {
    if measured <= rank {
        return Err(CliError::bad_input(format!(
            "{}: {measured} measured coordinates for {rank} identifiable directions: nothing left to estimate the errors; measure more poses",
            file.display()
        )));
    }
    Ok(())
}
