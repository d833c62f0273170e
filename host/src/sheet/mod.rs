//! The printable trace sheet: its geometry, shared by the SVG renderer ([`svg`]), the simulated
//! scan renderer (`trace::synth`) and the tracer (`trace`); the paths drawn on it in the
//! simulated sessions and where their sheet lies ([`drawn`]).
//!
//! Sheet coordinates (FORMATS.md "Scanned sheets"): origin at the centre of the fiducial square,
//! x to the right, y up, mm. The square's centre sits at the centre of an A4 portrait page.
//! Page coordinates (SVG, renderer) have their origin at the page's top-left corner, x to the
//! right, y down, mm.

pub mod drawn;
pub mod svg;

/// A4 page width, mm.
pub const PAGE_WIDTH_MM: f64 = 210.0;
/// A4 page height, mm.
pub const PAGE_HEIGHT_MM: f64 = 297.0;
/// Nominal centre-to-centre spacing of the corner fiducials (the side of the square), mm.
pub const FIDUCIAL_SPACING_MM: f64 = 180.0;
/// Diameter of the four corner fiducial discs, mm.
pub const FIDUCIAL_DIAMETER_MM: f64 = 6.0;
/// Diameter of the orientation dot, mm.
pub const ORIENTATION_DOT_DIAMETER_MM: f64 = 3.0;
/// Nominal centre of the orientation dot (near the top-left fiducial), sheet mm.
pub const ORIENTATION_DOT_MM: [f64; 2] = [-90.0, 75.0];
/// Radius of the reference circle, mm: the thesis' 45-degree-plane circle through
/// [0 -370.7107 210], [-100 -300 139.2893], [0 -229.2893 68.5786], [100 -300 139.2893]
/// (centre [0 -300 139.2893]) seen in its own plane.
pub const CIRCLE_RADIUS_MM: f64 = 100.0;
/// Half length of the reference line (along x, through the origin), mm.
pub const LINE_HALF_LENGTH_MM: f64 = 100.0;
/// The tracer reads pencil only inside |x| <= this (nominal sheet mm).
pub const TRACE_AREA_HALF_WIDTH_MM: f64 = 105.0;
/// The tracer reads pencil only inside |y| <= this (nominal sheet mm); the scale bar and the
/// text lie outside.
pub const TRACE_AREA_HALF_HEIGHT_MM: f64 = 108.0;
/// Length of the printed scale bar, mm.
pub const SCALE_BAR_LENGTH_MM: f64 = 100.0;
/// y of the printed scale bar's baseline, sheet mm.
pub const SCALE_BAR_Y_MM: f64 = -116.0;

/// The four corner fiducial centres for a square of side `spacing_mm`, sheet mm, in the order
/// top-left, top-right, bottom-right, bottom-left.
pub fn fiducial_centres_mm(spacing_mm: f64) -> [[f64; 2]; 4] {
    let h = spacing_mm / 2.0;
    [[-h, h], [h, h], [h, -h], [-h, -h]]
}

/// The orientation dot's centre for a square of side `spacing_mm` (it scales with the print).
pub fn orientation_dot_mm(spacing_mm: f64) -> [f64; 2] {
    let f = spacing_mm / FIDUCIAL_SPACING_MM;
    [ORIENTATION_DOT_MM[0] * f, ORIENTATION_DOT_MM[1] * f]
}

/// Diameter of the sheet-v2 ring dots, mm.
pub const RING_DOT_DIAMETER_MM: f64 = 1.5;
/// Pitch of the sheet-v2 ring dots along the fiducial square's sides, mm (nominal print).
pub const RING_PITCH_MM: f64 = 15.0;

/// The 43 ring dots of sheet v2 (FORMATS.md "Scanned sheets"), sheet mm, for a square of side
/// `spacing_mm`: at `(t, +-h)` and `(+-h, t)` for `t = -75, -60, ..., 75` (scaled with the print),
/// leaving out the orientation dot's place `(-h, 75)`.
pub fn ring_dots_mm(spacing_mm: f64) -> Vec<[f64; 2]> {
    let f = spacing_mm / FIDUCIAL_SPACING_MM;
    let h = spacing_mm / 2.0;
    let dot = orientation_dot_mm(spacing_mm);
    let mut out = Vec::with_capacity(43);
    for i in -5i32..=5 {
        let t = i as f64 * RING_PITCH_MM * f;
        for p in [[t, h], [t, -h], [h, t], [-h, t]] {
            if (p[0] - dot[0]).abs() + (p[1] - dot[1]).abs() > 1e-9 {
                out.push(p);
            }
        }
    }
    out
}

/// Sheet mm -> page mm (origin top-left, y down).
pub fn sheet_to_page_mm(p: [f64; 2]) -> [f64; 2] {
    [PAGE_WIDTH_MM / 2.0 + p[0], PAGE_HEIGHT_MM / 2.0 - p[1]]
}

/// The printed reference path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReferencePath {
    /// The thesis circle: radius [`CIRCLE_RADIUS_MM`] about the sheet origin.
    Circle,
    /// A straight line along x through the origin, from -[`LINE_HALF_LENGTH_MM`] to
    /// +[`LINE_HALF_LENGTH_MM`].
    Line,
}

impl ReferencePath {
    /// A short human description for the printed caption.
    pub fn description(self) -> String {
        match self {
            Self::Circle => format!("circle, radius {CIRCLE_RADIUS_MM} mm about the origin"),
            Self::Line => format!(
                "straight line y = 0 from x = -{LINE_HALF_LENGTH_MM} to +{LINE_HALF_LENGTH_MM} mm"
            ),
        }
    }

    /// Distance from the sheet point `p` (mm) to the printed path, mm.
    pub fn distance_mm(self, p: [f64; 2]) -> f64 {
        match self {
            ReferencePath::Circle => (p[0].hypot(p[1]) - CIRCLE_RADIUS_MM).abs(),
            ReferencePath::Line => (p[0].abs() - LINE_HALF_LENGTH_MM).max(0.0).hypot(p[1]),
        }
    }

    /// Length of the printed path, mm.
    pub fn length_mm(self) -> f64 {
        match self {
            ReferencePath::Circle => std::f64::consts::TAU * CIRCLE_RADIUS_MM,
            ReferencePath::Line => 2.0 * LINE_HALF_LENGTH_MM,
        }
    }

    /// Whether the path is closed.
    pub fn is_closed(self) -> bool {
        matches!(self, Self::Circle)
    }

    /// The path as a polyline in sheet mm with vertices at most `spacing_mm` apart (for a
    /// closed path the last vertex is not repeated).
    pub fn polyline_mm(self, spacing_mm: f64) -> Vec<[f64; 2]> {
        let spacing_mm = if spacing_mm.is_finite() && spacing_mm > 1e-3 {
            spacing_mm
        } else {
            0.1
        };
        match self {
            Self::Circle => {
                let n = ((self.length_mm() / spacing_mm).ceil() as usize).max(8);
                (0..n)
                    .map(|i| {
                        let a = std::f64::consts::TAU * i as f64 / n as f64;
                        [CIRCLE_RADIUS_MM * a.cos(), CIRCLE_RADIUS_MM * a.sin()]
                    })
                    .collect()
            }
            Self::Line => {
                let n = ((self.length_mm() / spacing_mm).ceil() as usize).max(1);
                (0..=n)
                    .map(|i| {
                        let x =
                            -LINE_HALF_LENGTH_MM + 2.0 * LINE_HALF_LENGTH_MM * i as f64 / n as f64;
                        [x, 0.0]
                    })
                    .collect()
            }
        }
    }
}

/// An axis-aligned filled rectangle in sheet mm (`min` and `max` corners).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RectMm {
    pub min: [f64; 2],
    pub max: [f64; 2],
}

/// The printed scale bar as filled rectangles (sheet mm): a 0.3 mm bar of
/// [`SCALE_BAR_LENGTH_MM`] centred on x = 0 at y = [`SCALE_BAR_Y_MM`], with 3 mm ticks every
/// 10 mm (5 mm at 0, 50 and 100 mm).
pub fn scale_bar_rects_mm() -> Vec<RectMm> {
    let x0 = -SCALE_BAR_LENGTH_MM / 2.0;
    let y = SCALE_BAR_Y_MM;
    let half_line = 0.15;
    let mut rects = vec![RectMm {
        min: [x0 - half_line, y - half_line],
        max: [x0 + SCALE_BAR_LENGTH_MM + half_line, y + half_line],
    }];
    for i in 0..=10 {
        let x = x0 + 10.0 * i as f64;
        let tick_mm = if i % 5 == 0 { 5.0 } else { 3.0 };
        rects.push(RectMm {
            min: [x - half_line, y],
            max: [x + half_line, y + tick_mm],
        });
    }
    rects
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The thesis' four circle points (section 5.5.1) lie on a circle of radius 100 mm about
    /// their mean, in a plane at 45 degrees: the sheet's circle radius.
    #[test]
    fn thesis_circle_has_radius_100() {
        let pts: [[f64; 3]; 4] = [
            [0.0, -370.7107, 210.0],
            [-100.0, -300.0, 139.2893],
            [0.0, -229.2893, 68.5786],
            [100.0, -300.0, 139.2893],
        ];
        let mut c = [0.0f64; 3];
        for p in &pts {
            for (ck, pk) in c.iter_mut().zip(p) {
                *ck += pk / 4.0;
            }
        }
        for p in &pts {
            let r = ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt();
            assert!((r - CIRCLE_RADIUS_MM).abs() < 1e-3, "r = {r}");
        }
        // Plane normal from two diameters: (0,1,-1)/sqrt2 -> 45 degrees to the base plane.
        let d1 = [
            pts[2][0] - pts[0][0],
            pts[2][1] - pts[0][1],
            pts[2][2] - pts[0][2],
        ];
        let d2 = [
            pts[3][0] - pts[1][0],
            pts[3][1] - pts[1][1],
            pts[3][2] - pts[1][2],
        ];
        let n = [
            d1[1] * d2[2] - d1[2] * d2[1],
            d1[2] * d2[0] - d1[0] * d2[2],
            d1[0] * d2[1] - d1[1] * d2[0],
        ];
        let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let tilt_deg = (n[2].abs() / norm).acos().to_degrees();
        assert!((tilt_deg - 45.0).abs() < 1e-3, "tilt {tilt_deg}");
    }

    #[test]
    fn fiducials_fit_on_a4_and_dot_is_near_top_left() {
        for c in fiducial_centres_mm(FIDUCIAL_SPACING_MM) {
            let p = sheet_to_page_mm(c);
            assert!(p[0] > 10.0 && p[0] < PAGE_WIDTH_MM - 10.0);
            assert!(p[1] > 10.0 && p[1] < PAGE_HEIGHT_MM - 10.0);
        }
        let tl = fiducial_centres_mm(FIDUCIAL_SPACING_MM)[0];
        let dot = orientation_dot_mm(FIDUCIAL_SPACING_MM);
        assert_eq!(dot, ORIENTATION_DOT_MM);
        assert!((tl[1] - dot[1] - 15.0).abs() < 1e-12 && tl[0] == dot[0]);
    }

    #[test]
    fn ring_has_43_dots_on_the_square_without_the_orientation_dot() {
        let ring = ring_dots_mm(FIDUCIAL_SPACING_MM);
        assert_eq!(ring.len(), 43);
        for p in &ring {
            assert!((p[0].abs() - 90.0).abs() < 1e-9 || (p[1].abs() - 90.0).abs() < 1e-9);
            assert!(p[0].abs() <= 90.0 && p[1].abs() <= 90.0);
            assert!((p[0] + 90.0).abs() + (p[1] - 75.0).abs() > 1.0);
        }
        assert!(ring.contains(&[-90.0, 60.0]) && ring.contains(&[75.0, -90.0]));
    }

    #[test]
    fn polylines_respect_spacing() {
        for path in [ReferencePath::Circle, ReferencePath::Line] {
            let pts = path.polyline_mm(0.5);
            let mut pairs: Vec<_> = pts.windows(2).map(|w| (w[0], w[1])).collect();
            if path.is_closed() {
                pairs.push((pts[pts.len() - 1], pts[0]));
            }
            for (a, b) in pairs {
                let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
                assert!(d <= 0.5 + 1e-9 && d > 0.1, "{path:?}: {d}");
            }
        }
    }
}
