//! The paths the simulated sessions draw on the sheet (the circle and the line), where their
//! sheet lies by default, and the pencil axis while drawing: shared by the simulator
//! (`crate::sim::session`) and the sheet planner (`crate::plan::sheets`).

use std::str::FromStr;

use nalgebra::Vector3;

use super::{ReferencePath, CIRCLE_RADIUS_MM};

/// Default sheet origin of the simulated session, mm in R. With the pencil holder (d5 = 330 mm)
/// the thesis's circle about [0 -300 139.2893] is only partly reachable within the joint limits
/// of table 3.1 with a fixed pencil axis (see the `sim_plan` integration tests); on this parallel 45-degree
/// plane the whole circle and line are, with the pencil inclined 22.5 deg from the sheet normal
/// towards -z ([`default_pencil_axis`]).
pub const SESSION_SHEET_ORIGIN_MM: [f64; 3] = [55.0, -200.0, 200.0];

/// The default pencil (tool) axis while drawing on a sheet with normal `n`: halfway between
/// `-n` and straight down (22.5 deg from `-n` on the 45-degree plane).
pub fn default_pencil_axis(n: &Vector3<f64>) -> Vector3<f64> {
    (-n - Vector3::z()).normalize()
}

/// Half length of the drawn line, mm (the printed reference line is +-100 mm).
pub const LINE_HALF_LENGTH_DRAWN_MM: f64 = 90.0;

/// The drawn path (`simulate --session`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SessionPath {
    /// The thesis circle, radius 100 mm about the sheet origin, counter-clockwise on the sheet
    /// from (-100, 0).
    Circle,
    /// A straight line along sheet x from -90 to +90 mm, on a sheet whose origin is 30 mm up
    /// the slope from the circle's centre.
    Line,
}

impl FromStr for SessionPath {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        // the names are clap's (`ValueEnum`)
        <Self as clap::ValueEnum>::from_str(s, false)
            .map_err(|_| format!("unknown session path `{s}` (circle, line)"))
    }
}

impl SessionPath {
    /// The name used on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Circle => "circle",
            Self::Line => "line",
        }
    }

    /// Sheet point at path parameter `s` in 0..1.
    pub fn sheet_point(self, s: f64) -> [f64; 2] {
        match self {
            Self::Circle => {
                let a = std::f64::consts::PI + std::f64::consts::TAU * s;
                [CIRCLE_RADIUS_MM * a.cos(), CIRCLE_RADIUS_MM * a.sin()]
            }
            Self::Line => [LINE_HALF_LENGTH_DRAWN_MM * (2.0 * s - 1.0), 0.0],
        }
    }

    /// The printed reference path this drawn path follows.
    pub fn reference(self) -> ReferencePath {
        match self {
            Self::Circle => ReferencePath::Circle,
            Self::Line => ReferencePath::Line,
        }
    }
}
