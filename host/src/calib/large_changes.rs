//! Plausibility of a calibration's result, after the fit: the parameters of the robot's own
//! geometry that moved further than a real arm's errors go, and a payload the robot's own links
//! make implausible (JSON `large_changes`; `calibrate`
//! exits 1 and writes no model unless asked to). The plausibility of a set before the fit is
//! [`super::plausible`].

use crate::model::Model;

/// The largest plausible change of a link length (or a prismatic joint's offset) by a
/// calibration, mm, and as a share of its nominal value (the larger of the two is the limit).
pub const MAX_LENGTH_CHANGE_MM: f64 = 20.0;
/// See [`MAX_LENGTH_CHANGE_MM`].
pub const MAX_LENGTH_CHANGE_SHARE: f64 = 0.05;
/// The largest plausible change of a joint offset or a twist by a calibration, deg. Real arms'
/// offsets are off by a few degrees at most; the real TIAGo's `arm_5_joint_offset` is identified
/// at -5.8 +- 0.5 deg from motion capture, so the limit leaves room above that.
pub const MAX_ANGLE_CHANGE_DEG: f64 = 10.0;

/// A parameter of the robot's own geometry that a calibration moved further than a real arm's
/// errors go (JSON `large_changes`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LargeChange {
    /// The parameter (`a2`, `dth6`).
    pub parameter: String,
    /// Its value in the model calibrated from (mm or deg).
    pub nominal: f64,
    /// Its calibrated value.
    pub calibrated: f64,
    /// The largest plausible change.
    pub limit: f64,
}

/// The parameters of the robot's geometry (joint offsets, twists, link lengths; not the base
/// or tool frames, which register the instrument and the measured point) that moved from
/// `nominal` to `calibrated` by more than a real arm's errors: 10 deg for an angle, the larger of
/// 20 mm and 5 % for a length. Such a change says the model, the units or the robot the poses
/// came from is wrong, or that the poses do not determine the parameter.
pub fn large_changes(nominal: &Model, calibrated: &Model) -> Vec<LargeChange> {
    use crate::model::{ParamKind, Unit};
    nominal
        .params()
        .iter()
        .zip(calibrated.params())
        .filter(|(p, _)| {
            matches!(
                p.kind,
                ParamKind::JointOffset | ParamKind::Twist | ParamKind::Length
            )
        })
        .filter_map(|(p, c)| {
            let limit = match p.unit {
                Unit::Deg => MAX_ANGLE_CHANGE_DEG,
                Unit::Mm => MAX_LENGTH_CHANGE_MM.max(MAX_LENGTH_CHANGE_SHARE * p.value.abs()),
                _ => return None,
            };
            let change = c.value - p.value;
            (change.abs() > limit || !change.is_finite()).then(|| LargeChange {
                parameter: p.name.clone(),
                nominal: p.value,
                calibrated: c.value,
                limit,
            })
        })
        .collect()
}

/// Sigmas beyond its bound at which a fitted payload is implausible, not noise about a
/// physical value.
pub const PAYLOAD_SIGMAS: f64 = 3.0;

/// The calibrated payload against what the model's link masses make plausible
/// ([`crate::model::effect::bound`]: not negative, not heavier than the links), with its
/// `sigma`: further outside than [`PAYLOAD_SIGMAS`] sigma (or with no sigma) it is a large
/// change (the mass stands in for something the model lacks: a joint's stiffness, the link
/// masses themselves); outside within that, a line for `unphysical` (the poses hardly determine
/// it); inside, nothing.
pub fn payload_plausibility(
    nominal: &Model,
    calibrated: &Model,
    sigma: Option<f64>,
) -> (Option<LargeChange>, Option<String>) {
    let i = nominal.payload_param();
    let (Some(p), Some(c)) = (nominal.params().get(i), calibrated.params().get(i)) else {
        return (None, None);
    };
    let u = crate::model::unknown::Unknown::Param(i);
    let Some(b) = crate::model::effect::bound_declared(u, calibrated, nominal) else {
        return (None, None);
    };
    let v = c.value;
    // a payload the fit left as declared is the user's, not the fit's
    if v == p.value || (v.is_finite() && b.outside(v).is_none()) {
        return (None, None);
    }
    let (edge, beyond) = if v < b.min {
        (b.min, b.min - v)
    } else {
        (b.max, v - b.max)
    };
    match sigma.filter(|s| s.is_finite() && *s > 0.0) {
        Some(s) if v.is_finite() && beyond <= PAYLOAD_SIGMAS * s => {
            let line = format!(
                "{} = {v:.4} +- {s:.4} kg is outside its physical range (0 to {:.4} kg, the \
                 robot's link masses) within {PAYLOAD_SIGMAS} sigma of {edge}: the poses hardly \
                 determine it",
                p.name, b.max
            );
            (None, Some(line))
        }
        _ => {
            // as printed in a message (the sum of the link masses carries rounding digits)
            let limit = ((edge - p.value).abs() * 1e6).round() / 1e6;
            let change = LargeChange {
                parameter: p.name.clone(),
                nominal: p.value,
                calibrated: v,
                limit,
            };
            (Some(change), None)
        }
    }
}

/// One line naming `changes` for a message.
pub fn large_changes_line(changes: &[LargeChange]) -> String {
    changes
        .iter()
        .map(|c| {
            format!(
                "{} {:.4} -> {:.4} (limit +-{})",
                c.parameter, c.nominal, c.calibrated, c.limit
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changes_beyond_a_real_arms_errors_are_named() {
        let nominal = crate::model::ur5().unwrap();
        let mut c = nominal.clone();
        c.set_param("a2", -425.0 + 21.0).unwrap();
        c.set_param("dth6", 9.9).unwrap();
        c.set_param("al4", nominal.param("al4").unwrap() + 10.1)
            .unwrap();
        c.set_param("tool_dz", 300.0).unwrap();
        c.set_param("base_x", 2000.0).unwrap();
        let names: Vec<String> = large_changes(&nominal, &c)
            .into_iter()
            .map(|l| l.parameter)
            .collect();
        assert_eq!(
            names,
            ["al4"],
            "a2 within 5 % of 425 mm, dth6 within 10 deg"
        );
        c.set_param("a2", -425.0 * 1e-3).unwrap();
        let line = large_changes_line(&large_changes(&nominal, &c));
        assert!(line.starts_with("a2 -425.0000 -> -0.4250"), "{line}");
    }
}
