//! Forward kinematics: frames of the chain, tool pose, static joint moments, tilting, ZXZ Euler
//! angles. Lengths in mm, angles in degrees at the interface; radians inside.

use nalgebra::{Matrix3, Vector3};

use super::chain::{Model, Motion, TiltValues};
use super::data::Data;
use super::error::ModelError;
use super::tilt::tilt_from_moment;
pub use super::tilt::{Tilt, GRAVITY_KGF_PER_KG};

/// World (frame R) placement of every frame of the chain: entry `k` is the frame after
/// element `k` of [`Model::elems`] (base and tool elements included). With tilting, the tilt of
/// joint i is part of the frame after the joint's element (joint frame i).
#[derive(Debug, Clone)]
pub struct Frames {
    /// Rotation of frame k in R.
    pub rot: Vec<Matrix3<f64>>,
    /// Origin of frame k in R (mm).
    pub pos_mm: Vec<Vector3<f64>>,
    /// Per joint: rotation of joint frame i before its tilt (equal to `rot[elem]` untilted).
    pub joint_rot_untilted: Vec<Matrix3<f64>>,
}

impl Frames {
    /// Rotation and origin of the frame before element `e` (identity / origin for e = 0).
    pub fn before(&self, e: usize) -> (Matrix3<f64>, Vector3<f64>) {
        if e == 0 {
            (Matrix3::identity(), Vector3::zeros())
        } else {
            (self.rot[e - 1], self.pos_mm[e - 1])
        }
    }

    /// Origin of the last frame (the tool point, before the measurement scale).
    pub fn tool_mm(&self) -> Vector3<f64> {
        self.pos_mm.last().copied().unwrap_or_else(Vector3::zeros)
    }

    /// Rotation of the last frame.
    pub fn tool_rot(&self) -> Matrix3<f64> {
        self.rot.last().copied().unwrap_or_else(Matrix3::identity)
    }
}

thread_local! {
    /// The workspace the allocating wrappers ([`Model::fk`], [`Model::position_jacobian`], ...)
    /// reuse on this thread (refreshed when the model or its parameter values change).
    static WORKSPACE: std::cell::RefCell<Option<Data>> = const { std::cell::RefCell::new(None) };
}

/// Runs `f` with this thread's reusable workspace for `model` (a fresh one if it is in use).
pub(crate) fn with_workspace<T>(model: &Model, f: impl FnOnce(&mut Data) -> T) -> T {
    WORKSPACE.with(|cell| match cell.try_borrow_mut() {
        Ok(mut slot) => {
            let d = slot.get_or_insert_with(|| Data::new(model));
            f(d)
        }
        Err(_) => f(&mut Data::new(model)),
    })
}

/// Result of forward kinematics for one pose.
#[derive(Debug, Clone)]
pub struct Fk {
    /// Tool point in R (mm), measurement scale included.
    pub position_mm: Vector3<f64>,
    /// Tool (last frame) rotation in R.
    pub rotation: Matrix3<f64>,
    /// Joint moments used for tilting (kgf.m, joint frame i); empty with `Tilt::Off`.
    pub moments_kgfm: Vec<Vector3<f64>>,
    /// Tilts `(da, db, dt)` per joint (deg); empty with `Tilt::Off`.
    pub tilts_deg: Vec<Vector3<f64>>,
}

impl Fk {
    /// The FK result held by an evaluated workspace.
    pub fn from_data(d: &Data) -> Self {
        Fk {
            position_mm: d.position_mm(),
            rotation: d.rotation(),
            moments_kgfm: d.moments_kgfm().to_vec(),
            tilts_deg: d.tilts_deg().to_vec(),
        }
    }

    /// ZXZ Euler angles `(phi, theta, psi)` of the tool rotation, degrees (thesis eq. 2.3).
    pub fn zxz_deg(&self) -> [f64; 3] {
        zxz_deg(&self.rotation)
    }
}

/// ZXZ Euler angles of thesis eq. 2.3, degrees: `phi = atan2(R13, -R23)`,
/// `theta = atan2(-R23 cos phi + R13 sin phi, R33)`, `psi = atan2(R31, R32)`.
pub fn zxz_deg(r: &Matrix3<f64>) -> [f64; 3] {
    let phi = r[(0, 2)].atan2(-r[(1, 2)]);
    let theta = (-r[(1, 2)] * phi.cos() + r[(0, 2)] * phi.sin()).atan2(r[(2, 2)]);
    let psi = r[(2, 0)].atan2(r[(2, 1)]);
    [phi.to_degrees(), theta.to_degrees(), psi.to_degrees()]
}

/// Rotation matrix about a coordinate axis (0 = x, 1 = y, 2 = z) by `rad`.
pub(crate) fn axis_rotation(axis: usize, rad: f64) -> Matrix3<f64> {
    let (s, c) = rad.sin_cos();
    match axis {
        0 => Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c),
        1 => Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c),
        _ => Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0),
    }
}

/// `Rx(da) . Ry(db) . Rz(dt)` for a tilt in degrees.
pub(crate) fn tilt_rotation(t_deg: &Vector3<f64>) -> Matrix3<f64> {
    axis_rotation(0, t_deg.x.to_radians())
        * axis_rotation(1, t_deg.y.to_radians())
        * axis_rotation(2, t_deg.z.to_radians())
}

impl Model {
    /// [`ModelError::JointCount`] unless `q_deg` has one value per joint.
    pub fn check_joints(&self, q_deg: &[f64]) -> Result<(), ModelError> {
        if q_deg.len() != self.joints.len() {
            return Err(ModelError::JointCount {
                expected: self.joints.len(),
                found: q_deg.len(),
            });
        }
        Ok(())
    }

    /// Effective joint value `q + offset + sum_n (s_n sin(n q) + c_n cos(n q))` (deg or mm) and
    /// its derivative wrt `q`, for joint index `joint` (0-based, `< n_joints()`; panics
    /// otherwise, like slice indexing).
    pub fn joint_value(&self, joint: usize, q: f64) -> (f64, f64) {
        let j = &self.joints[joint];
        let mut v = q + self.params[self.elems[j.elem].param].value;
        let mut dv = 1.0;
        for h in &j.harmonics {
            let n = f64::from(h.order);
            let (s, c) = (n * q).to_radians().sin_cos();
            let (a_s, a_c) = (
                self.params[h.sin_param].value,
                self.params[h.cos_param].value,
            );
            v += a_s * s + a_c * c;
            dv += n * std::f64::consts::PI / 180.0 * (a_s * c - a_c * s);
        }
        (v, dv)
    }

    /// World placement of every frame for joints `q_deg`, with the given tilts (deg, one per
    /// joint) inserted at the joint frames, or none.
    pub fn frames(
        &self,
        q_deg: &[f64],
        tilts_deg: Option<&[Vector3<f64>]>,
    ) -> Result<Frames, ModelError> {
        self.check_joints(q_deg)?;
        if let Some(t) = tilts_deg {
            if t.len() != self.joints.len() {
                return Err(ModelError::TiltCount {
                    expected: self.joints.len(),
                    found: t.len(),
                });
            }
        }
        let n = self.elems.len();
        let mut rot = Vec::with_capacity(n);
        let mut pos_mm = Vec::with_capacity(n);
        let mut joint_rot_untilted = Vec::with_capacity(self.joints.len());
        let mut r = Matrix3::identity();
        let mut p = Vector3::zeros();
        for e in &self.elems {
            let v = match e.joint {
                Some(j) => self.joint_value(j, q_deg[j]).0,
                None => self.params[e.param].value,
            };
            match e.motion {
                Motion::Rot => r *= axis_rotation(e.axis.index(), v.to_radians()),
                Motion::Trans => p += r.column(e.axis.index()) * v,
            }
            if let Some(j) = e.joint {
                joint_rot_untilted.push(r);
                if let Some(t) = tilts_deg {
                    r *= tilt_rotation(&t[j]);
                }
            }
            rot.push(r);
            pos_mm.push(p);
        }
        Ok(Frames {
            rot,
            pos_mm,
            joint_rot_untilted,
        })
    }

    /// Multiplier of the measurement scale, `1 + scale_ppm * 1e-6`.
    pub fn scale_factor(&self) -> f64 {
        1.0 + self.params[self.scale_param].value * 1e-6
    }

    /// Static joint moments (kgf.m, joint frame i) at `q_deg`, computed on the untilted chain
    /// (link masses + payload, gravity -z of R).
    pub fn moments_kgfm(&self, q_deg: &[f64]) -> Result<Vec<Vector3<f64>>, ModelError> {
        with_workspace(self, |d| {
            self.static_moments_with(d, q_deg)?;
            Ok(d.moments_kgfm.clone())
        })
    }

    /// Tilts `(da, db, dt)` (deg) of every joint for moments `moments_kgfm` (one per joint).
    pub fn tilts_deg(
        &self,
        moments_kgfm: &[Vector3<f64>],
    ) -> Result<Vec<Vector3<f64>>, ModelError> {
        let tv = self.require_tilt()?;
        if moments_kgfm.len() != self.joints.len() {
            return Err(ModelError::MomentCount {
                expected: self.joints.len(),
                found: moments_kgfm.len(),
            });
        }
        Ok(moments_kgfm
            .iter()
            .zip(&tv)
            .map(|(eta, tv)| tilt_from_moment(eta, tv, self.gamma_law))
            .collect())
    }

    pub(crate) fn require_tilt(&self) -> Result<Vec<TiltValues>, ModelError> {
        self.tilt_values().ok_or_else(|| ModelError::NoTiltData {
            model: self.name.clone(),
        })
    }

    /// Forward kinematics of one pose: tool point (mm, R, scale included), rotation, and the
    /// moments and tilts used. Allocates a workspace per call; [`Model::fk_with`] reuses one.
    pub fn fk(&self, q_deg: &[f64], tilt: Tilt<'_>) -> Result<Fk, ModelError> {
        with_workspace(self, |d| {
            self.fk_with(d, q_deg, tilt)?;
            Ok(Fk::from_data(d))
        })
    }

    /// Tool point only (mm, R).
    pub fn position_mm(&self, q_deg: &[f64], tilt: Tilt<'_>) -> Result<Vector3<f64>, ModelError> {
        with_workspace(self, |d| {
            self.fk_with(d, q_deg, tilt)?;
            Ok(d.position_mm())
        })
    }
}
