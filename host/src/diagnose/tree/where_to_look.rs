//! Where to look when a tree's final residual stays above its floor: the chain's regressor scan
//! ([`crate::diagnose::residual::explain`]) on every tip's residual. The regressors of tree joint
//! `i` are `q<i>` and `sin/cos(h q<i>)` for h = 1..3 (revolute joints), as on a chain; each tip's
//! measured points are regressed apart (one tip's residual is not the other's), and a
//! regressor's share is the residual variance it explains in sample over every tip together
//! (each tip's share weighted by its residual sum of squares). The shares go to
//! [`crate::diagnose::report::Unexplained::add_where_to_look`], which names the joints that
//! explain most.

use nalgebra::Vector3;

use crate::calib::MeasuredSet;
use crate::diagnose::residual::{explain, joint_regressors, Regressor};
use crate::model::Tree;

/// The regressors of the tree's joints over the points `rows` (pose index of each point): a
/// chain's per joint ([`joint_regressors`]).
fn tree_joint_regressors(tree: &Tree, set: &MeasuredSet, rows: &[usize]) -> Vec<Regressor> {
    let mut out = Vec::new();
    for (j, joint) in tree.joints.iter().enumerate() {
        let q: Option<Vec<f64>> = rows
            .iter()
            .map(|&k| set.poses.q_deg.get(k).and_then(|q| q.get(j)).copied())
            .collect();
        if let Some(q) = q {
            out.extend(joint_regressors(j, &q, joint.prismatic));
        }
    }
    out
}

/// The in-sample share of the residual `residual` (the error vectors of `set`'s measured tip
/// points, in [`crate::calib::tree_fit::tree_errors`]' order) each joint regressor explains,
/// over every tip together (see the module doc).
pub fn tree_regressor_shares(
    tree: &Tree,
    set: &MeasuredSet,
    residual: &[Vector3<f64>],
) -> Vec<(String, f64)> {
    // (pose, tip) of every residual point, in order
    let at: Vec<(usize, usize)> = (0..set.len())
        .flat_map(|k| set.measured_of(k).map(move |m| (k, set.tip(m.slot))))
        .collect();
    if at.len() != residual.len() {
        return Vec::new();
    }
    let total: f64 = residual.iter().map(|e| e.norm_squared()).sum();
    if total <= 0.0 {
        return Vec::new();
    }
    let mut shares: Vec<(String, f64)> = Vec::new();
    for tip in 0..tree.tips.len() {
        let idx: Vec<usize> = (0..at.len()).filter(|&i| at[i].1 == tip).collect();
        let v: Vec<Vector3<f64>> = idx.iter().map(|&i| residual[i]).collect();
        let rows: Vec<usize> = idx.iter().map(|&i| at[i].0).collect();
        let weight = v.iter().map(|e| e.norm_squared()).sum::<f64>() / total;
        for reg in tree_joint_regressors(tree, set, &rows) {
            let e = explain(&v, &reg);
            let share = weight * if e.r2.is_finite() { e.r2 } else { 0.0 };
            match shares.iter_mut().find(|(n, _)| *n == reg.name) {
                Some((_, s)) => *s += share,
                None => shares.push((reg.name, share)),
            }
        }
    }
    shares
}
