//! The low-cost measurement of thesis section 5.5.2 (fig. 5.11, 5.13): a pencil on a spring-loaded
//! potentiometer draws the planned path on a sheet lying on the 45-degree plane; the joint
//! readings of the robot controller, the board's potentiometer recording and the scanned pencil
//! trace are fused into **partial** Cartesian error samples (`rigctl fuse`), which
//! [`crate::calib::projected`] turns into a calibration (`rigctl calibrate --samples`).
//!
//! | module | holds |
//! |---|---|
//! | [`placement`] | where the sheet lies in frame R (sheet mm <-> R mm), the placement file |
//! | [`potcal`] | potentiometer calibration: raw ADC counts -> pencil travel mm (`rigctl potcal`) |
//! | [`pot`] | the potentiometer samples of a board recording |
//! | [`align`] | clock alignment of the board (pot) and the robot (joints) by the dip markers |
//! | [`curve`] | the traced curve: closest point and local in-plane normal |
//! | [`fuse`] | the fusion itself: joint readings + pot recording + trace -> fused samples |
//! | [`fused_file`] | the fused-samples file `FUSED.csv`: its columns, writer and reader |
//! | [`error`] | [`FusionError`] |
//!
//! # What is measured, and what is not
//! * **Out of plane** (along the sheet normal `n`, i.e. the tool axis while drawing): the pencil
//!   slides in its holder; its travel (potentiometer) is the height of the tool point above the
//!   paper. Measured at every contact sample.
//! * **In plane, across the path** (along the in-plane normal `u` of the traced curve): the
//!   distance from the nominal point's projection to the pencil trace.
//! * **Along the path: not measured.** The trace has no time stamps, so a point running ahead of
//!   or behind its schedule along the path leaves the same trace. Each fused sample therefore
//!   carries two measured components (`u` and `n`) and their directions, never a 3-D point.

pub mod align;
pub mod curve;
pub mod error;
pub mod fuse;
pub mod fused_file;
pub mod placement;
pub mod pot;
pub mod potcal;

pub use error::FusionError;
pub use fuse::{fuse, FuseOptions, Fused, FusedSample, JointSamples};
pub use fused_file::{read_fused, write_fused};
pub use placement::SheetPlacement;
pub use potcal::{JigPoint, PotCalibration};
