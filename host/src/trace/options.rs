//! The settings of [`super::trace_image`]: how pixels become sheet mm, which printed path the
//! pencil was meant to follow (a hint for choosing between chains of graphite, never a mask), and
//! the thresholds of the stroke search.

use super::stages::TraceParams;
use crate::sheet::{ReferencePath, FIDUCIAL_SPACING_MM};

/// Which printed path the pencil followed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PathChoice {
    /// Whichever of circle and line the tracked pencil runs along (a hint only).
    Auto,
    Known(ReferencePath),
    /// No printed path: no hint.
    Free,
}

/// How pixels become sheet mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mapping {
    /// From the printed fiducials, whose measured centre-to-centre spacing is `spacing_mm`.
    Fiducials { spacing_mm: f64 },
    /// A plain scale for images without fiducials: origin at the image centre, x right, y up.
    Scale { mm_per_px: f64 },
}

/// Settings of [`trace_image`].
#[derive(Debug, Clone, PartialEq)]
pub struct TraceOptions {
    pub mapping: Mapping,
    /// Spacing of the output points, mm (FORMATS.md: at most 0.5).
    pub spacing_mm: f64,
    /// Least graphite darkness (fraction of the local paper level absorbed) for a pixel to seed a
    /// stroke.
    pub min_darkness: f32,
    /// Pencil skips up to this long (between the ends of two pieces that continue each other)
    /// are bridged; longer ones are missing, mm.
    pub max_gap_mm: f64,
    /// Strokes shorter than this are dropped, mm.
    pub min_stroke_mm: f64,
    /// Strokes wider than this are not pencil, mm.
    pub max_width_mm: f64,
    /// The printed path the pencil followed.
    pub path: PathChoice,
    /// Graphite within this distance of a printed path counts for `Auto`'s choice of hint, mm.
    pub band_mm: f64,
    /// Largest RMS residual of the camera model on the printed marks, mm.
    pub max_camera_rms_mm: f64,
    /// Largest smooth pattern the camera model may leave on the printed marks (a sheet not
    /// lying flat), RMS mm ([`super::flatness`]); `f64::INFINITY`: not checked.
    pub max_bend_pattern_mm: f64,
    /// Every stage's tuned numbers (default: the tuned values), carried into each stage.
    pub params: TraceParams,
}

impl Default for TraceOptions {
    fn default() -> Self {
        Self {
            mapping: Mapping::Fiducials {
                spacing_mm: FIDUCIAL_SPACING_MM,
            },
            spacing_mm: 0.25,
            min_darkness: 0.12,
            max_gap_mm: 10.0,
            min_stroke_mm: 2.0,
            max_width_mm: 3.0,
            path: PathChoice::Auto,
            band_mm: 6.0,
            max_camera_rms_mm: 0.08,
            max_bend_pattern_mm: 0.006,
            params: TraceParams::default(),
        }
    }
}
