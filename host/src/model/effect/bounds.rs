//! The one table of physical bounds on the values an identification frees: a compliance (axial
//! or lateral), a
//! stiffness, a backlash, a clearance and a payload mass cannot be negative, a thermal time
//! constant is positive. `diagnose` holds a fitted value outside its bound at the bound
//! (`hold`) and refits the others; `plan --from-diagnose` sizes and moves values only within
//! them; the extended fit keeps a step of the time constant within its range.

use crate::model::unknown::Unknown;
use crate::model::Model;

/// The stiffness (kgf.m per deg) that holds a joint rigid: its deflection at 1 kgf.m is 1e-6 deg.
pub const RIGID_STIFFNESS_KGFM_PER_DEG: f64 = 1e6;

/// The range of a thermal time constant, min (a fit's step is kept within it).
const THERMAL_TAU_RANGE_MIN: (f64, f64) = (1e-3, 1e6);

/// A physical bound of one value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bound {
    /// Smallest physical value.
    pub min: f64,
    /// Whether `min` itself is unphysical (a stiffness must be above 0).
    pub min_excluded: bool,
    /// Largest physical value.
    pub max: f64,
    /// The value a fitted value below `min` is held at (`min`; a rigid joint for a stiffness).
    pub hold: f64,
}

impl Bound {
    /// `v >= 0` (held at 0).
    const NON_NEGATIVE: Bound = Bound {
        min: 0.0,
        min_excluded: false,
        max: f64::INFINITY,
        hold: 0.0,
    };

    /// Whether `v` is below the bound.
    pub fn below(&self, v: f64) -> bool {
        if self.min_excluded {
            v <= self.min
        } else {
            v < self.min
        }
    }

    /// Whether `v` is a physical value.
    pub fn admits(&self, v: f64) -> bool {
        !self.below(v) && v <= self.max
    }

    /// `v` within `[min, max]` (a step of a fit kept in range).
    pub fn clamp(&self, v: f64) -> f64 {
        v.clamp(self.min, self.max)
    }
}

/// The physical bound of `u` on `model`, when it has one.
pub fn bound(u: Unknown, model: &Model) -> Option<Bound> {
    match u {
        Unknown::Compliance(_) | Unknown::LateralCompliance(_) => Some(Bound::NON_NEGATIVE),
        Unknown::ThermalTauMin => Some(Bound {
            min: THERMAL_TAU_RANGE_MIN.0,
            min_excluded: false,
            max: THERMAL_TAU_RANGE_MIN.1,
            hold: THERMAL_TAU_RANGE_MIN.0,
        }),
        Unknown::Param(i) => {
            if i == model.payload_param() {
                return Some(Bound::NON_NEGATIVE);
            }
            let tp = model.tilt_params()?;
            if tp.iter().any(|t| i == t.stiffness) {
                Some(Bound {
                    min_excluded: true,
                    hold: RIGID_STIFFNESS_KGFM_PER_DEG,
                    ..Bound::NON_NEGATIVE
                })
            } else if tp.iter().any(|t| i == t.backlash || i == t.clearance) {
                Some(Bound::NON_NEGATIVE)
            } else {
                None
            }
        }
        _ => None,
    }
}
