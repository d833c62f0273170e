//! The terms of a model that depend on the pose time `t` (s from the start of the session):
//! FORMATS.md effects `thermal`, `time_drift` and `time_drift:j<i>`.
//!
//! ```text
//! q_eff_j = q_j + r_j t / 3600                          joint-offset drift r_j, deg per hour
//! p       = (1 + s 1e-6 (1 - exp(-t / (60 tau)))) fk(q_eff) + v t / 3600
//! ```
//!
//! `thermal` (s ppm, tau min): the arm grows as it warms from the start of the session, every
//! length from its structural base (the origin of frame R) to the tool point by the same factor,
//! so the chain's position scales about the origin of R. `time_drift` (v mm per hour in R): the
//! measured position drifts linearly (the instrument or the base). A pose without a time has
//! `t = 0`, where every term vanishes.

use nalgebra::Vector3;

/// Seconds per hour (drift rates are per hour).
const S_PER_H: f64 = 3600.0;
/// Seconds per minute (the thermal time constant is in minutes).
const S_PER_MIN: f64 = 60.0;
/// The thermal time constant a model has when none is given, min (any positive value: with
/// `thermal_ppm` 0 it has no effect).
pub const DEFAULT_THERMAL_TAU_MIN: f64 = 20.0;

/// A model's time-dependent terms (all zero: none).
#[derive(Debug, Clone, PartialEq)]
pub struct TimeTerms {
    /// Thermal growth at saturation, ppm of every length.
    pub thermal_ppm: f64,
    /// Thermal time constant, min (> 0).
    pub thermal_tau_min: f64,
    /// Drift of the measured position, mm per hour in R.
    pub drift_mm_per_h: Vector3<f64>,
    /// Drift of each joint's offset, deg per hour (empty: none).
    pub joint_drift_deg_per_h: Vec<f64>,
    /// Changes within the session at a time ([`super::changes`]: `tool_change`,
    /// `payload_change`), in time order.
    pub changes: Vec<super::changes::Step>,
}

impl Default for TimeTerms {
    fn default() -> Self {
        Self {
            thermal_ppm: 0.0,
            thermal_tau_min: DEFAULT_THERMAL_TAU_MIN,
            drift_mm_per_h: Vector3::zeros(),
            joint_drift_deg_per_h: Vec::new(),
            changes: Vec::new(),
        }
    }
}

impl TimeTerms {
    /// No term, sized for `n_joints` joints.
    pub fn zeros(n_joints: usize) -> Self {
        Self {
            joint_drift_deg_per_h: vec![0.0; n_joints],
            ..Self::default()
        }
    }

    /// Whether any term is non-zero.
    pub fn is_active(&self) -> bool {
        self.thermal_ppm != 0.0
            || self.drift_mm_per_h != Vector3::zeros()
            || self.joint_drift_deg_per_h.iter().any(|r| *r != 0.0)
            || self.changes.iter().any(|c| c.is_active())
    }

    /// Joint `j`'s offset drift at `t_s`, deg.
    pub fn joint_drift_deg(&self, j: usize, t_s: f64) -> f64 {
        self.joint_drift_deg_per_h.get(j).copied().unwrap_or(0.0) * t_s / S_PER_H
    }

    /// The position drift at `t_s`, mm in R.
    pub fn drift_mm(&self, t_s: f64) -> Vector3<f64> {
        self.drift_mm_per_h * (t_s / S_PER_H)
    }

    /// The warm-up curve `1 - exp(-t / tau)` at `t_s` (0 for `t <= 0`).
    pub fn warm_up(&self, t_s: f64) -> f64 {
        warm_up(t_s, self.thermal_tau_min)
    }

    /// The position a measurement of the chain's position `chain_mm` (frame R) at `t_s` gives:
    /// thermal growth about the origin of R plus the drift.
    pub fn measured_mm(&self, chain_mm: &Vector3<f64>, t_s: f64) -> Vector3<f64> {
        self.grown_mm(chain_mm, t_s) + self.drift_mm(t_s)
    }

    /// The factor every length has grown by at `t_s`: `1 + s 1e-6 (1 - exp(-t / tau))`.
    pub fn growth_factor(&self, t_s: f64) -> f64 {
        1.0 + self.thermal_ppm * 1e-6 * self.warm_up(t_s)
    }

    /// The chain's position `chain_mm` grown by the warm-up at `t_s` (the tool point's real
    /// position, before the drift of the measurement).
    pub fn grown_mm(&self, chain_mm: &Vector3<f64>, t_s: f64) -> Vector3<f64> {
        chain_mm * self.growth_factor(t_s)
    }

    /// Derivatives of [`Self::measured_mm`] at `t_s`: with respect to `thermal_ppm` and to
    /// `thermal_tau_min` (mm per ppm, mm per min), and the factor multiplying the chain's
    /// position (its derivatives carry it to the chain's own Jacobian).
    pub fn thermal_derivatives(&self, chain_mm: &Vector3<f64>, t_s: f64) -> ThermalDerivatives {
        let tau_s = self.thermal_tau_min * S_PER_MIN;
        let w = self.warm_up(t_s);
        // d/dtau_min (1 - exp(-t / tau_s)) = -exp(-t / tau_s) t / tau_s^2 * 60
        let dw_dtau = if t_s > 0.0 && tau_s > 0.0 {
            -(-t_s / tau_s).exp() * t_s / (tau_s * tau_s) * S_PER_MIN
        } else {
            0.0
        };
        ThermalDerivatives {
            d_ppm: chain_mm * (1e-6 * w),
            d_tau_min: chain_mm * (self.thermal_ppm * 1e-6 * dw_dtau),
            factor: self.growth_factor(t_s),
        }
    }

    /// Derivative of the measured position with respect to drift axis `axis` (mm per mm/h).
    pub fn drift_column(axis: usize, t_s: f64) -> Vector3<f64> {
        let mut v = Vector3::zeros();
        v[axis.min(2)] = t_s / S_PER_H;
        v
    }

    /// Derivative of joint `j`'s angle with respect to its drift rate (deg per deg/h).
    pub fn joint_drift_regressor(t_s: f64) -> f64 {
        t_s / S_PER_H
    }
}

/// Derivatives of the measured position with respect to the thermal terms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThermalDerivatives {
    /// mm per ppm.
    pub d_ppm: Vector3<f64>,
    /// mm per min of the time constant.
    pub d_tau_min: Vector3<f64>,
    /// The factor on the chain's position (1 without growth).
    pub factor: f64,
}

/// `1 - exp(-t / tau)` (t in s, tau in min); 0 for `t <= 0` or a non-positive `tau`.
pub fn warm_up(t_s: f64, tau_min: f64) -> f64 {
    let tau_s = tau_min * S_PER_MIN;
    if t_s <= 0.0 || tau_s <= 0.0 {
        0.0
    } else {
        1.0 - (-t_s / tau_s).exp()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thermal_derivatives_match_central_differences() {
        let p = Vector3::new(400.0, -120.0, 310.0);
        let terms = TimeTerms {
            thermal_ppm: 150.0,
            thermal_tau_min: 25.0,
            ..TimeTerms::zeros(5)
        };
        for t_s in [0.0, 60.0, 900.0, 3600.0, 7200.0] {
            let d = terms.thermal_derivatives(&p, t_s);
            let h = 1e-3;
            let at = |ppm: f64, tau: f64| {
                TimeTerms {
                    thermal_ppm: ppm,
                    thermal_tau_min: tau,
                    ..terms.clone()
                }
                .measured_mm(&p, t_s)
            };
            let fd_ppm = (at(150.0 + h, 25.0) - at(150.0 - h, 25.0)) / (2.0 * h);
            let fd_tau = (at(150.0, 25.0 + h) - at(150.0, 25.0 - h)) / (2.0 * h);
            assert!(
                (fd_ppm - d.d_ppm).norm() <= 1e-9 + 1e-7 * fd_ppm.norm(),
                "t {t_s}"
            );
            assert!(
                (fd_tau - d.d_tau_min).norm() <= 1e-9 + 1e-6 * fd_tau.norm(),
                "t {t_s}"
            );
        }
    }

    #[test]
    fn no_growth_at_the_start_and_full_growth_late() {
        let terms = TimeTerms {
            thermal_ppm: 100.0,
            thermal_tau_min: 10.0,
            ..TimeTerms::zeros(2)
        };
        let p = Vector3::new(1000.0, 0.0, 0.0);
        assert_eq!(terms.measured_mm(&p, 0.0), p);
        let late = terms.measured_mm(&p, 100.0 * 600.0);
        assert!((late.x - 1000.1).abs() < 1e-9, "{late:?}");
    }
}
