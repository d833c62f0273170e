//! `rigctl poses --joints LOG|BAG --points INSTRUMENT.csv --out POSES.csv [--robot NAME |
//! --model FILE.toml]`: the measured poses of a session from the robot's continuous joint log
//! (a CSV with `t` and the joint columns, or a ROS 2 bag of JointState) and the instrument's
//! continuous log (generic CSV, Vicon Nexus, OptiTrack Motive, SpatialAnalyzer points):
//! standstills, clock offset, robust means and their spread (`rigctl::capture`,
//! docs/capture.md). Exit 1, after writing the poses found, when a standstill gave no pose.

use std::path::PathBuf;

use rigctl::capture::instrument::{read_instrument, Format, ReadOptions};
use rigctl::capture::{capture, output, Capture, JointLog, Options};
use rigctl::io::atomic::write_text_atomic;
use rigctl::io::finite::TextFormat;
use rigctl::io::pose_csv::read_poses;
use rigctl::model::Model;

use super::joint_log::JointLogArgs;
use super::model_args::ModelArgs;
use super::out::{errln, outln};
use super::pose_args::PoseArgs;
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The robot's continuous joint log: a CSV with `t` (s) and the joint columns (q1..qN or
    /// the model's joint names; --units, --sep, --decimal), or a ROS 2 bag (.mcap file or
    /// rosbag2 directory) of sensor_msgs/msg/JointState.
    #[arg(long, value_name = "LOG.csv|BAG")]
    pub joints: PathBuf,
    /// The instrument's continuous log (see --points-format).
    #[arg(long, value_name = "INSTRUMENT.csv")]
    pub points: PathBuf,
    /// The pose file to write: id,t,q1..qN,x,y,z (x1,y1,z1,... for several markers),
    /// spread_mm,n_samples,rejected.
    #[arg(long, value_name = "POSES.csv")]
    pub out: PathBuf,
    /// Format of --points (auto: recognised from its first line).
    #[arg(long, value_enum, default_value = "auto")]
    pub points_format: Format,
    /// A marker (Vicon `Subject:Marker` or `Marker`) or rigid body (Motive) to take; repeatable
    /// (default: every marker of a Vicon file, the rigid bodies of a Motive file).
    #[arg(long = "marker", value_name = "NAME")]
    pub markers: Vec<String>,
    /// A joint is still below this speed, deg/s (mm/s for a prismatic joint).
    #[arg(long, value_name = "DEG_S", default_value_t = 0.5)]
    pub still_deg_s: f64,
    /// Shortest standstill that is a pose, s.
    #[arg(long, value_name = "S", default_value_t = 1.0)]
    pub min_still_s: f64,
    /// Left out at each end of a standstill before averaging, s.
    #[arg(long, value_name = "S", default_value_t = 0.25)]
    pub trim_s: f64,
    /// Instrument samples farther than this many sigmas (the pose's own scatter) from its
    /// median are left out as moving or outlying.
    #[arg(long, value_name = "K", default_value_t = 4.0)]
    pub reject_sigma: f64,
    /// Fewest kept instrument samples per marker for a pose.
    #[arg(long, value_name = "N", default_value_t = 5)]
    pub min_samples: usize,
    /// The clock offset when known, s (joint-log time = instrument time + offset); default:
    /// estimated.
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub offset_s: Option<f64>,
    /// Search the offset only within +-S s (default: every shift overlapping half a log).
    #[arg(long, value_name = "S", conflicts_with = "offset_s")]
    pub max_offset_s: Option<f64>,
    #[command(flatten)]
    pub model: ModelArgs,
    // --units (joint CSV; the length of a generic or SA instrument log), --sep, --decimal.
    #[command(flatten)]
    pub pose: PoseArgs,
    #[command(flatten)]
    pub joint_log: JointLogArgs,
}

fn positive(name: &str, v: f64) -> Result<f64, CliError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(CliError::bad_input(format!(
            "{name} {v}: must be a positive number"
        )))
    }
}

/// The joint log, CSV or bag.
fn joint_log(args: &Args, model: &Model) -> Result<JointLog, CliError> {
    let source = args.joints.display().to_string();
    if args.joint_log.check_for(&args.joints)? {
        if args.pose.units != Default::default() {
            return Err(CliError::bad_input(format!(
                "{source}: --units applies to CSV files; a bag's JointState positions are in \
                 rad and m"
            )));
        }
        let s = args.joint_log.read_samples(&args.joints, model, false)?;
        return Ok(JointLog {
            source,
            t_s: s.t_s,
            q: s.q_deg,
        });
    }
    let file = read_poses(&args.joints, &args.pose.spec(model, false, 0))?;
    let mut log = JointLog {
        source,
        ..Default::default()
    };
    for p in &file.poses {
        let t = p.t_s.ok_or_else(|| {
            CliError::bad_input(format!(
                "{}:{}: a joint log needs the time `t` (s) on every row",
                file.source, p.line
            ))
        })?;
        log.t_s.push(t);
        log.q.push(p.q.clone());
    }
    Ok(log)
}

fn report(c: &Capture, n_markers: usize) -> Result<(), CliError> {
    let offset = if c.offset_given {
        format!("clock offset {:.4} s (given)", c.offset.offset_s)
    } else {
        format!(
            "clock offset {:.4} s (joint log = instrument + offset; tool-speed correlation {:.3})",
            c.offset.offset_s, c.offset.correlation
        )
    };
    outln!(
        "standstills {}, poses {}, {offset}",
        c.standstills,
        c.poses.len()
    )?;
    match c.repeatability_mm() {
        Some(r) => {
            outln!(
            "instrument repeatability {r:.4} mm (median over the poses of the one-sigma spread \
             per coordinate{})",
            if n_markers > 1 { ", RMS over the markers" } else { "" }
        )?
        }
        None => outln!("instrument repeatability: no pose")?,
    }
    outln!(
        "instrument samples: {} used, {} rejected (moving or outlying inside a standstill), {} \
         missing (empty cells), {} during motion or at trimmed edges",
        c.samples_used,
        c.samples_rejected,
        c.samples_missing,
        c.samples_elsewhere
    )
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("--joints", Some(&args.joints))
        .input("--points", Some(&args.points))
        .input("--model", args.model.model.as_deref())
        .output("--out", Some(&args.out))
        .check()?;
    let model = args.model.choose()?;
    let opts = Options {
        still_speed: positive("--still-deg-s", args.still_deg_s)?,
        min_still_s: positive("--min-still-s", args.min_still_s)?,
        trim_s: if args.trim_s.is_finite() && args.trim_s >= 0.0 {
            args.trim_s
        } else {
            return Err(CliError::bad_input(format!(
                "--trim-s {}: must be >= 0",
                args.trim_s
            )));
        },
        reject_sigma: positive("--reject-sigma", args.reject_sigma)?,
        min_samples: args.min_samples.max(1),
        offset_s: match args.offset_s {
            Some(o) if !o.is_finite() => {
                return Err(CliError::bad_input(format!("--offset-s {o}: not a number")))
            }
            o => o,
        },
        offset_range_s: match args.max_offset_s {
            Some(m) => {
                let m = positive("--max-offset-s", m)?;
                Some((-m, m))
            }
            None => None,
        },
    };
    let joints = joint_log(&args, &model)?;
    let dialect = args.pose.dialect();
    let inst = read_instrument(
        &args.points,
        &ReadOptions {
            format: args.points_format,
            dialect,
            dialect_given: !dialect.is_default(),
            mm_per_unit: args.pose.units.mm_per_length(),
            markers: args.markers.clone(),
        },
    )?;
    let c = capture(&model, &joints, &inst, &opts)?;
    if c.standstills == 0 {
        return Err(CliError::failure(format!(
            "{}: no standstill of at least {} s with every joint below {} deg/s: nothing \
             written (--min-still-s, --still-deg-s)",
            joints.source, opts.min_still_s, opts.still_speed
        )));
    }
    let n_markers = inst.marker_names.len();
    let comments = vec![
        format!(
            "rigctl poses: joints {} ({} samples), points {} ({}, {} samples, markers {})",
            joints.source,
            joints.t_s.len(),
            inst.source,
            inst.format.name(),
            inst.t_s.len(),
            inst.marker_names.join(" ")
        ),
        format!(
            "clock offset {:.6} s (t of the joint log = instrument time + offset){}",
            c.offset.offset_s,
            if c.offset_given {
                ", given"
            } else {
                ", estimated"
            }
        ),
        format!(
            "t: joint-log time (s); x,y,z: mean of the kept instrument samples (mm); spread_mm: \
             their one-sigma scatter per coordinate; repeatability (median spread) {}",
            c.repeatability_mm()
                .map_or("-".into(), |r| format!("{r:.6} mm"))
        ),
    ];
    if !c.poses.is_empty() {
        let text = output::pose_csv(&c, model.n_joints(), n_markers, &comments);
        write_text_atomic(&args.out, TextFormat::Csv, &text)?;
    }
    report(&c, n_markers)?;
    if c.is_partial() {
        for g in &c.gaps {
            errln!(
                "rigctl poses: standstill {} ({:.3}..{:.3} s): no pose: {}",
                g.standstill,
                g.start_s,
                g.end_s,
                g.reason
            );
        }
        return Err(CliError::failure(format!(
            "{} of {} standstills gave no pose{}",
            c.gaps.len(),
            c.standstills,
            if c.poses.is_empty() {
                "; nothing written"
            } else {
                "; the others are written"
            }
        )));
    }
    Ok(())
}
