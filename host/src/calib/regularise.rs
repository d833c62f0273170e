//! The prior of an identification on full positions, chosen ([`super::prior`]): off on a
//! well-posed set, otherwise the weight of lowest leave-one-pose-out PRESS.

use serde::Serialize;

use super::accumulator::position_errors;
use super::error::CalibError;
use super::fit::{Fit, PriorAt};
use super::identifiability::analyse;
use super::lm::LmConfig;
use super::measured::PosePoints;
use super::position_fit::fit_parameters;
use super::prior::{choose_weight, ill_posed, ridge_press, PriorMode, PriorScales};
use super::problem::stacked_jacobian;
use crate::model::Model;
use nalgebra::DVector;

/// The prior in force and why (`prior` of the `calibrate --json` document).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PriorChoice {
    /// Weight (mm^2 per squared scale); 0 = no prior.
    pub weight: f64,
    /// Scale of a length (mm).
    pub length_scale_mm: f64,
    /// Scale of an angle (deg).
    pub angle_scale_deg: f64,
    /// `"off"`, `"given"`, `"well_posed"` (auto, and the set is not ill-posed) or
    /// `"cross_validation"`.
    pub chosen_by: String,
    /// Measured coordinates per selected parameter.
    pub redundancy: f64,
    /// Leave-one-pose-out PRESS (mm^2) of every weight tried (cross-validation only).
    pub press: Vec<(f64, f64)>,
}

impl PriorChoice {
    /// The prior of the fits, `None` at weight 0.
    pub fn at<'a>(&self, scales: &'a PriorScales, center: &'a Model) -> Option<PriorAt<'a>> {
        (self.weight > 0.0).then_some(PriorAt {
            weight: self.weight,
            scales,
            center,
        })
    }

    /// One line for the text output (`None` when no prior was considered).
    pub fn line(&self) -> Option<String> {
        match self.chosen_by.as_str() {
            "cross_validation" if self.weight > 0.0 => Some(format!(
                "prior: the robot's lengths and angles drawn toward their input values ({} mm, {} \
                 deg) with weight {} chosen by leave-one-pose-out cross-validation ({:.1} measured \
                 coordinates per parameter: an ill-posed set)",
                self.length_scale_mm, self.angle_scale_deg, self.weight, self.redundancy
            )),
            "cross_validation" => Some(format!(
                "prior: none (ill-posed set, {:.1} measured coordinates per parameter, but no prior \
                 weight predicted the left-out poses better)",
                self.redundancy
            )),
            "given" => Some(format!(
                "prior: weight {} ({} mm, {} deg), as given",
                self.weight, self.length_scale_mm, self.angle_scale_deg
            )),
            _ => None,
        }
    }
}

/// The prior of an identification of `selection` on `poses` from `nominal` (tilting as `tilt`)
/// under `mode`.
#[allow(clippy::too_many_arguments)]
pub fn choose_prior(
    nominal: &Model,
    poses: &PosePoints,
    selection: &[usize],
    tilt: bool,
    lm: &LmConfig,
    rtol: f64,
    mode: PriorMode,
    scales: &PriorScales,
) -> Result<PriorChoice, CalibError> {
    let n_res = 3 * poses.len();
    // measured coordinates per parameter the poses can determine (the rank at the start; the
    // selection's size when it is clearly well-posed anyway)
    let n_par = if ill_posed(n_res, selection.len()) {
        analyse(&stacked_jacobian(nominal, poses, selection, tilt)?, rtol).rank
    } else {
        selection.len()
    };
    let redundancy = n_res as f64 / n_par.max(1) as f64;
    let choice = |weight: f64, by: &str, press: Vec<(f64, f64)>| PriorChoice {
        weight,
        length_scale_mm: scales.length_mm,
        angle_scale_deg: scales.angle_deg,
        chosen_by: by.into(),
        redundancy,
        press,
    };
    let has_prior_rows = selection.iter().any(|&i| scales.of(nominal, i).is_some());
    match mode {
        PriorMode::Off => return Ok(choice(0.0, "off", Vec::new())),
        PriorMode::Weight(w) => return Ok(choice(w, "given", Vec::new())),
        PriorMode::Auto if !ill_posed(n_res, n_par) || !has_prior_rows => {
            return Ok(choice(0.0, "well_posed", Vec::new()))
        }
        PriorMode::Auto => {}
    }
    let blocks = vec![3; poses.len()];
    let (weight, press) = choose_weight(|w| -> Result<Option<f64>, CalibError> {
        let at = PriorAt {
            weight: w,
            scales,
            center: nominal,
        };
        let fit = match fit_parameters(nominal, poses, selection, tilt, lm, rtol, Some(at)) {
            Ok(f) => f,
            Err(CalibError::NothingToFit) => return Ok(None),
            Err(e) => return Err(e),
        };
        score(&fit, poses, tilt, &at, &blocks)
    })?;
    Ok(choice(weight, "cross_validation", press))
}

/// Block PRESS of `fit`'s linearisation at its solution with the prior `at`.
fn score(
    fit: &Fit,
    poses: &PosePoints,
    tilt: bool,
    at: &PriorAt<'_>,
    blocks: &[usize],
) -> Result<Option<f64>, CalibError> {
    let jac = stacked_jacobian(&fit.model, poses, &fit.fitted, tilt)?;
    let e = position_errors(&fit.model, poses, tilt)?;
    let r = DVector::from_iterator(3 * e.len(), e.iter().flat_map(|v| v.iter().copied()));
    let diag = if at.weight > 0.0 {
        at.on(&fit.fitted).normal()
    } else {
        DVector::zeros(fit.fitted.len())
    };
    Ok(ridge_press(&jac, &r, &diag, blocks))
}
