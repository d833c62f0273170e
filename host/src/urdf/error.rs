//! Errors of the URDF import.

use crate::error::{Classify, ErrorKind};
use crate::model::ModelError;

/// Everything that can stop a URDF import. Positions are 1-based `line:column` in the file.
#[derive(Debug, thiserror::Error)]
pub enum UrdfError {
    /// The file cannot be read.
    #[error("cannot read URDF file {path}: {source}")]
    Read {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The text is not well-formed XML.
    #[error("URDF {source_name}: XML error: {message}")]
    Xml {
        source_name: String,
        message: String,
    },
    /// An element or attribute is missing or malformed.
    #[error("URDF {source_name}:{line}:{column}: {message}")]
    Element {
        source_name: String,
        line: u32,
        column: u32,
        message: String,
    },
    /// A link named on the command line or in a joint that the file does not define.
    #[error("URDF {source_name}: no link `{link}`; its links, nearest first: {known}")]
    UnknownLink {
        source_name: String,
        link: String,
        /// The file's links, nearest to `link` first ([`crate::error::nearest_first`]).
        known: String,
    },
    /// The tip link is not below the base link in the tree.
    #[error("URDF {source_name}: link `{tip}` is not below link `{base}`")]
    NotBelow {
        source_name: String,
        base: String,
        tip: String,
    },
    /// The tree has no single root link (a cycle, or several roots and no `--base-link`).
    #[error("URDF {source_name}: {message}")]
    Tree {
        source_name: String,
        message: String,
    },
    /// A joint type the model cannot represent (floating, planar).
    #[error("URDF {source_name}: joint `{joint}` is of type `{kind}`, which a serial model cannot represent")]
    Unsupported {
        source_name: String,
        joint: String,
        kind: String,
    },
    /// The chain has no movable joint.
    #[error("URDF {source_name}: the chain from `{base}` to `{tip}` has no movable joint")]
    NoJoint {
        source_name: String,
        base: String,
        tip: String,
    },
    /// The model builder refused the chain (e.g. two joints whose names sanitize alike).
    #[error("URDF {source_name}: {source}")]
    Model {
        source_name: String,
        #[source]
        source: ModelError,
    },
}

impl Classify for UrdfError {
    fn kind(&self) -> ErrorKind {
        // Every variant is about the user's file or arguments (a missing file included, as
        // for model files).
        ErrorKind::BadInput
    }
}
