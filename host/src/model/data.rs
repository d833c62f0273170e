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
    /// Whether the sweep inserted tilts: the declared tilting, a lateral compliance, or a
    /// Jacobian with respect to one ([`super::Wrt::Lateral`]).
    pub(crate) bent: bool,
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
            bent: false,
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

    /// Moments used for tilting and lateral compliance (kgf.m, joint frame i); empty when no
    /// joint tilts.
    pub fn moments_kgfm(&self) -> &[Vector3<f64>] {
        if self.bent {
            &self.moments_kgfm
        } else {
            &[]
        }
    }

    /// Tilts per joint (deg: the declared tilting plus the lateral compliance's bend); empty
    /// when no joint tilts.
    pub fn tilts_deg(&self) -> &[Vector3<f64>] {
        if self.bent {
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

mod eval;
