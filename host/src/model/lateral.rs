//! Lateral compliance (effect `lateral_compliance:j<i>`): joint i bends about the two axes of
//! joint frame i perpendicular to its own axis, in proportion to the static gravity moments
//! about them,
//!
//! ```text
//! (da_i, db_i) = c_i (eta_x, eta_y)       deg; c_i deg per kgf.m, one isotropic value per joint
//! ```
//!
//! with `eta_i` the moment of MODEL.md (kgf.m, joint frame i, the untilted chain: the model's
//! link masses and payload). The bend is applied where the declared tilting is (MODEL.md
//! "Joint tilting": `Rx(da) . Ry(db)` in joint frame i, right after the joint's rotation) and
//! added to the declared tilt when the model has one, so the tilted chain, its moments and the
//! analytic Jacobian (`jacobian.rs`, the tilt's slope `d tilt / d eta` gains `c_i` on its x and
//! y diagonal) are the tilting's. A model without link masses has no moments and so no bend.
//! The axial counterpart is `compliance:j<i>` ([`super::transmission`]).

use nalgebra::Vector3;

use super::{Model, ModelError};

/// The bend `(da, db, 0)` (deg) of a joint with lateral compliance `c` (deg per kgf.m) under the
/// moment `eta` (kgf.m, joint frame i).
pub fn lateral_tilt_deg(c: f64, eta: &Vector3<f64>) -> Vector3<f64> {
    lateral_regressor(eta) * c
}

/// The derivative of [`lateral_tilt_deg`] with respect to `c`: `(eta_x, eta_y, 0)`.
pub fn lateral_regressor(eta: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(eta.x, eta.y, 0.0)
}

impl Model {
    /// The lateral compliances per joint (deg per kgf.m; empty: none).
    pub fn lateral_compliance(&self) -> &[f64] {
        &self.lateral_deg_per_kgfm
    }

    /// Joint `j`'s lateral compliance (0-based; 0 when absent).
    pub fn lateral_compliance_at(&self, j: usize) -> f64 {
        self.lateral_deg_per_kgfm.get(j).copied().unwrap_or(0.0)
    }

    /// Whether some joint bends laterally (a non-zero value).
    pub fn has_lateral_compliance(&self) -> bool {
        self.lateral_deg_per_kgfm.iter().any(|c| *c != 0.0)
    }

    /// Sets joint `j`'s lateral compliance (0-based, deg per kgf.m).
    pub fn set_lateral_compliance(&mut self, j: usize, c: f64) -> Result<(), ModelError> {
        let n = self.joints.len();
        if j >= n {
            return Err(ModelError::JointIndex { index: j, count: n });
        }
        if !c.is_finite() {
            return Err(ModelError::NonFinite {
                name: format!("lateral_compliance_j{}_deg_per_kgfm", j + 1),
                value: c,
            });
        }
        self.lateral_deg_per_kgfm.resize(n, 0.0);
        self.lateral_deg_per_kgfm[j] = c;
        Ok(())
    }

    /// Drops the lateral compliances when all are zero (a model without them reads back as one
    /// that never had them).
    pub fn clear_zero_lateral_compliance(&mut self) {
        if !self.has_lateral_compliance() {
            self.lateral_deg_per_kgfm.clear();
        }
    }
}

#[cfg(test)]
mod tests;
