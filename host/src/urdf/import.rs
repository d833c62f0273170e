//! A URDF serial chain as a [`Model`].
//!
//! # The chain
//! From the base link (default: the root link) to the tip link, the model is
//!
//! `[base_x base_y base_z base_rx base_ry] . Rz(base_rz) . for every movable joint J:
//!  Tx(J_x) Ty(J_y) Tz(J_z) Rz(J_rz) Ry(J_ry) Rx(J_rx) [Rz(J_axis_rz) Ry(J_axis_ry)]
//!  Rz|Tz(q + J_offset) . [Tx(tip_x) Ty(tip_y) Tz(tip_z) Rz(tip_rz) Ry(tip_ry) Rx(tip_rx)]
//!  . [tool_dx tool_dy tool_dz]`
//!
//! * `J` is the joint's URDF name with every character other than ASCII letters, digits and `_`
//!   replaced by `_` (e.g. `arm_1_joint_x`, `arm_1_joint_offset`).
//! * `J_x.._rx` is the joint's `<origin>` (URDF `xyz` in mm, `rpy` in deg: URDF rpy are
//!   fixed-axis roll-pitch-yaw, `R = Rz(y) Ry(p) Rx(r)`, hence the order `Rz Ry Rx`), composed
//!   with every fixed joint before it and with the axis alignment of the previous movable
//!   joint; when nothing is folded in, the values are the file's own numbers.
//! * A joint axis other than `+z` gets constant rotations `Rz(phi) Ry(theta)` that turn `z` onto
//!   it (`theta = acos(a_z)`, `phi = atan2(a_y, a_x)`, only the non-zero ones are emitted); the
//!   inverse rotation is folded into the next constants, so the URDF child frame is reproduced
//!   exactly.
//! * `revolute` and `continuous` joints become `Rz(q + J_offset)` (q in deg, limits in deg,
//!   `continuous` gets -360..360), `prismatic` ones `Tz(q + J_offset)` (q and limits in mm);
//!   `fixed` joints fold into constants; `floating` and `planar` joints are refused; a `mimic`
//!   joint is imported as an independent joint.
//! * `base_rz` (deg, 0) completes the model's base (`base_rx base_ry` + `base_rz`: any
//!   orientation of the base link in frame R).
//! * `tip_*` is the fixed transform from the last movable joint's frame to the tip link (fixed
//!   joints after it, and the last axis alignment); it is emitted only when not the identity, so
//!   `tool_d*` is always a point in the tip link's frame.

use nalgebra::{Matrix3, Rotation3, Vector3};

use super::error::UrdfError;
use super::parse::{JointType, Urdf, UrdfJoint};
use crate::model::{Axis, Model, ModelBuilder, ModelError, Motion};

/// What to import.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImportOptions<'a> {
    /// First link of the chain (frame of the base); `None` = the root link.
    pub base_link: Option<&'a str>,
    /// Last link of the chain (the tool point is expressed in its frame).
    pub tip_link: &'a str,
    /// Tool point in the tip link's frame (mm).
    pub tool_mm: [f64; 3],
}

/// An imported chain: the model and the URDF names of its joints, in model joint order.
#[derive(Debug, Clone)]
pub struct Imported {
    /// The model (joints in deg, mm for prismatic joints).
    pub model: Model,
    /// URDF joint names, one per model joint.
    pub joint_names: Vec<String>,
}

/// The parameter-name stem of a URDF joint: non `[A-Za-z0-9_]` characters become `_`.
pub fn param_stem(joint_name: &str) -> String {
    joint_name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// A rigid transform in metres: `p -> r p + t`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Frame {
    r: Matrix3<f64>,
    t: Vector3<f64>,
}

impl Frame {
    fn identity() -> Self {
        Self {
            r: Matrix3::identity(),
            t: Vector3::zeros(),
        }
    }

    fn is_identity(&self) -> bool {
        self.r == Matrix3::identity() && self.t == Vector3::zeros()
    }

    fn then(&self, next: &Frame) -> Frame {
        Frame {
            r: self.r * next.r,
            t: self.r * next.t + self.t,
        }
    }

    fn origin(xyz_m: [f64; 3], rpy_rad: [f64; 3]) -> Self {
        Self {
            r: rpy_matrix(rpy_rad),
            t: Vector3::from(xyz_m),
        }
    }
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

struct Emitter<'u> {
    urdf: &'u Urdf,
    builder: ModelBuilder,
}

impl Emitter<'_> {
    fn model_err(&self, source: ModelError) -> UrdfError {
        UrdfError::Model {
            source_name: self.urdf.source_name.clone(),
            source,
        }
    }

    fn constant(
        &mut self,
        motion: Motion,
        axis: Axis,
        name: &str,
        v: f64,
    ) -> Result<(), UrdfError> {
        self.builder
            .constant(motion, axis, name, v)
            .map(|_| ())
            .map_err(|e| self.model_err(e))
    }

    /// `Tx Ty Tz Rz Ry Rx` of `xyz` (m) and `rpy` (rad), named `<stem>_x .. <stem>_rx`.
    fn six(&mut self, stem: &str, xyz_m: [f64; 3], rpy_rad: [f64; 3]) -> Result<(), UrdfError> {
        use Axis::{X, Y, Z};
        use Motion::{Rot, Trans};
        for (axis, k, suffix) in [(X, 0, "x"), (Y, 1, "y"), (Z, 2, "z")] {
            self.constant(Trans, axis, &format!("{stem}_{suffix}"), xyz_m[k] * 1e3)?;
        }
        for (axis, k, suffix) in [(Z, 2, "rz"), (Y, 1, "ry"), (X, 0, "rx")] {
            self.constant(
                Rot,
                axis,
                &format!("{stem}_{suffix}"),
                rpy_rad[k].to_degrees(),
            )?;
        }
        Ok(())
    }

    /// The origin constants of a movable joint, with `pending` (fixed joints, previous axis
    /// alignment) folded in.
    fn origin(&mut self, stem: &str, pending: &Frame, j: &UrdfJoint) -> Result<(), UrdfError> {
        if pending.is_identity() {
            return self.six(stem, j.origin_xyz_m, j.origin_rpy_rad);
        }
        let f = pending.then(&Frame::origin(j.origin_xyz_m, j.origin_rpy_rad));
        self.six(stem, f.t.into(), rpy_of(&f.r))
    }

    /// The constants turning `z` onto the joint axis; returns the alignment rotation.
    fn align(&mut self, stem: &str, j: &UrdfJoint) -> Result<Matrix3<f64>, UrdfError> {
        let a = Vector3::from(j.axis);
        let norm = a.norm();
        if norm.is_nan() || norm <= 1e-9 {
            return Err(UrdfError::Element {
                source_name: self.urdf.source_name.clone(),
                line: j.line,
                column: 1,
                message: format!("joint `{}`: axis {:?} has no direction", j.name, j.axis),
            });
        }
        let a = a / norm;
        let theta = a.z.clamp(-1.0, 1.0).acos();
        let phi = if a.x.hypot(a.y) < 1e-15 {
            0.0
        } else {
            a.y.atan2(a.x)
        };
        if phi != 0.0 {
            self.constant(
                Motion::Rot,
                Axis::Z,
                &format!("{stem}_axis_rz"),
                phi.to_degrees(),
            )?;
        }
        if theta != 0.0 {
            self.constant(
                Motion::Rot,
                Axis::Y,
                &format!("{stem}_axis_ry"),
                theta.to_degrees(),
            )?;
        }
        Ok(*(Rotation3::from_axis_angle(&Vector3::z_axis(), phi)
            * Rotation3::from_axis_angle(&Vector3::y_axis(), theta))
        .matrix())
    }

    fn joint(&mut self, stem: &str, j: &UrdfJoint) -> Result<(), UrdfError> {
        let missing_limit = || UrdfError::Element {
            source_name: self.urdf.source_name.clone(),
            line: j.line,
            column: 1,
            message: format!(
                "{} joint `{}` needs a <limit lower upper>",
                j.joint_type.as_str(),
                j.name
            ),
        };
        let (prismatic, limits) = match j.joint_type {
            JointType::Revolute => {
                let [lo, hi] = j.limits.ok_or_else(missing_limit)?;
                (false, [lo.to_degrees(), hi.to_degrees()])
            }
            JointType::Continuous => (false, [-360.0, 360.0]),
            JointType::Prismatic => {
                let [lo, hi] = j.limits.ok_or_else(missing_limit)?;
                (true, [lo * 1e3, hi * 1e3])
            }
            other => {
                return Err(UrdfError::Unsupported {
                    source_name: self.urdf.source_name.clone(),
                    joint: j.name.clone(),
                    kind: other.as_str().to_string(),
                })
            }
        };
        self.builder
            .joint(prismatic, &format!("{stem}_offset"), 0.0, limits, None)
            .map(|_| ())
            .map_err(|e| self.model_err(e))
    }
}

/// Imports the chain `opts.base_link` .. `opts.tip_link` of `urdf` (see the module doc for the
/// structure and the parameter names).
pub fn import_chain(urdf: &Urdf, opts: &ImportOptions) -> Result<Imported, UrdfError> {
    let chain = urdf.chain(opts.base_link, opts.tip_link)?;
    let base = match opts.base_link {
        Some(b) => b.to_string(),
        None => urdf.root_link()?.to_string(),
    };
    if chain.iter().all(|j| j.joint_type == JointType::Fixed) {
        return Err(UrdfError::NoJoint {
            source_name: urdf.source_name.clone(),
            base,
            tip: opts.tip_link.to_string(),
        });
    }
    let mut em = Emitter {
        urdf,
        builder: ModelBuilder::new(&param_stem(&urdf.robot_name)),
    };
    em.constant(Motion::Rot, Axis::Z, "base_rz", 0.0)?;
    let mut pending = Frame::identity();
    let mut joint_names = Vec::new();
    for j in chain {
        if j.joint_type == JointType::Fixed {
            pending = pending.then(&Frame::origin(j.origin_xyz_m, j.origin_rpy_rad));
            continue;
        }
        let stem = param_stem(&j.name);
        em.origin(&stem, &pending, j)?;
        let align = em.align(&stem, j)?;
        em.joint(&stem, j)?;
        joint_names.push(j.name.clone());
        pending = Frame {
            r: align.transpose(),
            t: Vector3::zeros(),
        };
    }
    if !pending.is_identity() {
        em.six("tip", pending.t.into(), rpy_of(&pending.r))?;
    }
    let mut model = em.builder.build().map_err(|e| UrdfError::Model {
        source_name: urdf.source_name.clone(),
        source: e,
    })?;
    for (name, v) in ["tool_dx", "tool_dy", "tool_dz"].iter().zip(opts.tool_mm) {
        model.set_param(name, v).map_err(|e| UrdfError::Model {
            source_name: urdf.source_name.clone(),
            source: e,
        })?;
    }
    Ok(Imported { model, joint_names })
}
