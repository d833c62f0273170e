//! One least-squares fit over a tree model ([`crate::model::Tree`]): the joints of the whole
//! tree in every pose, a measured point on any of its tips, and every parameter once, however
//! many tips it moves (a torso's constants are one unknown for both arms, not one per chain).
//!
//! Gauss-Newton on the analytic position Jacobians of the tips' chains
//! ([`crate::model::Model::param_jacobian`]), columns scaled to unit norm and solved by SVD;
//! the unknowns are named as [`Tree::set_param`] names them (`NAME@TIP` for a tip's own
//! values). A selection the poses cannot identify (a singular value below 1e-9 of the largest)
//! is refused, naming the worst-determined unknown. Sigmas: `s^2 (J^T J)^-1`,
//! `s^2 = RSS / (m - n)`.

use nalgebra::{DMatrix, DVector, Vector3};

use crate::model::{Model, ModelError, Tilt, Tree};

/// A pose of the whole tree: its joints (tree order; deg, mm for prismatic joints) and the
/// measured point of each tip (mm in frame R), `None` where a tip was not measured.
#[derive(Debug, Clone, PartialEq)]
pub struct TreePose {
    pub q: Vec<f64>,
    pub points_mm: Vec<Option<[f64; 3]>>,
}

/// The result of [`fit_tree`].
#[derive(Debug, Clone, PartialEq)]
pub struct TreeFit {
    /// The tree with the fitted values.
    pub tree: Tree,
    /// The unknowns, their fitted values and one-sigma uncertainties (their units: deg / mm).
    pub names: Vec<String>,
    pub values: Vec<f64>,
    pub sigmas: Vec<f64>,
    /// RMS of the residual coordinates before and after (mm).
    pub rms_before_mm: f64,
    pub rms_after_mm: f64,
    /// Number of residual coordinates.
    pub n_residuals: usize,
}

/// Why a tree fit did not run.
#[derive(Debug, thiserror::Error)]
pub enum TreeFitError {
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("pose {pose}: {found} joint values for a tree of {expected} joints, or {points} points for {tips} tips")]
    Shape {
        pose: usize,
        expected: usize,
        found: usize,
        points: usize,
        tips: usize,
    },
    #[error("{residuals} measured coordinates for {unknowns} unknowns: more measurements needed")]
    TooFew { residuals: usize, unknowns: usize },
    #[error("the poses do not identify the unknowns: `{worst}` is (nearly) a combination of the others (singular value ratio {ratio:.1e})")]
    NotIdentified { worst: String, ratio: f64 },
    #[error("the fit diverged (a non-finite value)")]
    Diverged,
}

impl crate::error::Classify for TreeFitError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            TreeFitError::Model(e) => e.kind(),
            TreeFitError::Diverged => crate::error::ErrorKind::Failure,
            _ => crate::error::ErrorKind::BadInput,
        }
    }
}

/// Every measured coordinate's residual (measured - model, mm), and with `unknowns` the
/// Jacobian of the model's points (mm per unit) for the unknowns.
fn residuals(
    tree: &Tree,
    poses: &[TreePose],
    unknowns: &[String],
    jacobian: bool,
) -> Result<(DVector<f64>, DMatrix<f64>), TreeFitError> {
    let chains: Vec<Model> = tree.chains()?;
    let paths: Vec<Vec<usize>> = (0..tree.tips.len()).map(|t| tree.path(t)).collect();
    // per tip: (column, chain parameter index) of the unknowns its chain has
    let cols: Vec<Vec<(usize, usize)>> = chains
        .iter()
        .enumerate()
        .map(|(t, m)| {
            m.param_names()
                .enumerate()
                .filter_map(|(i, n)| {
                    let tree_name = tree.tree_param_name(t, n);
                    unknowns
                        .iter()
                        .position(|u| *u == tree_name)
                        .map(|c| (c, i))
                })
                .collect()
        })
        .collect();
    let n_rows: usize = poses
        .iter()
        .map(|p| 3 * p.points_mm.iter().flatten().count())
        .sum();
    let mut r = DVector::zeros(n_rows);
    let mut j = DMatrix::zeros(if jacobian { n_rows } else { 0 }, unknowns.len());
    let mut row = 0;
    for (k, pose) in poses.iter().enumerate() {
        if pose.q.len() != tree.n_joints() || pose.points_mm.len() != tree.tips.len() {
            return Err(TreeFitError::Shape {
                pose: k + 1,
                expected: tree.n_joints(),
                found: pose.q.len(),
                points: pose.points_mm.len(),
                tips: tree.tips.len(),
            });
        }
        for (t, point) in pose.points_mm.iter().enumerate() {
            let Some(p) = point else { continue };
            let q: Vec<f64> = paths[t].iter().map(|&i| pose.q[i]).collect();
            let idx: Vec<usize> = cols[t].iter().map(|(_, i)| *i).collect();
            let (fk, jac) = chains[t].param_jacobian(&q, Tilt::Off, &idx)?;
            let model_mm = chains[t].measured_mm(&fk.position_mm, 0.0);
            let d = Vector3::from(*p) - model_mm;
            for c in 0..3 {
                r[row + c] = d[c];
                if jacobian {
                    for (n, (col, _)) in cols[t].iter().enumerate() {
                        j[(row + c, *col)] = jac[(c, n)];
                    }
                }
            }
            row += 3;
        }
    }
    Ok((r, j))
}

/// RMS (mm) of the residual coordinates of `poses` on `tree` (e.g. held-out poses).
pub fn tree_rms_mm(tree: &Tree, poses: &[TreePose]) -> Result<f64, TreeFitError> {
    let (r, _) = residuals(tree, poses, &[], false)?;
    Ok((r.norm_squared() / r.len().max(1) as f64).sqrt())
}

/// Fits `unknowns` (tree parameter names) of `tree` to `poses` (see the module doc).
pub fn fit_tree(
    tree: &Tree,
    poses: &[TreePose],
    unknowns: &[String],
) -> Result<TreeFit, TreeFitError> {
    let mut tree = tree.clone();
    for u in unknowns {
        let v = tree.param(u).ok_or_else(|| ModelError::UnknownParam {
            name: u.clone(),
            valid: "the tree's constants and joint offsets, base_x .. base_ry, scale_ppm, \
                        NAME@TIP (tool_dx@TIP ..)"
                .into(),
        })?;
        tree.set_param(u, v)?;
    }
    let n = unknowns.len();
    let (r0, _) = residuals(&tree, poses, unknowns, false)?;
    let m = r0.len();
    if m <= n {
        return Err(TreeFitError::TooFew {
            residuals: m,
            unknowns: n,
        });
    }
    let rms = |r: &DVector<f64>| (r.norm_squared() / m as f64).sqrt();
    let rms_before_mm = rms(&r0);
    let mut last = f64::INFINITY;
    let mut cov_scaled = DMatrix::zeros(n, n);
    let mut scale = DVector::from_element(n, 1.0);
    for _ in 0..30 {
        let (r, mut j) = residuals(&tree, poses, unknowns, true)?;
        for c in 0..n {
            let norm = j.column(c).norm();
            scale[c] = if norm > 0.0 { 1.0 / norm } else { 1.0 };
            j.column_mut(c).scale_mut(scale[c]);
        }
        let svd = j.svd(true, true);
        let smax = svd.singular_values.max();
        let (kmin, smin) = svd.singular_values.argmin();
        if smax.is_nan() || smax <= 0.0 || smin < 1e-9 * smax {
            let v_t = svd.v_t.as_ref().ok_or(TreeFitError::Diverged)?;
            let worst = (0..n)
                .max_by(|&a, &b| v_t[(kmin, a)].abs().total_cmp(&v_t[(kmin, b)].abs()))
                .unwrap_or(0);
            return Err(TreeFitError::NotIdentified {
                worst: unknowns[worst].clone(),
                ratio: smin / smax,
            });
        }
        let step = svd.solve(&r, 0.0).map_err(|_| TreeFitError::Diverged)?;
        let v_t = svd.v_t.as_ref().ok_or(TreeFitError::Diverged)?;
        let inv_s2 = svd.singular_values.map(|s| 1.0 / (s * s));
        cov_scaled = v_t.transpose() * DMatrix::from_diagonal(&inv_s2) * v_t;
        for (c, u) in unknowns.iter().enumerate() {
            let v = tree.param(u).unwrap_or(0.0) + step[c] * scale[c];
            if !v.is_finite() {
                return Err(TreeFitError::Diverged);
            }
            tree.set_param(u, v)?;
        }
        let now = rms(&r);
        if (last - now).abs() <= 1e-12 * now.max(1e-9) && step.norm() < 1e-10 {
            break;
        }
        last = now;
        if step.norm() < 1e-12 {
            break;
        }
    }
    let (r, _) = residuals(&tree, poses, unknowns, false)?;
    let s2 = r.norm_squared() / (m - n) as f64;
    let sigmas = (0..n)
        .map(|c| (s2 * cov_scaled[(c, c)]).sqrt() * scale[c])
        .collect();
    Ok(TreeFit {
        values: unknowns
            .iter()
            .map(|u| tree.param(u).unwrap_or(0.0))
            .collect(),
        names: unknowns.to_vec(),
        sigmas,
        rms_before_mm,
        rms_after_mm: rms(&r),
        n_residuals: m,
        tree,
    })
}

/// Every parameter of `tree` a geometric fit may free: the root's and the joints' constants,
/// the joint offsets, each tip's own constants and tool point (`NAME@TIP`).
pub fn tree_candidates(tree: &Tree) -> Vec<String> {
    let mut out: Vec<String> = tree.root.iter().map(|e| e.name.clone()).collect();
    for j in &tree.joints {
        out.extend(j.before.iter().map(|e| e.name.clone()));
        out.push(j.offset_name.clone());
    }
    for t in &tree.tips {
        out.extend(t.after.iter().map(|e| format!("{}@{}", e.name, t.name)));
        out.extend(["tool_dx", "tool_dy", "tool_dz"].map(|n| format!("{n}@{}", t.name)));
    }
    out
}

/// The unknowns of `candidates` the poses identify, in candidate order: a rank-revealing QR
/// (column pivoting) of the scaled Jacobian at `tree` keeps the columns whose pivot is above
/// `1e-6` of the largest; the others are (nearly) combinations of the kept ones and stay at
/// their values.
pub fn identifiable(
    tree: &Tree,
    poses: &[TreePose],
    candidates: &[String],
) -> Result<Vec<String>, TreeFitError> {
    let (_, mut j) = residuals(tree, poses, candidates, true)?;
    let n = candidates.len();
    let mut used = vec![false; n];
    for (c, used) in used.iter_mut().enumerate() {
        let norm = j.column(c).norm();
        if norm > 0.0 {
            j.column_mut(c).scale_mut(1.0 / norm);
            *used = true;
        }
    }
    let qr = j.col_piv_qr();
    let r = qr.r();
    let mut order = DMatrix::from_fn(1, n, |_, c| c as f64);
    qr.p().permute_columns(&mut order);
    let d_max = (0..r.nrows().min(n))
        .map(|k| r[(k, k)].abs())
        .fold(0.0, f64::max);
    let mut keep = vec![false; n];
    for k in 0..r.nrows().min(n) {
        let c = order[(0, k)] as usize;
        if r[(k, k)].abs() > 1e-6 * d_max && used[c] {
            keep[c] = true;
        }
    }
    Ok(candidates
        .iter()
        .zip(keep)
        .filter(|(_, k)| *k)
        .map(|(c, _)| c.clone())
        .collect())
}
