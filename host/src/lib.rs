//! `rigctl`'s library: everything the CLI does, as typed functions with typed errors.
//!
//! | module | holds |
//! |---|---|
//! | [`model`] | the robot physics: chain, FK, Jacobians, moments, tilting, transmission terms, IK, model files |
//! | [`io`] | CSV readers (pose, joints, trace, jig, fused files), atomic output files, interrupt handling |
//! | [`joints`] | joint-tilting values (clearance, backlash, stiffness) from inclinometer readings (`rigctl joints`) |
//! | [`sim`] | the virtual rig with known truth (`rigctl simulate`) |
//! | [`capture`] | `rigctl poses`: poses from a continuous joint log and an instrument log (standstills, clock offset, robust means) |
//! | [`calib`] | identification (`rigctl calibrate`): solvers, identifiability, statistics |
//! | [`compensate`] | trajectory correction (`rigctl compensate`, eq. 5.22): joints that put the calibrated, tilting arm on a path |
//! | [`diagnose`] | `rigctl diagnose`: residual analysis, candidate effects, forward selection |
//! | [`plan`] | `rigctl plan`: optimal calibration poses (A-optimal by default; G, I, D and their subset forms), expected sigmas vs random poses |
//! | [`daq`] | the acquisition path: recordings, `record`, `export`, the virtual board |
//! | [`sheet`] | the printable trace sheet's geometry and SVG |
//! | [`trace`] | scanned pencil traces -> centreline in sheet mm; simulated scans |
//! | [`urdf`] | URDF import: a serial chain of a URDF file as a [`model::Model`] (`rigctl urdf2model`) |
//! | [`fusion`] | the low-cost measurement: pot calibration, clock alignment, joints + pot + trace -> partial error samples |
//! | [`plot`] | plots (PNG/SVG): the path-error chart, the report's stage bars and workspace views, plan views |
//! | [`report`] | `rigctl report`: the self-contained HTML page of a run directory |
//! | [`error`] | how errors are classified (bad input vs failure of the run) |
#![forbid(unsafe_code)]

pub mod calib;
pub mod capture;
pub mod compensate;
pub mod daq;
pub mod diagnose;
pub mod error;
pub mod fusion;
pub mod io;
pub mod joints;
pub mod model;
pub mod plan;
pub mod plot;
pub mod report;
pub mod sheet;
pub mod sim;
pub mod trace;
pub mod urdf;

/// Whether this run is CI (`CI=true`, as CI sets it): tests then require the shared data
/// instead of skipping without it.
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v.eq_ignore_ascii_case("true") || v == "1")
}

/// Where the shared documents and data live: `$RIG_SHARED_DIR`, else `../shared` beside the
/// repository checkout. `None` when neither exists.
pub fn shared_dir() -> Option<std::path::PathBuf> {
    if let Some(dir) = std::env::var_os("RIG_SHARED_DIR") {
        let dir = std::path::PathBuf::from(dir);
        return dir.is_dir().then_some(dir);
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared");
    dir.is_dir().then_some(dir)
}
