//! [`ModelBuilder`]: assembles a [`Model`] from base elements, the robot's chain (DH, modified
//! DH or elementary rows, joints, masses, tilting values) and, when built, the tool point and the
//! encoder, tilt, payload and scale parameters.

use nalgebra::Vector3;

/// The name of every chain's payload parameter (kg at the tool point).
pub const PAYLOAD_PARAM: &str = "payload_kg";

use super::chain::{
    Axis, Elem, GammaLaw, Harmonic, Joint, Model, Motion, PointMass, TiltParams, TiltValues,
    HARMONIC_ORDERS,
};
use super::error::ModelError;
use super::param::{Param, ParamKind, Unit};

/// Assembles a [`Model`]: base elements first, then the robot's chain in order, then (in
/// [`ModelBuilder::build`]) the tool elements and the encoder, tilt, payload and scale
/// parameters.
#[derive(Debug, Clone)]
pub struct ModelBuilder {
    name: String,
    elems: Vec<Elem>,
    robot_start: usize,
    params: Vec<Param>,
    joints: Vec<Joint>,
    masses: Vec<PointMass>,
    tilt_values: Vec<Option<TiltValues>>,
    gamma_law: GammaLaw,
    /// The names in `params` (a name is checked once, not against every earlier one).
    param_names: std::collections::HashSet<String>,
}

impl ModelBuilder {
    /// Starts a model: adds `base_x, base_y, base_z` (mm) and `base_rx, base_ry` (deg), all 0,
    /// as `Tx Ty Tz Rx Ry` in frame R.
    pub fn new(name: &str) -> Self {
        let mut b = Self {
            name: name.to_string(),
            elems: Vec::new(),
            robot_start: 0,
            params: Vec::new(),
            joints: Vec::new(),
            masses: Vec::new(),
            tilt_values: Vec::new(),
            gamma_law: GammaLaw::Linear,
            param_names: std::collections::HashSet::new(),
        };
        let base = [
            (Motion::Trans, Axis::X, "base_x"),
            (Motion::Trans, Axis::Y, "base_y"),
            (Motion::Trans, Axis::Z, "base_z"),
            (Motion::Rot, Axis::X, "base_rx"),
            (Motion::Rot, Axis::Y, "base_ry"),
        ];
        for (motion, axis, name) in base {
            let unit = if motion == Motion::Rot {
                Unit::Deg
            } else {
                Unit::Mm
            };
            let param = b.params.len();
            b.param_names.insert(name.to_string());
            b.params.push(Param {
                name: name.into(),
                value: 0.0,
                unit,
                kind: ParamKind::Base,
            });
            b.elems.push(Elem {
                motion,
                axis,
                param,
                joint: None,
            });
        }
        b.robot_start = b.elems.len();
        b
    }

    fn add_param(
        &mut self,
        name: &str,
        value: f64,
        unit: Unit,
        kind: ParamKind,
    ) -> Result<usize, ModelError> {
        if self.param_names.contains(name) {
            return Err(ModelError::Invalid(format!(
                "parameter name `{name}` used twice"
            )));
        }
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(ModelError::Invalid(format!(
                "parameter name `{name}`: use letters, digits and `_`"
            )));
        }
        if !value.is_finite() {
            return Err(ModelError::NonFinite {
                name: name.into(),
                value,
            });
        }
        self.param_names.insert(name.to_string());
        self.params.push(Param {
            name: name.into(),
            value,
            unit,
            kind,
        });
        Ok(self.params.len() - 1)
    }

    /// Appends a constant transform `R<axis>(value deg)` or `T<axis>(value mm)` whose value is
    /// the new parameter `name`. The parameter kind is `Twist` / `Length` unless given.
    pub fn constant(
        &mut self,
        motion: Motion,
        axis: Axis,
        name: &str,
        value: f64,
    ) -> Result<&mut Self, ModelError> {
        let (unit, kind) = match motion {
            Motion::Rot => (Unit::Deg, ParamKind::Twist),
            Motion::Trans => (Unit::Mm, ParamKind::Length),
        };
        let param = self.add_param(name, value, unit, kind)?;
        self.elems.push(Elem {
            motion,
            axis,
            param,
            joint: None,
        });
        Ok(self)
    }

    /// Appends the next joint: `Rz(q + offset)` (revolute) or `Tz(q + offset)` (prismatic),
    /// with offset parameter `offset_name`, limits `[min, max]` and optional tilting values.
    /// Joint frame i is the frame right after this element.
    pub fn joint(
        &mut self,
        prismatic: bool,
        offset_name: &str,
        offset: f64,
        limits: [f64; 2],
        tilt: Option<TiltValues>,
    ) -> Result<&mut Self, ModelError> {
        if !(limits[0].is_finite() && limits[1].is_finite() && limits[0] <= limits[1]) {
            return Err(ModelError::Invalid(format!(
                "joint {}: limits [{}, {}] are not an interval",
                self.joints.len() + 1,
                limits[0],
                limits[1]
            )));
        }
        let unit = if prismatic { Unit::Mm } else { Unit::Deg };
        let param = self.add_param(offset_name, offset, unit, ParamKind::JointOffset)?;
        let joint = self.joints.len();
        let (motion, axis) = if prismatic {
            (Motion::Trans, Axis::Z)
        } else {
            (Motion::Rot, Axis::Z)
        };
        self.elems.push(Elem {
            motion,
            axis,
            param,
            joint: Some(joint),
        });
        self.joints.push(Joint {
            elem: self.elems.len() - 1,
            prismatic,
            limits,
            harmonics: Vec::new(),
        });
        self.tilt_values.push(tilt);
        Ok(self)
    }

    /// Attaches a link mass to joint `joint` (1-based), `after` elements past its element.
    pub fn mass(
        &mut self,
        joint: usize,
        after: usize,
        mass_kg: f64,
        com_mm: [f64; 3],
    ) -> Result<&mut Self, ModelError> {
        if joint == 0 || joint > self.joints.len() {
            return Err(ModelError::Invalid(format!(
                "mass on joint {joint}: joints are numbered 1..{} (declare the mass after its joint)",
                self.joints.len()
            )));
        }
        if !(mass_kg.is_finite() && mass_kg >= 0.0 && com_mm.iter().all(|c| c.is_finite())) {
            return Err(ModelError::Invalid(format!(
                "mass on joint {joint}: values must be finite, kg >= 0"
            )));
        }
        self.masses.push(PointMass {
            joint: joint - 1,
            after,
            mass_kg,
            com_mm: Vector3::from(com_mm),
        });
        Ok(self)
    }

    /// Chooses the gamma law.
    pub fn gamma_law(&mut self, law: GammaLaw) -> &mut Self {
        self.gamma_law = law;
        self
    }

    /// Number of joints added so far.
    pub fn n_joints(&self) -> usize {
        self.joints.len()
    }

    /// Finishes the model: appends `tool_dx, tool_dy, tool_dz` (mm, `Tx Ty Tz` in the last
    /// frame), the encoder harmonics `enc_j<i>_h<n>_sin/_cos` (deg, n = 1..3, revolute joints),
    /// `clearance_j<i>, backlash_j<i>, stiffness_j<i>` (if every joint has tilting values),
    /// `payload_kg` and `scale_ppm`.
    pub fn build(mut self) -> Result<Model, ModelError> {
        if self.joints.is_empty() {
            return Err(ModelError::Invalid("the chain has no joint".into()));
        }
        let robot_elems = self.robot_start..self.elems.len();
        self.add_tool_point()?;
        self.check_masses()?;
        self.add_harmonics()?;
        let tilt = self.add_tilt_params()?;
        let payload_param = self.add_param(PAYLOAD_PARAM, 0.0, Unit::Kg, ParamKind::Payload)?;
        let scale_param = self.add_param("scale_ppm", 0.0, Unit::Ppm, ParamKind::Scale)?;
        Ok(Model {
            name: self.name,
            elems: self.elems,
            robot_elems,
            joints: self.joints,
            params: self.params,
            masses: self.masses,
            masses_assumed: false,
            tilt,
            gamma_law: self.gamma_law,
            tilt_direction_frozen: false,
            payload_param,
            scale_param,
            joint_names: Vec::new(),
            transmission: Default::default(),
            time_terms: Default::default(),
            lateral_deg_per_kgfm: Vec::new(),
        })
    }

    /// Appends `tool_dx, tool_dy, tool_dz` (mm, `Tx Ty Tz` in the last frame).
    fn add_tool_point(&mut self) -> Result<(), ModelError> {
        for (axis, name) in [
            (Axis::X, "tool_dx"),
            (Axis::Y, "tool_dy"),
            (Axis::Z, "tool_dz"),
        ] {
            let param = self.add_param(name, 0.0, Unit::Mm, ParamKind::Tool)?;
            self.elems.push(Elem {
                motion: Motion::Trans,
                axis,
                param,
                joint: None,
            });
        }
        Ok(())
    }

    /// Every mass lies within the chain (tool point included).
    fn check_masses(&self) -> Result<(), ModelError> {
        let last_frame = self.elems.len() - 1;
        for m in &self.masses {
            if self.joints[m.joint].elem + m.after > last_frame {
                return Err(ModelError::Invalid(format!(
                    "mass on joint {} is {} elements past its joint, beyond the end of the chain",
                    m.joint + 1,
                    m.after
                )));
            }
        }
        Ok(())
    }

    /// Adds the encoder harmonics `enc_j<i>_h<n>_sin/_cos` (deg, n = 1..3) of every revolute
    /// joint.
    fn add_harmonics(&mut self) -> Result<(), ModelError> {
        for j in 0..self.joints.len() {
            if self.joints[j].prismatic {
                continue;
            }
            for n in 1..=HARMONIC_ORDERS {
                let s = self.add_param(
                    &format!("enc_j{}_h{n}_sin", j + 1),
                    0.0,
                    Unit::Deg,
                    ParamKind::EncoderHarmonic,
                )?;
                let c = self.add_param(
                    &format!("enc_j{}_h{n}_cos", j + 1),
                    0.0,
                    Unit::Deg,
                    ParamKind::EncoderHarmonic,
                )?;
                self.joints[j].harmonics.push(Harmonic {
                    order: n,
                    sin_param: s,
                    cos_param: c,
                });
            }
        }
        Ok(())
    }

    /// Adds `clearance_j<i>, backlash_j<i>, stiffness_j<i>` when every joint has tilting values
    /// (`None` when none has).
    fn add_tilt_params(&mut self) -> Result<Option<Vec<TiltParams>>, ModelError> {
        let n_tilt = self.tilt_values.iter().filter(|t| t.is_some()).count();
        let tilt = if n_tilt == 0 {
            None
        } else if n_tilt < self.joints.len() {
            return Err(ModelError::Invalid(
                "tilting values must be given for every joint or for none".into(),
            ));
        } else {
            let mut out = Vec::new();
            for (j, tv) in self.tilt_values.clone().into_iter().enumerate() {
                let tv = tv.ok_or_else(|| ModelError::Invalid("missing tilt values".into()))?;
                if tv.stiffness_kgfm_per_deg <= 0.0 {
                    return Err(ModelError::Invalid(format!(
                        "joint {}: stiffness must be > 0",
                        j + 1
                    )));
                }
                let i = j + 1;
                out.push(TiltParams {
                    clearance: self.add_param(
                        &format!("clearance_j{i}"),
                        tv.clearance_deg,
                        Unit::Deg,
                        ParamKind::Tilt,
                    )?,
                    backlash: self.add_param(
                        &format!("backlash_j{i}"),
                        tv.backlash_deg,
                        Unit::Deg,
                        ParamKind::Tilt,
                    )?,
                    stiffness: self.add_param(
                        &format!("stiffness_j{i}"),
                        tv.stiffness_kgfm_per_deg,
                        Unit::KgfmPerDeg,
                        ParamKind::Tilt,
                    )?,
                });
            }
            Some(out)
        };
        Ok(tilt)
    }
}
