//! `rigctl trace`: the pencil centreline of a scanned sheet, in sheet mm (FORMATS.md "Scanned
//! sheets").
//!
//! Pipeline ([`trace_image`], [`trace_prepared`]):
//! 1. whole-image passes, band by band on all cores or while a PNG is decoded ([`prepare`],
//!    [`files`]): the local paper level (uneven light, [`paper`]), a coarse map of the darkest
//!    red value per block ([`raster`]); then the red ink's colour ([`ink`]);
//! 2. fiducials: black blobs of disc shape, sub-pixel centroids, the square of four corner discs
//!    and the orientation dot that names the top-left corner; mirrored scans are refused
//!    ([`fiducials`]);
//! 3. the camera: with the sheet-v2 ring, homography + radial lens distortion fitted on all 48
//!    marks, its residual checked ([`camera`]); without it (sheet v1) the homography of the four
//!    corners (normalised DLT), checked at the orientation dot ([`homography`], [`mapping`]);
//! 4. graphite: blocks inside the sheet's trace area darker than the paper, light or black
//!    (red ink is almost invisible in the red channel and is divided out of the centroid
//!    weights);
//! 5. centreline: tracking with darkness-weighted centroids across the stroke, bridging the
//!    printed ring dots ([`centreline`], its window statistics in `centreline/section.rs`);
//!    edges of light cut out: a hard shadow's step, a scan's page edge
//!    (`centreline/illumination.rs`);
//! 6. the drawn path from the graphite itself: pieces linked end to end by continuity of
//!    position, direction and curvature, skips bridged, what is left out listed and judged
//!    ([`link`]; the printed path only a hint between chains of similar length); the written
//!    centres smoothed along the path between bridges (`smooth.rs`); resampled ([`chain`]).
//!
//! [`synth`] draws synthetic scans and phone photos with known truth for tests, benches and
//! simulation. [`trace_paths`] writes every path of a drawing ([`paths`]) and its drawn lines,
//! each followed through the band of ink its passes leave ([`band`], [`lines`]), the image read
//! past each line's ends for ink nothing written covers ([`probe`]). Errors: [`error`];
//! settings: [`options`].

mod area;
mod band;
mod bridge_fit;
pub mod chain;
mod error;
mod files;
pub mod flatness;
pub mod grey_print;
pub mod homography;
mod ink;
mod mapping;
mod options;
pub mod overlay;
mod paper;
mod paths;
mod plane;
mod png_read;
mod probe;
mod raster;
mod smooth;
pub mod stages;
#[cfg(feature = "synth")]
pub mod synth;
pub mod tone;

pub use stages::{camera, fiducials, link};
use stages::{centreline, lines, prepare};

pub use camera::{CameraModel, FitQuality};
pub use chain::{polyline_length, resample, Stroke};
pub use error::TraceError;
pub use fiducials::{Disc, Fiducials};
pub use files::{load_prepared, load_prepared_with, load_scan, write_csv, MAX_RGB_BYTES};
pub use flatness::Flatness;
pub use grey_print::GreyPrint;
pub use homography::Homography;
pub use lines::DrawnLine;
pub use link::{Crossing, Gap, LeftOut, LeftOutKind, Linking};
pub use options::{Mapping, PathChoice, TraceOptions};
pub use paths::{line_file_name, path_file_name, write_drawing, Drawing, DrawnPath, SUMMARY_FILE};
pub use png_read::read_png;
pub use prepare::Prepared;
pub use stages::params_file::ParamsFileError;
pub use stages::{
    CameraParams, CentrelineParams, FiducialParams, LinesParams, LinkParams, PrepareParams,
    TraceParams,
};
pub use tone::{Tone, ToneCurve, ToneSource};

use crate::sheet::ReferencePath;
use image::RgbImage;
use indicatif::ProgressBar;

/// The result of [`trace_image`].
#[derive(Debug, Clone)]
pub struct Trace {
    /// Strokes in sheet mm, resampled at the requested spacing: the drawn path first, then the
    /// other marks of at least `min_stroke_mm`, longest first.
    pub strokes: Vec<Stroke>,
    /// How the path was linked: its gaps (bridged or missing) and what was left out.
    pub linking: Linking,
    /// The printed path found as dark as the pencil (no red ink), left out with the pencil
    /// near it.
    pub grey_print: Option<GreyPrint>,
    /// The path's free ends that meet the grey print: it may go on under the print, unseen.
    pub ends_at_print_mm: Vec<[f64; 2]>,
    /// The fiducials (fiducial mapping only).
    pub fiducials: Option<Fiducials>,
    /// Distance between the orientation dot's measured and predicted positions, mm.
    pub dot_residual_mm: Option<f64>,
    /// The camera model (fiducial mapping only) and, with the sheet-v2 ring, its fit.
    pub camera: Option<CameraModel>,
    pub camera_fit: Option<FitQuality>,
    /// Image scale, pixels per mm (mean over the fiducial square).
    pub px_per_mm: f64,
    /// The device's tone curve the image was linearised through, and how it was known.
    pub tone: Tone,
    /// The printed marks' residual pattern under the camera (sheet v2): how far from flat the
    /// sheet lay, as the marks see it.
    pub flatness: Option<Flatness>,
}

impl Trace {
    /// The drawn path (`trace_image` always returns it).
    pub fn main_stroke(&self) -> Option<&Stroke> {
        self.strokes.first()
    }

    /// Whether the written stroke is the whole drawn path: no gap longer than `max_gap_mm`,
    /// nothing left out that could be part of it (FORMATS.md: exit 0 only then).
    pub fn is_whole(&self) -> bool {
        self.linking.is_whole() && self.ends_at_print_mm.is_empty()
    }
}

/// Traces the pencil of a scan or photo. `progress` is advanced while strokes are tracked (pass
/// `ProgressBar::hidden()` for none).
pub fn trace_image(
    img: &RgbImage,
    opts: &TraceOptions,
    progress: &ProgressBar,
) -> Result<Trace, TraceError> {
    area::check_options(opts)?;
    trace_prepared(
        img,
        &Prepared::build_with(img, &opts.params.prepare),
        opts,
        progress,
    )
}

/// [`trace_image`] with the whole-image maps already built (by [`load_prepared`] while
/// decoding, or [`Prepared::build`]); maps of another image are rebuilt.
pub fn trace_prepared(
    img: &RgbImage,
    prepared: &Prepared,
    opts: &TraceOptions,
    progress: &ProgressBar,
) -> Result<Trace, TraceError> {
    let Tracked {
        pieces_mm, meta, ..
    } = track(img, prepared, opts, progress)?;
    // Without red ink the printed path, if printed, is graphite to the tracker.
    let grey_print = match opts.mapping {
        Mapping::Scale { .. } => None,
        _ if meta.red_ink => None,
        _ => grey_print::find(&pieces_mm),
    };
    let pieces_mm = match &grey_print {
        Some(g) => grey_print::strip(pieces_mm, g),
        None => pieces_mm,
    };
    let hint = match (opts.path, opts.mapping, grey_print) {
        (_, Mapping::Scale { .. }, _) | (PathChoice::Free, ..) => None,
        (PathChoice::Known(p), ..) => Some(p),
        (PathChoice::Auto, _, Some(g)) => Some(g.path),
        (PathChoice::Auto, _, None) => {
            let c = link::length_near(&pieces_mm, ReferencePath::Circle, opts.band_mm);
            let l = link::length_near(&pieces_mm, ReferencePath::Line, opts.band_mm);
            let (best, len) = if c >= l {
                (ReferencePath::Circle, c)
            } else {
                (ReferencePath::Line, l)
            };
            (len >= 20.0).then_some(best)
        }
    };
    let no_trace = || TraceError::NoTrace {
        min_length_mm: opts.min_stroke_mm,
    };
    let linking =
        link::link(&pieces_mm, opts.max_gap_mm, hint, &opts.params.link).ok_or_else(no_trace)?;
    if linking.path.length_mm() < opts.min_stroke_mm {
        return Err(no_trace());
    }
    let strokes: Vec<Stroke> = std::iter::once(&linking.path)
        .chain(
            linking
                .others
                .iter()
                .filter(|s| s.length_mm() >= opts.min_stroke_mm),
        )
        .map(|s| Stroke {
            points_mm: resample(&s.points_mm, s.closed, opts.spacing_mm),
            ..s.clone()
        })
        .collect();
    let ends_at_print_mm = grey_print.map_or_else(Vec::new, |g| g.ends_meeting(&linking.path));
    Ok(Trace {
        strokes,
        linking,
        grey_print,
        ends_at_print_mm,
        fiducials: meta.fiducials,
        dot_residual_mm: meta.dot_residual_mm,
        camera: meta.camera,
        camera_fit: meta.camera_fit,
        px_per_mm: meta.px_per_mm,
        tone: meta.tone,
        flatness: meta.flatness,
    })
}

/// Every drawn line of a scan or photo as a path of its own ([`paths`]), with the whole-image
/// maps already built as for [`trace_prepared`].
pub fn trace_paths(
    img: &RgbImage,
    prepared: &Prepared,
    opts: &TraceOptions,
    progress: &ProgressBar,
) -> Result<Drawing, TraceError> {
    let Tracked {
        pieces_mm,
        meta,
        linear,
    } = track(img, prepared, opts, progress)?;
    let (img, prepared) = match &linear {
        Some((i, p)) => (i, p),
        None => (img, prepared),
    };
    let no_trace = || TraceError::NoTrace {
        min_length_mm: opts.min_stroke_mm,
    };
    let mut drawing = paths::drawing(&pieces_mm, opts, meta.px_per_mm).ok_or_else(no_trace)?;
    if drawing.paths.is_empty() {
        return Err(no_trace());
    }
    drawing.camera = meta.camera;
    drawing.fiducials = meta.fiducials;
    // Ink past a line's end that nothing written covers: the line may go on.
    let to_px = mapping::SheetToPx {
        camera: drawing.camera,
        px_per_mm: drawing.px_per_mm,
        size_px: [f64::from(img.width()), f64::from(img.height())],
    };
    let (paper, lp) = (&prepared.paper, &opts.params.lines);
    probe::mark_untraced_ink(&mut drawing, img, paper, &to_px, opts.max_gap_mm, lp);
    Ok(drawing)
}

/// How the image was mapped to sheet mm.
struct Meta {
    /// The tone curve the image was linearised through.
    tone: tone::Tone,
    flatness: Option<Flatness>,
    /// Whether red ink was found (the printed path told from the pencil by colour).
    red_ink: bool,
    fiducials: Option<Fiducials>,
    dot_residual_mm: Option<f64>,
    camera: Option<CameraModel>,
    camera_fit: Option<FitQuality>,
    px_per_mm: f64,
}

/// The tracked pieces of graphite in sheet mm (steps 1-5 of the pipeline).
struct Tracked {
    pieces_mm: Vec<chain::PieceMm>,
    /// The image linearised through a measured tone curve, with its maps (`None`: the image as
    /// given was used).
    linear: Option<(RgbImage, Prepared)>,
    meta: Meta,
}

/// The tone curve of an image the file said nothing about, measured on its marks
/// ([`tone::estimate`]); the linearised image and its maps when it is not linear.
fn settle_tone(
    img: &RgbImage,
    prepared: &Prepared,
    opts: &TraceOptions,
) -> (tone::Tone, Option<(RgbImage, Prepared)>) {
    let given = prepared.tone.clone();
    let Mapping::Fiducials { spacing_mm } = opts.mapping else {
        return (given, None);
    };
    if given.from_file() {
        return (given, None);
    }
    let black = fiducials::black_of_paper(
        img,
        &prepared.map,
        &prepared.paper,
        spacing_mm,
        &opts.params.fiducials,
    );
    match black.and_then(tone::estimate) {
        None => (given, None),
        Some(t) => {
            let mut lin = img.clone();
            tone::apply(&mut lin, &t.curve);
            let mut p = Prepared::build_with(&lin, &opts.params.prepare);
            p.tone = t.clone();
            (t, Some((lin, p)))
        }
    }
}

fn track(
    img: &RgbImage,
    prepared: &Prepared,
    opts: &TraceOptions,
    progress: &ProgressBar,
) -> Result<Tracked, TraceError> {
    area::check_options(opts)?;
    let rebuilt;
    let prepared = if prepared.fits(img, &opts.params.prepare) {
        prepared
    } else {
        rebuilt = Prepared::build_with(img, &opts.params.prepare);
        &rebuilt
    };
    // The device's tone curve undone before darkness is measured (a file that names its curve
    // was linearised while read).
    let (tone, linear) = settle_tone(img, prepared, opts);
    let (img, prepared) = match &linear {
        Some((i, p)) => (i, p),
        None => (img, prepared),
    };
    let (paper, map) = (&prepared.paper, &prepared.map);
    let (w_px, h_px) = (img.width() as f64, img.height() as f64);
    // The red ink's colour (a pass over the whole image) on a second thread, beside the
    // mapping and the seeds.
    let (ink, mapped) = std::thread::scope(|s| {
        let ink = s.spawn(|| ink::InkModel::estimate(img, paper, ink::DEFAULT_FLOOR, map.k));
        let mapped = mapping::map_pixels(img, map, paper, opts).map(|m| {
            let seeds = {
                let roi = area::roi_predicate(opts.mapping, &m.to_mm, w_px, h_px);
                area::seed_mask(map, paper, opts, &roi, m.px_per_mm)
            };
            (m, seeds)
        });
        let ink = ink
            .join()
            .unwrap_or_else(|payload| std::panic::resume_unwind(payload));
        (ink, mapped)
    });
    let (mapped, seeds) = mapped?;
    let mapping::Mapped {
        to_mm,
        fiducials: fids,
        camera,
        camera_fit,
        dot_residual_mm,
        flatness,
        px_per_mm,
        occluders,
    } = mapped;

    let roi = area::roi_predicate(opts.mapping, &to_mm, w_px, h_px);
    let params = centreline::TrackParams {
        px_per_mm,
        step_px: 0.25 * px_per_mm,
        max_width_px: opts.max_width_mm * px_per_mm,
        min_mass: 0.03 * px_per_mm,
        centreline: opts.params.centreline,
    };
    let pieces = centreline::track_all(
        img, &ink, paper, &occluders, map, &seeds, &roi, &params, progress,
    );
    // Edges of light are not ink: steps of light cut out, the page's own edge dropped (on a
    // printed sheet; a plain-scale image, e.g. a plotter's photo, is traced as it was).
    let cp = &opts.params.centreline;
    let sheet = matches!(opts.mapping, Mapping::Fiducials { .. });
    let pieces = if sheet {
        centreline::cut_light_steps(pieces, img, &ink, paper, px_per_mm, cp)
    } else {
        pieces
    };
    let pieces_mm: Vec<chain::PieceMm> = pieces
        .into_iter()
        .map(|p| chain::PieceMm {
            pts: p.pts_px.iter().map(|q| to_mm(*q)).collect(),
            closed: p.closed,
        })
        .filter(|p| polyline_length(&p.pts, p.closed) >= 0.5)
        .filter(|p| !sheet || !centreline::is_page_edge(p, cp))
        .collect();
    Ok(Tracked {
        pieces_mm,
        linear,
        meta: Meta {
            tone,
            flatness,
            red_ink: ink.red_ink.is_some(),
            fiducials: fids,
            dot_residual_mm,
            camera,
            camera_fit,
            px_per_mm,
        },
    })
}
