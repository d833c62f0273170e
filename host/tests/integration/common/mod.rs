//! Shared by the integration tests: the files of `../shared`, which CI requires.
#![allow(dead_code)]

use std::path::PathBuf;

/// `rel` (a file or folder) under the shared directory (`rigctl::shared_dir()`: `$RIG_SHARED_DIR`
/// or `../shared`), or `None` after a `SKIPPED` message when it is absent. With `CI=true` its
/// absence fails the test instead: CI runs with `../shared` beside the clone, so a missing file
/// there is a broken setup, never a reason to pass.
pub fn shared_file(test: &str, rel: &str) -> Option<PathBuf> {
    let path = rigctl::shared_dir().map(|d| d.join(rel));
    if let Some(p) = path.filter(|p| p.exists()) {
        return Some(p);
    }
    let msg = format!("{test}: ../shared/{rel} is absent (or set RIG_SHARED_DIR)");
    if rigctl::in_ci() {
        panic!("{msg}; with CI=true the shared data is required");
    }
    eprintln!("SKIPPED {msg}");
    None
}

/// The `ur5` preset with the laser tracker's SMR as its tool point (`UR5_SMR_TOOL_MM`), the
/// model the UR5 data sets of `../shared` are calibrated with.
pub fn ur5_with_smr_tool() -> rigctl::model::Model {
    let mut model = rigctl::model::ur5().expect("the ur5 preset builds");
    for (name, v) in ["tool_dx", "tool_dy", "tool_dz"]
        .iter()
        .zip(rigctl::model::UR5_SMR_TOOL_MM)
    {
        model
            .set_param(name, v)
            .expect("the ur5 preset has a tool point");
    }
    model
}

/// The real UR5 laser-tracker set (`../shared/data/real/ur5_laser_tracker`): the model of
/// [`ur5_with_smr_tool`], the 1000 grid poses and the 20 random test poses; `None` after the
/// [`shared_file`] message when it is absent.
pub fn ur5_tracker(
    test: &str,
) -> Option<(
    rigctl::model::Model,
    rigctl::calib::Poses,
    rigctl::calib::Poses,
)> {
    let dir = shared_file(test, "data/real/ur5_laser_tracker")?;
    let model = ur5_with_smr_tool();
    let read = |name: &str| {
        rigctl::calib::Poses::read(&dir.join(name), &model)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
    };
    let (grid, random) = (read("grid.csv"), read("random.csv"));
    Some((model, grid, random))
}

/// One row `t,x,y,z,ax,ay,az` of a `compensate --path` file (s, mm, unit tool axis).
pub fn path_row(t_s: f64, x: &nalgebra::Vector3<f64>, a: &nalgebra::Vector3<f64>) -> String {
    format!(
        "{t_s:.3},{:.12},{:.12},{:.12},{:.15},{:.15},{:.15}\n",
        x.x, x.y, x.z, a.x, a.y, a.z
    )
}
