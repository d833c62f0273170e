//! The ISO 9283 test cube and the 118 calibration positions of thesis section 4.4.2.
//!
//! # Reading of the thesis
//! Section 4.4.2 (and 3.4) says only: "118 poses ... are chosen on the diagonal planes within the
//! largest cube of the robot's workspace, and some of the poses are selected close to workspace
//! boundary", sequenced "such that all five joints angles have to be changed when moving from one
//! pose to another". Fig. 4.8 (not in the text) shows them. ISO 9283:1998 §6.2 defines the cube
//! (corners C1..C8), four diagonal planes through pairs of opposite edges, and on the chosen plane
//! the points P1 (the cube centre) and P2..P5 on the plane's diagonals at 10 % of the diagonal's
//! length from its corners. Section 5.4/5.5.1 names the "frontal cube" whose 45-degree diagonal
//! plane carries the circle through [0 -370.7107 210], [-100 -300 139.2893],
//! [0 -229.2893 68.5786], [100 -300 139.2893]: that circle (radius 100) is inscribed in the
//! diagonal rectangle of the cube with centre (0, -300, 139.2893) and edge 200 mm, edges parallel
//! to the base axes. That is the cube used here ([`Cube::thesis_frontal`]).
//!
//! Construction (the thesis gives no grid, so this is this project's documented choice):
//! - the four diagonal planes that hold a pair of opposite *horizontal* edges (they are the
//!   45-degree planes; the thesis's circle lies on one of them): two planes hold edges parallel
//!   to x, two hold edges parallel to y;
//! - on each plane a grid of 7 points along the edge direction by 5 points along the slanted
//!   direction, both spanning 10 %..90 % of the plane's rectangle. The grid therefore contains
//!   the ISO points P1 (centre) and P2..P5 (10 % of the diagonal from each corner) of every plane;
//! - positions shared by two planes (the centre lines and the body diagonals) are kept once:
//!   117 distinct positions;
//! - as in the ISO 9283 cycle (P1 .. P5, back to P1) the sequence starts and ends at P1, giving
//!   118 poses.
//!
//! Positions are in frame R (mm). Which frame the thesis's circle coordinates are in is not
//! stated unambiguously (eq. 5.6 converts measurements to the nominal base). Read as frame R,
//! all 117 positions are reachable within the joint limits of table 3.1 with d5 = 200 mm (with
//! the orientation rule of [`super::plan`]); read as frame 0 (shifted by [55 55 201.5] into R),
//! only 110 are. So they are taken as frame R.

use nalgebra::Vector3;

/// Fraction of the plane's extent left free at each side (ISO 9283: 10 % of the diagonal).
pub const ISO_INSET: f64 = 0.1;
/// Grid points along the horizontal edge of each diagonal plane.
pub const GRID_ALONG_EDGE: usize = 7;
/// Grid points along the slanted direction of each diagonal plane.
pub const GRID_ALONG_SLANT: usize = 5;
/// Number of poses of the calibration set (thesis section 4.4.2).
pub const ISO_POSE_COUNT: usize = 118;

/// A cube with edges parallel to the axes of frame R.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cube {
    /// Centre (ISO P1), mm in frame R.
    pub centre_mm: Vector3<f64>,
    /// Edge length, mm.
    pub side_mm: f64,
}

impl Cube {
    /// The "frontal cube" of thesis section 5.4: centre (0, -300, 139.2893) mm in frame R
    /// (module docs), edge 200 mm.
    pub fn thesis_frontal() -> Self {
        Self {
            centre_mm: Vector3::new(0.0, -300.0, 139.289_3),
            side_mm: 200.0,
        }
    }

    /// Corner at fractional coordinates `f` (each 0..1) of the cube.
    pub fn at(&self, f: Vector3<f64>) -> Vector3<f64> {
        self.centre_mm + (f - Vector3::repeat(0.5)) * self.side_mm
    }

    /// The four 45-degree diagonal planes (see the module documentation).
    pub fn diagonal_planes(&self) -> [DiagonalPlane; 4] {
        let s = self.side_mm;
        let (x, y, z) = (Vector3::x(), Vector3::y(), Vector3::z());
        // Each plane: a corner, the edge vector, the slanted vector (0..1 fractions of each).
        [
            // edge along x, rising with y: from (y=0,z=0) to (y=1,z=1)
            DiagonalPlane::new(self.at(Vector3::new(0.0, 0.0, 0.0)), x * s, (y + z) * s),
            // edge along x, falling with y: from (y=0,z=1) to (y=1,z=0)
            DiagonalPlane::new(self.at(Vector3::new(0.0, 0.0, 1.0)), x * s, (y - z) * s),
            // edge along y, rising with x
            DiagonalPlane::new(self.at(Vector3::new(0.0, 0.0, 0.0)), y * s, (x + z) * s),
            // edge along y, falling with x
            DiagonalPlane::new(self.at(Vector3::new(0.0, 0.0, 1.0)), y * s, (x - z) * s),
        ]
    }
}

/// A diagonal rectangle of the cube: `corner + a * edge + b * slant`, `a, b` in 0..1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiagonalPlane {
    /// One corner of the rectangle, mm in frame R.
    pub corner_mm: Vector3<f64>,
    /// The horizontal edge (a cube edge), mm.
    pub edge_mm: Vector3<f64>,
    /// The slanted side (a face diagonal), mm.
    pub slant_mm: Vector3<f64>,
}

impl DiagonalPlane {
    fn new(corner_mm: Vector3<f64>, edge_mm: Vector3<f64>, slant_mm: Vector3<f64>) -> Self {
        Self {
            corner_mm,
            edge_mm,
            slant_mm,
        }
    }

    /// The point at fractions `a` (along the edge) and `b` (along the slant).
    pub fn at(&self, a: f64, b: f64) -> Vector3<f64> {
        self.corner_mm + self.edge_mm * a + self.slant_mm * b
    }

    /// Unit normal of the plane, oriented downwards (negative z component).
    pub fn normal_down(&self) -> Vector3<f64> {
        let n = self.edge_mm.cross(&self.slant_mm).normalize();
        if n.z > 0.0 {
            -n
        } else {
            n
        }
    }

    /// ISO 9283 P1..P5 of this plane: the centre, then the points on the diagonals at 10 % of the
    /// diagonal's length from the corners.
    pub fn iso_points(&self) -> [Vector3<f64>; 5] {
        let (lo, hi) = (ISO_INSET, 1.0 - ISO_INSET);
        [
            self.at(0.5, 0.5),
            self.at(hi, hi),
            self.at(hi, lo),
            self.at(lo, lo),
            self.at(lo, hi),
        ]
    }
}

/// A calibration position with the diagonal planes that hold it.
#[derive(Debug, Clone, PartialEq)]
pub struct IsoPosition {
    /// Name: `P1` for the cube centre, else `D<plane>_<i>_<j>` (plane 1..4, grid indices).
    pub id: String,
    /// Position, mm in frame R.
    pub position_mm: Vector3<f64>,
    /// Index (0..4) of the first diagonal plane that holds the position.
    pub plane: usize,
}

fn grid_fraction(i: usize, n: usize) -> f64 {
    ISO_INSET + (1.0 - 2.0 * ISO_INSET) * i as f64 / (n - 1) as f64
}

/// The 117 distinct positions on the four diagonal planes (module documentation), P1 first,
/// then plane by plane, edge index then slant index. Duplicates (within 1e-6 mm) keep the
/// first occurrence.
pub fn distinct_positions(cube: &Cube) -> Vec<IsoPosition> {
    let planes = cube.diagonal_planes();
    let mut out = vec![IsoPosition {
        id: "P1".into(),
        position_mm: cube.centre_mm,
        plane: 0,
    }];
    for (k, plane) in planes.iter().enumerate() {
        for i in 0..GRID_ALONG_EDGE {
            for j in 0..GRID_ALONG_SLANT {
                let p = plane.at(
                    grid_fraction(i, GRID_ALONG_EDGE),
                    grid_fraction(j, GRID_ALONG_SLANT),
                );
                if out.iter().all(|o| (o.position_mm - p).norm() > 1e-6) {
                    out.push(IsoPosition {
                        id: format!("D{}_{}_{}", k + 1, i + 1, j + 1),
                        position_mm: p,
                        plane: k,
                    });
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Cube {
        Cube::thesis_frontal()
    }

    #[test]
    fn thesis_circle_lies_on_the_first_diagonal_plane() {
        // The four circle points of thesis section 5.5.1, frame 0.
        let pts = [
            [0.0, -370.7107, 210.0],
            [-100.0, -300.0, 139.2893],
            [0.0, -229.2893, 68.5786],
            [100.0, -300.0, 139.2893],
        ];
        let plane = cube().diagonal_planes()[1];
        let n = plane.normal_down();
        for p in pts {
            let d = (Vector3::from(p) - plane.corner_mm).dot(&n);
            assert!(d.abs() < 1e-3, "point {p:?} is {d} mm off the plane");
            // and 100 mm from the cube centre
            let r = (Vector3::from(p) - cube().centre_mm).norm();
            assert!((r - 100.0).abs() < 1e-3, "radius {r}");
        }
    }

    #[test]
    fn planes_are_at_45_degrees_and_through_the_centre() {
        let c = cube();
        for plane in c.diagonal_planes() {
            let n = plane.normal_down();
            assert!((n.z + 0.5f64.sqrt()).abs() < 1e-12, "normal {n}");
            assert!((c.centre_mm - plane.corner_mm).dot(&n).abs() < 1e-9);
            assert!((plane.at(0.5, 0.5) - c.centre_mm).norm() < 1e-9);
        }
    }

    #[test]
    fn iso_points_are_ten_percent_of_the_diagonal_from_the_corners() {
        let plane = cube().diagonal_planes()[0];
        let diag = (plane.at(1.0, 1.0) - plane.at(0.0, 0.0)).norm();
        let p = plane.iso_points();
        // side 200: diagonal of the 200 x 282.84 rectangle = 200*sqrt(3)
        assert!((diag - 200.0 * 3f64.sqrt()).abs() < 1e-9);
        assert!(((p[3] - plane.at(0.0, 0.0)).norm() - 0.1 * diag).abs() < 1e-9);
        assert!(((p[1] - plane.at(1.0, 1.0)).norm() - 0.1 * diag).abs() < 1e-9);
    }

    #[test]
    fn there_are_117_distinct_positions_inside_the_cube() {
        let c = cube();
        let pos = distinct_positions(&c);
        assert_eq!(pos.len(), ISO_POSE_COUNT - 1);
        for (i, a) in pos.iter().enumerate() {
            let f = (a.position_mm - c.centre_mm) / c.side_mm;
            assert!(
                f.amax() <= 0.5 - 0.1 * 0.999,
                "{} outside the inset cube",
                a.id
            );
            for b in &pos[i + 1..] {
                assert!((a.position_mm - b.position_mm).norm() > 1.0);
            }
        }
        // every plane's ISO points are in the set
        for plane in c.diagonal_planes() {
            for p in plane.iso_points() {
                assert!(pos.iter().any(|a| (a.position_mm - p).norm() < 1e-9));
            }
        }
    }
}
