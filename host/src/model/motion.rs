//! Joint moments along a logged joint trajectory (the declared tilting in motion).

use nalgebra::Vector3;

use super::dynamics::{moments_kgfm, Inertia};
use super::{Model, ModelError};

/// Joint moments in motion (kgf.m, joint frames) of `model` at every logged sample: joint rates
/// and accelerations by central differences over the neighbouring samples when both lie within
/// 1.5 times the median sample interval (one-sided rate and zero acceleration when only one
/// does, the arm at rest when none does), then recursive Newton-Euler with slender-rod links
/// ([`crate::model::dynamics`]).
pub fn moments_in_motion(
    model: &Model,
    t_s: &[f64],
    q_deg: &[Vec<f64>],
) -> Result<Vec<Vec<Vector3<f64>>>, ModelError> {
    let n = t_s.len().min(q_deg.len());
    let mut dts: Vec<f64> = t_s[..n]
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .collect();
    dts.sort_by(f64::total_cmp);
    let max_dt = 1.5 * dts.get(dts.len() / 2).copied().unwrap_or(0.0);
    let near = |a: usize, b: usize| {
        let d = (t_s[b] - t_s[a]).abs();
        d > 0.0 && d <= max_dt
    };
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let prev = (k > 0 && near(k - 1, k)).then(|| k - 1);
        let next = (k + 1 < n && near(k, k + 1)).then_some(k + 1);
        let nj = q_deg[k].len();
        let (mut qd, mut qdd) = (vec![0.0; nj], vec![0.0; nj]);
        for j in 0..nj {
            let q = |i: usize| q_deg[i][j];
            match (prev, next) {
                (Some(a), Some(b)) => {
                    let (h1, h2) = (t_s[k] - t_s[a], t_s[b] - t_s[k]);
                    let d1 = (q(k) - q(a)) / h1;
                    let d2 = (q(b) - q(k)) / h2;
                    qd[j] = (d1 * h2 + d2 * h1) / (h1 + h2);
                    qdd[j] = 2.0 * (d2 - d1) / (h1 + h2);
                }
                (Some(a), None) => qd[j] = (q(k) - q(a)) / (t_s[k] - t_s[a]),
                (None, Some(b)) => qd[j] = (q(b) - q(k)) / (t_s[b] - t_s[k]),
                (None, None) => {}
            }
        }
        out.push(moments_kgfm(
            model,
            &q_deg[k],
            &qd,
            &qdd,
            Inertia::default(),
        )?);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::katana450;

    #[test]
    fn at_rest_the_moments_are_the_static_ones_and_motion_changes_them() {
        let m = katana450(330.0).unwrap();
        let q0 = vec![-90.0, 60.0, -60.0, 10.0, 90.0];
        let t: Vec<f64> = (0..5).map(|k| k as f64 * 0.01).collect();
        let still = vec![q0.clone(); 5];
        let mo = moments_in_motion(&m, &t, &still).unwrap();
        let stat = m.moments_kgfm(&q0).unwrap();
        for (a, b) in mo[2].iter().zip(&stat) {
            assert!((a - b).norm() < 1e-12);
        }
        // joint 1 accelerating at 100 deg/s^2: a torque about its axis appears
        let moving: Vec<Vec<f64>> = t
            .iter()
            .map(|&tk| {
                let mut q = q0.clone();
                q[0] += 50.0 * tk * tk;
                q
            })
            .collect();
        let mo = moments_in_motion(&m, &t, &moving).unwrap();
        assert!(mo[2][0].z.abs() > 1e-4, "{}", mo[2][0].z);
    }
}
