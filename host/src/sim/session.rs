//! A simulated session of the low-cost rig (thesis 5.5.2, fig. 5.11 right): the arm draws a
//! path with a spring-loaded pencil on a sheet lying on the 45-degree plane, the board records
//! the pencil's potentiometer, the robot controller logs its joint readings, and the sheet is
//! scanned. Everything the real session would leave behind is written, plus the truth.
//!
//! # The robot
//! * Truth model: the declared model (katana450 with the 330 mm pencil holder) with random
//!   geometric errors (normal, `geometric_sigma_deg`, the same draw as `rigctl simulate` for the
//!   same seed: [`super::simulate::truth_model`]), plus any undeclared effects
//!   ([`SessionConfig::effects`], e.g. `encoder_harmonic:j1:h1`), and the declared joint tilting driven by the
//!   moments **in motion** (RNEA, [`crate::model::dynamics::moments_kgfm`], slender-rod links; joint
//!   rates and accelerations by central differences over +-10 ms of the 1 kHz joint path).
//! * Commands: the controller knows only the nominal model, so the joint trajectory is the IK of
//!   the **nominal** rigid model ([`crate::model::ik::solve`]) of the planned targets (tool axis fixed,
//!   [`default_pencil_axis`]: 22.5 deg from the sheet normal), computed at 1 kHz; the arm follows it exactly in joint space and the
//!   joint readings are logged at `robot_rate_hz` (`joints.csv`: `t,q1..q5`, robot clock from 0).
//!
//! # The timeline (robot clock)
//! dwell 0.5 s with the tool point `lift_mm` above the path's start; descend onto the paper in
//! 1 s (quintic); dwell 0.3 s; **dip** `dip_mm` into the paper and back in 0.5 s
//! (`-dip sin^2`); dwell 0.3 s; draw the path in `draw_duration_s` (quintic profile); dwell
//! 0.3 s; dip again; dwell 0.3 s; lift in 1 s; dwell 0.5 s. The dips are the clock-alignment
//! markers of [`crate::fusion::align`].
//!
//! # The pencil and the board
//! The pencil slides along the true tool axis; its travel (mm, + = extended, 0 = the tool point)
//! is what keeps its tip on the paper, `-h_true / (n . a_true)`, up to its stop at
//! `pencil_stop_mm` (off the paper). The potentiometer reads
//! `raw = counts_at_zero + counts_per_mm * travel + N(0, pot_noise_counts)`, rounded and
//! clamped to 12 bits, sampled at `pot_rate_hz` on the **board clock**
//! `board = robot (1 + clock_drift_ppm 1e-6) + clock_offset_s`, sent in `PotBatch` frames of 50
//! samples and stored as a recording (`pot.rec`, [`crate::daq::recording`]). A gauge-block jig
//! (`potjig.csv`: `raw,travel_mm` at -3..+2 mm, each the mean of 100 readings) calibrates it.
//!
//! # The sheet
//! `placement.toml` ([`crate::fusion::placement`]; by default the 45-degree plane through
//! [`SESSION_SHEET_ORIGIN_MM`]); the pencil tip's path on the paper, rendered
//! as a scan ([`crate::trace::synth::render_scan`]) at `dpi`, rotated by `scan_rotation_deg` and
//! shifted on the glass (`scan.png`), with the printed reference path.
//!
//! # Files (written into the output directory, each atomically)
//! `joints.csv`, `pot.rec`, `potjig.csv`, `scan.png`, `placement.toml` (the session's inputs) and
//! `truth.toml` (truth model), `truth_path.csv` (`t,q1..q5,x,y,z`: the true tool point at every
//! joint reading, a pose file), `session.json` (clock offset, pot scale, geometric errors).

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rig_protocol::{encode_device, DeviceMsg, PotBatch, DEVICE_FRAME_MAX};

use super::effects::Change;
use super::paths::quintic_profile;
use super::simulate::{truth_model, SimConfig};
use crate::fusion::{JigPoint, SheetPlacement};
use crate::model::dynamics::moments_kgfm;
use crate::model::ik::KATANA_SEED_DEG;
use crate::model::ik::{solve, IkTilt, ToolTarget};
use crate::model::{Model, Tilt};
pub use crate::sheet::drawn::{
    default_pencil_axis, SessionPath, LINE_HALF_LENGTH_DRAWN_MM, SESSION_SHEET_ORIGIN_MM,
};

mod config;
mod files;

pub use config::{SessionConfig, SessionError};
pub use files::{render_session_scan, write_session};

/// Format tag of `session.json`.
pub const SESSION_FORMAT: &str = "rigctl-session-truth/1";
/// Half width (1 ms steps) of the central differences giving the joint rates of the truth.
const DIFF_STEPS: usize = 10;
/// Potentiometer samples per frame.
const BATCH: usize = 50;
/// A simulated session in memory.
#[derive(Debug, Clone)]
pub struct Session {
    /// The truth model.
    pub truth: Model,
    /// Geometric errors of the truth (name, deg).
    pub geometric_errors: Vec<(String, f64)>,
    /// The sheet placement.
    pub placement: SheetPlacement,
    /// Joint log times (robot clock), s.
    pub t_s: Vec<f64>,
    /// Joint readings at those times, deg.
    pub q_deg: Vec<Vec<f64>>,
    /// True tool point at those times, mm in R.
    pub truth_mm: Vec<Vector3<f64>>,
    /// Stored frames (COBS bytes without the delimiter) with their host receive times, µs.
    pub frames: Vec<(u64, Vec<u8>)>,
    /// First board sample time, µs.
    pub board_t0_us: u64,
    /// Board time between potentiometer samples, µs.
    pub pot_period_us: u32,
    /// The potentiometer counts, one per sample from `board_t0_us`.
    pub pot_raw: Vec<u16>,
    /// The pencil tip's path on the paper while in contact, sheet mm.
    pub pencil_mm: Vec<[f64; 2]>,
    /// The gauge-block jig readings.
    pub jig: Vec<JigPoint>,
}

impl Session {
    /// The fused samples an ideal trace and potentiometer would give for this session (no image
    /// or clock-alignment step): every joint sample while drawing (the `declared` model's point
    /// within 0.05 mm of the sheet and moving at 5 mm/s or more in its plane) with the true
    /// tool point's deviation from the nominal rigid one across the path (`u`, in the sheet
    /// plane, to the left of the motion) and out of the sheet (`n`), each plus white noise of
    /// `noise_mm`. For studying calibration and diagnosis on partial measurements apart from
    /// the tracer; `rigctl fuse` gives the real thing.
    pub fn ideal_fused_samples(
        &self,
        declared: &Model,
        noise_mm: f64,
        seed: u64,
    ) -> Result<Vec<crate::fusion::FusedSample>, SessionError> {
        let noise = Normal::new(0.0, noise_mm)
            .map_err(|e| SessionError::Config(format!("noise {noise_mm} mm: {e}")))?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let n = self.placement.normal();
        let nominal = self
            .q_deg
            .iter()
            .map(|q| declared.position_mm(q, Tilt::Off))
            .collect::<Result<Vec<_>, _>>()?;
        let mut out = Vec::new();
        for k in 1..self.t_s.len().saturating_sub(1) {
            let v = (nominal[k + 1] - nominal[k - 1]) / (self.t_s[k + 1] - self.t_s[k - 1]);
            let v_plane = v - n * n.dot(&v);
            if self.placement.height_mm(&nominal[k]).abs() > 0.05 || v_plane.norm() < 5.0 {
                continue;
            }
            let u = n.cross(&v_plane).normalize();
            let e = self.truth_mm[k] - nominal[k];
            out.push(crate::fusion::FusedSample {
                t_s: self.t_s[k],
                q_deg: self.q_deg[k].clone(),
                nominal_mm: nominal[k],
                dev_u_mm: u.dot(&e) + noise.sample(&mut rng),
                u,
                dev_n_mm: n.dot(&e) + noise.sample(&mut rng),
                n,
            });
        }
        Ok(out)
    }
}

/// The planned target at robot time `t`: path parameter and height above the paper (mm).
fn timeline(cfg: &SessionConfig, t: f64) -> (f64, f64) {
    let dip = |tau: f64| -cfg.dip_mm * (std::f64::consts::PI * tau).sin().powi(2);
    let q = |tau: f64, dur: f64| quintic_profile(tau, dur).0;
    let phases: [(f64, u8); 11] = [
        (0.5, 0),
        (1.0, 1),
        (0.3, 2),
        (0.5, 3),
        (0.3, 2),
        (cfg.draw_duration_s, 4),
        (0.3, 5),
        (0.5, 6),
        (0.3, 5),
        (1.0, 7),
        (0.5, 8),
    ];
    let mut start = 0.0;
    for (dur, kind) in phases {
        if t < start + dur || kind == 8 {
            let tau = (t - start).clamp(0.0, dur);
            return match kind {
                0 => (0.0, cfg.lift_mm),
                1 => (0.0, cfg.lift_mm * (1.0 - q(tau, dur))),
                2 => (0.0, 0.0),
                3 => (0.0, dip(tau / dur)),
                4 => (q(tau, dur), 0.0),
                5 => (1.0, 0.0),
                6 => (1.0, dip(tau / dur)),
                7 => (1.0, cfg.lift_mm * q(tau, dur)),
                _ => (1.0, cfg.lift_mm),
            };
        }
        start += dur;
    }
    (1.0, cfg.lift_mm)
}

/// Total robot time of the session, s.
pub fn session_duration_s(cfg: &SessionConfig) -> f64 {
    5.2 + cfg.draw_duration_s
}

fn check(cfg: &SessionConfig) -> Result<(), SessionError> {
    let bad = |m: String| Err(SessionError::Config(m));
    if !(cfg.draw_duration_s > 0.5 && cfg.draw_duration_s <= 600.0) {
        return bad(format!(
            "draw duration {} s: must be in 0.5..600",
            cfg.draw_duration_s
        ));
    }
    if cfg.robot_rate_hz == 0 || 1000 % cfg.robot_rate_hz != 0 {
        return bad(format!(
            "robot rate {} Hz must divide 1000",
            cfg.robot_rate_hz
        ));
    }
    if cfg.pot_rate_hz == 0 || 1_000_000 % cfg.pot_rate_hz != 0 || cfg.pot_rate_hz > 10_000 {
        return bad(format!(
            "pot rate {} Hz must divide 1e6 and be <= 10 kHz",
            cfg.pot_rate_hz
        ));
    }
    let finite = [
        cfg.clock_offset_s,
        cfg.clock_drift_ppm,
        cfg.counts_at_zero,
        cfg.counts_per_mm,
        cfg.pot_noise_counts,
        cfg.pencil_stop_mm,
        cfg.lift_mm,
        cfg.dip_mm,
        cfg.dpi,
        cfg.scan_rotation_deg,
        cfg.geometric_sigma_deg,
    ];
    if finite.iter().any(|v| !v.is_finite())
        || cfg.clock_offset_s < 1.0
        || cfg.counts_per_mm == 0.0
        || cfg.pot_noise_counts < 0.0
        || cfg.lift_mm <= cfg.pencil_stop_mm
        || cfg.dpi < 300.0
        || cfg.geometric_sigma_deg < 0.0
    {
        return bad("session settings out of range (offset >= 1 s, lift above the pencil stop, dpi >= 300, ...)".into());
    }
    if let Some(e) = cfg
        .effects
        .iter()
        .find(|e| !matches!(e.change, Change::Params(_)))
    {
        return bad(format!(
            "effect {}: time drifts and joint-angle terms are not simulated in a session; use `rigctl simulate` poses",
            e.id
        ));
    }
    Ok(())
}

/// Simulates a session of the `declared` model.
pub fn simulate_session(declared: &Model, cfg: &SessionConfig) -> Result<Session, SessionError> {
    check(cfg)?;
    let (truth, geometric_errors) = truth_model(
        declared,
        &SimConfig {
            seed: cfg.seed,
            geometric_sigma_deg: cfg.geometric_sigma_deg,
            effects: cfg.effects.clone(),
            ..SimConfig::default()
        },
    )?;
    let placement = cfg
        .placement
        .unwrap_or_else(|| cfg.path.default_placement());
    let n = placement.normal();
    let pencil_axis = cfg.pencil_axis.unwrap_or_else(|| default_pencil_axis(&n));
    if pencil_axis.dot(&n).is_nan() || pencil_axis.dot(&n) >= -0.5 {
        return Err(SessionError::Config(
            "the pencil axis must point into the sheet, within 60 deg of its normal".into(),
        ));
    }
    let steps = (session_duration_s(cfg) / STEP_S).round() as usize;
    let q_all = commanded_joints(declared, cfg, &placement, &pencil_axis, steps)?;
    let motion = truth_in_motion(&truth, cfg, &placement, &q_all)?;
    // the joint log at the robot's rate
    let every = (1000 / cfg.robot_rate_hz) as usize;
    let idx: Vec<usize> = (0..=steps).step_by(every).collect();
    let t_s: Vec<f64> = idx.iter().map(|&k| k as f64 * STEP_S).collect();
    let q_deg: Vec<Vec<f64>> = idx.iter().map(|&k| round_q(&q_all[k])).collect();
    let truth_mm: Vec<Vector3<f64>> = idx.iter().map(|&k| motion.p_true[k]).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    rng.set_stream(7);
    let noise = Normal::new(0.0, cfg.pot_noise_counts.max(1e-12))
        .map_err(|e| SessionError::Config(format!("pot noise: {e}")))?;
    let pot = pot_recording(cfg, &motion.travel, &noise, &mut rng)?;
    let jig = gauge_jig(cfg, &noise, &mut rng);
    Ok(Session {
        truth,
        geometric_errors,
        placement,
        t_s,
        q_deg,
        truth_mm,
        frames: pot.frames,
        board_t0_us: pot.board_t0_us,
        pot_period_us: pot.period_us,
        pot_raw: pot.raws,
        pencil_mm: motion.pencil_mm,
        jig,
    })
}

/// Time step of the simulation (s): joints, moments and positions at 1 kHz.
const STEP_S: f64 = 1e-3;

/// Step 1: the commanded joints at every step, IK of the nominal rigid model along the path.
fn commanded_joints(
    declared: &Model,
    cfg: &SessionConfig,
    placement: &SheetPlacement,
    pencil_axis: &Vector3<f64>,
    steps: usize,
) -> Result<Vec<Vec<f64>>, SessionError> {
    let n = placement.normal();
    let mut seed = KATANA_SEED_DEG.to_vec();
    seed.truncate(declared.n_joints());
    seed.resize(declared.n_joints(), 0.0);
    let mut q_all: Vec<Vec<f64>> = Vec::with_capacity(steps + 1);
    for k in 0..=steps {
        let (s, h) = timeline(cfg, k as f64 * STEP_S);
        let target = ToolTarget {
            position_mm: placement.to_r_mm(cfg.path.sheet_point(s)) + n * h,
            axis: *pencil_axis,
        };
        let q = solve(declared, &target, &seed, IkTilt::Off)?;
        seed.clone_from(&q);
        q_all.push(q);
    }
    Ok(q_all)
}

/// What the truth did at every step: tool point, pencil travel, and the drawn line.
struct Motion {
    /// True tool point (mm, frame R) per step.
    p_true: Vec<Vector3<f64>>,
    /// Pencil travel (mm) per step.
    travel: Vec<f64>,
    /// The pencil's line on the sheet (sheet mm), points >= 0.05 mm apart.
    pencil_mm: Vec<[f64; 2]>,
}

/// Step 2: the truth in motion: rates by central differences, RNEA moments, tilted FK, the
/// pencil's travel and where it touches the sheet.
fn truth_in_motion(
    truth: &Model,
    cfg: &SessionConfig,
    placement: &SheetPlacement,
    q_all: &[Vec<f64>],
) -> Result<Motion, SessionError> {
    let n = placement.normal();
    let nj = truth.n_joints();
    let steps = q_all.len() - 1;
    let mut out = Motion {
        p_true: Vec::with_capacity(steps + 1),
        travel: Vec::with_capacity(steps + 1),
        pencil_mm: Vec::new(),
    };
    for k in 0..=steps {
        // rates over +-10 ms: the IK's round-off would swamp second differences over 1 ms
        let w = DIFF_STEPS.min(k).min(steps - k);
        let (a, b) = (k - w, k + w);
        let h = w as f64 * STEP_S;
        let (qd, qdd): (Vec<f64>, Vec<f64>) = if w == 0 {
            (vec![0.0; nj], vec![0.0; nj])
        } else {
            (0..nj)
                .map(|j| {
                    (
                        (q_all[b][j] - q_all[a][j]) / (2.0 * h),
                        (q_all[b][j] - 2.0 * q_all[k][j] + q_all[a][j]) / (h * h),
                    )
                })
                .unzip()
        };
        let m = moments_kgfm(truth, &q_all[k], &qd, &qdd, cfg.inertia)?;
        let fk = truth.fk(&q_all[k], Tilt::Moments(&m))?;
        let axis = fk.rotation.column(2).into_owned();
        let free = -placement.height_mm(&fk.position_mm) / n.dot(&axis);
        let d = free.min(cfg.pencil_stop_mm);
        if d.is_nan() || d <= -cfg.lift_mm {
            return Err(SessionError::PencilRange {
                travel_mm: d,
                t_s: k as f64 * STEP_S,
            });
        }
        if free <= cfg.pencil_stop_mm {
            let tip = placement.to_sheet_mm(&(fk.position_mm + axis * d));
            let far = out
                .pencil_mm
                .last()
                .is_none_or(|l| (l[0] - tip[0]).hypot(l[1] - tip[1]) >= 0.05);
            if far {
                out.pencil_mm.push(tip);
            }
        }
        out.p_true.push(fk.position_mm);
        out.travel.push(d);
    }
    Ok(out)
}

/// The board's potentiometer recording: raw counts and their frames.
struct PotRecording {
    raws: Vec<u16>,
    frames: Vec<(u64, Vec<u8>)>,
    board_t0_us: u64,
    period_us: u32,
}

/// Step 3: the potentiometer sampled on the board clock (offset, drift, noise), batched and
/// framed as the board sends it.
fn pot_recording(
    cfg: &SessionConfig,
    travel: &[f64],
    noise: &Normal<f64>,
    rng: &mut ChaCha8Rng,
) -> Result<PotRecording, SessionError> {
    let steps = travel.len() - 1;
    let rate = 1.0 + cfg.clock_drift_ppm * 1e-6;
    let period_us = 1_000_000 / cfg.pot_rate_hz;
    let board_t0_us = ((-0.3 * rate + cfg.clock_offset_s) * 1e6).round() as u64;
    let board_t1_us = (((session_duration_s(cfg) + 0.3) * rate + cfg.clock_offset_s) * 1e6) as u64;
    let n_pot = ((board_t1_us - board_t0_us) / u64::from(period_us)) as usize;
    let travel_at = |tr: f64| {
        let x = (tr / STEP_S).clamp(0.0, steps as f64);
        let i = (x.floor() as usize).min(steps.saturating_sub(1));
        let f = x - i as f64;
        travel[i] + f * (travel[(i + 1).min(steps)] - travel[i])
    };
    let mut raws = Vec::with_capacity(n_pot);
    for j in 0..n_pot {
        let tb = (board_t0_us + j as u64 * u64::from(period_us)) as f64 * 1e-6;
        let tr = (tb - cfg.clock_offset_s) / rate;
        let c = cfg.counts_at_zero + cfg.counts_per_mm * travel_at(tr) + noise.sample(rng);
        raws.push(c.round().clamp(0.0, 4095.0) as u16);
    }
    let mut frames = Vec::new();
    let mut buf = [0u8; DEVICE_FRAME_MAX];
    for (b, chunk) in raws.chunks(BATCH).enumerate() {
        let t0_us = board_t0_us + (b * BATCH) as u64 * u64::from(period_us);
        let samples = heapless::Vec::from_slice(chunk)
            .map_err(|_| SessionError::Encode("batch too long".into()))?;
        let msg = DeviceMsg::Pot(PotBatch {
            seq: b as u32,
            t0_us,
            period_us,
            samples,
        });
        let frame =
            encode_device(&msg, &mut buf).map_err(|e| SessionError::Encode(format!("{e:?}")))?;
        let stored = frame[..frame.len() - 1].to_vec();
        let last_us = t0_us + (chunk.len() as u64 - 1) * u64::from(period_us);
        frames.push((last_us - board_t0_us + 1500, stored));
    }
    Ok(PotRecording {
        raws,
        frames,
        board_t0_us,
        period_us,
    })
}

/// Step 4: the gauge-block jig: mean counts of 100 readings at -3..2 mm of travel.
fn gauge_jig(cfg: &SessionConfig, noise: &Normal<f64>, rng: &mut ChaCha8Rng) -> Vec<JigPoint> {
    (-3..=2)
        .map(|k| {
            let travel_mm = f64::from(k);
            let mean: f64 = (0..100)
                .map(|_| cfg.counts_at_zero + cfg.counts_per_mm * travel_mm + noise.sample(rng))
                .map(|c| c.round())
                .sum::<f64>()
                / 100.0;
            JigPoint {
                raw: mean,
                travel_mm,
            }
        })
        .collect()
}

/// Joint readings as the controller logs them (6 decimals of a degree).
fn round_q(q: &[f64]) -> Vec<f64> {
    q.iter().map(|v| (v * 1e6).round() / 1e6).collect()
}

#[cfg(test)]
mod tests;
