//! The virtual rig (`rigctl simulate`): a robot with known truth, commanded through poses and
//! paths, measured with noise.
//!
//! | module | holds |
//! |---|---|
//! | [`iso9283`] | the ISO 9283 cube and the 117 + 1 calibration positions (thesis 4.4.2) |
//! | [`plan`] | tool orientations, the joint-change ordering, random validation poses |
//! | [`paths`] | the thesis's circle (5.5.1), straight lines, the quintic time profile |
//! | [`trajectory`] | joint trajectories along paths (IK per sample), positions in motion |
//! | [`effects`] | the FORMATS.md effect ids and how they change the truth |
//! | [`session`] | a simulated low-cost session: joints, pot recording, scanned trace, truth |
//! | [`simulate`] | one session: truth model, commanded poses, noisy measurements |
//! | [`output`] | `cal.csv`, `val.csv`, `truth.toml`, `truth.json` |
//!
//! The physics it uses (IK, moments in motion) lives in [`crate::model`]. Main entry points:
//! - [`trajectory::joint_trajectory`]`(&Model, &dyn Path, duration_s, samples, seed)`,
//!   [`trajectory::positions_in_motion`];
//! - [`simulate::simulate`]`(&Model, &SimConfig) -> SimOutput`,
//!   [`output::write_outputs`]`(dir, &SimOutput, &SimConfig)`;
//! - [`effects::parse_effect`]`("ID=VALUE")`.

pub mod effects;
pub mod iso9283;
pub mod output;
pub mod paths;
pub mod plan;
pub mod session;
pub mod simulate;
pub mod trajectory;
