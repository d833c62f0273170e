//! A tree at one pose, as its compliances make it: the joints deflected about their axes by
//! the whole tree's gravity torques (`compliance_j<i>`, [`compliant_joints`]) and the moments
//! its laterally compliant joints bend under (`lateral_compliance_j<i>`), so that a torso joint
//! bends under both arms and every tip whose path holds it sees the bend.
//!
//! The lateral law is a chain's ([`super::lateral`]): joint i bends by `Rx(c_i eta_x) .
//! Ry(c_i eta_y)` in its joint frame right after its rotation, `eta_i` the static gravity
//! moment (kgf.m, joint frame i). On a tree, `eta_i` is the **whole tree's**
//! ([`tree_moments_kgfm`]), taken as a chain takes its own: on the unbent tree, at the joints
//! the tree really takes (the readings deflected axially). Every tip's chain is evaluated with
//! [`Tilt::Bend`] on those moments and the lateral compliances of its path
//! ([`Tree::bent_chains`]); a tree of one chain gives the chain's own result.

use nalgebra::Vector3;

use super::error::ModelError;
use super::kinematics::Tilt;
use super::tree::Tree;
use super::tree_gravity::{compliant_joints, tree_moments_kgfm};
use super::Model;

/// One pose of a tree: what every tip's chain is evaluated at.
#[derive(Debug, Clone, PartialEq)]
pub struct TreeAt {
    /// The joints the tree takes (tree order): the readings deflected by the axial
    /// compliances.
    pub q_eff: Vec<f64>,
    /// The whole tree's gravity torques about the axes at the readings (kgf.m, tree order;
    /// empty when not asked for and no joint is compliant about its axis).
    pub tau_kgfm: Vec<f64>,
    /// The whole tree's static moments at `q_eff` (kgf.m, joint frame i, tree order; empty when
    /// not asked for and no joint is laterally compliant).
    pub eta_kgfm: Vec<Vector3<f64>>,
}

impl TreeAt {
    /// The joints of the chain whose tree joints are `path` ([`Tree::path`]).
    pub fn chain_joints(&self, path: &[usize]) -> Vec<f64> {
        path.iter().map(|&j| self.q_eff[j]).collect()
    }

    /// The moments along `path` (empty without moments): [`bend`] makes the chain's tilt.
    pub fn chain_moments(&self, path: &[usize]) -> Vec<Vector3<f64>> {
        if self.eta_kgfm.is_empty() {
            return Vec::new();
        }
        path.iter().map(|&j| self.eta_kgfm[j]).collect()
    }
}

/// The tilt a tip's chain is evaluated with: [`Tilt::Bend`] on `moments`
/// ([`TreeAt::chain_moments`]), [`Tilt::Off`] without them.
pub fn bend(moments: &[Vector3<f64>]) -> Tilt<'_> {
    if moments.is_empty() {
        Tilt::Off
    } else {
        Tilt::Bend(moments)
    }
}

/// The tree `tree` at the readings `q` (tree order), with `chains` its tip chains (passed in so
/// that a fit's current chains are used): the torques when `torques_needed` or some joint is
/// compliant about its axis, the moments when `moments_needed` or some joint is laterally
/// compliant.
pub fn tree_at(
    tree: &Tree,
    chains: &[Model],
    q: &[f64],
    torques_needed: bool,
    moments_needed: bool,
) -> Result<TreeAt, ModelError> {
    let (q_eff, tau_kgfm) = compliant_joints(tree, chains, q, torques_needed)?;
    let eta_kgfm = if moments_needed || tree.has_lateral_compliance() {
        tree_moments_kgfm(tree, chains, &q_eff)?
    } else {
        Vec::new()
    };
    Ok(TreeAt {
        q_eff,
        tau_kgfm,
        eta_kgfm,
    })
}

impl Tree {
    /// Every tip's chain ([`Tree::chains`]) with the lateral compliances of the joints on its
    /// path: evaluated with [`bend`] on a [`TreeAt`]'s moments (never alone: on its own moments
    /// a chain would bend under its own branch only).
    pub fn bent_chains(&self) -> Result<Vec<Model>, ModelError> {
        let mut chains = self.chains()?;
        for (t, chain) in chains.iter_mut().enumerate() {
            for (k, &j) in self.path(t).iter().enumerate() {
                let c = self.joints[j].lateral_compliance_deg_per_kgfm;
                if c != 0.0 {
                    chain.set_lateral_compliance(k, c)?;
                }
            }
        }
        Ok(chains)
    }

    /// The tool point (mm, R) of every tip at the readings `q` (tree order), compliances
    /// applied (see the module doc).
    pub fn tip_points_mm(&self, q: &[f64]) -> Result<Vec<Vector3<f64>>, ModelError> {
        let chains = self.bent_chains()?;
        let at = tree_at(self, &chains, q, false, false)?;
        chains
            .iter()
            .enumerate()
            .map(|(t, chain)| {
                let path = self.path(t);
                let m = at.chain_moments(&path);
                Ok(chain.fk(&at.chain_joints(&path), bend(&m))?.position_mm)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests;
