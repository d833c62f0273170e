//! A tree's parameters by name, for a fit over the whole tree: shared constants and joint
//! offsets by their names, the shared base and scale values (`base_x` .. `scale_ppm`), and a
//! tip's own values as `NAME@TIP` (its constants, `tool_dx@TIP` .. `tool_dz@TIP`), and the
//! axial compliance of tree joint i as `compliance_j<i>_deg_per_kgfm` and its lateral
//! compliance as `lateral_compliance_j<i>_deg_per_kgfm` (i 1-based, tree order; a chain's
//! model-file keys for the same laws).

/// The name of tree joint `j`'s compliance (0-based `j`).
pub fn compliance_name(j: usize) -> String {
    format!("compliance_j{}_deg_per_kgfm", j + 1)
}

/// The tree joint (0-based) whose compliance `name` is, if it is a compliance name.
pub fn compliance_joint(name: &str) -> Option<usize> {
    let i: usize = name
        .strip_prefix("compliance_j")?
        .strip_suffix("_deg_per_kgfm")?
        .parse()
        .ok()?;
    i.checked_sub(1)
}

/// The name of tree joint `j`'s lateral compliance (0-based `j`).
pub fn lateral_name(j: usize) -> String {
    format!("lateral_compliance_j{}_deg_per_kgfm", j + 1)
}

/// The tree joint (0-based) whose lateral compliance `name` is, if it is such a name.
pub fn lateral_joint(name: &str) -> Option<usize> {
    compliance_joint(name.strip_prefix("lateral_")?)
}

use super::error::ModelError;
use super::tree::{Tree, TREE_SHARED_PARAMS};

impl Tree {
    /// The value of parameter `name` (see the module doc), `None` if the tree has none.
    pub fn param(&self, name: &str) -> Option<f64> {
        let mut t = self.clone();
        t.slot(name).map(|v| *v)
    }

    /// Sets parameter `name` (see the module doc) to a finite `value`.
    pub fn set_param(&mut self, name: &str, value: f64) -> Result<(), ModelError> {
        if !value.is_finite() {
            return Err(ModelError::NonFinite {
                name: name.to_string(),
                value,
            });
        }
        let slot = self.slot(name).ok_or_else(|| ModelError::UnknownParam {
            name: name.to_string(),
            valid: "the tree's constants and joint offsets, base_x .. base_ry, scale_ppm, \
                    compliance_j<i>_deg_per_kgfm, lateral_compliance_j<i>_deg_per_kgfm, NAME@TIP for a tip's own constants and tool_dx@TIP .. tool_dz@TIP"
                .into(),
        })?;
        *slot = value;
        if TREE_SHARED_PARAMS.contains(&name) && value == 0.0 {
            self.params.remove(name);
        }
        Ok(())
    }

    fn slot(&mut self, name: &str) -> Option<&mut f64> {
        if let Some((local, tip)) = name.split_once('@') {
            let t = self.tips.iter_mut().find(|t| t.name == tip)?;
            return match local {
                "tool_dx" => Some(&mut t.tool_mm[0]),
                "tool_dy" => Some(&mut t.tool_mm[1]),
                "tool_dz" => Some(&mut t.tool_mm[2]),
                _ => t
                    .after
                    .iter_mut()
                    .find(|e| e.name == local)
                    .map(|e| &mut e.value),
            };
        }
        if let Some(j) = lateral_joint(name) {
            return self
                .joints
                .get_mut(j)
                .map(|j| &mut j.lateral_compliance_deg_per_kgfm);
        }
        if let Some(j) = compliance_joint(name) {
            return self
                .joints
                .get_mut(j)
                .map(|j| &mut j.compliance_deg_per_kgfm);
        }
        if TREE_SHARED_PARAMS.contains(&name) {
            return Some(self.params.entry(name.to_string()).or_insert(0.0));
        }
        if let Some(e) = self.root.iter_mut().find(|e| e.name == name) {
            return Some(&mut e.value);
        }
        for j in &mut self.joints {
            if j.offset_name == name {
                return Some(&mut j.offset);
            }
            if let Some(e) = j.before.iter_mut().find(|e| e.name == name) {
                return Some(&mut e.value);
            }
        }
        None
    }

    /// The compliance parameters of every revolute tree joint (`compliance_j<i>_deg_per_kgfm`,
    /// tree order): what `calibrate --compliance` frees on a tree.
    pub fn compliance_names(&self) -> Vec<String> {
        (0..self.joints.len())
            .filter(|&j| !self.joints[j].prismatic)
            .map(compliance_name)
            .collect()
    }

    /// The lateral compliance parameters of every revolute tree joint
    /// (`lateral_compliance_j<i>_deg_per_kgfm`, tree order): what `calibrate --compliance` frees
    /// on a tree after the axial ones.
    pub fn lateral_names(&self) -> Vec<String> {
        (0..self.joints.len())
            .filter(|&j| !self.joints[j].prismatic)
            .map(lateral_name)
            .collect()
    }

    /// Whether some tree joint has a non-zero lateral compliance.
    pub fn has_lateral_compliance(&self) -> bool {
        self.joints
            .iter()
            .any(|j| j.lateral_compliance_deg_per_kgfm != 0.0)
    }

    /// Whether some tree joint has a non-zero compliance.
    pub fn has_compliance(&self) -> bool {
        self.joints.iter().any(|j| j.compliance_deg_per_kgfm != 0.0)
    }

    /// The name parameter `chain_param` of tip `tip`'s chain has in the tree: a tip's own
    /// constants and tool point as `NAME@TIP`, the others as they are.
    pub fn tree_param_name(&self, tip: usize, chain_param: &str) -> String {
        let local = self.tips.get(tip).is_some_and(|t| {
            matches!(chain_param, "tool_dx" | "tool_dy" | "tool_dz")
                || t.after.iter().any(|e| e.name == chain_param)
        });
        match (local, self.tips.get(tip)) {
            (true, Some(t)) => format!("{chain_param}@{}", t.name),
            _ => chain_param.to_string(),
        }
    }
}
