//! The one table of physical bounds on the values an identification frees: a compliance (axial
//! or lateral), a
//! stiffness, a backlash, a clearance and a payload mass cannot be negative, a payload is not
//! heavier than the robot's own links ([`PAYLOAD_MAX_PER_LINK_MASS`]), a thermal time
//! constant is positive. `diagnose` holds a fitted value outside its bound at the bound
//! (`hold`) and refits the others; `plan --from-diagnose` sizes and moves values only within
//! them; the extended fit keeps a step of the time constant within its range.

use crate::model::unknown::Unknown;
use crate::model::Model;

/// The stiffness (kgf.m per deg) that holds a joint rigid: its deflection at 1 kgf.m is 1e-6 deg.
pub const RIGID_STIFFNESS_KGFM_PER_DEG: f64 = 1e6;

/// A payload heavier than this many times the model's own link masses is not a payload: a serial
/// arm carries well under its own weight (the Katana 450 0.5 kg on 3.7 kg of moving links, a UR5
/// 5 kg on 18 kg), so a fitted value above stands in for something the model lacks.
pub const PAYLOAD_MAX_PER_LINK_MASS: f64 = 1.0;

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

    /// The value a fitted `v` outside the bound is held at (`hold` below it, `max` above it);
    /// `None` for a physical value.
    pub fn outside(&self, v: f64) -> Option<f64> {
        if self.below(v) {
            Some(self.hold)
        } else if v > self.max {
            Some(self.max)
        } else {
            None
        }
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
                return Some(payload_bound(model));
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

/// [`bound`] of `u` on the fitted `model`, a payload's range widened to admit what `declared`
/// (the model the user gave) declares: a payload the user declared is a fact, not a fit to judge.
pub fn bound_declared(u: Unknown, model: &Model, declared: &Model) -> Option<Bound> {
    let mut b = bound(u, model)?;
    if let Unknown::Param(i) = u {
        if i == declared.payload_param() {
            if let Some(p) = declared.params().get(i).filter(|p| p.value.is_finite()) {
                b.max = b.max.max(p.value);
            }
        }
    }
    Some(b)
}

/// A payload's range: not negative, and at most [`PAYLOAD_MAX_PER_LINK_MASS`] times the model's
/// link masses; unbounded above on a model without link masses, which gives nothing to judge
/// by.
fn payload_bound(model: &Model) -> Bound {
    let links_kg: f64 = model.masses().iter().map(|m| m.mass_kg).sum();
    let max = if links_kg > 0.0 {
        PAYLOAD_MAX_PER_LINK_MASS * links_kg
    } else {
        f64::INFINITY
    };
    Bound {
        max,
        ..Bound::NON_NEGATIVE
    }
}
