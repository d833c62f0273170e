//! `rigctl poses`: measured poses from a robot's continuous joint log and an instrument's
//! continuous log. The standstills of the joint log ([`standstill`]) are the poses; the clock
//! offset between the logs is found by lining up the tool speed computed from the joints with
//! the measured point's speed ([`offset`]); the instrument samples inside each standstill
//! (edges trimmed) are averaged with moving and outlying samples left out ([`average`]); the
//! instrument logs are read by [`instrument`]. See docs/capture.md.

pub mod average;
pub mod error;
pub mod instrument;
pub mod offset;
pub mod output;
pub mod standstill;

use crate::model::{Model, Tilt};
pub use error::CaptureError;
use instrument::InstrumentLog;
use offset::{OffsetEstimate, Signal};

/// A continuous joint log (deg; mm for prismatic joints), times increasing (s).
#[derive(Debug, Clone, Default)]
pub struct JointLog {
    pub source: String,
    pub t_s: Vec<f64>,
    pub q: Vec<Vec<f64>>,
}

/// The settings of a capture (the CLI's defaults in docs/capture.md).
#[derive(Debug, Clone)]
pub struct Options {
    /// A joint is still below this speed (deg/s; mm/s for prismatic joints).
    pub still_speed: f64,
    /// Shortest standstill that is a pose (s).
    pub min_still_s: f64,
    /// Left out at each end of a standstill before averaging (s).
    pub trim_s: f64,
    /// Instrument samples farther than this many sigmas from a pose's median are left out.
    pub reject_sigma: f64,
    /// Fewest kept instrument samples (per marker) for a pose.
    pub min_samples: usize,
    /// The clock offset when known (`t_joint = t_instrument + offset`), else estimated.
    pub offset_s: Option<f64>,
    /// The range searched for the offset (s), default every shift overlapping half a log.
    pub offset_range_s: Option<(f64, f64)>,
}

/// Correlation of the aligned speed signals below which the logs are taken not to match.
pub const MIN_CORRELATION: f64 = 0.5;

/// One captured pose.
#[derive(Debug, Clone, PartialEq)]
pub struct CapturedPose {
    pub id: String,
    /// Middle of the averaged stretch, joint-log clock (s).
    pub t_s: f64,
    /// Mean joint readings over the averaged stretch.
    pub q: Vec<f64>,
    /// Mean of each marker (mm, instrument frame).
    pub points_mm: Vec<[f64; 3]>,
    /// One-sigma scatter per coordinate of the kept samples (RMS over the markers), mm.
    pub spread_mm: f64,
    /// Kept instrument samples (fewest over the markers).
    pub n_samples: usize,
    /// Samples left out as moving or outlying (all markers).
    pub rejected: usize,
}

/// A standstill that gave no pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Gap {
    /// 1-based number of the standstill.
    pub standstill: usize,
    pub start_s: f64,
    pub end_s: f64,
    pub reason: String,
}

/// What a capture found.
#[derive(Debug, Clone)]
pub struct Capture {
    pub poses: Vec<CapturedPose>,
    pub gaps: Vec<Gap>,
    pub standstills: usize,
    pub offset: OffsetEstimate,
    pub offset_given: bool,
    /// Instrument marker samples: used in a pose, rejected inside a standstill, missing in the
    /// log (empty cells), and the rest (during motion or at trimmed edges).
    pub samples_used: usize,
    pub samples_rejected: usize,
    pub samples_missing: usize,
    pub samples_elsewhere: usize,
}

impl Capture {
    /// The instrument's repeatability: the median of the poses' spreads (mm).
    pub fn repeatability_mm(&self) -> Option<f64> {
        let mut s: Vec<f64> = self.poses.iter().map(|p| p.spread_mm).collect();
        if s.is_empty() {
            return None;
        }
        s.sort_by(f64::total_cmp);
        let n = s.len();
        Some(if n % 2 == 1 {
            s[n / 2]
        } else {
            0.5 * (s[n / 2 - 1] + s[n / 2])
        })
    }

    /// Whether some standstill gave no pose.
    pub fn is_partial(&self) -> bool {
        !self.gaps.is_empty()
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The instrument's first-marker points with single-sample spikes removed, for the speed
/// signal only: a sample farther from the midpoint of its neighbours than 10 times the larger
/// of the log's median such distance and half the neighbours' distance from each other (so
/// that neither noise at rest nor fast motion looks like a spike).
fn despiked(inst: &InstrumentLog) -> Vec<Option<[f64; 3]>> {
    let p: Vec<Option<[f64; 3]>> = inst.points.iter().map(|m| m[0]).collect();
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let dev = |k: usize| -> Option<(f64, f64)> {
        let (a, b, c) = (p[k - 1]?, p[k]?, p[k + 1]?);
        let mid = [0, 1, 2].map(|i| b[i] - 0.5 * (a[i] + c[i]));
        Some((norm(mid), 0.5 * norm([0, 1, 2].map(|i| c[i] - a[i]))))
    };
    let devs: Vec<Option<(f64, f64)>> = (0..p.len())
        .map(|k| {
            if k == 0 || k + 1 >= p.len() {
                None
            } else {
                dev(k)
            }
        })
        .collect();
    let typical = median(devs.iter().flatten().map(|d| d.0).collect()).max(average::MIN_SCATTER_MM);
    p.iter()
        .zip(&devs)
        .map(|(&pt, d)| match d {
            Some((dev, half)) if *dev > 10.0 * typical.max(*half) => None,
            _ => pt,
        })
        .collect()
}

/// The tool positions of the joint log (model forward kinematics, no tilting).
fn tool_points(model: &Model, joints: &JointLog) -> Result<Vec<Option<[f64; 3]>>, CaptureError> {
    joints
        .q
        .iter()
        .enumerate()
        .map(|(k, q)| {
            let fk = model
                .fk(q, Tilt::Off)
                .map_err(|source| CaptureError::Model {
                    sample: k + 1,
                    source,
                })?;
            let p = fk.position_mm;
            Ok(Some([p.x, p.y, p.z]))
        })
        .collect()
}

/// Median sample period of increasing times (s).
fn period(t: &[f64]) -> f64 {
    median(t.windows(2).map(|w| w[1] - w[0]).collect())
}

/// The clock offset by [`offset::estimate`] on the tool speeds.
fn estimate_offset(
    model: &Model,
    joints: &JointLog,
    inst: &InstrumentLog,
    range: Option<(f64, f64)>,
) -> Result<OffsetEstimate, CaptureError> {
    let pj = tool_points(model, joints)?;
    let pi = despiked(inst);
    let (dt_j, dt_i) = (period(&joints.t_s), inst.median_period_s());
    let gap_j = (5.0 * dt_j).max(0.1);
    let gap_i = (5.0 * dt_i).max(0.1);
    let cs = offset::COARSE_STEP_S;
    let fine = (dt_i / offset::FINE_DIVISOR).clamp(1e-4, 0.01);
    let span = ((0.05 / fine).round() as usize).max(1);
    let coarse_i = Signal::speed(&inst.t_s, &pi, cs, 1, gap_i);
    let coarse_j = Signal::speed(&joints.t_s, &pj, cs, 1, gap_j);
    let fine_i = Signal::speed(&inst.t_s, &pi, fine, span, gap_i);
    let fine_j = Signal::speed(&joints.t_s, &pj, fine, span, gap_j);
    let e =
        offset::estimate((&coarse_i, &coarse_j), (&fine_i, &fine_j), range).ok_or_else(|| {
            CaptureError::Offset(
                "no shift of the logs overlaps enough motion of both (do they record the same \
             session? give --offset-s when the offset is known)"
                    .into(),
            )
        })?;
    if e.correlation < MIN_CORRELATION {
        return Err(CaptureError::Offset(format!(
            "the tool speeds from the joints and from the instrument agree at best with \
             correlation {:.2} (at {:.3} s; below {MIN_CORRELATION}): are they logs of the same \
             session, is the marker on the robot? give --offset-s when the offset is known",
            e.correlation, e.offset_s
        )));
    }
    Ok(e)
}

/// Checks the joint log and the options.
fn check(joints: &JointLog, opts: &Options) -> Result<(), CaptureError> {
    let bad = |problem: String| CaptureError::JointLog {
        file: joints.source.clone(),
        problem,
    };
    if joints.t_s.len() < 3 {
        return Err(bad(format!(
            "{} samples: a joint log needs many",
            joints.t_s.len()
        )));
    }
    if let Some(k) = joints.t_s.windows(2).position(|w| w[1] <= w[0]) {
        return Err(bad(format!(
            "sample {}: time {} s does not increase",
            k + 2,
            joints.t_s[k + 1]
        )));
    }
    if opts.min_still_s.is_nan() || opts.min_still_s <= 2.0 * opts.trim_s {
        return Err(CaptureError::Options(format!(
            "--min-still-s {} must be longer than twice --trim-s {} (what is left is averaged)",
            opts.min_still_s, opts.trim_s
        )));
    }
    Ok(())
}

/// Finds the poses of a session: standstills, clock offset, robust means.
pub fn capture(
    model: &Model,
    joints: &JointLog,
    inst: &InstrumentLog,
    opts: &Options,
) -> Result<Capture, CaptureError> {
    check(joints, opts)?;
    let stills =
        standstill::find_standstills(&joints.t_s, &joints.q, opts.still_speed, opts.min_still_s);
    let (offset, offset_given) = match opts.offset_s {
        Some(o) => (
            OffsetEstimate {
                offset_s: o,
                correlation: f64::NAN,
            },
            true,
        ),
        None => (
            estimate_offset(model, joints, inst, opts.offset_range_s)?,
            false,
        ),
    };
    let n_markers = inst.marker_names.len();
    let valid_total = inst.points.iter().flatten().filter(|p| p.is_some()).count();
    let mut out = Capture {
        poses: Vec::new(),
        gaps: Vec::new(),
        standstills: stills.len(),
        offset,
        offset_given,
        samples_used: 0,
        samples_rejected: 0,
        samples_missing: inst.missing,
        samples_elsewhere: 0,
    };
    let mut in_windows = 0usize;
    for (k, s) in stills.iter().enumerate() {
        let (a, b) = (s.start_s + opts.trim_s, s.end_s - opts.trim_s);
        let gap = |reason: String| Gap {
            standstill: k + 1,
            start_s: s.start_s,
            end_s: s.end_s,
            reason,
        };
        let js: Vec<&Vec<f64>> = (s.first..=s.last)
            .filter(|&i| (a..=b).contains(&joints.t_s[i]))
            .map(|i| &joints.q[i])
            .collect();
        let i0 = inst.t_s.partition_point(|&t| t + offset.offset_s < a);
        let i1 = inst.t_s.partition_point(|&t| t + offset.offset_s <= b);
        if js.is_empty() || i1 <= i0 {
            out.gaps.push(gap(format!(
                "no instrument samples in {a:.3}..{b:.3} s (joint clock; the instrument log \
                 covers {:.3}..{:.3} s)",
                inst.t_s[0] + offset.offset_s,
                inst.t_s[inst.t_s.len() - 1] + offset.offset_s
            )));
            continue;
        }
        let mut means = Vec::with_capacity(n_markers);
        let mut problem = None;
        for m in 0..n_markers {
            let pts: Vec<[f64; 3]> = inst.points[i0..i1].iter().filter_map(|r| r[m]).collect();
            in_windows += pts.len();
            match average::robust_mean(&pts, opts.reject_sigma) {
                Some(r) if r.used >= opts.min_samples => means.push(r),
                r => {
                    out.samples_rejected += pts.len();
                    problem.get_or_insert(format!(
                        "marker `{}`: {} usable samples of {} (at least {} needed)",
                        inst.marker_names[m],
                        r.map_or(0, |r| r.used),
                        i1 - i0,
                        opts.min_samples
                    ));
                }
            }
        }
        if let Some(p) = problem {
            for r in &means {
                out.samples_rejected += r.used + r.rejected;
            }
            out.gaps.push(gap(p));
            continue;
        }
        let nq = js[0].len();
        let q = (0..nq)
            .map(|j| js.iter().map(|v| v[j]).sum::<f64>() / js.len() as f64)
            .collect();
        let used = means.iter().map(|r| r.used).min().unwrap_or(0);
        let rejected: usize = means.iter().map(|r| r.rejected).sum();
        out.samples_used += means.iter().map(|r| r.used).sum::<usize>();
        out.samples_rejected += rejected;
        let spread =
            (means.iter().map(|r| r.spread_mm.powi(2)).sum::<f64>() / n_markers as f64).sqrt();
        out.poses.push(CapturedPose {
            id: format!("s{:03}", k + 1),
            t_s: 0.5 * (a + b),
            q,
            points_mm: means.iter().map(|r| r.mean_mm).collect(),
            spread_mm: spread,
            n_samples: used,
            rejected,
        });
    }
    out.samples_elsewhere = valid_total.saturating_sub(in_windows);
    Ok(out)
}
