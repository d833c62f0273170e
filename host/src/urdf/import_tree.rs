//! Several chains of a URDF from one base link as a [`Tree`] (`rigctl urdf2model --tip A --tip
//! B`): each tip's chain is imported as [`super::import`] imports one chain (same structure and
//! parameter names), and the chains are joined at their shared joints ([`Tree::from_chains`]).
//! Link masses: every movable joint of the tree carries the `<inertial>` masses of the links it
//! moves rigidly up to the next movable joint of the *tree* (so a torso joint carries the torso,
//! and each arm's links are carried by the arm's own joints); links before the first movable
//! joint are not carried.

use super::error::UrdfError;
use super::import::{import_chain_stopping_at, param_stem, ImportOptions};
use super::parse::{JointType, Urdf};
use crate::model::Tree;

/// One tip to import: its link and the tool point in its frame (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TipLink<'a> {
    pub link: &'a str,
    pub tool_mm: [f64; 3],
}

/// The tree of the chains `base_link` (default: the root link) .. every tip link; tips are named
/// by their links.
pub fn import_tree(
    urdf: &Urdf,
    base_link: Option<&str>,
    tips: &[TipLink],
) -> Result<Tree, UrdfError> {
    let model_err = |source| UrdfError::Model {
        source_name: urdf.source_name.clone(),
        source,
    };
    let mut stop: Vec<&str> = Vec::new();
    for t in tips {
        for j in urdf.chain(base_link, t.link)? {
            if j.joint_type != JointType::Fixed && !stop.contains(&j.name.as_str()) {
                stop.push(j.name.as_str());
            }
        }
    }
    let mut chains = Vec::with_capacity(tips.len());
    for t in tips {
        let imported = import_chain_stopping_at(
            urdf,
            &ImportOptions {
                base_link,
                tip_link: t.link,
                tool_mm: t.tool_mm,
            },
            &stop,
        )?;
        chains.push((t.link.to_string(), imported.model));
    }
    Tree::from_chains(&param_stem(&urdf.robot_name), &chains).map_err(model_err)
}
