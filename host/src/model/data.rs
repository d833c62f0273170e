//! The per-evaluation workspace of a [`Model`] (pinocchio's `Model` / `Data` split): every
//! buffer forward kinematics, moments, tilts and the analytic Jacobian need, allocated once
//! ([`Data::new`]) and reused, so that [`Model::fk_with`] and [`Model::jacobian_with`] do not
//! touch the heap per pose.
//!
//! The `Model` is the constant part (chain, parameters); the joint-independent values derived
//! from its parameters (sine and cosine of every constant rotation, the tilting values, the
//! measurement scale, which element each parameter moves) are cached in the `Data` and refreshed
//! automatically when the model's parameter values change (one comparison per parameter and
//! evaluation), so a `Data` can follow a model through an identification.
//!
//! Per pose, each joint costs one `sin_cos` (plus one per non-zero encoder harmonic); each
//! constant element costs a two-column update of the running rotation (or a translation). With
//! static tilting the untilted chain is evaluated once for the moments and the tilted chain
//! reuses its joint sines and cosines (only the three tilt angles per joint are new).

use nalgebra::{Matrix3, Vector3};

use super::chain::{Elem, Model, Motion, TiltValues};
use super::error::ModelError;
use super::tilt::tilt_from_moment;
use super::tilt::{Tilt, GRAVITY_KGF_PER_KG};

/// What a parameter moves directly (the Jacobian's direct effect).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum ParamEffect {
    /// No element: tilting values, payload, scale (handled separately).
    None,
    /// The value of element `elem` (rate 1).
    Elem(usize),
    /// An encoder harmonic of `joint` of order `order`: `sin` (true) or `cos` coefficient.
    Harmonic { joint: usize, order: u32, sin: bool },
}

/// Reusable workspace for evaluating one [`Model`] (see the module doc). Results of the last
/// evaluation are read with the accessors ([`Data::position_mm`], [`Data::jacobian`], ...).
#[derive(Debug, Clone)]
pub struct Data {
    // --- joint-independent cache, keyed on the model's parameter values ---
    pub(crate) param_bits: Vec<u64>,
    pub(crate) n_elems: usize,
    /// The model's elements (the cache is refreshed when they differ).
    pub(crate) elems: Vec<Elem>,
    /// Per element: `(sin, cos)` of a constant rotation's value, or `(value, 0)` for a constant
    /// translation; per pose for joint elements.
    pub(crate) elem_sc: Vec<(f64, f64)>,
    /// Per element: the value (deg / mm); per pose for joint elements.
    pub(crate) elem_value: Vec<f64>,
    pub(crate) tilt_values: Vec<TiltValues>,
    pub(crate) scale: f64,
    pub(crate) payload_kg: f64,
    pub(crate) effects: Vec<ParamEffect>,
    /// Per joint: `(sin, cos)` of its offset parameter (for [`Data::give_joint_sin_cos`]).
    pub(crate) offset_sc: Vec<(f64, f64)>,
    // --- per evaluation ---
    /// Per joint: `(sin, cos)` of the reading, given by the caller for the next evaluation
    /// (`q_sc_given`), e.g. cached once per pose over the iterations of an identification.
    pub(crate) q_sc: Vec<(f64, f64)>,
    pub(crate) q_sc_given: bool,
    /// Per joint: `(q_eff, d q_eff / d q)`.
    pub(crate) joint_dv: Vec<f64>,
    /// Frames of the evaluated (tilted when tilting is on) chain.
    pub(crate) rot: Vec<Matrix3<f64>>,
    pub(crate) pos_mm: Vec<Vector3<f64>>,
    /// Untilted frames (static moments), valid when `has_untilted`.
    pub(crate) rot0: Vec<Matrix3<f64>>,
    pub(crate) pos0_mm: Vec<Vector3<f64>>,
    pub(crate) has_untilted: bool,
    /// Per joint: the three tilt axes in R (`r0 x`, `(r0 Rx) y`, `(r0 Rx Ry) z`).
    pub(crate) tilt_axes: Vec<[Vector3<f64>; 3]>,
    /// Mass points of the untilted chain: (frame, kg, world point mm).
    pub(crate) points: Vec<(usize, f64, Vector3<f64>)>,
    /// Per frame k: sum of `m c` (kg mm) and of `m` (kg) over the points on frames `>= k`.
    pub(crate) suffix_mc: Vec<Vector3<f64>>,
    pub(crate) suffix_m: Vec<f64>,
    pub(crate) moments_kgfm: Vec<Vector3<f64>>,
    pub(crate) tilts_deg: Vec<Vector3<f64>>,
    pub(crate) tilted: bool,
    pub(crate) position_mm: Vector3<f64>,
    // --- Jacobian ---
    pub(crate) jac: Vec<Vector3<f64>>,
    pub(crate) sums: Vec<Vector3<f64>>,
    pub(crate) tilt_g: Vec<Matrix3<f64>>,
    pub(crate) tilt_partials: Vec<super::tilt::TiltPartials>,
    /// Per joint: `K_i = G_i (d tilt_i / d eta_i) R_i^T`, tool motion per moment change in R.
    pub(crate) k_mat: Vec<Matrix3<f64>>,
    /// `sum_{i < j} K_i` (j = 0..=joints).
    pub(crate) k_pre: Vec<Matrix3<f64>>,
    /// `sum_{i >= j} K_i A_i` with `A_i w` the change of joint i's moment (R) for a rotation `w`
    /// before it (j = 0..=joints).
    pub(crate) ka_post: Vec<Matrix3<f64>>,
    /// Per element: the number of joints whose element comes before it (structure).
    pub(crate) joints_before: Vec<usize>,
}

impl Data {
    /// A workspace sized for `model` (its current parameter values cached).
    pub fn new(model: &Model) -> Self {
        let mut d = Data::new_shape(model);
        d.refresh(model);
        d
    }

    /// Recomputes the joint-independent cache from `model` (allocates only when the model's
    /// shape differs from the one the workspace was made for).
    fn refresh(&mut self, model: &Model) {
        let (ne, nj) = (model.elems.len(), model.joints.len());
        if ne != self.n_elems || nj != self.joint_dv.len() {
            *self = Data::new_shape(model);
        }
        self.param_bits.clear();
        self.param_bits
            .extend(model.params.iter().map(|p| p.value.to_bits()));
        self.elems.clone_from(&model.elems);
        for (e, slot) in self.joints_before.iter_mut().enumerate() {
            *slot = model.joints.iter().filter(|j| j.elem < e).count();
        }
        for (k, e) in model.elems.iter().enumerate() {
            let v = model.params[e.param].value;
            self.elem_value[k] = v;
            self.elem_sc[k] = match e.motion {
                Motion::Rot => v.to_radians().sin_cos(),
                Motion::Trans => (v, 0.0),
            };
        }
        for (slot, joint) in self.offset_sc.iter_mut().zip(&model.joints) {
            *slot = model.params[model.elems[joint.elem].param]
                .value
                .to_radians()
                .sin_cos();
        }
        self.tilt_values.clear();
        if let Some(tps) = &model.tilt {
            self.tilt_values.extend(tps.iter().map(|tp| TiltValues {
                clearance_deg: model.params[tp.clearance].value,
                backlash_deg: model.params[tp.backlash].value,
                stiffness_kgfm_per_deg: model.params[tp.stiffness].value,
            }));
        }
        self.scale = model.scale_factor();
        self.payload_kg = model.params[model.payload_param].value;
        self.effects.clear();
        self.effects
            .extend((0..model.params.len()).map(|i| param_effect(model, i)));
    }

    /// A workspace of `model`'s shape with an empty cache (filled by `refresh`).
    fn new_shape(model: &Model) -> Self {
        let mut d = Data::new_empty();
        d.n_elems = model.elems.len();
        let (ne, nj) = (model.elems.len(), model.joints.len());
        d.elem_sc = vec![(0.0, 1.0); ne];
        d.elem_value = vec![0.0; ne];
        d.joint_dv = vec![1.0; nj];
        d.offset_sc = vec![(0.0, 1.0); nj];
        d.q_sc = vec![(0.0, 1.0); nj];
        d.rot = vec![Matrix3::identity(); ne];
        d.pos_mm = vec![Vector3::zeros(); ne];
        d.rot0 = vec![Matrix3::identity(); ne];
        d.pos0_mm = vec![Vector3::zeros(); ne];
        d.tilt_axes = vec![[Vector3::zeros(); 3]; nj];
        d.suffix_mc = vec![Vector3::zeros(); ne];
        d.suffix_m = vec![0.0; ne];
        d.moments_kgfm = vec![Vector3::zeros(); nj];
        d.tilts_deg = vec![Vector3::zeros(); nj];
        d.sums = vec![Vector3::zeros(); nj];
        d.tilt_g = vec![Matrix3::zeros(); nj];
        d.k_mat = vec![Matrix3::zeros(); nj];
        d.k_pre = vec![Matrix3::zeros(); nj + 1];
        d.ka_post = vec![Matrix3::zeros(); nj + 1];
        d.joints_before = vec![0; ne];
        d.tilt_values = Vec::with_capacity(nj);
        d.tilt_partials = Vec::with_capacity(nj);
        d.points = Vec::with_capacity(model.masses.len() + 1);
        d.jac = Vec::with_capacity(model.params.len().max(nj));
        d.param_bits = Vec::with_capacity(model.params.len());
        d.effects = Vec::with_capacity(model.params.len());
        d
    }

    fn new_empty() -> Self {
        Data {
            param_bits: Vec::new(),
            n_elems: 0,
            elems: Vec::new(),
            elem_sc: Vec::new(),
            elem_value: Vec::new(),
            tilt_values: Vec::new(),
            scale: 1.0,
            payload_kg: 0.0,
            effects: Vec::new(),
            offset_sc: Vec::new(),
            q_sc: Vec::new(),
            q_sc_given: false,
            joint_dv: Vec::new(),
            rot: Vec::new(),
            pos_mm: Vec::new(),
            rot0: Vec::new(),
            pos0_mm: Vec::new(),
            has_untilted: false,
            tilt_axes: Vec::new(),
            points: Vec::new(),
            suffix_mc: Vec::new(),
            suffix_m: Vec::new(),
            moments_kgfm: Vec::new(),
            tilts_deg: Vec::new(),
            tilted: false,
            position_mm: Vector3::zeros(),
            jac: Vec::new(),
            sums: Vec::new(),
            tilt_g: Vec::new(),
            tilt_partials: Vec::new(),
            k_mat: Vec::new(),
            k_pre: Vec::new(),
            ka_post: Vec::new(),
            joints_before: Vec::new(),
        }
    }

    /// Refreshes the cache if `model`'s parameter values (or shape) changed since the last call
    /// (the `*_with` evaluations call it themselves).
    pub fn sync(&mut self, model: &Model) {
        let same = self.elems == model.elems
            && self.tilt_values.len() == model.tilt.as_ref().map_or(0, Vec::len)
            && self.param_bits.len() == model.params.len()
            && self
                .param_bits
                .iter()
                .zip(&model.params)
                .all(|(b, p)| *b == p.value.to_bits());
        if !same {
            self.refresh(model);
        }
    }

    /// Gives `(sin, cos)` of every joint reading (radians of the degrees read) for the next
    /// evaluation only: a caller that evaluates the same poses many times (an identification)
    /// computes them once per pose; the evaluation then takes `sin`/`cos` of `q + offset` by
    /// the angle sum instead of calling `sin_cos` (not for a joint with encoder harmonics).
    /// Ignored unless there is one pair per joint.
    pub fn give_joint_sin_cos(&mut self, sin_cos: &[(f64, f64)]) {
        if sin_cos.len() == self.q_sc.len() {
            self.q_sc.copy_from_slice(sin_cos);
            self.q_sc_given = true;
        }
    }

    /// Tool point (mm, R, scale included) of the last evaluation.
    pub fn position_mm(&self) -> Vector3<f64> {
        self.position_mm
    }

    /// Tool (last frame) rotation of the last evaluation.
    pub fn rotation(&self) -> Matrix3<f64> {
        self.rot.last().copied().unwrap_or_else(Matrix3::identity)
    }

    /// Moments used for tilting (kgf.m, joint frame i); empty without tilting.
    pub fn moments_kgfm(&self) -> &[Vector3<f64>] {
        if self.tilted {
            &self.moments_kgfm
        } else {
            &[]
        }
    }

    /// Tilts per joint (deg); empty without tilting.
    pub fn tilts_deg(&self) -> &[Vector3<f64>] {
        if self.tilted {
            &self.tilts_deg
        } else {
            &[]
        }
    }

    /// Jacobian columns of the last [`Model::jacobian_with`] (one per `wrt` entry, mm per unit).
    pub fn jacobian(&self) -> &[Vector3<f64>] {
        &self.jac
    }

    /// Origin of the tool frame before the scale (tilted chain).
    pub(crate) fn tool_unscaled(&self) -> Vector3<f64> {
        self.pos_mm.last().copied().unwrap_or_else(Vector3::zeros)
    }
}

/// The direct effect of parameter `i` of `model`.
fn param_effect(model: &Model, i: usize) -> ParamEffect {
    if let Some(e) = model.elems.iter().position(|e| e.param == i) {
        return ParamEffect::Elem(e);
    }
    for (j, joint) in model.joints.iter().enumerate() {
        for h in &joint.harmonics {
            if h.sin_param == i || h.cos_param == i {
                return ParamEffect::Harmonic {
                    joint: j,
                    order: h.order,
                    sin: h.sin_param == i,
                };
            }
        }
    }
    ParamEffect::None
}

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
        Ok(())
    }

    fn tilt_checks(&self, d: &Data, tilt: Tilt<'_>) -> Result<(), ModelError> {
        let nj = self.joints.len();
        match tilt {
            Tilt::Off => return Ok(()),
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
        // Given sines and cosines are for this evaluation only, even one that fails.
        let given = std::mem::replace(&mut d.q_sc_given, false);
        self.check_joints(q_deg)?;
        self.tilt_checks(d, tilt)?;
        self.load_joints(d, q_deg, given);
        d.has_untilted = false;
        d.tilted = !matches!(tilt, Tilt::Off);
        match tilt {
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
        }
        if d.tilted {
            for j in 0..self.joints.len() {
                d.tilts_deg[j] =
                    tilt_from_moment(&d.moments_kgfm[j], &d.tilt_values[j], self.gamma_law);
            }
        }
        self.sweep(d, d.tilted, false);
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
