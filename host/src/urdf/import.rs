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

use super::frame::Frame;
pub use super::frame::{rpy_matrix, rpy_of};
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

/// An imported chain: the model (carrying the joint names, [`Model::joint_names`]) and the URDF
/// names of its joints, in model joint order.
#[derive(Debug, Clone)]
pub struct Imported {
    /// The model (joints in deg, mm for prismatic joints).
    pub model: Model,
    /// URDF joint names, one per model joint.
    pub joint_names: Vec<String>,
}

/// Widens every joint's limits by `fraction` of its range at both ends (readings of a real
/// robot may pass its URDF limits slightly: TIAGo's torso reads 350.18 mm against 350).
/// Negative or non-finite fractions change nothing.
pub fn widen_limits(model: &mut Model, fraction: f64) {
    if !(fraction.is_finite() && fraction > 0.0) {
        return;
    }
    for j in &mut model.joints {
        let margin = fraction * (j.limits[1] - j.limits[0]).abs();
        j.limits = [j.limits[0] - margin, j.limits[1] + margin];
    }
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
        let f = pending.then(&Frame::at(j.origin_xyz_m, j.origin_rpy_rad));
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
    import(urdf, opts, false, &[])
}

/// As [`import_chain`], and every movable joint of the chain carries, as one point mass in its
/// joint frame, the `<inertial>` masses of the links it moves rigidly: its child link and every
/// link below it up to the next movable joint of the chain (joints off the chain, e.g. gripper
/// fingers, count at zero; links below the tip count with the last joint). Links before the
/// first movable joint are not carried. Used for gravity torques
/// ([`crate::model::gravity::GravityModel::for_model`]).
pub fn import_chain_with_masses(urdf: &Urdf, opts: &ImportOptions) -> Result<Imported, UrdfError> {
    import(urdf, opts, true, &[])
}

/// As [`import_chain_with_masses`], and a rigid body also stops at the joints `stop` (a tree's
/// other movable joints: each carries its own links).
pub(super) fn import_chain_stopping_at(
    urdf: &Urdf,
    opts: &ImportOptions,
    stop: &[&str],
) -> Result<Imported, UrdfError> {
    import(urdf, opts, true, stop)
}

/// The URDF's links by name for [`rigid_mass`]: inertials and child joints of every link, and
/// the joints a rigid body stops at (linear in the size of the file, not quadratic).
struct Tree<'a> {
    inertials: std::collections::HashMap<&'a str, Vec<usize>>,
    children: std::collections::HashMap<&'a str, Vec<usize>>,
    stop: std::collections::HashSet<&'a str>,
}

impl<'a> Tree<'a> {
    fn new(urdf: &'a Urdf, stop: &[&'a str]) -> Self {
        let mut inertials: std::collections::HashMap<&str, Vec<usize>> = Default::default();
        for (k, i) in urdf.inertials.iter().enumerate() {
            inertials.entry(i.link.as_str()).or_default().push(k);
        }
        let mut children: std::collections::HashMap<&str, Vec<usize>> = Default::default();
        for (k, j) in urdf.joints.iter().enumerate() {
            children.entry(j.parent.as_str()).or_default().push(k);
        }
        Self {
            inertials,
            children,
            stop: stop.iter().copied().collect(),
        }
    }
}

/// Mass (kg) and centre of mass (m, in `link`'s frame) of the links moved rigidly with `link`:
/// its subtree, not crossing the joints in `stop` (joints off the chain at zero).
fn rigid_mass(tree: &Tree, urdf: &Urdf, link: &str) -> (f64, Vector3<f64>) {
    let mut mass_kg = 0.0;
    let mut moment = Vector3::zeros();
    let mut stack = vec![(link.to_string(), Frame::identity())];
    let mut visited = 0;
    while let Some((l, f)) = stack.pop() {
        visited += 1;
        if visited > urdf.links.len() {
            break; // a cycle; `chain` reports it for the chain itself
        }
        for &k in tree.inertials.get(l.as_str()).into_iter().flatten() {
            let i = &urdf.inertials[k];
            mass_kg += i.mass_kg;
            moment += i.mass_kg * (f.r * Vector3::from(i.com_xyz_m) + f.t);
        }
        for j in tree
            .children
            .get(l.as_str())
            .into_iter()
            .flatten()
            .map(|&k| &urdf.joints[k])
            .filter(|j| !tree.stop.contains(j.name.as_str()))
        {
            stack.push((
                j.child.clone(),
                f.then(&Frame::at(j.origin_xyz_m, j.origin_rpy_rad)),
            ));
        }
    }
    let com = if mass_kg > 0.0 {
        moment / mass_kg
    } else {
        Vector3::zeros()
    };
    (mass_kg, com)
}

fn import(
    urdf: &Urdf,
    opts: &ImportOptions,
    masses: bool,
    extra_stop: &[&str],
) -> Result<Imported, UrdfError> {
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
    let movable: Vec<&str> = chain
        .iter()
        .filter(|j| j.joint_type != JointType::Fixed)
        .map(|j| j.name.as_str())
        .chain(extra_stop.iter().copied())
        .collect();
    let tree = Tree::new(urdf, &movable);
    for j in &chain {
        if j.joint_type == JointType::Fixed {
            pending = pending.then(&Frame::at(j.origin_xyz_m, j.origin_rpy_rad));
            continue;
        }
        let stem = param_stem(&j.name);
        em.origin(&stem, &pending, j)?;
        let align = em.align(&stem, j)?;
        em.joint(&stem, j)?;
        joint_names.push(j.name.clone());
        if masses {
            let (mass_kg, com_m) = rigid_mass(&tree, urdf, &j.child);
            // The URDF child frame is the joint frame turned by `align^T`.
            let com_mm: [f64; 3] = (align.transpose() * com_m * 1e3).into();
            em.builder
                .mass(joint_names.len(), 0, mass_kg, com_mm)
                .map_err(|source| UrdfError::Model {
                    source_name: urdf.source_name.clone(),
                    source,
                })?;
        }
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
    model
        .set_joint_names(joint_names.clone())
        .map_err(|e| UrdfError::Model {
            source_name: urdf.source_name.clone(),
            source: e,
        })?;
    // every value of the file within its physical range (a link mass of 1e308 kg is refused)
    model.check_ranges().map_err(|message| UrdfError::Model {
        source_name: urdf.source_name.clone(),
        source: ModelError::Invalid(message),
    })?;
    Ok(Imported { model, joint_names })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Joint 1 (z) carries link1 (2 kg at x = 0.5 m) and, through a fixed joint at x = 1 m
    /// turned 90 deg about z, link1b (1 kg at its own x = 0.1 m, i.e. link1's y = 0.1 m):
    /// 3 kg at (2/3, 0.1/3, 0) m. Joint 2 (axis x, so an aligned joint frame) carries link2
    /// (1 kg at its own z = 0.2 m), at (1, 0, 0.2) m in the world at q = 0.
    const XML: &str = r#"<robot name="m">
      <link name="base"/>
      <link name="link1"><inertial><mass value="2"/><origin xyz="0.5 0 0"/></inertial></link>
      <link name="link1b"><inertial><mass value="1"/><origin xyz="0.1 0 0"/></inertial></link>
      <link name="link2"><inertial><mass value="1"/><origin xyz="0 0 0.2"/></inertial></link>
      <joint name="j1" type="revolute"><parent link="base"/><child link="link1"/>
        <axis xyz="0 0 1"/><limit lower="-3" upper="3"/></joint>
      <joint name="f" type="fixed"><parent link="link1"/><child link="link1b"/>
        <origin xyz="1 0 0" rpy="0 0 1.5707963267948966"/></joint>
      <joint name="j2" type="revolute"><parent link="link1b"/><child link="link2"/>
        <axis xyz="1 0 0"/><limit lower="-3" upper="3"/></joint>
    </robot>"#;

    #[test]
    fn link_masses_are_carried_by_their_joints() {
        let urdf = Urdf::parse(XML, "m.urdf").unwrap();
        assert_eq!(urdf.inertials.len(), 3);
        let opts = ImportOptions {
            base_link: None,
            tip_link: "link2",
            tool_mm: [0.0; 3],
        };
        let model = import_chain_with_masses(&urdf, &opts).unwrap().model;
        assert!(import_chain(&urdf, &opts)
            .unwrap()
            .model
            .masses()
            .is_empty());
        let masses = model.masses();
        assert_eq!(masses.len(), 2);
        assert!((masses[0].mass_kg - 3.0).abs() < 1e-12);
        assert!((masses[1].mass_kg - 1.0).abs() < 1e-12);
        let fr = model.frames(&[0.0, 0.0], None).unwrap();
        let world = |k: usize| {
            let f = model.mass_frame(&masses[k]);
            fr.rot[f] * masses[k].com_mm + fr.pos_mm[f]
        };
        let expected = [
            Vector3::new(2000.0 / 3.0, 100.0 / 3.0, 0.0),
            Vector3::new(1000.0, 0.0, 200.0),
        ];
        for (k, e) in expected.iter().enumerate() {
            assert!((world(k) - e).norm() < 1e-9, "{k}: {}", world(k));
        }
    }
}
