//! The kinematic part of a URDF file: links and joints (origin, axis, type, limits).
//!
//! Only `<joint>` elements that are direct children of `<robot>` count (the ones inside
//! `<transmission>` or `<gazebo>` are references, not joints). Values stay in URDF units
//! (metres, radians) here; [`super::import`] converts at the model's edge.

use std::collections::HashMap;

use super::error::UrdfError;

/// URDF joint type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointType {
    Revolute,
    Continuous,
    Prismatic,
    Fixed,
    Floating,
    Planar,
}

impl JointType {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "revolute" => Self::Revolute,
            "continuous" => Self::Continuous,
            "prismatic" => Self::Prismatic,
            "fixed" => Self::Fixed,
            "floating" => Self::Floating,
            "planar" => Self::Planar,
            _ => return None,
        })
    }

    /// The URDF spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Revolute => "revolute",
            Self::Continuous => "continuous",
            Self::Prismatic => "prismatic",
            Self::Fixed => "fixed",
            Self::Floating => "floating",
            Self::Planar => "planar",
        }
    }
}

/// One `<joint>` of the file (URDF units: m, rad).
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfJoint {
    /// The `name` attribute.
    pub name: String,
    /// The `type` attribute.
    pub joint_type: JointType,
    /// `<parent link=..>`.
    pub parent: String,
    /// `<child link=..>`.
    pub child: String,
    /// `<origin xyz>` (m), default 0.
    pub origin_xyz_m: [f64; 3],
    /// `<origin rpy>` (rad, fixed-axis roll-pitch-yaw: `R = Rz(y) Ry(p) Rx(r)`), default 0.
    pub origin_rpy_rad: [f64; 3],
    /// `<axis xyz>` as written (not normalised), default `1 0 0` as the URDF spec says.
    pub axis: [f64; 3],
    /// `<limit lower upper>` (rad or m), if the element is present.
    pub limits: Option<[f64; 2]>,
    /// 1-based line of the `<joint>` element.
    pub line: u32,
}

/// The mass and centre of mass of a link's `<inertial>` (URDF units).
#[derive(Debug, Clone, PartialEq)]
pub struct LinkInertial {
    /// The link's name.
    pub link: String,
    /// `<mass value>` (kg).
    pub mass_kg: f64,
    /// `<origin xyz>` of the `<inertial>` (m, in the link frame), default 0.
    pub com_xyz_m: [f64; 3],
}

/// The links and joints of a URDF file.
#[derive(Debug, Clone, PartialEq)]
pub struct Urdf {
    /// Where the text came from (file name), for messages.
    pub source_name: String,
    /// The `<robot name>`.
    pub robot_name: String,
    /// Link names, in file order.
    pub links: Vec<String>,
    /// Joints, in file order.
    pub joints: Vec<UrdfJoint>,
    /// The `<inertial>` of every link that has one, in file order.
    pub inertials: Vec<LinkInertial>,
}

impl Urdf {
    /// Reads and parses a URDF file.
    pub fn from_file(path: &std::path::Path) -> Result<Self, UrdfError> {
        let text = crate::io::read::read_text_capped(path, crate::io::read::CAP_URDF).map_err(
            |source| UrdfError::Read {
                path: path.to_path_buf(),
                source,
            },
        )?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parses URDF text; `source_name` names it in error messages.
    pub fn parse(text: &str, source_name: &str) -> Result<Self, UrdfError> {
        let doc = roxmltree::Document::parse(text).map_err(|e| UrdfError::Xml {
            source_name: source_name.to_string(),
            message: e.to_string(),
        })?;
        let ctx = Ctx {
            doc: &doc,
            source_name,
            newlines: text
                .bytes()
                .enumerate()
                .filter(|(_, b)| *b == b'\n')
                .map(|(i, _)| i)
                .collect(),
        };
        let robot = doc.root_element();
        if robot.tag_name().name() != "robot" {
            return Err(ctx.err(robot, "the root element must be <robot>".into()));
        }
        let robot_name = robot.attribute("name").unwrap_or("urdf").to_string();
        let mut links = Vec::new();
        let mut joints = Vec::new();
        let mut inertials = Vec::new();
        let mut seen = std::collections::HashSet::new();
        for node in robot.children().filter(|n| n.is_element()) {
            match node.tag_name().name() {
                "link" => {
                    let name = ctx.attr(node, "name")?.to_string();
                    if !seen.insert(name.clone()) {
                        return Err(ctx.err(node, format!("a second link named `{name}`")));
                    }
                    if let Some(i) = ctx.inertial(node, &name)? {
                        inertials.push(i);
                    }
                    links.push(name);
                }
                "joint" => joints.push(ctx.joint(node)?),
                _ => {}
            }
        }
        let urdf = Urdf {
            source_name: source_name.to_string(),
            robot_name,
            links,
            joints,
            inertials,
        };
        urdf.check_links()?;
        Ok(urdf)
    }

    fn check_links(&self) -> Result<(), UrdfError> {
        let links: std::collections::HashSet<&str> =
            self.links.iter().map(String::as_str).collect();
        for j in &self.joints {
            for link in [&j.parent, &j.child] {
                if !links.contains(link.as_str()) {
                    return Err(UrdfError::UnknownLink {
                        source_name: self.source_name.clone(),
                        link: link.clone(),
                        known: self.links_nearest(link),
                    });
                }
            }
        }
        Ok(())
    }

    /// The file's links, nearest to `name` first (for a message about a link it lacks).
    pub fn links_nearest(&self, name: &str) -> String {
        crate::error::nearest_first(name, self.links.iter().map(String::as_str), 30)
    }

    /// The file's joints, nearest to `name` first (for a message about a joint it lacks).
    pub fn joints_nearest(&self, name: &str) -> String {
        crate::error::nearest_first(name, self.joints.iter().map(|j| j.name.as_str()), 30)
    }

    /// The root link: the only link that is no joint's child.
    pub fn root_link(&self) -> Result<&str, UrdfError> {
        let children: std::collections::HashSet<&str> =
            self.joints.iter().map(|j| j.child.as_str()).collect();
        let roots: Vec<&str> = self
            .links
            .iter()
            .filter(|l| !children.contains(l.as_str()))
            .map(String::as_str)
            .collect();
        match roots.as_slice() {
            [one] => Ok(one),
            [] => Err(self.tree_err("no root link (every link is a joint's child)".into())),
            many => Err(self.tree_err(format!(
                "several root links ({}); choose one with --base-link",
                many.join(", ")
            ))),
        }
    }

    /// The joints from `base` (default: the root link) down to `tip`, in order from the base.
    pub fn chain(&self, base: Option<&str>, tip: &str) -> Result<Vec<&UrdfJoint>, UrdfError> {
        let base = match base {
            Some(b) => b,
            None => self.root_link()?,
        };
        for link in [base, tip] {
            if !self.links.iter().any(|l| l == link) {
                return Err(UrdfError::UnknownLink {
                    source_name: self.source_name.clone(),
                    link: link.to_string(),
                    known: self.links_nearest(link),
                });
            }
        }
        let mut by_child: HashMap<&str, usize> = HashMap::new();
        for (i, j) in self.joints.iter().enumerate() {
            if by_child.insert(j.child.as_str(), i).is_some() {
                return Err(self.tree_err(format!("link `{}` has two parent joints", j.child)));
            }
        }
        // A URDF is a tree: a loop anywhere is refused, even when the chain asked for avoids it.
        // Each link is walked towards the root once: a walk stops at a link already known to
        // reach the root (linear in the number of links).
        let mut reaches_root: std::collections::HashSet<&str> =
            std::collections::HashSet::with_capacity(self.links.len());
        for start in &self.links {
            let mut path: Vec<&str> = Vec::new();
            let mut on_path: std::collections::HashSet<&str> = std::collections::HashSet::new();
            let mut link = start.as_str();
            while !reaches_root.contains(link) {
                if !on_path.insert(link) {
                    return Err(self.tree_err(format!(
                        "the joints form a loop through link `{start}` (a URDF must be a tree)"
                    )));
                }
                path.push(link);
                match by_child.get(link) {
                    Some(&i) => link = &self.joints[i].parent,
                    None => break,
                }
            }
            reaches_root.extend(path);
        }
        let mut out = Vec::new();
        let mut link = tip;
        while link != base {
            let Some(&i) = by_child.get(link) else {
                return Err(UrdfError::NotBelow {
                    source_name: self.source_name.clone(),
                    base: base.to_string(),
                    tip: tip.to_string(),
                });
            };
            if out.len() > self.joints.len() {
                return Err(self.tree_err("the joints form a cycle".into()));
            }
            out.push(&self.joints[i]);
            link = &self.joints[i].parent;
        }
        out.reverse();
        Ok(out)
    }

    fn tree_err(&self, message: String) -> UrdfError {
        UrdfError::Tree {
            source_name: self.source_name.clone(),
            message,
        }
    }
}

struct Ctx<'d, 'i> {
    doc: &'d roxmltree::Document<'i>,
    source_name: &'d str,
    /// Byte offsets of the text's line feeds: the line of an element by binary search (the
    /// document's own `text_pos_at` scans from the start, quadratic over every joint).
    newlines: Vec<usize>,
}

impl Ctx<'_, '_> {
    /// 1-based line of byte offset `pos`.
    fn line_at(&self, pos: usize) -> u32 {
        let row = self.newlines.partition_point(|&nl| nl < pos) + 1;
        u32::try_from(row).unwrap_or(u32::MAX)
    }

    fn err(&self, node: roxmltree::Node, message: String) -> UrdfError {
        let pos = self.doc.text_pos_at(node.range().start);
        UrdfError::Element {
            source_name: self.source_name.to_string(),
            line: pos.row,
            column: pos.col,
            message,
        }
    }

    fn attr<'a>(&self, node: roxmltree::Node<'a, '_>, name: &str) -> Result<&'a str, UrdfError> {
        node.attribute(name).ok_or_else(|| {
            self.err(
                node,
                format!("<{}> needs a `{name}` attribute", node.tag_name().name()),
            )
        })
    }

    fn child<'a, 'i>(
        &self,
        node: roxmltree::Node<'a, 'i>,
        tag: &str,
    ) -> Option<roxmltree::Node<'a, 'i>> {
        node.children()
            .find(|n| n.is_element() && n.tag_name().name() == tag)
    }

    fn number(&self, node: roxmltree::Node, attr: &str, text: &str) -> Result<f64, UrdfError> {
        match text.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.err(node, format!("`{attr}`: `{text}` is not a finite number"))),
        }
    }

    fn triple(&self, node: roxmltree::Node, attr: &str) -> Result<Option<[f64; 3]>, UrdfError> {
        let Some(text) = node.attribute(attr) else {
            return Ok(None);
        };
        let parts: Vec<&str> = text.split_whitespace().collect();
        if parts.len() != 3 {
            return Err(self.err(node, format!("`{attr}` = `{text}`: expected 3 numbers")));
        }
        let mut out = [0.0; 3];
        for (o, p) in out.iter_mut().zip(parts) {
            *o = self.number(node, attr, p)?;
        }
        Ok(Some(out))
    }

    fn link_ref(&self, joint: roxmltree::Node, tag: &str) -> Result<String, UrdfError> {
        let node = self.child(joint, tag).ok_or_else(|| {
            self.err(
                joint,
                format!("<joint> needs a <{tag} link=\"...\"/> element"),
            )
        })?;
        Ok(self.attr(node, "link")?.to_string())
    }

    /// The `<inertial>` of `<link>` `node` (named `link`), if it has one with a `<mass>`.
    fn inertial(
        &self,
        node: roxmltree::Node,
        link: &str,
    ) -> Result<Option<LinkInertial>, UrdfError> {
        let Some(inertial) = self.child(node, "inertial") else {
            return Ok(None);
        };
        let Some(mass) = self.child(inertial, "mass") else {
            return Ok(None);
        };
        let mass_kg = self.number(mass, "value", self.attr(mass, "value")?)?;
        if mass_kg < 0.0 {
            return Err(self.err(mass, format!("link `{link}`: negative mass {mass_kg}")));
        }
        let com_xyz_m = match self.child(inertial, "origin") {
            Some(o) => self.triple(o, "xyz")?.unwrap_or([0.0; 3]),
            None => [0.0; 3],
        };
        Ok(Some(LinkInertial {
            link: link.to_string(),
            mass_kg,
            com_xyz_m,
        }))
    }

    fn joint(&self, node: roxmltree::Node) -> Result<UrdfJoint, UrdfError> {
        let name = self.attr(node, "name")?.to_string();
        let type_text = self.attr(node, "type")?;
        let joint_type = JointType::parse(type_text)
            .ok_or_else(|| self.err(node, format!("joint `{name}`: unknown type `{type_text}`")))?;
        let (mut xyz, mut rpy) = ([0.0; 3], [0.0; 3]);
        if let Some(origin) = self.child(node, "origin") {
            xyz = self.triple(origin, "xyz")?.unwrap_or(xyz);
            rpy = self.triple(origin, "rpy")?.unwrap_or(rpy);
        }
        let axis = match self.child(node, "axis") {
            Some(a) => self.triple(a, "xyz")?.unwrap_or([1.0, 0.0, 0.0]),
            None => [1.0, 0.0, 0.0],
        };
        let limits = match self.child(node, "limit") {
            Some(l) => {
                let get = |attr: &str| -> Result<f64, UrdfError> {
                    l.attribute(attr)
                        .map_or(Ok(0.0), |t| self.number(l, attr, t))
                };
                let (lower, upper) = (get("lower")?, get("upper")?);
                if lower > upper {
                    return Err(self.err(
                        l,
                        format!("joint `{name}`: limit lower {lower} > upper {upper}"),
                    ));
                }
                Some([lower, upper])
            }
            None => None,
        };
        Ok(UrdfJoint {
            parent: self.link_ref(node, "parent")?,
            child: self.link_ref(node, "child")?,
            name,
            joint_type,
            origin_xyz_m: xyz,
            origin_rpy_rad: rpy,
            axis,
            limits,
            line: self.line_at(node.range().start),
        })
    }
}
