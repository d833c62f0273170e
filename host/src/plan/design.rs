//! Optimal designs on a candidate set: greedy selection then Fedorov-type exchange, with rank-k
//! updates of the inverse information matrix (a chain's pose measures three coordinates, a
//! tree's three per tip).
//!
//! `b` stacks the (column-scaled) Jacobian blocks of every candidate, [`Problem::rows`] rows
//! each. The
//! information of a design `S` is `M = M0 + sum_{c in S} B_c^T B_c` (`M0`: poses already
//! measured); the criteria (D/Ds, A, G, I) and their per-candidate gains are in
//! [`super::criteria`].
//!
//! `M^-1` is updated by the Woodbury identity; a small ridge
//! ([`RIDGE`], relative to the unit column scale) keeps `M` invertible while fewer poses than
//! parameters are chosen. Each exchange pass removes every chosen pose in turn and puts back the
//! best candidate (possibly the same one); passes stop when none improves the criterion by
//! more than [`MIN_GAIN`], and `M^-1` is rebuilt from scratch after every pass.

use nalgebra::DMatrix;

pub use super::criteria::{information, Criterion, POSE_ROWS, RIDGE};
use super::criteria::{value, Scorer};
use super::PlanError;

/// Smallest criterion gain of an exchange.
pub const MIN_GAIN: f64 = 1e-9;
/// Most exchange passes.
pub const MAX_PASSES: usize = 10;

/// A chosen design.
#[derive(Debug, Clone, PartialEq)]
pub struct Design {
    /// Indices of the chosen candidates, in the order chosen.
    pub chosen: Vec<usize>,
    /// Criterion value (larger is better; see [`super::criteria`]).
    pub criterion: f64,
    /// Exchanges made after the greedy start.
    pub exchanges: usize,
}

/// `-trace` of the ridged `M^-1` over `interest` (all when empty) of the design `chosen`.
pub fn a_criterion(
    b: &DMatrix<f64>,
    prior: &DMatrix<f64>,
    chosen: &[usize],
    interest: &[usize],
) -> f64 {
    let m = information(b, POSE_ROWS, prior, chosen);
    value(Criterion::A, &m, interest, &DMatrix::zeros(0, 0))
}

/// D criterion of the design `chosen`: `log det M - log det M_OO` (`nuisance` = O; plain
/// `log det M` when empty).
pub fn criterion(
    b: &DMatrix<f64>,
    prior: &DMatrix<f64>,
    chosen: &[usize],
    nuisance: &[usize],
) -> f64 {
    let m = information(b, POSE_ROWS, prior, chosen);
    let p = m.nrows();
    let interest: Vec<usize> = (0..p).filter(|c| !nuisance.contains(c)).collect();
    let interest = if nuisance.is_empty() {
        Vec::new()
    } else {
        interest
    };
    value(Criterion::D, &m, &interest, &DMatrix::zeros(0, 0))
}

/// Chooses `n` distinct candidates (a chain's poses: rows `3c..3c+3` of `b`) maximising the criterion `kind`
/// (restricted to the columns `interest` when it is a non-empty proper subset), greedily from
/// an empty design then by exchanges. `prior`: the information of poses already measured
/// (p x p, zeros for none).
pub fn optimal_design(
    b: &DMatrix<f64>,
    prior: &DMatrix<f64>,
    n: usize,
    interest: &[usize],
    kind: Criterion,
) -> Result<Design, PlanError> {
    exchange_from(b, prior, n, interest, kind, &[])
}

/// As [`optimal_design`], starting from the candidates `start` (completed greedily to `n`).
pub fn exchange_from(
    b: &DMatrix<f64>,
    prior: &DMatrix<f64>,
    n: usize,
    interest: &[usize],
    kind: Criterion,
    start: &[usize],
) -> Result<Design, PlanError> {
    exchange_weighted(b, prior, n, interest, kind, start, &[])
}

/// As [`exchange_from`], with the A criterion's column weights `weights` (empty: all 1; see
/// [`Scorer::with_weights`]).
pub fn exchange_weighted(
    b: &DMatrix<f64>,
    prior: &DMatrix<f64>,
    n: usize,
    interest: &[usize],
    kind: Criterion,
    start: &[usize],
    weights: &[f64],
) -> Result<Design, PlanError> {
    let problem = Problem {
        b,
        rows: POSE_ROWS,
        prior,
        interest,
        kind,
        weights,
        prediction: None,
        admissible: &[],
    };
    exchange(&problem, n, start)
}

/// A design problem on a candidate set.
#[derive(Debug, Clone, Copy)]
pub struct Problem<'a> {
    /// Scaled Jacobian blocks of the candidates, `rows` rows each.
    pub b: &'a DMatrix<f64>,
    /// Rows of a candidate's block ([`POSE_ROWS`] on a chain, 3 per tip on a tree).
    pub rows: usize,
    /// Information of the poses already measured (p x p).
    pub prior: &'a DMatrix<f64>,
    /// Columns of interest (all when empty).
    pub interest: &'a [usize],
    /// The criterion.
    pub kind: Criterion,
    /// A's column weights (empty: all 1).
    pub weights: &'a [f64],
    /// I's prediction weight (`None`: the mean over all rows of `b`).
    pub prediction: Option<&'a DMatrix<f64>>,
    /// Per candidate, whether it may be chosen (empty: all; `--from-diagnose` leaves out the
    /// poses where the effects to separate are not linear in their values, [`super::robust`]).
    pub admissible: &'a [bool],
}

/// Greedy completion of `start` to `n` candidates, then exchange passes (module docs).
pub fn exchange(problem: &Problem<'_>, n: usize, start: &[usize]) -> Result<Design, PlanError> {
    let Problem {
        b,
        rows,
        prior,
        interest,
        kind,
        weights,
        prediction,
        admissible,
    } = *problem;
    let n_cand = b.nrows() / rows.max(1);
    // a candidate that may not be chosen counts as taken from the start
    let mut taken: Vec<bool> = (0..n_cand)
        .map(|c| admissible.get(c).is_some_and(|a| !a))
        .collect();
    let available = taken.iter().filter(|t| !**t).count();
    if n > available {
        return Err(PlanError::TooFewCandidates {
            n,
            candidates: available,
        });
    }
    let mut sc = Scorer::new(kind, b, rows, prior, interest)?.with_weights(weights);
    if let Some(q) = prediction {
        sc = sc.with_prediction_weight(q);
    }
    let mut chosen = Vec::with_capacity(n);
    for &c in start.iter().take(n) {
        if c < n_cand && !taken[c] {
            taken[c] = true;
            chosen.push(c);
            sc.update(c, 1.0);
        }
    }
    while chosen.len() < n {
        let s = sc.gains();
        let best = best_free(&s, &taken).ok_or(PlanError::Numerical("no finite gain"))?;
        taken[best] = true;
        chosen.push(best);
        sc.update(best, 1.0);
    }
    let mut exchanges = 0;
    for _ in 0..MAX_PASSES {
        let mut improved = false;
        for slot in chosen.iter_mut() {
            let old = *slot;
            sc.update(old, -1.0);
            taken[old] = false;
            let s = sc.gains();
            let best = match best_free(&s, &taken) {
                Some(c) if c != old && s[c] > s[old] + MIN_GAIN => {
                    exchanges += 1;
                    improved = true;
                    c
                }
                _ => old,
            };
            taken[best] = true;
            *slot = best;
            sc.update(best, 1.0);
        }
        sc.rebuild(&chosen)?;
        if !improved {
            break;
        }
    }
    Ok(Design {
        criterion: sc.value(&chosen),
        chosen,
        exchanges,
    })
}

fn best_free(score: &[f64], taken: &[bool]) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (c, &s) in score.iter().enumerate() {
        if taken[c] || !s.is_finite() {
            continue;
        }
        if best.is_none_or(|(_, v)| s > v) {
            best = Some((c, s));
        }
    }
    best.map(|(c, _)| c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::test_support::random_stack;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The rank-3 updates give the same criterion as a direct evaluation, and the design beats
    /// every random design of the same size drawn here.
    #[test]
    fn greedy_exchange_beats_random_designs() {
        let (p, n) = (8, 6);
        let b = random_stack(300, p, 3);
        let prior = DMatrix::zeros(p, p);
        let d = optimal_design(&b, &prior, n, &[], Criterion::D).unwrap();
        assert_eq!(d.chosen.len(), n);
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for _ in 0..50 {
            let mut pick: Vec<usize> = Vec::new();
            while pick.len() < n {
                let c = rng.gen_range(0..300);
                if !pick.contains(&c) {
                    pick.push(c);
                }
            }
            assert!(criterion(&b, &prior, &pick, &[]) < d.criterion);
        }
        // the exchange ends at a local optimum: no single swap improves
        let base = d.criterion;
        for k in 0..n {
            for c in (0..300).step_by(7) {
                if d.chosen.contains(&c) {
                    continue;
                }
                let mut alt = d.chosen.clone();
                alt[k] = c;
                assert!(criterion(&b, &prior, &alt, &[]) <= base + 1e-6);
            }
        }
    }

    /// A-optimal designs beat random ones on the trace too.
    #[test]
    fn a_optimal_beats_random_designs() {
        let (p, n) = (6, 5);
        let b = random_stack(200, p, 4);
        let prior = DMatrix::zeros(p, p);
        let d = optimal_design(&b, &prior, n, &[], Criterion::A).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        for _ in 0..50 {
            let mut pick: Vec<usize> = Vec::new();
            while pick.len() < n {
                let c = rng.gen_range(0..200);
                if !pick.contains(&c) {
                    pick.push(c);
                }
            }
            assert!(a_criterion(&b, &prior, &pick, &[]) < d.criterion);
        }
    }

    /// Candidates that are not admissible are never chosen, even the best ones; too few
    /// admissible candidates is an error.
    #[test]
    fn inadmissible_candidates_are_never_chosen() {
        let p = 6;
        let b = random_stack(100, p, 6);
        let prior = DMatrix::zeros(p, p);
        let free = optimal_design(&b, &prior, 8, &[], Criterion::A).unwrap();
        let mut admissible = vec![true; 100];
        for &c in &free.chosen {
            admissible[c] = false;
        }
        let problem = Problem {
            b: &b,
            rows: POSE_ROWS,
            prior: &prior,
            interest: &[],
            kind: Criterion::A,
            weights: &[],
            prediction: None,
            admissible: &admissible,
        };
        let d = exchange(&problem, 8, &free.chosen).unwrap();
        assert_eq!(d.chosen.len(), 8);
        assert!(d.chosen.iter().all(|&c| admissible[c]), "{:?}", d.chosen);
        assert!(d.criterion < free.criterion);
        let few = vec![false; 100];
        let problem = Problem {
            admissible: &few,
            ..problem
        };
        assert!(matches!(
            exchange(&problem, 8, &[]),
            Err(PlanError::TooFewCandidates { candidates: 0, .. })
        ));
    }

    /// Ds on two nearly aliased columns picks the candidates that tell them apart.
    #[test]
    fn ds_separates_aliased_columns() {
        let p = 4;
        let mut b = random_stack(200, p, 5);
        // column 3 = column 2 except on the last 10 candidates
        for r in 0..b.nrows() {
            let v = b[(r, 2)];
            b[(r, 3)] = if r < 3 * 190 { v } else { -v };
        }
        let prior = DMatrix::zeros(p, p);
        let d = optimal_design(&b, &prior, 8, &[2, 3], Criterion::D).unwrap();
        let separating = d.chosen.iter().filter(|&&c| c >= 190).count();
        assert!(separating >= 4, "{:?}", d.chosen);
    }
}
