//! A model as a URDF (`rigctl model2urdf`): a chain from link `world` (frame R) to link `tool0`
//! (the model's tool point) whose forward kinematics equals the model's untilted FK.
//!
//! # The chain
//! The model is a product of elementary transforms; joint i is `Rz(q_i + offset_i)` (or `Tz`).
//! A URDF joint is one rigid origin (`xyz`, `rpy`) followed by the motion about (along) its
//! axis. So:
//!
//! * [`model_to_urdf`]: links `world`, `link_1` .. `link_N`, `tool0`. Joint i's origin is the
//!   product of the constant transforms between joint i-1 and joint i (the base elements for
//!   joint 1) and `Rz(offset_i)` (`Tz` for a prismatic joint); its axis is `0 0 1`. The fixed
//!   joint `tool0_joint` holds the constants after the last joint (tool point included). The
//!   measurement scale `scale_ppm` multiplies every constant length (exact for revolute arms).
//! * [`model_into_urdf`](super::model_into_urdf) (a model from `urdf2model` and its original URDF): the original text
//!   is kept byte for byte except the `<origin>` of the chain's movable joints (found by the
//!   model's joint names). Fixed joints between them keep their origins; each movable joint's
//!   origin is what puts its child link where the model puts it (the model's joint frame at
//!   `q = 0` turned back from `z` to the joint's own axis, which is kept). Frame R is the link
//!   `world`: when the chain's base link is the root, a link `world` and a fixed joint
//!   `world_joint` holding the model's base (`base_x .. base_ry`, `base_rz`) are added; when
//!   the root already is `world` with a fixed joint to the base link, that joint's origin is
//!   rewritten; when the base link is `world`, the base goes into the first movable joint's
//!   origin. The link `tool0` and its fixed joint `tool0_joint` hang from the child link of the
//!   last movable joint (an existing `tool0` there has its joint's origin rewritten).
//!
//! Units: m and rad; numbers are written with the shortest text that reads back to the same
//! f64. What a URDF cannot hold is listed in [`Exported::not_representable`]: joint tilting,
//! the transmission terms (scale, coupling, hysteresis, gravity compliance), encoder
//! harmonics, the payload, and with `--urdf` a non-zero `scale_ppm`.

pub use super::frame::Origin;
use super::frame::{rpy_of, Frame};
use nalgebra::{Matrix3, Vector3};

use crate::model::effect::Kind;
use crate::model::{axis_rotation, Model, Motion, ParamKind};

/// One joint origin written (and what it was in the original URDF, if any).
#[derive(Debug, Clone, PartialEq)]
pub struct OriginChange {
    pub joint: String,
    pub before: Option<Origin>,
    pub after: Origin,
}

/// The URDF text and what went into it.
#[derive(Debug, Clone, PartialEq)]
pub struct Exported {
    /// The URDF document.
    pub text: String,
    /// Every joint origin written, in chain order (world joint, movable joints, tool joint).
    pub origins: Vec<OriginChange>,
    /// Terms of the model a URDF cannot hold (one line each).
    pub not_representable: Vec<String>,
}

/// The URDF origin of a frame; rounding noise below 1e-15 (m, rad) is written as 0 (it moves the
/// tool point by less than 1e-11 mm).
pub(super) fn origin_of(f: &Frame) -> Origin {
    let clean = |v: [f64; 3]| v.map(|x| if x.abs() < 1e-15 { 0.0 } else { x });
    Origin {
        xyz_m: clean(f.t.into()),
        rpy_rad: clean(rpy_of(&f.r)),
    }
}

/// The model's chain at `q = 0` as frames in metres: `frames[k]` is the frame after element
/// `k`; joint elements carry their offset (lengths multiplied by `scale`).
pub(super) fn chain_frames(model: &Model, scale: f64) -> Vec<Frame> {
    let mut f = Frame::identity();
    let mut out = Vec::with_capacity(model.elems().len());
    for e in model.elems() {
        let v = model.params()[e.param].value;
        let step = match e.motion {
            Motion::Rot => Frame {
                r: axis_rotation(e.axis.index(), v.to_radians()),
                t: Vector3::zeros(),
            },
            Motion::Trans => {
                let mut t = Vector3::zeros();
                t[e.axis.index()] = v / 1e3 * scale;
                Frame {
                    r: Matrix3::identity(),
                    t,
                }
            }
        };
        f = f.then(&step);
        out.push(f);
    }
    out
}

/// The terms of `model` that a URDF cannot hold.
pub(super) fn not_representable(model: &Model, scale_written: bool) -> Vec<String> {
    let mut out = Vec::new();
    if let Some(tilt) = model.tilt_values() {
        let active: Vec<String> = tilt
            .iter()
            .enumerate()
            .filter(|(_, t)| t.clearance_deg != 0.0 || t.backlash_deg != 0.0)
            .map(|(i, _)| format!("j{}", i + 1))
            .collect();
        out.push(format!(
            "joint tilting (clearance, backlash, stiffness{}): the URDF is the untilted model \
             (`rigctl fk` without --tilt)",
            if active.is_empty() {
                String::new()
            } else {
                format!("; non-zero on {}", active.join(", "))
            }
        ));
    }
    let tr = &model.transmission;
    if tr.is_active() {
        let mut terms = Vec::new();
        if tr.scale.iter().any(|v| *v != 0.0) {
            terms.push(Kind::JointScale.family().to_string());
        }
        if tr.coupling.iter().flatten().any(|v| *v != 0.0) {
            terms.push(Kind::JointCoupling.family().to_string());
        }
        if tr.hysteresis_deg.iter().any(|v| *v != 0.0) {
            terms.push(Kind::Hysteresis.family().to_string());
        }
        if tr.has_compliance() {
            terms.push(format!("{} (gravity)", Kind::Compliance.family()));
        }
        out.push(format!(
            "transmission terms ({}): they act on the joint readings, which a URDF takes as they \
             are (`rigctl compensate` writes corrected trajectories)",
            terms.join(", ")
        ));
    }
    if model.has_lateral_compliance() {
        let joints: Vec<String> = (0..model.n_joints())
            .filter(|&j| model.lateral_compliance_at(j) != 0.0)
            .map(|j| format!("j{}", j + 1))
            .collect();
        out.push(format!(
            "{} ({}): a bend under the gravity moments of the pose, which a URDF's fixed joint \
             origins cannot hold",
            Kind::LateralCompliance.family(),
            joints.join(", ")
        ));
    }
    let harmonics: Vec<&str> = model
        .params()
        .iter()
        .filter(|p| p.kind == ParamKind::EncoderHarmonic && p.value != 0.0)
        .map(|p| p.name.as_str())
        .collect();
    if !harmonics.is_empty() {
        out.push(format!(
            "encoder harmonics ({}): a function of the joint reading",
            harmonics.join(", ")
        ));
    }
    if model.time_terms().is_active() {
        out.push(format!(
            "time terms ({}): they depend on the time of a reading, which a URDF has not",
            [
                (model.time_terms().thermal_ppm != 0.0, Kind::Thermal),
                (
                    model.time_terms().drift_mm_per_h != Vector3::zeros(),
                    Kind::TimeDrift,
                ),
                (
                    model
                        .time_terms()
                        .joint_drift_deg_per_h
                        .iter()
                        .any(|r| *r != 0.0),
                    Kind::JointDrift,
                ),
            ]
            .iter()
            .filter(|(on, _)| *on)
            .map(|(_, k)| k.row().grammar)
            .collect::<Vec<_>>()
            .join(", ")
        ));
    }
    let payload = model.params()[model.payload_param()].value;
    if payload != 0.0 {
        out.push(format!(
            "payload_kg = {payload}: it acts only through tilting and compliance"
        ));
    }
    let ppm = model.params()[model.scale_param()].value;
    if ppm != 0.0 {
        if !scale_written {
            out.push(format!(
                "scale_ppm = {ppm}: the original's fixed joints keep their lengths, so the \
                 measurement scale is not in the URDF"
            ));
        } else if model.joints().iter().any(|j| j.prismatic) {
            out.push(format!(
                "scale_ppm = {ppm}: written into the constant lengths, not into the prismatic \
                 joints' travel"
            ));
        }
    }
    out
}

/// Shortest text that reads back to the same f64 (plain, or with an exponent when shorter).
pub fn num(v: f64) -> String {
    let v = if v == 0.0 { 0.0 } else { v }; // no "-0"
    let plain = format!("{v}");
    let exp = format!("{v:e}");
    if exp.len() < plain.len() {
        exp
    } else {
        plain
    }
}

pub(super) fn origin_xml(o: &Origin) -> String {
    let [x, y, z] = o.xyz_m;
    let [r, p, w] = o.rpy_rad;
    format!(
        "<origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>",
        num(x),
        num(y),
        num(z),
        num(r),
        num(p),
        num(w)
    )
}

/// `s` as an XML attribute value or text that a parser reads back as `s`
/// ([`crate::io::markup::Blanks::References`]).
pub(super) fn xml_escape(s: &str) -> String {
    crate::io::markup::escape(s, crate::io::markup::Blanks::References)
}

/// The model's joint names, or `joint_1..joint_N`.
fn joint_names(model: &Model) -> Vec<String> {
    if model.joint_names().is_empty() {
        (1..=model.n_joints())
            .map(|i| format!("joint_{i}"))
            .collect()
    } else {
        model.joint_names().to_vec()
    }
}

/// A movable joint of `model_to_urdf`: its child link and the joint element (axis `0 0 1`).
pub(super) fn movable_joint_xml(
    name: &str,
    j: &crate::model::Joint,
    parent: &str,
    child: &str,
    o: &Origin,
) -> String {
    let [lo, hi] = j.limits;
    let (kind, limit) = if j.prismatic {
        (
            "prismatic",
            format!(
                "\n    <limit lower=\"{}\" upper=\"{}\" effort=\"0\" velocity=\"0\"/>",
                num(lo * 1e-3),
                num(hi * 1e-3)
            ),
        )
    } else if lo <= -360.0 && hi >= 360.0 {
        ("continuous", String::new())
    } else {
        (
            "revolute",
            format!(
                "\n    <limit lower=\"{}\" upper=\"{}\" effort=\"0\" velocity=\"0\"/>",
                num(lo.to_radians()),
                num(hi.to_radians())
            ),
        )
    };
    format!(
        "  <link name=\"{child}\"/>\n  <joint name=\"{}\" type=\"{kind}\">\n    <parent \
         link=\"{parent}\"/>\n    <child link=\"{child}\"/>\n    {}\n    <axis xyz=\"0 0 \
         1\"/>{limit}\n  </joint>\n",
        xml_escape(name),
        origin_xml(o)
    )
}

/// The model as a new URDF (see the module doc).
pub fn model_to_urdf(model: &Model) -> Exported {
    let scale = model.scale_factor();
    let frames = chain_frames(model, scale);
    let names = joint_names(model);
    let mut text = format!(
        "<?xml version=\"1.0\"?>\n<!-- rigctl model2urdf: model `{}`, frame R = link world, \
         tool point = link tool0; m and rad -->\n<robot name=\"{}\">\n  <link name=\"world\"/>\n",
        xml_escape(model.name()).replace("--", "- -"),
        xml_escape(model.name())
    );
    let mut origins = Vec::new();
    let mut prev = Frame::identity();
    let mut parent = "world".to_string();
    for (i, j) in model.joints().iter().enumerate() {
        let here = frames[j.elem];
        let o = origin_of(&prev.inverse().then(&here));
        let child = format!("link_{}", i + 1);
        text.push_str(&movable_joint_xml(&names[i], j, &parent, &child, &o));
        origins.push(OriginChange {
            joint: names[i].clone(),
            before: None,
            after: o,
        });
        prev = here;
        parent = child;
    }
    let tool = frames.last().copied().unwrap_or_else(Frame::identity);
    let o = origin_of(&prev.inverse().then(&tool));
    text.push_str(&format!(
        "  <link name=\"tool0\"/>\n  <joint name=\"tool0_joint\" type=\"fixed\">\n    <parent \
         link=\"{parent}\"/>\n    <child link=\"tool0\"/>\n    {}\n  </joint>\n</robot>\n",
        origin_xml(&o)
    ));
    origins.push(OriginChange {
        joint: "tool0_joint".into(),
        before: None,
        after: o,
    });
    Exported {
        text,
        origins,
        not_representable: not_representable(model, true),
    }
}

#[cfg(test)]
mod tests;
