//! Changes within a session (effects `tool_change`, `payload_change`, [`crate::model::changes`]):
//! where in time a step explains most of the residual.
//!
//! A step at `t_s` adds columns `S X` to the fit: `X` the regressors of the change at every pose
//! (the tool point's columns in the last frame, or the payload's), `S` the indicator of the poses
//! at `t >= t_s`. Any `t_s` between two consecutive distinct pose times gives the same
//! prediction, so the time is found exactly over the `D - 1` splits of the `D` distinct times
//! ([`scan`]): for each split, what the step's columns explain of the residual `e` once the
//! fitted unknowns re-adjust (their columns `L` projected out: `Q` an orthonormal basis of `L`),
//!
//! ```text
//! gain(s) = b^T A^+ b,   b = X_s^T e - (Q^T X_s)^T Q^T e,   A = X_s^T X_s - (Q^T X_s)^T (Q^T X_s)
//! ```
//!
//! with every sum over the poses after the split accumulated once from the last pose back
//! (`O(N r c)` for all splits). The time reported is the midpoint of the split's two pose times
//! (the data place it nowhere closer), and a kind is offered only when its best split's F
//! statistic passes the selection's level after a Bonferroni correction over the splits tried.
//! The full refit of the candidate then moves the split to a neighbour while that lowers the
//! refitted residual ([`refine`]): the exact search where the law is not linear (a payload's
//! moments through the tilting).

use nalgebra::{DMatrix, DVector};

use super::extended::{fit, ExtModel, Unknown, Values};
use super::stat::f_test_p_value;
use crate::calib::fit::Fit;
use crate::calib::lm::LmConfig;
use crate::calib::{CalibError, MeasuredSet};
use crate::model::changes::{Step, StepKind};
use crate::model::effect::{self, EffectId, Offers};

/// The fewest distinct pose times on either side of a change: at least 3 and 5 % of them. A
/// change with one or two poses on a side is the constant effect with those poses off (a
/// constant payload read as one picked up after the first pose), which nothing else tells apart.
pub fn min_side(n_times: usize) -> usize {
    MIN_SIDE_TIMES.max((MIN_SIDE_SHARE * n_times as f64).ceil() as usize)
}

/// See [`min_side`].
const MIN_SIDE_TIMES: usize = 3;
/// See [`min_side`].
const MIN_SIDE_SHARE: f64 = 0.05;

/// The best split of the poses by time for a step of given regressors.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ChangePoint {
    /// The change time: the midpoint of the split's two pose times, s.
    pub t_s: f64,
    /// The last pose time before the split, s.
    pub last_before_s: f64,
    /// The first pose time after it, s.
    pub first_after_s: f64,
    /// What the step explains of the residual's sum of squares, mm^2.
    pub gain_mm2: f64,
    /// The residual's sum of squares (fitted columns projected out), mm^2.
    pub rss_mm2: f64,
    /// Independent directions the step adds.
    pub added: usize,
    /// The F-test's p value times the number of splits tried (Bonferroni; at most 1).
    pub p_value: f64,
    /// The number of splits tried.
    pub splits: usize,
}

/// First row of each pose in the stacked rows of `data`.
fn row_offsets(data: &MeasuredSet) -> Vec<usize> {
    let mut off = Vec::with_capacity(data.len() + 1);
    let mut r = 0;
    for k in 0..data.len() {
        off.push(r);
        r += data.rows(k);
    }
    off.push(r);
    off
}

/// `b^T A^+ b` and the rank of `A` (symmetric, pseudo-inverse by eigen-decomposition).
fn explained(a: &DMatrix<f64>, b: &DVector<f64>) -> (f64, usize) {
    let eig = a.clone().symmetric_eigen();
    let lmax = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
    let (mut g, mut rank) = (0.0, 0);
    for (i, &l) in eig.eigenvalues.iter().enumerate() {
        if lmax > 0.0 && l > 1e-9 * lmax {
            let proj = eig.eigenvectors.column(i).dot(b);
            g += proj * proj / l;
            rank += 1;
        }
    }
    (g, rank)
}

/// The best split by time of the residual `e` (stacked over `data`'s measured components) for a
/// step of the regressors `x` (same rows, one column per unknown of the step), with the fitted
/// columns' orthonormal basis `q` projected out. `None` with fewer than two distinct times.
pub fn scan(
    data: &MeasuredSet,
    x: &DMatrix<f64>,
    q: &DMatrix<f64>,
    e: &DVector<f64>,
) -> Option<ChangePoint> {
    let off = row_offsets(data);
    let (c, r) = (x.ncols(), q.ncols());
    let mut order: Vec<usize> = (0..data.len()).collect();
    order.sort_by(|&a, &b| data.t(a).total_cmp(&data.t(b)).then(a.cmp(&b)));
    // the groups of poses with one time, in time order
    let mut groups: Vec<(f64, Vec<usize>)> = Vec::new();
    for &k in &order {
        match groups.last_mut() {
            Some((t, ks)) if *t == data.t(k) => ks.push(k),
            _ => groups.push((data.t(k), vec![k])),
        }
    }
    let side = min_side(groups.len());
    let splits = (groups.len() + 1)
        .checked_sub(2 * side)
        .filter(|&s| s > 0)?;
    let qte_all = q.transpose() * e;
    let rss = (e.norm_squared() - qte_all.norm_squared()).max(0.0);
    let m = e.len();
    let (mut c1, mut c2) = (DMatrix::zeros(c, c), DMatrix::zeros(r, c));
    let mut c3 = DVector::zeros(c);
    let mut best: Option<ChangePoint> = None;
    for g in (side..groups.len()).rev() {
        for &k in &groups[g].1 {
            let (a, n) = (off[k], off[k + 1] - off[k]);
            let xk = x.rows(a, n);
            let qk = q.rows(a, n);
            let ek = e.rows(a, n);
            c1 += xk.transpose() * xk;
            c2 += qk.transpose() * xk;
            c3 += xk.transpose() * ek;
        }
        if groups.len() - g < side {
            continue;
        }
        // the step's columns and the residual both projected off the fitted columns: `Q^T e`
        // over every pose (the step's columns are zero before the split, the residual is not)
        let b = &c3 - c2.transpose() * &qte_all;
        let a = &c1 - c2.transpose() * &c2;
        let (gain, added) = explained(&a, &b);
        if added == 0 || best.as_ref().is_some_and(|bst| bst.gain_mm2 >= gain) {
            continue;
        }
        let dof = m.saturating_sub(r + added);
        let p = if dof == 0 || rss <= gain {
            0.0
        } else {
            let f = (gain / added as f64) / ((rss - gain) / dof as f64);
            f_test_p_value(f, added as f64, dof as f64)
        };
        let (before, after) = (groups[g - 1].0, groups[g].0);
        best = Some(ChangePoint {
            t_s: 0.5 * (before + after),
            last_before_s: before,
            first_after_s: after,
            gain_mm2: gain,
            rss_mm2: rss,
            added,
            p_value: (p * splits as f64).min(1.0),
            splits,
        });
    }
    best
}

/// The change kinds the effect table offers on `ext` with `data`'s times.
pub fn change_kinds(ext: &ExtModel, data: &MeasuredSet) -> Vec<EffectId> {
    let offers = Offers {
        approach: data.has_approach(),
        time: data.has_time(),
    };
    effect::library(&ext.model, offers)
        .into_iter()
        .filter(EffectId::is_change)
        .collect()
}

/// A step of `effect`'s kind with no size at `t_s`.
fn empty_step(effect: &EffectId, t_s: f64) -> Option<Step> {
    let kind = match effect {
        EffectId::ToolChange => StepKind::Tool(nalgebra::Vector3::zeros()),
        EffectId::PayloadChange => StepKind::Payload(0.0),
        _ => return None,
    };
    Some(Step { t_s, kind })
}

/// The best split for a change `effect` on the fit `cur`: the residual and the fitted columns
/// at `cur`, the step's regressors at every pose.
pub fn scan_change(
    cur: &Fit<ExtModel, Unknown>,
    effect: &EffectId,
    data: &MeasuredSet,
) -> Result<Option<ChangePoint>, CalibError> {
    let mut ext = cur.model.clone();
    let Some(step) = empty_step(effect, f64::NEG_INFINITY) else {
        return Ok(None);
    };
    ext.model.time_terms_mut().changes.push(step);
    let step_unknowns: Vec<Unknown> = effect.unknowns(&ext.model).into_iter().flatten().collect();
    scan_steps(&cur.fitted, &ext, &step_unknowns, data)
}

/// The best split for a step in the unknowns `step` of `ext` (a fit's state with the step's
/// slot open, no size), with the fit's unknowns `fitted` projected out; `None` without a step
/// unknown.
fn scan_steps(
    fitted: &[Unknown],
    ext: &ExtModel,
    step: &[Unknown],
    data: &MeasuredSet,
) -> Result<Option<ChangePoint>, CalibError> {
    if step.is_empty() {
        return Ok(None);
    }
    let mut all = fitted.to_vec();
    all.extend(step.iter().copied());
    let (jac, e) = ext.stacked(data, &all)?;
    let p = fitted.len();
    let l = jac.columns(0, p).into_owned();
    let x = jac.columns(p, step.len()).into_owned();
    Ok(scan(
        data,
        &x,
        &super::residual::column_basis(&l, 1e-10),
        &e,
    ))
}

/// Opens a change slot of each kind whose best split on `cur` passes `alpha` (Bonferroni over
/// the splits), at that split's time: the last slot of its kind when it is not yet `requested`
/// (an earlier round's that was not accepted), otherwise a new one. Returns the kinds opened,
/// for the library to offer; the slots have no size, so `cur`'s predictions do not change.
pub fn open_slots(
    cur: &mut Fit<ExtModel, Unknown>,
    requested: &[Unknown],
    data: &MeasuredSet,
    alpha: f64,
) -> Result<Vec<EffectId>, CalibError> {
    let mut opened = Vec::new();
    // samples along a traced path are serially correlated: the scan's test assumes independent
    // residuals, and a step at the path's start is the constant effect itself
    if !data.has_time() || data.is_serial() {
        return Ok(opened);
    }
    for effect in change_kinds(&cur.model, data) {
        let Some(cp) = scan_change(cur, &effect, data)? else {
            continue;
        };
        if cp.p_value >= alpha {
            continue;
        }
        // the kind's last slot, when no accepted effect sizes it
        let last = effect.unknowns(&cur.model.model);
        let open_slot = match last.first().copied().flatten().and_then(slot_of) {
            Some(s) if last.iter().flatten().all(|u| !requested.contains(u)) => Some(s),
            _ => None,
        };
        let changes = &mut cur.model.model.time_terms_mut().changes;
        match open_slot.and_then(|s| changes.get_mut(s)) {
            Some(step) => step.t_s = cp.t_s,
            None => changes.extend(empty_step(&effect, cp.t_s)),
        }
        opened.push(effect);
    }
    Ok(opened)
}

/// The probe's change-point scan of the final residual of `last` ([`super::probe`]): a step at
/// one time of a constant in the measurement frame (the columns of `base_x/y/z`) and of an
/// offset in the last link frame (a tool point, marker or instrument frame that moved), with
/// the fitted unknowns projected out. `Some` when the best split passes `alpha` after the
/// Bonferroni correction over the splits: "something changed at t = ..." even where no
/// candidate describes the change.
pub fn residual_change_point(
    last: &Fit<ExtModel, Unknown>,
    data: &MeasuredSet,
    alpha: f64,
) -> Result<Option<ChangePoint>, CalibError> {
    if !data.has_time() || data.is_serial() {
        return Ok(None);
    }
    let mut ext = last.model.clone();
    let mut step_unknowns: Vec<Unknown> = ["base_x", "base_y", "base_z"]
        .iter()
        .filter_map(|n| ext.model.param_index(n).map(Unknown::Param))
        .collect();
    if let Some(step) = empty_step(&EffectId::ToolChange, f64::NEG_INFINITY) {
        ext.model.time_terms_mut().changes.push(step);
        step_unknowns.extend(
            EffectId::ToolChange
                .unknowns(&ext.model)
                .into_iter()
                .flatten(),
        );
    }
    Ok(scan_steps(&last.fitted, &ext, &step_unknowns, data)?.filter(|cp| cp.p_value < alpha))
}

impl ChangePoint {
    /// The sentence of the probe's note.
    pub fn sentence(&self) -> String {
        format!(
            "something changed at t = {:.1} s (between the poses at {:.1} and {:.1} s): a step \
             there (a constant in the measurement frame and an offset in the last link frame) \
             explains {:.0} % of the residual (p = {:.1e} after {} splits tried)",
            self.t_s,
            self.last_before_s,
            self.first_after_s,
            100.0 * self.gain_mm2 / self.rss_mm2.max(f64::MIN_POSITIVE),
            self.p_value,
            self.splits
        )
    }
}

/// The change slot an unknown sizes.
pub fn slot_of(u: Unknown) -> Option<usize> {
    match u {
        Unknown::ToolStep { slot, .. } | Unknown::PayloadStep(slot) => Some(slot),
        _ => None,
    }
}

/// The distinct pose times of `data`, in order.
fn distinct_times(data: &MeasuredSet) -> Vec<f64> {
    let mut t: Vec<f64> = (0..data.len()).map(|k| data.t(k)).collect();
    t.sort_by(f64::total_cmp);
    t.dedup();
    t
}

/// The best split for the change `slot` of `fit` at the other fitted values: the residual with
/// that change's size set to zero, its columns at every pose, the other fitted unknowns'
/// columns projected out.
fn rescan_slot(
    f: &Fit<ExtModel, Unknown>,
    slot: usize,
    data: &MeasuredSet,
) -> Result<Option<ChangePoint>, CalibError> {
    let mut ext = f.model.clone();
    let (own, others): (Vec<Unknown>, Vec<Unknown>) =
        f.fitted.iter().partition(|u| slot_of(**u) == Some(slot));
    if own.is_empty() {
        return Ok(None);
    }
    for u in &own {
        ext.set_value(*u, 0.0)?;
    }
    match ext.model.time_terms_mut().changes.get_mut(slot) {
        Some(step) => step.t_s = f64::NEG_INFINITY,
        None => return Ok(None),
    }
    scan_steps(&others, &ext, &own, data)
}

/// Most re-scans of a change's time at the refitted values ([`refine`]).
const RESCANS: usize = 4;

/// Refines the time of change `slot` of `after`: the split re-scanned at the refitted values of
/// the other unknowns and the fit redone there, while the split moves and the residual drops
/// (at most [`RESCANS`] times); then the neighbouring splits of the pose times while the refit
/// (every unknown of `after` from its values) lowers the residual, at most `max_moves` moves.
/// The fit with the lowest residual.
pub fn refine(
    after: Fit<ExtModel, Unknown>,
    slot: usize,
    data: &MeasuredSet,
    lm: &LmConfig,
    rtol: f64,
    max_moves: usize,
) -> Result<Fit<ExtModel, Unknown>, CalibError> {
    let unknowns = after.fitted.clone();
    let refit_at = |from: &Fit<ExtModel, Unknown>, t_s: f64| -> Option<Fit<ExtModel, Unknown>> {
        let mut start = from.model.clone();
        start.model.time_terms_mut().changes.get_mut(slot)?.t_s = t_s;
        fit(&start, data, &unknowns, lm, rtol, true)
            .ok()
            .filter(|f| f.rss_mm2.is_finite())
    };
    let mut best = after;
    for _ in 0..RESCANS {
        let Some(t0) = best.model.model.steps().get(slot).map(|s| s.t_s) else {
            return Ok(best);
        };
        let Some(cp) = rescan_slot(&best, slot, data)? else {
            break;
        };
        if cp.t_s == t0 {
            break;
        }
        match refit_at(&best, cp.t_s) {
            Some(f) if f.rss_mm2 < best.rss_mm2 => best = f,
            _ => break,
        }
    }
    let times = distinct_times(data);
    let Some(t0) = best.model.model.steps().get(slot).map(|s| s.t_s) else {
        return Ok(best);
    };
    // the split index i: between times[i] and times[i + 1]
    let Some(i0) =
        (0..times.len().saturating_sub(1)).find(|&i| times[i] < t0 && t0 <= times[i + 1])
    else {
        return Ok(best);
    };
    let mut i = i0;
    for dir in [-1i64, 1] {
        let mut moves = 0;
        loop {
            let j = i as i64 + dir;
            // split j leaves j + 1 times before it and times.len() - j - 1 after
            let side = min_side(times.len());
            if j + 1 < side as i64
                || (times.len() as i64) - j - 1 < side as i64
                || moves >= max_moves
            {
                break;
            }
            let j = j as usize;
            match refit_at(&best, 0.5 * (times[j] + times[j + 1])) {
                Some(f) if f.rss_mm2 < best.rss_mm2 => {
                    best = f;
                    i = j;
                    moves += 1;
                }
                _ => break,
            }
        }
    }
    Ok(best)
}

/// Refines the time of every change `cur` sizes except `skip` ([`refine`]) at `cur`'s values:
/// after another effect is accepted an earlier change's best time may move. Whether any moved.
pub fn refine_all(
    cur: &mut Fit<ExtModel, Unknown>,
    skip: Option<usize>,
    data: &MeasuredSet,
    lm: &LmConfig,
    rtol: f64,
    max_moves: usize,
) -> Result<bool, CalibError> {
    let mut slots: Vec<usize> = cur.fitted.iter().filter_map(|u| slot_of(*u)).collect();
    slots.sort_unstable();
    slots.dedup();
    let mut moved = false;
    for slot in slots.into_iter().filter(|s| Some(*s) != skip) {
        let before = cur.model.model.steps().get(slot).map(|s| s.t_s);
        let f = refine(cur.clone(), slot, data, lm, rtol, max_moves)?;
        if f.model.model.steps().get(slot).map(|s| s.t_s) != before {
            *cur = f;
            moved = true;
        }
    }
    Ok(moved)
}
