//! The decision rule: greedy forward selection of effects, each accepted only when the data
//! demand it.
//!
//! At each step, with the current fit (declared model + effects accepted so far):
//!
//! 1. **Screen** every remaining candidate linearly ([`super::residual::screen`]) and rank by the
//!    linearised change of BIC (`m ln(RSS1/RSS0) + k ln m`, `k` = new identifiable directions,
//!    `m` = 3 x poses). Candidates that only alias fitted parameters (`k = 0`) drop out here.
//!    A linear screen taken where a sign step of the tilting law sits exactly at zero (e.g. the
//!    joint-1 axis torque, 0 at every pose until the base tilts) cannot see the step the
//!    candidate would switch on; every candidate whose small move flips such a sign
//!    ([`onset_candidates`]) is therefore refitted too, whatever its screen.
//! 2. **Refit** the best [`DecideConfig::refit_top`] fully (Levenberg-Marquardt on every fitted
//!    unknown plus the candidate's, with the SVD identifiability analysis deciding which of the
//!    candidate's unknowns are new; aliased ones stay fixed and are reported as unidentifiable
//!    combinations), and rank them by the exact change of BIC. A refit that crossed sign steps
//!    of the tilting law and stopped at one is polished derivative-free first
//!    ([`super::polish`]).
//! 3. **Test** in that order; the first candidate that passes both tests is accepted. Candidates
//!    that pass the F-test and BIC and lie within [`DecideConfig::bic_tie`] of the best exact BIC
//!    are near-aliases on the calibration poses (e.g. a first and a second encoder harmonic over a
//!    narrow joint range, or a tool offset along the last axis and that link's length): their
//!    cross-validated errors decide, and where those do not differ significantly the simplest
//!    candidate (fewest unknowns, lowest harmonic order) comes first:
//!    * the nested-model F-test on the RSS with `k` added parameters, `p <` [`DecideConfig::alpha`]
//!      (default 0.001), and a BIC decrease;
//!    * k-fold cross-validation on the calibration poses ([`DecideConfig::folds`], default 5,
//!      folds drawn with a seeded ChaCha8 permutation): every fold is refitted (from the full-data
//!      solution, same unknowns) and predicts its held-out poses; with per-pose held-out errors
//!      `e0` (without the candidate) and `e1` (with it), the mean must drop by at least
//!      [`DecideConfig::cv_min_gain`] (relative, default 2 %) and the paired one-sided t statistic
//!      of `e0 - e1` must exceed [`DecideConfig::cv_t_min`] (default 2.326, p < 0.01).
//! 4. Repeat until no candidate passes (or [`DecideConfig::max_effects`]).

use crate::calib::fit::Fit;
use nalgebra::Vector3;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::candidates::Candidate;
use super::compress::stacked_or_compressed;
use super::extended::{fit_values, ExtModel, Unknown, Values};
use super::parallel::map_ordered;
use crate::calib::lm::LmConfig;
use crate::calib::stats::autocorrelation_time;
use crate::calib::CalibError;
use crate::calib::MeasuredSet;
use crate::model::effect::Tie;
use crate::model::ModelError;

/// Settings of the selection.
#[derive(Debug, Clone, PartialEq)]
pub struct DecideConfig {
    /// Significance level of the F-test.
    pub alpha: f64,
    /// Number of cross-validation folds.
    pub folds: usize,
    /// Seed of the fold assignment.
    pub seed: u64,
    /// Smallest relative drop of the cross-validated mean error.
    pub cv_min_gain: f64,
    /// Smallest paired t statistic of the cross-validated improvement.
    pub cv_t_min: f64,
    /// Number of screened candidates refitted fully per step.
    pub refit_top: usize,
    /// Most effects accepted.
    pub max_effects: usize,
    /// Solver settings of the full fits.
    pub lm: LmConfig,
    /// Solver settings of the cross-validation refits.
    pub lm_cv: LmConfig,
    /// Identifiability threshold (relative singular value).
    pub rtol: f64,
    /// Most profile evaluations of the derivative-free polish of a refit that crossed sign steps
    /// of the tilting law ([`super::polish`]); 0 disables it.
    pub polish_max_evals: usize,
    /// Width of the band of exact BIC changes (from the best) within which passing candidates
    /// are ranked by their cross-validated error instead (10 = "strong evidence" on the
    /// Kass-Raftery scale).
    pub bic_tie: f64,
    /// Step (in each unknown's own unit) of the probe that looks for sign steps a candidate
    /// switches on ([`onset_candidates`]).
    pub onset_probe: f64,
    /// A known floor (one sigma per coordinate, mm: the larger of the instrument's and the
    /// repeatability, [`super::floor`]), for the report; the acceptance rule is the same with or
    /// without it.
    pub floor_mm: Option<f64>,
}

impl Default for DecideConfig {
    fn default() -> Self {
        Self {
            alpha: 1e-3,
            folds: 5,
            seed: 1,
            cv_min_gain: 0.02,
            cv_t_min: 2.326,
            refit_top: 4,
            max_effects: 8,
            lm: LmConfig::default(),
            lm_cv: LmConfig {
                max_iterations: 30,
                max_iterations_hard: 30,
                ftol: 1e-10,
                final_correction: false,
                ..LmConfig::default()
            },
            rtol: crate::calib::identifiability::DEFAULT_RTOL,
            polish_max_evals: 100,
            bic_tie: 10.0,
            onset_probe: 1e-3,
            floor_mm: None,
        }
    }
}

/// The tests of one candidate at one step.
#[derive(Debug, Clone, PartialEq)]
pub struct Trial {
    /// The candidate.
    pub candidate: Candidate,
    /// New identifiable directions it added.
    pub added: usize,
    /// RSS before and after (mm^2).
    pub rss_before_mm2: f64,
    /// RSS after the refit (mm^2).
    pub rss_after_mm2: f64,
    /// F statistic and p-value of the nested test.
    pub f: f64,
    /// p-value of the F-test.
    pub p_value: f64,
    /// Change of BIC (negative = better).
    pub delta_bic: f64,
    /// Cross-validated mean error without / with the candidate (mm); NaN when not run.
    pub cv_mean_mm: [f64; 2],
    /// Paired t statistic of the cross-validated improvement (NaN when not run).
    pub cv_t: f64,
    /// Whether it was accepted.
    pub accepted: bool,
    /// Why not, when it was not.
    pub reason: String,
    /// Its values that the refit put outside their physical bounds, held there before the
    /// tests (`name = value held at bound`).
    pub held: Vec<String>,
}

/// One accepted effect.
#[derive(Debug, Clone)]
pub struct Accepted {
    /// Its tests.
    pub trial: Trial,
    /// The fit before it was added.
    pub before: Fit<ExtModel, Unknown>,
    /// The fit with it.
    pub after: Fit<ExtModel, Unknown>,
    /// Candidates equivalent to it on these poses (near ties within noise).
    pub equivalent: Vec<String>,
}

/// Result of [`forward_selection`].
#[derive(Debug, Clone)]
pub struct Selection {
    /// Accepted effects in order.
    pub steps: Vec<Accepted>,
    /// The candidates tested (refitted) at the last step, none accepted.
    pub last_trials: Vec<Trial>,
    /// The final fit.
    pub last: Fit<ExtModel, Unknown>,
    /// All unknowns requested in the final fit.
    pub requested: Vec<Unknown>,
    /// The greedy selection this one replaced, when a smaller set did as well
    /// ([`super::simplest`]).
    pub simpler: Option<Simpler>,
}

/// A smaller set that replaced the greedy selection (reported in the JSON and the text).
#[derive(Debug, Clone, PartialEq)]
pub struct Simpler {
    /// The effects of the greedy selection, in order.
    pub greedy: Vec<String>,
    /// The effects of the smaller set taken instead.
    pub taken: Vec<String>,
    /// Cross-validated mean error (mm) of the greedy set and of the set taken.
    pub cv_mean_mm: [f64; 2],
    /// BIC of the set taken minus the greedy set's (negative: the smaller set is preferred).
    pub delta_bic: f64,
    /// Other sets no larger than the one taken that did as well (`a + b`), the closest first.
    pub close: Vec<String>,
}

/// Fold of every pose: a seeded permutation cut into `k` nearly equal parts.
pub fn fold_assignment(n: usize, k: usize, seed: u64) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
    let mut fold = vec![0; n];
    for (rank, &i) in order.iter().enumerate() {
        fold[i] = rank % k.max(1);
    }
    fold
}

/// Fold of every sample of a serially correlated dataset: `k` contiguous blocks in sample order
/// (a randomly drawn fold would leave each held-out sample's neighbours, which carry nearly the
/// same error, in the training set).
pub fn block_fold_assignment(n: usize, k: usize) -> Vec<usize> {
    let k = k.max(1);
    (0..n).map(|i| (i * k / n.max(1)).min(k - 1)).collect()
}

/// Integrated autocorrelation time of the residuals of `ext` on `data`
/// ([`crate::calib::stats::autocorrelation_time`] of each measured component's series in sample
/// order; the largest), 1 for independent poses (full positions). The statistics of the
/// selection count `residuals / tau` independent residuals.
pub fn serial_tau(ext: &ExtModel, data: &MeasuredSet) -> Result<f64, CalibError> {
    if !data.is_serial() {
        return Ok(1.0);
    }
    let mut series: Vec<Vec<f64>> = Vec::new();
    for k in 0..data.len() {
        let e = data.poses.xyz_mm[k] - ext.predict_pose(data, k)?;
        for (slot, c) in data.components(k, &e).into_iter().enumerate() {
            if series.len() <= slot {
                series.push(Vec::new());
            }
            series[slot].push(c);
        }
    }
    Ok(series
        .iter()
        .map(|s| autocorrelation_time(s))
        .fold(1.0, f64::max))
}

/// Held-out error (mm, the measured part) of every pose under k-fold cross-validation of
/// `fit`'s unknowns (contiguous folds for serial data, [`block_fold_assignment`]).
pub fn cv_errors(
    f: &Fit<ExtModel, Unknown>,
    data: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<Vec<f64>, CalibError> {
    let n = data.len();
    let k = cfg.folds.clamp(2, n.max(2));
    let fold = if data.is_serial() {
        block_fold_assignment(n, k)
    } else {
        fold_assignment(n, k, cfg.seed)
    };
    // the folds are independent: refitted on both cores, each by the same code
    let groups: Vec<usize> = (0..k).collect();
    let per_fold = map_ordered(&groups, |&g| -> Result<Vec<(usize, f64)>, CalibError> {
        let train: Vec<usize> = (0..n).filter(|&i| fold[i] != g).collect();
        let test: Vec<usize> = (0..n).filter(|&i| fold[i] == g).collect();
        if test.is_empty() || 3 * train.len() < f.fitted.len() {
            return Ok(Vec::new());
        }
        let sub = data.subset(&train);
        let refit = fit_values(&f.model, &sub, &f.fitted, &cfg.lm_cv, cfg.rtol)?;
        test.iter()
            .map(|&i| {
                let p = refit.predict_pose(data, i)?;
                Ok((i, data.error_mm(i, &p).norm()))
            })
            .collect()
    });
    let mut out = vec![0.0; n];
    for part in per_fold {
        for (i, e) in part? {
            out[i] = e;
        }
    }
    Ok(out)
}

/// Mean of `e0 - e1`, relative to mean `e0`, and the paired t statistic; with `serial` the
/// differences are a series along a path and the t statistic is divided by the square root of
/// its autocorrelation time.
pub(super) fn paired_gain(e0: &[f64], e1: &[f64], serial: bool) -> (f64, f64, f64, f64) {
    let n = e0.len().min(e1.len());
    if n < 2 {
        return (f64::NAN, f64::NAN, 0.0, 0.0);
    }
    let nf = n as f64;
    let m0 = e0.iter().sum::<f64>() / nf;
    let m1 = e1.iter().sum::<f64>() / nf;
    let d: Vec<f64> = e0.iter().zip(e1).map(|(a, b)| a - b).collect();
    let md = d.iter().sum::<f64>() / nf;
    let var = d.iter().map(|x| (x - md).powi(2)).sum::<f64>() / (nf - 1.0);
    let t = if var > 0.0 {
        md / (var / nf).sqrt()
    } else if md > 0.0 {
        f64::INFINITY
    } else {
        0.0
    };
    let t = if serial {
        t / autocorrelation_time(&d).sqrt()
    } else {
        t
    };
    let rel = if m0 > 0.0 { md / m0 } else { 0.0 };
    (m0, m1, rel, t)
}

/// Order of near-tied candidates (indices `ids`, cross-validated per-pose errors `errs`): the
/// ones the best cross-validated candidate does not beat significantly (paired t below
/// [`DecideConfig::cv_t_min`]) are statistically equivalent, and among them the simplest comes
/// first ([`simplicity`]: fewer unknowns, then a lower harmonic order); the others follow by
/// cross-validated mean.
pub(super) fn rank_contenders<'a>(
    ids: &[usize],
    errs: &[Vec<f64>],
    candidate: impl Fn(usize) -> &'a Candidate,
    cfg: &DecideConfig,
    serial: bool,
) -> (Vec<usize>, Vec<usize>) {
    let mean = |e: &[f64]| e.iter().sum::<f64>() / e.len().max(1) as f64;
    let Some(best) = (0..ids.len()).min_by(|&a, &b| mean(&errs[a]).total_cmp(&mean(&errs[b])))
    else {
        return (Vec::new(), Vec::new());
    };
    let (mut equivalent, mut worse): (Vec<usize>, Vec<usize>) = (0..ids.len()).partition(|&k| {
        let t = paired_gain(&errs[k], &errs[best], serial).3;
        t.is_nan() || t < cfg.cv_t_min
    });
    equivalent.sort_by_key(|&k| simplicity(candidate(ids[k])));
    worse.sort_by(|&a, &b| mean(&errs[a]).total_cmp(&mean(&errs[b])));
    let eq: Vec<usize> = equivalent.iter().map(|&k| ids[k]).collect();
    (
        equivalent
            .into_iter()
            .chain(worse)
            .map(|k| ids[k])
            .collect(),
        eq,
    )
}

/// Occam's order of a candidate: its number of unknowns, then its harmonic order (a first
/// harmonic is smoother than a second one; 0 for effects that are not harmonics); the kinds the
/// effect table ranks [`Tie::Transmission`] after every other.
fn simplicity(c: &Candidate) -> (usize, u32) {
    match c.effect.row().tie {
        Tie::Transmission => (usize::MAX, 0),
        // a change's time is one more parameter: the constant effect first
        Tie::Named => (
            c.unknowns.len() + usize::from(c.effect.is_change()),
            c.effect.harmonic_order(),
        ),
    }
}

/// The moves tried by [`onset_candidates`], in units of [`DecideConfig::onset_probe`]: from a
/// step at a moment that sits exactly at zero up to, for an effect that changes the loads
/// ([`crate::model::effect::Kind::changes_loads`]), a move of the unknown's own unit (a
/// kilogram of payload, a degree of base tilt), which switches on the sign steps of every pose
/// whose moment it crosses, in either direction (only while no effect on the loads has been
/// accepted: [`super::select::shortlist`]'s `ladder`). Other effects move the joints, and a large
/// move of theirs flips the moments of some pose whatever the data: only the first step is
/// tried for them.
const ONSET_LADDER: [f64; 4] = [1.0, 10.0, 100.0, 1000.0];

/// Indices of the candidates whose small move (`onset_probe`, [`DecideConfig::onset_probe`], on
/// each of their unknowns) flips a sign of the joint moments at some pose: where the tilting law's sign steps
/// sit exactly at zero in the current fit, the linear screen cannot see what the candidate would
/// switch on, so these are always refitted.
pub fn onset_candidates(
    model: &ExtModel,
    cands: &[Candidate],
    data: &MeasuredSet,
    onset_probe: f64,
    ladder: bool,
) -> Result<Vec<usize>, ModelError> {
    let base = model.moment_signs(data)?;
    if base.is_empty() || onset_probe <= 0.0 {
        return Ok(Vec::new());
    }
    let flips = |cand: &Candidate, size: f64| -> bool {
        let mut probe = model.clone();
        for &u in &cand.unknowns {
            if probe.set_value(u, probe.value(u) + size).is_err() {
                return false;
            }
        }
        probe
            .moment_signs(data)
            .is_ok_and(|signs| signs.iter().zip(&base).any(|(a, b)| a != b))
    };
    Ok(cands
        .iter()
        .enumerate()
        .filter(|(_, cand)| {
            flips(cand, onset_probe)
                || (ladder
                    && cand.effect.row().kind.changes_loads()
                    && ONSET_LADDER
                        .iter()
                        .any(|m| flips(cand, m * onset_probe) || flips(cand, -m * onset_probe)))
        })
        .map(|(ci, _)| ci)
        .collect())
}

/// The current model moved by the Gauss-Newton step of its fitted unknowns plus `cand`'s
/// (minimum-norm least squares on column-scaled Jacobians), or `None` if it cannot be computed.
pub(super) fn linear_start(
    cur: &Fit<ExtModel, Unknown>,
    data: &MeasuredSet,
    cand: &Candidate,
) -> Option<ExtModel> {
    let mut unknowns = cur.fitted.clone();
    unknowns.extend(
        cand.unknowns
            .iter()
            .copied()
            .filter(|u| !cur.fitted.contains(u)),
    );
    let (mut jac, err) = stacked_or_compressed(&cur.model, data, &unknowns).ok()?;
    let norms: Vec<f64> = (0..jac.ncols()).map(|k| jac.column(k).norm()).collect();
    for (k, n) in norms.iter().enumerate() {
        if *n > 0.0 {
            jac.column_mut(k).unscale_mut(*n);
        }
    }
    let svd = jac.svd(true, true);
    let top = svd.singular_values.iter().copied().fold(0.0, f64::max);
    let step = svd.solve(&err, 1e-6 * top).ok()?;
    let mut ext = cur.model.clone();
    for (k, u) in unknowns.iter().enumerate() {
        if norms[k] > 0.0 {
            let v = ext.value(*u) + step[k] / norms[k];
            ext.set_value(*u, v).ok()?;
        }
    }
    Some(ext)
}

/// The best start for a candidate with an unknown the prediction is not linear in
/// ([`Unknown::start_values`], e.g. a time constant whose column vanishes while its growth is
/// zero): for each start value, that value set and the [`linear_start`] step of the others; the
/// start of least squared error. `None` when the candidate has no such unknown.
pub(super) fn nonlinear_start(
    cur: &Fit<ExtModel, Unknown>,
    data: &MeasuredSet,
    cand: &Candidate,
) -> Option<ExtModel> {
    let (u, values) = cand
        .unknowns
        .iter()
        .find_map(|u| u.start_values().map(|v| (*u, v)))?;
    values
        .iter()
        .filter_map(|&v| {
            let mut from = cur.clone();
            from.model.set_value(u, v).ok()?;
            let start = linear_start(&from, data, cand)?;
            let cost: f64 = start
                .errors(data)
                .ok()?
                .iter()
                .map(|e| e.norm_squared())
                .sum();
            cost.is_finite().then_some((cost, start))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, start)| start)
}

/// Per-pose contribution of an effect: predictions after minus before (mm) on `data`.
pub fn contribution(
    before: &Fit<ExtModel, Unknown>,
    after: &Fit<ExtModel, Unknown>,
    data: &MeasuredSet,
) -> Result<Vec<Vector3<f64>>, CalibError> {
    let e0 = before.model.errors(data)?;
    let e1 = after.model.errors(data)?;
    Ok(e0.iter().zip(&e1).map(|(a, b)| a - b).collect())
}

#[cfg(test)]
mod tests;
