//! The input model with only the instrument's frame fitted (registration only; with the tool
//! point when the run frees `@tool`, as a marker's place is unknown too): the meaningful
//! "before" of a run whose instrument frame is not the robot's (`calibrate --base`). The
//! unregistered figure (`calibration.before`) measures the distance between the two frames as
//! much as the robot's errors.

use super::calibrate::{CalibrateOptions, Method};
use super::calibrate_general::{calibrate_poses, GeneralOptions};
use super::prior::PriorMode;
use super::report::{CalibrateReport, StandardSummary};
use super::{CalibError, MeasuredSet};
use crate::model::Model;

/// Fits the base frame (`@base`: position and rotation) and, with `with_tool`, the tool point
/// (`@tool`: where the measured point sits on the last link, when the run fits it too), every
/// other parameter at its input value, with the standard method and every pose kept; the
/// errors after it on the calibration poses and, with `val`, on the held-out ones.
pub fn registration_only(
    nominal: &Model,
    cal: &MeasuredSet,
    val: Option<&MeasuredSet>,
    with_tool: bool,
) -> Result<StandardSummary, CalibError> {
    let opts = registration_options(with_tool);
    let g = calibrate_poses(nominal, cal, val, &opts, &GeneralOptions::default())?;
    Ok(registered_summary(&g.outcome.report))
}

/// The options of a registration (see [`registration_only`]): `@base` (and `@tool`), the
/// standard method, every pose kept, no prior.
pub fn registration_options(with_tool: bool) -> CalibrateOptions {
    let mut groups = vec!["@base".to_string()];
    if with_tool {
        groups.push("@tool".to_string());
    }
    CalibrateOptions {
        method: Method::Standard,
        params: Some(groups),
        base: true,
        keep_outliers: true,
        prior: PriorMode::Off,
        ..Default::default()
    }
}

/// The report's `registered`: the errors after a registration's fit (its report `r`).
pub fn registered_summary(r: &CalibrateReport) -> StandardSummary {
    StandardSummary {
        calibration: r.calibration.after,
        validation: r.validation.as_ref().map(|v| v.after),
    }
}
