//! The camera model fitted on the sheet's printed marks: a homography (sheet mm -> ideal pixel)
//! followed by radial lens distortion about the distortion centre `c`,
//! `p = c + d (1 + k1 r^2 + k2 r^4)`, `d = H(s) - c`, `r = |d| / L` with `L` the image's half
//! diagonal. Fitted by Levenberg-Marquardt (analytic Jacobian) on the four corner fiducials, the
//! orientation dot and the sheet-v2 ring dots; outlying ring dots (dust on a dot, a dot half
//! hidden) are dropped once and the fit repeated. A flatbed scan fits with k1 = k2 = 0.
//!
//! The distortion centre is fitted too when the marks ask for it: a photo cropped off its centre
//! has its lens's axis far from the image centre, and distortion taken about the wrong centre fits
//! the ring of marks while bending the inside of the ring by a tenth of a millimetre. The model is
//! fitted with the centre held at the image centre and with it free; the free centre is kept when
//! its two parameters explain far more than noise (an F test on the marks' residuals, `CameraParams::centre_f`),
//! otherwise two more parameters would only fit the marks' noise. While fitted, a weak prior
//! holds the centre near the image centre where little determines it (standard deviation a
//! quarter of the half diagonal, against a mark located to `CameraParams::mark_sigma_px`).

use crate::trace::Homography;
use nalgebra::{Matrix3, SMatrix, SVector};

/// Number of parameters: eight of the homography (h22 = 1), k1, k2, the distortion centre.
const NP: usize = 12;

/// Index of the distortion centre's first parameter (x, then y).
const CENTRE_AT: usize = 10;

/// A fitted camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraModel {
    /// Sheet mm -> ideal (undistorted) pixel.
    pub h: Matrix3<f64>,
    h_inv: Matrix3<f64>,
    pub k1: f64,
    pub k2: f64,
    /// Distortion centre, pixels (fitted; the image centre for a pure homography).
    pub centre_px: [f64; 2],
    /// Distortion radius unit (the image half diagonal), pixels.
    pub radius_px: f64,
}

/// How well the camera model explains the printed marks, sheet mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitQuality {
    /// RMS distance between the measured marks (mapped to the sheet) and their printed places.
    pub rms_mm: f64,
    pub max_mm: f64,
    /// Marks used / marks found.
    pub used: usize,
    pub found: usize,
}

impl CameraModel {
    /// A pure homography (`to_px`: sheet mm -> pixel) for an image of `size_px`.
    pub fn from_homography(to_px: &Homography, size_px: [f64; 2]) -> Option<Self> {
        Self::new(
            to_px.m,
            0.0,
            0.0,
            image_centre(size_px),
            half_diagonal(size_px),
        )
    }

    fn new(h: Matrix3<f64>, k1: f64, k2: f64, centre_px: [f64; 2], radius_px: f64) -> Option<Self> {
        let h = h / h[(2, 2)];
        let h_inv = h.try_inverse()?;
        let ok = [k1, k2, centre_px[0], centre_px[1], radius_px]
            .iter()
            .all(|v| v.is_finite());
        ok.then_some(Self {
            h,
            h_inv,
            k1,
            k2,
            centre_px,
            radius_px,
        })
    }

    /// Sheet mm -> pixel.
    pub fn to_px(&self, s: [f64; 2]) -> [f64; 2] {
        let v = self.h * nalgebra::Vector3::new(s[0], s[1], 1.0);
        let u = [v[0] / v[2], v[1] / v[2]];
        let d = [u[0] - self.centre_px[0], u[1] - self.centre_px[1]];
        let g = self.gain(d);
        [self.centre_px[0] + d[0] * g, self.centre_px[1] + d[1] * g]
    }

    /// Pixel -> sheet mm (the distortion is inverted by fixed-point iteration).
    pub fn to_mm(&self, p: [f64; 2]) -> [f64; 2] {
        let dd = [p[0] - self.centre_px[0], p[1] - self.centre_px[1]];
        let mut d = dd;
        if self.k1 != 0.0 || self.k2 != 0.0 {
            for _ in 0..12 {
                let g = self.gain(d);
                d = [dd[0] / g, dd[1] / g];
            }
        }
        let u = [self.centre_px[0] + d[0], self.centre_px[1] + d[1]];
        let v = self.h_inv * nalgebra::Vector3::new(u[0], u[1], 1.0);
        [v[0] / v[2], v[1] / v[2]]
    }

    fn gain(&self, d: [f64; 2]) -> f64 {
        let r2 = (d[0] * d[0] + d[1] * d[1]) / (self.radius_px * self.radius_px);
        1.0 + self.k1 * r2 + self.k2 * r2 * r2
    }

    /// Fits homography + k1, k2 + distortion centre to `sheet_mm[i] -> px[i]` (at least 12
    /// marks), starting from the homography through all marks with the centre at the image
    /// centre, the numbers of the fit from `params`. Returns the model and its quality.
    pub fn fit(
        sheet_mm: &[[f64; 2]],
        px: &[[f64; 2]],
        size_px: [f64; 2],
        params: &CameraParams,
    ) -> Option<(Self, FitQuality)> {
        if sheet_mm.len() != px.len() || sheet_mm.len() < 12 {
            return None;
        }
        let h0 = Homography::fit(sheet_mm, px)?;
        let start = Self::new(
            h0.m,
            0.0,
            0.0,
            image_centre(size_px),
            half_diagonal(size_px),
        )?;
        let prior = CentrePrior::at_image_centre(&start, params);
        let all: Vec<usize> = (0..px.len()).collect();
        let first = select(start, sheet_mm, px, &all, &prior)?;
        // Drop marks far off the first fit (robust scale from the median) and refit.
        let res: Vec<f64> = all
            .iter()
            .map(|&i| err_mm(&first, sheet_mm[i], px[i]))
            .collect();
        let mut sorted = res.clone();
        sorted.sort_by(|a, b| a.total_cmp(b));
        let med = sorted[sorted.len() / 2];
        let keep: Vec<usize> = all
            .iter()
            .copied()
            .filter(|&i| i < 5 || res[i] <= (5.0 * med).max(0.05))
            .collect();
        let model = if keep.len() < all.len() {
            select(first, sheet_mm, px, &keep, &prior)?
        } else {
            first
        };
        let errs: Vec<f64> = keep
            .iter()
            .map(|&i| err_mm(&model, sheet_mm[i], px[i]))
            .collect();
        let rms_mm = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len() as f64).sqrt();
        let max_mm = errs.iter().fold(0.0, |a: f64, &b| a.max(b));
        Some((
            model,
            FitQuality {
                rms_mm,
                max_mm,
                used: keep.len(),
                found: px.len(),
            },
        ))
    }

    fn params(&self) -> SVector<f64, NP> {
        let h = &self.h;
        SVector::<f64, NP>::from_column_slice(&[
            h[(0, 0)],
            h[(0, 1)],
            h[(0, 2)],
            h[(1, 0)],
            h[(1, 1)],
            h[(1, 2)],
            h[(2, 0)],
            h[(2, 1)],
            self.k1,
            self.k2,
            self.centre_px[0],
            self.centre_px[1],
        ])
    }

    fn with_params(&self, p: &SVector<f64, NP>) -> Option<Self> {
        let h = Matrix3::new(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], 1.0);
        let c = [p[CENTRE_AT], p[CENTRE_AT + 1]];
        Self::new(h, p[8], p[9], c, self.radius_px)
    }

    /// The pixel of sheet point `s` and its Jacobian with respect to the parameters.
    pub(crate) fn project_with_jacobian(&self, s: [f64; 2]) -> ([f64; 2], SMatrix<f64, 2, NP>) {
        let h = &self.h;
        let (x, y) = (s[0], s[1]);
        let w = h[(2, 0)] * x + h[(2, 1)] * y + 1.0;
        let u = (h[(0, 0)] * x + h[(0, 1)] * y + h[(0, 2)]) / w;
        let v = (h[(1, 0)] * x + h[(1, 1)] * y + h[(1, 2)]) / w;
        let mut du = SMatrix::<f64, 2, NP>::zeros();
        du[(0, 0)] = x / w;
        du[(0, 1)] = y / w;
        du[(0, 2)] = 1.0 / w;
        du[(1, 3)] = x / w;
        du[(1, 4)] = y / w;
        du[(1, 5)] = 1.0 / w;
        du[(0, 6)] = -u * x / w;
        du[(0, 7)] = -u * y / w;
        du[(1, 6)] = -v * x / w;
        du[(1, 7)] = -v * y / w;
        let d = [u - self.centre_px[0], v - self.centre_px[1]];
        let l2 = self.radius_px * self.radius_px;
        let rho = (d[0] * d[0] + d[1] * d[1]) / l2;
        let g = 1.0 + self.k1 * rho + self.k2 * rho * rho;
        let dg = self.k1 + 2.0 * self.k2 * rho; // dg/drho
                                                // dp/du = g I + d (dg/du)^T, dg/du = dg * 2 d / L^2
        let a = SMatrix::<f64, 2, 2>::new(
            g + d[0] * dg * 2.0 * d[0] / l2,
            d[0] * dg * 2.0 * d[1] / l2,
            d[1] * dg * 2.0 * d[0] / l2,
            g + d[1] * dg * 2.0 * d[1] / l2,
        );
        let mut j = a * du;
        j[(0, 8)] = d[0] * rho;
        j[(1, 8)] = d[1] * rho;
        j[(0, 9)] = d[0] * rho * rho;
        j[(1, 9)] = d[1] * rho * rho;
        // p = c + g(d) d with d = u - c: dp/dc = I - dp/du's distortion part `a`.
        let dc = SMatrix::<f64, 2, 2>::identity() - a;
        j.fixed_view_mut::<2, 2>(0, CENTRE_AT).copy_from(&dc);
        (
            [self.centre_px[0] + d[0] * g, self.centre_px[1] + d[1] * g],
            j,
        )
    }
}

/// Distance on the sheet between the mark measured at `p` and its printed place `s`, mm.
fn err_mm(m: &CameraModel, s: [f64; 2], p: [f64; 2]) -> f64 {
    let q = m.to_mm(p);
    (q[0] - s[0]).hypot(q[1] - s[1])
}

/// The image centre of an image of `size_px`.
fn image_centre(size_px: [f64; 2]) -> [f64; 2] {
    [size_px[0] / 2.0, size_px[1] / 2.0]
}

/// The half diagonal of an image of `size_px`: the distortion's radius unit.
fn half_diagonal(size_px: [f64; 2]) -> f64 {
    0.5 * size_px[0].hypot(size_px[1])
}

/// The weak prior on the distortion centre: a pseudo-residual `weight * (c0 - c)` (pixels) beside
/// the marks' residuals.
struct CentrePrior {
    centre_px: [f64; 2],
    weight: f64,
    /// The F statistic above which the fitted centre is kept ([`CameraParams::centre_f`]).
    keep_f: f64,
}

impl CentrePrior {
    fn at_image_centre(start: &CameraModel, params: &CameraParams) -> Self {
        Self {
            centre_px: start.centre_px,
            weight: params.mark_sigma_px / (params.centre_sigma_half_diagonals * start.radius_px),
            keep_f: params.centre_f,
        }
    }

    fn residual(&self, m: &CameraModel) -> [f64; 2] {
        [
            self.weight * (self.centre_px[0] - m.centre_px[0]),
            self.weight * (self.centre_px[1] - m.centre_px[1]),
        ]
    }
}

/// The sum of the squared pixel residuals of the marks `idx`.
fn marks_cost(m: &CameraModel, s: &[[f64; 2]], p: &[[f64; 2]], idx: &[usize]) -> f64 {
    idx.iter()
        .map(|&i| {
            let q = m.to_px(s[i]);
            (q[0] - p[i][0]).powi(2) + (q[1] - p[i][1]).powi(2)
        })
        .sum::<f64>()
}

/// What LM minimises: the marks' squared residuals, plus the prior's when the centre is fitted.
fn cost(
    m: &CameraModel,
    s: &[[f64; 2]],
    p: &[[f64; 2]],
    idx: &[usize],
    prior: Option<&CentrePrior>,
) -> f64 {
    let r = prior.map_or([0.0, 0.0], |pr| pr.residual(m));
    marks_cost(m, s, p, idx) + r[0] * r[0] + r[1] * r[1]
}

/// Fits the marks `idx` from `from` twice, the distortion centre held at the image centre and
/// free, and keeps the free centre only when the F test says its two parameters explain more
/// than the marks' noise.
fn select(
    from: CameraModel,
    s: &[[f64; 2]],
    p: &[[f64; 2]],
    idx: &[usize],
    prior: &CentrePrior,
) -> Option<CameraModel> {
    let at_image_centre =
        CameraModel::new(from.h, from.k1, from.k2, prior.centre_px, from.radius_px)?;
    let held = lm(at_image_centre, s, p, idx, None)?;
    let free = lm(held, s, p, idx, Some(prior))?;
    let dof = (2 * idx.len()).saturating_sub(NP);
    if dof == 0 {
        return Some(held);
    }
    let (c_held, c_free) = (marks_cost(&held, s, p, idx), marks_cost(&free, s, p, idx));
    let variance = (c_free / dof as f64).max(1e-12);
    let f = 0.5 * (c_held - c_free) / variance;
    Some(if f > prior.keep_f { free } else { held })
}

/// Levenberg-Marquardt on the pixel residuals of the marks `idx` (Marquardt's diagonal scaling),
/// with the distortion centre fitted under `prior`, or held where it is (`None`).
fn lm(
    start: CameraModel,
    s: &[[f64; 2]],
    p: &[[f64; 2]],
    idx: &[usize],
    prior: Option<&CentrePrior>,
) -> Option<CameraModel> {
    let mut m = start;
    let mut c = cost(&m, s, p, idx, prior);
    let mut lambda = 1e-3;
    for _ in 0..100 {
        let mut jtj = SMatrix::<f64, NP, NP>::zeros();
        let mut jtr = SVector::<f64, NP>::zeros();
        for &i in idx {
            let (q, j) = m.project_with_jacobian(s[i]);
            let r = nalgebra::Vector2::new(p[i][0] - q[0], p[i][1] - q[1]);
            jtj += j.transpose() * j;
            jtr += j.transpose() * r;
        }
        match prior {
            // The prior's residual w (c0 - c) has the Jacobian -w I on the centre's parameters.
            Some(prior) => {
                let r = prior.residual(&m);
                for k in 0..2 {
                    jtj[(CENTRE_AT + k, CENTRE_AT + k)] += prior.weight * prior.weight;
                    jtr[CENTRE_AT + k] += prior.weight * r[k];
                }
            }
            // Held: the centre's rows and columns are taken out of the step.
            None => {
                for k in CENTRE_AT..CENTRE_AT + 2 {
                    jtj.row_mut(k).fill(0.0);
                    jtj.column_mut(k).fill(0.0);
                    jtj[(k, k)] = 1.0;
                    jtr[k] = 0.0;
                }
            }
        }
        let mut improved = false;
        for _ in 0..10 {
            let mut a = jtj;
            for k in 0..NP {
                a[(k, k)] += lambda * jtj[(k, k)].max(1e-12);
            }
            let Some(step) = a.lu().solve(&jtr) else {
                lambda *= 10.0;
                continue;
            };
            let Some(next) = m.with_params(&(m.params() + step)) else {
                lambda *= 10.0;
                continue;
            };
            let nc = cost(&next, s, p, idx, prior);
            if nc.is_finite() && nc < c {
                let rel = (c - nc) / c.max(1e-300);
                m = next;
                c = nc;
                lambda = (lambda / 10.0).max(1e-12);
                improved = rel > 1e-12;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    Some(m)
}

mod params;
pub use params::CameraParams;
#[cfg(test)]
mod tests;
