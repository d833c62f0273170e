//! A plan checked on a simulated truth: calibrate on the planned (or random) poses "measured"
//! on a truth model with noise, and compare the held-out error with the noise floor.

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::candidates::{draw_candidates, CandidatePose};
use super::{plan, PlanConfig, PlanError};
use crate::calib::identifiability::DEFAULT_RTOL;
use crate::calib::lm::LmConfig;
use crate::calib::position_fit::fit_parameters;
use crate::calib::{default_selection, position_errors, MeasuredSet, Stats};
use crate::model::{Model, Tilt};

/// Held-out result of one calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeldOut {
    /// Mean held-out error of the calibrated model, mm.
    pub mean_mm: f64,
    /// Mean held-out error of the truth model itself (the noise floor), mm.
    pub floor_mm: f64,
}

/// The measured set of `q` on `truth` (declared static tilting when it has tilting data) with
/// Gaussian noise `noise_mm` per coordinate.
pub fn measure(
    truth: &Model,
    q: &[Vec<f64>],
    noise_mm: f64,
    rng: &mut ChaCha8Rng,
) -> Result<MeasuredSet, PlanError> {
    let tilt = if truth.has_tilt() {
        Tilt::Static
    } else {
        Tilt::Off
    };
    let normal = Normal::new(0.0, noise_mm)
        .map_err(|e| PlanError::Config(format!("noise {noise_mm}: {e}")))?;
    let mut xyz = Vec::with_capacity(q.len());
    for qk in q {
        let p = truth.position_mm(qk, tilt)?;
        xyz.push(p + Vector3::from_fn(|_, _| normal.sample(rng)));
    }
    Ok(MeasuredSet::from_points(q.to_vec(), xyz))
}

/// Calibrates `declared` ([`default_selection`], declared tilting) on `cal` and evaluates on
/// `val`, both measured on the same truth.
pub fn held_out(
    declared: &Model,
    truth: &Model,
    cal: &MeasuredSet,
    val: &MeasuredSet,
) -> Result<HeldOut, PlanError> {
    let tilt = declared.has_tilt();
    let sel = default_selection(declared, false);
    let fit = fit_parameters(
        declared,
        &cal.poses,
        &sel,
        tilt,
        &LmConfig::default(),
        DEFAULT_RTOL,
        None,
    )
    .map_err(|e| PlanError::Config(format!("calibration failed: {e}")))?;
    let mean = |m: &Model| -> Result<f64, PlanError> {
        Ok(Stats::from_errors(&position_errors(m, &val.poses, tilt)?).mean_mm)
    };
    Ok(HeldOut {
        mean_mm: mean(&fit.model)?,
        floor_mm: mean(truth)?,
    })
}

/// Planned and random held-out errors for `n` poses: the plan of `cfg` (with `n`), and `n`
/// random candidates of another draw; `val` held-out poses of a third draw.
pub fn planned_vs_random(
    declared: &Model,
    truth: &Model,
    cfg: &PlanConfig,
    n: usize,
    n_val: usize,
    seed: u64,
) -> Result<(HeldOut, HeldOut), PlanError> {
    let mut c = cfg.clone();
    c.n = n;
    c.seed = seed;
    let planned = plan(declared, &c, None)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_add(1_000_003));
    let random: Vec<CandidatePose> = draw_candidates(declared, n, &cfg.workspace, &mut rng)?;
    let val_q: Vec<Vec<f64>> = draw_candidates(declared, n_val, &cfg.workspace, &mut rng)?
        .into_iter()
        .map(|p| p.q_deg)
        .collect();
    let val = measure(truth, &val_q, cfg.noise_mm, &mut rng)?;
    let q_of = |ps: &[CandidatePose]| ps.iter().map(|p| p.q_deg.clone()).collect::<Vec<_>>();
    let cal_p = measure(truth, &q_of(&planned.poses), cfg.noise_mm, &mut rng)?;
    let cal_r = measure(truth, &q_of(&random), cfg.noise_mm, &mut rng)?;
    Ok((
        held_out(declared, truth, &cal_p, &val)?,
        held_out(declared, truth, &cal_r, &val)?,
    ))
}
