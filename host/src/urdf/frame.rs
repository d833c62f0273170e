//! A rigid transform in metres, `p -> r p + t`: the joint origins of a URDF, composed when a
//! chain is imported ([`super::import`]) and split again when a model is exported
//! ([`super::export`]).

use nalgebra::{Matrix3, Vector3};

use super::export::Origin;
use super::import::rpy_matrix;

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
