//! Small charts of the report's first screen and plan section: [`StageBars`] (held-out error,
//! mean and RMS, at each stage: nominal, calibrated, with the effects found) and
//! [`WorkspaceViews`] (poses in the workspace, x-y and x-z projections).

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::charts::{bar_swatch, data_err, dot_swatch, finite_range, legend_box, PALETTE};
use super::{draw_err, Chart, PlotError, FONT_FAMILY};

/// Horizontal bars: mean and RMS of the held-out error at each stage on a logarithmic axis (so
/// 0.036 mm reads beside 71.8 mm), with the value written at the end of each bar and, when
/// known, the measurement floor as a dashed line.
#[derive(Debug, Clone, PartialEq)]
pub struct StageBars {
    /// Title.
    pub title: String,
    /// Stage names, top to bottom.
    pub stages: Vec<String>,
    /// Mean error at each stage (mm).
    pub mean_mm: Vec<f64>,
    /// RMS error at each stage (mm).
    pub rms_mm: Vec<f64>,
    /// The floor the errors are judged against: its name and its RMS Euclidean error (mm).
    pub floor_mm: Option<(String, f64)>,
}

/// The decade at or below `v` (`v` > 0).
fn decade_below(v: f64) -> f64 {
    10f64.powf(v.log10().floor())
}

/// An axis tick of a logarithmic length axis: `0.01`, `0.1`, `1`, `10`.
fn tick_text(v: f64) -> String {
    let s = format!("{v:.6}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

impl StageBars {
    /// Bands below the stages for the legend: one for mean and RMS, two with the floor.
    fn legend_bands(&self) -> usize {
        1 + usize::from(self.floor_mm.is_some())
    }

    /// The axis range (mm): from the decade below the smallest value (floor included) to
    /// twice the largest, for the labels.
    pub fn axis_mm(&self) -> Option<(f64, f64)> {
        let floor = self.floor_mm.iter().map(|f| f.1);
        let positive: Vec<f64> = self
            .mean_mm
            .iter()
            .chain(&self.rms_mm)
            .copied()
            .chain(floor)
            .filter(|v| v.is_finite() && *v > 0.0)
            .collect();
        let lo = positive.iter().copied().reduce(f64::min)?;
        let hi = positive.iter().copied().reduce(f64::max)?;
        Some((decade_below(lo), hi * 4.0))
    }
}

impl Chart for StageBars {
    fn title(&self) -> &str {
        &self.title
    }
    fn size_px(&self) -> (u32, u32) {
        // one band per stage and, below them, one for the legend
        (
            640,
            90 + 46 * (self.stages.len().max(1) + self.legend_bands()) as u32,
        )
    }
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let t = self.title.as_str();
        let n = self.stages.len();
        if n == 0 {
            return Err(data_err(t, "no stage"));
        }
        if self.mean_mm.len() != n || self.rms_mm.len() != n {
            return Err(data_err(t, "one mean and one RMS per stage are needed"));
        }
        // whole bands, so that the stage labels stay at the bands' middles
        let legend_band = self.legend_bands() as f64;
        let (x_min, x_max) = self
            .axis_mm()
            .ok_or_else(|| data_err(t, "no positive finite value"))?;
        let stages = self.stages.clone();
        let mut chart = ChartBuilder::on(area)
            .caption(t, (FONT_FAMILY, 17))
            .margin(8)
            .x_label_area_size(36)
            .y_label_area_size(225)
            .build_cartesian_2d((x_min..x_max).log_scale(), -legend_band..n as f64)
            .map_err(draw_err(t))?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .y_labels((n + self.legend_bands()) * 2 + 1)
            .y_label_formatter(&|y| {
                // a label at the middle of each stage's band, top to bottom
                let k = y.floor();
                if (y - k - 0.5).abs() < 1e-6 && k >= 0.0 && (k as usize) < stages.len() {
                    stages[stages.len() - 1 - k as usize].clone()
                } else {
                    String::new()
                }
            })
            .x_label_formatter(&|x| tick_text(*x))
            .x_desc("held-out error (mm, logarithmic)")
            .label_style((FONT_FAMILY, 15))
            .draw()
            .map_err(draw_err(t))?;
        let bands = [
            ("mean", &self.mean_mm, 0.52, 0.88),
            ("RMS", &self.rms_mm, 0.12, 0.48),
        ];
        for (k, (label, values, lo, hi)) in bands.into_iter().enumerate() {
            let color = PALETTE[k];
            let bars = values
                .iter()
                .enumerate()
                .filter(|(_, v)| v.is_finite() && **v > 0.0)
                .map(move |(i, &v)| {
                    let y = (n - 1 - i) as f64;
                    Rectangle::new([(x_min, y + lo), (v, y + hi)], color.filled())
                });
            chart
                .draw_series(bars)
                .map_err(draw_err(t))?
                .label(label)
                .legend(bar_swatch(color));
            let texts = values
                .iter()
                .enumerate()
                .filter(|(_, v)| v.is_finite() && **v > 0.0)
                .map(move |(i, &v)| {
                    let y = (n - 1 - i) as f64 + (lo + hi) / 2.0;
                    Text::new(
                        format!(" {}", fmt_mm(v)),
                        (v, y),
                        TextStyle::from((FONT_FAMILY, 15).into_font())
                            .pos(Pos::new(HPos::Left, VPos::Center)),
                    )
                });
            chart.draw_series(texts).map_err(draw_err(t))?;
        }
        if let Some((name, f)) = &self.floor_mm {
            if f.is_finite() && *f > 0.0 {
                let grey = RGBColor(90, 90, 90);
                chart
                    .draw_series(DashedLineSeries::new(
                        [(*f, -legend_band), (*f, n as f64)],
                        5,
                        4,
                        grey.stroke_width(2),
                    ))
                    .map_err(draw_err(t))?
                    .label(format!("{name} floor, RMS {} mm", fmt_mm(*f)))
                    .legend(move |(x, y)| {
                        PathElement::new([(x, y), (x + 16, y)], grey.stroke_width(2))
                    });
            }
        }
        // in the band below the stages
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font((FONT_FAMILY, 14))
            .draw()
            .map_err(draw_err(t))
    }
}

/// A length in mm with 3 significant digits (at least 4 decimals below 0.1 mm).
pub fn fmt_mm(v: f64) -> String {
    let a = v.abs();
    if a >= 100.0 {
        format!("{v:.1}")
    } else if a >= 0.1 {
        format!("{v:.3}")
    } else {
        format!("{v:.4}")
    }
}

/// Points in the workspace seen from above (x-y) and from the side (x-z), side by side.
#[derive(Debug, Clone, PartialEq)]
pub struct WorkspaceViews {
    /// Title.
    pub title: String,
    /// Named point sets (e.g. planned poses), mm in frame R.
    pub sets: Vec<(String, Vec<[f64; 3]>)>,
}

impl Chart for WorkspaceViews {
    fn title(&self) -> &str {
        &self.title
    }
    fn size_px(&self) -> (u32, u32) {
        (900, 420)
    }
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let t = self.title.as_str();
        let all = || self.sets.iter().flat_map(|(_, p)| p.iter());
        if all().next().is_none() {
            return Err(data_err(t, "no point"));
        }
        let titled = area.titled(t, (FONT_FAMILY, 16)).map_err(draw_err(t))?;
        let panels = titled.split_evenly((1, 2));
        for (panel, (axis, name)) in panels.iter().zip([(1usize, "y (mm)"), (2, "z (mm)")]) {
            let xs: Vec<f64> = all().map(|p| p[0]).collect();
            let vs: Vec<f64> = all().map(|p| p[axis]).collect();
            let (x0, x1) = finite_range(&xs).ok_or_else(|| data_err(t, "no finite x"))?;
            let (v0, v1) = finite_range(&vs).ok_or_else(|| data_err(t, "no finite value"))?;
            let mut chart = ChartBuilder::on(panel)
                .margin(8)
                .x_label_area_size(32)
                .y_label_area_size(55)
                .build_cartesian_2d(x0..x1, v0..v1)
                .map_err(draw_err(t))?;
            chart
                .configure_mesh()
                .x_desc("x (mm)")
                .y_desc(name)
                .label_style((FONT_FAMILY, 12))
                .draw()
                .map_err(draw_err(t))?;
            for (k, (label, pts)) in self.sets.iter().enumerate() {
                let color = PALETTE[k % PALETTE.len()];
                let dots = pts
                    .iter()
                    .filter(|p| p[0].is_finite() && p[axis].is_finite())
                    .map(move |p| Circle::new((p[0], p[axis]), 3, color.filled()));
                chart
                    .draw_series(dots)
                    .map_err(draw_err(t))?
                    .label(label.as_str())
                    .legend(dot_swatch(color));
            }
            legend_box(&mut chart, t)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::svg_string;

    #[test]
    fn stage_bars_write_every_value() {
        let c = StageBars {
            title: "held-out".into(),
            stages: vec!["nominal".into(), "calibrated".into()],
            mean_mm: vec![1.12, 0.0155],
            rms_mm: vec![1.3, 0.019],
            floor_mm: Some(("instrument".into(), 0.015)),
        };
        let svg = svg_string(&c).unwrap();
        for want in [
            "1.120",
            "0.0155",
            "1.300",
            "0.0190",
            "nominal",
            "calibrated",
        ] {
            assert!(svg.contains(want), "{want} missing");
        }
        // logarithmic: from the decade below the smallest value
        assert_eq!(c.axis_mm(), Some((0.01, 1.3 * 4.0)));
        assert!(svg.contains("instrument floor, RMS 0.0150 mm"));
        let bad = StageBars {
            rms_mm: vec![1.0],
            ..c
        };
        assert!(matches!(svg_string(&bad), Err(PlotError::Data { .. })));
    }

    #[test]
    fn workspace_views_need_points() {
        let c = WorkspaceViews {
            title: "plan".into(),
            sets: vec![("planned".into(), vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])],
        };
        assert!(svg_string(&c).unwrap().contains("planned"));
        let empty = WorkspaceViews {
            title: "plan".into(),
            sets: vec![],
        };
        assert!(matches!(svg_string(&empty), Err(PlotError::Data { .. })));
    }

    #[test]
    fn lengths_keep_three_significant_digits() {
        assert_eq!(fmt_mm(1.1234), "1.123");
        assert_eq!(fmt_mm(0.03961), "0.0396");
        assert_eq!(fmt_mm(0.2512), "0.251");
    }
}
