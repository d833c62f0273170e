//! The scaffolding every chart of [`crate::plot`] is drawn with: the colours, [`Series`],
//! the ranges of finite values, `Axes::draw` (caption, margins, label areas, mesh and axis
//! descriptions), `labelled_series` (a series with its legend swatch: `bar_swatch`,
//! `dot_swatch`, `line_swatch`) and `legend_box`.

use std::borrow::Borrow;
use std::ops::Range;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;

use super::{draw_err, PlotError, FONT_FAMILY};

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
pub(crate) fn finite_bounds<'a>(values: impl IntoIterator<Item = &'a f64>) -> Option<(f64, f64)> {
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

pub(crate) fn check_before_after(
    title: &str,
    before: &[f64],
    after: &[f64],
) -> Result<(), PlotError> {
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
