//! The TIAGo motion-capture data set (FIGAROH examples, `shared/data/real/
//! thanhndv212__figaroh-examples/examples/tiago`): posture files as poses ([`mocap`]) and the
//! calibration levels compared with FIGAROH's published held-out numbers ([`levels`]).

pub mod levels;
pub mod markers;
pub mod mocap;
pub mod select;
pub mod terms;

pub use mocap::{MocapError, Posture, PostureSet, N_MARKERS};
