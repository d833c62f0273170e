//! The chart types of [`crate::plot`]: plain data in, drawing on any plotters backend, on the
//! scaffolding of [`super::scaffold`].

use plotters::coord::Shift;
use plotters::prelude::*;

pub use super::scaffold::*;
use super::{draw_err, Chart, PlotError, FONT_FAMILY};

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
