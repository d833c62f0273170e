//! How well a fit predicts a pose it was not fitted on: the standard deviation of the model's
//! prediction from the covariance of the fitted parameters, `J_k s^2 (J^T J + P)^-1 J_k^T`
//! (`J` the calibration poses' Jacobian, `P` the prior's normal matrix, `J_k` the pose's rows).
//! A held-out pose far from the calibration poses has a large one: its error is extrapolation,
//! not a gross error ([`super::outliers::flag_held_out`]).

use nalgebra::{DMatrix, DVector};

use super::error::CalibError;
use super::fit::Fit;
use super::measured::PosePoints;
use super::prior::{scaled_normal_inverse, Prior};
use super::problem::stacked_jacobian;

/// One standard deviation per coordinate (mm) of `fit`'s prediction at every pose of `at`: the
/// square root of a third of the trace of the pose's prediction covariance, with the
/// calibration poses `cal` (those `fit` was fitted on), the residual scale `sigma_mm` per
/// coordinate and the prior `prior` (on `fit.fitted`) of the fit.
pub fn prediction_sd_mm(
    fit: &Fit,
    cal: &PosePoints,
    at: &PosePoints,
    tilt: bool,
    sigma_mm: f64,
    prior: Option<&Prior>,
) -> Result<Vec<f64>, CalibError> {
    let n = fit.fitted.len();
    if n == 0 {
        return Ok(vec![0.0; at.len()]);
    }
    let j = stacked_jacobian(&fit.model, cal, &fit.fitted, tilt)?;
    let diag = prior.map_or_else(|| DVector::zeros(n), Prior::normal);
    let Some((d, inv)) = scaled_normal_inverse(&j, &diag) else {
        return Ok(vec![f64::INFINITY; at.len()]);
    };
    let jk = stacked_jacobian(&fit.model, at, &fit.fitted, tilt)?;
    let s2 = sigma_mm * sigma_mm;
    Ok((0..at.len())
        .map(|k| {
            let rows = DMatrix::from_fn(3, n, |r, c| jk[(3 * k + r, c)] / d[c]);
            let cov = &rows * &inv * rows.transpose();
            (s2 * cov.trace() / 3.0).max(0.0).sqrt()
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::lm::LmConfig;
    use crate::calib::position_fit::fit_parameters;
    use nalgebra::Vector3;

    /// Poses far from the calibration poses are predicted less well than poses among them.
    #[test]
    fn far_poses_have_larger_prediction_uncertainty() {
        let m = crate::model::katana450(0.0).unwrap();
        let pose = |a: f64| vec![10.0, a, -40.0 + 0.3 * a, 20.0, 10.0];
        let make = |angles: &[f64]| -> PosePoints {
            let q: Vec<Vec<f64>> = angles.iter().map(|&a| pose(a)).collect();
            let xyz: Vec<Vector3<f64>> = q
                .iter()
                .map(|q| m.position_mm(q, crate::model::Tilt::Off).unwrap())
                .collect();
            PosePoints {
                q_deg: q,
                xyz_mm: xyz,
            }
        };
        let cal = make(&(0..30).map(|i| 40.0 + i as f64).collect::<Vec<_>>());
        let at = make(&[55.0, 150.0]);
        let sel: Vec<usize> = ["dth2", "dth3", "a2", "a3"]
            .iter()
            .filter_map(|n| m.param_index(n))
            .collect();
        let fit = fit_parameters(&m, &cal, &sel, false, &LmConfig::default(), 1e-4, None).unwrap();
        let sd = prediction_sd_mm(&fit, &cal, &at, false, 0.1, None).unwrap();
        assert!(sd[0] > 0.0 && sd[1] > 2.0 * sd[0], "{sd:?}");
        let none = Fit {
            fitted: Vec::new(),
            ..fit
        };
        assert_eq!(
            prediction_sd_mm(&none, &cal, &at, false, 0.1, None).unwrap(),
            [0.0, 0.0]
        );
    }
}
