//! Least-squares identification of each joint's clearance tilt C, backlash b and stiffness k
//! from inclinometer readings (MODEL.md eq. 5.16-5.19; thesis 4.4.1 and 5.3).

use nalgebra::{DMatrix, DVector, Vector3};

use super::readings::TiltReading;
use super::JointsError;
use crate::model::{sign_1e9, tilt_from_moment, Model, ModelError, TiltValues};

/// Columns are scaled to unit norm; a design whose condition number exceeds this is treated
/// as not identifying its parameters.
const MAX_CONDITION: f64 = 1e8;

/// An estimated value and its standard deviation (same unit).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Estimate {
    /// Estimated value.
    pub value: f64,
    /// One standard deviation, from the fit's residual variance.
    pub sigma: f64,
}

/// The identification of one joint.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct JointTiltFit {
    /// Joint number (1-based, as in the file and the parameter names).
    pub joint: usize,
    /// Readings of this joint.
    pub rows: usize,
    /// Clearance tilt C (deg), when the x/y readings identify it.
    pub clearance_deg: Option<Estimate>,
    /// Backlash b (deg), when the z readings identify it.
    pub backlash_deg: Option<Estimate>,
    /// Compliance 1/k (deg per kgf.m), when the z readings identify it.
    pub compliance_deg_per_kgfm: Option<Estimate>,
    /// Stiffness k = 1/compliance (kgf.m/deg; sigma by first-order propagation), when the
    /// compliance is identified and positive.
    pub stiffness_kgfm_per_deg: Option<Estimate>,
    /// Inclinometer zero offsets about x, y, z (deg) fitted alongside.
    pub offsets_deg: [Option<f64>; 3],
    /// RMS residual of the x/y readings (deg).
    pub rms_xy_deg: Option<f64>,
    /// RMS residual of the z readings (deg).
    pub rms_z_deg: Option<f64>,
    /// Why a value was not identified.
    pub notes: Vec<String>,
}

/// Joint moment (kgf.m, joint frame `joint`) of `model` at `q_deg` with `payload_kg` at the
/// tool point (the model's own `payload_kg` parameter is replaced).
pub fn joint_moment_kgfm(
    model: &Model,
    q_deg: &[f64],
    payload_kg: f64,
    joint: usize,
) -> Result<Vector3<f64>, ModelError> {
    let mut m = model.clone();
    m.set_param_at(m.payload_param(), payload_kg)?;
    let moments = m.moments_kgfm(q_deg)?;
    moments.get(joint).copied().ok_or(ModelError::JointIndex {
        index: joint,
        count: moments.len(),
    })
}

/// The tilt `(da, db, dt)` (deg) the declared model predicts for `joint` at `q_deg` with
/// `payload_kg`: what an ideal, zeroed inclinometer on the link after the joint reads.
pub fn predicted_tilt_deg(
    model: &Model,
    q_deg: &[f64],
    payload_kg: f64,
    joint: usize,
) -> Result<Vector3<f64>, ModelError> {
    let eta = joint_moment_kgfm(model, q_deg, payload_kg, joint)?;
    let tv = model.tilt_values().ok_or_else(|| ModelError::NoTiltData {
        model: model.name().to_string(),
    })?;
    let v = tv.get(joint).ok_or(ModelError::JointIndex {
        index: joint,
        count: tv.len(),
    })?;
    Ok(tilt_from_moment(&eta, v, model.gamma_law()))
}

/// Solution of a linear least-squares problem.
struct LinearFit {
    params: DVector<f64>,
    sigmas: DVector<f64>,
    rms: f64,
}

/// Least squares `a x = y` with covariance `s^2 (a^T a)^-1`, `s^2 = rss / (m - p)`; `None` when
/// there are not more rows than unknowns or the (column-scaled) design is rank-deficient.
fn least_squares(a: &DMatrix<f64>, y: &DVector<f64>) -> Option<LinearFit> {
    let (m, p) = a.shape();
    if m <= p || p == 0 {
        return None;
    }
    let norms: Vec<f64> = (0..p).map(|j| a.column(j).norm()).collect();
    if norms.iter().any(|&n| n == 0.0 || !n.is_finite()) {
        return None;
    }
    let mut scaled = a.clone();
    for (j, &n) in norms.iter().enumerate() {
        scaled.column_mut(j).scale_mut(1.0 / n);
    }
    let svd = scaled.clone().svd(true, true);
    let smax = svd.singular_values.max();
    let smin = svd.singular_values.min();
    if smin <= 0.0 || smax / smin > MAX_CONDITION {
        return None;
    }
    let u = svd.u.as_ref()?;
    let v_t = svd.v_t.as_ref()?;
    let mut z = u.transpose() * y;
    for (zi, s) in z.iter_mut().zip(svd.singular_values.iter()) {
        *zi /= s;
    }
    let xs = v_t.transpose() * z;
    let resid = y - &scaled * &xs;
    let rss = resid.norm_squared();
    let s2 = rss / (m - p) as f64;
    let mut params = DVector::zeros(p);
    let mut sigmas = DVector::zeros(p);
    for j in 0..p {
        // var(x_j scaled) = s2 * sum_k V_jk^2 / sigma_k^2
        let var: f64 = (0..p)
            .map(|k| (v_t[(k, j)] / svd.singular_values[k]).powi(2))
            .sum::<f64>()
            * s2;
        params[j] = xs[j] / norms[j];
        sigmas[j] = var.sqrt() / norms[j];
    }
    Some(LinearFit {
        params,
        sigmas,
        rms: (rss / m as f64).sqrt(),
    })
}

/// Identifies joint `joint` (0-based) from `readings` (those of other joints are ignored).
///
/// Model per reading, with `eta` the declared model's moment at the reading's joints and
/// payload and `o` unknown inclinometer zero offsets (one per axis, so only *changes* between
/// configurations inform the values, as in the thesis's paired configurations):
/// - `incl_x = o_x + C sign(eta_x) sin(gamma)`, `incl_y = o_y + C sign(eta_y) cos(gamma)`
///   (eq. 5.16-5.18, the model's gamma law): linear in `(C, o_x, o_y)`;
/// - `incl_z = o_z + b sign(eta_z) + eta_z / k` (eq. 5.19): linear in `(b, 1/k, o_z)`.
///
/// A part that the readings do not determine (e.g. no sign change of eta_x/eta_y, or joint 1's
/// eta_z = 0 under gravity) is left `None` with a note.
pub fn fit_joint(
    model: &Model,
    readings: &[TiltReading],
    joint: usize,
) -> Result<JointTiltFit, ModelError> {
    let unit_c = TiltValues {
        clearance_deg: 1.0,
        backlash_deg: 0.0,
        stiffness_kgfm_per_deg: f64::INFINITY,
    };
    let law = model.gamma_law();
    let mut xy: Vec<(usize, f64, f64)> = Vec::new(); // (axis, regressor, reading)
    let mut z: Vec<(f64, f64, f64)> = Vec::new(); // (sign eta_z, eta_z, reading)
    let mut rows = 0;
    for r in readings.iter().filter(|r| r.joint == joint) {
        rows += 1;
        let eta = joint_moment_kgfm(model, &r.q_deg, r.payload_kg, joint)?;
        let reg = tilt_from_moment(&eta, &unit_c, law);
        for axis in 0..2 {
            if let Some(v) = r.incl_deg[axis] {
                xy.push((axis, reg[axis], v));
            }
        }
        if let Some(v) = r.incl_deg[2] {
            z.push((sign_1e9(eta.z), eta.z, v));
        }
    }
    let mut fit = JointTiltFit {
        joint: joint + 1,
        rows,
        clearance_deg: None,
        backlash_deg: None,
        compliance_deg_per_kgfm: None,
        stiffness_kgfm_per_deg: None,
        offsets_deg: [None; 3],
        rms_xy_deg: None,
        rms_z_deg: None,
        notes: Vec::new(),
    };
    fit_xy(&mut fit, &xy);
    fit_z(&mut fit, &z);
    Ok(fit)
}

/// The x/y part of [`fit_joint`] from `xy` = (axis, regressor, reading): clearance `C` and an
/// offset per axis that has readings, written into `fit`.
fn fit_xy(fit: &mut JointTiltFit, xy: &[(usize, f64, f64)]) {
    // x/y: columns C, then an offset per axis that has readings
    let axes: Vec<usize> = (0..2).filter(|a| xy.iter().any(|r| r.0 == *a)).collect();
    if axes.is_empty() {
        fit.notes
            .push("no x/y readings: clearance not identified".into());
    } else {
        let mut a = DMatrix::zeros(xy.len(), 1 + axes.len());
        let mut y = DVector::zeros(xy.len());
        for (i, &(axis, reg, v)) in xy.iter().enumerate() {
            a[(i, 0)] = reg;
            if let Some(k) = axes.iter().position(|&x| x == axis) {
                a[(i, 1 + k)] = 1.0;
            }
            y[i] = v;
        }
        match least_squares(&a, &y) {
            Some(f) => {
                fit.clearance_deg = Some(Estimate {
                    value: f.params[0],
                    sigma: f.sigmas[0],
                });
                for (k, &axis) in axes.iter().enumerate() {
                    fit.offsets_deg[axis] = Some(f.params[1 + k]);
                }
                fit.rms_xy_deg = Some(f.rms);
            }
            None => fit.notes.push(
                "x/y readings do not identify the clearance (need more readings than unknowns \
                 and moments eta_x/eta_y that change sign between configurations)"
                    .into(),
            ),
        }
    }
}

/// The z part of [`fit_joint`] from `z` = (sign eta_z, eta_z, reading): backlash, compliance
/// (and stiffness when positive) and the z offset, written into `fit`.
fn fit_z(fit: &mut JointTiltFit, z: &[(f64, f64, f64)]) {
    // z: columns b, 1/k, offset
    if z.is_empty() {
        fit.notes
            .push("no z readings: backlash and stiffness not identified".into());
    } else {
        let mut a = DMatrix::zeros(z.len(), 3);
        let mut y = DVector::zeros(z.len());
        for (i, &(s, eta_z, v)) in z.iter().enumerate() {
            a[(i, 0)] = s;
            a[(i, 1)] = eta_z;
            a[(i, 2)] = 1.0;
            y[i] = v;
        }
        match least_squares(&a, &y) {
            Some(f) => {
                fit.backlash_deg = Some(Estimate {
                    value: f.params[0],
                    sigma: f.sigmas[0],
                });
                let c = Estimate {
                    value: f.params[1],
                    sigma: f.sigmas[1],
                };
                fit.compliance_deg_per_kgfm = Some(c);
                if c.value > 0.0 {
                    fit.stiffness_kgfm_per_deg = Some(Estimate {
                        value: 1.0 / c.value,
                        sigma: c.sigma / (c.value * c.value),
                    });
                } else {
                    fit.notes.push(format!(
                        "fitted compliance {:.3e} deg/kgf.m is not positive: stiffness not identified",
                        c.value
                    ));
                }
                fit.offsets_deg[2] = Some(f.params[2]);
                fit.rms_z_deg = Some(f.rms);
            }
            None => fit.notes.push(
                "z readings do not identify backlash and stiffness (need eta_z of both signs \
                 and of several sizes; joint 1's eta_z is 0 under gravity)"
                    .into(),
            ),
        }
    }
}

/// The result of [`identify`]: one fit per joint that has readings, and the model with every
/// identified value written into `clearance_j<i>`, `backlash_j<i>`, `stiffness_j<i>` (values
/// not identified keep the input model's).
#[derive(Debug, Clone)]
pub struct TiltIdentification {
    /// Per-joint fits, in joint order.
    pub fits: Vec<JointTiltFit>,
    /// The updated model.
    pub model: Model,
}

/// Identifies every joint that has readings and writes the values into a copy of `model`.
pub fn identify(
    model: &Model,
    readings: &[TiltReading],
) -> Result<TiltIdentification, JointsError> {
    if !model.has_tilt() {
        return Err(ModelError::NoTiltData {
            model: model.name().to_string(),
        }
        .into());
    }
    let mut out = model.clone();
    let mut fits = Vec::new();
    for j in 0..model.n_joints() {
        if !readings.iter().any(|r| r.joint == j) {
            continue;
        }
        let fit = fit_joint(model, readings, j)?;
        let n = j + 1;
        if let Some(c) = fit.clearance_deg {
            out.set_param(&format!("clearance_j{n}"), c.value)?;
        }
        if let Some(b) = fit.backlash_deg {
            out.set_param(&format!("backlash_j{n}"), b.value)?;
        }
        if let Some(k) = fit.stiffness_kgfm_per_deg {
            out.set_param(&format!("stiffness_j{n}"), k.value)?;
        }
        fits.push(fit);
    }
    let any = fits.iter().any(|f| {
        f.clearance_deg.is_some() || f.backlash_deg.is_some() || f.stiffness_kgfm_per_deg.is_some()
    });
    if !any {
        return Err(JointsError::NothingIdentified);
    }
    Ok(TiltIdentification { fits, model: out })
}
