//! The joint-tilting law of MODEL.md (eq. 5.16-5.19): from the moment `eta_i` in joint frame i to
//! the tilt angles `(da, db, dt)` applied there as `Rx(da) . Ry(db) . Rz(dt)`.

use nalgebra::{Matrix3, Vector3};
use std::f64::consts::FRAC_PI_2;

use super::chain::{GammaLaw, TiltValues};

/// Gravity in frame R, per kg, in kgf (MODEL.md: -z of R, 1 kgf per kg).
pub const GRAVITY_KGF_PER_KG: Vector3<f64> = Vector3::new(0.0, 0.0, -1.0);

/// Which joint tilting to apply when evaluating the chain.
#[derive(Debug, Clone, Copy, Default)]
pub enum Tilt<'a> {
    /// No tilting (the conventional rigid model).
    #[default]
    Off,
    /// Tilting from the static gravity moments of this pose (the declared model).
    Static,
    /// Tilting from externally supplied moments (kgf.m in joint frame i, one per joint), e.g.
    /// from recursive Newton-Euler along a trajectory.
    Moments(&'a [Vector3<f64>]),
    /// Tilting from the static gravity moments of this pose **plus** supplied extra moments
    /// (kgf.m in joint frame i, one per joint; e.g. the inertial part of the moments in motion).
    /// The static part follows the model's parameters (payload, base tilt) and the joints, and
    /// is differentiated like `Static`; the extra part is held fixed.
    StaticPlus(&'a [Vector3<f64>]),
    /// No declared tilting; the lateral bend of the model's laterally compliant joints
    /// ([`super::lateral`]) under supplied moments (kgf.m in joint frame i, one per joint; e.g.
    /// a tree's whole-tree moments, [`super::tree_bend`]), held fixed in the Jacobian.
    Bend(&'a [Vector3<f64>]),
}

/// `sign(x)` of MODEL.md: 0 for `|x| < 1e-9`, else +-1.
pub fn sign_1e9(x: f64) -> f64 {
    if x.abs() < 1e-9 {
        0.0
    } else {
        x.signum()
    }
}

/// Derivative of `|x|` (0 at 0).
fn abs_slope(x: f64) -> f64 {
    if x == 0.0 {
        0.0
    } else {
        x.signum()
    }
}

/// The contact-direction angle gamma (rad) and its partials wrt `eta_x`, `eta_y`.
fn gamma(eta_x: f64, eta_y: f64, law: GammaLaw) -> (f64, f64, f64) {
    let (ax, ay) = (eta_x.abs(), eta_y.abs());
    match law {
        GammaLaw::Linear => {
            let s = ax + ay;
            if s == 0.0 {
                return (0.0, 0.0, 0.0);
            }
            let g = FRAC_PI_2 * ax / s;
            let dgx = FRAC_PI_2 * ay / (s * s) * abs_slope(eta_x);
            let dgy = -FRAC_PI_2 * ax / (s * s) * abs_slope(eta_y);
            (g, dgx, dgy)
        }
        GammaLaw::Atan2 => {
            let r2 = ax * ax + ay * ay;
            if r2 == 0.0 {
                return (0.0, 0.0, 0.0);
            }
            (
                ax.atan2(ay),
                ay / r2 * abs_slope(eta_x),
                -ax / r2 * abs_slope(eta_y),
            )
        }
    }
}

/// Tilt `(da, db, dt)` in degrees of a joint with moment `eta` (kgf.m, joint frame) and
/// declared values `tv` (MODEL.md eq. 5.16-5.19).
pub fn tilt_from_moment(eta: &Vector3<f64>, tv: &TiltValues, law: GammaLaw) -> Vector3<f64> {
    let (g, _, _) = gamma(eta.x, eta.y, law);
    Vector3::new(
        sign_1e9(eta.x) * tv.clearance_deg * g.sin(),
        sign_1e9(eta.y) * tv.clearance_deg * g.cos(),
        sign_1e9(eta.z) * tv.backlash_deg + eta.z / tv.stiffness_kgfm_per_deg,
    )
}

/// Partials of [`tilt_from_moment`]: `d tilt / d eta` (deg per kgf.m; the sign steps count as
/// flat) and `d tilt / d C`, `d tilt / d b`, `d tilt / d k`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TiltPartials {
    pub wrt_eta: Matrix3<f64>,
    pub wrt_clearance: Vector3<f64>,
    pub wrt_backlash: Vector3<f64>,
    pub wrt_stiffness: Vector3<f64>,
}

impl TiltPartials {
    /// No slope: a joint without declared tilting.
    pub(crate) fn none() -> Self {
        Self {
            wrt_eta: Matrix3::zeros(),
            wrt_clearance: Vector3::zeros(),
            wrt_backlash: Vector3::zeros(),
            wrt_stiffness: Vector3::zeros(),
        }
    }

    /// Drops the slope of the contact direction gamma (the `da`, `db` rows wrt `eta_x`,
    /// `eta_y`), keeping the compliance slope `1 / k` ([`crate::model::Model::set_tilt_direction_frozen`]).
    pub(crate) fn freeze_direction(&mut self) {
        for r in 0..2 {
            for c in 0..2 {
                self.wrt_eta[(r, c)] = 0.0;
            }
        }
    }
}

pub(crate) fn tilt_partials(eta: &Vector3<f64>, tv: &TiltValues, law: GammaLaw) -> TiltPartials {
    let (g, dgx, dgy) = gamma(eta.x, eta.y, law);
    let (sx, sy, sz) = (sign_1e9(eta.x), sign_1e9(eta.y), sign_1e9(eta.z));
    let c = tv.clearance_deg;
    let k = tv.stiffness_kgfm_per_deg;
    let mut wrt_eta = Matrix3::zeros();
    wrt_eta[(0, 0)] = sx * c * g.cos() * dgx;
    wrt_eta[(0, 1)] = sx * c * g.cos() * dgy;
    wrt_eta[(1, 0)] = -sy * c * g.sin() * dgx;
    wrt_eta[(1, 1)] = -sy * c * g.sin() * dgy;
    wrt_eta[(2, 2)] = 1.0 / k;
    TiltPartials {
        wrt_eta,
        wrt_clearance: Vector3::new(sx * g.sin(), sy * g.cos(), 0.0),
        wrt_backlash: Vector3::new(0.0, 0.0, sz),
        wrt_stiffness: Vector3::new(0.0, 0.0, -eta.z / (k * k)),
    }
}
