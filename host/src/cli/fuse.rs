//! `rigctl fuse --joints JOINTS.csv --recording REC --trace TRACE.csv --placement SHEET.toml
//! --pot POT.toml [--robot NAME | --model FILE] [--tool-mm L] --out FUSED.csv`: joint readings +
//! potentiometer recording + pencil trace -> partial error samples (`rigctl::fusion::fuse`).
//! The joint log may be a ROS 2 bag (`--joint-topic`, `--joint-names`; `rigctl::io::rosbag`).

use std::path::PathBuf;

use rigctl::fusion::curve::{read_trace_csv, TracedCurve};
use rigctl::fusion::pot::{read_pot_samples, TravelSeries};
use rigctl::fusion::{
    fuse, write_fused, FuseOptions, JointSamples, PotCalibration, SheetPlacement,
};
use rigctl::model::KATANA_PENCIL_TOOL_MM;

use super::joint_log::JointLogArgs;
use super::model_args::ModelArgs;
use super::out::outln;
use super::{note_damage, note_out_of_range, out_of_range_failure, CliError};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Joint readings of the robot controller: CSV `t` (s, robot clock), `q1..qN` (deg), or a
    /// ROS 2 bag (.mcap file or rosbag2 directory) of sensor_msgs/msg/JointState.
    #[arg(long, value_name = "JOINTS.csv|BAG")]
    pub joints: PathBuf,
    // --joint-topic, --joint-names of a bag.
    #[command(flatten)]
    pub joint_log: JointLogArgs,
    /// The board recording (potentiometer samples, board clock).
    #[arg(long, value_name = "REC")]
    pub recording: PathBuf,
    /// The pencil trace: CSV `x,y` in sheet mm (`rigctl trace` output).
    #[arg(long, value_name = "TRACE.csv")]
    pub trace: PathBuf,
    /// Where the sheet lies in frame R (TOML, see rigctl::fusion::placement).
    #[arg(long, value_name = "SHEET.toml")]
    pub placement: PathBuf,
    /// Potentiometer calibration (`rigctl potcal` output).
    #[arg(long, value_name = "POT.toml")]
    pub pot: PathBuf,
    // The model choice: --robot NAME | --model FILE.toml, --tool-mm L, --set NAME=VALUE.
    #[command(flatten)]
    pub model: ModelArgs,
    /// Largest in-plane distance from the trace, mm.
    #[arg(long, default_value_t = 3.0)]
    pub max_in_plane_mm: f64,
    /// Output: the fused samples (CSV, format rigctl-fused/1).
    #[arg(long, value_name = "FUSED.csv")]
    pub out: PathBuf,
    /// Refuse a damaged recording or bag (exit 2) instead of skipping what is damaged.
    #[arg(long)]
    pub strict: bool,
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("--joints", Some(&args.joints))
        .input("--recording", Some(&args.recording))
        .input("--trace", Some(&args.trace))
        .input("--placement", Some(&args.placement))
        .input("--pot", Some(&args.pot))
        .input("--model", args.model.model.as_deref())
        .output("--out", Some(&args.out))
        .check()?;
    let model = args
        .model
        .choose_with_default_tool(Some(KATANA_PENCIL_TOOL_MM))?;
    if !(args.max_in_plane_mm > 0.0 && args.max_in_plane_mm.is_finite()) {
        return Err(CliError::bad_input(
            "--max-in-plane-mm must be a positive number",
        ));
    }
    let joints = if args.joint_log.check_for(&args.joints)? {
        args.joint_log
            .read_samples(&args.joints, &model, args.strict)?
    } else {
        JointSamples::read(&args.joints, &model)?
    };
    let cal = PotCalibration::read(&args.pot)?;
    let read = read_pot_samples(&args.recording, args.strict, &mut note_damage)?;
    note_out_of_range(&args.recording, read.out_of_range.as_deref());
    let samples = read.samples;
    if samples.is_empty() {
        if read.out_of_range.is_some() {
            return Err(CliError::failure(
                "no potentiometer sample within the board's announced range",
            )
            .in_file(&args.recording));
        }
        return Err(
            CliError::bad_input("the recording has no potentiometer sample")
                .in_file(&args.recording),
        );
    }
    let pot = TravelSeries::new(&samples, |r| cal.travel_mm(r));
    let opts = FuseOptions {
        max_in_plane_mm: args.max_in_plane_mm,
        ..FuseOptions::default()
    };
    let curve = TracedCurve::new(read_trace_csv(&args.trace)?, opts.close_tol_mm)
        .ok_or_else(|| CliError::bad_input(format!("{}: too few points", args.trace.display())))?;
    let placement = SheetPlacement::read(&args.placement)?;
    let fused = fuse(&model, &joints, &pot, &curve, &placement, &opts)?;
    write_fused(&args.out, &fused.samples)?;
    let a = &fused.alignment;
    outln!(
        "clock: board = robot {} {:.6} s, drift {:+.2} ppm ({} markers)",
        if a.offset_s < 0.0 { "-" } else { "+" },
        a.offset_s.abs(),
        a.drift_ppm,
        a.markers.len()
    )?;
    for m in &a.markers {
        outln!(
            "  marker {:.2}..{:.2} s: offset {:.6} s, level {:+.3} mm, misfit rms {:.4} mm",
            m.start_s,
            m.end_s,
            m.offset_s,
            m.level_mm,
            m.rms_mm
        )?;
    }
    let n = fused.samples.len() as f64;
    let rms = |f: &dyn Fn(&rigctl::fusion::FusedSample) -> f64| {
        (fused.samples.iter().map(|s| f(s).powi(2)).sum::<f64>() / n).sqrt()
    };
    let sk = fused.skipped;
    outln!(
        "fused {} of {} joint samples (skipped: {} not drawing, {} ambiguous, {} at a trace kink, \
         {} outside the recording, {} pencil off the paper, {} off the trace, {} near a trace end)",
        fused.samples.len(),
        joints.t_s.len(),
        sk.not_drawing,
        sk.ambiguous,
        sk.kinked,
        sk.outside_recording,
        sk.off_paper,
        sk.off_trace,
        sk.near_trace_end
    )?;
    outln!(
        "measured deviation from the nominal model: rms across the path {:.4} mm, out of plane {:.4} mm \
         (along the path: not measured); pencil stop {:.3} mm",
        rms(&|s| s.dev_u_mm),
        rms(&|s| s.dev_n_mm),
        fused.stop_mm
    )?;
    if read.out_of_range.is_some() {
        return Err(out_of_range_failure(&args.recording, &args.out));
    }
    Ok(())
}
