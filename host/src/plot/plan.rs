//! The poses of a calibration plan in the workspace: top view (x-y) and side view (x-z) of the
//! planned tool points over the candidate set (for `rigctl plan --plot` and the report).

use plotters::coord::Shift;
use plotters::prelude::*;

use super::charts::{data_err, finite_range, AFTER};
use super::{draw_err, svg_string, Chart, PlotError, FONT_FAMILY};

/// Planned poses over the candidates, two projections side by side.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanPoses {
    /// Title.
    pub title: String,
    /// Nominal tool points of the planned poses, mm (frame R).
    pub planned_mm: Vec<[f64; 3]>,
    /// Tool points of (some of) the candidates, mm, drawn light grey.
    pub candidates_mm: Vec<[f64; 3]>,
    /// The robot at a few poses: stick figures from the base through the link origins to the
    /// tool point, mm.
    pub robots_mm: Vec<Vec<[f64; 3]>>,
}

const GREY: RGBColor = RGBColor(200, 200, 200);
const ROBOT: RGBColor = RGBColor(60, 60, 60);

impl PlanPoses {
    fn projection<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        axes: (usize, usize),
        caption: &str,
    ) -> Result<(), PlotError> {
        let t = self.title.as_str();
        let all = || {
            self.planned_mm
                .iter()
                .chain(&self.candidates_mm)
                .chain(self.robots_mm.iter().flatten())
        };
        let xs: Vec<f64> = all().map(|p| p[axes.0]).collect();
        let ys: Vec<f64> = all().map(|p| p[axes.1]).collect();
        let (x0, x1) = finite_range(&xs).ok_or_else(|| data_err(t, "no finite tool point"))?;
        let (y0, y1) = finite_range(&ys).ok_or_else(|| data_err(t, "no finite tool point"))?;
        let names = ["x (mm)", "y (mm)", "z (mm)"];
        let mut chart = ChartBuilder::on(area)
            .caption(caption, (FONT_FAMILY, 16))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(55)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(draw_err(t))?;
        chart
            .configure_mesh()
            .x_desc(names[axes.0])
            .y_desc(names[axes.1])
            .label_style((FONT_FAMILY, 12))
            .draw()
            .map_err(draw_err(t))?;
        chart
            .draw_series(
                self.candidates_mm
                    .iter()
                    .map(|p| Circle::new((p[axes.0], p[axes.1]), 1, GREY.filled())),
            )
            .map_err(draw_err(t))?
            .label("candidates")
            .legend(|(x, y)| Circle::new((x, y), 3, GREY.filled()));
        chart
            .draw_series(
                self.planned_mm
                    .iter()
                    .map(|p| Circle::new((p[axes.0], p[axes.1]), 4, AFTER.filled())),
            )
            .map_err(draw_err(t))?
            .label("planned")
            .legend(|(x, y)| Circle::new((x, y), 4, AFTER.filled()));
        for (k, robot) in self.robots_mm.iter().enumerate() {
            let line = chart
                .draw_series(LineSeries::new(
                    robot.iter().map(|p| (p[axes.0], p[axes.1])),
                    ShapeStyle::from(&ROBOT).stroke_width(3),
                ))
                .map_err(draw_err(t))?;
            if k == 0 {
                line.label("robot at a few poses")
                    .legend(|(x, y)| PathElement::new(vec![(x - 8, y), (x + 8, y)], ROBOT));
            }
            chart
                .draw_series(
                    robot
                        .iter()
                        .map(|p| Circle::new((p[axes.0], p[axes.1]), 2, ROBOT.filled())),
                )
                .map_err(draw_err(t))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font((FONT_FAMILY, 12))
            .draw()
            .map_err(draw_err(t))?;
        Ok(())
    }
}

impl Chart for PlanPoses {
    fn title(&self) -> &str {
        &self.title
    }
    fn size_px(&self) -> (u32, u32) {
        (1000, 480)
    }
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        if self.planned_mm.is_empty() {
            return Err(data_err(&self.title, "no planned pose"));
        }
        let t = self.title.as_str();
        let inner = area.titled(t, (FONT_FAMILY, 20)).map_err(draw_err(t))?;
        let (left, right) = inner.split_horizontally(500);
        self.projection(&left, (0, 1), "top view (x-y)")?;
        self.projection(&right, (0, 2), "side view (x-z)")?;
        Ok(())
    }
}

/// The SVG document of planned poses over candidates (see [`PlanPoses`]).
pub fn poses_svg(
    title: &str,
    planned_mm: &[[f64; 3]],
    candidates_mm: &[[f64; 3]],
    robots_mm: &[Vec<[f64; 3]>],
) -> Result<String, PlotError> {
    svg_string(&PlanPoses {
        title: title.to_string(),
        planned_mm: planned_mm.to_vec(),
        candidates_mm: candidates_mm.to_vec(),
        robots_mm: robots_mm.to_vec(),
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn draws_both_views() {
        let planned = [[100.0, 0.0, 200.0], [0.0, 150.0, 300.0]];
        let cands = [[50.0, 50.0, 250.0]];
        let robot = vec![vec![
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 150.0],
            [100.0, 0.0, 200.0],
        ]];
        let svg = super::poses_svg("plan", &planned, &cands, &robot).unwrap();
        assert!(svg.contains("top view") && svg.contains("side view"));
        assert!(svg.contains("robot at a few poses") && svg.contains("<polyline"));
        assert!(super::poses_svg("plan", &[], &cands, &[]).is_err());
    }
}
