//! The greedy forward selection itself ([`forward_selection`]), in named steps: screen and rank
//! the library ([`shortlist`]), refit the shortlist ([`refit_candidate`], on both cores), order
//! near ties by cross-validation ([`order_contenders`]) and test in that order
//! ([`test_in_order`]). The rule is documented in [`super::decide`].

use super::candidates::{library, Candidate};
use super::changes::{open_slots, refine, refine_all, slot_of};
use super::decide::{
    cv_errors, linear_start, nonlinear_start, onset_candidates, paired_gain, rank_contenders,
    serial_tau, Accepted, DecideConfig, Selection, Trial,
};
use super::extended::{fit, ExtModel, ExtendedFit, Unknown, Values};
use super::parallel::map_ordered;
use super::polish::{needs_polish, polish};
use super::residual::screen;
use super::stat::{delta_bic, nested_f_test};
use crate::calib::fit::Fit;
use crate::calib::CalibError;
use crate::calib::MeasuredSet;
use crate::model::effect::bound_declared;
use crate::model::Model;

/// Most moves of a change's time from the split the linear scan found ([`refine`]).
const REFINE_MAX_MOVES: usize = 3;

/// Independent residuals: all of them for full positions, fewer along a traced path.
pub(super) fn m_eff(data: &MeasuredSet, tau: f64) -> usize {
    ((data.n_residuals() as f64 / tau).round() as usize).max(1)
}

/// Greedy forward selection from the declared fit `declared` (its requested unknowns
/// `declared_unknowns`) on `data`. See the [`super::decide`] module documentation.
pub fn forward_selection(
    declared: Fit<ExtModel, Unknown>,
    declared_unknowns: &[Unknown],
    data: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<Selection, CalibError> {
    forward_selection_among(declared, declared_unknowns, data, cfg, None)
}

/// [`forward_selection`] over the library's effects whose ids are in `among` (all when `None`).
pub fn forward_selection_among(
    declared: Fit<ExtModel, Unknown>,
    declared_unknowns: &[Unknown],
    data: &MeasuredSet,
    cfg: &DecideConfig,
    among: Option<&[String]>,
) -> Result<Selection, CalibError> {
    let mut cur = declared;
    let mut requested: Vec<Unknown> = declared_unknowns.to_vec();
    let mut steps: Vec<Accepted> = Vec::new();
    let mut last_trials = Vec::new();
    // The cross-validated errors of the current fit: those of the accepted candidate's refit
    // (the same unknowns from the same values on the same folds), computed once.
    let mut cv_cur: Option<Vec<f64>> = None;
    while steps.len() < cfg.max_effects {
        // changes within the session: a slot at the best split of each kind that shows one
        let opened = open_slots(&mut cur, &requested, data, cfg.alpha)?;
        let mut cands = library(&cur.model, &requested, data);
        cands.retain(|c| !c.effect.is_change() || opened.contains(&c.effect));
        if let Some(ids) = among {
            cands.retain(|c| ids.contains(&c.id));
        }
        if cands.is_empty() {
            break;
        }
        // the onset ladder looks for the first effect on the loads; once one is in the model
        // the sign steps sit where it put them, and a second load effect moved by the ladder
        // only re-places a few of them (a stand-in for the first one's exact value)
        let ladder = !steps
            .iter()
            .any(|s| s.trial.candidate.effect.row().kind.changes_loads());
        let shortlisted = shortlist(&cur, &cands, data, cfg, ladder)?;
        let refitted: Vec<Option<(Trial, Fit<ExtModel, Unknown>)>> =
            map_ordered(&shortlisted, |&ci| {
                refit_candidate(&cur, &requested, &cands[ci], data, cfg)
            })
            .into_iter()
            .collect::<Result<_, _>>()?;
        let mut refits: Vec<(Trial, Fit<ExtModel, Unknown>)> =
            refitted.into_iter().flatten().collect();
        refits.sort_by(|a, b| a.0.delta_bic.total_cmp(&b.0.delta_bic));
        let (refits, cv_cache, equivalent_ids) = order_contenders(refits, data, cfg)?;
        let round = test_in_order(refits, cv_cache, &cur, cv_cur.take(), data, cfg)?;
        match round.chosen {
            Some((trial, mut after, cv_after)) => {
                requested.extend(trial.candidate.unknowns.iter().copied());
                // the times of the changes accepted earlier, at the new values
                let own = trial.candidate.unknowns.first().copied().and_then(slot_of);
                let moved = refine_all(&mut after, own, data, &cfg.lm, cfg.rtol, REFINE_MAX_MOVES)?;
                let before = std::mem::replace(&mut cur, after.clone());
                cv_cur = (!moved).then_some(cv_after);
                let equivalent = if equivalent_ids.contains(&trial.candidate.id) {
                    equivalent_ids
                        .iter()
                        .filter(|i| **i != trial.candidate.id)
                        .cloned()
                        .collect()
                } else {
                    Vec::new()
                };
                steps.push(Accepted {
                    trial,
                    before,
                    after,
                    equivalent,
                });
            }
            None => {
                last_trials = round.trials;
                break;
            }
        }
    }
    Ok(Selection {
        steps,
        last_trials,
        last: cur,
        requested,
        simpler: None,
    })
}

/// Step 1: the candidates to refit, by index into `cands`: the [`DecideConfig::refit_top`] best
/// by the linearised change of BIC (only those that lower it), then every candidate whose small
/// move flips a sign of the joint moments ([`onset_candidates`]; with `ladder`, the larger moves
/// of the effects on the loads too).
pub fn shortlist(
    cur: &Fit<ExtModel, Unknown>,
    cands: &[Candidate],
    data: &MeasuredSet,
    cfg: &DecideConfig,
    ladder: bool,
) -> Result<Vec<usize>, CalibError> {
    let screens = screen(&cur.model, data, &cur.fitted, cands, cfg.rtol)?;
    let rss0 = cur.rss_mm2;
    let m = m_eff(data, serial_tau(&cur.model, data)?);
    let mut ranked: Vec<(usize, f64)> = screens
        .iter()
        .filter(|s| s.added > 0)
        .map(|s| {
            (
                s.candidate,
                delta_bic(m, rss0, (rss0 - s.delta_rss_mm2).max(rss0 * 1e-12), s.added),
            )
        })
        .filter(|(_, b)| *b < 0.0)
        .collect();
    ranked.sort_by(|a, b| a.1.total_cmp(&b.1));
    ranked.truncate(cfg.refit_top);
    let mut out: Vec<usize> = ranked.into_iter().map(|r| r.0).collect();
    for ci in onset_candidates(&cur.model, cands, data, cfg.onset_probe, ladder)? {
        if !out.contains(&ci) {
            out.push(ci);
        }
    }
    Ok(out)
}

/// Step 2: the full refit of one candidate on top of `cur` and its nested F-test and exact BIC
/// change (`None` when the solver fails).
///
/// Starts: the current values, and (with the tilting law) the linearised least-squares step of
/// all fitted unknowns plus the candidate's, repeated from the best fit while it lowers the RSS
/// by more than 1 %: that reaches effects whose influence is switched on only away from zero
/// (e.g. a base tilt that gives joint 1 a gravity torque and so its backlash) and steps across
/// the sign steps of the tilt law where the solver stops. Without the tilting law the problem is
/// smooth in every unknown and the solver from the current values reaches the same minimum, so
/// there is no restart. The lower RSS wins; a refit stopped at a sign step is polished.
pub fn refit_candidate(
    cur: &Fit<ExtModel, Unknown>,
    requested: &[Unknown],
    cand: &Candidate,
    data: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<Option<(Trial, ExtendedFit)>, CalibError> {
    let mut req = requested.to_vec();
    req.extend(cand.unknowns.iter().copied());
    let mut best: Option<Fit<ExtModel, Unknown>> =
        fit(&cur.model, data, &req, &cfg.lm, cfg.rtol, false).ok();
    // a non-linear unknown (a time constant): the fit also from the best of its start values
    if let Some(start) = nonlinear_start(cur, data, cand) {
        if let Ok(f) = fit(&start, data, &req, &cfg.lm, cfg.rtol, false) {
            if best.as_ref().is_none_or(|b| f.rss_mm2 < b.rss_mm2) {
                best = Some(f);
            }
        }
    }
    let mut from = cur.clone();
    let restarts = if cur.model.tilt { 4 } else { 0 };
    for _ in 0..restarts {
        let Some(start) = linear_start(&from, data, cand) else {
            break;
        };
        let Ok(f2) = fit(&start, data, &req, &cfg.lm, cfg.rtol, false) else {
            break;
        };
        if !best.as_ref().is_none_or(|b| f2.rss_mm2 < 0.99 * b.rss_mm2) {
            break;
        }
        from = f2.clone();
        best = Some(f2);
    }
    let Some(mut after) = best else {
        return Ok(None);
    };
    // a change within the session: its time moved to the split the full refit prefers
    let change = cand.unknowns.first().copied().and_then(slot_of);
    if let Some(slot) = change {
        after = refine(after, slot, data, &cfg.lm, cfg.rtol, REFINE_MAX_MOVES)?;
    }
    if needs_polish(&cur.model, &after, data, cfg.rtol)? {
        after = polish(after, &cur.model, &cand.unknowns, data, cfg)?;
    }
    // the candidate's own values outside their physical bounds: held at the bound, the others
    // refitted, before the tests (a negative compliance is not an explanation)
    let (after, held) = hold_at_bounds(after, &cur.model.model, &req, cand, data, cfg)?;
    let rss0 = cur.rss_mm2;
    let directions = after.fitted.len().saturating_sub(cur.fitted.len());
    // a change's time is fitted too (chosen among the splits): one more parameter in the tests,
    // so that a constant effect is not read as one that changed after the first poses
    let added = directions + usize::from(change.is_some() && directions > 0);
    // the tests count the independent residuals of the refit: under the null hypothesis its
    // residual is the noise, whose serial correlation sets the count
    let m = m_eff(data, serial_tau(&after.model, data)?);
    let dof = m.saturating_sub(cur.fitted.len() + added);
    let (f, p) = nested_f_test(rss0, after.rss_mm2, added, dof);
    let dbic = if added > 0 {
        delta_bic(m, rss0, after.rss_mm2, added)
    } else {
        0.0
    };
    let trial = Trial {
        candidate: cand.clone(),
        added,
        rss_before_mm2: rss0,
        rss_after_mm2: after.rss_mm2,
        f,
        p_value: p,
        delta_bic: dbic,
        cv_mean_mm: [f64::NAN; 2],
        cv_t: f64::NAN,
        accepted: false,
        reason: String::new(),
        held,
    };
    Ok(Some((trial, after)))
}

/// `after` with every unknown of `cand` whose value lies outside its physical bound
/// ([`crate::model::effect::bound_declared`]: a payload as heavy as the one `before` carries is
/// within it) held at the bound and the other unknowns of `requested` refitted; the held values
/// as `name = value` (empty when none was outside).
fn hold_at_bounds(
    after: ExtendedFit,
    before: &Model,
    requested: &[Unknown],
    cand: &Candidate,
    data: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<(ExtendedFit, Vec<String>), CalibError> {
    let model = &after.model.model;
    let outside: Vec<(Unknown, f64, f64)> = cand
        .unknowns
        .iter()
        .filter_map(|&u| {
            let b = bound_declared(u, model, before)?;
            let v = after.model.value(u);
            b.outside(v).map(|hold| (u, v, hold))
        })
        .collect();
    if outside.is_empty() {
        return Ok((after, Vec::new()));
    }
    let mut start = after.model.clone();
    for &(u, _, hold) in &outside {
        start.set_value(u, hold).map_err(CalibError::Model)?;
    }
    let keep: Vec<Unknown> = requested
        .iter()
        .copied()
        .filter(|u| !outside.iter().any(|(o, _, _)| o == u))
        .collect();
    let held = outside
        .iter()
        .map(|&(u, v, hold)| format!("{} = {v:.4} held at {hold}", u.name(model)))
        .collect();
    Ok((fit(&start, data, &keep, &cfg.lm, cfg.rtol, false)?, held))
}

/// Whether a refit passes the F-test and lowers the BIC.
fn passes(t: &Trial, cfg: &DecideConfig) -> bool {
    t.added > 0 && t.p_value < cfg.alpha && t.delta_bic < 0.0
}

/// The refits, in exact-BIC order, with their cross-validated errors when computed, and the ids
/// of the near ties that are equivalent on these poses.
type Ordered = (
    Vec<(Trial, Fit<ExtModel, Unknown>)>,
    Vec<Option<Vec<f64>>>,
    Vec<String>,
);

/// Step 3: near ties first. The refits that pass and lie within [`DecideConfig::bic_tie`] of the
/// best exact BIC are ranked by their cross-validated errors ([`rank_contenders`]: the simplest
/// of the equivalent ones first), the rest follow in BIC order. The known floor (if any) does
/// not relax the rule: on the UR5 tracker data, accepting every significant cross-validated
/// gain above the floor added effects that made the held-out error worse (0.0886 -> 0.0951 mm).
pub fn order_contenders(
    refits: Vec<(Trial, Fit<ExtModel, Unknown>)>,
    data: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<Ordered, CalibError> {
    let n = refits.len();
    let contenders: Vec<usize> = match refits.iter().map(|r| &r.0).find(|t| passes(t, cfg)) {
        Some(best) => (0..n)
            .filter(|&i| {
                passes(&refits[i].0, cfg) && refits[i].0.delta_bic <= best.delta_bic + cfg.bic_tie
            })
            .collect(),
        None => Vec::new(),
    };
    if contenders.len() <= 1 {
        return Ok((refits, vec![None; n], Vec::new()));
    }
    let errs: Vec<Vec<f64>> = contenders
        .iter()
        .map(|&i| cv_errors(&refits[i].1, data, cfg))
        .collect::<Result<_, _>>()?;
    let (ranked, eq) = rank_contenders(
        &contenders,
        &errs,
        |i| &refits[i].0.candidate,
        cfg,
        data.is_serial(),
    );
    let equivalent_ids: Vec<String> = if eq.len() > 1 {
        eq.iter()
            .map(|&i| refits[i].0.candidate.id.clone())
            .collect()
    } else {
        Vec::new()
    };
    let mut caches: Vec<Option<Vec<f64>>> = vec![None; n];
    for (&i, e) in contenders.iter().zip(errs) {
        caches[i] = Some(e);
    }
    let order: Vec<usize> = ranked
        .into_iter()
        .chain((0..n).filter(|i| !contenders.contains(i)))
        .collect();
    let mut slots: Vec<Option<(Trial, Fit<ExtModel, Unknown>)>> =
        refits.into_iter().map(Some).collect();
    let (mut out, mut cv) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for i in order {
        if let Some(r) = slots[i].take() {
            out.push(r);
            cv.push(caches[i].take());
        }
    }
    Ok((out, cv, equivalent_ids))
}

/// The outcome of one round: the accepted candidate (its trial, fit and cross-validated
/// errors), and every trial with its reason.
pub struct Round {
    /// The accepted candidate, if any.
    pub chosen: Option<(Trial, Fit<ExtModel, Unknown>, Vec<f64>)>,
    /// The trials of the round (the accepted one excluded).
    pub trials: Vec<Trial>,
}

/// Step 4: the tests in order; the first candidate that passes the F-test, the BIC and the
/// cross-validated gain is accepted, the rest are "not tested". `cv_cur` are the current fit's
/// cross-validated errors when known.
pub fn test_in_order(
    refits: Vec<(Trial, Fit<ExtModel, Unknown>)>,
    cv_cache: Vec<Option<Vec<f64>>>,
    cur: &Fit<ExtModel, Unknown>,
    mut cv_cur: Option<Vec<f64>>,
    data: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<Round, CalibError> {
    let mut chosen: Option<(Trial, Fit<ExtModel, Unknown>, Vec<f64>)> = None;
    let mut trials = Vec::new();
    for ((mut trial, after), cached) in refits.into_iter().zip(cv_cache) {
        if chosen.is_some() {
            trial.reason = "not tested: an earlier candidate was accepted".into();
            trials.push(trial);
            continue;
        }
        if trial.added == 0 && !trial.held.is_empty() {
            trial.reason = format!(
                "outside its physical bound ({}): held there it adds nothing",
                trial.held.join(", ")
            );
        } else if trial.added == 0 {
            trial.reason = "adds no identifiable direction (aliases fitted parameters)".into();
        } else if !passes(&trial, cfg) {
            trial.reason = format!(
                "F-test p = {:.2e} (needs < {:.0e}) or BIC change {:+.1} (needs < 0)",
                trial.p_value, cfg.alpha, trial.delta_bic
            );
        } else {
            if cv_cur.is_none() {
                cv_cur = Some(cv_errors(cur, data, cfg)?);
            }
            let e0 = cv_cur.as_deref().unwrap_or(&[]);
            let e1 = match cached {
                Some(e1) => e1,
                None => cv_errors(&after, data, cfg)?,
            };
            let (m0, m1, rel, t) = paired_gain(e0, &e1, data.is_serial());
            trial.cv_mean_mm = [m0, m1];
            trial.cv_t = t;
            if rel >= cfg.cv_min_gain && rel > 0.0 && t >= cfg.cv_t_min {
                trial.accepted = true;
                chosen = Some((trial, after, e1));
                continue;
            }
            trial.reason = format!(
                "cross-validation: mean {m0:.4} -> {m1:.4} mm ({:+.1} %, t = {t:.2}; needs >= {:.0} % and t >= {:.2})",
                -100.0 * rel,
                100.0 * cfg.cv_min_gain,
                cfg.cv_t_min
            );
        }
        trials.push(trial);
    }
    Ok(Round { chosen, trials })
}
