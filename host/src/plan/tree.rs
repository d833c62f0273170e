//! `rigctl plan` on a tree model: the poses of the whole tree (every joint, a point on every
//! tip) that identify the tree's calibration best.
//!
//! The chain plan's parts on the tree's identification: random configurations within the
//! joint limits (less the margin) that are safe for **every** tip's chain
//! ([`Workspace::violation`] on the chain of the tip's path: the tip point and every joint
//! frame origin above the table and out of the keep-out boxes) and keep the branches apart
//! (every pair of points of two different branches - the frame origins beyond the shared path
//! and the tip points - at least [`TreePlanConfig::branch_clearance_mm`] apart); the unknowns
//! of `calibrate` on the tree ([`tree_selection`]: the geometric default, and the joint and
//! lateral compliances when the tree has link masses), restricted to what the whole candidate
//! set identifies and scaled to unit RMS ([`Scaled`]); the exchange of [`super::design`] on
//! blocks of 3 rows per tip; the random baseline of as many poses drawn from the same
//! candidates ([`random_baseline_draws`]).
//!
//! With the robot's URDF ([`TreePlanConfig::collider`]) every candidate's links are kept apart
//! (the URDF's or the SRDF's pairs), above the table and out of the keep-out boxes. A tree plan
//! is not ordered nor refined: the moves between poses are not checked
//! ([`TreePlan::moves_verified`] is false), nor the links without collision geometry
//! ([`TreePlan::collisions_verified`]); the output says so.

use nalgebra::{DMatrix, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::candidates::{random_configuration, TRIES_PER_CANDIDATE};
use super::criteria::{prediction_weight, Criterion};
use super::design::{exchange, Problem};
use super::metrics::{design_stats, median_ratio, random_baseline, stack_rows, DesignStats};
use super::setup::Scaled;
use super::steps::baseline_weights;
use super::workspace::{SharedCollider, Workspace};
use super::{PlanError, MAX_CANDIDATES};
use crate::calib::measured::MeasuredSet;
use crate::calib::tree_calibrate::tree_selection;
use crate::calib::tree_fit::TreeUnknowns;
use crate::calib::CalibrateOptions;
use crate::model::{Model, Tilt, Tree};

use super::collision::{model_joint_origins_mm, Environment};

/// Default smallest distance between points of two branches (frame origins and tip points), mm.
pub const DEFAULT_BRANCH_CLEARANCE_MM: f64 = 100.0;

/// What a tree plan is asked for.
#[derive(Debug, Clone)]
pub struct TreePlanConfig {
    /// Poses to choose.
    pub n: usize,
    /// Seed of the candidates and of the random baseline.
    pub seed: u64,
    /// Random candidate configurations.
    pub candidates: usize,
    /// Random designs of the baseline.
    pub random_draws: usize,
    /// Measurement noise per coordinate (mm) of the expected sigmas.
    pub noise_mm: f64,
    pub criterion: Criterion,
    /// The base frame among the unknowns (as `calibrate --base`).
    pub base: bool,
    /// Table, keep-out boxes, limit margin, lowest tip height, box (the chain's constraints,
    /// applied to every tip's chain).
    pub workspace: Workspace,
    /// Smallest distance between points of two branches, mm.
    pub branch_clearance_mm: f64,
    /// The robot's collision geometry for the whole tree
    /// ([`super::collision::Collider::from_urdf_tree`]): every
    /// candidate's links kept apart, above the table and out of the keep-out boxes; `None`: the
    /// frame origins and tips only.
    pub collider: Option<SharedCollider>,
}

impl TreePlanConfig {
    /// `n` poses with the defaults (2000 candidates, 100 random draws, 0.01 mm, criterion A).
    pub fn new(n: usize) -> Self {
        Self {
            n,
            seed: 1,
            candidates: 2000,
            random_draws: 100,
            noise_mm: 0.01,
            criterion: Criterion::A,
            base: false,
            workspace: Workspace::default(),
            branch_clearance_mm: DEFAULT_BRANCH_CLEARANCE_MM,
            collider: None,
        }
    }
}

/// One planned pose: the joints of the whole tree and the nominal point of every tip.
#[derive(Debug, Clone, PartialEq)]
pub struct TreePlanPose {
    /// Joint readings in tree order, deg (mm for prismatic joints).
    pub q_deg: Vec<f64>,
    /// Nominal (declared, rigid) point of every tip in tree order, mm (frame R).
    pub tips_mm: Vec<Vector3<f64>>,
}

/// A tree plan.
#[derive(Debug, Clone)]
pub struct TreePlan {
    pub tree: String,
    /// Tip names in tree order.
    pub tips: Vec<String>,
    /// Joint names in tree order.
    pub joints: Vec<String>,
    pub poses: Vec<TreePlanPose>,
    /// The unknowns planned for (identifiable on the candidates).
    pub parameters: Vec<String>,
    /// Combinations no candidate set identifies (kept at their values by a calibration).
    pub unidentifiable: Vec<String>,
    /// Expected sigmas of the planned poses (parameter units).
    pub planned: DesignStats,
    /// Median sigmas of random designs of as many candidates.
    pub random: DesignStats,
    /// Median over the parameters of planned / random sigma.
    pub median_sigma_ratio: f64,
    /// Expected RMS prediction error per coordinate over the candidates (mm): planned, and the
    /// median over the random designs.
    pub prediction_rms_mm: (f64, f64),
    pub candidates: usize,
    /// Random configurations drawn to find them.
    pub tries: usize,
    /// Whether the moves between the poses were checked: never on a tree.
    pub moves_verified: bool,
    /// Whether the links were checked for collisions (with [`TreePlanConfig::collider`]; else
    /// the frame origins and tip points only).
    pub collisions_verified: bool,
}

/// Plans `cfg.n` poses for `tree` (module docs).
pub fn plan_tree(tree: &Tree, cfg: &TreePlanConfig) -> Result<TreePlan, PlanError> {
    check(tree, cfg)?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let safety = Safety::new(tree, cfg)?;
    let (cands, tries) = safety.draw(cfg.candidates, &mut rng)?;
    let compliance = tree.has_masses();
    let opts = CalibrateOptions {
        base: cfg.base,
        ..CalibrateOptions::default()
    };
    let names =
        tree_selection(tree, &opts, compliance).map_err(|e| PlanError::Config(e.to_string()))?;
    let q: Vec<Vec<f64>> = cands.iter().map(|c| c.q_deg.clone()).collect();
    let set = MeasuredSet::from_tip_points(
        q,
        cands
            .iter()
            .map(|c| c.tips_mm.iter().copied().map(Some).collect())
            .collect(),
    );
    let jac = TreeUnknowns::new(tree, names.clone())?.jacobian(&set)?;
    if !jac.iter().all(|v| v.is_finite()) {
        return Err(PlanError::Numerical(
            "tree Jacobian not finite at a candidate",
        ));
    }
    let scaled = Scaled::of(&jac, &names, cands.len());
    let rows = 3 * tree.tips.len();
    let p = scaled.kept.len();
    if cfg.n * rows < p {
        return Err(PlanError::TooFewPoses {
            n: cfg.n,
            rows: cfg.n * rows,
            params: p,
            min: p.div_ceil(rows).max(1),
        });
    }
    let no_prior = DMatrix::zeros(0, p);
    let random = random_baseline(
        &scaled.b,
        rows,
        &scaled.scale,
        &no_prior,
        cfg.n,
        cfg.random_draws,
        cfg.noise_mm,
        &mut rng,
    );
    let weights = baseline_weights(&random.sigma, &scaled.scale, cfg.noise_mm);
    let prediction = prediction_weight(&scaled.b, rows);
    let prior = DMatrix::zeros(p, p);
    let design = exchange(
        &Problem {
            b: &scaled.b,
            rows,
            prior: &prior,
            interest: &[],
            kind: cfg.criterion,
            weights: &weights,
            prediction: Some(&prediction),
            admissible: &[],
        },
        cfg.n,
        &[],
    )?;
    let planned_jac = stack_rows(&scaled.b, rows, &scaled.scale, &no_prior, &design.chosen);
    let planned = design_stats(&planned_jac, cfg.n, cfg.noise_mm);
    let prediction_rms = |design: &DMatrix<f64>| prediction_rms_mm(&prediction, rows, design);
    // the expected prediction error of random designs (fewer draws: a p x p inverse each)
    let random_rms: Vec<f64> = (0..cfg.random_draws.clamp(1, 25))
        .map(|_| {
            let pick = rand::seq::index::sample(&mut rng, cands.len(), cfg.n).into_vec();
            prediction_rms(&stack_rows(
                &scaled.b,
                rows,
                &vec![1.0; p],
                &no_prior,
                &pick,
            ))
        })
        .collect();
    let planned_rms = prediction_rms(&stack_rows(
        &scaled.b,
        rows,
        &vec![1.0; p],
        &no_prior,
        &design.chosen,
    ));
    Ok(TreePlan {
        tree: tree.name.clone(),
        tips: tree.tips.iter().map(|t| t.name.clone()).collect(),
        joints: tree.joint_names(),
        poses: design.chosen.iter().map(|&c| cands[c].clone()).collect(),
        parameters: scaled.kept.iter().map(|&k| names[k].clone()).collect(),
        unidentifiable: scaled.unidentifiable,
        median_sigma_ratio: median_ratio(&planned.sigma, &random.sigma),
        planned,
        random,
        prediction_rms_mm: (
            cfg.noise_mm * planned_rms,
            cfg.noise_mm * super::metrics::median(&random_rms),
        ),
        candidates: cands.len(),
        tries,
        moves_verified: false,
        collisions_verified: cfg.collider.is_some(),
    })
}

/// The root mean prediction variance per coordinate over the candidates of a design whose
/// scaled rows are `design` (unit noise): `sqrt(trace(Q M^-1) / rows)` with `q` = `Q` the mean
/// information of a candidate ([`prediction_weight`]) and `rows` a pose's rows. Infinite when
/// the design does not determine the parameters.
fn prediction_rms_mm(q: &DMatrix<f64>, rows: usize, design: &DMatrix<f64>) -> f64 {
    let m = design.transpose() * design;
    let Some(inv) = m.cholesky().map(|c| c.inverse()) else {
        return f64::INFINITY;
    };
    ((inv * q).trace() / rows as f64).max(0.0).sqrt()
}

fn check(tree: &Tree, cfg: &TreePlanConfig) -> Result<(), PlanError> {
    if cfg.n == 0 {
        return Err(PlanError::Config("--n: at least one pose".into()));
    }
    if cfg.candidates < cfg.n || cfg.candidates > MAX_CANDIDATES {
        return Err(PlanError::Config(format!(
            "--candidates {}: between --n ({}) and {MAX_CANDIDATES}",
            cfg.candidates, cfg.n
        )));
    }
    if !(cfg.noise_mm.is_finite() && cfg.noise_mm > 0.0) {
        return Err(PlanError::Config(format!(
            "--noise-mm {}: a positive number",
            cfg.noise_mm
        )));
    }
    if !(cfg.branch_clearance_mm.is_finite() && cfg.branch_clearance_mm >= 0.0) {
        return Err(PlanError::Config(format!(
            "--branch-clearance-mm {}: a non-negative number",
            cfg.branch_clearance_mm
        )));
    }
    if tree.tips.is_empty() {
        return Err(PlanError::Config(format!("tree {}: no [[tip]]", tree.name)));
    }
    Ok(())
}

/// The safety of a tree configuration: every tip's chain and the branches' distances.
struct Safety<'a> {
    tree: &'a Tree,
    ws: &'a Workspace,
    chains: Vec<Model>,
    paths: Vec<Vec<usize>>,
    clearance_mm: f64,
    collider: Option<&'a SharedCollider>,
}

impl<'a> Safety<'a> {
    fn new(tree: &'a Tree, cfg: &'a TreePlanConfig) -> Result<Self, PlanError> {
        Ok(Self {
            chains: tree.chains()?,
            paths: (0..tree.tips.len()).map(|t| tree.path(t)).collect(),
            tree,
            ws: &cfg.workspace,
            clearance_mm: cfg.branch_clearance_mm,
            collider: cfg.collider.as_ref(),
        })
    }

    /// `count` random safe configurations and the configurations drawn.
    fn draw(
        &self,
        count: usize,
        rng: &mut impl Rng,
    ) -> Result<(Vec<TreePlanPose>, usize), PlanError> {
        let limits = self.tree.joint_limits();
        let max_tries = TRIES_PER_CANDIDATE * count.max(1);
        let mut out = Vec::with_capacity(count);
        let mut tries = 0;
        while out.len() < count {
            if tries >= max_tries {
                return Err(PlanError::Candidates {
                    wanted: count,
                    found: out.len(),
                    tries,
                    loosen: "--table-z-mm / --keep-out / --branch-clearance-mm / \
                             --limit-margin-deg / --min-z-mm / --box",
                });
            }
            tries += 1;
            let q = random_configuration(&limits, self.ws, rng);
            out.extend(self.admitted(q)?);
        }
        Ok((out, tries))
    }

    /// The pose at `q` when it is safe.
    fn admitted(&self, q: Vec<f64>) -> Result<Option<TreePlanPose>, PlanError> {
        let mut tips_mm = Vec::with_capacity(self.chains.len());
        // per tip: the points beyond the path it shares with an earlier tip
        let mut branch_points: Vec<Vec<Vector3<f64>>> = Vec::with_capacity(self.chains.len());
        for (chain, path) in self.chains.iter().zip(&self.paths) {
            let qc: Vec<f64> = path.iter().map(|&j| q[j]).collect();
            let fk = chain.fk(&qc, Tilt::Off)?;
            let axis = fk.rotation.column(2).into_owned();
            if self
                .ws
                .violation(chain, &qc, &fk.position_mm, &axis)?
                .is_some()
            {
                return Ok(None);
            }
            let origins = model_joint_origins_mm(chain, &qc)?;
            let mut points: Vec<Vector3<f64>> = origins
                .iter()
                .zip(path)
                .filter(|(_, j)| !self.shared(**j))
                .map(|(o, _)| *o)
                .collect();
            points.push(fk.position_mm);
            branch_points.push(points);
            tips_mm.push(fk.position_mm);
        }
        for (a, pa) in branch_points.iter().enumerate() {
            for pb in &branch_points[a + 1..] {
                let close = pa
                    .iter()
                    .any(|x| pb.iter().any(|y| (x - y).norm() < self.clearance_mm));
                if close {
                    return Ok(None);
                }
            }
        }
        if let Some(c) = self.collider {
            let env = Environment {
                table_z_mm: self.ws.table_z_mm,
                keep_out_mm: &self.ws.keep_out_mm,
                slack_mm: 0.0,
            };
            if c.0.collision(&q, &env).is_some() {
                return Ok(None);
            }
        }
        Ok(Some(TreePlanPose { q_deg: q, tips_mm }))
    }

    /// Whether tree joint `j` lies on the path of more than one tip (a shared torso joint).
    fn shared(&self, j: usize) -> bool {
        self.paths.iter().filter(|p| p.contains(&j)).count() > 1
    }
}
