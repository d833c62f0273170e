//! Held-out poses that a parameter set within the fit's own uncertainty predicts: not gross
//! errors. A law with a sign step (the declared tilting's contact side, a backlash, a
//! hysteresis) makes the prediction jump where a joint's moment changes sign; near that point a
//! fitted value one standard deviation away puts the pose on the other side, and the pose's
//! error is the step, not a blunder. The linearised prediction uncertainty cannot see a step, so
//! every pose the gross-error rule flags is tried under the final model moved by
//! [`ENVELOPE_SIGMAS`] standard deviations along each principal direction of the fitted
//! unknowns' covariance (both signs): when one of those models predicts it within its
//! threshold, the pose stays in the statistics and is listed as predicted within the fit's
//! uncertainty.

use nalgebra::{DMatrix, DVector, SymmetricEigen};

use super::extended::{ExtModel, Unknown};
use crate::calib::fit::Fit;
use crate::calib::outliers::{OutlierReport, PoseError};
use crate::calib::unknown::Values;
use crate::calib::MeasuredSet;
use crate::model::ModelError;

/// How far along each principal direction the fitted unknowns are moved (standard deviations).
pub const ENVELOPE_SIGMAS: f64 = 3.0;

/// Directions whose scaled eigenvalue is below this share of the largest are not moved along
/// (they are not determined: the fit kept them out).
const EIGEN_RTOL: f64 = 1e-10;

/// The parameter steps (one per principal direction and sign) of `ENVELOPE_SIGMAS` standard
/// deviations of the fitted unknowns, from the calibration Jacobians `cal_jac` (3 x unknowns per
/// pose of `cal`) and the residual scale `sigma_mm` per measured component.
pub fn principal_steps(
    cal: &MeasuredSet,
    cal_jac: &[DMatrix<f64>],
    sigma_mm: f64,
) -> Vec<DVector<f64>> {
    let p = cal_jac.first().map_or(0, DMatrix::ncols);
    if p == 0 || !(sigma_mm.is_finite() && sigma_mm > 0.0) {
        return Vec::new();
    }
    let n = super::verdict::calibration_normal(cal, cal_jac, p);
    let d: Vec<f64> = (0..p).map(|c| n[(c, c)].max(0.0).sqrt()).collect();
    if d.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        return Vec::new();
    }
    let scaled = DMatrix::from_fn(p, p, |r, c| n[(r, c)] / (d[r] * d[c]));
    let eig = SymmetricEigen::new(scaled);
    let top = eig.eigenvalues.amax();
    let mut out = Vec::new();
    for (i, &lambda) in eig.eigenvalues.iter().enumerate() {
        if lambda.is_nan() || lambda <= EIGEN_RTOL * top {
            continue;
        }
        let size = ENVELOPE_SIGMAS * sigma_mm / lambda.sqrt();
        let step = DVector::from_fn(p, |c, _| size * eig.eigenvectors[(c, i)] / d[c]);
        out.push(step.clone());
        out.push(-step);
    }
    out
}

/// The smallest error norm (mm) of pose `k` of `val` under `last`'s model moved by each of
/// `steps` (on `last.fitted`), and under `last` itself.
pub fn best_error_mm(
    last: &Fit<ExtModel, Unknown>,
    steps: &[DVector<f64>],
    val: &MeasuredSet,
    k: usize,
) -> Result<f64, ModelError> {
    let one = val.subset(&[k]);
    let error = |m: &ExtModel| -> Result<f64, ModelError> {
        Ok(m.errors(&one)?.first().map_or(f64::INFINITY, |e| e.norm()))
    };
    let mut best = error(&last.model)?;
    for step in steps {
        let mut moved = last.model.clone();
        for (&u, &s) in last.fitted.iter().zip(step.iter()) {
            moved.set_value(u, last.model.value(u) + s)?;
        }
        if let Ok(e) = error(&moved) {
            best = best.min(e);
        }
    }
    Ok(best)
}

/// The flagged poses still gross errors, and those kept with the best model's error (mm).
pub type Split = (Vec<usize>, Vec<(usize, f64)>);

/// Splits the flagged held-out poses `flagged` (indices into `val`) into those still gross
/// errors and those a model within the fit's uncertainty predicts within their threshold
/// (`thresholds_mm[k]`), the latter with that model's error (mm).
pub fn within_uncertainty(
    last: &Fit<ExtModel, Unknown>,
    cal: &MeasuredSet,
    cal_jac: &[DMatrix<f64>],
    val: &MeasuredSet,
    flagged: &[usize],
    thresholds_mm: &[f64],
    sigma_mm: f64,
) -> Result<Split, ModelError> {
    if flagged.is_empty() {
        return Ok((Vec::new(), Vec::new()));
    }
    let steps = principal_steps(cal, cal_jac, sigma_mm);
    let mut gross = Vec::new();
    let mut explained = Vec::new();
    for &k in flagged {
        let best = best_error_mm(last, &steps, val, k)?;
        match thresholds_mm.get(k) {
            Some(&thr) if best <= thr => explained.push((k, best)),
            _ => gross.push(k),
        }
    }
    Ok((gross, explained))
}

/// The report entries of the held-out poses `kept` ([`within_uncertainty`]): their error
/// under the final model (`errors_mm`) and under the best model within the uncertainty.
pub fn reports(
    kept: &[(usize, f64)],
    errors_mm: &[f64],
    thresholds_mm: &[f64],
) -> Vec<OutlierReport> {
    kept.iter()
        .map(|&(k, best)| OutlierReport {
            pose: PoseError::new("val", k, errors_mm[k]),
            note: format!(
                "error {:.4} mm > {:.4} mm, but the model moved by at most {ENVELOPE_SIGMAS} standard \
                 deviations of its fitted values predicts it to {best:.4} mm (a sign step of a law \
                 near this pose, which the fit does not place exactly): not a gross error, kept in \
                 the statistics",
                errors_mm[k], thresholds_mm[k]
            ),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The steps are `ENVELOPE_SIGMAS` standard deviations: for independent unknowns with
    /// Jacobian columns of norms 2 and 10 on one pose, the steps are 3 s / 2 and 3 s / 10.
    #[test]
    fn steps_are_three_standard_deviations() {
        let set = MeasuredSet::from_poses(crate::calib::measured::PosePoints {
            q_deg: vec![vec![0.0, 30.0, -30.0, 10.0, 0.0]],
            xyz_mm: vec![nalgebra::Vector3::zeros()],
        });
        let j = DMatrix::from_row_slice(3, 2, &[2.0, 0.0, 0.0, 10.0, 0.0, 0.0]);
        let steps = principal_steps(&set, &[j], 0.5);
        assert_eq!(steps.len(), 4);
        let mut sizes: Vec<f64> = steps.iter().map(|s| s.amax()).collect();
        sizes.sort_by(f64::total_cmp);
        assert!((sizes[0] - 0.15).abs() < 1e-12, "{sizes:?}");
        assert!((sizes[3] - 0.75).abs() < 1e-12, "{sizes:?}");
    }
}
