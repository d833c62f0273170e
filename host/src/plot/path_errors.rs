//! Thesis fig. 5.12 from the low-cost rig (thesis 5.5.2): the error of the robot along the
//! drawn path, before calibration (nominal model), after the standard (rigid) calibration and
//! after the chosen method (e.g. tilting).
//!
//! Input is the per-sample error file of `rigctl calibrate --samples FUSED.csv --errors-csv
//! ERR.csv` (`rigctl report` reads it as `path_errors.csv`):
//!
//! ```text
//! t,q1..qN,dev_u_before,dev_n_before,dp_before,dev_u_after,dev_n_after,dp_after,dev_u_standard,dev_n_standard,dp_standard
//! ```
//!
//! `t` in s, joints in deg, errors in mm: `dev_u` across the path in the sheet plane, `dev_n`
//! out of the sheet along its normal, `dp = hypot(dev_u, dev_n)` (checked to within
//! [`DP_TOLERANCE_MM`]). Other columns are ignored; `#` comment lines and blank lines are
//! skipped. Files of several sheets may be concatenated: a decrease of `t` or a step larger
//! than [`SEGMENT_GAP_S`] starts a new segment. The chart's x axis is the time along the path
//! with the segments joined end to end ([`PathErrors::path_time_s`]), their boundaries dashed.

use std::ops::Range;
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::charts::{
    data_err, finite_range, labelled_series, legend_box, line_swatch, line_x_range, Axes, AFTER,
    BEFORE, PALETTE,
};
use super::{draw_err, svg_string, Chart, PlotError, FONT_FAMILY};
use crate::error::{Classify, ErrorKind};
use crate::joints::table::{Table, TableError};

/// A step of `t` larger than this (s) starts a new segment (sheet).
pub const SEGMENT_GAP_S: f64 = 1.0;

/// Largest accepted difference between `dp_*` and `hypot(dev_u_*, dev_n_*)`, mm (the writer
/// rounds every value to 1e-6 mm).
pub const DP_TOLERANCE_MM: f64 = 2e-3;

/// Legend label of the nominal model.
pub const BEFORE_LABEL: &str = "before (nominal model)";
/// Legend label of the standard (rigid) calibration.
pub const STANDARD_LABEL: &str = "standard (rigid calibration)";
/// Default legend label of the chosen method ([`PathErrors::after_label`]).
pub const AFTER_LABEL: &str = "after (chosen method)";

/// Colour of the standard calibration's curve.
const STANDARD: RGBColor = PALETTE[2];
/// Colour of the segment boundaries.
const BOUNDARY: RGBColor = RGBColor(127, 127, 127);

/// Why a path error file cannot be used (always bad input).
#[derive(Debug, thiserror::Error)]
pub enum PathErrorsError {
    /// Unreadable file, missing column, wrong field count or a value that is not a number.
    #[error(transparent)]
    Table(#[from] TableError),
    /// `dp_*` is not the magnitude of its two deviations.
    #[error(
        "{file}:{line}: column `{column}` = {dp_mm} mm, but hypot of its deviations is {hypot_mm:.6} mm"
    )]
    Magnitude {
        file: String,
        line: usize,
        column: String,
        dp_mm: f64,
        hypot_mm: f64,
    },
}

impl Classify for PathErrorsError {
    fn kind(&self) -> ErrorKind {
        match self {
            PathErrorsError::Table(e) => e.kind(),
            PathErrorsError::Magnitude { .. } => ErrorKind::BadInput,
        }
    }
}

/// The errors of one model at every sample, mm.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ErrorSet {
    /// Across the path, in the sheet plane.
    pub dev_u_mm: Vec<f64>,
    /// Out of the sheet, along its normal.
    pub dev_n_mm: Vec<f64>,
    /// `hypot(dev_u, dev_n)`.
    pub dp_mm: Vec<f64>,
}

/// Root mean square of `v` (0 for no value).
fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

impl ErrorSet {
    /// RMS / max / mean of `dp` and RMS of each deviation (all 0 for no sample).
    pub fn summary(&self) -> SetSummary {
        SetSummary {
            dp_rms_mm: rms(&self.dp_mm),
            dp_max_mm: self.dp_mm.iter().copied().fold(0.0, f64::max),
            dp_mean_mm: self.dp_mm.iter().sum::<f64>() / self.dp_mm.len().max(1) as f64,
            dev_u_rms_mm: rms(&self.dev_u_mm),
            dev_n_rms_mm: rms(&self.dev_n_mm),
        }
    }

    fn push(&mut self, dev_u_mm: f64, dev_n_mm: f64, dp_mm: f64) {
        self.dev_u_mm.push(dev_u_mm);
        self.dev_n_mm.push(dev_n_mm);
        self.dp_mm.push(dp_mm);
    }
}

/// Statistics of one [`ErrorSet`], mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SetSummary {
    /// RMS of `dp`.
    pub dp_rms_mm: f64,
    /// Largest `dp`.
    pub dp_max_mm: f64,
    /// Mean of `dp`.
    pub dp_mean_mm: f64,
    /// RMS of `dev_u`.
    pub dev_u_rms_mm: f64,
    /// RMS of `dev_n`.
    pub dev_n_rms_mm: f64,
}

/// Statistics of a [`PathErrors`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathErrorSummary {
    /// Number of samples.
    pub n_samples: usize,
    /// Number of segments (sheets).
    pub n_segments: usize,
    /// Nominal model.
    pub before: SetSummary,
    /// Standard (rigid) calibration.
    pub standard: SetSummary,
    /// Chosen method.
    pub after: SetSummary,
}

/// The per-sample errors along the drawn path.
#[derive(Debug, Clone, PartialEq)]
pub struct PathErrors {
    /// Where the data came from (file name), for messages.
    pub source: String,
    /// Robot-clock time of each sample, s.
    pub t_s: Vec<f64>,
    /// Joint readings of each sample, deg (`q1..qN`; empty rows if the file has none).
    pub q_deg: Vec<Vec<f64>>,
    /// Nominal model.
    pub before: ErrorSet,
    /// Standard (rigid) calibration.
    pub standard: ErrorSet,
    /// Chosen method.
    pub after: ErrorSet,
    /// Sample ranges of the segments (sheets), in order, covering every sample.
    pub segments: Vec<Range<usize>>,
    /// Legend label of [`PathErrors::after`] (default [`AFTER_LABEL`]; e.g. `after (tilting)`).
    pub after_label: String,
}

/// Splits sample times into segments: a new one starts where `t` decreases or steps by more
/// than [`SEGMENT_GAP_S`].
pub fn segments_of(t_s: &[f64]) -> Vec<Range<usize>> {
    let mut out = Vec::new();
    let mut start = 0;
    for i in 1..t_s.len() {
        let step = t_s[i] - t_s[i - 1];
        if !(0.0..=SEGMENT_GAP_S).contains(&step) {
            out.push(start..i);
            start = i;
        }
    }
    if start < t_s.len() {
        out.push(start..t_s.len());
    }
    out
}

impl PathErrors {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// No sample.
    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Median positive time step inside the segments, s (0 if there is none).
    fn typical_step_s(&self) -> f64 {
        let mut steps: Vec<f64> = self
            .segments
            .iter()
            .flat_map(|r| {
                let t = self.t_s.get(r.clone()).unwrap_or(&[]);
                t.windows(2).map(|w| w[1] - w[0])
            })
            .filter(|d| *d > 0.0)
            .collect();
        steps.sort_by(f64::total_cmp);
        steps.get(steps.len() / 2).copied().unwrap_or(0.0)
    }

    /// Time along the path, s: 0 at the first sample, each segment's times relative to its
    /// first sample, the segments joined end to end one typical step apart.
    pub fn path_time_s(&self) -> Vec<f64> {
        let step_s = self.typical_step_s();
        let mut x: Vec<f64> = Vec::with_capacity(self.len());
        for r in &self.segments {
            let Some(t) = self.t_s.get(r.clone()) else {
                continue;
            };
            let offset = x.last().map_or(0.0, |last| last + step_s);
            x.extend(t.iter().map(|ti| offset + ti - t[0]));
        }
        x
    }

    /// RMS / max / mean of each model.
    pub fn summary(&self) -> PathErrorSummary {
        PathErrorSummary {
            n_samples: self.len(),
            n_segments: self.segments.len(),
            before: self.before.summary(),
            standard: self.standard.summary(),
            after: self.after.summary(),
        }
    }

    /// Every column has one value per sample and the segments cover the samples in order.
    fn check(&self) -> Result<(), String> {
        let n = self.len();
        if n == 0 {
            return Err("no samples".into());
        }
        for (name, set) in [
            ("before", &self.before),
            ("standard", &self.standard),
            ("after", &self.after),
        ] {
            for v in [&set.dev_u_mm, &set.dev_n_mm, &set.dp_mm] {
                if v.len() != n {
                    return Err(format!("{name}: {} values for {n} samples", v.len()));
                }
            }
        }
        let mut next = 0;
        for r in &self.segments {
            if r.start != next || r.end <= r.start {
                return Err(format!("segment {r:?} does not follow sample {next}"));
            }
            next = r.end;
        }
        if next != n {
            return Err(format!("segments cover {next} of {n} samples"));
        }
        Ok(())
    }
}

/// Reads a path error file (see the module documentation).
pub fn read_path_errors(path: &Path) -> Result<PathErrors, PathErrorsError> {
    from_table(&Table::read(path)?)
}

/// Parses path error text; `origin` names it in messages.
pub fn parse_path_errors(text: &str, origin: &str) -> Result<PathErrors, PathErrorsError> {
    from_table(&Table::parse(text, origin)?)
}

fn from_table(table: &Table) -> Result<PathErrors, PathErrorsError> {
    let t_col = table.need("t")?;
    let q_cols: Vec<usize> = (1..).map_while(|j| table.find(&format!("q{j}"))).collect();
    let sets = ["before", "standard", "after"];
    let mut cols = Vec::with_capacity(sets.len());
    for set in sets {
        cols.push([
            table.need(&format!("dev_u_{set}"))?,
            table.need(&format!("dev_n_{set}"))?,
            table.need(&format!("dp_{set}"))?,
        ]);
    }
    let mut t_s = Vec::with_capacity(table.rows.len());
    let mut q_deg = Vec::with_capacity(table.rows.len());
    let mut errors: [ErrorSet; 3] = Default::default();
    for row in &table.rows {
        t_s.push(table.number(row, t_col)?);
        q_deg.push(
            q_cols
                .iter()
                .map(|&c| table.number(row, c))
                .collect::<Result<Vec<f64>, _>>()?,
        );
        for (set, &[u_col, n_col, dp_col]) in errors.iter_mut().zip(&cols) {
            let (u, n, dp) = (
                table.number(row, u_col)?,
                table.number(row, n_col)?,
                table.number(row, dp_col)?,
            );
            let hypot_mm = u.hypot(n);
            if (dp - hypot_mm).abs() > DP_TOLERANCE_MM {
                return Err(PathErrorsError::Magnitude {
                    file: table.file.clone(),
                    line: row.line,
                    column: table.header[dp_col].clone(),
                    dp_mm: dp,
                    hypot_mm,
                });
            }
            set.push(u, n, dp);
        }
    }
    let [before, standard, after] = errors;
    Ok(PathErrors {
        source: table.file.clone(),
        segments: segments_of(&t_s),
        t_s,
        q_deg,
        before,
        standard,
        after,
        after_label: AFTER_LABEL.to_string(),
    })
}

/// The fig. 5.12 chart of a [`PathErrors`]: `|dP|` of the three models on top, `dev_u` and
/// `dev_n` before / after below, against the time along the path.
#[derive(Debug, Clone)]
pub struct PathErrorsChart<'a> {
    /// The data.
    pub data: &'a PathErrors,
    /// Title (with the RMS of `|dP|` of each model).
    pub title: String,
}

impl<'a> PathErrorsChart<'a> {
    /// The chart of `data`, titled with the RMS of each model's `|dP|`.
    pub fn new(data: &'a PathErrors) -> Self {
        let s = data.summary();
        Self {
            data,
            title: format!(
                "Path error along the drawn path: RMS |dP| before {:.3}, standard {:.3}, after {:.3} mm",
                s.before.dp_rms_mm, s.standard.dp_rms_mm, s.after.dp_rms_mm
            ),
        }
    }
}

/// One curve of a panel: values, legend label, colour.
type Curve<'c> = (&'c [f64], String, RGBColor);

impl PathErrorsChart<'_> {
    /// Draws one panel: the curves segment by segment, the segment boundaries and the legend.
    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        x: &[f64],
        y_desc: &str,
        curves: &[Curve<'_>],
    ) -> Result<(), PlotError> {
        let t = self.title.as_str();
        let (x0, x1) = line_x_range(x).ok_or_else(|| data_err(t, "no finite time"))?;
        let (y0, y1) = finite_range(curves.iter().flat_map(|c| c.0).chain(&[0.0]))
            .ok_or_else(|| data_err(t, format!("panel {y_desc:?}: no finite value")))?;
        // headroom for the legend (upper right), one line per curve
        let y1 = y1 + 0.1 * curves.len() as f64 * (y1 - y0);
        let x_desc = if self.data.segments.len() > 1 {
            format!(
                "time along the path (s); {} segments joined, boundaries dashed",
                self.data.segments.len()
            )
        } else {
            "time along the path (s)".to_string()
        };
        let mut chart = Axes {
            caption: None,
            x: x0..x1,
            y: y0..y1,
            x_desc: &x_desc,
            y_desc,
            y_label_px: 65,
            x_mesh: true,
        }
        .draw(area, t)?;
        let step_s = self.data.typical_step_s();
        for r in self.data.segments.iter().skip(1) {
            let xb = x[r.start] - 0.5 * step_s;
            chart
                .draw_series(DashedLineSeries::new(
                    [(xb, y0), (xb, y1)],
                    6,
                    4,
                    BOUNDARY.stroke_width(1),
                ))
                .map_err(draw_err(t))?;
        }
        for (values, label, color) in curves {
            let lines = self.data.segments.iter().flat_map(|r| {
                let pts: Vec<(f64, f64)> = r.clone().map(|i| (x[i], values[i])).collect();
                let dot = if pts.len() == 1 { 2 } else { 0 };
                LineSeries::new(pts, color.stroke_width(2)).point_size(dot)
            });
            labelled_series(&mut chart, t, lines, label, line_swatch(*color))?;
        }
        legend_box(&mut chart, t)
    }
}

impl Chart for PathErrorsChart<'_> {
    fn title(&self) -> &str {
        &self.title
    }
    fn size_px(&self) -> (u32, u32) {
        (1000, 1040)
    }
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let t = self.title.as_str();
        let d = self.data;
        d.check()
            .map_err(|m| data_err(t, format!("{}: {m}", d.source)))?;
        let s = d.summary();
        let x = d.path_time_s();
        let label = |name: &str, rms_mm: f64| format!("{name}, RMS {rms_mm:.3} mm");
        let titled = area.titled(t, (FONT_FAMILY, 18)).map_err(draw_err(t))?;
        let h = titled.dim_in_pixel().1;
        let (top, rest) = titled.split_vertically(h * 2 / 5);
        let (middle, bottom) = rest.split_vertically(rest.dim_in_pixel().1 / 2);
        let after_label = d.after_label.as_str();
        self.panel(
            &top,
            &x,
            "|dP| (mm)",
            &[
                (
                    &d.before.dp_mm,
                    label(BEFORE_LABEL, s.before.dp_rms_mm),
                    BEFORE,
                ),
                (
                    &d.standard.dp_mm,
                    label(STANDARD_LABEL, s.standard.dp_rms_mm),
                    STANDARD,
                ),
                (&d.after.dp_mm, label(after_label, s.after.dp_rms_mm), AFTER),
            ],
        )?;
        self.panel(
            &middle,
            &x,
            "dev_u, across the path (mm)",
            &[
                (
                    &d.before.dev_u_mm,
                    label(BEFORE_LABEL, s.before.dev_u_rms_mm),
                    BEFORE,
                ),
                (
                    &d.after.dev_u_mm,
                    label(after_label, s.after.dev_u_rms_mm),
                    AFTER,
                ),
            ],
        )?;
        self.panel(
            &bottom,
            &x,
            "dev_n, out of the sheet (mm)",
            &[
                (
                    &d.before.dev_n_mm,
                    label(BEFORE_LABEL, s.before.dev_n_rms_mm),
                    BEFORE,
                ),
                (
                    &d.after.dev_n_mm,
                    label(after_label, s.after.dev_n_rms_mm),
                    AFTER,
                ),
            ],
        )
    }
}

/// The fig. 5.12 chart of `p` as an SVG document (write it with
/// [`crate::io::atomic::write_atomic`], or use [`super::write`] with [`PathErrorsChart`] for
/// PNG or SVG by extension).
pub fn path_errors_svg(p: &PathErrors) -> Result<String, PlotError> {
    svg_string(&PathErrorsChart::new(p))
}

#[cfg(test)]
pub(crate) mod tests;
