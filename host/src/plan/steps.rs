//! The steps of [`super::plan`] around the exchange: the options it refuses, the candidate
//! set, the rows needed, the random-design baseline and criterion A's weights from it, the
//! refinement sweeps, and the best possible design's report against the planned poses.

use nalgebra::DMatrix;
use rand_chacha::ChaCha8Rng;

use super::candidates::{self, draw_candidates, structured_candidates, CandidatePose};
use super::continuous;
use super::criteria;
use super::metrics::{self, DesignStats};
use super::optimum;
use super::setup::Setup;
use super::{default_refine_sweeps, PlanConfig, PlanError, MAX_CANDIDATES};
use crate::model::Model;

/// The options `plan` refuses before any work: the noise, the pose count, the candidate and
/// baseline draw counts.
pub(super) fn check_config(cfg: &PlanConfig) -> Result<(), PlanError> {
    if !(cfg.noise_mm > 0.0 && cfg.noise_mm.is_finite()) {
        return Err(PlanError::Config(format!(
            "--noise-mm {}: must be a positive number",
            cfg.noise_mm
        )));
    }
    if cfg.n == 0 {
        return Err(PlanError::Config("--n must be at least 1".into()));
    }
    if cfg.candidates > MAX_CANDIDATES {
        return Err(PlanError::Config(format!(
            "--candidates {}: at most {MAX_CANDIDATES}",
            cfg.candidates
        )));
    }
    // the poses are chosen among the candidates: never more than they allow
    if cfg.pool_q.is_none() && cfg.n > cfg.candidates {
        return Err(PlanError::TooFewCandidates {
            n: cfg.n,
            candidates: cfg.candidates,
        });
    }
    if cfg.random_draws > MAX_CANDIDATES {
        return Err(PlanError::Config(format!(
            "--random-draws {}: at most {MAX_CANDIDATES}",
            cfg.random_draws
        )));
    }
    Ok(())
}

/// The candidates of a plan.
pub(super) struct CandidateSet {
    /// The uniform (drawn or `--candidates-from`) candidates, then the structured extremes.
    pub(super) cands: Vec<CandidatePose>,
    /// With `--candidates-from`: each candidate's index among that file's poses.
    pub(super) pool_index: Option<Vec<usize>>,
    /// How many come before the structured extremes.
    pub(super) n_uniform: usize,
}

/// The candidates: the `--candidates-from` poses that pass (with their index in that file),
/// or `cfg.candidates` drawn, followed by the structured extremes; and how many come before
/// the structured ones.
pub(super) fn candidate_set(
    model: &Model,
    cfg: &PlanConfig,
    rng: &mut ChaCha8Rng,
) -> Result<CandidateSet, PlanError> {
    let (mut cands, pool_index) = match &cfg.pool_q {
        Some(pool) => {
            let (c, index) = candidates::pool_candidates(model, pool, &cfg.workspace)?;
            if c.len() < cfg.n {
                return Err(PlanError::TooFewCandidates {
                    n: cfg.n,
                    candidates: c.len(),
                });
            }
            (c, Some(index))
        }
        None => (
            draw_candidates(model, cfg.candidates.max(cfg.n), &cfg.workspace, rng)?,
            None,
        ),
    };
    let n_uniform = cands.len();
    if pool_index.is_none() && cfg.structured.unwrap_or(true) {
        cands.extend(structured_candidates(model, &cfg.workspace)?);
    }
    Ok(CandidateSet {
        cands,
        pool_index,
        n_uniform,
    })
}

/// Enough rows (3 per pose, the prior poses' included) for `params` parameters.
pub(super) fn check_rows(n: usize, prior_poses: usize, params: usize) -> Result<(), PlanError> {
    let rows = 3 * (n + prior_poses);
    if rows < params {
        return Err(PlanError::TooFewPoses {
            n,
            rows,
            params,
            min: params.div_ceil(3).saturating_sub(prior_poses).max(1),
        });
    }
    Ok(())
}

/// The random-design baseline of `cfg.n` poses drawn from the candidates of `b_uniform` (its
/// summary and every draw's sigmas), and criterion A's weights from it.
pub(super) fn baseline(
    b_uniform: &DMatrix<f64>,
    setup: &Setup,
    cfg: &PlanConfig,
    rng: &mut ChaCha8Rng,
) -> (DesignStats, Vec<Vec<f64>>, Vec<f64>) {
    let (random, random_draws) = metrics::random_baseline_draws(
        b_uniform,
        criteria::POSE_ROWS,
        &setup.scale,
        &setup.prior_rows,
        cfg.n,
        cfg.random_draws,
        cfg.noise_mm,
        rng,
    );
    let weights = baseline_weights(&random.sigma, &setup.scale, cfg.noise_mm);
    (random, random_draws, weights)
}

/// Criterion A's weight of each parameter: 1 / its random-design variance (scaled), 1 where
/// that is not a positive number.
pub(super) fn baseline_weights(random_sigma: &[f64], scale: &[f64], noise_mm: f64) -> Vec<f64> {
    random_sigma
        .iter()
        .zip(scale)
        .map(|(s, k)| {
            let w = 1.0 / (s * k / noise_mm).powi(2);
            if w.is_finite() && w > 0.0 {
                w
            } else {
                1.0
            }
        })
        .collect()
}

/// The refinement sweeps: none for `--candidates-from` poses (they are kept as measured), else
/// `--refine-sweeps` or the default.
pub(super) fn refine_sweeps(cfg: &PlanConfig, pooled: bool, from_diagnose: bool) -> usize {
    if pooled {
        0
    } else {
        cfg.refine_sweeps
            .unwrap_or_else(|| default_refine_sweeps(from_diagnose))
    }
}

/// The best possible design `b` against the planned poses (`chosen` rows of `blocks`, the
/// scaled Jacobian blocks).
pub(super) fn optimum_report(
    b: continuous::BestPossible,
    blocks: &DMatrix<f64>,
    chosen: &[usize],
    scale: &[f64],
    cfg: &PlanConfig,
    random_sigma: &[f64],
) -> optimum::OptimumReport {
    let p = blocks.ncols();
    let m_plan = criteria::information(blocks, criteria::POSE_ROWS, &DMatrix::zeros(p, p), chosen);
    optimum::OptimumReport::new(
        b.optimum,
        &b.weight,
        &m_plan,
        scale,
        cfg.noise_mm,
        random_sigma,
    )
    .with_extension(b.extension)
}
