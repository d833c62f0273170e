//! `rigctl plan`: choose the calibration poses that identify the model best.
//!
//! | module | holds |
//! |---|---|
//! | [`workspace`] | the safety of a configuration: joint-limit margin, table plane, keep-out boxes, link origins, collisions |
//! | [`collision`] | the URDF's collision geometry (parry3d): self-collision of non-adjacent links, table, keep-out boxes |
//! | [`meshes`] | collision meshes: `package://` and relative paths, STL vertices |
//! | [`order`] | the poses in a short joint-travel order, every segment checked at a joint step |
//! | [`trajectory`] | the ordered poses as a ROS JointTrajectory YAML |
//! | [`candidates`] | random reachable configurations within the limits and workspace constraints, and the structured extremes (limits and mid-range) |
//! | [`setup`] | the identification Jacobian of every candidate (declared tilting on), identifiability, column scaling |
//! | `steps` | the steps of [`plan`] around the exchange: options refused, the candidate set, the random baseline and criterion A's weights, refinement sweeps, the best possible design's report |
//! | [`criteria`] | D/Ds, A, G (geometric-mean sigma) and I (prediction variance) criteria and their rank-3 gains |
//! | [`design`] | greedy start + exchange with rank-3 updates |
//! | [`refine`] | continuous refinement of the chosen poses' joint values within the constraints |
//! | [`continuous`] | the optimum extended over the reachable configurations: climbs of its sensitivity function add configurations to the pool |
//! | [`optimum`] | the approximate optimum on the candidates (multiplicative algorithm) and its equivalence-theorem bound: how far a plan is from the best possible |
//! | [`metrics`] | expected sigmas, condition number, O1; the random baseline |
//! | [`aliased`] | `--from-diagnose`: the aliased pairs of a diagnose JSON as unknowns to separate |
//! | [`robust`] | `--from-diagnose`: the plausible size of each effect to separate and the linearity test that keeps the poses where it is linear in its value |
//! | [`output`] | `plan.csv` and `plan.json` |
//! | [`sheets`] | `--sheets`: candidate pencil sheets and paths, what each sheet and pair identifies, the blind parameters |
//! | [`sheets_output`] | the `sheets` object of `plan.json` and the sheet table |
//! | [`evaluate`] | a plan checked on a simulated truth: held-out error against the noise floor |
//! | [`tree`] | the plan of a tree model: safe for every tip's chain, branches kept apart, the tree's identification |
//! | [`tree_output`] | a tree plan's `plan.csv`, `plan.json` and summary |
//!
//! The parameters are those the calibration identifies ([`crate::calib::default_selection`],
//! the thesis's 12 on the Katana), linearised at the declared model with its declared static
//! tilting (the contact direction held fixed: [`crate::model::Model::set_tilt_direction_frozen`]),
//! restricted to the combinations identifiable on the whole candidate set (the others are
//! listed as `unidentifiable`). Columns are scaled to unit RMS over the candidates so that
//! degrees and millimetres compare; the design optimises one of the criteria of [`criteria`]
//! (weighted A by default) or, with `--from-diagnose`, its restriction to the aliased effects'
//! columns (As / Ds), and is compared with the best possible on the candidates ([`optimum`],
//! [`continuous`]).

pub mod aliased;
pub mod candidates;
pub mod collision;
pub mod continuous;
pub mod criteria;
pub mod design;
pub mod evaluate;
pub mod meshes;
pub mod metrics;
pub mod optimum;
pub mod order;
pub mod output;
pub mod refine;
pub mod robust;
pub mod setup;
pub mod sheets;
pub mod sheets_output;
mod steps;
#[cfg(test)]
mod test_support;
pub mod trajectory;
pub mod tree;
pub mod tree_output;
pub mod workspace;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::error::{Classify, ErrorKind};
use crate::model::{Model, ModelError};
pub use aliased::{FromDiagnose, FromDiagnoseReport};
pub use candidates::{draw_candidates, structured_candidates, CandidatePose, Workspace};
pub use design::{exchange, exchange_from, exchange_weighted, optimal_design, Criterion, Design};
pub use metrics::{
    design_stats, median_ratio, quantile, random_baseline, DesignStats, DirectRatio,
};
pub use setup::Setup;
use steps::{
    baseline, candidate_set, check_config, check_rows, optimum_report, refine_sweeps, CandidateSet,
};

/// Everything that can stop a plan.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// The workspace constraints admit too few configurations.
    #[error("only {found} of {wanted} candidate poses satisfy the workspace constraints after {tries} random configurations (loosen {loosen})")]
    Candidates {
        wanted: usize,
        found: usize,
        tries: usize,
        /// The options that constrain these candidates, as the user would loosen them.
        loosen: &'static str,
    },
    /// More poses asked than candidates.
    #[error("--n {n} is more than the {candidates} candidates")]
    TooFewCandidates { n: usize, candidates: usize },
    /// Too few poses for the parameters.
    #[error("--n {n}: {n} poses give {rows} measured coordinates for {params} identifiable parameters; use at least {min}")]
    TooFewPoses {
        n: usize,
        rows: usize,
        params: usize,
        min: usize,
    },
    /// A bad setting.
    #[error("{0}")]
    Config(String),
    /// A bad `--from-diagnose` file.
    #[error("{path}: {message}")]
    Diagnose { path: String, message: String },
    /// Linear algebra failed.
    #[error("numerical failure: {0}")]
    Numerical(&'static str),
    /// The model failed.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The collision geometry cannot be read (a mesh, the chain, an SRDF).
    #[error("{0}")]
    Geometry(String),
    /// The URDF cannot be read.
    #[error(transparent)]
    Urdf(#[from] crate::urdf::UrdfError),
    /// Fewer safe poses than asked (collision-free, above the table, in the limits).
    #[error("only {found} of the {wanted} poses asked are safe: {why}")]
    Unsafe {
        wanted: usize,
        found: usize,
        why: String,
    },
}

impl Classify for PlanError {
    fn kind(&self) -> ErrorKind {
        match self {
            PlanError::Candidates { .. } | PlanError::Numerical(_) | PlanError::Unsafe { .. } => {
                ErrorKind::Failure
            }
            PlanError::Model(e) => e.kind(),
            _ => ErrorKind::BadInput,
        }
    }
}

/// Refinement sweeps when [`PlanConfig::refine_sweeps`] is `None`: 3, with or without
/// `--from-diagnose`. (Linearised at the declared model, where the payload is zero, refinement
/// alone would drive poses to where a joint moment vanishes and the payload column at zero is
/// unbounded, 40-200 mm/kg against 0.03-0.06 at 0.5 kg: an expected payload sigma of 8e-5 kg
/// against a true 0.024-0.039, and `diagnose` not naming the payload. The linearity test of
/// [`robust`] keeps every chosen or refined pose where the effects to separate are linear over
/// their plausible values, so refinement is on with `--from-diagnose` too.)
pub fn default_refine_sweeps(_from_diagnose: bool) -> usize {
    DEFAULT_REFINE_SWEEPS
}

/// Random designs drawn for the baseline by default: the per-parameter median over them is
/// the `random_sigma` every ratio is taken against. With 25 its sampling error moved a seed's
/// median sigma ratio by up to 0.04 (seed 1: 0.634 against 0.600 with 400); a draw costs a
/// 3N x p SVD, so 400 cost about 10 ms.
pub const DEFAULT_RANDOM_DRAWS: usize = 400;

/// Refinement sweeps of a declared plan by default.
pub const DEFAULT_REFINE_SWEEPS: usize = 3;

/// Settings of [`plan`].
#[derive(Debug, Clone, PartialEq)]
pub struct PlanConfig {
    /// Poses to choose.
    pub n: usize,
    /// Size of the candidate set.
    pub candidates: usize,
    /// Seed of the candidates and of the random baseline.
    pub seed: u64,
    /// Workspace constraints.
    pub workspace: Workspace,
    /// Measurement noise per coordinate (mm) for the expected sigmas.
    pub noise_mm: f64,
    /// Random designs drawn for the baseline.
    pub random_draws: usize,
    /// Optimality criterion.
    pub criterion: Criterion,
    /// Exchange runs from random starts besides the greedy one (the best design is kept).
    pub restarts: usize,
    /// Joint readings of poses already measured (their information is added to the plan's).
    pub existing_q: Vec<Vec<f64>>,
    /// Add the structured candidates (joint limits and mid-range combinations) to the pool;
    /// `None`: yes (with `--from-diagnose` too, see [`default_refine_sweeps`]).
    pub structured: Option<bool>,
    /// Sweeps of the continuous refinement of the chosen poses (0: off); `None`:
    /// [`DEFAULT_REFINE_SWEEPS`] (see [`default_refine_sweeps`]).
    pub refine_sweeps: Option<usize>,
    /// The candidates given (`--candidates-from`: configurations the robot can reach, or poses
    /// measured already): the plan is a subset of them; no random or structured candidates, no
    /// refinement, no climbs (the best possible is on these alone).
    pub pool_q: Option<Vec<Vec<f64>>>,
    /// Plan for the base frame too (`--base`, as `calibrate --base` identifies it).
    pub base: bool,
    /// Largest joint step between the configurations checked along a segment between two
    /// consecutive poses, deg (mm for prismatic joints).
    pub segment_step_deg: f64,
}

impl PlanConfig {
    /// Defaults for `model`: 5000 candidates (plus the structured ones), seed 1, noise 0.01 mm,
    /// [`DEFAULT_RANDOM_DRAWS`] random draws, weighted A, 1 restart, default refinement.
    pub fn new(model: &Model, n: usize) -> Self {
        Self {
            n,
            candidates: 5000,
            seed: 1,
            workspace: Workspace::for_model(model),
            noise_mm: 0.01,
            random_draws: DEFAULT_RANDOM_DRAWS,
            criterion: Criterion::default(),
            restarts: 1,
            existing_q: Vec::new(),
            structured: None,
            refine_sweeps: None,
            pool_q: None,
            base: false,
            segment_step_deg: order::DEFAULT_STEP_DEG,
        }
    }
}

/// A plan and what it is expected to give.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Robot (model) name.
    pub robot: String,
    /// `"D-optimal"` or `"Ds-optimal"`.
    pub criterion: String,
    /// Number of candidates (uniform + structured).
    pub candidates: usize,
    /// Of which structured (joint limits and mid-range).
    pub structured_candidates: usize,
    /// The chosen poses, in the order chosen.
    pub poses: Vec<CandidatePose>,
    /// Identifiable parameters (unknown names), in the order of the sigmas.
    pub parameters: Vec<String>,
    /// Their column scale: RMS tool-point change per unit of each over the candidates (mm per
    /// parameter unit).
    pub scale: Vec<f64>,
    /// Unidentifiable parameters or combinations on the whole candidate set.
    pub unidentifiable: Vec<String>,
    /// Expected quality of the plan (with the poses already measured, if any).
    pub planned: DesignStats,
    /// Median quality of random designs of the same size (same prior poses).
    pub random: DesignStats,
    /// Median over parameters of planned / random sigma.
    pub median_sigma_ratio: f64,
    /// The `--from-diagnose` part.
    pub from_diagnose: Option<FromDiagnoseReport>,
    /// Exchanges made after the greedy start.
    pub exchanges: usize,
    /// The spread of the baseline: per random design (another `random_draws` draws), the median
    /// over parameters of planned / that design's sigma.
    pub ratio_per_draw: Vec<f64>,
    /// The direct reading: median planned sigma against the median sigma of each of
    /// the baseline's random designs (mixed units).
    pub direct: DirectRatio,
    /// The continuous refinement: criterion before and after, accepted moves, sweeps run.
    pub refinement: RefineSummary,
    /// With [`PlanConfig::pool_q`]: the index in the pool of each planned pose.
    pub pool_index: Option<Vec<usize>>,
    /// The best possible on the candidates (approximate optimum and its bound) and the plan's
    /// efficiency against it; `None` with poses already measured or `--from-diagnose`.
    pub optimum: Option<optimum::OptimumReport>,
    /// The visiting order ([`order`]): `poses` (and `pool_index`) are in that order.
    pub order: order::Ordered,
}

/// What the continuous refinement did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineSummary {
    /// Criterion of the exchange's design (larger is better).
    pub criterion_before: f64,
    /// Criterion after the refinement.
    pub criterion_after: f64,
    /// Accepted joint moves.
    pub moves: usize,
    /// Sweeps run.
    pub sweeps: usize,
}

impl RefineSummary {
    fn of(r: &refine::Refined) -> Self {
        Self {
            criterion_before: r.criterion_before,
            criterion_after: r.criterion_after,
            moves: r.moves,
            sweeps: r.sweeps,
        }
    }
}

/// Most drawn candidates (`--candidates`) and random baseline draws (`--random-draws`); `--n`
/// is at most the number of candidates (drawn, or the `--candidates-from` poses that pass).
pub const MAX_CANDIDATES: usize = 200_000;

/// Plans `cfg.n` poses for `model` (see the module docs); with `from`, the extra poses that
/// separate the aliased effects of a diagnosis, given the poses already measured.
pub fn plan(
    model: &Model,
    cfg: &PlanConfig,
    from: Option<&FromDiagnose>,
) -> Result<Plan, PlanError> {
    check_config(cfg)?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let CandidateSet {
        mut cands,
        pool_index,
        n_uniform,
    } = candidate_set(model, cfg, &mut rng)?;
    let mut setup = match from {
        None => Setup::declared_with_base(model, &cands, &cfg.existing_q, cfg.base)?,
        Some(f) => f.setup(model, &cands, &cfg.existing_q)?,
    };
    let p = setup.names.len();
    let prior_poses = setup.prior_rows.nrows() / 3;
    check_rows(cfg.n, prior_poses, p)?;
    let prior = setup.prior_rows.transpose() * &setup.prior_rows;
    // the baseline draws from the uniform candidates only (not the structured extremes)
    let b_uniform = setup.b.rows(0, 3 * n_uniform).into_owned();
    // the baseline first: A weighs each parameter's variance by 1 / its random-design variance
    let (random, random_draws, weights) = baseline(&b_uniform, &setup, cfg, &mut rng);
    let prediction = criteria::prediction_weight(&b_uniform, criteria::POSE_ROWS);
    let n_pool = cands.len();
    let best =
        continuous::best_possible(model, cfg, &mut setup, &mut cands, &weights, &prediction)?;
    let problem = design::Problem {
        b: &setup.b,
        rows: criteria::POSE_ROWS,
        prior: &prior,
        interest: &setup.interest,
        kind: cfg.criterion,
        weights: &weights,
        prediction: Some(&prediction),
        admissible: &setup.admissible,
    };
    let rounded = best.as_ref().map(|b| b.optimum.rounded(cfg.n));
    let design = best_exchange(&problem, cfg, rounded.as_deref(), &mut rng)?;
    let refiner = refine::Refiner {
        model,
        setup: &setup,
        workspace: &cfg.workspace,
        kind: cfg.criterion,
        weights: &weights,
        prediction: &prediction,
    };
    let start: Vec<CandidatePose> = design.chosen.iter().map(|&c| cands[c].clone()).collect();
    let sweeps = refine_sweeps(cfg, pool_index.is_some(), from.is_some());
    let refined = refiner.refine(&prior, &start, sweeps)?;
    let chosen: Vec<usize> = (0..refined.poses.len()).collect();
    let jac = metrics::stack_rows(
        &refined.blocks,
        criteria::POSE_ROWS,
        &setup.scale,
        &setup.prior_rows,
        &chosen,
    );
    let planned = design_stats(&jac, prior_poses + cfg.n, cfg.noise_mm);
    let median_sigma_ratio = median_ratio(&planned.sigma, &random.sigma);
    let optimum = best.map(|b| {
        optimum_report(
            b,
            &refined.blocks,
            &chosen,
            &setup.scale,
            cfg,
            &random.sigma,
        )
    });
    let direct = DirectRatio::new(&planned.sigma, &random_draws);
    let ratio_per_draw = metrics::ratio_per_draw(
        &b_uniform,
        &setup.scale,
        &setup.prior_rows,
        &planned.sigma,
        cfg.n,
        cfg.random_draws,
        cfg.noise_mm,
        &mut rng,
    );
    let refinement = RefineSummary::of(&refined);
    setup.b = refined.blocks;
    let from_diagnose = from.map(|f| f.report(&setup, &chosen));
    let weights_j = vec![1.0; model.n_joints()];
    let ordered = order::order_poses(
        model,
        &cfg.workspace,
        &refined.poses,
        &weights_j,
        cfg.segment_step_deg,
    )?;
    if let Some((_, why)) = ordered.dropped.first() {
        return Err(PlanError::Unsafe {
            wanted: cfg.n,
            found: ordered.order.len(),
            why: format!(
                "{} poses have no safe segment to any other (first: {why}); loosen the constraints or plan fewer",
                ordered.dropped.len()
            ),
        });
    }
    let poses: Vec<CandidatePose> = ordered
        .order
        .iter()
        .map(|&k| refined.poses[k].clone())
        .collect();
    let pool_index = pool_index.map(|index| {
        let chosen: Vec<usize> = design.chosen.iter().map(|&c| index[c]).collect();
        ordered.order.iter().map(|&k| chosen[k]).collect()
    });
    Ok(Plan {
        robot: model.name().to_string(),
        criterion: cfg.criterion.name(!setup.interest.is_empty()).into(),
        candidates: n_pool,
        structured_candidates: n_pool - n_uniform,
        poses,
        parameters: setup.names.clone(),
        scale: setup.scale.clone(),
        unidentifiable: setup.unidentifiable.clone(),
        planned,
        random,
        median_sigma_ratio,
        from_diagnose,
        exchanges: design.exchanges,
        ratio_per_draw,
        direct,
        refinement,
        pool_index,
        optimum,
        order: ordered,
    })
}

/// The greedy start's exchange, the exchange from `rounded` (the approximate optimum's
/// heaviest candidates) and `cfg.restarts` exchanges from random starts; the best.
fn best_exchange(
    problem: &design::Problem<'_>,
    cfg: &PlanConfig,
    rounded: Option<&[usize]>,
    rng: &mut ChaCha8Rng,
) -> Result<Design, PlanError> {
    let n_cand = problem.b.nrows() / 3;
    let mut best: Option<Design> = None;
    if let Some(start) = rounded {
        best = Some(exchange(problem, cfg.n, start)?);
    }
    for r in 0..=cfg.restarts {
        let start = if r == 0 {
            Vec::new()
        } else {
            rand::seq::index::sample(rng, n_cand, cfg.n.min(n_cand)).into_vec()
        };
        let d = exchange(problem, cfg.n, &start)?;
        if best.as_ref().is_none_or(|b| d.criterion > b.criterion) {
            best = Some(d);
        }
    }
    best.ok_or(PlanError::Numerical("no design"))
}
