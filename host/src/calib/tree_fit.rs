//! One identification over a tree model ([`crate::model::Tree`]): the joints of the whole tree
//! in every pose, a measured point on any of its tips, and every parameter once, however many
//! tips it moves (a torso's constants are one unknown for both arms, not one per chain).
//!
//! The poses are the one measurement set, a [`MeasuredSet`] of the tree (see
//! `calib/measured/tips.rs`): the joints of the whole tree in every pose and each point slot on
//! a tip ([`MeasuredSet::tip`]), a point a pose leaves unmeasured skipped
//! ([`MeasuredSet::measured_of`]).
//!
//! It is an identification like a chain's, not a solver of its own: the unknowns (tree
//! parameters named as [`Tree::set_param`] names them, `NAME@TIP` for a tip's own values) are a
//! state ([`TreeUnknowns`], written into the tree and every tip's chain), the residual rows are
//! `predicted - measured` of every measured tip point (3 rows each, the rows of a full position,
//! [`put_position_rows`], on the analytic position Jacobian of the tip's chain), and the fit is
//! [`refine`] on it: the identifiability analysis and split of [`super::fit::Split`] (what the
//! poses do not identify is kept at its value and reported, with its combination's name), the
//! solve of [`solve_split`] (Levenberg-Marquardt, sigmas `s^2 (J^T J)^-1`), the rank analysed
//! again at the solution. The result is the one [`Fit`], here `Fit<Tree, String>`.
//!
//! Joint compliance (`compliance_j<i>_deg_per_kgfm`, a chain's `compliance:j<i>` law on tree
//! joint i) deflects joint i by `c_i tau_i` with `tau_i` the gravity torque of the **whole
//! tree** about its axis ([`compliant_joints`]): a torso joint bends under both arms, and every
//! tip whose path holds it sees the bend. Lateral compliance (`lateral_compliance_j<i>_deg_per_kgfm`)
//! bends joint i across its axis under the whole tree's perpendicular moments
//! ([`crate::model::tree_bend`]); its column is the tip's motion per bend angle times those
//! moments (exact: the moments do not depend on it).

use nalgebra::{DMatrix, DVector, Vector3};

use super::error::CalibError;
use super::fit::{solve_split, Fit, Split};
use super::identifiability::analyse;
use super::lm::LmConfig;
use super::measured::MeasuredSet;
use super::plausible::check_set;
use super::position_fit::{refine, Identification};
use super::problem::{put_position_rows, ModelProblem, SetUnknowns};
use crate::model::transmission::compliance_regressor;
use crate::model::tree_bend::{bend, tree_at, TreeAt};
use crate::model::tree_params::{compliance_joint, lateral_joint};
use crate::model::{Data, Model, ModelError, Tree, Wrt};

/// The unknowns of a tree identification: a copy of the tree and of every tip's chain, whose
/// parameters `names` (tree names) are the unknowns; all others stay at their values.
#[derive(Debug, Clone)]
pub struct TreeUnknowns {
    tree: Tree,
    chains: Vec<Model>,
    /// The tree joints of every tip's chain ([`Tree::path`]).
    paths: Vec<Vec<usize>>,
    names: Vec<String>,
    /// Per tip: the chain parameter index of every unknown its chain has (`None`: the unknown
    /// does not move this tip, or is a compliance).
    slots: Vec<Vec<Option<usize>>>,
    /// Per unknown: the tree joint (0-based) whose compliance it is, `None` for a parameter.
    compliance: Vec<Option<usize>>,
    /// Per unknown: the tree joint (0-based) whose lateral compliance it is.
    lateral: Vec<Option<usize>>,
}

impl TreeUnknowns {
    /// The parameters `names` of a copy of `tree` ([`ModelError::UnknownParam`] for a name
    /// the tree does not have).
    pub fn new(tree: &Tree, names: Vec<String>) -> Result<Self, ModelError> {
        if let Some(bad) = names.iter().find(|n| tree.param(n).is_none()) {
            return Err(ModelError::UnknownParam {
                name: bad.clone(),
                valid: "the tree's constants and joint offsets, base_x .. base_ry, scale_ppm, \
                        compliance_j<i>_deg_per_kgfm, lateral_compliance_j<i>_deg_per_kgfm, \
                        NAME@TIP (tool_dx@TIP ..)"
                    .into(),
            });
        }
        let chains = tree.bent_chains()?;
        let slots = chains
            .iter()
            .enumerate()
            .map(|(t, m)| {
                let chain_names: Vec<String> = m
                    .param_names()
                    .map(|n| tree.tree_param_name(t, n))
                    .collect();
                names
                    .iter()
                    .map(|u| chain_names.iter().position(|n| n == u))
                    .collect()
            })
            .collect();
        Ok(Self {
            compliance: names.iter().map(|n| compliance_joint(n)).collect(),
            lateral: names.iter().map(|n| lateral_joint(n)).collect(),
            paths: (0..tree.tips.len()).map(|t| tree.path(t)).collect(),
            tree: tree.clone(),
            chains,
            names,
            slots,
        })
    }

    /// The tree with the unknowns last set.
    pub fn tree(&self) -> &Tree {
        &self.tree
    }

    /// The tree with the unknowns last set.
    pub fn into_tree(self) -> Tree {
        self.tree
    }

    /// The unknowns' current values (a solver's start).
    pub fn values(&self) -> DVector<f64> {
        DVector::from_iterator(
            self.names.len(),
            self.names
                .iter()
                .map(|n| self.tree.param(n).unwrap_or(f64::NAN)),
        )
    }

    /// What every pose's tips are evaluated at ([`tree_at`]): the readings deflected by the
    /// joints' compliances under the whole tree's gravity torques, the torques (when a joint is
    /// compliant or a compliance is an unknown) and the whole tree's moments (when a joint is
    /// laterally compliant or a lateral compliance is an unknown).
    fn effective_joints(&self, q: &[f64]) -> Result<TreeAt, ModelError> {
        let torques = self.compliance.iter().any(Option::is_some);
        let moments = self.lateral.iter().any(Option::is_some);
        tree_at(&self.tree, &self.chains, q, torques, moments)
    }

    /// Residuals `predicted - measured` (3 rows per measured tip point, mm) into `r` and, with
    /// `jac`, their Jacobian wrt the unknowns (`set` checked by [`check_poses`]). A
    /// compliance's column is the tip's motion per joint angle times the joint's torque (the
    /// torques are taken as given by the readings, as on a chain); a lateral compliance's the
    /// chain's [`Wrt::Lateral`] column under the whole tree's moments.
    fn rows(
        &self,
        set: &MeasuredSet,
        r: &mut DVector<f64>,
        mut jac: Option<&mut DMatrix<f64>>,
    ) -> Result<(), ModelError> {
        let n = self.names.len();
        let mut data: Vec<Data> = self.chains.iter().map(Data::new).collect();
        // per tip, what every unknown is for its chain: a parameter, a joint (a compliance of a
        // joint on its path, scaled by the torque), a lateral compliance of a joint on its path,
        // or nothing
        let of_unknown: Vec<Vec<Option<Wrt>>> = self
            .slots
            .iter()
            .zip(&self.paths)
            .map(|(s, path)| {
                s.iter()
                    .zip(self.compliance.iter().zip(&self.lateral))
                    .map(|(slot, joint)| match (slot, joint) {
                        (Some(i), _) => Some(Wrt::Param(*i)),
                        (None, (Some(j), _)) => path.iter().position(|p| p == j).map(Wrt::Joint),
                        (None, (None, Some(j))) => {
                            path.iter().position(|p| p == j).map(Wrt::Lateral)
                        }
                        (None, (None, None)) => None,
                    })
                    .collect()
            })
            .collect();
        let wrt: Vec<Vec<Wrt>> = of_unknown
            .iter()
            .map(|u| u.iter().flatten().copied().collect())
            .collect();
        // per tip, the position of every unknown in its `wrt`
        let column: Vec<Vec<Option<usize>>> = of_unknown
            .iter()
            .map(|s| {
                let mut k = 0;
                s.iter()
                    .map(|i| {
                        i.map(|_| {
                            k += 1;
                            k - 1
                        })
                    })
                    .collect()
            })
            .collect();
        let mut row = 0;
        for (k, q_read) in set.poses.q_deg.iter().enumerate() {
            let at = self.effective_joints(q_read)?;
            let tau = &at.tau_kgfm;
            for point in set.measured_of(k) {
                let t = set.tip(point.slot);
                let q = at.chain_joints(&self.paths[t]);
                let moments = at.chain_moments(&self.paths[t]);
                let (chain, d) = (&self.chains[t], &mut data[t]);
                let measured = point.xyz_mm;
                match jac.as_deref_mut() {
                    Some(jac) => {
                        chain.jacobian_with(d, &q, bend(&moments), &wrt[t])?;
                        let mut columns = (0..n).map(|c| {
                            let scale =
                                self.compliance[c].map_or(1.0, |j| compliance_regressor(tau, j));
                            column[t][c].map_or_else(Vector3::zeros, |k| d.jacobian()[k] * scale)
                        });
                        let jac =
                            Some((jac, &mut columns as &mut dyn Iterator<Item = Vector3<f64>>));
                        put_position_rows(row, &d.position_mm(), &measured, r, jac);
                    }
                    None => {
                        chain.fk_with(d, &q, bend(&moments))?;
                        put_position_rows(row, &d.position_mm(), &measured, r, None);
                    }
                }
                row += 3;
            }
        }
        Ok(())
    }

    /// The stacked Jacobian of the rows of `set` wrt the unknowns.
    pub(crate) fn jacobian(&self, set: &MeasuredSet) -> Result<DMatrix<f64>, ModelError> {
        let m = n_rows(set);
        let mut jac = DMatrix::zeros(m, self.names.len());
        self.rows(set, &mut DVector::zeros(m), Some(&mut jac))?;
        Ok(jac)
    }
}

impl SetUnknowns for TreeUnknowns {
    fn n_unknowns(&self) -> usize {
        self.names.len()
    }

    fn set(&mut self, x: &DVector<f64>) -> Result<(), ModelError> {
        for (k, (name, &v)) in self.names.iter().zip(x.iter()).enumerate() {
            self.tree.set_param(name, v)?;
            for ((chain, slots), path) in self.chains.iter_mut().zip(&self.slots).zip(&self.paths) {
                if let Some(i) = slots[k] {
                    chain.set_param_at(i, v)?;
                }
                // a lateral compliance bends every chain whose path holds its joint
                if let Some(at) = self.lateral[k].and_then(|j| path.iter().position(|p| *p == j)) {
                    chain.set_lateral_compliance(at, v)?;
                }
            }
        }
        Ok(())
    }
}

/// Number of residual rows of `set` (3 per measured tip point).
fn n_rows(set: &MeasuredSet) -> usize {
    3 * set.n_measured_points()
}

/// Checks that `set` is a set of `tree`: full positions, every pose with the tree's joints, and
/// every point slot on a tip of the tree (a set without tips: one point per pose, on a tree of
/// one tip).
pub fn check_poses(tree: &Tree, set: &MeasuredSet) -> Result<(), CalibError> {
    if set.is_serial() {
        return Err(CalibError::Unsupported(
            "a tree model's calibration reads full positions (x,y,z per tip); partial \
             measurements are for a single chain"
                .into(),
        ));
    }
    let tips = tree.tips.len();
    for slot in 0..set.n_slots() {
        let tip = (!set.tips.is_empty() || slot == 0).then(|| set.tip(slot));
        if tip.is_none_or(|t| t >= tips) {
            return Err(CalibError::TreeSlot {
                slot: slot + 1,
                tip,
                tips,
            });
        }
    }
    for (k, q) in set.poses.q_deg.iter().enumerate() {
        if q.len() != tree.n_joints() {
            return Err(CalibError::TreeJoints {
                pose: k + 1,
                expected: tree.n_joints(),
                found: q.len(),
            });
        }
    }
    Ok(())
}

/// Refuses (`CalibError::Implausible`, exit 2) a set whose points on some tip cannot be of
/// that tip's chain as given (a length unit, the angle unit, another robot): a chain's
/// pre-fit check ([`super::plausible::check_set`]) on every tip's measured points
/// ([`MeasuredSet::tip_view`]); `what` names the file.
pub fn check_tree_plausible(tree: &Tree, set: &MeasuredSet, what: &str) -> Result<(), CalibError> {
    check_poses(tree, set)?;
    for (t, chain) in tree.chains()?.iter().enumerate() {
        let view = set.tip_view(t, &tree.path(t));
        let name = &tree.tips[t].name;
        check_set(chain, &view, &format!("{what} (tip `{name}`)"))?;
    }
    Ok(())
}

/// The tree identification: the set, the candidate unknowns (tree names, preference order:
/// of a combination the poses cannot tell apart, the later ones are kept at their values), the
/// solver's settings and the identifiability threshold.
struct TreeIdentification<'a> {
    set: &'a MeasuredSet,
    names: &'a [String],
    selection: Vec<usize>,
    lm: &'a LmConfig,
    rtol: f64,
}

impl TreeIdentification<'_> {
    fn unknowns(&self, tree: &Tree, selection: &[usize]) -> Result<TreeUnknowns, ModelError> {
        let names = selection.iter().map(|&u| self.names[u].clone()).collect();
        TreeUnknowns::new(tree, names)
    }
}

impl Identification for TreeIdentification<'_> {
    type State = Tree;

    fn selection(&self) -> &[usize] {
        &self.selection
    }

    fn once(&self, start: &Tree, selection: &[usize]) -> Result<Fit<Tree, usize>, CalibError> {
        let jac0 = self.unknowns(start, selection)?.jacobian(self.set)?;
        let names: Vec<&str> = selection.iter().map(|&u| self.names[u].as_str()).collect();
        let split = Split::of(selection, &names, &analyse(&jac0, self.rtol)).nonempty()?;
        let state = self.unknowns(start, &split.fitted)?;
        let x0 = state.values();
        let set = self.set;
        let rows = move |s: &TreeUnknowns, r: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>| {
            s.rows(set, r, jac)
        };
        let problem = ModelProblem::new(state, n_rows(set), rows);
        Ok(solve_split(split, problem, x0, self.lm, self.rtol)?.map_model(TreeUnknowns::into_tree))
    }

    fn rank_at(&self, tree: &Tree) -> Result<usize, CalibError> {
        let jac = self.unknowns(tree, &self.selection)?.jacobian(self.set)?;
        Ok(analyse(&jac, self.rtol).rank)
    }

    fn value(&self, tree: &Tree, u: usize) -> f64 {
        tree.param(&self.names[u]).unwrap_or(f64::NAN)
    }

    fn set_value(&self, tree: &mut Tree, u: usize, v: f64) -> Result<(), CalibError> {
        Ok(tree.set_param(&self.names[u], v)?)
    }
}

/// Identifies the parameters `selection` (tree names, preference order) of `tree` from the
/// tree's set `set` (see the module doc): the fitted tree, the fitted and fixed unknowns by name, their sigmas,
/// the unidentifiable combinations, the rank.
pub fn fit_tree(
    tree: &Tree,
    set: &MeasuredSet,
    selection: &[String],
    lm: &LmConfig,
    rtol: f64,
) -> Result<Fit<Tree, String>, CalibError> {
    if set.is_empty() {
        return Err(CalibError::NoPoses);
    }
    if selection.is_empty() {
        return Err(CalibError::EmptySelection);
    }
    check_poses(tree, set)?;
    TreeUnknowns::new(tree, selection.to_vec())?;
    let on = TreeIdentification {
        set,
        names: selection,
        selection: (0..selection.len()).collect(),
        lm,
        rtol,
    };
    Ok(refine(&on, tree)?.map_unknowns(|u| selection[u].clone()))
}

/// Error vectors `measured - model` (mm) of every measured tip point of `set` on `tree`, in
/// pose order, slots in order ([`MeasuredSet::measured_of`]).
pub fn tree_errors(tree: &Tree, set: &MeasuredSet) -> Result<Vec<Vector3<f64>>, CalibError> {
    check_poses(tree, set)?;
    let m = n_rows(set);
    let mut r = DVector::zeros(m);
    TreeUnknowns::new(tree, Vec::new())?.rows(set, &mut r, None)?;
    Ok((0..m / 3)
        .map(|k| -Vector3::new(r[3 * k], r[3 * k + 1], r[3 * k + 2]))
        .collect())
}

/// RMS (mm) of the residual coordinates of `set` on `tree` (e.g. held-out poses).
pub fn tree_rms_mm(tree: &Tree, set: &MeasuredSet) -> Result<f64, CalibError> {
    let e = tree_errors(tree, set)?;
    let ss: f64 = e.iter().map(|v| v.norm_squared()).sum();
    Ok((ss / (3 * e.len()).max(1) as f64).sqrt())
}

#[cfg(test)]
mod tests;
