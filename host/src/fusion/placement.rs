//! Where the sheet lies in frame R: the sheet frame (FORMATS.md "Scanned sheets": origin at the
//! centre of the fiducial square, x right, y up, mm) placed on the 45-degree plane.
//!
//! # Placement file (TOML, `--placement SHEET.toml`)
//! ```toml
//! format = "rigctl-placement/1"
//! origin_mm = [0.0, -300.0, 139.2893]     # sheet origin in R, mm
//! x_axis = [-1.0, 0.0, 0.0]               # sheet x in R (unit)
//! y_axis = [0.0, -0.70710678, 0.70710678] # sheet y in R (unit)
//! ```
//! The axes must be unit vectors at right angles (within 1e-3; they are re-orthonormalised).
//! The sheet normal `n = x_axis x y_axis` points out of the paper, towards the pencil; the tool
//! axis while drawing is `-n`. Heights above the sheet are `n . (p - origin)`.

use std::path::Path;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::error::FusionError;
use crate::io::atomic::write_text_atomic;
use crate::io::finite::TextFormat;

/// Format tag of the placement file.
pub const PLACEMENT_FORMAT: &str = "rigctl-placement/1";

/// Centre of the thesis's circle (section 5.5.1), mm in R: the default sheet origin.
pub const THESIS_CIRCLE_CENTRE_MM: [f64; 3] = [0.0, -300.0, 139.289_3];

/// The sheet frame in R.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SheetPlacement {
    /// Sheet origin, mm in R.
    pub origin_mm: Vector3<f64>,
    /// Sheet x axis in R (unit).
    pub x_axis: Vector3<f64>,
    /// Sheet y axis in R (unit, at right angles to x).
    pub y_axis: Vector3<f64>,
}

#[derive(Serialize, Deserialize)]
struct PlacementFile {
    format: String,
    origin_mm: [f64; 3],
    x_axis: [f64; 3],
    y_axis: [f64; 3],
}

impl SheetPlacement {
    /// A placement from an origin and two axes; the axes must be unit length and at right angles
    /// within 1e-3 (then they are made exactly orthonormal, x kept).
    pub fn new(
        origin_mm: Vector3<f64>,
        x_axis: Vector3<f64>,
        y_axis: Vector3<f64>,
    ) -> Result<Self, FusionError> {
        let finite = origin_mm
            .iter()
            .chain(x_axis.iter())
            .chain(y_axis.iter())
            .all(|v| v.is_finite());
        if !finite {
            return Err(FusionError::Invalid(
                "sheet placement: non-finite value".into(),
            ));
        }
        let tol = 1e-3;
        if (x_axis.norm() - 1.0).abs() > tol
            || (y_axis.norm() - 1.0).abs() > tol
            || x_axis.dot(&y_axis).abs() > tol
        {
            return Err(FusionError::Invalid(format!(
                "sheet placement: x_axis {:?} and y_axis {:?} must be unit vectors at right angles",
                x_axis.as_slice(),
                y_axis.as_slice()
            )));
        }
        let x = x_axis.normalize();
        let y = (y_axis - x * x.dot(&y_axis)).normalize();
        Ok(Self {
            origin_mm,
            x_axis: x,
            y_axis: y,
        })
    }

    /// The sheet on the thesis's 45-degree plane (the plane of the circle of section 5.5.1),
    /// origin at `origin_mm`, read from the far side of the robot's base: y runs up the slope
    /// (towards -y and +z of R), x = -x of R, so the normal `(0, 1, 1)/sqrt 2` faces the robot.
    pub fn thesis_plane(origin_mm: Vector3<f64>) -> Self {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        Self {
            origin_mm,
            x_axis: Vector3::new(-1.0, 0.0, 0.0),
            y_axis: Vector3::new(0.0, -h, h),
        }
    }

    /// Unit normal `x_axis x y_axis` (out of the paper, towards the pencil).
    pub fn normal(&self) -> Vector3<f64> {
        self.x_axis.cross(&self.y_axis)
    }

    /// Sheet mm -> R mm (a point on the paper).
    pub fn to_r_mm(&self, s: [f64; 2]) -> Vector3<f64> {
        self.origin_mm + self.x_axis * s[0] + self.y_axis * s[1]
    }

    /// A direction in sheet coordinates -> the direction in R.
    pub fn dir_to_r(&self, d: [f64; 2]) -> Vector3<f64> {
        self.x_axis * d[0] + self.y_axis * d[1]
    }

    /// R mm -> sheet mm of the point's orthogonal projection onto the paper.
    pub fn to_sheet_mm(&self, p: &Vector3<f64>) -> [f64; 2] {
        let d = p - self.origin_mm;
        [d.dot(&self.x_axis), d.dot(&self.y_axis)]
    }

    /// Signed height of `p` above the paper, mm (positive on the pencil's side).
    pub fn height_mm(&self, p: &Vector3<f64>) -> f64 {
        (p - self.origin_mm).dot(&self.normal())
    }

    /// The placement file's text.
    pub fn to_toml_string(&self) -> String {
        let f = PlacementFile {
            format: PLACEMENT_FORMAT.into(),
            origin_mm: self.origin_mm.into(),
            x_axis: self.x_axis.into(),
            y_axis: self.y_axis.into(),
        };
        let body = toml::to_string(&f).unwrap_or_default();
        format!(
            "# rigctl sheet placement: sheet frame (origin at the fiducial square's centre, x \
             right, y up) in frame R, mm\n{body}"
        )
    }

    /// Parses a placement file's text (`path` names it in errors).
    pub fn from_toml_str(text: &str, path: &Path) -> Result<Self, FusionError> {
        let bad = |reason: String| FusionError::Toml {
            path: path.to_path_buf(),
            reason,
        };
        let f: PlacementFile = toml::from_str(text).map_err(|e| bad(e.to_string()))?;
        if f.format != PLACEMENT_FORMAT {
            return Err(bad(format!(
                "format `{}`, expected `{PLACEMENT_FORMAT}`",
                f.format
            )));
        }
        Self::new(f.origin_mm.into(), f.x_axis.into(), f.y_axis.into())
            .map_err(|e| bad(e.to_string()))
    }

    /// Reads a placement file.
    pub fn read(path: &Path) -> Result<Self, FusionError> {
        let text = crate::io::read::read_text_capped(path, crate::io::read::CAP_SMALL_TEXT)
            .map_err(|source| FusionError::Read {
                path: path.to_path_buf(),
                source,
            })?;
        Self::from_toml_str(&text, path)
    }

    /// Writes the placement file atomically.
    pub fn write(&self, path: &Path) -> Result<(), FusionError> {
        write_text_atomic(path, TextFormat::Toml, &self.to_toml_string())?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thesis_plane_holds_the_thesis_circle_points() {
        let pl = SheetPlacement::thesis_plane(Vector3::from(THESIS_CIRCLE_CENTRE_MM));
        // the four points of section 5.5.1 lie on the plane, 100 mm from the origin
        for p in crate::sim::paths::THESIS_CIRCLE_POINTS_MM {
            let p = Vector3::from(p);
            assert!(pl.height_mm(&p).abs() < 1e-4, "{p}");
            let s = pl.to_sheet_mm(&p);
            assert!((s[0].hypot(s[1]) - 100.0).abs() < 1e-4);
            assert!((pl.to_r_mm(s) - p).norm() < 1e-9);
        }
        // the normal faces the robot (+y) and up (+z), at 45 degrees
        let n = pl.normal();
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((n - Vector3::new(0.0, h, h)).norm() < 1e-12);
        // the top of the sheet is the highest point
        assert!(pl.to_r_mm([0.0, 100.0]).z > pl.to_r_mm([0.0, -100.0]).z);
    }

    #[test]
    fn file_round_trip_and_bad_axes() {
        let pl = SheetPlacement::thesis_plane(Vector3::new(1.0, -310.0, 150.0));
        let text = pl.to_toml_string();
        let back = SheetPlacement::from_toml_str(&text, Path::new("p.toml")).unwrap();
        assert!((back.origin_mm - pl.origin_mm).norm() < 1e-12);
        assert!((back.y_axis - pl.y_axis).norm() < 1e-12);
        let skew = text.replace("x_axis = [-1.0, 0.0, 0.0]", "x_axis = [-1.0, 0.1, 0.0]");
        assert_ne!(skew, text);
        assert!(SheetPlacement::from_toml_str(&skew, Path::new("p.toml")).is_err());
    }
}
