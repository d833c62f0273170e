//! The model's structure: a sequence of elementary transforms over named parameters, joints,
//! point masses and joint-tilting values ([`super::ModelBuilder`] assembles it).

use nalgebra::Vector3;

use super::error::ModelError;
use super::param::{Param, ParamKind, Unit};

/// Coordinate axis of an elementary transform.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    /// Column index 0, 1, 2.
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// Rotation about or translation along an axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Motion {
    /// `R<axis>(value)`, value in degrees.
    Rot,
    /// `T<axis>(value)`, value in millimetres.
    Trans,
}

/// One elementary transform of the chain. Its value is the parameter `param`, plus, when it is
/// driven by joint `joint` (0-based), the joint reading and the joint's encoder-harmonic error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Elem {
    pub motion: Motion,
    pub axis: Axis,
    /// Index into the model's parameters: the constant value, or the joint offset.
    pub param: usize,
    /// The joint driving this transform, if any (0-based).
    pub joint: Option<usize>,
}

/// One harmonic `s sin(n q) + c cos(n q)` (deg) of a joint's encoder error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Harmonic {
    /// Order `n` (1..=3).
    pub order: u32,
    /// Index of the `enc_j<i>_h<n>_sin` parameter.
    pub sin_param: usize,
    /// Index of the `enc_j<i>_h<n>_cos` parameter.
    pub cos_param: usize,
}

/// Number of encoder harmonics every revolute joint carries (FORMATS.md: n = 1..3).
pub const HARMONIC_ORDERS: u32 = 3;

/// One joint: the transform it drives, its limits and its encoder harmonics.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Index of the driven element; joint frame i is the frame right after it.
    pub elem: usize,
    /// `true` for a prismatic joint (`Tz`), `false` for a revolute one (`Rz`).
    pub prismatic: bool,
    /// Lower and upper limit (deg, or mm for a prismatic joint).
    pub limits: [f64; 2],
    /// Encoder harmonics (empty for a prismatic joint).
    pub harmonics: Vec<Harmonic>,
}

/// A point mass rigidly attached to a frame of the chain (link centre of gravity).
#[derive(Debug, Clone, PartialEq)]
pub struct PointMass {
    /// The joint that carries it (0-based).
    pub joint: usize,
    /// Number of elements after the joint's element: the mass sits in the frame after element
    /// `joints[joint].elem + after`.
    pub after: usize,
    /// Mass (kg).
    pub mass_kg: f64,
    /// Centre of gravity in that frame (mm).
    pub com_mm: Vector3<f64>,
}

/// How the tilt direction angle gamma is computed from the moment (MODEL.md eq. 5.16).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GammaLaw {
    /// `gamma = (pi/2) |eta_x| / (|eta_x| + |eta_y|)`: the declared model.
    #[default]
    Linear,
    /// `gamma = atan2(|eta_x|, |eta_y|)`: the exact direction (erratum 3), an option.
    Atan2,
}

/// Per-joint indices of the tilting parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TiltParams {
    /// `clearance_j<i>` (deg).
    pub clearance: usize,
    /// `backlash_j<i>` (deg).
    pub backlash: usize,
    /// `stiffness_j<i>` (kgf.m/deg).
    pub stiffness: usize,
}

/// Declared tilting values of one joint (thesis table 5.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TiltValues {
    pub clearance_deg: f64,
    pub backlash_deg: f64,
    pub stiffness_kgfm_per_deg: f64,
}

/// A robot model: constant structure plus current parameter values. Cheap to clone; change
/// values with [`Model::set_param`] / [`Model::set_param_values`].
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    pub(crate) name: String,
    pub(crate) elems: Vec<Elem>,
    /// Range of `elems` that is the robot's own chain (without base and tool elements).
    pub(crate) robot_elems: std::ops::Range<usize>,
    pub(crate) joints: Vec<Joint>,
    pub(crate) params: Vec<Param>,
    pub(crate) masses: Vec<PointMass>,
    /// The masses are assumed, not declared ([`Model::with_assumed_masses`]).
    pub(crate) masses_assumed: bool,
    pub(crate) tilt: Option<Vec<TiltParams>>,
    pub(crate) gamma_law: GammaLaw,
    /// The Jacobian holds the clearance tilt's direction fixed (see
    /// [`Model::set_tilt_direction_frozen`]).
    pub(crate) tilt_direction_frozen: bool,
    pub(crate) payload_param: usize,
    pub(crate) scale_param: usize,
    /// Names of the joints (e.g. URDF joint names), or empty.
    pub(crate) joint_names: Vec<String>,
    /// Transmission terms on the joint angles (model files; [`super::transmission`]).
    pub(crate) transmission: super::transmission::JointTerms,
    /// Terms that depend on the pose time ([`super::time_terms`]).
    pub(crate) time_terms: super::time_terms::TimeTerms,
    /// Lateral compliance per joint, deg per kgf.m (empty: none; [`super::lateral`]).
    pub(crate) lateral_deg_per_kgfm: Vec<f64>,
}

impl Model {
    /// Names of the joints in order (e.g. the URDF's, for pose-file columns), or empty.
    pub fn joint_names(&self) -> &[String] {
        &self.joint_names
    }

    /// Names the joints (one name per joint, all different; an empty list removes the names).
    pub fn set_joint_names(&mut self, names: Vec<String>) -> Result<(), ModelError> {
        let mut seen = std::collections::HashSet::with_capacity(names.len());
        let distinct = names.iter().all(|n| seen.insert(n.as_str()));
        // a joint name is a pose-file column: no separator, control character or outer blank
        if let Some(bad) = names.iter().find(|n| {
            n.is_empty()
                || n.trim() != n.as_str()
                || n.contains(',')
                || n.chars().any(char::is_control)
        }) {
            return Err(ModelError::Invalid(format!(
                "joint name {bad:?}: not usable as a pose-file column (empty, a comma, a control character or outer blanks)"
            )));
        }
        if !names.is_empty() && (names.len() != self.joints.len() || !distinct) {
            return Err(ModelError::Invalid(format!(
                "{} joint names (all different) needed, got {names:?}",
                self.joints.len()
            )));
        }
        self.joint_names = names;
        Ok(())
    }

    /// The model's name (e.g. `"katana450"`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of joints.
    pub fn n_joints(&self) -> usize {
        self.joints.len()
    }

    /// The joints, in order.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// Joint limits `[min, max]` (deg, mm for prismatic), in joint order.
    pub fn joint_limits(&self) -> Vec<[f64; 2]> {
        self.joints.iter().map(|j| j.limits).collect()
    }

    /// The elementary transforms, base and tool elements included.
    pub fn elems(&self) -> &[Elem] {
        &self.elems
    }

    /// Link masses (without the payload).
    pub fn masses(&self) -> &[PointMass] {
        &self.masses
    }

    /// Whether the model has tilting data (so `Tilt::Static` / `Tilt::Moments` can be used).
    pub fn has_tilt(&self) -> bool {
        self.tilt.is_some()
    }

    /// Tilting parameter indices per joint, if the model has tilting data.
    pub fn tilt_params(&self) -> Option<&[TiltParams]> {
        self.tilt.as_deref()
    }

    /// The gamma law used by the tilt model.
    pub fn gamma_law(&self) -> GammaLaw {
        self.gamma_law
    }

    /// Chooses the gamma law (the declared model is [`GammaLaw::Linear`]).
    pub fn set_gamma_law(&mut self, law: GammaLaw) {
        self.gamma_law = law;
    }

    /// Whether the Jacobian holds the clearance tilt's direction fixed.
    pub fn tilt_direction_frozen(&self) -> bool {
        self.tilt_direction_frozen
    }

    /// Makes the Jacobian (not the position) hold the direction of the clearance tilt fixed:
    /// the contact angle gamma of MODEL.md eq. 5.16, like the `sign()` steps, counts as flat
    /// in the moments, while the compliance term `eta_z / k` keeps its slope. Gamma's slope
    /// grows as `1 / (|eta_x| + |eta_y|)` where a joint's moment vanishes: there the linearised
    /// information holds only within a hair of the nominal parameters and the contact direction
    /// is physically undetermined, so `rigctl plan` designs on this Jacobian (elsewhere the term
    /// is a small share of a column). Off by default (calibration differentiates the declared
    /// law exactly).
    pub fn set_tilt_direction_frozen(&mut self, frozen: bool) {
        self.tilt_direction_frozen = frozen;
    }

    /// All parameters, in a fixed order (the order of Jacobian columns by index).
    pub fn params(&self) -> &[Param] {
        &self.params
    }

    /// Parameter names, in order.
    pub fn param_names(&self) -> impl Iterator<Item = &str> {
        self.params.iter().map(|p| p.name.as_str())
    }

    /// Index of the parameter called `name`.
    pub fn param_index(&self, name: &str) -> Option<usize> {
        self.params.iter().position(|p| p.name == name)
    }

    /// Index of `name`, or [`ModelError::UnknownParam`] listing the valid names.
    pub fn require_param(&self, name: &str) -> Result<usize, ModelError> {
        self.param_index(name)
            .ok_or_else(|| ModelError::UnknownParam {
                name: name.to_string(),
                valid: self.param_names().collect::<Vec<_>>().join(", "),
            })
    }

    /// Current value of `name`.
    pub fn param(&self, name: &str) -> Option<f64> {
        self.param_index(name).map(|i| self.params[i].value)
    }

    /// Sets `name` to `value` (in the parameter's unit).
    pub fn set_param(&mut self, name: &str, value: f64) -> Result<(), ModelError> {
        let i = self.require_param(name)?;
        self.set_param_at(i, value)
    }

    /// Sets parameter `index` to `value`.
    pub fn set_param_at(&mut self, index: usize, value: f64) -> Result<(), ModelError> {
        let count = self.params.len();
        let p = self
            .params
            .get_mut(index)
            .ok_or(ModelError::ParamIndex { index, count })?;
        if !value.is_finite() {
            return Err(ModelError::NonFinite {
                name: p.name.clone(),
                value,
            });
        }
        if p.unit == Unit::KgfmPerDeg && value <= 0.0 {
            return Err(ModelError::Invalid(format!(
                "{} = {value}: a stiffness must be > 0",
                p.name
            )));
        }
        p.value = value;
        Ok(())
    }

    /// All current values, in parameter order.
    pub fn param_values(&self) -> Vec<f64> {
        self.params.iter().map(|p| p.value).collect()
    }

    /// Sets all values at once (`values.len()` must equal the number of parameters).
    pub fn set_param_values(&mut self, values: &[f64]) -> Result<(), ModelError> {
        if values.len() != self.params.len() {
            return Err(ModelError::ParamIndex {
                index: values.len(),
                count: self.params.len(),
            });
        }
        for (i, &v) in values.iter().enumerate() {
            self.set_param_at(i, v)?;
        }
        Ok(())
    }

    /// Indices of the parameters of one kind, in order.
    pub fn params_of_kind(&self, kind: ParamKind) -> Vec<usize> {
        (0..self.params.len())
            .filter(|&i| self.params[i].kind == kind)
            .collect()
    }

    /// Index of `payload_kg`.
    pub fn payload_param(&self) -> usize {
        self.payload_param
    }

    /// Index of `scale_ppm`.
    pub fn scale_param(&self) -> usize {
        self.scale_param
    }

    /// Declared tilting values of every joint (current parameter values), if any.
    pub fn tilt_values(&self) -> Option<Vec<TiltValues>> {
        self.tilt.as_ref().map(|t| {
            t.iter()
                .map(|tp| TiltValues {
                    clearance_deg: self.params[tp.clearance].value,
                    backlash_deg: self.params[tp.backlash].value,
                    stiffness_kgfm_per_deg: self.params[tp.stiffness].value,
                })
                .collect()
        })
    }

    /// Index `k` of the frame (the one after element `k`) that carries `mass`.
    pub fn mass_frame(&self, mass: &PointMass) -> usize {
        self.joints[mass.joint].elem + mass.after
    }
}
