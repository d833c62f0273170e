//! Errors of the model: unknown names, bad values, malformed model files.

use crate::error::{Classify, ErrorKind};

/// Everything that can go wrong building, changing or evaluating a [`super::Model`].
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// A parameter name the model does not have.
    #[error("unknown parameter `{name}`; valid names: {valid}")]
    UnknownParam { name: String, valid: String },
    /// A parameter value that is NaN or infinite.
    #[error("parameter `{name}` = {value}: not a finite number")]
    NonFinite { name: String, value: f64 },
    /// A parameter index past the end of the parameter list.
    #[error("parameter index {index} out of range ({count} parameters)")]
    ParamIndex { index: usize, count: usize },
    /// A joint vector of the wrong length.
    #[error("expected {expected} joint values, got {found}")]
    JointCount { expected: usize, found: usize },
    /// A joint index past the last joint.
    #[error("joint index {index} out of range ({count} joints)")]
    JointIndex { index: usize, count: usize },
    /// Tilting asked of a model without clearance/backlash/stiffness values.
    #[error("model `{model}` has no joint-tilting data (clearance, backlash, stiffness)")]
    NoTiltData { model: String },
    /// A list of external moments of the wrong length.
    #[error("expected {expected} joint moments, got {found}")]
    MomentCount { expected: usize, found: usize },
    /// A list of tilts of the wrong length.
    #[error("expected {expected} joint tilts, got {found}")]
    TiltCount { expected: usize, found: usize },
    /// A preset name that does not exist.
    #[error("unknown robot `{name}` (built-in presets: katana450, ur5)")]
    UnknownPreset { name: String },
    /// A `--set` argument that is not `NAME=VALUE` with a finite number.
    #[error("--set `{arg}`: expected NAME=VALUE with a finite number, e.g. dth2=0.03")]
    BadSet { arg: String },
    /// Options that do not go together (e.g. `--tool-mm` with a model file).
    #[error("{0}")]
    Usage(String),
    /// A structurally invalid model (duplicate names, joints out of order, ...).
    #[error("invalid model: {0}")]
    Invalid(String),
    /// A model file that cannot be parsed or describes an invalid model.
    #[error("model file {file}: {message}")]
    File { file: String, message: String },
    /// A model file that cannot be read.
    #[error("cannot read model file {path}: {source}")]
    Read {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A model file that cannot be written.
    #[error(transparent)]
    Write(#[from] crate::io::atomic::AtomicWriteError),
}

impl Classify for ModelError {
    fn kind(&self) -> ErrorKind {
        match self {
            ModelError::ParamIndex { .. }
            | ModelError::JointIndex { .. }
            | ModelError::Write(_) => ErrorKind::Failure,
            _ => ErrorKind::BadInput,
        }
    }
}
