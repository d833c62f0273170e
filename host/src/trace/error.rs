//! Everything that can go wrong in `trace`, and how the binary classifies it.

use crate::error::{Classify, ErrorKind};
use crate::io::atomic::AtomicWriteError;
use std::path::PathBuf;

/// Everything that can go wrong in `trace`.
#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    #[error("cannot read scan {path}: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    #[error(
        "no fiducials found: expected four filled 6 mm black discs at the corners of a square \
         ({discs} disc-like marks seen); for an image without fiducials use \
         --no-fiducials --mm-per-px"
    )]
    NoFiducials { discs: usize },
    #[error("orientation dot not found: expected a 3 mm disc 15 mm from the top-left fiducial, towards the bottom-left one")]
    NoOrientationDot,
    #[error("orientation ambiguous: {candidates} marks could be the orientation dot")]
    AmbiguousOrientation { candidates: usize },
    #[error(
        "the scan is mirrored (the orientation dot is on the wrong side of the top-left \
         fiducial); scan the sheet face down on the glass or un-mirror the image"
    )]
    Mirrored,
    #[error("fiducials inconsistent: the orientation dot lies {residual_mm:.2} mm from where the four corner fiducials put it")]
    FiducialResidual { residual_mm: f64 },
    #[error(
        "the camera model does not explain the printed marks: {rms_mm:.3} mm RMS, {max_mm:.3} mm \
         at worst over {used} of {found} marks (limit {limit_mm} mm RMS); the sheet is not flat \
         or the lens is beyond a radial model: photograph it flat and square-on"
    )]
    CameraCheck {
        rms_mm: f64,
        max_mm: f64,
        used: usize,
        found: usize,
        limit_mm: f64,
    },
    #[error(
        "the sheet is not flat: the printed marks sit in a smooth pattern of {pattern_mm:.3} mm RMS \
         ({pattern_max_mm:.3} mm at worst) off a flat sheet's image, over their own scatter of \
         {scatter_mm:.3} mm (limit {limit_mm} mm): a bow or a lifted edge, which the trace inside \
         the ring would follow by more than that: lay the sheet flat (under glass, or taped at \
         its edges) and photograph it again"
    )]
    NotFlat {
        pattern_mm: f64,
        pattern_max_mm: f64,
        scatter_mm: f64,
        limit_mm: f64,
    },
    #[error("fiducials degenerate: no homography through the four corner fiducials")]
    DegenerateFiducials,
    #[error(
        "no pencil trace found: no grey stroke of {min_length_mm} mm or longer in the trace area"
    )]
    NoTrace { min_length_mm: f64 },
    #[error("invalid {name} = {value}: {reason}")]
    BadOption {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Atomic(#[from] AtomicWriteError),
}

impl Classify for TraceError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::Write { .. } | Self::Atomic(_) => ErrorKind::Failure,
            _ => ErrorKind::BadInput,
        }
    }
}
