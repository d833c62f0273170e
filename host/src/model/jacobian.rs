//! Analytic Jacobians of the tool position (mm) wrt joints and wrt any subset of parameters.
//!
//! The function differentiated is exactly [`Model::fk`]'s `position_mm`, including, with
//! `Tilt::Static`, the dependence of the tilt on the joints and parameters through the static
//! moments (the moments are recomputed from the untilted chain at the current values, so their
//! derivative is included). The `sign()` steps of the tilt law (MODEL.md eq. 5.17-5.19) are
//! piecewise constant and count as flat. With `Tilt::Moments` the supplied moments are held
//! fixed (derivative 0); only the tilting values act through them. With
//! [`Model::set_tilt_direction_frozen`] the contact direction (gamma) counts as flat too (the
//! design Jacobian of `rigctl plan`); the position is unchanged.
//!
//! [`Model::jacobian_with`] works in a reusable [`Data`] workspace (no heap allocation per
//! pose); [`Model::position_jacobian`], [`Model::joint_jacobian`] and [`Model::param_jacobian`]
//! are wrappers that allocate a workspace per call.

use nalgebra::{Matrix3, Matrix3xX, Vector3};
use std::f64::consts::PI;

use super::chain::{Model, Motion};
use super::data::{Data, ParamEffect};
use super::error::ModelError;
use super::kinematics::{with_workspace, Fk, Tilt, GRAVITY_KGF_PER_KG};
use super::lateral::lateral_regressor;
use super::tilt::{tilt_partials, TiltPartials};

const DEG: f64 = PI / 180.0;

/// A coordinate to differentiate the tool position with respect to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wrt {
    /// Joint reading `q_i` (0-based); column in mm/deg (mm/mm for a prismatic joint).
    Joint(usize),
    /// Parameter by index ([`Model::param_index`]); column in mm per parameter unit.
    Param(usize),
    /// Lateral compliance of joint j (0-based, [`super::lateral`]); column in mm per (deg per
    /// kgf.m): `G_j (eta_x, eta_y, 0)`, evaluated at any value, zero included.
    Lateral(usize),
}

/// The axis (unit, R) of element `e` and a point on it (mm): the frame before the element.
#[inline(always)]
fn elem_axis(
    model: &Model,
    rot: &[Matrix3<f64>],
    pos: &[Vector3<f64>],
    e: usize,
) -> (Vector3<f64>, Vector3<f64>) {
    let ax = model.elems[e].axis.index();
    if e == 0 {
        (Vector3::ith(ax, 1.0), Vector3::zeros())
    } else {
        (rot[e - 1].column(ax).into_owned(), pos[e - 1])
    }
}

/// Twist of element `e` moved at `rate` in the frames `rot` / `pos`: `(w rad, v mm)` with point
/// velocity `w x x + v`. Inlined: returning the pair through memory stalled the per-pose loop.
#[inline(always)]
fn elem_twist(
    model: &Model,
    rot: &[Matrix3<f64>],
    pos: &[Vector3<f64>],
    e: usize,
    rate: f64,
) -> (Vector3<f64>, Vector3<f64>) {
    let (axis, o) = elem_axis(model, rot, pos, e);
    match model.elems[e].motion {
        Motion::Rot => {
            let w = axis * (rate * DEG);
            (w, -w.cross(&o))
        }
        Motion::Trans => (Vector3::zeros(), axis * rate),
    }
}

/// Velocity of the point `p` when element `e` moves at `rate` in the frames `rot` / `pos`
/// (`w x (p - o)` for a rotation about an axis through `o`, the axis for a translation).
#[inline(always)]
fn elem_point_velocity(
    model: &Model,
    rot: &[Matrix3<f64>],
    pos: &[Vector3<f64>],
    e: usize,
    rate: f64,
    p: &Vector3<f64>,
) -> Vector3<f64> {
    let (axis, o) = elem_axis(model, rot, pos, e);
    match model.elems[e].motion {
        Motion::Rot => (axis * (rate * DEG)).cross(&(p - o)),
        Motion::Trans => axis * rate,
    }
}

impl Model {
    /// The element a coordinate moves directly, and its rate (deg or mm per unit).
    #[inline(always)]
    fn direct_effect(&self, d: &Data, wrt: Wrt, q_deg: &[f64]) -> Option<(usize, f64)> {
        match wrt {
            Wrt::Joint(j) => Some((self.joints[j].elem, d.joint_dv[j])),
            Wrt::Lateral(_) => None,
            Wrt::Param(i) => match d.effects[i] {
                ParamEffect::None => None,
                ParamEffect::Elem(e) => Some((e, 1.0)),
                ParamEffect::Harmonic { joint, order, sin } => {
                    let (s, c) = (f64::from(order) * q_deg[joint]).to_radians().sin_cos();
                    Some((self.joints[joint].elem, if sin { s } else { c }))
                }
            },
        }
    }

    fn check_wrt(&self, wrt: &[Wrt]) -> Result<(), ModelError> {
        for w in wrt {
            match *w {
                Wrt::Joint(j) | Wrt::Lateral(j) if j >= self.joints.len() => {
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
        Ok(())
    }

    /// Per joint: `d tool / d (da, db, dt)` (mm/deg) and the tilt law's partials, into `d`.
    fn tilt_sensitivities(&self, d: &mut Data) {
        let p = d.tool_unscaled();
        d.tilt_partials.clear();
        for (i, joint) in self.joints.iter().enumerate() {
            let arm = p - d.pos_mm[joint.elem];
            let [a0, a1, a2] = d.tilt_axes[i];
            d.tilt_g[i] = Matrix3::from_columns(&[
                a0.cross(&arm) * DEG,
                a1.cross(&arm) * DEG,
                a2.cross(&arm) * DEG,
            ]);
            let mut tp = if d.tilted {
                let mut tp = tilt_partials(&d.moments_kgfm[i], &d.tilt_values[i], self.gamma_law);
                if self.tilt_direction_frozen {
                    tp.freeze_direction();
                }
                tp
            } else {
                TiltPartials::none()
            };
            // the lateral bend's slope: c on the x and y diagonal (kept with a frozen direction)
            let c = self.lateral_compliance_at(i);
            if c != 0.0 {
                tp.wrt_eta[(0, 0)] += c;
                tp.wrt_eta[(1, 1)] += c;
            }
            d.tilt_partials.push(tp);
        }
        if d.has_untilted {
            self.moment_sensitivities(d);
        }
    }

    /// The moment part of the tilt's derivative, summed over the joints once per pose (see
    /// `Data::k_pre`, `Data::ka_post`): moving element `e` at `(w, v)` (untilted frames) changes
    /// the static moment of a joint at or after `e` by `A_i w` (in R;
    /// `A_i = [g]x [L_i]x + [S_i]x`, `L_i` the mass-weighted lever of the carried masses in m,
    /// `S_i` their moment), and of a joint before `e` by `((w x sum m c + v sum m) 1e-3) x g`,
    /// the same for all of them; the tool moves by `K_i` times the change.
    fn moment_sensitivities(&self, d: &mut Data) {
        let nj = self.joints.len();
        let g = GRAVITY_KGF_PER_KG.cross_matrix();
        d.k_pre[0] = Matrix3::zeros();
        for (i, joint) in self.joints.iter().enumerate() {
            let ei = joint.elem;
            let k = d.tilt_g[i] * d.tilt_partials[i].wrt_eta * d.rot0[ei].transpose();
            d.k_mat[i] = k;
            d.k_pre[i + 1] = d.k_pre[i] + k;
        }
        d.ka_post[nj] = Matrix3::zeros();
        for (i, joint) in self.joints.iter().enumerate().rev() {
            let ei = joint.elem;
            let lever = (d.suffix_mc[ei] - d.pos0_mm[ei] * d.suffix_m[ei]) * 1e-3;
            let a = g * lever.cross_matrix() + d.sums[i].cross_matrix();
            d.ka_post[i] = d.ka_post[i + 1] + d.k_mat[i] * a;
        }
    }

    /// Column of the Jacobian wrt one coordinate (unscaled), from an evaluated workspace.
    #[inline]
    fn jacobian_column(&self, d: &Data, w: Wrt, q_deg: &[f64]) -> Vector3<f64> {
        let p = d.tool_unscaled();
        let direct = self.direct_effect(d, w, q_deg);
        let mut col = match direct {
            Some((e, rate)) => elem_point_velocity(self, &d.rot, &d.pos_mm, e, rate, &p),
            None => Vector3::zeros(),
        };
        if !d.bent {
            return col;
        }
        if let Wrt::Lateral(j) = w {
            col += d.tilt_g[j] * lateral_regressor(&d.moments_kgfm[j]);
        }
        if d.has_untilted {
            if w == Wrt::Param(self.payload_param) {
                let tool0 = d.pos0_mm.last().copied().unwrap_or_else(Vector3::zeros);
                for (i, joint) in self.joints.iter().enumerate() {
                    let arm = (tool0 - d.pos0_mm[joint.elem]) * 1e-3;
                    col += d.k_mat[i] * arm.cross(&GRAVITY_KGF_PER_KG);
                }
            } else if let Some((e, rate)) = direct {
                let (w, v) = elem_twist(self, &d.rot0, &d.pos0_mm, e, rate);
                let j = d.joints_before[e];
                let after = ((w.cross(&d.suffix_mc[e]) + v * d.suffix_m[e]) * 1e-3)
                    .cross(&GRAVITY_KGF_PER_KG);
                col += d.ka_post[j] * w + d.k_pre[j] * after;
            }
        }
        if let (Wrt::Param(pi), Some(tps)) = (w, &self.tilt) {
            for (i, (t, tp)) in tps.iter().zip(&d.tilt_partials).enumerate() {
                let dtilt = if pi == t.clearance {
                    tp.wrt_clearance
                } else if pi == t.backlash {
                    tp.wrt_backlash
                } else if pi == t.stiffness {
                    tp.wrt_stiffness
                } else {
                    continue;
                };
                col += d.tilt_g[i] * dtilt;
            }
        }
        col
    }

    /// FK and the Jacobian of the tool position wrt `wrt` (one column per entry, mm per unit of
    /// the coordinate, read with [`Data::jacobian`]) in the workspace `d`: no heap allocation
    /// once `d` is warm. Same values as [`Model::position_jacobian`].
    pub fn jacobian_with(
        &self,
        d: &mut Data,
        q_deg: &[f64],
        tilt: Tilt<'_>,
        wrt: &[Wrt],
    ) -> Result<(), ModelError> {
        d.sync(self);
        self.jacobian_synced(d, q_deg, tilt, wrt)
    }

    /// [`Model::jacobian_with`] on a workspace already synchronised with this model.
    pub(crate) fn jacobian_synced(
        &self,
        d: &mut Data,
        q_deg: &[f64],
        tilt: Tilt<'_>,
        wrt: &[Wrt],
    ) -> Result<(), ModelError> {
        if let Err(e) = self.check_wrt(wrt) {
            d.q_sc_given = false;
            return Err(e);
        }
        let lateral_wrt = wrt.iter().any(|w| matches!(w, Wrt::Lateral(_)));
        self.fk_bent(d, q_deg, tilt, lateral_wrt)?;
        if d.bent {
            self.tilt_sensitivities(d);
        }
        let p = d.tool_unscaled();
        let sf = d.scale;
        let mut jac = std::mem::take(&mut d.jac);
        jac.clear();
        for &w in wrt {
            if w == Wrt::Param(self.scale_param) {
                jac.push(p * 1e-6);
            } else if d.bent {
                jac.push(self.jacobian_column(d, w, q_deg) * sf);
            } else {
                // Untilted: the direct effect only (inlined; the common identification case).
                let col = match self.direct_effect(d, w, q_deg) {
                    Some((e, rate)) => elem_point_velocity(self, &d.rot, &d.pos_mm, e, rate, &p),
                    None => Vector3::zeros(),
                };
                jac.push(col * sf);
            }
        }
        d.jac = jac;
        Ok(())
    }

    /// Tool position (and the full FK) at `q_deg` with its Jacobian wrt `wrt` (one column per
    /// entry, mm per unit of the coordinate). See the module doc for what is differentiated.
    pub fn position_jacobian(
        &self,
        q_deg: &[f64],
        tilt: Tilt<'_>,
        wrt: &[Wrt],
    ) -> Result<(Fk, Matrix3xX<f64>), ModelError> {
        with_workspace(self, |d| {
            self.jacobian_with(d, q_deg, tilt, wrt)?;
            let jac = if wrt.is_empty() {
                Matrix3xX::zeros(0)
            } else {
                Matrix3xX::from_columns(d.jacobian())
            };
            Ok((Fk::from_data(d), jac))
        })
    }

    /// [`Model::position_jacobian`] read in this thread's evaluation workspace: `f` gets the
    /// tool position (mm) and the Jacobian's columns (one per `wrt` entry), and nothing is
    /// copied out (the per-pose evaluations of an identification).
    pub fn with_position_jacobian<T>(
        &self,
        q_deg: &[f64],
        tilt: Tilt<'_>,
        wrt: &[Wrt],
        f: impl FnOnce(&Vector3<f64>, &[Vector3<f64>]) -> T,
    ) -> Result<T, ModelError> {
        with_workspace(self, |d| {
            self.jacobian_with(d, q_deg, tilt, wrt)?;
            Ok(f(&d.position_mm(), d.jacobian()))
        })
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
