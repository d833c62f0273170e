//! Forward selection of the probe's terms by cross-validated error (see [`super`] for the rule).

use super::design::Design;
use super::{ProbeConfig, TermShare};
use crate::calib::stats::autocorrelation_time;
use crate::diagnose::stat::f_test_p_value;

/// The outcome of [`forward`].
#[derive(Debug, Clone, PartialEq)]
pub struct Selected {
    /// Indices into [`Design::terms`], in the order they entered.
    pub selected: Vec<usize>,
    /// Their shares of the baseline squared error.
    pub shares: Vec<TermShare>,
    /// Sum of the squared measured residual (predicting nothing), mm^2.
    pub baseline_sse: f64,
    /// Held-out sum of squared errors with the selected terms, mm^2.
    pub final_sse: f64,
}

/// Relative decrease of `sum e0` to `sum e1` and the one-sided paired t statistic of
/// `e0 - e1` (divided by the square root of its autocorrelation time when `serial`), with the
/// effective number of pairs.
pub fn paired(e0: &[f64], e1: &[f64], serial: bool) -> (f64, f64, f64) {
    let n = e0.len().min(e1.len());
    if n < 3 {
        return (0.0, 0.0, n as f64);
    }
    let d: Vec<f64> = e0.iter().zip(e1).map(|(a, b)| a - b).collect();
    let nf = n as f64;
    let mean = d.iter().sum::<f64>() / nf;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (nf - 1.0);
    let s0: f64 = e0.iter().sum();
    let rel = if s0 > 0.0 { mean * nf / s0 } else { 0.0 };
    let tau = if serial {
        autocorrelation_time(&d)
    } else {
        1.0
    };
    let t = if var > 0.0 {
        mean / (var / nf).sqrt() / tau.sqrt()
    } else if mean > 0.0 {
        f64::INFINITY
    } else {
        0.0
    };
    (rel, t, nf / tau)
}

/// One-sided p-value of a t statistic with `n_eff` pairs.
fn one_sided_p(t: f64, n_eff: f64) -> f64 {
    if t.is_nan() || t <= 0.0 {
        return 1.0;
    }
    if t.is_infinite() {
        return 0.0;
    }
    0.5 * f_test_p_value(t * t, 1.0, (n_eff - 1.0).max(1.0))
}

/// Forward selection over `design`'s terms; `n_components` measured components in all.
pub fn forward(design: &Design, serial: bool, n_components: usize, cfg: &ProbeConfig) -> Selected {
    let sse_of = |r: &[nalgebra::Vector3<f64>]| r.iter().map(|v| v.norm_squared()).sum::<f64>();
    let mut cur = design.null_residuals().to_vec();
    let baseline_sse = sse_of(&cur);
    let mut selected: Vec<usize> = Vec::new();
    let mut shares = Vec::new();
    // a training fold holds about (folds - 1) / folds of the components
    let train_rows = n_components * (cfg.folds.max(2) - 1) / cfg.folds.max(2);
    while selected.len() < cfg.max_terms && baseline_sse > 0.0 {
        let tried: Vec<usize> = (0..design.terms().len())
            .filter(|t| !selected.contains(t))
            .collect();
        let mut best: Option<(usize, Vec<nalgebra::Vector3<f64>>, f64)> = None;
        for &t in &tried {
            let mut s = selected.clone();
            s.push(t);
            let cols = design.columns(&s);
            // keep at least two training residuals per coefficient
            if 2 * 3 * cols.len() > train_rows {
                continue;
            }
            let Some(e) = design.cv_residuals(&cols) else {
                continue;
            };
            let sse = sse_of(&e);
            if best.as_ref().is_none_or(|b| sse < b.2) {
                best = Some((t, e, sse));
            }
        }
        let Some((t, e, sse)) = best else {
            break;
        };
        let (_, tstat, n_eff) = paired(&design.slots(&cur), &design.slots(&e), serial);
        let cur_sse = sse_of(&cur);
        let rel = if cur_sse > 0.0 {
            1.0 - sse / cur_sse
        } else {
            0.0
        };
        let p = one_sided_p(tstat, n_eff);
        let floor_ok = cfg.floor_mm.is_none_or(|f| {
            let explained_ms = (cur_sse - sse) / n_components.max(1) as f64;
            explained_ms >= (cfg.floor_min_ratio * f).powi(2)
        });
        if rel < cfg.min_gain || p * tried.len() as f64 >= cfg.alpha || !floor_ok {
            break;
        }
        shares.push(TermShare {
            term: design.terms()[t].name(),
            share: (cur_sse - sse) / baseline_sse,
            t: tstat,
        });
        selected.push(t);
        cur = e;
    }
    Selected {
        selected,
        shares,
        baseline_sse,
        final_sse: sse_of(&cur),
    }
}
