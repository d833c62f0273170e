//! The optimality criteria of a design and their cheap per-candidate gains.
//!
//! `b` stacks the (column-scaled) Jacobian blocks `B_c` of every candidate, `k` rows each (a
//! chain's pose measures one point, [`POSE_ROWS`]; a tree's pose a point on every tip);
//! `M = M0 + sum_{c in S} B_c^T B_c (+ RIDGE I)` is the information of a design `S`. Adding
//! candidate `c` gives, with `W_c = B_c M^-1` (k x p) and `S_c = I_k + W_c B_c^T`:
//!
//! * **D** (`log det M`): gain `log det S_c` (matrix determinant lemma); with columns of interest
//!   `I` (nuisance `O` the others) Ds: `log det M - log det M_OO`, the log-determinant of the
//!   Schur complement (what is known about `I` once `O` is estimated);
//! * **A** (`-trace (M^-1)_II`, the sum of the squared scaled sigmas): the diagonal of `M^-1`
//!   drops by `a_i = w_i^T S_c^-1 w_i` (`w_i` column `i` of `W_c`; Woodbury);
//! * **G** (`-sum_i log (M^-1)_ii`: the geometric mean of the parameter sigmas, invariant to
//!   the column scale, so every parameter's *relative* improvement counts alike; the criterion
//!   for the median sigma): gain `sum_i log (M^-1)_ii - log((M^-1)_ii - a_i)`;
//! * **I** (`-trace(M^-1 Q)`, `Q` the mean `B_c^T B_c` over all candidates: the average
//!   prediction variance of the tool point over the candidate workspace, I- or V-optimality;
//!   the criterion for the held-out error on poses drawn like the candidates): gain
//!   `trace(S_c^-1 W_c Q W_c^T)`.
//!
//! With columns of interest, A, G and I are restricted to them (As, Gs, Is).

use nalgebra::{DMatrix, DVector};

use super::PlanError;

/// The rows of a chain pose's Jacobian block: one measured point (x, y, z).
pub const POSE_ROWS: usize = 3;

/// Ridge added to the information matrix (columns are scaled to unit RMS per pose).
pub const RIDGE: f64 = 1e-6;

/// A scaled variance beyond this (1% of the ridge's 1/RIDGE) means the ridge, not the design,
/// determines that parameter.
pub const DEFICIENT_VARIANCE: f64 = 1e-2 / RIDGE;

/// What a design maximises (see the module docs; `plan --criterion`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Criterion {
    /// `log det M` (or of the Schur complement of the columns of interest: Ds).
    D,
    /// `-trace(M^-1)` over the columns of interest (all by default): the sum of the squared
    /// scaled parameter sigmas (A-optimality).
    #[default]
    A,
    /// `-sum log (M^-1)_ii`: the geometric mean of the parameter sigmas.
    G,
    /// `-trace(M^-1 Q)`: the mean prediction variance over the candidates (I-optimality).
    I,
}

impl Criterion {
    /// Name in `plan.json` (`"D-optimal"`, `"Ds-optimal"`, `"A-optimal"`, ...).
    pub fn name(self, subset: bool) -> &'static str {
        match (self, subset) {
            (Criterion::D, false) => "D-optimal",
            (Criterion::D, true) => "Ds-optimal",
            (Criterion::A, false) => "A-optimal",
            (Criterion::A, true) => "As-optimal",
            (Criterion::G, false) => "G-mean-optimal",
            (Criterion::G, true) => "Gs-mean-optimal",
            (Criterion::I, false) => "I-optimal",
            (Criterion::I, true) => "Is-optimal",
        }
    }

    /// The command-line letter.
    pub fn letter(self) -> &'static str {
        match self {
            Criterion::D => "d",
            Criterion::A => "a",
            Criterion::G => "g",
            Criterion::I => "i",
        }
    }

    /// Parses `d`, `a`, `g` or `i`.
    pub fn parse(s: &str) -> Option<Self> {
        // the letters are clap's (`ValueEnum`), in either case
        <Self as clap::ValueEnum>::from_str(s, true).ok()
    }
}

/// The information of `chosen` (blocks of `rows` rows of `b`) on top of `prior`.
pub fn information(
    b: &DMatrix<f64>,
    rows: usize,
    prior: &DMatrix<f64>,
    chosen: &[usize],
) -> DMatrix<f64> {
    let mut m = prior.clone();
    for &c in chosen {
        let bc = b.rows(rows * c, rows);
        m += bc.transpose() * bc;
    }
    m
}

fn ridged_inverse(m: &DMatrix<f64>, cols: &[usize]) -> Option<DMatrix<f64>> {
    let q = cols.len();
    let sub =
        DMatrix::from_fn(q, q, |r, c| m[(cols[r], cols[c])]) + DMatrix::identity(q, q) * RIDGE;
    sub.cholesky().map(|c| c.inverse())
}

fn log_det_ridged(m: &DMatrix<f64>, cols: &[usize]) -> f64 {
    if cols.is_empty() {
        return 0.0;
    }
    let q = cols.len();
    let sub =
        DMatrix::from_fn(q, q, |r, c| m[(cols[r], cols[c])]) + DMatrix::identity(q, q) * RIDGE;
    match sub.cholesky() {
        Some(ch) => 2.0 * ch.l().diagonal().iter().map(|d| d.ln()).sum::<f64>(),
        None => f64::NEG_INFINITY,
    }
}

/// The prediction weight `Q = B^T B / candidates` (mean information of one candidate, blocks
/// of `rows` rows).
pub fn prediction_weight(b: &DMatrix<f64>, rows: usize) -> DMatrix<f64> {
    let n = (b.nrows() / rows.max(1)).max(1) as f64;
    b.transpose() * b / n
}

/// The value of criterion `kind` for the information `m` (larger is better); `interest`: the
/// columns of interest (all when empty); `q`: the prediction weight (criterion I).
pub fn value(kind: Criterion, m: &DMatrix<f64>, interest: &[usize], q: &DMatrix<f64>) -> f64 {
    let p = m.nrows();
    let all: Vec<usize> = (0..p).collect();
    let cols = if interest.is_empty() { &all } else { interest };
    if kind == Criterion::D {
        let nuisance: Vec<usize> = all
            .iter()
            .copied()
            .filter(|c| !interest.contains(c))
            .collect();
        let nuisance = if interest.is_empty() {
            Vec::new()
        } else {
            nuisance
        };
        return log_det_ridged(m, &all) - log_det_ridged(m, &nuisance);
    }
    let Some(inv) = ridged_inverse(m, &all) else {
        return f64::NEG_INFINITY;
    };
    match kind {
        Criterion::A => -cols.iter().map(|&i| inv[(i, i)]).sum::<f64>(),
        Criterion::G => -cols.iter().map(|&i| inv[(i, i)].ln()).sum::<f64>(),
        _ => -cols
            .iter()
            .flat_map(|&i| cols.iter().map(move |&k| (i, k)))
            .map(|(i, k)| inv[(i, k)] * q[(k, i)])
            .sum::<f64>(),
    }
}

/// As [`value`], with A's column weights `weights` (one per column of `m`; empty: all 1).
pub fn value_weighted(
    kind: Criterion,
    m: &DMatrix<f64>,
    interest: &[usize],
    q: &DMatrix<f64>,
    weights: &[f64],
) -> f64 {
    if kind != Criterion::A || weights.len() != m.nrows() {
        return value(kind, m, interest, q);
    }
    let all: Vec<usize> = (0..m.nrows()).collect();
    let cols = if interest.is_empty() { &all } else { interest };
    match ridged_inverse(m, &all) {
        Some(inv) => -cols.iter().map(|&i| weights[i] * inv[(i, i)]).sum::<f64>(),
        None => f64::NEG_INFINITY,
    }
}

/// `M^-1` of the ridged information restricted to some columns, recomputed from `M` (kept
/// by rank-3 additions) after every change: a Woodbury update from the ridge-only start loses
/// digits (entries of 1/RIDGE cancelling to O(1)), a p x p Cholesky costs nothing next to the
/// gains of all candidates.
struct InfoState {
    cols: Vec<usize>,
    m: DMatrix<f64>,
    minv: DMatrix<f64>,
}

impl InfoState {
    fn new(m: &DMatrix<f64>, cols: Vec<usize>) -> Result<Self, PlanError> {
        let minv = ridged_inverse(m, &cols).ok_or(PlanError::Numerical(
            "information matrix not positive definite",
        ))?;
        Ok(Self {
            cols,
            m: m.clone(),
            minv,
        })
    }

    /// Adds (`sign` = 1) or removes (-1) candidate `c` (rows `rows c ..` of `b`).
    fn update(&mut self, b: &DMatrix<f64>, rows: usize, c: usize, sign: f64) {
        if self.cols.is_empty() {
            return;
        }
        let bc = b.rows(rows * c, rows);
        self.m += bc.transpose() * bc * sign;
        if let Some(inv) = ridged_inverse(&self.m, &self.cols) {
            self.minv = inv;
        }
    }
}

fn log_det(s: &DMatrix<f64>) -> f64 {
    let d = s.determinant();
    if d > 0.0 {
        d.ln()
    } else {
        f64::NEG_INFINITY
    }
}

/// The criterion's state along a greedy / exchange run: `M^-1` kept by rank-k updates.
pub struct Scorer<'a> {
    kind: Criterion,
    b: &'a DMatrix<f64>,
    /// Rows of one candidate's block.
    rows: usize,
    prior: &'a DMatrix<f64>,
    /// Columns of interest (all when none were given).
    cols: Vec<usize>,
    /// Whether columns of interest were given.
    subset: bool,
    nuisance: Vec<usize>,
    b_nui: DMatrix<f64>,
    q: DMatrix<f64>,
    full: InfoState,
    nui: InfoState,
    /// Weight of each column's variance in A (1 by default; see [`Scorer::with_weights`]).
    weights: Vec<f64>,
}

impl<'a> Scorer<'a> {
    /// Weights of the columns' variances in the A criterion, e.g. `1 / var_random_i`: then A
    /// minimises the sum of the squared planned / random sigma ratios (non-finite or
    /// non-positive weights count as 1).
    pub fn with_weights(mut self, weights: &[f64]) -> Self {
        for (w, v) in self.weights.iter_mut().zip(weights) {
            *w = if v.is_finite() && *v > 0.0 { *v } else { 1.0 };
        }
        self
    }

    /// The prediction weight of criterion I: `q` (p x p, e.g. [`prediction_weight`] of the
    /// uniformly drawn candidates only) instead of the mean over all rows of `b`.
    pub fn with_prediction_weight(mut self, q: &DMatrix<f64>) -> Self {
        if self.kind == Criterion::I && q.nrows() == self.b.ncols() && q.ncols() == q.nrows() {
            self.q = q.clone();
        }
        self
    }

    /// The state of the empty design (information `prior`) on the candidates' blocks of `rows`
    /// rows of `b`.
    pub fn new(
        kind: Criterion,
        b: &'a DMatrix<f64>,
        rows: usize,
        prior: &'a DMatrix<f64>,
        interest: &[usize],
    ) -> Result<Self, PlanError> {
        let p = b.ncols();
        let all: Vec<usize> = (0..p).collect();
        let subset = !interest.is_empty() && interest.len() < p;
        let cols = if subset {
            interest.to_vec()
        } else {
            all.clone()
        };
        let nuisance: Vec<usize> = if subset && kind == Criterion::D {
            all.iter().copied().filter(|c| !cols.contains(c)).collect()
        } else {
            Vec::new()
        };
        let b_nui = DMatrix::from_fn(b.nrows(), nuisance.len(), |r, k| b[(r, nuisance[k])]);
        let q = if kind == Criterion::I {
            prediction_weight(b, rows)
        } else {
            DMatrix::zeros(0, 0)
        };
        Ok(Self {
            kind,
            b,
            rows: rows.max(1),
            prior,
            full: InfoState::new(prior, all)?,
            nui: InfoState::new(prior, nuisance.clone())?,
            cols,
            subset,
            nuisance,
            b_nui,
            q,
            weights: vec![1.0; p],
        })
    }

    /// Adds (`sign` 1) or removes (-1) candidate `c`.
    pub fn update(&mut self, c: usize, sign: f64) {
        self.full.update(self.b, self.rows, c, sign);
        self.nui.update(self.b, self.rows, c, sign);
    }

    /// Rebuilds `M` and `M^-1` from scratch for the design `chosen` (rounding drift of the
    /// additions and removals).
    pub fn rebuild(&mut self, chosen: &[usize]) -> Result<(), PlanError> {
        let m = information(self.b, self.rows, self.prior, chosen);
        self.full = InfoState::new(&m, self.full.cols.clone())?;
        self.nui = InfoState::new(&m, self.nuisance.clone())?;
        Ok(())
    }

    /// The criterion of the design `chosen` (larger is better).
    pub fn value(&self, chosen: &[usize]) -> f64 {
        let m = information(self.b, self.rows, self.prior, chosen);
        let interest = if self.subset { &self.cols[..] } else { &[] };
        value_weighted(self.kind, &m, interest, &self.q, &self.weights)
    }

    /// Whether the ridge still stands in for information the design lacks (some scaled
    /// variance beyond [`DEFICIENT_VARIANCE`]).
    pub fn deficient(&self) -> bool {
        self.full
            .minv
            .diagonal()
            .iter()
            .any(|v| !(v.is_finite() && *v < DEFICIENT_VARIANCE))
    }

    /// The gain of adding each candidate to the current design. While the design is deficient,
    /// G ranks by the D gain (its own gain would come from variances of order 1/RIDGE cancelling
    /// to O(1), with few digits left; D-greedy is the usual way to full rank).
    pub fn gains(&self) -> Vec<f64> {
        let (b, k) = (self.b, self.rows);
        let w = b * &self.full.minv; // k n x p
        let deficient = self.kind == Criterion::G && self.deficient();
        let wq = (self.kind == Criterion::I).then(|| {
            let k = self.cols.len();
            let qi = DMatrix::from_fn(k, k, |r, c| self.q[(self.cols[r], self.cols[c])]);
            let wi = DMatrix::from_fn(w.nrows(), k, |r, j| w[(r, self.cols[j])]);
            (&wi * qi, wi)
        });
        let nui_w = (!self.nuisance.is_empty()).then(|| &self.b_nui * &self.nui.minv);
        let nui_gain = |c: usize| -> f64 {
            let Some(nw) = &nui_w else {
                return 0.0;
            };
            let sn = DMatrix::identity(k, k)
                + DMatrix::from_fn(k, k, |r, t| {
                    nw.row(k * c + r).dot(&self.b_nui.row(k * c + t))
                });
            log_det(&sn)
        };
        (0..b.nrows() / k)
            .map(|c| {
                let s = DMatrix::identity(k, k)
                    + DMatrix::from_fn(k, k, |r, t| w.row(k * c + r).dot(&b.row(k * c + t)));
                match self.kind {
                    Criterion::D => log_det(&s) - nui_gain(c),
                    Criterion::G if deficient => log_det(&s),
                    _ => self.diag_gain(&w, &s, c, wq.as_ref()),
                }
            })
            .collect()
    }

    fn diag_gain(
        &self,
        w: &DMatrix<f64>,
        s: &DMatrix<f64>,
        c: usize,
        wq: Option<&(DMatrix<f64>, DMatrix<f64>)>,
    ) -> f64 {
        let k = self.rows;
        let Some(si) = s.clone().try_inverse() else {
            return f64::NEG_INFINITY;
        };
        if let Some((wqm, wi)) = wq {
            // trace(S^-1 W Q W^T) over the columns of interest
            let a = DMatrix::from_fn(k, k, |r, t| wqm.row(k * c + r).dot(&wi.row(k * c + t)));
            return (si * a).trace();
        }
        self.cols
            .iter()
            .map(|&i| {
                let v = DVector::from_fn(k, |r, _| w[(k * c + r, i)]);
                let drop = v.dot(&(&si * &v));
                if self.kind == Criterion::A {
                    self.weights[i] * drop
                } else {
                    let var = self.full.minv[(i, i)];
                    var.ln() - (var - drop).max(f64::MIN_POSITIVE).ln()
                }
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::test_support::random_stack;

    /// Every criterion's rank-3 gain equals the change of its directly evaluated value, from an
    /// empty (ridge only) design, rank-deficient ones and full ones, after a removal too, with
    /// and without columns of interest.
    #[test]
    fn gains_match_direct_evaluation() {
        let p = 7;
        let prior = DMatrix::zeros(p, p);
        // a chain's pose (3 rows) and a two-tip tree's (6 rows)
        for (rows, b) in [
            (POSE_ROWS, random_stack(40, p, 8)),
            (6, random_stack(80, p, 9)),
        ] {
            for kind in [Criterion::D, Criterion::A, Criterion::G, Criterion::I] {
                for interest in [vec![], vec![1usize, 4]] {
                    let mut sc = Scorer::new(kind, &b, rows, &prior, &interest).unwrap();
                    let mut chosen: Vec<usize> = Vec::new();
                    for add in [3usize, 9, 17, 21] {
                        let g = sc.gains();
                        if kind == Criterion::G && sc.deficient() {
                            sc.update(add, 1.0);
                            chosen.push(add);
                            continue;
                        }
                        let before = sc.value(&chosen);
                        for c in [0usize, 5, 30] {
                            let mut with = chosen.clone();
                            with.push(c);
                            let direct = sc.value(&with) - before;
                            // while rank deficient, 1/RIDGE-sized variances cancel to O(1): fewer digits
                            let rel = if rows * chosen.len() < p { 1e-5 } else { 1e-7 };
                            let tol = rel * (1.0 + direct.abs());
                            assert!(
                                (g[c] - direct).abs() < tol,
                                "{kind:?} {interest:?} after {chosen:?} + {c}: {} vs {direct}",
                                g[c]
                            );
                        }
                        sc.update(add, 1.0);
                        chosen.push(add);
                    }
                    sc.update(9, -1.0);
                    chosen.retain(|&c| c != 9);
                    let g = sc.gains();
                    let mut with = chosen.clone();
                    with.push(11);
                    let direct = sc.value(&with) - sc.value(&chosen);
                    assert!(
                        (g[11] - direct).abs() < 1e-6 * (1.0 + direct.abs()),
                        "{kind:?} after removal"
                    );
                }
            }
        }
    }
}
