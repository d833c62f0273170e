//! Errors of the fusion and of the potentiometer calibration.

use std::path::{Path, PathBuf};

use crate::daq::export::ExportError;
use crate::daq::recording::RecordingError;
use crate::error::{Classify, ErrorKind};
use crate::io::atomic::AtomicWriteError;
use crate::io::pose_csv::PoseCsvError;
use crate::io::table::TableError;
use crate::model::ModelError;

/// Everything that can stop `rigctl fuse` or `rigctl potcal`.
#[derive(Debug, thiserror::Error)]
pub enum FusionError {
    /// A file could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A bad value or row in a CSV file.
    #[error("{path}:{line}: {column}: {reason}")]
    Csv {
        path: PathBuf,
        line: usize,
        column: String,
        reason: String,
    },
    /// A TOML file (placement, pot calibration) that does not parse or holds bad values.
    #[error("{path}: {reason}")]
    Toml { path: PathBuf, reason: String },
    /// Input that is well formed but unusable (too few jig points, degenerate axes, ...).
    #[error("{0}")]
    Invalid(String),
    /// The clocks could not be aligned.
    #[error("clock alignment failed: {0}")]
    Alignment(String),
    /// No sample had the pencil on the paper and on the trace.
    #[error("no fused sample: {0}")]
    NoSamples(String),
    /// The recording could not be read.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The recording's frames could not be decoded.
    #[error(transparent)]
    Export(#[from] ExportError),
    /// The joint readings file is bad.
    #[error(transparent)]
    PoseCsv(#[from] PoseCsvError),
    /// The model could not be evaluated.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// An output file could not be written.
    #[error(transparent)]
    Atomic(#[from] AtomicWriteError),
}

impl Classify for FusionError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::Recording(e) => e.kind(),
            Self::Export(e) => e.kind(),
            Self::PoseCsv(e) => e.kind(),
            Self::Model(e) => e.kind(),
            Self::Atomic(e) => e.kind(),
            Self::Read { .. }
            | Self::Csv { .. }
            | Self::Toml { .. }
            | Self::Invalid(_)
            | Self::Alignment(_)
            | Self::NoSamples(_) => ErrorKind::BadInput,
        }
    }
}

impl FusionError {
    /// A [`FusionError::Csv`] at `line` of `path`.
    pub(crate) fn csv(path: &Path, line: usize, column: &str, reason: impl Into<String>) -> Self {
        Self::Csv {
            path: path.to_path_buf(),
            line,
            column: column.into(),
            reason: reason.into(),
        }
    }

    /// The fusion's form of a problem the table reader found in the CSV file `path`;
    /// `no_rows` says what a file with a header and no data row lacks.
    pub(crate) fn from_table(e: TableError, path: &Path, no_rows: &str) -> Self {
        let csv = |line, column: &str, reason: String| Self::csv(path, line, column, reason);
        match e {
            TableError::Read { source, .. } => Self::Read {
                path: path.to_path_buf(),
                source,
            },
            TableError::NoHeader { .. } => csv(1, "header", "no header row".into()),
            TableError::Dialect { line, hint, .. } => csv(line, "header", hint),
            TableError::NoRows { line, .. } => csv(line, "rows", no_rows.into()),
            TableError::MissingColumn { line, column, .. } => {
                csv(line, &column, "column missing from the header".into())
            }
            TableError::DuplicateColumn { line, column, .. } => {
                csv(line, &column, "column appears twice in the header".into())
            }
            TableError::FieldCount {
                line,
                expected,
                found,
                ..
            } => csv(
                line,
                "row",
                format!("{found} fields, the header has {expected}"),
            ),
            TableError::BadValue {
                line,
                column,
                value,
                problem,
                ..
            } => csv(line, &column, format!("{problem} (`{value}`)")),
        }
    }
}
