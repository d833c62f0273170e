//! The best any design on the candidate set can do: the approximate optimum of the criterion
//! (Kiefer's continuous designs: a weight on every candidate, `N` poses in all), found by the
//! multiplicative algorithm (Silvey, Titterington and Torsney; with the power 1, twice the one
//! Yu (2010) proves monotone for A, so the best design met and the tightest bound are kept),
//! with the equivalence-theorem certificate that bounds the optimum.
//!
//! An exact design of `N` poses from the candidates is a special approximate design, so the
//! approximate optimum is a bound on every plan drawn from the pool: it says how far the plan
//! is from the best possible, and what the best possible gives (e.g. its median sigma ratio).
//! The continuous refinement leaves the pool, so a refined plan can pass the pool's optimum
//! slightly (efficiency above 1).
//!
//! With `M(xi) = N sum_c xi_c B_c^T B_c` (columns scaled as in [`super::setup`]):
//!
//! * A and I (`phi = trace(W M^-1)`, `W` the A weights or I's prediction weight): directional
//!   derivative `d_c = N trace(M^-1 W M^-1 B_c^T B_c)`, update `xi_c *= d_c / phi`;
//!   by convexity and `phi(tM) = phi(M)/t`, every design `xi` certifies
//!   `phi* >= phi(xi)^2 / max_c d_c`;
//! * D (`log det M`): `d_c = N trace(M^-1 B_c^T B_c)`, update `xi_c *= d_c / p`; certificate
//!   `log det M* <= log det M(xi) + p log(max_c d_c / p)`;
//! * G (`-sum_i log (M^-1)_ii`, the geometric mean of the sigmas): concave in `M`, since
//!   `1 / (M^-1)_ii` is a Schur complement of `M` (concave) and the log of a positive concave
//!   function is concave; `d_c = N trace(M^-1 V^-1 M^-1 B_c^T B_c)` with `V = diag(M^-1)`,
//!   `sum_c xi_c d_c = p`, update `xi_c *= d_c / p`; as `phi(tM) = phi(M) + p log t`, the same
//!   certificate as D: `phi* <= phi(xi) + p log(max_c d_c / p)`.

use nalgebra::{DMatrix, DVector};

use super::criteria::Criterion;

/// Iterations at most.
pub const MAX_ITERATIONS: usize = 2000;
/// Stop when the certificate puts the current design within this relative gap of the optimum
/// (A/I: `1 - bound / phi`; D/G: `1 - exp(-(bound - value) / p)`, an efficiency).
pub const TARGET_GAP: f64 = 0.005;
/// Candidates with less weight than this fraction of one pose count as outside the support.
const SUPPORT_WEIGHT: f64 = 0.01;

/// The approximate optimum on the candidates and its certificate.
#[derive(Debug, Clone, PartialEq)]
pub struct Optimum {
    /// The criterion (A, I, D or G).
    pub kind: Criterion,
    /// Value at the approximate optimum found: `trace(W M^-1)` (A, I; smaller is better),
    /// `log det M` (D) or `-sum log (M^-1)_ii` (G; larger is better).
    pub value: f64,
    /// No design on the candidates does better than this: a lower bound on `trace(W M^-1)`
    /// (A, I) or an upper bound on the value (D, G).
    pub bound: f64,
    /// Scaled variances `(M^-1)_ii` at the approximate optimum (unit noise).
    pub variance: Vec<f64>,
    /// Iterations run.
    pub iterations: usize,
    /// Candidates carrying at least 1 % of a pose.
    pub support: usize,
    /// The optimum's weight on each candidate (sums to 1; times N: poses).
    pub design: Vec<f64>,
    /// `G` of the optimum's sensitivity `d(B) = N trace(G B^T B)`: `M^-1 W M^-1` (A, I),
    /// `M^-1` (D) or `M^-1 diag(M^-1)^-1 M^-1` (G).
    pub dual: DMatrix<f64>,
    /// The number of poses `N` the design is for.
    pub n: usize,
}

impl Optimum {
    /// Efficiency of a design with information `m` (scaled, unit noise) against the optimum
    /// found: `phi*/phi(m)` (A, I) or `exp((value(m) - value*)/p)` (D: `(det m / det
    /// M*)^(1/p)`; G: the geometric mean over the parameters of `var* / var(m)`); 1 = as good,
    /// above 1 = better than the pool's optimum (possible only off the pool).
    pub fn efficiency(&self, m: &DMatrix<f64>, weight: &DMatrix<f64>) -> f64 {
        self.relative(self.value, m, weight)
    }

    /// The efficiency of the design `m` against the certificate's bound: the design is at
    /// least this efficient relative to the best design on the candidates (for designs from
    /// the pool; a refined design may pass it).
    pub fn efficiency_bound(&self, m: &DMatrix<f64>, weight: &DMatrix<f64>) -> f64 {
        self.relative(self.bound, m, weight)
    }

    /// The `n` candidates of most weight (ties by index): an exact design to start an exchange
    /// from.
    pub fn rounded(&self, n: usize) -> Vec<usize> {
        let mut order: Vec<usize> = (0..self.design.len()).collect();
        order.sort_by(|&a, &b| self.design[b].total_cmp(&self.design[a]).then(a.cmp(&b)));
        order.truncate(n);
        order
    }

    /// The sensitivity of a configuration with scaled block `blk` (3 x p): the directional
    /// derivative of the criterion towards it; above [`Optimum::threshold`] it would improve
    /// the design, at most the threshold everywhere at the optimum (equivalence theorem).
    pub fn sensitivity(&self, blk: &DMatrix<f64>) -> f64 {
        if blk.ncols() != self.dual.nrows() {
            return f64::NAN;
        }
        self.n as f64 * (blk * &self.dual).component_mul(blk).sum()
    }

    /// The sensitivity every point stays under at the optimum: `trace(W M^-1)` (A, I) or `p`
    /// (D, G).
    pub fn threshold(&self) -> f64 {
        match self.kind {
            Criterion::D | Criterion::G => self.dual.nrows() as f64,
            _ => self.value,
        }
    }

    fn relative(&self, best: f64, m: &DMatrix<f64>, weight: &DMatrix<f64>) -> f64 {
        let p = m.nrows().max(1) as f64;
        match self.kind {
            Criterion::D => match log_det(m) {
                Some(ld) => ((ld - best) / p).exp(),
                None => 0.0,
            },
            Criterion::G => match m.clone().cholesky() {
                Some(ch) => ((neg_log_variances(&ch.inverse()) - best) / p).exp(),
                None => 0.0,
            },
            _ => match m.clone().cholesky() {
                Some(ch) => best / (ch.inverse() * weight).trace(),
                None => 0.0,
            },
        }
    }
}

/// What [`super::continuous::extend`] added to the pool.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Extension {
    /// Configurations added.
    pub added: usize,
    /// Rounds run.
    pub rounds: usize,
    /// Largest sensitivity over the threshold in the last round's climbs (at most 1 + 1e-3
    /// when the rounds ended because none improved the design).
    pub last_excess: f64,
}

/// What a plan is told about the best possible on its candidates.
#[derive(Debug, Clone, PartialEq)]
pub struct OptimumReport {
    /// The configurations added to the pool by the sensitivity climbs.
    pub extension: Extension,
    /// The approximate optimum found and its certificate.
    pub optimum: Optimum,
    /// The plan against the optimum found ([`Optimum::efficiency`]).
    pub efficiency: f64,
    /// The plan against the certificate's bound ([`Optimum::efficiency_bound`]).
    pub efficiency_bound: f64,
    /// Parameter sigmas at the optimum (parameter units, the plan's noise).
    pub sigma: Vec<f64>,
    /// Median over parameters of the optimum's sigma over the random designs' sigma.
    pub median_sigma_ratio: f64,
}

impl OptimumReport {
    /// The report for a plan of scaled information `m_plan`: `weight` as given to
    /// [`approximate_optimum`], `scale` the column scale, `noise_mm` the noise,
    /// `random_sigma` the baseline's sigmas (parameter units).
    pub fn new(
        optimum: Optimum,
        weight: &DMatrix<f64>,
        m_plan: &DMatrix<f64>,
        scale: &[f64],
        noise_mm: f64,
        random_sigma: &[f64],
    ) -> Self {
        let sigma: Vec<f64> = optimum
            .variance
            .iter()
            .zip(scale)
            .map(|(v, k)| v.max(0.0).sqrt() * noise_mm / k)
            .collect();
        Self {
            extension: Extension::default(),
            efficiency: optimum.efficiency(m_plan, weight),
            efficiency_bound: optimum.efficiency_bound(m_plan, weight),
            median_sigma_ratio: super::metrics::median_ratio(&sigma, random_sigma),
            sigma,
            optimum,
        }
    }
}

impl OptimumReport {
    /// With what the sensitivity climbs added.
    pub fn with_extension(mut self, extension: Extension) -> Self {
        self.extension = extension;
        self
    }
}

/// `-sum_i log (M^-1)_ii` of an inverse information `minv` (G's value; larger is better).
fn neg_log_variances(minv: &DMatrix<f64>) -> f64 {
    -minv.diagonal().iter().map(|v| v.ln()).sum::<f64>()
}

fn log_det(m: &DMatrix<f64>) -> Option<f64> {
    m.clone()
        .cholesky()
        .map(|ch| 2.0 * ch.l().diagonal().iter().map(|d| d.ln()).sum::<f64>())
}

/// Packs the upper triangle of each candidate's `B_c^T B_c` into a column (`p(p+1)/2` rows).
fn packed_information(b: &DMatrix<f64>) -> DMatrix<f64> {
    let (n_cand, p) = (b.nrows() / 3, b.ncols());
    let mut mc = DMatrix::<f64>::zeros(p * (p + 1) / 2, n_cand);
    for c in 0..n_cand {
        let bc = b.rows(3 * c, 3);
        let mut k = 0;
        for i in 0..p {
            for j in i..p {
                mc[(k, c)] = bc.column(i).dot(&bc.column(j));
                k += 1;
            }
        }
    }
    mc
}

/// The symmetric `p x p` matrix of a packed upper triangle, times `factor`.
fn unpack(v: &DVector<f64>, p: usize, factor: f64) -> DMatrix<f64> {
    let mut m = DMatrix::<f64>::zeros(p, p);
    let mut k = 0;
    for i in 0..p {
        for j in i..p {
            m[(i, j)] = factor * v[k];
            m[(j, i)] = factor * v[k];
            k += 1;
        }
    }
    m
}

/// `G` packed so that `packed(G) . packed(B_c^T B_c) = trace(G B_c^T B_c)` (off-diagonal
/// entries counted twice).
fn pack_dual(g: &DMatrix<f64>) -> DVector<f64> {
    let p = g.nrows();
    let mut v = DVector::<f64>::zeros(p * (p + 1) / 2);
    let mut k = 0;
    for i in 0..p {
        for j in i..p {
            v[k] = if i == j {
                g[(i, i)]
            } else {
                g[(i, j)] + g[(j, i)]
            };
            k += 1;
        }
    }
    v
}

/// The approximate optimum of `kind` over designs of `n` poses from the candidates `b` (3 rows
/// each, scaled), `weight` = `W` (A: diagonal weights; I: prediction weight; ignored for D
/// and G).
/// `None` for no candidates, or when the candidates do not identify every column.
/// The update uses the power 1 for every criterion (twice A's monotone 1/2: half the
/// iterations here); the best design met and the tightest bound are kept, so the certificate
/// holds whatever the path.
pub fn approximate_optimum(
    b: &DMatrix<f64>,
    n: usize,
    kind: Criterion,
    weight: &DMatrix<f64>,
) -> Option<Optimum> {
    approximate_optimum_from(b, n, kind, weight, &[])
}

/// As [`approximate_optimum`], starting from the weights `start` (one per candidate, any
/// positive scale; uniform when the length does not match).
pub fn approximate_optimum_from(
    b: &DMatrix<f64>,
    n: usize,
    kind: Criterion,
    weight: &DMatrix<f64>,
    start: &[f64],
) -> Option<Optimum> {
    let (n_cand, p) = (b.nrows() / 3, b.ncols());
    if n_cand == 0 || p == 0 || n == 0 {
        return None;
    }
    let weighted = matches!(kind, Criterion::A | Criterion::I);
    if weighted && (weight.nrows() != p || weight.ncols() != p) {
        return None;
    }
    let (nf, pf) = (n as f64, p as f64);
    let larger_is_better = !weighted;
    let mc = packed_information(b);
    let total: f64 = start.iter().sum();
    let mut xi =
        if start.len() == n_cand && start.iter().all(|x| x.is_finite() && *x >= 0.0) && total > 0.0
        {
            DVector::from_iterator(n_cand, start.iter().map(|x| x / total))
        } else {
            DVector::from_element(n_cand, 1.0 / n_cand as f64)
        };
    let mut packed = DVector::<f64>::zeros(mc.nrows());
    let mut d = DVector::<f64>::zeros(n_cand);
    let mut best: Option<Optimum> = None;
    let mut bound = if larger_is_better {
        f64::INFINITY
    } else {
        f64::NEG_INFINITY
    };
    for it in 1..=MAX_ITERATIONS {
        packed.gemv(1.0, &mc, &xi, 0.0);
        let m = unpack(&packed, p, nf);
        let minv = m.clone().cholesky()?.inverse();
        // G = M^-1 W M^-1 (A, I) or M^-1 (D); d_c = N trace(G B_c^T B_c)
        let (g, phi) = match kind {
            Criterion::D => (minv.clone(), log_det(&m)?),
            Criterion::G => {
                let inv_var = DMatrix::from_diagonal(&minv.diagonal().map(|v| 1.0 / v));
                (&minv * inv_var * &minv, neg_log_variances(&minv))
            }
            _ => (&minv * weight * &minv, (&minv * weight).trace()),
        };
        d.gemv_tr(nf, &mc, &pack_dual(&g), 0.0);
        let dmax = d.iter().copied().fold(0.0, f64::max);
        if !(dmax.is_finite() && dmax > 0.0 && phi.is_finite()) {
            return best;
        }
        bound = if larger_is_better {
            bound.min(phi + pf * (dmax / pf).ln())
        } else {
            bound.max(phi * phi / dmax)
        };
        let improves = best.as_ref().is_none_or(|o| {
            if larger_is_better {
                phi > o.value
            } else {
                phi < o.value
            }
        });
        if improves {
            best = Some(Optimum {
                kind,
                value: phi,
                bound,
                variance: minv.diagonal().iter().copied().collect(),
                iterations: it,
                support: xi.iter().filter(|x| **x * nf >= SUPPORT_WEIGHT).count(),
                design: xi.iter().copied().collect(),
                dual: g,
                n,
            });
        }
        let o = best.as_mut()?;
        o.bound = bound;
        o.iterations = it;
        let gap = if larger_is_better {
            1.0 - (-(o.bound - o.value) / pf).exp()
        } else {
            1.0 - o.bound / o.value
        };
        if gap <= TARGET_GAP {
            break;
        }
        let scale = if larger_is_better { pf } else { phi };
        xi.iter_mut()
            .zip(d.iter())
            .for_each(|(x, dc)| *x *= (dc / scale).max(0.0));
        let total = xi.sum();
        if !(total.is_finite() && total > 0.0) {
            break;
        }
        xi /= total;
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::criteria::{information, POSE_ROWS};
    use crate::plan::test_support::random_stack;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// The certificate brackets the optimum: every exact design of N candidates is worse than
    /// the bound, and the approximate optimum is within the target gap of it.
    #[test]
    fn the_bound_holds_for_every_exact_design_tried() {
        let (p, n) = (6, 5);
        let b = random_stack(60, p, 3);
        let w = DMatrix::from_diagonal(&nalgebra::DVector::from_fn(p, |i, _| 1.0 + i as f64));
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for kind in [Criterion::A, Criterion::D, Criterion::G] {
            let o = approximate_optimum(&b, n, kind, &w).unwrap();
            match kind {
                Criterion::D | Criterion::G => {
                    assert!(
                        o.value <= o.bound
                            && o.bound - o.value <= -(p as f64) * (1.0 - TARGET_GAP).ln() + 1e-12
                    )
                }
                _ => assert!(o.value >= o.bound && o.bound >= (1.0 - TARGET_GAP) * o.value - 1e-12),
            }
            for _ in 0..300 {
                let pick = rand::seq::index::sample(&mut rng, 60, n).into_vec();
                let m = information(&b, POSE_ROWS, &DMatrix::zeros(p, p), &pick);
                let eff = o.efficiency_bound(&m, &w);
                assert!(
                    eff <= 1.0 + 1e-9,
                    "{kind:?}: an exact design beats the bound ({eff})"
                );
            }
        }
    }

    /// On a problem with a known optimum: two candidates, each measuring one of two parameters.
    #[test]
    fn known_optimum_of_two_orthogonal_candidates() {
        let mut b = DMatrix::zeros(6, 2);
        b[(0, 0)] = 1.0;
        b[(3, 1)] = 2.0;
        let w = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![1.0, 4.0]));
        let n = 10.0;
        // A: weights x, 1-x on var 1/(n x) and 1/(4 n (1-x)); phi = 1/(n x) + 4/(4 n (1-x))
        // minimised at x = 1/2: phi = 4/n
        let o = approximate_optimum(&b, 10, Criterion::A, &w).unwrap();
        assert!(
            (o.value - 4.0 / n).abs() < 4.0 / n * TARGET_GAP,
            "{}",
            o.value
        );
        // D and G (orthogonal columns: the same here) both put half the poses on each
        let best = (n * 0.5).ln() + (4.0 * n * 0.5).ln();
        for kind in [Criterion::D, Criterion::G] {
            let o = approximate_optimum(&b, 10, kind, &w).unwrap();
            assert!(
                (o.value - best).abs() < 1e-2 && o.bound >= best - 1e-12,
                "{o:?}"
            );
        }
    }
}
