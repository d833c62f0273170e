//! The weighted least squares of a bridge's polynomials: normal equations solved by Cholesky,
//! with each point's leave-one-out residual from the same factor (the PRESS statistic).

use super::{horner, Node};

/// The highest degree the fixed-size normal equations have room for: a higher
/// `LinkParams::bridge_max_degree` finds no fit of that degree.
const ROOM_DEGREE: usize = 5;
/// Room for the coefficients of the highest degree.
const M: usize = ROOM_DEGREE + 1;

/// Weighted least squares of x and y on powers of `ts` up to `deg`: coefficients and the mean
/// squared leave-one-out residual.
pub(super) fn weighted_fit(
    data: &[Node],
    ts: &[f64],
    w: &[f64],
    deg: usize,
) -> Option<(Vec<f64>, Vec<f64>, f64)> {
    let m = deg + 1;
    if m > M {
        return None;
    }
    let mut a = [0.0; M * M];
    let (mut bx, mut by) = ([0.0; M], [0.0; M]);
    let mut pw = [0.0; M];
    for ((v, t), wi) in data.iter().zip(ts).zip(w) {
        if *wi <= 0.0 {
            continue;
        }
        powers(*t, &mut pw[..m]);
        for r in 0..m {
            for c in 0..m {
                a[r * m + c] += wi * pw[r] * pw[c];
            }
            bx[r] += wi * pw[r] * v.p[0];
            by[r] += wi * pw[r] * v.p[1];
        }
    }
    let l = cholesky(&a, m)?;
    let cx = solve(&l, m, &bx)[..m].to_vec();
    let cy = solve(&l, m, &by)[..m].to_vec();
    // Leave-one-out residuals r / (1 - h), h the leverage w p^T A^-1 p = w |L^-1 p|^2.
    let (mut press, mut wsum) = (0.0, 0.0);
    for ((v, t), wi) in data.iter().zip(ts).zip(w) {
        if *wi <= 0.0 {
            continue;
        }
        powers(*t, &mut pw[..m]);
        let y = forward(&l, m, &pw);
        let h = wi * y[..m].iter().map(|q| q * q).sum::<f64>();
        if h >= 1.0 - 1e-9 {
            return None;
        }
        let rx = v.p[0] - horner(&cx, *t);
        let ry = v.p[1] - horner(&cy, *t);
        press += wi * (rx * rx + ry * ry) / ((1.0 - h) * (1.0 - h));
        wsum += wi;
    }
    (wsum > 0.0).then_some((cx, cy, press / wsum))
}

fn powers(t: f64, out: &mut [f64]) {
    let mut v = 1.0;
    for o in out.iter_mut() {
        *o = v;
        v *= t;
    }
}

/// Lower Cholesky factor of the `m` x `m` row-major matrix `a` (`m` <= [`M`]), or `None` when
/// not positive definite.
fn cholesky(a: &[f64; M * M], m: usize) -> Option<[f64; M * M]> {
    let mut l = [0.0; M * M];
    for r in 0..m {
        for c in 0..=r {
            let mut sum = a[r * m + c];
            for k in 0..c {
                sum -= l[r * m + k] * l[c * m + k];
            }
            if r == c {
                if sum <= 1e-12 * a[r * m + r].abs().max(1e-300) {
                    return None;
                }
                l[r * m + r] = sum.sqrt();
            } else {
                l[r * m + c] = sum / l[c * m + c];
            }
        }
    }
    Some(l)
}

/// Solves `L y = b`.
fn forward(l: &[f64; M * M], m: usize, b: &[f64; M]) -> [f64; M] {
    let mut y = [0.0; M];
    for r in 0..m {
        let mut sum = b[r];
        for k in 0..r {
            sum -= l[r * m + k] * y[k];
        }
        y[r] = sum / l[r * m + r];
    }
    y
}

/// Solves `L L^T x = b`.
fn solve(l: &[f64; M * M], m: usize, b: &[f64; M]) -> [f64; M] {
    let y = forward(l, m, b);
    let mut x = [0.0; M];
    for r in (0..m).rev() {
        let mut sum = y[r];
        for k in r + 1..m {
            sum -= l[k * m + r] * x[k];
        }
        x[r] = sum / l[r * m + r];
    }
    x
}
