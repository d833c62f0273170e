//! The virtual rig (`rigctl simulate`): a robot with known truth, commanded through poses and
//! paths, measured with noise.
//!
//! | module | holds |
//! |---|---|
//! | [`ik`] | inverse kinematics of the 5-DOF Katana: closed form + Newton on any model's FK |
//! | [`iso9283`] | the ISO 9283 cube and the 117 + 1 calibration positions (thesis 4.4.2) |
//! | [`plan`] | tool orientations, the joint-change ordering, random validation poses |
//! | [`paths`] | the thesis's circle (5.5.1), straight lines, the quintic time profile |
//! | [`rnea`] | recursive Newton-Euler joint moments (thesis eq. 5.14), generic |
//! | [`dynamics`] | RNEA on a [`crate::model::Model`], joint trajectories, positions in motion |
//! | [`effects`] | the FORMATS.md effect ids and how they change the truth |
//! | [`session`] | a simulated low-cost session: joints, pot recording, scanned trace, truth |
//! | [`simulate`] | one session: truth model, commanded poses, noisy measurements |
//! | [`output`] | `cal.csv`, `val.csv`, `truth.toml`, `truth.json` |
//!
//! Main entry points:
//! - [`ik::solve`]`(&Model, &ToolTarget, seed_deg, IkTilt) -> Result<Vec<f64>, IkError>`,
//!   [`ik::tool_target`]`(&Model, q_deg, IkTilt)`;
//! - [`dynamics::moments_kgfm`]`(&Model, q, qd, qdd, Inertia)`,
//!   [`dynamics::joint_trajectory`]`(&Model, &dyn Path, duration_s, samples, seed)`,
//!   [`dynamics::positions_in_motion`];
//! - [`simulate::simulate`]`(&Model, &SimConfig) -> SimOutput`,
//!   [`output::write_outputs`]`(dir, &SimOutput, &SimConfig)`;
//! - [`effects::parse_effect`]`("ID=VALUE")`.

pub mod dynamics;
pub mod effects;
pub mod ik;
pub mod iso9283;
pub mod output;
pub mod paths;
pub mod plan;
pub mod rnea;
pub mod session;
pub mod simulate;
