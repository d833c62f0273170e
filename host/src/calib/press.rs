//! Parameter selection on the calibration data alone (`calibrate --select press`): greedy
//! forward selection minimising the leave-one-pose-out prediction error (block PRESS) of the
//! linearised problem.
//!
//! With the Jacobian `J_S` of a parameter set `S` (column-scaled) at the linearisation point
//! and residuals `r`, the fitted residuals are `e = (I - H) r`, `H = J_S (J_S^T J_S)^-1 J_S^T`,
//! and leaving pose `i` (its block of rows: 3 per measured point) out predicts it with error
//! `(I - H_ii)^-1 e_i` (exact for linear least squares). PRESS is the sum of their squares.
//! Parameters are added while PRESS decreases; held-out (validation) data are never looked at.

use nalgebra::{DMatrix, DVector};

/// Block PRESS of the columns `cols` of `jac`, rows in consecutive blocks of the sizes
/// `blocks` (one block per pose); `None` when the columns are (numerically) dependent, a block
/// is fully explained by its own parameters, or the blocks do not cover the rows.
pub fn block_press(
    jac: &DMatrix<f64>,
    r: &DVector<f64>,
    cols: &[usize],
    blocks: &[usize],
) -> Option<f64> {
    let m = jac.nrows();
    if blocks.iter().sum::<usize>() != m || r.len() != m || cols.len() >= m {
        return None;
    }
    let mut a = DMatrix::zeros(m, cols.len());
    for (k, &c) in cols.iter().enumerate() {
        if c >= jac.ncols() {
            return None;
        }
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
    let mut start = 0;
    for &size in blocks {
        let qb = q.rows(start, size);
        let hii = DMatrix::identity(size, size) - qb * qb.transpose();
        let loo = hii.lu().solve(&e.rows(start, size).into_owned())?;
        press += loo.norm_squared();
        start += size;
    }
    Some(press)
}

/// Greedy forward selection: starting from the columns `always`, repeatedly adds the candidate
/// column that lowers the block PRESS most, until none lowers it. Returns the added candidates
/// in order (empty if `always` itself has no PRESS).
pub fn forward_select(
    jac: &DMatrix<f64>,
    r: &DVector<f64>,
    blocks: &[usize],
    always: &[usize],
    candidates: &[usize],
) -> Vec<usize> {
    let mut chosen: Vec<usize> = always.to_vec();
    let mut added = Vec::new();
    let Some(mut best) = block_press(jac, r, &chosen, blocks) else {
        return added;
    };
    loop {
        let mut step: Option<(usize, f64)> = None;
        for &c in candidates {
            if chosen.contains(&c) {
                continue;
            }
            chosen.push(c);
            if let Some(p) = block_press(jac, r, &chosen, blocks) {
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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Brute-force leave-one-out of a fit of `y` on the first two columns of `jac` (`fit`
    /// solves one): the sum of the squared errors of every row predicted by the fit without it,
    /// the reference of a PRESS.
    pub(crate) fn leave_one_out(
        jac: &DMatrix<f64>,
        y: &DVector<f64>,
        fit: impl Fn(&DMatrix<f64>, &DVector<f64>) -> DVector<f64>,
    ) -> f64 {
        let n = y.len();
        let mut brute = 0.0;
        for out in 0..n {
            let keep: Vec<usize> = (0..n).filter(|&i| i != out).collect();
            let a = DMatrix::from_fn(n - 1, 2, |k, c| jac[(keep[k], c)]);
            let b = DVector::from_fn(n - 1, |k, _| y[keep[k]]);
            let x = fit(&a, &b);
            brute += (y[out] - jac[(out, 0)] * x[0] - jac[(out, 1)] * x[1]).powi(2);
        }
        brute
    }

    /// y = 2 t + noise-free: the slope column is added, a column of pure noise is not, and the
    /// block PRESS of a straight-line fit equals the brute-force leave-one-out error.
    #[test]
    fn selects_the_explaining_column_and_matches_brute_force() {
        let n = 12;
        let t: Vec<f64> = (0..n).map(|i| i as f64 - 5.5).collect();
        let wiggle: Vec<f64> = (0..n).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
        let jac = DMatrix::from_fn(n, 3, |i, c| match c {
            0 => 1.0,
            1 => t[i],
            _ => wiggle[i],
        });
        let r = DVector::from_fn(n, |i, _| 1.0 + 2.0 * t[i] + 0.01 * (i as f64 % 3.0 - 1.0));
        let blocks = vec![1; n];
        assert_eq!(forward_select(&jac, &r, &blocks, &[0], &[1, 2]), vec![1]);
        // Brute force leave-one-out of the line fit.
        let brute = leave_one_out(&jac, &r, |a, b| {
            a.clone().svd(true, true).solve(b, 1e-12).unwrap()
        });
        let press = block_press(&jac, &r, &[0, 1], &blocks).unwrap();
        assert!(
            (press - brute).abs() < 1e-9 * brute.max(1.0),
            "{press} vs {brute}"
        );
        assert!(block_press(&jac, &r, &[0, 1], &[5, 5]).is_none());
    }
}
