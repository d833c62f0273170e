//! The simplest explanation: a greedy selection can take a stand-in first (a scale for two link
//! lengths that changed together) and then need more effects to mend what the stand-in got
//! wrong. Before a set of several effects is accepted, it is compared with the best single
//! effects and pairs of the library refitted from the declared fit on the same poses; a smaller
//! set that does as well is preferred, and the set it replaces is reported.
//!
//! "Does as well": the larger set would not have been accepted over the smaller one by the
//! selection's own rule (its cross-validated mean error is not lower by
//! [`DecideConfig::cv_min_gain`]; the t statistic is not asked, so that on few poses a much
//! lower error with a weak t still keeps the larger set), and the smaller set's BIC is not
//! higher. Among the sets that do as well, the smallest wins, then the lowest BIC, provided that
//! the same greedy rule restricted to its effects accepts every one of them (its selection is
//! the output: every step passed the same tests as always); otherwise the next one is tried.

use super::candidates::{library, Candidate};
use super::decide::{
    cv_errors, onset_candidates, paired_gain, serial_tau, DecideConfig, Selection, Simpler,
};
use super::extended::{ExtModel, Unknown};
use super::parallel::map_ordered;
use super::residual::{screen, Screen};
use super::select::{forward_selection_among, m_eff, refit_candidate};
use super::stat::delta_bic;
use crate::calib::fit::Fit;
use crate::calib::{CalibError, MeasuredSet};

/// Single effects refitted from the declared fit: the best by the linearised screen.
const SINGLES: usize = 8;

/// The best refitted singles that are paired with each other (and with the greedy set's own
/// effects).
const PAIRED: usize = 5;

/// A single or a pair is refitted only if its linearised fit ([`screen`]: the Gauss-Newton step
/// of its unknowns from the declared fit, or for a pair's second effect from the first one's
/// refit) leaves at most this many times the residual sum of squares at which its BIC would
/// match the greedy set's: for it to do as well otherwise, the linearisation would have to leave
/// 25 % more than the refit (on geometric effects it is within a fraction of a per cent of it;
/// on the UR5 tracker data within 0.1 BIC units). Effects that switch a sign step of the tilting
/// law on, which no linearisation sees, are always refitted.
const LINEAR_RSS_RATIO: f64 = 1.25;

/// The greedy set's BIC (relative to the declared fit's RSS `rss0` on `m` independent residuals):
/// what a smaller set must not exceed.
struct Bar {
    m: usize,
    rss0: f64,
    bic_greedy: f64,
}

impl Bar {
    /// Whether the linearised step `s` from `from` (its RSS lowered by `s.delta_rss_mm2` with
    /// `s.added` more directions) may meet the greedy set's BIC: within [`LINEAR_RSS_RATIO`] of
    /// the residual sum of squares at which it would.
    fn may_match(&self, from: &Fit<ExtModel, Unknown>, s: &Screen) -> bool {
        let rss = (from.rss_mm2 - s.delta_rss_mm2).max(self.rss0 * 1e-12);
        let bic = delta_bic(self.m, self.rss0, rss, from.fitted.len() + s.added);
        bic - self.bic_greedy <= self.m as f64 * LINEAR_RSS_RATIO.ln()
    }
}

/// A smaller set that was refitted and compared.
struct Contender {
    ids: Vec<String>,
    fit: Fit<ExtModel, Unknown>,
}

/// BIC of a fit on `m` independent residuals (up to a constant shared by every fit on the same
/// data): `m ln(RSS) + p ln(m)`, as [`delta_bic`] differences it.
fn bic_from(m: usize, rss0: f64, f: &Fit<ExtModel, Unknown>) -> f64 {
    delta_bic(m, rss0, f.rss_mm2.max(rss0 * 1e-12), f.fitted.len())
}

/// `selection` (greedy, from `declared` with its unknowns `declared_unknowns`), or the
/// selection of a smaller set that does as well (see the module documentation). Selections of
/// fewer than two effects, or with a change within the session, are returned as they are.
pub fn prefer_simplest(
    selection: Selection,
    declared: &Fit<ExtModel, Unknown>,
    declared_unknowns: &[Unknown],
    data: &MeasuredSet,
    cfg: &DecideConfig,
) -> Result<Selection, CalibError> {
    let k = selection.steps.len();
    if k < 2
        || selection
            .steps
            .iter()
            .any(|s| s.trial.candidate.effect.is_change())
    {
        return Ok(selection);
    }
    let greedy_ids: Vec<String> = selection
        .steps
        .iter()
        .map(|s| s.trial.candidate.id.clone())
        .collect();
    let m = m_eff(data, serial_tau(&selection.last.model, data)?);
    let rss0 = declared.rss_mm2.max(f64::MIN_POSITIVE);
    let bic_greedy = bic_from(m, rss0, &selection.last);
    let bar = Bar {
        m,
        rss0,
        bic_greedy,
    };
    let contenders = smaller_sets(declared, declared_unknowns, data, cfg, k, &greedy_ids, &bar)?;
    if contenders.is_empty() {
        return Ok(selection);
    }
    // cheap test first: only the sets the BIC does not rule out are cross-validated
    let mut plausible: Vec<(f64, Contender)> = contenders
        .into_iter()
        .map(|c| (bic_from(m, rss0, &c.fit) - bic_greedy, c))
        .filter(|(d, _)| *d <= 0.0)
        .collect();
    if plausible.is_empty() {
        return Ok(selection);
    }
    plausible.sort_by(|a, b| a.1.ids.len().cmp(&b.1.ids.len()).then(a.0.total_cmp(&b.0)));
    let e_greedy = cv_errors(&selection.last, data, cfg)?;
    let serial = data.is_serial();
    let mut as_well: Vec<(f64, f64, Contender)> = Vec::new();
    for (dbic, c) in plausible {
        let e = cv_errors(&c.fit, data, cfg)?;
        // the greedy set's gain over the smaller one: below the acceptance rule's smallest gain
        // (so the greedy set would not have been accepted over it), whatever the t statistic
        let (m_small, m_greedy, rel, _) = paired_gain(&e, &e_greedy, serial);
        if m_small.is_finite() && m_greedy.is_finite() && rel < cfg.cv_min_gain {
            as_well.push((dbic, m_small, c));
        }
    }
    let cv_greedy = e_greedy.iter().sum::<f64>() / e_greedy.len().max(1) as f64;
    // in order (fewest effects, then BIC): the first whose selection by the same greedy rule on
    // its effects alone accepts every one of them
    for i in 0..as_well.len() {
        let chosen = &as_well[i].2;
        let rebuilt = forward_selection_among(
            declared.clone(),
            declared_unknowns,
            data,
            cfg,
            Some(&chosen.ids),
        )?;
        let mut taken: Vec<String> = rebuilt
            .steps
            .iter()
            .map(|s| s.trial.candidate.id.clone())
            .collect();
        let mut want = chosen.ids.clone();
        taken.sort();
        want.sort();
        if taken != want {
            continue;
        }
        let size = want.len();
        let close: Vec<String> = as_well
            .iter()
            .enumerate()
            .filter(|(j, (_, _, c))| *j != i && c.ids.len() <= size + 1)
            .map(|(_, (_, _, c))| c.ids.join(" + "))
            .collect();
        return Ok(Selection {
            simpler: Some(Simpler {
                greedy: greedy_ids,
                taken: rebuilt
                    .steps
                    .iter()
                    .map(|s| s.trial.candidate.id.clone())
                    .collect(),
                cv_mean_mm: [cv_greedy, as_well[i].1],
                delta_bic: as_well[i].0,
                close,
            }),
            ..rebuilt
        });
    }
    Ok(selection)
}

/// The single effects and pairs (pairs only when the greedy set has at least three) refitted
/// from the declared fit; the greedy set's own effects among the singles.
fn smaller_sets(
    declared: &Fit<ExtModel, Unknown>,
    declared_unknowns: &[Unknown],
    data: &MeasuredSet,
    cfg: &DecideConfig,
    k: usize,
    greedy_ids: &[String],
    bar: &Bar,
) -> Result<Vec<Contender>, CalibError> {
    let mut cands = library(&declared.model, declared_unknowns, data);
    cands.retain(|c| !c.effect.is_change());
    let screens = screen(&declared.model, data, &declared.fitted, &cands, cfg.rtol)?;
    let mut ranked: Vec<(usize, f64)> = screens
        .iter()
        .filter(|s| s.added > 0)
        .map(|s| (s.candidate, -s.delta_rss_mm2))
        .collect();
    ranked.sort_by(|a, b| a.1.total_cmp(&b.1));
    let mut picked: Vec<usize> = ranked.iter().take(SINGLES).map(|r| r.0).collect();
    for (ci, c) in cands.iter().enumerate() {
        if greedy_ids.contains(&c.id) && !picked.contains(&ci) {
            picked.push(ci);
        }
    }
    if !any_may_do_as_well(
        declared,
        data,
        cfg,
        (&cands, &screens),
        (&picked, greedy_ids),
        k,
        bar,
    )? {
        return Ok(Vec::new());
    }
    let singles: Vec<Option<(Candidate, Fit<ExtModel, Unknown>)>> = map_ordered(&picked, |&ci| {
        refit_candidate(declared, declared_unknowns, &cands[ci], data, cfg)
            .map(|r| r.map(|(_, f)| (cands[ci].clone(), f)))
    })
    .into_iter()
    .collect::<Result<_, _>>()?;
    let mut singles: Vec<(Candidate, Fit<ExtModel, Unknown>)> =
        singles.into_iter().flatten().collect();
    singles.sort_by(|a, b| a.1.rss_mm2.total_cmp(&b.1.rss_mm2));
    let mut out: Vec<Contender> = Vec::new();
    if k >= 3 {
        // the best singles and the greedy set's own effects are paired
        let pool: Vec<usize> = (0..singles.len())
            .filter(|&i| i < PAIRED || greedy_ids.contains(&singles[i].0.id))
            .collect();
        // the pairs whose linearised refit from the better single could match the greedy set
        // (or whose second effect switches a sign step on, which no linearisation sees)
        let mut pairs: Vec<(usize, usize)> = Vec::new();
        for (x, &a) in pool.iter().enumerate() {
            let (ca, fa) = &singles[a];
            let mut req = declared_unknowns.to_vec();
            req.extend(ca.unknowns.iter().copied());
            let partners: Vec<(usize, Candidate)> = pool[x + 1..]
                .iter()
                .filter_map(|&b| {
                    Candidate::new(singles[b].0.effect.clone(), &fa.model, &req).map(|c| (b, c))
                })
                .collect();
            let free: Vec<Candidate> = partners.iter().map(|(_, c)| c.clone()).collect();
            let lin = screen(&fa.model, data, &fa.fitted, &free, cfg.rtol)?;
            let onset = onset_candidates(&fa.model, &free, data, cfg.onset_probe, false)?;
            for (i, (b, _)) in partners.iter().enumerate() {
                let s = &lin[i];
                if onset.contains(&i) || bar.may_match(fa, s) {
                    pairs.push((a, *b));
                }
            }
        }
        let fits = map_ordered(&pairs, |&(a, b)| -> Result<Option<Contender>, CalibError> {
            let (ca, fa) = &singles[a];
            let (cb, _) = &singles[b];
            let mut req = declared_unknowns.to_vec();
            req.extend(ca.unknowns.iter().copied());
            let Some(cb_free) = Candidate::new(cb.effect.clone(), &fa.model, &req) else {
                return Ok(None);
            };
            Ok(
                refit_candidate(fa, &req, &cb_free, data, cfg)?.map(|(_, f)| Contender {
                    ids: vec![ca.id.clone(), cb.id.clone()],
                    fit: f,
                }),
            )
        });
        for f in fits {
            out.extend(f?);
        }
    }
    out.extend(singles.into_iter().map(|(c, f)| Contender {
        ids: vec![c.id],
        fit: f,
    }));
    Ok(out)
}

/// Whether any of the singles `picked` (indices into `cands`, screened at the declared fit in
/// `screens`) or, with `k >= 3`, any pair of the best [`PAIRED`] of them by the screen and of
/// the greedy set's own effects (`greedy_ids`) may do as well as the greedy set: its linearised fit from the declared fit
/// meets the BIC bar within [`LINEAR_RSS_RATIO`], or one of them switches a sign step of the
/// tilting law on. When none may, nothing is refitted.
fn any_may_do_as_well(
    declared: &Fit<ExtModel, Unknown>,
    data: &MeasuredSet,
    cfg: &DecideConfig,
    (cands, screens): (&[Candidate], &[Screen]),
    (picked, greedy_ids): (&[usize], &[String]),
    k: usize,
    bar: &Bar,
) -> Result<bool, CalibError> {
    let chosen: Vec<Candidate> = picked.iter().map(|&ci| cands[ci].clone()).collect();
    if !onset_candidates(&declared.model, &chosen, data, cfg.onset_probe, false)?.is_empty() {
        return Ok(true);
    }
    let passes = |s: &Screen| bar.may_match(declared, s);
    if screens
        .iter()
        .any(|s| picked.contains(&s.candidate) && passes(s))
    {
        return Ok(true);
    }
    if k < 3 {
        return Ok(false);
    }
    // each pair screened as one candidate freeing both effects' unknowns
    let pool: Vec<usize> = picked
        .iter()
        .enumerate()
        .filter(|(i, ci)| *i < PAIRED || greedy_ids.contains(&cands[**ci].id))
        .map(|(_, ci)| *ci)
        .collect();
    let mut unions: Vec<Candidate> = Vec::new();
    for (x, &a) in pool.iter().enumerate() {
        for &b in &pool[x + 1..] {
            let mut union = cands[a].clone();
            union.unknowns.extend(
                cands[b]
                    .unknowns
                    .iter()
                    .filter(|u| !cands[a].unknowns.contains(u)),
            );
            unions.push(union);
        }
    }
    let lin = screen(&declared.model, data, &declared.fitted, &unions, cfg.rtol)?;
    Ok(lin.iter().any(passes))
}
