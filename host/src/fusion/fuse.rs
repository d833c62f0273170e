//! The fusion (`rigctl fuse`): joint readings + potentiometer recording + pencil trace ->
//! partial Cartesian error samples.
//!
//! For every joint sample (robot clock `t`) **while drawing** (the pencil predicted on the paper
//! and the model's point moving at `min_speed_mm_s` or faster in the plane; dwells, dips, the
//! descent and the lift only serve the clock alignment) and not **ambiguous** (no other
//! drawing sample more than `ambiguity_gap_s` away in time passes within `ambiguity_mm`: there
//! the trace cannot tell the passes apart, e.g. where a closed path meets its start; every
//! sample with the pencil predicted on the paper counts, dwells included):
//! 1. the nominal tool point `p = p(q)` and tool axis `a` of the fusing model (with its declared
//!    tilting driven by the moments in motion along the logged joints,
//!    [`crate::model::motion::moments_in_motion`], when the model has tilting data; rigid otherwise)
//!    and its height `h = n . (p - origin)` above the sheet;
//! 2. the board time of `t` from the clock alignment ([`super::align`], on the travel the
//!    pencil would show for the model, `-h / (n . a)`), and the pencil travel
//!    `d` there (potentiometer counts through the pot calibration, linear interpolation);
//!    samples with the pencil off the paper (`d > stop - contact_margin_mm`) are skipped;
//! 3. **out of plane**: the pencil tip `p_true + d a` lies on the paper, so the true tool point's
//!    height is `-d (n . a)` (= `d` while the tool axis is the sheet normal); `dev_n` is that
//!    minus `h`;
//! 4. **in plane, across the path**: the nominal tip `p + d a` projected onto the sheet, the
//!    closest point of the traced curve, the curve's unit tangent there (oriented along the
//!    motion) and the in-plane normal `u` to its left (seen from the pencil side); `dev_u` is
//!    the signed distance from the projection to the trace along `u`. Samples farther than
//!    `max_in_plane_mm` from the trace, nearer than `end_exclusion_mm` to an end of an open
//!    trace, or where the trace turns more than `max_kink_rad` away from the nominal motion or
//!    has a step within +-2 mm (roughness above `max_roughness_rad`; e.g. a backlash step of the
//!    arm): there the closest point is not across the path;
//! 5. **along the path: nothing** -- the trace carries no time, so the component of the error
//!    along the path is not measured and is not in the file.
//!
//! Second order: the unmeasured along-path error `e_t` bends the across-path reading by about
//! `e_t^2 / (2 R)` on a path of radius `R` (0.02 mm for 2 mm on the 100 mm circle); fusing again
//! with the calibrated model (`rigctl fuse --model CAL.toml`, then calibrate again) shrinks `e_t`
//! and this with it.
//!
//! The tip offset `d a` uses the model's tool axis; the arm's true axis differs by its
//! orientation error (a fraction of a degree), which moves the tip by `|d|` times that angle
//! (about 0.002 mm for `|d| = 1 mm`); it is neglected.
//!
//! The samples are written to and read from `FUSED.csv` by [`super::fused_file`].

use std::path::Path;

use nalgebra::Vector3;

use super::align::{align, AlignOptions, ClockAlignment};
use super::curve::TracedCurve;
use super::error::FusionError;
use super::placement::SheetPlacement;
use super::pot::TravelSeries;
use crate::io::pose_csv::{read_poses, PoseSpec};
use crate::model::motion::moments_in_motion;
use crate::model::{Model, Tilt};

/// Joint readings of the robot controller with their times.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointSamples {
    /// Robot-clock times, s, increasing.
    pub t_s: Vec<f64>,
    /// Joint readings, deg.
    pub q_deg: Vec<Vec<f64>>,
}

impl JointSamples {
    /// Reads a joint file (pose-file rules of FORMATS.md: columns `t`, `q1..qN`; `t` required
    /// and strictly increasing).
    pub fn read(path: &Path, model: &Model) -> Result<Self, FusionError> {
        let file = read_poses(path, &PoseSpec::for_model(model, false))?;
        let mut out = Self::default();
        for p in &file.poses {
            let t = p.t_s.ok_or_else(|| {
                FusionError::csv(path, p.line, "t", "a time is required in every row")
            })?;
            if out.t_s.last().is_some_and(|&prev| t <= prev) {
                return Err(FusionError::csv(
                    path,
                    p.line,
                    "t",
                    format!("time {t} s does not increase"),
                ));
            }
            out.t_s.push(t);
            out.q_deg.push(p.q.clone());
        }
        Ok(out)
    }
}

/// Settings of [`fuse`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FuseOptions {
    /// Clock alignment settings.
    pub align: AlignOptions,
    /// A sample is on the paper when its travel is this much below the stop, mm.
    pub contact_margin_mm: f64,
    /// Largest in-plane distance to the trace accepted, mm.
    pub max_in_plane_mm: f64,
    /// Samples whose closest trace point is nearer than this to an end of an open trace are
    /// skipped, mm.
    pub end_exclusion_mm: f64,
    /// A trace whose ends are this close is closed, mm.
    pub close_tol_mm: f64,
    /// Largest gap between potentiometer samples to interpolate across, s.
    pub max_pot_gap_s: f64,
    /// Least in-plane speed of the nominal point for a drawing sample, mm/s.
    pub min_speed_mm_s: f64,
    /// A sample whose nominal projection passes within this distance of another drawing
    /// sample's more than `ambiguity_gap_s` apart is ambiguous, mm.
    pub ambiguity_mm: f64,
    /// See `ambiguity_mm`, s.
    pub ambiguity_gap_s: f64,
    /// Largest angle between the trace's tangent and the nominal motion, rad: a larger one is a
    /// kink or step of the trace (e.g. a backlash step of the arm), where the closest point is
    /// not across the path.
    pub max_kink_rad: f64,
    /// Largest roughness of the trace around the closest point ([`super::curve::Closest`]),
    /// rad: beyond it the trace has a step there.
    pub max_roughness_rad: f64,
}

impl Default for FuseOptions {
    fn default() -> Self {
        Self {
            align: AlignOptions::default(),
            contact_margin_mm: 0.3,
            max_in_plane_mm: 3.0,
            end_exclusion_mm: 3.0,
            close_tol_mm: 2.0,
            max_pot_gap_s: 0.01,
            min_speed_mm_s: 5.0,
            ambiguity_mm: 3.0,
            ambiguity_gap_s: 1.0,
            max_kink_rad: 0.05,
            max_roughness_rad: 0.1,
        }
    }
}

pub use crate::calib::samples::FusedSample;

/// Counts of skipped joint samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Skipped {
    /// Not drawing: the nominal point is still or moving slower than `min_speed_mm_s` in the
    /// plane (dwells, dips, the descent and the lift), or off the paper's plane.
    pub not_drawing: usize,
    /// Where the pencil marked the same place at another time (the trace cannot tell the
    /// passes apart).
    pub ambiguous: usize,
    /// Where the trace turns away from the nominal motion by more than `max_kink_rad`.
    pub kinked: usize,
    /// Outside the recording (after alignment).
    pub outside_recording: usize,
    /// Pencil off the paper.
    pub off_paper: usize,
    /// Farther than `max_in_plane_mm` from the trace.
    pub off_trace: usize,
    /// Near an end of an open trace.
    pub near_trace_end: usize,
}

/// Result of [`fuse`].
#[derive(Debug, Clone, PartialEq)]
pub struct Fused {
    /// The fused samples, in time order.
    pub samples: Vec<FusedSample>,
    /// The clock alignment found.
    pub alignment: ClockAlignment,
    /// The pencil's stop reading (off the paper), mm.
    pub stop_mm: f64,
    /// Why the other joint samples were left out.
    pub skipped: Skipped,
}

/// Fuses the joint readings `joints` (nominal `model`), the pencil travel `pot` (board clock),
/// the traced curve `trace` (sheet mm) and the sheet `placement`.
pub fn fuse(
    model: &Model,
    joints: &JointSamples,
    pot: &TravelSeries,
    trace: &TracedCurve,
    placement: &SheetPlacement,
    o: &FuseOptions,
) -> Result<Fused, FusionError> {
    let n = placement.normal();
    // the model's tool point: with its declared tilting in motion when it has tilting data
    // (which also moves the point by backlash steps as the torques change sign)
    let nom = nominal_tool(model, joints)?;
    let h: Vec<f64> = nom.iter().map(|(p, _)| placement.height_mm(p)).collect();
    let stop_mm = pot.stop_mm().ok_or_else(|| {
        FusionError::NoSamples("the recording has no potentiometer sample".into())
    })?;
    // the travel the pencil would show for the model: -h / (n . a)
    let predicted: Vec<f64> = nom
        .iter()
        .zip(&h)
        .map(|((_, a), hk)| -hk / n.dot(a).min(-1e-6))
        .collect();
    let alignment = align(pot, &joints.t_s, &predicted, stop_mm, &o.align)?;
    let proj: Vec<[f64; 2]> = nom.iter().map(|(p, _)| placement.to_sheet_mm(p)).collect();
    let mut skipped = Skipped::default();
    let mut samples = Vec::new();
    let last = joints.t_s.len().saturating_sub(1);
    let (moving, marking) = drawing(&joints.t_s, &proj, &predicted, stop_mm, o);
    for (k, &t) in joints.t_s.iter().enumerate() {
        if !moving[k] {
            skipped.not_drawing += 1;
            continue;
        }
        let ambiguous = marking.iter().any(|&j| {
            (joints.t_s[j] - t).abs() > o.ambiguity_gap_s
                && (proj[j][0] - proj[k][0]).hypot(proj[j][1] - proj[k][1]) < o.ambiguity_mm
        });
        if ambiguous {
            skipped.ambiguous += 1;
            continue;
        }
        let Some(d) = pot.at(alignment.board_s(t), o.max_pot_gap_s) else {
            skipped.outside_recording += 1;
            continue;
        };
        if d > stop_mm - o.contact_margin_mm {
            skipped.off_paper += 1;
            continue;
        }
        let (p, a) = nom[k];
        let height_true = -d * n.dot(&a);
        let tip = placement.to_sheet_mm(&(p + a * d));
        let motion = [
            proj[(k + 1).min(last)][0] - proj[k.saturating_sub(1)][0],
            proj[(k + 1).min(last)][1] - proj[k.saturating_sub(1)][1],
        ];
        let (dev_u, u_sheet) = match trace_deviation(trace, tip, motion, o) {
            Ok(d) => d,
            Err(TraceSkip::OffTrace) => {
                skipped.off_trace += 1;
                continue;
            }
            Err(TraceSkip::NearEnd) => {
                skipped.near_trace_end += 1;
                continue;
            }
            Err(TraceSkip::Kinked) => {
                skipped.kinked += 1;
                continue;
            }
        };
        samples.push(FusedSample {
            t_s: t,
            q_deg: joints.q_deg[k].clone(),
            nominal_mm: p,
            dev_u_mm: dev_u,
            u: placement.dir_to_r(u_sheet),
            dev_n_mm: height_true - h[k],
            n,
        });
    }
    if samples.is_empty() {
        return Err(FusionError::NoSamples(skipped.why_none(joints.t_s.len())));
    }
    Ok(Fused {
        samples,
        alignment,
        stop_mm,
        skipped,
    })
}

/// A tool point (mm) and the tool axis, frame R.
type ToolPose = (Vector3<f64>, Vector3<f64>);

/// The model's tool point and tool axis (frame R) at every joint sample: with its declared
/// tilting in motion when it has tilting data (which also moves the point by backlash steps as
/// the torques change sign).
fn nominal_tool(model: &Model, joints: &JointSamples) -> Result<Vec<ToolPose>, FusionError> {
    let moments = if model.has_tilt() {
        Some(moments_in_motion(model, &joints.t_s, &joints.q_deg)?)
    } else {
        None
    };
    let mut nom = Vec::with_capacity(joints.t_s.len());
    for (k, q) in joints.q_deg.iter().enumerate() {
        let tilt = moments.as_ref().map_or(Tilt::Off, |m| Tilt::Moments(&m[k]));
        let fk = model.fk(q, tilt)?;
        nom.push((fk.position_mm, fk.rotation.column(2).into_owned()));
    }
    Ok(nom)
}

/// Per joint sample, whether the pencil draws there (moving fast enough on the sheet with the
/// pencil predicted on the paper); and the samples with the pencil predicted on the paper
/// (each left a mark the trace may hold).
fn drawing(
    t_s: &[f64],
    proj: &[[f64; 2]],
    predicted: &[f64],
    stop_mm: f64,
    o: &FuseOptions,
) -> (Vec<bool>, Vec<usize>) {
    let last = t_s.len().saturating_sub(1);
    let speed = |k: usize| {
        let (a, b) = (k.saturating_sub(1), (k + 1).min(last));
        let dt = t_s[b] - t_s[a];
        let d = (proj[b][0] - proj[a][0]).hypot(proj[b][1] - proj[a][1]);
        if dt > 0.0 {
            d / dt
        } else {
            0.0
        }
    };
    let on_paper = |k: usize| predicted[k] < stop_mm - o.align.contact_margin_mm;
    let moving: Vec<bool> = (0..t_s.len())
        .map(|k| speed(k) >= o.min_speed_mm_s && on_paper(k))
        .collect();
    // every sample with the pencil predicted on the paper left a mark the trace may hold
    let marking: Vec<usize> = (0..t_s.len()).filter(|&k| on_paper(k)).collect();
    (moving, marking)
}

/// Why a sample is left out at the trace.
enum TraceSkip {
    /// The tip is farther from the trace than `max_in_plane_mm`.
    OffTrace,
    /// The closest trace point is within `end_exclusion_mm` of an end.
    NearEnd,
    /// The trace turns away from the motion, or is rough there.
    Kinked,
}

/// The in-plane deviation of the trace from the pencil `tip` (sheet mm) along the sheet
/// direction normal to the trace, and that direction (oriented by the tip's `motion` on the
/// sheet).
fn trace_deviation(
    trace: &TracedCurve,
    tip: [f64; 2],
    motion: [f64; 2],
    o: &FuseOptions,
) -> Result<(f64, [f64; 2]), TraceSkip> {
    let c = trace.closest(tip);
    if c.distance_mm > o.max_in_plane_mm {
        return Err(TraceSkip::OffTrace);
    }
    if c.to_end_mm < o.end_exclusion_mm {
        return Err(TraceSkip::NearEnd);
    }
    let mut tan = c.tangent;
    let m_len = motion[0].hypot(motion[1]);
    if m_len > 1e-3 && tan[0] * motion[0] + tan[1] * motion[1] < 0.0 {
        tan = [-tan[0], -tan[1]];
    }
    let cross = (tan[0] * motion[1] - tan[1] * motion[0]) / m_len.max(1e-300);
    if cross.abs() > o.max_kink_rad.sin() || c.roughness_rad > o.max_roughness_rad {
        return Err(TraceSkip::Kinked);
    }
    let u_sheet = [-tan[1], tan[0]];
    let dev_u = (c.point[0] - tip[0]) * u_sheet[0] + (c.point[1] - tip[1]) * u_sheet[1];
    Ok((dev_u, u_sheet))
}

impl Skipped {
    /// Why no sample of `total` joint samples was kept.
    fn why_none(&self, total: usize) -> String {
        format!(
            "{} joint samples: {} not drawing, {} ambiguous, {} outside the recording, {} with the \
             pencil off the paper, {} off the trace, {} near a trace end, {} at a kink",
            total,
            self.not_drawing,
            self.ambiguous,
            self.outside_recording,
            self.off_paper,
            self.off_trace,
            self.near_trace_end,
            self.kinked
        )
    }
}
