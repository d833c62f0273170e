//! Joint-tilting values from inclinometer readings (`rigctl joints`; thesis 4.4.1, 5.3,
//! fig. 4.6 / 5.4; MODEL.md eq. 5.16-5.19).
//!
//! # Input: `JOINTS_TILT.csv`
//! A header row, then one reading per row (`#` comment lines and blank lines are skipped):
//!
//! | column | unit | meaning |
//! |---|---|---|
//! | `joint` | 1..N | the joint whose tilt is read |
//! | `config` | text | free configuration label (e.g. `j3_up`, `j3_down`) |
//! | `q1..qN` | deg | joint readings of the configuration (within the model's limits) |
//! | `payload_kg` | kg | optional column: point mass at the tool point (empty or absent = 0) |
//! | `incl_x_deg incl_y_deg incl_z_deg` | deg | rotation of the link after joint i relative to joint frame i, about its x, y, z axes; an empty field = not measured |
//!
//! The inclinometer angles are read as the relative orientation across the joint (two
//! inclinometers, one each side, as in the thesis), so each axis carries an unknown zero offset
//! that is fitted along with the values: only the *change* between configurations informs them
//! (the thesis's paired configurations). Geometric errors do not enter (section 4.4.1).
//!
//! # Method ([`fit_joint`])
//! The declared model gives the moment `eta` at each reading (statics, payload included).
//! `incl_x = o_x + C sign(eta_x) sin(gamma)`, `incl_y = o_y + C sign(eta_y) cos(gamma)` are
//! fitted for `C` (eq. 5.16-5.18), and `incl_z = o_z + b sign(eta_z) + eta_z / k` for `b` and
//! `1/k` (eq. 5.19), by linear least squares with sigmas from the residual variance. So the
//! configurations must make eta_x / eta_y change sign (clearance), and eta_z change sign and
//! size (backlash = the jump at the sign change, stiffness = the slope). Joint 1's eta_z is 0
//! under gravity: its b and k are not identified by inclinometers (the thesis used end-effector
//! measurements) and keep the input model's values.
//!
//! # API
//! [`read_readings`]`(path, &Model)`, [`identify`]`(&Model, &[TiltReading]) ->
//! TiltIdentification { fits, model }`, [`fit_joint`], [`predicted_tilt_deg`] (the forward
//! law, e.g. to simulate readings), [`joint_moment_kgfm`], [`report_json`].

mod fit;
mod readings;
pub mod table;

pub use fit::{
    fit_joint, identify, joint_moment_kgfm, predicted_tilt_deg, Estimate, JointTiltFit,
    TiltIdentification,
};
pub use readings::{header, parse_readings, read_readings, row, TiltReading};

use crate::error::{Classify, ErrorKind};

/// Why joint-tilting identification failed.
#[derive(Debug, thiserror::Error)]
pub enum JointsError {
    /// The readings file is malformed.
    #[error(transparent)]
    Table(#[from] table::TableError),
    /// The model is unusable (e.g. no tilting data) or failed.
    #[error(transparent)]
    Model(#[from] crate::model::ModelError),
    /// No joint's readings identify any value.
    #[error("the readings identify no clearance, backlash or stiffness (see the per-joint notes: moments must change sign between configurations)")]
    NothingIdentified,
    /// The JSON report could not be written.
    #[error(transparent)]
    Write(#[from] crate::io::atomic::AtomicWriteError),
}

impl Classify for JointsError {
    fn kind(&self) -> ErrorKind {
        match self {
            JointsError::Table(e) => e.kind(),
            JointsError::Model(e) => e.kind(),
            JointsError::NothingIdentified => ErrorKind::BadInput,
            JointsError::Write(_) => ErrorKind::Failure,
        }
    }
}

/// The per-joint fits as a JSON document: `{"joints": [JointTiltFit...]}` (values in deg,
/// kgf.m/deg, deg per kgf.m; `null` where not identified).
pub fn report_json(fits: &[JointTiltFit]) -> serde_json::Value {
    serde_json::json!({ "joints": fits })
}
