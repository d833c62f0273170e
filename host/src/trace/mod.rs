//! `rigctl trace`: the pencil centreline of a scanned sheet, in sheet mm (FORMATS.md "Scanned
//! sheets").
//!
//! Pipeline ([`trace_image`]):
//! 1. whole-image passes: the local paper level (uneven light, [`paper`]), a coarse map of the
//!    darkest red value per block ([`raster`]), the red ink's colour ([`ink`]);
//! 2. fiducials: black blobs of disc shape, sub-pixel centroids, the square of four corner discs
//!    and the orientation dot that names the top-left corner; mirrored scans are refused
//!    ([`fiducials`]);
//! 3. the camera: with the sheet-v2 ring, homography + radial lens distortion fitted on all 48
//!    marks, its residual checked ([`camera`]); without it (sheet v1) the homography of the four
//!    corners (normalised DLT), checked at the orientation dot ([`homography`]);
//! 4. graphite: blocks inside the sheet's trace area that are grey but not black (red ink is
//!    almost invisible in the red channel and is divided out of the centroid weights);
//! 5. centreline: tracking with darkness-weighted centroids across the stroke, stopping at
//!    print and dust ([`centreline`]);
//! 6. the pieces assembled along the printed path, skips bridged, gaps reported ([`path`]), or,
//!    without a known path, joined by nearness ([`chain`]); resampled.
//!
//! [`render`] draws synthetic scans with known truth for tests, benches and simulation.

mod area;
pub mod camera;
mod centreline;
pub mod chain;
pub mod fiducials;
pub mod homography;
mod ink;
pub mod overlay;
mod paper;
pub mod path;
mod raster;
pub mod render;
mod render_extras;
pub mod render_photo;

pub use camera::{CameraModel, FitQuality};
pub use chain::{polyline_length, resample, Stroke};
pub use fiducials::{Disc, Fiducials};
pub use homography::Homography;
pub use path::{Assembly, Gap};
pub use render::{render_scan, RenderSpec};
pub use render_photo::{render_photo, Camera, PhotoSpec};

use crate::error::{Classify, ErrorKind};
use crate::io::atomic::{write_atomic, AtomicWriteError};
use crate::sheet::{fiducial_centres_mm, orientation_dot_mm, ReferencePath, FIDUCIAL_SPACING_MM};
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

/// The result of [`trace_image`].
#[derive(Debug, Clone)]
pub struct Trace {
    /// Strokes in sheet mm, longest first, resampled at the requested spacing. Along a printed
    /// path: exactly one, the assembled path.
    pub strokes: Vec<Stroke>,
    /// The assembly along the printed path, if the pencil followed one.
    pub assembly: Option<(ReferencePath, Assembly)>,
    /// The fiducials (fiducial mapping only).
    pub fiducials: Option<Fiducials>,
    /// Distance between the orientation dot's measured and predicted positions, mm.
    pub dot_residual_mm: Option<f64>,
    /// The camera model (fiducial mapping only) and, with the sheet-v2 ring, its fit.
    pub camera: Option<CameraModel>,
    pub camera_fit: Option<FitQuality>,
    /// Image scale, pixels per mm (mean over the fiducial square).
    pub px_per_mm: f64,
}

impl Trace {
    /// The longest stroke (`trace_image` always returns at least one).
    pub fn main_stroke(&self) -> Option<&Stroke> {
        self.strokes.first()
    }

    /// Whether the written stroke is the whole drawn path (always true without a printed path).
    pub fn is_whole(&self) -> bool {
        self.assembly
            .as_ref()
            .is_none_or(|(_, a)| a.missing().next().is_none())
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

/// The camera of a fiducial mapping: fitted on all marks with the ring, else the corners'
/// homography. Returns the model, the fit (ring) and the orientation dot's residual, mm.
fn fit_camera(
    img: &RgbImage,
    fid: &Fiducials,
    spacing_mm: f64,
    opts: &TraceOptions,
) -> Result<(CameraModel, Option<FitQuality>, f64), TraceError> {
    let size = [img.width() as f64, img.height() as f64];
    let expected = orientation_dot_mm(spacing_mm);
    if fid.ring.len() >= 8 {
        let mut mm: Vec<[f64; 2]> = fiducial_centres_mm(spacing_mm).to_vec();
        let mut px: Vec<[f64; 2]> = fid.corners.iter().map(|d| d.centre_px).collect();
        mm.push(expected);
        px.push(fid.dot.centre_px);
        for (d, m) in &fid.ring {
            mm.push(*m);
            px.push(d.centre_px);
        }
        let (cam, q) = CameraModel::fit(&mm, &px, size).ok_or(TraceError::DegenerateFiducials)?;
        let limit_mm = opts.max_camera_rms_mm * spacing_mm / FIDUCIAL_SPACING_MM;
        if !(q.rms_mm <= limit_mm && q.max_mm <= 4.0 * limit_mm) {
            return Err(TraceError::CameraCheck {
                rms_mm: q.rms_mm,
                max_mm: q.max_mm,
                used: q.used,
                found: q.found,
                limit_mm,
            });
        }
        let dot = cam.to_mm(fid.dot.centre_px);
        let residual = (dot[0] - expected[0]).hypot(dot[1] - expected[1]);
        return Ok((cam, Some(q), residual));
    }
    let px: Vec<[f64; 2]> = fid.corners.iter().map(|d| d.centre_px).collect();
    let to_px = Homography::fit(&fiducial_centres_mm(spacing_mm), &px)
        .ok_or(TraceError::DegenerateFiducials)?;
    let cam = CameraModel::from_homography(&to_px, size).ok_or(TraceError::DegenerateFiducials)?;
    let dot = cam.to_mm(fid.dot.centre_px);
    let residual_mm = (dot[0] - expected[0]).hypot(dot[1] - expected[1]);
    if residual_mm.is_nan() || residual_mm > 1.0 {
        return Err(TraceError::FiducialResidual { residual_mm });
    }
    Ok((cam, None, residual_mm))
}

/// Traces the pencil of a scan or photo. `progress` is advanced while strokes are tracked (pass
/// `ProgressBar::hidden()` for none).
pub fn trace_image(
    img: &RgbImage,
    opts: &TraceOptions,
    progress: &ProgressBar,
) -> Result<Trace, TraceError> {
    area::check_options(opts)?;
    let paper = paper::PaperMap::build(img, paper::PaperMap::block_size_for(img));
    let map = raster::CoarseMap::build(img, raster::CoarseMap::block_size_for(img));
    let ink = ink::InkModel::estimate(img, &paper, ink::DEFAULT_FLOOR, map.k);
    let (w_px, h_px) = (img.width() as f64, img.height() as f64);

    let mut occluders = centreline::Occluders::default();
    let (to_mm, fids, camera, camera_fit, dot_residual_mm, px_per_mm): (
        ToMm,
        Option<Fiducials>,
        Option<CameraModel>,
        Option<FitQuality>,
        Option<f64>,
        f64,
    ) = match opts.mapping {
        Mapping::Fiducials { spacing_mm } => {
            let fid = fiducials::find(img, &map, &paper, spacing_mm)?;
            let (cam, fit, residual) = fit_camera(img, &fid, spacing_mm, opts)?;
            let ppmm = fid.side_px() / spacing_mm;
            for (d, _) in &fid.ring {
                occluders
                    .discs
                    .push((d.centre_px, 0.5 * d.diameter_px + 0.3 * ppmm));
            }
            (
                Box::new(move |p| cam.to_mm(p)),
                Some(fid),
                Some(cam),
                fit,
                Some(residual),
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
            None,
            None,
            1.0 / mm_per_px,
        ),
    };

    let roi = area::roi_predicate(opts.mapping, &to_mm, w_px, h_px);
    let seeds = area::seed_mask(&map, &paper, opts, fids.is_some(), &roi, px_per_mm);
    let params = centreline::TrackParams {
        px_per_mm,
        step_px: 0.25 * px_per_mm,
        max_width_px: opts.max_width_mm * px_per_mm,
        min_mass: 0.03 * px_per_mm,
    };
    let pieces = centreline::track_all(
        img, &ink, &paper, &occluders, &map, &seeds, &roi, &params, progress,
    );
    let pieces_mm: Vec<chain::PieceMm> = pieces
        .into_iter()
        .map(|p| chain::PieceMm {
            pts: p.pts_px.iter().map(|q| to_mm(*q)).collect(),
            closed: p.closed,
        })
        .filter(|p| polyline_length(&p.pts, p.closed) >= 0.5)
        .collect();
    let path = match (opts.path, opts.mapping) {
        (_, Mapping::Scale { .. }) | (PathChoice::Free, _) => None,
        (PathChoice::Known(p), _) => Some(p),
        (PathChoice::Auto, _) => {
            let c = path::length_near(&pieces_mm, ReferencePath::Circle, opts.band_mm);
            let l = path::length_near(&pieces_mm, ReferencePath::Line, opts.band_mm);
            let (best, len) = if c >= l {
                (ReferencePath::Circle, c)
            } else {
                (ReferencePath::Line, l)
            };
            (len >= 20.0).then_some(best)
        }
    };
    let assembly = path
        .and_then(|p| path::assemble(&pieces_mm, p, opts.band_mm, opts.max_gap_mm).map(|a| (p, a)));
    let raw_strokes: Vec<Stroke> = match &assembly {
        Some((_, a)) => vec![a.stroke.clone()],
        None => chain::chain(pieces_mm, opts.max_gap_mm.min(2.0)),
    };
    let strokes: Vec<Stroke> = raw_strokes
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
        assembly,
        fiducials: fids,
        dot_residual_mm,
        camera,
        camera_fit,
        px_per_mm,
    })
}
