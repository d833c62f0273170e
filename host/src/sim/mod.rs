//! The virtual rig (`rigctl simulate`): a robot with known truth, commanded through poses and
//! paths, measured with noise.
//!
//! | module | holds |
//! |---|---|
//! | [`ik`] | inverse kinematics of the 5-DOF Katana (closed form + Newton on any model's FK) |
//! | [`iso9283`] | the ISO 9283 cube and the 118 calibration positions (thesis 4.4.2) |
//! | [`paths`] | the thesis's circle, straight lines, the quintic time profile |
//! | [`rnea`] | recursive Newton-Euler joint moments (thesis eq. 5.14) |

pub mod dynamics;
pub mod effects;
pub mod ik;
pub mod iso9283;
pub mod output;
pub mod paths;
pub mod plan;
pub mod rnea;
pub mod simulate;
