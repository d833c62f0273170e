//! Tree model files (TOML; docs/model-files.md "Tree models"): a [`Tree`] read and written.
//!
//! ```toml
//! name = "talos"
//!
//! [[root]]                 # constants after the base elements, shared by every branch
//! op = "rz"
//! name = "base_rz"
//! value = 0.0
//!
//! [[chain]]                # as in a chain file: constants, then the joint they lead to
//! op = "tz"
//! name = "torso_1_joint_z"
//! value = -22.3
//!
//! [[chain]]
//! op = "rz"
//! joint = 1                # joints numbered 1..N in tree order
//! name = "torso_1_joint_offset"
//! value = 0.0
//!
//! [[joint]]
//! name = "torso_1_joint"   # required in a tree: the pose-file column
//! parent = 0               # 0: the constants start after the root's; k: after joint k's frame
//! min = -75.0              # (default: the previous joint, as in a chain)
//! max = 75.0
//! compliance_deg_per_kgfm = 0.0  # optional: deflection per kgf.m of the whole tree's gravity
//! lateral_compliance_deg_per_kgfm = 0.0  # optional: bend across the axis, same moments
//!
//! [[mass]]                 # in the joint frame (after = 0 only)
//! joint = 1
//! kg = 3.0
//! com_mm = [0.0, 0.0, 100.0]
//!
//! [[tip]]                  # one per tip, in the order of the pose files' x1.., x2..
//! name = "gripper_left_base_link"
//! joint = 9                # the joint the tip's constants start from
//! tool_mm = [0.0, 0.0, 0.0]
//!
//! [[tip.chain]]            # the tip's own constants (names local to the tip)
//! op = "tx"
//! name = "tip_x"
//! value = 12.0
//!
//! [params]                 # base_x .. base_ry, scale_ppm (shared by every tip)
//! base_z = 1000.0
//! ```
//!
//! A file is a tree file when it has `[[tip]]` tables ([`is_tree_text`]); a chain file (no
//! `[[tip]]`) is read by [`Model::from_toml_str`](super::Model::from_toml_str) as before.

use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use super::chain::{Axis, Motion};
use super::error::ModelError;
use super::toml_file::parse_axis_op;
use super::toml_write::{fmt_f64, op_name, toml_string};
use super::tree::{Tip, Tree, TreeElem, TreeJoint, TreeMass, TREE_SHARED_PARAMS};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TreeFile {
    name: String,
    #[serde(default)]
    root: Vec<ElemEntry>,
    #[serde(default)]
    chain: Vec<ElemEntry>,
    #[serde(default)]
    joint: Vec<JointEntry>,
    #[serde(default)]
    mass: Vec<MassEntry>,
    tip: Vec<TipEntry>,
    #[serde(default)]
    params: BTreeMap<String, f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ElemEntry {
    op: String,
    name: String,
    #[serde(default)]
    value: f64,
    joint: Option<usize>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct JointEntry {
    name: String,
    parent: Option<usize>,
    min: f64,
    max: f64,
    #[serde(default)]
    compliance_deg_per_kgfm: f64,
    #[serde(default)]
    lateral_compliance_deg_per_kgfm: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MassEntry {
    joint: usize,
    #[serde(default)]
    after: usize,
    kg: f64,
    com_mm: [f64; 3],
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TipEntry {
    name: String,
    joint: usize,
    #[serde(default)]
    tool_mm: [f64; 3],
    #[serde(default)]
    chain: Vec<ElemEntry>,
}

/// A model file's text (capped as every model file).
fn read_model_text(path: &Path) -> Result<String, ModelError> {
    crate::io::read::read_text_capped(path, crate::io::read::CAP_SMALL_TEXT).map_err(|source| {
        ModelError::Read {
            path: path.to_path_buf(),
            source,
        }
    })
}

/// Whether a model file's text is a tree file (it has `[[tip]]` tables). Text that is not TOML
/// is not a tree file (the chain reader reports its error).
pub fn is_tree_text(text: &str) -> bool {
    text.parse::<toml::Table>()
        .is_ok_and(|t| t.contains_key("tip"))
}

fn constant(e: &ElemEntry, at: &str) -> Result<TreeElem, String> {
    if e.joint.is_some() {
        return Err(format!("{at}: a joint belongs in [[chain]]"));
    }
    let (motion, axis) = parse_axis_op(&e.op)
        .ok_or_else(|| format!("{at}: op \"{}\": use rx ry rz tx ty tz", e.op))?;
    if !e.value.is_finite() {
        return Err(format!("{at}: value = {} is not finite", e.value));
    }
    Ok(TreeElem {
        motion,
        axis,
        name: e.name.clone(),
        value: e.value,
    })
}

fn build(f: TreeFile) -> Result<Tree, String> {
    let root = f
        .root
        .iter()
        .enumerate()
        .map(|(n, e)| constant(e, &format!("root entry {}", n + 1)))
        .collect::<Result<Vec<_>, _>>()?;
    let mut joints: Vec<TreeJoint> = Vec::new();
    let mut pending = Vec::new();
    for (n, e) in f.chain.iter().enumerate() {
        let at = format!("chain entry {} (op = \"{}\")", n + 1, e.op);
        let Some(j) = e.joint else {
            pending.push(constant(e, &at)?);
            continue;
        };
        let expected = joints.len() + 1;
        if j != expected {
            return Err(format!(
                "{at}: joint {j}: joints must come in order, expected {expected}"
            ));
        }
        let prismatic = match parse_axis_op(&e.op) {
            Some((Motion::Rot, Axis::Z)) => false,
            Some((Motion::Trans, Axis::Z)) => true,
            _ => return Err(format!("{at}: a joint is rz (revolute) or tz (prismatic)")),
        };
        let info = f
            .joint
            .get(j - 1)
            .ok_or_else(|| format!("{at}: joint {j} has no [[joint]] entry"))?;
        let parent = match info.parent {
            None => joints.len().checked_sub(1),
            Some(0) => None,
            Some(p) if p < j => Some(p - 1),
            Some(p) => {
                return Err(format!(
                    "[[joint]] {j} (`{}`): parent = {p}: a parent comes before its joint",
                    info.name
                ))
            }
        };
        if !e.value.is_finite() {
            return Err(format!("{at}: value = {} is not finite", e.value));
        }
        for (key, v) in [
            ("compliance_deg_per_kgfm", info.compliance_deg_per_kgfm),
            (
                "lateral_compliance_deg_per_kgfm",
                info.lateral_compliance_deg_per_kgfm,
            ),
        ] {
            if !v.is_finite() {
                return Err(format!(
                    "[[joint]] {j} (`{}`): {key} is not finite",
                    info.name
                ));
            }
        }
        joints.push(TreeJoint {
            name: info.name.clone(),
            parent,
            before: std::mem::take(&mut pending),
            prismatic,
            offset_name: e.name.clone(),
            offset: e.value,
            limits: [info.min, info.max],
            masses: Vec::new(),
            compliance_deg_per_kgfm: info.compliance_deg_per_kgfm,
            lateral_compliance_deg_per_kgfm: info.lateral_compliance_deg_per_kgfm,
        });
    }
    if !pending.is_empty() {
        return Err(
            "[[chain]] entries after the last joint: in a tree, a tip's constants go in its \
             [[tip.chain]] entries"
                .into(),
        );
    }
    if f.joint.len() != joints.len() {
        return Err(format!(
            "{} [[joint]] entries for {} joints in the chain",
            f.joint.len(),
            joints.len()
        ));
    }
    for (n, m) in f.mass.iter().enumerate() {
        let at = format!("mass entry {}", n + 1);
        if m.after != 0 {
            return Err(format!(
                "{at}: after = {}: a tree's masses are in their joint frame (after = 0)",
                m.after
            ));
        }
        let joint = m
            .joint
            .checked_sub(1)
            .and_then(|j| joints.get_mut(j))
            .ok_or_else(|| format!("{at}: joint {} does not exist", m.joint))?;
        joint.masses.push(TreeMass {
            mass_kg: m.kg,
            com_mm: m.com_mm,
        });
    }
    let mut tips = Vec::new();
    for (n, t) in f.tip.iter().enumerate() {
        let at = format!("tip entry {} (`{}`)", n + 1, t.name);
        let joint = t
            .joint
            .checked_sub(1)
            .filter(|j| *j < joints.len())
            .ok_or_else(|| format!("{at}: joint {} does not exist", t.joint))?;
        let after = t
            .chain
            .iter()
            .enumerate()
            .map(|(k, e)| constant(e, &format!("{at} chain entry {}", k + 1)))
            .collect::<Result<Vec<_>, _>>()?;
        tips.push(Tip {
            name: t.name.clone(),
            joint,
            after,
            tool_mm: t.tool_mm,
        });
    }
    for name in f.params.keys() {
        if !TREE_SHARED_PARAMS.contains(&name.as_str()) {
            return Err(format!(
                "[params] `{name}`: a tree file sets {} here; the other values are in the \
                 entries",
                TREE_SHARED_PARAMS.join(", ")
            ));
        }
    }
    let tree = Tree {
        name: f.name,
        root,
        joints,
        tips,
        params: f.params.into_iter().filter(|(_, v)| *v != 0.0).collect(),
        masses_assumed: false,
    };
    tree.validate().map_err(|e| e.to_string())?;
    Ok(tree)
}

fn write_elem(s: &mut String, table: &str, e: &TreeElem) {
    let _ = writeln!(
        s,
        "\n[[{table}]]\nop = \"{}\"\nname = {}\nvalue = {}",
        op_name(e.motion, e.axis),
        toml_string(&e.name),
        fmt_f64(e.value)
    );
}

impl Tree {
    /// Parses a tree model file's text; `source` names it in error messages.
    pub fn from_toml_str(text: &str, source: &str) -> Result<Tree, ModelError> {
        let file_err = |message: String| ModelError::File {
            file: source.to_string(),
            message,
        };
        let file: TreeFile = toml::from_str(text).map_err(|e| file_err(e.to_string()))?;
        build(file).map_err(file_err)
    }

    /// Reads a tree model file.
    pub fn from_file(path: &Path) -> Result<Tree, ModelError> {
        let text = read_model_text(path)?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// Reads `path` as a tree model file when it is one (it has `[[tip]]` tables); `None` for
    /// any other file (a chain's model file: its own reader reports its errors).
    pub fn from_file_if_tree(path: &Path) -> Result<Option<Tree>, ModelError> {
        let text = read_model_text(path)?;
        if !is_tree_text(&text) {
            return Ok(None);
        }
        Self::from_toml_str(&text, &path.display().to_string()).map(Some)
    }

    /// The tree as a tree model file (reads back to the identical tree).
    pub fn to_toml_string(&self) -> String {
        let mut s = String::from(
            "# rigctl tree model file (format: docs/model-files.md \"Tree models\")\n",
        );
        let _ = writeln!(s, "name = {}", toml_string(&self.name));
        for e in &self.root {
            write_elem(&mut s, "root", e);
        }
        for (i, j) in self.joints.iter().enumerate() {
            for e in &j.before {
                write_elem(&mut s, "chain", e);
            }
            let _ = writeln!(
                s,
                "\n[[chain]]\nop = \"{}\"\njoint = {}\nname = {}\nvalue = {}",
                if j.prismatic { "tz" } else { "rz" },
                i + 1,
                toml_string(&j.offset_name),
                fmt_f64(j.offset)
            );
        }
        for j in &self.joints {
            let _ = writeln!(
                s,
                "\n[[joint]]\nname = {}\nparent = {}\nmin = {}\nmax = {}",
                toml_string(&j.name),
                j.parent.map_or(0, |p| p + 1),
                fmt_f64(j.limits[0]),
                fmt_f64(j.limits[1])
            );
            if j.compliance_deg_per_kgfm != 0.0 {
                let _ = writeln!(
                    s,
                    "compliance_deg_per_kgfm = {}",
                    fmt_f64(j.compliance_deg_per_kgfm)
                );
            }
            if j.lateral_compliance_deg_per_kgfm != 0.0 {
                let _ = writeln!(
                    s,
                    "lateral_compliance_deg_per_kgfm = {}",
                    fmt_f64(j.lateral_compliance_deg_per_kgfm)
                );
            }
        }
        if self.masses_assumed && self.has_masses() {
            s.push_str(
                "\n# The link masses below are ASSUMED by rigctl (the model declared none): one per\n\
                 # segment from a joint to each child joint or tip, mid-segment, in proportion to\n\
                 # the segment lengths. Replace them with the robot's own masses for compliance\n\
                 # values in real units.\n",
            );
        }
        for (i, j) in self.joints.iter().enumerate() {
            for m in &j.masses {
                let [x, y, z] = m.com_mm;
                let _ = writeln!(
                    s,
                    "\n[[mass]]\njoint = {}\nafter = 0\nkg = {}\ncom_mm = [{}, {}, {}]",
                    i + 1,
                    fmt_f64(m.mass_kg),
                    fmt_f64(x),
                    fmt_f64(y),
                    fmt_f64(z)
                );
            }
        }
        for t in &self.tips {
            let [x, y, z] = t.tool_mm;
            let _ = writeln!(
                s,
                "\n[[tip]]\nname = {}\njoint = {}\ntool_mm = [{}, {}, {}]",
                toml_string(&t.name),
                t.joint + 1,
                fmt_f64(x),
                fmt_f64(y),
                fmt_f64(z)
            );
            for e in &t.after {
                write_elem(&mut s, "tip.chain", e);
            }
        }
        let _ = writeln!(s, "\n[params]");
        for (name, v) in &self.params {
            let _ = writeln!(s, "{name} = {}", fmt_f64(*v));
        }
        s
    }

    /// Writes [`Tree::to_toml_string`] to `path` atomically.
    pub fn write_file(&self, path: &Path) -> Result<(), ModelError> {
        crate::io::atomic::write_text_atomic(
            path,
            crate::io::finite::TextFormat::Toml,
            &self.to_toml_string(),
        )?;
        Ok(())
    }
}
