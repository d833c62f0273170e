//! The traced curve (`rigctl trace` output, sheet mm): closest point and local in-plane normal.

use std::path::Path;

use super::FusionError;
use crate::io::table::Table;

/// The closest point of the curve to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest {
    /// The closest point, sheet mm.
    pub point: [f64; 2],
    /// Distance from the query, mm.
    pub distance_mm: f64,
    /// Unit tangent of the curve there (in the curve's point order), averaged over about
    /// +-[`TANGENT_HALF_SPAN_MM`].
    pub tangent: [f64; 2],
    /// Arc length from the curve's start to the closest point, mm.
    pub arc_mm: f64,
    /// Distance along the curve to its nearer end (infinite for a closed curve), mm.
    pub to_end_mm: f64,
    /// Largest angle between `tangent` and the 0.5 mm chords centred within +-2 mm of the
    /// closest point, rad: large at a step or kink of the curve.
    pub roughness_rad: f64,
}

/// Half length of the curve piece whose chord gives the tangent, mm.
pub const TANGENT_HALF_SPAN_MM: f64 = 1.5;

/// A traced polyline.
#[derive(Debug, Clone, PartialEq)]
pub struct TracedCurve {
    pts: Vec<[f64; 2]>,
    /// Cumulative arc length at each point, mm.
    arc: Vec<f64>,
    closed: bool,
}

impl TracedCurve {
    /// A curve through `pts` (at least 2); closed when its ends are within `close_tol_mm`.
    pub fn new(pts: Vec<[f64; 2]>, close_tol_mm: f64) -> Option<Self> {
        if pts.len() < 2 {
            return None;
        }
        let (a, b) = (pts[0], pts[pts.len() - 1]);
        let closed = (a[0] - b[0]).hypot(a[1] - b[1]) <= close_tol_mm;
        let mut pts = pts;
        if closed {
            pts.push(a);
        }
        let mut arc = vec![0.0];
        for w in pts.windows(2) {
            let l = arc[arc.len() - 1] + (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
            arc.push(l);
        }
        Some(Self { pts, arc, closed })
    }

    /// Whether the curve closes on itself.
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// Total length, mm.
    pub fn length_mm(&self) -> f64 {
        self.arc[self.arc.len() - 1]
    }

    /// The point at arc length `s` (wrapped for a closed curve, clamped otherwise).
    pub fn point_at(&self, s: f64) -> [f64; 2] {
        let len = self.length_mm();
        let s = if self.closed {
            s.rem_euclid(len)
        } else {
            s.clamp(0.0, len)
        };
        let i = self
            .arc
            .partition_point(|&a| a <= s)
            .clamp(1, self.pts.len() - 1);
        let (a0, a1) = (self.arc[i - 1], self.arc[i]);
        let f = if a1 > a0 { (s - a0) / (a1 - a0) } else { 0.0 };
        let (p, q) = (self.pts[i - 1], self.pts[i]);
        [p[0] + f * (q[0] - p[0]), p[1] + f * (q[1] - p[1])]
    }

    /// The closest point to `p` (brute force over the segments).
    pub fn closest(&self, p: [f64; 2]) -> Closest {
        let mut best = (f64::INFINITY, [0.0; 2], 0.0);
        for (i, w) in self.pts.windows(2).enumerate() {
            let d = [w[1][0] - w[0][0], w[1][1] - w[0][1]];
            let l2 = d[0] * d[0] + d[1] * d[1];
            let f = if l2 > 0.0 {
                (((p[0] - w[0][0]) * d[0] + (p[1] - w[0][1]) * d[1]) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let c = [w[0][0] + f * d[0], w[0][1] + f * d[1]];
            let dist = (p[0] - c[0]).hypot(p[1] - c[1]);
            if dist < best.0 {
                best = (dist, c, self.arc[i] + f * l2.sqrt());
            }
        }
        let (distance_mm, point, arc_mm) = best;
        let a = self.point_at(arc_mm - TANGENT_HALF_SPAN_MM);
        let b = self.point_at(arc_mm + TANGENT_HALF_SPAN_MM);
        let (tx, ty) = (b[0] - a[0], b[1] - a[1]);
        let tn = tx.hypot(ty).max(1e-300);
        let to_end_mm = if self.closed {
            f64::INFINITY
        } else {
            arc_mm.min(self.length_mm() - arc_mm)
        };
        let tangent = [tx / tn, ty / tn];
        let roughness_rad = (-4..=4)
            .map(|k| {
                let c = arc_mm + 0.5 * f64::from(k);
                let (a, b) = (self.point_at(c - 0.25), self.point_at(c + 0.25));
                let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                let cross = tangent[0] * dy - tangent[1] * dx;
                let dot = tangent[0] * dx + tangent[1] * dy;
                if dx == 0.0 && dy == 0.0 {
                    0.0
                } else {
                    cross.atan2(dot).abs()
                }
            })
            .fold(0.0, f64::max);
        Closest {
            point,
            distance_mm,
            tangent,
            arc_mm,
            to_end_mm,
            roughness_rad,
        }
    }
}

/// What a trace with fewer than two points lacks.
const TOO_FEW_POINTS: &str = "a trace needs at least 2 points";

/// Reads a trace file (`rigctl trace` output, FORMATS.md: CSV `x,y` in sheet mm, a header row,
/// `#` comment lines; at least 2 points).
pub fn read_trace_csv(path: &Path) -> Result<Vec<[f64; 2]>, FusionError> {
    let table_err = |e| FusionError::from_table(e, path, TOO_FEW_POINTS);
    let table = Table::read(path).map_err(table_err)?;
    let (ix, iy) = (
        table.need("x").map_err(table_err)?,
        table.need("y").map_err(table_err)?,
    );
    let pts = table
        .rows
        .iter()
        .map(|row| table.numbers(row, [ix, iy]))
        .collect::<Result<Vec<_>, _>>()
        .map_err(table_err)?;
    if pts.len() < 2 {
        return Err(FusionError::csv(
            path,
            table.header_line,
            "rows",
            TOO_FEW_POINTS,
        ));
    }
    Ok(pts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::{Classify, ErrorKind};

    #[test]
    fn trace_file_rows_and_errors() {
        let dir = tempfile::tempdir().unwrap();
        let write = |name: &str, text: &str| {
            let p = dir.path().join(name);
            std::fs::write(&p, text).unwrap();
            p
        };
        let p = write("ok.csv", "# trace\ny,x\n1,2\n\n3.5,-4\n");
        assert_eq!(read_trace_csv(&p).unwrap(), [[2.0, 1.0], [-4.0, 3.5]]);
        let cases = [
            ("nan.csv", "x,y\n1,2\n3,nan\n", ":3: y: NaN (`nan`)"),
            ("noy.csv", "# c\nx,z\n1,2\n3,4\n", ":2: y: column missing"),
            (
                "short.csv",
                "x,y\n1,2\n3\n",
                ":3: row: 1 fields, the header has 2",
            ),
            (
                "one.csv",
                "x,y\n1,2\n",
                ":1: rows: a trace needs at least 2 points",
            ),
            (
                "none.csv",
                "x,y\n",
                ":1: rows: a trace needs at least 2 points",
            ),
            ("empty.csv", "# c\n", ":1: header: no header row"),
        ];
        for (name, text, want) in cases {
            let e = read_trace_csv(&write(name, text)).unwrap_err();
            assert_eq!(e.kind(), ErrorKind::BadInput);
            let msg = e.to_string();
            assert!(
                msg.contains(&format!("{name}{want}")),
                "`{msg}` vs `{want}`"
            );
        }
        let e = read_trace_csv(&dir.path().join("absent.csv")).unwrap_err();
        assert!(e.to_string().contains("absent.csv"), "{e}");
    }

    #[test]
    fn circle_normal_is_radial_and_distance_exact() {
        let pts: Vec<[f64; 2]> = (0..1257)
            .map(|k| {
                let a = k as f64 / 1257.0 * std::f64::consts::TAU;
                [100.0 * a.cos(), 100.0 * a.sin()]
            })
            .collect();
        let c = TracedCurve::new(pts, 1.0).unwrap();
        assert!(c.is_closed());
        for ang in [0.3f64, 2.0, 4.5] {
            let q = [100.7 * ang.cos(), 100.7 * ang.sin()];
            let cl = c.closest(q);
            // chord sagitta of 0.5 mm segments on r = 100: < 0.0004 mm
            assert!((cl.distance_mm - 0.7).abs() < 1e-3, "{cl:?}");
            // tangent at right angles to the radius
            let radial = [ang.cos(), ang.sin()];
            assert!(
                (cl.tangent[0] * radial[0] + cl.tangent[1] * radial[1]).abs() < 1e-4,
                "{cl:?}"
            );
            assert!(cl.to_end_mm.is_infinite());
            // chords 2 mm away turn by 0.02 rad on r = 100 mm
            assert!(cl.roughness_rad < 0.03, "{cl:?}");
        }
    }

    #[test]
    fn open_line_reports_distance_to_the_ends() {
        let pts: Vec<[f64; 2]> = (0..=400).map(|k| [-100.0 + 0.5 * k as f64, 0.0]).collect();
        let c = TracedCurve::new(pts, 1.0).unwrap();
        assert!(!c.is_closed());
        let cl = c.closest([95.0, -0.2]);
        assert!((cl.distance_mm - 0.2).abs() < 1e-12);
        assert!((cl.to_end_mm - 5.0).abs() < 1e-9);
        assert!((cl.tangent[0] - 1.0).abs() < 1e-12);
        assert!(cl.roughness_rad < 1e-12);
        // a 0.3 mm step across the line (over one 0.5 mm segment) shows as roughness
        let mut pts: Vec<[f64; 2]> = (0..=400).map(|k| [-100.0 + 0.5 * k as f64, 0.0]).collect();
        for p in pts.iter_mut().skip(201) {
            p[1] += 0.3;
        }
        let c = TracedCurve::new(pts, 1.0).unwrap();
        let r = c.closest([1.0, 0.3]).roughness_rad;
        assert!(r > 0.2, "{r}"); // 2.5x the fusion's threshold of 0.1 rad
        assert!(c.closest([5.0, 0.3]).roughness_rad < 1e-9);
    }
}
