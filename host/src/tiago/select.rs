//! Parameter selection on the training data alone: greedy forward selection minimising the
//! leave-one-posture-out prediction error (block PRESS) of the linearised problem.
//!
//! With the Jacobian `J_S` of a parameter set `S` (column-scaled) at the linearisation point
//! and residuals `r`, the fitted residuals are `e = (I - H) r`, `H = J_S (J_S^T J_S)^-1 J_S^T`,
//! and leaving posture `i` (its block of rows) out predicts it with error
//! `(I - H_ii)^-1 e_i` (exact for linear least squares). PRESS is the sum of their squares.
//! Parameters are added while PRESS decreases; the validation data are never looked at.

use nalgebra::{DMatrix, DVector};

/// Block PRESS of the columns `cols` of `jac` (rows in blocks of `block`); `None` when the
/// columns are (numerically) dependent or a block is fully explained by its own parameters.
pub fn block_press(
    jac: &DMatrix<f64>,
    r: &DVector<f64>,
    cols: &[usize],
    block: usize,
) -> Option<f64> {
    let m = jac.nrows();
    if block == 0 || !m.is_multiple_of(block) || cols.len() >= m {
        return None;
    }
    let mut a = DMatrix::zeros(m, cols.len());
    for (k, &c) in cols.iter().enumerate() {
        let col = jac.column(c);
        let norm = col.norm();
        if norm == 0.0 {
            return None;
        }
        a.column_mut(k).copy_from(&(col / norm));
    }
    let qr = a.qr();
    let rr = qr.r();
    if (0..cols.len()).any(|k| rr[(k, k)].abs() < 1e-8) {
        return None;
    }
    let q = qr.q();
    let e = r - &q * (q.transpose() * r);
    let mut press = 0.0;
    for b in 0..m / block {
        let qb = q.rows(b * block, block);
        let hii = DMatrix::identity(block, block) - qb * qb.transpose();
        let loo = hii.lu().solve(&e.rows(b * block, block).into_owned())?;
        press += loo.norm_squared();
    }
    Some(press)
}

/// Greedy forward selection: starting from `always`, repeatedly adds the candidate that lowers
/// the block PRESS most, until none lowers it. Returns the added candidates in order.
pub fn forward_select(
    jac: &DMatrix<f64>,
    r: &DVector<f64>,
    block: usize,
    always: &[usize],
    candidates: &[usize],
) -> Vec<usize> {
    let mut chosen: Vec<usize> = always.to_vec();
    let mut added = Vec::new();
    let Some(mut best) = block_press(jac, r, &chosen, block) else {
        return added;
    };
    loop {
        let mut step: Option<(usize, f64)> = None;
        for &c in candidates {
            if chosen.contains(&c) {
                continue;
            }
            chosen.push(c);
            if let Some(p) = block_press(jac, r, &chosen, block) {
                if p < step.map_or(best, |s| s.1) {
                    step = Some((c, p));
                }
            }
            chosen.pop();
        }
        match step {
            Some((c, p)) => {
                chosen.push(c);
                added.push(c);
                best = p;
            }
            None => return added,
        }
    }
}
