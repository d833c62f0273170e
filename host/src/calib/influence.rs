//! Influence-based identification (thesis section 3.6, eq. 3.7-3.8), as read here.
//!
//! * **Influence** (section 3.5): at each pose, the position change caused by a deviation of
//!   0.05 deg of an angular parameter or 0.1 mm of a linear one; to first order
//!   `I_j = |J_j| * delta_j`. The influence vector is `k_j = I_j / max_j I_j` (the most
//!   influential parameter gets 1, e.g. `k_2 = 1` for theta_2 at 0.34 mm, `k_8 = 0.59`).
//! * **Per-pose iteration** (eq. 3.7-3.8): with `K = diag(k)` the error model is
//!   `dP = J (K dE)`; the minimum-norm correction of eq. 3.6 applied to `J K` and damped by the
//!   coefficient `C < 1` gives the parameter update `C K (J K)^T ((J K)(J K)^T)^-1 dP`. So the
//!   correction is shared out in proportion to `k^2`: influential parameters take most of it,
//!   weak ones (theta_3 in the thesis's example with theta_4 at 80 deg) little. It is repeated,
//!   re-evaluating `dP` and `J` with the corrected parameters, until `|dP|` is below the
//!   detectable 0.01 mm or an iteration cap.
//! * **Combination**: "from the sets of errors of all poses, a set of kinematics parameters is
//!   calculated that best fit the accuracy to all measured poses". Each pose gives one set; the
//!   candidates are their element-wise mean and median, and the one with the smaller mean error
//!   over all calibration poses is kept.
//!
//! A per-pose minimum-norm solution only sees the 3 directions one pose can observe, so this is
//! in general not the least-squares optimum; the report shows how it compares.

use nalgebra::{DVector, Matrix3};

use super::accumulator::position_errors;
use super::error::CalibError;
use super::measured::PosePoints;
use super::problem::{param_vector, set_params};
use crate::model::{Model, Tilt, Unit};

/// Settings of the influence-based identification.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InfluenceConfig {
    /// Coefficient `C < 1` of eq. 3.8.
    pub coefficient: f64,
    /// Per-pose stop: position error below this (mm; the thesis's 0.01 mm resolution).
    pub tolerance_mm: f64,
    /// Per-pose iteration cap.
    pub max_iterations: usize,
    /// Deviation used for the influence of angular parameters (deg).
    pub angular_deviation_deg: f64,
    /// Deviation used for the influence of linear parameters (mm).
    pub linear_deviation_mm: f64,
}

impl Default for InfluenceConfig {
    fn default() -> Self {
        Self {
            coefficient: 0.5,
            tolerance_mm: 0.01,
            max_iterations: 200,
            angular_deviation_deg: 0.05,
            linear_deviation_mm: 0.1,
        }
    }
}

/// Result of [`fit_influence`].
#[derive(Debug, Clone)]
pub struct InfluenceFit {
    /// The model with the combined parameter set.
    pub model: Model,
    /// Total per-pose iterations.
    pub iterations: usize,
    /// Poses whose iteration reached the tolerance.
    pub poses_converged: usize,
    /// `"mean"` or `"median"`: the combination kept.
    pub combination: &'static str,
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        0.0
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Influence-based identification of the parameters `cols` of `start` (no tilting, as in
/// thesis chapter 3).
pub fn fit_influence(
    start: &Model,
    poses: &PosePoints,
    cols: &[usize],
    cfg: &InfluenceConfig,
) -> Result<InfluenceFit, CalibError> {
    if poses.is_empty() {
        return Err(CalibError::NoPoses);
    }
    let n = cols.len();
    let deviation: Vec<f64> = cols
        .iter()
        .map(|&c| {
            if start.params().get(c).is_some_and(|p| p.unit == Unit::Deg) {
                cfg.angular_deviation_deg
            } else {
                cfg.linear_deviation_mm
            }
        })
        .collect();
    let x0 = param_vector(start, cols);
    let mut per_pose: Vec<DVector<f64>> = Vec::with_capacity(poses.len());
    let mut iterations = 0;
    let mut poses_converged = 0;
    let mut model = start.clone();
    for (q, measured) in poses.q_deg.iter().zip(&poses.xyz_mm) {
        let mut x = x0.clone();
        for it in 0..=cfg.max_iterations {
            set_params(&mut model, cols, &x)?;
            let (fk, j) = model.param_jacobian(q, Tilt::Off, cols)?;
            let dp = measured - fk.position_mm;
            if dp.norm() < cfg.tolerance_mm {
                poses_converged += 1;
                break;
            }
            if it == cfg.max_iterations {
                break;
            }
            iterations += 1;
            // Influence vector k of this configuration.
            let infl: Vec<f64> = (0..n).map(|c| j.column(c).norm() * deviation[c]).collect();
            let top = infl.iter().copied().fold(0.0, f64::max);
            if top <= 0.0 {
                break;
            }
            let k = DVector::from_iterator(n, infl.iter().map(|i| i / top));
            let mut jk = j.clone();
            for c in 0..n {
                jk.column_mut(c).scale_mut(k[c]);
            }
            let gram: Matrix3<f64> = &jk * jk.transpose();
            // Pseudo-inverse of the 3x3 Gram matrix (a pose may see fewer than 3 directions).
            let Ok(pinv) = gram.pseudo_inverse(1e-12 * gram.norm()) else {
                break;
            };
            let de = jk.transpose() * (pinv * dp);
            x += de.component_mul(&k) * cfg.coefficient;
        }
        per_pose.push(x);
    }
    let mean = per_pose.iter().fold(DVector::zeros(n), |a, x| a + x) / per_pose.len() as f64;
    let med = DVector::from_iterator(
        n,
        (0..n).map(|c| {
            let mut v: Vec<f64> = per_pose.iter().map(|x| x[c]).collect();
            median(&mut v)
        }),
    );
    let mut best: Option<(f64, Model, &'static str)> = None;
    for (cand, label) in [(mean, "mean"), (med, "median")] {
        let mut m = start.clone();
        set_params(&mut m, cols, &cand)?;
        let e = position_errors(&m, poses, false)?;
        let mean_mm = e.iter().map(|v| v.norm()).sum::<f64>() / e.len() as f64;
        if best.as_ref().is_none_or(|(b, _, _)| mean_mm < *b) {
            best = Some((mean_mm, m, label));
        }
    }
    let (_, model, combination) = best.ok_or(CalibError::NoPoses)?;
    Ok(InfluenceFit {
        model,
        iterations,
        poses_converged,
        combination,
    })
}
