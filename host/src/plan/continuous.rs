//! The best design over the reachable configurations, not only the candidate pool: the
//! approximate optimum on the pool is extended by the configurations that maximise its
//! sensitivity function (the classical route for a continuous design region: Fedorov's and
//! Wynn's algorithms, the equivalence theorem of Kiefer and Wolfowitz).
//!
//! At the optimum on a pool, every configuration's sensitivity `d(q)` (the directional
//! derivative of the criterion towards it, [`Optimum::sensitivity`]) is at most the threshold
//! ([`Optimum::threshold`]). A reachable configuration above it improves the design: each round
//! climbs `d(q)` from the pool's most sensitive candidates (the coordinate search of the
//! refinement, within every constraint), adds the configurations found above the threshold to
//! the pool, and solves the pool again from the previous weights. It stops when no climb
//! finds one, i.e. when the equivalence condition holds at the local maxima of `d` reached from
//! those starts, or after [`MAX_ROUNDS`].

use nalgebra::{DMatrix, DVector};

#[cfg(test)]
use super::candidates::usable_range;
use super::candidates::CandidatePose;
use super::criteria::Criterion;
use super::optimum::{approximate_optimum, approximate_optimum_from, Extension, Optimum};
use super::refine::Refiner;
use super::setup::Setup;
use super::{PlanConfig, PlanError};
use crate::model::Model;

/// Rounds of climbing and re-solving at most.
pub const MAX_ROUNDS: usize = 4;
/// Climbs per round: from this many of the most sensitive candidates.
pub const STARTS_PER_ROUND: usize = 12;
/// A configuration is added when its sensitivity exceeds the threshold by this fraction.
const MIN_EXCESS: f64 = 1e-3;
/// Configurations closer than this in every joint (deg) to one added before are not added.
const SAME_POSE_DEG: f64 = 0.5;
/// Share of the weight given to the configurations added in a round, at the re-solve's start.
const NEW_SHARE: f64 = 0.1;

/// The pool extended towards the continuous optimum.
#[derive(Debug, Clone)]
pub struct Extended {
    /// The configurations added.
    pub poses: Vec<CandidatePose>,
    /// Scaled blocks of the pool given, then of the added configurations (3 rows each).
    pub pool: DMatrix<f64>,
    /// The optimum on the pool plus the added configurations.
    pub optimum: Optimum,
    /// How many were added in how many rounds, and the last round's largest sensitivity.
    pub extension: Extension,
}

/// Extends the pool `b` (scaled blocks of `cands`) from its optimum `first` (criterion weight
/// `weight`, as given to [`super::optimum::approximate_optimum`]).
pub fn extend(
    refiner: &Refiner<'_>,
    cands: &[CandidatePose],
    b: &DMatrix<f64>,
    weight: &DMatrix<f64>,
    first: Optimum,
) -> Result<Extended, PlanError> {
    let p = b.ncols();
    let ranges: Vec<(f64, f64)> = refiner
        .model
        .joint_limits()
        .iter()
        .map(|l| refiner.workspace.usable_range(l))
        .collect();
    let mut pool_q: Vec<Vec<f64>> = cands.iter().map(|c| c.q_deg.clone()).collect();
    let mut pool_b = b.clone();
    let mut added: Vec<CandidatePose> = Vec::new();
    let mut optimum = first;
    let (mut rounds, mut last_excess) = (0, 0.0);
    for _ in 0..MAX_ROUNDS {
        rounds += 1;
        let threshold = optimum.threshold();
        let n_pool = pool_b.nrows() / 3;
        let mut order: Vec<(usize, f64)> = (0..n_pool)
            .map(|c| (c, optimum.sensitivity(&pool_b.rows(3 * c, 3).into_owned())))
            .collect();
        order.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        let mut found: Vec<(Vec<f64>, DMatrix<f64>)> = Vec::new();
        last_excess = 0.0;
        for &(c, _) in order.iter().take(STARTS_PER_ROUND) {
            let b0 = pool_b.rows(3 * c, 3).into_owned();
            let (q, blk, _) =
                refiner.climb(&pool_q[c], b0, &ranges, |bt| optimum.sensitivity(bt))?;
            let s = optimum.sensitivity(&blk) / threshold;
            last_excess = f64::max(last_excess, s);
            let near = |other: &Vec<f64>| {
                other
                    .iter()
                    .zip(&q)
                    .all(|(a, b)| (a - b).abs() < SAME_POSE_DEG)
            };
            let seen = found.iter().any(|(o, _)| near(o)) || added.iter().any(|a| near(&a.q_deg));
            if s > 1.0 + MIN_EXCESS && !seen {
                found.push((q, blk));
            }
        }
        if found.is_empty() {
            break;
        }
        let mut start: Vec<f64> = optimum
            .design
            .iter()
            .map(|x| x * (1.0 - NEW_SHARE))
            .collect();
        let mut grown = DMatrix::zeros(pool_b.nrows() + 3 * found.len(), p);
        grown.rows_mut(0, pool_b.nrows()).copy_from(&pool_b);
        for (k, (q, blk)) in found.into_iter().enumerate() {
            grown.rows_mut(pool_b.nrows() + 3 * k, 3).copy_from(&blk);
            added.push(CandidatePose::at(refiner.model, q.clone())?);
            pool_q.push(q);
            start.push(0.0);
        }
        let k_new = (grown.nrows() - pool_b.nrows()) / 3;
        for x in start.iter_mut().skip(n_pool) {
            *x = NEW_SHARE / k_new as f64;
        }
        pool_b = grown;
        match approximate_optimum_from(&pool_b, optimum.n, optimum.kind, weight, &start) {
            Some(o) => optimum = o,
            None => return Err(PlanError::Numerical("approximate optimum lost rank")),
        }
    }
    Ok(Extended {
        extension: Extension {
            added: added.len(),
            rounds,
            last_excess,
        },
        pool: pool_b,
        poses: added,
        optimum,
    })
}

/// The best possible of [`best_possible`].
pub(crate) struct BestPossible {
    pub optimum: Optimum,
    /// The criterion weight it was computed with.
    pub weight: DMatrix<f64>,
    /// What the climbs added.
    pub extension: Extension,
}

/// The best possible for the declared identification (no poses measured before, no columns
/// of interest): the approximate optimum on the candidates, then extended over the
/// reachable configurations ([`extend`]; not with [`PlanConfig::pool_q`]), whose
/// configurations join the pool (`cands` and `setup.b`).
pub(crate) fn best_possible(
    model: &Model,
    cfg: &PlanConfig,
    setup: &mut Setup,
    cands: &mut Vec<CandidatePose>,
    weights: &[f64],
    prediction: &DMatrix<f64>,
) -> Result<Option<BestPossible>, PlanError> {
    if setup.prior_rows.nrows() != 0 || !setup.interest.is_empty() {
        return Ok(None);
    }
    let w = match cfg.criterion {
        Criterion::I => prediction.clone(),
        _ => DMatrix::from_diagonal(&DVector::from_column_slice(weights)),
    };
    let Some(first) = approximate_optimum(&setup.b, cfg.n, cfg.criterion, &w) else {
        return Ok(None);
    };
    if cfg.pool_q.is_some() {
        return Ok(Some(BestPossible {
            optimum: first,
            weight: w,
            extension: Extension::default(),
        }));
    }
    let refiner = Refiner {
        model,
        setup,
        workspace: &cfg.workspace,
        kind: cfg.criterion,
        weights,
        prediction,
    };
    let ext = extend(&refiner, cands, &setup.b, &w, first)?;
    setup.b = ext.pool;
    cands.extend(ext.poses);
    Ok(Some(BestPossible {
        optimum: ext.optimum,
        weight: w,
        extension: ext.extension,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::criteria::{prediction_weight, POSE_ROWS};
    use crate::plan::test_support::{katana_pool, KatanaPool};

    /// On a small Katana pool: the configurations added lie within the constraints and each
    /// improved the design it was found for; the extended optimum is at least as good as the
    /// pool's, and the certificate still brackets it.
    #[test]
    fn climbs_add_reachable_configurations_that_improve_the_optimum() {
        let KatanaPool {
            model,
            ws,
            cands,
            setup,
        } = katana_pool(300, 2);
        let p = setup.b.ncols();
        let q = prediction_weight(&setup.b, POSE_ROWS);
        let w = DMatrix::identity(p, p);
        for kind in [Criterion::A, Criterion::D] {
            let first = approximate_optimum(&setup.b, 12, kind, &w).unwrap();
            let refiner = Refiner {
                model: &model,
                setup: &setup,
                workspace: &ws,
                kind,
                weights: &[],
                prediction: &q,
            };
            let ext = extend(&refiner, &cands, &setup.b, &w, first.clone()).unwrap();
            assert!(
                !ext.poses.is_empty(),
                "{kind:?}: 300 random candidates are not the optimum"
            );
            let n0 = setup.b.nrows();
            assert_eq!(ext.pool.nrows(), n0 + 3 * ext.poses.len());
            assert_eq!(ext.extension.added, ext.poses.len());
            let sensitive = (0..ext.poses.len())
                .filter(|&k| {
                    first.sensitivity(&ext.pool.rows(n0 + 3 * k, 3).into_owned())
                        > first.threshold()
                })
                .count();
            assert!(
                sensitive > 0,
                "{kind:?}: the first round's additions improve the first optimum"
            );
            for pose in &ext.poses {
                assert!(pose.nominal_mm.z >= 40.0 - 1e-9, "table");
                for (v, l) in pose.q_deg.iter().zip(model.joint_limits()) {
                    let (lo, hi) = usable_range(&l);
                    assert!(*v >= lo - 1e-9 && *v <= hi + 1e-9);
                }
            }
            let o = &ext.optimum;
            match kind {
                Criterion::D => {
                    assert!(o.value >= first.value - 1e-9 && o.bound >= o.value);
                }
                _ => {
                    assert!(o.value <= first.value + 1e-9 && o.bound <= o.value);
                }
            }
        }
    }
}
