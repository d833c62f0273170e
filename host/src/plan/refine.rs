//! Continuous refinement of a design: after the exchange on the finite candidate set, each
//! chosen pose's joint values are moved by a deterministic coordinate (pattern) search on the
//! design criterion, keeping every constraint (joint limits less the margin, the workspace's
//! table, box and line of sight). The design is then no longer limited to the candidates.
//!
//! One pose at a time: with `M_rest` the information of all the other poses (and of the poses
//! already measured), the criterion of `M_rest + B(q)^T B(q)` is evaluated directly (a p x p
//! Cholesky) for trial moves of one joint by `±step`, `B(q)` the scaled identification
//! Jacobian block of the configuration `q` ([`Setup::block_at`], analytic). Steps are fractions
//! of each joint's usable range ([`STEP_FRACTIONS`], coarse to fine, so prismatic joints work
//! alike); a move is kept when it raises the criterion; a joint can end exactly on its usable
//! limit. Sweeps over all poses repeat until none moves (at most `sweeps`).

use nalgebra::DMatrix;

#[cfg(test)]
use super::candidates::usable_range;
use super::candidates::{CandidatePose, Workspace};
use super::criteria::{value_weighted, Criterion};
use super::setup::Setup;
use super::PlanError;
use crate::model::Model;

/// Trial steps as fractions of each joint's usable range, coarse to fine (about 20 deg down to
/// 0.6 deg on a 300-deg joint).
pub const STEP_FRACTIONS: [f64; 8] = [
    1.0 / 4.0,
    1.0 / 8.0,
    1.0 / 16.0,
    1.0 / 32.0,
    1.0 / 64.0,
    1.0 / 128.0,
    1.0 / 256.0,
    1.0 / 512.0,
];

/// Most accepted moves per pose and step size (a bound on the walk, never reached in practice).
const MAX_MOVES_PER_STEP: usize = 12;

/// Relative criterion gain below which a move is not taken.
const MIN_REL_GAIN: f64 = 1e-10;

/// What the refinement works with.
#[derive(Debug, Clone, Copy)]
pub struct Refiner<'a> {
    /// The model the constraints are checked on (declared, rigid, like the candidates).
    pub model: &'a Model,
    /// The Jacobians, columns of interest and column scale.
    pub setup: &'a Setup,
    /// Where a pose may be.
    pub workspace: &'a Workspace,
    /// The criterion.
    pub kind: Criterion,
    /// A's column weights (one per column, or empty for all 1).
    pub weights: &'a [f64],
    /// I's prediction weight (p x p; unused by the others).
    pub prediction: &'a DMatrix<f64>,
}

/// A refined design.
#[derive(Debug, Clone)]
pub struct Refined {
    /// The poses (joint values, deg), in the order given.
    pub poses: Vec<CandidatePose>,
    /// Their scaled Jacobian blocks, 3 rows per pose.
    pub blocks: DMatrix<f64>,
    /// Criterion before and after (larger is better).
    pub criterion_before: f64,
    /// Criterion after the refinement.
    pub criterion_after: f64,
    /// Accepted joint moves.
    pub moves: usize,
    /// Sweeps over the poses run.
    pub sweeps: usize,
}

impl Refiner<'_> {
    fn value(&self, m: &DMatrix<f64>) -> f64 {
        value_weighted(
            self.kind,
            m,
            &self.setup.interest,
            self.prediction,
            self.weights,
        )
    }

    /// The block of `q` when the pose satisfies the workspace constraints and, with
    /// `--from-diagnose`, the linearity test of the effects to separate ([`Setup::admits`];
    /// `None` otherwise).
    fn feasible_block(&self, q: &[f64]) -> Result<Option<DMatrix<f64>>, PlanError> {
        let admitted = CandidatePose::admitted(self.model, q.to_vec(), self.workspace)?;
        if admitted.is_none() || !self.setup.admits(q)? {
            return Ok(None);
        }
        Ok(Some(self.setup.block_at(q)?))
    }

    /// Refines the design `start` (poses within the constraints) on top of the information
    /// `prior`, with at most `sweeps` sweeps (0: the design as given).
    pub fn refine(
        &self,
        prior: &DMatrix<f64>,
        start: &[CandidatePose],
        sweeps: usize,
    ) -> Result<Refined, PlanError> {
        let p = self.setup.b.ncols();
        let mut poses = start.to_vec();
        let mut blocks = DMatrix::zeros(3 * poses.len(), p);
        let mut m = prior.clone();
        for (k, pose) in poses.iter().enumerate() {
            let bk = self.setup.block_at(&pose.q_deg)?;
            m += bk.transpose() * &bk;
            blocks.view_mut((3 * k, 0), (3, p)).copy_from(&bk);
        }
        let criterion_before = self.value(&m);
        let ranges: Vec<(f64, f64)> = self
            .model
            .joint_limits()
            .iter()
            .map(|l| self.workspace.usable_range(l))
            .collect();
        let (mut moves, mut run) = (0, 0);
        for _ in 0..sweeps {
            run += 1;
            let mut moved = false;
            for (k, pose) in poses.iter_mut().enumerate() {
                let bk = blocks.rows(3 * k, 3).into_owned();
                let rest = &m - bk.transpose() * &bk;
                let (q, blk, n) = self.search(&rest, &pose.q_deg, bk, &ranges)?;
                if n == 0 {
                    continue;
                }
                moves += n;
                moved = true;
                m = &rest + blk.transpose() * &blk;
                blocks.view_mut((3 * k, 0), (3, p)).copy_from(&blk);
                *pose = CandidatePose::at(self.model, q)?;
            }
            if !moved {
                break;
            }
        }
        Ok(Refined {
            criterion_after: self.value(&m),
            poses,
            blocks,
            criterion_before,
            moves,
            sweeps: run,
        })
    }

    /// The coordinate search of one pose given the information `rest` of all the others: the
    /// new joints, block and the number of accepted moves.
    fn search(
        &self,
        rest: &DMatrix<f64>,
        q0: &[f64],
        b0: DMatrix<f64>,
        ranges: &[(f64, f64)],
    ) -> Result<(Vec<f64>, DMatrix<f64>, usize), PlanError> {
        self.climb(q0, b0, ranges, |bt| {
            self.value(&(rest + bt.transpose() * bt))
        })
    }

    /// The coordinate search of one configuration `q0` (block `b0`) on `objective` of the
    /// scaled block (larger is better), within the joint `ranges` and the workspace: the new
    /// joints, block and the number of accepted moves.
    pub fn climb(
        &self,
        q0: &[f64],
        b0: DMatrix<f64>,
        ranges: &[(f64, f64)],
        objective: impl Fn(&DMatrix<f64>) -> f64,
    ) -> Result<(Vec<f64>, DMatrix<f64>, usize), PlanError> {
        let (mut q, mut blk) = (q0.to_vec(), b0);
        let mut best = objective(&blk);
        let mut accepted = 0;
        for frac in STEP_FRACTIONS {
            for _ in 0..MAX_MOVES_PER_STEP {
                let mut improved = false;
                for (j, &(lo, hi)) in ranges.iter().enumerate().take(q.len()) {
                    let step = frac * (hi - lo);
                    if step <= 0.0 {
                        continue;
                    }
                    for dir in [1.0, -1.0] {
                        let v = (q[j] + dir * step).clamp(lo, hi);
                        if (v - q[j]).abs() < 1e-12 * step.max(1.0) {
                            continue;
                        }
                        let mut trial = q.clone();
                        trial[j] = v;
                        let Some(bt) = self.feasible_block(&trial)? else {
                            continue;
                        };
                        let val = objective(&bt);
                        if val > best + MIN_REL_GAIN * best.abs().max(1e-300) {
                            (best, q, blk, improved) = (val, trial, bt, true);
                            accepted += 1;
                            break;
                        }
                    }
                }
                if !improved {
                    break;
                }
            }
        }
        Ok((q, blk, accepted))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::criteria::{prediction_weight, POSE_ROWS};
    use crate::plan::test_support::{katana_pool, KatanaPool};

    /// The analytic block of a configuration equals the candidate set's rows; the refinement
    /// raises the criterion, keeps every constraint and is deterministic.
    #[test]
    fn refinement_improves_within_the_constraints() {
        let KatanaPool {
            model,
            ws,
            cands,
            setup,
        } = katana_pool(300, 4);
        for k in [0usize, 17, 299] {
            let blk = setup.block_at(&cands[k].q_deg).unwrap();
            let diff = (blk - setup.b.rows(3 * k, 3)).abs().max();
            assert!(diff < 1e-9, "candidate {k}: {diff}");
        }
        let p = setup.b.ncols();
        let prior = DMatrix::zeros(p, p);
        let q = prediction_weight(&setup.b, POSE_ROWS);
        for kind in [Criterion::A, Criterion::D, Criterion::I] {
            let r = Refiner {
                model: &model,
                setup: &setup,
                workspace: &ws,
                kind,
                weights: &[],
                prediction: &q,
            };
            let start = &cands[..12];
            let a = r.refine(&prior, start, 2).unwrap();
            assert!(a.moves > 0);
            assert!(a.criterion_after > a.criterion_before, "{kind:?}");
            let b = r.refine(&prior, start, 2).unwrap();
            assert_eq!(a.poses, b.poses, "deterministic");
            let limits = model.joint_limits();
            for pose in &a.poses {
                assert!(pose.nominal_mm.z >= 40.0 - 1e-9, "table");
                for (v, l) in pose.q_deg.iter().zip(&limits) {
                    let (lo, hi) = usable_range(l);
                    assert!(*v >= lo - 1e-9 && *v <= hi + 1e-9, "{v} not in {lo}..{hi}");
                }
            }
            let none = r.refine(&prior, start, 0).unwrap();
            assert_eq!(none.moves, 0);
            assert_eq!(none.criterion_after, none.criterion_before);
        }
    }
}
