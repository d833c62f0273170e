//! The probe design's physical side: the fitted physical parameters alone refitted without
//! each group of poses (the physical cross-validation the probe's terms are judged against),
//! and how many parameter combinations the poses support.

use nalgebra::{DMatrix, DVector, Vector3};

use super::design::{Design, LOO_MAX_POSES};

impl Design {
    /// Number of fitted physical parameters whose Jacobians the design holds.
    pub fn n_physical(&self) -> usize {
        if self.jac.is_empty() {
            0
        } else {
            self.total.n.nrows()
        }
    }

    /// The groups left out by the physical cross-validation: every pose alone (leave-one-out)
    /// up to [`LOO_MAX_POSES`] poses, so that each training set keeps as many residuals per
    /// parameter as the poses allow; the design's folds above.
    fn physical_groups(&self) -> Vec<Vec<usize>> {
        if self.m.len() <= LOO_MAX_POSES {
            (0..self.m.len()).map(|k| vec![k]).collect()
        } else {
            self.members.clone()
        }
    }

    /// `sum L^T L` and `sum L^T m` over the poses `group`.
    fn group_sums(&self, group: &[usize]) -> (DMatrix<f64>, DVector<f64>) {
        let p = self.total.n.nrows();
        let mut n = DMatrix::zeros(p, p);
        let mut h = DVector::zeros(p);
        for &k in group {
            let l = &self.jac[k];
            n += l.transpose() * l;
            h += l.transpose() * self.m[k];
        }
        (n, h)
    }

    /// Held-out residual (measured part, mm) of every pose when the **physical parameters alone**
    /// are refitted without its group ([`Design::physical_groups`]), linearised at the final
    /// fit: with `N_g`, `h_g` the sums of `L^T L` and `L^T m` over group `g`, the fit on the
    /// other poses moves the parameters by `N_{-g}^+ (h - h_g)` and the held-out residual is
    /// `m_k - L_k N_{-g}^+ (h - h_g)` (exact for a model linear in its parameters). Also the
    /// expected ratio of their sum of squares to the residual's for a right model with
    /// independent noise of equal variance in every measured component,
    /// `(m + sum_g tr(N_g N_{-g}^+)) / m` over the `m` = `n_components` components (the exact
    /// leverage of every group). Without Jacobians: the residual itself and 1.
    pub fn physical_cv(&self, n_components: usize) -> (Vec<Vector3<f64>>, f64) {
        let mut out = self.m.clone();
        if self.jac.is_empty() || n_components == 0 {
            return (out, 1.0);
        }
        let mut extra = 0.0;
        for group in self.physical_groups() {
            let (ng, hg) = self.group_sums(&group);
            let n = &self.total.n - &ng;
            let scale = n.diagonal().amax().max(f64::MIN_POSITIVE);
            let Ok(ninv) = n.pseudo_inverse(1e-10 * scale) else {
                continue;
            };
            let delta = &ninv * (&self.total.h - hg);
            if !delta.iter().all(|v| v.is_finite()) {
                continue;
            }
            extra += (ng * &ninv).trace();
            for &k in &group {
                out[k] = self.m[k] - &self.jac[k] * &delta;
            }
        }
        let m = n_components as f64;
        (out, ((m + extra.max(0.0)) / m).max(1.0))
    }

    /// How many parameter combinations these poses support: the physical problem linearised at
    /// the final fit, `z_k = m_k + L_k d` with `d` the fitted parameters' departure from their
    /// starting values (`nd = N d` given), is refitted on the directions of the `r` largest
    /// eigenvalues of the column-scaled `N` of the training folds only (a truncated-SVD fit),
    /// for `r = 0 ..= p`; the `r` with the least k-fold held-out squared error is returned.
    /// `None` without Jacobians.
    pub fn supported_parameters(&self, d: &DVector<f64>) -> Option<usize> {
        let p = self.n_physical();
        if p == 0 || d.len() != p {
            return None;
        }
        let scale: Vec<f64> = (0..p)
            .map(|i| {
                let v = self.total.n[(i, i)];
                if v > 0.0 {
                    1.0 / v.sqrt()
                } else {
                    0.0
                }
            })
            .collect();
        let sd = DMatrix::from_diagonal(&DVector::from_vec(scale));
        let mut sse = vec![0.0; p + 1];
        for (g, members) in self.members.iter().enumerate() {
            let fold = &self.per_fold[g];
            let n_tr = &self.total.n - &fold.n;
            let h_tr = (&self.total.h - &fold.h) + &n_tr * d;
            let ns = &sd * n_tr * &sd;
            let hs = &sd * h_tr;
            let eig = ns.symmetric_eigen();
            let mut order: Vec<usize> = (0..p).collect();
            order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
            let top = eig.eigenvalues[order[0]].max(f64::MIN_POSITIVE);
            let mut x = DVector::zeros(p);
            let z: Vec<Vector3<f64>> = members
                .iter()
                .map(|&k| self.m[k] + &self.jac[k] * d)
                .collect();
            for r in 0..=p {
                if r > 0 {
                    let i = order[r - 1];
                    let lam = eig.eigenvalues[i];
                    if lam > 1e-12 * top {
                        let v = eig.eigenvectors.column(i);
                        x += v * (v.dot(&hs) / lam);
                    }
                }
                let theta = &sd * &x;
                sse[r] += members
                    .iter()
                    .zip(&z)
                    .map(|(&k, zk)| (zk - &self.jac[k] * &theta).norm_squared())
                    .sum::<f64>();
            }
        }
        (0..=p).min_by(|&a, &b| sse[a].total_cmp(&sse[b]))
    }
}
