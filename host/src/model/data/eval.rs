//! One pose evaluated in a [`Data`] workspace: the joint values, the sweep of the chain (with
//! the tilts inserted at the joint frames), the static moments of the untilted chain, and
//! [`Model::fk_with`] that ties them together. The workspace itself and its cache: the parent
//! module.

use nalgebra::{Matrix3, Vector3};

use super::Data;
use crate::model::chain::{Model, Motion};
use crate::model::error::ModelError;
use crate::model::lateral::lateral_tilt_deg;
use crate::model::tilt::tilt_from_moment;
use crate::model::tilt::{Tilt, GRAVITY_KGF_PER_KG};

impl Model {
    /// Joint values (deg / mm, offset and encoder harmonics included) and their sines and
    /// cosines into `d`; harmonics with both coefficients 0 cost nothing.
    /// The joint values (and their `sin`/`cos`: from [`Data::give_joint_sin_cos`] when `given`).
    fn load_joints(&self, d: &mut Data, q_deg: &[f64], given: bool) {
        for (j, joint) in self.joints.iter().enumerate() {
            let q = q_deg[j];
            let e = joint.elem;
            let mut v = q + self.params[self.elems[e].param].value;
            let mut dv = 1.0;
            let mut harmonics = false;
            for h in &joint.harmonics {
                let (a_s, a_c) = (
                    self.params[h.sin_param].value,
                    self.params[h.cos_param].value,
                );
                if a_s == 0.0 && a_c == 0.0 {
                    continue;
                }
                harmonics = true;
                let n = f64::from(h.order);
                let (s, c) = (n * q).to_radians().sin_cos();
                v += a_s * s + a_c * c;
                dv += n * std::f64::consts::PI / 180.0 * (a_s * c - a_c * s);
            }
            d.elem_value[e] = v;
            d.joint_dv[j] = dv;
            d.elem_sc[e] = match self.elems[e].motion {
                Motion::Rot if given && !harmonics => {
                    // sin / cos of `q + offset` by the angle sum (same values to round-off).
                    let ((sq, cq), (so, co)) = (d.q_sc[j], d.offset_sc[j]);
                    (sq * co + cq * so, cq * co - sq * so)
                }
                Motion::Rot => v.to_radians().sin_cos(),
                Motion::Trans => (v, 0.0),
            };
        }
    }

    /// One sweep of the chain with the values in `d`; with `tilts` the tilt of joint i is
    /// inserted after its element (and the tilt axes recorded). Writes `rot` / `pos`.
    fn sweep(&self, d: &mut Data, tilts: bool, untilted: bool) {
        // The running frame as three column values and a position (kept in registers; a
        // `Matrix3` updated through indices went through the stack with stalled reloads).
        let mut f = Frame::identity();
        for (k, e) in self.elems.iter().enumerate() {
            if d.elem_value[k] != 0.0 {
                let (s, c) = d.elem_sc[k];
                f.apply(e.motion, e.axis.index(), s, c, d.elem_value[k]);
            }
            if let (Some(j), true) = (e.joint, tilts) {
                let t = d.tilts_deg[j];
                let x0 = f.cols[0];
                if t.x != 0.0 {
                    let (s, c) = t.x.to_radians().sin_cos();
                    f.rotate(0, s, c);
                }
                let x1 = f.cols[1];
                if t.y != 0.0 {
                    let (s, c) = t.y.to_radians().sin_cos();
                    f.rotate(1, s, c);
                }
                let x2 = f.cols[2];
                if t.z != 0.0 {
                    let (s, c) = t.z.to_radians().sin_cos();
                    f.rotate(2, s, c);
                }
                d.tilt_axes[j] = [x0, x1, x2];
            }
            let (rot, pos) = if untilted {
                (&mut d.rot0[k], &mut d.pos0_mm[k])
            } else {
                (&mut d.rot[k], &mut d.pos_mm[k])
            };
            *rot = Matrix3::from_columns(&f.cols);
            *pos = f.pos;
        }
    }

    /// Static moments of every joint from the untilted frames in `d` (`rot0`, `pos0_mm`), also
    /// filling the mass points.
    fn static_moments(&self, d: &mut Data) {
        d.points.clear();
        for m in &self.masses {
            let k = self.mass_frame(m);
            d.points
                .push((k, m.mass_kg, d.rot0[k] * m.com_mm + d.pos0_mm[k]));
        }
        if d.payload_kg != 0.0 {
            let last = self.elems.len() - 1;
            d.points.push((last, d.payload_kg, d.pos0_mm[last]));
        }
        d.suffix_mc.fill(Vector3::zeros());
        d.suffix_m.fill(0.0);
        for (k, m, c) in &d.points {
            d.suffix_mc[*k] += c * *m;
            d.suffix_m[*k] += *m;
        }
        for k in (0..d.suffix_m.len().saturating_sub(1)).rev() {
            let (mc, m) = (d.suffix_mc[k + 1], d.suffix_m[k + 1]);
            d.suffix_mc[k] += mc;
            d.suffix_m[k] += m;
        }
        for (i, j) in self.joints.iter().enumerate() {
            let o = d.pos0_mm[j.elem];
            let mut s = Vector3::zeros();
            for (k, m, c) in &d.points {
                if *k >= j.elem {
                    s += ((c - o) * 1e-3).cross(&(GRAVITY_KGF_PER_KG * *m));
                }
            }
            d.sums[i] = s;
            d.moments_kgfm[i] = d.rot0[j.elem].transpose() * s;
        }
    }

    /// Static moments (kgf.m, joint frame i) of the untilted chain at `q_deg` into `d` (read
    /// them from `d.moments_kgfm`).
    pub(crate) fn static_moments_with(
        &self,
        d: &mut Data,
        q_deg: &[f64],
    ) -> Result<(), ModelError> {
        d.q_sc_given = false;
        self.check_joints(q_deg)?;
        d.sync(self);
        self.load_joints(d, q_deg, false);
        self.sweep(d, false, true);
        self.static_moments(d);
        d.has_untilted = true;
        d.tilted = false;
        d.bent = false;
        Ok(())
    }

    fn tilt_checks(&self, d: &Data, tilt: Tilt<'_>) -> Result<(), ModelError> {
        let nj = self.joints.len();
        match tilt {
            Tilt::Off => return Ok(()),
            Tilt::Bend(m) if m.len() != nj => {
                return Err(ModelError::MomentCount {
                    expected: nj,
                    found: m.len(),
                })
            }
            Tilt::Bend(_) => return Ok(()),
            Tilt::Moments(m) if m.len() != nj => {
                self.require_tilt()?;
                return Err(ModelError::MomentCount {
                    expected: nj,
                    found: m.len(),
                });
            }
            Tilt::StaticPlus(m) if m.len() != nj => {
                return Err(ModelError::JointCount {
                    expected: nj,
                    found: m.len(),
                })
            }
            _ => {}
        }
        if d.tilt_values.len() != nj {
            return Err(ModelError::NoTiltData {
                model: self.name.clone(),
            });
        }
        Ok(())
    }

    /// Forward kinematics of one pose into the workspace `d` (no heap allocation once `d` is
    /// warm): tool point ([`Data::position_mm`]), rotation, moments and tilts. Same results as
    /// [`Model::fk`].
    pub fn fk_with(&self, d: &mut Data, q_deg: &[f64], tilt: Tilt<'_>) -> Result<(), ModelError> {
        d.sync(self);
        self.fk_synced(d, q_deg, tilt)
    }

    /// [`Model::fk_with`] on a workspace already synchronised with this model ([`Data::sync`]).
    pub(crate) fn fk_synced(
        &self,
        d: &mut Data,
        q_deg: &[f64],
        tilt: Tilt<'_>,
    ) -> Result<(), ModelError> {
        self.fk_bent(d, q_deg, tilt, false)
    }

    /// [`Model::fk_synced`]; with `bend_always` the static moments and the tilt axes are
    /// evaluated even where nothing tilts (the Jacobian wrt a lateral compliance at zero).
    pub(crate) fn fk_bent(
        &self,
        d: &mut Data,
        q_deg: &[f64],
        tilt: Tilt<'_>,
        bend_always: bool,
    ) -> Result<(), ModelError> {
        // Given sines and cosines are for this evaluation only, even one that fails.
        let given = std::mem::replace(&mut d.q_sc_given, false);
        self.check_joints(q_deg)?;
        self.tilt_checks(d, tilt)?;
        self.load_joints(d, q_deg, given);
        d.has_untilted = false;
        d.tilted = !matches!(tilt, Tilt::Off | Tilt::Bend(_));
        let lateral = self.has_lateral_compliance();
        d.bent = d.tilted || lateral || bend_always;
        match tilt {
            Tilt::Off if d.bent => {
                self.sweep(d, false, true);
                self.static_moments(d);
                d.has_untilted = true;
            }
            Tilt::Off => {}
            Tilt::Static | Tilt::StaticPlus(_) => {
                self.sweep(d, false, true);
                self.static_moments(d);
                d.has_untilted = true;
                if let Tilt::StaticPlus(extra) = tilt {
                    for (m, e) in d.moments_kgfm.iter_mut().zip(extra) {
                        *m += e;
                    }
                }
            }
            Tilt::Moments(m) => d.moments_kgfm.copy_from_slice(m),
            Tilt::Bend(m) if d.bent => d.moments_kgfm.copy_from_slice(m),
            Tilt::Bend(_) => {}
        }
        if d.bent {
            for j in 0..self.joints.len() {
                let eta = &d.moments_kgfm[j];
                let mut t = if d.tilted {
                    tilt_from_moment(eta, &d.tilt_values[j], self.gamma_law)
                } else {
                    Vector3::zeros()
                };
                if lateral {
                    t += lateral_tilt_deg(self.lateral_compliance_at(j), eta);
                }
                d.tilts_deg[j] = t;
            }
        }
        self.sweep(d, d.bent, false);
        d.position_mm = d.tool_unscaled() * d.scale;
        Ok(())
    }
}

/// The running frame of a sweep: rotation columns and position (mm).
#[derive(Debug, Clone, Copy)]
struct Frame {
    cols: [Vector3<f64>; 3],
    pos: Vector3<f64>,
}

impl Frame {
    fn identity() -> Self {
        Self {
            cols: [Vector3::x(), Vector3::y(), Vector3::z()],
            pos: Vector3::zeros(),
        }
    }

    /// `R <- R . R_axis(angle)` given `(sin, cos)`: the two other columns turn.
    #[inline(always)]
    fn rotate(&mut self, axis: usize, s: f64, c: f64) {
        let [x, y, z] = self.cols;
        self.cols = match axis {
            0 => [x, y * c + z * s, z * c - y * s],
            1 => [x * c - z * s, y, z * c + x * s],
            _ => [x * c + y * s, y * c - x * s, z],
        };
    }

    /// One element with its cached `(sin, cos)` (rotation) or value `v` (translation).
    #[inline(always)]
    fn apply(&mut self, motion: Motion, axis: usize, s: f64, c: f64, v: f64) {
        match motion {
            Motion::Rot => self.rotate(axis, s, c),
            Motion::Trans => {
                let [x, y, z] = self.cols;
                self.pos += match axis {
                    0 => x,
                    1 => y,
                    _ => z,
                } * v;
            }
        }
    }
}
