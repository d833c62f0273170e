//! `rigctl trace`: the pencil centreline of a scanned sheet, in sheet mm (FORMATS.md "Scanned
//! sheets").
//!
//! Pipeline ([`trace_image`]):
//! 1. whole-image passes: paper level, a coarse map of the darkest red value per block
//!    ([`raster`]), the red ink's colour ([`ink`]);
//! 2. fiducials: black blobs of disc shape, sub-pixel centroids, the square of four corner discs
//!    and the orientation dot that names the top-left corner; mirrored scans are refused
//!    ([`fiducials`]);
//! 3. the pixel -> sheet mm homography from the four corners (normalised DLT), checked at the
//!    orientation dot ([`homography`]);
//! 4. graphite: blocks inside the sheet's trace area that are grey but not black (red ink is
//!    almost invisible in the red channel and is divided out of the centroid weights);
//! 5. centreline: tracking with darkness-weighted centroids across the stroke
//!    ([`centreline`]), pieces joined and resampled ([`chain`]).
//!
//! [`render`] draws synthetic scans with known truth for tests, benches and simulation.

mod centreline;
pub mod chain;
pub mod fiducials;
pub mod homography;
mod ink;
mod raster;
pub mod render;

pub use chain::{polyline_length, resample, Stroke};
pub use fiducials::{Disc, Fiducials};
pub use homography::Homography;
pub use render::{render_scan, RenderSpec};

use crate::error::{Classify, ErrorKind};
use crate::io::atomic::{write_atomic, AtomicWriteError};
use crate::sheet::{
    fiducial_centres_mm, orientation_dot_mm, FIDUCIAL_DIAMETER_MM, FIDUCIAL_SPACING_MM,
    ORIENTATION_DOT_DIAMETER_MM, TRACE_AREA_HALF_HEIGHT_MM, TRACE_AREA_HALF_WIDTH_MM,
};
use image::RgbImage;
use indicatif::ProgressBar;
use std::path::{Path, PathBuf};

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

/// A pixel -> sheet mm map.
type ToMm = Box<dyn Fn([f64; 2]) -> [f64; 2]>;

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
    /// Least graphite darkness (fraction of the paper level absorbed) for a pixel to seed a stroke.
    pub min_darkness: f32,
    /// Pieces whose ends are at most this far apart are joined into one stroke, mm.
    pub max_gap_mm: f64,
    /// Strokes shorter than this are dropped, mm.
    pub min_stroke_mm: f64,
    /// Strokes wider than this are not pencil, mm.
    pub max_width_mm: f64,
}

impl Default for TraceOptions {
    fn default() -> Self {
        Self {
            mapping: Mapping::Fiducials {
                spacing_mm: FIDUCIAL_SPACING_MM,
            },
            spacing_mm: 0.25,
            min_darkness: 0.2,
            max_gap_mm: 2.0,
            min_stroke_mm: 2.0,
            max_width_mm: 3.0,
        }
    }
}

/// The result of [`trace_image`].
#[derive(Debug, Clone)]
pub struct Trace {
    /// Strokes in sheet mm, longest first, resampled at the requested spacing.
    pub strokes: Vec<Stroke>,
    /// The fiducials (fiducial mapping only).
    pub fiducials: Option<Fiducials>,
    /// Distance between the orientation dot's measured and predicted positions, mm.
    pub dot_residual_mm: Option<f64>,
    /// Scan scale, pixels per mm.
    pub px_per_mm: f64,
}

impl Trace {
    /// The longest stroke (`trace_image` always returns at least one).
    pub fn main_stroke(&self) -> Option<&Stroke> {
        self.strokes.first()
    }
}

/// Reads a scan (PNG or JPEG) as RGB.
pub fn load_scan(path: &Path) -> Result<RgbImage, TraceError> {
    let read = |source| TraceError::Read {
        path: path.to_path_buf(),
        source,
    };
    Ok(image::ImageReader::open(path)
        .map_err(|e| read(image::ImageError::IoError(e)))?
        .with_guessed_format()
        .map_err(|e| read(image::ImageError::IoError(e)))?
        .decode()
        .map_err(read)?
        .into_rgb8())
}

/// Writes points as CSV `x,y` (mm, 4 decimals), atomically.
pub fn write_csv(path: &Path, points_mm: &[[f64; 2]]) -> Result<(), TraceError> {
    write_atomic(path, |w| {
        let io = |source| TraceError::Write {
            path: path.to_path_buf(),
            source,
        };
        writeln!(w, "x,y").map_err(io)?;
        for p in points_mm {
            writeln!(w, "{:.4},{:.4}", p[0], p[1]).map_err(io)?;
        }
        Ok(())
    })
}

/// Traces the pencil strokes of a scan. `progress` is advanced while strokes are tracked (pass
/// `ProgressBar::hidden()` for none).
pub fn trace_image(
    img: &RgbImage,
    opts: &TraceOptions,
    progress: &ProgressBar,
) -> Result<Trace, TraceError> {
    check_options(opts)?;
    let paper = raster::paper_level(img);
    let map = raster::CoarseMap::build(img, raster::CoarseMap::block_size_for(img));
    let ink = ink::InkModel::estimate(img, paper, ink::DEFAULT_FLOOR, map.k);
    let (w_px, h_px) = (img.width() as f64, img.height() as f64);

    let (to_mm, fids, dot_residual_mm, px_per_mm): (ToMm, Option<Fiducials>, Option<f64>, f64) =
        match opts.mapping {
            Mapping::Fiducials { spacing_mm } => {
                let fid = fiducials::find(img, &map, paper)?;
                let px: Vec<[f64; 2]> = fid.corners.iter().map(|d| d.centre_px).collect();
                let h = Homography::fit(&px, &fiducial_centres_mm(spacing_mm))
                    .ok_or(TraceError::DegenerateFiducials)?;
                let dot = h.apply(fid.dot.centre_px);
                let expected = orientation_dot_mm(spacing_mm);
                let residual_mm = (dot[0] - expected[0]).hypot(dot[1] - expected[1]);
                if residual_mm.is_nan() || residual_mm > 1.0 {
                    return Err(TraceError::FiducialResidual { residual_mm });
                }
                let ppmm = fid.side_px() / spacing_mm;
                (
                    Box::new(move |p| h.apply(p)),
                    Some(fid),
                    Some(residual_mm),
                    ppmm,
                )
            }
            Mapping::Scale { mm_per_px } => (
                Box::new(move |p: [f64; 2]| {
                    [
                        (p[0] - w_px / 2.0) * mm_per_px,
                        (h_px / 2.0 - p[1]) * mm_per_px,
                    ]
                }),
                None,
                None,
                1.0 / mm_per_px,
            ),
        };

    let roi = roi_predicate(opts.mapping, &to_mm, w_px, h_px);
    let seeds = seed_mask(&map, paper, opts, fids.is_some(), &roi, px_per_mm);
    let params = centreline::TrackParams {
        px_per_mm,
        step_px: 0.25 * px_per_mm,
        max_width_px: opts.max_width_mm * px_per_mm,
        min_mass: 0.03 * px_per_mm,
    };
    let pieces = centreline::track_all(img, &ink, &map, &seeds, &roi, &params, progress);
    let pieces_mm: Vec<chain::PieceMm> = pieces
        .into_iter()
        .map(|p| chain::PieceMm {
            pts: p.pts_px.iter().map(|q| to_mm(*q)).collect(),
            closed: p.closed,
        })
        .filter(|p| polyline_length(&p.pts, p.closed) >= 0.5)
        .collect();
    let strokes: Vec<Stroke> = chain::chain(pieces_mm, opts.max_gap_mm)
        .into_iter()
        .filter(|s| s.length_mm() >= opts.min_stroke_mm)
        .map(|s| Stroke {
            points_mm: resample(&s.points_mm, s.closed, opts.spacing_mm),
            ..s
        })
        .collect();
    if strokes.is_empty() {
        return Err(TraceError::NoTrace {
            min_length_mm: opts.min_stroke_mm,
        });
    }
    Ok(Trace {
        strokes,
        fiducials: fids,
        dot_residual_mm,
        px_per_mm,
    })
}

fn check_options(opts: &TraceOptions) -> Result<(), TraceError> {
    let bad = |name, value, reason| {
        Err(TraceError::BadOption {
            name,
            value,
            reason,
        })
    };
    match opts.mapping {
        Mapping::Fiducials { spacing_mm }
            if !(spacing_mm.is_finite() && (10.0..=1000.0).contains(&spacing_mm)) =>
        {
            return bad(
                "--fiducial-spacing-mm",
                spacing_mm,
                "expected 10..1000 mm (nominally 180)",
            );
        }
        Mapping::Scale { mm_per_px }
            if !(mm_per_px.is_finite() && mm_per_px > 0.0 && mm_per_px < 100.0) =>
        {
            return bad(
                "--mm-per-px",
                mm_per_px,
                "expected a positive scale below 100 mm per pixel",
            );
        }
        _ => {}
    }
    if !(opts.spacing_mm > 0.0 && opts.spacing_mm <= 0.5) {
        return bad("spacing_mm", opts.spacing_mm, "expected (0, 0.5] mm");
    }
    if !(opts.min_darkness > 0.0 && opts.min_darkness < 1.0) {
        return bad("min_darkness", opts.min_darkness as f64, "expected (0, 1)");
    }
    Ok(())
}

/// Where strokes are read, in pixel coordinates: the sheet's trace area without the fiducials
/// (fiducial mapping) or the image less a 2-pixel border (scale mapping).
fn roi_predicate<'a>(
    mapping: Mapping,
    to_mm: &'a dyn Fn([f64; 2]) -> [f64; 2],
    w_px: f64,
    h_px: f64,
) -> Box<dyn Fn([f64; 2]) -> bool + 'a> {
    let inside_image =
        move |p: [f64; 2]| p[0] >= 2.0 && p[1] >= 2.0 && p[0] <= w_px - 2.0 && p[1] <= h_px - 2.0;
    match mapping {
        Mapping::Scale { .. } => Box::new(inside_image),
        Mapping::Fiducials { spacing_mm } => {
            let f = spacing_mm / FIDUCIAL_SPACING_MM;
            let mut keep_out: Vec<([f64; 2], f64)> = fiducial_centres_mm(spacing_mm)
                .iter()
                .map(|c| (*c, (0.5 * FIDUCIAL_DIAMETER_MM + 2.0) * f))
                .collect();
            keep_out.push((
                orientation_dot_mm(spacing_mm),
                (0.5 * ORIENTATION_DOT_DIAMETER_MM + 2.0) * f,
            ));
            Box::new(move |p| {
                if !inside_image(p) {
                    return false;
                }
                let s = to_mm(p);
                s[0].abs() <= TRACE_AREA_HALF_WIDTH_MM * f
                    && s[1].abs() <= TRACE_AREA_HALF_HEIGHT_MM * f
                    && keep_out
                        .iter()
                        .all(|(c, r)| (s[0] - c[0]).hypot(s[1] - c[1]) > *r)
            })
        }
    }
}

/// Coarse blocks that may seed a stroke: dark enough, not black print (fiducial mapping), in the
/// trace area, in a component larger than a speck.
fn seed_mask(
    map: &raster::CoarseMap,
    paper: [f32; 3],
    opts: &TraceOptions,
    exclude_black: bool,
    roi: &dyn Fn([f64; 2]) -> bool,
    px_per_mm: f64,
) -> Vec<bool> {
    let dark_max = (paper[0] * (1.0 - opts.min_darkness)).max(0.0);
    let black = if exclude_black { paper[0] * 0.22 } else { -1.0 };
    let mut mask = vec![false; map.min_red.len()];
    for (i, &v) in map.min_red.iter().enumerate() {
        let v = v as f32;
        if v <= dark_max && v >= black {
            mask[i] = roi(map.block_centre_px(i % map.w, i / map.w));
        }
    }
    let (labels, comps) = raster::components(&mask, map.w, map.h);
    let block_mm = map.k as f64 / px_per_mm;
    let keep: Vec<bool> = comps
        .iter()
        .map(|c| {
            let extent =
                (c.bbox[2] - c.bbox[0] + 1).max(c.bbox[3] - c.bbox[1] + 1) as f64 * block_mm;
            extent >= 0.5 * opts.min_stroke_mm.min(2.0)
        })
        .collect();
    for (m, &l) in mask.iter_mut().zip(&labels) {
        if *m {
            *m = keep[l as usize - 1];
        }
    }
    mask
}
