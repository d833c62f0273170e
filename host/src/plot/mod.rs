//! Plots of the calibration reports (thesis figures 3.8, 5.8-5.10, 5.12 and the error plots of
//! chapter 4), as PNG or SVG files or as SVG text for inline HTML.
//!
//! Every chart is a plain-data struct implementing [`Chart`] (see [`charts`], drawn on `scaffold`):
//!
//! | chart | shows |
//! |---|---|
//! | [`PoseErrorBars`] | error of every pose before / after, sorted by the "before" error |
//! | [`ErrorHistogram`] | histogram of the pose errors before / after |
//! | [`LineChart`] | one or more stacked panels of series over a common x: error along a path (fig. 5.12), influence of each parameter over the poses (fig. 3.8), joint moments and tilts along a trajectory (fig. 5.8-5.10) |
//! | [`Scatter`] | residual against a regressor, before / after (diagnose) |
//! | [`plan::PlanPoses`] | the poses of a calibration plan over the candidates, top and side views (`rigctl plan --plot`, [`plan::poses_svg`]) |
//! | [`StageBars`] | held-out error (mean, RMS) at each stage: nominal, calibrated, with the effects found (report's first screen) |
//! | [`WorkspaceViews`] | points in the workspace from above (x-y) and the side (x-z): planned poses |
//! | [`PathErrorsChart`] | thesis fig. 5.12 from the low-cost rig: `|dP|` before / standard / after and the two measured deviations along the drawn path, from a `calibrate --errors-csv` file (see [`path_errors`]) |
//!
//! [`write()`]`(path, &chart)` picks the format from the extension (`.png` or `.svg`) and writes
//! the file atomically; [`svg_string`] returns the SVG document. Text in PNG files is drawn
//! with the embedded DejaVu Sans (assets/DejaVuSans.ttf, Bitstream Vera licence), registered on
//! first use: no system font is looked up.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{Classify, ErrorKind};
use crate::io::atomic::{write_bytes_atomic, AtomicWriteError};

pub mod charts;
pub mod path_errors;
pub mod plan;
mod scaffold;
pub mod summary;

pub use charts::{ErrorHistogram, LineChart, Panel, PoseErrorBars, Scatter, Series};
pub use path_errors::{
    parse_path_errors, path_errors_svg, read_path_errors, PathErrorSummary, PathErrors,
    PathErrorsChart, PathErrorsError,
};
pub use summary::{StageBars, WorkspaceViews};

/// The font family name every chart uses.
pub const FONT_FAMILY: &str = "sans-serif";

static FONT_BYTES: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// Why a plot could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The output file name has no `.png` / `.svg` extension.
    #[error("{path}: unknown plot format (use a .png or .svg file name)")]
    Format { path: PathBuf },
    /// The data cannot be plotted (empty, mismatched lengths, no finite value).
    #[error("plot {title:?}: {message}")]
    Data { title: String, message: String },
    /// The embedded font could not be loaded.
    #[error("the embedded font could not be registered")]
    Font,
    /// The drawing backend failed.
    #[error("plot {title:?}: drawing failed: {message}")]
    Draw { title: String, message: String },
    /// PNG encoding failed.
    #[error("{path}: PNG encoding failed: {message}")]
    Encode { path: PathBuf, message: String },
    /// The file could not be written.
    #[error(transparent)]
    Write(#[from] AtomicWriteError),
}

impl Classify for PlotError {
    fn kind(&self) -> ErrorKind {
        match self {
            PlotError::Format { .. } | PlotError::Data { .. } => ErrorKind::BadInput,
            _ => ErrorKind::Failure,
        }
    }
}

/// Output format of a plot file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Portable Network Graphics (raster, text drawn with the embedded font).
    Png,
    /// Scalable Vector Graphics (text left to the viewer's sans-serif font).
    Svg,
}

impl Format {
    /// The format named by `path`'s extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Self, PlotError> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(Format::Png),
            Some("svg") => Ok(Format::Svg),
            _ => Err(PlotError::Format {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Something that can be drawn on a plotters drawing area of any backend.
pub trait Chart {
    /// Title (also used in error messages).
    fn title(&self) -> &str;
    /// Size in pixels (width, height).
    fn size_px(&self) -> (u32, u32);
    /// Draws the chart onto `area` (already filled white).
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError>;
}

/// Registers the embedded font under [`FONT_FAMILY`] once per process. Called by [`write()`] and
/// [`svg_string`]; any other code drawing text with plotters must call it first.
pub fn register_fonts() -> Result<(), PlotError> {
    static DONE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, FONT_BYTES).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(PlotError::Font)
    }
}

pub(crate) fn draw_err<E: std::fmt::Display>(title: &str) -> impl Fn(E) -> PlotError + '_ {
    move |e| PlotError::Draw {
        title: title.to_string(),
        message: e.to_string(),
    }
}

/// The chart as a standalone SVG document.
pub fn svg_string<C: Chart>(chart: &C) -> Result<String, PlotError> {
    register_fonts()?;
    let mut text = String::new();
    {
        let area = SVGBackend::with_string(&mut text, chart.size_px()).into_drawing_area();
        area.fill(&WHITE).map_err(draw_err(chart.title()))?;
        chart.draw(&area)?;
        area.present().map_err(draw_err(chart.title()))?;
    }
    Ok(text)
}

/// The chart as PNG bytes.
pub fn png_bytes<C: Chart>(chart: &C) -> Result<Vec<u8>, PlotError> {
    register_fonts()?;
    let (w, h) = chart.size_px();
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let area = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        area.fill(&WHITE).map_err(draw_err(chart.title()))?;
        chart.draw(&area)?;
        area.present().map_err(draw_err(chart.title()))?;
    }
    let encode_err = |message: String| PlotError::Encode {
        path: PathBuf::from(chart.title()),
        message,
    };
    let img = image::RgbImage::from_raw(w, h, rgb)
        .ok_or_else(|| encode_err("buffer size mismatch".into()))?;
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(|e| encode_err(e.to_string()))?;
    Ok(out.into_inner())
}

/// Writes `chart` to `path` (PNG or SVG by extension), atomically.
pub fn write<C: Chart>(path: &Path, chart: &C) -> Result<(), PlotError> {
    let bytes = match Format::from_path(path)? {
        Format::Svg => {
            let svg = svg_string(chart)?;
            crate::io::atomic::check_text_for(path, crate::io::finite::TextFormat::Xml, &svg)?;
            svg.into_bytes()
        }
        Format::Png => png_bytes(chart)?,
    };
    write_bytes_atomic(path, &bytes)?;
    Ok(())
}
