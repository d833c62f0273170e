//! Gravity of the whole tree on every joint: the statics of a [`Tree`] (pinocchio's
//! `computeGeneralizedGravity` at rest, in this crate's units), so that a shared joint (a torso)
//! carries every branch hanging from it.
//!
//! A forward pass places every tree joint's frame (from the tip chains that contain it, [`Tree::chain`],
//! untilted, so the chains' own conventions hold: base elements, joint offsets, encoder terms);
//! a backward pass over the joints in reverse topological order accumulates, per joint, the
//! weight `f` (kgf, frame R) of its own masses and of every descendant's, and their moment `n`
//! about the origin of R; the moment about joint i's origin `o_i` is `n_i - o_i x f_i`,
//! expressed in joint frame i:
//!
//! ```text
//! eta_i = R_i^T sum_{masses m on joints in subtree(i)} (c_m - o_i) x (m g)      kgf.m, g = -z of R
//! ```
//!
//! the same moment, frame and units as a chain's ([`Model::moments_kgfm`]: MODEL.md, 1 kgf per
//! kg), so `eta_i.z` is the torque about the axis that `compliance:j<i>` needs
//! ([`super::GravityModel::axis_torques_kgfm`] on a chain) and `(eta_i.x, eta_i.y)` the
//! moments about the perpendicular axes that lateral compliance needs. For a tree of one chain
//! the two are equal.

use nalgebra::{Matrix3, Vector3};

use super::error::ModelError;
use super::tilt::GRAVITY_KGF_PER_KG;
use super::transmission::compliance_deflection_deg;
use super::tree::Tree;
use super::Model;

/// The world placement of one tree joint's frame: rotation and origin (mm) in R.
#[derive(Debug, Clone, Copy)]
struct JointFrame {
    rot: Matrix3<f64>,
    origin_mm: Vector3<f64>,
}

/// Static gravity moments of the whole tree (kgf.m, joint frame i, tree order) at the tree
/// joints `q` (tree order), with `chains` the tree's tip chains ([`Tree::chains`], in tip
/// order; passed in so that a fit's current chains are used).
pub fn tree_moments_kgfm(
    tree: &Tree,
    chains: &[Model],
    q: &[f64],
) -> Result<Vec<Vector3<f64>>, ModelError> {
    let n = tree.n_joints();
    if q.len() != n {
        return Err(ModelError::JointCount {
            expected: n,
            found: q.len(),
        });
    }
    if chains.len() != tree.tips.len() {
        return Err(ModelError::Invalid(format!(
            "{} chain(s) for a tree of {} tips",
            chains.len(),
            tree.tips.len()
        )));
    }
    // forward: every joint's frame, from the first tip chain through it
    let mut frames: Vec<Option<JointFrame>> = vec![None; n];
    for (t, chain) in chains.iter().enumerate() {
        let path = tree.path(t);
        if path.iter().all(|&j| frames[j].is_some()) {
            continue;
        }
        let q_chain: Vec<f64> = path.iter().map(|&j| q[j]).collect();
        let fr = chain.frames(&q_chain, None)?;
        for (k, &j) in path.iter().enumerate() {
            let e = chain.joints().get(k).map(|cj| cj.elem).ok_or_else(|| {
                ModelError::Invalid(format!("tip {t}: chain shorter than its path"))
            })?;
            frames[j].get_or_insert(JointFrame {
                rot: fr.rot[e],
                origin_mm: fr.pos_mm[e],
            });
        }
    }
    // backward: weight and moment about R's origin of every subtree
    let mut force = vec![Vector3::<f64>::zeros(); n];
    let mut moment = vec![Vector3::<f64>::zeros(); n];
    let mut out = vec![Vector3::zeros(); n];
    for i in (0..n).rev() {
        // a joint on no tip's path moves no tip: it carries its subtree, placed nowhere
        let Some(f) = frames[i] else { continue };
        for m in &tree.joints[i].masses {
            let c_m = (f.rot * Vector3::from(m.com_mm) + f.origin_mm) * 1e-3;
            let w = GRAVITY_KGF_PER_KG * m.mass_kg;
            force[i] += w;
            moment[i] += c_m.cross(&w);
        }
        let about_origin = moment[i] - (f.origin_mm * 1e-3).cross(&force[i]);
        out[i] = f.rot.transpose() * about_origin;
        if let Some(p) = tree.joints[i].parent {
            let (fi, ni) = (force[i], moment[i]);
            force[p] += fi;
            moment[p] += ni;
        }
    }
    Ok(out)
}

/// The joints a tree really takes for the readings `q` (tree order): joint i deflected by its
/// compliance under the whole tree's gravity torque, `q_i + c_i tau_i`
/// ([`compliance_deflection_deg`], the chain's law), and the torques `tau` (kgf.m). Without a
/// compliant joint and unless `torques_needed`, the readings as they are and no torques.
pub fn compliant_joints(
    tree: &Tree,
    chains: &[Model],
    q: &[f64],
    torques_needed: bool,
) -> Result<(Vec<f64>, Vec<f64>), ModelError> {
    if !torques_needed && !tree.has_compliance() {
        return Ok((q.to_vec(), Vec::new()));
    }
    let tau: Vec<f64> = tree_moments_kgfm(tree, chains, q)?
        .iter()
        .map(|m| m.z)
        .collect();
    let c: Vec<f64> = tree
        .joints
        .iter()
        .map(|j| j.compliance_deg_per_kgfm)
        .collect();
    let q_eff = q
        .iter()
        .enumerate()
        .map(|(j, q)| q + compliance_deflection_deg(&c, &tau, j))
        .collect();
    Ok((q_eff, tau))
}

impl Tree {
    /// Static gravity moments of the whole tree at `q` (see the module doc).
    pub fn moments_kgfm(&self, q: &[f64]) -> Result<Vec<Vector3<f64>>, ModelError> {
        tree_moments_kgfm(self, &self.chains()?, q)
    }

    /// Gravity torque about every tree joint's axis (kgf.m, tree order) at `q`: the axis
    /// component of [`Tree::moments_kgfm`], what `compliance:j<i>` of a tree joint sees.
    pub fn axis_torques_kgfm(&self, q: &[f64]) -> Result<Vec<f64>, ModelError> {
        Ok(self.moments_kgfm(q)?.iter().map(|m| m.z).collect())
    }

    /// Whether some tree joint carries a link mass.
    pub fn has_masses(&self) -> bool {
        self.joints.iter().any(|j| !j.masses.is_empty())
    }
}

#[cfg(test)]
mod tests;
