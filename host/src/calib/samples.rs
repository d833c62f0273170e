//! The partial measurement that the pencil rig gives: a fused sample (`FUSED.csv` row), the
//! tool point's error across the drawn path and out of the sheet, never along the path.

use nalgebra::Vector3;

/// One fused sample: a partial measurement of the tool point along a drawn path (see
/// `crate::fusion::fuse` for how it is made and what each field means).
#[derive(Debug, Clone, PartialEq)]
pub struct FusedSample {
    /// Robot-clock time, s.
    pub t_s: f64,
    /// Joint readings, deg.
    pub q_deg: Vec<f64>,
    /// Nominal tool point of the fusing model, mm in R.
    pub nominal_mm: Vector3<f64>,
    /// Measured minus nominal along `u`, mm.
    pub dev_u_mm: f64,
    /// In-plane normal of the path (unit, R).
    pub u: Vector3<f64>,
    /// Measured minus nominal along `n`, mm.
    pub dev_n_mm: f64,
    /// Sheet normal (unit, R).
    pub n: Vector3<f64>,
}

impl FusedSample {
    /// The measured part of the error as a vector in R: `dev_u u + dev_n n` (mm).
    pub fn measured_error_mm(&self) -> Vector3<f64> {
        self.u * self.dev_u_mm + self.n * self.dev_n_mm
    }
}
