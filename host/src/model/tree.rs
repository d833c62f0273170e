//! Tree models: several tips from one root, every joint once (docs/model-files.md "Tree
//! models").
//!
//! Laid out as pinocchio lays out a kinematic tree: the joints in topological order, each with
//! the index of its parent joint (`None`: it hangs from the root), and named tips (frames
//! attached to a joint, with their own constants and tool point). Every tip's serial chain, root
//! to tip, is an ordinary [`Model`] ([`Tree::chain`]), so every single-chain algorithm works per
//! tip; [`Tree::from_chains`] builds the tree back from such chains (shared joints found by
//! name, their constants checked equal).
//!
//! The whole tree's joint vector `q` is in tree joint order; [`Tree::path`] gives the tree
//! joints of one tip's chain, in chain order (`q_chain[k] = q[path[k]]`).

use std::collections::{BTreeMap, HashMap, HashSet};

use super::builder::ModelBuilder;
use super::chain::{Axis, Model, Motion};
use super::error::ModelError;
use super::param::ParamKind;

/// A constant elementary transform of a tree: `R<axis>(value)` (deg) or `T<axis>(value)` (mm).
#[derive(Debug, Clone, PartialEq)]
pub struct TreeElem {
    pub motion: Motion,
    pub axis: Axis,
    /// Parameter name (unique in the tree; a tip's own constants are unique within the tip).
    pub name: String,
    pub value: f64,
}

/// A link mass carried by a tree joint, in its joint frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TreeMass {
    pub mass_kg: f64,
    pub com_mm: [f64; 3],
}

/// One joint of the tree.
#[derive(Debug, Clone, PartialEq)]
pub struct TreeJoint {
    /// Joint name (a pose-file column).
    pub name: String,
    /// The joint whose frame [`TreeJoint::before`] starts at; `None`: the end of the root
    /// constants.
    pub parent: Option<usize>,
    /// Constants from the parent's frame to this joint.
    pub before: Vec<TreeElem>,
    /// `Tz(q + offset)` if prismatic (mm), else `Rz(q + offset)` (deg).
    pub prismatic: bool,
    /// Name of the joint-offset parameter.
    pub offset_name: String,
    pub offset: f64,
    /// Limits (deg, mm if prismatic).
    pub limits: [f64; 2],
    /// Link masses in the joint frame.
    pub masses: Vec<TreeMass>,
    /// Axial compliance (deg per kgf.m, mm per kgf.m if prismatic) of the joint under the
    /// gravity torque of the whole tree about its axis ([`Tree::axis_torques_kgfm`]); parameter
    /// `compliance_j<i>_deg_per_kgfm` (i: tree joint number, 1-based). 0: rigid.
    pub compliance_deg_per_kgfm: f64,
    /// Lateral compliance (deg per kgf.m) of the joint: a bend `Rx(c eta_x) . Ry(c eta_y)` in
    /// its joint frame right after the joint's rotation, `eta` the whole tree's gravity moment
    /// ([`Tree::moments_kgfm`], at the axially deflected joints, unbent), the chain's
    /// `lateral_compliance:j<i>` law ([`super::lateral`]); parameter
    /// `lateral_compliance_j<i>_deg_per_kgfm`. 0: rigid across the axis.
    pub lateral_compliance_deg_per_kgfm: f64,
}

/// A tip: a frame after a joint, and the tool point in it.
#[derive(Debug, Clone, PartialEq)]
pub struct Tip {
    /// Tip name (e.g. the URDF link).
    pub name: String,
    /// The joint (tree index) the tip's constants start from.
    pub joint: usize,
    /// Constants from the joint frame to the tip frame (names local to the tip).
    pub after: Vec<TreeElem>,
    /// Tool point in the tip frame (mm): the chain's `tool_dx tool_dy tool_dz`.
    pub tool_mm: [f64; 3],
}

/// A tree model (see the module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct Tree {
    pub name: String,
    /// Constants after the automatic base elements, shared by every branch.
    pub root: Vec<TreeElem>,
    pub joints: Vec<TreeJoint>,
    pub tips: Vec<Tip>,
    /// Values of the automatic parameters shared by every chain (`base_x .. base_ry`,
    /// `scale_ppm`), non-zero ones only.
    pub params: BTreeMap<String, f64>,
    /// Whether the link masses are assumed ([`Tree::with_assumed_masses`]), not declared.
    pub masses_assumed: bool,
}

/// The automatic parameters a tree carries (shared by every tip's chain).
pub const TREE_SHARED_PARAMS: [&str; 6] = [
    "base_x",
    "base_y",
    "base_z",
    "base_rx",
    "base_ry",
    "scale_ppm",
];

fn invalid(message: String) -> ModelError {
    ModelError::Invalid(message)
}

impl Tree {
    /// Number of joints of the whole tree.
    pub fn n_joints(&self) -> usize {
        self.joints.len()
    }

    /// Joint names in tree order.
    pub fn joint_names(&self) -> Vec<String> {
        self.joints.iter().map(|j| j.name.clone()).collect()
    }

    /// Joint limits in tree order.
    pub fn joint_limits(&self) -> Vec<[f64; 2]> {
        self.joints.iter().map(|j| j.limits).collect()
    }

    /// Which joints are prismatic, in tree order.
    pub fn prismatic(&self) -> Vec<bool> {
        self.joints.iter().map(|j| j.prismatic).collect()
    }

    /// The index of the tip named `name`.
    pub fn tip_index(&self, name: &str) -> Result<usize, ModelError> {
        self.tips
            .iter()
            .position(|t| t.name == name)
            .ok_or_else(|| {
                invalid(format!(
                    "no tip `{name}`; the tree's tips: {}",
                    self.tips
                        .iter()
                        .map(|t| t.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })
    }

    /// The tree joints of tip `tip`'s chain, root first.
    pub fn path(&self, tip: usize) -> Vec<usize> {
        let mut path = Vec::new();
        let mut at = self.tips.get(tip).map(|t| t.joint);
        while let Some(j) = at.filter(|j| *j < self.joints.len() && path.len() <= self.joints.len())
        {
            path.push(j);
            at = self.joints[j].parent;
        }
        path.reverse();
        path
    }

    /// Tip `tip`'s serial chain (root to tip) as a single-chain model: the root constants, each
    /// joint's constants and joint, the tip's constants; its masses, joint names, tool point
    /// and the tree's shared parameters.
    pub fn chain(&self, tip: usize) -> Result<Model, ModelError> {
        let t = self
            .tips
            .get(tip)
            .ok_or_else(|| invalid(format!("tip index {tip} out of range")))?;
        let mut b = ModelBuilder::new(&self.name);
        let constants = |b: &mut ModelBuilder, elems: &[TreeElem]| -> Result<(), ModelError> {
            for e in elems {
                b.constant(e.motion, e.axis, &e.name, e.value)?;
            }
            Ok(())
        };
        constants(&mut b, &self.root)?;
        let path = self.path(tip);
        for (k, &j) in path.iter().enumerate() {
            let joint = &self.joints[j];
            constants(&mut b, &joint.before)?;
            b.joint(
                joint.prismatic,
                &joint.offset_name,
                joint.offset,
                joint.limits,
                None,
            )?;
            for m in &joint.masses {
                b.mass(k + 1, 0, m.mass_kg, m.com_mm)?;
            }
        }
        constants(&mut b, &t.after)?;
        let mut model = b.build()?;
        for (name, v) in ["tool_dx", "tool_dy", "tool_dz"].iter().zip(t.tool_mm) {
            model.set_param(name, v)?;
        }
        for (name, v) in &self.params {
            model.set_param(name, *v)?;
        }
        model.set_joint_names(path.iter().map(|&j| self.joints[j].name.clone()).collect())?;
        model.check_ranges().map_err(invalid)?;
        Ok(model)
    }

    /// Every tip's chain, in tip order.
    pub fn chains(&self) -> Result<Vec<Model>, ModelError> {
        (0..self.tips.len()).map(|t| self.chain(t)).collect()
    }

    /// Checks the structure: at least one tip, parents before their children, joint, tip and
    /// shared parameter names distinct, and every tip's chain a valid model.
    pub fn validate(&self) -> Result<(), ModelError> {
        if self.tips.is_empty() {
            return Err(invalid("a tree needs at least one [[tip]]".into()));
        }
        let mut names = HashSet::new();
        for (i, j) in self.joints.iter().enumerate() {
            if j.parent.is_some_and(|p| p >= i) {
                return Err(invalid(format!(
                    "joint {} (`{}`): its parent must come before it",
                    i + 1,
                    j.name
                )));
            }
            if !names.insert(j.name.as_str()) {
                return Err(invalid(format!("joint name `{}` given twice", j.name)));
            }
        }
        let mut params = HashSet::new();
        let shared = self
            .root
            .iter()
            .map(|e| &e.name)
            .chain(self.joints.iter().flat_map(|j| {
                j.before
                    .iter()
                    .map(|e| &e.name)
                    .chain(std::iter::once(&j.offset_name))
            }));
        for n in shared {
            if !params.insert(n.as_str()) {
                return Err(invalid(format!("parameter name `{n}` given twice")));
            }
        }
        let mut tips = HashSet::new();
        for (k, t) in self.tips.iter().enumerate() {
            if t.joint >= self.joints.len() {
                return Err(invalid(format!(
                    "tip `{}`: joint {} does not exist ({} joints)",
                    t.name,
                    t.joint + 1,
                    self.joints.len()
                )));
            }
            if !tips.insert(t.name.as_str()) {
                return Err(invalid(format!("tip name `{}` given twice", t.name)));
            }
            self.chain(k)
                .map_err(|e| invalid(format!("tip `{}`: {e}", t.name)))?;
        }
        Ok(())
    }

    /// The tree of the single-chain models `chains` (tip name, chain): joints shared by name
    /// (a chain without joint names uses the offset parameters' names), the root the constants
    /// every chain starts with. A shared joint must have the same parent, constants, limits and
    /// masses in every chain. Chains with tilting, transmission or time terms, encoder
    /// harmonics or a payload are refused (a tree holds geometry and masses).
    pub fn from_chains(name: &str, chains: &[(String, Model)]) -> Result<Tree, ModelError> {
        let split: Vec<Split> = chains
            .iter()
            .map(|(tip, m)| split_chain(tip, m))
            .collect::<Result<_, _>>()?;
        // the root: the leading constants common to every chain
        let mut root_len = split.first().map_or(0, |s| s.leading.len());
        for s in &split {
            root_len = root_len.min(
                s.leading
                    .iter()
                    .zip(&split[0].leading)
                    .take_while(|(a, b)| a == b)
                    .count(),
            );
        }
        let mut tree = Tree {
            name: name.to_string(),
            root: split
                .first()
                .map(|s| s.leading[..root_len].to_vec())
                .unwrap_or_default(),
            joints: Vec::new(),
            tips: Vec::new(),
            params: BTreeMap::new(),
            masses_assumed: false,
        };
        let mut by_name: HashMap<String, usize> = HashMap::new();
        for (s, (tip, model)) in split.into_iter().zip(chains) {
            let mut parent = None;
            for (k, mut joint) in s.joints.into_iter().enumerate() {
                if k == 0 {
                    let mut before = s.leading[root_len..].to_vec();
                    before.append(&mut joint.before);
                    joint.before = before;
                }
                joint.parent = parent;
                let index = match by_name.get(&joint.name) {
                    Some(&i) => {
                        if tree.joints[i] != joint {
                            return Err(invalid(format!(
                                "joint `{}` differs between the chains (its constants, parent, \
                                 limits or masses): not one tree",
                                joint.name
                            )));
                        }
                        i
                    }
                    None => {
                        by_name.insert(joint.name.clone(), tree.joints.len());
                        tree.joints.push(joint);
                        tree.joints.len() - 1
                    }
                };
                parent = Some(index);
            }
            let joint = parent.ok_or_else(|| invalid(format!("tip `{tip}`: no joint")))?;
            let tool = |n: &str| model.param(n).unwrap_or(0.0);
            tree.tips.push(Tip {
                name: tip.clone(),
                joint,
                after: s.trailing,
                tool_mm: [tool("tool_dx"), tool("tool_dy"), tool("tool_dz")],
            });
            for p in TREE_SHARED_PARAMS {
                let v = model.param(p).unwrap_or(0.0);
                match tree.params.get(p) {
                    Some(&w) if w != v => {
                        return Err(invalid(format!(
                            "`{p}` differs between the chains ({w} and {v})"
                        )))
                    }
                    None if v != 0.0 && tree.tips.len() > 1 => {
                        return Err(invalid(format!(
                            "`{p}` differs between the chains (0 and {v})"
                        )))
                    }
                    _ if v != 0.0 => {
                        tree.params.insert(p.to_string(), v);
                    }
                    _ => {}
                }
            }
        }
        tree.validate()?;
        Ok(tree)
    }
}

/// A chain cut at its joints.
struct Split {
    leading: Vec<TreeElem>,
    /// Each joint with the constants since the previous joint (parent unset).
    joints: Vec<TreeJoint>,
    trailing: Vec<TreeElem>,
}

fn split_chain(tip: &str, m: &Model) -> Result<Split, ModelError> {
    let refuse = |what: &str| {
        invalid(format!(
            "tip `{tip}`: a tree holds geometry and masses; this chain has {what}"
        ))
    };
    if m.has_tilt() {
        return Err(refuse("joint tilting"));
    }
    if m.transmission.is_active() {
        return Err(refuse("transmission terms"));
    }
    if m.has_lateral_compliance() {
        return Err(refuse("lateral compliance"));
    }
    if m.time_terms().is_active() {
        return Err(refuse("time terms"));
    }
    if m.params().iter().any(|p| {
        matches!(p.kind, ParamKind::EncoderHarmonic | ParamKind::Payload) && p.value != 0.0
    }) {
        return Err(refuse("encoder harmonics or a payload"));
    }
    if m.masses().iter().any(|p| p.after != 0) {
        return Err(refuse("a mass past a joint frame"));
    }
    let mut current = Vec::new();
    let mut leading = None;
    let mut joints = Vec::new();
    for e in &m.elems[m.robot_elems.clone()] {
        let p = &m.params[e.param];
        let Some(j) = e.joint else {
            current.push(TreeElem {
                motion: e.motion,
                axis: e.axis,
                name: p.name.clone(),
                value: p.value,
            });
            continue;
        };
        if leading.is_none() {
            leading = Some(std::mem::take(&mut current));
        }
        let joint = &m.joints[j];
        joints.push(TreeJoint {
            name: m
                .joint_names()
                .get(j)
                .cloned()
                .unwrap_or_else(|| p.name.clone()),
            parent: None,
            before: std::mem::take(&mut current),
            prismatic: joint.prismatic,
            offset_name: p.name.clone(),
            offset: p.value,
            limits: joint.limits,
            masses: m
                .masses()
                .iter()
                .filter(|pm| pm.joint == j)
                .map(|pm| TreeMass {
                    mass_kg: pm.mass_kg,
                    com_mm: pm.com_mm.into(),
                })
                .collect(),
            compliance_deg_per_kgfm: 0.0,
            lateral_compliance_deg_per_kgfm: 0.0,
        });
    }
    Ok(Split {
        leading: leading.unwrap_or_default(),
        joints,
        trailing: current,
    })
}

#[cfg(test)]
pub(crate) mod test_support;
#[cfg(test)]
mod tests;
