//! The stacked Jacobian and errors of many poses ([`ExtModel::stacked`]) compressed, pose by
//! pose, to the triangular factor of their QR decomposition: `[J | e] = Q [R | z]` with `R`
//! `p x p` and `z` of length `p + 1` (the last entry carries the part of `e` outside `J`'s span).
//! Every quantity the screens, start steps and alias tests take from `(J, e)` is built from
//! inner products, projections and SVDs of its columns, which an orthogonal `Q^T` on the rows
//! leaves as they are: `(R, z)` gives them to round-off (as a Householder QR, with no squared
//! condition number) in `O(p^2)` memory whatever the number of poses.
//!
//! [`stacked_or_compressed`] keeps the tall matrices below [`COMPRESS_MIN_RESIDUALS`]
//! residuals, where they are small.

use nalgebra::{DMatrix, DVector};

use super::extended::{ExtModel, Unknown};
use crate::calib::MeasuredSet;
use crate::model::ModelError;

/// Rows gathered below the running factor before each QR.
const CHUNK_ROWS: usize = 1024;

pub use super::extended::COMPRESS_MIN_RESIDUALS;

/// `[J | e]` of `ext` on `data` wrt `unknowns` (as [`ExtModel::stacked`]) reduced to at most
/// `unknowns.len() + 1` rows with the same inner products.
pub fn compressed(
    ext: &ExtModel,
    data: &MeasuredSet,
    unknowns: &[Unknown],
) -> Result<(DMatrix<f64>, DVector<f64>), ModelError> {
    let p = unknowns.len();
    let cols = p + 1;
    let mut a = DMatrix::zeros(cols + CHUNK_ROWS + 3, cols);
    let mut filled = 0;
    for k in 0..data.len() {
        let rows = data.rows(k);
        if filled + rows > a.nrows() {
            filled = reduce(&mut a, filled);
        }
        let (pred, j) = ext.predict_with_jacobian(data, k, unknowns)?;
        let jr = data.jacobian_rows(k, &j);
        let e = data.components(k, &(data.poses.xyz_mm[k] - pred));
        for (i, ei) in e.iter().enumerate() {
            for c in 0..p {
                a[(filled + i, c)] = jr[(i, c)];
            }
            a[(filled + i, p)] = *ei;
        }
        filled += rows;
    }
    let filled = reduce(&mut a, filled);
    let jac = a.view((0, 0), (filled, p)).into_owned();
    let err = a.view((0, p), (filled, 1)).column(0).into_owned();
    Ok((jac, err))
}

/// Replaces the first `filled` rows of `a` by the triangular factor of their QR decomposition
/// (the other rows zero); returns its row count.
fn reduce(a: &mut DMatrix<f64>, filled: usize) -> usize {
    let cols = a.ncols();
    if filled <= cols {
        return filled;
    }
    let r = a.view((0, 0), (filled, cols)).into_owned().qr().r();
    a.view_mut((0, 0), (filled, cols)).fill(0.0);
    a.view_mut((0, 0), (r.nrows(), cols)).copy_from(&r);
    r.nrows()
}

/// [`ExtModel::stacked`] below [`COMPRESS_MIN_RESIDUALS`] residuals, [`compressed`] from there.
pub fn stacked_or_compressed(
    ext: &ExtModel,
    data: &MeasuredSet,
    unknowns: &[Unknown],
) -> Result<(DMatrix<f64>, DVector<f64>), ModelError> {
    if data.n_residuals() >= COMPRESS_MIN_RESIDUALS {
        compressed(ext, data, unknowns)
    } else {
        ext.stacked(data, unknowns)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::measured::PosePoints;
    use crate::model::katana450;
    use nalgebra::Vector3;

    /// Random joints and positions off the model by a few millimetres.
    fn data(n: usize) -> MeasuredSet {
        let model = katana450(200.0).expect("preset");
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut q, mut xyz) = (Vec::new(), Vec::new());
        for _ in 0..n {
            let qk: Vec<f64> = (0..5).map(|_| -90.0 + 180.0 * rnd()).collect();
            let p = model
                .position_mm(&qk, crate::model::Tilt::Off)
                .unwrap_or_else(|_| Vector3::zeros());
            xyz.push(p + Vector3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 4.0);
            q.push(qk);
        }
        MeasuredSet::from_poses(PosePoints {
            q_deg: q,
            xyz_mm: xyz,
        })
        .with_approach()
    }

    #[test]
    fn the_factor_keeps_the_inner_products_of_the_tall_matrices() {
        let d = data(2500);
        let ext = ExtModel::new(katana450(200.0).expect("preset"));
        let unknowns: Vec<Unknown> = (0..8)
            .map(Unknown::Param)
            .chain([Unknown::JointScale(1), Unknown::Hysteresis(2)])
            .collect();
        let (j, e) = ext.stacked(&d, &unknowns).unwrap();
        let (r, z) = compressed(&ext, &d, &unknowns).unwrap();
        assert_eq!(r.nrows(), unknowns.len() + 1);
        let gram = |m: &DMatrix<f64>, v: &DVector<f64>| (m.transpose() * m, m.transpose() * v);
        let (g0, h0) = gram(&j, &e);
        let (g1, h1) = gram(&r, &z);
        let scale = g0.amax();
        assert!((&g0 - &g1).amax() <= 1e-12 * scale);
        assert!((&h0 - &h1).amax() <= 1e-12 * h0.amax().max(1.0) * scale.sqrt());
        let (e0, e1) = (e.norm_squared(), z.norm_squared());
        assert!((e0 - e1).abs() <= 1e-12 * e0);
        // the least-squares fits leave the same residual sum of squares
        let rss = |m: &DMatrix<f64>, v: &DVector<f64>| {
            let svd = m.clone().svd(true, true);
            let top = svd.singular_values.max();
            let x = svd.solve(v, 1e-9 * top).unwrap();
            (v - m * x).norm_squared()
        };
        let (r0, r1) = (rss(&j, &e), rss(&r, &z));
        assert!(r0 < 0.9 * e0);
        assert!((r0 - r1).abs() <= 1e-9 * r0, "{r0} vs {r1}");
    }

    #[test]
    fn the_normal_equation_fit_of_many_poses_matches_the_tall_one() {
        use super::super::extended::{fit, uses_normal, Values};
        use crate::calib::lm::LmConfig;
        let d = data(2500);
        // without the tilting law the problem is smooth: both solvers reach the same minimum
        let mut ext = ExtModel::new(katana450(200.0).expect("preset"));
        ext.tilt = false;
        let unknowns: Vec<Unknown> = crate::calib::default_selection(&ext.model, false)
            .into_iter()
            .map(Unknown::Param)
            .chain([Unknown::JointScale(1)])
            .collect();
        let lm = LmConfig::default();
        // rtol 1e-4 takes the normal equations on 7500 residuals, 1e-7 the tall QR
        assert!(uses_normal(&d, 1e-4) && !uses_normal(&d, 1e-7));
        let normal = fit(&ext, &d, &unknowns, &lm, 1e-4, false).unwrap();
        let tall = fit(&ext, &d, &unknowns, &lm, 1e-7, false).unwrap();
        assert_eq!(normal.fitted, tall.fitted);
        assert!((normal.rss_mm2 - tall.rss_mm2).abs() <= 1e-9 * tall.rss_mm2);
        for (k, &u) in tall.fitted.iter().enumerate() {
            let (a, b) = (normal.model.value(u), tall.model.value(u));
            assert!((a - b).abs() <= 1e-3 * tall.sigma[k], "{u:?}: {a} vs {b}");
            assert!((normal.sigma[k] - tall.sigma[k]).abs() <= 1e-6 * tall.sigma[k]);
        }
    }
}
