//! What a design is expected to give: parameter sigmas for a given measurement noise, the
//! condition number and the observability index O1 of the column-scaled identification
//! Jacobian; and the same for random designs of the same size (the baseline).

use nalgebra::DMatrix;
use rand::seq::index::sample;
use rand::Rng;

use super::criteria::POSE_ROWS;
use crate::calib::fit::parameter_sigmas;
use crate::calib::identifiability::{scaled_svd, DEFAULT_RTOL};

/// Expected quality of a design.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignStats {
    /// One sigma of each parameter (parameter units) for the noise given; infinite when the
    /// design does not identify it.
    pub sigma: Vec<f64>,
    /// Condition number of the column-scaled Jacobian (infinite when rank deficient).
    pub condition_number: f64,
    /// Smallest singular value of the column-scaled Jacobian.
    pub min_singular_value: f64,
    /// Observability index O1 (Sun & Hollerbach): geometric mean of the singular values of the
    /// column-scaled Jacobian over the square root of the number of poses.
    pub o1: f64,
}

/// Stacks the block (rows `k c .. k c + k`, `k` = `rows`) of `b` of every `c` of `chosen` under
/// `prior_rows`, with the column scale `scale` undone (parameter units).
pub fn stack_rows(
    b: &DMatrix<f64>,
    rows: usize,
    scale: &[f64],
    prior_rows: &DMatrix<f64>,
    chosen: &[usize],
) -> DMatrix<f64> {
    let p = b.ncols();
    let m0 = prior_rows.nrows();
    let k = rows.max(1);
    DMatrix::from_fn(m0 + k * chosen.len(), p, |r, c| {
        let v = if r < m0 {
            prior_rows[(r, c)]
        } else {
            let i = r - m0;
            b[(k * chosen[i / k] + i % k, c)]
        };
        v * scale[c]
    })
}

/// The triangular factor `R` of the prior rows (QR): the same `J^T J`, column norms and singular
/// values as the prior rows, with at most as many rows as parameters, so that a random draw
/// costs the same whatever the number of poses already measured (the draws stack the prior
/// with the drawn poses hundreds of times).
pub fn compact_prior(prior_rows: &DMatrix<f64>) -> DMatrix<f64> {
    if prior_rows.nrows() > prior_rows.ncols() && prior_rows.iter().all(|v| v.is_finite()) {
        prior_rows.clone().qr().r()
    } else {
        prior_rows.clone()
    }
}

/// Expected sigmas (noise `noise_mm` per coordinate), condition number and O1 of the Jacobian
/// `jac` (parameter units) of `poses` poses.
pub fn design_stats(jac: &DMatrix<f64>, poses: usize, noise_mm: f64) -> DesignStats {
    let (m, n) = (jac.nrows(), jac.ncols());
    let dof = m.saturating_sub(n).max(1) as f64;
    let sigma = parameter_sigmas(jac, noise_mm * noise_mm * dof, DEFAULT_RTOL);
    let (_, s, _) = scaled_svd(jac);
    let lo = s.get(n.saturating_sub(1)).copied().unwrap_or(0.0);
    let hi = s.first().copied().unwrap_or(0.0);
    let cut = DEFAULT_RTOL * hi;
    let full = s.len() >= n && lo > cut;
    let o1 = if full && n > 0 {
        (s.iter().take(n).map(|x| x.ln()).sum::<f64>() / n as f64).exp()
            / (poses.max(1) as f64).sqrt()
    } else {
        0.0
    };
    DesignStats {
        sigma,
        condition_number: if full { hi / lo } else { f64::INFINITY },
        min_singular_value: if s.len() >= n { lo } else { 0.0 },
        o1,
    }
}

/// Median of finite-or-infinite values (`total_cmp` order); NaN for none.
pub fn median(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let k = v.len();
    if k % 2 == 1 {
        v[k / 2]
    } else {
        let (a, b) = (v[k / 2 - 1], v[k / 2]);
        if a.is_infinite() || b.is_infinite() {
            b
        } else {
            0.5 * (a + b)
        }
    }
}

/// The random baseline: `draws` designs of `n` distinct random candidates (plus the prior
/// rows); per parameter the median sigma over the draws, and the median condition number.
#[allow(clippy::too_many_arguments)]
pub fn random_baseline(
    b: &DMatrix<f64>,
    rows: usize,
    scale: &[f64],
    prior_rows: &DMatrix<f64>,
    n: usize,
    draws: usize,
    noise_mm: f64,
    rng: &mut impl Rng,
) -> DesignStats {
    random_baseline_draws(b, rows, scale, prior_rows, n, draws, noise_mm, rng).0
}

/// As [`random_baseline`], with every draw's sigmas (one vector per draw).
#[allow(clippy::too_many_arguments)]
pub fn random_baseline_draws(
    b: &DMatrix<f64>,
    rows: usize,
    scale: &[f64],
    prior_rows: &DMatrix<f64>,
    n: usize,
    draws: usize,
    noise_mm: f64,
    rng: &mut impl Rng,
) -> (DesignStats, Vec<Vec<f64>>) {
    let n_cand = b.nrows() / rows.max(1);
    let p = b.ncols();
    let prior_poses = prior_rows.nrows() / rows.max(1);
    let prior_rows = &compact_prior(prior_rows);
    let mut sig: Vec<Vec<f64>> = vec![Vec::with_capacity(draws); p];
    let mut per_draw = Vec::with_capacity(draws.max(1));
    let (mut conds, mut mins, mut o1s) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..draws.max(1) {
        let pick = sample(rng, n_cand, n.min(n_cand)).into_vec();
        let jac = stack_rows(b, rows, scale, prior_rows, &pick);
        let st = design_stats(&jac, prior_poses + pick.len(), noise_mm);
        for (k, s) in st.sigma.iter().enumerate() {
            sig[k].push(*s);
        }
        conds.push(st.condition_number);
        mins.push(st.min_singular_value);
        o1s.push(st.o1);
        per_draw.push(st.sigma);
    }
    let stats = DesignStats {
        sigma: sig.iter().map(|v| median(v)).collect(),
        condition_number: median(&conds),
        min_singular_value: median(&mins),
        o1: median(&o1s),
    };
    (stats, per_draw)
}

/// The direct reading of "median parameter sigma": the median over parameters of the
/// planned sigmas against the same median of each random design (mixed units: degrees and
/// millimetres are compared as numbers, so it depends on the unit choice).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectRatio {
    /// Median over parameters of the planned sigmas.
    pub planned: f64,
    /// Mean over the random draws of each draw's median sigma.
    pub random_mean: f64,
    /// Median over the random draws of each draw's median sigma.
    pub random_median: f64,
}

impl DirectRatio {
    /// From the planned sigmas and every random draw's sigmas (non-finite sigmas count as
    /// infinite in each median).
    pub fn new(planned: &[f64], draws: &[Vec<f64>]) -> Self {
        let med = |v: &[f64]| {
            let w: Vec<f64> = v
                .iter()
                .map(|x| if x.is_finite() { *x } else { f64::INFINITY })
                .collect();
            median(&w)
        };
        let per: Vec<f64> = draws.iter().map(|d| med(d)).collect();
        let finite: Vec<f64> = per.iter().copied().filter(|x| x.is_finite()).collect();
        let random_mean = if finite.len() == per.len() && !per.is_empty() {
            finite.iter().sum::<f64>() / finite.len() as f64
        } else {
            f64::INFINITY
        };
        Self {
            planned: med(planned),
            random_mean,
            random_median: median(&per),
        }
    }

    /// `planned / random_mean`.
    pub fn ratio_to_mean(&self) -> f64 {
        self.planned / self.random_mean
    }

    /// `planned / random_median`.
    pub fn ratio_to_median(&self) -> f64 {
        self.planned / self.random_median
    }
}

/// The spread of a chain plan's baseline: for each of `draws` random designs of `n` candidates (plus the
/// prior rows), the median over parameters of `planned[i] / sigma_i(draw)`.
#[allow(clippy::too_many_arguments)]
pub fn ratio_per_draw(
    b: &DMatrix<f64>,
    scale: &[f64],
    prior_rows: &DMatrix<f64>,
    planned: &[f64],
    n: usize,
    draws: usize,
    noise_mm: f64,
    rng: &mut impl Rng,
) -> Vec<f64> {
    let n_cand = b.nrows() / POSE_ROWS;
    let prior_poses = prior_rows.nrows() / POSE_ROWS;
    let prior_rows = &compact_prior(prior_rows);
    (0..draws)
        .map(|_| {
            let pick = sample(rng, n_cand, n.min(n_cand)).into_vec();
            let jac = stack_rows(b, POSE_ROWS, scale, prior_rows, &pick);
            let st = design_stats(&jac, prior_poses + pick.len(), noise_mm);
            median_ratio(planned, &st.sigma)
        })
        .collect()
}

/// The `q`-quantile (0..1, linear between order statistics) of the finite values; NaN for none.
pub fn quantile(values: &[f64], q: f64) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let pos = q.clamp(0.0, 1.0) * (v.len() - 1) as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    v[lo] + (v[hi] - v[lo]) * (pos - lo as f64)
}

/// Median over parameters of `planned / random` sigma (parameters with an infinite random
/// sigma count as ratio 0, those never identified are left out).
pub fn median_ratio(planned: &[f64], random: &[f64]) -> f64 {
    let r: Vec<f64> = planned
        .iter()
        .zip(random)
        .filter(|(p, _)| p.is_finite())
        .map(|(p, r)| {
            if r.is_finite() && *r > 0.0 {
                p / r
            } else {
                0.0
            }
        })
        .collect();
    median(&r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sigmas_follow_the_noise_and_the_pose_count() {
        let jac = DMatrix::from_fn(30, 3, |r, c| {
            ((r * (c + 1)) as f64 * 0.37).sin() + 0.1 * c as f64
        });
        let a = design_stats(&jac, 10, 0.01);
        let b = design_stats(&jac, 10, 0.02);
        for (x, y) in a.sigma.iter().zip(&b.sigma) {
            assert!((y / x - 2.0).abs() < 1e-9);
        }
        assert!(a.condition_number.is_finite() && a.condition_number >= 1.0);
        assert!(a.o1 > 0.0);
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[1.0, f64::INFINITY]), f64::INFINITY);
        assert!((median_ratio(&[1.0, 2.0, 3.0], &[2.0, 4.0, 6.0]) - 0.5).abs() < 1e-12);
    }
}
