//! A rigid transform in metres, `p -> r p + t`: the joint origins of a URDF, composed when a
//! chain is imported ([`super::import`]) and split again when a model is exported
//! ([`super::export`]); a joint [`Origin`] in URDF units, and the URDF `rpy` angles to and from
//! a rotation matrix ([`rpy_matrix`], [`rpy_of`]). Imports nothing of its siblings.

use nalgebra::{Matrix3, Rotation3, Vector3};

/// A joint origin in URDF units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Origin {
    /// `xyz`, m.
    pub xyz_m: [f64; 3],
    /// `rpy`, rad (`R = Rz(y) Ry(p) Rx(r)`).
    pub rpy_rad: [f64; 3],
}

/// `Rz(y) Ry(p) Rx(r)` of URDF `rpy = [r, p, y]` (rad).
pub fn rpy_matrix(rpy_rad: [f64; 3]) -> Matrix3<f64> {
    let [r, p, y] = rpy_rad;
    *(Rotation3::from_axis_angle(&Vector3::z_axis(), y)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), p)
        * Rotation3::from_axis_angle(&Vector3::x_axis(), r))
    .matrix()
}

/// URDF `rpy` (rad) of a rotation matrix: `R = Rz(y) Ry(p) Rx(r)`, `p` in `[-pi/2, pi/2]`; at
/// gimbal lock (`cos p < 1e-12`) `r = 0`. Near gimbal lock the angles are exact to about
/// `1e-16 / cos p` rad each, and the recomposed matrix to a few 1e-12.
pub fn rpy_of(m: &Matrix3<f64>) -> [f64; 3] {
    let cp = m[(0, 0)].hypot(m[(1, 0)]);
    let p = (-m[(2, 0)]).atan2(cp);
    if cp < 1e-12 {
        // R = Rz(y) Ry(+-pi/2): the first two rows of column 1 are (-sin y, cos y).
        [0.0, p, (-m[(0, 1)]).atan2(m[(1, 1)])]
    } else {
        [m[(2, 1)].atan2(m[(2, 2)]), p, m[(1, 0)].atan2(m[(0, 0)])]
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Frame {
    pub(super) r: Matrix3<f64>,
    pub(super) t: Vector3<f64>,
}

impl Frame {
    pub(super) fn identity() -> Self {
        Self {
            r: Matrix3::identity(),
            t: Vector3::zeros(),
        }
    }

    pub(super) fn is_identity(&self) -> bool {
        self.r == Matrix3::identity() && self.t == Vector3::zeros()
    }

    /// `self` followed by `next` (`next` expressed in `self`'s frame).
    pub(super) fn then(&self, next: &Frame) -> Frame {
        Frame {
            r: self.r * next.r,
            t: self.r * next.t + self.t,
        }
    }

    pub(super) fn inverse(&self) -> Frame {
        let rt = self.r.transpose();
        Frame {
            r: rt,
            t: -(rt * self.t),
        }
    }

    /// The frame of a URDF origin (`xyz` m, `rpy` rad).
    pub(super) fn at(xyz_m: [f64; 3], rpy_rad: [f64; 3]) -> Self {
        Self {
            r: rpy_matrix(rpy_rad),
            t: Vector3::from(xyz_m),
        }
    }

    /// The frame of an [`Origin`].
    pub(super) fn of_origin(o: &Origin) -> Self {
        Self::at(o.xyz_m, o.rpy_rad)
    }
}
