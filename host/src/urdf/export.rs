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
//! * [`model_into_urdf`] (a model from `urdf2model` and its original URDF): the original text
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

use super::frame::Frame;
use nalgebra::{Matrix3, Rotation3, Vector3};

use super::error::UrdfError;
use super::import::rpy_of;
use super::parse::{JointType, Urdf};
use crate::model::effect::Kind;
use crate::model::{axis_rotation, Model, Motion, ParamKind};

/// A joint origin in URDF units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Origin {
    /// `xyz`, m.
    pub xyz_m: [f64; 3],
    /// `rpy`, rad (`R = Rz(y) Ry(p) Rx(r)`).
    pub rpy_rad: [f64; 3],
}

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
fn origin_of(f: &Frame) -> Origin {
    let clean = |v: [f64; 3]| v.map(|x| if x.abs() < 1e-15 { 0.0 } else { x });
    Origin {
        xyz_m: clean(f.t.into()),
        rpy_rad: clean(rpy_of(&f.r)),
    }
}

/// The model's chain at `q = 0` as frames in metres: `frames[k]` is the frame after element
/// `k`; joint elements carry their offset (lengths multiplied by `scale`).
fn chain_frames(model: &Model, scale: f64) -> Vec<Frame> {
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
fn not_representable(model: &Model, scale_written: bool) -> Vec<String> {
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

fn origin_xml(o: &Origin) -> String {
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
fn xml_escape(s: &str) -> String {
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
        text.push_str(&format!(
            "  <link name=\"{child}\"/>\n  <joint name=\"{}\" type=\"{kind}\">\n    <parent \
             link=\"{parent}\"/>\n    <child link=\"{child}\"/>\n    {}\n    <axis xyz=\"0 0 \
             1\"/>{limit}\n  </joint>\n",
            xml_escape(&names[i]),
            origin_xml(&o)
        ));
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

/// A text edit of the original: replace `range` by `with`.
struct Edit {
    range: std::ops::Range<usize>,
    with: String,
}

/// The model (from `urdf2model`) written into its original URDF `text` (see the module doc).
/// `base_link` is the chain's first link as given to `urdf2model` (default: the root link).
pub fn model_into_urdf(
    model: &Model,
    text: &str,
    source_name: &str,
    base_link: Option<&str>,
) -> Result<Exported, UrdfError> {
    let urdf = Urdf::parse(text, source_name)?;
    let invalid = |message: String| UrdfError::Tree {
        source_name: source_name.to_string(),
        message,
    };
    if model.joint_names().is_empty() {
        return Err(invalid(
            "the model names no joints: --urdf needs a model written by `rigctl urdf2model` \
             (its [[joint]] entries carry the URDF names)"
                .into(),
        ));
    }
    let names = model.joint_names();
    let mut last_child = None;
    for (name, mj) in names.iter().zip(model.joints()) {
        let Some(uj) = urdf.joints.iter().find(|j| &j.name == name) else {
            return Err(invalid(format!("no joint `{name}` (a joint of the model)")));
        };
        let ok = match uj.joint_type {
            JointType::Prismatic => mj.prismatic,
            JointType::Revolute | JointType::Continuous => !mj.prismatic,
            _ => false,
        };
        if !ok {
            return Err(invalid(format!(
                "joint `{name}` is {} in the URDF but {} in the model",
                uj.joint_type.as_str(),
                if mj.prismatic {
                    "prismatic"
                } else {
                    "revolute"
                }
            )));
        }
        last_child = Some(uj.child.clone());
    }
    let last_child = last_child.unwrap_or_default();
    let base = match base_link {
        Some(b) => b.to_string(),
        None => urdf.root_link()?.to_string(),
    };
    let chain = urdf.chain(Some(&base), &last_child)?;
    let movable: Vec<&str> = chain
        .iter()
        .filter(|j| j.joint_type != JointType::Fixed)
        .map(|j| j.name.as_str())
        .collect();
    if movable != names.iter().map(String::as_str).collect::<Vec<_>>() {
        return Err(invalid(format!(
            "the movable joints from `{base}` to `{last_child}` are ({}), the model's are ({}): \
             give the base link the model was imported from (--base-link)",
            movable.join(", "),
            names.join(", ")
        )));
    }

    let frames = chain_frames(model, 1.0);
    // The model's base: the base elements and, for a model from urdf2model, `base_rz`.
    let robot_start = model.robot_elems.start;
    let base_end = match model.elems().get(robot_start) {
        Some(e) if model.params()[e.param].name == "base_rz" => robot_start,
        _ => robot_start.wrapping_sub(1),
    };
    let base_frame = frames
        .get(base_end)
        .copied()
        .unwrap_or_else(Frame::identity);

    let doc = roxmltree::Document::parse(text).map_err(|e| UrdfError::Xml {
        source_name: source_name.to_string(),
        message: e.to_string(),
    })?;
    let robot = doc.root_element();
    let joint_node = |name: &str| {
        robot
            .children()
            .find(|n| n.has_tag_name("joint") && n.attribute("name") == Some(name))
    };
    let mut edits: Vec<Edit> = Vec::new();
    let mut origins = Vec::new();
    // Rewrites (or adds) the <origin> of joint `name`.
    let set_origin = |name: &str,
                      o: Origin,
                      edits: &mut Vec<Edit>,
                      origins: &mut Vec<OriginChange>|
     -> Result<(), UrdfError> {
        let node = joint_node(name).ok_or_else(|| invalid(format!("no joint `{name}`")))?;
        let before = urdf.joints.iter().find(|j| j.name == name).map(|j| Origin {
            xyz_m: j.origin_xyz_m,
            rpy_rad: j.origin_rpy_rad,
        });
        match node.children().find(|n| n.has_tag_name("origin")) {
            Some(origin) => edits.push(Edit {
                range: origin.range(),
                with: origin_xml(&o),
            }),
            None => {
                let first = node
                    .children()
                    .find(|n| n.is_element())
                    .ok_or_else(|| invalid(format!("joint `{name}` has no child element")))?;
                let at = first.range().start;
                let indent: String = text[..at]
                    .chars()
                    .rev()
                    .take_while(|c| *c == ' ' || *c == '\t')
                    .collect();
                edits.push(Edit {
                    range: at..at,
                    with: format!("{}\n{indent}", origin_xml(&o)),
                });
            }
        }
        origins.push(OriginChange {
            joint: name.to_string(),
            before,
            after: o,
        });
        Ok(())
    };
    let mut added = String::new();

    // Frame R.
    let mut pose = if base == "world" {
        Frame::identity()
    } else {
        let parent_joint = urdf.joints.iter().find(|j| j.child == base);
        match parent_joint {
            None => {
                if urdf.links.iter().any(|l| l == "world") || joint_node("world_joint").is_some() {
                    return Err(invalid(format!(
                        "the base link `{base}` is the root, but a link `world` or joint \
                         `world_joint` exists elsewhere"
                    )));
                }
                let o = origin_of(&base_frame);
                added.push_str(&format!(
                    "  <link name=\"world\"/>\n  <joint name=\"world_joint\" type=\"fixed\">\n    \
                     <parent link=\"world\"/>\n    <child link=\"{}\"/>\n    {}\n  </joint>\n",
                    xml_escape(&base),
                    origin_xml(&o)
                ));
                origins.push(OriginChange {
                    joint: "world_joint".into(),
                    before: None,
                    after: o,
                });
                base_frame
            }
            Some(j) if j.parent == "world" && j.joint_type == JointType::Fixed => {
                let name = j.name.clone();
                set_origin(&name, origin_of(&base_frame), &mut edits, &mut origins)?;
                base_frame
            }
            Some(j) => {
                return Err(invalid(format!(
                    "the base link `{base}` hangs from `{}` by joint `{}`: the exported chain \
                     starts at link `world`, so the base link must be the root (or `world`, or \
                     fixed to a root `world`)",
                    j.parent, j.name
                )))
            }
        }
    };

    // The chain's movable joints.
    let mut k = 0;
    for j in &chain {
        if j.joint_type == JointType::Fixed {
            pose = pose.then(&Frame::of_origin(&Origin {
                xyz_m: j.origin_xyz_m,
                rpy_rad: j.origin_rpy_rad,
            }));
            continue;
        }
        let mj = &model.joints()[k];
        k += 1;
        let a = Vector3::from(j.axis);
        let norm = a.norm();
        if norm.is_nan() || norm <= 1e-9 {
            return Err(UrdfError::Element {
                source_name: source_name.to_string(),
                line: j.line,
                column: 1,
                message: format!("joint `{}`: axis {:?} has no direction", j.name, j.axis),
            });
        }
        let a = a / norm;
        // Any rotation that turns z onto the axis: A Rz(q) A^-1 = rotation about a by q.
        let align = Rotation3::rotation_between(&Vector3::z(), &a)
            .map(|r| *r.matrix())
            .unwrap_or_else(|| axis_rotation(0, std::f64::consts::PI));
        let model_joint = frames[mj.elem];
        let child = Frame {
            r: model_joint.r * align.transpose(),
            t: model_joint.t,
        };
        let o = origin_of(&pose.inverse().then(&child));
        set_origin(&j.name, o, &mut edits, &mut origins)?;
        pose = child;
    }

    // The tool point.
    let tool = frames.last().copied().unwrap_or_else(Frame::identity);
    let o = origin_of(&pose.inverse().then(&tool));
    match urdf.joints.iter().find(|j| j.child == "tool0") {
        Some(j) if j.parent == last_child && j.joint_type == JointType::Fixed => {
            let name = j.name.clone();
            set_origin(&name, o, &mut edits, &mut origins)?;
        }
        Some(j) => {
            return Err(invalid(format!(
                "a link `tool0` exists, hanging from `{}` by `{}`, not fixed to `{last_child}`",
                j.parent, j.name
            )))
        }
        None => {
            if urdf.links.iter().any(|l| l == "tool0") || joint_node("tool0_joint").is_some() {
                return Err(invalid(
                    "a link `tool0` or joint `tool0_joint` exists off the chain".into(),
                ));
            }
            added.push_str(&format!(
                "  <link name=\"tool0\"/>\n  <joint name=\"tool0_joint\" type=\"fixed\">\n    \
                 <parent link=\"{}\"/>\n    <child link=\"tool0\"/>\n    {}\n  </joint>\n",
                xml_escape(&last_child),
                origin_xml(&o)
            ));
            origins.push(OriginChange {
                joint: "tool0_joint".into(),
                before: None,
                after: o,
            });
        }
    }
    if !added.is_empty() {
        let end = robot.range().end;
        let close = text[..end]
            .rfind("</")
            .ok_or_else(|| invalid("<robot> has no closing tag".into()))?;
        edits.push(Edit {
            range: close..close,
            with: format!(
                "  <!-- rigctl model2urdf: frame R (world) and the model's tool point (tool0) \
                 -->\n{added}"
            ),
        });
    }
    edits.sort_by_key(|e| e.range.start);
    let mut out = String::with_capacity(text.len() + 1024);
    let mut at = 0;
    for e in &edits {
        out.push_str(&text[at..e.range.start]);
        out.push_str(&e.with);
        at = e.range.end;
    }
    out.push_str(&text[at..]);
    Ok(Exported {
        text: out,
        origins,
        not_representable: not_representable(model, false),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Axis, ModelBuilder, Tilt};
    use crate::urdf::{import_chain, ImportOptions};

    /// A chain with a pitch of exactly 90 deg in an origin (gimbal lock of rpy), a prismatic
    /// joint and a joint offset.
    fn gimbal_model() -> Model {
        let mut b = ModelBuilder::new("gimbal");
        b.constant(Motion::Trans, Axis::Z, "h", 250.0).unwrap();
        b.joint(false, "o1", 3.0, [-170.0, 170.0], None).unwrap();
        b.constant(Motion::Rot, Axis::Y, "p1", 90.0).unwrap();
        b.constant(Motion::Rot, Axis::Z, "y1", 30.0).unwrap();
        b.constant(Motion::Trans, Axis::X, "a1", 120.0).unwrap();
        b.joint(true, "o2", 5.0, [0.0, 300.0], None).unwrap();
        b.constant(Motion::Rot, Axis::Y, "p2", -90.0).unwrap();
        b.joint(false, "o3", -1.0, [-360.0, 360.0], None).unwrap();
        b.constant(Motion::Trans, Axis::Y, "a3", 40.0).unwrap();
        let mut m = b.build().unwrap();
        m.set_param("base_rx", 0.4).unwrap();
        m.set_param("tool_dz", 60.0).unwrap();
        m
    }

    #[test]
    fn gimbal_origins_and_prismatic_joints_read_back_exactly() {
        let model = gimbal_model();
        let e = model_to_urdf(&model);
        assert!(e.text.contains("type=\"prismatic\""), "{}", e.text);
        assert!(e.text.contains("type=\"continuous\""), "{}", e.text);
        let urdf = Urdf::parse(&e.text, "g.urdf").unwrap();
        let back = import_chain(
            &urdf,
            &ImportOptions {
                base_link: None,
                tip_link: "tool0",
                tool_mm: [0.0; 3],
            },
        )
        .unwrap()
        .model;
        for q in [
            [0.0, 0.0, 0.0],
            [40.0, 120.0, -200.0],
            [-160.0, 299.0, 350.0],
        ] {
            let a = model.fk(&q, Tilt::Off).unwrap();
            let b = back.fk(&q, Tilt::Off).unwrap();
            assert!((a.position_mm - b.position_mm).norm() < 1e-9, "{q:?}");
            assert!((a.rotation - b.rotation).norm() < 1e-12, "{q:?}");
        }
        assert!(e.not_representable.is_empty(), "{:?}", e.not_representable);
    }

    #[test]
    fn what_a_urdf_cannot_hold_is_named() {
        let mut model = gimbal_model();
        let mut terms = crate::model::transmission::JointTerms::zeros(3);
        terms.hysteresis_deg[0] = 0.05;
        model.set_transmission(terms);
        model.set_param("enc_j1_h1_sin", 0.01).unwrap();
        model.set_param("scale_ppm", 20.0).unwrap();
        model.set_param("payload_kg", 1.5).unwrap();
        let notes = model_to_urdf(&model).not_representable.join("\n");
        for word in [
            "hysteresis",
            "enc_j1_h1_sin",
            "scale_ppm = 20",
            "prismatic",
            "payload_kg",
        ] {
            assert!(notes.contains(word), "{word}: {notes}");
        }
    }

    #[test]
    fn numbers_read_back_to_the_same_double() {
        for v in [
            0.0,
            -0.0,
            0.39225,
            1.0 / 3.0,
            1e-17,
            -2.5e-300,
            std::f64::consts::FRAC_PI_2,
            123456.789,
        ] {
            let t = num(v);
            assert_eq!(t.parse::<f64>().unwrap(), v, "{t}");
            assert!(!t.starts_with("-0") || v != 0.0, "{t}");
        }
        assert_eq!(num(0.39225), "0.39225");
        assert_eq!(num(1e-17), "1e-17");
    }

    #[test]
    fn a_urdf_whose_base_hangs_from_another_link_is_refused() {
        let text = r#"<robot name="r">
  <link name="a"/><link name="b"/><link name="c"/>
  <joint name="fix" type="fixed"><parent link="a"/><child link="b"/></joint>
  <joint name="j" type="revolute"><parent link="b"/><child link="c"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"#;
        let urdf = Urdf::parse(text, "r.urdf").unwrap();
        let model = import_chain(
            &urdf,
            &ImportOptions {
                base_link: Some("b"),
                tip_link: "c",
                tool_mm: [0.0; 3],
            },
        )
        .unwrap()
        .model;
        let err = model_into_urdf(&model, text, "r.urdf", Some("b")).unwrap_err();
        assert!(err.to_string().contains("hangs from `a`"), "{err}");
        // From the root it is written, the fixed joint kept and an origin added to `j`.
        let model = import_chain(
            &urdf,
            &ImportOptions {
                base_link: None,
                tip_link: "c",
                tool_mm: [0.0; 3],
            },
        )
        .unwrap()
        .model;
        let e = model_into_urdf(&model, text, "r.urdf", None).unwrap();
        assert!(e.text.contains("<joint name=\"world_joint\""), "{}", e.text);
        assert!(e.text.contains("<child link=\"a\"/>"), "{}", e.text);
        let j = e.text.find("<joint name=\"j\"").unwrap();
        assert!(
            e.text[j..].starts_with(
                "<joint name=\"j\" type=\"revolute\"><origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n<parent link=\"b\"/>"
            ),
            "{}",
            e.text
        );
        // Everything before the added elements is the original's, but for that origin.
        let added = e.text.find("  <!-- rigctl model2urdf").unwrap();
        assert_eq!(
            e.text[..added].replace("<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n", ""),
            text[..text.rfind("</robot>").unwrap()]
        );
    }
}
