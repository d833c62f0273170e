//! A tree's parameters by name, for a fit over the whole tree: shared constants and joint
//! offsets by their names, the shared base and scale values (`base_x` .. `scale_ppm`), and a
//! tip's own values as `NAME@TIP` (its constants, `tool_dx@TIP` .. `tool_dz@TIP`).

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
                    NAME@TIP for a tip's own constants and tool_dx@TIP .. tool_dz@TIP"
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
