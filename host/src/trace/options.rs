//! The settings of [`super::trace_image`]: how pixels become sheet mm, which printed path the
//! pencil followed, and the thresholds of the stroke search.

use crate::sheet::{ReferencePath, FIDUCIAL_SPACING_MM};

/// Which printed path the pencil followed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PathChoice {
    /// Whichever of circle and line the tracked pencil runs along.
    Auto,
    Known(ReferencePath),
    /// Not along a printed path: pieces are joined by nearness and the longest stroke is kept.
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
    /// Along a printed path: skips up to this long are bridged; without one: pieces whose ends
    /// are at most this far apart are joined. mm.
    pub max_gap_mm: f64,
    /// Strokes shorter than this are dropped, mm.
    pub min_stroke_mm: f64,
    /// Strokes wider than this are not pencil, mm.
    pub max_width_mm: f64,
    /// The printed path the pencil followed.
    pub path: PathChoice,
    /// Pencil farther than this from the printed path is not the trace, mm.
    pub band_mm: f64,
    /// Largest RMS residual of the camera model on the printed marks, mm.
    pub max_camera_rms_mm: f64,
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
        }
    }
}
