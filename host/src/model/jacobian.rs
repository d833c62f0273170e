//! Analytic Jacobians of the tool position (mm) wrt joints and wrt any subset of parameters.
//!
//! The function differentiated is exactly [`Model::fk`]'s `position_mm`, including, with
//! `Tilt::Static`, the dependence of the tilt on the joints and parameters through the static
//! moments (the moments are recomputed from the untilted chain at the current values, so their
//! derivative is included). The `sign()` steps of the tilt law (MODEL.md eq. 5.17-5.19) are
//! piecewise constant and count as flat. With `Tilt::Moments` the supplied moments are held
//! fixed (derivative 0); only the tilting values act through them.

use nalgebra::{Matrix3, Matrix3xX, Vector3};
use std::f64::consts::PI;

use super::chain::{Model, Motion};
use super::error::ModelError;
use super::kinematics::{axis_rotation, Fk, Frames, Tilt, TiltState, GRAVITY_KGF_PER_KG};
use super::tilt::{tilt_partials, TiltPartials};

const DEG: f64 = PI / 180.0;

/// A coordinate to differentiate the tool position with respect to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wrt {
    /// Joint reading `q_i` (0-based); column in mm/deg (mm/mm for a prismatic joint).
    Joint(usize),
    /// Parameter by index ([`Model::param_index`]); column in mm per parameter unit.
    Param(usize),
}

/// Moments data of the untilted chain, kept for the moment derivatives.
struct MomentData {
    frames: Frames,
    /// (frame index, kg, world point mm) of every mass, payload included when non-zero.
    points: Vec<(usize, f64, Vector3<f64>)>,
    /// Per joint: `sum (c - o_i) x m g` in R (kgf.m).
    sums: Vec<Vector3<f64>>,
}

impl Model {
    /// The element a coordinate moves directly, and its rate (deg or mm per unit).
    fn direct_effect(&self, wrt: Wrt, q_deg: &[f64]) -> Option<(usize, f64)> {
        match wrt {
            Wrt::Joint(j) => Some((self.joints[j].elem, self.joint_value(j, q_deg[j]).1)),
            Wrt::Param(i) => {
                if let Some(e) = self.elems.iter().position(|e| e.param == i) {
                    return Some((e, 1.0));
                }
                self.joints.iter().enumerate().find_map(|(j, joint)| {
                    joint.harmonics.iter().find_map(|h| {
                        let (s, c) = (f64::from(h.order) * q_deg[j]).to_radians().sin_cos();
                        if h.sin_param == i {
                            Some((joint.elem, s))
                        } else if h.cos_param == i {
                            Some((joint.elem, c))
                        } else {
                            None
                        }
                    })
                })
            }
        }
    }

    /// Twist of element `e` moved at `rate` in `fr`: `(w rad, v mm)` with point velocity
    /// `w x x + v`.
    fn elem_twist(&self, fr: &Frames, e: usize, rate: f64) -> (Vector3<f64>, Vector3<f64>) {
        let (r, p) = fr.before(e);
        let axis = r.column(self.elems[e].axis.index()).into_owned();
        match self.elems[e].motion {
            Motion::Rot => {
                let w = axis * (rate * DEG);
                (w, -w.cross(&p))
            }
            Motion::Trans => (Vector3::zeros(), axis * rate),
        }
    }

    /// Derivative of the moment of joint `i` (kgf.m, joint frame) for element `e` moved at
    /// `rate`.
    fn moment_derivative(&self, md: &MomentData, i: usize, e: usize, rate: f64) -> Vector3<f64> {
        let ei = self.joints[i].elem;
        let ri = md.frames.rot[ei];
        let oi = md.frames.pos_mm[ei];
        let (w, v) = self.elem_twist(&md.frames, e, rate);
        let mut d = Vector3::zeros();
        if e <= ei {
            if w == Vector3::zeros() {
                return d;
            }
            d -= w.cross(&md.sums[i]);
            for (k, m, c) in &md.points {
                if *k >= ei {
                    d += w
                        .cross(&((c - oi) * 1e-3))
                        .cross(&(GRAVITY_KGF_PER_KG * *m));
                }
            }
        } else {
            for (k, m, c) in &md.points {
                if *k >= e {
                    d += ((w.cross(c) + v) * 1e-3).cross(&(GRAVITY_KGF_PER_KG * *m));
                }
            }
        }
        ri.transpose() * d
    }

    /// Tool position (and the full FK) at `q_deg` with its Jacobian wrt `wrt` (one column per
    /// entry, mm per unit of the coordinate). See the module doc for what is differentiated.
    pub fn position_jacobian(
        &self,
        q_deg: &[f64],
        tilt: Tilt<'_>,
        wrt: &[Wrt],
    ) -> Result<(Fk, Matrix3xX<f64>), ModelError> {
        for w in wrt {
            match *w {
                Wrt::Joint(j) if j >= self.joints.len() => {
                    return Err(ModelError::JointIndex {
                        index: j,
                        count: self.joints.len(),
                    })
                }
                Wrt::Param(i) if i >= self.params.len() => {
                    return Err(ModelError::ParamIndex {
                        index: i,
                        count: self.params.len(),
                    })
                }
                _ => {}
            }
        }
        let TiltState {
            moments_kgfm: moments,
            tilts_deg: tilts,
            untilted,
        } = self.tilt_state(q_deg, tilt)?;
        let tilted = !tilts.is_empty();
        let fr = self.frames(q_deg, tilted.then_some(&tilts[..]))?;
        let p = fr.tool_mm();
        let sf = self.scale_factor();
        let fk = Fk {
            position_mm: p * sf,
            rotation: fr.tool_rot(),
            moments_kgfm: moments,
            tilts_deg: tilts,
        };

        // Per joint: d tool / d (da, db, dt) (mm/deg) and the tilt law's partials.
        let mut tilt_data: Vec<(Matrix3<f64>, TiltPartials)> = Vec::new();
        if tilted {
            let tv = self.require_tilt()?;
            for (i, joint) in self.joints.iter().enumerate() {
                let t = &fk.tilts_deg[i];
                let r0 = fr.joint_rot_untilted[i];
                let rx = r0 * axis_rotation(0, t.x.to_radians());
                let rxy = rx * axis_rotation(1, t.y.to_radians());
                let arm = p - fr.pos_mm[joint.elem];
                let g = Matrix3::from_columns(&[
                    r0.column(0).cross(&arm) * DEG,
                    rx.column(1).cross(&arm) * DEG,
                    rxy.column(2).cross(&arm) * DEG,
                ]);
                tilt_data.push((
                    g,
                    tilt_partials(&fk.moments_kgfm[i], &tv[i], self.gamma_law),
                ));
            }
        }
        let moment_data = untilted.map(|frames| {
            let points = self.mass_points(&frames);
            let sums = self
                .joints
                .iter()
                .map(|j| {
                    let o = frames.pos_mm[j.elem];
                    points
                        .iter()
                        .filter(|(k, _, _)| *k >= j.elem)
                        .map(|(_, m, c)| ((c - o) * 1e-3).cross(&(GRAVITY_KGF_PER_KG * *m)))
                        .sum()
                })
                .collect();
            MomentData {
                frames,
                points,
                sums,
            }
        });

        let mut jac = Matrix3xX::zeros(wrt.len());
        for (col, &w) in wrt.iter().enumerate() {
            if w == Wrt::Param(self.scale_param) {
                jac.set_column(col, &(p * 1e-6));
                continue;
            }
            let direct = self.direct_effect(w, q_deg);
            let mut d = Vector3::zeros();
            if let Some((e, rate)) = direct {
                let (tw, tv) = self.elem_twist(&fr, e, rate);
                d += tw.cross(&p) + tv;
            }
            for (i, (g, tp)) in tilt_data.iter().enumerate() {
                let mut dtilt = Vector3::zeros();
                if let Some(md) = &moment_data {
                    let deta = if w == Wrt::Param(self.payload_param) {
                        let ei = self.joints[i].elem;
                        let arm = (md.frames.tool_mm() - md.frames.pos_mm[ei]) * 1e-3;
                        md.frames.rot[ei].transpose() * arm.cross(&GRAVITY_KGF_PER_KG)
                    } else if let Some((e, rate)) = direct {
                        self.moment_derivative(md, i, e, rate)
                    } else {
                        Vector3::zeros()
                    };
                    dtilt += tp.wrt_eta * deta;
                }
                if let (Wrt::Param(pi), Some(tps)) = (w, &self.tilt) {
                    let t = &tps[i];
                    if pi == t.clearance {
                        dtilt += tp.wrt_clearance;
                    } else if pi == t.backlash {
                        dtilt += tp.wrt_backlash;
                    } else if pi == t.stiffness {
                        dtilt += tp.wrt_stiffness;
                    }
                }
                d += g * dtilt;
            }
            jac.set_column(col, &(d * sf));
        }
        Ok((fk, jac))
    }

    /// Jacobian of the tool position wrt all joints (mm/deg), with the FK.
    pub fn joint_jacobian(
        &self,
        q_deg: &[f64],
        tilt: Tilt<'_>,
    ) -> Result<(Fk, Matrix3xX<f64>), ModelError> {
        let wrt: Vec<Wrt> = (0..self.joints.len()).map(Wrt::Joint).collect();
        self.position_jacobian(q_deg, tilt, &wrt)
    }

    /// Jacobian of the tool position wrt the parameters `params` (indices; mm per unit), with
    /// the FK.
    pub fn param_jacobian(
        &self,
        q_deg: &[f64],
        tilt: Tilt<'_>,
        params: &[usize],
    ) -> Result<(Fk, Matrix3xX<f64>), ModelError> {
        let wrt: Vec<Wrt> = params.iter().map(|&i| Wrt::Param(i)).collect();
        self.position_jacobian(q_deg, tilt, &wrt)
    }
}
