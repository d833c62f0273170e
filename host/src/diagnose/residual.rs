//! Residual analysis: regressors of every pose, the linearised screening of the candidates, and
//! the test for structure left in a residual.
//!
//! **Screening.** At the current fit, with stacked residual `r` and Jacobian `J_A` of the
//! already-fitted unknowns, the candidate's Jacobian columns `J_C` (scaled to unit norm) are
//! projected off the span of `J_A`: `J_C' = (I - Q_A Q_A^T) J_C`. Directions of `J_C'` whose
//! singular value is below [`ALIAS_RTOL`] are aliases of fitted parameters (they add nothing);
//! the others span the candidate's new directions, and the share of `r` they hold,
//! `|U_C'^T r|^2`, is the residual sum of squares the candidate would remove to first order.
//!
//! **Structure.** A residual (or an effect's contribution) is regressed, coordinate by
//! coordinate, on a regressor group (an intercept plus one or more columns per pose: a joint
//! angle, `sin/cos(n q_i)`, a joint's gravity torque, `t`, the distance from the base, the tool
//! direction, the position). The explained share `R^2` and the F-test of the slopes (`3 c`
//! parameters for `c` columns) measure how much of it the regressor traces.

use nalgebra::{DMatrix, DVector, Vector3};

use super::candidates::Candidate;
use super::compress::stacked_or_compressed;
use super::extended::{ExtModel, Unknown};
use super::stat::f_test_p_value;
use crate::calib::MeasuredSet;
use crate::model::ModelError;

/// A candidate direction counts as an alias of the fitted parameters when less than this
/// fraction of its (unit) column survives the projection.
pub const ALIAS_RTOL: f64 = 1e-5;

/// One regressor group, per pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Regressor {
    /// Name, e.g. `"q2"`, `"sin/cos(1 q2)"`, `"tau_j2"`, `"t"`.
    pub name: String,
    /// Abscissa for plots (e.g. `q2` for `sin/cos(1 q2)`).
    pub x: Vec<f64>,
    /// Label of the abscissa with its unit.
    pub x_label: String,
    /// Regression columns (one vector per column, one entry per pose).
    pub columns: Vec<Vec<f64>>,
}

/// The regressors of joint `j` (0-based) with readings `q` (deg, mm when `prismatic`): `q<j+1>`,
/// and `sin/cos(h q<j+1>)` for h = 1..3 of a revolute joint.
pub fn joint_regressors(j: usize, q: &[f64], prismatic: bool) -> Vec<Regressor> {
    let label = format!("q{} (deg)", j + 1);
    let mut out = vec![Regressor {
        name: format!("q{}", j + 1),
        x: q.to_vec(),
        x_label: label.clone(),
        columns: vec![q.to_vec()],
    }];
    if !prismatic {
        for h in 1..=3 {
            let hf = f64::from(h);
            let s = q.iter().map(|v| (hf * v).to_radians().sin()).collect();
            let c = q.iter().map(|v| (hf * v).to_radians().cos()).collect();
            out.push(Regressor {
                name: format!("sin/cos({h} q{})", j + 1),
                x: q.to_vec(),
                x_label: label.clone(),
                columns: vec![s, c],
            });
        }
    }
    out
}

/// The regressors of every pose of `data` under `ext`.
pub fn regressors(ext: &ExtModel, data: &MeasuredSet) -> Result<Vec<Regressor>, ModelError> {
    let n = data.len();
    let nj = ext.model.n_joints();
    let mut out = Vec::new();
    for j in 0..nj {
        let q: Vec<f64> = data.poses.q_deg.iter().map(|q| q[j]).collect();
        out.extend(joint_regressors(j, &q, ext.model.joints()[j].prismatic));
    }
    if ext.gravity.is_some() {
        let taus: Vec<Vec<f64>> = data
            .poses
            .q_deg
            .iter()
            .map(|q| ext.torques_kgfm(q))
            .collect::<Result<_, _>>()?;
        for j in 0..nj {
            let tau: Vec<f64> = taus.iter().map(|t| t[j]).collect();
            if tau.iter().any(|v| v.abs() > 1e-9) {
                out.push(Regressor {
                    name: format!("tau_j{}", j + 1),
                    x: tau.clone(),
                    x_label: format!("gravity torque j{} (kgf.m)", j + 1),
                    columns: vec![tau],
                });
            }
        }
    }
    if data.has_time() {
        let t: Vec<f64> = (0..n).map(|k| data.t(k)).collect();
        out.push(Regressor {
            name: "t".into(),
            x: t.clone(),
            x_label: "t (s)".into(),
            columns: vec![t],
        });
    }
    let mut dist = Vec::with_capacity(n);
    let mut dirs = [
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    ];
    for q in &data.poses.q_deg {
        let fk = ext.model.fk(q, crate::model::Tilt::Off)?;
        dist.push(fk.position_mm.norm());
        for (a, d) in dirs.iter_mut().enumerate() {
            d.push(fk.rotation[(a, 2)]);
        }
    }
    out.push(Regressor {
        name: "distance".into(),
        x: dist.clone(),
        x_label: "distance from the origin of R (mm)".into(),
        columns: vec![dist],
    });
    let dir_x = dirs[0].clone();
    out.push(Regressor {
        name: "tool_direction".into(),
        x: dir_x,
        x_label: "tool z axis, x component".into(),
        columns: dirs.to_vec(),
    });
    let pos: Vec<Vec<f64>> = (0..3)
        .map(|a| data.poses.xyz_mm.iter().map(|p| p[a]).collect())
        .collect();
    out.push(Regressor {
        name: "position".into(),
        x: pos[0].clone(),
        x_label: "x (mm)".into(),
        columns: pos,
    });
    Ok(out)
}

/// How much of a set of per-pose vectors a regressor explains.
#[derive(Debug, Clone, PartialEq)]
pub struct Explained {
    /// The regressor's name.
    pub regressor: String,
    /// Share of the total sum of squares explained by the slopes.
    pub r2: f64,
    /// F statistic of the slopes.
    pub f: f64,
    /// Its p-value (not corrected for multiple tests).
    pub p_value: f64,
}

/// Regresses each coordinate of `v` on `[1, reg.columns]` (independent full positions; see
/// [`explain_with`]).
pub fn explain(v: &[Vector3<f64>], reg: &Regressor) -> Explained {
    explain_with(v, reg, 3, 1.0)
}

/// [`explain`] for vectors with `dims` measured components per pose (2 for traced samples,
/// whose errors lie in the measured plane) that are serially correlated with integrated
/// autocorrelation time `tau`: the F-test counts `dims n / tau` independent residuals.
pub fn explain_with(v: &[Vector3<f64>], reg: &Regressor, dims: usize, tau: f64) -> Explained {
    let n = v.len();
    let c = reg.columns.len();
    let total: f64 = v.iter().map(|e| e.norm_squared()).sum();
    let none = Explained {
        regressor: reg.name.clone(),
        r2: 0.0,
        f: 0.0,
        p_value: 1.0,
    };
    if n <= c + 2 || total <= 0.0 {
        return none;
    }
    let x = DMatrix::from_fn(
        n,
        c + 1,
        |r, k| if k == 0 { 1.0 } else { reg.columns[k - 1][r] },
    );
    let svd = x.clone().svd(true, true);
    let (mut rss_mean, mut rss_fit) = (0.0, 0.0);
    for a in 0..3 {
        let y = DVector::from_iterator(n, v.iter().map(|e| e[a]));
        let mean = y.mean();
        rss_mean += y.iter().map(|yi| (yi - mean).powi(2)).sum::<f64>();
        let Ok(beta) = svd.solve(&y, 1e-12) else {
            return none;
        };
        rss_fit += (&y - &x * beta).norm_squared();
    }
    let gain = (rss_mean - rss_fit).max(0.0);
    let dims = dims.clamp(1, 3) as f64;
    let n_eff = dims * n as f64 / tau.max(1.0);
    let (d1, d2) = (dims * c as f64, n_eff - dims * (c + 1) as f64);
    if d2 < 1.0 {
        return none;
    }
    let f = if rss_fit > 0.0 {
        (gain / d1) / (rss_fit / d2)
    } else {
        f64::INFINITY
    };
    Explained {
        regressor: reg.name.clone(),
        r2: gain / total,
        f,
        p_value: f_test_p_value(f, d1, d2),
    }
}

/// The regressor that explains most of `v` (largest `R^2`).
pub fn best_regressor(v: &[Vector3<f64>], regs: &[Regressor]) -> Option<(usize, Explained)> {
    regs.iter()
        .enumerate()
        .map(|(i, r)| (i, explain(v, r)))
        .max_by(|a, b| a.1.r2.total_cmp(&b.1.r2))
}

/// Linearised screening result of one candidate.
#[derive(Debug, Clone, PartialEq)]
pub struct Screen {
    /// Index into the candidate list.
    pub candidate: usize,
    /// New directions it adds beyond the fitted unknowns.
    pub added: usize,
    /// Residual sum of squares it removes to first order (mm^2).
    pub delta_rss_mm2: f64,
}

/// Orthonormal basis of the column space of `a` (columns scaled to unit norm first; singular
/// values below `rtol` times the largest are dropped).
pub fn column_basis(a: &DMatrix<f64>, rtol: f64) -> DMatrix<f64> {
    if a.ncols() == 0 || a.nrows() == 0 {
        return DMatrix::zeros(a.nrows(), 0);
    }
    let mut s = a.clone();
    for mut c in s.column_iter_mut() {
        let n = c.norm();
        if n > 0.0 {
            c /= n;
        }
    }
    let svd = s.svd(true, false);
    let Some(u) = svd.u else {
        return DMatrix::zeros(a.nrows(), 0);
    };
    let top = svd.singular_values.iter().copied().fold(0.0, f64::max);
    let keep: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&i| svd.singular_values[i] > rtol * top && top > 0.0)
        .collect();
    DMatrix::from_fn(a.nrows(), keep.len(), |r, c| u[(r, keep[c])])
}

/// Screens `candidates` at `ext` (current fit with unknowns `current`) on `data`.
pub fn screen(
    ext: &ExtModel,
    data: &MeasuredSet,
    current: &[Unknown],
    candidates: &[Candidate],
    rtol: f64,
) -> Result<Vec<Screen>, ModelError> {
    let mut all: Vec<Unknown> = current.to_vec();
    for c in candidates {
        for u in &c.unknowns {
            if !all.contains(u) {
                all.push(*u);
            }
        }
    }
    let (jac, r) = stacked_or_compressed(ext, data, &all)?;
    let m = jac.nrows();
    let ja = jac.columns(0, current.len()).into_owned();
    let qa = column_basis(&ja, rtol);
    let project = |v: &DMatrix<f64>| -> DMatrix<f64> {
        if qa.ncols() == 0 {
            v.clone()
        } else {
            v - &qa * (qa.transpose() * v)
        }
    };
    let r_perp = project(&DMatrix::from_column_slice(m, 1, r.as_slice()));
    let top_norm = (0..jac.ncols())
        .map(|k| jac.column(k).norm())
        .fold(0.0, f64::max);
    let mut out = Vec::with_capacity(candidates.len());
    for (ci, c) in candidates.iter().enumerate() {
        let cols: Vec<usize> = c
            .unknowns
            .iter()
            .filter_map(|u| all.iter().position(|a| a == u))
            .collect();
        let mut jc = DMatrix::zeros(m, cols.len());
        let mut live = 0;
        for &k in &cols {
            let col = jac.column(k);
            let n = col.norm();
            if n > 1e-10 * top_norm && n > 0.0 {
                jc.set_column(live, &(col / n));
                live += 1;
            }
        }
        let jc = jc.columns(0, live).into_owned();
        let jp = project(&jc);
        let (added, delta) = if live == 0 {
            (0, 0.0)
        } else {
            let svd = jp.svd(true, false);
            let Some(u) = svd.u else { continue };
            let keep: Vec<usize> = (0..svd.singular_values.len())
                .filter(|&i| svd.singular_values[i] > ALIAS_RTOL)
                .collect();
            let d: f64 = keep
                .iter()
                .map(|&i| u.column(i).dot(&r_perp.column(0)).powi(2))
                .sum();
            (keep.len(), d)
        };
        out.push(Screen {
            candidate: ci,
            added,
            delta_rss_mm2: delta,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn explain_finds_a_sine_and_ignores_an_unrelated_column() {
        let n = 90;
        let q: Vec<f64> = (0..n)
            .map(|k| -170.0 + 340.0 * k as f64 / n as f64)
            .collect();
        let v: Vec<Vector3<f64>> = q
            .iter()
            .map(|a| Vector3::new(a.to_radians().sin(), 0.0, 0.5 * a.to_radians().cos()))
            .collect();
        let sc = Regressor {
            name: "sc".into(),
            x: q.clone(),
            x_label: String::new(),
            columns: vec![
                q.iter().map(|a| a.to_radians().sin()).collect(),
                q.iter().map(|a| a.to_radians().cos()).collect(),
            ],
        };
        let e = explain(&v, &sc);
        assert!(e.r2 > 0.99 && e.p_value < 1e-10, "{e:?}");
        // A column that alternates sign pose by pose traces almost nothing of the sine.
        let alt = Regressor {
            name: "alt".into(),
            x: q.clone(),
            x_label: String::new(),
            columns: vec![(0..n)
                .map(|k| if k % 2 == 0 { 1.0 } else { -1.0 })
                .collect()],
        };
        let e = explain(&v, &alt);
        assert!(e.r2 < 0.05, "{e:?}");
    }
}
