//! The chart types of [`crate::plot`]: plain data in, drawing on any plotters backend.
//!
//! Every chart is built from the same crate-internal scaffolding: `Axes::draw` (caption,
//! margins, label areas, mesh and axis descriptions), `labelled_series` (a series with its
//! legend swatch: `bar_swatch`, `dot_swatch`, `line_swatch`) and `legend_box`.

use std::borrow::Borrow;
use std::ops::Range;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;

use super::{draw_err, Chart, PlotError, FONT_FAMILY};

/// Colour of "before" data.
pub const BEFORE: RGBColor = RGBColor(31, 119, 180);
/// Colour of "after" data.
pub const AFTER: RGBColor = RGBColor(214, 39, 40);
/// Colours of the series of a [`LineChart`], in order (repeating).
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// A named sequence of values (one per x of the chart).
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Values, one per x.
    pub values: Vec<f64>,
}

impl Series {
    /// A series called `label`.
    pub fn new(label: impl Into<String>, values: Vec<f64>) -> Self {
        Self {
            label: label.into(),
            values,
        }
    }
}

pub(crate) fn data_err(title: &str, message: impl Into<String>) -> PlotError {
    PlotError::Data {
        title: title.to_string(),
        message: message.into(),
    }
}

/// Smallest and largest finite value of `values`; `None` if nothing is finite.
fn finite_bounds<'a>(values: impl IntoIterator<Item = &'a f64>) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &v in values.into_iter().filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    (lo <= hi).then_some((lo, hi))
}

/// Finite range of `values`, widened so that it is never empty; `None` if nothing is finite.
pub(crate) fn finite_range<'a>(values: impl IntoIterator<Item = &'a f64>) -> Option<(f64, f64)> {
    let (lo, hi) = finite_bounds(values)?;
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        lo.abs().max(1.0) * 0.05
    };
    Some((lo - pad, hi + pad))
}

/// X range of a line plot: the exact finite extent (lines end at the frame), padded only when
/// it is a single value.
pub(crate) fn line_x_range<'a>(
    values: impl IntoIterator<Item = &'a f64> + Clone,
) -> Option<(f64, f64)> {
    match finite_bounds(values.clone())? {
        (lo, hi) if hi > lo => Some((lo, hi)),
        _ => finite_range(values),
    }
}

fn check_before_after(title: &str, before: &[f64], after: &[f64]) -> Result<(), PlotError> {
    if before.is_empty() {
        return Err(data_err(title, "no values"));
    }
    if before.len() != after.len() {
        return Err(data_err(
            title,
            format!("{} values before but {} after", before.len(), after.len()),
        ));
    }
    Ok(())
}

/// A chart context with `f64` axes.
pub(crate) type XyChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The axes of one plot: ranges, descriptions and layout. [`Axes::draw`] is the scaffolding
/// every chart shares.
pub(crate) struct Axes<'s> {
    /// Caption above the plotting area (`None` when the area is already titled).
    pub caption: Option<&'s str>,
    /// X range.
    pub x: Range<f64>,
    /// Y range.
    pub y: Range<f64>,
    /// X axis description (with unit).
    pub x_desc: &'s str,
    /// Y axis description (with unit).
    pub y_desc: &'s str,
    /// Width of the y label area, px.
    pub y_label_px: u32,
    /// Draw vertical grid lines.
    pub x_mesh: bool,
}

impl Axes<'_> {
    /// Builds the coordinate system on `area` and draws the mesh and axis descriptions;
    /// `title` names the chart in errors.
    pub(crate) fn draw<'a, DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        title: &str,
    ) -> Result<XyChart<'a, DB>, PlotError> {
        let mut builder = ChartBuilder::on(area);
        if let Some(caption) = self.caption {
            builder.caption(caption, (FONT_FAMILY, 18));
        }
        let mut chart = builder
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(self.y_label_px)
            .build_cartesian_2d(self.x.clone(), self.y.clone())
            .map_err(draw_err(title))?;
        let mut mesh = chart.configure_mesh();
        if !self.x_mesh {
            mesh.disable_x_mesh();
        }
        mesh.x_desc(self.x_desc)
            .y_desc(self.y_desc)
            .label_style((FONT_FAMILY, 12))
            .draw()
            .map_err(draw_err(title))?;
        Ok(chart)
    }
}

/// Legend swatch of bars: a filled box.
pub(crate) fn bar_swatch(color: RGBColor) -> impl Fn((i32, i32)) -> Rectangle<(i32, i32)> {
    move |(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], color.filled())
}

/// Legend swatch of scatter points: a dot.
pub(crate) fn dot_swatch(color: RGBColor) -> impl Fn((i32, i32)) -> Circle<(i32, i32), i32> {
    move |(x, y)| Circle::new((x + 7, y), 3, color.filled())
}

/// Legend swatch of a line series: a short line.
pub(crate) fn line_swatch(color: RGBColor) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
}

/// Draws `elements` on `chart` and registers them in the legend as `label`, shown by
/// `swatch` (one of [`bar_swatch`], [`dot_swatch`], [`line_swatch`]).
pub(crate) fn labelled_series<'a, DB, E, R, S, L, LE>(
    chart: &mut XyChart<'a, DB>,
    title: &str,
    elements: S,
    label: &str,
    swatch: L,
) -> Result<(), PlotError>
where
    DB: DrawingBackend + 'a,
    S: IntoIterator<Item = R>,
    R: Borrow<E>,
    E: Drawable<DB>,
    for<'b> &'b E: PointCollection<'b, (f64, f64)>,
    L: Fn((i32, i32)) -> LE + 'a,
    LE: IntoDynElement<'a, DB, (i32, i32)>,
{
    chart
        .draw_series(elements)
        .map_err(draw_err(title))?
        .label(label)
        .legend(swatch);
    Ok(())
}

/// Draws the legend of `chart` (upper right, white box).
pub(crate) fn legend_box<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    title: &str,
) -> Result<(), PlotError> {
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT_FAMILY, 13))
        .draw()
        .map_err(draw_err(title))
}

/// Error of every pose before and after calibration as bars, poses sorted by decreasing
/// "before" error (the "after" bar of the same pose drawn narrower on top).
#[derive(Debug, Clone, PartialEq)]
pub struct PoseErrorBars {
    /// Title.
    pub title: String,
    /// Error of each pose before (mm).
    pub before_mm: Vec<f64>,
    /// Error of the same poses after (mm).
    pub after_mm: Vec<f64>,
    /// Legend labels of before / after.
    pub labels: [String; 2],
}

impl Chart for PoseErrorBars {
    fn title(&self) -> &str {
        &self.title
    }
    fn size_px(&self) -> (u32, u32) {
        (900, 380)
    }
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let t = self.title.as_str();
        check_before_after(t, &self.before_mm, &self.after_mm)?;
        let mut order: Vec<usize> = (0..self.before_mm.len()).collect();
        order.sort_by(|&a, &b| self.before_mm[b].total_cmp(&self.before_mm[a]));
        let (_, hi) = finite_range(self.before_mm.iter().chain(&self.after_mm))
            .ok_or_else(|| data_err(t, "no finite value"))?;
        let mut chart = Axes {
            caption: Some(t),
            x: 0.0..order.len() as f64,
            y: 0.0..hi.max(1e-9),
            x_desc: "pose (sorted by error before)",
            y_desc: "|dP| (mm)",
            y_label_px: 60,
            x_mesh: false,
        }
        .draw(area, t)?;
        let bar = |values: &[f64], inset: f64, color: RGBColor| {
            order
                .iter()
                .enumerate()
                .filter(|(_, &i)| values[i].is_finite())
                .map(move |(k, &i)| {
                    let x = k as f64;
                    Rectangle::new(
                        [(x + inset, 0.0), (x + 1.0 - inset, values[i])],
                        color.filled(),
                    )
                })
                .collect::<Vec<_>>()
        };
        for (values, inset, label, color) in [
            (&self.before_mm, 0.05, &self.labels[0], BEFORE),
            (&self.after_mm, 0.25, &self.labels[1], AFTER),
        ] {
            let bars = bar(values, inset, color);
            labelled_series(&mut chart, t, bars, label, bar_swatch(color))?;
        }
        legend_box(&mut chart, t)
    }
}

/// Histogram of pose errors before and after (same bins, side-by-side bars).
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorHistogram {
    /// Title.
    pub title: String,
    /// Errors before (mm).
    pub before_mm: Vec<f64>,
    /// Errors after (mm).
    pub after_mm: Vec<f64>,
    /// Number of bins (at least 1).
    pub bins: usize,
    /// Legend labels of before / after.
    pub labels: [String; 2],
}

impl ErrorHistogram {
    /// Counts of `values` in `bins` equal bins over `0..max_mm` (the last bin includes
    /// `max_mm`; non-finite values are not counted).
    pub fn counts(values: &[f64], bins: usize, max_mm: f64) -> Vec<usize> {
        let bins = bins.max(1);
        let mut c = vec![0usize; bins];
        let w = max_mm / bins as f64;
        for &v in values.iter().filter(|v| v.is_finite() && **v >= 0.0) {
            let k = if w > 0.0 { (v / w) as usize } else { 0 };
            c[k.min(bins - 1)] += 1;
        }
        c
    }
}

impl Chart for ErrorHistogram {
    fn title(&self) -> &str {
        &self.title
    }
    fn size_px(&self) -> (u32, u32) {
        (900, 380)
    }
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let t = self.title.as_str();
        if self.before_mm.is_empty() && self.after_mm.is_empty() {
            return Err(data_err(t, "no values"));
        }
        let max_mm = self
            .before_mm
            .iter()
            .chain(&self.after_mm)
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max)
            .max(1e-9);
        let bins = self.bins.max(1);
        let cb = Self::counts(&self.before_mm, bins, max_mm);
        let ca = Self::counts(&self.after_mm, bins, max_mm);
        let top = cb.iter().chain(&ca).copied().max().unwrap_or(1).max(1) as f64 * 1.1;
        let w = max_mm / bins as f64;
        let mut chart = Axes {
            caption: Some(t),
            x: 0.0..max_mm,
            y: 0.0..top,
            x_desc: "|dP| (mm)",
            y_desc: "poses",
            y_label_px: 50,
            x_mesh: false,
        }
        .draw(area, t)?;
        let bars = |c: &[usize], half: f64, color: RGBColor| {
            c.iter()
                .enumerate()
                .map(|(k, &n)| {
                    let x0 = k as f64 * w + half * w * 0.5 + 0.05 * w;
                    Rectangle::new([(x0, 0.0), (x0 + 0.4 * w, n as f64)], color.filled())
                })
                .collect::<Vec<_>>()
        };
        for (counts, half, label, color) in [
            (&cb, 0.0, &self.labels[0], BEFORE),
            (&ca, 1.0, &self.labels[1], AFTER),
        ] {
            let elements = bars(counts, half, color);
            labelled_series(&mut chart, t, elements, label, bar_swatch(color))?;
        }
        legend_box(&mut chart, t)
    }
}

/// One panel of a [`LineChart`]: a y axis and its series.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Y axis description (with unit).
    pub y_label: String,
    /// Series, each with one value per x of the chart.
    pub series: Vec<Series>,
}

/// Stacked panels of line series over a common x axis.
#[derive(Debug, Clone, PartialEq)]
pub struct LineChart {
    /// Title.
    pub title: String,
    /// X axis description (with unit).
    pub x_label: String,
    /// X values (common to every series).
    pub x: Vec<f64>,
    /// Panels, drawn top to bottom.
    pub panels: Vec<Panel>,
    /// Mark every point with a dot (for sparse x, e.g. pose numbers).
    pub markers: bool,
}

impl LineChart {
    /// Thesis fig. 5.12: position error along a path against the path parameter, before and
    /// after calibration.
    pub fn path_error(
        s: Vec<f64>,
        before_mm: Vec<f64>,
        after_mm: Vec<f64>,
        labels: [&str; 2],
    ) -> Self {
        Self {
            title: "Position error along the path".into(),
            x_label: "path parameter s".into(),
            x: s,
            panels: vec![Panel {
                y_label: "|dP| (mm)".into(),
                series: vec![
                    Series::new(labels[0], before_mm),
                    Series::new(labels[1], after_mm),
                ],
            }],
            markers: false,
        }
    }

    /// Thesis fig. 3.8: the position change `|dP|` (mm) each parameter's small step causes at
    /// every pose (`series` one per parameter, one value per pose).
    pub fn influence(series: Vec<Series>) -> Self {
        let n = series.first().map_or(0, |s| s.values.len());
        Self {
            title: "Influence of each parameter per configuration".into(),
            x_label: "pose".into(),
            x: (1..=n).map(|k| k as f64).collect(),
            panels: vec![Panel {
                y_label: "|dP| (mm)".into(),
                series,
            }],
            markers: true,
        }
    }

    /// Thesis fig. 5.8-5.10: joint moments (kgf.m) and tilts (deg) along a trajectory; one
    /// series per joint (and component) in each panel.
    pub fn moments_tilts(t_s: Vec<f64>, moments: Vec<Series>, tilts: Vec<Series>) -> Self {
        Self {
            title: "Joint moments and tilts along the trajectory".into(),
            x_label: "t (s)".into(),
            x: t_s,
            panels: vec![
                Panel {
                    y_label: "moment (kgf.m)".into(),
                    series: moments,
                },
                Panel {
                    y_label: "tilt (deg)".into(),
                    series: tilts,
                },
            ],
            markers: false,
        }
    }
}

impl Chart for LineChart {
    fn title(&self) -> &str {
        &self.title
    }
    fn size_px(&self) -> (u32, u32) {
        (900, 140 + 300 * self.panels.len().max(1) as u32)
    }
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let t = self.title.as_str();
        if self.x.is_empty() || self.panels.is_empty() {
            return Err(data_err(t, "no values"));
        }
        let (x0, x1) = if self.markers {
            finite_range(&self.x)
        } else {
            line_x_range(&self.x)
        }
        .ok_or_else(|| data_err(t, "no finite x"))?;
        let titled = area.titled(t, (FONT_FAMILY, 18)).map_err(draw_err(t))?;
        let parts = titled.split_evenly((self.panels.len(), 1));
        for (panel, part) in self.panels.iter().zip(&parts) {
            for s in &panel.series {
                if s.values.len() != self.x.len() {
                    return Err(data_err(
                        t,
                        format!(
                            "series {:?} has {} values for {} x",
                            s.label,
                            s.values.len(),
                            self.x.len()
                        ),
                    ));
                }
            }
            let (y0, y1) =
                finite_range(panel.series.iter().flat_map(|s| &s.values)).ok_or_else(|| {
                    data_err(t, format!("panel {:?}: no finite value", panel.y_label))
                })?;
            let mut chart = Axes {
                caption: None,
                x: x0..x1,
                y: y0..y1,
                x_desc: &self.x_label,
                y_desc: &panel.y_label,
                y_label_px: 65,
                x_mesh: true,
            }
            .draw(part, t)?;
            for (k, s) in panel.series.iter().enumerate() {
                let color = PALETTE[k % PALETTE.len()];
                let pts: Vec<(f64, f64)> = self
                    .x
                    .iter()
                    .zip(&s.values)
                    .filter(|(x, y)| x.is_finite() && y.is_finite())
                    .map(|(x, y)| (*x, *y))
                    .collect();
                let line = LineSeries::new(pts.clone(), color.stroke_width(2));
                labelled_series(&mut chart, t, line, &s.label, line_swatch(color))?;
                if self.markers {
                    chart
                        .draw_series(pts.into_iter().map(|p| Circle::new(p, 2, color.filled())))
                        .map_err(draw_err(t))?;
                }
            }
            legend_box(&mut chart, t)?;
        }
        Ok(())
    }
}

/// Residual against a regressor, before and after (e.g. an effect added by `diagnose`).
#[derive(Debug, Clone, PartialEq)]
pub struct Scatter {
    /// Title.
    pub title: String,
    /// X axis description (the regressor, with unit).
    pub x_label: String,
    /// Y axis description (with unit).
    pub y_label: String,
    /// Regressor value of each point.
    pub x: Vec<f64>,
    /// Residual before, one per x.
    pub before: Vec<f64>,
    /// Residual after, one per x.
    pub after: Vec<f64>,
    /// Legend labels of before / after.
    pub labels: [String; 2],
}

impl Chart for Scatter {
    fn title(&self) -> &str {
        &self.title
    }
    fn size_px(&self) -> (u32, u32) {
        (900, 420)
    }
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let t = self.title.as_str();
        check_before_after(t, &self.before, &self.after)?;
        if self.x.len() != self.before.len() {
            return Err(data_err(
                t,
                format!("{} x for {} residuals", self.x.len(), self.before.len()),
            ));
        }
        let (x0, x1) = finite_range(&self.x).ok_or_else(|| data_err(t, "no finite x"))?;
        let (y0, y1) = finite_range(self.before.iter().chain(&self.after).chain(&[0.0]))
            .ok_or_else(|| data_err(t, "no finite value"))?;
        let mut chart = Axes {
            caption: Some(t),
            x: x0..x1,
            y: y0..y1,
            x_desc: &self.x_label,
            y_desc: &self.y_label,
            y_label_px: 65,
            x_mesh: true,
        }
        .draw(area, t)?;
        let pts = |ys: &[f64], color: RGBColor| {
            self.x
                .iter()
                .zip(ys)
                .filter(|(x, y)| x.is_finite() && y.is_finite())
                .map(move |(x, y)| Circle::new((*x, *y), 3, color.filled()))
                .collect::<Vec<_>>()
        };
        for (ys, label, color) in [
            (&self.before, &self.labels[0], BEFORE),
            (&self.after, &self.labels[1], AFTER),
        ] {
            let dots = pts(ys, color);
            labelled_series(&mut chart, t, dots, label, dot_swatch(color))?;
        }
        legend_box(&mut chart, t)
    }
}

#[cfg(test)]
mod tests;
