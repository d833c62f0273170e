//! The UR5 preset against the laser-tracker data of shared/data/real/ur5_laser_tracker: with
//! the SMR offset the nominal model must reproduce the measured points to the few millimetres
//! that the published work reports before calibration (mean 2.5664 mm on random.csv), which
//! checks the DH convention, the joint order and the units.

use crate::common;

use rigctl::io::pose_csv::{read_poses, PoseSpec};
use rigctl::model::{ur5, Tilt, UR5_SMR_TOOL_MM};

fn mean_error_mm(file: &str) -> Option<f64> {
    let path = common::shared_file(
        &format!("UR5 {file}"),
        &format!("data/real/ur5_laser_tracker/{file}"),
    )?;
    let mut model = ur5().unwrap();
    for (name, v) in ["tool_dx", "tool_dy", "tool_dz"]
        .iter()
        .zip(UR5_SMR_TOOL_MM)
    {
        model.set_param(name, v).unwrap();
    }
    let poses = read_poses(&path, &PoseSpec::for_model(&model, true)).unwrap();
    let sum: f64 = poses
        .poses
        .iter()
        .map(|p| {
            let [x, y, z] = p.xyz_mm.unwrap();
            (model.position_mm(&p.q, Tilt::Off).unwrap() - nalgebra::Vector3::new(x, y, z)).norm()
        })
        .sum();
    Some(sum / poses.poses.len() as f64)
}

#[test]
fn nominal_ur5_reproduces_the_laser_tracker_points() {
    let Some(random) = mean_error_mm("random.csv") else {
        return;
    };
    let grid = mean_error_mm("grid.csv").unwrap();
    eprintln!("UR5 nominal mean error: random.csv {random:.4} mm, grid.csv {grid:.4} mm");
    assert!(
        (random - 2.5664).abs() < 0.02,
        "random.csv mean error {random} mm"
    );
    assert!(grid < 5.0, "grid.csv mean error {grid} mm");
}
