//! The selection of a tree's elastic effects: forward steps, then swaps (each accepted effect
//! against the candidates of its neighbourhood - the other kind on its joint, and both kinds on
//! its parent and child joints, whose frames share or nearly share its origin - the set kept
//! whose residual is lowest), so that a stand-in accepted early (a lateral bend of the torso's
//! yaw joint for the bends of the pitch joint beside it) gives way to the effect the later
//! steps make the better one. Every fit is the
//! tree's one identification ([`calibrate_tree`]), started from the current fit (a warm start:
//! the same solution in fewer iterations), candidates fitted on up to
//! [`crate::diagnose::parallel::threads`] threads with results in candidate order.

use std::collections::HashMap;

use crate::calib::tree_calibrate::{calibrate_tree, TreeOutcome};
use crate::calib::tree_fit::tree_errors;
use crate::calib::{CalibError, CalibrateOptions, MeasuredSet, Stats};
use crate::diagnose::parallel::map_ordered;
use crate::diagnose::stat::{delta_bic, nested_f_test};
use crate::model::Tree;

/// Folds of the cross-validation that confirms an accepted candidate.
pub const TREE_CV_FOLDS: usize = 5;

/// Two candidates are equivalent when the one's set has a residual sum of squares above the
/// other's by less than this many residual variances (the 5 % point of chi-square with 1 degree
/// of freedom): one parameter each, the poses cannot tell them apart.
pub const EQUIVALENT_RSS_VARIANCES: f64 = 3.84;

/// Most rounds of swaps (each round makes the one swap that lowers the residual most).
pub const MAX_SWAP_ROUNDS: usize = 8;

/// A candidate: its effect id and the tree parameter it frees.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    pub id: String,
    pub param: String,
    /// The tree joint (0-based).
    pub joint: usize,
}

/// Whether `b` is in the neighbourhood of `a` on `tree`: the same joint, its parent or a child.
fn neighbours(tree: &Tree, a: &Candidate, b: &Candidate) -> bool {
    let parent = |j: usize| tree.joints.get(j).and_then(|x| x.parent);
    a.joint == b.joint || parent(a.joint) == Some(b.joint) || parent(b.joint) == Some(a.joint)
}

/// One fit of the declared unknowns plus some candidates' parameters.
#[derive(Debug, Clone)]
pub struct Trial {
    pub outcome: TreeOutcome,
    pub rss_mm2: f64,
    pub n_fitted: usize,
    pub m: usize,
}

impl From<TreeOutcome> for Trial {
    fn from(outcome: TreeOutcome) -> Self {
        Self {
            rss_mm2: outcome.fit.rss_mm2,
            n_fitted: outcome.fit.fitted.len(),
            m: outcome.fit.n_residuals,
            outcome,
        }
    }
}

/// What the fits share: the tree, the poses, the options and the declared unknowns.
pub struct Fits<'a> {
    pub nominal: &'a Tree,
    pub cal: &'a MeasuredSet,
    pub opts: &'a CalibrateOptions,
    pub declared: &'a [String],
    /// Cross-validated means by set of extra parameters (the replay asks again).
    cv_cache: std::sync::Mutex<HashMap<Vec<String>, f64>>,
}

impl<'a> Fits<'a> {
    pub fn new(
        nominal: &'a Tree,
        cal: &'a MeasuredSet,
        opts: &'a CalibrateOptions,
        declared: &'a [String],
    ) -> Self {
        Self {
            nominal,
            cal,
            opts,
            declared,
            cv_cache: Default::default(),
        }
    }

    /// The fit of the declared unknowns and `extra` on `set` (the calibration poses when
    /// `None`), started from `start`, with `val` evaluated.
    pub fn fit(
        &self,
        start: &Tree,
        set: Option<&MeasuredSet>,
        val: Option<&MeasuredSet>,
        extra: &[String],
    ) -> Result<Trial, CalibError> {
        let mut o = self.opts.clone();
        o.keep_outliers = true;
        o.params = Some(self.declared.iter().chain(extra).cloned().collect());
        Ok(calibrate_tree(start, set.unwrap_or(self.cal), val, &o, false)?.into())
    }

    /// Cross-validated mean error norm (mm) with `extra`: folds of every
    /// [`TREE_CV_FOLDS`]-th pose, each predicted by the fit on the others (from the nominal
    /// tree).
    pub fn cv_mean_mm(&self, extra: &[String]) -> Result<f64, CalibError> {
        let key = extra.to_vec();
        if let Some(v) = self.cv_cache.lock().ok().and_then(|c| c.get(&key).copied()) {
            return Ok(v);
        }
        let n = self.cal.len();
        let folds: Vec<usize> = (0..TREE_CV_FOLDS).collect();
        let per_fold = map_ordered(&folds, |&f| {
            let (test, train): (Vec<usize>, Vec<usize>) =
                (0..n).partition(|k| k % TREE_CV_FOLDS == f);
            if test.is_empty() {
                return Ok(Vec::new());
            }
            let t = self.fit(self.nominal, Some(&self.cal.subset(&train)), None, extra)?;
            tree_errors(&t.outcome.fit.model, &self.cal.subset(&test))
        });
        let mut errors = Vec::new();
        for e in per_fold {
            errors.extend(e?);
        }
        let v = Stats::from_errors(&errors).mean_mm;
        if let Ok(mut c) = self.cv_cache.lock() {
            c.insert(key, v);
        }
        Ok(v)
    }
}

/// The outcome of the selection: the accepted candidates in order and, for each, the candidates
/// its swap scan found equivalent.
pub struct Selected {
    pub accepted: Vec<Candidate>,
    pub equivalent: Vec<Vec<String>>,
    /// Swaps made (`a` replaced by `b`), in order.
    pub swaps: Vec<(String, String)>,
}

/// Forward steps and swaps over `all` (see the module doc); `current` is the declared fit and
/// `alpha` the F-test's level.
pub fn select(
    fits: &Fits,
    all: &[Candidate],
    current: Trial,
    alpha: f64,
) -> Result<Selected, CalibError> {
    let mut current = current;
    let mut accepted: Vec<Candidate> = Vec::new();
    let mut swaps = Vec::new();
    let mut equivalent = Vec::new();
    let mut settled = false;
    for _ in 0..MAX_SWAP_ROUNDS {
        current = forward(fits, all, &mut accepted, current, alpha)?;
        let (next, swap, eq) = swap_once(fits, all, &accepted, &current)?;
        equivalent = eq;
        match (next, swap) {
            (Some(t), Some((a, c))) => {
                swaps.push((accepted[a].id.clone(), all[c].id.clone()));
                accepted[a] = all[c].clone();
                current = t;
            }
            _ => {
                settled = true;
                break;
            }
        }
    }
    if !settled {
        // the rounds ended on a swap: the equivalents are those of the set after it
        equivalent = swap_once(fits, all, &accepted, &current)?.2;
    }
    Ok(Selected {
        accepted,
        equivalent,
        swaps,
    })
}

/// The parameters of `set`.
fn params(set: &[Candidate]) -> Vec<String> {
    set.iter().map(|c| c.param.clone()).collect()
}

/// Whether a trial freed every parameter asked, beyond the current fit's count.
fn frees(t: &Trial, extra: &[String], current: &Trial, added: usize) -> bool {
    t.n_fitted == current.n_fitted + added && extra.iter().all(|p| t.outcome.fit.fitted.contains(p))
}

/// Forward steps from `current` until no candidate passes the F-test, the BIC and the
/// cross-validation; returns the last accepted fit.
fn forward(
    fits: &Fits,
    all: &[Candidate],
    accepted: &mut Vec<Candidate>,
    mut current: Trial,
    alpha: f64,
) -> Result<Trial, CalibError> {
    loop {
        let base = params(accepted);
        let left: Vec<usize> = (0..all.len())
            .filter(|&i| !accepted.contains(&all[i]))
            .collect();
        let start = &current.outcome.fit.model;
        let trials = map_ordered(&left, |&i| {
            let mut e = base.clone();
            e.push(all[i].param.clone());
            // a candidate the tree's fit refuses or cannot identify is no candidate here
            fits.fit(start, None, None, &e)
                .ok()
                .filter(|t| frees(t, &e, &current, 1))
        });
        let Some((k, t)) = trials
            .into_iter()
            .enumerate()
            .filter_map(|(k, t)| t.map(|t| (k, t)))
            .min_by(|a, b| a.1.rss_mm2.total_cmp(&b.1.rss_mm2))
        else {
            return Ok(current);
        };
        let dof = t.m.saturating_sub(t.n_fitted);
        let (_, p) = nested_f_test(current.rss_mm2, t.rss_mm2, 1, dof);
        let dbic = delta_bic(t.m, current.rss_mm2, t.rss_mm2, 1);
        if !(p < alpha && dbic < 0.0) {
            return Ok(current);
        }
        let mut e = base.clone();
        e.push(all[left[k]].param.clone());
        if fits.cv_mean_mm(&e)? >= fits.cv_mean_mm(&base)? {
            return Ok(current);
        }
        accepted.push(all[left[k]].clone());
        current = t;
    }
}

/// One swap scan: every accepted effect against the candidates of its neighbourhood not
/// accepted. Returns the fit
/// and the swap (accepted index, candidate index) that lowers the residual most, if any does,
/// and per accepted effect the candidates whose swap leaves the residual within
/// [`EQUIVALENT_RSS_VARIANCES`] residual variances.
#[allow(clippy::type_complexity)]
fn swap_once(
    fits: &Fits,
    all: &[Candidate],
    accepted: &[Candidate],
    current: &Trial,
) -> Result<(Option<Trial>, Option<(usize, usize)>, Vec<Vec<String>>), CalibError> {
    let left: Vec<usize> = (0..all.len())
        .filter(|&i| !accepted.contains(&all[i]))
        .collect();
    let pairs: Vec<(usize, usize)> = (0..accepted.len())
        .flat_map(|a| left.iter().map(move |&c| (a, c)))
        .filter(|&(a, c)| neighbours(fits.nominal, &accepted[a], &all[c]))
        .collect();
    let trials = map_ordered(&pairs, |&(a, c)| {
        let mut start = current.outcome.fit.model.clone();
        let back = fits.nominal.param(&accepted[a].param).unwrap_or(0.0);
        start.set_param(&accepted[a].param, back).ok()?;
        let mut e = params(accepted);
        e[a] = all[c].param.clone();
        fits.fit(&start, None, None, &e)
            .ok()
            .filter(|t| frees(t, &e, current, 0))
    });
    let s2 = current.rss_mm2 / current.m.saturating_sub(current.n_fitted).max(1) as f64;
    let mut equivalent = vec![Vec::new(); accepted.len()];
    let mut best: Option<(usize, f64)> = None;
    for (k, t) in trials.iter().enumerate() {
        let Some(t) = t else { continue };
        let (a, c) = pairs[k];
        if t.rss_mm2 - current.rss_mm2 < EQUIVALENT_RSS_VARIANCES * s2 {
            equivalent[a].push(all[c].id.clone());
        }
        // a swap must lower the residual by more than rounding
        if t.rss_mm2 < current.rss_mm2 * (1.0 - 1e-9) && best.is_none_or(|(_, r)| t.rss_mm2 < r) {
            best = Some((k, t.rss_mm2));
        }
    }
    let Some((k, _)) = best else {
        return Ok((None, None, equivalent));
    };
    let mut trials = trials;
    Ok((trials[k].take(), Some(pairs[k]), equivalent))
}

/// The accepted set in the order a forward selection among them alone takes: at each step the
/// one whose addition lowers the residual most (the report's steps then read in order of
/// importance, each significant where the set is).
pub fn replay_order(
    fits: &Fits,
    accepted: &[Candidate],
    declared: &Trial,
) -> Result<Vec<Candidate>, CalibError> {
    let mut order: Vec<Candidate> = Vec::new();
    let mut left: Vec<Candidate> = accepted.to_vec();
    let mut start = declared.outcome.fit.model.clone();
    while !left.is_empty() {
        let base = params(&order);
        let rss = map_ordered(&left, |c| {
            let mut e = base.clone();
            e.push(c.param.clone());
            fits.fit(&start, None, None, &e)
                .map(|t| (t.rss_mm2, t.outcome.fit.model))
        });
        let mut best: Option<(usize, f64, Tree)> = None;
        for (k, r) in rss.into_iter().enumerate() {
            let (r, m) = r?;
            if best.as_ref().is_none_or(|b| r < b.1) {
                best = Some((k, r, m));
            }
        }
        let Some((k, _, m)) = best else { break };
        order.push(left.remove(k));
        start = m;
    }
    Ok(order)
}
