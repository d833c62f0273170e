//! Plane-to-plane homography by the normalised direct linear transform (Hartley & Zisserman,
//! "Multiple View Geometry", alg. 4.2).

use nalgebra::{Matrix3, SMatrix, Vector3};

/// A 3x3 homography mapping `from` points to `to` points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Homography {
    pub m: Matrix3<f64>,
}

impl Homography {
    /// Fits a homography to `n >= 4` correspondences (least squares in the algebraic error,
    /// exact for 4 points in general position). `None` if the points are degenerate.
    pub fn fit(from: &[[f64; 2]], to: &[[f64; 2]]) -> Option<Self> {
        if from.len() != to.len() || from.len() < 4 {
            return None;
        }
        let (tf, nf) = normalise(from)?;
        let (tt, nt) = normalise(to)?;
        let mut ata = SMatrix::<f64, 9, 9>::zeros();
        for (p, q) in nf.iter().zip(&nt) {
            let (x, y, u, v) = (p[0], p[1], q[0], q[1]);
            let r1 = [-x, -y, -1.0, 0.0, 0.0, 0.0, u * x, u * y, u];
            let r2 = [0.0, 0.0, 0.0, -x, -y, -1.0, v * x, v * y, v];
            for r in [r1, r2] {
                for i in 0..9 {
                    for j in 0..9 {
                        ata[(i, j)] += r[i] * r[j];
                    }
                }
            }
        }
        let eig = ata.symmetric_eigen();
        let (imin, _) = eig
            .eigenvalues
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))?;
        let h = eig.eigenvectors.column(imin);
        let hn = Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
        let m = tt.try_inverse()? * hn * tf;
        let scale = m[(2, 2)];
        if !scale.is_finite() || scale.abs() < 1e-300 {
            return None;
        }
        let m = m / scale;
        m.iter().all(|v| v.is_finite()).then_some(Self { m })
    }

    /// Maps one point.
    pub fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let v = self.m * Vector3::new(p[0], p[1], 1.0);
        [v[0] / v[2], v[1] / v[2]]
    }

    /// The inverse mapping, if the matrix is invertible.
    pub fn inverse(&self) -> Option<Self> {
        self.m.try_inverse().map(|m| Self { m })
    }
}

/// Hartley normalisation: centroid to the origin, mean distance sqrt(2).
fn normalise(pts: &[[f64; 2]]) -> Option<(Matrix3<f64>, Vec<[f64; 2]>)> {
    let n = pts.len() as f64;
    let cx = pts.iter().map(|p| p[0]).sum::<f64>() / n;
    let cy = pts.iter().map(|p| p[1]).sum::<f64>() / n;
    let mean_d = pts
        .iter()
        .map(|p| (p[0] - cx).hypot(p[1] - cy))
        .sum::<f64>()
        / n;
    if !(mean_d.is_finite() && mean_d > 0.0) {
        return None;
    }
    let s = std::f64::consts::SQRT_2 / mean_d;
    let t = Matrix3::new(s, 0.0, -s * cx, 0.0, s, -s * cy, 0.0, 0.0, 1.0);
    Some((
        t,
        pts.iter()
            .map(|p| [s * (p[0] - cx), s * (p[1] - cy)])
            .collect(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_known_projective_map() {
        let truth = Matrix3::new(0.9, -0.1, 30.0, 0.05, 1.1, -12.0, 1e-4, -2e-4, 1.0);
        let h = Homography { m: truth };
        let from = [[0.0, 0.0], [1000.0, 10.0], [980.0, 1500.0], [-20.0, 1490.0]];
        let to: Vec<_> = from.iter().map(|p| h.apply(*p)).collect();
        let fit = Homography::fit(&from, &to).expect("fit");
        for p in [[500.0, 700.0], [10.0, 1400.0], [-300.0, 2000.0]] {
            let (a, b) = (h.apply(p), fit.apply(p));
            assert!(
                (a[0] - b[0]).abs() < 1e-8 && (a[1] - b[1]).abs() < 1e-8,
                "{a:?} {b:?}"
            );
        }
        let back = fit.inverse().expect("inverse").apply(to[2]);
        assert!((back[0] - from[2][0]).abs() < 1e-8 && (back[1] - from[2][1]).abs() < 1e-8);
    }

    #[test]
    fn degenerate_points_give_none() {
        let same = [[1.0, 1.0]; 4];
        assert!(Homography::fit(&same, &same).is_none());
        assert!(Homography::fit(&same[..3], &same[..3]).is_none());
    }
}
