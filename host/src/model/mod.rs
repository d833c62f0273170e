//! The kinematic + tilting model of the rig (shared/docs/MODEL.md).
//!
//! # Structure
//! A [`Model`] is a sequence of elementary transforms ([`Elem`]: `Rx Ry Rz Tx Ty Tz`), each with
//! a named parameter ([`Param`], the constant value or the joint offset) and optionally driven
//! by a joint (revolute `Rz(q + offset)` or prismatic `Tz(q + offset)`). **Joint frame i** is
//! the frame right after joint i's element; tilting is inserted there and moments are expressed
//! there. Every model carries, besides its chain parameters:
//!
//! | parameters | unit | meaning |
//! |---|---|---|
//! | `base_x base_y base_z`, `base_rx base_ry` | mm, deg | `Tx Ty Tz Rx Ry` in frame R before the chain |
//! | `tool_dx tool_dy tool_dz` | mm | `Tx Ty Tz` in the last frame (the tool point) |
//! | `enc_j<i>_h<n>_sin`, `enc_j<i>_h<n>_cos` (n = 1..3) | deg | encoder error `s sin(n q) + c cos(n q)` added to joint i (= `A sin(n q + phi)` with `A = hypot(s, c)`, `phi = atan2(c, s)`, see [`harmonic_amplitude_phase`]) |
//! | `clearance_j<i> backlash_j<i> stiffness_j<i>` | deg, deg, kgf.m/deg | tilting values (only if the model has tilting data) |
//! | `payload_kg` | kg | point mass at the tool point (acts through the moments, i.e. tilting) |
//! | `scale_ppm` | ppm | measurement scale about the origin of R: output = (1 + s 1e-6) p |
//!
//! All default to 0 (absent). Parameter values are in the units above (deg / mm), the same as
//! `--set` and model files. Parameter order is fixed per model; Jacobian columns follow the
//! indices given.
//!
//! # Presets
//! - [`katana450`]`(tool_mm)` (MODEL.md chain; names `mount_x mount_y mount_z` (55, 55, 201.5),
//!   `dth1..dth5`, `al2..al5`, `be3..be5`, `a2`, `a3`, `d4`, `d5`; limits table 3.1; masses
//!   table 4.2; tilting table 5.2). [`KATANA_GEOMETRIC_PARAMS`] lists the thesis's 12.
//! - [`ur5`]`()` (standard DH rows `dth<i> d<i> a<i> al<i>`, i = 1..6; tool point = flange,
//!   [`UR5_SMR_TOOL_MM`] is the laser-tracker SMR offset to `--set`; the link masses Universal
//!   Robots publishes, [`UR5_LINK_MASS_KG`]; no tilting).
//! - [`preset`]`(name, tool_mm)`; [`choose_model`]`(&ModelChoice { robot, model_file, tool_mm,
//!   sets })` implements the CLI's `--robot | --model`, `--tool-mm`, `--set NAME=VALUE`
//!   ([`parse_set`]).
//! - Other arms: [`ModelBuilder`] (`new`, `constant`, `joint`, `dh_row`, `mdh_row`, `mass`,
//!   `build`), or a model file.
//!
//! # Evaluation (all `&self`, joints `q_deg` in deg / mm)
//! - [`Model::fk`]`(q, Tilt) -> Fk { position_mm, rotation, moments_kgfm, tilts_deg }`,
//!   [`Fk::zxz_deg`], [`Model::position_mm`]; [`zxz_deg`]`(&Matrix3)` (thesis eq. 2.3).
//! - [`Tilt`]: `Off`, `Static` (gravity moments of the untilted chain, the declared model), or
//!   `Moments(&[Vector3])` (external moments, kgf.m in joint frame i, e.g. from RNEA).
//! - [`Model::moments_kgfm`]`(q)`, [`Model::tilts_deg`]`(&moments)`, [`tilt_from_moment`],
//!   [`Model::frames`]`(q, tilts)` (world placement of every frame, for RNEA),
//!   [`Model::joint_value`] (offset + encoder harmonics and d/dq).
//! - [`Model::position_jacobian`]`(q, Tilt, &[Wrt]) -> (Fk, Matrix3xX)`, and the shorthands
//!   [`Model::joint_jacobian`] (mm/deg) and [`Model::param_jacobian`]`(q, Tilt, &[param index])`
//!   (mm per parameter unit). Analytic, and exact for `fk`'s position including the tilt's
//!   dependence on joints and parameters through the static moments (see [`jacobian`]'s doc).
//!
//! # Parameters
//! [`Model::params`], [`Model::param_names`], [`Model::param_index`], [`Model::require_param`]
//! (error lists the valid names), [`Model::param`], [`Model::set_param`], [`Model::set_param_at`],
//! [`Model::param_values`], [`Model::set_param_values`], [`Model::params_of_kind`] ([`ParamKind`]).
//!
//! # Physics beyond the chain
//! [`dynamics`] (joint moments in motion by recursive Newton-Euler, [`rnea`]; along a logged
//! joint trajectory: [`motion`], with the model's
//! link masses), [`gravity`] (gravity torque about each joint axis, for compliance: the axis
//! components of the static moments), [`time_terms`] (thermal growth and drifts in the pose
//! time), [`transmission`] (gear-ratio, coupling and hysteresis terms on the joint
//! angles, and the direction of approach from the pose order), [`ik`] (inverse kinematics of
//! the 5-DOF Katana on any model's FK).
//!
//! # Trees
//! [`Tree`]: several tips from one root, every joint once (a parent index per joint, named
//! tips); [`Tree::chain`] is one tip's chain as a [`Model`], [`Tree::from_chains`] joins chains
//! at their shared joints; files in [`tree_file`].
//!
//! # Model files
//! [`Model::from_toml_str`], [`Model::from_file`], [`Model::to_toml_string`],
//! [`Model::write_file`]; the format is documented in [`toml_file`].

mod assumed_masses;
mod builder;
mod chain;
pub mod changes;
mod data;
pub mod dynamics;
pub mod effect;
mod error;
pub mod gravity;
pub mod ik;
pub mod jacobian;
mod kinematics;
pub mod lateral;
pub mod motion;
mod param;
mod pose_spec;
mod presets;
pub mod ranges;
pub mod rnea;
mod tilt;
pub mod time_terms;
pub mod toml_file;
mod toml_write;
pub mod transmission;
pub(crate) mod tree;
pub mod tree_bend;
pub mod tree_file;
pub mod tree_gravity;
pub mod tree_params;
pub mod unknown;

pub use builder::{ModelBuilder, PAYLOAD_PARAM};
pub use chain::*;
pub use data::Data;
pub use error::ModelError;
pub use jacobian::Wrt;
pub use kinematics::*;
pub use param::*;
pub use presets::*;
pub use tilt::{sign_1e9, tilt_from_moment};
pub use tree::{Tip, Tree, TreeElem, TreeJoint, TreeMass, TREE_SHARED_PARAMS};

/// Amplitude `A` and phase `phi` (deg) of the encoder harmonic `s sin(nq) + c cos(nq)` written
/// as `A sin(n q + phi)` (FORMATS.md effect `encoder_harmonic:j<i>:h<n>`).
pub fn harmonic_amplitude_phase(sin_deg: f64, cos_deg: f64) -> (f64, f64) {
    (sin_deg.hypot(cos_deg), cos_deg.atan2(sin_deg).to_degrees())
}
