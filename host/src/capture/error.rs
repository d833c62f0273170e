//! Errors of `rigctl poses`.

use crate::error::{Classify, ErrorKind};

/// Why the capture could not run.
#[derive(Debug, thiserror::Error)]
pub enum CaptureError {
    /// The instrument log cannot be read or is not in a format it claims.
    #[error("{file}:{line}: {problem}")]
    Instrument {
        file: String,
        line: usize,
        problem: String,
    },
    /// The instrument log's file could not be read.
    #[error("cannot read instrument log {file}: {source}")]
    Read {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// The shared table reader's errors (generic CSV instrument logs).
    #[error(transparent)]
    Table(#[from] crate::io::table::TableError),
    /// The joint log is not usable (too short, times not increasing).
    #[error("{file}: {problem}")]
    JointLog { file: String, problem: String },
    /// An option that cannot work (e.g. a minimum standstill shorter than its trimmed edges).
    #[error("{0}")]
    Options(String),
    /// The clock offset cannot be estimated from these logs.
    #[error("cannot estimate the clock offset between the logs: {0}")]
    Offset(String),
    /// The model's forward kinematics failed on a logged joint vector.
    #[error("joint log sample {sample}: {source}")]
    Model {
        sample: usize,
        #[source]
        source: crate::model::ModelError,
    },
}

impl Classify for CaptureError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::Offset(_) | Self::Model { .. } => ErrorKind::Failure,
            Self::Read { source, .. } if !crate::io::read::is_refusal(source) => {
                ErrorKind::BadInput
            }
            _ => ErrorKind::BadInput,
        }
    }
}
