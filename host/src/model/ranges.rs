//! Physical ranges of a model's values, checked where a model enters (a model file, `--set`,
//! a URDF), as [`crate::io::ranges`] does for CSV columns: finite values far beyond any robot
//! (a length of 1e308 mm, a gear-ratio error of 1e308) are refused as bad input instead of
//! reaching the numerics as infinities and NaN.
//!
//! | value | limit |
//! |---|---|
//! | lengths, offsets, prismatic limits, centres of mass (mm) | +-100 m |
//! | angles, revolute limits, clearance, backlash, harmonic amplitudes (deg) | +-10 000 deg |
//! | joint stiffness (kgf.m/deg) | (0, 1e12] |
//! | masses, payload (kg) | [0, 100 000] |
//! | measurement scale (ppm) | +-1e6 |
//! | `joint_scale` | +-1 |
//! | `joint_coupling` (deg/deg) | +-10 |
//! | `hysteresis_deg` | +-360 |
//! | `compliance_deg_per_kgfm` | +-1000 |
//! | `lateral_compliance_deg_per_kgfm` | +-1000 |
//! | `thermal_ppm` | +-1e5 (10 %) |
//! | `thermal_tau_min` | (0, 1e6] |
//! | `drift_mm_per_h`, `joint_drift_deg_per_h` | +-100 m/h, +-10 000 deg/h |

use super::chain::Model;
use super::param::Unit;
use crate::io::ranges::{MAX_ANGLE_DEG, MAX_OTHER, MAX_POSITION_MM};

/// Largest mass of a link or payload, kg.
pub const MAX_MASS_KG: f64 = 1e5;
/// Largest measurement scale error, ppm.
pub const MAX_SCALE_PPM: f64 = 1e6;
/// Largest transmission-ratio error (`joint_scale`).
pub const MAX_JOINT_SCALE: f64 = 1.0;
/// Largest coupling, deg/deg.
pub const MAX_COUPLING: f64 = 10.0;
/// Largest hysteresis, deg.
pub const MAX_HYSTERESIS_DEG: f64 = 360.0;
/// Largest compliance, deg per kgf.m.
pub const MAX_COMPLIANCE: f64 = 1e3;

/// Largest thermal growth, ppm.
pub const MAX_THERMAL_PPM: f64 = 1e5;
/// Largest thermal time constant, min.
pub const MAX_THERMAL_TAU_MIN: f64 = 1e6;

/// The limit of a parameter of unit `unit`.
pub fn unit_limit(unit: Unit) -> f64 {
    match unit {
        Unit::Deg => MAX_ANGLE_DEG,
        Unit::Mm => MAX_POSITION_MM,
        Unit::Kg => MAX_MASS_KG,
        Unit::Ppm => MAX_SCALE_PPM,
        Unit::KgfmPerDeg => MAX_OTHER,
    }
}

fn within(what: &str, v: f64, limit: f64) -> Result<(), String> {
    if v.is_finite() && v.abs() <= limit {
        Ok(())
    } else {
        Err(format!(
            "{what} = {}: out of physical range (|value| <= {limit})",
            crate::io::ranges::show(v)
        ))
    }
}

impl Model {
    /// Checks every value of the model against its physical range (see the module
    /// documentation); the error names the value.
    pub fn check_ranges(&self) -> Result<(), String> {
        for p in &self.params {
            within(&p.name, p.value, unit_limit(p.unit))?;
        }
        for (j, joint) in self.joints.iter().enumerate() {
            let limit = if joint.prismatic {
                MAX_POSITION_MM
            } else {
                MAX_ANGLE_DEG
            };
            within(&format!("joint {} min", j + 1), joint.limits[0], limit)?;
            within(&format!("joint {} max", j + 1), joint.limits[1], limit)?;
        }
        for (k, m) in self.masses.iter().enumerate() {
            within(&format!("mass {} kg", k + 1), m.mass_kg, MAX_MASS_KG)?;
            if m.mass_kg < 0.0 {
                return Err(format!("mass {} kg = {}: must be >= 0", k + 1, m.mass_kg));
            }
            for v in m.com_mm.iter() {
                within(&format!("mass {} com_mm", k + 1), *v, MAX_POSITION_MM)?;
            }
        }
        for (i, v) in self.lateral_deg_per_kgfm.iter().enumerate() {
            within(
                &format!("joint {} lateral_compliance_deg_per_kgfm", i + 1),
                *v,
                MAX_COMPLIANCE,
            )?;
        }
        let t = &self.transmission;
        for (i, v) in t.scale.iter().enumerate() {
            within(&format!("joint {} joint_scale", i + 1), *v, MAX_JOINT_SCALE)?;
        }
        for (i, v) in t.hysteresis_deg.iter().enumerate() {
            within(
                &format!("joint {} hysteresis_deg", i + 1),
                *v,
                MAX_HYSTERESIS_DEG,
            )?;
        }
        for (i, v) in t.compliance_deg_per_kgfm.iter().enumerate() {
            within(
                &format!("joint {} compliance_deg_per_kgfm", i + 1),
                *v,
                MAX_COMPLIANCE,
            )?;
        }
        for (i, row) in t.coupling.iter().enumerate() {
            for (k, v) in row.iter().enumerate() {
                within(
                    &format!("joint {} joint_coupling j{}", i + 1, k + 1),
                    *v,
                    MAX_COUPLING,
                )?;
            }
        }
        let time = &self.time_terms;
        within("[time] thermal_ppm", time.thermal_ppm, MAX_THERMAL_PPM)?;
        within(
            "[time] thermal_tau_min",
            time.thermal_tau_min,
            MAX_THERMAL_TAU_MIN,
        )?;
        if time.thermal_tau_min <= 0.0 {
            return Err(format!(
                "[time] thermal_tau_min = {}: must be > 0",
                crate::io::ranges::show(time.thermal_tau_min)
            ));
        }
        for v in time.drift_mm_per_h.iter() {
            within("[time] drift_mm_per_h", *v, MAX_POSITION_MM)?;
        }
        for c in &time.changes {
            within("[[change]] t_s", c.t_s, f64::MAX)?;
            match c.kind {
                super::changes::StepKind::Tool(d) => {
                    for v in d.iter() {
                        within("[[change]] tool_mm", *v, MAX_POSITION_MM)?;
                    }
                }
                super::changes::StepKind::Payload(kg) => {
                    within("[[change]] payload_kg", kg, MAX_MASS_KG)?;
                }
            }
        }
        for (j, v) in time.joint_drift_deg_per_h.iter().enumerate() {
            within(
                &format!("[time] joint_drift_deg_per_h j{}", j + 1),
                *v,
                MAX_ANGLE_DEG,
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn presets_are_within_range_and_absurd_values_are_not() {
        let mut m = crate::model::katana450(200.0).unwrap();
        m.check_ranges().unwrap();
        m.set_param("a2", 1e300).unwrap();
        assert!(m.check_ranges().unwrap_err().contains("a2"));
    }
}
