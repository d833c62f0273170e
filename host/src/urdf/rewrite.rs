//! [`model_into_urdf`]: a model from `urdf2model` written into its original URDF (`rigctl
//! model2urdf --urdf`). The original text is kept byte for byte except the `<origin>` of the
//! chain's movable joints, the frame R (`world`) and the tool point (`tool0`); the chain and the
//! rules are described in [`super::export`].

use nalgebra::{Matrix3, Rotation3, Vector3};

use super::error::UrdfError;
use super::export::{
    chain_frames, not_representable, origin_of, origin_xml, xml_escape, Exported, OriginChange,
};
use super::frame::{Frame, Origin};
use super::parse::{JointType, Urdf, UrdfJoint};
use crate::model::{axis_rotation, Model};

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
    let last_child = check_model_joints(model, &urdf)?;
    let base = match base_link {
        Some(b) => b.to_string(),
        None => urdf.root_link()?.to_string(),
    };
    let chain = model_chain(model, &urdf, &base, &last_child)?;
    let frames = chain_frames(model, 1.0);
    let base_frame = model_base_frame(model, &frames);
    let doc = roxmltree::Document::parse(text).map_err(|e| UrdfError::Xml {
        source_name: source_name.to_string(),
        message: e.to_string(),
    })?;
    let mut w = Rewrite {
        text,
        urdf: &urdf,
        robot: doc.root_element(),
        edits: Vec::new(),
        origins: Vec::new(),
        added: String::new(),
    };
    let pose = w.frame_r(&base, base_frame)?;
    let pose = w.movable_joints(model, &chain, &frames, pose)?;
    let tool = frames.last().copied().unwrap_or_else(Frame::identity);
    w.tool_point(&last_child, &pose.inverse().then(&tool))?;
    let (text, origins) = w.finish()?;
    Ok(Exported {
        text,
        origins,
        not_representable: not_representable(model, false),
    })
}

/// A malformed or mismatching URDF tree of `urdf`.
fn invalid(urdf: &Urdf, message: String) -> UrdfError {
    UrdfError::Tree {
        source_name: urdf.source_name.clone(),
        message,
    }
}

/// Every joint of the model is a URDF joint of the same kind; returns the child link of the
/// last one.
fn check_model_joints(model: &Model, urdf: &Urdf) -> Result<String, UrdfError> {
    if model.joint_names().is_empty() {
        return Err(invalid(
            urdf,
            "the model names no joints: --urdf needs a model written by `rigctl urdf2model` \
             (its [[joint]] entries carry the URDF names)"
                .into(),
        ));
    }
    let mut last_child = None;
    for (name, mj) in model.joint_names().iter().zip(model.joints()) {
        let Some(uj) = urdf.joints.iter().find(|j| &j.name == name) else {
            return Err(invalid(
                urdf,
                format!(
                    "no joint `{name}` (a joint of the model); its joints, nearest first: {}",
                    urdf.joints_nearest(name)
                ),
            ));
        };
        let ok = match uj.joint_type {
            JointType::Prismatic => mj.prismatic,
            JointType::Revolute | JointType::Continuous => !mj.prismatic,
            _ => false,
        };
        if !ok {
            return Err(invalid(
                urdf,
                format!(
                    "joint `{name}` is {} in the URDF but {} in the model",
                    uj.joint_type.as_str(),
                    if mj.prismatic {
                        "prismatic"
                    } else {
                        "revolute"
                    }
                ),
            ));
        }
        last_child = Some(uj.child.clone());
    }
    Ok(last_child.unwrap_or_default())
}

/// The URDF chain from `base` to `last_child`, whose movable joints must be the model's.
fn model_chain<'u>(
    model: &Model,
    urdf: &'u Urdf,
    base: &str,
    last_child: &str,
) -> Result<Vec<&'u UrdfJoint>, UrdfError> {
    let names = model.joint_names();
    let chain = urdf.chain(Some(base), last_child)?;
    let movable: Vec<&str> = chain
        .iter()
        .filter(|j| j.joint_type != JointType::Fixed)
        .map(|j| j.name.as_str())
        .collect();
    if movable != names.iter().map(String::as_str).collect::<Vec<_>>() {
        return Err(invalid(
            urdf,
            format!(
                "the movable joints from `{base}` to `{last_child}` are ({}), the model's are \
                 ({}): give the base link the model was imported from (--base-link)",
                movable.join(", "),
                names.join(", ")
            ),
        ));
    }
    Ok(chain)
}

/// The model's base: the base elements and, for a model from urdf2model, `base_rz`.
fn model_base_frame(model: &Model, frames: &[Frame]) -> Frame {
    let robot_start = model.robot_elems.start;
    let base_end = match model.elems().get(robot_start) {
        Some(e) if model.params()[e.param].name == "base_rz" => robot_start,
        _ => robot_start.wrapping_sub(1),
    };
    frames
        .get(base_end)
        .copied()
        .unwrap_or_else(Frame::identity)
}

/// The original URDF text being rewritten: the edits so far, the origins written and the
/// elements to add before `</robot>`.
struct Rewrite<'a, 'd> {
    text: &'a str,
    urdf: &'a Urdf,
    robot: roxmltree::Node<'d, 'a>,
    edits: Vec<Edit>,
    origins: Vec<OriginChange>,
    added: String,
}

impl Rewrite<'_, '_> {
    fn invalid(&self, message: String) -> UrdfError {
        invalid(self.urdf, message)
    }

    fn joint_node(&self, name: &str) -> Option<roxmltree::Node<'_, '_>> {
        self.robot
            .children()
            .find(|n| n.has_tag_name("joint") && n.attribute("name") == Some(name))
    }

    /// Rewrites (or adds) the `<origin>` of joint `name`.
    fn set_origin(&mut self, name: &str, o: Origin) -> Result<(), UrdfError> {
        let node = self
            .joint_node(name)
            .ok_or_else(|| self.invalid(format!("no joint `{name}`")))?;
        let before = self
            .urdf
            .joints
            .iter()
            .find(|j| j.name == name)
            .map(|j| Origin {
                xyz_m: j.origin_xyz_m,
                rpy_rad: j.origin_rpy_rad,
            });
        let edit = match node.children().find(|n| n.has_tag_name("origin")) {
            Some(origin) => Edit {
                range: origin.range(),
                with: origin_xml(&o),
            },
            None => {
                let first = node
                    .children()
                    .find(|n| n.is_element())
                    .ok_or_else(|| self.invalid(format!("joint `{name}` has no child element")))?;
                let at = first.range().start;
                let indent: String = self.text[..at]
                    .chars()
                    .rev()
                    .take_while(|c| *c == ' ' || *c == '\t')
                    .collect();
                Edit {
                    range: at..at,
                    with: format!("{}\n{indent}", origin_xml(&o)),
                }
            }
        };
        self.edits.push(edit);
        self.origins.push(OriginChange {
            joint: name.to_string(),
            before,
            after: o,
        });
        Ok(())
    }

    /// Frame R: link `world`, added (with `world_joint` holding the model's base) when `base`
    /// is the root, or its fixed joint to `base` rewritten; returns the pose of `base`.
    fn frame_r(&mut self, base: &str, base_frame: Frame) -> Result<Frame, UrdfError> {
        if base == "world" {
            return Ok(Frame::identity());
        }
        match self.urdf.joints.iter().find(|j| j.child == base) {
            None => {
                if self.urdf.links.iter().any(|l| l == "world")
                    || self.joint_node("world_joint").is_some()
                {
                    return Err(self.invalid(format!(
                        "the base link `{base}` is the root, but a link `world` or joint \
                         `world_joint` exists elsewhere"
                    )));
                }
                let o = origin_of(&base_frame);
                self.added.push_str(&format!(
                    "  <link name=\"world\"/>\n  <joint name=\"world_joint\" type=\"fixed\">\n    \
                     <parent link=\"world\"/>\n    <child link=\"{}\"/>\n    {}\n  </joint>\n",
                    xml_escape(base),
                    origin_xml(&o)
                ));
                self.origins.push(OriginChange {
                    joint: "world_joint".into(),
                    before: None,
                    after: o,
                });
                Ok(base_frame)
            }
            Some(j) if j.parent == "world" && j.joint_type == JointType::Fixed => {
                let name = j.name.clone();
                self.set_origin(&name, origin_of(&base_frame))?;
                Ok(base_frame)
            }
            Some(j) => Err(self.invalid(format!(
                "the base link `{base}` hangs from `{}` by joint `{}`: the exported chain \
                 starts at link `world`, so the base link must be the root (or `world`, or \
                 fixed to a root `world`)",
                j.parent, j.name
            ))),
        }
    }

    /// The origin of every movable joint of `chain`: what puts its child link where the model
    /// puts it (the model's joint frame at `q = 0` turned back from `z` to the joint's axis).
    /// Fixed joints keep their origins. `pose` is the pose of the chain's base link; returns
    /// the pose of the last movable joint's child link.
    fn movable_joints(
        &mut self,
        model: &Model,
        chain: &[&UrdfJoint],
        frames: &[Frame],
        mut pose: Frame,
    ) -> Result<Frame, UrdfError> {
        let mut k = 0;
        for j in chain {
            if j.joint_type == JointType::Fixed {
                pose = pose.then(&Frame::of_origin(&Origin {
                    xyz_m: j.origin_xyz_m,
                    rpy_rad: j.origin_rpy_rad,
                }));
                continue;
            }
            let mj = &model.joints()[k];
            k += 1;
            let align = axis_alignment(&self.urdf.source_name, j)?;
            let model_joint = frames[mj.elem];
            let child = Frame {
                r: model_joint.r * align.transpose(),
                t: model_joint.t,
            };
            let o = origin_of(&pose.inverse().then(&child));
            self.set_origin(&j.name, o)?;
            pose = child;
        }
        Ok(pose)
    }

    /// The tool point: `tool0` fixed to `last_child` at `tool` (in `last_child`'s frame), its
    /// joint rewritten when it exists, else added.
    fn tool_point(&mut self, last_child: &str, tool: &Frame) -> Result<(), UrdfError> {
        let o = origin_of(tool);
        match self.urdf.joints.iter().find(|j| j.child == "tool0") {
            Some(j) if j.parent == last_child && j.joint_type == JointType::Fixed => {
                let name = j.name.clone();
                self.set_origin(&name, o)
            }
            Some(j) => Err(self.invalid(format!(
                "a link `tool0` exists, hanging from `{}` by `{}`, not fixed to `{last_child}`",
                j.parent, j.name
            ))),
            None => {
                if self.urdf.links.iter().any(|l| l == "tool0")
                    || self.joint_node("tool0_joint").is_some()
                {
                    return Err(self.invalid(
                        "a link `tool0` or joint `tool0_joint` exists off the chain".into(),
                    ));
                }
                self.added.push_str(&format!(
                    "  <link name=\"tool0\"/>\n  <joint name=\"tool0_joint\" type=\"fixed\">\n    \
                     <parent link=\"{}\"/>\n    <child link=\"tool0\"/>\n    {}\n  </joint>\n",
                    xml_escape(last_child),
                    origin_xml(&o)
                ));
                self.origins.push(OriginChange {
                    joint: "tool0_joint".into(),
                    before: None,
                    after: o,
                });
                Ok(())
            }
        }
    }

    /// The rewritten text (the added elements before `</robot>`) and the origins written.
    fn finish(mut self) -> Result<(String, Vec<OriginChange>), UrdfError> {
        if !self.added.is_empty() {
            let end = self.robot.range().end;
            let close = self.text[..end]
                .rfind("</")
                .ok_or_else(|| self.invalid("<robot> has no closing tag".into()))?;
            self.edits.push(Edit {
                range: close..close,
                with: format!(
                    "  <!-- rigctl model2urdf: frame R (world) and the model's tool point (tool0) \
                     -->\n{}",
                    self.added
                ),
            });
        }
        self.edits.sort_by_key(|e| e.range.start);
        let mut out = String::with_capacity(self.text.len() + 1024);
        let mut at = 0;
        for e in &self.edits {
            out.push_str(&self.text[at..e.range.start]);
            out.push_str(&e.with);
            at = e.range.end;
        }
        out.push_str(&self.text[at..]);
        Ok((out, self.origins))
    }
}

/// A rotation that turns `z` onto the unit axis of joint `j` (any one: `A Rz(q) A^-1` is the
/// rotation about the axis by `q`); an axis without direction is an error.
fn axis_alignment(source_name: &str, j: &UrdfJoint) -> Result<Matrix3<f64>, UrdfError> {
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
    Ok(Rotation3::rotation_between(&Vector3::z(), &a)
        .map(|r| *r.matrix())
        .unwrap_or_else(|| axis_rotation(0, std::f64::consts::PI)))
}
