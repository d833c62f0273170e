//! Priors for ill-posed identifications: many parameters on few poses.
//!
//! With about as many unknowns as measured coordinates, a least-squares fit reaches the
//! calibration poses by moving weakly seen combinations of the robot's geometry far from any
//! real arm's errors (TIAGo, 31 parameters on 37 postures: a torso 300 mm shorter and turned by
//! 20 deg against a base turned back by 19 deg), and extrapolates badly to other poses. A prior
//! draws every fitted parameter of the robot's own geometry toward its input value:
//! the rows `sqrt(w) (x_i - x0_i) / s_i` are appended to the residuals, with a physical scale
//! `s_i` per kind ([`PriorScales`]: 1 mm for lengths, 0.1 deg for angles by default) and one
//! weight `w` (mm^2 of squared residual per squared scale). The instrument's frame (`Base`), the
//! measured point (`Tool`) and the point offsets have no prior: they are anywhere.
//!
//! The weight is chosen by leave-one-pose-out cross-validation ([`choose_weight`]): the fit is
//! made at every weight of a grid (0 included) and scored by the block PRESS of its linearisation
//! at its solution (exact for linear ridge regression: the prior rows are never left out); the
//! lowest PRESS wins, 0 when no weight lowers it by [`MIN_GAIN`]. Applied automatically only
//! when the set is ill-posed ([`ill_posed`]), so well-posed sets fit exactly as without it.

use nalgebra::{DMatrix, DVector};

use super::lm::Problem;
use crate::model::{Model, ParamKind};

/// Default prior scale of a length (mm).
pub const LENGTH_SCALE_MM: f64 = 1.0;
/// Default prior scale of an angle (deg).
pub const ANGLE_SCALE_DEG: f64 = 0.1;
/// A set is ill-posed below this many measured coordinates per fitted unknown.
pub const ILL_POSED_REDUNDANCY: f64 = 10.0;
/// Weights tried by [`choose_weight`] besides 0 (a log grid, mm^2 per squared scale).
pub const WEIGHT_GRID: [f64; 13] = [
    1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0,
];
/// A weight is chosen only when it lowers the PRESS of the unregularised fit by this share.
pub const MIN_GAIN: f64 = 0.02;

/// How the prior is used (`calibrate --prior`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum PriorMode {
    /// Weight by cross-validation when the set is ill-posed ([`ill_posed`]), none otherwise.
    #[default]
    Auto,
    /// No prior.
    Off,
    /// This weight, whatever the set.
    Weight(f64),
}

impl std::str::FromStr for PriorMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(PriorMode::Auto),
            "off" => Ok(PriorMode::Off),
            w => match w.parse::<f64>() {
                Ok(v) if v.is_finite() && v >= 0.0 => Ok(PriorMode::Weight(v)),
                _ => Err(format!(
                    "`{w}`: the prior is `auto`, `off` or a weight >= 0 (mm^2 per squared scale)"
                )),
            },
        }
    }
}

/// Prior scales per kind of parameter (`calibrate --prior-scale length=1,angle=0.1`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PriorScales {
    /// Lengths of the chain (mm).
    pub length_mm: f64,
    /// Joint offsets and twists (deg).
    pub angle_deg: f64,
}

impl Default for PriorScales {
    fn default() -> Self {
        Self {
            length_mm: LENGTH_SCALE_MM,
            angle_deg: ANGLE_SCALE_DEG,
        }
    }
}

impl std::str::FromStr for PriorScales {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let mut out = PriorScales::default();
        for part in s.split(',').filter(|p| !p.trim().is_empty()) {
            let (k, v) = part
                .split_once('=')
                .ok_or_else(|| format!("`{part}`: expected length=MM or angle=DEG"))?;
            let v: f64 = v
                .trim()
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite() && *v > 0.0)
                .ok_or_else(|| format!("`{part}`: the scale is a number > 0"))?;
            match k.trim() {
                "length" => out.length_mm = v,
                "angle" => out.angle_deg = v,
                other => return Err(format!("`{other}`: the kinds are `length` and `angle`")),
            }
        }
        Ok(out)
    }
}

impl PriorScales {
    /// The scale of model parameter `i` (its unit), `None` for a parameter without prior (the
    /// instrument frame, the tool point, terms of laws).
    pub fn of(&self, model: &Model, i: usize) -> Option<f64> {
        match model.params().get(i)?.kind {
            ParamKind::Length => Some(self.length_mm),
            ParamKind::JointOffset | ParamKind::Twist => Some(self.angle_deg),
            _ => None,
        }
    }
}

/// Whether `n_residuals` measured coordinates are few for `n_unknowns` unknowns.
pub fn ill_posed(n_residuals: usize, n_unknowns: usize) -> bool {
    (n_residuals as f64) < ILL_POSED_REDUNDANCY * n_unknowns as f64
}

/// A prior on the unknowns of a solve: start values, scales (`None`: no row) and the weight.
#[derive(Debug, Clone, PartialEq)]
pub struct Prior {
    pub weight: f64,
    pub x0: DVector<f64>,
    pub scales: Vec<Option<f64>>,
}

impl Prior {
    /// Number of prior rows.
    pub fn n_rows(&self) -> usize {
        self.scales.iter().flatten().count()
    }

    /// Appends the rows `sqrt(w) (x_i - x0_i) / s_i` (and their Jacobian) from row `row`.
    fn put(
        &self,
        x: &DVector<f64>,
        row: usize,
        r: &mut DVector<f64>,
        jac: Option<&mut DMatrix<f64>>,
    ) {
        let sw = self.weight.sqrt();
        let mut k = row;
        let mut jac = jac;
        for (i, s) in self.scales.iter().enumerate() {
            if let Some(s) = s {
                r[k] = sw * (x[i] - self.x0[i]) / s;
                if let Some(j) = jac.as_deref_mut() {
                    j.row_mut(k).fill(0.0);
                    j[(k, i)] = sw / s;
                }
                k += 1;
            }
        }
    }

    /// `J^T J` of the prior rows (diagonal).
    pub fn normal(&self) -> DVector<f64> {
        DVector::from_iterator(
            self.scales.len(),
            self.scales
                .iter()
                .map(|s| s.map_or(0.0, |s| self.weight / (s * s))),
        )
    }
}

/// A problem with a prior's rows after its own.
pub struct WithPrior<'a, P> {
    pub inner: &'a mut P,
    pub prior: &'a Prior,
    r: DVector<f64>,
    jac: DMatrix<f64>,
}

impl<'a, P: Problem> WithPrior<'a, P> {
    pub fn new(inner: &'a mut P, prior: &'a Prior) -> Self {
        let (m, n) = (inner.n_residuals(), inner.n_params());
        Self {
            inner,
            prior,
            r: DVector::zeros(m),
            jac: DMatrix::zeros(m, n),
        }
    }
}

impl<P: Problem> Problem for WithPrior<'_, P> {
    type Error = P::Error;

    fn n_params(&self) -> usize {
        self.inner.n_params()
    }

    fn n_residuals(&self) -> usize {
        self.inner.n_residuals() + self.prior.n_rows()
    }

    fn evaluate(
        &mut self,
        x: &DVector<f64>,
        r: &mut DVector<f64>,
        jac: Option<&mut DMatrix<f64>>,
    ) -> Result<(), P::Error> {
        let m = self.r.len();
        match jac {
            Some(j) => {
                self.inner.evaluate(x, &mut self.r, Some(&mut self.jac))?;
                r.rows_mut(0, m).copy_from(&self.r);
                j.rows_mut(0, m).copy_from(&self.jac);
                self.prior.put(x, m, r, Some(j));
            }
            None => {
                self.inner.evaluate(x, &mut self.r, None)?;
                r.rows_mut(0, m).copy_from(&self.r);
                self.prior.put(x, m, r, None);
            }
        }
        Ok(())
    }
}

/// The column scales `d` (`d_j = sqrt(|J_j|^2 + P_jj)`) and the pseudo-inverse of the scaled
/// regularised normal matrix `D^-1 (J^T J + P) D^-1` (`P` diagonal, `prior_diag`; singular values
/// below 1e-12 of the largest dropped): what the leave-one-out error of a ridge fit
/// ([`ridge_press`]) and a fit's prediction uncertainty ([`super::predict`]) are made of.
/// `None` when `prior_diag` does not match the columns or the SVD fails.
pub fn scaled_normal_inverse(
    jac: &DMatrix<f64>,
    prior_diag: &DVector<f64>,
) -> Option<(Vec<f64>, DMatrix<f64>)> {
    let n = jac.ncols();
    if prior_diag.len() != n {
        return None;
    }
    let d: Vec<f64> = (0..n)
        .map(|j| {
            (jac.column(j).norm_squared() + prior_diag[j])
                .sqrt()
                .max(1e-300)
        })
        .collect();
    let mut a = jac.transpose() * jac;
    for j in 0..n {
        a[(j, j)] += prior_diag[j];
    }
    let scaled = DMatrix::from_fn(n, n, |r, c| a[(r, c)] / (d[r] * d[c]));
    let svd = scaled.svd(true, true);
    let top = svd.singular_values.max();
    let inv = svd.pseudo_inverse(1e-12 * top).ok()?;
    Some((d, inv))
}

/// Block PRESS of a regularised linearisation: data Jacobian `jac` and residuals `r` at the
/// solution, prior normal diagonal `prior_diag` (`J^T J` of the prior rows), rows in blocks of
/// `blocks`; leaving block `i` out predicts it with error `(I - H_ii)^-1 e_i`,
/// `H = J (J^T J + P)^-1 J^T`. `None` when the blocks do not cover the rows or a block is fully
/// explained by its own unknowns.
pub fn ridge_press(
    jac: &DMatrix<f64>,
    r: &DVector<f64>,
    prior_diag: &DVector<f64>,
    blocks: &[usize],
) -> Option<f64> {
    let (m, n) = (jac.nrows(), jac.ncols());
    if blocks.iter().sum::<usize>() != m || r.len() != m || prior_diag.len() != n {
        return None;
    }
    let (d, inv) = scaled_normal_inverse(jac, prior_diag)?;
    let mut js = jac.clone();
    for (j, dj) in d.iter().enumerate() {
        js.column_mut(j).unscale_mut(*dj);
    }
    let mut press = 0.0;
    let mut start = 0;
    for &size in blocks {
        let jb = js.rows(start, size);
        let h = jb * &inv * jb.transpose();
        let i_h = DMatrix::identity(size, size) - h;
        let loo = i_h.lu().solve(&r.rows(start, size).into_owned())?;
        if !loo.iter().all(|v| v.is_finite()) {
            return None;
        }
        press += loo.norm_squared();
        start += size;
    }
    Some(press)
}

/// The weight of lowest PRESS among `0` and [`WEIGHT_GRID`]: `press_at(w)` fits at weight `w`
/// and returns the PRESS of that fit (`None`: no score). Returns the weight and the PRESS of
/// every weight scored, in grid order.
pub fn choose_weight<E>(
    mut press_at: impl FnMut(f64) -> Result<Option<f64>, E>,
) -> Result<(f64, Vec<(f64, f64)>), E> {
    let mut scores = Vec::new();
    for w in std::iter::once(0.0).chain(WEIGHT_GRID) {
        if let Some(p) = press_at(w)? {
            if p.is_finite() {
                scores.push((w, p));
            }
        }
    }
    let zero = scores.iter().find(|(w, _)| *w == 0.0).map(|s| s.1);
    let best = scores
        .iter()
        .copied()
        .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.total_cmp(&b.0)));
    let chosen = match (best, zero) {
        (Some((w, p)), Some(z)) if p < (1.0 - MIN_GAIN) * z => w,
        (Some((w, _)), None) => w,
        _ => 0.0,
    };
    Ok((chosen, scores))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::press::tests::leave_one_out;

    /// The ridge PRESS of the residuals at a solution equals brute-force leave-one-out of the
    /// same ridge fit (weight 0: plain least squares).
    #[test]
    fn ridge_press_matches_brute_force() {
        let n = 10;
        let t: Vec<f64> = (0..n).map(|i| i as f64 - 4.5).collect();
        let jac = DMatrix::from_fn(n, 2, |i, c| if c == 0 { 1.0 } else { t[i] });
        let y = DVector::from_fn(n, |i, _| 0.3 + 0.7 * t[i] + 0.05 * ((i * 7) % 5) as f64);
        let ridge = |a: &DMatrix<f64>, b: &DVector<f64>, w: f64| {
            let mut ata = a.transpose() * a;
            ata[(1, 1)] += w;
            ata.try_inverse().unwrap() * a.transpose() * b
        };
        for w in [0.0, 0.5, 4.0] {
            let brute = leave_one_out(&jac, &y, |a, b| ridge(a, b, w));
            let e = &y - &jac * ridge(&jac, &y, w);
            let p = DVector::from_vec(vec![0.0, w]);
            let press = ridge_press(&jac, &e, &p, &vec![1; n]).unwrap();
            assert!(
                (press - brute).abs() < 1e-9 * brute,
                "w {w}: {press} vs {brute}"
            );
        }
        assert!(ridge_press(&jac, &y, &DVector::zeros(2), &[3, 3]).is_none());
    }

    #[test]
    fn weight_of_lowest_press_and_zero_without_gain() {
        let (w, _) = choose_weight(|w| {
            Ok::<_, ()>(Some(
                1.0 + (w.ln() - 0.1f64.ln()).powi(2) * 0.01 - if w == 0.0 { -5.0 } else { 0.0 },
            ))
        })
        .unwrap();
        assert!((w - 0.1).abs() < 1e-12, "{w}");
        let (w, _) =
            choose_weight(|w| Ok::<_, ()>(Some(if w == 0.0 { 1.0 } else { 0.995 }))).unwrap();
        assert_eq!(w, 0.0);
    }

    #[test]
    fn modes_and_scales_parse() {
        assert_eq!("auto".parse::<PriorMode>(), Ok(PriorMode::Auto));
        assert_eq!("0.3".parse::<PriorMode>(), Ok(PriorMode::Weight(0.3)));
        assert!("-1".parse::<PriorMode>().is_err());
        let s: PriorScales = "length=2,angle=0.05".parse().unwrap();
        assert_eq!((s.length_mm, s.angle_deg), (2.0, 0.05));
        assert!("mass=1".parse::<PriorScales>().is_err());
    }
}
