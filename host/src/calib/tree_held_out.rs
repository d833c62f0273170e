//! Held-out gross errors on a tree: a chain's rule (FORMATS.md "Gross errors",
//! [`outliers::flag_held_out_dims`]) on the error norm of every held-out pose over its measured
//! tips. A pose is listed only when its error is inconsistent with the calibration's robust
//! scale **and** the tree fit's own prediction uncertainty at that pose (its covariance
//! propagated through the tree's Jacobian there), and stands apart from the other held-out
//! poses; a pose whose joints lie outside the calibration poses' ranges is never a gross error
//! (the fit extrapolates there) and is listed as `extrapolated` when the scale alone would
//! flag it.

use nalgebra::DMatrix;

use super::error::CalibError;
use super::fit::Fit;
use super::measured::MeasuredSet;
use super::outliers::{self, Extrapolated, OutlierReport, PoseError};
use super::prior::scaled_normal_inverse;
use super::tree_fit::{tree_errors, TreeUnknowns};
use crate::model::Tree;

/// The held-out poses a tree fit lists: flagged (left out of the held-out statistics, listed
/// in `outliers`) and extrapolated (kept, listed apart).
#[derive(Debug, Clone, Default)]
pub struct TreeHeldOut {
    /// Indices of the flagged held-out poses, ascending.
    pub flagged: Vec<usize>,
    pub reports: Vec<OutlierReport>,
    pub extrapolated: Vec<Extrapolated>,
}

/// Error norm (mm) of every pose of `set` over its measured tip points under `tree`.
pub fn pose_norms_mm(tree: &Tree, set: &MeasuredSet) -> Result<Vec<f64>, CalibError> {
    let errors = tree_errors(tree, set)?;
    let mut errors = errors.iter();
    Ok((0..set.len())
        .map(|k| {
            let n = set.measured_of(k).count();
            errors
                .by_ref()
                .take(n)
                .map(|v| v.norm_squared())
                .sum::<f64>()
                .sqrt()
        })
        .collect())
}

/// One standard deviation per coordinate (mm) of the fit's prediction at every pose of `at`:
/// `sigma_mm` times the root of the mean diagonal of `J_k (J^T J)^-1 J_k^T` over the pose's
/// measured coordinates (`J` the calibration Jacobian of the fitted unknowns, `J_k` the pose's
/// rows). Infinite where the calibration Jacobian cannot be inverted.
pub fn tree_prediction_sd_mm(
    fit: &Fit<Tree, String>,
    cal: &MeasuredSet,
    at: &MeasuredSet,
    sigma_mm: f64,
) -> Result<Vec<f64>, CalibError> {
    let n = fit.fitted.len();
    if n == 0 {
        return Ok(vec![0.0; at.len()]);
    }
    let u = TreeUnknowns::new(&fit.model, fit.fitted.clone())?;
    let j = u.jacobian(cal)?;
    let Some((d, inv)) = scaled_normal_inverse(&j, &nalgebra::DVector::zeros(n)) else {
        return Ok(vec![f64::INFINITY; at.len()]);
    };
    let jk = u.jacobian(at)?;
    let s2 = sigma_mm * sigma_mm;
    let mut row = 0;
    Ok((0..at.len())
        .map(|k| {
            let rows = 3 * at.measured_of(k).count();
            let block = DMatrix::from_fn(rows, n, |r, c| jk[(row + r, c)] / d[c]);
            row += rows;
            if rows == 0 {
                return 0.0;
            }
            let cov = &block * &inv * block.transpose();
            (s2 * cov.trace() / rows as f64).max(0.0).sqrt()
        })
        .collect())
}

/// The held-out poses of `val` that the fit `fit` on `cal` lists (see the module doc), judged
/// at the calibration's robust per-coordinate scale `sigma_mm`.
pub fn flag_tree_held_out(
    fit: &Fit<Tree, String>,
    cal: &MeasuredSet,
    val: &MeasuredSet,
    sigma_mm: f64,
) -> Result<TreeHeldOut, CalibError> {
    if val.is_empty() {
        return Ok(TreeHeldOut::default());
    }
    let norms = pose_norms_mm(&fit.model, val)?;
    let sd = tree_prediction_sd_mm(fit, cal, val, sigma_mm)?;
    let outside = outliers::outside_range(&cal.poses.q_deg, &val.poses.q_deg);
    let judged_sd: Vec<f64> = sd
        .iter()
        .zip(&outside)
        .map(|(s, o)| if o.is_empty() { *s } else { f64::INFINITY })
        .collect();
    let dims = 3 * val.n_slots().max(1);
    let (flagged, thresholds) = outliers::flag_held_out_dims(&norms, &judged_sd, sigma_mm, dims);
    let (plain, _) = outliers::flag_held_out_dims(&norms, &vec![0.0; val.len()], sigma_mm, dims);
    let extrapolated = plain
        .iter()
        .copied()
        .filter(|k| flagged.binary_search(k).is_err())
        .map(|k| Extrapolated {
            pose: PoseError::new("val", k, norms[k]),
            prediction_sd_mm: sd[k],
            outside_joints: outside[k].clone(),
        })
        .collect();
    let reports = outliers::held_out_reports(&flagged, &norms, &norms, &thresholds, &sd);
    Ok(TreeHeldOut {
        flagged,
        reports,
        extrapolated,
    })
}
