//! Errors of the identification.

use super::lm::LmError;
use crate::error::{Classify, ErrorKind};
use crate::model::ModelError;

/// Everything that can stop a calibration.
#[derive(Debug, thiserror::Error)]
pub enum CalibError {
    /// The model could not be evaluated or changed (bad parameter name, wrong joint count...).
    #[error(transparent)]
    Model(#[from] ModelError),
    /// No pose to calibrate on.
    #[error("no calibration pose")]
    NoPoses,
    /// None of the selected parameters is identifiable from these poses.
    #[error("none of the selected parameters is identifiable from these poses")]
    NothingToFit,
    /// Fewer measured coordinates than unknowns.
    #[error("{residuals} measured coordinates cannot determine {params} parameters; add poses")]
    TooFewPoses { residuals: usize, params: usize },
    /// The solver failed (non-finite values).
    #[error("solver failed: {0}")]
    Solver(String),
    /// A parameter selection that names no parameter.
    #[error("--params: empty parameter list")]
    EmptySelection,
    /// Joint compliance asked of a model without link masses.
    #[error("--compliance needs link masses in the model (e.g. `urdf2model` from a URDF with <inertial>)")]
    NoMasses,
    /// A combination of options that the identification does not support.
    #[error("{0}")]
    Unsupported(String),
    /// A pose of a tree model's set with the wrong number of joint values.
    #[error("pose {pose}: {found} joint values for a tree of {expected} joints")]
    TreeJoints {
        pose: usize,
        expected: usize,
        found: usize,
    },
    /// A point slot of a tree model's set on no tip of the tree (`tip`: the tip it names, or
    /// `None`: a set of several points per pose that names no tips, a chain's `--markers`).
    #[error("measured point {slot} of the poses is on {}, for a tree of {tips} tips", tip.map_or("no tip".to_string(), |t| format!("tip {}", t + 1)))]
    TreeSlot {
        slot: usize,
        tip: Option<usize>,
        tips: usize,
    },
    /// A tree model's set (points on its tips, or unmeasured points) given to a chain's
    /// identification, which reads one chain's joints and every point of every pose.
    #[error("{what}: the measured points are on a tree's tips or some are missing; a chain's identification reads one chain's joints and every point (give the tree model)")]
    NotChainSet { what: String },
    /// Measurements that cannot be of this model as given (units, joint order, another robot):
    /// [`super::plausible`].
    #[error("{0}")]
    Implausible(String),
}

impl CalibError {
    /// Maps a solver error.
    pub fn from_lm(e: LmError<ModelError>) -> Self {
        match e {
            LmError::Problem(m) => CalibError::Model(m),
            LmError::Underdetermined { residuals, params } => {
                CalibError::TooFewPoses { residuals, params }
            }
            other => CalibError::Solver(other.to_string()),
        }
    }
}

impl Classify for CalibError {
    fn kind(&self) -> ErrorKind {
        match self {
            CalibError::Model(e) => e.kind(),
            CalibError::Solver(_) => ErrorKind::Failure,
            CalibError::NoPoses
            | CalibError::NothingToFit
            | CalibError::TooFewPoses { .. }
            | CalibError::EmptySelection
            | CalibError::NoMasses
            | CalibError::Unsupported(_)
            | CalibError::TreeJoints { .. }
            | CalibError::TreeSlot { .. }
            | CalibError::NotChainSet { .. }
            | CalibError::Implausible(_) => ErrorKind::BadInput,
        }
    }
}
