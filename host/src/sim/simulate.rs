//! One simulated calibration session: a truth model, commanded poses, noisy measurements.
//!
//! - **Declared model**: the preset or model file given (nominal, tilting values of table 5.2).
//! - **Truth**: the declared model + random geometric errors, Gaussian with standard deviation
//!   `geometric_sigma_deg` (default 0.05 deg, the size of the thesis's section 3.5 deviations)
//!   on each of the thesis's 12 geometric parameters (`dth1..5, al2..5, be3..5`; for another
//!   model: every joint offset and twist parameter), + the `--effect`s ([`super::effects`]).
//!   The truth is evaluated **with static joint tilting** (declared law, table 5.2 values as
//!   changed by effects; a model without tilting data is evaluated rigid).
//! - **Commanded joints**: calibration poses are the ISO 9283 sequence ([`super::plan`]) solved
//!   by IK on the *declared rigid* model (what the controller commands); for a model that is not
//!   a 5-joint Katana-type chain, 118 random poses instead. Validation poses are random joints
//!   within the limits ([`super::plan::random_poses`]). Joint readings are written with 9
//!   decimals and the truth is evaluated at exactly the written values.
//! - **Measurement**: truth position + time drift + independent Gaussian noise of standard
//!   deviation `noise_mm` on each coordinate.
//! - **Time**: pose k of the session is measured at `t = k * pose_interval_s` (default 10 s);
//!   validation poses follow the calibration poses in the same session.
//!
//! Random streams (ChaCha8, seeded with `seed`): stream 1 geometric errors, stream 2 validation
//! poses, stream 3 measurement noise; so adding an effect does not change the other draws.

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::effects::{Effect, EffectError};
use super::iso9283::{Cube, ISO_POSE_COUNT};
use super::plan::{iso_calibration_sequence, random_poses, PlanError, PlannedPose};
use crate::model::ik::ArmGeometry;
use crate::model::transmission::approach_directions;
use crate::model::{Model, ModelError, ParamKind, Tilt, KATANA_GEOMETRIC_PARAMS};

/// Settings of a simulated session.
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// Seed of all random draws.
    pub seed: u64,
    /// Standard deviation of the measurement noise per coordinate, mm.
    pub noise_mm: f64,
    /// Standard deviation of the geometric parameter errors, deg.
    pub geometric_sigma_deg: f64,
    /// Effects the declared model lacks.
    pub effects: Vec<Effect>,
    /// Number of validation poses.
    pub n_val: usize,
    /// Time between two measured poses, s.
    pub pose_interval_s: f64,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            seed: 1,
            noise_mm: 0.01,
            geometric_sigma_deg: 0.05,
            effects: Vec::new(),
            n_val: 60,
            pose_interval_s: 10.0,
        }
    }
}

/// Why a simulation failed.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A setting out of range.
    #[error("{0}")]
    Config(String),
    /// A bad effect.
    #[error(transparent)]
    Effect(#[from] EffectError),
    /// Poses could not be planned.
    #[error(transparent)]
    Plan(#[from] PlanError),
    /// The model failed.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// An output file or directory could not be written.
    #[error("cannot write {path}: {source}")]
    Write {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// An atomic write failed.
    #[error(transparent)]
    Atomic(#[from] crate::io::atomic::AtomicWriteError),
}

impl crate::error::Classify for SimError {
    fn kind(&self) -> crate::error::ErrorKind {
        use crate::error::ErrorKind;
        match self {
            SimError::Config(_) | SimError::Effect(_) => ErrorKind::BadInput,
            SimError::Plan(e) => e.kind(),
            SimError::Model(e) => e.kind(),
            SimError::Atomic(e) => e.kind(),
            SimError::Write { .. } => ErrorKind::Failure,
        }
    }
}

/// One measured pose.
#[derive(Debug, Clone, PartialEq)]
pub struct SimPose {
    /// Pose name.
    pub id: String,
    /// Joint readings as written (deg).
    pub q_deg: Vec<f64>,
    /// Truth tool point (mm, R), before drift and noise.
    pub truth_mm: Vector3<f64>,
    /// Measured tool point (mm, R): truth + drift + noise.
    pub measured_mm: Vector3<f64>,
    /// Time of the measurement, s.
    pub t_s: f64,
}

/// Everything a session produced.
#[derive(Debug, Clone)]
pub struct SimOutput {
    /// The declared model.
    pub declared: Model,
    /// The truth model: parameters, joint terms and time terms ([`Model::time_terms`]).
    pub truth: Model,
    /// The geometric errors drawn, `(name, delta)`, in draw order.
    pub geometric_errors: Vec<(String, f64)>,
    /// Whether the truth was evaluated with tilting.
    pub tilt: bool,
    /// Calibration poses (ISO 9283 sequence).
    pub cal: Vec<SimPose>,
    /// Validation poses.
    pub val: Vec<SimPose>,
}

fn rng(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    r.set_stream(stream);
    r
}

/// Names of the parameters that get random geometric errors.
pub fn geometric_param_names(model: &Model) -> Vec<String> {
    if KATANA_GEOMETRIC_PARAMS
        .iter()
        .all(|n| model.param_index(n).is_some())
    {
        return KATANA_GEOMETRIC_PARAMS
            .iter()
            .map(|s| s.to_string())
            .collect();
    }
    model
        .params()
        .iter()
        .filter(|p| matches!(p.kind, ParamKind::JointOffset | ParamKind::Twist))
        .map(|p| p.name.clone())
        .collect()
}

/// Longest time between two poses, s (one day).
const MAX_POSE_INTERVAL_S: f64 = 86_400.0;

/// Builds the truth model: declared + geometric errors + effects.
pub fn truth_model(
    declared: &Model,
    cfg: &SimConfig,
) -> Result<(Model, Vec<(String, f64)>), SimError> {
    let mut truth = declared.clone();
    let normal = Normal::new(0.0, cfg.geometric_sigma_deg).map_err(|e| {
        SimError::Config(format!("geometric sigma {}: {e}", cfg.geometric_sigma_deg))
    })?;
    let mut r = rng(cfg.seed, 1);
    let mut errors = Vec::new();
    for name in geometric_param_names(declared) {
        let delta = normal.sample(&mut r);
        let v = truth.param(&name).unwrap_or(0.0);
        truth.set_param(&name, v + delta)?;
        errors.push((name, delta));
    }
    for e in &cfg.effects {
        e.apply(&mut truth)?;
    }
    truth
        .check_ranges()
        .map_err(|e| SimError::Config(format!("the truth model with the effects: {e}")))?;
    Ok((truth, errors))
}

/// Rounds joint readings to the 9 decimals written to the files.
fn as_written(q: &[f64]) -> Vec<f64> {
    q.iter()
        .map(|v| format!("{v:.9}").parse::<f64>().unwrap_or(*v))
        .collect()
}

/// Runs a session (see the module documentation).
pub fn simulate(declared: &Model, cfg: &SimConfig) -> Result<SimOutput, SimError> {
    if !(cfg.noise_mm.is_finite()
        && cfg.noise_mm >= 0.0
        && cfg.noise_mm <= crate::io::ranges::MAX_POSITION_MM)
    {
        return Err(SimError::Config(format!(
            "--noise-mm {}: must be a finite number in [0, 100 000] mm",
            cfg.noise_mm
        )));
    }
    if !(cfg.pose_interval_s.is_finite()
        && cfg.pose_interval_s >= 0.0
        && cfg.pose_interval_s <= MAX_POSE_INTERVAL_S)
    {
        return Err(SimError::Config(format!(
            "--pose-interval-s {}: must be a finite number in [0, {MAX_POSE_INTERVAL_S}] s",
            cfg.pose_interval_s
        )));
    }
    if !(cfg.geometric_sigma_deg.is_finite()
        && cfg.geometric_sigma_deg >= 0.0
        && cfg.geometric_sigma_deg <= crate::io::ranges::MAX_ANGLE_DEG)
    {
        return Err(SimError::Config(format!(
            "geometric sigma {}: must be >= 0",
            cfg.geometric_sigma_deg
        )));
    }
    let (truth, geometric_errors) = truth_model(declared, cfg)?;
    let tilt = truth.has_tilt();
    let cal_plan: Vec<PlannedPose> = if ArmGeometry::of(declared).is_ok() {
        iso_calibration_sequence(declared, &Cube::thesis_frontal())?
    } else {
        let mut r = rng(cfg.seed, 4);
        random_poses(declared, ISO_POSE_COUNT, &[], &mut r)?
            .into_iter()
            .enumerate()
            .map(|(k, mut p)| {
                p.id = format!("C{}", k + 1);
                p
            })
            .collect()
    };
    let val_plan = random_poses(declared, cfg.n_val, &cal_plan, &mut rng(cfg.seed, 2))?;
    let noise =
        Normal::new(0.0, cfg.noise_mm).map_err(|e| SimError::Config(format!("--noise-mm: {e}")))?;
    let mut noise_rng = rng(cfg.seed, 3);
    let mut measure =
        |plan: &[PlannedPose], first_index: usize| -> Result<Vec<SimPose>, SimError> {
            // each file is its own visit order: its first pose has no history (FORMATS.md)
            let written: Vec<Vec<f64>> = plan.iter().map(|p| as_written(&p.q_deg)).collect();
            let approach = approach_directions(&written, None);
            plan.iter()
                .enumerate()
                .map(|(k, p)| {
                    let t_s = (first_index + k) as f64 * cfg.pose_interval_s;
                    let q = written[k].clone();
                    // the truth carries the joint map and the time terms
                    let q_true = truth.effective_joints_at(&q, t_s, &approach[k])?;
                    // the truth as it is at t (changes within the session)
                    let chain_mm = truth
                        .at_time(t_s)
                        .position_mm(&q_true, if tilt { Tilt::Static } else { Tilt::Off })?;
                    let time = truth.time_terms();
                    let truth_mm = time.grown_mm(&chain_mm, t_s);
                    let n = Vector3::new(
                        noise.sample(&mut noise_rng),
                        noise.sample(&mut noise_rng),
                        noise.sample(&mut noise_rng),
                    );
                    let measured_mm = truth_mm + time.drift_mm(t_s) + n;
                    Ok(SimPose {
                        id: p.id.clone(),
                        q_deg: q,
                        truth_mm,
                        measured_mm,
                        t_s,
                    })
                })
                .collect()
        };
    let cal = measure(&cal_plan, 0)?;
    let val = measure(&val_plan, cal_plan.len())?;
    Ok(SimOutput {
        declared: declared.clone(),
        truth,
        geometric_errors,
        tilt,
        cal,
        val,
    })
}

/// A simulation's poses as the diagnosis reads them.
impl crate::calib::MeasuredSet {
    /// The measured poses of a simulation (`rigctl simulate`), with their times, in the order
    /// the robot visited them.
    pub fn from_sim_poses(poses: &[SimPose]) -> Self {
        Self {
            poses: crate::calib::measured::PosePoints {
                q_deg: poses.iter().map(|p| p.q_deg.clone()).collect(),
                xyz_mm: poses.iter().map(|p| p.measured_mm).collect(),
            },
            t_s: Some(poses.iter().map(|p| p.t_s).collect()),
            ..Self::default()
        }
    }
}
